#pragma once
/// @file simulator.hpp
/// The virtual robot: the plant that stands in for a physical arm (DESIGN.md "Observable element").
///
/// Its physics is deliberately richer than anything the twin fits (DESIGN.md rule 2):
/// - rigid body: the robot file's model with every link mass / first moment / inertia perturbed by
///   a seeded factor (the real arm never matches its datasheet);
/// - friction per joint: LuGre [Canudas1995] (Stribeck curve, pre-sliding hysteresis at velocity
///   reversals) + viscous friction that grows when the joint is cold, + harmonic-drive ripple
///   (N-per-revolution and once-per-revolution terms);
/// - drive: tau_joint = i kt N eta when motoring, i kt N / eta_rev when back-driven [UR3e eq. 3];
/// - thermal: C dT/dt = R i² - (T - T_ambient) / R_th per joint;
/// - measurement: current noise (DESIGN.md rule 4 range), offset, 0.1 mA quantisation; 20-bit
///   encoders; the controller's velocity estimate from encoder differences; controller timestamp.
/// The controller is an industrial one: PD + feed-forward of the NOMINAL model (the robot file,
/// with the payload the user declared) on the target, torque limits; it hides faults in position.
///
/// Integration: semi-implicit Euler of the forward dynamics at `physics_rate` (>= 2 kHz), the
/// controller and the recording at `rate` (500 Hz); the LuGre state is advanced exactly for the
/// velocity held over a substep (stable for stiff bristles).
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "twinwatch/core/sample.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "twinwatch/sim/trajectory.hpp"

namespace twinwatch::sim {

/// The truth of one joint (never visible to the twin).
struct JointTruth {
  // friction, joint side
  double Fc = 0.4;        ///< Coulomb [N·m]
  double Fs = 0.6;        ///< static (Stribeck peak) [N·m]
  double vs = 0.05;       ///< Stribeck velocity [rad/s]
  double Fv = 0.4;        ///< viscous at the reference temperature [N·m·s/rad]
  double sigma0 = 2000;   ///< bristle stiffness [N·m/rad] (pre-sliding)
  double sigma1 = 5;      ///< bristle damping [N·m·s/rad]
  double visc_temp_coeff = 0.02;  ///< Fv(T) = Fv exp(-k (T - T_ref)) [1/°C]
  double T_ref = 35.0;    ///< [°C]
  double ripple = 0.03;   ///< N-per-rev ripple amplitude [N·m]
  double ripple_phase = 0.0;
  double ripple1 = 0.05;  ///< once-per-rev ripple amplitude [N·m]
  double ripple1_phase = 0.0;
  // drive
  double gear_ratio = 101;
  double kt = 0.1;        ///< [N·m/A]
  double eta = 0.9;       ///< motoring efficiency
  double eta_rev = 0.85;  ///< back-driven efficiency
  // thermal
  double R_heat = 0.8;    ///< heating [W/A²]
  double R_th = 6.0;      ///< [°C/W]
  double C_th = 400.0;    ///< [J/°C]
  // measurement
  double current_sigma = 0.02;  ///< [A]
  double current_offset = 0.0;  ///< [A]
  /// [N·m] noise of the joint's torque sensor (SimOptions::joint_torque_sensors): 0.2 % of the joint's
  /// torque limit (UR3e 0.108 N·m on J1-J2, 0.056 on J3, 0.018 on the wrist), about the resolution
  /// strain-gauge joint sensors of arms this size quote; an assumption, not a UR figure (UR arms have none)
  double torque_sigma = 0.05;
};

/// The plant's hidden parameters.
struct PlantTruth {
  std::vector<JointTruth> joints;
  double ambient = 22.0;              ///< [°C]
  double current_lsb = 1e-4;          ///< [A] (0.1 mA resolution of the logged current)
  double encoder_lsb = 2 * M_PI / (1 << 20);  ///< [rad]
  double inertial_perturbation = 0.05;  ///< relative spread of the truth link parameters vs the file
  /// Identity of the physical robot: the same serial gives the same hidden parameters in every
  /// scenario (the seed of a scenario only changes noise), as one real arm would.
  unsigned serial = 1;
};

/// Rotor inertia reflected through the gear, J_m N^2 [kg·m²], that the plant adds to M(q)'s diagonal.
double armature(const JointTruth& joint);

/// UR-sized default truth for a model (documented in docs/scenarios.md); `serial` picks one
/// physical robot (its friction, inertial and drive spread).
PlantTruth default_truth(const model::RobotModel& model, unsigned serial);

enum class FaultType {
  Resistance,      ///< extra resistance on a joint [N·m], e.g. [UR3e §4.2] J5
  FrictionGrowth,  ///< wear: friction (Coulomb and viscous) grows by `magnitude` (relative, 0.3 = +30 %) over the ramp
  PayloadPick,     ///< a payload of `mass` is gripped (digital output bit set)
  PayloadLoss,     ///< the payload is released / lost (digital output bit cleared) [UR3e §4.3]
  Collision,       ///< force pulse at a point on a link; magnitude = peak joint-equivalent torque [N·m]
  CurrentOffset,   ///< sensor: constant offset on one current channel [A]
  StuckCurrent,    ///< sensor: one current channel frozen at its last value
  DroppedSamples,  ///< stream: `magnitude` consecutive samples are not delivered (every `period` s)
  TimestampJitter, ///< stream: controller timestamp jitter of sigma = magnitude [s] (clipped, see kJitterClipSigmas)
  MissedPick,      ///< the program declares a payload of `mass` (set_payload) and closes the gripper on nothing
};

/// Lower-case YAML name ("resistance", "friction_growth", ...).
const char* to_string(FaultType t);

struct FaultSpec {
  FaultType type = FaultType::Resistance;
  double onset = 0.0;   ///< [s]
  double ramp = 0.0;    ///< [s] linear ramp to full magnitude
  double end = std::numeric_limits<double>::infinity();  ///< [s]
  double magnitude = 0.0;
  int joint = -1;       ///< 0-based
  int link = -1;        ///< 0-based (collisions)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();       ///< on the link, body frame [m]
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();  ///< world frame
  double duration = 0.05;  ///< collision pulse length [s]
  double period = 0.0;     ///< dropped samples: repeat every period [s] (0: once)
  model::RigidBodyInertia payload;  ///< payload pick
  int io_bit = 0;          ///< digital output bit of the gripper, 0 to kMaxDigitalOutputBit
  /// payload pick: the program declares the part (set_payload) this long after the gripper closes
  /// on it [s], as a gripper's URCap does once it has seen the grip; negative: before (the program
  /// declares, then closes the gripper). 0: at once. Between the two the controller's feed-forward
  /// and the stream's declaration differ from what the arm carries.
  double declare_delay = 0.0;

  /// 0 before onset, ramps to 1, 0 after end.
  double level(double t) const;
};

/// A stop of the running program, as an operator or the safety system makes one on a real arm: the
/// controller decelerates along the path (the program's time slows to a halt, as a UR controller's
/// speed scaling does), holds, and resumes the program where it stopped with the same ramp. Not a
/// fault: the stream says it in robot_mode and safety_mode, as a UR controller's does
/// (../shared/reference/rtde-protocol.md), and the labels do not list it.
enum class StopKind {
  Pause,       ///< the operator pauses the program: powered, safety_mode NORMAL throughout
  Protective,  ///< a protective stop (stop category 2: powered, holding): safety_mode PROTECTIVE_STOP until unlocked
  Emergency,   ///< an emergency stop (category 1): decelerates, then power off with the brakes on; powered on,
               ///< brakes released and the program resumed at the end of the hold
};

/// Lower-case YAML name ("pause", "protective", "emergency").
const char* to_string(StopKind k);

struct StopSpec {
  StopKind kind = StopKind::Pause;
  double at = 0.0;             ///< [s] the stop is triggered
  double hold = 5.0;           ///< [s] from the trigger until the program resumes
  double stopping_time = 0.3;  ///< [s] the deceleration along the path (and the resume's ramp)
};

/// The stop timeline's fixed steps [s]: a protective stop is unlocked (safety_mode NORMAL again)
/// kUnlockLead before the program resumes; after an emergency stop the arm is powered on with the
/// brakes still on (robot_mode IDLE) for kIdleBeforeRelease, and its brakes are released
/// (robot_mode RUNNING, holding at rest) kBrakeReleaseLead before the program resumes.
inline constexpr double kUnlockLead = 0.5;
inline constexpr double kIdleBeforeRelease = 1.0;
inline constexpr double kBrakeReleaseLead = 1.0;
/// The longest deceleration a stop may take [s] (UR stopping times are well below it).
inline constexpr double kMaxStoppingTime = 2.0;
/// The shortest hold a stop of `kind` needs [s]: its deceleration and, for an emergency stop, the
/// power-on and brake-release steps before the program resumes.
double min_stop_hold(const StopSpec& stop);

/// Joint torque per newton of a collision fault's force, J_link(point)^T direction [N·m/N], at the
/// configuration `d` holds (forward_kinematics done). The simulator scales it so that its largest
/// entry is the fault's magnitude; evaluation reads it to score the contact isolation.
VectorJ collision_torque_per_newton(const model::RobotModel& m, const model::DynamicsData& d, const FaultSpec& f);

/// Control and recording rates the simulator accepts [Hz]. The lowest is the slowest real UR
/// controller's (CB3 RTDE, 125 Hz): below it the default joint PD (10 Hz closed-loop bandwidth) no
/// longer tracks (worst error on the library figure-eight: 3 mrad at 500 Hz, 12 mrad at 125 Hz,
/// 38 mrad at 100 Hz, 0.25 rad at 50 Hz). The highest, 20x an e-Series controller's 500 Hz, keeps
/// duration * rate (the sample count) far inside a long.
inline constexpr double kMinRate = 125.0;
inline constexpr double kMaxRate = 10000.0;
/// Physics steps per second the integration needs, rate * substeps [Hz].
inline constexpr double kMinPhysicsRate = 2000.0;
/// Longest run the simulator accepts [s], about 11.6 days (5e8 samples at 500 Hz): anything longer is
/// a typo or an overflow (1e300, .inf), not a rehearsal.
inline constexpr double kMaxDuration = 1e6;
/// Highest digital output bit a fault may drive: a UR controller's actual_digital_output_bits holds
/// the standard outputs in bits 0-7, the configurable ones in 8-15 and the tool's in 16-17.
inline constexpr int kMaxDigitalOutputBit = 17;
/// The longest a program may declare a pick before or after the grip in a scenario [s]
/// (FaultSpec::declare_delay): a gripper's URCap declares within a second of the grip.
inline constexpr double kMaxDeclareDelay = 2.0;
/// Timestamp jitter: each draw is clipped to kJitterClipSigmas sigmas and sigma may be at most
/// kMaxJitterFraction of the sample period, so that consecutive timestamps stay at least
/// 1 - 2 * 3 / 8 = a quarter period apart (the recording reader requires increasing timestamps).
inline constexpr double kJitterClipSigmas = 3.0;
inline constexpr double kMaxJitterFraction = 0.125;

/// Why a run of `duration` [s] cannot be recorded at `rate` [Hz] ("expected ..., got ..."), or "" when
/// it can: it must be > 0, at least one sample period (1 / rate) and at most kMaxDuration.
std::string duration_problem(double duration, double rate);

struct SimOptions {
  double rate = 500.0;          ///< controller and recording rate [Hz], kMinRate to kMaxRate
  int substeps = 4;             ///< physics steps per control step (rate * substeps >= kMinPhysicsRate)
  double duration = 10.0;       ///< [s], see duration_problem()
  unsigned seed = 1;
  bool cold_start = false;      ///< joints start at ambient temperature (else warmed up, ~T_ref)
  model::RigidBodyInertia payload;  ///< carried at start (truth), also declared to the controller
  bool payload_declared = true; ///< the controller's model includes the payload
  /// the controller streams the payload it is told (RTDE payload / payload_cog, controllers >= 5.5.1):
  /// every sample carries it (kFieldPayload). False: a controller or a recording without it
  bool streams_payload = true;
  /// the stream carries the controller's targets (target_q, target_qd, target_qdd, target_current,
  /// target_moment), as RTDE does. False: a log without them (another robot's, a user's own logger
  /// that keeps the measured signals only); the controller still tracks its targets
  bool streams_targets = true;
  /// the arm has joint torque sensors between each gear and its link (as a Panda or a Kinova Gen3
  /// does; a UR does not) and the stream carries them: actual_joint_torque = the link-side torque,
  /// tau_cmd - friction - rotor inertia x qdd = M qdd + h - tau_ext, plus JointTruth::torque_sigma
  /// noise (drawn from a stream of its own: every other signal is the same with or without them)
  bool joint_torque_sensors = false;
  VectorJ kp, kd;               ///< PD gains [N·m/rad], [N·m·s/rad]; empty: defaults from the inertia
  /// stops of the program (StopSpec), in time order, each resumed before the next begins
  std::vector<StopSpec> stops;
  void validate(int n_dof) const;
};

/// Steps the plant and emits recorded samples.
class Simulator {
 public:
  /// @param nominal the robot file's model (the controller's model); the plant's truth is derived
  /// from it with `truth` perturbations. Throws InvalidArgument on invalid options or faults (a joint
  /// or link out of range, an io_bit beyond kMaxDigitalOutputBit, a jitter above kMaxJitterFraction).
  Simulator(const model::RobotModel& nominal, std::shared_ptr<const Trajectory> trajectory, PlantTruth truth,
            SimOptions options, std::vector<FaultSpec> faults);

  /// Runs for options.duration and calls `sink` for every delivered sample (dropped ones are not).
  /// `progress` (may be empty) gets the fraction done now and then.
  void run(const std::function<void(const RobotSample&)>& sink,
           const std::function<void(double)>& progress = {});

  /// One control period; returns false if the sample is dropped by a stream fault.
  bool step(RobotSample& out);

  double time() const { return t_; }
  const VectorJ& q() const { return q_; }
  const VectorJ& qd() const { return qd_; }
  const model::RobotModel& truth_model() const { return truth_model_; }
  /// Fields every sample carries with the default options (sample_fields(): what the options leave).
  static std::uint32_t fields();
  /// The controller's targets among fields(): what options.streams_targets = false leaves out
  static constexpr std::uint32_t kTargetFields = kFieldTargetQ | kFieldTargetQd | kFieldTargetQdd | kFieldTargetCurrent | kFieldTargetMoment;
  /// Fields this simulator's samples carry: fields(), with options.streams_payload kFieldPayload,
  /// without options.streams_targets none of the target fields (kTargetFields).
  std::uint32_t sample_fields() const;

 private:
  /// What the program and the controller do at wall time t (the stops): the program's time t - lost
  /// (the trajectory's clock), its rate r and the rate's derivative, the modes the stream reports,
  /// whether the brakes hold the arm.
  struct ProgramState {
    double lost = 0.0, r = 1.0, rdot = 0.0;
    std::int32_t robot_mode = kRobotModeRunning, safety_mode = kSafetyModeNormal;
    bool braked = false;
  };
  ProgramState program_state(double t) const;
  /// Throws InvalidArgument when a sample is beyond a joint's range by kPositionLimitMargin or
  /// beyond kSpeedLimitFactor x its speed limit.
  void check_within_limits(const RobotSample& s) const;
  static constexpr double kSpeedLimitFactor = 3.0;
  static constexpr double kPositionLimitMargin = 0.05;  ///< [rad]
  /// Joint j's friction torque at velocity qd over a substep dt (without a resistance fault's).
  double friction_torque(int j, double qd, double dt);
  /// The size of the resistance faults on joint j now [N·m] (0: none).
  double resistance(int j) const;
  /// A substep's qdd with the resistances R taken at the velocity qd + h qdd it ends with:
  /// M qdd = b - R tanh((qd + h qdd)/vs).
  VectorJ implicit_acceleration(const MatrixJ& M, const VectorJ& b, const VectorJ& qd, const VectorJ& R, double h);
  void apply_payload_faults(double t);

  model::RobotModel nominal_;
  model::RobotModel truth_model_;
  model::RobotModel controller_model_;
  std::shared_ptr<const Trajectory> traj_;
  PlantTruth truth_;
  SimOptions opt_;
  std::vector<FaultSpec> faults_;
  model::DynamicsData dtruth_, dctrl_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::mt19937_64 torque_rng_;  // the joint torque sensors' noise (its own stream: see SimOptions::joint_torque_sensors)
  std::normal_distribution<double> torque_normal_{0.0, 1.0};
  VectorJ link_torque_;  // the last physics substep's link-side torque, tau - friction - rotor inertia x qdd
  int n_;
  double t_ = 0.0, t_ctrl_ = 0.0;
  long tick_ = 0;
  VectorJ q_, qd_, z_, temp_, q_meas_prev_, current_held_;
  VectorJ kp_, kd_;
  std::uint64_t dout_ = 0;
  bool payload_on_ = false;
  std::vector<bool> fault_applied_;
  std::vector<bool> declaration_applied_;  // a payload pick's declaration (FaultSpec::declare_delay)
  long dropped_left_ = 0;
};

}  // namespace twinwatch::sim
