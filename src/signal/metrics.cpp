#include "twinwatch/signal/metrics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "twinwatch/core/error.hpp"

namespace twinwatch::signal {

FitMetrics fit_metrics(std::span<const double> y, std::span<const double> yhat) {
  if (y.size() != yhat.size())
    throw InvalidArgument(fmt::format("fit metrics: measured has {} values, predicted {}, expected equal", y.size(), yhat.size()));
  FitMetrics m;
  double sum = 0.0, sum2 = 0.0, sse = 0.0, sae = 0.0, lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (size_t k = 0; k < y.size(); ++k) {
    if (std::isnan(y[k]) || std::isnan(yhat[k])) continue;
    const double e = y[k] - yhat[k];
    sse += e * e;
    sae += std::abs(e);
    sum += y[k];
    sum2 += y[k] * y[k];
    lo = std::min(lo, y[k]);
    hi = std::max(hi, y[k]);
    m.max_abs = std::max(m.max_abs, std::abs(e));
    ++m.n;
  }
  if (m.n == 0) throw InvalidArgument("fit metrics: no valid (non-NaN) samples");
  const double n = static_cast<double>(m.n);
  m.rmse = std::sqrt(sse / n);
  m.mae = sae / n;
  const double sst = sum2 - sum * sum / n;
  m.r2 = sst > 0.0 ? 1.0 - sse / sst : 0.0;
  m.range = hi - lo;
  m.nrmse_pct = hi > lo ? 100.0 * m.rmse / (hi - lo) : 0.0;
  m.rel_err_pct = sum2 > 0.0 ? 100.0 * std::sqrt(sse / sum2) : 0.0;
  return m;
}

}  // namespace twinwatch::signal
