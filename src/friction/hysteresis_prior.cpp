#include "twinwatch/friction/hysteresis_prior.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "twinwatch/core/error.hpp"

namespace twinwatch::friction {

namespace {

double percentile(std::vector<double> a, double q) {
  const auto k = static_cast<std::size_t>(q * static_cast<double>(a.size() - 1));
  std::nth_element(a.begin(), a.begin() + static_cast<long>(k), a.end());
  return a[k];
}

std::vector<double> abs_of(std::span<const double> x) {
  std::vector<double> a(x.size());
  std::transform(x.begin(), x.end(), a.begin(), [](double v) { return std::abs(v); });
  return a;
}

}  // namespace

LoopDescriptors loop_descriptors(std::span<const double> qd, std::span<const double> y, double v_ref) {
  check_size("y", static_cast<long>(y.size()), static_cast<long>(qd.size()), "size of qd");
  if (qd.size() < 3) throw InvalidArgument(fmt::format("qd has {} samples, expected at least 3", qd.size()));
  if (!std::isfinite(v_ref) || v_ref <= 0.0)
    throw InvalidArgument(fmt::format("reversal threshold v_ref is {}, must be > 0 [rad/s]", v_ref));
  // robust range of y
  constexpr double kLow = 0.01, kHigh = 0.99;
  std::vector<double> ys(y.begin(), y.end());
  const double range = std::max(percentile(ys, kHigh) - percentile(ys, kLow), std::numeric_limits<double>::min());
  LoopDescriptors d;
  double down_sum = 0.0, up_sum = 0.0, slope_sum = 0.0;
  int n_down = 0, n_up = 0;
  // walk the record: a reversal is a sign change of qd after an excursion beyond +-v_ref
  int armed = 0;  // sign of the last excursion beyond v_ref (0: none yet)
  for (std::size_t k = 1; k < qd.size(); ++k) {
    if (armed == 0) {
      if (std::abs(qd[k]) >= v_ref) armed = qd[k] > 0.0 ? 1 : -1;
      continue;
    }
    const bool crossed = armed > 0 ? (qd[k - 1] > 0.0 && qd[k] <= 0.0) : (qd[k - 1] < 0.0 && qd[k] >= 0.0);
    if (!crossed) continue;
    // y at qd = 0 by linear interpolation between k-1 and k
    const double denom = qd[k - 1] - qd[k];
    const double w = denom != 0.0 ? qd[k - 1] / denom : 1.0;
    const double y0 = y[k - 1] + w * (y[k] - y[k - 1]);
    // first sample after the crossing with |qd| >= v_ref in the new direction
    std::size_t m = k;
    while (m < qd.size() && -armed * qd[m] < v_ref) ++m;
    if (m == qd.size()) break;  // the record ends inside the reversal
    if (armed > 0) {
      down_sum += y0;
      ++n_down;
    } else {
      up_sum += y0;
      ++n_up;
    }
    slope_sum += -armed * (y[m] - y0);
    ++d.reversals;
    armed = -armed;
    k = m;
  }
  if (d.reversals == 0) return d;
  // width needs both directions; with one only, the loop height is taken against 0
  const double down = n_down > 0 ? down_sum / n_down : 0.0;
  const double up = n_up > 0 ? up_sum / n_up : 0.0;
  d.width = (n_down > 0 && n_up > 0 ? down - up : 2.0 * (n_down > 0 ? down : -up)) / range;
  d.slope = slope_sum / d.reversals / range;
  return d;
}

void HysteresisPriorOptions::validate() const {
  if (!std::isfinite(alpha_min) || alpha_min <= 0.0)
    throw InvalidArgument(fmt::format("prior alpha_min is {}, must be > 0 [1/s]", alpha_min));
  if (!std::isfinite(alpha_max) || alpha_max <= alpha_min)
    throw InvalidArgument(fmt::format("prior alpha_max is {}, must be > alpha_min ({})", alpha_max, alpha_min));
  if (!std::isfinite(displacement_alpha_min) || displacement_alpha_min <= 0.0)
    throw InvalidArgument(
        fmt::format("prior displacement_alpha_min is {}, must be > 0 [1/rad]", displacement_alpha_min));
  if (!std::isfinite(displacement_alpha_max) || displacement_alpha_max <= displacement_alpha_min)
    throw InvalidArgument(fmt::format("prior displacement_alpha_max is {}, must be > displacement_alpha_min ({})",
                                      displacement_alpha_max, displacement_alpha_min));
  if (!std::isfinite(beta_min) || beta_min <= 0.0)
    throw InvalidArgument(fmt::format("prior beta_min is {}, must be > 0 [s/rad]", beta_min));
  if (!std::isfinite(beta_max) || beta_max <= beta_min)
    throw InvalidArgument(fmt::format("prior beta_max is {}, must be > beta_min ({})", beta_max, beta_min));
  if (grid < 2) throw InvalidArgument(fmt::format("prior grid is {}, must be >= 2", grid));
  if (!(weight_width >= 0.0) || !(weight_slope >= 0.0) || weight_width + weight_slope <= 0.0)
    throw InvalidArgument(fmt::format("prior weights (weight_width {}, weight_slope {}) must be >= 0 with a positive sum",
                                      weight_width, weight_slope));
  if (!(v_ref_fraction > 0.0 && v_ref_fraction < 1.0))
    throw InvalidArgument(fmt::format("prior v_ref_fraction is {}, must be in (0, 1)", v_ref_fraction));
}

HysteresisParams HysteresisPriorOptions::fallback() const noexcept {
  HysteresisParams p;
  p.drive = drive;
  if (drive == HysteresisDrive::Displacement) p.alpha = std::sqrt(displacement_alpha_min * displacement_alpha_max);
  return p;
}

HysteresisPrior calibrate_hysteresis_prior(const FrictionRecord& record, const HysteresisPriorOptions& options) {
  options.validate();
  record.validate("training record", 3);
  // reversal threshold from the velocity scale
  constexpr double kVelocityQuantile = 0.99;
  const double v_ref = options.v_ref_fraction * percentile(abs_of(record.qd), kVelocityQuantile);
  if (!(v_ref > 0.0)) throw InvalidArgument("training record: qd is zero, no hysteresis loop to calibrate on");
  // measured descriptors on a lightly smoothed tau_f (5-sample centred moving average)
  constexpr int kHalfWindow = 2;
  const auto n = static_cast<long>(record.tau.size());
  std::vector<double> tau_s(record.tau.size());
  for (long k = 0; k < n; ++k) {
    const long a = std::max(0L, k - kHalfWindow), b = std::min(n - 1, k + kHalfWindow);
    double s = 0.0;
    for (long i = a; i <= b; ++i) s += record.tau[static_cast<std::size_t>(i)];
    tau_s[static_cast<std::size_t>(k)] = s / static_cast<double>(b - a + 1);
  }
  if (options.remove_viscous) {
    // least squares tau ~ c0 + c1 qd + c2 sgn(qd) on the sliding samples: 3x3 normal equations
    double A[3][4] = {};
    for (long k = 0; k < n; ++k) {
      const double v = record.qd[static_cast<std::size_t>(k)];
      if (std::abs(v) < v_ref) continue;
      const double row[3] = {1.0, v, v > 0.0 ? 1.0 : -1.0};
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) A[i][j] += row[i] * row[j];
        A[i][3] += row[i] * tau_s[static_cast<std::size_t>(k)];
      }
    }
    // Gauss-Jordan with partial pivoting; a singular system (no sliding in one direction) keeps tau
    bool ok = true;
    for (int c = 0; c < 3 && ok; ++c) {
      int piv = c;
      for (int r = c + 1; r < 3; ++r)
        if (std::abs(A[r][c]) > std::abs(A[piv][c])) piv = r;
      constexpr double kSingular = 1e-12;
      if (std::abs(A[piv][c]) < kSingular * (1.0 + std::abs(A[0][0]))) {
        ok = false;
        break;
      }
      std::swap(A[c], A[piv]);
      for (int r = 0; r < 3; ++r) {
        if (r == c) continue;
        const double f = A[r][c] / A[c][c];
        for (int j = c; j < 4; ++j) A[r][j] -= f * A[c][j];
      }
    }
    if (ok) {
      const double c1 = A[1][3] / A[1][1];
      for (long k = 0; k < n; ++k) tau_s[static_cast<std::size_t>(k)] -= c1 * record.qd[static_cast<std::size_t>(k)];
    }
  }
  HysteresisPrior out;
  out.measured = loop_descriptors(record.qd, tau_s, v_ref);
  if (out.measured.reversals == 0)
    throw InvalidArgument(fmt::format("training record: qd never reverses beyond +-{:.3g} rad/s, no hysteresis loop "
                                      "to calibrate (alpha, beta) on",
                                      v_ref));
  // bounded log grid; in the time clock alpha is kept inside the stability region of eq. 11
  const bool time = options.drive == HysteresisDrive::Time;
  constexpr double kStableFraction = 0.9;
  const double alpha_max =
      time ? std::min(options.alpha_max, kStableFraction / record.dt) : options.displacement_alpha_max;
  const double alpha_min = time ? std::min(options.alpha_min, 0.5 * alpha_max) : options.displacement_alpha_min;
  out.cost = std::numeric_limits<double>::infinity();
  for (int i = 0; i < options.grid; ++i) {
    const double alpha = alpha_min * std::pow(alpha_max / alpha_min, i / (options.grid - 1.0));
    for (int j = 0; j < options.grid; ++j) {
      const double beta = options.beta_min * std::pow(options.beta_max / options.beta_min, j / (options.grid - 1.0));
      const HysteresisParams p{alpha, beta, options.drive};
      const HysteresisFeatures f = hysteresis_features(record.qd, record.dt, p);
      const LoopDescriptors g = loop_descriptors(record.qd, f.h, v_ref);
      // J_h of eq. 13
      const double cost = options.weight_width * std::abs(out.measured.width - g.width) +
                          options.weight_slope * std::abs(out.measured.slope - g.slope);
      if (cost < out.cost) {
        out.cost = cost;
        out.params = p;
        out.generated = g;
      }
    }
  }
  return out;
}

}  // namespace twinwatch::friction
