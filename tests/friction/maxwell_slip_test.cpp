// The generalized Maxwell-slip truth and the simulated joint records: pre-sliding physics
// (initial stiffness, break-away, Masing's rule, rate independence), sliding limit, measurement.
#include "twinwatch/friction/maxwell_slip.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <vector>

#include "twinwatch/core/error.hpp"
#include "twinwatch/friction/synthetic_joint.hpp"

namespace twinwatch::friction {
namespace {

using ::testing::HasSubstr;

/// Three elements, no Stribeck peak (Fs = Fc) so the caps do not depend on the velocity.
MaxwellSlipParams flat_params() {
  MaxwellSlipParams p;
  p.elements = {{4000.0, 0.5}, {1000.0, 0.3}, {200.0, 0.2}};
  p.Fc = p.Fs = 2.0;
  p.vs = 0.05;
  p.sigma2 = 0.0;
  return p;
}

/// Moves the model by displacement x at constant velocity v in steps of h; returns the last torque.
double move(MaxwellSlipFriction& m, double x, double v, double h = 1e-5) {
  const auto n = static_cast<long>(std::lround(std::abs(x / v) / h));
  double tau = 0.0;
  for (long i = 0; i < n; ++i) tau = m.step(v, h);
  return tau;
}

TEST(MaxwellSlip, VirginCurveHasTheSummedStiffnessThenBreaksAwayElementByElement) {
  const MaxwellSlipParams p = flat_params();
  MaxwellSlipFriction m(p);
  // before the first break-away (w_1 Fc / k_1 = 0.25 mrad) the slope is sum k_i
  EXPECT_NEAR(move(m, 1e-4, 0.01), 1e-4 * 5200.0, 1e-3);
  // beyond the last break-away (0.4 Fc... w_3 Fc / k_3 = 2 mrad) the full Coulomb level
  MaxwellSlipFriction m2(p);
  EXPECT_NEAR(move(m2, 5e-3, 0.01), p.Fc, 1e-9);
}

TEST(MaxwellSlip, ReversalFollowsMasingsRule) {
  // after a reversal the curve is the virgin curve scaled by two: F_r - F(d) = 2 F_virgin(d / 2)
  const MaxwellSlipParams p = flat_params();
  for (double d : {2e-4, 8e-4, 2e-3}) {
    MaxwellSlipFriction virgin(p);
    const double fv = move(virgin, d / 2.0, 0.01);
    MaxwellSlipFriction m(p);
    const double f_rev = move(m, 1e-2, 0.01);  // fully sliding in +
    const double f_after = move(m, d, -0.01);
    EXPECT_NEAR(f_rev - f_after, 2.0 * fv, 2e-3) << "d " << d;
  }
}

TEST(MaxwellSlip, PreSlidingIsRateIndependent) {
  // the same displacement at two velocities (no Stribeck, no lag) gives the same force
  const MaxwellSlipParams p = flat_params();
  MaxwellSlipFriction slow(p), fast(p);
  EXPECT_NEAR(move(slow, 1.5e-3, 0.002, 1e-5), move(fast, 1.5e-3, 0.2, 1e-7), 1e-3);
}

TEST(MaxwellSlip, SteadySlidingFollowsTheStribeckCurvePlusViscous) {
  MaxwellSlipParams p = flat_params();
  p.Fs = 3.0;
  p.sigma2 = 1.5;
  p.lag_time = 0.02;
  for (double v : {0.01, 0.05, 0.2, -0.5}) {
    MaxwellSlipFriction m(p);
    const double tau = move(m, 0.5 * std::abs(v) + 0.02, v, 1e-4);  // long enough for the lag to settle
    const double s = p.Fc + (p.Fs - p.Fc) * std::exp(-(v / p.vs) * (v / p.vs));
    EXPECT_NEAR(tau, std::copysign(s, v) + p.sigma2 * v, 1e-6) << "v " << v;
  }
}

TEST(MaxwellSlip, InvalidParametersAreNamed) {
  MaxwellSlipParams p = flat_params();
  p.elements[1].stiffness = -3.0;
  EXPECT_THAT([&] { MaxwellSlipFriction{p}; },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("elements[1].stiffness is -3")));
  p = flat_params();
  p.elements[0].weight = 0.6;
  EXPECT_THAT([&] { MaxwellSlipFriction{p}; },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("weights sum to 1.1, expected 1")));
  p = flat_params();
  p.lag_time = -1.0;
  EXPECT_THAT([&] { MaxwellSlipFriction{p}; }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("lag_time is -1")));
  p.elements.clear();
  EXPECT_THAT([&] { p.validate(); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("elements is empty")));
}

TEST(SyntheticJoint, MeasuredVelocityAndNoiseHaveTheRequestedLevels) {
  const MaxwellSlipParams p = flat_params();
  SyntheticJointOptions o;
  o.torque_noise = 0.1;
  o.seed = 31;
  const SyntheticRecord r = simulate_joint(p, sine_profile(0.25, 1.2, 20.0), o);
  ASSERT_EQ(r.record.size(), 4001);
  ASSERT_EQ(r.frequency.size(), 4001u);
  // velocity: central difference of a 20-bit encoder: error ~ lsb / (2 dt) plus O(dt^2)
  double max_dv = 0.0, s = 0.0, s2 = 0.0;
  for (std::size_t k = 1; k + 1 < r.true_qd.size(); ++k) max_dv = std::max(max_dv, std::abs(r.record.qd[k] - r.true_qd[k]));
  EXPECT_LT(max_dv, o.encoder_lsb / o.dt + 2e-4);
  // torque noise: sample standard deviation within 5 % of sigma
  for (std::size_t k = 0; k < r.true_tau.size(); ++k) {
    const double e = r.record.tau[k] - r.true_tau[k];
    s += e;
    s2 += e * e;
  }
  const double n = static_cast<double>(r.true_tau.size());
  EXPECT_NEAR(std::sqrt(s2 / n - (s / n) * (s / n)), o.torque_noise, 0.05 * o.torque_noise) << "seed " << o.seed;
  // same seed, same record
  EXPECT_EQ(simulate_joint(p, sine_profile(0.25, 1.2, 20.0), o).record.tau, r.record.tau);
}

TEST(SyntheticJoint, ChirpFrequencyRunsFromStartToEnd) {
  const SyntheticRecord r = simulate_joint(flat_params(), chirp_profile(0.1, 1.0, 1.2, 20.0));
  EXPECT_NEAR(r.frequency.front(), 0.1, 1e-12);
  EXPECT_NEAR(r.frequency.back(), 1.0, 1e-12);
  EXPECT_NEAR(r.frequency[2000], 0.55, 1e-12);
}

TEST(SyntheticJoint, FourierProfileReachesTheRequestedPeak) {
  const VelocityProfile p = fourier_profile(5, 0.1, 1.2, 20.0, 4);
  double peak = 0.0;
  for (int i = 0; i < 20000; ++i) peak = std::max(peak, std::abs(p.qd(i * 1e-3)));
  EXPECT_NEAR(peak, 1.2, 1e-3);
}

// the crawl-training profile: the sweep, then plateaus held after a raised-cosine blend, continuous
// everywhere; a sweep that is not a whole number of periods is refused with its numbers
TEST(SyntheticJoint, SweepAndCrawlsHoldsEachPlateauAfterAContinuousBlend) {
  const std::vector<double> crawls{0.02, -0.05, 0.1};
  const VelocityProfile p = sweep_and_crawls_profile(0.25, 1.2, 8.0, crawls, 1.0, 0.2);
  EXPECT_DOUBLE_EQ(p.duration, 11.0);
  EXPECT_DOUBLE_EQ(p.qd(1.0), 1.2);                             // the sweep's crest
  EXPECT_NEAR(p.qd(8.0 - 1e-9), 0.0, 1e-8);                      // ends at rest
  for (std::size_t i = 0; i < crawls.size(); ++i) {
    const double t0 = 8.0 + static_cast<double>(i);
    EXPECT_DOUBLE_EQ(p.qd(t0 + 0.2), crawls[i]) << i;             // held after the blend
    EXPECT_DOUBLE_EQ(p.qd(t0 + 0.99), crawls[i]) << i;
    const double from = i == 0 ? 0.0 : crawls[i - 1];
    EXPECT_NEAR(p.qd(t0 + 0.1), 0.5 * (from + crawls[i]), 1e-12) << i;  // half-way at mid-blend
  }
  for (double t = 0.0; t < p.duration; t += 1e-3) EXPECT_LT(std::abs(p.qd(t + 1e-3) - p.qd(t)), 2e-3) << t;
  try {
    sweep_and_crawls_profile(0.25, 1.2, 7.0, crawls, 1.0, 0.2);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("sweep_time 7 s is 1.75 periods"));
  }
}

// One joint, two motions in a row: simulating the second from the state the first left gives the
// truth of one run over both (the memory carries across: pre-sliding from stressed elements), and
// differs from the same motion started relaxed by up to the Coulomb level.
TEST(SyntheticJoint, ASecondMotionContinuesTheStateTheFirstLeft) {
  const MaxwellSlipParams p = flat_params();
  const VelocityProfile first = sine_profile(0.25, 1.2, 4.0);  // one period, ends at rest moving down to 0 from below
  VelocityProfile second;
  second.name = "second";
  second.duration = 2.0;
  second.qd = [](double t) { return 0.3 * std::sin(M_PI * t); };  // starts at rest, moves up
  VelocityProfile both;
  both.name = "both";
  both.duration = 6.0;
  both.qd = [&](double t) { return t < 4.0 ? first.qd(t) : second.qd(t - 4.0); };
  SyntheticJointOptions o;
  o.torque_noise = 0.0;
  MaxwellSlipFriction state(p);
  simulate_joint(state, first, o);
  EXPECT_LT(state.torque(0.0), -0.5 * p.Fc) << "the sweep's last motion (down) leaves the elements stressed";
  const SyntheticRecord continued = simulate_joint(state, second, o);
  const SyntheticRecord whole = simulate_joint(p, both, o);
  const SyntheticRecord fresh = simulate_joint(p, second, o);
  ASSERT_EQ(continued.true_tau.size(), 401u);
  double worst = 0.0, apart = 0.0;
  for (std::size_t k = 0; k < continued.true_tau.size(); ++k) {
    worst = std::max(worst, std::abs(continued.true_tau[k] - whole.true_tau[800 + k]));
    apart = std::max(apart, std::abs(continued.true_tau[k] - fresh.true_tau[k]));
  }
  EXPECT_LT(worst, 1e-9) << "N·m";
  EXPECT_GT(apart, 0.9 * p.Fc) << "a relaxed start forgets the first motion";
}

TEST(SyntheticJoint, InvalidOptionsAreNamed) {
  SyntheticJointOptions o;
  o.substeps = 0;
  EXPECT_THAT([&] { o.validate(); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("substeps is 0")));
  o = {};
  o.torque_noise = -0.1;
  EXPECT_THAT([&] { o.validate(); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("torque_noise is -0.1")));
  VelocityProfile empty;
  empty.name = "nothing";
  EXPECT_THAT([&] { simulate_joint(flat_params(), empty); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("profile 'nothing' has no qd(t)")));
}

}  // namespace
}  // namespace twinwatch::friction
