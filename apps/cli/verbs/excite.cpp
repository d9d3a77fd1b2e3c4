// `twinwatch excite ROBOT -o traj.yaml`: design an optimised finite-Fourier excitation trajectory
// (Cao eq. 21-22, condition number of the base-parameter observation matrix) and write it as a
// scenario that `twinwatch simulate` runs.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <utility>
#include <nlohmann/json.hpp>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"
#include "twinwatch/ident/excitation.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/sim/simulator.hpp"
#include "verb_registry.hpp"

namespace {

using namespace twinwatch;

// the default --min-height, and the height below which a design is warned about when the user asked
// for a lower one [m] (5 cm over the base's mounting plane: the flange and the wrist bodies are that
// wide). Without it the default UR3e design took the wrist 0.28-0.38 m below the table (session 19).
constexpr double kWarnHeight = 0.05;
// cond(W) above which a design is said to excite the dynamics too little to identify them [-].
// Measured on the virtual UR3e (session 46, docs/validation.md "A design the limits leave too
// little motion"): the tool speed limit shrinks the design; with the swing pair beside it, designs of
// cond 147 and 1005 identified the twin alike, 5.5e4 raised J2's current error by 18-45 %, 5e6 by
// 72-134 %; with the swing pair slowed to the same limit, 2.5e4 raised it by 17-38 %.
constexpr double kWarnCond = 1e4;
constexpr const char* kBodyNames[] = {"", "J2", "J3", "J4", "J5", "J6", "J7"};

// a duration is a whole number of periods when it is within this of one (relative)
constexpr double kWholeCycleTolerance = 1e-9;

struct Options {
  std::string robot, output;
  int harmonics = 5, samples = 100, global = 3000, local = 3000;
  double base_frequency = 0.1, duration = 0.0, amplitude = 1.0, qdd_default = 5.0, fraction = 0.9;
  double min_height = kWarnHeight;  // [m] over the base's mounting plane
  unsigned seed = 1;
  std::vector<double> q0;
  std::vector<double> tool;  // --tool-point, three numbers per point [m, flange frame]
  // the installation's safety limits (Installation > Safety > Robot Limits), kept when given, and the tool
  twinwatch::cli::SafetyLimitOptions safety;
  bool duration_given = false;  // (else one period)
  bool json = false, quiet = false, progress = false;
};

nlohmann::json tool_json(const std::vector<Eigen::Vector3d>& points) {
  nlohmann::json a = nlohmann::json::array();
  for (const Eigen::Vector3d& p : points) a.push_back({p.x(), p.y(), p.z()});
  return a;
}

nlohmann::json vec(const VectorJ& v) {
  nlohmann::json a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}

int run(const Options& o) {
  require_output(o.output, {o.robot});  // (before the design's minute; never over the robot description)
  const model::RobotModel m = model::load_robot(o.robot);
  ident::ExcitationOptions eo;
  eo.harmonics = o.harmonics;
  eo.base_frequency = o.base_frequency;
  eo.seed = o.seed;
  eo.samples = o.samples;
  // the final limit check's grid at least as fine as the design's (--samples 100000 was refused as
  // "check_samples is 5000", a name no option has: audit of session 56)
  eo.check_samples = std::max(eo.check_samples, o.samples);
  eo.amplitude = o.amplitude;
  eo.default_qdd_max = o.qdd_default;
  eo.limit_fraction = o.fraction;
  // (each limit less the safety system's tolerance: what the controller lets the arm reach)
  const std::vector<twinwatch::cli::OperationalLimit> held = twinwatch::cli::operational_limits(o.safety);
  eo.tool_speed_max = held[0].value();
  eo.elbow_speed_max = held[1].value();
  eo.momentum_max = held[2].value();
  eo.carried = twinwatch::cli::carried_on_flange(o.safety, m);
  eo.global_evaluations = o.global;
  eo.local_evaluations = o.local;
  eo.min_height = o.min_height;
  if (!o.q0.empty()) eo.q0 = Eigen::Map<const Eigen::VectorXd>(o.q0.data(), static_cast<Eigen::Index>(o.q0.size()));
  eo.tool_points = twinwatch::cli::tool_points(o.tool);
  try {
    eo.validate(m.n_dof());
  } catch (const InvalidArgument& e) {
    // the library names its fields; the user typed options (audit of session 22: "q0 has 3 values")
    std::string what = e.what();
    // "tool_points[k] is ..." -> "--tool-point (number k+1 of n) is ..."
    if (what.rfind("tool_points[", 0) == 0) {
      const auto close = what.find(']');
      const int k = std::atoi(what.c_str() + 12);
      what = fmt::format("--tool-point (number {} of {})", k + 1, eo.tool_points.size()) + what.substr(close + 1);
    }
    what = twinwatch::cli::with_option_names(
        what, {{"harmonics", "--harmonics"}, {"base_frequency", "--base-frequency"}, {"samples", "--samples"}, {"q0", "--q0"},
               {"amplitude", "--amplitude"}, {"limit_fraction", "--limit-fraction"}, {"default_qdd_max", "--default-qdd-max"},
               {"min_height", "--min-height"}, {"global_evaluations", "--global-evals"}, {"local_evaluations", "--local-evals"},
               {"tool_speed_max", "--tool-speed-limit"}, {"elbow_speed_max", "--elbow-speed-limit"}, {"momentum_max", "--momentum-limit"}});
    throw InvalidArgument(what + fmt::format(" ({})", m.name()));
  }
  // the run must end at rest: a whole number of periods
  const double period = 1.0 / o.base_frequency;
  int cycles = 1;
  if (o.duration_given) {
    // the scenario written must load: a run of at most sim::kMaxDuration
    if (!(o.duration > 0.0 && o.duration <= sim::kMaxDuration))
      throw InvalidArgument(fmt::format("--duration: expected a time > 0 s and at most {:g} s (the longest run the simulator accepts), got {}",
                                        sim::kMaxDuration, o.duration));
    const double c = o.duration / period;
    cycles = static_cast<int>(std::lround(c));
    if (cycles < 1 || std::abs(c - cycles) > kWholeCycleTolerance * std::max(1.0, c))
      throw InvalidArgument(fmt::format("--duration {} s is not a whole number of periods ({} s at --base-frequency {} Hz); "
                                        "use e.g. {} s", o.duration, period, o.base_frequency, std::max(1L, std::lround(c)) * period));
  }
  // (one period beyond the longest run: the file was written, exit 0, and simulate refused it;
  // audit of session 56)
  if (!(cycles * period <= sim::kMaxDuration))
    throw InvalidArgument(cycles == 1 ? fmt::format("--base-frequency {} Hz: one period is {:g} s, longer than the longest run the simulator "
                                                    "accepts ({:g} s); expected at least {:g} Hz",
                                                    o.base_frequency, period, sim::kMaxDuration, 1.0 / sim::kMaxDuration)
                                      : fmt::format("--duration {}: {} whole periods of {:g} s make {:g} s, longer than the longest run the "
                                                    "simulator accepts ({:g} s)",
                                                    o.duration, cycles, period, cycles * period, sim::kMaxDuration));
  const bool bar = !o.quiet && !o.json && (o.progress || isatty(STDERR_FILENO));
  const auto t0 = std::chrono::steady_clock::now();
  const auto progress = [&](double f, double best) {
    if (!bar) return;
    const int w = 30, k = static_cast<int>(f * w);
    std::fprintf(stderr, "\r  optimising [%.*s%*s] %3.0f %%  best cond %.4g   ", k, "##############################", w - k, "",
                 100 * f, best);
    if (f >= 1.0) std::fprintf(stderr, "\n");
  };
  ident::ExcitationResult r = ident::design_excitation(m, eo, progress);
  std::string raised;  // what was done when the default centre left no room above --min-height
  if (o.q0.empty() && r.lowest.z < o.min_height) {
    // the middle of the ranges (a UR's stretched-out zero pose) holds the wrist a few cm over the
    // table: the centre is raised and the design run again
    eo.q0 = ident::excitation_raised_centre(m, eo);
    std::string q;
    for (Eigen::Index j = 0; j < eo.q0.size(); ++j) q += fmt::format("{}{:.3f}", j ? " " : "", eo.q0[j]);
    raised = fmt::format("the middle of the joint ranges left no design above --min-height {:g} m (lowest {:+.3f} m); the centre "
                         "was raised to --q0 {}", o.min_height, r.lowest.z, q);
    if (!o.quiet && !o.json) fmt::print(stderr, "{}; designing again\n", raised);
    r = ident::design_excitation(m, eo, progress);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // the design keeps the arm above --min-height on its grid; whether it held on the dense grid is
  // checked here, before the file a real robot program may run is written
  const ident::ExcitationLowestPoint& low = r.lowest;
  const auto tool_text = [&](size_t k) {
    const Eigen::Vector3d& p = eo.tool_points[k];
    return fmt::format("tool point {} ({:g}, {:g}, {:g}) m", k + 1, p.x(), p.y(), p.z());
  };
  const std::string where = low.body > m.n_dof()    ? "the " + tool_text(static_cast<size_t>(low.body - m.n_dof() - 1))
                            : low.body == m.n_dof() ? std::string("the flange")
                                                    : fmt::format("the {} axis", kBodyNames[std::min(low.body, 6)]);
  const std::string low_text = fmt::format("{} comes down to z = {:+.3f} m (z = 0: the base's mounting plane) at t = {:.2f} s", where, low.z, low.t);
  if (low.z < o.min_height)
    throw InvalidArgument(fmt::format("the search found no design above --min-height {:g} m: in the best one, {}; no file written. "
                                      "Raise the centre pose (--q0), reduce --amplitude, give more --global-evals, or try "
                                      "another --seed",
                                      o.min_height, low_text));
  // which points were kept up: the tool's, when the user gave them
  std::string tools_checked;
  for (size_t k = 0; k < eo.tool_points.size(); ++k) tools_checked += (k ? "; " : " with ") + tool_text(k);
  std::vector<std::string> warnings;
  if (r.cond_final > kWarnCond) {
    const bool limited = std::any_of(held.begin(), held.end(), [](const twinwatch::cli::OperationalLimit& l) { return l.given(); });
    warnings.push_back(fmt::format(
        "cond(W) is {:.3g}, above {:g}: the design moves the arm too little to identify its dynamics well{} (on the virtual UR3e a "
        "design of cond 5.5e4 raised the twin's J2 current error by 18-45 %, one of 1e3 did not). Identify it together with the swing "
        "pair (scenarios/ur3e/train/swing_train*.yaml through twinwatch urscript, with --robot for another arm), and check the twin with twinwatch validate on a "
        "run it was not identified from; {}",
        r.cond_final, kWarnCond,
        limited ? fmt::format(" (the safety limits scaled it down: peak tool speed {:.3f} m/s)", r.speed_peak.tool) : std::string(),
        limited ? "or, where the risk assessment allows, identify under a safety configuration with higher limits (a fenced cell)"
                : "or raise --amplitude or --limit-fraction"));
  }
  if (low.z < kWarnHeight)
    fmt::print(stderr,
               "WARNING: {} (--min-height {:g} m): on a real robot this may hit the table or the robot itself. Check it in "
               "simulation first\n",
               low_text, o.min_height);
  // the figures the installation's safety limits bound, at their peaks on the dense grid
  const model::CartesianSpeeds& sp = r.speed_peak;
  const std::string tool_peak_where = sp.tool_point < 0 ? std::string("the flange's centre") : tool_text(static_cast<size_t>(sp.tool_point));
  const auto kept = [](const twinwatch::cli::OperationalLimit& l, const char* unit) {
    return l.given() ? "kept within " + l.text(unit) : fmt::format("not limited: {}", l.option);
  };
  const std::string speeds_text =
      fmt::format("peak tool speed {:.3f} m/s at {} ({}), {}, "
                  "momentum {:.2f} kg m/s of the links{} ({})",
                  sp.tool, tool_peak_where, kept(held[0], "m/s"),
                  std::isnan(sp.elbow) ? std::string("no elbow (fewer than three joints)")
                                       : fmt::format("elbow {:.3f} m/s ({})", sp.elbow, kept(held[1], "m/s")),
                  sp.momentum, eo.carried.mass > 0 ? fmt::format(" and the {:g} kg tool", eo.carried.mass) : std::string(), kept(held[2], "kg m/s"));
  const std::string comment = fmt::format(
      "excitation trajectory for {} by `twinwatch excite` (finite Fourier series, Cao eq. 21-22)\n"
      "{} harmonics, base frequency {} Hz, seed {}; zero velocity and acceleration at start and end\n"
      "cond(W) over {} base-parameter columns on {} points: random start {:.6g}, global {:.6g}, final {:.6g}\n"
      "lowest point: {} (kept above {:g} m{})\n{}",
      m.name(), o.harmonics, o.base_frequency, o.seed, r.base_columns, o.samples, r.cond_start, r.cond_global, r.cond_final, low_text,
      o.min_height, tools_checked, speeds_text);
  const std::string comment_all = raised.empty() ? comment : comment + "\n" + raised;
  write_text_file(o.output, ident::excitation_scenario_yaml(r.trajectory, o.robot, cycles, comment_all));
  for (const std::string& w : warnings) fmt::print(stderr, "WARNING: {}\n", w);
  if (o.json) {
    nlohmann::json j{{"robot", m.name()},
                     {"output", o.output},
                     {"harmonics", o.harmonics},
                     {"base_frequency", o.base_frequency},
                     {"period", period},
                     {"cycles", cycles},
                     {"seed", o.seed},
                     {"base_columns", r.base_columns},
                     {"cond_start", r.cond_start},
                     {"cond_global", r.cond_global},
                     {"cond_final", r.cond_final},
                     {"evaluations", r.evaluations},
                     {"seconds", wall},
                     {"q_lo", vec(r.q_lo)},
                     {"q_hi", vec(r.q_hi)},
                     {"qd_limit", vec(r.qd_lim)},
                     {"qdd_limit", vec(r.qdd_lim)},
                     {"q_min", vec(r.q_min_seen)},
                     {"q_max", vec(r.q_max_seen)},
                     {"qd_peak", vec(r.qd_peak)},
                     {"qdd_peak", vec(r.qdd_peak)},
                     {"lowest_point", {{"z", low.z}, {"t", low.t}, {"where", where}}},
                     {"tool_points", tool_json(eo.tool_points)},
                     {"peak_tool_speed", sp.tool},
                     {"peak_tool_speed_point", sp.tool_point < 0 ? nlohmann::json("flange")
                                                                 : nlohmann::json::array({eo.tool_points[static_cast<size_t>(sp.tool_point)].x(),
                                                                                          eo.tool_points[static_cast<size_t>(sp.tool_point)].y(),
                                                                                          eo.tool_points[static_cast<size_t>(sp.tool_point)].z()})},
                     {"tool_mass", eo.carried.mass},
                     {"peak_elbow_speed", std::isnan(sp.elbow) ? nlohmann::json(nullptr) : nlohmann::json(sp.elbow)},
                     {"peak_momentum", sp.momentum},
                     {"limits", [&] {
                        nlohmann::json c = nlohmann::json::object();
                        const char* keys[] = {"tool_speed", "elbow_speed", "momentum"};
                        for (size_t k = 0; k < held.size(); ++k)
                          if (held[k].given())
                            c[keys[k]] = {{"entered", held[k].entered}, {"tolerance", held[k].tolerance}, {"kept_within", held[k].value()}};
                        return c;
                      }()},
                     {"min_height", o.min_height},
                     {"q0", vec(r.trajectory.q0)},
                     {"centre_raised", !raised.empty()},
                     {"warnings", warnings},
                     {"units", {{"z", "m (base frame)"}, {"t", "s"}, {"tool_points", "m (flange frame)"}, {"min_height", "m"}, {"q0", "rad"},
                                {"peak_tool_speed", "m/s"}, {"peak_elbow_speed", "m/s"}, {"peak_momentum", "kg m/s"}}}};
    fmt::print("{}\n", j.dump(2));
    return 0;
  }
  if (o.quiet) return 0;
  fmt::print("excitation for {}: {} harmonics, period {:g} s x {} cycle(s) -> {}\n", m.name(), o.harmonics, period, cycles,
             o.output);
  fmt::print("cond(W), {} base columns on {} points: random start {:.4g} -> global {:.4g} -> final {:.4g} ({} evaluations, {:.1f} s)\n",
             r.base_columns, o.samples, r.cond_start, r.cond_global, r.cond_final, r.evaluations, wall);
  fmt::print("{:<6} {:>22} {:>22} {:>16} {:>16}\n", "joint", "q range used rad", "q allowed rad", "|qd| peak/limit",
             "|qdd| peak/limit");
  for (int j = 0; j < m.n_dof(); ++j)
    fmt::print("J{:<5} {:>22} {:>22} {:>16} {:>16}\n", j + 1, fmt::format("[{:.3f}, {:.3f}]", r.q_min_seen[j], r.q_max_seen[j]),
               fmt::format("[{:.3f}, {:.3f}]", r.q_lo[j], r.q_hi[j]), fmt::format("{:.3f}/{:.3f}", r.qd_peak[j], r.qd_lim[j]),
               fmt::format("{:.2f}/{:.2f}", r.qdd_peak[j], r.qdd_lim[j]));
  fmt::print("lowest point: {} (kept above --min-height {:g} m{}; no other collision check)\n", low_text, o.min_height,
             tools_checked);
  fmt::print("{}\n", speeds_text);
  if (eo.tool_points.empty())
    fmt::print("  a tool on the flange was not checked: give its lowest points with --tool-point X Y Z (flange frame, m), e.g. a "
               "gripper's fingertips 0.15 m out: --tool-point 0 0 0.15\n");
  fmt::print("run it: twinwatch simulate {} -o excitation.csv\n", o.output);
  return 0;
}

twinwatch::cli::VerbRegistrar reg{"excite", 35, [](CLI::App& app) {
  auto o = std::make_shared<Options>();
  auto* sub = app.add_subcommand("excite", "Design an optimised excitation trajectory (finite Fourier, min cond(W)) as a scenario");
  sub->footer(twinwatch::cli::with_exit_status(
      "A finite Fourier series per joint (Cao eq. 21) that starts and ends at rest (zero velocity and\n"
      "acceleration, position back at q0), stays inside the joint position, velocity and acceleration limits,\n"
      "and whose coefficients NLopt chooses (global CRS2 then local Subplex) to minimise the condition number of\n"
      "the base-parameter observation matrix (rigid body + Coulomb/viscous/offset friction), keeping the arm above\n"
      "--min-height over the table it stands on (the tool too, with --tool-point). Writes a scenario\n"
      "YAML that `twinwatch simulate` runs; the coefficients in it drive a real robot program too."));
  sub->add_option("ROBOT", o->robot, "Built-in robot name (ur3e, ur5e, ur10e, panda) or a .json/.urdf description")->required();
  sub->add_option("-o,--output", o->output, "Scenario YAML to write")->required();
  sub->add_option("--harmonics", o->harmonics, "Harmonics L per joint (>= 3)")->capture_default_str();
  sub->add_option("--base-frequency", o->base_frequency, "Base frequency [Hz]; the period is its inverse")->capture_default_str();
  auto* duration = sub->add_option("--duration", o->duration, "Total run time [s], a whole number of periods (default: one period)");
  sub->add_option("--seed", o->seed, "Seed of the random start and of the global search")->capture_default_str();
  sub->add_option("--q0", o->q0, "Centre (start and end) position per joint [rad] (default: middle of each range, raised to a pose that holds the arm up when that leaves no design above --min-height)");
  sub->add_option("--amplitude", o->amplitude, "Largest excursion from q0 [rad] besides the joint limits")->capture_default_str();
  sub->add_option("--limit-fraction", o->fraction, "Share of the velocity/acceleration limits and position range used")
      ->capture_default_str();
  sub->add_option("--default-qdd-max", o->qdd_default,
                  "Acceleration limit [rad/s²] for joints whose description publishes none")->capture_default_str();
  sub->add_option("--samples", o->samples, "Points per period at which cond(W) is evaluated")->capture_default_str();
  sub->add_option("--global-evals", o->global, "Objective evaluations of the global step (0: skip)")->capture_default_str();
  sub->add_option("--local-evals", o->local, "Objective evaluations of the local step (0: skip)")->capture_default_str();
  sub->add_option("--min-height", o->min_height,
                  "Keep the body origins and the flange above this height [m] over the base's mounting plane: a constraint "
                  "of the search, and a design that still comes lower is refused, no file written. Negative for an arm on "
                  "a pedestal (e.g. -0.3); below 0.05 m a warning is printed. No other collision check is made")
      ->capture_default_str();
  twinwatch::cli::add_tool_point_option(sub, o->tool,
                                        "A point of the tool on the flange, in the flange frame [m] (3 numbers; repeat for more points, e.g. a "
                                        "gripper's two fingertips): kept above --min-height like the flange, and its speed counts as the tool's for "
                                        "--tool-speed-limit. Without it a tool is not checked");
  twinwatch::cli::add_safety_limit_options(sub, o->safety, "Keep the design within");
  sub->add_flag("--json", o->json, "Print the summary (condition numbers, limits, peaks) as JSON");
  sub->add_flag("-q,--quiet", o->quiet, "Print nothing on success but the JSON that --json asks for");
  sub->add_flag("--progress", o->progress, "Show the progress bar even when stderr is not a terminal");
  sub->callback([o, duration] {
    o->duration_given = duration->count() > 0;
    twinwatch::cli::set_exit_code(run(*o));
  });
}};

}  // namespace
