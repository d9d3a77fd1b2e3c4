#pragma once
/// @file butterworth.hpp
/// Digital Butterworth low-pass [Butterworth1930] in second-order sections and zero-phase
/// (forward-backward) filtering. Matches scipy.signal: `butter(N, Wn, output='sos', fs=fs)` for the
/// design (analog prototype, prewarped bilinear transform, scipy's nearest pole/zero pairing and
/// section order) and `sosfiltfilt(sos, x)` for the filtering (odd extension of padlen samples,
/// initial conditions from `sosfilt_zi` scaled by the first sample of each pass).
///
/// Used to smooth qd/current before differentiation (UR3e §3.5 preprocessing) where a batch,
/// zero-phase filter is allowed; causal filters for the monitor are in fir.hpp.
#include <array>
#include <span>
#include <vector>

namespace twinwatch::signal {

/// One second-order section, scipy's sos row [b0 b1 b2 a0 a1 a2] with a0 = 1:
///   H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2)
using Sos = std::array<double, 6>;

/// Butterworth low-pass of order `order` with -3 dB point `cutoff_hz` at sample rate `fs_hz`
/// (scipy.signal.butter(order, cutoff_hz, output='sos', fs=fs_hz)).
/// Sections are ordered as scipy orders them: the pole pair closest to the unit circle is last,
/// the overall gain is in the first section. ceil(order / 2) sections; for odd orders the first
/// section holds the real pole and has b2 = a2 = 0.
/// Throws InvalidArgument: order outside [1, kMaxButterworthOrder], fs_hz <= 0, cutoff_hz outside
/// (0, fs_hz / 2).
std::vector<Sos> butterworth_lowpass(int order, double cutoff_hz, double fs_hz);

/// Highest order butterworth_lowpass accepts (beyond it the poles crowd the unit circle at low
/// cutoffs and double precision loses the response; scipy does not limit it).
constexpr int kMaxButterworthOrder = 20;

/// Causal filtering through the cascade, transposed direct form II (scipy.signal.sosfilt).
/// zi: optional initial state, 2 values per section (size 2 * sos.size()), updated to the final
/// state; empty span: zero state. Throws InvalidArgument on a zi of the wrong size.
std::vector<double> sosfilt(std::span<const Sos> sos, std::span<const double> x, std::span<double> zi = {});

/// Steady-state initial conditions for a unit step input (scipy.signal.sosfilt_zi): 2 values per
/// section, section after section, so that sosfilt of a constant c with zi = c * zi_step starts
/// without a transient.
std::vector<double> sosfilt_zi(std::span<const Sos> sos);

/// Number of padding samples scipy.signal.sosfiltfilt uses by default:
///   3 * (2 * n_sections + 1 - min(#sections with b2 == 0, #sections with a2 == 0))
int sosfiltfilt_padlen(std::span<const Sos> sos);

/// Zero-phase forward-backward filtering (scipy.signal.sosfiltfilt with padtype 'odd'): the input
/// is extended at both ends by point reflection about its end values (padlen samples, default
/// sosfiltfilt_padlen), filtered forward and backward with steady-state initial conditions, and
/// the padding removed. The magnitude response is |H|^2 and the phase is zero.
/// padlen < 0: the default. Throws InvalidArgument when x.size() <= padlen (scipy's rule: "the
/// length of the input must be greater than padlen") or on an empty sos.
std::vector<double> sosfiltfilt(std::span<const Sos> sos, std::span<const double> x, int padlen = -1);

/// Options of a zero-phase Butterworth low-pass applied to a whole signal.
struct ButterworthLowpass {
  int order = 4;           ///< filter order N (the forward-backward pass doubles it)
  double cutoff_hz = 10.0; ///< -3 dB frequency of one pass [Hz] (-6 dB after filtfilt)
  double fs_hz = 500.0;    ///< sample rate [Hz] (RTDE default 500 Hz)
  /// Throws InvalidArgument naming the field: order outside [1, kMaxButterworthOrder], fs_hz <= 0,
  /// cutoff_hz outside (0, fs_hz / 2).
  void validate() const;
  /// The design (butterworth_lowpass).
  std::vector<Sos> sections() const;
  /// sosfiltfilt of x with the default padding. Throws InvalidArgument on a too-short x, naming
  /// its size and the padlen limit.
  std::vector<double> apply(std::span<const double> x) const;
};

}  // namespace twinwatch::signal
