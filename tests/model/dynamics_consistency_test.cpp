// Internal consistency of the dynamics kernels on random chains (no external oracle here;
// the KDL cross-check lives in kdl_oracle_test.cpp).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include <Eigen/Eigenvalues>

#include "twinwatch/core/error.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"

namespace twinwatch::model {
namespace {

constexpr double kTol = 1e-10;

// a random 6-joint chain with physical inertias
RobotModel random_chain(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  RobotDescription d;
  d.name = "random";
  for (int i = 0; i < n; ++i) {
    Joint j;
    j.name = "j" + std::to_string(i);
    j.placement = Eigen::Translation3d(0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng)) *
                  Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized());
    j.q_offset = u(rng);
    j.body.mass = 1.0 + u(rng) * 0.5;
    j.body.com = Eigen::Vector3d(0.1 * u(rng), 0.1 * u(rng), 0.1 * u(rng));
    // principal moments in [0.01, 0.015]: any two sum to more than the third (triangle inequality)
    const Eigen::Vector3d principal(0.0125 + 0.0025 * u(rng), 0.0125 + 0.0025 * u(rng), 0.0125 + 0.0025 * u(rng));
    const Eigen::Matrix3d Rb = Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
    j.body.inertia_com = Rb * principal.asDiagonal() * Rb.transpose();
    d.joints.push_back(j);
  }
  d.flange = Eigen::Translation3d(0, 0, 0.1) * Eigen::Quaterniond::Identity();
  return RobotModel(d);
}

VectorJ random_vec(std::mt19937& rng, int n, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  VectorJ v(n);
  for (int i = 0; i < n; ++i) v[i] = u(rng);
  return v;
}

TEST(Dynamics, MassMatrixTimesAccelerationPlusBiasEqualsRnea) {
  const unsigned seed = 1234;
  std::mt19937 rng(seed);
  for (int trial = 0; trial < 200; ++trial) {
    RobotModel m = random_chain(rng, 6);
    DynamicsData d(m);
    const VectorJ q = random_vec(rng, 6, 3.0), qd = random_vec(rng, 6, 2.0), qdd = random_vec(rng, 6, 5.0);
    const VectorJ tau = rnea(m, d, q, qd, qdd);
    const VectorJ h = nonlinear_effects(m, d, q, qd);
    const MatrixJ M = crba(m, d, q);
    EXPECT_LT((M * qdd + h - tau).cwiseAbs().maxCoeff(), kTol) << "seed " << seed << " trial " << trial;
    EXPECT_LT((M - M.transpose()).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<MatrixJ>(M).eigenvalues().minCoeff(), 0.0);
    const VectorJ qdd2 = forward_dynamics(m, d, q, qd, tau);
    EXPECT_LT((qdd2 - qdd).cwiseAbs().maxCoeff(), 1e-8) << "seed " << seed << " trial " << trial;
  }
}

// rnea_pair: the second torque through the first pass's rotations, tau2 = tau + M (qdd2 - qdd), on
// general placements and on the UR3e's DH placements (the forward pass's about-x branch)
TEST(Dynamics, PairedRneaEqualsTwoRneasAndDiffersByTheMassMatrixTimesTheAccelerationStep) {
  std::mt19937 rng(4321);
  std::vector<RobotModel> models;
  for (int k = 0; k < 50; ++k) models.push_back(random_chain(rng, 6));
  models.push_back(load_robot("ur3e"));
  ASSERT_TRUE(models.back().placements_about_x());
  for (size_t k = 0; k < models.size(); ++k) {
    const RobotModel& m = models[k];
    DynamicsData d(m), d2(m);
    const VectorJ q = random_vec(rng, 6, 3.0), qd = random_vec(rng, 6, 2.0), qdd = random_vec(rng, 6, 5.0),
                  qdd2 = random_vec(rng, 6, 5.0);
    VectorJ tau2;
    const VectorJ tau = rnea_pair(m, d, q, qd, qdd, qdd2, tau2);
    const VectorJ tau_ref = rnea(m, d2, q, qd, qdd);
    const VectorJ tau2_ref = rnea(m, d2, q, qd, qdd2);
    EXPECT_LT((tau - tau_ref).cwiseAbs().maxCoeff(), 1e-12) << "model " << k;
    EXPECT_LT((tau2 - tau2_ref).cwiseAbs().maxCoeff(), kTol) << "model " << k;
    // the step is the inertia's: independent of velocity and gravity
    const MatrixJ M = crba(m, d2, q);
    EXPECT_LT((tau2 - tau - M * (qdd2 - qdd)).cwiseAbs().maxCoeff(), kTol) << "model " << k;
    EXPECT_GT((tau2 - tau).cwiseAbs().maxCoeff(), 0.01) << "model " << k;  // the step is not trivially zero
    // the workspace holds the first acceleration's pass, as after rnea()
    EXPECT_LT((d.tau - tau_ref).cwiseAbs().maxCoeff(), 1e-12);
  }
  DynamicsData d(models[0]);
  VectorJ tau2;
  EXPECT_THROW(rnea_pair(models[0], d, VectorJ::Zero(6), VectorJ::Zero(6), VectorJ::Zero(6), VectorJ::Zero(5), tau2), InvalidArgument);
}

TEST(Dynamics, WrongSizeNamesArgumentAndExpectedSize) {
  std::mt19937 rng(1);
  RobotModel m = random_chain(rng, 6);
  DynamicsData d(m);
  VectorJ q = VectorJ::Zero(5);
  try {
    gravity_torque(m, d, q);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("q has size 5, expected 6"));
  }
}

}  // namespace
}  // namespace twinwatch::model
