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
///
/// The offset means something only while the controller's clock runs at the pace of this
/// machine's: a replay served faster than real time (serve-robot --speed 8) or a monitor that
/// falls ever further behind its stream moves `now − t` steadily, and a least-delay offset then
/// puts an event seconds away from when it happened (review of session 48: a live line and the
/// stored event 10 s apart). The pace is read from the least `now − t` of blocks of 2 controller
/// seconds: three steps in a row that say the controller's clock runs more than 2 % faster (or
/// slower) than this machine's put the clock off pace, and offset() is NaN until three steps in a
/// row are within 2 % again, when the offset is read afresh.
class StreamWallClock {
 public:
  /// what a sample changed
  enum class Change {
    none,
    started,    ///< the first sample, or the controller's clock jumped (a restart): read afresh
    off_pace,   ///< the controller's clock runs at another pace than this machine's: offset() is NaN
    on_pace,    ///< back in pace: the offset is read afresh
  };
  explicit StreamWallClock(double window_s = 10.0, double jump_s = 30.0) : window_s_(window_s), jump_s_(jump_s) {}
  /// A sample stamped `t` [s, controller clock] read at Unix time `now` [s].
  Change sample(double t, double now);
  /// [s] Unix time − controller time; NaN before the first sample and while off pace
  double offset() const { return off_pace_ ? std::numeric_limits<double>::quiet_NaN() : offset_; }
  bool off_pace() const { return off_pace_; }
  /// controller seconds per second of this machine's clock over the last three pace blocks (1: in
  /// pace; 8: a replay at 8 times real time); NaN before three blocks
  double pace() const { return pace_; }

 private:
  void restart(double t, double d);
  static constexpr double kBlockS = 2.0, kPaceTolerance = 0.02;
  static constexpr int kPaceSteps = 3;
  double window_s_, jump_s_;
  double offset_ = std::numeric_limits<double>::quiet_NaN();
  double window_min_ = std::numeric_limits<double>::infinity();
  double window_start_ = 0.0;
  // pace: the least now − t of the current block, and of the last kPaceSteps + 1 blocks ended
  double block_start_ = 0.0, block_min_ = std::numeric_limits<double>::infinity(), block_min_t_ = 0.0;
  double ended_min_[kPaceSteps + 1] = {}, ended_t_[kPaceSteps + 1] = {};
  int ended_ = 0;      // blocks ended since the last restart
  int fast_ = 0, slow_ = 0, steady_ = 0;  // steps in a row of each kind
  bool off_pace_ = false;
  double pace_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace twinwatch
