#include "twinwatch/monitor/declaration.hpp"

#include <fmt/format.h>

#include <cmath>

namespace twinwatch::monitor {

bool declaration_readable(const RobotSample& s) {
  const double* c = s.payload_cog;
  return std::isfinite(s.payload) && s.payload >= 0.0 && std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]);
}

std::string declaration_refusal(const ident::TwinModel& twin, const RobotSample& s) {
  const double m = s.payload;
  const double* c = s.payload_cog;
  const double cog_distance = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  if (!twin.gains_known()) return "its torques are relative (it was identified without a known payload that fixes its gains)";
  if (!twin.predicts_payload()) return "its prediction does not carry a payload (method '" + twin.method + "')";
  if (m > twin.robot().payload_limit())
    return fmt::format("above {:g} kg ({})", twin.robot().payload_limit(), twin.robot().payload_limit_text());
  if (m > 0.0 && cog_distance > kDeclaredCogMax)
    return fmt::format("its centre of mass is {:.3g} m from the flange, more than {:g} m (a value in mm?)", cog_distance, kDeclaredCogMax);
  return {};
}

model::RigidBodyInertia declared_inertia(const RobotSample& s, const model::RigidBodyInertia& had) {
  model::RigidBodyInertia now;
  if (s.payload > 0.0) {
    now.mass = s.payload;
    now.com = Eigen::Vector3d(s.payload_cog[0], s.payload_cog[1], s.payload_cog[2]);
    if (had.mass == now.mass && had.com == now.com) now.inertia_com = had.inertia_com;
  }
  return now;
}

bool same_payload(const model::RigidBodyInertia& a, const model::RigidBodyInertia& b) {
  return a.mass == b.mass && (a.mass == 0.0 || a.com == b.com);
}

PayloadTimeline::PayloadTimeline(const ident::TwinModel& twin, const HealthyRun& h, bool follow, double period)
    : PayloadTimeline(twin, h.payload, follow && (h.recording->present & kFieldPayload)) {
  const auto& smp = h.recording->samples;
  for (size_t k = 0; k < smp.size(); ++k) see(k, smp[k]);
  finish(smp.size(), h.recording->median_period > 0.0 ? h.recording->median_period : period);
}

PayloadTimeline::PayloadTimeline(const ident::TwinModel& twin, const model::RigidBodyInertia& payload, bool follow)
    : twin_(&twin), follow_(follow), steps_{{0, payload, 0.0}} {}

void PayloadTimeline::see(size_t k, const RobotSample& s) {
  if (k == 0) steps_.front().t = s.timestamp;
  if (!follow_ || !s.has(kFieldPayload)) return;
  if (seen_any_ && s.payload == last_mass_ && std::equal(s.payload_cog, s.payload_cog + 3, last_cog_)) return;
  seen_any_ = true;
  last_mass_ = s.payload;
  std::copy(s.payload_cog, s.payload_cog + 3, last_cog_);
  if (!declaration_readable(s) || !declaration_refusal(*twin_, s).empty()) return;
  const model::RigidBodyInertia now = declared_inertia(s, steps_.back().payload);
  if (same_payload(now, steps_.back().payload)) return;
  if (k == 0) {
    steps_.back().payload = now;  // declared from the start: the run's payload
    return;
  }
  steps_.push_back({k, now, s.timestamp});
}

namespace {
// the samples the current residual settles for after a change, at `period`
size_t settle_samples(double period) { return static_cast<size_t>(std::ceil(kDeclarationSettle / period)); }
}  // namespace

bool PayloadTimeline::judged_seen(size_t k, double period) const {
  const size_t wait = settle_samples(period);
  // the latest change at or before k: the settlings are of one length, so its is the one that ends last
  for (size_t i = steps_.size(); i-- > 1;)
    if (steps_[i].from <= k) return k >= steps_[i].from + wait;
  return true;
}

void PayloadTimeline::finish(size_t samples, double period) {
  judged_.assign(samples, 1);
  judged_observer_.assign(samples, 1);
  const size_t wait = settle_samples(period);
  const size_t observer_wait = std::max(wait, static_cast<size_t>(kObserverSettle));
  for (size_t i = 1; i < steps_.size(); ++i) {
    const size_t k = steps_[i].from;
    std::fill(judged_.begin() + static_cast<long>(k), judged_.begin() + static_cast<long>(std::min(samples, k + wait)), 0);
    std::fill(judged_observer_.begin() + static_cast<long>(k), judged_observer_.begin() + static_cast<long>(std::min(samples, k + observer_wait)), 0);
  }
}

}  // namespace twinwatch::monitor
