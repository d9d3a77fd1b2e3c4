#pragma once
/// @file decoupling.hpp
/// Rigid-body decoupling of one joint's measured torque (HESR §III-C..E): the residual torque
///
///   tau_f = tau_meas - Y_b pi_b                                                  (HESR eq. 9)
///
/// with the single-joint rigid-body regressor
///
///   Y_b = [qdd, sin q, cos q, 1]     pi_b = [I, g_s, g_c, c]
///
/// (inertia about the axis, the gravity torque of the moving joint with the other joints at rest
/// as a sin/cos pair, a constant offset). It is exact for a joint that moves while the others
/// stand still (a joint-wise friction experiment, e.g. the Kinova Gen3 joint_2_trapez log) and
/// for the simulated study joints; for coupled multi-joint motion the robot model's base
/// regressor would be needed instead.
///
/// pi_b is estimated by least squares with two HESR rules:
///   - reversal screening: samples with |qd| < threshold are left out of the rigid-body fit only,
///     never out of the residual record (§III-E);
///   - the velocity-odd friction part, which HESR cancels by forward-reverse averaging, is
///     absorbed by nuisance columns [sign(qd), qd] that are estimated with pi_b and then dropped
///     (they are not subtracted: tau_f keeps all the friction).
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "twinwatch/friction/friction_model.hpp"

namespace twinwatch::friction {

/// One joint's measured signals at a uniform sample time.
struct JointRecord {
  double dt = 0.005;        ///< sample time [s], > 0
  std::vector<double> q;    ///< joint position [rad], size n
  std::vector<double> qd;   ///< joint velocity [rad/s], size n
  std::vector<double> tau;  ///< measured (current-based) joint torque [N·m], size n

  /// Throws InvalidArgument naming `what`, the field and the index: dt, sizes, fewer than
  /// `min_samples` samples, a non-finite value.
  void validate(std::string_view what = "record", long min_samples = 5) const;
  long size() const noexcept { return static_cast<long>(q.size()); }
};

/// Joint acceleration [rad/s^2]: central difference of qd, smoothed by a centred moving
/// average of `window` samples (odd, >= 1); one-sided at the ends.
std::vector<double> joint_acceleration(std::span<const double> qd, double dt, int window = 5);

/// Centred moving average of `window` samples (odd, >= 1), shrinking at the ends. Throws
/// InvalidArgument for an even or non-positive window.
std::vector<double> moving_average(std::span<const double> x, int window);

struct RigidBodyFitOptions {
  double reversal_threshold = 0.1;  ///< |qd| below this is screened out of the fit [rad/s], >= 0 (HESR: 0.1)
  bool friction_nuisance = true;    ///< estimate [sign(qd), qd] alongside pi_b (then dropped)
  int acceleration_window = 5;      ///< moving-average window of qdd, odd >= 1
  /// Throws InvalidArgument naming the first field out of range.
  void validate() const;
};

/// The fitted single-joint rigid-body model and the HESR Table III statistics.
struct RigidBodyFit {
  double inertia = 0.0;       ///< I [kg·m^2]
  double gravity_sin = 0.0;   ///< g_s [N·m]
  double gravity_cos = 0.0;   ///< g_c [N·m]
  double offset = 0.0;        ///< c [N·m]
  double coulomb = 0.0;       ///< nuisance sign(qd) coefficient [N·m] (not subtracted)
  double viscous = 0.0;       ///< nuisance qd coefficient [N·m·s/rad] (not subtracted)
  long samples = 0;           ///< retained samples (|qd| >= threshold) over all records
  int rank = 0;               ///< numerical rank of the retained regressor (with nuisance columns)
  int columns = 0;            ///< its number of columns
  double rmse_all = 0.0;      ///< RMSE of the full fitted model (incl. nuisance) over all samples [N·m]
  double rmse_retained = 0.0; ///< the same over the retained samples [N·m]
  double log10_condition = 0.0;  ///< log10 of the 2-norm condition number of the retained regressor
  RigidBodyFitOptions options;

  /// Y_b pi_b per sample of `r` [N·m] (rigid-body part only).
  std::vector<double> torque(const JointRecord& r) const;
  /// tau_f = tau - Y_b pi_b with the record's dt and qd (HESR eq. 9).
  FrictionRecord residual(const JointRecord& r) const;
  /// "tau_rb = I*qdd + g_s*sin(q) + g_c*cos(q) + c" with the values.
  std::string equation() const;
};

/// Fits pi_b on the records together. Throws InvalidArgument on bad records/options or when
/// fewer retained samples than columns remain.
RigidBodyFit fit_rigid_body(std::span<const JointRecord* const> records, const RigidBodyFitOptions& options = {});

}  // namespace twinwatch::friction
