#include "model/fast_sincos.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace twinwatch::model::detail {
namespace {

// agreement with libm within a few ulp over the range joint angles take, and beyond
TEST(FastSincos, MatchesLibmToAFewUlp) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  double worst = 0.0;
  for (int k = 0; k < 200000; ++k) {
    const double x = k < 100 ? (k - 50) * M_PI / 4 : u(rng);  // include the quadrant boundaries
    double s, c;
    fast_sincos(x, s, c);
    worst = std::max({worst, std::abs(s - std::sin(x)), std::abs(c - std::cos(x))});
  }
  EXPECT_LT(worst, 4e-16);
  double s, c;
  fast_sincos(1e9, s, c);  // fallback path
  EXPECT_EQ(s, std::sin(1e9));
  EXPECT_EQ(c, std::cos(1e9));
}

// the batched, branch-free version (vectorised) gives bit-identical results, fallback included
TEST(FastSincos, BatchEqualsScalarElementByElement) {
  std::mt19937 rng(18);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  for (int k = 0; k < 20000; ++k) {
    double x[7], s[7], c[7];
    const int n = 1 + k % 7;
    for (int i = 0; i < n; ++i) x[i] = k < 100 ? (k - 50 + i) * M_PI / 4 : u(rng);
    if (k % 1000 == 999) x[n - 1] = 1e9;  // one angle out of range: the whole batch falls back
    fast_sincos_n(x, n, s, c);
    for (int i = 0; i < n; ++i) {
      double se, ce;
      fast_sincos(x[i], se, ce);
      ASSERT_EQ(s[i], se) << "seed 18 batch " << k << " element " << i;
      ASSERT_EQ(c[i], ce) << "seed 18 batch " << k << " element " << i;
    }
  }
}

}  // namespace
}  // namespace twinwatch::model::detail
