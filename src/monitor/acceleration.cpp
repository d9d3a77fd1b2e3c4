#include "twinwatch/monitor/acceleration.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "twinwatch/core/error.hpp"

namespace twinwatch::monitor {

WindowedAcceleration::WindowedAcceleration(int n, int w, double max_step)
    : n_(n), w_(w), max_step_(max_step), qd_(static_cast<size_t>(2 * std::max(w, 1)), VectorJ::Zero(std::max(n, 1))),
      t_(static_cast<size_t>(2 * std::max(w, 1)), 0.0), qdd_(VectorJ::Zero(std::max(n, 1))), newer_(VectorJ::Zero(std::max(n, 1))),
      older_(VectorJ::Zero(std::max(n, 1))) {
  if (n < 1 || w < 1 || !(max_step > 0.0))
    throw InvalidArgument(fmt::format("WindowedAcceleration: needs n >= 1 joints, w >= 1 samples per mean and a longest step > 0 s, "
                                      "got {}, {}, {}",
                                      n, w, max_step));
}

void WindowedAcceleration::restart() { count_ = 0; }

const VectorJ& WindowedAcceleration::push(double t, const VectorJ& qd) {
  const size_t cap = qd_.size();
  // a step longer than the window's own span: what came before says nothing of now
  if (count_ > 0 && !(t - t_[(head_ + cap - 1) % cap] <= max_step_)) restart();
  qd_[head_] = qd;
  t_[head_] = t;
  head_ = (head_ + 1) % cap;
  count_ = std::min(count_ + 1, cap);
  if (count_ < cap) return qdd_;  // (held until both means are whole: means of a sample or two are the raw difference)
  newer_.setZero();
  older_.setZero();
  double tn = 0.0, to = 0.0;
  for (size_t i = 0; i < cap; ++i) {
    const size_t at = (head_ + cap - 1 - i) % cap;
    if (i < static_cast<size_t>(w_)) {
      newer_ += qd_[at];
      tn += t_[at];
    } else {
      older_ += qd_[at];
      to += t_[at];
    }
  }
  const double span = (tn - to) / static_cast<double>(w_);
  if (span > 0.0) qdd_ = (newer_ - older_) / (static_cast<double>(w_) * span);
  return qdd_;
}

}  // namespace twinwatch::monitor
