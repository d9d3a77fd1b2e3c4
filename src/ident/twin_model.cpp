#include "twinwatch/ident/twin_model.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "twinwatch/core/error.hpp"
#include "twinwatch/model/description_io.hpp"

#include "json_numbers.hpp"

namespace twinwatch::ident {

namespace {
// JSON has no NaN: write it as null and read null back as NaN
nlohmann::json numbers(const Eigen::VectorXd& v) {
  nlohmann::json a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(std::isfinite(v(i)) ? nlohmann::json(v(i)) : nlohmann::json(nullptr));
  return a;
}
Eigen::VectorXd numbers(const nlohmann::json& a, const std::string& origin, const std::string& field) {
  if (!a.is_array()) throw ParseError(origin, 0, field, "expected an array of numbers");
  Eigen::VectorXd v(static_cast<Eigen::Index>(a.size()));
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].is_null()) v(static_cast<Eigen::Index>(i)) = std::numeric_limits<double>::quiet_NaN();
    else if (a[i].is_number()) v(static_cast<Eigen::Index>(i)) = a[i].get<double>();
    else throw ParseError(origin, 0, fmt::format("{}[{}]", field, i), fmt::format("expected a number, got {}", a[i].type_name()));
  }
  return v;
}

// the optional "sequential" block (Cao's sequential model, sequential_model.hpp)
nlohmann::json sequential_to_json(const SequentialModel& m, int n) {
  nlohmann::json s;
  s["library"] = {{"motion_joints", m.library.motion_joints},
                  {"config_joints", m.library.config_joints},
                  {"harmonics", m.library.harmonics},
                  {"candidates", m.library.size(n)}};
  s["gravity_columns"] = m.gravity_columns;
  s["recordings"] = {{"quasi_static", m.quasi_static}, {"sine", m.sine}, {"general", m.general}};
  for (const auto& jm : m.joints) {
    nlohmann::json e;
    e["gravity"] = numbers(jm.gravity);
    e["coulomb"] = jm.coulomb;
    e["viscous"] = jm.viscous;
    e["intercept"] = jm.intercept;
    e["lasso_index"] = jm.lasso_index;
    e["lasso_value"] = jm.lasso_value;
    std::vector<std::string> names;
    for (int k : jm.lasso_index) names.push_back(m.library.name(n, k));
    e["lasso_terms"] = names;
    if (jm.payload.size() > 0) e["payload"] = numbers(jm.payload);
    e["lambda"] = jm.lambda;
    e["cv_rmse"] = jm.cv_rmse;
    e["train_rmse"] = jm.rmse;
    e["train_r2"] = jm.r2;
    s["joints"].push_back(e);
  }
  return s;
}

SequentialModel sequential_from_json(const nlohmann::json& s, int n, const std::string& origin) {
  auto need = [&](const nlohmann::json& o, const char* key, const std::string& path) -> const nlohmann::json& {
    if (!o.contains(key)) throw ParseError(origin, 0, path + key, "missing required field");
    return o.at(key);
  };
  SequentialModel m;
  const auto& lib = need(s, "library", "sequential.");
  if (lib.contains("motion_joints")) m.library.motion_joints = json_wholes(lib.at("motion_joints"), origin, "sequential.library.motion_joints");
  m.library.config_joints = json_wholes(need(lib, "config_joints", "sequential.library."), origin, "sequential.library.config_joints");
  m.library.harmonics = json_whole(need(lib, "harmonics", "sequential.library."), origin, "sequential.library.harmonics");
  try {
    m.library.validate(n);
  } catch (const InvalidArgument& e) {
    throw ParseError(origin, 0, "sequential.library", e.what());
  }
  const int p = m.library.size(n);
  m.gravity_columns = json_wholes(need(s, "gravity_columns", "sequential."), origin, "sequential.gravity_columns");
  for (int c : m.gravity_columns)
    if (c < 0 || c >= 10 * n) throw ParseError(origin, 0, "sequential.gravity_columns", fmt::format("column {} out of range 0..{}", c, 10 * n - 1));
  if (s.contains("recordings")) {
    m.quasi_static = s["recordings"].value("quasi_static", std::vector<std::string>{});
    m.sine = s["recordings"].value("sine", std::vector<std::string>{});
    m.general = s["recordings"].value("general", std::vector<std::string>{});
  }
  const auto& js = need(s, "joints", "sequential.");
  if (!js.is_array() || static_cast<int>(js.size()) != n)
    throw ParseError(origin, 0, "sequential.joints", fmt::format("expected {} joints, got {}", n, js.size()));
  for (size_t k = 0; k < js.size(); ++k) {
    const std::string f = fmt::format("sequential.joints[{}].", k);
    SequentialJoint jm;
    jm.gravity = numbers(need(js[k], "gravity", f), origin, f + "gravity");
    if (jm.gravity.size() != static_cast<Eigen::Index>(m.gravity_columns.size()))
      throw ParseError(origin, 0, f + "gravity", fmt::format("expected {} values (one per gravity column), got {}", m.gravity_columns.size(), jm.gravity.size()));
    jm.coulomb = need(js[k], "coulomb", f).get<double>();
    jm.viscous = need(js[k], "viscous", f).get<double>();
    jm.intercept = need(js[k], "intercept", f).get<double>();
    jm.lasso_index = json_wholes(need(js[k], "lasso_index", f), origin, f + "lasso_index");
    jm.lasso_value = need(js[k], "lasso_value", f).get<std::vector<double>>();
    if (jm.lasso_index.size() != jm.lasso_value.size())
      throw ParseError(origin, 0, f + "lasso_value", fmt::format("expected {} values (one per lasso_index), got {}", jm.lasso_index.size(), jm.lasso_value.size()));
    for (int i : jm.lasso_index)
      if (i < 0 || i >= p) throw ParseError(origin, 0, f + "lasso_index", fmt::format("candidate {} out of range 0..{}", i, p - 1));
    if (js[k].contains("payload")) {
      jm.payload = numbers(js[k]["payload"], origin, f + "payload");
      if (jm.payload.size() != n) throw ParseError(origin, 0, f + "payload", fmt::format("expected {} values, got {}", n, jm.payload.size()));
    }
    if (!jm.gravity.allFinite() || !jm.payload.allFinite()) throw ParseError(origin, 0, f + "gravity", "values must be finite numbers");
    jm.lambda = js[k].value("lambda", 0.0);
    jm.cv_rmse = js[k].value("cv_rmse", 0.0);
    jm.rmse = js[k].value("train_rmse", 0.0);
    jm.r2 = js[k].value("train_r2", 0.0);
    m.joints.push_back(std::move(jm));
  }
  for (size_t k = 1; k < m.joints.size(); ++k)
    if (m.joints[k].payload.size() != m.joints[0].payload.size())
      throw ParseError(origin, 0, fmt::format("sequential.joints[{}].payload", k), "present on some joints only");
  return m;
}
// Current factor of a joint for its power direction: 1 motoring, c_gen back-driven (tau qd < 0).
// Within |qd| of a few blend widths the switch is smooth: the measured velocity's sign there is no
// better than its resolution (a finite difference of encoder counts), and the drive switches on
// the true velocity, so a hard switch on the measured one puts a jump of (1 - c_gen) tau / g into
// the residual at every reversal of a loaded joint. blend <= 0: the hard switch.
double direction_factor(double c_gen, double tau, double qd, double blend) {
  if (!(blend > 0.0)) return tau * qd < 0.0 ? c_gen : 1.0;
  const double x = (tau >= 0.0 ? qd : -qd) / blend;
  // beyond |x| = 20, tanh(x) is +-1 to the last bit (1 - tanh < 1e-17): skip the call (per sample
  // and joint in the monitor, where most samples are far from a reversal)
  if (x > 20.0) return 1.0;
  if (x < -20.0) return c_gen;
  const double w = 0.5 * (1.0 - std::tanh(x));  // 1 back-driven, 0 motoring
  return 1.0 + (c_gen - 1.0) * w;
}

}  // namespace

TwinModel::TwinModel(std::string robot, const model::RobotModel& model)
    : robot_name_(std::move(robot)),
      robot_(std::make_shared<model::RobotModel>(model)),
      data_(std::make_shared<model::DynamicsData>(model)) {
  robot_->clear_payload();
}

void TwinModel::regress(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, model::RegressorMatrix& Y,
                        VectorJ& tau_payload) const {
  const int n = robot_->n_dof();
  model::regressor(*robot_, *data_, q, qd, qdd, Y);
  tau_payload.setZero(n);
  if (payload_.mass > 0.0) {
    // the payload's standard parameters in the last body frame times the last link's columns
    const model::StandardParameters pi = payload_.expressed_in(robot_->description().flange).to_standard_parameters();
    tau_payload = Y.block(0, 10 * (n - 1), n, 10) * pi;
  }
}

void TwinModel::friction_row(int j, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature,
                             Eigen::Ref<Eigen::Matrix<double, kFrictionColumns, 1>> row) const {
  const double v = qd[j];
  const double T = temperature.size() > j && std::isfinite(temperature[j]) ? temperature[j] : temperature_ref;
  row(kCoulomb) = v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0);
  row(kViscous) = v;
  row(kOffset) = 1.0;
  row(kArmature) = qdd[j];
  row(kViscousTemperature) = v * (T - temperature_ref);
}

void TwinModel::sync_fitted() const {
  // per sample: one byte compare of what the fitted copy was made from (bitwise: a NaN in beta
  // compares equal to itself here, so it does not re-sync on every call)
  const auto bytes_equal = [](const double* a, const double* b, Eigen::Index n) {
    return std::memcmp(a, b, static_cast<size_t>(n) * sizeof(double)) == 0;
  };
  const bool same = fitted_ && fitted_columns_ == base_columns && fitted_beta_.size() == beta.size() &&
                    bytes_equal(fitted_beta_.data(), beta.data(), beta.size()) && fitted_payload_.mass == payload_.mass &&
                    bytes_equal(fitted_payload_.com.data(), payload_.com.data(), 3) &&
                    bytes_equal(fitted_payload_.inertia_com.data(), payload_.inertia_com.data(), 9);
  if (same) return;
  const int n = robot_->n_dof();
  Eigen::VectorXd pi = Eigen::VectorXd::Zero(10 * n);
  for (size_t c = 0; c < base_columns.size(); ++c) pi(base_columns[c]) = beta(static_cast<Eigen::Index>(c));
  if (!fitted_) fitted_.emplace(*robot_);
  fitted_->set_standard_parameters(pi);
  fitted_->set_payload(payload_);
  if (!fitted_data_) fitted_data_.emplace(*fitted_);
  fitted_columns_ = base_columns;
  fitted_beta_ = beta;
  fitted_payload_ = payload_;
}

void TwinModel::predict_sequential(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, VectorJ& torque,
                                   VectorJ& current) const {
  // payload torque first (it uses Y_), then the gravity regressor Yg = Y(q, 0, 0) into Y_
  const int n = robot_->n_dof();
  VectorJ tau_p = VectorJ::Zero(n);
  if (payload_.mass > 0.0 && sequential->has_payload()) regress(q, qd, qdd, Y_, tau_p);
  const VectorJ zero = VectorJ::Zero(n);
  model::regressor(*robot_, *data_, q, zero, zero, Y_);
  sequential->predict(q, qd, qdd, Y_, tau_p, current);
  torque.resize(n);
  for (int j = 0; j < n; ++j) torque[j] = current[j] * joints[static_cast<size_t>(j)].gain;
}

void TwinModel::predict_torque(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature, VectorJ& torque,
                               const FrictionMemory* memory) const {
  if (sequential || learned) {
    VectorJ current;
    return predict(q, qd, qdd, temperature, torque, current, memory);
  }
  physics_torque(q, qd, qdd, temperature, torque, memory);
}

void TwinModel::physics_torque(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature, VectorJ& torque,
                               const FrictionMemory* memory, const VectorJ* qdd2, VectorJ* torque2) const {
  sync_fitted();
  const int n = robot_->n_dof();
  const bool pair = qdd2 != nullptr && torque2 != nullptr;
  const VectorJ& tau_rb = pair ? model::rnea_pair(*fitted_, *fitted_data_, q, qd, qdd, *qdd2, *torque2)
                               : model::rnea(*fitted_, *fitted_data_, q, qd, qdd);
  torque.resize(n);
  Eigen::Matrix<double, kFrictionColumns, 1> f;
  for (int j = 0; j < n; ++j) {
    const JointDrive& d = joints[static_cast<size_t>(j)];
    friction_row(j, qd, qdd, temperature, f);
    double tau_f = f.dot(d.friction);
    // low-speed friction: the memory's departure from steady sliding, and the Stribeck rise
    const double s = qd[j] > 0.0 ? 1.0 : (qd[j] < 0.0 ? -1.0 : 0.0);
    if (memory != nullptr && d.presliding_alpha > 0.0 && memory->primed) tau_f += d.presliding * (memory->h[j] - s);
    if (d.stribeck_velocity > 0.0) tau_f += d.stribeck * stribeck_shape(qd[j], d.stribeck_velocity);
    torque[j] = tau_rb[j] + tau_f;
    // the second acceleration changes the rigid body (rnea_pair) and the armature term only
    if (pair) (*torque2)[j] += tau_f + d.friction(kArmature) * ((*qdd2)[j] - qdd[j]);
  }
}

void TwinModel::drive_current(const VectorJ& qd, const VectorJ& torque, VectorJ& current) const {
  const int n = robot_->n_dof();
  current.resize(n);
  for (int j = 0; j < n; ++j) {
    const JointDrive& d = joints[static_cast<size_t>(j)];
    current[j] = direction_factor(d.c_gen, torque[j], qd[j], direction_blend) * torque[j] / d.gain;
  }
}

void TwinModel::predict(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature, VectorJ& torque,
                        VectorJ& current, const FrictionMemory* memory) const {
  if (sequential) return predict_sequential(q, qd, qdd, torque, current);
  physics_torque(q, qd, qdd, temperature, torque, memory);
  drive_current(qd, torque, current);
  if (learned) apply_learned(q, qd, qdd, temperature, torque, current);
}

void TwinModel::predict_pair(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& qdd2, const VectorJ& temperature,
                             VectorJ& torque, VectorJ& current, VectorJ& torque2, const FrictionMemory* memory) const {
  if (sequential || learned) {
    predict(q, qd, qdd, temperature, torque, current, memory);
    return predict_torque(q, qd, qdd2, temperature, torque2, memory);
  }
  physics_torque(q, qd, qdd, temperature, torque, memory, &qdd2, &torque2);
  drive_current(qd, torque, current);
}

void TwinModel::apply_learned(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature, VectorJ& torque,
                              VectorJ& current) const {
  // network output: the current itself (mlp) or a correction of the physics current (hybrid);
  // torque through the drive gain, with the direction factor of the resulting current
  VectorJ y;
  learned->evaluate(q, qd, qdd, temperature, y);
  const int n = robot_->n_dof();
  for (int j = 0; j < n; ++j) {
    const JointDrive& d = joints[static_cast<size_t>(j)];
    if (learned->role == LearnedRole::Current) {
      current[j] = y[j];
      torque[j] = d.gain * y[j] / direction_factor(d.c_gen, y[j], qd[j], direction_blend);
    } else {
      const double c = direction_factor(d.c_gen, torque[j], qd[j], direction_blend);
      current[j] += y[j];
      torque[j] += d.gain * y[j] / c;
    }
  }
}

void TwinModel::predict_current(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature,
                                VectorJ& current, const FrictionMemory* memory) const {
  VectorJ tau;
  predict(q, qd, qdd, temperature, tau, current, memory);
}

// Low-speed friction. Coulomb sign(qd) is the friction of steady sliding. A harmonic drive's
// friction has a memory instead [HESR §II; Dahl]: through a reversal it turns over a pre-sliding
// distance 1/alpha, not in one sample, and a joint that stops keeps the friction of the direction it
// came from (static friction holding the controller's error) -- a stateless twin predicts none
// there, which left the triangle's stops 2-9 sigma off (docs/validation.md). The state h follows the
// Dahl law in the displacement clock (presliding_step) and enters as presliding * (h - sign(qd)),
// zero in steady motion, so the main fit's Coulomb term keeps its meaning. The Stribeck rise is
// stateless: stribeck * sign(qd) exp(-(qd/vs)^2).
void TwinModel::advance(FrictionMemory& m, const VectorJ& q) const {
  const int n = robot_->n_dof();
  if (!m.primed) {
    m.h = VectorJ::Zero(n);
    m.q_prev = q;
    m.primed = true;
    return;
  }
  for (int j = 0; j < n; ++j) {
    m.h[j] = presliding_step(m.h[j], q[j] - m.q_prev[j], joints[static_cast<size_t>(j)].presliding_alpha);
    m.q_prev[j] = q[j];
  }
}

std::string TwinModel::to_json() const {
  nlohmann::json j;
  j["format"] = "twinwatch-twin";
  j["version"] = 1;
  j["robot"] = robot_name_;
  j["method"] = method;
  j["created"] = created;
  j["recordings"] = recordings;
  j["temperature_ref"] = temperature_ref;
  j["direction_blend"] = direction_blend;
  j["payload"] = {{"mass", payload_.mass}, {"com", {payload_.com.x(), payload_.com.y(), payload_.com.z()}}};
  j["gains_absolute"] = gains_absolute;
  if (!monitor_json.empty()) j["monitor"] = nlohmann::json::parse(monitor_json);
  if (learned) j["learned"] = nlohmann::json::parse(learned->to_json());
  if (!friction_json.empty()) j["friction_models"] = nlohmann::json::parse(friction_json);
  j["base_columns"] = base_columns;
  j["beta"] = numbers(beta);
  for (const auto& m : joints) {
    nlohmann::json e;
    e["gain"] = m.gain;
    e["c_gen"] = m.c_gen;
    e["gain_identified"] = m.gain_identified;
    e["friction"] = numbers(Eigen::VectorXd(m.friction));
    e["friction_columns"] = {"coulomb", "viscous", "offset", "armature", "viscous_temperature"};
    if (m.presliding_alpha > 0.0 || m.stribeck_velocity > 0.0)
      e["low_speed_friction"] = {{"presliding_alpha", m.presliding_alpha},
                                 {"presliding", m.presliding},
                                 {"stribeck_velocity", m.stribeck_velocity},
                                 {"stribeck", m.stribeck}};
    e["train_rmse"] = m.rmse;
    e["train_r2"] = m.r2;
    j["joints"].push_back(e);
  }
  if (sequential) j["sequential"] = sequential_to_json(*sequential, n_dof());
  return j.dump(1);
}

TwinModel TwinModel::from_json(const std::string& text, const std::string& origin) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw ParseError(origin, 0, "", fmt::format("not valid JSON: {}", e.what()));
  } catch (const nlohmann::json::out_of_range& e) {  // a number beyond a double ("1e400")
    throw ParseError(origin, 0, "", fmt::format("expected numbers within the range of a double: {}", e.what()));
  }
  auto need = [&](const nlohmann::json& o, const char* key, const std::string& path) -> const nlohmann::json& {
    if (!o.contains(key)) throw ParseError(origin, 0, path + key, "missing required field");
    return o.at(key);
  };
  // (value() would throw a json type_error for a file that is not an object or a format that is not text)
  if (!j.is_object())
    throw ParseError(origin, 0, "", fmt::format("expected a JSON object (a twin file from twinwatch identify), got {}", j.type_name()));
  if (!j.contains("format") || j.at("format") != "twinwatch-twin")
    throw ParseError(origin, 0, "format", fmt::format("expected \"twinwatch-twin\" (is this a twin file from twinwatch identify?), got {}",
                                                      j.contains("format") ? j.at("format").dump() : "nothing"));
  try {
    const std::string robot = need(j, "robot", "").get<std::string>();
    TwinModel t(robot, model::load_robot(robot));
    t.method = j.value("method", "physics");
    t.created = j.value("created", "");
    t.recordings = j.value("recordings", std::vector<std::string>{});
    t.temperature_ref = j.value("temperature_ref", 35.0);
    t.direction_blend = j.value("direction_blend", 0.0);  // files before it: the hard switch
    const auto& js = need(j, "joints", "");
    if (!js.is_array() || static_cast<int>(js.size()) != t.n_dof())
      throw ParseError(origin, 0, "joints", fmt::format("expected {} joints for robot '{}', got {}", t.n_dof(), robot, js.size()));
    t.gains_absolute = j.value("gains_absolute", false);
    if (j.contains("monitor")) t.monitor_json = j["monitor"].dump();
    if (j.contains("learned")) t.learned = LearnedModel::from_json(j["learned"].dump(), origin, t.n_dof());
    if (j.contains("friction_models")) t.friction_json = j["friction_models"].dump();
    t.base_columns = json_wholes(need(j, "base_columns", ""), origin, "base_columns");
    for (int c : t.base_columns)
      if (c < 0 || c >= 10 * t.n_dof()) throw ParseError(origin, 0, "base_columns", fmt::format("column {} out of range 0..{}", c, 10 * t.n_dof() - 1));
    t.beta = numbers(need(j, "beta", ""), origin, "beta");
    if (static_cast<size_t>(t.beta.size()) != t.base_columns.size())
      throw ParseError(origin, 0, "beta", fmt::format("expected {} values (one per base column), got {}", t.base_columns.size(), t.beta.size()));
    if (!t.beta.allFinite()) throw ParseError(origin, 0, "beta", "values must be finite numbers");
    for (size_t k = 0; k < js.size(); ++k) {
      const std::string p = fmt::format("joints[{}].", k);
      JointDrive m;
      m.gain = need(js[k], "gain", p).get<double>();
      if (!(m.gain > 0.0)) throw ParseError(origin, 0, p + "gain", fmt::format("must be > 0, got {}", m.gain));
      m.c_gen = js[k].value("c_gen", 1.0);
      m.gain_identified = js[k].value("gain_identified", true);
      const Eigen::VectorXd f = numbers(need(js[k], "friction", p), origin, p + "friction");
      if (f.size() != kFrictionColumns)
        throw ParseError(origin, 0, p + "friction", fmt::format("expected {} values, got {}", int(kFrictionColumns), f.size()));
      m.friction = f;
      if (js[k].contains("low_speed_friction")) {
        // files before it: none (plain Coulomb)
        const auto& l = js[k]["low_speed_friction"];
        const std::string lp = p + "low_speed_friction.";
        auto nonneg = [&](const char* key) {
          const double v = need(l, key, lp).get<double>();
          if (!std::isfinite(v) || v < 0.0) throw ParseError(origin, 0, lp + key, fmt::format("must be a finite number >= 0, got {}", v));
          return v;
        };
        m.presliding_alpha = nonneg("presliding_alpha");
        m.stribeck_velocity = nonneg("stribeck_velocity");
        m.presliding = need(l, "presliding", lp).get<double>();
        m.stribeck = need(l, "stribeck", lp).get<double>();
        if (!std::isfinite(m.presliding) || !std::isfinite(m.stribeck))
          throw ParseError(origin, 0, lp + "presliding", "presliding and stribeck must be finite numbers");
      }
      m.rmse = js[k].value("train_rmse", 0.0);
      m.r2 = js[k].value("train_r2", 0.0);
      t.joints.push_back(m);
    }
    if (j.contains("sequential")) t.sequential = sequential_from_json(j["sequential"], t.n_dof(), origin);
    if (j.contains("payload")) {
      model::RigidBodyInertia p;
      p.mass = j["payload"].value("mass", 0.0);
      const auto c = j["payload"].value("com", std::vector<double>{0, 0, 0});
      if (c.size() == 3) p.com = Eigen::Vector3d(c[0], c[1], c[2]);
      t.set_payload(p);
    }
    return t;
  } catch (const nlohmann::json::type_error& e) {
    throw ParseError(origin, 0, "", fmt::format("wrong type: {}", e.what()));
  } catch (const InvalidArgument& e) {
    throw ParseError(origin, 0, "robot", e.what());
  }
}

void TwinModel::save(const std::string& path) const {
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open for writing");
  f << to_json() << '\n';
}

TwinModel TwinModel::load(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw ParseError(path, 0, "", "cannot open the twin file");
  std::stringstream ss;
  ss << f.rdbuf();
  return from_json(ss.str(), path);
}

}  // namespace twinwatch::ident
