// Rigid-body decoupling of one joint (HESR §III): recovery of a known rigid body from a simulated
// current-based torque whose friction is a Maxwell-slip truth, screening, and the chirp frequency.
#include "twinwatch/friction/decoupling.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "twinwatch/core/error.hpp"
#include "twinwatch/friction/protocol.hpp"

namespace twinwatch::friction {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

constexpr unsigned kSeed = 1;

TEST(MovingAverage, MatchesANaiveWindowedMean) {
  const std::vector<double> x{1.0, 4.0, -2.0, 8.0, 0.5, 3.0, 7.0};
  const std::vector<double> y = moving_average(x, 5);
  for (int k = 0; k < 7; ++k) {
    double s = 0.0;
    int n = 0;
    for (int i = std::max(0, k - 2); i <= std::min(6, k + 2); ++i, ++n) s += x[static_cast<std::size_t>(i)];
    EXPECT_DOUBLE_EQ(y[static_cast<std::size_t>(k)], s / n) << k;
  }
  EXPECT_EQ(moving_average(x, 1), x);
}

TEST(MovingAverage, EvenWindowIsNamed) {
  const std::vector<double> x(5, 1.0);
  EXPECT_THAT([&] { moving_average(x, 4); }, ThrowsMessage<InvalidArgument>(HasSubstr("moving-average window is 4")));
}

TEST(JointAcceleration, DifferentiatesASineToTwoPercent) {
  // qd = sin(2 pi 0.5 t): qdd = pi cos(pi t); central difference + 5-sample mean at 200 Hz
  const double dt = 0.005;
  std::vector<double> qd(800);
  for (std::size_t k = 0; k < qd.size(); ++k) qd[k] = std::sin(std::numbers::pi * static_cast<double>(k) * dt);
  const std::vector<double> qdd = joint_acceleration(qd, dt, 5);
  for (std::size_t k = 5; k + 5 < qd.size(); ++k)
    EXPECT_NEAR(qdd[k], std::numbers::pi * std::cos(std::numbers::pi * static_cast<double>(k) * dt), 0.02 * std::numbers::pi) << k;
}

// the decoupling recovers the rigid body the simulation put into the measured torque, and what is
// left is the friction: compared with the simulator's own residual record (evaluation code only)
TEST(RigidBodyFit, RecoversTheSimulatedRigidBodyAndLeavesTheFriction) {
  const SimulatedJoint joint = simulated_study_joints()[1];  // J2: I 0.6, g_s -22, g_c 2.5, c -0.4
  const ProtocolRecords r = simulated_protocol_records(joint, kSeed);
  const std::vector<const JointRecord*> recs{&r.train, &r.fourier, &r.chirp};
  const RigidBodyFit fit = fit_rigid_body(recs);
  EXPECT_NEAR(fit.inertia, 0.60, 0.05);
  EXPECT_NEAR(fit.gravity_sin, -22.0, 0.5);
  // the cos and constant columns are close to collinear for |q| < 1 rad: check their sum at q = 0
  EXPECT_NEAR(fit.gravity_cos + fit.offset, 2.5 - 0.4, 0.5);
  EXPECT_EQ(fit.rank, 6);
  // residual of the Fourier record vs the simulator's friction measurement (same noise draw)
  const FrictionStudyData truth = simulated_study_data(joint, kSeed);
  const FrictionRecord res = fit.residual(r.fourier);
  double s = 0.0;
  for (std::size_t k = 0; k < res.tau.size(); ++k) s += std::pow(res.tau[k] - truth.fourier.tau[k], 2);
  EXPECT_LT(std::sqrt(s / static_cast<double>(res.tau.size())), 0.3) << fit.equation();
}

TEST(RigidBodyFit, ScreeningKeepsExactlyTheSamplesAboveTheThreshold) {
  const ProtocolRecords r = simulated_protocol_records(simulated_study_joints()[2], kSeed);
  const std::vector<const JointRecord*> recs{&r.train};
  for (double th : {0.05, 0.10, 0.15}) {
    RigidBodyFitOptions o;
    o.reversal_threshold = th;
    long expected = 0;
    for (double v : r.train.qd) expected += std::abs(v) >= th;
    EXPECT_EQ(fit_rigid_body(recs, o).samples, expected) << th;
  }
}

TEST(RigidBodyFit, OneDirectionalMotionIsRankDeficient) {
  // constant-sign velocity: sign(qd) equals the constant column, the rank drops by one
  JointRecord r;
  r.dt = 0.005;
  for (int k = 0; k < 400; ++k) {
    const double t = k * r.dt;
    r.q.push_back(-0.5 + 0.4 * t + 0.02 * std::sin(3.0 * t));
    r.qd.push_back(0.4 + 0.06 * std::cos(3.0 * t));
    r.tau.push_back(10.0 * std::sin(r.q.back()) + 2.0);
  }
  const std::vector<const JointRecord*> recs{&r};
  EXPECT_EQ(fit_rigid_body(recs).rank, 5);
}

TEST(RigidBodyFit, TooFewRetainedSamplesAreNamed) {
  JointRecord r;
  r.q.assign(50, 0.0);
  r.qd.assign(50, 0.01);
  r.tau.assign(50, 1.0);
  const std::vector<const JointRecord*> recs{&r};
  EXPECT_THAT([&] { fit_rigid_body(recs); },
              ThrowsMessage<InvalidArgument>(HasSubstr("keeps 0 samples with |qd| >= 0.1 rad/s, expected at least 6")));
}

TEST(RigidBodyFit, BadRecordsAndOptionsAreNamed) {
  JointRecord r;
  r.q.assign(10, 0.0);
  r.qd.assign(9, 0.0);
  r.tau.assign(10, 0.0);
  EXPECT_THAT([&] { r.validate("train"); }, ThrowsMessage<InvalidArgument>(HasSubstr("train.qd has size 9, expected 10")));
  r.qd.assign(10, 0.0);
  r.tau[3] = std::nan("");
  EXPECT_THAT([&] { r.validate("train"); }, ThrowsMessage<InvalidArgument>(HasSubstr("train.tau[3] is nan")));
  RigidBodyFitOptions o;
  o.reversal_threshold = -0.1;
  EXPECT_THAT([&] { o.validate(); }, ThrowsMessage<InvalidArgument>(HasSubstr("reversal_threshold is -0.1")));
  o = {};
  o.acceleration_window = 4;
  EXPECT_THAT([&] { o.validate(); }, ThrowsMessage<InvalidArgument>(HasSubstr("acceleration_window is 4")));
}

TEST(ChirpFrequency, EstimatedFromReversalsFollowsTheSweep) {
  // the simulated chirp knows its frequency: the estimate from the measured velocity is within 10 %
  // of it after the first reversal (t = 3.6 s at 0.1 Hz start)
  const ProtocolRecords r = simulated_protocol_records(simulated_study_joints()[0], kSeed);
  const std::vector<double> f = frequency_from_reversals(r.chirp.qd, r.chirp.dt, 0.05);
  ASSERT_EQ(f.size(), r.chirp_frequency.size());
  for (std::size_t k = 800; k + 200 < f.size(); k += 100)
    EXPECT_NEAR(f[k], r.chirp_frequency[k], 0.1 * r.chirp_frequency[k] + 0.02) << k;
}

TEST(ChirpFrequency, TooFewReversalsAreNamed) {
  const std::vector<double> qd(100, 0.5);
  EXPECT_THAT([&] { frequency_from_reversals(qd, 0.005, 0.05); },
              ThrowsMessage<InvalidArgument>(HasSubstr("chirp record has 0 velocity reversals")));
}

}  // namespace
}  // namespace twinwatch::friction
