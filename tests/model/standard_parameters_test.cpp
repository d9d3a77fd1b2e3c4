// RobotModel::set_standard_parameters: RNEA with non-physical parameters (a base-parameter fit
// mapped to standard ones) equals the regressor times those parameters — the identity the twin's
// fast prediction path relies on.
#include <gtest/gtest.h>

#include <random>

#include "twinwatch/core/error.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "twinwatch/model/regressor.hpp"

using namespace twinwatch;

TEST(StandardParameters, RneaWithNonPhysicalParametersEqualsTheRegressor) {
  model::RobotModel m = model::load_robot("ur3e");
  const int n = m.n_dof();
  std::mt19937_64 rng(7);
  std::normal_distribution<double> N(0.0, 1.0);
  model::DynamicsData d(m);
  model::RegressorMatrix Y;
  for (int trial = 0; trial < 50; ++trial) {
    Eigen::VectorXd pi(10 * n);
    for (int k = 0; k < pi.size(); ++k) pi(k) = N(rng);  // negative masses, indefinite inertias
    pi(0) = 0.0;                                          // zero mass with a first moment
    m.set_standard_parameters(pi);
    VectorJ q(n), qd(n), qdd(n);
    for (int j = 0; j < n; ++j) {
      q[j] = 3 * N(rng);
      qd[j] = N(rng);
      qdd[j] = 2 * N(rng);
    }
    const VectorJ tau = model::rnea(m, d, q, qd, qdd);
    model::regressor(m, d, q, qd, qdd, Y);
    const VectorJ expected = Y.leftCols(10 * n) * pi;
    EXPECT_LT((tau - expected).cwiseAbs().maxCoeff(), 1e-10 * (1.0 + expected.cwiseAbs().maxCoeff())) << "trial " << trial;
  }
}

TEST(StandardParameters, PayloadIsAddedOnTopAndLinkInertiaClearsTheOverride) {
  model::RobotModel physical = model::load_robot("ur3e");
  model::RobotModel m = physical;
  m.set_standard_parameters(model::standard_parameters(physical));  // the same parameters, by vector
  model::RigidBodyInertia p;
  p.mass = 0.5;
  p.com = Eigen::Vector3d(0, 0, 0.04);
  m.set_payload(p);
  physical.set_payload(p);
  model::DynamicsData d1(m), d2(physical);
  VectorJ q = VectorJ::Constant(6, 0.3), qd = VectorJ::Constant(6, -0.2), qdd = VectorJ::Constant(6, 0.5);
  const VectorJ a = model::rnea(m, d1, q, qd, qdd);
  const VectorJ b = model::rnea(physical, d2, q, qd, qdd);
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-12);
  m.set_link_inertia(0, physical.joint(0).body);  // back to the description's parameters
  EXPECT_LT((model::rnea(m, d1, q, qd, qdd) - b).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(StandardParameters, BadVectorsAreNamed) {
  model::RobotModel m = model::load_robot("ur3e");
  try {
    m.set_standard_parameters(Eigen::VectorXd::Zero(59));
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("size 59, expected 60"), std::string::npos) << e.what();
  }
  Eigen::VectorXd pi = Eigen::VectorXd::Zero(60);
  pi(23) = std::nan("");
  try {
    m.set_standard_parameters(pi);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("parameter 23 (link 2, column 3)"), std::string::npos) << e.what();
  }
}
