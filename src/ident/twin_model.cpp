#include "twinwatch/ident/twin_model.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"
#include "twinwatch/core/json_fields.hpp"
#include "twinwatch/core/log.hpp"
#include "twinwatch/core/numbers.hpp"
#include "twinwatch/model/description_io.hpp"

#include "json_numbers.hpp"

namespace twinwatch::ident {

namespace {
// the names of the friction columns, in their order (FrictionColumn)
const std::vector<std::string> kFrictionColumnNames{"coulomb", "viscous", "offset", "armature", "viscous_temperature"};
// the methods identify writes (IdentOptions, identify --method)
const std::array<std::string, 4> kMethods{"physics", "mlp", "hybrid", "sequential"};
// the back-driven current factor a file may hold: c_gen = eta_motoring * eta_back-driven <= 1 for
// a drive (physics_ident.cpp pins the joint fit to [0.25, 1]); the alternating efficiency fit is
// unbounded and wrote up to 6.8 on the simulated UR3e (a joint hardly ever back-driven), so the
// file takes up to 10. Zero or less would zero or flip the back-driven current, and the learned
// block divides by it.
constexpr double kCGenFileMax = 10.0;

// JSON has no NaN: write it as null (the reader takes finite numbers only)
nlohmann::json numbers(const Eigen::VectorXd& v) {
  nlohmann::json a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(std::isfinite(v(i)) ? nlohmann::json(v(i)) : nlohmann::json(nullptr));
  return a;
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

SequentialModel sequential_from_json(const nlohmann::json& block, int n, const std::string& origin) {
  const JsonFields s(block, origin, "sequential");
  s.only({"library", "gravity_columns", "recordings", "joints"});
  SequentialModel m;
  const JsonFields lib = s.object("library");
  lib.only({"motion_joints", "config_joints", "harmonics", "candidates"});
  m.library.motion_joints = json_wholes(lib.need("motion_joints"), origin, lib.field("motion_joints"));
  m.library.config_joints = json_wholes(lib.need("config_joints"), origin, lib.field("config_joints"));
  m.library.harmonics = lib.whole("harmonics");
  try {
    m.library.validate(n);
  } catch (const InvalidArgument& e) {
    throw ParseError(origin, 0, "sequential.library", e.what());
  }
  const int p = m.library.size(n);
  if (const int c = lib.whole("candidates"); c != p)
    lib.fail("candidates", fmt::format("expected {} (the size of this library for {} joints), got {}", p, n, c));
  m.gravity_columns = json_wholes(s.need("gravity_columns"), origin, "sequential.gravity_columns");
  for (int c : m.gravity_columns)
    if (c < 0 || c >= 10 * n) throw ParseError(origin, 0, "sequential.gravity_columns", fmt::format("column {} out of range 0..{}", c, 10 * n - 1));
  const JsonFields rec = s.object("recordings");
  rec.only({"quasi_static", "sine", "general"});
  m.quasi_static = rec.texts("quasi_static");
  m.sine = rec.texts("sine");
  m.general = rec.texts("general");
  const nlohmann::json& js = s.need("joints");
  if (!js.is_array() || static_cast<int>(js.size()) != n)
    throw ParseError(origin, 0, "sequential.joints", fmt::format("expected {} joints, got {}", n, json_brief(js)));
  for (size_t k = 0; k < js.size(); ++k) {
    const JsonFields e(js[k], origin, json_element("sequential.joints", k));
    e.only({"gravity", "coulomb", "viscous", "intercept", "lasso_index", "lasso_value", "lasso_terms", "payload", "lambda", "cv_rmse",
            "train_rmse", "train_r2"});
    SequentialJoint jm;
    const std::vector<double> g = e.numbers("gravity");
    if (g.size() != m.gravity_columns.size())
      e.fail("gravity", fmt::format("expected {} values (one per gravity column), got {}", m.gravity_columns.size(), g.size()));
    jm.gravity = Eigen::Map<const Eigen::VectorXd>(g.data(), static_cast<Eigen::Index>(g.size()));
    jm.coulomb = e.number("coulomb");
    jm.viscous = e.number("viscous");
    // friction opposes motion: in current, whose sign convention may be either, the two levels
    // share one sign (identify holds them to it)
    if (jm.coulomb * jm.viscous < 0.0)
      e.fail("viscous", fmt::format("expected the sign of coulomb ({}) or 0 (friction opposes the motion), got {}", jm.coulomb, jm.viscous));
    jm.intercept = e.number("intercept");
    jm.lasso_index = json_wholes(e.need("lasso_index"), origin, e.field("lasso_index"));
    jm.lasso_value = e.numbers("lasso_value");
    if (jm.lasso_index.size() != jm.lasso_value.size())
      e.fail("lasso_value", fmt::format("expected {} values (one per lasso_index), got {}", jm.lasso_index.size(), jm.lasso_value.size()));
    for (int i : jm.lasso_index)
      if (i < 0 || i >= p) e.fail("lasso_index", fmt::format("candidate {} out of range 0..{}", i, p - 1));
    if (const auto terms = e.texts("lasso_terms"); terms.size() != jm.lasso_index.size())
      e.fail("lasso_terms", fmt::format("expected {} names (one per lasso_index), got {}", jm.lasso_index.size(), terms.size()));
    if (e.has("payload")) {  // only when a recording had a known payload
      const std::vector<double> h = e.numbers("payload", static_cast<size_t>(n));
      jm.payload = Eigen::Map<const Eigen::VectorXd>(h.data(), n);
    }
    jm.lambda = e.nonnegative("lambda");
    jm.cv_rmse = e.nonnegative("cv_rmse");
    jm.rmse = e.nonnegative("train_rmse");
    jm.r2 = e.number("train_r2");
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
// (x: the blend's argument, qd / blend, or a direction read with the target)
// beyond |x| = 20, tanh(x) is +-1 to the last bit (1 - tanh < 1e-17): the factor is 1 or c_gen
// without the call (per sample and joint in the monitor, where most samples are far from a reversal)
constexpr double kBlendSaturated = 20.0;

// the blend's tanh in single precision: 1e-7 relative on a factor in [c_gen, 1], far below its
// meaning, and cheaper where it is evaluated every sample (a wrist joint near standstill read with
// the target)
double blend_tanh(double x) { return static_cast<double>(std::tanh(static_cast<float>(x))); }

// the factor for the blend's argument x and its tanh t (tanh is odd: the torque's sign flips both)
double factor_with(double c_gen, double tau, double x, double t) {
  if (tau < 0.0) {
    x = -x;
    t = -t;
  }
  if (x > kBlendSaturated) return 1.0;
  if (x < -kBlendSaturated) return c_gen;
  const double w = 0.5 * (1.0 - t);  // 1 back-driven, 0 motoring
  return 1.0 + (c_gen - 1.0) * w;
}

double factor_at(double c_gen, double tau, double x) {
  return factor_with(c_gen, tau, x, std::abs(x) > kBlendSaturated ? 0.0 : blend_tanh(x));
}

double direction_factor(double c_gen, double tau, double qd, double blend) {
  if (!(blend > 0.0)) return tau * qd < 0.0 ? c_gen : 1.0;
  return factor_at(c_gen, tau, qd / blend);
}

}  // namespace

TwinModel::TwinModel(std::string robot, const model::RobotModel& model)
    : robot_name_(std::move(robot)),
      robot_(std::make_shared<model::RobotModel>(model)),
      data_(std::make_shared<model::DynamicsData>(model)) {
  robot_->clear_payload();
}

namespace {
bool trusted(const JointDrive& d) { return d.gain_identified && d.gain >= TwinModel::kTrustedGainMin && d.gain <= TwinModel::kTrustedGainMax; }
}  // namespace

bool TwinModel::any_trusted_gain() const { return std::any_of(joints.begin(), joints.end(), trusted); }

bool TwinModel::gain_from_median(int j) const {
  return gains_known() && !measures_torque() && !trusted(joints[static_cast<size_t>(j)]) && any_trusted_gain();
}

double TwinModel::trusted_gain(int j) const {
  if (measures_torque()) return 1.0;
  if (trusted(joints[static_cast<size_t>(j)])) return joints[static_cast<size_t>(j)].gain;
  std::vector<double> ok;
  for (const JointDrive& d : joints)
    if (trusted(d)) ok.push_back(d.gain);
  if (ok.empty()) return 1.0;
  std::nth_element(ok.begin(), ok.begin() + static_cast<long>(ok.size() / 2), ok.end());
  return ok[ok.size() / 2];
}

bool TwinModel::predicts_payload() const {
  if (sequential) return sequential->has_payload();
  return !(learned && learned->role == LearnedRole::Current);
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

double TwinModel::drive_factor(int j, double tau, double qd, double qdd, const FrictionMemory* memory) const {
  const double c_gen = joints[static_cast<size_t>(j)].c_gen;
  if (memory != nullptr && memory->direction.size() > j && !std::isnan(memory->direction[j])) {
    const double x = memory->direction[j];
    if (memory->direction_tanh.size() == memory->direction.size()) return factor_with(c_gen, tau, x, memory->direction_tanh[j]);
    return factor_at(c_gen, tau, x);
  }
  return direction_factor(c_gen, tau, direction_velocity(qd, qdd), direction_blend);
}

bool TwinModel::drive_in_doubt(int j, double tau, const FrictionMemory& memory, double& to_motoring, double& to_back_driven) const {
  if (sequential || (learned && learned->role == LearnedRole::Current)) return false;
  if (memory.crossing.size() <= j || memory.crossing[j] == 0.0) return false;
  const JointDrive& d = joints[static_cast<size_t>(j)];
  if (!(d.c_gen < 1.0) || !(d.gain > 0.0) || tau == 0.0) return false;
  // the blend's back-driven weight from the tanh advance() left (crossing implies it is there): the
  // weight and factor drive_factor computes, without the factor's division back to the weight
  const double x = memory.direction[j];
  if (!(std::abs(x) <= kBlendSaturated)) return false;  // (saturated: sure)
  const double t = tau < 0.0 ? -memory.direction_tanh[j] : memory.direction_tanh[j];
  const double w = 0.5 * (1.0 - t);
  if (!(w >= kDriveDoubt && w <= 1.0 - kDriveDoubt)) return false;
  const double f = 1.0 + (d.c_gen - 1.0) * w;
  to_motoring = (1.0 - f) * tau / d.gain;
  to_back_driven = (d.c_gen - f) * tau / d.gain;
  return true;
}

void TwinModel::drive_current(const VectorJ& qd, const VectorJ& qdd, const VectorJ& torque, VectorJ& current,
                              const FrictionMemory* memory) const {
  const int n = robot_->n_dof();
  current.resize(n);
  for (int j = 0; j < n; ++j)
    current[j] = drive_factor(j, torque[j], qd[j], qdd[j], memory) * torque[j] / joints[static_cast<size_t>(j)].gain;
}

void TwinModel::predict(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature, VectorJ& torque,
                        VectorJ& current, const FrictionMemory* memory) const {
  if (sequential) return predict_sequential(q, qd, qdd, torque, current);
  physics_torque(q, qd, qdd, temperature, torque, memory);
  drive_current(qd, qdd, torque, current, memory);
  if (learned) apply_learned(q, qd, qdd, temperature, torque, current, memory);
}

void TwinModel::predict_pair(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& qdd2, const VectorJ& temperature,
                             VectorJ& torque, VectorJ& current, VectorJ& torque2, const FrictionMemory* memory) const {
  if (sequential || learned) {
    predict(q, qd, qdd, temperature, torque, current, memory);
    return predict_torque(q, qd, qdd2, temperature, torque2, memory);
  }
  physics_torque(q, qd, qdd, temperature, torque, memory, &qdd2, &torque2);
  drive_current(qd, qdd, torque, current, memory);
}

void TwinModel::apply_learned(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature, VectorJ& torque,
                              VectorJ& current, const FrictionMemory* memory) const {
  // network output: the current itself (mlp) or a correction of the physics current (hybrid);
  // torque through the drive gain, with the direction factor of the resulting current
  VectorJ y;
  learned->evaluate(q, qd, qdd, temperature, y);
  const int n = robot_->n_dof();
  for (int j = 0; j < n; ++j) {
    const JointDrive& d = joints[static_cast<size_t>(j)];
    if (learned->role == LearnedRole::Current) {
      current[j] = y[j];
      torque[j] = d.gain * y[j] / drive_factor(j, y[j], qd[j], qdd[j], memory);
    } else {
      const double c = drive_factor(j, torque[j], qd[j], qdd[j], memory);
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

void TwinModel::advance(FrictionMemory& m, const RobotSample& s, const VectorJ& qdd) const {
  advance(m, s.q);
  const int n = robot_->n_dof();
  if (target_direction.empty() || !s.has(kFieldTargetQd)) {
    // no target to read the direction with: the measured velocity's own blend, kept where the
    // direction is in doubt (drive_in_doubt) and NaN elsewhere (drive_factor's fallback there; the
    // observer's hard switch, monitor::measured_drive_torque). The current predicted at this
    // sample's qdd is the fallback's factor; a prediction at another acceleration (a learned twin's
    // torque at the observer's, the diagnosis window's) reads the direction kept here, as on the
    // target path, which differs only where velocity_lag's lead crosses kDirectionLeadMin
    m.measured = true;
    if (!(direction_blend > 0.0)) {
      m.direction.resize(0);
      m.direction_tanh.resize(0);
      m.crossing.resize(0);
      return;
    }
    m.direction.resize(n);
    m.direction_tanh.resize(n);
    m.crossing.resize(n);
    for (int j = 0; j < n; ++j) {
      const double x = direction_velocity(s.qd[j], qdd[j]) / direction_blend;
      const bool doubt = std::abs(x) <= kDoubtArgument;
      m.direction[j] = doubt ? x : std::numeric_limits<double>::quiet_NaN();
      m.direction_tanh[j] = doubt ? blend_tanh(x) : 0.0;
      m.crossing[j] = doubt ? 1.0 : 0.0;
    }
    return;
  }
  m.measured = false;
  m.direction.resize(n);
  m.direction_tanh.resize(n);
  m.crossing.resize(n);
  const bool accelerating = s.has(kFieldTargetQdd);
  for (int j = 0; j < n; ++j) {
    double& x = m.direction[j];
    if (!target_drive_direction(s, qdd, j, x)) x = std::numeric_limits<double>::quiet_NaN();
    m.direction_tanh[j] = std::isnan(x) || std::abs(x) > kBlendSaturated ? 0.0 : blend_tanh(x);
    const bool resting = std::abs(s.target_qd[j]) < kTargetRestVelocity && !(accelerating && std::abs(s.target_qdd[j]) >= kTargetRestAcceleration);
    m.crossing[j] = !std::isnan(x) && !resting ? 1.0 : 0.0;
  }
}

void MotionEnvelope::include(const VectorJ& q, const VectorJ& qd) {
  if (empty()) {
    q_min = q_max = q;
    qd_max = qd.cwiseAbs();
    return;
  }
  q_min = q_min.cwiseMin(q);
  q_max = q_max.cwiseMax(q);
  qd_max = qd_max.cwiseMax(qd.cwiseAbs());
}

std::string TwinModel::to_json() const {
  nlohmann::json j;
  j["format"] = "twinwatch-twin";
  j["version"] = kTwinFormatVersion;
  j["robot"] = robot_name_;
  j["method"] = method;
  j["created"] = created;
  j["recordings"] = recordings;
  if (!envelope.empty())
    j["motion_envelope"] = {{"q_min", numbers(Eigen::VectorXd(envelope.q_min))},
                            {"q_max", numbers(Eigen::VectorXd(envelope.q_max))},
                            {"qd_max", numbers(Eigen::VectorXd(envelope.qd_max))}};
  j["temperature_ref"] = temperature_ref;
  j["direction_blend"] = direction_blend;
  // (only when set: a twin without it reads the streamed velocity as it is, and older readers,
  // which refuse unknown keys, still load it)
  if (velocity_lag != 0.0) j["velocity_lag"] = velocity_lag;
  if (!target_direction.empty())  // (the same: only when measured)
    j["target_direction"] = {{"lead_s", numbers(Eigen::VectorXd(target_direction.lead))},
                             {"width", numbers(Eigen::VectorXd(target_direction.width))},
                             {"width_s", numbers(Eigen::VectorXd(target_direction.width_time))}};
  j["payload"] = {{"mass", payload_.mass}, {"com", {payload_.com.x(), payload_.com.y(), payload_.com.z()}}};
  j["gains_absolute"] = gains_absolute;
  // (only for a joint-torque twin: a current twin's file stays what older readers load)
  if (measures_torque()) j["signal"] = signal_name();
  if (acceleration_window > 0.0) j["acceleration_window"] = acceleration_window;  // (the same: only when set)
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
    e["friction_columns"] = kFrictionColumnNames;
    // always written (all zero: none), so that a block lost from a file is not read as "none"
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

namespace {

// The format version of a twin file: a whole number from 1 to kTwinFormatVersion.
int format_version(const nlohmann::json& j, const std::string& origin) {
  if (!j.contains("version"))
    throw ParseError(origin, 0, "version", fmt::format("missing required field (the twin file format version, 1 to {})", kTwinFormatVersion));
  const nlohmann::json& v = j.at("version");
  const std::optional<int> x = v.is_number() ? whole_int(v.get<double>()) : std::nullopt;
  if (!x) throw ParseError(origin, 0, "version", fmt::format("expected a whole number from 1 to {}, got {}", kTwinFormatVersion, json_brief(v)));
  if (*x < 1 || *x > kTwinFormatVersion)
    throw ParseError(origin, 0, "version",
                     fmt::format("expected 1 to {}, got {} (a file from a newer twinwatch? this one reads versions 1 to {})",
                                 kTwinFormatVersion, *x, kTwinFormatVersion));
  return *x;
}

// The monitor's trend settings a version-1 file without a "trend" block is read with: those of
// monitor::TrendConfig when version 2 came (tests/monitor/monitor_test.cpp checks that they still are)
const nlohmann::json& version_1_trend() {
  static const nlohmann::json t = {{"enabled", true},         {"window_s", 30.0},   {"cycle_period", 0.0},
                                   {"v_min", 0.05},           {"min_moving_fraction", 0.2}, {"baseline_windows", 4},
                                   {"min_windows", 12},       {"history", 240},     {"z_crit", 4.0},
                                   {"min_rate_pct_per_h", 4.0}, {"persist", 3},     {"temperature_ref", 35.0}};
  return t;
}

// Version 1 -> 2: every version-1 writer wrote the fields version 2 requires except these, added
// over time; a file without one is given the value the program has always read it with (the
// defaults of the time, "files before it"). Returns "field = value" for each one filled.
std::vector<std::string> upgrade_version_1(nlohmann::json& j) {
  std::vector<std::string> filled;
  const auto fill = [&](nlohmann::json& o, const char* key, const nlohmann::json& value, const std::string& field, const char* meaning) {
    if (o.contains(key)) return;
    o[key] = value;
    filled.push_back(fmt::format("{} = {}", field, meaning));
  };
  fill(j, "direction_blend", 0.0, "direction_blend", "0 (the hard motoring/back-driven switch)");
  if (j.contains("joints") && j["joints"].is_array())
    for (size_t k = 0; k < j["joints"].size(); ++k) {
      nlohmann::json& e = j["joints"][k];
      if (!e.is_object()) continue;  // (named by the reader)
      const std::string p = json_element("joints", k);
      fill(e, "gain_identified", true, p + ".gain_identified", "true");
      fill(e, "low_speed_friction", {{"presliding_alpha", 0.0}, {"presliding", 0.0}, {"stribeck_velocity", 0.0}, {"stribeck", 0.0}},
           p + ".low_speed_friction", "none (plain Coulomb friction)");
    }
  if (j.contains("monitor") && j["monitor"].is_object()) {
    nlohmann::json& m = j["monitor"];
    fill(m, "trend", version_1_trend(), "monitor.trend", "the defaults (30 s windows)");
    fill(m, "observer_gain", 150.0, "monitor.observer_gain", "150 1/s");
    fill(m, "observer_alerts", true, "monitor.observer_alerts", "true");
  }
  return filled;
}

// one joint's drive, friction and fit (an element of "joints")
JointDrive joint_from_json(const nlohmann::json& v, const std::string& origin, const std::string& path) {
  const JsonFields e(v, origin, path);
  e.only({"gain", "c_gen", "gain_identified", "friction", "friction_columns", "low_speed_friction", "train_rmse", "train_r2"});
  JointDrive m;
  m.gain = e.positive("gain");
  m.c_gen = e.number("c_gen");
  if (!(m.c_gen > 0.0 && m.c_gen <= kCGenFileMax))
    e.fail("c_gen", fmt::format("expected a number in (0, {}] (the current factor when back-driven; 1: as when motoring), got {}", kCGenFileMax,
                                m.c_gen));
  m.gain_identified = e.boolean("gain_identified");
  // the column names first: they say what the values are
  if (e.texts("friction_columns") != kFrictionColumnNames)
    e.fail("friction_columns", fmt::format("expected [\"{}\"] (the order of the friction values), got {}", fmt::join(kFrictionColumnNames, "\", \""),
                                           json_brief(e.need("friction_columns"))));
  const std::vector<double> f = e.numbers("friction", kFrictionColumns);
  // friction opposes the motion: a negative Coulomb or viscous coefficient would push it along
  for (const int c : {int(kCoulomb), int(kViscous)})
    if (f[static_cast<size_t>(c)] < 0.0)
      throw ParseError(origin, 0, json_element(e.field("friction"), static_cast<size_t>(c)),
                       fmt::format("expected {} friction >= 0 (friction opposes the motion), got {}", kFrictionColumnNames[static_cast<size_t>(c)],
                                   f[static_cast<size_t>(c)]));
  m.friction = Eigen::Map<const Eigen::Matrix<double, kFrictionColumns, 1>>(f.data());
  const JsonFields l = e.object("low_speed_friction");
  l.only({"presliding_alpha", "presliding", "stribeck_velocity", "stribeck"});
  m.presliding_alpha = l.nonnegative("presliding_alpha");
  m.presliding = l.number("presliding");
  m.stribeck_velocity = l.nonnegative("stribeck_velocity");
  m.stribeck = l.number("stribeck");
  // a level without its shape would be dropped by the prediction (all zero: none)
  if (m.presliding_alpha == 0.0 && m.presliding != 0.0)
    l.fail("presliding_alpha", fmt::format("expected a number > 0 [1/rad] when presliding is nonzero ({}), got 0", m.presliding));
  if (m.stribeck_velocity == 0.0 && m.stribeck != 0.0)
    l.fail("stribeck_velocity", fmt::format("expected a number > 0 [rad/s] when stribeck is nonzero ({}), got 0", m.stribeck));
  m.rmse = e.nonnegative("train_rmse");
  m.r2 = e.number("train_r2");
  return m;
}

}  // namespace

TwinModel TwinModel::from_json(const std::string& text, const std::string& origin) {
  nlohmann::json j = parse_json(text, origin);
  // (a file that is not an object, or whose format is no string, gets these messages rather than a missing field)
  if (!j.is_object())
    throw ParseError(origin, 0, "", fmt::format("expected a JSON object (a twin file from twinwatch identify), got {}", j.type_name()));
  if (!j.contains("format") || j.at("format") != "twinwatch-twin")
    throw ParseError(origin, 0, "format", fmt::format("expected \"twinwatch-twin\" (is this a twin file from twinwatch identify?), got {}",
                                                      j.contains("format") ? json_brief(j.at("format")) : "nothing"));
  const int version = format_version(j, origin);
  const std::vector<std::string> filled = version == 1 ? upgrade_version_1(j) : std::vector<std::string>{};
  try {
    const JsonFields top(j, origin, "");
    top.only({"format", "version", "robot", "method", "created", "recordings", "temperature_ref", "direction_blend", "velocity_lag", "target_direction",
              "payload", "gains_absolute", "signal", "acceleration_window", "monitor", "learned", "friction_models", "base_columns", "beta", "joints", "sequential",
              "motion_envelope"});
    const std::string robot = top.text("robot");
    TwinModel t;
    // a robot file named by a relative path (twins written before identify stored it absolute) is
    // looked for from the working directory, then beside the twin file (a twin copied with its robot)
    std::string where = robot;
    {
      namespace fs = std::filesystem;
      std::error_code ec;
      const fs::path rp(robot);
      const bool is_file = rp.extension() == ".json" || rp.extension() == ".urdf";
      if (is_file && rp.is_relative() && !fs::exists(rp, ec)) {
        const fs::path beside = fs::path(origin).parent_path() / rp;
        if (fs::exists(beside, ec)) where = beside.string();
      }
    }
    try {
      t = TwinModel(robot, model::load_robot(where));
    } catch (const InvalidArgument& e) {
      throw ParseError(origin, 0, "robot", e.what());
    } catch (const ParseError& e) {
      throw ParseError(origin, 0, "robot", fmt::format("the robot description cannot be read: {}", e.what()));
    }
    const int n = t.n_dof();
    t.origin = origin;
    t.method = top.text("method");
    if (std::find(kMethods.begin(), kMethods.end(), t.method) == kMethods.end())
      top.fail("method", fmt::format("expected one of \"{}\", got {}", fmt::join(kMethods, "\", \""), json_brief(top.need("method"))));
    t.created = top.text("created");
    t.recordings = top.texts("recordings");
    t.temperature_ref = top.number("temperature_ref");
    t.direction_blend = top.nonnegative("direction_blend");
    // optional (since session 26; a twin from before reads the streamed velocity as it is)
    if (top.has("velocity_lag")) {
      t.velocity_lag = top.number("velocity_lag");
      if (!(std::abs(t.velocity_lag) <= TwinModel::kVelocityLagMax))
        top.fail("velocity_lag", fmt::format("expected a lag in seconds within +-{:g} s (the streamed velocity against its sample's instant), got {}",
                                             TwinModel::kVelocityLagMax, t.velocity_lag));
    }
    t.gains_absolute = top.boolean("gains_absolute");
    const JsonFields pl = top.object("payload");
    pl.only({"mass", "com"});
    model::RigidBodyInertia payload;
    payload.mass = pl.nonnegative("mass");
    const std::vector<double> com = pl.numbers("com", 3);
    payload.com = Eigen::Vector3d(com[0], com[1], com[2]);
    t.set_payload(payload);
    // base parameters: each standard column once, one value per column
    t.base_columns = json_wholes(top.need("base_columns"), origin, "base_columns");
    std::vector<int> first(static_cast<size_t>(10 * n), -1);
    for (size_t i = 0; i < t.base_columns.size(); ++i) {
      const int c = t.base_columns[i];
      if (c < 0 || c >= 10 * n) throw ParseError(origin, 0, "base_columns", fmt::format("column {} out of range 0..{}", c, 10 * n - 1));
      if (first[static_cast<size_t>(c)] >= 0)
        throw ParseError(origin, 0, json_element("base_columns", i),
                         fmt::format("expected each standard column once, got column {} again (also at base_columns[{}])", c, first[static_cast<size_t>(c)]));
      first[static_cast<size_t>(c)] = static_cast<int>(i);
    }
    const nlohmann::json& bj = top.need("beta");
    if (!bj.is_array()) top.fail("beta", fmt::format("expected an array of numbers, got {}", json_brief(bj)));
    if (bj.size() != t.base_columns.size())
      top.fail("beta", fmt::format("expected {} values (one per base column), got {}", t.base_columns.size(), bj.size()));
    const std::vector<double> beta = top.numbers("beta");
    t.beta = Eigen::Map<const Eigen::VectorXd>(beta.data(), static_cast<Eigen::Index>(beta.size()));
    const nlohmann::json& js = top.need("joints");
    if (!js.is_array() || static_cast<int>(js.size()) != n)
      throw ParseError(origin, 0, "joints", fmt::format("expected {} joints for robot '{}', got {}", n, robot, js.is_array() ? std::to_string(js.size()) : json_brief(js)));
    for (size_t k = 0; k < js.size(); ++k) t.joints.push_back(joint_from_json(js[k], origin, json_element("joints", k)));
    // the optional blocks (the monitor's and the friction study's are read by their modules)
    if (top.has("monitor")) t.monitor_json = top.object("monitor").json().dump();
    if (top.has("learned")) t.learned = LearnedModel::from_json(j["learned"].dump(), origin, n);
    if (top.has("friction_models")) {
      if (!j["friction_models"].is_array()) top.fail("friction_models", fmt::format("expected an array, got {}", json_brief(j["friction_models"])));
      t.friction_json = j["friction_models"].dump();
    }
    if (top.has("sequential")) t.sequential = sequential_from_json(j["sequential"], n, origin);
    // optional: twins written before session 17 do not have it (then nothing is said about extrapolation)
    // optional (since session 31; a twin from before reads the drive's direction on the measured velocity)
    if (top.has("target_direction")) {
      const JsonFields td = top.object("target_direction");
      td.only({"lead_s", "width", "width_s"});
      const std::vector<double> lead = td.numbers("lead_s", static_cast<size_t>(n)), width = td.numbers("width", static_cast<size_t>(n)),
                                width_s = td.numbers("width_s", static_cast<size_t>(n));
      for (int k = 0; k < n; ++k) {
        if (!(std::abs(lead[static_cast<size_t>(k)]) <= TwinModel::kVelocityLagMax))
          throw ParseError(origin, 0, json_element(td.field("lead_s"), static_cast<size_t>(k)),
                           fmt::format("expected a lead in seconds within +-{:g} s (the joint's velocity against its target), got {}",
                                       TwinModel::kVelocityLagMax, lead[static_cast<size_t>(k)]));
        if (!(width[static_cast<size_t>(k)] > 0.0 && width[static_cast<size_t>(k)] <= TwinModel::kTargetDirectionWidthMax))
          throw ParseError(origin, 0, json_element(td.field("width"), static_cast<size_t>(k)),
                           fmt::format("expected a tracking error in (0, {:g}] rad/s, got {}", TwinModel::kTargetDirectionWidthMax,
                                       width[static_cast<size_t>(k)]));
      }
      for (int k = 0; k < n; ++k)
        if (!(width_s[static_cast<size_t>(k)] >= 0.0 && width_s[static_cast<size_t>(k)] <= TwinModel::kVelocityLagMax))
          throw ParseError(origin, 0, json_element(td.field("width_s"), static_cast<size_t>(k)),
                           fmt::format("expected a time in [0, {:g}] s (the tracking error per unit of acceleration), got {}",
                                       TwinModel::kVelocityLagMax, width_s[static_cast<size_t>(k)]));
      t.target_direction.width_time = VectorJ(Eigen::Map<const Eigen::VectorXd>(width_s.data(), n));
      t.target_direction.lead = VectorJ(Eigen::Map<const Eigen::VectorXd>(lead.data(), n));
      t.target_direction.width = VectorJ(Eigen::Map<const Eigen::VectorXd>(width.data(), n));
    }
    if (top.has("motion_envelope")) {
      const JsonFields env = top.object("motion_envelope");
      env.only({"q_min", "q_max", "qd_max"});
      const auto vec = [&](const char* key) {
        const std::vector<double> v = env.numbers(key, static_cast<size_t>(n));
        return VectorJ(Eigen::Map<const Eigen::VectorXd>(v.data(), n));
      };
      t.envelope.q_min = vec("q_min");
      t.envelope.q_max = vec("q_max");
      t.envelope.qd_max = vec("qd_max");
      for (int k = 0; k < n; ++k) {
        if (t.envelope.q_min[k] > t.envelope.q_max[k])
          throw ParseError(origin, 0, json_element(env.field("q_min"), static_cast<size_t>(k)),
                           fmt::format("expected at most q_max[{}] = {}, got {}", k, t.envelope.q_max[k], t.envelope.q_min[k]));
        if (t.envelope.qd_max[k] < 0.0)
          throw ParseError(origin, 0, json_element(env.field("qd_max"), static_cast<size_t>(k)),
                           fmt::format("expected a speed >= 0 [rad/s], got {}", t.envelope.qd_max[k]));
      }
    }
    // the method names the model that predicts: its block must be there, and no other
    const bool mlp = t.learned && t.learned->role == LearnedRole::Current, hybrid = t.learned && t.learned->role == LearnedRole::Residual;
    const char* wants = t.method == "mlp" ? (mlp ? nullptr : "a \"learned\" block with role \"current\"")
                        : t.method == "hybrid" ? (hybrid ? nullptr : "a \"learned\" block with role \"residual\"")
                        : t.method == "sequential" ? (t.sequential && !t.learned ? nullptr : "a \"sequential\" block and no \"learned\" block")
                                                   : (t.learned || t.sequential ? "no \"learned\" or \"sequential\" block" : nullptr);
    if (wants != nullptr)
      top.fail("method", fmt::format("method \"{}\" expects {}, got {}", t.method, wants,
                                     t.learned ? (mlp ? "a \"learned\" block with role \"current\"" : "a \"learned\" block with role \"residual\"")
                                               : (t.sequential ? "a \"sequential\" block" : "neither block")));
    // optional (since session 54; absent: 3 samples)
    if (top.has("acceleration_window")) {
      t.acceleration_window = top.number("acceleration_window");
      if (!(t.acceleration_window > 0.0 && t.acceleration_window <= TwinModel::kAccelerationWindowMax))
        top.fail("acceleration_window", fmt::format("expected a half window in (0, {:g}] s (the velocity smoothing of the acceleration), got {}",
                                                    TwinModel::kAccelerationWindowMax, t.acceleration_window));
    }
    // optional (since session 54; absent: the motor currents)
    if (top.has("signal")) {
      const std::string sig = top.text("signal");
      if (sig == "joint_torque") t.signal = TwinModel::Signal::JointTorque;
      else if (sig != "current")
        top.fail("signal", fmt::format("expected \"current\" (motor currents) or \"joint_torque\" (joint torque sensors), got {}",
                                       json_brief(top.need("signal"))));
    }
    if (t.measures_torque()) {
      // a torque sensor reads the link side: no drive gain or back-driven factor between it and the
      // model's torque (a twin edited to carry them would predict other units than it compares)
      if (!t.gains_absolute) top.fail("gains_absolute", "a joint_torque twin's torque scale is the sensors' own: expected true, got false");
      for (size_t k = 0; k < t.joints.size(); ++k)
        if (t.joints[k].gain != 1.0 || t.joints[k].c_gen != 1.0)
          throw ParseError(origin, 0, json_element("joints", k),
                           fmt::format("a joint_torque twin has no drive between its sensor and the link: expected gain 1 and c_gen 1, got "
                                       "gain {} and c_gen {}",
                                       t.joints[k].gain, t.joints[k].c_gen));
      if (t.method != "physics" && t.method != "hybrid")
        top.fail("signal", fmt::format("a joint_torque twin is identified with method \"physics\" or \"hybrid\", got \"{}\"", t.method));
    }
    if (version == 1)
      log::warn(fmt::format("{}: a version-1 twin file, read as version {} with {}; re-identify (twinwatch identify) to write a version-{} "
                            "file, in which every field is required",
                            origin, kTwinFormatVersion,
                            filled.empty() ? std::string("every field present") : fmt::format("defaults for the fields it lacks: {}", fmt::join(filled, ", ")),
                            kTwinFormatVersion));
    return t;
  } catch (const nlohmann::json::exception& e) {  // (every field is type-checked above: a safety net for the fuzzer's contract)
    throw ParseError(origin, 0, "", fmt::format("wrong type: {}", e.what()));
  }
}

namespace {

// Writes `text` to `file` and checks that every byte reached it (a full disk shows at the flush or
// the close, not at the write). `shown`: the path named in errors.
void write_text(const std::string& file, const std::string& text, const std::string& shown) {
  errno = 0;
  std::ofstream f(file, std::ios::binary | std::ios::trunc);
  if (!f) throw std::runtime_error(fmt::format("{}: cannot open for writing: {}", shown, std::strerror(errno != 0 ? errno : EIO)));
  f.write(text.data(), static_cast<std::streamsize>(text.size()));
  f.flush();
  int err = errno;
  f.close();
  if (err == 0) err = errno;
  if (!f) throw std::runtime_error(fmt::format("{}: cannot write the twin file: {}", shown, std::strerror(err != 0 ? err : EIO)));
}

}  // namespace

void TwinModel::save(const std::string& path) const {
  namespace fs = std::filesystem;
  const std::string text = to_json() + '\n';
  // what is written must load back: a value the reader refuses is named now, not when the twin is used
  try {
    from_json(text, path);
  } catch (const ParseError& e) {
    throw std::runtime_error(fmt::format("{}: not written, the twin would not load back: {}", path, e.what()));
  }
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);  // (through a symbolic link)
  // a device or a pipe (/dev/stdout) is written in place
  if (fs::exists(st) && !fs::is_regular_file(st)) return write_text(path, text, path);
  // a regular file is replaced only once the new text is completely on disk: a full disk or a
  // failed write leaves the twin it held (thresholds and friction-study rewrite the twin they read)
  const fs::path target = fs::exists(st) ? fs::canonical(path, ec) : fs::path(path);
  fs::path tmp = target;
  tmp += fmt::format(".tmp{}", static_cast<long>(::getpid()));
  {
    std::ofstream probe(tmp, std::ios::binary | std::ios::trunc);
    if (!probe) return write_text(path, text, path);  // no file can be made beside it: in place, as before
  }
  try {
    write_text(tmp.string(), text, path);
    if (fs::exists(st)) fs::permissions(tmp, st.permissions(), ec);
    fs::rename(tmp, target, ec);
    if (ec) throw std::runtime_error(fmt::format("{}: cannot write the twin file: {}", path, ec.message()));
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
}

TwinModel TwinModel::load(const std::string& path) {
  refuse_directory_input(path);
  errno = 0;
  std::ifstream f(path);
  if (!f) throw ParseError(path, 0, "", fmt::format("cannot open the twin file: {}", std::strerror(errno != 0 ? errno : ENOENT)));
  std::stringstream ss;
  ss << f.rdbuf();
  return from_json(ss.str(), path);
}

}  // namespace twinwatch::ident
