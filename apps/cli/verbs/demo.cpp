// `twinwatch demo`: the main job on the built-in virtual UR3e. Each step is a function; later
// stages (simulation, identification, monitoring) add their steps here.
#include <fmt/format.h>

#include <random>

#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "verb_registry.hpp"

namespace {

using namespace twinwatch;

// step 1: load the robot and check the dynamics against itself on seeded random states
int step_model_check(const std::string& robot_name) {
  model::RobotModel m = model::load_robot(robot_name);
  model::DynamicsData d(m);
  fmt::print("== step 1: robot model '{}' ({} joints, {} )\n", m.name(), m.n_dof(), m.description().source);
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  double worst = 0.0;
  for (int k = 0; k < 1000; ++k) {
    VectorJ q(m.n_dof()), qd(m.n_dof()), qdd(m.n_dof());
    for (int i = 0; i < m.n_dof(); ++i) q[i] = u(rng), qd[i] = u(rng), qdd[i] = u(rng);
    const VectorJ tau = model::rnea(m, d, q, qd, qdd);
    const VectorJ h = model::nonlinear_effects(m, d, q, qd);
    const MatrixJ M = model::crba(m, d, q);
    worst = std::max(worst, (M * qdd + h - tau).cwiseAbs().maxCoeff());
  }
  fmt::print("   RNEA vs M(q) qdd + C qd + g on 1000 seeded states: max difference {:.2e} N·m\n", worst);
  VectorJ home = VectorJ::Zero(m.n_dof());
  if (m.n_dof() == 6) home << 0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0;
  const VectorJ g = model::gravity_torque(m, d, home);
  fmt::print("   gravity torque at the home pose [N·m]:");
  for (int i = 0; i < m.n_dof(); ++i) fmt::print(" {:+.3f}", g[i]);
  fmt::print("\n");
  return worst < 1e-9 ? 0 : 1;
}

twinwatch::cli::VerbRegistrar reg{"demo", 1, [](CLI::App& app) {
  auto robot = std::make_shared<std::string>("ur3e");
  auto* demo = app.add_subcommand("demo", "Run the whole story on the built-in virtual UR3e");
  demo->add_option("--robot", *robot, "Robot to use")->capture_default_str();
  demo->callback([robot] { twinwatch::cli::set_exit_code(step_model_check(*robot)); });
}};

}  // namespace
