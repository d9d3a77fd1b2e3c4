#include "twinwatch/monitor/momentum_observer.hpp"

#include <gtest/gtest.h>

#include "twinwatch/core/error.hpp"
#include "twinwatch/model/description_io.hpp"

namespace twinwatch::monitor {
namespace {

// The observer's residual is a first-order low-pass of the external torque: after a step of
// tau_ext it must converge to tau_ext (no acceleration needed), and stay ~0 without one.
TEST(MomentumObserver, ConvergesToExternalTorqueStep) {
  model::RobotModel robot = model::load_robot("ur3e");
  model::DynamicsData d(robot);
  const int n = robot.n_dof();
  const double dt = 0.0001, gain = 100.0;
  MomentumObserver obs(robot, gain);

  VectorJ q = VectorJ::Zero(n), qd = VectorJ::Zero(n);
  q << 0.3, -1.2, 1.0, -1.4, -1.5, 0.2;
  VectorJ tau_ext = VectorJ::Zero(n);
  obs.reset(q, qd);
  // excitation and damping sized per joint: the wrist links are light (1e-4..1e-3 kg m^2)
  const double amp[] = {2.0, 2.0, 1.0, 0.02, 0.02, 0.005}, damp[] = {1.0, 1.0, 0.5, 0.005, 0.005, 0.001};
  for (int k = 0; k < 20000; ++k) {
    const double t = k * dt;
    // drive torque: gravity compensation plus a damping and a sinusoidal excitation
    VectorJ tau_m = model::gravity_torque(robot, d, q);
    for (int j = 0; j < n; ++j) tau_m[j] += amp[j] * std::sin(3.0 * t + j) - damp[j] * qd[j];
    if (t >= 1.0) tau_ext << 0.0, 3.0, -2.0, 0.0, 0.0, 0.0;
    // semi-implicit Euler of the true plant, driven by tau_m + tau_ext
    const VectorJ qdd = model::forward_dynamics(robot, d, q, qd, tau_m + tau_ext);
    obs.update(q, qd, tau_m, dt);
    qd += qdd * dt;
    q += qd * dt;
    if (t > 0.5 && t < 1.0) {
      EXPECT_LT(obs.residual().cwiseAbs().maxCoeff(), 0.05) << "t=" << t;
    }
  }
  // after 1 s of step (100 time constants) the residual equals tau_ext within discretisation
  EXPECT_LT((obs.residual() - tau_ext).cwiseAbs().maxCoeff(), 0.05);
}

TEST(MomentumObserver, RejectsNonPositiveGain) {
  model::RobotModel robot = model::load_robot("ur3e");
  EXPECT_THROW(MomentumObserver(robot, 0.0), InvalidArgument);
}

}  // namespace
}  // namespace twinwatch::monitor
