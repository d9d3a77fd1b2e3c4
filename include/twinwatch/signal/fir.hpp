#pragma once
/// @file fir.hpp
/// Causal FIR filtering: window-method low-pass design with a Kaiser window [Kaiser1980] (as
/// scipy.signal.firwin), the torque filter of Cao eq. (29), and a streaming filter object.
///
/// Cao eq. (29): H(z) = sum_{i=0..5} h(i) z^-i with h0 = h5 = 0.1118, h1 = h4 = 0.1677,
/// h2 = h3 = 0.2205 — six taps (a fifth-order FIR), "cutoff 10 Hz, Kaiser window" at a sample
/// rate the paper does not state. The taps sum to 1 (DC gain 1), are symmetric (linear phase,
/// group delay 2.5 samples) and put a zero at Nyquist. At the UR's 500 Hz their -3 dB point is
/// 42.8 Hz; 10 Hz at -3 dB corresponds to fs = 117 Hz. No firwin(6, fc, ('kaiser', beta)) design
/// reproduces them to the printed 4 decimals (the nearest differs by 0.0064 in h1), so they are
/// used verbatim (cao_torque_fir_taps) rather than redesigned.
#include <span>
#include <vector>

namespace twinwatch::signal {

/// Kaiser window of length n, symmetric (scipy.signal.get_window(('kaiser', beta), n, fftbins=False)):
///   w(k) = I0(beta sqrt(1 - ((k - a) / a)^2)) / I0(beta),  a = (n - 1) / 2.
/// Throws InvalidArgument for n < 1 or beta < 0.
std::vector<double> kaiser_window(int n, double beta);

/// Window-method FIR low-pass (scipy.signal.firwin(numtaps, cutoff_hz, window=('kaiser', beta),
/// fs=fs_hz), scale=True): ideal low-pass impulse response c sinc(c (k - a)), c = cutoff / Nyquist,
/// times the Kaiser window, scaled to unit DC gain. cutoff_hz is the -6 dB point for long filters.
/// Throws InvalidArgument: numtaps < 1, fs_hz <= 0, cutoff_hz outside (0, fs_hz / 2), beta < 0.
std::vector<double> fir_lowpass_kaiser(int numtaps, double cutoff_hz, double beta, double fs_hz);

/// The six taps of Cao eq. (29) (see the file comment).
std::vector<double> cao_torque_fir_taps();

/// Frequency response magnitude |H(e^{i 2 pi f / fs})| = |sum_k h_k e^{-i 2 pi f k / fs}| of taps h.
double fir_magnitude(std::span<const double> taps, double f_hz, double fs_hz);

/// Streaming causal FIR y[n] = sum_k h[k] x[n - k] over a ring buffer allocated once at
/// construction: push() neither allocates nor throws. The first push (and the first after
/// reset()) fills the history with that sample, so a constant input gives a constant output from
/// the start (no start-up transient towards zero), as the monitor's IIR starts at its first value.
class FirFilter {
 public:
  /// No taps: push() returns its input unchanged (identity filter), for joints whose residual uses the IIR instead.
  FirFilter() = default;
  /// Throws InvalidArgument on empty taps or a non-finite tap (naming its index).
  explicit FirFilter(std::vector<double> taps);

  /// Filters one sample and returns the output.
  double push(double x);
  /// Forgets the history; the next push starts the filter again.
  void reset() { primed_ = false; }
  const std::vector<double>& taps() const { return h_; }
  /// Group delay [samples] of a symmetric (linear-phase) filter: (taps - 1) / 2.
  double group_delay() const { return h_.empty() ? 0.0 : 0.5 * static_cast<double>(h_.size() - 1); }

 private:
  std::vector<double> h_;
  std::vector<double> buf_;  // last taps().size() inputs, buf_[head_] the newest
  size_t head_ = 0;
  bool primed_ = false;
};

}  // namespace twinwatch::signal
