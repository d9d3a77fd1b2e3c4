#include "twinwatch/model/regressor.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "twinwatch/core/error.hpp"
#include "turned_frames.hpp"
#include "twinwatch/model/description_io.hpp"

namespace twinwatch::model {
namespace {

constexpr double kTol = 1e-10;

TEST(Regressor, TimesStandardParametersEqualsRnea) {
  for (const char* name : {"ur3e", "ur5e"}) {
    RobotModel m = load_robot(name);
    DynamicsData d(m);
    RegressorMatrix Y;
    const Eigen::VectorXd pi = standard_parameters(m);
    const unsigned seed = 77;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-2.0, 2.0);
    for (int s = 0; s < 500; ++s) {
      VectorJ q(6), qd(6), qdd(6);
      for (int i = 0; i < 6; ++i) q[i] = u(rng), qd[i] = u(rng), qdd[i] = 3 * u(rng);
      regressor(m, d, q, qd, qdd, Y);
      const VectorJ tau = rnea(m, d, q, qd, qdd);
      EXPECT_LT((Y * pi - tau).cwiseAbs().maxCoeff(), kTol) << name << " seed " << seed << " state " << s;
    }
  }
}

// general placement rotations take the other branch of the forward pass; the torque of the
// same robot must not change, and Y pi must still equal the RNEA
TEST(Regressor, TurnedBodyFramesTakeTheGeneralPathAndAgree) {
  const RobotModel dh = load_robot("ur3e");
  const RobotModel m = testing_support::with_turned_body_frames(dh, 11);
  ASSERT_TRUE(dh.placements_about_x());
  ASSERT_FALSE(m.placements_about_x());
  DynamicsData d(m), d_dh(dh);
  RegressorMatrix Y;
  const Eigen::VectorXd pi = standard_parameters(m);
  const unsigned seed = 78;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int s = 0; s < 200; ++s) {
    VectorJ q(6), qd(6), qdd(6);
    for (int i = 0; i < 6; ++i) q[i] = u(rng), qd[i] = u(rng), qdd[i] = 3 * u(rng);
    regressor(m, d, q, qd, qdd, Y);
    const VectorJ tau = rnea(m, d, q, qd, qdd);
    EXPECT_LT((Y * pi - tau).cwiseAbs().maxCoeff(), kTol) << "seed " << seed << " state " << s;
    EXPECT_LT((rnea(dh, d_dh, q, qd, qdd) - tau).cwiseAbs().maxCoeff(), kTol) << "seed " << seed << " state " << s;
  }
}

// rows below the diagonal of each link block are exact zeros (joint j < i never feels link i)
TEST(Regressor, JointsBeforeALinkDoNotFeelIt) {
  const RobotModel m = load_robot("ur3e");
  DynamicsData d(m);
  RegressorMatrix Y = RegressorMatrix::Constant(6, 60, 7.0);  // stale contents must be overwritten
  VectorJ q(6), qd(6), qdd(6);
  q << 0.1, -0.7, 1.2, 0.4, -0.3, 2.0;
  qd << 0.5, -0.2, 0.3, 1.0, -1.0, 0.3;
  qdd << 1.0, 2.0, -1.5, 0.7, 0.2, -0.4;
  regressor(m, d, q, qd, qdd, Y);
  for (int i = 0; i < 6; ++i)
    for (int j = i + 1; j < 6; ++j)
      for (int k = 0; k < 10; ++k) EXPECT_EQ(Y(j, 10 * i + k), 0.0) << "row " << j << " link " << i << " column " << k;
}

TEST(Regressor, FrictionColumnsSitOnTheirJointRow) {
  RobotModel m = load_robot("ur3e");
  DynamicsData d(m);
  RegressorMatrix Y;
  VectorJ q = VectorJ::Zero(6), qd(6), qdd = VectorJ::Zero(6);
  qd << 0.5, -0.2, 0.0, 1.0, -1.0, 0.3;
  regressor(m, d, q, qd, qdd, Y, FrictionColumns::CoulombViscousOffset);
  ASSERT_EQ(Y.cols(), 60 + 18);
  for (int j = 0; j < 6; ++j)
    for (int r = 0; r < 6; ++r) {
      const double sgn = qd[j] > 0 ? 1.0 : (qd[j] < 0 ? -1.0 : 0.0);
      EXPECT_EQ(Y(r, 60 + 3 * j), r == j ? sgn : 0.0);
      EXPECT_EQ(Y(r, 60 + 3 * j + 1), r == j ? qd[j] : 0.0);
      EXPECT_EQ(Y(r, 60 + 3 * j + 2), r == j ? 1.0 : 0.0);
    }
}

TEST(Regressor, WrongSizeIsReported) {
  RobotModel m = load_robot("ur3e");
  DynamicsData d(m);
  RegressorMatrix Y;
  try {
    regressor(m, d, VectorJ::Zero(6), VectorJ::Zero(5), VectorJ::Zero(6), Y);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("qd has size 5, expected 6"));
  }
}

// An independent symbolic tool finds 36 inertial + 12 friction base parameters for the UR3e.
TEST(BaseParameters, Ur3eHas36InertialAnd12FrictionParameters) {
  RobotModel m = load_robot("ur3e");
  EXPECT_EQ(compute_base_parameters(m).rank, 36);
  EXPECT_EQ(compute_base_parameters(m, FrictionColumns::CoulombViscous).rank, 48);
}

TEST(BaseParameters, BaseRegressorReproducesTorqueOnNewStates) {
  RobotModel m = load_robot("ur3e");
  const BaseParameters b = compute_base_parameters(m, FrictionColumns::CoulombViscous);
  Eigen::VectorXd pi = standard_parameters(m, FrictionColumns::CoulombViscous);
  for (int j = 0; j < 6; ++j) pi(60 + 2 * j) = 0.5 + 0.1 * j, pi(60 + 2 * j + 1) = 0.2;
  const Eigen::VectorXd beta = b.base_values(pi);
  DynamicsData d(m);
  RegressorMatrix Y;
  std::mt19937 rng(99);  // other states than the ones the base set was computed on
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (int s = 0; s < 200; ++s) {
    VectorJ q(6), qd(6), qdd(6);
    for (int i = 0; i < 6; ++i) q[i] = u(rng), qd[i] = u(rng), qdd[i] = u(rng);
    regressor(m, d, q, qd, qdd, Y, FrictionColumns::CoulombViscous);
    const Eigen::VectorXd tau_std = Y * pi;
    const Eigen::VectorXd tau_base = b.base_regressor(Y) * beta;
    EXPECT_LT((tau_std - tau_base).cwiseAbs().maxCoeff(), kTol) << "seed 99 state " << s;
    // and the non-physical standard vector rebuilt from beta gives the same torque
    EXPECT_LT((Y * b.standard_from_base(beta) - tau_std).cwiseAbs().maxCoeff(), kTol);
  }
}

TEST(BaseParameterOptions, RejectsBadValues) {
  BaseParameterOptions o;
  o.n_states = 0;
  EXPECT_THROW(o.validate(), InvalidArgument);
  o = {};
  o.relative_tolerance = 2.0;
  try {
    o.validate();
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("relative_tolerance is 2, must be in (0, 1)"));
  }
}

}  // namespace
}  // namespace twinwatch::model
