#pragma once
/// @file parfam_stage3.hpp
/// Private: the Stage 3 cost of ParFam-H (HESR eq. 16), exposed to the tests for a
/// finite-difference check of its Jacobian.
#include <ceres/ceres.h>

#include <cmath>
#include <vector>

#include "parfam_family.hpp"
#include "twinwatch/friction/hysteresis.hpp"

namespace twinwatch::friction::detail {

/// Stage 3 (HESR eq. 16): residuals y_k - f(x_k(alpha, beta)) with the Jacobian through the h
/// recursion of eq. 11. Parameter blocks: (ln alpha, ln beta) and the active coefficients.
///
///   dh_k/dalpha = (1 - alpha dt) dh_{k-1}/dalpha + dt (T_k - h_{k-1}),   T_k = tanh(beta qd_k)
///   dh_k/dbeta  = (1 - alpha dt) dh_{k-1}/dbeta + alpha dt qd_k (1 - T_k^2)
///   hd_k = alpha (T_k - h_k):  dhd/dalpha = T_k - h_k - alpha dh_k/dalpha,
///                              dhd/dbeta  = alpha (qd_k (1 - T_k^2) - dh_k/dbeta)
///
/// and for the displacement clock (hysteresis.hpp), E_k = exp(-alpha |qd_k| dt):
///
///   h_k = T_k + (h_{k-1} - T_k) E_k
///   dh_k/dalpha = E_k dh_{k-1}/dalpha - |qd_k| dt (h_{k-1} - T_k) E_k
///   dh_k/dbeta  = E_k dh_{k-1}/dbeta + (1 - E_k) qd_k (1 - T_k^2)
///   hd_k = alpha |qd_k| (T_k - h_k): dhd/dalpha = |qd_k| (T_k - h_k) - alpha |qd_k| dh_k/dalpha,
///                                     dhd/dbeta  = alpha |qd_k| (qd_k (1 - T_k^2) - dh_k/dbeta)
class Stage3Cost final : public ceres::CostFunction {
 public:
  Stage3Cost(const std::vector<double>& qd, double dt, const double* sx, const std::vector<double>& y, Layout L,
             const UnaryOp* ops, bool rational, double floor, std::vector<double> theta, std::vector<int> active,
             HysteresisDrive drive = HysteresisDrive::Time)
      : qd_(qd), dt_(dt), drive_(drive), y_(y), L_(L), ops_(ops), rational_(rational), floor_(floor), theta_(std::move(theta)),
        active_(std::move(active)) {
    for (int i = 0; i < 3; ++i) inv_sx_[i] = 1.0 / sx[i];
    set_num_residuals(static_cast<int>(qd.size()));
    mutable_parameter_block_sizes()->push_back(2);
    mutable_parameter_block_sizes()->push_back(static_cast<int>(active_.size()));
  }

  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    const double alpha = std::exp(p[0][0]), beta = std::exp(p[0][1]);
    const bool time = drive_ == HysteresisDrive::Time;
    const double decay = 1.0 - alpha * dt_;
    if (time && !(decay > 0.0 && decay < 1.0)) return false;  // outside the stability region of eq. 11
    std::vector<double> th = theta_;
    const auto m = active_.size();
    for (std::size_t a = 0; a < m; ++a) th[static_cast<std::size_t>(active_[a])] = p[1][a];
    std::vector<double> grad(th.size());
    double h = 0.0, dha = 0.0, dhb = 0.0;
    Cache cache;
    for (std::size_t k = 0; k < qd_.size(); ++k) {
      // eq. 11 and its sensitivities
      const double v = qd_[k];
      const double T = HysteresisState::fast_tanh(beta * v), sech2 = 1.0 - T * T;
      double hd = 0.0, dhda = 0.0, dhdb = 0.0;
      if (time) {
        dha = decay * dha + dt_ * (T - h);
        dhb = decay * dhb + alpha * dt_ * v * sech2;
        h = decay * h + alpha * dt_ * T;
        hd = alpha * (T - h);
        dhda = T - h - alpha * dha;
        dhdb = alpha * (v * sech2 - dhb);
      } else {
        const double av = std::abs(v), E = std::exp(-alpha * av * dt_);
        dha = E * dha - av * dt_ * (h - T) * E;
        dhb = E * dhb + (1.0 - E) * v * sech2;
        h = T + (h - T) * E;
        hd = alpha * av * (T - h);
        dhda = av * (T - h) - alpha * av * dha;
        dhdb = alpha * av * (v * sech2 - dhb);
      }
      // residual
      const double x[3] = {v * inv_sx_[0], h * inv_sx_[1], hd * inv_sx_[2]};
      residuals[k] = y_[k] - detail::forward(L_, ops_, th.data(), x, rational_, floor_, cache);
      if (!jacobians) continue;
      // reverse pass with seed -1: grad = dr/dtheta, gx = dr/dx
      double gx[3] = {0.0, 0.0, 0.0};
      std::fill(grad.begin(), grad.end(), 0.0);
      detail::backward(L_, th.data(), x, rational_, cache, -1.0, grad.data(), gx);
      if (jacobians[0]) {
        // chain through h, hd and the logarithmic parameters
        jacobians[0][2 * k] = alpha * (gx[1] * inv_sx_[1] * dha + gx[2] * inv_sx_[2] * dhda);
        jacobians[0][2 * k + 1] = beta * (gx[1] * inv_sx_[1] * dhb + gx[2] * inv_sx_[2] * dhdb);
      }
      if (jacobians[1])
        for (std::size_t a = 0; a < m; ++a) jacobians[1][k * m + a] = grad[static_cast<std::size_t>(active_[a])];
    }
    return true;
  }

 private:
  const std::vector<double>& qd_;
  double dt_;
  HysteresisDrive drive_;
  const std::vector<double>& y_;
  Layout L_;
  const UnaryOp* ops_;
  bool rational_;
  double floor_;
  std::vector<double> theta_;
  std::vector<int> active_;
  double inv_sx_[3] = {1.0, 1.0, 1.0};
};

}  // namespace twinwatch::friction::detail
