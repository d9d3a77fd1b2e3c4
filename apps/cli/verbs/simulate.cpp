// `twinwatch simulate SCENARIO.yaml -o rec.csv`: run the virtual robot, write a recording and its
// ground-truth labels (rec.labels.json).
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <stdexcept>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"
#include "twinwatch/device/recording.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/sim/robot_program.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "recordings.hpp"
#include "verb_registry.hpp"

namespace {

struct Options {
  std::string scenario, output, robot;
  long seed = -1;
  double duration = -1;
  bool seed_given = false, duration_given = false;  // (the values above are then the user's)
  bool quiet = false, progress = false;
  bool as_program = false;  // rehearse the motion `twinwatch urscript` writes (ramps, started at rest)
  double ramp = 2.0;
  double slow_down = 1.0;  // (as urscript --slow-down)
};

std::string labels_path(const std::string& output) {
  std::filesystem::path p(output);
  p.replace_extension();
  return p.string() + ".labels.json";
}

int run(const Options& o) {
  using namespace twinwatch;
  // a file, with its labels beside it: not '-' (which would be a file named '-', not standard
  // output) and not a device or pipe (/dev/stdout: the labels would go to /dev/stdout.labels.json)
  std::error_code ec;
  const auto st = std::filesystem::status(o.output, ec);
  const bool device = o.output.rfind("/dev/", 0) == 0 || o.output.rfind("/proc/", 0) == 0;  // (/dev/stdout into a file is one)
  if (o.output == "-" || device || (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st) && !std::filesystem::is_directory(st)))
    throw PathError(fmt::format("{}: cannot write: simulate writes a recording file and its labels beside it (rec.csv -> "
                                "rec.labels.json); give a file name{}",
                                o.output, o.output == "-" ? " ('-' is no standard output here)" : ", not a device or pipe"));
  // (-o x.labels.json wrote the recording under a labels file's name and its labels as
  // x.labels.labels.json; over another recording's labels it replaced them: audit of session 56)
  if (o.output.size() >= 12 && o.output.compare(o.output.size() - 12, 12, ".labels.json") == 0)
    throw PathError(fmt::format("{}: cannot write: that is a labels file's name; give the recording's (rec.csv), and its labels are "
                                "written beside it (rec.labels.json)",
                                o.output));
  // neither output may be the scenario (or the other output): checked before the run writes anything
  require_output(o.output, {o.scenario});
  require_output(labels_path(o.output), {o.scenario, o.output});
  if (!o.robot.empty()) model::load_robot(o.robot);  // (a bad --robot said as such, not as the scenario's)
  sim::Scenario s = [&] {
    // (with --as-program the program's own motion, slowed and ramped, is checked below)
    if (o.robot.empty()) return sim::load_scenario(o.scenario, "", !o.as_program);
    try {
      return sim::load_scenario(o.scenario, o.robot, !o.as_program);
    } catch (const std::exception& e) {  // (the file's field is right for its own robot: the message says which robot it was read for)
      throw InvalidArgument(fmt::format("{} (the scenario read for --robot {})", e.what(), o.robot));
    }
  }();
  // nor the robot description the scenario names
  require_output(o.output, {model::robot_file(s.robot)});
  require_output(labels_path(o.output), {model::robot_file(s.robot)});
  if (o.seed_given) {
    if (o.seed < 0 || o.seed > static_cast<long>(std::numeric_limits<unsigned>::max()))
      throw InvalidArgument(fmt::format("--seed: expected 0 to {}, got {}", std::numeric_limits<unsigned>::max(), o.seed));
    s.options.seed = static_cast<unsigned>(o.seed);
  }
  if (o.duration_given) sim::override_duration(s, o.duration, "--duration", !o.as_program);
  std::shared_ptr<const sim::ProgramMotion> program;
  if (o.as_program) {
    sim::ProgramOptions po;
    po.duration = s.options.duration;
    po.ramp = o.ramp;
    po.slow_down = o.slow_down;
    std::optional<sim::ClosedForm> form;  // (the scenario's, before rehearse_as_program puts the program in its place)
    try {
      form = sim::scenario_closed_form(s);
      program = sim::rehearse_as_program(s, po);
    } catch (const InvalidArgument& e) {
      // (the library names its fields; the user typed options)
      const std::string m = twinwatch::cli::with_option_names(
          e.what(), {{"ramp", "--ramp"}, {"slow_down", "--slow-down"}, {"duration", o.duration_given ? "--duration" : "the scenario's duration"}});
      throw InvalidArgument(m.rfind(o.scenario, 0) == 0 ? m : fmt::format("{}: {}", o.scenario, m));
    }
    const model::RobotModel robot = model::load_robot(s.robot);
    // the limits a rehearsal with --slow-down K leaves: a remedy is checked on the program it suggests
    const auto violation_at = [&](double k) {
      sim::ProgramOptions p = po;
      p.slow_down = k;
      const sim::ProgramMotion m(*form, p);
      return sim::joint_limit_violation(m, robot, m.total(), s.options.rate);
    };
    if (const std::string v = sim::joint_limit_violation(*program, robot, program->total(), s.options.rate); !v.empty())
      throw InvalidArgument(fmt::format("{}: the program's motion leaves the robot's limits: {}; nothing written{}", o.scenario, v,
                                        twinwatch::cli::slow_down_remedy(*program, robot, o.slow_down, std::numeric_limits<double>::infinity(), violation_at)));
  }
  auto simulator = sim::make_simulator(s);
  const int n = simulator->truth_model().n_dof();
  // a run that cannot fit the disk is refused before it fills it (--duration 1e6 wrote 481 MB in 5 s
  // towards 480 GB on a 72 GB disk: audit of session 56). A cell is 16 bytes or fewer as written
  // (shortest round-trip; the figure-eight's 62 columns write 960 bytes a row)
  {
    constexpr double kBytesPerCell = 16.0;
    const double rows = s.options.duration * s.options.rate;
    const double bytes = rows * kBytesPerCell * static_cast<double>(device::recording_columns(n, simulator->sample_fields()).size());
    std::error_code ec;
    const std::filesystem::path dir = std::filesystem::absolute(o.output, ec).parent_path();
    const std::filesystem::space_info room = std::filesystem::space(dir, ec);
    if (!ec && bytes > static_cast<double>(room.available))
      throw PathError(fmt::format("{}: cannot write: the run's {:.4g} s at {:g} Hz make about {:.3g} GB, and {} has {:.3g} GB free; "
                                  "shorten it (--duration) or write elsewhere",
                                  o.output, s.options.duration, s.options.rate, bytes / 1e9, dir.string(),
                                  static_cast<double>(room.available) / 1e9));
  }
  device::RecordingWriter writer(o.output, n, simulator->sample_fields());
  const bool bar = !o.quiet && (o.progress || isatty(STDERR_FILENO));
  const auto t0 = std::chrono::steady_clock::now();
  try {
    simulator->run([&](const RobotSample& smp) { writer.write(smp); },
                   [&](double f) {
                     if (!bar) return;
                     const int w = 40, k = static_cast<int>(f * w);
                     std::fprintf(stderr, "\r  simulating [%.*s%*s] %3.0f %%", k, "########################################",
                                  w - k, "", 100 * f);
                     if (f >= 1.0) std::fprintf(stderr, "\n");
                   });
  } catch (const InvalidArgument& e) {
    // (no half recording is left behind under the name of a whole one)
    if (bar) std::fprintf(stderr, "\n");
    writer.close();
    std::error_code ec;
    std::filesystem::remove(o.output, ec);
    throw InvalidArgument(fmt::format("{}: {}; nothing written", o.scenario, e.what()));
  }
  writer.close();
  write_text_file(labels_path(o.output), sim::labels_json(s) + "\n");
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!o.quiet && program)
    fmt::print("{}: rehearsed as its URScript program runs it: started at rest, the clock rising over {:.1f} s and falling over {:.1f} s "
               "({:.1f} s of the trajectory in {:.1f} s{}; the approach to the start pose is not simulated)\n",
               s.name, program->ramp_in(), program->ramp_out(), program->clock(program->total()) / o.slow_down, program->total(),
               o.slow_down != 1.0 ? fmt::format(", {:g} times slower", o.slow_down) : std::string());
  if (!o.quiet)
    fmt::print("{}: {} samples, {:.1f} s of robot time at {:g} Hz in {:.2f} s ({:.0f}x real time), {} fault(s) -> {}\n",
               s.name, writer.rows(), s.options.duration, s.options.rate, wall, s.options.duration / wall, s.faults.size(),
               labels_path(o.output));
  return 0;
}

twinwatch::cli::VerbRegistrar reg{"simulate", 20, [](CLI::App& app) {
  auto o = std::make_shared<Options>();
  auto* sub = app.add_subcommand("simulate", "Run the virtual robot on a scenario and write a recording (+ labels)");
  sub->add_option("SCENARIO", o->scenario, "Scenario YAML (see scenarios/ur3e/ and docs/scenarios.md)")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("-o,--output", o->output, "Recording CSV to write; the labels go beside it (rec.csv -> rec.labels.json)")->required();
  auto* seed = sub->add_option("--seed", o->seed, "Override the scenario's seed");
  sub->add_option("--robot", o->robot,
                  "Run the scenario on this robot (name or file) instead of its own, e.g. the UR3e swing pair on a ur5e (its limits "
                  "and rated payload are checked for this one)")
      ->transform([](std::string r) { return twinwatch::cli::robot_reference(r); });
  auto* duration = sub->add_option("--duration", o->duration, "Override the duration [s] (one sample period to 1e6 s)");
  auto* as_program = sub->add_flag("--as-program", o->as_program,
                "Run the motion 'twinwatch urscript' writes for a real arm instead: started at rest, the clock ramped where the "
                "trajectory starts or ends moving (joint-space trajectories only)");
  auto* ramp = sub->add_option("--ramp", o->ramp, "With --as-program: seconds of the clock's rise and fall (as urscript --ramp)")
                   ->capture_default_str()
                   ->check(twinwatch::cli::nonnegative_number());
  auto* slow = sub->add_option("--slow-down", o->slow_down,
                               "With --as-program: run the trajectory this many times slower, 1-100 (as urscript --slow-down)")
                   ->capture_default_str();
  sub->add_flag("-q,--quiet", o->quiet, "Print nothing on success");
  sub->add_flag("--progress", o->progress, "Show the progress bar even when stderr is not a terminal");
  sub->callback([o, seed, duration, as_program, ramp, slow] {
    twinwatch::cli::refuse_unless({ramp, slow}, as_program->count() > 0, "with --as-program");
    o->seed_given = seed->count() > 0;
    o->duration_given = duration->count() > 0;
    twinwatch::cli::set_exit_code(run(*o));
  });
}};

}  // namespace
