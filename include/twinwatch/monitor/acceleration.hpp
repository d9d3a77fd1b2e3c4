#pragma once
/// @file acceleration.hpp
/// The joint acceleration the monitor predicts with on a stream without target_qdd, when the twin
/// keeps an acceleration window (ident::TwinModel::acceleration_window: a noisy velocity, e.g. a
/// Panda's dq at 1 kHz). Causal: the monitor judges each sample as it comes.
#include <vector>

#include "twinwatch/core/types.hpp"

namespace twinwatch::monitor {

/// The difference of two consecutive means of the measured velocity, the last w samples' and the w
/// before them, over the difference of their mean times. For a velocity with white noise sigma its
/// noise is sqrt(2 / w) sigma / (w dt), and it lags the acceleration by about w sample periods. The
/// first-order filtered one-step difference the monitor uses otherwise (cutoff f) has
/// alpha sqrt(2 / (2 - alpha)) sigma / dt with alpha = 1 - exp(-2 pi f dt): 22 times the noise for
/// w = 26 at 1 kHz and 40 Hz, for a lag of 4 ms instead of 26. An arm's inertial torque moves little in 26 ms (the Panda's excitation: ~0.4 N·m on J1), its
/// velocity noise times the inertia a lot (the thresholds it set, docs/validation.md, "Joint torque
/// sensors"). Measured on the real Panda log's J2 against a zero-phase +-25 sample estimate: rms
/// 0.35 rad/s^2 at w = 26, 1.77 for the filtered difference; a causal quadratic fit at the newest
/// sample over 52 samples (no lag, more noise) 0.72. A stream gap (a logger's lost samples) does not
/// restart it: it uses the samples' times; only a step longer than `max_step` does, and after a
/// restart the estimate is held until 2w samples have come (means of one or two samples are the raw
/// one-step difference: restarted at each of the Panda log's gaps, it set thresholds 1.5x wider).
/// Why our own: a ring of the last 2w samples with running sums, summed anew once a turn (the
/// rounding of 2w additions at most), allocation-free after construction; nothing in Eigen or
/// signal/ is this estimator.
/// Samples after the estimate became whole before the monitor judges on it (the residual filter's tail)
inline constexpr long kWindowSettle = 10;

class WindowedAcceleration {
 public:
  /// @param n joints; @param w samples per mean, >= 1 (TwinModel::acceleration_half_width + 1);
  /// @param max_step [s] the longest step between samples the estimate spans (longer: restart)
  WindowedAcceleration(int n, int w, double max_step);
  /// Forgets the velocities; the estimate is held until 2w samples have come.
  void restart();
  /// The next sample's velocity [rad/s] at time t [s]; returns the acceleration [rad/s^2] (held,
  /// 0 at first, until 2w samples have come since the start or a restart).
  const VectorJ& push(double t, const VectorJ& qd);
  const VectorJ& value() const { return qdd_; }
  /// Both means whole since the start or the last restart: before, the value is a held one, which
  /// the monitor does not judge on (a stream that starts mid-motion: 0, M qdd missing from the twin)
  bool ready() const { return count_ == qd_.size(); }

 private:
  int w_;
  double max_step_;
  std::vector<VectorJ> qd_;  // ring of the last 2w velocities
  std::vector<double> t_;
  size_t head_ = 0;   // where the next sample goes
  size_t count_ = 0;  // samples since the (re)start, at most 2w
  VectorJ qdd_, newer_, older_;  // the estimate; the sums of the newer and the older w velocities
  double t_newer_ = 0.0, t_older_ = 0.0;  // the sums of their times
  void sum_exactly();
};

}  // namespace twinwatch::monitor
