#include "twinwatch/sim/scenario.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"
#include "twinwatch/core/log.hpp"
#include "twinwatch/core/json_fields.hpp"
#include "twinwatch/core/numbers.hpp"
#include "twinwatch/model/description_io.hpp"

namespace twinwatch::sim {

namespace {

class Y {
 public:
  Y(std::string origin) : origin_(std::move(origin)) {}

  [[noreturn]] void fail(const YAML::Node& n, const std::string& field, const std::string& what) const {
    const int line = n.IsDefined() && n.Mark().line >= 0 ? n.Mark().line + 1 : 0;
    throw ParseError(origin_, line, field, what);
  }

  // yaml-cpp keeps every entry of a repeated key and n[key] answers the first: a second `duration:`
  // would be dropped without a word
  void unique_keys(const YAML::Node& n, const std::string& path) const {
    if (!n.IsMap()) return;
    std::map<std::string, int> first_line;
    for (auto it = n.begin(); it != n.end(); ++it) {
      if (!it->first.IsScalar()) continue;
      const std::string k = it->first.Scalar();
      const int line = it->first.Mark().line + 1;
      const auto [first, fresh] = first_line.emplace(k, line);
      if (!fresh) fail(it->first, join(path, k), fmt::format("key given twice, on lines {} and {}; expected it once", first->second, line));
    }
  }

  void only_keys(const YAML::Node& n, const std::string& path, const std::set<std::string>& allowed) const {
    if (!n.IsMap()) fail(n, path, "expected a mapping of keys");
    unique_keys(n, path);
    for (auto it = n.begin(); it != n.end(); ++it) {
      // (as<std::string>() of a list or mapping used as a key, "? [a]", throws a YAML exception)
      if (!it->first.IsScalar()) fail(it->first, path, "expected text keys, got a list or mapping as a key");
      const std::string k = it->first.as<std::string>();
      if (!allowed.count(k)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(it->first, join(path, k), fmt::format("unknown key '{}', expected one of: {}", k, list));
      }
    }
  }

  double number(const YAML::Node& parent, const std::string& path, const std::string& key) const {
    const YAML::Node n = parent[key];
    if (!n) fail(parent, join(path, key), "missing required field");
    return as_number(n, join(path, key));
  }
  double number_or(const YAML::Node& parent, const std::string& path, const std::string& key, double fallback) const {
    const YAML::Node n = parent[key];
    return n ? as_number(n, join(path, key)) : fallback;
  }
  double as_number(const YAML::Node& n, const std::string& field) const {
    if (n.IsNull()) fail(n, field, "expected a number, got nothing");
    if (!n.IsScalar()) fail(n, field, "expected a number, got a list or mapping");
    double v = 0.0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(n, field, fmt::format("expected a number, got '{}'", n.Scalar()));
    }
    // (.inf and .nan are YAML numbers no scenario value takes: a run without an end omits 'end')
    if (!std::isfinite(v)) fail(n, field, fmt::format("expected a finite number, got {}", v));
    return v;
  }
  int integer(const YAML::Node& parent, const std::string& path, const std::string& key, int fallback) const {
    const YAML::Node n = parent[key];
    if (!n) return fallback;
    const double v = as_number(n, join(path, key));
    const std::optional<int> x = whole_int(v);
    if (!x) fail(n, join(path, key), fmt::format("expected a whole number within +-{}, got {}", std::numeric_limits<int>::max(), v));
    return *x;
  }
  // a seed: a whole number 0 to 2^32 - 1, as 'simulate --seed' takes (an int stopped at 2^31 - 1)
  unsigned seed(const YAML::Node& parent, const std::string& path, const std::string& key, unsigned fallback) const {
    const YAML::Node n = parent[key];
    if (!n) return fallback;
    const double v = as_number(n, join(path, key));
    constexpr double kMax = static_cast<double>(std::numeric_limits<unsigned>::max());
    if (!(v >= 0.0 && v <= kMax && v == std::floor(v)))
      fail(n, join(path, key), fmt::format("expected a whole number from 0 to {}, got {}", std::numeric_limits<unsigned>::max(), n.Scalar()));
    return static_cast<unsigned>(v);
  }
  std::string text(const YAML::Node& parent, const std::string& path, const std::string& key, const std::string& fallback) const {
    const YAML::Node n = parent[key];
    if (!n) return fallback;
    if (!n.IsScalar()) fail(n, join(path, key), "expected a text value");
    return n.Scalar();
  }
  bool boolean(const YAML::Node& parent, const std::string& path, const std::string& key, bool fallback) const {
    const YAML::Node n = parent[key];
    if (!n) return fallback;
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(n, join(path, key), fmt::format("expected true or false, got '{}'", n.Scalar()));
    }
  }
  // a list of numbers of length `size` (or a scalar broadcast when allow_scalar)
  VectorJ vec(const YAML::Node& parent, const std::string& path, const std::string& key, int size, bool allow_scalar = false) const {
    const YAML::Node n = parent[key];
    const std::string f = join(path, key);
    if (!n) fail(parent, f, "missing required field");
    return as_vec(n, f, size, allow_scalar);
  }
  VectorJ finite_vec(const YAML::Node& parent, const std::string& path, const std::string& key, int size) const {
    const VectorJ v = vec(parent, path, key, size);
    for (int i = 0; i < size; ++i)
      if (!std::isfinite(v[i]))
        fail(parent[key][static_cast<size_t>(i)], fmt::format("{}[{}]", join(path, key), i), fmt::format("expected a finite number, got {}", v[i]));
    return v;
  }
  VectorJ as_vec(const YAML::Node& n, const std::string& f, int size, bool allow_scalar = false) const {
    if (allow_scalar && n.IsScalar()) return VectorJ::Constant(size, as_number(n, f));
    if (!n.IsSequence()) fail(n, f, fmt::format("expected a list of {} numbers", size));
    if (static_cast<int>(n.size()) != size) fail(n, f, fmt::format("expected {} numbers, got {}", size, n.size()));
    VectorJ v(size);
    for (int i = 0; i < size; ++i) v[i] = as_number(n[static_cast<size_t>(i)], fmt::format("{}[{}]", f, i));
    return v;
  }
  // the key node of `key` in mapping `n` (its line is where the user wrote the key, also when the
  // value is a block mapping that starts on the next line); undefined if absent
  static YAML::Node key_of(const YAML::Node& n, const std::string& key) {
    if (n.IsMap())
      for (auto it = n.begin(); it != n.end(); ++it)
        if (it->first.IsScalar() && it->first.Scalar() == key) return it->first;
    return YAML::Node();  // no mark: reported without a line
  }
  static std::string join(const std::string& p, const std::string& k) { return p.empty() ? k : p + "." + k; }

 private:
  std::string origin_;
};

// the payload check's "expected" text, e.g. "expected at most 3 kg (the rated payload of ur3e), got 500 kg"
std::string payload_above_limit(const model::RobotModel& m, double mass) {
  return fmt::format("expected at most {:g} kg ({}), got {} kg", m.payload_limit(), m.payload_limit_text(), mass);
}

// a payload's `com` under `n`: three finite numbers within model::kPayloadComMax of the flange
Eigen::Vector3d payload_com(const Y& y, const YAML::Node& n, const std::string& path) {
  const VectorJ c = y.finite_vec(n, path, "com", 3);
  if (c.norm() > model::kPayloadComMax)
    y.fail(n["com"], path + ".com",
           fmt::format("expected a centre of mass within {:g} m of the flange, got {:.3g} m away (in mm? give metres)", model::kPayloadComMax,
                       c.norm()));
  return Eigen::Vector3d(c[0], c[1], c[2]);
}

model::RigidBodyInertia payload_from(const Y& y, const YAML::Node& n, const std::string& path, const model::RobotModel& m) {
  y.only_keys(n, path, {"mass", "com", "inertia"});
  model::RigidBodyInertia p;
  p.mass = y.number(n, path, "mass");
  if (!(p.mass >= 0.0)) y.fail(n["mass"], path + ".mass", fmt::format("must be >= 0, got {}", p.mass));
  if (p.mass > m.payload_limit()) y.fail(n["mass"], path + ".mass", payload_above_limit(m, p.mass));
  if (n["com"]) p.com = payload_com(y, n, path);
  if (n["inertia"]) {
    const VectorJ I = y.vec(n, path, "inertia", 6);
    p.inertia_com << I[0], I[1], I[2], I[1], I[3], I[4], I[2], I[4], I[5];
  }
  try {
    p.validate("payload");
  } catch (const InvalidArgument& e) {
    y.fail(n, path, e.what());
  }
  // a part a flange carries lies within a metre of its centre of mass: its inertia about that centre
  // is at most m (1 m)² (0.5 kg with [100, 0, 0, 100, 0, 100] kg m² was taken: audit of session 56)
  if (n["inertia"]) {
    constexpr double kPartExtent = 1.0;  // [m]
    const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(p.inertia_com, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
    if (largest > p.mass * kPartExtent * kPartExtent)
      y.fail(n["inertia"], path + ".inertia",
             fmt::format("a {:g} kg part has an inertia of at most {:g} kg m² about its centre of mass unless it reaches beyond {:g} m from "
                         "it, got a principal moment of {:.4g} kg m² (in kg cm² or g m²? give kg m²)",
                         p.mass, p.mass * kPartExtent * kPartExtent, kPartExtent, largest));
  }
  return p;
}

// a frequency the controller, reading the target `rate` times a second, can command: at or above
// rate / 2 the samples alias (a 1000 Hz sine read at 500 Hz looks still while its velocity is huge)
bool below_nyquist(double f, double rate) { return f < 0.5 * rate; }

std::shared_ptr<const Trajectory> trajectory_from(const Y& y, const YAML::Node& t, const model::RobotModel& m,
                                                  std::string& type, double rate) {
  const std::string p = "trajectory";
  if (!t) y.fail(t, p, "missing required field");
  if (!t.IsMap()) y.fail(t, p, "expected a mapping with a 'type'");
  y.unique_keys(t, p);
  type = y.text(t, p, "type", "");
  const int n = m.n_dof();
  VectorJ home = VectorJ::Zero(n);
  if (n == 6) home << 0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0;
  const VectorJ start = t["start"] ? y.vec(t, p, "start", n) : home;
  try {
    if (type == "figure_eight") {
      y.only_keys(t, p, {"type", "start", "size", "period", "tilt"});
      const VectorJ size = t["size"] ? y.vec(t, p, "size", 2) : VectorJ(VectorJ::Constant(2, 0.1));
      const VectorJ tilt = t["tilt"] ? y.vec(t, p, "tilt", 3) : VectorJ(VectorJ::Zero(3));
      return make_figure_eight(m, start, size[0], size[1], y.number_or(t, p, "period", 8.0),
                               Eigen::Vector3d(tilt[0], tilt[1], tilt[2]));
    }
    if (type == "triangle") {
      y.only_keys(t, p, {"type", "start", "side", "speed"});
      return make_triangle(m, start, y.number_or(t, p, "side", 0.15), y.number_or(t, p, "speed", 0.2));
    }
    if (type == "fourier") {
      y.only_keys(t, p, {"type", "start", "amplitude", "period", "harmonics", "seed"});
      const unsigned fseed = y.seed(t, p, "seed", 1);
      const auto c = random_fourier(start, y.number_or(t, p, "amplitude", 0.8), y.number_or(t, p, "period", 10.0),
                                    y.integer(t, p, "harmonics", 5), fseed);
      return make_fourier(c);
    }
    if (type == "fourier_series") {
      // explicit coefficients, e.g. written by `twinwatch excite` [Cao eq. 21]
      y.only_keys(t, p, {"type", "base_frequency", "q0", "a", "b"});
      FourierCoefficients c;
      const double f = y.number(t, p, "base_frequency");
      if (!(f > 0.0)) y.fail(t["base_frequency"], p + ".base_frequency", fmt::format("must be > 0 Hz, got {}", f));
      c.w_f = 2.0 * M_PI * f;
      c.q0 = y.vec(t, p, "q0", n);
      auto matrix = [&](const std::string& key) {
        const YAML::Node mn = t[key];
        const std::string f2 = p + "." + key;
        if (!mn) y.fail(t, f2, "missing required field");
        if (!mn.IsSequence() || static_cast<int>(mn.size()) != n)
          y.fail(mn, f2, fmt::format("expected {} rows (one per joint), each a list of harmonics", n));
        const YAML::Node r0 = mn[0];
        const int L = r0.IsSequence() ? static_cast<int>(r0.size()) : 0;
        if (L < 1) y.fail(r0, f2 + "[0]", "expected a list of at least one number");
        Eigen::MatrixXd M(n, L);
        for (int j = 0; j < n; ++j) {
          const VectorJ r = y.as_vec(mn[static_cast<size_t>(j)], fmt::format("{}[{}]", f2, j), L);
          M.row(j) = r.transpose();
        }
        return M;
      };
      c.a = matrix("a");
      c.b = matrix("b");
      if (c.a.cols() != c.b.cols())
        y.fail(t["b"], p + ".b", fmt::format("expected {} harmonics per row (as in a), got {}", c.a.cols(), c.b.cols()));
      return make_fourier(c);
    }
    if (type == "sine") {
      y.only_keys(t, p, {"type", "start", "amplitude", "frequency", "phase"});
      const VectorJ A = y.vec(t, p, "amplitude", n, true);
      const VectorJ f = y.vec(t, p, "frequency", n, true);
      for (int j = 0; j < n; ++j)
        if (!(f[j] >= 0.0 && below_nyquist(f[j], rate)))
          y.fail(t["frequency"], p + ".frequency",
                 fmt::format("expected frequencies from 0 to below half the control rate ({:g} Hz at {:g} Hz), got {} Hz on joint {}",
                             0.5 * rate, rate, f[j], j + 1));
      const VectorJ ph = t["phase"] ? y.vec(t, p, "phase", n, true) : VectorJ(VectorJ::Zero(n));
      return make_sine(start, A, f, ph);
    }
    if (type == "chirp") {
      y.only_keys(t, p, {"type", "start", "amplitude", "f0", "f1", "sweep"});
      const double f0 = y.number_or(t, p, "f0", 0.1), f1 = y.number_or(t, p, "f1", 1.0);
      for (const auto& [key, f] : {std::pair{"f0", f0}, std::pair{"f1", f1}})
        if (!below_nyquist(f, rate))
          y.fail(t[key], p + "." + key,
                 fmt::format("expected a frequency below half the control rate ({:g} Hz at {:g} Hz), got {} Hz", 0.5 * rate, rate, f));
      return make_chirp(start, y.vec(t, p, "amplitude", n, true), f0, f1, y.number_or(t, p, "sweep", 30.0));
    }
    if (type == "point_to_point") {
      y.only_keys(t, p, {"type", "start", "waypoints", "durations"});
      const YAML::Node w = t["waypoints"], d = t["durations"];
      if (!w || !w.IsSequence()) y.fail(t, p + ".waypoints", "expected a list of joint vectors");
      std::vector<VectorJ> wp;
      for (size_t k = 0; k < w.size(); ++k) wp.push_back(y.as_vec(w[k], fmt::format("{}.waypoints[{}]", p, k), n));
      if (!d || !d.IsSequence()) y.fail(t, p + ".durations", "expected a list of durations [s]");
      std::vector<double> T;
      for (size_t k = 0; k < d.size(); ++k) T.push_back(y.as_number(d[k], fmt::format("{}.durations[{}]", p, k)));
      return make_point_to_point(wp, T);
    }
    if (type == "quasi_static") {
      y.only_keys(t, p, {"type", "start", "poses", "delta", "creep_speed", "hold"});
      const YAML::Node w = t["poses"];
      if (!w || !w.IsSequence()) y.fail(t, p + ".poses", "expected a list of joint vectors");
      std::vector<VectorJ> poses;
      for (size_t k = 0; k < w.size(); ++k) poses.push_back(y.as_vec(w[k], fmt::format("{}.poses[{}]", p, k), n));
      return make_quasi_static(poses, y.number_or(t, p, "delta", 0.1), y.number_or(t, p, "creep_speed", 0.05),
                               y.number_or(t, p, "hold", 0.5));
    }
  } catch (const InvalidArgument& e) {
    y.fail(t, p, e.what());
  }
  y.fail(t["type"] ? t["type"] : t, p + ".type",
         fmt::format("expected one of figure_eight, triangle, fourier, fourier_series, sine, chirp, point_to_point, quasi_static; got '{}'", type));
}

// [A] the largest current_offset fault: a sensor offset of tens of amperes is no longer an offset
constexpr double kMaxCurrentOffset = 20.0;
// [m] a collision's contact point from its link's frame (a value in mm is metres away)
constexpr double kMaxContactPointDistance = 1.0;

// the keys a fault of each type takes (parse_scenario)
std::set<std::string> fault_keys(FaultType t) {
  std::set<std::string> k{"type", "onset", "ramp", "end"};
  switch (t) {
    case FaultType::Resistance:
    case FaultType::FrictionGrowth:
    case FaultType::CurrentOffset: k.insert({"joint", "magnitude"}); break;
    case FaultType::StuckCurrent: k.insert("joint"); break;
    case FaultType::Collision: k = {"type", "onset", "link", "point", "direction", "duration", "magnitude"}; break;
    // (a pick or a loss happens at its onset: it has no ramp and no end, which the simulator would
    // ignore while the label's window used them)
    case FaultType::PayloadPick: k = {"type", "onset", "mass", "com", "io_bit", "declare_delay"}; break;
    case FaultType::MissedPick: k = {"type", "onset", "mass", "com", "io_bit"}; break;
    case FaultType::PayloadLoss: k = {"type", "onset", "io_bit"}; break;
    case FaultType::DroppedSamples: k.insert({"magnitude", "period"}); break;
    case FaultType::TimestampJitter: k.insert("magnitude"); break;
  }
  return k;
}

FaultType fault_type(const Y& y, const YAML::Node& n, const std::string& f) {
  const std::string s = y.text(n, f, "type", "");
  for (FaultType t : {FaultType::Resistance, FaultType::FrictionGrowth, FaultType::PayloadPick, FaultType::PayloadLoss,
                      FaultType::Collision, FaultType::CurrentOffset, FaultType::StuckCurrent, FaultType::DroppedSamples,
                      FaultType::TimestampJitter, FaultType::MissedPick})
    if (s == to_string(t)) return t;
  y.fail(n["type"] ? n["type"] : n, f + ".type",
         fmt::format("expected one of resistance, friction_growth, payload_pick, payload_loss, collision, current_offset, "
                     "stuck_current, dropped_samples, timestamp_jitter, missed_pick; got '{}'", s));
}

}  // namespace


Scenario parse_scenario(const std::string& text, const std::string& origin, const std::string& robot, bool trajectory_limits) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw ParseError(origin, e.mark.line + 1, "", fmt::format("not valid YAML: {}", e.msg));
  }
  const Y y(origin);
  y.only_keys(root, "", {"name", "robot", "robot_serial", "seed", "duration", "cycles", "rate", "substeps", "cold_start", "payload",
                         "payload_declared", "streams_payload", "streams_targets", "joint_torque_sensors", "trajectory", "noise", "faults", "stops", "description", "program"});
  Scenario s;
  s.path = origin;
  s.name = y.text(root, "", "name", origin);
  s.robot = robot.empty() ? y.text(root, "", "robot", "ur3e") : robot;
  // a description file the scenario names is found beside the scenario (as the scenario is moved
  // with it), else from the working directory: 'robot: ../robots/arm.json' was read from the
  // working directory only (audit of session 56). Kept as the path found, for every later load
  if (robot.empty() && !model::robot_file(s.robot).empty()) {
    const std::filesystem::path given(s.robot), dir = std::filesystem::path(origin).parent_path();
    const std::string beside = (dir / given).string();
    std::error_code ec;
    if (given.is_relative() && !dir.empty() && std::filesystem::exists(model::robot_file(beside), ec)) s.robot = beside;
  }
  s.program = y.text(root, "", "program", "");
  if (root["program"] && (s.program.empty() || s.program.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_.-") !=
                                                   std::string::npos))
    y.fail(root["program"], "program", fmt::format("expected a program name of letters, digits, '_', '.' and '-' (as 'twinwatch "
                                                   "thresholds --program' takes), got '{}'", s.program));
  model::RobotModel m = [&] {
    try {
      return model::load_robot(s.robot);
    } catch (const std::exception& e) {  // (a description file's own error too: ParseError naming it)
      if (!root["robot"]) throw;
      y.fail(root["robot"], "robot", e.what());
    }
  }();
  const int n = m.n_dof();
  // (a negative seed or serial would wrap around to a large unsigned number)
  const unsigned seed = y.seed(root, "", "seed", 1);
  const int serial = y.integer(root, "", "robot_serial", 1);
  if (serial < 0) y.fail(root["robot_serial"], "robot_serial", fmt::format("expected a whole number >= 0, got {}", serial));
  s.options.seed = seed;
  s.serial = static_cast<unsigned>(serial);
  // control rate and physics substeps: the default substeps meet rate x substeps >= kMinPhysicsRate
  const double rate = s.options.rate = y.number_or(root, "", "rate", 500.0);
  if (!(rate >= kMinRate && rate <= kMaxRate))
    y.fail(root["rate"], "rate", fmt::format("expected a control rate from {:g} to {:g} Hz, got {}", kMinRate, kMaxRate, rate));
  const int min_substeps = static_cast<int>(std::ceil(kMinPhysicsRate / rate));
  const int substeps = s.options.substeps = y.integer(root, "", "substeps", std::max(1, min_substeps));
  if (substeps < 1) y.fail(root["substeps"], "substeps", fmt::format("expected >= 1, got {}", substeps));
  if (rate * substeps < kMinPhysicsRate)
    y.fail(root["substeps"], "substeps",
           fmt::format("physics rate is {} Hz (rate {} x substeps {}), must be >= {:g} Hz: expected substeps >= {}", rate * substeps,
                       rate, substeps, kMinPhysicsRate, min_substeps));
  s.options.cold_start = y.boolean(root, "", "cold_start", false);
  s.options.payload_declared = y.boolean(root, "", "payload_declared", true);
  s.options.streams_payload = y.boolean(root, "", "streams_payload", true);
  s.options.streams_targets = y.boolean(root, "", "streams_targets", true);
  s.options.joint_torque_sensors = y.boolean(root, "", "joint_torque_sensors", false);
  if (root["payload"]) s.options.payload = payload_from(y, root["payload"], "payload", m);
  s.trajectory = trajectory_from(y, root["trajectory"], m, s.trajectory_type, rate);
  // duration, given or as cycles of the trajectory (default one cycle), each checked at its own line
  const double period = s.trajectory->period();
  if (root["duration"] && root["cycles"]) y.fail(root["cycles"], "cycles", "give either duration or cycles, not both");
  if (const YAML::Node c = root["cycles"]) {
    const double cycles = y.as_number(c, "cycles");
    if (!(cycles > 0.0 && std::isfinite(cycles)))
      y.fail(c, "cycles", fmt::format("expected a number of trajectory periods > 0, got {}", cycles));
    s.options.duration = cycles * period;
    if (const std::string why = duration_problem(s.options.duration, rate); !why.empty())
      y.fail(c, "cycles", fmt::format("{:g} cycles of the {:g} s period last {:g} s: {}", cycles, period, s.options.duration, why));
  } else if (const YAML::Node d = root["duration"]) {
    s.options.duration = y.as_number(d, "duration");
    if (const std::string why = duration_problem(s.options.duration, rate); !why.empty()) y.fail(d, "duration", why);
  } else {
    s.options.duration = period;
    if (const std::string why = duration_problem(s.options.duration, rate); !why.empty())
      y.fail(Y::key_of(root, "trajectory"), "duration", fmt::format("the default, one trajectory period of {:g} s: {}", period, why));
  }
  if (root["noise"]) {
    const YAML::Node nz = root["noise"];
    y.only_keys(nz, "noise", {"current_sigma", "joint_torque_sigma"});
    // per joint (or one for all), each >= 0
    const auto sigmas = [&](const char* key, const char* unit, std::vector<double>& out) {
      const VectorJ sg = y.vec(nz, "noise", key, n, true);
      for (int j = 0; j < n; ++j) {
        if (!(sg[j] >= 0.0)) y.fail(nz[key], std::string("noise.") + key, fmt::format("must be >= 0{}, got {}", unit, sg[j]));
        out.push_back(sg[j]);
      }
    };
    // (a noise block with neither is named by the one it had to have before the sensors: current_sigma)
    if (nz["current_sigma"] || !nz["joint_torque_sigma"]) sigmas("current_sigma", "", s.current_sigma);
    if (nz["joint_torque_sigma"]) {
      if (!s.options.joint_torque_sensors)
        y.fail(nz["joint_torque_sigma"], "noise.joint_torque_sigma", "the joint torque sensors' noise needs 'joint_torque_sensors: true'");
      sigmas("joint_torque_sigma", " [N·m]", s.joint_torque_sigma);
    }
  }
  // stops of the program (an operator's pause, a protective or an emergency stop): each at its line
  if (const YAML::Node sl = root["stops"]) {
    if (!sl.IsSequence()) y.fail(sl, "stops", "expected a list of stops");
    double free_from = 0.0;
    for (size_t k = 0; k < sl.size(); ++k) {
      const YAML::Node st = sl[k];
      const std::string p = fmt::format("stops[{}]", k);
      y.only_keys(st, p, {"kind", "at", "hold", "stopping_time"});
      StopSpec sp;
      const std::string kind = y.text(st, p, "kind", "");
      if (kind == "pause") sp.kind = StopKind::Pause;
      else if (kind == "protective") sp.kind = StopKind::Protective;
      else if (kind == "emergency") sp.kind = StopKind::Emergency;
      else y.fail(st["kind"] ? st["kind"] : st, p + ".kind", fmt::format("expected pause, protective or emergency, got '{}'", kind));
      sp.at = y.number(st, p, "at");
      if (!(sp.at >= 0.0 && sp.at < s.options.duration))
        y.fail(st["at"], p + ".at", fmt::format("expected a time from 0 s to the end of the run ({} s), got {}", s.options.duration, sp.at));
      if (sp.at < free_from)
        y.fail(st["at"], p + ".at", fmt::format("expected a time after the previous stop has resumed ({:g} s), got {}: stops in "
                                                "time order, one at a time", free_from, sp.at));
      sp.stopping_time = y.number_or(st, p, "stopping_time", sp.stopping_time);
      if (!(sp.stopping_time > 0.0 && sp.stopping_time <= kMaxStoppingTime))
        y.fail(st["stopping_time"], p + ".stopping_time",
               fmt::format("expected more than 0 and at most {:g} s, got {}", kMaxStoppingTime, sp.stopping_time));
      sp.hold = y.number_or(st, p, "hold", std::max(sp.hold, min_stop_hold(sp)));
      if (!(sp.hold >= min_stop_hold(sp) && std::isfinite(sp.hold)))
        y.fail(st["hold"], p + ".hold",
               fmt::format("expected at least {:g} s for a{} {} stop with a stopping_time of {:g} s, got {}", min_stop_hold(sp),
                           sp.kind == StopKind::Emergency ? "n" : "", kind, sp.stopping_time, sp.hold));
      free_from = sp.at + sp.hold + sp.stopping_time;
      s.options.stops.push_back(sp);
    }
  }
  try {
    s.options.validate(n);  // each field is checked above at its line; this catches what they miss
  } catch (const InvalidArgument& e) {
    y.fail(root, "", e.what());
  }
  // the commanded trajectory stays inside the joint limits over the run (the controller would
  // otherwise drive the arm through its end stops or faster than its drives turn)
  if (const std::string v = trajectory_limits ? joint_limit_violation(*s.trajectory, m, s.options.duration, rate) : std::string();
      !v.empty())
    y.fail(Y::key_of(root, "trajectory"), "trajectory", v);
  s.trajectory_line = Y::key_of(root, "trajectory").Mark().line + 1;
  if (const YAML::Node fl = root["faults"]) {
    if (!fl.IsSequence()) y.fail(fl, "faults", "expected a list of faults");
    for (size_t k = 0; k < fl.size(); ++k) {
      const YAML::Node f = fl[k];
      const std::string p = fmt::format("faults[{}]", k);
      if (!f.IsMap()) y.fail(f, p, "expected a mapping of keys");
      FaultSpec fs;
      fs.type = fault_type(y, f, p);
      // each type takes its own keys: another type's key would be ignored silently (a stuck
      // current's 'magnitude', a resistance's 'link', a collision's 'end', which its duration sets)
      const std::set<std::string> keys = fault_keys(fs.type);
      y.only_keys(f, p, keys);
      fs.onset = y.number(f, p, "onset");
      if (!(fs.onset >= 0.0)) y.fail(f["onset"], p + ".onset", fmt::format("must be >= 0 s, got {}", fs.onset));
      fs.ramp = y.number_or(f, p, "ramp", 0.0);
      if (!(fs.ramp >= 0.0)) y.fail(f["ramp"], p + ".ramp", fmt::format("must be >= 0 s, got {}", fs.ramp));
      fs.end = y.number_or(f, p, "end", std::numeric_limits<double>::infinity());
      if (!(fs.end > fs.onset)) y.fail(f["end"], p + ".end", fmt::format("must be after onset ({} s), got {}", fs.onset, fs.end));
      // (the keys a type takes say what it needs: one list, fault_keys)
      if (keys.count("joint")) {
        // users count joints from 1 (J1..J6), as the papers do
        if (!f["joint"]) y.fail(f, p + ".joint", "missing required field");
        const int j = y.integer(f, p, "joint", 0);
        if (j < 1 || j > n) y.fail(f["joint"] ? f["joint"] : f, p + ".joint", fmt::format("expected 1 to {}, got {}", n, j));
        fs.joint = j - 1;
      }
      if (keys.count("magnitude")) {
        fs.magnitude = y.number(f, p, "magnitude");
        if (!std::isfinite(fs.magnitude)) y.fail(f["magnitude"], p + ".magnitude", fmt::format("expected a finite number, got {}", fs.magnitude));
      }
      if (fs.type == FaultType::Resistance && !(fs.magnitude > 0.0))
        y.fail(f["magnitude"], p + ".magnitude",
               fmt::format("expected extra friction > 0 N·m (it opposes the motion), got {}", fs.magnitude));
      if (fs.type == FaultType::FrictionGrowth && !(fs.magnitude > -1.0))
        y.fail(f["magnitude"], p + ".magnitude",
               fmt::format("expected a relative change > -1 (friction x (1 + magnitude) stays positive), got {}", fs.magnitude));
      // (a value in mA: 300 "A" wrote a recording every reader then refuses as mA)
      if (fs.type == FaultType::CurrentOffset && !(std::abs(fs.magnitude) <= kMaxCurrentOffset))
        y.fail(f["magnitude"], p + ".magnitude",
               fmt::format("expected a current offset within ±{:g} A, got {} (in mA? give amperes)", kMaxCurrentOffset, fs.magnitude));
      if (fs.type == FaultType::Collision) {
        if (!f["link"]) y.fail(f, p + ".link", "missing required field");
        const int l = y.integer(f, p, "link", 0);
        if (l < 1 || l > n) y.fail(f["link"] ? f["link"] : f, p + ".link", fmt::format("expected 1 to {}, got {}", n, l));
        fs.link = l - 1;
        if (f["point"]) fs.point = y.finite_vec(f, p, "point", 3);
        if (f["direction"]) fs.direction = y.finite_vec(f, p, "direction", 3);
        if (!(fs.direction.norm() > 0)) y.fail(f["direction"], p + ".direction", "must not be zero");
        fs.duration = y.number_or(f, p, "duration", 0.05);
        if (!(fs.duration > 0)) y.fail(f["duration"], p + ".duration", fmt::format("must be > 0 s, got {}", fs.duration));
        if (!(fs.magnitude > 0)) y.fail(f["magnitude"], p + ".magnitude", fmt::format("must be > 0 N·m, got {}", fs.magnitude));
        fs.end = fs.onset + fs.duration;
      }
      if (fs.type == FaultType::MissedPick && !s.options.streams_payload)
        y.fail(f["type"], p + ".type",
               "a missed_pick is a payload the program declares and the arm does not carry: it needs 'streams_payload: true' (without "
               "the declaration in the stream nothing of it shows)");
      if (fs.type == FaultType::PayloadPick || fs.type == FaultType::MissedPick) {
        fs.payload.mass = y.number(f, p, "mass");
        if (!(fs.payload.mass > 0)) y.fail(f["mass"], p + ".mass", fmt::format("must be > 0 kg, got {}", fs.payload.mass));
        if (fs.payload.mass > m.payload_limit()) y.fail(f["mass"], p + ".mass", payload_above_limit(m, fs.payload.mass));
        if (f["com"]) fs.payload.com = payload_com(y, f, p);
      }
      if (f["declare_delay"]) {
        fs.declare_delay = y.number(f, p, "declare_delay");
        if (!(std::abs(fs.declare_delay) <= kMaxDeclareDelay))
          y.fail(f["declare_delay"], p + ".declare_delay",
                 fmt::format("expected a time from -{0:g} to {0:g} s (the program declares the part this long after the grip; "
                             "negative: before it), got {1}",
                             kMaxDeclareDelay, fs.declare_delay));
        if (!(fs.onset + fs.declare_delay >= 0.0))
          y.fail(f["declare_delay"], p + ".declare_delay",
                 fmt::format("the declaration would come at {:g} s, before the run starts", fs.onset + fs.declare_delay));
        if (fs.declare_delay != 0.0 && !s.options.streams_payload)
          y.fail(f["declare_delay"], p + ".declare_delay",
                 "a declaration's timing needs 'streams_payload: true' (without it the stream carries no declaration)");
      }
      fs.io_bit = y.integer(f, p, "io_bit", 0);
      if (fs.io_bit < 0 || fs.io_bit > kMaxDigitalOutputBit)
        y.fail(f["io_bit"], p + ".io_bit",
               fmt::format("expected a digital output bit from 0 to {} (standard 0-7, configurable 8-15, tool 16-17), got {}",
                           kMaxDigitalOutputBit, fs.io_bit));
      if (fs.type == FaultType::TimestampJitter) {
        const double max_jitter = kMaxJitterFraction / rate;
        // (0 was labelled a fault that changes nothing: audit of session 56)
        if (!(fs.magnitude > 0.0 && fs.magnitude <= max_jitter))
          y.fail(f["magnitude"], p + ".magnitude",
                 fmt::format("expected a jitter sigma above 0 and at most {:g} s (an eighth of the {:g} s sample period), got {} s",
                             max_jitter, 1.0 / rate, fs.magnitude));
      }
      if (fs.type == FaultType::DroppedSamples) {
        fs.period = y.number_or(f, p, "period", 0.0);
        if (!(fs.magnitude >= 1) || fs.magnitude != std::floor(fs.magnitude))
          y.fail(f["magnitude"], p + ".magnitude", fmt::format("expected a whole number of samples >= 1, got {}", fs.magnitude));
        if (!(fs.period >= 0.0) || !std::isfinite(fs.period))
          y.fail(f["period"], p + ".period", fmt::format("expected a repeat period >= 0 s (0: once), got {}", fs.period));
      }
      // the fault's own fields first, then whether it happens at all in this run
      if (!(fs.onset < s.options.duration))
        y.fail(f["onset"], p + ".onset", fmt::format("expected a time before the end of the run ({} s), got {} s: the {} would never fire",
                                                     s.options.duration, fs.onset, to_string(fs.type)));
      // and whether it happens as labelled: the label claims the full magnitude, which a ramp that
      // ends after the run never reaches (scored "not detected" for a fault that never was)
      if (fs.onset + fs.ramp > s.options.duration + 1e-9)
        y.fail(f["ramp"], p + ".ramp",
               fmt::format("the ramp from {} s over {} s ends after the run ({} s): the {} would never reach its magnitude, which its label "
                           "claims; shorten the ramp or lengthen the run",
                           fs.onset, fs.ramp, s.options.duration, to_string(fs.type)));
      // (an end after the run stayed in the label, a time the fault never reached: audit of session 56)
      if (f["end"] && fs.end > s.options.duration + 1e-9)
        y.fail(f["end"], p + ".end",
               fmt::format("the {} would end at {} s, after the run ({} s), which its label would claim; leave 'end' out (it lasts to "
                           "the end) or end it by {} s",
                           to_string(fs.type), fs.end, s.options.duration, s.options.duration));
      if (fs.declare_delay != 0.0 && !(fs.onset + fs.declare_delay < s.options.duration))
        y.fail(f["declare_delay"], p + ".declare_delay",
               fmt::format("the declaration would come at {:g} s, not before the end of the run ({} s): the stream would never show it",
                           fs.onset + fs.declare_delay, s.options.duration));
      if (fs.type == FaultType::Collision && fs.onset + fs.duration > s.options.duration + 1e-9)
        y.fail(f["duration"], p + ".duration",
               fmt::format("the contact from {} s for {} s lasts past the end of the run ({} s)", fs.onset, fs.duration, s.options.duration));
      if (fs.type == FaultType::Collision && !(fs.point.norm() <= kMaxContactPointDistance))
        y.fail(f["point"], p + ".point",
               fmt::format("expected a contact point within {:g} m of the link's frame, got one {:.4g} m away (in mm? give metres)",
                           kMaxContactPointDistance, fs.point.norm()));
      if (fs.type == FaultType::DroppedSamples) {
        const double left = std::floor((s.options.duration - fs.onset) * rate + 1e-9);
        if (fs.magnitude > left)
          y.fail(f["magnitude"], p + ".magnitude",
                 fmt::format("expected at most the {:g} samples left after the onset, got {:g}: the stream would end there, which is no "
                             "gap the monitor can see",
                             left, fs.magnitude));
      }
      s.faults.push_back(fs);
    }
    // a payload fault's label is the change of the mass the flange carries: a pick replaces what it
    // held (the simulator's set_payload), a loss takes all of it; in the order they happen
    std::vector<size_t> order(s.faults.size());
    for (size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return s.faults[a].onset < s.faults[b].onset; });
    // a missed pick's label is what the arm carries less than the controller now believes (the
    // truth does not change; the declaration does)
    double carried = s.options.payload.mass;
    for (size_t k : order) {
      FaultSpec& fs = s.faults[k];
      if (fs.type == FaultType::PayloadPick) {
        fs.magnitude = fs.payload.mass - carried;
        carried = fs.payload.mass;
      } else if (fs.type == FaultType::MissedPick) {
        fs.magnitude = carried - fs.payload.mass;
      } else if (fs.type == FaultType::PayloadLoss) {
        if (!(carried > 0.0))
          y.fail(fl[k], fmt::format("faults[{}]", k),
                 fmt::format("a payload_loss at {} s, but the arm carries nothing then (give the scenario a 'payload' or an earlier "
                             "payload_pick)",
                             fs.onset));
        fs.magnitude = -carried;
        carried = 0.0;
      }
    }
  }
  return s;
}

Scenario load_scenario(const std::string& path, const std::string& robot, bool trajectory_limits) {
  refuse_directory_input(path);
  std::ifstream f(path);
  if (!f) throw ParseError(path, 0, "", "cannot open the scenario file");
  std::stringstream ss;
  ss << f.rdbuf();
  return parse_scenario(ss.str(), path, robot, trajectory_limits);
}

void override_duration(Scenario& s, double duration, const std::string& option, bool trajectory_limits) {
  if (const std::string why = duration_problem(duration, s.options.rate); !why.empty())
    throw InvalidArgument(fmt::format("{}: {}", option, why));
  // a longer run may reach a part of the trajectory the file's own duration did not
  const model::RobotModel m = model::load_robot(s.robot);
  if (const std::string v = trajectory_limits ? joint_limit_violation(*s.trajectory, m, duration, s.options.rate) : std::string();
      !v.empty())
    throw InvalidArgument(fmt::format("{} {} s: {} ({}:{}, trajectory)", option, duration, v, s.path, s.trajectory_line));
  s.options.duration = duration;
  for (size_t k = 0; k < s.faults.size(); ++k)
    if (!(s.faults[k].onset < duration))
      log::warn(fmt::format("{} {} s ends the run before faults[{}] ({}, onset {} s) of {} starts: it does not fire", option, duration, k,
                            to_string(s.faults[k].type), s.faults[k].onset, s.path));
}

std::unique_ptr<Simulator> make_simulator(const Scenario& s) {
  const model::RobotModel m = model::load_robot(s.robot);
  PlantTruth truth = default_truth(m, s.serial);
  for (size_t j = 0; j < s.current_sigma.size() && j < truth.joints.size(); ++j) truth.joints[j].current_sigma = s.current_sigma[j];
  for (size_t j = 0; j < s.joint_torque_sigma.size() && j < truth.joints.size(); ++j) truth.joints[j].torque_sigma = s.joint_torque_sigma[j];
  return std::make_unique<Simulator>(m, s.trajectory, truth, s.options, s.faults);
}

namespace {

constexpr FaultType kFaultTypes[] = {FaultType::Resistance,    FaultType::FrictionGrowth, FaultType::PayloadPick,
                                     FaultType::PayloadLoss,   FaultType::Collision,      FaultType::CurrentOffset,
                                     FaultType::StuckCurrent,  FaultType::DroppedSamples, FaultType::TimestampJitter,
                                     FaultType::MissedPick};

// the units of a fault type's magnitude in the labels
const char* units_of(FaultType t) {
  switch (t) {
    case FaultType::Resistance: case FaultType::Collision: return "N·m";
    case FaultType::FrictionGrowth: return "relative";
    case FaultType::PayloadPick: case FaultType::PayloadLoss: case FaultType::MissedPick: return "kg";
    case FaultType::CurrentOffset: return "A";
    case FaultType::StuckCurrent: return "";
    case FaultType::DroppedSamples: return "samples";
    case FaultType::TimestampJitter: return "s";
  }
  return "";
}

// a joint or link number of the labels (from 1), or null: none (-1 returned, 0-based otherwise)
int label_index(const JsonFields& f, const char* key) {
  if (f.need(key).is_null()) return -1;
  const int i = f.whole(key);
  if (i < 1 || i > kMaxDof) f.fail(key, fmt::format("expected null or a whole number from 1 to {}, got {}", kMaxDof, i));
  return i - 1;
}

}  // namespace

std::string labels_json(const Scenario& s) {
  nlohmann::json j;
  j["scenario"] = s.name;
  j["seed"] = s.options.seed;
  j["duration"] = s.options.duration;
  j["rate"] = s.options.rate;
  j["faults"] = nlohmann::json::array();
  for (const FaultSpec& f : s.faults) {
    nlohmann::json e;
    e["type"] = to_string(f.type);
    e["onset"] = f.onset;
    e["ramp"] = f.ramp;
    e["end"] = std::isfinite(f.end) ? nlohmann::json(f.end) : nlohmann::json(nullptr);
    e["magnitude"] = f.magnitude;
    e["joint"] = f.joint >= 0 ? nlohmann::json(f.joint + 1) : nlohmann::json(nullptr);
    e["link"] = f.link >= 0 ? nlohmann::json(f.link + 1) : nlohmann::json(nullptr);
    e["units"] = units_of(f.type);
    j["faults"].push_back(e);
  }
  return j.dump(2);
}

Labels parse_labels(const std::string& text, const std::string& origin) {
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw ParseError(origin, 0, "", "the file is empty, expected the labels JSON that twinwatch simulate writes beside a recording");
  const nlohmann::json j = parse_json(text, origin);
  if (!j.is_object())
    throw ParseError(origin, 0, "", fmt::format("expected a JSON object (the labels twinwatch simulate writes), got {}", json_brief(j)));
  const JsonFields top(j, origin, "");
  top.only({"scenario", "seed", "duration", "rate", "faults"});
  Labels l;
  l.scenario = top.text("scenario");
  const int seed = top.whole("seed");
  if (seed < 0) top.fail("seed", fmt::format("expected a whole number >= 0, got {}", seed));
  l.seed = static_cast<unsigned>(seed);
  l.duration = top.positive("duration");
  l.rate = top.positive("rate");
  const nlohmann::json& fl = top.need("faults");
  if (!fl.is_array()) top.fail("faults", fmt::format("expected an array of faults, got {}", json_brief(fl)));
  for (size_t k = 0; k < fl.size(); ++k) {
    const JsonFields f(fl[k], origin, json_element("faults", k));
    f.only({"type", "onset", "ramp", "end", "magnitude", "joint", "link", "units"});
    FaultLabel e;
    const std::string type = f.text("type");
    const auto* t = std::find_if(std::begin(kFaultTypes), std::end(kFaultTypes), [&](FaultType x) { return type == to_string(x); });
    if (t == std::end(kFaultTypes))
      f.fail("type", fmt::format("expected one of resistance, friction_growth, payload_pick, payload_loss, collision, current_offset, "
                                 "stuck_current, dropped_samples, timestamp_jitter, missed_pick; got \"{}\"", type));
    e.type = *t;
    e.onset = f.nonnegative("onset");
    e.ramp = f.nonnegative("ramp");
    if (!f.need("end").is_null()) {  // null: to the end of the run
      e.end = f.number("end");
      if (!(e.end > e.onset)) f.fail("end", fmt::format("expected null or a time after onset ({} s), got {}", e.onset, e.end));
    }
    e.magnitude = f.number("magnitude");
    e.joint = label_index(f, "joint");
    e.link = label_index(f, "link");
    e.units = f.text("units");
    if (e.units != units_of(e.type)) f.fail("units", fmt::format("expected \"{}\" (the units of {}), got \"{}\"", units_of(e.type), type, e.units));
    l.faults.push_back(e);
  }
  return l;
}

}  // namespace twinwatch::sim
