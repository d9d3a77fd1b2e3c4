#pragma once
// Synthetic residual-torque records for the friction tests: a velocity profile, a truth evaluated
// along it, Gaussian torque noise with a printed seed.
#include <cmath>
#include <functional>
#include <numbers>
#include <random>

#include "twinwatch/friction/friction_model.hpp"

namespace twinwatch::friction::testing {

constexpr double kDt = 0.005;  // 200 Hz (HESR §V)

/// qd(t) = v sin(2 pi f t) for `duration` seconds: the HESR training sweep (0.25 Hz, 1.2 rad/s).
inline std::vector<double> sine_velocity(double duration, double f = 0.25, double v = 1.2) {
  const auto n = static_cast<std::size_t>(std::lround(duration / kDt));
  std::vector<double> qd(n);
  for (std::size_t k = 0; k < n; ++k) qd[k] = v * std::sin(2.0 * std::numbers::pi * f * static_cast<double>(k) * kDt);
  return qd;
}

/// Two superposed sines (0.2 and 0.53 Hz): reversals at varying decelerations, unlike the sweep.
inline std::vector<double> two_tone_velocity(double duration) {
  const auto n = static_cast<std::size_t>(std::lround(duration / kDt));
  std::vector<double> qd(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * kDt;
    qd[k] = 0.8 * std::sin(2.0 * std::numbers::pi * 0.2 * t) + 0.5 * std::sin(2.0 * std::numbers::pi * 0.53 * t + 0.7);
  }
  return qd;
}

/// Record with tau = truth(qd) sample by sample (truth may carry state) + N(0, sigma^2) noise.
inline FrictionRecord make_record(const std::vector<double>& qd, const std::function<double(double)>& truth,
                                  double sigma, unsigned seed) {
  FrictionRecord r;
  r.dt = kDt;
  r.qd = qd;
  r.tau.resize(qd.size());
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (std::size_t k = 0; k < qd.size(); ++k) r.tau[k] = truth(qd[k]) + noise(rng);
  return r;
}

/// RMSE of a model's prediction against a record's tau.
inline double rmse_of(FrictionModel& m, const FrictionRecord& r) {
  const std::vector<double> y = m.predict(r);
  double s = 0.0;
  for (std::size_t k = 0; k < y.size(); ++k) s += (y[k] - r.tau[k]) * (y[k] - r.tau[k]);
  return std::sqrt(s / static_cast<double>(y.size()));
}

}  // namespace twinwatch::friction::testing
