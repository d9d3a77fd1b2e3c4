#pragma once
/// @file trajectory.hpp
/// Target trajectories for the virtual robot (and, exported, for a real robot program).
/// All are smooth (C2) so target_qdd exists; cyclic ones repeat with period().
#include <Eigen/Geometry>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "twinwatch/core/types.hpp"
#include "twinwatch/model/robot_model.hpp"

namespace twinwatch::sim {

/// A joint-space target in closed form, which a robot program can evaluate on the controller itself
/// (robot_program.hpp): a sum of K sinusoidal components whose phases are polynomials of degree two,
///   q_j(t) = q0_j + w(u) * sum_k ( s_jk sin(theta_k(u)) + c_jk cos(theta_k(u)) ),
///   theta_k(u) = omega_k u + sweep_k u^2 / 2,   u = t mod wrap (u = t when wrap is infinite),
/// w(u) the raised-cosine fade 0 -> 1 over the first and 1 -> 0 over the last `fade` seconds of each
/// wrap (w = 1 when fade is 0). Fourier series and sines are components of constant pulsation; the
/// linear chirp is one component with its sweep rate, faded, repeating every sweep.
struct ClosedForm {
  VectorJ q0;                    ///< [rad]
  std::vector<double> omega;     ///< pulsation of each component at u = 0 [rad/s]
  std::vector<double> sweep;     ///< d(omega)/du of each component [rad/s²]
  Eigen::MatrixXd s, c;          ///< n_dof x K amplitudes of sin and cos [rad]
  double wrap = std::numeric_limits<double>::infinity();  ///< [s]
  double fade = 0.0;             ///< [s], at most wrap / 2
  int n_dof() const { return static_cast<int>(q0.size()); }
  int components() const { return static_cast<int>(omega.size()); }
  /// Target and its first two time derivatives at t >= 0 (the formula above).
  void evaluate(double t, VectorJ& q, VectorJ& qd, VectorJ& qdd) const;
  /// The same path `factor` times slower: q'(t) = q(t / factor), so velocities divide by factor and
  /// accelerations by its square (omega / f, sweep / f², wrap and fade times f). factor > 0.
  ClosedForm slowed(double factor) const;
};

class Trajectory {
 public:
  virtual ~Trajectory() = default;
  virtual int n_dof() const = 0;
  /// Target position [rad], velocity [rad/s] and acceleration [rad/s²] at time t [s] >= 0.
  virtual void evaluate(double t, VectorJ& q, VectorJ& qd, VectorJ& qdd) const = 0;
  /// Duration of one cycle [s]; evaluation beyond it repeats the cycle.
  virtual double period() const = 0;
  /// The same target as a ClosedForm, for trajectories that have one (Fourier series, sines, the
  /// chirp); nullopt for those computed numerically or piecewise (Cartesian paths through inverse
  /// kinematics, point-to-point and quasi-static segments).
  virtual std::optional<ClosedForm> closed_form() const { return std::nullopt; }
};

/// Finite Fourier series [Cao eq. 21] per joint j, harmonics l = 1..L, base pulsation w_f:
///   q_j(t) = q0_j + sum_l ( a_lj / (l w_f) sin(l w_f t) - b_lj / (l w_f) cos(l w_f t) )
struct FourierCoefficients {
  double w_f = 0.0;         ///< base pulsation [rad/s]
  VectorJ q0;               ///< offsets [rad]
  Eigen::MatrixXd a, b;     ///< n_dof x L
};
std::unique_ptr<Trajectory> make_fourier(const FourierCoefficients& c);
/// Random coefficients scaled so every joint stays inside +-amplitude [rad] around q0 (seeded).
FourierCoefficients random_fourier(const VectorJ& q0, double amplitude, double period, int harmonics, unsigned seed);

/// q_j = q0_j + A_j sin(2 pi f_j t + phi_j)
std::unique_ptr<Trajectory> make_sine(const VectorJ& q0, const VectorJ& amplitude, const VectorJ& frequency,
                                      const VectorJ& phase);

/// Linear chirp from f0 to f1 [Hz] over `sweep` seconds on every joint with amplitude A_j [HESR §V-F].
std::unique_ptr<Trajectory> make_chirp(const VectorJ& q0, const VectorJ& amplitude, double f0, double f1, double sweep);

/// Point-to-point through waypoints with quintic segments (zero velocity and acceleration at each
/// waypoint); segment k takes durations[k] seconds; the cycle returns to the first waypoint.
std::unique_ptr<Trajectory> make_point_to_point(const std::vector<VectorJ>& waypoints, const std::vector<double>& durations);

/// Bidirectional quasi-static poses [Cao eq. 12-14]: each pose is approached slowly from below and
/// from above (offset delta [rad], creep speed [rad/s]) and held for `hold` seconds each time.
std::unique_ptr<Trajectory> make_quasi_static(const std::vector<VectorJ>& poses, double delta, double creep_speed,
                                              double hold);

/// Cartesian paths of the flange position (orientation held at the start pose), through numerical
/// inverse kinematics (damped least squares) sampled every `ik_step` seconds and interpolated.
/// Figure-eight [UR3e §3.4]: a lemniscate of half-widths (ax, ay) [m] in the horizontal plane around
/// the flange position at `start`, one loop per `period` seconds. `tilt` [rad] rocks the tool
/// about its own x, y, z axes (amplitudes, at the loop frequency) so that the wrist joints move too.
std::unique_ptr<Trajectory> make_figure_eight(const model::RobotModel& model, const VectorJ& start, double ax, double ay,
                                              double period, const Eigen::Vector3d& tilt = Eigen::Vector3d::Zero(),
                                              double ik_step = 0.002);
/// Triangle [Cao validation]: an equilateral triangle of side `side` [m] in the horizontal plane,
/// each edge a quintic whose peak speed is `speed` [m/s].
std::unique_ptr<Trajectory> make_triangle(const model::RobotModel& model, const VectorJ& start, double side, double speed,
                                          double ik_step = 0.002);

/// The first place where the target leaves the robot's joint position range or exceeds its velocity
/// or (where the description publishes one, as the Panda's) acceleration limit, as the controller
/// would command it: sampled at t = k / rate [s, Hz] over the run of
/// `duration` [s], or over one period when the run is longer (the trajectory repeats). Returns the
/// violation as text, e.g. "joint 2 target velocity reaches 4.1 rad/s at t = 1.25 s, beyond its limit
/// of 3.14159 rad/s (ur3e)", or "" when the target stays inside. Limits the description does not
/// publish (infinite) are not checked; a NaN target always is a violation. Throws InvalidArgument if
/// the trajectory and the model have different numbers of joints.
std::string joint_limit_violation(const Trajectory& trajectory, const model::RobotModel& model, double duration, double rate);

/// Damped-least-squares IK for a flange pose, from `seed`. Returns false if not converged.
bool inverse_kinematics(const model::RobotModel& model, const Eigen::Isometry3d& target, const VectorJ& seed, VectorJ& q);

}  // namespace twinwatch::sim
