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

// the largest joint acceleration a program is written with when the robot file publishes no
// acceleration limit [rad/s²]: the approach movej's own bound (ProgramOptions::approach_acceleration).
// The designs and the swing pair stay below 6.
constexpr double kMaxProgramAcceleration = 40.0;

struct Options {
  std::string scenario, output, name, robot;
  double duration = 0.0;
  std::vector<double> tool;  // --tool-point, three numbers per point [m, flange frame]
  // the installation's safety limits (Installation > Safety > Robot Limits), checked when given, and the tool
  twinwatch::cli::SafetyLimitOptions safety;
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
  // another arm than the scenario's (the swing pair is written for the UR3e): the scenario is loaded
  // for it (its limits and rated payload checked), as simulate --robot does
  if (!o.robot.empty()) {
    const model::RobotModel other = model::load_robot(o.robot);
    if (other.n_dof() != 6)
      throw InvalidArgument(fmt::format("--robot {}: it has {} joints: URScript programs run on Universal Robots arms, of six", o.robot,
                                        other.n_dof()));
    require_output(o.output, {model::robot_file(o.robot)});
  }
  // (the program's own motion, slowed and ramped, is checked against the limits below, and a
  // motion too fast is answered with the slow-down it needs: a UR3e swing on a UR10e's slower base
  // was refused at the scenario's line, whatever --slow-down; session 57)
  sim::Scenario s = sim::load_scenario(o.scenario, o.robot, /*trajectory_limits=*/false);
  require_output(o.output, {model::robot_file(s.robot)});
  if (o.duration_given) sim::override_duration(s, o.duration, "--duration", /*trajectory_limits=*/false);
  const sim::ClosedForm form = sim::scenario_closed_form(s);
  const model::RobotModel robot = model::load_robot(s.robot);
  if (robot.n_dof() != 6)
    throw InvalidArgument(fmt::format("{}: the robot {} has {} joints: URScript programs run on Universal Robots arms, of six", o.scenario,
                                      robot.name(), robot.n_dof()));
  o.program.duration = s.options.duration;
  o.program.title = o.scenario;
  o.program.name = o.name.empty() ? s.name : o.name;
  const bool declare_given = o.program.declare_payload;  // (--set-target-payload implies it; messages name the one typed)
  if (o.program.target_payload) o.program.declare_payload = true;
  // what the flange carries: the tool and the scenario's payload (the momentum, the torque and a declared payload)
  const model::RigidBodyInertia carried = twinwatch::cli::carried_on_flange(o.safety, robot, s.options.payload);
  o.program.payload = carried;
  // (the library names its fields; the user typed options)
  const auto motion_of = [&]() {
    try {
      return sim::ProgramMotion(form, o.program);
    } catch (const InvalidArgument& e) {
      const std::string m = twinwatch::cli::with_option_names(
          e.what(), {{"ramp", "--ramp"}, {"slow_down", "--slow-down"}, {"lookahead", "--lookahead"}, {"gain", "--gain"}, {"approach_speed", "--approach-speed"},
                     {"approach_acceleration", "--approach-acceleration"}, {"max_approach", "--max-approach"},
                     {"payload", o.program.target_payload && !declare_given ? "--set-target-payload" : "--declare-payload"},
                     {"duration", o.duration_given ? "--duration" : "the scenario's duration"}});
      throw InvalidArgument(fmt::format("{}: {}", o.scenario, m));
    }
  };
  const sim::ProgramMotion motion = motion_of();
  // the first joint accelerating beyond kMaxProgramAcceleration where the robot file publishes no
  // acceleration limit (-1: none; a published one is joint_limit_violation's)
  const auto over_acceleration_cap = [&](const sim::MotionPeaks& p) {
    for (int j = 0; j < robot.n_dof(); ++j)
      if (!std::isfinite(robot.joint(j).limits.qdd_max) && p.qdd[j] > kMaxProgramAcceleration) return j;
    return -1;
  };
  // the joint limits a program with --slow-down K leaves (speeds, ranges, accelerations): a remedy
  // is checked on the program it suggests
  const auto violation_at = [&](double k) {
    sim::ProgramOptions p = o.program;
    p.slow_down = k;
    const sim::ProgramMotion m(form, p);
    const std::string v = sim::joint_limit_violation(m, robot, m.total(), 1.0 / m.servo_period());
    if (!v.empty()) return v;
    const int j = over_acceleration_cap(sim::motion_peaks(m));
    return j < 0 ? std::string() : fmt::format("J{} accelerates beyond {:g} rad/s²", j + 1, kMaxProgramAcceleration);
  };
  // the motion the arm makes, ramps included, within the robot's joint ranges and speed limits
  const std::string violation = sim::joint_limit_violation(motion, robot, motion.total(), 1.0 / motion.servo_period());
  if (!violation.empty())
    throw InvalidArgument(fmt::format("{}: the program's motion leaves the robot's limits: {}; no program written{}", o.scenario, violation,
                                      twinwatch::cli::slow_down_remedy(motion, robot, o.program.slow_down, kMaxProgramAcceleration, violation_at)));
  const sim::MotionPeaks peaks = sim::motion_peaks(motion);
  // the speeds and the momentum the installation's safety limits bound (the payload moves too, declared or not)
  const std::vector<Eigen::Vector3d> tool_points = twinwatch::cli::tool_points(o.tool);
  for (size_t k = 0; k < tool_points.size(); ++k)
    if (!tool_points[k].allFinite() || tool_points[k].norm() > 2.0)
      throw InvalidArgument(fmt::format("--tool-point (number {} of {}): expected a point within 2 m of the flange [m], got ({:g}, {:g}, {:g})",
                                        k + 1, tool_points.size(), tool_points[k].x(), tool_points[k].y(), tool_points[k].z()));
  const std::vector<twinwatch::cli::OperationalLimit> held = twinwatch::cli::operational_limits(o.safety);
  const sim::SafetyPeaks safety = sim::safety_peaks(motion, robot, tool_points, carried);
  const std::string tool_where =
      safety.tool_point < 0 ? std::string("the flange's centre")
                            : fmt::format("tool point {} ({:g}, {:g}, {:g}) m", safety.tool_point + 1, tool_points[safety.tool_point].x(),
                                          tool_points[safety.tool_point].y(), tool_points[safety.tool_point].z());
  struct Limit {
    const char* key;  // (--json, as excite's)
    const char* what;
    double peak, at;
    twinwatch::cli::OperationalLimit limit;
    const char* unit;
    std::string where;  // " (the point)" for the tool, else empty
    bool exceeded() const { return limit.given() && peak > limit.value(); }
  };
  const std::vector<Limit> limits{{"tool_speed", "tool speed", safety.tool_speed, safety.tool_t, held[0], "m/s", " (" + tool_where + ")"},
                                  {"elbow_speed", "elbow speed", safety.elbow_speed, safety.elbow_t, held[1], "m/s", ""},
                                  {"momentum", "momentum", safety.momentum, safety.momentum_t, held[2], "kg·m/s", ""}};
  // the same path K times slower divides every speed and the momentum by K: the factor that fits them all
  double fits = 1.0;
  std::string beyond;  // every limit the motion passes
  for (const Limit& l : limits)
    if (l.exceeded()) {
      fits = std::max(fits, l.peak / l.limit.value());
      beyond += fmt::format("{}its {} reaches {:.3f} {} at {:.2f} s{}, beyond {}", beyond.empty() ? "" : "; ", l.what, l.peak, l.unit, l.at,
                            l.where, l.limit.text(l.unit));
    }
  if (!beyond.empty()) {
    const double slower = std::ceil(o.program.slow_down * fits * 1.001 * 100.0) / 100.0;
    std::string remedy;
    if (slower <= 100.0) {
      sim::ProgramOptions p = o.program;
      p.slow_down = slower;
      remedy = fmt::format("--slow-down {:.2f} runs the same path within {} ({:.1f} s instead of {:.1f} s)", slower,
                           std::count_if(limits.begin(), limits.end(), [](const Limit& l) { return l.exceeded(); }) > 1 ? "them" : "it",
                           sim::ProgramMotion(form, p).total(), motion.total());
    } else {
      remedy = fmt::format("No --slow-down up to 100 fits it (it needs {:.3g})", slower);
    }
    throw InvalidArgument(fmt::format(
        "{}: the program exceeds the installation's limits: {}: the arm would be slowed or stopped mid-run; no program written. {}; or make the motion slower ({}), or "
        "run it where the installation allows more",
        o.scenario, beyond, remedy,
        s.trajectory_type == "fourier" ? "design the excitation again with a lower twinwatch excite --limit-fraction or --amplitude"
                                       : "lower the trajectory's amplitudes or frequencies"));
  }
  // what the drives can follow: the rigid body's torque within each joint's torque_max, and, where the
  // robot file publishes no acceleration limit (UR publishes none), accelerations within
  // kMaxProgramAcceleration (a ramp of a few ms commanded 1000 rad/s², review of session 45)
  if (const int j = over_acceleration_cap(peaks); j >= 0)
    throw InvalidArgument(fmt::format("{}: the program accelerates J{} at up to {:.3g} rad/s², beyond {:g} rad/s² (the most a program "
                                      "written here commands where the robot file gives no acceleration limit, as for the approach's "
                                      "movej); no program written. {}",
                                      o.scenario, j + 1, peaks.qdd[j], kMaxProgramAcceleration,
                                      motion.ramp_in() + motion.ramp_out() > 0.0 && motion.ramp_in() < 0.5 && motion.ramp_out() < 0.5
                                          ? fmt::format("Its ramps are short (--ramp {:g} s): lengthen them, or slow it down (--slow-down)",
                                                        o.program.ramp)
                                          : std::string("Slow it down (--slow-down)") +
                                                twinwatch::cli::slow_down_remedy(motion, robot, o.program.slow_down, kMaxProgramAcceleration, violation_at)));
  for (int j = 0; j < robot.n_dof(); ++j) {
    const double tmax = robot.joint(j).limits.torque_max;
    if (std::isfinite(tmax) && safety.torque[j] > tmax)
      throw InvalidArgument(fmt::format("{}: the program's motion needs {:.1f} N·m on J{} at {:.2f} s (rigid body{}, no friction), beyond "
                                        "its {:g} N·m: the drive cannot follow it; no program written. {}",
                                        o.scenario, safety.torque[j], j + 1, safety.torque_t[j],
                                        carried.mass > 0 ? fmt::format(" with {:g} kg on the flange", carried.mass) : std::string(), tmax,
                                        peaks.qdd[j] > 1.0 ? "Slow it down (--slow-down) or lengthen --ramp" : "Carry less"));
  }
  std::vector<std::string> header{fmt::format("Written by 'twinwatch urscript' from {} (trajectory {}).", o.scenario, s.trajectory_type)};
  header.push_back(fmt::format("Peak tool speed {:.3f} m/s ({}, at {:.2f} s), elbow speed {:.3f} m/s, momentum {:.2f} kg m/s{}:",
                               safety.tool_speed, tool_where, safety.tool_t, safety.elbow_speed, safety.momentum,
                               carried.mass > 0 ? fmt::format(" (with {:g} kg on the flange)", carried.mass) : std::string()));
  header.push_back("  the installation's Robot Limits (tool speed, elbow speed, momentum) must allow them, or the arm stops or slows mid-run.");
  if (!s.faults.empty())
    header.push_back(fmt::format("The scenario's {} fault(s) are the virtual robot's: the program has none.", s.faults.size()));
  // (the stops were dropped without a word: audit of session 56)
  if (!s.options.stops.empty())
    header.push_back(fmt::format("The scenario's {} stop(s) are the operator's and the safety system's on the virtual robot: the program "
                                 "runs without them.",
                                 s.options.stops.size()));
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
  // the approach's movej is the controller's: the longest it takes, from --max-approach away (a
  // trapezoid in the leading joint; the controller itself keeps it within the installation's limits)
  const double approach_s = sim::approach_time_at_most(o.program);
  const double record_for = std::ceil(approach_s + motion.total() + 30.0);
  if (o.json) {
    nlohmann::json j;
    j["program"] = o.output;
    j["scenario"] = o.scenario;
    j["robot"] = robot.name();
    j["motion_s"] = motion.total();
    j["slow_down"] = o.program.slow_down;
    j["servo_period_s"] = motion.servo_period();
    j["ramp_in_s"] = motion.ramp_in();
    j["ramp_out_s"] = motion.ramp_out();
    j["start_pose"] = vec(q0);
    j["q_min"] = vec(peaks.q_min);
    j["q_max"] = vec(peaks.q_max);
    j["peak_qd"] = vec(peaks.qd);
    j["peak_qdd"] = vec(peaks.qdd);
    j["peak_tool_speed"] = safety.tool_speed;
    j["peak_tool_speed_t"] = safety.tool_t;
    j["peak_tool_speed_point"] = safety.tool_point < 0 ? nlohmann::json("flange")
                                                       : nlohmann::json::array({tool_points[safety.tool_point].x(), tool_points[safety.tool_point].y(),
                                                                                tool_points[safety.tool_point].z()});
    j["peak_elbow_speed"] = safety.elbow_speed;
    j["peak_elbow_speed_t"] = safety.elbow_t;
    j["peak_momentum"] = safety.momentum;
    j["peak_momentum_t"] = safety.momentum_t;
    j["limits"] = [&] {
      nlohmann::json c = nlohmann::json::object();
      for (const Limit& l : limits)
        if (l.limit.given()) c[l.key] = {{"entered", l.limit.entered}, {"tolerance", l.limit.tolerance}, {"kept_within", l.limit.value()}};
      return c;
    }();
    j["max_approach"] = o.program.max_approach;
    j["approach_s_at_most"] = approach_s;
    j["record_for_s"] = record_for;
    j["tool_points"] = [&] {
      nlohmann::json a = nlohmann::json::array();
      for (const Eigen::Vector3d& p : tool_points) a.push_back({p.x(), p.y(), p.z()});
      return a;
    }();
    j["tool_mass"] = o.safety.tool_mass;
    j["carried_mass"] = carried.mass;
    j["peak_torque"] = vec(safety.torque);
    j["payload_declared"] = o.program.declare_payload;
    j["payload_command"] = o.program.declare_payload ? nlohmann::json(o.program.target_payload ? "set_target_payload" : "set_payload")
                                                     : nlohmann::json(nullptr);
    j["faults_left_out"] = s.faults.size();
    j["stops_left_out"] = s.options.stops.size();
    j["warnings"] = warnings;
    j["units"] = {{"motion_s", "s"}, {"start_pose", "rad"}, {"q_min", "rad"}, {"q_max", "rad"}, {"approach_s_at_most", "s"}, {"record_for_s", "s"},
                  {"tool_points", "m (flange frame)"}, {"tool_mass", "kg"}, {"carried_mass", "kg (tool and the scenario's payload)"},
                  {"peak_torque", "N·m (rigid body)"}, {"peak_qd", "rad/s"}, {"peak_qdd", "rad/s^2"},
                  {"peak_tool_speed", "m/s"}, {"peak_elbow_speed", "m/s"}, {"peak_momentum", "kg m/s"}, {"max_approach", "rad"},
                  {"peak_tool_speed_t", "s"}, {"peak_elbow_speed_t", "s"}, {"peak_momentum_t", "s"}, {"limits", "m/s, m/s, kg m/s (entered, the tolerance, and the value kept within)"}};
    fmt::print("{}\n", j.dump(2));
  } else if (!o.quiet) {
    fmt::print("{} -> {}: URScript for a {} (e-Series), {:.1f} s of motion{}, servoj every {:g} ms\n", s.name, o.output, robot.name(),
               motion.total(), o.program.slow_down != 1.0 ? fmt::format(" ({:g} times slower than the scenario)", o.program.slow_down) : "",
               1e3 * motion.servo_period());
    if (motion.ramp_in() > 0 || motion.ramp_out() > 0)
      fmt::print("  the target's clock rises over {:.1f} s and falls over {:.1f} s: the arm starts and ends at rest\n", motion.ramp_in(),
                 motion.ramp_out());
    else
      fmt::print("  the target starts and ends at rest: run as the scenario runs it\n");
    fmt::print("  start pose [rad]           {}\n", joints(q0, nullptr));
    fmt::print("  start pose [deg]           {}\n", [&] {
      std::string d;
      for (Eigen::Index j = 0; j < q0.size(); ++j) d += fmt::format("{}J{} {:.1f}", j ? "  " : "", j + 1, q0[j] * 180.0 / M_PI);
      return d;
    }());
    fmt::print("  (jog the arm within {:g} rad of it on every joint first: farther, the program halts before anything moves)\n",
               o.program.max_approach);
    fmt::print("  peak speed [rad/s]         {}\n", joints(peaks.qd, &qd_limit));
    fmt::print("  peak acceleration [rad/s²] {}\n", joints(peaks.qdd, &qdd_limit));
    for (const Limit& l : limits)
      fmt::print("  peak {:<22} {:.3f} {} at {:.2f} s{}{}\n", l.what, l.peak, l.unit, l.at,
                 l.where,
                 l.limit.given() ? fmt::format(": within {} ({:.0f} %)", l.limit.text(l.unit), 100.0 * l.peak / l.limit.value())
                                 : fmt::format(": not checked (the installation's limit: {})", l.limit.option));
    if (tool_points.empty()) fmt::print("  a tool on the flange was not checked: give its farthest points with --tool-point X Y Z (flange frame, m)\n");
    fmt::print("  payload: {}\n", o.program.declare_payload
                                      ? fmt::format("declared with {}({:g} kg, [{:g}, {:g}, {:g}] m{})",
                                                    o.program.target_payload ? "set_target_payload" : "set_payload", o.program.payload.mass,
                                                    o.program.payload.com.x(), o.program.payload.com.y(), o.program.payload.com.z(),
                                                    o.program.target_payload ? ", its inertia about the CoG" : "")
                                      : std::string("not changed (the installation's payload is used; --declare-payload declares the scenario's)"));
    if (!s.faults.empty()) fmt::print("  note: the scenario's {} fault(s) are the virtual robot's; the program has none\n", s.faults.size());
    if (!s.options.stops.empty())
      fmt::print("  note: the scenario's {} stop(s) (pause, protective or emergency stop) are the virtual robot's; the program runs "
                 "without them\n",
                 s.options.stops.size());
    fmt::print("  record it: start 'twinwatch record --rtde ROBOT_IP --frequency 500 --duration {:.0f} -o {}.csv', then run the program\n"
               "    (the motion, up to {:.1f} s of approach from --max-approach away at --approach-speed {:g} rad/s, and 30 s to spare)\n",
               record_for, s.name, approach_s, o.program.approach_speed);
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
      "file's joint ranges and speed limits before anything is written; its peak tool and elbow speed and momentum\n"
      "are reported, and checked against the installation's safety limits when given (--tool-speed-limit ...). The\n"
      "program halts before moving when the arm stands farther than --max-approach from the start pose. Send it to\n"
      "the controller's port 30002 or load it in a Script node (with --call), and record it meanwhile with 'twinwatch\n"
      "record --rtde'. Faults in the scenario are the virtual robot's and are left out. Exports fourier, fourier_series, sine and chirp trajectories.\n\n"
      "Building a twin of your own arm (docs/rtde.md, \"A twin of your own arm\"):\n"
      "  twinwatch excite ur5e -o exc.yaml --tool-point 0 0 0.15 && twinwatch urscript exc.yaml -o exc.script\n"
      "  twinwatch urscript scenarios/ur3e/train/swing_train.yaml --robot ur5e -o swing.script   # then again with the test weight (--slow-down as it says)\n"
      "  twinwatch identify exc.csv swing.csv swing_weight.csv --robot ur5e --known-payload swing_weight.csv=M,X,Y,Z -o twin.json"));
  sub->add_option("SCENARIO", o->scenario, "Scenario YAML whose trajectory the program runs (its robot's limits are checked)")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("-o,--output", o->output, "URScript program to write (.script)")->required();
  auto* duration = sub->add_option("--duration", o->duration, "Run the trajectory this long [s] (default: the scenario's duration)")
                       ->check(twinwatch::cli::positive_number());
  sub->add_option("--ramp", o->program.ramp, "Seconds over which the clock rises and falls where the target moves at its start or end")
      ->capture_default_str()
      ->check(twinwatch::cli::nonnegative_number());
  sub->add_option("--slow-down", o->program.slow_down,
                  "Run the trajectory this many times slower, 1-100: the same path, speeds (joint and Cartesian) and momentum / K, "
                  "accelerations / K²")
      ->capture_default_str();
  sub->add_option("--lookahead", o->program.lookahead, "servoj lookahead_time [s], 0.03-0.2")->capture_default_str();
  sub->add_option("--gain", o->program.gain, "servoj gain, 100-2000")->capture_default_str();
  sub->add_option("--approach-speed", o->program.approach_speed, "movej speed to the start pose [rad/s]")
      ->capture_default_str()
      ->check(twinwatch::cli::positive_number());
  sub->add_option("--approach-acceleration", o->program.approach_acceleration, "movej acceleration to the start pose [rad/s²]")
      ->capture_default_str()
      ->check(twinwatch::cli::positive_number());
  sub->add_option("--max-approach", o->program.max_approach,
                  "The program halts before anything moves when a joint is farther than this from the start pose [rad] (the approach "
                  "is a movej from wherever the arm stands)")
      ->capture_default_str()
      ->check(twinwatch::cli::positive_number());
  twinwatch::cli::add_tool_point_option(sub, o->tool,
                                        "A point of the tool on the flange, in the flange frame [m] (3 numbers; repeat for more points): "
                                        "its speed counts as the tool's, as the installation's tool positions do");
  twinwatch::cli::add_safety_limit_options(sub, o->safety, "Refuse (no program written) a motion beyond");
  sub->add_flag("--declare-payload", o->program.declare_payload,
                "Declare the scenario's payload (and the --tool-mass tool: everything on the flange) with set_payload before moving "
                "(else the installation's payload is kept)");
  sub->add_flag("--set-target-payload", o->program.target_payload,
                "Declare it with set_target_payload (mass, CoG and the inertia about the CoG; PolyScope 5.10 and newer, where "
                "set_payload is deprecated) instead; implies --declare-payload");
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
