// `twinwatch identify REC.csv... -o twin.json` and `twinwatch validate --twin twin.json REC.csv`.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <system_error>
#include <limits>
#include <unistd.h>

#include <cmath>
#include <optional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"
#include "twinwatch/device/recording.hpp"
#include "twinwatch/ident/learned_ident.hpp"
#include "twinwatch/ident/controller_torque.hpp"
#include "twinwatch/ident/physics_ident.hpp"
#include "twinwatch/ident/sequential_ident.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/monitor/declaration.hpp"
#include "twinwatch/monitor/monitor.hpp"
#include "twinwatch/signal/metrics.hpp"
#include "recordings.hpp"
#include "verb_registry.hpp"

namespace {

using namespace twinwatch;

// "rec.csv=0.5" or "rec.csv=0.5,0,0,0.04": the payload a recording was made with
struct PayloadArg {
  std::string file;
  model::RigidBodyInertia payload;
};

PayloadArg parse_payload(const std::string& s, const model::RobotModel& robot) {
  const auto eq = s.rfind('=');
  if (eq == std::string::npos)
    throw InvalidArgument(fmt::format("--known-payload '{}': expected FILE=MASS[,CX,CY,CZ]", s));
  PayloadArg a;
  a.file = s.substr(0, eq);
  std::stringstream ss(s.substr(eq + 1));
  std::vector<double> v;
  std::string tok;
  while (std::getline(ss, tok, ',')) {
    // the whole cell is the number (std::stod took "0.5kg" as 0.5 and "4cm" as 4 m)
    double x = 0.0;
    const char* b = tok.data();
    const char* e = tok.data() + tok.size();
    while (b < e && std::isspace(static_cast<unsigned char>(*b))) ++b;
    while (e > b && std::isspace(static_cast<unsigned char>(e[-1]))) --e;
    const auto r = std::from_chars(b, e, x);
    if (b == e || r.ec != std::errc() || r.ptr != e || !std::isfinite(x))
      throw InvalidArgument(fmt::format("--known-payload '{}': '{}' is not a number (mass in kg, centre of mass in m, plain numbers "
                                        "without units)",
                                        s, tok));
    v.push_back(x);
  }
  if (v.size() != 1 && v.size() != 4)
    throw InvalidArgument(fmt::format("--known-payload '{}': expected 1 or 4 numbers (mass [kg], COM [m] in the flange frame), got {}", s, v.size()));
  a.payload.mass = v[0];
  if (v.size() == 4) a.payload.com = Eigen::Vector3d(v[1], v[2], v[3]);
  a.payload.validate("--known-payload");
  // a centre of mass metres from the flange (most likely mm), as the monitor refuses a declared one
  if (a.payload.com.norm() > model::kPayloadComMax)
    throw InvalidArgument(fmt::format("--known-payload '{}': expected a centre of mass within {:g} m of the flange, got ({:g}, {:g}, {:g}) "
                                      "m, {:.3g} m away (in mm? give metres)",
                                      s, model::kPayloadComMax, a.payload.com.x(), a.payload.com.y(), a.payload.com.z(),
                                      a.payload.com.norm()));
  // a mass beyond what the arm may carry is a typo (5 for 0.5 kg): it would set every drive gain wrong
  if (a.payload.mass > robot.payload_limit())
    throw InvalidArgument(fmt::format("--known-payload '{}': expected a mass of at most {:g} kg ({}), got {:g} kg", s,
                                      robot.payload_limit(), robot.payload_limit_text(), a.payload.mass));
  return a;
}

struct IdentifyOptions {
  std::vector<std::string> recordings, payloads, column_maps;
  std::string output, robot = "ur3e", method = "physics";
  std::string signal = "current";  // current | joint_torque: what the twin predicts and the monitor compares
  double acceleration_window = 0.0;  // [s] half window of the velocity smoothing (0: 3 samples)
  double reversal_screen = 0.0;
  bool no_low_speed_friction = false;
  bool no_target_direction = false;
  double direction_blend = ident::IdentOptions{}.direction_blend;
  double velocity_lag = std::numeric_limits<double>::quiet_NaN();  // NaN: measured on the recordings
  int decimate = 1;
  std::string efficiency_fit = "joint";
  int efficiency_passes = 2;
  bool quiet = false, progress = false;
  bool robot_given = false;  // (--robot on the command line; else the default, which the recordings are checked against)
  // --method sequential (Cao): the recordings of the gravity and friction steps, the library
  std::vector<std::string> quasi_static, sine;
  std::vector<int> lasso_joints{2, 3};
  double prune = 1e-3;
  bool lasso_1se = false;
  // learned methods (mlp, hybrid); unset: the method's defaults
  std::vector<int> hidden;
  std::optional<double> l2;
  std::optional<std::uint64_t> seed;
  std::optional<int> max_evaluations;
  std::string inputs;
};

// --efficiency-fit
ident::EfficiencyFit efficiency_fit_of(const std::string& v) {
  if (v == "joint") return ident::EfficiencyFit::Joint;
  if (v == "alternating") return ident::EfficiencyFit::Alternating;
  throw InvalidArgument(fmt::format("--efficiency-fit {}: expected joint or alternating", v));
}

// options of the learned methods: the method's defaults, then what the command line sets
ident::LearnedIdentOptions learned_options(const IdentifyOptions& o) {
  ident::LearnedIdentOptions lo = ident::LearnedIdentOptions::defaults(o.method);
  if (!o.hidden.empty()) lo.mlp.hidden = o.hidden;
  if (o.l2) lo.mlp.l2 = *o.l2;
  if (o.seed) lo.mlp.seed = *o.seed;
  if (o.max_evaluations) lo.mlp.max_evaluations = *o.max_evaluations;
  if (!o.inputs.empty()) lo.inputs = ident::LearnedInputs::parse(o.inputs);
  lo.physics.reversal_screen = o.reversal_screen;
  lo.physics.decimate = o.decimate;
  lo.physics.efficiency_fit = efficiency_fit_of(o.efficiency_fit);
  lo.physics.direction_blend = o.direction_blend;
  lo.physics.velocity_lag = o.velocity_lag;
  lo.physics.low_speed_friction = !o.no_low_speed_friction;
  lo.physics.target_direction = !o.no_target_direction;
  lo.physics.efficiency_passes = o.efficiency_passes;
  lo.physics.joint_torque = o.signal == "joint_torque";
  lo.physics.acceleration_window = o.acceleration_window;
  lo.decimate = std::max(lo.decimate, o.decimate);
  lo.validate();
  return lo;
}

int run_identify_sequential(const IdentifyOptions& o);

// one --known-payload per recording: of two, one would win silently
void require_one_payload_each(const std::vector<PayloadArg>& pay) {
  for (size_t a = 0; a < pay.size(); ++a)
    for (size_t b = a + 1; b < pay.size(); ++b)
      if (same_file(pay[a].file, pay[b].file))
        throw InvalidArgument(fmt::format("--known-payload names '{}' twice ({} kg and {} kg); give one payload per recording",
                                          pay[b].file, pay[a].payload.mass, pay[b].payload.mass));
}

// A recording that carries the payload its controller declares (RTDE payload / payload_cog, a
// recording's payload columns) is not taken as a known payload: a part declared and not carried (or
// carried undeclared) would set the drive gains wrong, where a --known-payload is the user's word.
// The declaration is said, with the option that takes it, and where the two differ.
void say_declared_payloads(const std::vector<ident::TrainingRun>& runs, const std::vector<PayloadArg>& given, bool quiet) {
  if (quiet) return;
  const auto what = [](double m, const double* c) {
    return m > 0.0 ? fmt::format("{} kg at ({}, {}, {}) m", m, c[0], c[1], c[2]) : std::string("no payload");
  };
  for (const auto& t : runs) {
    const device::Recording& r = *t.recording;
    if (!(r.present & kFieldPayload) || r.samples.empty()) continue;
    const RobotSample& a = r.samples.front();
    const RobotSample* other = nullptr;  // the first sample that declares something else
    for (const auto& x : r.samples)
      if (x.payload != a.payload || !std::equal(a.payload_cog, a.payload_cog + 3, x.payload_cog)) {
        other = &x;
        break;
      }
    bool told = false;
    for (const auto& p : given) told |= same_file(p.file, r.path);
    if (other != nullptr) {
      fmt::print(stderr, "note: {}: the payload the controller declares changes within it ({} from the start, {} from {:.3f} s); "
                         "identification takes {}\n",
                 r.path, what(a.payload, a.payload_cog), what(other->payload, other->payload_cog), other->timestamp,
                 told ? fmt::format("the --known-payload, {} kg, for all of it", t.payload.mass)
                      : std::string("no payload from it (cut it where the declaration changes, and give each part its --known-payload)"));
    } else if (told) {
      const Eigen::Vector3d cog(a.payload_cog[0], a.payload_cog[1], a.payload_cog[2]);
      if (a.payload != t.payload.mass || (a.payload > 0.0 && (cog - t.payload.com).norm() > 1e-9))
        fmt::print(stderr, "note: {}: the controller declares {}; --known-payload says {}, which is taken\n", r.path,
                   what(a.payload, a.payload_cog), what(t.payload.mass, t.payload.com.data()));
    } else if (a.payload > 0.0) {
      fmt::print(stderr, "note: {}: the controller declares {} throughout; it is not taken as a known payload. If the arm carried "
                         "it, give --known-payload {}={},{},{},{}\n",
                 r.path, what(a.payload, a.payload_cog), r.path, a.payload, a.payload_cog[0], a.payload_cog[1], a.payload_cog[2]);
    }
  }
}

// The recordings' controller torque (target_moment) against the robot's model and every built-in
// arm's of the same joint count (ident::ArmCheck), each recording on its own (a UR5e's
// among UR3e recordings must not hide in a pooled fit that no arm explains): a recording of another
// arm is refused when --robot was the default, and said when it was given (a description file of
// the user's own may be right where the built-in ones are not); a recording no arm reproduces well
// (an undeclared payload, another controller's torque) is said too.
void check_robot_against_controller(const IdentifyOptions& o, const model::RobotModel& robot,
                                    const std::vector<const device::Recording*>& recs) {
  size_t checked = 0;
  double worst = 0.0;
  for (const device::Recording* r : recs) {
    ident::ArmCheck check(robot, std::max<size_t>(1, r->samples.size() / 20000));
    for (const RobotSample& s : r->samples) check.add(s);
    const ident::ArmVerdict v = check.verdict();
    if (v.own.samples == 0) continue;
    ++checked;
    worst = std::max(worst, v.own.relative_rms);
    if (v.other_arm()) {
      const double j2 = robot.n_dof() >= 2 ? v.own.rms[1] : v.own.rms[0];
      const std::string what = fmt::format(
          "{} is not a recording of a {}: the controller's own torque (target_moment) along its targets is reproduced by the {}'s model "
          "(relative rms {:.2f}) and not by the {}'s ({:.2f}; J2 off by {:.1f} N·m rms)",
          r->path, robot.name(), v.better, v.theirs.relative_rms, robot.name(), v.own.relative_rms, j2);
      if (!o.robot_given)
        throw InvalidArgument(fmt::format("{}. Give --robot {} (or --robot {} to identify it as a {} all the same)", what, v.better,
                                          robot.name(), robot.name()));
      fmt::print(stderr, "WARNING: {}; identified as the {} you gave, as asked\n", what, robot.name());
    } else {
      cli::warn_if_another_arm(r->path, robot, v, "identify");  // (a poor fit: the same warning as the other verbs')
    }
  }
  if (o.robot_given || o.quiet) return;
  if (checked == 0)
    fmt::print(stderr, "note: --robot not given: identified as a {} (the default); the recordings carry no usable target_moment (none, or only zeros) to tell "
                       "which arm they are from. Give --robot for another arm (twinwatch model list)\n",
               robot.name());
  else
    fmt::print(stderr, "note: --robot not given: identified as a {} (the default), whose model reproduces the controller's torque to "
                       "{:.2f} relative rms at worst over {} recording(s)\n",
               robot.name(), worst, checked);
}

int run_identify(const IdentifyOptions& o) {
  // before the fit: a bad output path found after minutes of fitting costs the fit
  cli::require_distinct(o.recordings, "RECORDINGS");
  const bool torque = o.signal == "joint_torque";
  if (torque && (o.method == "sequential" || o.method == "mlp"))
    throw InvalidArgument(fmt::format("--signal joint_torque takes --method physics or hybrid, got {}: the {} method predicts the motor currents",
                                      o.method, o.method));
  if (o.method == "sequential") return run_identify_sequential(o);
  const cli::ColumnMaps maps(o.column_maps, o.recordings, torque);
  {
    std::vector<std::string> inputs = o.recordings;
    inputs.insert(inputs.end(), maps.files().begin(), maps.files().end());
    inputs.push_back(model::robot_file(o.robot));  // (a description file; empty for a built-in name)
    require_output(o.output, inputs);
  }
  const bool learned = o.method == "mlp" || o.method == "hybrid";
  const ident::LearnedIdentOptions lo = learned ? learned_options(o) : ident::LearnedIdentOptions{};
  cli::check_held_size(o.recordings, "identify");
  std::vector<device::Recording> recs;
  for (const auto& f : o.recordings) {
    recs.push_back(device::read_recording(f, maps.of(f)));
    device::require_fields(recs.back(), kFieldActualQd | kFieldActualCurrent, fmt::format("identify --method {}", o.method));
  }
  recs = cli::driven_only(std::move(recs), o.quiet);
  const model::RobotModel robot = model::load_robot(o.robot);
  for (const auto& r : recs) cli::check_training_recording(r, robot, "identify", torque);
  {
    std::vector<const device::Recording*> all;
    for (const auto& r : recs) all.push_back(&r);
    check_robot_against_controller(o, robot, all);
  }
  std::vector<ident::TrainingRun> runs;
  std::vector<PayloadArg> pay;
  for (const auto& p : o.payloads) pay.push_back(parse_payload(p, robot));
  require_one_payload_each(pay);
  // the same file under another name (./fig.csv, an absolute path) is the same recording
  for (const auto& r : recs) {
    ident::TrainingRun t{&r, {}};
    for (const auto& p : pay)
      if (same_file(p.file, r.path)) t.payload = p.payload;
    runs.push_back(t);
  }
  for (const auto& p : pay) {
    bool found = false;
    for (const auto& r : recs) found |= same_file(r.path, p.file);
    if (!found) throw InvalidArgument(fmt::format("--known-payload names '{}', which is not one of the recordings", p.file));
  }
  say_declared_payloads(runs, pay, o.quiet);
  ident::IdentOptions io;
  io.reversal_screen = o.reversal_screen;
  io.decimate = o.decimate;
  io.efficiency_fit = efficiency_fit_of(o.efficiency_fit);
  io.direction_blend = o.direction_blend;
  io.velocity_lag = o.velocity_lag;
  io.low_speed_friction = !o.no_low_speed_friction;
  io.target_direction = !o.no_target_direction;
  io.efficiency_passes = o.efficiency_passes;
  io.joint_torque = torque;
  io.acceleration_window = o.acceleration_window;
  ident::IdentReport report;
  const bool bar = !o.quiet && (o.progress || isatty(STDERR_FILENO));
  auto show = [&](double f) {
    if (bar) std::fprintf(stderr, "\r  identifying %3.0f %%%s", 100 * f, f >= 1.0 ? "\n" : "");
  };
  ident::LearnedIdentReport lr;
  ident::TwinModel twin = learned ? ident::identify_learned(o.robot, runs, o.method == "mlp" ? ident::LearnedRole::Current
                                                                                             : ident::LearnedRole::Residual,
                                                            lo, lr, show)
                                  : ident::identify_physics(o.robot, runs, io, report, show);
  if (learned) {
    report = lr.physics;
    report.rmse = lr.rmse;
    report.r2 = lr.r2;
  }
  // a window narrower than the default's samples differences a noisier velocity (audit of session 55:
  // 0.0005 s at 1 kHz, one sample, gave the Panda's J1 R² 0.50 and a false payload change)
  if (o.acceleration_window > 0.0 && !runs.empty() && !o.quiet) {
    const double period = runs.front().recording->median_period;
    if (const int h = twin.acceleration_half_width(period); h < ident::TwinModel::kAccelerationHalfWidth)
      fmt::print(stderr,
                 "note: --acceleration-window {:g} s is {} sample(s) at the recordings' {:.3g} ms period, narrower than the default {}: "
                 "the acceleration of a recording without target_qdd is then noisier (the default, or a wider window for a noisy "
                 "velocity: ~0.025 s for a Franka Panda's dq)\n",
                 o.acceleration_window, h, 1000.0 * period, ident::TwinModel::kAccelerationHalfWidth);
  }
  // thresholds of the monitor from the same healthy recordings (re-learn with 'twinwatch thresholds')
  std::vector<monitor::HealthyRun> healthy;
  for (const auto& r : runs) healthy.push_back({r.recording, r.payload});
  twin.monitor_json = monitor::learn_thresholds(twin, healthy).to_json();
  twin.save(o.output);
  if (!o.quiet) {
    fmt::print("twin '{}' ({} method) from {} recording(s){} -> {}\n", twin.robot_name(), twin.method, o.recordings.size(),
               recs.size() > o.recordings.size() ? fmt::format(" ({} driven stretches)", recs.size()) : "", o.output);
    // (a torque twin has no drive: no c_gen, back-driven share or gain to show)
    if (twin.measures_torque())
      fmt::print("{:<6} {:>9} {:>9} {:>8}\n", "joint", "samples", fmt::format("RMSE {}", twin.channel_unit()), "R²");
    else
      fmt::print("{:<6} {:>9} {:>9} {:>8} {:>10} {:>7} {:>12}\n", "joint", "samples", fmt::format("RMSE {}", twin.channel_unit()), "R²",
                 "c_gen", "gen %", "gain N·m/A");
    // a gain the recordings did not fix is shown as the monitor uses it (TwinModel::trusted_gain): the
    // median of the trusted ones (the fitted number itself can be anything, e.g. 3240 on a joint no
    // payload loads)
    for (int j = 0; j < twin.n_dof(); ++j) {
      const size_t J = static_cast<size_t>(j);
      const auto& m = twin.joints[J];
      // back-driven share of the samples; '*' marks a c_gen the data did not fit (kept or pinned)
      const bool fitted = J < report.c_gen_identified.size() && report.c_gen_identified[J];
      const double gen = J < report.generating_fraction.size() ? 100.0 * report.generating_fraction[J] : 0.0;
      if (twin.measures_torque()) {  // (no drive between the torque sensor and the link: nothing of it to show)
        fmt::print("J{:<5} {:>9} {:>9.4f} {:>8.4f}\n", j + 1, report.samples_used[J], m.rmse, m.r2);
        continue;
      }
      fmt::print("J{:<5} {:>9} {:>9.4f} {:>8.4f} {:>10} {:>7} {:>12}\n", j + 1, report.samples_used[J], m.rmse, m.r2,
                 fmt::format("{:.3f}{}", m.c_gen, fitted ? "" : "*"), std::isfinite(gen) ? fmt::format("{:.1f}", gen) : std::string("-"),
                 !twin.gains_known()        ? fmt::format("({:.3f})", m.gain)
                 : twin.gain_from_median(j) ? fmt::format("{:.3f}*", twin.trusted_gain(j))
                                            : fmt::format("{:.3f}", m.gain));
    }
    // the notes say why; the mark keeps a reader of the table alone from taking the number as measured
    // (no trusted gain: no median to show, the fitted ones are shown as they are)
    bool median_shown = false;
    for (int j = 0; j < twin.n_dof(); ++j) median_shown |= twin.gain_from_median(j);
    if (median_shown)
      fmt::print("* gain: not identified (no recording loads the joint enough) or beyond a harmonic drive's {:g}-{:g} N·m/A; shown is the "
                 "median of the identified ones, which the monitor uses\n",
                 ident::TwinModel::kTrustedGainMin, ident::TwinModel::kTrustedGainMax);
    // a joint fitted far worse than a constant would be: its recordings carry almost none of its
    // signal (audit of session 55: the Kinova's wrist roll J7 reads ±0.0004 N·m on its torque sensor
    // while it moves, and its fit had R² -33318, and -19557 on a held-out run). R² below -1: an error
    // beyond 1.4 times the channel's own spread (a UR3e's J5 current sits near 0 at worst)
    for (int j = 0; j < twin.n_dof(); ++j) {
      const auto& m = twin.joints[static_cast<size_t>(j)];
      if (std::isfinite(m.r2) && m.r2 < -1.0)
        fmt::print("note: J{}'s fit is far worse than a constant (R² {:.4g}, RMSE {:.3g} {}): the recordings carry almost none of its {} "
                   "(a joint its load hardly reaches, such as a wrist roll without a payload, or a dead channel); its parameters are not "
                   "determined, and validate and monitor mean little on J{}\n",
                   j + 1, m.r2, m.rmse, twin.channel_unit(), twin.channel_name(), j + 1);
    }
    const ident::VelocityLag& vl = report.velocity_lag;
    if (vl.given)
      fmt::print("velocity lag: {:.3f} ms, as given (--velocity-lag): the drive's direction is read on actual_qd + lag x qdd\n",
                 1000.0 * twin.velocity_lag);
    else if (vl.note.empty())
      fmt::print("velocity lag: actual_qd is {:.3f} ms (+-{:.3f}, as if the samples were independent) late against its positions ({:.2f} "
                 "of the {:.3g} ms period; {} joint samples): the drive's direction is read on the velocity carried forward by it\n",
                 1000.0 * vl.seconds, 1000.0 * vl.stderr_s, vl.period > 0.0 ? vl.seconds / vl.period : 0.0, 1000.0 * vl.period, vl.samples);
    if (!twin.target_direction.empty()) {
      const ident::TargetDirection& td = twin.target_direction;
      std::vector<std::string> lead, width, width_time;
      for (int j = 0; j < td.lead.size(); ++j) {
        lead.push_back(fmt::format("{:.2f}", 1000.0 * td.lead[j]));
        width.push_back(fmt::format("{:.2f}", 1000.0 * td.width[j]));
        width_time.push_back(fmt::format("{:.1f}", 1000.0 * td.width_time[j]));
      }
      if (report.target_direction.with_acceleration)
        fmt::print("drive direction near standstill: read on target_qd + lead x target_qdd where it agrees with actual_qd; lead [ms] {}; "
                   "tracking error near standstill sqrt(w^2 + (t x target_qdd)^2), w [mrad/s] {}, t [ms] {} ({} joint samples)\n",
                   fmt::join(lead, " "), fmt::join(width, " "), fmt::join(width_time, " "), report.target_direction.samples);
      else  // (a torque twin reads no target_qdd; nor does a log without it)
        fmt::print("{} near standstill: read on target_qd where it agrees with actual_qd (no target_qdd read: without a lead); "
                   "tracking error near standstill w [mrad/s] {} ({} joint samples)\n",
                   twin.measures_torque() ? "direction of motion" : "drive direction", fmt::join(width, " "), report.target_direction.samples);
    }
    for (const auto& note : report.notes) fmt::print("note: {}\n", note);
    if (learned) {
      const auto& mo = twin.learned->net;
      fmt::print("network: inputs {} ({}), hidden {}, l2 {:g}, seed {}; L-BFGS {} after {} evaluations (kept #{}), "
                 "loss (z units) fit {:.4g} held-out {:.4g}\n",
                 twin.learned->inputs.to_string(), mo.n_inputs(), fmt::join(mo.hidden(), "-"), mo.l2, mo.seed,
                 ident::to_string(lr.fit.stop), lr.fit.evaluations, lr.fit.best_evaluation, lr.fit.train_loss, lr.fit.validation_loss);
      fmt::print("held-out RMSE {}: {:.4f}\n", twin.channel_unit(), fmt::join(lr.validation_rmse, " "));
    }
  }
  return 0;
}

// Cao's sequential identification: gravity (--quasi-static), friction (--sine), Lasso (RECORDINGS)
int run_identify_sequential(const IdentifyOptions& o) {
  std::vector<std::string> all = o.recordings;
  for (const auto* v : {&o.quasi_static, &o.sine}) all.insert(all.end(), v->begin(), v->end());
  const cli::ColumnMaps maps(o.column_maps, all);
  {
    std::vector<std::string> inputs = all;
    inputs.insert(inputs.end(), maps.files().begin(), maps.files().end());
    inputs.push_back(model::robot_file(o.robot));
    require_output(o.output, inputs);
  }
  if (o.quasi_static.empty())
    throw InvalidArgument("--method sequential needs --quasi-static FILE: a recording of poses reached from both directions "
                          "(e.g. scenarios/ur3e/validation/quasi_static_train.yaml)");
  if (o.sine.empty())
    throw InvalidArgument("--method sequential needs --sine FILE: a recording of a sine with common turning points on every joint "
                          "(e.g. scenarios/ur3e/validation/sine_train.yaml)");
  auto read_all = [&](const std::vector<std::string>& files) {
    std::vector<device::Recording> v;
    for (const auto& f : files) v.push_back(device::read_recording(f, maps.of(f)));
    return cli::driven_only(std::move(v), o.quiet);
  };
  {
    std::vector<std::string> all = o.quasi_static;
    all.insert(all.end(), o.sine.begin(), o.sine.end());
    all.insert(all.end(), o.recordings.begin(), o.recordings.end());
    cli::check_held_size(all, "identify");
  }
  const auto qs = read_all(o.quasi_static), sn = read_all(o.sine), gen = read_all(o.recordings);
  const model::RobotModel robot = model::load_robot(o.robot);
  for (const auto* v : {&qs, &sn, &gen})
    for (const auto& r : *v) cli::check_training_recording(r, robot, "identify");
  {
    std::vector<const device::Recording*> all;
    for (const auto* v : {&qs, &sn, &gen})
      for (const auto& r : *v) all.push_back(&r);
    check_robot_against_controller(o, robot, all);
  }
  std::vector<const device::Recording*> qsp, snp;
  for (const auto& r : qs) qsp.push_back(&r);
  for (const auto& r : sn) snp.push_back(&r);
  std::vector<ident::TrainingRun> runs;
  std::vector<PayloadArg> pay;
  for (const auto& p : o.payloads) pay.push_back(parse_payload(p, robot));
  require_one_payload_each(pay);
  for (const auto& p : pay) {
    bool found = false;
    for (const auto& r : gen) found |= same_file(r.path, p.file);
    if (!found) throw InvalidArgument(fmt::format("--known-payload names '{}', which is not one of the general recordings", p.file));
  }
  for (const auto& r : gen) {
    ident::TrainingRun t{&r, {}};
    for (const auto& p : pay)
      if (same_file(p.file, r.path)) t.payload = p.payload;
    runs.push_back(t);
  }
  say_declared_payloads(runs, pay, o.quiet);
  ident::SequentialOptions so;
  so.library.config_joints.clear();
  for (int j : o.lasso_joints) {
    if (j < 1 || j > robot.n_dof())
      throw InvalidArgument(fmt::format("--lasso-joints {}: expected joints from 1 to {} ({})", j, robot.n_dof(), robot.name()));
    so.library.config_joints.push_back(j - 1);
  }
  so.prune_ratio = o.prune;
  so.use_1se = o.lasso_1se;
  so.decimate = std::max(o.decimate, 2);
  ident::SequentialReport report;
  const bool bar = !o.quiet && (o.progress || isatty(STDERR_FILENO));
  ident::TwinModel twin = ident::identify_sequential(o.robot, qsp, snp, runs, so, report, [&](double f) {
    if (bar) std::fprintf(stderr, "\r  identifying (sequential) %3.0f %%%s", 100 * f, f >= 1.0 ? "\n" : "");
  });
  std::vector<monitor::HealthyRun> healthy;
  for (const auto& r : runs) healthy.push_back({r.recording, r.payload});
  twin.monitor_json = monitor::learn_thresholds(twin, healthy).to_json();
  twin.save(o.output);
  if (!o.quiet) {
    fmt::print("twin '{}' (sequential method, Cao) from {} quasi-static, {} sine, {} general recording(s) -> {}\n", twin.robot_name(),
               qs.size(), sn.size(), gen.size(), o.output);
    fmt::print("gravity from {} paired poses; Lasso on {} candidates (A ⊗ B, m = 2) x {} samples, {}-fold CV\n", report.poses,
               report.candidates, report.lasso_samples, so.nfolds);
    fmt::print("{:<6} {:>9} {:>10} {:>8} {:>9} {:>9} {:>9} {:>8}\n", "joint", "grav A", "fric pairs", "nonzero", "CV RMSE", "RMSE A",
               "R²", "Fc A");
    for (int j = 0; j < twin.n_dof(); ++j) {
      const size_t J = static_cast<size_t>(j);
      fmt::print("J{:<5} {:>9.4f} {:>10} {:>8} {:>9.4f} {:>9.4f} {:>9.4f} {:>8.3f}\n", j + 1, report.gravity_rmse[J], report.friction_pairs[J],
                 report.nonzero[J], report.cv_rmse[J], report.rmse[J], report.r2[J], twin.sequential->joints[J].coulomb);
    }
    for (const auto& note : report.notes) fmt::print("note: {}\n", note);
  }
  return 0;
}

constexpr size_t kMinValidateSamples = 10;

std::string payload_words(const model::RigidBodyInertia& p) {
  return p.mass > 0.0 ? fmt::format("{:.2f} kg at ({:.3f}, {:.3f}, {:.3f}) m", p.mass, p.com.x(), p.com.y(), p.com.z()) : "no payload";
}

// what validate predicts with, where the recording declares a payload (RTDE payload / payload_cog):
// each declaration the twin takes, as the monitor does, or, with --keep-payload, none; and the first
// declaration the twin cannot take (`refused`, "" if none), with the monitor's reason
void say_validated_payload(std::uint32_t present, const std::string& path, const model::RigidBodyInertia& given,
                           const monitor::PayloadTimeline& payload, bool keep, const std::string& refused) {
  if (!(present & kFieldPayload)) return;
  if (keep) {
    fmt::print(stderr, "note: {} declares the payload it carries; --keep-payload: validated with {} throughout\n", path,
               payload_words(given));
    return;
  }
  std::string taken = payload_words(payload.step_payload(0)) + " from the start";
  for (size_t i = 1; i < payload.steps(); ++i)
    taken += fmt::format(", {} from {:.3f} s", payload_words(payload.step_payload(i)), payload.step_time(i));
  fmt::print(stderr,
             "note: {}: validated with the payload it declares, as the monitor predicts ({}; --keep-payload keeps {} throughout); the "
             "monitor also follows a payload change it diagnoses, which validate does not\n",
             path, taken, payload_words(given));
  if (!refused.empty()) fmt::print(stderr, "note: {}: {}\n", path, refused);
}

struct ValidateOptions {
  std::string twin, recording, column_map, predictions;
  double payload_mass = std::numeric_limits<double>::quiet_NaN();  // not given: the twin file's payload
  std::vector<double> payload_com;
  bool json = false, keep_payload = false;
};

int run_validate(const ValidateOptions& o) {
  ident::TwinModel twin = cli::load_twin(o.twin);
  const auto map = cli::load_column_map(o.column_map, twin);
  if (!o.predictions.empty()) require_output(o.predictions, {o.recording, o.twin, o.column_map});
  // The recording is read twice, row by row, and never held, as `monitor` and `report` read one:
  // first to check every row, its units, the timing of its steps and the payloads it declares, then
  // to predict it (the accelerations' smoothing looks a few samples ahead: ident::JointAccelerationStream),
  // the metrics summed as they come and the predictions written as they come. Held whole, an hour at
  // 500 Hz took 1.7 GB (docs/validation.md, "A report of a long recording").
  // the payload: the one given (else the twin's), and, as the monitor predicts (--keep-payload
  // aside), each payload the recording declares from its sample on (monitor::PayloadTimeline)
  const model::RigidBodyInertia given = cli::payload_for(twin, o.twin, o.payload_mass, o.payload_com);
  twin.set_payload(given);
  monitor::PayloadTimeline payload(twin, given, !o.keep_payload);
  size_t rows = 0, driven = 0;
  std::string refused;  // the first declaration the twin cannot take, and why
  const device::RecordingScan scan =
      cli::scan_recording(o.recording, map ? &*map : nullptr, twin.robot(), "validate", "validate", [&](const RobotSample& s) {
    payload.see(rows++, s);
    driven += s.driven() ? 1 : 0;
    if (!refused.empty() || !s.has(kFieldPayload)) return;
    const std::string why = monitor::declaration_readable(s) ? monitor::declaration_refusal(twin, s) : "not a finite mass and centre of mass";
    if (!why.empty()) refused = fmt::format("the declaration at {:.3f} s ({:g} kg) is not taken: {}", s.timestamp, s.payload, why);
  });
  payload.finish(rows, scan.timing.median_period > 0 ? scan.timing.median_period : monitor::MonitorConfig{}.nominal_period);
  // R² and NRMSE need a spread of measured currents: on fewer samples they would print 0 as numbers
  if (rows < kMinValidateSamples)
    throw InvalidArgument(fmt::format("validate: {} has {} sample(s), expected at least {}", o.recording, rows, kMinValidateSamples));
  // a sample in which the controller does not drive the arm (a stop, power off, brakes on) is no
  // driven motion to compare with the twin: left out of the metrics and the predictions file, said
  if (driven < kMinValidateSamples)
    throw InvalidArgument(fmt::format("validate: {} has {} sample(s) in which the controller drives the arm, expected at least {}",
                                      o.recording, driven, kMinValidateSamples));
  if (!o.json) say_validated_payload(scan.present, o.recording, given, payload, o.keep_payload, refused);
  if (driven < rows && !o.json)
    fmt::print(stderr, "note: {}: {} sample(s) in which the controller did not drive the arm (robot_mode not RUNNING or safety_mode not "
                       "NORMAL/REDUCED) are left out\n",
               o.recording, rows - driven);
  payload.start(twin);
  const int n = twin.n_dof();
  std::vector<signal::FitAccumulator> fit(static_cast<size_t>(n));
  std::vector<double> first_measured(static_cast<size_t>(n), NAN);  // (a channel that never changes is said with its value)
  // per sample: time, measured and predicted current of every joint (for plots), written checked: a
  // full disk names the file
  // (beside its target until complete: a recording found changed while it was read leaves no part)
  std::optional<ReplacingFile> predictions_file;
  std::ofstream* predictions = nullptr;
  fmt::memory_buffer line;
  if (!o.predictions.empty()) {
    predictions = &predictions_file.emplace(o.predictions).stream();
    auto w = std::back_inserter(line);
    fmt::format_to(w, "timestamp");
    // (a joint-torque twin's channel: actual_joint_torque_*, predicted_joint_torque_*)
    for (int j = 0; j < n; ++j) fmt::format_to(w, ",actual_{}_{}", twin.signal_name(), j);
    for (int j = 0; j < n; ++j) fmt::format_to(w, ",predicted_{}_{}", twin.signal_name(), j);
    fmt::format_to(w, "\n");
    predictions->write(line.data(), static_cast<std::streamsize>(line.size()));
  }
  VectorJ i;
  ident::FrictionMemory memory;
  size_t k = 0;
  const ident::JointAccelerationStream::Ready predict = [&](const RobotSample& s, const VectorJ& qdd) {
    payload.advance(k++, twin);
    twin.advance(memory, s, qdd);
    if (!s.driven()) return;
    twin.predict_current(s.q, s.qd, qdd, s.temperature, i, &memory);
    for (int j = 0; j < n; ++j) {
      const size_t J = static_cast<size_t>(j);
      fit[J].add(s.current[j], i[j]);
      if (std::isnan(first_measured[J])) first_measured[J] = s.current[j];
    }
    if (predictions == nullptr) return;
    line.clear();
    auto w = std::back_inserter(line);
    fmt::format_to(w, "{}", s.timestamp);
    for (int j = 0; j < n; ++j) fmt::format_to(w, ",{}", s.current[j]);
    for (int j = 0; j < n; ++j) fmt::format_to(w, ",{}", i[j]);
    fmt::format_to(w, "\n");
    predictions->write(line.data(), static_cast<std::streamsize>(line.size()));
  };
  ident::JointAccelerationStream accelerations(n, scan.present, twin.acceleration_half_width(scan.timing.median_period));
  device::RecordingReader again(o.recording, map ? &*map : nullptr);
  const long replayed = device::replay_rows(again, scan, [&](const RobotSample& s) { accelerations.push(s, predict); });
  accelerations.finish(predict);
  if (replayed < scan.rows)
    throw std::runtime_error(fmt::format("{}: {} of the {} rows checked were there to validate on (the file was cut or replaced while it "
                                         "was read): validate a copy",
                                         o.recording, replayed, scan.rows));
  if (predictions_file) predictions_file->commit();
  nlohmann::json out;
  out["recording"] = o.recording;
  out["twin"] = o.twin;
  if (driven < rows) out["samples_not_driven"] = rows - driven;
  // the payload predicted with, from each time on (the declared ones taken, as in the note)
  for (size_t i = 0; i < payload.steps(); ++i) {
    const model::RigidBodyInertia& p = payload.step_payload(i);
    out["payload"].push_back({{"from_s", payload.step_time(i)},
                              {"mass", p.mass},
                              {"com", {p.com.x(), p.com.y(), p.com.z()}}});
  }
  if (!o.json) {
    fmt::print("validation of {} on {} ({} samples), {} [{}] (UR3e Table 3 layout)\n", o.twin, o.recording, driven,
               twin.measures_torque() ? "joint torque sensors" : "current domain", twin.channel_unit());
    fmt::print("{:<8}", "metric");
    for (int j = 0; j < n; ++j) fmt::print(" {:>8}", fmt::format("J{}", j + 1));
    fmt::print("\n");
  }
  std::vector<signal::FitMetrics> ms;
  for (int j = 0; j < n; ++j) ms.push_back(fit[static_cast<size_t>(j)].metrics());
  // a measured channel that never changes (a dead or stuck sensor, a joint logged as a constant) has
  // no R² or NRMSE, and at 0 throughout no d_tau: null in JSON, n/a in the table, and said
  std::vector<char> constant(static_cast<size_t>(n)), zero(static_cast<size_t>(n));
  for (int j = 0; j < n; ++j) {
    const auto J = static_cast<size_t>(j);
    constant[J] = !(ms[J].range > 0.0);
    zero[J] = constant[J] && first_measured[J] == 0.0;
  }
  const auto value = [](bool defined, double v) { return defined ? nlohmann::json(v) : nlohmann::json(nullptr); };
  for (int j = 0; j < n; ++j) {
    const auto J = static_cast<size_t>(j);
    const signal::FitMetrics& m = ms[J];
    out["joints"].push_back({{"rmse", m.rmse}, {"mae", m.mae}, {"r2", value(!constant[J], m.r2)},
                             {"nrmse_pct", value(!constant[J], m.nrmse_pct)}, {"d_tau_pct", value(!zero[J], m.rel_err_pct)}});
    if (constant[J]) out["joints"].back()["measured_constant"] = first_measured[J];
  }
  const std::string unit = twin.channel_unit();
  out["signal"] = twin.signal_name();
  out["units"] = {{"rmse", unit}, {"mae", unit}, {"r2", "1"}, {"nrmse_pct", "% of the measured range"},
                  {"d_tau_pct", twin.measures_torque() ? "% (norm of the error / norm of the measured torque)"
                                                       : "% (norm of the error / norm of the measured current)"},
                  {"measured_constant", unit},
                  {"from_s", "s"}, {"mass", "kg"}, {"com", "m (flange frame)"}};
  if (o.json) {
    fmt::print("{}\n", out.dump());
    return 0;
  }
  auto row = [&](const char* name, auto get, const char* f, const std::vector<char>& undefined) {
    fmt::print("{:<8}", name);
    // a space before every cell: a large number (a twin far off) must not run into its neighbour
    for (size_t J = 0; J < ms.size(); ++J)
      fmt::print(" {:>8}", undefined[J] ? std::string("n/a") : fmt::format(fmt::runtime(f), get(ms[J])));
    fmt::print("\n");
  };
  const std::vector<char> none(ms.size(), 0);
  row("RMSE", [](const signal::FitMetrics& m) { return m.rmse; }, "{:.4f}", none);
  row("MAE", [](const signal::FitMetrics& m) { return m.mae; }, "{:.4f}", none);
  row("R²", [](const signal::FitMetrics& m) { return m.r2; }, "{:.4f}", constant);
  row("NRMSE%", [](const signal::FitMetrics& m) { return m.nrmse_pct; }, "{:.2f}", constant);
  row("d_tau%", [](const signal::FitMetrics& m) { return m.rel_err_pct; }, "{:.2f}", zero);
  for (int j = 0; j < n; ++j)
    if (constant[static_cast<size_t>(j)])
      fmt::print("note: J{}'s measured {} is {:g} {} in every sample: R² and NRMSE are undefined (n/a); a dead or stuck channel?\n",
                 j + 1, twin.channel_name(), first_measured[static_cast<size_t>(j)], twin.channel_unit());
  return 0;
}

twinwatch::cli::VerbRegistrar reg_identify{"identify", 30, [](CLI::App& app) {
  auto o = std::make_shared<IdentifyOptions>();
  auto* sub = app.add_subcommand("identify", "Build the reference model (twin file) from recordings of a healthy robot");
  sub->add_option("RECORDINGS", o->recordings, "Recording CSV files (RTDE column names)")->required()->check(CLI::ExistingFile);
  sub->add_option("-o,--output", o->output, "Twin file to write (JSON)")->required();
  auto* robot_option =
      sub->add_option("--robot", o->robot,
                      "Robot description (built-in name or .json/.urdf file; a file is stored in the twin by its absolute path). "
                      "Recordings with the controller's torque (target_moment) are checked against it: not given, another "
                      "built-in arm's recordings are refused")
      ->capture_default_str()
      ->transform([](std::string s) { return cli::robot_reference(s); });
  sub->add_option("--method", o->method,
                  "physics (rigid body + friction + drive, current domain); mlp (UR3e §3.5: a network on q and smoothed qd "
                  "predicts the currents; torque only through known gains); hybrid (physics + a network trained on its "
                  "current residual); sequential (Cao: gravity from --quasi-static, friction from --sine, Lasso over A ⊗ B on "
                  "RECORDINGS with 10-fold CV)")->capture_default_str();
  auto* hidden = sub->add_option("--hidden", o->hidden, "mlp/hybrid: units per hidden layer, one number per layer (default 15)");
  auto* l2 = sub->add_option("--l2", o->l2, "mlp/hybrid: L2 penalty on the weights, z-scored units (default mlp 1e-4, hybrid 1e-2)")
                 ->check(twinwatch::cli::nonnegative_number());
  auto* seed = sub->add_option("--seed", o->seed, "mlp/hybrid: seed of the initial weights; the same seed gives the same twin (default 1)");
  auto* max_evaluations = sub->add_option("--max-evaluations", o->max_evaluations, "mlp/hybrid: cap on L-BFGS loss evaluations (default 3000)")
                              ->check(twinwatch::cli::whole_number(1, 100000000));
  auto* inputs = sub->add_option("--inputs", o->inputs,
                  "mlp/hybrid: network features per joint joined by '+': q, qd, qdd, temperature, friction_shape "
                  "(mlp default q+qd, hybrid qd+friction_shape)");
  auto* quasi_static = sub->add_option("--quasi-static", o->quasi_static, "sequential: recording of poses reached from below and from above and held (Cao eq. 13-14); repeatable")
      ->expected(1)
      ->allow_extra_args(false)
      ->check(CLI::ExistingFile);
  auto* sine = sub->add_option("--sine", o->sine, "sequential: recording of a sine with the same frequency and phase on every joint (Cao eq. 15); repeatable")
      ->expected(1)
      ->allow_extra_args(false)
      ->check(CLI::ExistingFile);
  auto* lasso_joints = sub->add_option("--lasso-joints", o->lasso_joints, "sequential: joints (1-based) whose sin/cos up to 2q form B of the library")
      ->delimiter(',')
      ->capture_default_str();
  auto* lasso_1se = sub->add_flag("--lasso-1se", o->lasso_1se, "sequential: choose lambda_1se (sparser) instead of lambda_min");
  auto* prune = sub->add_option("--prune", o->prune, "sequential: drop Lasso terms with |p_k| sd(g_k) < PRUNE sd(y)")->capture_default_str();
  sub->add_option("--signal", o->signal,
                  "What the twin predicts and the monitor compares: current (the motor currents actual_current_* [A], through "
                  "identified drive gains) or joint_torque (joint torque sensors actual_joint_torque_* [N·m], as a Franka Panda or a "
                  "Kinova Gen3 logs them: no drive gain, the sensor's own scale). physics and hybrid methods")
      ->capture_default_str()
      ->check(CLI::IsMember({"current", "joint_torque"}));
  auto* acceleration_window = sub->add_option("--acceleration-window", o->acceleration_window,
                  "physics/mlp/hybrid: half window [s] of the velocity smoothing that recordings without target_qdd take their "
                  "joint acceleration from, kept in the twin: validate uses it, and the monitor and thresholds take the difference "
                  "of two means of as many velocities (default 0: 3 samples, 6 ms at 500 Hz, and the monitor's filtered difference). "
                  "A 1 kHz log of a noisy velocity (a Franka Panda's dq) wants ~0.025: differenced over 3 ms its noise biases the "
                  "inertia the fit finds, and widens the thresholds")
      ->capture_default_str()
      ->check(cli::number_in(0.0, ident::TwinModel::kAccelerationWindowMax, "s"));
  sub->add_option("--known-payload", o->payloads,
                  "FILE=MASS[,CX,CY,CZ]: the recording FILE was made with this payload (kg, m in the flange frame); "
                  "identifies the current-to-torque gains; repeat the option for several recordings")
      ->allow_extra_args(false);
  auto* efficiency_passes = sub->add_option("--efficiency-passes", o->efficiency_passes,
                  "physics/mlp/hybrid: alternations of the back-driven factor and the gains; a heavy known payload needs ~20 to settle "
                  "(scenarios/ur3e/train/swing_train*.yaml)")
      ->capture_default_str()
      ->check(twinwatch::cli::whole_number(0, 1000));
  auto* reversal_screen = sub->add_option("--reversal-screen", o->reversal_screen,
                                          "physics/mlp/hybrid: leave |qd| below this [rad/s] out of the fit (HESR §III-E)")
                              ->check(twinwatch::cli::nonnegative_number());
  auto* no_low_speed_friction = sub->add_flag("--no-low-speed-friction", o->no_low_speed_friction,
                "physics/mlp/hybrid: leave out the low-speed friction (pre-sliding memory and Stribeck rise; shapes chosen on the "
                "plain fit's residual, then the whole fit again with them, which takes about twice as long); the twin then has "
                "plain Coulomb sign(qd) friction");
  auto* direction_blend = sub->add_option("--direction-blend", o->direction_blend,
                  "physics/mlp/hybrid: width [rad/s] of the smooth switch between the motoring and the back-driven current "
                  "factor around qd = 0 (about the measured velocity's resolution; 0: hard switch)")
      ->capture_default_str()
      ->check(twinwatch::cli::nonnegative_number());
  auto* velocity_lag = sub->add_option("--velocity-lag", o->velocity_lag,
                  "physics/mlp/hybrid: how late actual_qd is against its sample's instant [s]; the drive's motoring/back-driven "
                  "switch is read on actual_qd + lag x qdd (default: measured on the recordings against the central difference "
                  "of actual_q; 0: actual_qd as it is, the twin of before)")
      ->check(CLI::Range(-ident::TwinModel::kVelocityLagMax, ident::TwinModel::kVelocityLagMax));
  auto* no_target_direction = sub->add_flag("--no-target-direction", o->no_target_direction,
                "physics/mlp/hybrid: read the drive's motoring/back-driven switch on actual_qd alone. Default: where the recordings "
                "stream target_qd, near standstill it is read on the target velocity (carried by its measured lead), which has no "
                "encoder counts: actual_qd is 0 for as long as a joint moves less than a count a period, 60 ms at a slow reversal");
  auto* efficiency_fit = sub->add_option("--efficiency-fit", o->efficiency_fit,
                  "physics/mlp/hybrid: how the back-driven current factor c_gen is fitted: 'joint' (with the rigid-body, friction and gain "
                  "parameters; recovers it; gains the known payload does not fix are flagged) or 'alternating' (the first version, "
                  "between passes; biased towards 1)")
      ->capture_default_str();
  sub->add_option("--decimate", o->decimate, "Use every k-th sample (the mlp/hybrid network uses at least every 5th)")->capture_default_str()->check(twinwatch::cli::whole_number(1, 1000000));
  sub->add_option("--column-map", o->column_maps,
                  "CSV map 'file_column,rtde_name[,scale]' for foreign logs (docs/recordings.md), or the name of one twinwatch ships. "
                  "MAP: every recording without one of its own; REC=MAP: that recording alone (repeat for each; REC is any name of the "
                  "file, --quasi-static and --sine recordings included; e.g. a log from another source among the robot's own)")->type_name("[REC=]MAP");
  sub->add_flag("-q,--quiet", o->quiet, "Print nothing on success");
  sub->add_flag("--progress", o->progress, "Show the progress bar even when stderr is not a terminal");
  sub->callback([=] {
    const std::string& m = o->method;
    if (m != "physics" && m != "sequential" && m != "mlp" && m != "hybrid")
      throw InvalidArgument(fmt::format("--method {}: expected physics, sequential, mlp or hybrid", m));
    twinwatch::cli::refuse_unless({hidden, l2, seed, max_evaluations, inputs}, m == "mlp" || m == "hybrid",
                                  fmt::format("to --method mlp or hybrid, not {}", m));
    twinwatch::cli::refuse_unless({quasi_static, sine, lasso_joints, lasso_1se, prune}, m == "sequential",
                                  fmt::format("to --method sequential, not {}", m));
    twinwatch::cli::refuse_unless({efficiency_passes, reversal_screen, no_low_speed_friction, direction_blend, velocity_lag,
                                   no_target_direction, efficiency_fit, acceleration_window},
                                  m != "sequential",
                                  "to --method physics, mlp or hybrid: the sequential method (Cao) fits gravity, friction and the "
                                  "rest its own way");
    // (a torque sensor has no drive to fit an efficiency of: refused before the recordings are read)
    twinwatch::cli::refuse_unless({efficiency_fit}, o->signal != "joint_torque" || o->efficiency_fit == "joint",
                                  "with --signal current: a joint torque sensor has no drive efficiency to fit (only 'joint', the default)");
    o->robot_given = robot_option->count() > 0;
    twinwatch::cli::set_exit_code(run_identify(*o));
  });
}};

twinwatch::cli::VerbRegistrar reg_validate{"validate", 31, [](CLI::App& app) {
  auto o = std::make_shared<ValidateOptions>();
  auto* sub = app.add_subcommand("validate", "Compare a twin's predicted currents (or joint torques, for a twin of torque sensors) with a recording (UR3e Table 3 metrics)");
  sub->add_option("--twin", o->twin, "Twin file from 'twinwatch identify'")->required()->check(CLI::ExistingFile);
  sub->add_option("RECORDING", o->recording, "Recording CSV")->required()->check(CLI::ExistingFile);
  sub->add_option("--payload-mass", o->payload_mass,
                  "Payload carried during the recording [kg] (default: the twin's). Where the recording declares the payload "
                  "(RTDE payload / payload_cog columns), each declaration is taken from its sample on, as 'monitor' does");
  sub->add_option("--payload-com", o->payload_com, "Payload centre of mass in the flange frame [m] (3 numbers)")->expected(3)->allow_extra_args(false);
  sub->add_flag("--keep-payload", o->keep_payload,
                "Predict with the payload given (--payload-mass, else the twin's) throughout, not with the ones the recording declares");
  sub->add_option("--column-map", o->column_map, "CSV map for foreign logs");
  sub->add_option("--predictions", o->predictions, "Also write time, measured and predicted current (joint torque, for a twin of torque sensors) per sample to this CSV");
  sub->add_flag("--json", o->json, "Print {\"joints\": [{\"rmse\", \"mae\", \"r2\", \"nrmse_pct\", \"d_tau_pct\"}, ...]}");
  sub->callback([o] { twinwatch::cli::set_exit_code(run_validate(*o)); });
}};

}  // namespace
