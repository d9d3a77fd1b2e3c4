#pragma once
/// @file friction_model.hpp
/// The common face of every residual-torque (friction) model of [HESR]: the physical baselines
/// (Stribeck, LuGre), the neural baselines (RBFNN, RBFNN-H) and the symbolic models (ParFam-V,
/// ParFam-H). All are fitted on the same record (HESR §V-B: same preprocessing for every model)
/// and evaluated sample by sample, because several carry an internal state (LuGre's bristle z,
/// the hysteresis state h of HESR eq. 11).
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace twinwatch::friction {

/// One residual-torque record at a uniform sample time (HESR Table II, "symbolic identification"
/// layer: t, qd, tau_f; h and hd are derived from qd by each model that needs them).
struct FrictionRecord {
  double dt = 0.005;        ///< sample time [s] (HESR: 200 Hz)
  std::vector<double> qd;   ///< measured joint velocity [rad/s], size n
  std::vector<double> tau;  ///< residual torque tau_f = tau_meas - Y_b pi_b [N·m], size n

  /// Throws InvalidArgument naming `what` and the field: dt not finite and > 0, qd and tau of
  /// different sizes, fewer than `min_samples` samples, a non-finite value (with its index).
  void validate(std::string_view what = "record", long min_samples = 2) const;
  long size() const noexcept { return static_cast<long>(qd.size()); }
};

/// How a fit ended (an expected outcome, returned rather than thrown: STYLE.md "Errors" 3).
enum class FitStatus {
  Converged,       ///< the local solver met its tolerance
  BudgetExhausted, ///< iteration/evaluation limit reached; the parameters are the best found
  Failed,          ///< no usable parameters (the model is left unfitted)
};

/// Lower-case name of a status ("converged", "budget_exhausted", "failed").
std::string_view to_string(FitStatus status) noexcept;

/// What a fit did, in the spirit of ceres::Solver::Summary.
struct FitSummary {
  FitStatus status = FitStatus::Failed;
  std::string message;          ///< one line: solver, reason
  double rmse = 0.0;            ///< training RMSE [N·m]
  long evaluations = 0;         ///< objective evaluations (all stages)
  double seconds = 0.0;         ///< wall time of the fit [s]
  /// One line: "<status>: rmse X N·m, N evaluations, T s (<message>)".
  std::string brief_report() const;
};

/// A residual-torque model: fit once, then evaluate one sample at a time.
///
/// Usage: `fit(train)`, then `start(dt)` and `step(qd_k)` for k = 0, 1, ... of a new record, or
/// `predict(record)` for a whole record. Evaluation never throws and never allocates.
class FrictionModel {
 public:
  virtual ~FrictionModel() = default;

  /// Short model name as in HESR Table VIII ("LuGre", "Stribeck", "RBFNN", "RBFNN-H",
  /// "ParFam-V", "ParFam-H").
  virtual std::string_view name() const noexcept = 0;

  /// Fits the model to `record` (validated). Throws InvalidArgument on a bad record or bad
  /// options; a fit that merely does not converge is reported in the summary.
  virtual FitSummary fit(const FrictionRecord& record) = 0;

  /// True once a fit produced usable parameters.
  virtual bool fitted() const noexcept = 0;

  /// Resets the internal state for a new record sampled every dt [s]. Throws InvalidArgument
  /// when the model is not fitted or dt is not valid for it (e.g. the stability condition of
  /// HESR eq. 11 fails at this dt).
  virtual void start(double dt) = 0;

  /// Predicted residual torque [N·m] at the next sample with measured velocity qd [rad/s];
  /// advances the internal state by one sample. O(1), real-time safe.
  virtual double step(double qd) noexcept = 0;

  /// Readable model equation with its fitted coefficients (HESR Table VII style).
  virtual std::string equation() const = 0;

  /// start(dt), then step() over every qd. Throws as start().
  std::vector<double> predict(std::span<const double> qd, double dt);
  /// predict(record.qd, record.dt).
  std::vector<double> predict(const FrictionRecord& record) { return predict(record.qd, record.dt); }
};

}  // namespace twinwatch::friction
