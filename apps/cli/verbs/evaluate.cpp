// `twinwatch evaluate` and `twinwatch report`: scoring a twin against scenario labels (and the
// collision-sensitivity sweep), and the HTML report of one recording. They run the monitor as
// `twinwatch monitor` does, with its alert settings (monitor_run.hpp); the work is in evaluate.cpp.
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "evaluate.hpp"
#include "monitor_run.hpp"
#include "recordings.hpp"
#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"
#include "twinwatch/ident/twin_model.hpp"
#include "twinwatch/monitor/monitor.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "verb_registry.hpp"

namespace {

using namespace twinwatch;

struct EvaluateOptions {
  std::vector<std::string> dirs;
  std::string twin, robot = "ur3e", save_twin, trend_csv, filter, signal = "current";
  bool json = false, static_threshold = false, sweep = false, all_programs = false;
  double max_duration = 0.0;
  double link_ceiling = -1.0;
  std::vector<double> sensitivity;
  int raise_after = 0, observer_raise_after = 0;  // debounce overrides (0: the twin's)
  std::vector<double> part_com;                     // where an undeclared part sits (empty: the twin's)
  cli::SweepOptions sweep_options;
};

// evaluate's --sensitivity / --raise-after / --observer-raise-after / --part-com written into the twin's monitor block
void apply_alert_settings(ident::TwinModel& twin, const EvaluateOptions& o) {
  if (o.sensitivity.empty() && o.raise_after == 0 && o.observer_raise_after == 0 && o.part_com.empty()) return;
  monitor::MonitorConfig cfg = cli::config_of(twin, o.twin.empty() ? "the reference twin" : o.twin);
  cli::apply_part_com(cfg, o.part_com);
  cli::apply_alert_settings(cfg, twin.n_dof(), o.sensitivity, o.raise_after, o.observer_raise_after);
  twin.monitor_json = cfg.to_json();
}

int run_evaluate(const EvaluateOptions& o) {
  {  // (the point is checked before the reference twin's minute of training)
    monitor::MonitorConfig probe;
    cli::apply_part_com(probe, o.part_com);
  }
  if (o.sweep) {
    if (!o.dirs.empty())
      throw InvalidArgument(fmt::format("--sweep-collisions simulates its own contacts; it takes no scenarios (got {})", o.dirs.front()));
    o.sweep_options.validate();
    if (!o.save_twin.empty()) require_output(o.save_twin, {o.twin});
    ident::TwinModel twin = o.twin.empty() ? cli::train_reference(o.robot, o.json, {}, o.all_programs, o.signal == "joint_torque") : cli::load_twin(o.twin);
    apply_alert_settings(twin, o);
    if (!o.save_twin.empty()) twin.save(o.save_twin);
    const cli::Sweep sw = cli::sweep_collisions(twin, o.sweep_options, o.json);
    if (o.json) fmt::print("{}\n", cli::sweep_json(sw, o.sweep_options));
    else cli::print_sweep(sw, o.sweep_options);
    return 0;
  }
  if (o.dirs.empty()) throw InvalidArgument("evaluate: give a SCENARIOS directory or file, or --sweep-collisions");
  std::vector<std::string> files;
  for (const auto& d : o.dirs) {
    std::vector<std::string> here;
    if (std::filesystem::is_directory(d)) {
      for (const auto& e : std::filesystem::directory_iterator(d))
        if (e.path().extension() == ".yaml" || e.path().extension() == ".yml") here.push_back(e.path().string());
    } else {
      here.push_back(d);
    }
    if (here.empty()) throw InvalidArgument(fmt::format("{}: no scenario files (*.yaml) found", d));
    std::sort(here.begin(), here.end());
    files.insert(files.end(), here.begin(), here.end());
  }
  if (!o.filter.empty() && !o.twin.empty())
    throw InvalidArgument("--filter applies to the reference trained here; a --twin file keeps the filter its thresholds were learned "
                          "with (re-learn them with 'twinwatch thresholds --filter')");
  // a scenario given twice would be scored twice
  cli::require_distinct(files, "SCENARIOS");
  // every scenario is read before any output is touched: a malformed one (or one of another robot)
  // used to fail after --save-twin had replaced its file and --trend-csv had emptied its own
  std::vector<std::string> robots;
  for (const auto& f : files) robots.push_back(sim::load_scenario(f).robot);
  // the outputs are checked before any work, and touched only once the twin is in hand: neither may
  // be an input (a scenario, the twin) or the other output
  std::vector<std::string> inputs = files;
  inputs.push_back(o.twin);
  if (!o.save_twin.empty()) require_output(o.save_twin, inputs);
  if (!o.trend_csv.empty()) {
    inputs.push_back(o.save_twin);
    require_output(o.trend_csv, inputs);
  }
  ident::TwinModel twin = o.twin.empty() ? cli::train_reference(o.robot, o.json, o.filter.empty() ? std::vector<std::string>{} : cli::split_filter(o.filter), o.all_programs,
                                                               o.signal == "joint_torque")
                                         : cli::load_twin(o.twin);
  apply_alert_settings(twin, o);
  for (size_t i = 0; i < files.size(); ++i)
    if (robots[i] != twin.robot_name())
      throw InvalidArgument(fmt::format("{} runs robot '{}', the twin is of '{}': evaluate scores a twin on scenarios of its own robot",
                                        files[i], robots[i], twin.robot_name()));
  if (!o.save_twin.empty()) twin.save(o.save_twin);
  // (the wear trend's rows are appended scenario by scenario: the file starts with the header only;
  // it had been created empty, so the header that the first append wrote to a new file never came:
  // audit of session 57)
  if (!o.trend_csv.empty()) write_text_file(o.trend_csv, cli::kTrendCsvHeader);
  const cli::Evaluation ev = cli::evaluate_scenarios(twin, files, o.static_threshold, o.max_duration, o.json, o.trend_csv, o.link_ceiling);
  if (o.json) fmt::print("{}\n", cli::evaluation_json(ev));
  else cli::print_evaluation(ev);
  return 0;
}

struct ReportOptions {
  std::string twin, output = "report.html", labels, column_map, program;
  std::vector<std::string> recordings;  // one stream in the order given, as monitor reads several
  bool quiet = false, keep_payload = false;
  // monitor's alert settings, so that the report shows the run monitor makes with them
  std::vector<double> sensitivity;
  int raise_after = 0, observer_raise_after = 0;
  std::string filter;
  bool static_threshold = false;
  double payload_mass = std::numeric_limits<double>::quiet_NaN();  // not given: the twin file's payload
  std::vector<double> payload_com;
  std::vector<double> part_com;
};

int run_report(const ReportOptions& o) {
  std::vector<std::string> inputs = o.recordings;
  for (const std::string* f : {&o.twin, &o.labels, &o.column_map}) inputs.push_back(*f);
  require_output(o.output, inputs);
  cli::require_distinct(o.recordings, "RECORDING");
  const ident::TwinModel twin = cli::load_twin(o.twin);
  std::optional<sim::Labels> labels;
  if (!o.labels.empty()) {
    std::error_code ec;
    if (std::filesystem::is_directory(o.labels, ec)) throw PathError(o.labels + ": cannot read the labels file: it is a directory");
    std::ifstream f(o.labels);
    if (!f) throw PathError(o.labels + ": cannot open the labels file");
    labels = sim::parse_labels(std::string(std::istreambuf_iterator<char>(f), {}), o.labels);
    // a run of the same length and rate cannot be told apart from this one by the report (it
    // refuses one that differs): a labels file not named after the recording is said
    const std::filesystem::path own = std::filesystem::path(o.recordings.front()).replace_extension(".labels.json");
    if (o.recordings.size() == 1 && !same_file(own.string(), o.labels))
      fmt::print(stderr, "note: --labels {} is not {}'s own labels file ({}): the spans shaded are those of scenario '{}'\n", o.labels,
                 o.recordings.front(), own.string(), labels->scenario);
  }
  const model::RigidBodyInertia payload = cli::payload_for(twin, o.twin, o.payload_mass, o.payload_com);
  const auto map = cli::load_column_map(o.column_map, twin);
  // (what monitor applies over the twin's block, in its order: the filter, then the alert settings)
  const auto adjust = [&](monitor::MonitorConfig& cfg) {
    if (o.static_threshold) cfg.use_dynamic = false;
    if (!o.filter.empty()) {
      cfg.residual_filter = cli::split_filter(o.filter);
      cfg.validate(twin.n_dof());
    }
    cli::apply_part_com(cfg, o.part_com);
    cli::apply_alert_settings(cfg, twin.n_dof(), o.sensitivity, o.raise_after, o.observer_raise_after);
  };
  cli::write_report(twin, o.recordings, payload, o.output, labels, map ? &*map : nullptr, o.program, o.keep_payload, adjust);
  if (!o.quiet) fmt::print("report written to {}\n", o.output);
  return 0;
}

twinwatch::cli::VerbRegistrar reg_evaluate{"evaluate", 42, [](CLI::App& app) {
  auto o = std::make_shared<EvaluateOptions>();
  auto* sub = app.add_subcommand("evaluate", "Simulate scenarios, monitor them and score detection against the labels");
  sub->add_option("SCENARIOS", o->dirs,
                  "Scenario directory (its .yaml files, not its subfolders: e.g. scenarios/ur3e; scenarios/ur3e/long holds >= 1 h "
                  "of nominal operation, scenarios/ur3e/wear the 2-hour wear ramps) or scenario files; several may be given")
      ->check(CLI::ExistingPath);
  sub->add_option("--twin", o->twin, "Twin file (default: identify one from simulated healthy runs first)");
  auto* robot = sub->add_option("--robot", o->robot, "Robot for the default twin")->capture_default_str();
  auto* signal = sub->add_option("--signal", o->signal,
                  "What the default twin compares: current (the motor currents, as a UR streams them) or joint_torque (the simulated "
                  "arm gets joint torque sensors between gear and link, noise 0.2 % of each joint's torque limit, and the twin is "
                  "identified on them; a --twin file brings its own)")
      ->capture_default_str()
      ->check(CLI::IsMember({"current", "joint_torque"}));
  sub->add_option("--save-twin", o->save_twin, "Write the twin used (trained or loaded) to this file");
  auto* max_duration = sub->add_option("--max-duration", o->max_duration, "Skip scenarios longer than this [s] (default 0: run all)")
                           ->check(twinwatch::cli::nonnegative_number());
  auto* static_threshold = sub->add_flag("--static", o->static_threshold, "Static threshold instead of the dynamic one");
  auto* all_programs = sub->add_flag("--all-programs", o->all_programs,
                "Learn ONE threshold set over every program of scenarios/ur3e/long (figure-eight, triangle at 3 speeds, "
                "pick-and-place) instead of one set per program; wider thresholds (misses payload loss on the figure-eight); "
                "for comparison");
  sub->add_option("--sensitivity", o->sensitivity,
                  std::string(cli::kSensitivityHelp) + ", over the twin's; e.g. to measure the false-alarm margin of the long runs")
      ->delimiter(',')
      ->allow_extra_args(false);
  sub->add_option("--raise-after", o->raise_after, cli::kRaiseAfterHelp)->check(twinwatch::cli::whole_number(1, 1000));
  sub->add_option("--observer-raise-after", o->observer_raise_after, cli::kObserverRaiseAfterHelp)->check(twinwatch::cli::whole_number(1, 1000));
  sub->add_option("--part-com", o->part_com, std::string(cli::kPartComHelp) + "; written into the twin scored (and --save-twin)")
      ->expected(3)
      ->allow_extra_args(false);
  auto* filter = sub->add_option("--filter", o->filter, cli::kFilterHelp);
  sub->add_flag("--json", o->json, "Print {\"scenarios\": [...], \"false_alarms_per_hour\": ...}");
  auto* trend_csv = sub->add_option("--trend-csv", o->trend_csv,
                  "Write every scenario's per-window wear-trend history to this CSV, one row per scenario, joint and trend "
                  "window (30 s by default), under the header scenario,t,joint,friction,coulomb,viscous,energy,temperature,valid,i_total: the "
                  "window's end [s], its temperature-compensated extra friction and its Coulomb and viscous parts, the "
                  "residual energy, the mean joint temperature [°C], 1 where the joint moved enough for a fit, and I_total [A]");
  auto* link_ceiling = sub->add_option("--link-ceiling", o->link_ceiling,
                  "Evaluation only: also name each detected contact's link from the simulator's TRUE joint impulse, exact "
                  "and with white noise at the sd the observer's estimate had on it: by the monitor's choice, by it told a "
                  "contact generator's point cube of this half extent [m] around the link's centre of mass (0.04: "
                  "scripts/make_validation_collisions.py), and by the Bayes choice for that generator's distribution "
                  "(every joint read / resting joints hidden by friction): what the joint torques carry. Adds "
                  "\"link_reference\" to --json")
      ->check(CLI::Range(1e-3, 1.0));
  sub->add_flag("--sweep-collisions", o->sweep,
                "Instead of scenario files: collisions of decreasing magnitude on --links, each monitored with the static "
                "and the dynamic threshold; prints the smallest contact detected on every link (Cao: 10 vs 5 N·m)");
  auto* links = sub->add_option("--links", o->sweep_options.links, "With --sweep-collisions: links to hit (1-based)")
                    ->delimiter(',')
                    ->capture_default_str();
  auto* magnitudes = sub->add_option("--magnitudes", o->sweep_options.magnitudes, "With --sweep-collisions: peak joint-equivalent torques [N·m]")
                         ->delimiter(',')
                         ->capture_default_str();
  auto* sweep_seed = sub->add_option("--sweep-seed", o->sweep_options.seed, "With --sweep-collisions: first noise seed (one per run)")->capture_default_str();
  auto* max_delay = sub->add_option("--max-delay", o->sweep_options.max_delay,
                                    "With --sweep-collisions: an alert later than this after the contact [s] does not count")
                        ->capture_default_str();
  sub->callback([=] {
    twinwatch::cli::refuse_unless({robot, all_programs, signal}, o->twin.empty(),
                                  "to the twin trained here; a --twin file has its own robot and thresholds (re-learn them with "
                                  "'twinwatch thresholds')");
    twinwatch::cli::refuse_unless({links, magnitudes, sweep_seed, max_delay}, o->sweep, "with --sweep-collisions");
    twinwatch::cli::refuse_unless({static_threshold, max_duration, filter, trend_csv, link_ceiling}, !o->sweep,
                                  "to scenario files, not to --sweep-collisions (it trains the default reference and monitors "
                                  "each contact with the static and the dynamic threshold)");
    twinwatch::cli::set_exit_code(run_evaluate(*o));
  });
}};

twinwatch::cli::VerbRegistrar reg_report{"report", 43, [](CLI::App& app) {
  auto o = std::make_shared<ReportOptions>();
  auto* sub = app.add_subcommand("report", "Write a self-contained HTML report: currents, residuals, thresholds, alerts, tables");
  sub->add_option("--twin", o->twin, "Twin file")->required()->check(CLI::ExistingFile);
  sub->add_option("RECORDING", o->recordings,
                  "Recording CSV; several are read as one stream in the order given, as 'monitor' reads them (the parts 'record "
                  "--split-every' writes: report --twin twin.json shift.0*.csv), into one page")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("-o,--output", o->output, "HTML file")->capture_default_str();
  sub->add_option("--program", o->program, "Threshold set of this program (as 'monitor --program'; default: the default set)")->check(cli::kProgramNameGiven);
  sub->add_option("--labels", o->labels, "Ground-truth labels to shade (evaluation only)");
  sub->add_option("--payload-mass", o->payload_mass, "Payload the program declares [kg] (default: the twin file's 'payload')")->check(twinwatch::cli::nonnegative_number());
  sub->add_option("--payload-com", o->payload_com, "Payload COM in the flange frame [m] (3 numbers; with --payload-mass)")->expected(3)->allow_extra_args(false);
  sub->add_option("--part-com", o->part_com, std::string(cli::kPartComHelp) + ", as 'monitor --part-com'")->expected(3)->allow_extra_args(false);
  sub->add_option("--column-map", o->column_map, cli::kColumnMapHelp);
  sub->add_flag("--keep-payload", o->keep_payload,
                "Keep the payload the twin starts with for the whole run, as 'monitor --keep-payload': no diagnosed change is "
                "followed and no declared payload taken (default: the twin follows both, as 'monitor' does)");
  sub->add_option("--sensitivity", o->sensitivity, std::string(cli::kSensitivityHelp) + ", as 'monitor --sensitivity'")
      ->delimiter(',')
      ->allow_extra_args(false);
  sub->add_option("--raise-after", o->raise_after, cli::kRaiseAfterHelp)->check(twinwatch::cli::whole_number(1, 1000));
  sub->add_option("--observer-raise-after", o->observer_raise_after, cli::kObserverRaiseAfterHelp)->check(twinwatch::cli::whole_number(1, 1000));
  sub->add_flag("--static", o->static_threshold, "Use the static threshold (UR3e §4.1) instead of the dynamic one, as 'monitor --static'");
  sub->add_option("--filter", o->filter, cli::kFilterHelp);
  sub->add_flag("-q,--quiet", o->quiet, "Print nothing on success");
  sub->callback([o] { twinwatch::cli::set_exit_code(run_report(*o)); });
}};

}  // namespace
