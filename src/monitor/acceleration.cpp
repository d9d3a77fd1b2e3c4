#include "twinwatch/monitor/acceleration.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "twinwatch/core/error.hpp"

namespace twinwatch::monitor {

WindowedAcceleration::WindowedAcceleration(int n, int w, double max_step)
    : w_(w), max_step_(max_step), qd_(static_cast<size_t>(2 * std::max(w, 1)), VectorJ::Zero(std::max(n, 1))),
      t_(static_cast<size_t>(2 * std::max(w, 1)), 0.0), qdd_(VectorJ::Zero(std::max(n, 1))), newer_(VectorJ::Zero(std::max(n, 1))),
      older_(VectorJ::Zero(std::max(n, 1))) {
  if (n < 1 || w < 1 || !(max_step > 0.0))
    throw InvalidArgument(fmt::format("WindowedAcceleration: needs n >= 1 joints, w >= 1 samples per mean and a longest step > 0 s, "
                                      "got {}, {}, {}",
                                      n, w, max_step));
}

void WindowedAcceleration::restart() { count_ = 0; }

// the two sums over the ring as it is (oldest at head_): the older half first
void WindowedAcceleration::sum_exactly() {
  const size_t cap = qd_.size();
  newer_.setZero();
  older_.setZero();
  t_newer_ = t_older_ = 0.0;
  for (size_t i = 0; i < cap; ++i) {
    const size_t at = (head_ + i) % cap;
    if (i < static_cast<size_t>(w_)) {
      older_ += qd_[at];
      t_older_ += t_[at];
    } else {
      newer_ += qd_[at];
      t_newer_ += t_[at];
    }
  }
}

const VectorJ& WindowedAcceleration::push(double t, const VectorJ& qd) {
  const size_t cap = qd_.size();
  // a step longer than the window's own span: what came before says nothing of now
  if (count_ > 0 && !(t - t_[(head_ + cap - 1) % cap] <= max_step_)) restart();
  if (count_ == cap) {
    // running sums (O(1) a sample instead of O(2w): 0.3 us a sample at w = 14 on six joints): the
    // oldest leaves the older half, the newer half's oldest moves into it, the new one joins the newer
    const size_t mid = (head_ + static_cast<size_t>(w_)) % cap;
    older_ += qd_[mid] - qd_[head_];
    t_older_ += t_[mid] - t_[head_];
    newer_ += qd - qd_[mid];
    t_newer_ += t - t_[mid];
  }
  qd_[head_] = qd;
  t_[head_] = t;
  head_ = (head_ + 1) % cap;
  const bool was_full = count_ == cap;
  count_ = std::min(count_ + 1, cap);
  if (count_ < cap) return qdd_;  // (held until both means are whole: means of a sample or two are the raw difference)
  // summed anew when the ring has just filled, and once a turn (the running sums' rounding stays
  // that of 2w additions)
  if (!was_full || head_ == 0) sum_exactly();
  const double span = (t_newer_ - t_older_) / static_cast<double>(w_);
  if (span > 0.0) qdd_ = (newer_ - older_) / (static_cast<double>(w_) * span);
  return qdd_;
}

}  // namespace twinwatch::monitor
