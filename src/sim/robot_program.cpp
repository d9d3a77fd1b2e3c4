#include "twinwatch/sim/robot_program.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

#include "twinwatch/core/error.hpp"
#include "twinwatch/model/dynamics.hpp"

namespace twinwatch::sim {

namespace {

// a velocity below this is "at rest" for the choice of a ramp [rad/s] (a Fourier series that ends on a
// whole cycle ends at 1e-15)
constexpr double kAtRest = 1e-9;
constexpr double kTwoPi = 2.0 * M_PI;

// steps of a ramp of `seconds`: rounded up to an even number, so that its half (what it adds to the
// program's time) is whole
long ramp_steps(double seconds, double dt) {
  long k = static_cast<long>(std::ceil(seconds / dt - 1e-9));
  return k + (k % 2);
}

// A number as URScript reads it: always with a decimal point (a bare "2" is an int, and int / int
// may divide as integers), never in exponent notation.
std::string flt(double x) {
  if (std::abs(x) < 1e-12) return "0.0";  // (a sum's rounding, e.g. sin(2 pi k))
  std::string s = std::abs(x) >= 1e-4 ? fmt::format("{:.9g}", x) : fmt::format("{:.15f}", x);
  if (s.find('e') != std::string::npos) s = fmt::format("{:.6f}", x);  // (|x| >= 1e9: not written here)
  if (s.find('.') == std::string::npos) return s + ".0";
  if (std::abs(x) < 1e-4) {  // trailing zeros of the fixed form
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s += '0';
  }
  return s;
}

std::string list(const VectorJ& v) {
  std::string s = "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) s += (i ? ", " : "") + flt(v[i]);
  return s + "]";
}

std::string program_name(const std::string& text) {
  std::string s;
  for (char ch : text) s += std::isalnum(static_cast<unsigned char>(ch)) ? static_cast<char>(std::tolower(static_cast<unsigned char>(ch))) : '_';
  std::string out;  // no runs of '_'
  for (char ch : s)
    if (!(ch == '_' && !out.empty() && out.back() == '_')) out += ch;
  while (!out.empty() && out.back() == '_') out.pop_back();
  while (!out.empty() && out.front() == '_') out.erase(out.begin());
  return "twinwatch" + (out.empty() ? std::string() : "_" + out);
}

std::string joints_text(const VectorJ& v, int precision) {
  std::string s;
  for (Eigen::Index j = 0; j < v.size(); ++j) s += fmt::format("{}J{} {:.{}f}", j ? ", " : "", j + 1, v[j], precision);
  return s;
}

}  // namespace

void ProgramOptions::validate() const {
  auto need = [](bool ok, const char* field, const std::string& expected, double got) {
    if (!ok) throw InvalidArgument(fmt::format("{}: expected {}, got {}", field, expected, got));
  };
  need(std::isfinite(duration) && duration > 0.0 && duration <= 1e6, "duration", "a time > 0 s and at most 1e6 s", duration);
  need(std::isfinite(ramp) && ramp >= 0.0 && ramp <= 60.0, "ramp", "a time from 0 to 60 s", ramp);
  need(std::isfinite(slow_down) && slow_down >= 1.0 && slow_down <= 100.0, "slow_down", "a factor from 1 to 100", slow_down);
  need(std::isfinite(servo_period) && servo_period >= 0.001 && servo_period <= 0.1, "servo_period", "0.001 to 0.1 s", servo_period);
  need(lookahead >= 0.03 && lookahead <= 0.2, "lookahead", "0.03 to 0.2 s (servoj's range)", lookahead);
  need(gain >= 100.0 && gain <= 2000.0, "gain", "100 to 2000 (servoj's range)", gain);
  need(std::isfinite(approach_speed) && approach_speed > 0.0 && approach_speed <= 3.14, "approach_speed", "> 0 and at most 3.14 rad/s",
       approach_speed);
  need(std::isfinite(approach_acceleration) && approach_acceleration > 0.0 && approach_acceleration <= 40.0, "approach_acceleration",
       "> 0 and at most 40 rad/s²", approach_acceleration);
  need(std::isfinite(max_approach) && max_approach > 0.0 && max_approach <= kTwoPi, "max_approach", "> 0 and at most 2 pi rad",
       max_approach);
  if (target_payload && !declare_payload) throw InvalidArgument("target_payload: it says how the payload is declared, and none is (declare_payload)");
  if (declare_payload) {
    need(payload.inertia_com.allFinite() && (payload.inertia_com - payload.inertia_com.transpose()).norm() <= 1e-12 * (1.0 + payload.inertia_com.norm()),
         "payload inertia", "a finite symmetric matrix", payload.inertia_com.norm());
    if (payload.mass == 0.0)
      throw InvalidArgument("payload: the motion carries no payload, so there is none to declare (set_payload(0) would tell the "
                            "controller the flange carries nothing, a gripper included)");
    need(std::isfinite(payload.mass) && payload.mass >= 0.0, "payload mass", "a mass >= 0 kg", payload.mass);
    need(payload.com.allFinite() && payload.com.norm() <= 1.0, "payload com", "a point within 1 m of the flange", payload.com.norm());
  }
}

ProgramMotion::ProgramMotion(ClosedForm form, const ProgramOptions& o) : form_(std::move(form)), dt_(o.servo_period) {
  o.validate();
  if (o.slow_down != 1.0) form_ = form_.slowed(o.slow_down);
  const int n = form_.n_dof(), K = form_.components();
  if (n < 1 || K < 1) throw InvalidArgument(fmt::format("the closed form has {} joints and {} components: nothing moves", n, K));
  if (static_cast<int>(form_.sweep.size()) != K || form_.s.rows() != n || form_.c.rows() != n || form_.s.cols() != K ||
      form_.c.cols() != K)
    throw InvalidArgument(fmt::format("the closed form's sizes disagree: {} pulsations, {} sweeps, s {}x{}, c {}x{} for {} joints", K,
                                      form_.sweep.size(), form_.s.rows(), form_.s.cols(), form_.c.rows(), form_.c.cols(), n));
  const bool numbers_ok = form_.q0.allFinite() && form_.s.allFinite() && form_.c.allFinite() &&
                          std::all_of(form_.omega.begin(), form_.omega.end(), [](double x) { return std::isfinite(x); }) &&
                          std::all_of(form_.sweep.begin(), form_.sweep.end(), [](double x) { return std::isfinite(x); }) &&
                          std::isfinite(form_.fade) && form_.fade >= 0.0 && !(form_.wrap <= 0.0) && !std::isnan(form_.wrap) &&
                          (std::isfinite(form_.wrap) || form_.fade == 0.0) && form_.fade <= 0.5 * form_.wrap;
  if (!numbers_ok) throw InvalidArgument("the closed form holds a number that is not finite, or a fade longer than half its wrap");
  duration_steps_ = std::llround(o.duration * o.slow_down / dt_);
  if (duration_steps_ < 2)
    throw InvalidArgument(fmt::format("duration: expected at least two servo periods ({} s), got {} s", 2 * dt_, o.duration));
  VectorJ q, qd, qdd;
  form_.evaluate(0.0, q, qd, qdd);
  const bool moving_in = qd.cwiseAbs().maxCoeff() > kAtRest;
  form_.evaluate(static_cast<double>(duration_steps_) * dt_, q, qd, qdd);
  const bool moving_out = qd.cwiseAbs().maxCoeff() > kAtRest;
  if ((moving_in || moving_out) && o.ramp == 0.0)
    throw InvalidArgument(fmt::format("ramp: the target {} at rest, and a ramp of 0 s would make the arm take a step of velocity; "
                                      "expected a ramp > 0 s (default 2 s)",
                                      moving_in ? "does not start" : "does not end"));
  // (a slow-down stretches the ramps too: the whole program runs K times slower, every speed / K)
  if (moving_in) ramp_in_steps_ = ramp_steps(o.ramp * o.slow_down, dt_);
  if (moving_out) ramp_out_steps_ = ramp_steps(o.ramp * o.slow_down, dt_);
  if (ramp_in_steps_ + ramp_out_steps_ > 2 * duration_steps_)
    throw InvalidArgument(fmt::format("duration: {} s is shorter than half the ramps: expected at least {:g} s of the trajectory{}, or a "
                                      "shorter ramp",
                                      o.duration, 0.5 * static_cast<double>(ramp_in_steps_ + ramp_out_steps_) * dt_ / o.slow_down,
                                      o.slow_down != 1.0 ? fmt::format(" (half its ramps take {:g} s of the program, {:g} times slower)",
                                                                       0.5 * static_cast<double>(ramp_in_steps_ + ramp_out_steps_) * dt_, o.slow_down)
                                                         : std::string()));
}

void ProgramMotion::rate(double t, double& r, double& dr) const {
  const double P = total(), Rin = ramp_in(), Rout = ramp_out();
  r = 1.0, dr = 0.0;
  if (t >= P) {
    r = 0.0;
  } else if (t < Rin) {
    const double k = M_PI / Rin;
    r = 0.5 - 0.5 * std::cos(k * t);
    dr = 0.5 * k * std::sin(k * t);
  } else if (t > P - Rout) {
    const double k = M_PI / Rout, u = t - (P - Rout);
    r = 0.5 + 0.5 * std::cos(k * u);
    dr = -0.5 * k * std::sin(k * u);
  }
}

double ProgramMotion::clock(double t) const {
  const double P = total(), Rin = ramp_in(), Rout = ramp_out();
  t = std::clamp(t, 0.0, P);
  if (t < Rin) return 0.5 * t - Rin / kTwoPi * std::sin(M_PI * t / Rin);
  if (t <= P - Rout) return t - 0.5 * Rin;
  const double u = t - (P - Rout);
  return (P - Rout - 0.5 * Rin) + 0.5 * u + Rout / kTwoPi * std::sin(M_PI * u / Rout);
}

void ProgramMotion::evaluate(double t, VectorJ& q, VectorJ& qd, VectorJ& qdd) const {
  double r, dr;
  rate(t, r, dr);
  VectorJ y1, y2;
  form_.evaluate(clock(t), q, y1, y2);
  qd = r * y1;
  qdd = r * r * y2 + dr * y1;
}

ClosedForm scenario_closed_form(const Scenario& s) {
  if (auto f = s.trajectory ? s.trajectory->closed_form() : std::nullopt) return *f;
  throw InvalidArgument(fmt::format(
      "{}:{}: trajectory '{}' has no closed form that a robot program can evaluate: programs are made of the joint-space "
      "trajectories fourier, fourier_series, sine and chirp (an excitation from 'twinwatch excite ROBOT -o exc.yaml', the swing pair "
      "scenarios/ur3e/train/swing_train*.yaml). A Cartesian path (figure_eight, triangle) or a point-to-point or quasi-static program is "
      "taught on the pendant (MoveP, MoveJ); record it with 'twinwatch record --rtde'",
      s.path.empty() ? s.name : s.path, s.trajectory_line, s.trajectory_type));
}

std::shared_ptr<const ProgramMotion> rehearse_as_program(Scenario& s, const ProgramOptions& options) {
  auto motion = std::make_shared<const ProgramMotion>(scenario_closed_form(s), options);
  s.trajectory = motion;
  s.options.duration = motion->total();
  return motion;
}

MotionPeaks motion_peaks(const ProgramMotion& motion) {
  const int n = motion.n_dof();
  MotionPeaks p{VectorJ::Zero(n), VectorJ::Zero(n), VectorJ::Constant(n, std::numeric_limits<double>::infinity()),
                VectorJ::Constant(n, -std::numeric_limits<double>::infinity())};
  VectorJ q, qd, qdd;
  for (long k = 0; k <= motion.steps(); ++k) {
    motion.evaluate(static_cast<double>(k) * motion.servo_period(), q, qd, qdd);
    p.qd = p.qd.cwiseMax(qd.cwiseAbs());
    p.qdd = p.qdd.cwiseMax(qdd.cwiseAbs());
    p.q_min = p.q_min.cwiseMin(q);
    p.q_max = p.q_max.cwiseMax(q);
  }
  return p;
}

double slow_down_for_joint_limits(const ProgramMotion& motion, const model::RobotModel& robot, double qdd_cap) {
  const MotionPeaks p = motion_peaks(motion);
  double k = 1.0;
  for (int j = 0; j < std::min(motion.n_dof(), robot.n_dof()); ++j) {
    const model::JointLimits& l = robot.joint(j).limits;
    if (p.q_min[j] < l.q_min || p.q_max[j] > l.q_max) return std::numeric_limits<double>::infinity();
    if (std::isfinite(l.qd_max)) k = std::max(k, p.qd[j] / l.qd_max);
    const double qdd_max = std::isfinite(l.qdd_max) ? l.qdd_max : qdd_cap;
    if (std::isfinite(qdd_max)) k = std::max(k, std::sqrt(p.qdd[j] / qdd_max));
  }
  return k;
}

double approach_time_at_most(const ProgramOptions& o) {
  const double v = o.approach_speed, a = o.approach_acceleration, d = o.max_approach;
  return d >= v * v / a ? d / v + v / a : 2.0 * std::sqrt(d / a);
}

SafetyPeaks safety_peaks(const ProgramMotion& motion, const model::RobotModel& robot, const std::vector<Eigen::Vector3d>& tool_points,
                         const model::RigidBodyInertia& payload) {
  if (robot.n_dof() != motion.n_dof())
    throw InvalidArgument(fmt::format("the motion has {} joints, the robot {} has {}", motion.n_dof(), robot.name(), robot.n_dof()));
  for (size_t k = 0; k < tool_points.size(); ++k)
    if (!tool_points[k].allFinite()) throw InvalidArgument(fmt::format("tool point {} is not finite", k + 1));
  model::DynamicsData d(robot);
  model::RobotModel loaded = robot;  // (for the torque: the payload on the flange)
  if (payload.mass > 0.0) loaded.set_payload(payload);
  model::DynamicsData dl(loaded);
  SafetyPeaks p;
  p.torque = VectorJ::Zero(robot.n_dof());
  p.torque_t = VectorJ::Zero(robot.n_dof());
  VectorJ q, qd, qdd;
  for (long k = 0; k <= motion.steps(); ++k) {
    const double t = static_cast<double>(k) * motion.servo_period();
    motion.evaluate(t, q, qd, qdd);
    const VectorJ& tau = model::rnea(loaded, dl, q, qd, qdd);
    for (int j = 0; j < robot.n_dof(); ++j)
      if (std::abs(tau[j]) > p.torque[j]) p.torque[j] = std::abs(tau[j]), p.torque_t[j] = t;
    const model::CartesianSpeeds c = model::cartesian_speeds(robot, d, q, qd, tool_points, payload);
    if (c.tool > p.tool_speed) p.tool_speed = c.tool, p.tool_t = t, p.tool_point = c.tool_point;
    if (c.elbow > p.elbow_speed) p.elbow_speed = c.elbow, p.elbow_t = t;
    if (c.momentum > p.momentum) p.momentum = c.momentum, p.momentum_t = t;
  }
  return p;
}

std::string urscript_program(const ProgramMotion& motion, const ProgramOptions& o, const model::RobotModel& robot,
                             const std::vector<std::string>& header) {
  const ClosedForm& f = motion.form();
  const int n = f.n_dof(), K = f.components();
  if (n != robot.n_dof())
    throw InvalidArgument(fmt::format("the motion has {} joints, the robot {} has {}", n, robot.name(), robot.n_dof()));
  const std::string name = program_name(o.name.empty() ? o.title : o.name);
  const double dt = motion.servo_period();
  const long N = motion.steps(), n_in = motion.ramp_in_steps(), n_out = motion.ramp_out_steps();
  const bool clocked = std::isfinite(f.wrap) || f.fade > 0.0 ||
                       std::any_of(f.sweep.begin(), f.sweep.end(), [](double x) { return x != 0.0; });
  const MotionPeaks peaks = motion_peaks(motion);
  VectorJ q_start, qd, qdd;
  motion.evaluate(0.0, q_start, qd, qdd);
  VectorJ q_end;
  motion.evaluate(motion.total(), q_end, qd, qdd);

  std::string s;
  auto line = [&s](int indent, const std::string& text) { s += std::string(static_cast<size_t>(2 * indent), ' ') + text + "\n"; };
  // (a comment is one line: no control character of a title or header line may end it)
  auto comment = [](std::string text) {
    for (char& ch : text)
      if (static_cast<unsigned char>(ch) < 0x20) ch = ' ';
    return text;
  };
  // the header inside the def (a controller that takes one def block reads nothing outside it): what
  // moves, and what to check first
  line(0, fmt::format("def {}():", name));
  line(1, fmt::format("# twinwatch: {} on a Universal Robots e-Series arm ({})", comment(o.title.empty() ? name : o.title), robot.name()));
  for (const std::string& h : header) line(1, "# " + comment(h));
  line(1, fmt::format("# Motion: {:.3f} s, servoj every {} s (t={}, lookahead_time={}, gain={}); {} sinusoidal component(s),", motion.total(), dt,
                      dt, o.lookahead, o.gain, K));
  line(1, fmt::format("#   evaluated on the controller (32-bit floats: phases kept in [0, 2 pi), steps counted in an integer)."));
  if (o.slow_down != 1.0)
    line(1, fmt::format("# The trajectory runs {} times slower than its scenario: the same path, speeds / {}.", o.slow_down, o.slow_down));
  if (n_in || n_out)
    line(1, fmt::format("# The target's clock rises over the first {:.3f} s and falls over the last {:.3f} s, so the arm starts and ends at rest.",
                        motion.ramp_in(), motion.ramp_out()));
  line(1, fmt::format("# Start pose [rad]: {}; reached with movej at {} rad/s, {} rad/s^2.", list(q_start), o.approach_speed,
                      o.approach_acceleration));
  line(1, fmt::format("# End pose [rad]:   {}.", list(q_end)));
  line(1, fmt::format("# Joint range [rad]: {}", [&] {
         std::string r;
         for (int j = 0; j < n; ++j) r += fmt::format("{}J{} {:.3f} .. {:.3f}", j ? ", " : "", j + 1, peaks.q_min[j], peaks.q_max[j]);
         return r;
       }()));
  line(1, fmt::format("# Peak speed [rad/s]: {}", joints_text(peaks.qd, 3)));
  line(1, fmt::format("# Peak acceleration [rad/s^2]: {}", joints_text(peaks.qdd, 3)));
  if (o.declare_payload)
    line(1, fmt::format("# Payload: declared with {}({:.6g} kg, CoG [{:.6g}, {:.6g}, {:.6g}] m{}) before the arm moves.",
                        o.target_payload ? "set_target_payload" : "set_payload", o.payload.mass, o.payload.com.x(), o.payload.com.y(),
                        o.payload.com.z(), o.target_payload ? ", its inertia about the CoG" : ""));
  else
    line(1, "# Payload: not changed: the controller uses the installation's (set it to what the flange carries).");
  line(1, "# Before running it: run it in URSim or at a low speed slider first (speed scaling slows the whole");
  line(1, "#   motion, it does not change its path); jog the arm near the start pose (the approach is a movej from");
  line(1, fmt::format("#   wherever it is: when a joint is more than {} rad from it, the program halts before anything moves);", o.max_approach));
  line(1, "#   clear the arm's whole reach; keep the emergency stop at hand. Over port 30002 the controller must be");
  line(1, "#   in Remote Control; a Polyscope Script node (file) needs the call line after the def: 'twinwatch urscript --call'.");
  line(1, fmt::format("# Record it meanwhile: twinwatch record --rtde ROBOT_IP --frequency 500 --duration {:.0f} -o RECORDING.csv, started",
                      std::ceil(approach_time_at_most(o) + motion.total() + 30.0)));
  line(1, "#   before the program (the approach and the rests before and after are recorded too: identify reads them as any motion),");
  line(1, "#   at full speed: at a speed slider of x %, the motion takes 100 / x times as long; record for that.");
  const std::string shown = name.substr(std::min(name.size(), std::string("twinwatch_").size()));  // (in messages)
  // The approach is a movej from wherever the arm stands, through a path nobody checked: farther than
  // max_approach on any joint, the program says so and halts before anything moves.
  line(1, "tw_a = get_actual_joint_positions()");
  line(1, "tw_far = 0.0");
  line(1, "tw_j = 0");
  for (int j = 0; j < n; ++j) {
    line(1, fmt::format("tw_d = tw_a[{}] {} {}", j, q_start[j] < 0.0 ? "+" : "-", flt(std::abs(q_start[j]))));
    line(1, "if tw_d < 0.0:");
    line(2, "tw_d = -tw_d");
    line(1, "end");
    line(1, "if tw_d > tw_far:");
    line(2, "tw_far = tw_d");
    line(2, fmt::format("tw_j = {}", j + 1));
    line(1, "end");
  }
  line(1, fmt::format("if tw_far > {}:", flt(o.max_approach)));
  line(2, fmt::format("textmsg(\"twinwatch: {}: not started: the joint farthest from the start pose is joint \", tw_j)", shown));
  line(2, fmt::format("textmsg(\"twinwatch: {}: by [rad]: \", tw_far)", shown));
  {
    std::string deg;
    for (int j = 0; j < n; ++j) deg += fmt::format("{}{:.1f}", j ? ", " : "", q_start[j] * 180.0 / M_PI);
    line(2, fmt::format("popup(\"twinwatch {}: a joint is more than {} rad from the start pose; nothing moved. Jog the arm near the "
                        "start pose first (Move tab, joints in degrees: {}).\", title=\"twinwatch\", error=True, blocking=True)",
                        shown, flt(o.max_approach), deg));
  }
  line(2, "halt");
  line(1, "end");
  line(1, fmt::format("textmsg(\"twinwatch: {}: moving to the start pose\")", shown));
  if (o.declare_payload && o.target_payload) {
    const Eigen::Matrix3d& I = o.payload.inertia_com;  // (URScript's order: Ixx, Iyy, Izz, Ixy, Ixz, Iyz)
    line(1, fmt::format("set_target_payload({}, [{}, {}, {}], [{}, {}, {}, {}, {}, {}])", flt(o.payload.mass), flt(o.payload.com.x()),
                        flt(o.payload.com.y()), flt(o.payload.com.z()), flt(I(0, 0)), flt(I(1, 1)), flt(I(2, 2)), flt(I(0, 1)), flt(I(0, 2)),
                        flt(I(1, 2))));
  } else if (o.declare_payload) {
    line(1, fmt::format("set_payload({}, [{}, {}, {}])", flt(o.payload.mass), flt(o.payload.com.x()), flt(o.payload.com.y()),
                        flt(o.payload.com.z())));
  }
  line(1, fmt::format("movej({}, a={}, v={})", list(q_start), flt(o.approach_acceleration), flt(o.approach_speed)));
  line(1, fmt::format("textmsg(\"twinwatch: {}: the motion starts ({:.1f} s)\")", shown, motion.total()));
  line(1, "tw_n = 0");
  line(1, fmt::format("tw_dtau = {}", flt(dt)));
  line(1, "tw_y = 0.0");
  line(1, "tw_s = 0.0");
  if (clocked) {
    line(1, "tw_u = 0.0");
    line(1, "tw_cu = 0.0");
  }
  for (int k = 0; k < K; ++k) {
    line(1, fmt::format("tw_th{} = 0.0", k));
    line(1, fmt::format("tw_c{} = 0.0", k));
  }
  line(1, fmt::format("while tw_n < {}:", N));
  // the clock's step: tau(t + dt) - tau(t) of the raised-cosine ramps, written as
  // dt/2 -+ (R/pi) sin(pi dt / 2R) cos(pi (m + 1/2) dt / R) (a difference of sines, well conditioned)
  const long out_from = N - n_out;
  auto ramp_step = [&](long steps, double sign, const std::string& m) {
    const double R = static_cast<double>(steps) * dt, k = M_PI * dt / R;
    return fmt::format("tw_dtau = {} {} {} * cos({} * ({} + 0.5))", flt(0.5 * dt), sign < 0 ? "-" : "+", flt(R / M_PI * std::sin(0.5 * k)),
                       flt(k), m);
  };
  if (n_in || n_out) {
    bool first = true;
    if (n_in) {
      line(2, fmt::format("if tw_n < {}:", n_in));
      line(3, ramp_step(n_in, -1.0, "tw_n"));
      first = false;
    }
    if (n_out) {
      line(2, fmt::format("{} tw_n >= {}:", first ? "if" : "elif", out_from));
      line(3, ramp_step(n_out, +1.0, fmt::format("(tw_n - {})", out_from)));
    }
    line(2, "else:");
    line(3, fmt::format("tw_dtau = {}", flt(dt)));
    line(2, "end");
  }
  // Each component's phase, advanced exactly for its polynomial: (omega + sweep u) dtau + sweep dtau^2 / 2,
  // and u by dtau. A 32-bit float sum of 2 ms steps loses up to half a unit in the last place a step:
  // summed plainly, 20000 steps of a sine drifted 1.8 mrad (tests/sim/robot_program_test.cpp). So each
  // sum is compensated (Kahan): tw_c* holds what the float sum holds too much (the phase is tw_th - tw_c). Wrapping by the float nearest 2 pi (exact by Sterbenz)
  // moves the difference to the exact 2 pi into the compensation.
  // Kahan's sum errs by at most 2 eps times the phase travelled (eps = 6e-8): a frequency error below
  // 1.2e-7, smooth; summed plainly it errs by up to n eps times it (tests/sim/robot_program_test.cpp).
  const float two_pi_f = static_cast<float>(kTwoPi);
  const double two_pi_excess = static_cast<double>(two_pi_f) - kTwoPi;
  auto compensated = [&](const std::string& sum, const std::string& comp, const std::string& increment) {
    line(2, fmt::format("tw_y = {} - {}", increment, comp));
    line(2, fmt::format("tw_s = {} + tw_y", sum));
    line(2, fmt::format("{} = (tw_s - {}) - tw_y", comp, sum));
    line(2, fmt::format("{} = tw_s", sum));
  };
  for (int k = 0; k < K; ++k) {
    const std::string th = fmt::format("tw_th{}", k), comp = fmt::format("tw_c{}", k);
    compensated(th, comp,
                f.sweep[k] != 0.0 ? fmt::format("({} + {} * tw_u) * tw_dtau + {} * tw_dtau * tw_dtau", flt(f.omega[k]), flt(f.sweep[k]),
                                                flt(0.5 * f.sweep[k]))
                                  : fmt::format("{} * tw_dtau", flt(f.omega[k])));
    line(2, fmt::format("if {} >= {}:", th, flt(two_pi_f)));
    line(3, fmt::format("{0} = {0} - {1}", th, flt(two_pi_f)));
    line(3, fmt::format("{0} = {0} - {1}", comp, flt(two_pi_excess)));
    line(2, fmt::format("elif {} < 0.0:", th));
    line(3, fmt::format("{0} = {0} + {1}", th, flt(two_pi_f)));
    line(3, fmt::format("{0} = {0} + {1}", comp, flt(two_pi_excess)));
    line(2, "end");
  }
  if (clocked) {
    compensated("tw_u", "tw_cu", "tw_dtau");
    if (std::isfinite(f.wrap)) {
      line(2, fmt::format("if tw_u >= {}:", flt(f.wrap)));
      line(3, fmt::format("tw_u = tw_u - {}", flt(f.wrap)));
      for (int k = 0; k < K; ++k) {
        line(3, fmt::format("tw_th{} = ({} + {} * tw_u) * tw_u", k, flt(f.omega[k]), flt(0.5 * f.sweep[k])));
        line(3, fmt::format("tw_c{} = 0.0", k));
      }
      line(2, "end");
    }
  }
  for (int k = 0; k < K; ++k) {
    line(2, fmt::format("tw_sn{0} = sin(tw_th{0})", k));
    line(2, fmt::format("tw_cs{0} = cos(tw_th{0})", k));
  }
  if (f.fade > 0.0) {
    const double kf = M_PI / f.fade;
    line(2, "tw_f = 1.0");
    line(2, fmt::format("if tw_u < {}:", flt(f.fade)));
    line(3, fmt::format("tw_f = 0.5 - 0.5 * cos({} * tw_u)", flt(kf)));
    line(2, fmt::format("elif tw_u > {}:", flt(f.wrap - f.fade)));
    line(3, fmt::format("tw_f = 0.5 - 0.5 * cos({} * ({} - tw_u))", flt(kf), flt(f.wrap)));
    line(2, "end");
  }
  std::string targets;
  for (int j = 0; j < n; ++j) {
    std::string sum;
    for (int k = 0; k < K; ++k)
      for (const auto& [a, v] : {std::pair{f.s(j, k), fmt::format("tw_sn{}", k)}, std::pair{f.c(j, k), fmt::format("tw_cs{}", k)}}) {
        if (a == 0.0) continue;
        sum += sum.empty() ? (a < 0 ? "-" : "") : (a < 0 ? " - " : " + ");
        sum += fmt::format("{} * {}", flt(std::abs(a)), v);
      }
    std::string q = flt(f.q0[j]);
    if (!sum.empty()) q += f.fade > 0.0 ? fmt::format(" + tw_f * ({})", sum) : (sum.front() == '-' ? " - " + sum.substr(1) : " + " + sum);
    line(2, fmt::format("tw_q{} = {}", j, q));
    targets += fmt::format("{}tw_q{}", j ? ", " : "", j);
  }
  line(2, fmt::format("servoj([{}], t={}, lookahead_time={}, gain={})", targets, flt(dt), flt(o.lookahead), flt(o.gain)));
  line(2, "tw_n = tw_n + 1");
  line(1, "end");
  line(1, "stopj(2.0)");
  line(1, fmt::format("textmsg(\"twinwatch: {}: done\")", shown));
  line(0, "end");
  if (o.call) line(0, fmt::format("{}()", name));
  return s;
}

}  // namespace twinwatch::sim
