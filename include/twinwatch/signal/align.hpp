#pragma once
/// @file align.hpp
/// Time alignment of two recordings of the same motion by cross-correlation, and the raw vs
/// aligned error report of UR3e Table 2 (§3.4: the URSim and Simscape joint angles were shifted
/// by about 0.7 s of RTDE start-trigger latency; RMSE and MAE are given before and after
/// compensating the phase lag).
///
/// Convention: b lags a by `lag` samples when b[k] ~ a[k - lag] (positive: b is late). The lag
/// maximises the normalised cross-correlation (Pearson correlation over the overlapping samples)
///   rho(L) = cov(a[k], b[k + L]) / (sd(a[k]) sd(b[k + L])),  k over the overlap,
/// searched over L in [-max_lag, max_lag]; optionally refined below one sample by fitting a
/// parabola through rho(L - 1), rho(L), rho(L + 1) (vertex offset
///   d = (rho(L-1) - rho(L+1)) / (2 (rho(L-1) - 2 rho(L) + rho(L+1)))).
/// The aligned comparison pairs a[k] with b at k + lag (linear interpolation for a fractional lag).
#include <cstddef>
#include <span>
#include <vector>

#include "twinwatch/signal/metrics.hpp"

namespace twinwatch::signal {

/// The fewest samples a signal to align needs: the parabola needs three correlation values around
/// the peak.
inline constexpr std::size_t kAlignMinSamples = 4;

struct AlignOptions {
  int max_lag = 1000;      ///< search window [samples]; clipped to half the shorter signal
  bool subsample = true;   ///< parabolic refinement of the correlation peak
  bool common_lag = true;  ///< align_channels: one lag for all channels (peak of the mean correlation)
  /// Throws InvalidArgument naming the field: max_lag < 0.
  void validate() const;
};

/// The alignment of one channel.
struct Alignment {
  bool valid = false;        ///< false when a signal is constant over the overlap (no correlation peak;
                             ///< with a common lag its metrics still use that lag)
  double lag = 0.0;          ///< [samples] b[k] ~ a[k - lag]; positive: b is late
  int integer_lag = 0;       ///< the correlation maximum on the integer grid [samples]
  double correlation = 0.0;  ///< rho at integer_lag
  bool at_window_edge = false;  ///< the maximum sits on the search window's edge: the lag may be outside
  int window = 0;            ///< the searched window after clipping [samples]
  FitMetrics raw;            ///< b against a sample by sample over the common length (b is "predicted")
  FitMetrics aligned;        ///< b shifted by -lag against a, over the overlap
};

/// Normalised cross-correlation rho(L) of b[k + L] with a[k] over the overlap (see the file
/// comment); NaN when the overlap has < 2 samples or a signal is constant over it.
double normalized_cross_correlation(std::span<const double> a, std::span<const double> b, int lag);

/// x evaluated at k + shift for k = 0..x.size()-1 (linear interpolation; NaN outside x).
std::vector<double> shifted(std::span<const double> x, double shift);

/// Aligns b to a (sizes >= 4). Throws InvalidArgument on a too-short signal or bad options.
Alignment align(std::span<const double> a, std::span<const double> b, const AlignOptions& options = {});

/// Aligns each channel of b to the same channel of a (equal channel counts). With
/// options.common_lag the lag is the maximum of the mean correlation over the channels that are
/// not constant, the same for all, and each channel's metrics use it; otherwise every channel has
/// its own. Throws InvalidArgument on different channel counts or a too-short channel.
std::vector<Alignment> align_channels(const std::vector<std::vector<double>>& a, const std::vector<std::vector<double>>& b,
                                      const AlignOptions& options = {});

}  // namespace twinwatch::signal
