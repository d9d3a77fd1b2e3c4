#include "twinwatch/friction/hysteresis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::friction {

void HysteresisParams::validate() const {
  if (!std::isfinite(alpha) || alpha <= 0.0)
    throw InvalidArgument(fmt::format("hysteresis alpha is {}, must be > 0", alpha));
  if (!std::isfinite(beta) || beta <= 0.0)
    throw InvalidArgument(fmt::format("hysteresis beta is {}, must be > 0", beta));
}

const char* to_string(HysteresisDrive d) noexcept {
  return d == HysteresisDrive::Time ? "time" : "displacement";
}

bool HysteresisParams::stable(double dt) const noexcept {
  if (drive == HysteresisDrive::Displacement) return dt > 0.0;
  const double decay = 1.0 - alpha * dt;
  return dt > 0.0 && decay > 0.0 && decay < 1.0;
}

HysteresisState::HysteresisState(HysteresisParams params, double dt, double h0)
    : params_(params), dt_(dt), decay_(1.0 - params.alpha * dt), alpha_dt_(params.alpha * dt) {
  params_.validate();
  if (!std::isfinite(dt) || dt <= 0.0)
    throw InvalidArgument(fmt::format("sample time dt is {}, must be > 0", dt));
  if (params_.drive == HysteresisDrive::Time && !params_.stable(dt))
    throw InvalidArgument(fmt::format(
        "hysteresis alpha*dt is {} (alpha {}, dt {}), must be in (0, 1) for a stable eq. 11",
        alpha_dt_, params_.alpha, dt));
  if (!(std::abs(h0) <= 1.0))
    throw InvalidArgument(fmt::format("initial hysteresis state h0 is {}, must be in [-1, 1]", h0));
  h_ = h0;
}

void HysteresisState::reset(double h0) noexcept { h_ = std::clamp(h0, -1.0, 1.0); }

double HysteresisState::fast_tanh(double x) noexcept {
  // beyond |x| = 20, tanh(x) = +-1 to double precision: skip the exp
  constexpr double kSaturate = 20.0;
  if (x > kSaturate) return 1.0;
  if (x < -kSaturate) return -1.0;
  return std::tanh(x);
}

HysteresisFeatures hysteresis_features(std::span<const double> qd, double dt,
                                       const HysteresisParams& params) {
  HysteresisState state(params, dt);
  HysteresisFeatures out;
  out.h.resize(qd.size());
  out.hd.resize(qd.size());
  // run eq. 11 sample by sample
  for (std::size_t k = 0; k < qd.size(); ++k) {
    const HysteresisSample s = state.step(qd[k]);
    out.h[k] = s.h;
    out.hd[k] = s.hd;
  }
  return out;
}

}  // namespace twinwatch::friction
