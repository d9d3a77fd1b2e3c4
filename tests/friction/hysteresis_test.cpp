#include "twinwatch/friction/hysteresis.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "twinwatch/core/error.hpp"

namespace twinwatch::friction {
namespace {

constexpr double kDt = 0.005;  // 200 Hz, as in HESR §V

TEST(Hysteresis, StaysBoundedUnderRandomVelocity) {
  const unsigned seed = 20261123;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 3.0);
  std::vector<double> qd(20000);
  for (double& v : qd) v = noise(rng);
  for (double alpha : {0.5, 10.0, 150.0, 199.0}) {
    const HysteresisParams p{alpha, 300.0};
    ASSERT_TRUE(p.stable(kDt)) << "alpha " << alpha;
    const HysteresisFeatures f = hysteresis_features(qd, kDt, p);
    for (std::size_t k = 0; k < qd.size(); ++k) {
      ASSERT_LE(std::abs(f.h[k]), 1.0) << "seed " << seed << " alpha " << alpha << " k " << k;
      // |hd| = alpha |tanh - h| <= 2 alpha
      ASSERT_LE(std::abs(f.hd[k]), 2.0 * alpha + 1e-12);
    }
  }
}

TEST(Hysteresis, StabilityConditionMatchesEulerFactor) {
  EXPECT_TRUE((HysteresisParams{10.0, 100.0}.stable(kDt)));
  EXPECT_FALSE((HysteresisParams{200.0, 100.0}.stable(kDt)));  // 1 - alpha dt = 0
  EXPECT_FALSE((HysteresisParams{250.0, 100.0}.stable(kDt)));  // oscillatory
  EXPECT_THROW(HysteresisState(HysteresisParams{250.0, 100.0}, kDt), InvalidArgument);
}

TEST(Hysteresis, EulerMatchesClosedFormStepResponse) {
  // constant qd > 0 with large beta: h(t) = 1 - exp(-alpha t) continuous, (1 - alpha dt)^k discrete
  const HysteresisParams p{8.0, 1e4};
  HysteresisState s(p, kDt);
  for (int k = 1; k <= 400; ++k) {
    const HysteresisSample x = s.step(1.0);
    const double discrete = 1.0 - std::pow(1.0 - p.alpha * kDt, k);
    EXPECT_NEAR(x.h, discrete, 1e-12);
    EXPECT_NEAR(x.hd, p.alpha * (1.0 - discrete), 1e-9);
    // the Euler solution stays within O(alpha dt) of the continuous one
    EXPECT_NEAR(x.h, 1.0 - std::exp(-p.alpha * k * kDt), 0.05);
  }
}

TEST(Hysteresis, DerivativeMatchesFiniteDifference) {
  // hd_k is the right-hand side of eq. 10 at step k; the forward difference of h equals it at k+1
  const HysteresisParams p{12.0, 50.0};
  std::vector<double> qd(2000);
  for (std::size_t k = 0; k < qd.size(); ++k)
    qd[k] = std::sin(2.0 * std::numbers::pi * 0.5 * static_cast<double>(k) * kDt);
  const HysteresisFeatures f = hysteresis_features(qd, kDt, p);
  for (std::size_t k = 1; k + 1 < qd.size(); ++k) {
    const double fd = (f.h[k + 1] - f.h[k]) / kDt;
    const double rhs_next = p.alpha * (std::tanh(p.beta * qd[k + 1]) - f.h[k]);
    EXPECT_NEAR(fd, rhs_next, 1e-9);
  }
}

TEST(Hysteresis, LoopIsMultiValuedAtZeroVelocity) {
  // a sinusoidal velocity gives h lagging behind tanh(beta qd): opposite signs at qd = 0 crossings
  const HysteresisParams p{6.0, 100.0};
  std::vector<double> qd(2000);
  for (std::size_t k = 0; k < qd.size(); ++k)
    qd[k] = std::sin(2.0 * std::numbers::pi * 0.5 * static_cast<double>(k) * kDt);
  const HysteresisFeatures f = hysteresis_features(qd, kDt, p);
  // qd crosses zero downwards at t = 1 s + 2n, upwards at 2 s + 2n
  EXPECT_GT(f.h[200 + 400], 0.5);
  EXPECT_LT(f.h[400 + 400], -0.5);
}

TEST(Hysteresis, SaturatesBetweenReversalsAndChangesSignAfterEach) {
  // a 0.25 Hz velocity sine (the HESR training sweep, 1.2 rad/s): between reversals
  // h settles at +-1; after each velocity reversal it changes sign within a few 1/alpha
  const HysteresisParams p{15.0, 250.0};
  const double f = 0.25, v = 1.2;
  const int n = static_cast<int>(8.0 / kDt);
  std::vector<double> qd(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k)
    qd[static_cast<std::size_t>(k)] = v * std::sin(2.0 * std::numbers::pi * f * k * kDt);
  const HysteresisFeatures feat = hysteresis_features(qd, kDt, p);
  // reversals of qd at t = 2, 4, 6 s; mid-stroke at t = 1, 3, 5, 7 s
  for (double t_mid : {1.0, 3.0, 5.0, 7.0}) {
    const auto k = static_cast<std::size_t>(t_mid / kDt);
    EXPECT_NEAR(std::abs(feat.h[k]), 1.0, 1e-6) << "t " << t_mid;
    EXPECT_GT(feat.h[k] * qd[k], 0.0) << "t " << t_mid;
  }
  for (double t_rev : {2.0, 4.0, 6.0}) {
    const auto k_rev = static_cast<std::size_t>(t_rev / kDt + 0.5);
    // just before the reversal h still has the sign of the old motion
    EXPECT_GT(feat.h[k_rev - 2] * qd[k_rev - 2], 0.0) << "t " << t_rev;
    // it crosses zero within 0.2 s (3 time constants of 1/alpha plus the tanh transition)
    std::size_t k_cross = k_rev;
    while (k_cross < feat.h.size() && feat.h[k_cross] * qd[k_rev + 2] < 0.0) ++k_cross;
    const double lag = static_cast<double>(k_cross - k_rev) * kDt;
    EXPECT_GT(lag, 0.0) << "t " << t_rev;  // memory: h lags the velocity
    EXPECT_LT(lag, 0.2) << "t " << t_rev;
    // hd has the sign of the new motion right after the reversal
    EXPECT_GT(feat.hd[k_rev + 4] * qd[k_rev + 4], 0.0) << "t " << t_rev;
  }
}

TEST(Hysteresis, StabilityViolationNamesAlphaAndDt) {
  try {
    HysteresisState s(HysteresisParams{250.0, 100.0}, kDt);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("alpha*dt is 1.25"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("must be in (0, 1)"));
  }
  // hysteresis_features reports the same violation
  const std::vector<double> qd(10, 0.1);
  EXPECT_THROW(hysteresis_features(qd, 0.01, HysteresisParams{150.0, 100.0}), InvalidArgument);
}

TEST(Hysteresis, InvalidAlphaIsRejected) {
  try {
    HysteresisParams{-1.0, 10.0}.validate();
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("alpha is -1"));
  }
}

TEST(Hysteresis, InvalidBetaIsRejected) {
  try {
    HysteresisParams{1.0, 0.0}.validate();
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("beta is 0"));
  }
}

TEST(Hysteresis, InvalidInitialStateIsRejected) {
  EXPECT_THROW(HysteresisState(HysteresisParams{}, kDt, 1.5), InvalidArgument);
  EXPECT_THROW(HysteresisState(HysteresisParams{}, 0.0), InvalidArgument);
}

// ---- the displacement clock (eq. 10 in ds = |qd| dt): Dahl-like, rate-independent memory ----

HysteresisParams displacement(double alpha, double beta) { return {alpha, beta, HysteresisDrive::Displacement}; }

TEST(HysteresisDisplacement, ReproducesTheDahlLoopAfterAReversal) {
  // Dahl (exponent 1) with a sign-like transition: after a reversal from h_r, moving a distance d
  // in the new direction gives h = sgn - (sgn - h_r) exp(-alpha d), whatever the speed profile.
  // The velocity here is random and positive; d is its rectangle-rule integral.
  const unsigned seed = 7;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> speed(0.01, 2.0);
  const HysteresisParams p = displacement(400.0, 1e7);
  HysteresisState s(p, kDt);
  // first saturate at h = -1 by a long negative move
  for (int k = 0; k < 400; ++k) s.step(-1.0);
  ASSERT_NEAR(s.h(), -1.0, 1e-12);
  double d = 0.0;
  for (int k = 0; k < 300; ++k) {
    const double v = speed(rng);
    const HysteresisSample x = s.step(v);
    d += v * kDt;
    const double dahl = 1.0 - 2.0 * std::exp(-p.alpha * d);
    ASSERT_NEAR(x.h, dahl, 1e-12) << "seed " << seed << " k " << k;
    // hd = dh/dt = alpha |qd| (1 - h): the Dahl slope dh/ds times the speed
    ASSERT_NEAR(x.hd, p.alpha * v * (1.0 - dahl), 1e-9);
  }
}

TEST(HysteresisDisplacement, LoopIsRateIndependentWhileTheTimeClockIsNot) {
  // position q = A sin(2 pi f t) at 0.25 Hz and 1 Hz, 400 samples per period each: the same
  // positions are visited at the same samples, and per-sample displacements are equal, so the
  // displacement clock gives the identical h-q loop; the time clock (eq. 11) gives different loops.
  constexpr int kPerPeriod = 400, kPeriods = 3;
  const double A = 0.3;  // [rad]
  const auto run = [&](double f, const HysteresisParams& p) {
    const double dt = 1.0 / (f * kPerPeriod);
    std::vector<double> qd(kPerPeriod * kPeriods);
    for (std::size_t k = 0; k < qd.size(); ++k)
      qd[k] = 2.0 * std::numbers::pi * f * A * std::cos(2.0 * std::numbers::pi * f * static_cast<double>(k) * dt);
    // beta scaled with 1/f keeps tanh(beta qd) a function of the position phase only
    HysteresisParams q = p;
    q.beta = p.beta / f;
    return hysteresis_features(qd, dt, q).h;
  };
  const std::vector<double> slow = run(0.25, displacement(60.0, 50.0)), fast = run(1.0, displacement(60.0, 50.0));
  double max_diff = 0.0;
  for (std::size_t k = 0; k < slow.size(); ++k) max_diff = std::max(max_diff, std::abs(slow[k] - fast[k]));
  EXPECT_LT(max_diff, 1e-12);
  // the loop is a real hysteresis loop: different h at the same position on the way up and down
  // (samples 400 and 200 of a period are both at q = 0, moving up and down)
  EXPECT_GT(slow[2 * kPerPeriod] - slow[kPerPeriod + 200], 1.0);
  // the time clock with the same alpha [1/s] at 0.25 and 1 Hz: not rate independent
  const HysteresisParams t{4.0, 50.0};
  const std::vector<double> slow_t = run(0.25, t), fast_t = run(1.0, t);
  double max_diff_t = 0.0;
  for (std::size_t k = 0; k < slow_t.size(); ++k) max_diff_t = std::max(max_diff_t, std::abs(slow_t[k] - fast_t[k]));
  EXPECT_GT(max_diff_t, 0.1);
}

TEST(HysteresisDisplacement, KeepsItsMemoryAtStandstill) {
  // the time clock relaxes h to tanh(0) = 0 while the joint stands still; the displacement clock
  // keeps the pre-sliding state (no motion, no change), like a deflected bristle
  HysteresisState disp(displacement(300.0, 200.0), kDt), time(HysteresisParams{10.0, 200.0}, kDt);
  for (int k = 0; k < 200; ++k) {
    disp.step(0.5);
    time.step(0.5);
  }
  const double h_disp = disp.h(), h_time = time.h();
  ASSERT_GT(h_disp, 0.99);
  ASSERT_GT(h_time, 0.99);
  for (int k = 0; k < 1000; ++k) {  // 5 s at rest
    const HysteresisSample d = disp.step(0.0);
    EXPECT_EQ(d.hd, 0.0);
    time.step(0.0);
  }
  EXPECT_EQ(disp.h(), h_disp);
  EXPECT_LT(std::abs(time.h()), 1e-6);
}

TEST(HysteresisDisplacement, StaysBoundedForAnyStepSize) {
  // the exact exponential step is a convex combination of h and tanh(beta qd): |h| <= 1 even when
  // alpha |qd| dt is far above the Euler limit of eq. 11
  const unsigned seed = 11;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 3.0);
  std::vector<double> qd(20000);
  for (double& v : qd) v = noise(rng);
  for (double alpha : {1.0, 1e3, 1e6}) {
    const HysteresisParams p = displacement(alpha, 300.0);
    EXPECT_TRUE(p.stable(kDt));
    const HysteresisFeatures f = hysteresis_features(qd, kDt, p);
    for (std::size_t k = 0; k < qd.size(); ++k) {
      ASSERT_LE(std::abs(f.h[k]), 1.0) << "seed " << seed << " alpha " << alpha << " k " << k;
      ASSERT_LE(std::abs(f.hd[k]), 2.0 * alpha * std::abs(qd[k]) + 1e-9);
    }
  }
}

TEST(HysteresisDisplacement, MatchesTheTimeClockInTheSmallStepLimitAtUnitSpeed) {
  // at |qd| = 1 rad/s the displacement clock is the time clock (ds = dt); its exact step
  // h = T + (h - T) e^{-alpha dt} and Euler's (1 - alpha dt) agree to O((alpha dt)^2) per step
  const double alpha = 2.0, dt = 1e-4;
  HysteresisState disp(displacement(alpha, 1e4), dt), time(HysteresisParams{alpha, 1e4}, dt);
  for (int k = 0; k < 20000; ++k) {
    const double v = (k / 5000) % 2 ? -1.0 : 1.0;
    EXPECT_NEAR(disp.step(v).h, time.step(v).h, 2e-4) << "k " << k;
  }
}

}  // namespace
}  // namespace twinwatch::friction
