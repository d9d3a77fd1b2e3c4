// The monitor's acceleration of a stream with a noisy velocity and no target_qdd (a twin with an
// acceleration window): exact on a velocity whose acceleration changes linearly, and its noise.
#include "twinwatch/monitor/acceleration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace twinwatch::monitor {
namespace {

TEST(WindowedAcceleration, IsExactWhereTheAccelerationChangesLinearlyAndRestartsAtAGap) {
  WindowedAcceleration a(2, 10, 0.05);
  // qd = 0.3 + 2 t + 1.5 t^2 (qdd = 2 + 3 t) on a jittering 1 kHz clock
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> jitter(-0.0001, 0.0001);
  double t = 0.0;
  for (int k = 0; k < 100; ++k) {
    t = 0.001 * k + jitter(rng);
    VectorJ qd(2);
    qd << 0.3 + 2 * t + 1.5 * t * t, -1.0;
    const VectorJ& qdd = a.push(t, qd);
    if (k >= 19) {  // (held until both means of 10 are whole)
      // the difference of the two means over their mean times: exact for a linear velocity, and for
      // a quadratic one the acceleration at the midpoint of the two means' times (10 samples back)
      const double tm = t - 0.0095;
      EXPECT_NEAR(qdd[0], 2 + 3 * tm, 2e-3) << k;
      EXPECT_NEAR(qdd[1], 0.0, 1e-9) << k;
      EXPECT_TRUE(a.ready()) << k;
    } else {
      EXPECT_EQ(qdd[0], 0.0) << k;
      EXPECT_FALSE(a.ready()) << k;  // (the monitor judges nothing on a held value)
    }
  }
  // a step within its span (a logger's lost samples) goes on; a longer one restarts it, and the
  // estimate is held until 20 samples came again
  const double before = a.value()[0];
  VectorJ qd(2);
  qd << 0.3 + 2 * (t + 0.004) + 1.5 * (t + 0.004) * (t + 0.004), -1.0;
  EXPECT_NEAR(a.push(t + 0.004, qd)[0], 2 + 3 * (t + 0.004 - 0.0095), 0.05);
  t += 0.004;
  const double held = a.value()[0];
  EXPECT_NE(held, before);
  for (int k = 0; k < 19; ++k) {
    EXPECT_EQ(a.push(t + 1.0 + 0.001 * k, qd)[0], held) << k;
    EXPECT_FALSE(a.ready()) << k;
  }
  EXPECT_NEAR(a.push(t + 1.019, qd)[0], 0.0, 1e-9);
}

TEST(WindowedAcceleration, TakesTheVelocitysNoiseOutAsTheWindowGrows) {
  std::mt19937 rng(2);
  std::normal_distribution<double> g(0.0, 0.01);
  auto rms = [&](int w) {
    WindowedAcceleration a(1, w, 0.05);
    double e2 = 0.0;
    int m = 0;
    for (int k = 0; k < 5000; ++k) {
      VectorJ qd(1);
      qd << g(rng);
      const double v = a.push(0.001 * k, qd)[0];
      if (k >= 2 * w) e2 += v * v, ++m;  // (the mean difference's noise: sqrt(2 / w) 0.01 / (w 0.001))
    }
    return std::sqrt(e2 / m);
  };
  // the one-step difference: sqrt(2) 0.01 / 0.001 = 14 rad/s^2
  const double w5 = rms(5), w25 = rms(25);
  EXPECT_NEAR(w5, std::sqrt(2.0 / 5) * 0.01 / 0.005, 0.2);
  EXPECT_NEAR(w25, std::sqrt(2.0 / 25) * 0.01 / 0.025, 0.02);
}

// the running sums give what the two means of the ring give, summed anew, over many turns of it
TEST(WindowedAcceleration, ItsRunningSumsAreTheMeansOfTheRing) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  const int w = 7;
  WindowedAcceleration a(3, w, 1.0);
  std::vector<VectorJ> qs;
  std::vector<double> ts;
  double t = 0.0;
  double worst = 0.0;
  for (int k = 0; k < 20000; ++k) {
    t += 0.001 * (1.0 + 0.1 * g(rng) * 0.1);
    VectorJ qd(3);
    qd << 5.0 + g(rng), -3.0 * g(rng), 1e-3 * g(rng);
    qs.push_back(qd);
    ts.push_back(t);
    const VectorJ got = a.push(t, qd);
    if (k + 1 < 2 * w) continue;
    VectorJ newer = VectorJ::Zero(3), older = VectorJ::Zero(3);
    double tn = 0.0, to = 0.0;
    for (int i = 0; i < w; ++i) {
      newer += qs[static_cast<size_t>(k - i)];
      tn += ts[static_cast<size_t>(k - i)];
      older += qs[static_cast<size_t>(k - w - i)];
      to += ts[static_cast<size_t>(k - w - i)];
    }
    const VectorJ want = (newer - older) / (tn - to);
    worst = std::max(worst, (got - want).cwiseAbs().maxCoeff() / (1.0 + want.cwiseAbs().maxCoeff()));
  }
  EXPECT_LT(worst, 1e-9);
}

}  // namespace
}  // namespace twinwatch::monitor
