#pragma once
/// @file debounce.hpp
/// Counter debounce of a threshold decision [AGV §5]: an alert is raised after `raise_after`
/// consecutive exceedances; any sample below the threshold resets the counter to 0; an active
/// alert clears after `clear_after` consecutive samples below. Streaming, allocation-free.
namespace twinwatch::monitor {

class Debouncer {
 public:
  enum class Change { None, Raised, Cleared };

  Debouncer(int raise_after = 3, int clear_after = 25) : raise_after_(raise_after), clear_after_(clear_after) {}

  /// Feeds one decision at time t [s]. Returns Raised on the sample that raises the alert (its
  /// start time is the first exceedance of the run), Cleared when it clears.
  Change update(bool exceeded, double t) {
    if (exceeded) {
      if (above_ == 0) run_start_ = t;
      ++above_;
      below_ = 0;
      if (!active_ && above_ >= raise_after_) {
        active_ = true;
        start_ = run_start_;
        return Change::Raised;
      }
    } else {
      above_ = 0;
      if (active_ && ++below_ >= clear_after_) {
        active_ = false;
        end_ = t;
        return Change::Cleared;
      }
    }
    return Change::None;
  }

  bool active() const { return active_; }
  double start() const { return start_; }
  double end() const { return end_; }
  void reset() { above_ = below_ = 0, active_ = false; }

 private:
  int raise_after_, clear_after_;
  int above_ = 0, below_ = 0;
  bool active_ = false;
  double run_start_ = 0.0, start_ = 0.0, end_ = 0.0;
};

}  // namespace twinwatch::monitor
