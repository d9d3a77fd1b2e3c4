#pragma once
/// @file lugre.hpp
/// The LuGre dynamic friction model [Canudas1995], the memory-carrying physical baseline of
/// [HESR] (eq. 1-3):
///
///   tau_f = sigma0 * z + sigma1 * zd + sigma2 * qd + offset                          (eq. 1)
///   zd    = qd - sigma0 * |qd| / g(qd) * z                                            (eq. 2)
///   g(qd) = Fc + (Fs - Fc) * exp(-(qd / vs)^2)                                       (eq. 3)
///
/// The bristle state z is simulated along the record: with qd held over a sample, eq. 2 is linear
/// in z and is advanced exactly,
///
///   a = sigma0 |qd| / g,   z_ss = qd / a,   z_k = z_ss + (z_{k-1} - z_ss) * exp(-a dt),
///
/// which stays stable for any stiffness sigma0 (an explicit Euler step would need a dt < 2).
/// zd_k is eq. 2 evaluated at z_k. z starts at 0. Fitted like the Stribeck model (global random
/// search, then Levenberg-Marquardt through the simulated state with automatic derivatives).
#include "twinwatch/friction/friction_model.hpp"
#include "twinwatch/friction/stribeck.hpp"

namespace twinwatch::friction {

/// Parameters of the LuGre model.
struct LugreParams {
  double sigma0 = 1e4;  ///< bristle stiffness [N·m/rad], > 0
  double sigma1 = 0.0;  ///< micro-damping [N·m·s/rad], >= 0
  double sigma2 = 0.0;  ///< viscous coefficient [N·m·s/rad], >= 0
  double Fc = 0.0;      ///< Coulomb friction [N·m], > 0
  double Fs = 0.0;      ///< static friction [N·m], > 0
  double vs = 0.05;     ///< Stribeck velocity [rad/s], > 0
  double offset = 0.0;  ///< constant residual [N·m]
  /// Throws InvalidArgument naming the first invalid field and its value.
  void validate() const;
};

/// The LuGre baseline.
class LugreModel final : public FrictionModel {
 public:
  explicit LugreModel(ParametricFitOptions options = {});
  /// Fixed parameters (validated), ready to evaluate after start().
  explicit LugreModel(const LugreParams& params);

  std::string_view name() const noexcept override { return "LuGre"; }
  FitSummary fit(const FrictionRecord& record) override;
  bool fitted() const noexcept override { return fitted_; }
  void start(double dt) override;
  double step(double qd) noexcept override;
  std::string equation() const override;

  const LugreParams& params() const noexcept { return params_; }
  /// Bristle state z [rad] after the last step.
  double z() const noexcept { return z_; }

 private:
  ParametricFitOptions options_;
  LugreParams params_;
  bool fitted_ = false;
  double dt_ = 0.0;
  double z_ = 0.0;
};

}  // namespace twinwatch::friction
