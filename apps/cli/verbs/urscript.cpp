// `twinwatch urscript SCENARIO.yaml -o PROGRAM.script`: the scenario's motion as a URScript program
// for a real UR e-Series arm (sim/robot_program.hpp), so that the recordings identify needs (an
// excitation from `excite`, the swing pair with and without a known payload) can be taken on the
// user's own arm while `twinwatch record --rtde` listens.
#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/sim/robot_program.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "verb_registry.hpp"

namespace {

using namespace twinwatch;

struct Options {
  std::string scenario, output, name, robot;
  double duration = 0.0;
  sim::ProgramOptions program;
  bool duration_given = false, json = false, quiet = false;
};

nlohmann::json vec(const VectorJ& v) {
  nlohmann::json a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}

std::string joints(const VectorJ& v, const VectorJ* limit) {
  std::string s;
  for (Eigen::Index j = 0; j < v.size(); ++j) {
    s += fmt::format("{}J{} {:.3f}", j ? "  " : "", j + 1, v[j]);
    if (limit && std::isfinite((*limit)[j])) s += fmt::format(" ({:.0f} %)", 100.0 * v[j] / (*limit)[j]);
  }
  return s;
}

int run(Options o) {
  require_output(o.output, {o.scenario});
  sim::Scenario s = sim::load_scenario(o.scenario);
  require_output(o.output, {model::robot_file(s.robot)});
  if (o.duration_given) sim::override_duration(s, o.duration, "--duration");
  const sim::ClosedForm form = sim::scenario_closed_form(s);
  // another arm than the scenario's (the swing pair is written for the UR3e): its file's limits are checked
  if (!o.robot.empty()) {
    const model::RobotModel other = model::load_robot(o.robot);
    if (other.n_dof() != form.n_dof())
      throw InvalidArgument(fmt::format("--robot {}: it has {} joints, the scenario's trajectory {}", o.robot, other.n_dof(), form.n_dof()));
    require_output(o.output, {model::robot_file(o.robot)});
    s.robot = o.robot;
  }
  const model::RobotModel robot = model::load_robot(s.robot);
  o.program.duration = s.options.duration;
  o.program.title = o.scenario;
  o.program.name = o.name.empty() ? s.name : o.name;
  o.program.payload = s.options.payload;
  // (the library names its fields; the user typed options)
  const auto motion_of = [&]() {
    try {
      return sim::ProgramMotion(form, o.program);
    } catch (const InvalidArgument& e) {
      const std::string m = twinwatch::cli::with_option_names(
          e.what(), {{"ramp", "--ramp"}, {"lookahead", "--lookahead"}, {"gain", "--gain"}, {"approach_speed", "--approach-speed"},
                     {"approach_acceleration", "--approach-acceleration"}, {"payload", "--declare-payload"},
                     {"duration", o.duration_given ? "--duration" : "the scenario's duration"}});
      throw InvalidArgument(fmt::format("{}: {}", o.scenario, m));
    }
  };
  const sim::ProgramMotion motion = motion_of();
  // the motion the arm makes, ramps included, within the robot's joint ranges and speed limits
  const std::string violation = sim::joint_limit_violation(motion, robot, motion.total(), 1.0 / motion.servo_period());
  if (!violation.empty())
    throw InvalidArgument(fmt::format("{}: the program's motion leaves the robot's limits: {}; no program written", o.scenario, violation));
  const sim::MotionPeaks peaks = sim::motion_peaks(motion);
  std::vector<std::string> header{fmt::format("Written by 'twinwatch urscript' from {} (trajectory {}).", o.scenario, s.trajectory_type)};
  if (!s.faults.empty())
    header.push_back(fmt::format("The scenario's {} fault(s) are the virtual robot's: the program has none.", s.faults.size()));
  write_text_file(o.output, sim::urscript_program(motion, o.program, robot, header));

  // (UR publishes no joint acceleration limits: a robot file that does is warned about beyond them)
  VectorJ qd_limit(robot.n_dof()), qdd_limit(robot.n_dof());
  std::vector<std::string> warnings;
  for (int j = 0; j < robot.n_dof(); ++j) {
    qd_limit[j] = robot.joint(j).limits.qd_max;
    qdd_limit[j] = robot.joint(j).limits.qdd_max;
    if (peaks.qdd[j] > qdd_limit[j])
      warnings.push_back(fmt::format("J{} accelerates at up to {:.2f} rad/s², beyond the robot file's limit of {:g} rad/s²", j + 1,
                                     peaks.qdd[j], qdd_limit[j]));
  }
  VectorJ q0, qd, qdd;
  motion.evaluate(0.0, q0, qd, qdd);
  const double record_for = std::ceil(motion.total() + 30.0);  // (and the approach, whose length depends on where the arm is)
  if (o.json) {
    nlohmann::json j;
    j["program"] = o.output;
    j["scenario"] = o.scenario;
    j["robot"] = robot.name();
    j["motion_s"] = motion.total();
    j["servo_period_s"] = motion.servo_period();
    j["ramp_in_s"] = motion.ramp_in();
    j["ramp_out_s"] = motion.ramp_out();
    j["start_pose"] = vec(q0);
    j["q_min"] = vec(peaks.q_min);
    j["q_max"] = vec(peaks.q_max);
    j["peak_qd"] = vec(peaks.qd);
    j["peak_qdd"] = vec(peaks.qdd);
    j["payload_declared"] = o.program.declare_payload;
    j["faults_left_out"] = s.faults.size();
    j["warnings"] = warnings;
    j["units"] = {{"motion_s", "s"}, {"start_pose", "rad"}, {"peak_qd", "rad/s"}, {"peak_qdd", "rad/s^2"}};
    fmt::print("{}\n", j.dump(2));
  } else if (!o.quiet) {
    fmt::print("{} -> {}: URScript for a {} (e-Series), {:.1f} s of motion, servoj every {:g} ms\n", s.name, o.output, robot.name(),
               motion.total(), 1e3 * motion.servo_period());
    if (motion.ramp_in() > 0 || motion.ramp_out() > 0)
      fmt::print("  the target's clock rises over {:.1f} s and falls over {:.1f} s: the arm starts and ends at rest\n", motion.ramp_in(),
                 motion.ramp_out());
    else
      fmt::print("  the target starts and ends at rest: run as the scenario runs it\n");
    fmt::print("  start pose [rad]           {}\n", joints(q0, nullptr));
    fmt::print("  peak speed [rad/s]         {}\n", joints(peaks.qd, &qd_limit));
    fmt::print("  peak acceleration [rad/s²] {}\n", joints(peaks.qdd, &qdd_limit));
    fmt::print("  payload: {}\n", o.program.declare_payload
                                      ? fmt::format("declared with set_payload({:g} kg, [{:g}, {:g}, {:g}] m)", s.options.payload.mass,
                                                    s.options.payload.com.x(), s.options.payload.com.y(), s.options.payload.com.z())
                                      : std::string("not changed (the installation's payload is used; --declare-payload declares the scenario's)"));
    if (!s.faults.empty()) fmt::print("  note: the scenario's {} fault(s) are the virtual robot's; the program has none\n", s.faults.size());
    fmt::print("  record it: start 'twinwatch record --rtde ROBOT_IP --frequency 500 --duration {:.0f} -o {}.csv', then run the program\n",
               record_for, s.name);
  }
  for (const std::string& w : warnings) fmt::print(stderr, "WARNING: {}\n", w);
  return 0;
}

twinwatch::cli::VerbRegistrar reg{"urscript", 27, [](CLI::App& app) {
  auto o = std::make_shared<Options>();
  auto* sub = app.add_subcommand("urscript", "Write a scenario's motion as a URScript program for a real UR e-Series arm");
  sub->footer(twinwatch::cli::with_exit_status(
      "The program moves the arm to the trajectory's start pose (movej), then commands the trajectory with servoj every 2 ms,\n"
      "evaluated on the controller, and stops. A target that starts or ends moving (a sine) runs on a clock that rises\n"
      "and falls over --ramp seconds, so the arm starts and ends at rest. The motion is checked against the robot\n"
      "file's joint ranges and speed limits before anything is written. Send it to the controller's port 30002 or load\n"
      "it in a Script node (with --call), and record it meanwhile with 'twinwatch record --rtde'. Faults in the scenario are the\n"
      "virtual robot's and are left out. Exports fourier, fourier_series, sine and chirp trajectories.\n\n"
      "Building a twin of your own arm (docs/rtde.md, \"A twin of your own arm\"):\n"
      "  twinwatch excite ur5e -o exc.yaml --tool-point 0 0 0.15 && twinwatch urscript exc.yaml -o exc.script\n"
      "  twinwatch urscript scenarios/ur3e/train/swing_train.yaml --robot ur5e -o swing.script   # then again with the test weight\n"
      "  twinwatch identify exc.csv swing.csv swing_weight.csv --known-payload swing_weight.csv=M,X,Y,Z -o twin.json"));
  sub->add_option("SCENARIO", o->scenario, "Scenario YAML whose trajectory the program runs (its robot's limits are checked)")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("-o,--output", o->output, "URScript program to write (.script)")->required();
  auto* duration = sub->add_option("--duration", o->duration, "Run the trajectory this long [s] (default: the scenario's duration)")
                       ->check(twinwatch::cli::positive_number());
  sub->add_option("--ramp", o->program.ramp, "Seconds over which the clock rises and falls where the target moves at its start or end")
      ->capture_default_str()
      ->check(twinwatch::cli::nonnegative_number());
  sub->add_option("--lookahead", o->program.lookahead, "servoj lookahead_time [s], 0.03-0.2")->capture_default_str();
  sub->add_option("--gain", o->program.gain, "servoj gain, 100-2000")->capture_default_str();
  sub->add_option("--approach-speed", o->program.approach_speed, "movej speed to the start pose [rad/s]")
      ->capture_default_str()
      ->check(twinwatch::cli::positive_number());
  sub->add_option("--approach-acceleration", o->program.approach_acceleration, "movej acceleration to the start pose [rad/s²]")
      ->capture_default_str()
      ->check(twinwatch::cli::positive_number());
  sub->add_flag("--declare-payload", o->program.declare_payload,
                "Declare the scenario's payload with set_payload before moving (else the installation's payload is kept)");
  sub->add_flag("--call", o->program.call,
                "End the file with the call NAME() after the def, as a Polyscope Script node (file) needs (port 30002 takes the def alone)");
  sub->add_option("--robot", o->robot,
                  "Check and write the motion for this robot (name or file) instead of the scenario's, e.g. the UR3e swing pair on a ur5e");
  sub->add_option("--name", o->name, "The program's name (default: the scenario's name, as twinwatch_NAME)");
  sub->add_flag("--json", o->json, "Print the summary as one JSON object");
  sub->add_flag("-q,--quiet", o->quiet, "Print nothing on success (warnings still go to stderr)");
  sub->callback([o, duration] {
    o->duration_given = duration->count() > 0;
    twinwatch::cli::set_exit_code(run(*o));
  });
}};

}  // namespace
