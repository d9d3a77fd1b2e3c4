#pragma once
/// @file rigid_body_ls.hpp
/// Rigid-body + joint-friction identification in the TORQUE domain (robots with joint torque
/// sensors, or a controller's current-derived torque), by linear least squares on the base
/// parameters [Gautier1990, Swevers1997, HESR §III-B..E]:
///
///   tau_j = Y_b,j(q, qd, qdd) beta + Fc_j sign(qd_j) + Fv_j qd_j + off_j
///
/// - qdd: zero-phase local polynomial derivative of qd on the recorded (possibly irregular) time
///   axis (a Savitzky-Golay filter that uses the true sample times).
/// - Reversal screen [HESR §III-E]: rows with |qd_j| < reversal_screen are left out of the
///   rigid-body fit only; the friction parameters are then re-estimated per joint on every row
///   (rigid body fixed), so the low-velocity data still shape the friction model.
/// - OLS, or weighted LS with per-joint weights 1 / sigma_j, sigma_j² the joint's residual
///   variance, iterated [Gautier1990].
/// - Forward/reverse averaging [HESR §III-C]: when a run is paired with the same trajectory played
///   backwards in time (q-(t) = q+(T - t)), the two torques at the same pose are averaged; the
///   odd friction terms cancel (the rigid-body terms are even in qd) and the averaged rows identify
///   beta and the offsets free of Coulomb/viscous friction.
/// - Parameter standard deviations sigma_i = sqrt(s² (W^T W)^-1_ii) with s² = |r|² / (rows - p)
///   on the (weighted) system, and relative std % = 100 sigma_i / |theta_i|.
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "twinwatch/device/recording.hpp"
#include "twinwatch/model/regressor.hpp"
#include "twinwatch/signal/metrics.hpp"

namespace twinwatch::ident {

/// Which recorded signal is the joint torque.
enum class TorqueSignal {
  JointTorque,      ///< actual_joint_torque_* (joint torque sensors)
  CurrentAsTorque,  ///< actual_current_as_torque_* (current-derived torque)
  TargetMoment,     ///< target_moment_* (the controller's commanded torque)
};
/// "joint_torque", "current_as_torque", "target_moment".
const char* to_string(TorqueSignal s);
/// Inverse of to_string(); throws InvalidArgument listing the names.
TorqueSignal torque_signal_from_string(const std::string& s);

struct RigidBodyLsOptions {
  TorqueSignal signal = TorqueSignal::JointTorque;
  double reversal_screen = 0.1;  ///< [rad/s] rows below are left out of the rigid-body fit (0: keep all)
  bool weighted = true;          ///< weighted LS (else OLS)
  int weight_iterations = 3;     ///< re-weightings after the OLS start
  bool refit_friction = true;    ///< re-estimate friction on all rows with the rigid body fixed
  int derivative_half_window = 15;  ///< [samples] half window of the local polynomial for qdd (and qd smoothing)
  int derivative_order = 2;      ///< polynomial order of that fit (>= 1)
  int decimate = 1;              ///< use every k-th sample (after differentiation)
  void validate() const;
};

/// A part of a recording: [from, to) as fractions of its duration (0..1).
struct Segment {
  const device::Recording* recording = nullptr;
  double from = 0.0, to = 1.0;
  /// Optional: the same trajectory played backwards in time (forward/reverse averaging).
  const device::Recording* reverse = nullptr;
};

/// The identified torque model.
struct RigidBodyModel {
  std::string robot;                  ///< description name or path the regressor came from
  TorqueSignal signal = TorqueSignal::JointTorque;
  std::vector<int> base_columns;      ///< standard-parameter columns kept (regressor order, rigid body only)
  Eigen::VectorXd beta, beta_std;     ///< base parameters and their standard deviations
  Eigen::MatrixXd friction, friction_std;  ///< n_dof x 3: [Fc, Fv, offset] and standard deviations
  /// n_dof x 2: Fc, Fv held at 0 by the friction re-fit (the free fit made them negative)
  Eigen::Array<bool, Eigen::Dynamic, 2> friction_held;
  std::vector<double> sigma;          ///< per-joint residual std of the fit [N·m]
  std::vector<long> rows_rigid;       ///< per-joint rows used by the rigid-body fit (after the screen)
  std::vector<long> rows_friction;    ///< per-joint rows used for friction
  double cond = 0.0;                  ///< condition number of the (weighted, column-scaled) rigid-body fit
  bool averaged = false;              ///< forward/reverse averaging was used
  int derivative_half_window = 15, derivative_order = 2;

  /// Predicted joint torque [N·m] at one state.
  VectorJ predict(const model::RobotModel& model, model::DynamicsData& data, const VectorJ& q, const VectorJ& qd,
                  const VectorJ& qdd) const;
  /// JSON text (save) and back (load). from_json checks every field's type and range, each base
  /// column against the robot's n_dof joints (10 standard parameters each; 0: as many joints as the
  /// friction rows), and throws ParseError naming the file and field.
  std::string to_json() const;
  static RigidBodyModel from_json(const std::string& text, const std::string& origin, int n_dof = 0);
};

/// Identifies the model from segments of recordings. Throws InvalidArgument when the data cannot
/// support it (missing torque or velocity columns, joint count mismatch, too few rows).
RigidBodyModel identify_rigid_body(const model::RobotModel& model, const std::string& robot,
                                   const std::vector<Segment>& segments, const RigidBodyLsOptions& options,
                                   const std::function<void(double)>& progress = {});

/// States and measured torques of a segment, as the identification sees them: qd smoothed and qdd
/// differentiated by the local polynomial (zero phase) on the true time axis.
struct TorqueData {
  std::vector<double> t;
  std::vector<VectorJ> q, qd, qdd, tau;
};
TorqueData torque_data(const Segment& segment, TorqueSignal signal, int half_window, int order);

/// Zero-phase local polynomial fit of x(t) on a possibly irregular time axis: value (deriv 0) or
/// first derivative (deriv 1) at every sample, from the `order` polynomial fitted over the
/// 2 half_window + 1 samples centred on it (shifted inside at the ends, as scipy's mode='interp').
/// For uniform t it equals Savitzky-Golay [Savitzky1964]. Throws InvalidArgument on sizes.
std::vector<double> local_polynomial(const std::vector<double>& t, const std::vector<double>& x, int half_window, int order,
                                     int deriv);

/// Per-joint fit metrics (RMSE, d_tau %, ...) of a predictor on a segment's data;
/// `predict(k)` returns the predicted torque at sample k of `data`.
std::vector<signal::FitMetrics> torque_metrics(const TorqueData& data, const std::function<VectorJ(size_t)>& predict);

}  // namespace twinwatch::ident
