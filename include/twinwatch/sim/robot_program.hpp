#pragma once
/// @file robot_program.hpp
/// A scenario's motion as a program the real robot runs: the URScript program that moves a Universal
/// Robots e-Series arm through the same joint-space target (an excitation, a swing, a chirp), so that
/// the recordings `twinwatch identify` needs can be taken on the user's own arm while
/// `twinwatch record --rtde` listens. The program evaluates the closed form (trajectory.hpp) on the
/// controller and hands it to servoj every 2 ms; it does not depend on twinwatch while it runs.
///
/// What the program moves is ProgramMotion, defined here in double precision so that it can be
/// checked before anything moves (joint limits, peak speed and acceleration) and compared with what
/// the program computes. The differences from the scenario's trajectory, each on purpose:
///  - the controller starts and ends at rest: a target that starts (ends) moving, as a sine does, is
///    run on a clock tau(t) whose rate rises 0 -> 1 (falls 1 -> 0) as a raised cosine over `ramp`
///    seconds, so the target's velocity starts (ends) at zero, and its acceleration stays finite
///    (the virtual robot jumps to the first target's velocity; an arm would take a step of it);
///  - URScript's numbers are 32-bit floats (UR's manual: "float: a floating point number (32 bit)"),
///    whose resolution at t = 600 s is 61 µs: the program never evaluates sin(omega t) at a large t.
///    It keeps each component's phase in [0, 2 pi), advances it by omega dtau per step as a
///    compensated (Kahan) sum, since a plain float sum of 2 ms steps drifts by milliradians in a
///    minute, and counts steps in an integer.
#include <string>
#include <vector>

#include <memory>

#include "twinwatch/model/robot_model.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "twinwatch/sim/trajectory.hpp"

namespace twinwatch::sim {

/// How the program runs its motion.
struct ProgramOptions {
  double duration = 0.0;      ///< [s] of the trajectory's own time to run (the scenario's duration)
  double ramp = 2.0;          ///< [s] of the clock's rise (fall) where the target starts (ends) moving
  /// runs the trajectory this many times slower (ClosedForm::slowed): the same path, its speeds
  /// (joint and Cartesian) divided by it, its accelerations by its square: the whole program, ramps
  /// included (each `ramp` times it), K times as long; 1-100. For an installation whose safety limits
  /// the motion would exceed.
  double slow_down = 1.0;
  double servo_period = 0.002;  ///< servoj's t [s]: the e-Series controller's 500 Hz
  double lookahead = 0.1;     ///< servoj lookahead_time [s], 0.03-0.2
  double gain = 300.0;        ///< servoj gain, 100-2000
  double approach_speed = 0.25;         ///< movej to the start pose: joint speed [rad/s]
  double approach_acceleration = 0.5;   ///< and acceleration [rad/s²]
  /// [rad] the program refuses to start (popup, halt: nothing moves) when any joint is farther than
  /// this from the start pose: the approach is a movej from wherever the arm is, through a path
  /// nobody checked. 0.5 rad takes the movej at most 2 s at 0.25 rad/s.
  double max_approach = 0.5;
  bool declare_payload = false;  ///< the program calls set_payload(mass, com) before it moves
  /// ... with set_target_payload(mass, com, [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]) instead (the inertia about
  /// the CoG, flange axes; PolyScope 5.10 and newer, where set_payload is deprecated)
  bool target_payload = false;
  /// the file ends with the call `NAME()` after the def, as a Polyscope Script node (file) needs; without
  /// it the file is the one def block the controller's port 30002 runs
  bool call = false;
  model::RigidBodyInertia payload;  ///< declared when declare_payload
  std::string name;           ///< the program's name (letters, digits, '_'; made so from any text)
  std::string title;          ///< the header comment's first line (e.g. the scenario's path)
  /// Throws InvalidArgument naming the field (ProgramOptions names: duration, ramp, ...).
  void validate() const;
};

/// The target the program commands, as a trajectory of the program's time t in [0, total()]: the
/// closed form at tau(t), tau = t in the middle, rising and falling clock rates at the ends where the
/// closed form moves there (ProgramOptions::ramp). Beyond total() it holds the end pose.
class ProgramMotion final : public Trajectory {
 public:
  /// Throws InvalidArgument for options that do not validate, a closed form without components or
  /// of non-finite numbers, or a duration shorter than one servo period.
  ProgramMotion(ClosedForm form, const ProgramOptions& options);
  int n_dof() const override { return form_.n_dof(); }
  /// Not cyclic: the whole program (joint_limit_violation checks every step).
  double period() const override { return std::numeric_limits<double>::infinity(); }
  void evaluate(double t, VectorJ& q, VectorJ& qd, VectorJ& qdd) const override;

  /// The program's time [s]: duration plus half of each ramp used.
  double total() const { return static_cast<double>(steps()) * dt_; }
  /// servoj calls: total() / servo period.
  long steps() const { return duration_steps_ + ramp_in_steps_ / 2 + ramp_out_steps_ / 2; }
  /// [s] of the rising and falling clock (0: the closed form is at rest there); each a whole, even
  /// number of servo periods, so that the program's time is a whole number of them.
  double ramp_in() const { return static_cast<double>(ramp_in_steps_) * dt_; }
  double ramp_out() const { return static_cast<double>(ramp_out_steps_) * dt_; }
  long ramp_in_steps() const { return ramp_in_steps_; }
  long ramp_out_steps() const { return ramp_out_steps_; }
  double servo_period() const { return dt_; }
  /// The trajectory's time tau at the program's time t.
  double clock(double t) const;
  const ClosedForm& form() const { return form_; }

 private:
  // the clock's rate and its derivative at t
  void rate(double t, double& r, double& dr) const;
  ClosedForm form_;
  double dt_;
  long duration_steps_, ramp_in_steps_ = 0, ramp_out_steps_ = 0;
};

/// The scenario's trajectory in closed form. Throws InvalidArgument naming the file, the line of its
/// `trajectory:` and its type when it has none (a Cartesian path, point-to-point, quasi-static).
ClosedForm scenario_closed_form(const Scenario& s);

/// The scenario as its robot program runs it, for the virtual robot to rehearse (simulate
/// --as-program): its trajectory becomes the program's motion over options.duration seconds of the
/// trajectory's time (ramps included, started at rest), its duration the program's time. The faults
/// keep their times, on the program's clock. Returns the motion; throws as scenario_closed_form and
/// ProgramMotion do.
std::shared_ptr<const ProgramMotion> rehearse_as_program(Scenario& s, const ProgramOptions& options);

/// Peak |target velocity| and |acceleration| per joint over a motion, sampled every servo period.
/// The longest the approach (movej from wherever the arm stands to the start pose) takes [s]: the
/// leading joint's trapezoid over max_approach at approach_speed and approach_acceleration (farther,
/// the program halts instead). The recording a program suggests covers it.
double approach_time_at_most(const ProgramOptions& o);

struct MotionPeaks {
  VectorJ qd, qdd;
  VectorJ q_min, q_max;
};
MotionPeaks motion_peaks(const ProgramMotion& motion);

/// How many times slower than `motion` the same program must run to keep every joint within the
/// robot's speed and (where published) acceleration limits: the peak speed over the limit, or the
/// square root of the peak acceleration over its limit, whichever is larger (a program K times
/// slower, ramps included, divides every speed by K and every acceleration by K²). 1 when the motion
/// is within them; infinity when a joint's range is left, which no slow-down fixes. `qdd_cap`
/// [rad/s²] stands for the acceleration limit of a joint whose description publishes none (urscript
/// writes no program beyond 40 rad/s² there); infinity: none.
double slow_down_for_joint_limits(const ProgramMotion& motion, const model::RobotModel& robot,
                                  double qdd_cap = std::numeric_limits<double>::infinity());

/// The figures of a motion that a UR installation's safety limits bound (PolyScope: Installation >
/// Safety > Robot Limits: tool speed, elbow speed, momentum), at their peaks, sampled every servo
/// period: a limit below them stops or slows the arm mid-run (a protective stop, or speed scaling
/// that changes the motion the recording was to take). The installation's values are the user's:
/// they are checked when given (urscript --tool-speed-limit ...), else only reported.
struct SafetyPeaks {
  double tool_speed = 0.0;   ///< [m/s] model::CartesianSpeeds::tool at its peak
  double tool_t = 0.0;       ///< [s] of the program's time, when
  int tool_point = -1;       ///< which point: -1 the flange's centre, k the tool point k
  double elbow_speed = 0.0;  ///< [m/s] model::CartesianSpeeds::elbow at its peak
  double elbow_t = 0.0;
  double momentum = 0.0;     ///< [kg·m/s] model::CartesianSpeeds::momentum at its peak
  double momentum_t = 0.0;
  /// [N·m] per joint, the largest |torque| the rigid body needs along the motion (inverse dynamics
  /// with the payload's mass at its centre; no friction, no rotor inertia: a lower bound of what the
  /// drive gives), and when [s]: beyond the joint's torque_max no drive follows the motion
  VectorJ torque, torque_t;
};
/// `tool_points` in the flange frame [m]; `payload` the part the flange carries (flange frame), part
/// of the momentum. Throws InvalidArgument when the robot has fewer than three joints or other than
/// the motion's, or a tool point is not finite.
SafetyPeaks safety_peaks(const ProgramMotion& motion, const model::RobotModel& robot, const std::vector<Eigen::Vector3d>& tool_points,
                         const model::RigidBodyInertia& payload);

/// The URScript program (text) that commands `motion` on a UR e-Series controller: one `def ... end`
/// block, as the controller's port 30002 and a Polyscope Script node take it. It moves to the start
/// pose with movej (options' approach speed), declares the payload if asked, commands the motion with
/// servoj every servo period, and stops with stopj. Its header says what it moves and what to check
/// before running it. `robot` names the arm in the header; `header` lines are added to it as comments.
std::string urscript_program(const ProgramMotion& motion, const ProgramOptions& options, const model::RobotModel& robot,
                             const std::vector<std::string>& header = {});

}  // namespace twinwatch::sim
