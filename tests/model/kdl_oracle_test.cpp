// RNEA, gravity, Coriolis and the mass matrix against Orocos KDL on seeded random states.
#include <gtest/gtest.h>

#include <kdl/chaindynparam.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <random>

#include "kdl_chain.hpp"
#include "turned_frames.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"

namespace twinwatch::model {
namespace {

// absolute agreement required between two double-precision implementations [N·m], [kg·m²]
constexpr double kOracleTol = 1e-9;
constexpr int kStates = 1000;

void compare_with_kdl(RobotModel& m, unsigned seed) {
  const int n = m.n_dof();
  const KDL::Chain chain = testing_support::to_kdl_chain(m);
  const KDL::Vector g(m.gravity().x(), m.gravity().y(), m.gravity().z());
  KDL::ChainIdSolver_RNE id(chain, g);
  KDL::ChainDynParam dyn(chain, g);
  DynamicsData d(m);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  KDL::JntArray kq(n), kqd(n), kqdd(n), ktau(n), kg(n), kc(n);
  KDL::JntSpaceInertiaMatrix kM(n);
  KDL::Wrenches f_ext(chain.getNrOfSegments(), KDL::Wrench::Zero());
  for (int s = 0; s < kStates; ++s) {
    VectorJ q(n), qd(n), qdd(n);
    for (int i = 0; i < n; ++i) {
      q[i] = M_PI * u(rng);
      qd[i] = 3.0 * u(rng);
      qdd[i] = 10.0 * u(rng);
      kq(i) = q[i] + m.joint(i).q_offset;
      kqd(i) = qd[i];
      kqdd(i) = qdd[i];
    }
    ASSERT_GE(id.CartToJnt(kq, kqd, kqdd, f_ext, ktau), 0);
    dyn.JntToMass(kq, kM);
    dyn.JntToGravity(kq, kg);
    dyn.JntToCoriolis(kq, kqd, kc);
    const VectorJ tau = rnea(m, d, q, qd, qdd);
    for (int i = 0; i < n; ++i) ASSERT_NEAR(tau[i], ktau(i), kOracleTol) << "rnea, seed " << seed << " state " << s << " joint " << i;
    const VectorJ gt = gravity_torque(m, d, q);
    for (int i = 0; i < n; ++i) ASSERT_NEAR(gt[i], kg(i), kOracleTol) << "gravity, seed " << seed << " state " << s;
    const VectorJ ct = coriolis_torque(m, d, q, qd);
    for (int i = 0; i < n; ++i) ASSERT_NEAR(ct[i], kc(i), kOracleTol) << "coriolis, seed " << seed << " state " << s;
    const MatrixJ M = crba(m, d, q);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) ASSERT_NEAR(M(i, j), kM(i, j), kOracleTol) << "M, seed " << seed << " state " << s;
  }
}

TEST(KdlOracle, Ur3eAgreesOnThousandStates) {
  RobotModel m = load_robot("ur3e");
  compare_with_kdl(m, 101);
}

TEST(KdlOracle, Ur5eWithPayloadAgreesOnThousandStates) {
  RobotModel m = load_robot("ur5e");
  RigidBodyInertia payload;
  payload.mass = 2.5;
  payload.com = Eigen::Vector3d(0.01, -0.02, 0.08);
  payload.inertia_com = Eigen::Vector3d(0.004, 0.005, 0.003).asDiagonal();
  m.set_payload(payload);
  compare_with_kdl(m, 202);
}

// the UR10e (session 57) with 10 kg on the flange
TEST(KdlOracle, Ur10eWithPayloadAgreesOnThousandStates) {
  RobotModel m = load_robot("ur10e");
  RigidBodyInertia payload;
  payload.mass = 10.0;
  payload.com = Eigen::Vector3d(0.0, 0.03, 0.12);
  payload.inertia_com = Eigen::Vector3d(0.03, 0.04, 0.02).asDiagonal();
  m.set_payload(payload);
  compare_with_kdl(m, 404);
}

// general placement rotations (not Rx(alpha)): the kernels' general path against the same oracle
TEST(KdlOracle, Ur5eWithTurnedBodyFramesAgreesOnThousandStates) {
  RobotModel m = testing_support::with_turned_body_frames(load_robot("ur5e"), 7);
  ASSERT_FALSE(m.placements_about_x());
  compare_with_kdl(m, 303);
}

}  // namespace
}  // namespace twinwatch::model
