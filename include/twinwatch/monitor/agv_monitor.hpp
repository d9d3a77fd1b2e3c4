#pragma once
/// @file agv_monitor.hpp
/// The AGV twin monitor [AGV §4.3, §5]: pairs the real robot's and the twin's state datagrams by
/// sequence number, forms the residual linear and angular speeds, filters them with a first-order
/// IIR, compares with thresholds and debounces (N consecutive exceedances raise; a sample below
/// resets the counter), and reports alerts with start time and duration. Lost, duplicated,
/// reordered and malformed datagrams are counted, never fatal. The last kHistory states of each
/// side are kept, so a partner that arrives after the other side's next state still pairs (the
/// two processes answer independently: on a loaded machine one runs a period behind); a state
/// whose partner never comes is counted as unpaired.
#include <array>
#include <cstdint>
#include <vector>

#include "twinwatch/device/agv_link.hpp"
#include "twinwatch/monitor/debounce.hpp"

namespace twinwatch::monitor {

struct AgvMonitorOptions {
  double threshold_v = 0.05;   ///< [m/s] on the filtered linear-speed residual
  double threshold_w = 0.5;    ///< [rad/s] on the filtered angular-speed residual
  double filter_alpha = 0.3;   ///< IIR y += a (x - y) per sample
  int raise_after = 5;         ///< consecutive exceedances (5 x 40 ms = 200 ms)
  int clear_after = 1;         ///< below once: the paper's counter reset and alert end
  void validate() const;
};

struct AgvAlert {
  char channel = 'v';   ///< 'v' linear or 'w' angular speed
  double start = 0.0, end = 0.0;
  bool open = true;
  double duration() const { return end - start; }
};

struct AgvCounters {
  long received = 0, paired = 0, lost = 0, duplicated = 0, reordered = 0, malformed = 0;
  long unpaired = 0;  ///< states received in order whose partner never came (counted when they can no longer pair)
  /// states whose sequence number jumped more than AgvMonitor::kResyncJump from the side's last and
  /// that no kConfirm consecutive states confirmed (a stray sender, a corrupted number): dropped
  long stray = 0;
  /// jumps that kConfirm consecutive states confirmed (a robot restarted its numbering): followed
  long resyncs = 0;
};

class AgvMonitor {
 public:
  explicit AgvMonitor(AgvMonitorOptions o = {});
  /// Feeds raw bytes of one datagram (decoded here; malformed ones are counted).
  void push_bytes(const std::uint8_t* data, std::size_t n);
  void push(const device::AgvStateDatagram& d);
  /// Closes the open alerts at `t` (the end of a test); the pairing goes on, so a partner that
  /// comes after it still pairs.
  void close_alerts(double t);
  /// The end of the stream: closes the open alerts; the states still waiting for a partner count as
  /// unpaired.
  void finish(double t);
  /// Once, when the sender is done: it sent sequence numbers first..last to each side. Those a side
  /// never answered before its first received state or after its last (a lost tail that no later
  /// datagram reveals as a gap, or a side that never answered at all) are counted as lost.
  void account_for_sent(std::uint32_t first, std::uint32_t last);
  static constexpr std::uint32_t kHistory = 16;  ///< states kept per side (640 ms at 40 ms)
  /// A sequence number this far from the side's last (41 s at 40 ms, either way) is not believed
  /// at once: one stray datagram with seq 0xFFFFFFF0 made every later state "reordered", and
  /// 4294967251 datagrams "lost" (review, session 47). It is followed once kConfirm states in a
  /// row confirm it (the robot restarted its numbering; the jump forward counts as lost).
  static constexpr std::uint32_t kResyncJump = 1024;
  static constexpr int kConfirm = 3;

  const std::vector<AgvAlert>& alerts() const { return alerts_; }
  const AgvCounters& counters() const { return c_; }
  double residual_v() const { return rv_; }
  double residual_w() const { return rw_; }

 private:
  void pair(const device::AgvStateDatagram& real, const device::AgvStateDatagram& twin);
  void accept(const device::AgvStateDatagram& d, int r);  // a state whose number is believed

  AgvMonitorOptions o_;
  AgvCounters c_;
  struct Slot {
    device::AgvStateDatagram d;
    bool used = false, paired = false;
  };
  std::array<std::array<Slot, kHistory>, 2> ring_{};  // per side, at seq % kHistory
  std::array<bool, 2> have_{false, false};
  std::array<std::uint32_t, 2> first_seq_{0, 0}, last_seq_{0, 0};
  std::uint32_t last_paired_ = 0;
  std::array<std::vector<device::AgvStateDatagram>, 2> suspect_;  // per side: a jump not yet confirmed
  bool paired_any_ = false;
  double rv_ = 0.0, rw_ = 0.0;
  Debouncer dv_, dw_;
  std::vector<AgvAlert> alerts_;
  int open_v_ = -1, open_w_ = -1;
};

}  // namespace twinwatch::monitor
