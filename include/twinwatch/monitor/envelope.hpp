#pragma once
/// @file envelope.hpp
/// Extrapolation watch: a stream compared with the motion its twin was identified on
/// (ident::MotionEnvelope). Beyond it a residual can be the twin's model error rather than a fault,
/// and whoever reads an alert raised there should be told (DESIGN.md: tell the truth, never cry wolf).
#include <deque>
#include <limits>
#include <string>
#include <vector>

#include "twinwatch/core/sample.hpp"
#include "twinwatch/core/types.hpp"
#include "twinwatch/ident/twin_model.hpp"

namespace twinwatch::monitor {

/// How far past the training motion a sample must be to count as outside: a speed above
/// qd_max (1 + speed_fraction) + speed_abs, a position more than `position` beyond [q_min, q_max].
/// The absolute speed margin keeps a joint that hardly moved in training from flagging its noise.
struct EnvelopeMargins {
  double speed_fraction = 0.10;
  double speed_abs = 0.05;  ///< [rad/s]
  double position = 0.10;   ///< [rad]
};

/// One joint outside the envelope at one sample.
struct Excursion {
  int joint = -1;       ///< 0-based; -1: inside
  bool speed = false;   ///< true: |qd| too high; false: q out of range
  double value = 0.0;   ///< |qd| [rad/s] or q [rad]
  double limit = 0.0;   ///< the trained qd_max, or the q_min / q_max crossed
  bool inside() const { return joint < 0; }
  /// "J2 at 1.37 rad/s, identified up to 1.04 rad/s" / "J3 at 2.10 rad, identified on -0.50 to 1.80 rad"
  std::string describe(const ident::MotionEnvelope& e) const;
};

/// Per-sample check, allocation-free; keeps counts and the largest excursion for a summary.
class EnvelopeWatch {
 public:
  explicit EnvelopeWatch(const ident::MotionEnvelope& envelope, EnvelopeMargins margins = {});
  /// False when the twin records no envelope (then check() always says inside).
  bool known() const { return !envelope_.empty(); }
  /// The sample's largest excursion (relative to its margin), or an inside one.
  Excursion check(const RobotSample& s);
  long samples() const { return samples_; }
  long samples_outside() const { return outside_; }
  /// The largest excursion seen so far (inside when none), and when.
  const Excursion& worst() const { return worst_; }
  double worst_time() const { return worst_t_; }
  /// Timestamp of the last sample outside (NaN when none).
  double last_outside_time() const { return last_t_; }
  const ident::MotionEnvelope& envelope() const { return envelope_; }
  /// The largest excursion of the stretches outside that overlap [t0, t1], as far as each had gone
  /// by t1 (inside when none): a stretch that went on growing after t1 is named as it was then, to
  /// within kRecordStep of its score. The last kEpisodes stretches are kept (a stretch ends after
  /// kEpisodeGap s back inside).
  Excursion outside_during(double t0, double t1) const;
  /// What an alert whose exceedance began at t_start and was raised at t_detected adds to its detail
  /// when it was raised where the robot moved beyond the training motion (from kAlertLead s before
  /// t_start, as a filtered residual lags the motion that caused it, to kAlertLag s after the raise;
  /// a long alert is not marked for a later excursion): "; raised where ... (J2 at ...): it may be
  /// model error, not a fault". "" when inside.
  std::string alert_note(double t_start, double t_detected) const;
  /// "N of M samples (x %) beyond the motion the twin was identified on; the farthest: ... at T s";
  /// "" when none was.
  std::string summary() const;
  static constexpr double kAlertLead = 0.5;  ///< [s]
  static constexpr double kAlertLag = 0.1;   ///< [s]
  static constexpr size_t kEpisodes = 1000;
  static constexpr double kEpisodeGap = 0.1;  ///< [s]
  static constexpr double kRecordStep = 0.01;  ///< a stretch's worst is kept when it grows by this fraction

 private:
  // a stretch's worst as it grew: a record each time its score passed the last record by kRecordStep
  // (a joint driven further and further past its range at 500 Hz would add one each sample)
  struct Record {
    double t, score;
    Excursion worst;
  };
  struct Episode {
    double t_begin, t_end, score;
    Excursion worst;
    std::vector<Record> records;
  };
  std::deque<Episode> episodes_;
  ident::MotionEnvelope envelope_;
  EnvelopeMargins margins_;
  long samples_ = 0, outside_ = 0;
  Excursion worst_;
  double worst_score_ = 0.0, worst_t_ = std::numeric_limits<double>::quiet_NaN();
  double last_t_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace twinwatch::monitor
