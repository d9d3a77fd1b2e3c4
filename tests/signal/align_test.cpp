#include "twinwatch/signal/align.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "twinwatch/core/error.hpp"
#include "error_text.hpp"

namespace twinwatch::signal {
namespace {

constexpr double kDt = 0.002;  // 500 Hz

// a smooth joint-angle-like motion [rad]: a few harmonics of a 4 s period plus a slow drift
double motion(double t) {
  return 0.6 * std::sin(2 * M_PI * 0.25 * t) + 0.2 * std::sin(2 * M_PI * 0.75 * t + 0.4) + 0.05 * std::cos(2 * M_PI * 1.5 * t) + 0.02 * t;
}

// n samples of the motion delayed by `delay` samples, plus white noise of sigma
std::vector<double> record(size_t n, double delay, double sigma, std::mt19937& rng) {
  std::normal_distribution<double> nd(0.0, 1.0);
  std::vector<double> x(n);
  for (size_t k = 0; k < n; ++k) x[k] = motion((static_cast<double>(k) - delay) * kDt) + sigma * nd(rng);
  return x;
}

TEST(Align, RecoversIntegerShiftsBothWays) {
  const unsigned seed = 11;
  std::mt19937 rng(seed);
  const auto a = record(4000, 0.0, 0.0, rng);
  for (int shift : {37, -120, 0, 350}) {
    const auto b = record(4000, shift, 0.0, rng);
    const Alignment r = align(a, b, {500, true, true});
    ASSERT_TRUE(r.valid);
    EXPECT_EQ(r.integer_lag, shift);
    EXPECT_NEAR(r.lag, shift, 1e-3) << "seed " << seed;
    EXPECT_FALSE(r.at_window_edge);
    EXPECT_NEAR(r.correlation, 1.0, 1e-12);
    // the parabola's vertex sits within 1e-3 samples of an exact integer peak (the overlap differs
    // by a sample between the neighbours); on the integer grid the comparison is exact
    EXPECT_LT(r.aligned.rmse, 1e-5);
    EXPECT_LT(align(a, b, {500, false, true}).aligned.rmse, 1e-12);
    if (shift != 0) {
      EXPECT_GT(r.raw.rmse, 100 * r.aligned.rmse + 1e-3);
    }
  }
}

// sub-sample refinement: the parabola through the correlation peak finds fractional delays that
// the integer grid rounds away
TEST(Align, ParabolicRefinementRecoversFractionalShifts) {
  const unsigned seed = 12;
  std::mt19937 rng(seed);
  const auto a = record(4000, 0.0, 0.0, rng);
  for (double shift : {12.3, -7.75, 0.5, 101.9}) {
    const auto b = record(4000, shift, 0.0, rng);
    const Alignment fine = align(a, b, {300, true, true});
    const Alignment coarse = align(a, b, {300, false, true});
    if (std::abs(shift - std::round(shift)) < 0.5) {
      EXPECT_EQ(coarse.lag, std::round(shift)) << shift;  // the integer grid rounds to the nearest sample
    }
    EXPECT_NEAR(fine.lag, shift, 0.02) << shift;
    EXPECT_LT(std::abs(fine.lag - shift), std::abs(coarse.lag - shift)) << shift;
    // the interpolated comparison beats the integer one
    EXPECT_LT(fine.aligned.rmse, coarse.aligned.rmse) << shift;
  }
}

// UR3e §3.4 / Table 2: a 0.7 s start-trigger latency between two noisy recordings of one motion
TEST(Align, NoisyRecordingsReportLowerAlignedErrors) {
  const unsigned seed = 13;
  std::mt19937 rng(seed);
  const double sigma = 0.002;  // [rad], far above an encoder's noise
  const auto a = record(6000, 0.0, sigma, rng);
  const auto b = record(6000, 350.0, sigma, rng);
  const Alignment r = align(a, b, {600, true, true});
  EXPECT_EQ(r.integer_lag, 350) << "seed " << seed;
  EXPECT_NEAR(r.lag, 350.0, 0.25) << "seed " << seed;
  // aligned: what is left is the noise of both, sqrt(2) sigma
  EXPECT_NEAR(r.aligned.rmse, std::sqrt(2.0) * sigma, 0.15 * sigma) << "seed " << seed;
  EXPECT_NEAR(r.aligned.mae, std::sqrt(2.0) * sigma * std::sqrt(2.0 / M_PI), 0.15 * sigma);
  EXPECT_GT(r.raw.rmse, 20 * r.aligned.rmse);
  EXPECT_GT(r.raw.mae, 20 * r.aligned.mae);
}

// the report's numbers are plain RMSE/MAE of the pairs it says it compares
TEST(Align, MetricsCompareTheStatedPairs) {
  std::vector<double> a(50), b(60);
  for (size_t k = 0; k < a.size(); ++k) a[k] = std::sin(0.3 * static_cast<double>(k));
  for (size_t k = 0; k < b.size(); ++k) b[k] = std::sin(0.3 * (static_cast<double>(k) - 4.0)) + (k % 2 ? 0.01 : -0.01);
  const Alignment r = align(a, b, {10, false, true});
  ASSERT_EQ(r.integer_lag, 4);
  double sse = 0.0, sae = 0.0;
  for (size_t k = 0; k < 50; ++k) {
    sse += (a[k] - b[k]) * (a[k] - b[k]);
    sae += std::abs(a[k] - b[k]);
  }
  EXPECT_NEAR(r.raw.rmse, std::sqrt(sse / 50), 1e-12);
  EXPECT_NEAR(r.raw.mae, sae / 50, 1e-12);
  // aligned: a[k] with b[k + 4], k = 0..49 (all inside b): the alternating 0.01
  EXPECT_EQ(r.aligned.n, 50);
  EXPECT_NEAR(r.aligned.rmse, 0.01, 1e-12);
  EXPECT_NEAR(r.aligned.mae, 0.01, 1e-12);
}

TEST(Align, CommonLagUsesAllChannelsAndSkipsConstantOnes) {
  const unsigned seed = 14;
  std::mt19937 rng(seed);
  std::vector<std::vector<double>> a, b;
  a.push_back(record(3000, 0.0, 0.01, rng));
  b.push_back(record(3000, 60.0, 0.01, rng));
  a.push_back(record(3000, 0.0, 0.0, rng));
  b.push_back(record(3000, 60.0, 0.0, rng));
  a.emplace_back(3000, 1.25);  // a joint that does not move
  b.emplace_back(3000, 1.25);
  const auto common = align_channels(a, b, {200, true, true});
  ASSERT_EQ(common.size(), 3u);
  for (const auto& r : common) EXPECT_NEAR(r.lag, 60.0, 0.3) << "seed " << seed;
  EXPECT_DOUBLE_EQ(common[0].lag, common[1].lag);
  EXPECT_TRUE(common[0].valid && common[1].valid);
  EXPECT_FALSE(common[2].valid);
  EXPECT_EQ(common[2].aligned.rmse, 0.0);
  const auto own = align_channels(a, b, {200, true, false});
  EXPECT_NE(own[0].lag, own[1].lag);  // each its own estimate
  EXPECT_NEAR(own[1].lag, 60.0, 0.02);
  EXPECT_FALSE(own[2].valid);
}

TEST(Align, FlagsAPeakOnTheWindowEdgeAndClipsTheWindow) {
  std::mt19937 rng(15);
  const auto a = record(2000, 0.0, 0.0, rng);
  const auto b = record(2000, 150.0, 0.0, rng);
  const Alignment r = align(a, b, {100, true, true});
  EXPECT_TRUE(r.at_window_edge);
  EXPECT_EQ(r.integer_lag, 100);
  EXPECT_EQ(align(a, b, {5000, true, true}).window, 1000);  // half the shorter signal
}

TEST(Align, ShiftedInterpolatesLinearly) {
  const std::vector<double> x{0, 2, 4, 6, 8};
  const auto y = shifted(x, 1.25);
  EXPECT_DOUBLE_EQ(y[0], 2.5);
  EXPECT_DOUBLE_EQ(y[2], 6.5);
  EXPECT_TRUE(std::isnan(y[4]));
  EXPECT_TRUE(std::isnan(shifted(x, -0.5)[0]));
  EXPECT_DOUBLE_EQ(shifted(x, -0.5)[1], 1.0);
}

std::string error_of(const std::function<void()>& f) {
  return twinwatch::test::error_text<InvalidArgument>([&] { f(); });
}

TEST(Align, ValidationNamesTheProblem) {
  const std::vector<double> x(10, 1.0), y(3, 1.0);
  EXPECT_THAT(error_of([&] { align(x, x, {-1, true, true}); }), ::testing::HasSubstr("max_lag is -1, must be >= 0"));
  EXPECT_THAT(error_of([&] { align(x, y); }), ::testing::HasSubstr("signal b has 3 samples, expected at least 4"));
  EXPECT_THAT(error_of([&] { align_channels({x, x}, {x}); }), ::testing::HasSubstr("a has 2 channels, b 1"));
  EXPECT_THAT(error_of([&] { align_channels({x, y}, {x, x}); }), ::testing::HasSubstr("signal a has 3 samples"));
}

}  // namespace
}  // namespace twinwatch::signal
