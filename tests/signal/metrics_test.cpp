#include "twinwatch/signal/metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "twinwatch/core/error.hpp"

namespace twinwatch::signal {
namespace {

TEST(FitMetrics, HandComputedValues) {
  const std::vector<double> y{1, 2, 3, 4}, yhat{1.5, 2, 2.5, 4};
  const FitMetrics m = fit_metrics(y, yhat);
  EXPECT_DOUBLE_EQ(m.rmse, std::sqrt(0.5 / 4));
  EXPECT_DOUBLE_EQ(m.mae, 1.0 / 4);
  EXPECT_DOUBLE_EQ(m.r2, 1.0 - 0.5 / 5.0);       // SS_tot = 5
  EXPECT_DOUBLE_EQ(m.nrmse_pct, 100 * std::sqrt(0.125) / 3);
  EXPECT_DOUBLE_EQ(m.rel_err_pct, 100 * std::sqrt(0.5 / 30));
  EXPECT_DOUBLE_EQ(m.max_abs, 0.5);
}

TEST(FitMetrics, PerfectPredictionAndNanSkipping) {
  const std::vector<double> y{1, NAN, 3}, yhat{1, 7, 3};
  const FitMetrics m = fit_metrics(y, yhat);
  EXPECT_EQ(m.n, 2);
  EXPECT_EQ(m.rmse, 0.0);
  EXPECT_EQ(m.r2, 1.0);
}

// a report streams a day's recording through one accumulator per joint: the same figures, pair by pair
TEST(FitMetrics, AccumulatedPairByPairTheyAreTheHandComputedOnes) {
  FitAccumulator acc;
  EXPECT_THROW(acc.metrics(), InvalidArgument);
  acc.add(NAN, 1.0);
  EXPECT_THROW(acc.metrics(), InvalidArgument) << "a NaN pair is no sample";
  const double y[] = {1, 2, 3, 4}, yhat[] = {1.5, 2, 2.5, 4};
  for (int k = 0; k < 4; ++k) acc.add(y[k], yhat[k]);
  const FitMetrics m = acc.metrics();
  EXPECT_EQ(acc.count(), 4);
  EXPECT_EQ(m.n, 4);
  EXPECT_DOUBLE_EQ(m.rmse, std::sqrt(0.5 / 4));
  EXPECT_DOUBLE_EQ(m.r2, 1.0 - 0.5 / 5.0);
  EXPECT_DOUBLE_EQ(m.range, 3.0);
  EXPECT_DOUBLE_EQ(m.rel_err_pct, 100 * std::sqrt(0.5 / 30));
}

TEST(FitMetrics, MismatchedLengthsAreRejected) {
  const std::vector<double> a{1, 2}, b{1};
  EXPECT_THROW(fit_metrics(a, b), InvalidArgument);
}

}  // namespace
}  // namespace twinwatch::signal
