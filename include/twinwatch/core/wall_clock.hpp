#pragma once
/// @file wall_clock.hpp
/// Wall-clock time for a stream that carries only its controller's clock (a UR controller counts
/// from its boot): ISO 8601 text, and the offset between the two clocks read live.
#include <limits>
#include <string>

namespace twinwatch {

/// Unix time [s] as ISO 8601 UTC with milliseconds: "2026-12-03T19:02:11.234Z".
std::string iso_utc(double unix_s);

/// Parses an ISO 8601 date and time with its zone: "2026-12-03T08:00:00Z",
/// "2026-12-03 08:00:00.5+01:00", "2026-12-03T08:00:00-0500". Returns Unix time [s]. Throws
/// InvalidArgument naming `what` (e.g. "--started-at"), the text and the form expected; a time
/// without a zone is refused (local time or UTC would be a guess).
double parse_iso_time(const std::string& text, const std::string& what);

/// The wall clock of a live stream's controller time: offset = Unix time − controller time.
///
/// A sample is read some time after the controller stamped it (the network, the client's queue),
/// so `now − t` = offset + delay ≥ offset: the offset is the smallest `now − t` seen. It is taken
/// anew from each window of `window_s` controller seconds, so that a drift between the two clocks
/// (tens of ppm) does not build up over a shift, and starts afresh when `now − t` moves by more
/// than `jump_s` (the controller's clock restarted: a reboot, another controller). Until the first
/// sample, offset() is NaN.
class StreamWallClock {
 public:
  explicit StreamWallClock(double window_s = 10.0, double jump_s = 30.0) : window_s_(window_s), jump_s_(jump_s) {}
  /// A sample stamped `t` [s, controller clock] read at Unix time `now` [s]. Returns true when the
  /// clock started afresh (the first sample, or a jump).
  bool sample(double t, double now);
  /// [s] Unix time − controller time; NaN before the first sample
  double offset() const { return offset_; }

 private:
  double window_s_, jump_s_;
  double offset_ = std::numeric_limits<double>::quiet_NaN();
  double window_min_ = std::numeric_limits<double>::infinity();
  double window_start_ = 0.0;
};

}  // namespace twinwatch
