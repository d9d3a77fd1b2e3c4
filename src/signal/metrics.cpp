#include "twinwatch/signal/metrics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "twinwatch/core/error.hpp"

namespace twinwatch::signal {

void FitAccumulator::add(double y, double yhat) {
  if (std::isnan(y) || std::isnan(yhat)) return;
  const double e = y - yhat;
  sse_ += e * e;
  sae_ += std::abs(e);
  sum_ += y;
  sum2_ += y * y;
  lo_ = std::min(lo_, y);
  hi_ = std::max(hi_, y);
  max_abs_ = std::max(max_abs_, std::abs(e));
  ++n_;
}

FitMetrics FitAccumulator::metrics() const {
  if (n_ == 0) throw InvalidArgument("fit metrics: no valid (non-NaN) samples");
  FitMetrics m;
  m.n = n_;
  m.max_abs = max_abs_;
  const double n = static_cast<double>(n_);
  m.rmse = std::sqrt(sse_ / n);
  m.mae = sae_ / n;
  const double sst = sum2_ - sum_ * sum_ / n;
  m.r2 = sst > 0.0 ? 1.0 - sse_ / sst : 0.0;
  m.range = hi_ - lo_;
  m.nrmse_pct = hi_ > lo_ ? 100.0 * m.rmse / (hi_ - lo_) : 0.0;
  m.rel_err_pct = sum2_ > 0.0 ? 100.0 * std::sqrt(sse_ / sum2_) : 0.0;
  return m;
}

FitMetrics fit_metrics(std::span<const double> y, std::span<const double> yhat) {
  if (y.size() != yhat.size())
    throw InvalidArgument(fmt::format("fit metrics: measured has {} values, predicted {}, expected equal", y.size(), yhat.size()));
  FitAccumulator acc;
  for (size_t k = 0; k < y.size(); ++k) acc.add(y[k], yhat[k]);
  return acc.metrics();
}

}  // namespace twinwatch::signal
