#pragma once
/// @file debounce.hpp
/// Counter debounce of a threshold decision [AGV §5]: an alert is raised after `raise_after`
/// consecutive exceedances; any sample below the threshold resets the counter to 0; an active
/// alert clears after `clear_after` consecutive samples below. Streaming, allocation-free.
///
/// DebouncedPeak measures how close a debounced decision came to raising: the largest value v such
/// that `raise_after` consecutive ratios |residual| / threshold were all above v. With every
/// threshold scaled by a sensitivity s (MonitorConfig::sensitivity), the debouncer first raises once
/// s < v, so v is the false-alarm margin of a healthy run read off directly (v < 1: no alarm).
#include <algorithm>
#include <vector>

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
      if (above_ < raise_after_) ++above_;  // saturated: an alert active for months must not overflow
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

class DebouncedPeak {
 public:
  explicit DebouncedPeak(int raise_after = 1) : ring_(static_cast<size_t>(std::max(1, raise_after)), 0.0) {}
  /// Feeds one ratio |residual| / threshold (>= 0); a sample without a decision is fed as 0.
  void update(double ratio) {
    ring_[head_] = ratio;
    head_ = (head_ + 1) % ring_.size();
    if (count_ < ring_.size()) ++count_;
    if (count_ == ring_.size()) peak_ = std::max(peak_, *std::min_element(ring_.begin(), ring_.end()));
  }
  /// The largest run-minimum so far (0 before raise_after samples).
  double peak() const { return peak_; }

 private:
  std::vector<double> ring_;
  size_t head_ = 0, count_ = 0;
  double peak_ = 0.0;
};

}  // namespace twinwatch::monitor
