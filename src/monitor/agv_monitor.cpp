#include "twinwatch/monitor/agv_monitor.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::monitor {

void AgvMonitorOptions::validate() const {
  if (!(threshold_v > 0)) throw InvalidArgument(fmt::format("threshold_v is {}, must be > 0", threshold_v));
  if (!(threshold_w > 0)) throw InvalidArgument(fmt::format("threshold_w is {}, must be > 0", threshold_w));
  if (!(filter_alpha > 0 && filter_alpha <= 1)) throw InvalidArgument(fmt::format("filter_alpha is {}, must be in (0, 1]", filter_alpha));
  if (raise_after < 1 || clear_after < 1)
    throw InvalidArgument(fmt::format("raise_after {} and clear_after {} must be >= 1", raise_after, clear_after));
}

AgvMonitor::AgvMonitor(AgvMonitorOptions o) : o_(o), dv_(o.raise_after, o.clear_after), dw_(o.raise_after, o.clear_after) {
  o_.validate();
  alerts_.reserve(64);
}

void AgvMonitor::push_bytes(const std::uint8_t* data, std::size_t n) {
  device::AgvStateDatagram d;
  if (device::decode(data, n, d) != device::DecodeStatus::Ok) {
    ++c_.malformed;
    return;
  }
  push(d);
}

void AgvMonitor::push(const device::AgvStateDatagram& d) {
  ++c_.received;
  const int r = d.role == device::AgvRole::Twin ? 1 : 0;
  const auto k = static_cast<size_t>(r);
  auto& held = suspect_[k];
  const std::uint32_t prev = last_seq_[k];
  const bool far = have_[k] && (d.seq > prev ? d.seq - prev : prev - d.seq) > kResyncJump;
  if (!far) {
    // a believed number: the unconfirmed jump was a stray
    c_.stray += static_cast<long>(held.size());
    held.clear();
    accept(d, r);
    return;
  }
  // a jump: held until kConfirm states in a row confirm it
  if (!held.empty() && d.seq != held.back().seq + 1) {
    c_.stray += static_cast<long>(held.size());
    held.clear();
  }
  held.push_back(d);
  if (static_cast<int>(held.size()) < kConfirm) return;
  // confirmed: the side's numbering starts again at the first held state (forward: the skipped
  // numbers are lost; backward: a restart, its ring emptied so old states do not pair with new)
  ++c_.resyncs;
  if (held.front().seq > prev) c_.lost += held.front().seq - prev - 1;
  for (Slot& slot : ring_[k])
    if (slot.used && !slot.paired) ++c_.unpaired, slot.paired = true;
  have_[k] = false;
  if (held.front().seq < prev) paired_any_ = false;  // (pairs stay in order within the new numbering)
  const std::vector<device::AgvStateDatagram> confirmed = std::move(held);
  held.clear();
  for (const auto& x : confirmed) accept(x, r);
}

void AgvMonitor::accept(const device::AgvStateDatagram& d, int r) {
  const auto k = static_cast<size_t>(r);
  if (have_[k]) {
    const std::uint32_t prev = last_seq_[k];
    if (d.seq == prev) {
      ++c_.duplicated;
      return;
    }
    if (d.seq < prev) {
      ++c_.reordered;  // late: its partner has moved on, it cannot be paired any more
      first_seq_[k] = std::min(first_seq_[k], d.seq);  // came, not lost
      return;
    }
    c_.lost += d.seq - prev - 1;
  } else if (first_seq_[k] == 0 && last_seq_[k] == 0) {
    first_seq_[k] = d.seq;
  } else {
    first_seq_[k] = std::min(first_seq_[k], d.seq);
  }
  have_[k] = true;
  last_seq_[k] = d.seq;
  Slot& mine = ring_[k][d.seq % kHistory];
  if (mine.used && !mine.paired) ++c_.unpaired;  // kHistory states later its partner has not come
  mine = Slot{d, true, false};
  // the partner of the same sequence number, if it came already; pairs stay in sequence order
  Slot& other = ring_[1 - k][d.seq % kHistory];
  if (other.used && !other.paired && other.d.seq == d.seq && (!paired_any_ || d.seq > last_paired_)) {
    mine.paired = other.paired = true;
    r == 0 ? pair(d, other.d) : pair(other.d, d);
  }
}

void AgvMonitor::pair(const device::AgvStateDatagram& real, const device::AgvStateDatagram& twin) {
  ++c_.paired;
  paired_any_ = true;
  last_paired_ = real.seq;
  const double t = real.t;
  // filtered residuals [AGV §4.3]
  rv_ += o_.filter_alpha * ((real.v - twin.v) - rv_);
  rw_ += o_.filter_alpha * ((real.w - twin.w) - rw_);
  auto handle = [&](Debouncer& d, double r, double thr, char ch, int& open) {
    const auto change = d.update(std::abs(r) > thr, t);
    if (change == Debouncer::Change::Raised) {
      alerts_.push_back({ch, d.start(), t, true});
      open = static_cast<int>(alerts_.size()) - 1;
    } else if (change == Debouncer::Change::Cleared && open >= 0) {
      alerts_[static_cast<size_t>(open)].end = t;
      alerts_[static_cast<size_t>(open)].open = false;
      open = -1;
    } else if (open >= 0) {
      alerts_[static_cast<size_t>(open)].end = t;
    }
  };
  handle(dv_, rv_, o_.threshold_v, 'v', open_v_);
  handle(dw_, rw_, o_.threshold_w, 'w', open_w_);
}

void AgvMonitor::account_for_sent(std::uint32_t first, std::uint32_t last) {
  if (last < first) throw InvalidArgument(fmt::format("AgvMonitor: sent sequence numbers {}..{}: the last is before the first", first, last));
  for (size_t r = 0; r < 2; ++r) {
    if (!have_[r]) {
      c_.lost += static_cast<long>(last - first) + 1;
      continue;
    }
    if (first_seq_[r] > first) c_.lost += first_seq_[r] - first;
    if (last_seq_[r] < last) c_.lost += last - last_seq_[r];
  }
}

void AgvMonitor::finish(double t) {
  for (auto& side : ring_)
    for (Slot& slot : side)
      if (slot.used && !slot.paired) {
        ++c_.unpaired;
        slot.paired = true;  // counted once
      }
  for (auto& held : suspect_) {
    c_.stray += static_cast<long>(held.size());
    held.clear();
  }
  close_alerts(t);
}

void AgvMonitor::close_alerts(double t) {
  for (int* open : {&open_v_, &open_w_})
    if (*open >= 0) {
      alerts_[static_cast<size_t>(*open)].end = t;
      alerts_[static_cast<size_t>(*open)].open = false;
      *open = -1;
    }
}

}  // namespace twinwatch::monitor
