#include "twinwatch/friction/maxwell_slip.hpp"

#include <fmt/format.h>

#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::friction {

namespace {
void require_positive(const char* field, double v, const char* unit) {
  if (!std::isfinite(v) || v <= 0.0)
    throw InvalidArgument(fmt::format("Maxwell-slip {} is {}, must be > 0 [{}]", field, v, unit));
}
}  // namespace

void MaxwellSlipParams::validate() const {
  if (elements.empty()) throw InvalidArgument("Maxwell-slip elements is empty, expected at least 1 element");
  double sum = 0.0;
  for (std::size_t i = 0; i < elements.size(); ++i) {
    const MaxwellSlipElement& e = elements[i];
    if (!std::isfinite(e.stiffness) || e.stiffness <= 0.0)
      throw InvalidArgument(
          fmt::format("Maxwell-slip elements[{}].stiffness is {}, must be > 0 [N·m/rad]", i, e.stiffness));
    if (!std::isfinite(e.weight) || e.weight <= 0.0)
      throw InvalidArgument(fmt::format("Maxwell-slip elements[{}].weight is {}, must be > 0", i, e.weight));
    sum += e.weight;
  }
  constexpr double kWeightSumTolerance = 1e-9;
  if (std::abs(sum - 1.0) > kWeightSumTolerance)
    throw InvalidArgument(fmt::format("Maxwell-slip element weights sum to {:.12g}, expected 1", sum));
  require_positive("Fc", Fc, "N·m");
  require_positive("Fs", Fs, "N·m");
  require_positive("vs", vs, "rad/s");
  require_positive("delta", delta, "-");
  if (!std::isfinite(sigma2) || sigma2 < 0.0)
    throw InvalidArgument(fmt::format("Maxwell-slip sigma2 is {}, must be >= 0 [N·m·s/rad]", sigma2));
  if (!std::isfinite(lag_time) || lag_time < 0.0)
    throw InvalidArgument(fmt::format("Maxwell-slip lag_time is {}, must be >= 0 [s]", lag_time));
}

double MaxwellSlipParams::breakaway_displacement(int i) const {
  const MaxwellSlipElement& e = elements.at(static_cast<std::size_t>(i));
  return 2.0 * e.weight * Fc / e.stiffness;
}

MaxwellSlipFriction::MaxwellSlipFriction(MaxwellSlipParams params) : params_(std::move(params)) {
  params_.validate();
  force_.assign(params_.elements.size(), 0.0);
  slip_dir_.assign(params_.elements.size(), 0);
}

void MaxwellSlipFriction::reset() noexcept {
  std::fill(force_.begin(), force_.end(), 0.0);
  std::fill(slip_dir_.begin(), slip_dir_.end(), 0);
}

double MaxwellSlipFriction::stribeck(double v) const noexcept {
  return params_.Fc + (params_.Fs - params_.Fc) * std::exp(-std::pow(std::abs(v / params_.vs), params_.delta));
}

double MaxwellSlipFriction::step(double v, double h) noexcept {
  const double s = stribeck(v);
  const int dir = v > 0.0 ? 1 : (v < 0.0 ? -1 : 0);
  // frictional lag of slipping elements: exact relaxation over h
  const double relax = params_.lag_time > 0.0 ? std::exp(-h / params_.lag_time) : 0.0;
  for (std::size_t i = 0; i < force_.size(); ++i) {
    const double cap = params_.elements[i].weight * s;
    double& F = force_[i];
    // a slipping element sticks again when the velocity reverses (or stops)
    if (slip_dir_[i] != 0 && slip_dir_[i] != dir) slip_dir_[i] = 0;
    if (slip_dir_[i] == 0) {
      // sticking: the element spring is deformed; it breaks away at its share of s(v)
      F += params_.elements[i].stiffness * v * h;
      if (dir != 0 && F * dir >= cap) {
        F = dir * cap;
        slip_dir_[i] = static_cast<signed char>(dir);
      }
    } else {
      // slipping: lagged tracking of its share of the Stribeck curve
      const double target = dir * cap;
      F = target + (F - target) * relax;
    }
  }
  return torque(v);
}

double MaxwellSlipFriction::torque(double v) const noexcept {
  double tau = params_.sigma2 * v;
  for (double F : force_) tau += F;
  return tau;
}

}  // namespace twinwatch::friction
