// HESR §V-G closed loop on the simulated joints: the eq. 19-20 feed-forward with the true friction
// must track better than no feed-forward and than the rigid-body-only baseline.
#include "twinwatch/friction/closed_loop.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::friction {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

constexpr unsigned kSeed = 1;

TEST(AdaptivePdGains, DecayFromMaxAtRestToMinAtSpeed) {
  AdaptivePdGains g;
  g.kp_min = 0.01;
  g.kp_max = 0.1;
  g.kd_min = 0.0;
  g.kd_max = 0.002;
  g.lambda = 4.0;
  EXPECT_DOUBLE_EQ(g.kp(0.0), 0.1);
  EXPECT_DOUBLE_EQ(g.kd(0.0), 0.002);
  EXPECT_NEAR(g.kp(10.0), 0.01, 1e-12);
  // eq. 20 is even in qd_d and halves the excess over K^min every ln(2)/lambda rad/s
  EXPECT_DOUBLE_EQ(g.kp(-0.3), g.kp(0.3));
  EXPECT_NEAR(g.kp(std::log(2.0) / 4.0) - 0.01, 0.5 * (0.1 - 0.01), 1e-12);
}

class ClosedLoopJoint : public ::testing::TestWithParam<int> {};

TEST_P(ClosedLoopJoint, TrueFrictionFeedForwardBeatsNoFeedForward) {
  const SimulatedJoint joint = simulated_study_joints()[static_cast<std::size_t>(GetParam())];
  const ClosedLoopOptions o = closed_loop_options_for(joint);
  const VelocityProfile desired = closed_loop_profile(kSeed);
  const ClosedLoopRun none = run_closed_loop(joint.truth, desired, nullptr, o, false);
  const ClosedLoopRun baseline = run_closed_loop(joint.truth, desired, nullptr, o, true);
  MaxwellSlipOracle oracle(joint.truth);
  const ClosedLoopRun ideal = run_closed_loop(joint.truth, desired, &oracle, o, true);
  EXPECT_GT(none.reversals, 3) << joint.name;
  EXPECT_LT(ideal.rmse, 0.8 * none.rmse) << joint.name;
  EXPECT_LT(ideal.rmse, baseline.rmse) << joint.name;
  EXPECT_LT(ideal.reversal_rmse, none.reversal_rmse) << joint.name;
  EXPECT_LT(ideal.segment_average, none.segment_average) << joint.name;
  // the error is a real tracking error: positions stay within 0.5 rad of the desired path
  for (std::size_t k = 0; k < none.q.size(); ++k) ASSERT_LT(std::abs(none.q_d[k] - none.q[k]), 0.5) << k;
}

INSTANTIATE_TEST_SUITE_P(Joints, ClosedLoopJoint, ::testing::Values(0, 1, 2),
                         [](const ::testing::TestParamInfo<int>& i) { return "J" + std::to_string(i.param + 1); });

TEST(ClosedLoop, WithoutFrictionEveryCompensationTracksAlike) {
  // a plant without friction: Baseline's tau_d = I qdd_d is exact, so it is no worse than None
  SimulatedJoint joint = simulated_study_joints()[2];
  MaxwellSlipParams smooth = joint.truth;
  smooth.Fc = smooth.Fs = 1e-9;
  smooth.sigma2 = 0.0;
  ClosedLoopOptions o = closed_loop_options_for(joint);
  o.torque_noise = 0.0;
  const VelocityProfile desired = closed_loop_profile(kSeed);
  const ClosedLoopRun none = run_closed_loop(smooth, desired, nullptr, o, false);
  const ClosedLoopRun baseline = run_closed_loop(smooth, desired, nullptr, o, true);
  EXPECT_LE(baseline.rmse, none.rmse * 1.0001);
}

TEST(ClosedLoop, InvalidOptionsAreNamed) {
  ClosedLoopOptions o;
  o.kv = 0.0;
  EXPECT_THAT([&] { o.validate(); }, ThrowsMessage<InvalidArgument>(HasSubstr("closed-loop kv is 0, must be > 0")));
  o = {};
  o.gains.kp_min = 0.2;
  o.gains.kp_max = 0.1;
  EXPECT_THAT([&] { o.validate(); }, ThrowsMessage<InvalidArgument>(HasSubstr("gains.kp_min is 0.2, must be <= kp_max")));
  o = {};
  o.substeps = 0;
  EXPECT_THAT([&] { o.validate(); }, ThrowsMessage<InvalidArgument>(HasSubstr("substeps is 0")));
}

}  // namespace
}  // namespace twinwatch::friction
