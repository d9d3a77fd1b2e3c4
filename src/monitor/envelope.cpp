#include "twinwatch/monitor/envelope.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>

namespace twinwatch::monitor {

std::string Excursion::describe(const ident::MotionEnvelope& e) const {
  if (inside()) return "inside the motion the twin was identified on";
  const auto j = static_cast<Eigen::Index>(joint);
  if (speed) return fmt::format("J{} at {:.2f} rad/s, identified up to {:.2f} rad/s", joint + 1, value, e.qd_max[j]);
  return fmt::format("J{} at {:.2f} rad, identified on {:.2f} to {:.2f} rad", joint + 1, value, e.q_min[j], e.q_max[j]);
}

EnvelopeWatch::EnvelopeWatch(const ident::MotionEnvelope& envelope, EnvelopeMargins margins)
    : envelope_(envelope), margins_(margins) {}

Excursion EnvelopeWatch::check(const RobotSample& s) {
  ++samples_;
  Excursion out;
  if (!known()) return out;
  // score: how far past the margin, in units of the margin's own size (speed: of the allowed
  // speed; position: of the position margin), so that speed and position compare
  double best = 0.0;
  const int n = static_cast<int>(std::min<Eigen::Index>(envelope_.qd_max.size(), s.qd.size()));
  for (int j = 0; j < n; ++j) {
    const double allowed = envelope_.qd_max[j] * (1.0 + margins_.speed_fraction) + margins_.speed_abs;
    const double v = std::abs(s.qd[j]);
    if (v > allowed && (v - allowed) / allowed > best) {
      best = (v - allowed) / allowed;
      out = Excursion{j, true, v, envelope_.qd_max[j]};
    }
    const double q = s.q[j];
    const double below = envelope_.q_min[j] - margins_.position - q, above = q - envelope_.q_max[j] - margins_.position;
    const double over = std::max(below, above);
    if (over > 0.0 && over / margins_.position > best) {
      best = over / margins_.position;
      out = Excursion{j, false, q, below > above ? envelope_.q_min[j] : envelope_.q_max[j]};
    }
  }
  if (out.inside()) return out;
  ++outside_;
  if (episodes_.empty() || !(s.timestamp - episodes_.back().t_end <= kEpisodeGap)) {
    if (episodes_.size() == kEpisodes) episodes_.pop_front();
    episodes_.push_back(Episode{s.timestamp, s.timestamp, best, out, {Record{s.timestamp, best, out}}});
  } else {
    Episode& e = episodes_.back();
    e.t_end = s.timestamp;
    if (best > e.score) {
      e.score = best;
      e.worst = out;
      if (best > e.records.back().score * (1.0 + kRecordStep)) e.records.push_back(Record{s.timestamp, best, out});
    }
  }
  last_t_ = s.timestamp;
  if (best > worst_score_) {
    worst_score_ = best;
    worst_ = out;
    worst_t_ = s.timestamp;
  }
  return out;
}

Excursion EnvelopeWatch::outside_during(double t0, double t1) const {
  Excursion out;
  double best = 0.0;
  for (const Episode& e : episodes_) {
    if (e.t_end < t0 || e.t_begin > t1) continue;
    // as far as it had gone by t1: all of it when it ended by then, else its last record by t1
    double score = e.score;
    const Excursion* worst = &e.worst;
    if (e.t_end > t1) {
      const auto after = std::upper_bound(e.records.begin(), e.records.end(), t1, [](double t, const Record& r) { return t < r.t; });
      score = std::prev(after)->score;  // (the first record is the stretch's first sample, at or before t1)
      worst = &std::prev(after)->worst;
    }
    if (score > best) {
      best = score;
      out = *worst;
    }
  }
  return out;
}

std::string EnvelopeWatch::alert_note(double t_start, double t_detected) const {
  const Excursion x = outside_during(t_start - kAlertLead, t_detected + kAlertLag);
  if (x.inside()) return "";
  return fmt::format("; raised where the robot moves beyond what the twin was identified on ({}): it may be model error, not a fault",
                     x.describe(envelope_));
}

std::string EnvelopeWatch::summary() const {
  if (outside_ == 0) return "";
  return fmt::format("{} of {} samples ({:.1f} %) beyond the motion the twin was identified on; the farthest: {} at {:.3f} s", outside_,
                     samples_, 100.0 * static_cast<double>(outside_) / static_cast<double>(samples_), worst_.describe(envelope_),
                     worst_t_);
}

}  // namespace twinwatch::monitor
