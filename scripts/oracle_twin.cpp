// Evaluation only (reads the simulator's hidden truth; never a twin to monitor with): writes a copy
// of a twin whose rigid-body base parameters and armature are the simulator's truth (serial 1), to
// measure how many contact-link misses the twin's inertia error causes (docs/validation.md, session
// 12: none). The truth is the simulator's own (Simulator::truth_model). Build and run after
// `cmake --build build`:
//   g++ -O2 -std=c++20 -Iinclude -I/usr/include/eigen3 scripts/oracle_twin.cpp -o /tmp/oracle_twin \
//     -Lbuild/src/sim -Lbuild/src/ident -Lbuild/src/friction -Lbuild/src/model -Lbuild/src/signal -Lbuild/src/core \
//     -ltwinwatch_sim -ltwinwatch_ident -ltwinwatch_friction -ltwinwatch_model -ltwinwatch_signal -ltwinwatch_core \
//     -lurdfdom_model -lyaml-cpp -lspdlog -lfmt -lnlopt -lceres -lglog
//   /tmp/oracle_twin twin.json oracle_twin.json        # prints twin vs truth per base parameter
//   build/twinwatch evaluate scenarios/ur3e/heldout4_collisions --twin oracle_twin.json
#include <fstream>
#include <iostream>
#include "twinwatch/ident/twin_model.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/regressor.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "twinwatch/sim/simulator.hpp"
using namespace twinwatch;
int main(int argc, char** argv) {
  std::ifstream in(argv[1]); std::string text((std::istreambuf_iterator<char>(in)), {});
  ident::TwinModel tw = ident::TwinModel::from_json(text, argv[1]);
  const std::string mode = argc > 3 ? argv[3] : "both";
  model::RobotModel nom = model::load_robot("ur3e");
  sim::PlantTruth pt = sim::default_truth(nom, 1);
  // the hidden link parameters of robot serial 1, as every scenario without a payload simulates them
  const auto simulator = sim::make_simulator(sim::parse_scenario(
      "robot: ur3e\nduration: 1\ntrajectory: {type: sine, start: [0, -1.57, 1.57, -1.57, -1.57, 0], amplitude: [0.1, 0.1, 0.1, 0.1, 0.1, 0.1], "
      "frequency: [0.2, 0.2, 0.2, 0.2, 0.2, 0.2]}\n", "oracle"));
  const model::RobotModel& tr = simulator->truth_model();
  model::BaseParameters bp = model::compute_base_parameters(nom);
  if (bp.independent != tw.base_columns) { std::cerr << "base columns differ\n"; return 1; }
  Eigen::VectorXd bt = bp.base_values(model::standard_parameters(tr));
  for (int i = 0; i < bt.size(); ++i) std::cerr << i << " twin " << tw.beta[i] << " truth " << bt[i] << "\n";
  if (mode == "both" || mode == "beta") tw.beta = bt;
  for (int j = 0; j < tw.n_dof(); ++j) {
    double a = sim::armature(pt.joints[j]);
    std::cerr << "J" << j+1 << " armature twin " << tw.joints[j].friction[ident::kArmature] << " truth " << a << "\n";
    if (mode == "both" || mode == "beta") tw.joints[j].friction[ident::kArmature] = a;
  }
  tw.save(argv[2]);
}
