#include "twinwatch/signal/fir.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numeric>

#include "twinwatch/core/error.hpp"

namespace twinwatch::signal {

std::vector<double> kaiser_window(int n, double beta) {
  if (n < 1) throw InvalidArgument(fmt::format("Kaiser window length is {}, must be >= 1", n));
  if (!(beta >= 0.0) || !std::isfinite(beta)) throw InvalidArgument(fmt::format("Kaiser beta is {}, must be >= 0", beta));
  if (n == 1) return {1.0};
  // w(k) = I0(beta sqrt(1 - ((k - a) / a)^2)) / I0(beta), a = (n - 1) / 2
  const double a = 0.5 * (n - 1);
  const double i0_beta = std::cyl_bessel_i(0.0, beta);
  std::vector<double> w(static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) {
    const double r = (k - a) / a;
    w[static_cast<size_t>(k)] = std::cyl_bessel_i(0.0, beta * std::sqrt(std::max(0.0, 1.0 - r * r))) / i0_beta;
  }
  return w;
}

std::vector<double> fir_lowpass_kaiser(int numtaps, double cutoff_hz, double beta, double fs_hz) {
  if (numtaps < 1) throw InvalidArgument(fmt::format("FIR numtaps is {}, must be >= 1", numtaps));
  if (!(fs_hz > 0.0) || !std::isfinite(fs_hz)) throw InvalidArgument(fmt::format("FIR fs_hz is {}, must be > 0", fs_hz));
  if (!(cutoff_hz > 0.0) || !(cutoff_hz < 0.5 * fs_hz))
    throw InvalidArgument(fmt::format("FIR cutoff_hz is {}, must be in (0, fs_hz / 2) = (0, {})", cutoff_hz, 0.5 * fs_hz));
  const std::vector<double> w = kaiser_window(numtaps, beta);
  // ideal low-pass h(m) = c sinc(c m), c = cutoff / Nyquist, m = k - (numtaps - 1) / 2
  const double c = cutoff_hz / (0.5 * fs_hz);
  const double a = 0.5 * (numtaps - 1);
  std::vector<double> h(static_cast<size_t>(numtaps));
  for (int k = 0; k < numtaps; ++k) {
    const double x = c * (k - a);
    const double sinc = x == 0.0 ? 1.0 : std::sin(M_PI * x) / (M_PI * x);
    h[static_cast<size_t>(k)] = c * sinc * w[static_cast<size_t>(k)];
  }
  // scale to unit gain at DC
  const double s = std::accumulate(h.begin(), h.end(), 0.0);
  for (double& v : h) v /= s;
  return h;
}

std::vector<double> cao_torque_fir_taps() { return {0.1118, 0.1677, 0.2205, 0.2205, 0.1677, 0.1118}; }

double fir_magnitude(std::span<const double> taps, double f_hz, double fs_hz) {
  std::complex<double> H = 0.0;
  const double w = 2.0 * M_PI * f_hz / fs_hz;
  for (size_t k = 0; k < taps.size(); ++k) H += taps[k] * std::polar(1.0, -w * static_cast<double>(k));
  return std::abs(H);
}

FirFilter::FirFilter(std::vector<double> taps) : h_(std::move(taps)) {
  if (h_.empty()) throw InvalidArgument("FIR filter: no taps given");
  for (size_t k = 0; k < h_.size(); ++k)
    if (!std::isfinite(h_[k])) throw InvalidArgument(fmt::format("FIR filter: tap {} is {}, must be finite", k, h_[k]));
  buf_.assign(h_.size(), 0.0);
}

double FirFilter::push(double x) {
  const size_t n = h_.size();
  if (n == 0) return x;  // default-constructed: pass-through
  if (!primed_) {
    std::fill(buf_.begin(), buf_.end(), x);
    primed_ = true;
  }
  // newest sample at head_, older ones behind it: y = sum_k h[k] x[n - k]
  head_ = head_ + 1 == n ? 0 : head_ + 1;
  buf_[head_] = x;
  double y = 0.0;
  size_t i = head_;
  for (size_t k = 0; k < n; ++k) {
    y += h_[k] * buf_[i];
    i = i == 0 ? n - 1 : i - 1;
  }
  return y;
}

}  // namespace twinwatch::signal
