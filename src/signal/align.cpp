#include "twinwatch/signal/align.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "twinwatch/core/error.hpp"

namespace twinwatch::signal {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr size_t kMinSamples = kAlignMinSamples;

// rho(L) for L = -W..W
std::vector<double> correlation_curve(std::span<const double> a, std::span<const double> b, int W) {
  std::vector<double> rho(static_cast<size_t>(2 * W + 1));
  for (int L = -W; L <= W; ++L) rho[static_cast<size_t>(L + W)] = normalized_cross_correlation(a, b, L);
  return rho;
}

struct Peak {
  bool valid = false;
  int integer_lag = 0;
  double lag = 0.0;
  bool at_edge = false;
};

// the maximum of rho over the window, refined by a parabola through its neighbours
Peak peak_of(const std::vector<double>& rho, int W, bool subsample) {
  Peak p;
  double best = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < static_cast<int>(rho.size()); ++i)
    if (std::isfinite(rho[static_cast<size_t>(i)]) && rho[static_cast<size_t>(i)] > best) {
      best = rho[static_cast<size_t>(i)];
      p.integer_lag = i - W;
      p.valid = true;
    }
  if (!p.valid) return p;
  p.lag = p.integer_lag;
  p.at_edge = W > 0 && std::abs(p.integer_lag) == W;
  if (subsample && !p.at_edge && W > 0) {
    // vertex of the parabola through (-1, r_m), (0, r_0), (1, r_p): d = (r_m - r_p) / (2 (r_m - 2 r_0 + r_p))
    const size_t i = static_cast<size_t>(p.integer_lag + W);
    const double rm = rho[i - 1], r0 = rho[i], rp = rho[i + 1];
    const double curv = rm - 2.0 * r0 + rp;
    if (std::isfinite(rm) && std::isfinite(rp) && curv < 0.0) p.lag += std::clamp(0.5 * (rm - rp) / curv, -0.5, 0.5);
  }
  return p;
}

// b at k + lag for k = 0..n-1 (linear interpolation, NaN outside b)
std::vector<double> sample_at(std::span<const double> b, size_t n, double lag) {
  std::vector<double> out(n, kNaN);
  const double last = static_cast<double>(b.size()) - 1.0;
  for (size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) + lag;
    if (t < 0.0 || t > last) continue;
    const double f = std::floor(t);
    const size_t i = static_cast<size_t>(f);
    const double w = t - f;
    out[k] = w == 0.0 ? b[i] : (1.0 - w) * b[i] + w * b[i + 1];
  }
  return out;
}

void check_signal(std::span<const double> x, const char* name) {
  if (x.size() < kMinSamples)
    throw InvalidArgument(fmt::format("align: signal {} has {} samples, expected at least {}", name, x.size(), kMinSamples));
}

int clipped_window(const AlignOptions& o, size_t na, size_t nb) {
  // keep at least half the shorter signal overlapping at every searched lag
  return std::min(o.max_lag, static_cast<int>(std::min(na, nb) / 2));
}

Alignment finish(std::span<const double> a, std::span<const double> b, const Peak& p, double rho_at_peak, int W) {
  Alignment r;
  r.window = W;
  const size_t n = std::min(a.size(), b.size());
  r.raw = fit_metrics(a.subspan(0, n), b.subspan(0, n));
  r.valid = p.valid;
  if (!p.valid) {
    r.aligned = r.raw;
    return r;
  }
  r.lag = p.lag;
  r.integer_lag = p.integer_lag;
  r.at_window_edge = p.at_edge;
  r.correlation = rho_at_peak;
  // a[k] against b(k + lag) over the overlap (fit_metrics skips the NaN outside b)
  r.aligned = fit_metrics(a, sample_at(b, a.size(), p.lag));
  return r;
}

}  // namespace

void AlignOptions::validate() const {
  if (max_lag < 0) throw InvalidArgument(fmt::format("max_lag is {}, must be >= 0 [samples]", max_lag));
}

double normalized_cross_correlation(std::span<const double> a, std::span<const double> b, int lag) {
  // overlap: k in [k0, k1) with 0 <= k < a.size() and 0 <= k + lag < b.size()
  const long na = static_cast<long>(a.size()), nb = static_cast<long>(b.size());
  const long k0 = std::max(0L, -static_cast<long>(lag)), k1 = std::min(na, nb - lag);
  if (k1 - k0 < 2) return kNaN;
  // two passes (means, then centred sums) keep the precision for signals far from zero
  double ma = 0.0, mb = 0.0;
  for (long k = k0; k < k1; ++k) {
    ma += a[static_cast<size_t>(k)];
    mb += b[static_cast<size_t>(k + lag)];
  }
  const double n = static_cast<double>(k1 - k0);
  ma /= n;
  mb /= n;
  double sab = 0.0, saa = 0.0, sbb = 0.0;
  for (long k = k0; k < k1; ++k) {
    const double da = a[static_cast<size_t>(k)] - ma, db = b[static_cast<size_t>(k + lag)] - mb;
    sab += da * db;
    saa += da * da;
    sbb += db * db;
  }
  if (!(saa > 0.0) || !(sbb > 0.0)) return kNaN;
  return sab / std::sqrt(saa * sbb);
}

std::vector<double> shifted(std::span<const double> x, double shift) { return sample_at(x, x.size(), shift); }

Alignment align(std::span<const double> a, std::span<const double> b, const AlignOptions& o) {
  o.validate();
  check_signal(a, "a");
  check_signal(b, "b");
  const int W = clipped_window(o, a.size(), b.size());
  const auto rho = correlation_curve(a, b, W);
  const Peak p = peak_of(rho, W, o.subsample);
  return finish(a, b, p, p.valid ? rho[static_cast<size_t>(p.integer_lag + W)] : kNaN, W);
}

std::vector<Alignment> align_channels(const std::vector<std::vector<double>>& a, const std::vector<std::vector<double>>& b,
                                      const AlignOptions& o) {
  o.validate();
  if (a.size() != b.size()) throw InvalidArgument(fmt::format("align: a has {} channels, b {}, expected equal", a.size(), b.size()));
  std::vector<Alignment> out;
  if (!o.common_lag) {
    for (size_t c = 0; c < a.size(); ++c) out.push_back(align(a[c], b[c], o));
    return out;
  }
  int W = o.max_lag;
  for (size_t c = 0; c < a.size(); ++c) {
    check_signal(a[c], "a");
    check_signal(b[c], "b");
    W = std::min(W, clipped_window(o, a[c].size(), b[c].size()));
  }
  // mean correlation over the channels that have one (constant channels give NaN curves)
  std::vector<std::vector<double>> rho;
  std::vector<double> mean(static_cast<size_t>(2 * W + 1), 0.0);
  std::vector<int> count(mean.size(), 0);
  for (size_t c = 0; c < a.size(); ++c) {
    rho.push_back(correlation_curve(a[c], b[c], W));
    for (size_t i = 0; i < mean.size(); ++i)
      if (std::isfinite(rho.back()[i])) {
        mean[i] += rho.back()[i];
        ++count[i];
      }
  }
  for (size_t i = 0; i < mean.size(); ++i) mean[i] = count[i] > 0 ? mean[i] / count[i] : kNaN;
  const Peak p = peak_of(mean, W, o.subsample);
  for (size_t c = 0; c < a.size(); ++c) {
    const double r = p.valid ? rho[c][static_cast<size_t>(p.integer_lag + W)] : kNaN;
    out.push_back(finish(a[c], b[c], p, r, W));
    // a constant channel has no correlation of its own but is still compared at the common lag
    out.back().valid = p.valid && std::isfinite(r);
  }
  return out;
}

}  // namespace twinwatch::signal
