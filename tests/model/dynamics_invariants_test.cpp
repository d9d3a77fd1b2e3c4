// Physical invariants and derivative checks of the dynamics kernels on the UR3e.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <random>

#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "twinwatch/model/regressor.hpp"

#include "malloc_counter.hpp"  // counts heap allocations (one TU per test binary)

namespace twinwatch::model {
namespace {

VectorJ random_state(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  VectorJ v(6);
  for (int i = 0; i < 6; ++i) v[i] = u(rng);
  return v;
}

// d/dt FK = J qd: finite difference of the flange position and orientation
TEST(Jacobian, MatchesFiniteDifferenceOfForwardKinematics) {
  const RobotModel m = load_robot("ur3e");
  DynamicsData d(m);
  std::mt19937 rng(5);
  const double h = 1e-7;
  for (int s = 0; s < 100; ++s) {
    const VectorJ q = random_state(rng, 3.0), qd = random_state(rng, 1.0);
    const Eigen::Vector3d point(0.01, -0.02, 0.03);
    forward_kinematics(m, d, q);
    Matrix6J J;
    point_jacobian(m, d, 5, point, J);
    const Eigen::Isometry3d T0 = d.oMi[5];
    forward_kinematics(m, d, q + h * qd);
    const Eigen::Isometry3d T1 = d.oMi[5];
    const Eigen::Vector3d v_fd = (T1 * point - T0 * point) / h;
    const Eigen::AngleAxisd dR(T1.linear() * T0.linear().transpose());
    const Eigen::Vector3d w_fd = dR.axis() * dR.angle() / h;
    const Eigen::Matrix<double, 6, 1> twist = J * qd;
    EXPECT_LT((twist.head<3>() - v_fd).norm(), 1e-5) << "seed 5 state " << s;
    EXPECT_LT((twist.tail<3>() - w_fd).norm(), 1e-5) << "seed 5 state " << s;
  }
}

// power balance: d/dt (T + V) = qd . tau_applied for the frictionless arm, i.e.
// qd^T (tau - g) = d/dt T = qd^T M qdd + 1/2 qd^T Mdot qd (finite difference of M along qd)
TEST(Dynamics, KineticEnergyRateMatchesPowerOfNonGravityTorque) {
  const RobotModel m = load_robot("ur3e");
  DynamicsData d(m);
  std::mt19937 rng(6);
  const double h = 1e-6;
  for (int s = 0; s < 100; ++s) {
    const VectorJ q = random_state(rng, 3.0), qd = random_state(rng, 2.0), qdd = random_state(rng, 4.0);
    const VectorJ tau = rnea(m, d, q, qd, qdd);
    const VectorJ g = gravity_torque(m, d, q);
    const MatrixJ M = crba(m, d, q);
    const MatrixJ Mp = crba(m, d, q + h * qd);
    const MatrixJ Mm = crba(m, d, q - h * qd);
    const double Tdot = qd.dot(M * qdd) + 0.5 * qd.dot((Mp - Mm) / (2 * h) * qd);
    EXPECT_NEAR(qd.dot(tau - g), Tdot, 1e-6) << "seed 6 state " << s;
  }
}

// gravity torque is the gradient of the potential energy
TEST(Dynamics, GravityTorqueIsGradientOfPotentialEnergy) {
  const RobotModel m = load_robot("ur3e");
  DynamicsData d(m);
  std::mt19937 rng(8);
  const double h = 1e-6;
  for (int s = 0; s < 100; ++s) {
    const VectorJ q = random_state(rng, 3.0);
    const VectorJ g = gravity_torque(m, d, q);
    for (int i = 0; i < 6; ++i) {
      VectorJ qp = q, qm = q;
      qp[i] += h;
      qm[i] -= h;
      const double dV = (potential_energy(m, d, qp) - potential_energy(m, d, qm)) / (2 * h);
      EXPECT_NEAR(g[i], dV, 1e-6) << "seed 8 state " << s << " joint " << i;
    }
  }
}

// a frictionless, unactuated UR3e falling under gravity conserves T + V (RK4, 0.5 ms, 2 s)
TEST(ForwardDynamics, FreeFallConservesEnergy) {
  const RobotModel m = load_robot("ur3e");
  DynamicsData d(m);
  VectorJ q(6), qd = VectorJ::Zero(6);
  q << 0.2, -0.8, 0.9, -1.2, 0.7, 0.1;
  const VectorJ zero = VectorJ::Zero(6);
  auto energy = [&](const VectorJ& qq, const VectorJ& vv) { return kinetic_energy(m, d, qq, vv) + potential_energy(m, d, qq); };
  const double E0 = energy(q, qd);
  const double dt = 5e-4;
  double max_drift = 0.0, max_T = 0.0;
  for (int k = 0; k < 4000; ++k) {
    const VectorJ a1 = forward_dynamics(m, d, q, qd, zero);
    const VectorJ v1 = qd;
    const VectorJ a2 = forward_dynamics(m, d, q + 0.5 * dt * v1, qd + 0.5 * dt * a1, zero);
    const VectorJ v2 = qd + 0.5 * dt * a1;
    const VectorJ a3 = forward_dynamics(m, d, q + 0.5 * dt * v2, qd + 0.5 * dt * a2, zero);
    const VectorJ v3 = qd + 0.5 * dt * a2;
    const VectorJ a4 = forward_dynamics(m, d, q + dt * v3, qd + dt * a3, zero);
    const VectorJ v4 = qd + dt * a3;
    q += dt / 6 * (v1 + 2 * v2 + 2 * v3 + v4);
    qd += dt / 6 * (a1 + 2 * a2 + 2 * a3 + a4);
    max_drift = std::max(max_drift, std::abs(energy(q, qd) - E0));
    max_T = std::max(max_T, kinetic_energy(m, d, q, qd));
  }
  ASSERT_GT(max_T, 1.0) << "the arm must actually move for the test to mean anything";
  EXPECT_LT(max_drift, 1e-6 * max_T);
}

TEST(Dynamics, HotPathsDoNotAllocate) {
  const RobotModel m = load_robot("ur3e");
  DynamicsData d(m);
  RegressorMatrix Y;
  Matrix6J J;
  const VectorJ q = VectorJ::Constant(6, 0.3), qd = VectorJ::Constant(6, -0.2), qdd = VectorJ::Constant(6, 0.5);
  regressor(m, d, q, qd, qdd, Y, FrictionColumns::CoulombViscous);  // sizes Y once
  // the counter itself must see an allocation, or the test could not fail
  g_allocations = 0;
  g_counting = true;
  void* probe = std::malloc(16);
  g_counting = false;
  std::free(probe);
  ASSERT_EQ(g_allocations.load(), 1);

  g_allocations = 0;
  g_counting = true;
  rnea(m, d, q, qd, qdd);
  gravity_torque(m, d, q);
  nonlinear_effects(m, d, q, qd);
  crba(m, d, q);
  forward_dynamics(m, d, q, qd, qdd);
  forward_kinematics(m, d, q);
  point_jacobian(m, d, 4, Eigen::Vector3d::Zero(), J);
  regressor(m, d, q, qd, qdd, Y, FrictionColumns::CoulombViscous);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
}

}  // namespace
}  // namespace twinwatch::model
