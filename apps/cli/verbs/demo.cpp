// `twinwatch demo`: the whole story on the built-in virtual UR3e — check the model, identify a twin
// from simulated healthy runs, monitor the fault scenarios, print the detection table and write
// an HTML report. Every step is a function.
#include <fmt/format.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>

#include "evaluate.hpp"
#include "twinwatch/core/data_dir.hpp"
#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"
#include "twinwatch/device/recording.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "verb_registry.hpp"

namespace {

using namespace twinwatch;

// step 1: load the robot and check the dynamics against itself on seeded random states
int step_model_check(const std::string& robot_name) {
  model::RobotModel m = model::load_robot(robot_name);
  model::DynamicsData d(m);
  fmt::print("== step 1: robot model '{}' ({} joints, {})\n", m.name(), m.n_dof(), m.description().source);
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
  return worst < 1e-9 ? 0 : 1;
}

// the scenario files of --scenarios; the J5-resistance run the report of step 4 shows must be one
std::vector<std::string> scenario_files(const std::string& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw PathError(fmt::format("--scenarios {}: {}", dir, std::filesystem::exists(dir, ec) ? "not a directory" : "no such directory"));
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".yaml") files.push_back(e.path().string());
  if (files.empty()) throw PathError(fmt::format("--scenarios {}: no scenario files (*.yaml)", dir));
  if (!std::filesystem::is_regular_file(std::filesystem::path(dir) / "j5_resistance.yaml", ec))
    throw PathError(fmt::format("--scenarios {}: no j5_resistance.yaml, the run step 4's report shows (the library's is in "
                                "scenarios/ur3e)",
                                dir));
  std::sort(files.begin(), files.end());
  return files;
}

// the output directory, made if it does not exist
void make_output_directory(const std::string& out) {
  std::error_code ec;
  if (std::filesystem::exists(out, ec) && !std::filesystem::is_directory(out, ec))
    throw PathError(fmt::format("-o {}: cannot write: it exists and is not a directory", out));
  std::filesystem::create_directories(out, ec);
  if (ec) throw PathError(fmt::format("-o {}: cannot make the directory: {}", out, ec.message()));
  require_writable((std::filesystem::path(out) / "twin.json").string());
}

struct Options {
  std::string robot = "ur3e", out = "twinwatch-demo", scenarios;
  double max_duration = 60.0;
  bool quick = false;
};

int run(const Options& o) {
  const auto t0 = std::chrono::steady_clock::now();
  if (step_model_check(o.robot) != 0) return 1;
  if (o.quick) return 0;
  // the scenarios must be of the twin's robot: checked before the minute of training, not after
  const auto files = scenario_files(o.scenarios);
  size_t too_long = 0;  // (every one skipped was said after the minute of training, not before)
  for (const auto& f : files) {
    const sim::Scenario sc = sim::load_scenario(f);
    if (sc.robot != o.robot)
      throw InvalidArgument(fmt::format("--robot {}: {} runs robot '{}'; give --scenarios DIR with scenarios of '{}' (the built-in "
                                        "library, scenarios/ur3e, is for the UR3e)",
                                        o.robot, f, sc.robot, o.robot));
    too_long += cli::longer_than_max(sc, o.max_duration);
  }
  if (!files.empty() && too_long == files.size())
    throw InvalidArgument(fmt::format("every scenario ({}) in {} is longer than --max-duration {:g} s: nothing would be evaluated",
                                      files.size(), o.scenarios, o.max_duration));
  make_output_directory(o.out);

  fmt::print("== step 2: identify the twin from simulated healthy runs (recordings only, DESIGN.md rule 1)\n");
  ident::TwinModel twin = cli::train_reference(o.robot, false);
  const std::string twin_path = (std::filesystem::path(o.out) / "twin.json").string();
  twin.save(twin_path);
  fmt::print("   twin written to {}\n", twin_path);

  fmt::print("== step 3: monitor the scenario library ({})\n", o.scenarios);
  const cli::Evaluation ev = cli::evaluate_scenarios(twin, files, false, o.max_duration, false);
  cli::print_evaluation(ev);
  write_text_file((std::filesystem::path(o.out) / "evaluation.json").string(), cli::evaluation_json(ev) + '\n');

  fmt::print("== step 4: report of the J5-resistance run (UR3e §4.2)\n");
  sim::Scenario s = sim::load_scenario((std::filesystem::path(o.scenarios) / "j5_resistance.yaml").string());
  const std::string rec = (std::filesystem::path(o.out) / "j5_resistance.csv").string();
  {
    const auto simulator = sim::make_simulator(s);
    device::RecordingWriter w(rec, 6, simulator->sample_fields());
    simulator->run([&](const RobotSample& x) { w.write(x); });
    w.close();
  }
  const std::string html = (std::filesystem::path(o.out) / "report.html").string();
  model::RigidBodyInertia declared;  // what the program declares: mass and centre of mass (the report's twin takes no inertia)
  declared.mass = s.options.payload.mass;
  declared.com = s.options.payload.com;
  cli::write_report(twin, {rec}, declared, html, sim::parse_labels(sim::labels_json(s), s.path + " (its labels)"));
  fmt::print("   {} (open it in a browser)\n", html);
  fmt::print("done in {:.1f} s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return 0;
}

twinwatch::cli::VerbRegistrar reg{"demo", 1, [](CLI::App& app) {
  auto o = std::make_shared<Options>();
  o->scenarios = twinwatch::data_directory("scenarios") + "/ur3e";
  auto* demo = app.add_subcommand("demo", "Run the whole story on the built-in virtual UR3e (identify, monitor faults, report)");
  demo->add_option("--robot", o->robot, "Robot to use")->capture_default_str();
  auto* out = demo->add_option("-o,--output", o->out, "Directory for the twin, recordings and report")->capture_default_str();
  auto* scen = demo->add_option("--scenarios", o->scenarios, "Scenario directory")->capture_default_str();
  auto* maxd = demo->add_option("--max-duration", o->max_duration, "Skip scenarios longer than this [s] (0: run all, wear_ramp's 7200 s included)")->capture_default_str()->check(twinwatch::cli::nonnegative_number());
  demo->add_flag("--quick", o->quick, "Only the model check (step 1)");
  demo->callback([o, out, scen, maxd] {
    // --quick runs step 1 alone: what the later steps take did nothing there
    twinwatch::cli::refuse_unless({out, scen, maxd}, !o->quick, "to the whole demo, not --quick (the model check alone)");
    twinwatch::cli::set_exit_code(run(*o));
  });
}};

}  // namespace
