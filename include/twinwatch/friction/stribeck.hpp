#pragma once
/// @file stribeck.hpp
/// Static Stribeck friction, the velocity-only physical baseline of [HESR] §V-C (Table VIII):
///
///   tau_f = sgn(qd) * g(qd) + sigma2 * qd + offset,
///   g(qd) = Fc + (Fs - Fc) * exp(-(qd / vs)^2)                                     (HESR eq. 3)
///
/// fitted, as in the paper, by a bounded global search on the mean-square error (eq. 18; NLopt's
/// controlled random search [Kaelo2006] instead of the paper's GA) refined by local
/// least squares (Levenberg-Marquardt, Ceres).
#include "twinwatch/friction/friction_model.hpp"

namespace twinwatch::friction {

/// Budget of the global + local fit shared by the physical baselines (Stribeck, LuGre).
struct ParametricFitOptions {
  int global_evaluations = 3000;  ///< NLopt GN_CRS2_LM objective evaluations, >= 10
  int local_iterations = 100;     ///< Ceres Levenberg-Marquardt iterations per start, >= 1
  int local_starts = 4;           ///< further LM starts drawn in the box, besides the global optimum, >= 0
  unsigned seed = 1;              ///< seeds the random search (deterministic fits)
  /// Throws InvalidArgument naming the first field out of range.
  void validate() const;
};

/// Parameters of the Stribeck model. Units: torques [N·m], velocities [rad/s].
struct StribeckParams {
  double Fc = 0.0;      ///< Coulomb friction [N·m], >= 0
  double Fs = 0.0;      ///< static (break-away) friction [N·m], >= 0
  double vs = 0.05;     ///< Stribeck velocity [rad/s], > 0
  double sigma2 = 0.0;  ///< viscous coefficient [N·m·s/rad], >= 0
  double offset = 0.0;  ///< constant residual [N·m] (any sign)
  /// Throws InvalidArgument naming the first invalid field and its value.
  void validate() const;
};

/// The Stribeck baseline.
class StribeckModel final : public FrictionModel {
 public:
  /// An unfitted model; fit() uses `options` (validated here).
  explicit StribeckModel(ParametricFitOptions options = {});
  /// A model with fixed parameters (validated), ready to evaluate.
  explicit StribeckModel(const StribeckParams& params);

  /// tau_f at velocity qd [rad/s] (HESR eq. 3 with sign and viscous term).
  static double evaluate(const StribeckParams& p, double qd) noexcept;

  std::string_view name() const noexcept override { return "Stribeck"; }
  FitSummary fit(const FrictionRecord& record) override;
  bool fitted() const noexcept override { return fitted_; }
  void start(double dt) override;
  double step(double qd) noexcept override { return evaluate(params_, qd); }
  std::string equation() const override;

  const StribeckParams& params() const noexcept { return params_; }

 private:
  ParametricFitOptions options_;
  StribeckParams params_;
  bool fitted_ = false;
};

}  // namespace twinwatch::friction
