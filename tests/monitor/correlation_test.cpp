#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "twinwatch/core/error.hpp"
#include "twinwatch/monitor/diagnosis.hpp"

namespace twinwatch::monitor {
namespace {

// UR3e Table 5's residual / velocity correlation, fed a sample at a time, against the textbook
// two-pass Pearson coefficient in long double. The residuals ride on offsets 10^4 to 10^7 times their
// spread (a current offset): one-pass raw sums lose the coefficient's digits there (J3's sum of
// squares, ~2e12, holds a spread of ~0.02),
// Welford's keep all but ~eps x offset / spread of them.
TEST(ResidualVelocityCorrelation, OnePassItIsTheTwoPassPearsonCoefficient) {
  const int n = 3, K = 20000;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<VectorJ> r(K, VectorJ::Zero(n)), v(K, VectorJ::Zero(n));
  ResidualVelocityCorrelation c(n);
  for (int k = 0; k < K; ++k) {
    const double t = 0.002 * k;
    v[k] << std::sin(t), std::cos(0.7 * t), noise(rng);
    // J1's residual follows J1's speed (a friction-like residual), J2's opposes J3's, J3's is noise
    r[k] << 1e4 + 0.5 * v[k][0] + 0.1 * noise(rng), -2e4 - 0.8 * v[k][2] + 0.3 * noise(rng), 1e4 + 1e-3 * noise(rng);
    c.add(r[k], v[k]);
  }
  EXPECT_EQ(c.count(), K);
  const MatrixJ m = c.matrix();
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      long double mr = 0, mv = 0;
      for (int k = 0; k < K; ++k) mr += r[k][i], mv += v[k][j];
      mr /= K, mv /= K;
      long double sxy = 0, sxx = 0, syy = 0;
      for (int k = 0; k < K; ++k) {
        const long double a = r[k][i] - mr, b = v[k][j] - mv;
        sxy += a * b, sxx += a * a, syy += b * b;
      }
      EXPECT_NEAR(m(i, j), static_cast<double>(sxy / std::sqrt(sxx * syy)), 1e-7) << "residual J" << i + 1 << " vs velocity J" << j + 1;
    }
  EXPECT_GT(m(0, 0), 0.95);
  EXPECT_LT(m(1, 2), -0.9);
  EXPECT_LT(std::abs(m(2, 0)), 0.05);
}

TEST(ResidualVelocityCorrelation, ASignalThatDoesNotVaryCorrelatesWithNothing) {
  ResidualVelocityCorrelation c(2);
  EXPECT_THROW(c.matrix(), InvalidArgument);
  VectorJ r(2), v(2);
  for (int k = 0; k < 100; ++k) {
    r << 0.2, std::sin(0.1 * k);
    v << std::sin(0.1 * k), 0.0;  // J2 at rest
    c.add(r, v);
  }
  const MatrixJ m = c.matrix();
  EXPECT_EQ(m(0, 0), 0.0);  // a constant residual
  EXPECT_EQ(m(1, 1), 0.0);  // a joint at rest
  EXPECT_NEAR(m(1, 0), 1.0, 1e-12);
  EXPECT_THROW(c.add(VectorJ::Zero(3), v), InvalidArgument);
}

}  // namespace
}  // namespace twinwatch::monitor
