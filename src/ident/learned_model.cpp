#include "twinwatch/ident/learned_model.hpp"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "twinwatch/core/error.hpp"

#include "json_numbers.hpp"

namespace twinwatch::ident {

int LearnedInputs::count(int n) const {
  return n * ((q ? 1 : 0) + (qd ? 1 : 0) + (qdd ? 1 : 0) + (temperature ? 1 : 0) + (friction_shape ? 2 : 0));
}

void LearnedInputs::validate() const {
  if (!q && !qd && !qdd && !temperature && !friction_shape)
    throw InvalidArgument("learned inputs: no feature selected, expected at least one of q, qd, qdd, temperature, friction_shape");
  if (!(v_scale > 0.0) || !std::isfinite(v_scale)) throw InvalidArgument(fmt::format("v_scale is {}, must be > 0 [rad/s]", v_scale));
}

std::string LearnedInputs::to_string() const {
  std::string s;
  auto add = [&](bool on, const char* name) {
    if (!on) return;
    if (!s.empty()) s += '+';
    s += name;
  };
  add(q, "q");
  add(qd, "qd");
  add(qdd, "qdd");
  add(temperature, "temperature");
  add(friction_shape, "friction_shape");
  return s;
}

LearnedInputs LearnedInputs::parse(const std::string& text) {
  LearnedInputs in;
  in.q = in.qd = in.qdd = in.temperature = in.friction_shape = false;
  std::stringstream ss(text);
  std::string tok;
  while (std::getline(ss, tok, '+')) {
    if (tok == "q") in.q = true;
    else if (tok == "qd") in.qd = true;
    else if (tok == "qdd") in.qdd = true;
    else if (tok == "temperature") in.temperature = true;
    else if (tok == "friction_shape") in.friction_shape = true;
    else
      throw InvalidArgument(fmt::format("learned inputs '{}': unknown feature '{}', expected q, qd, qdd, temperature or friction_shape "
                                        "joined by '+'", text, tok));
  }
  in.validate();
  return in;
}

void LearnedInputs::build(const VectorJ& q_, const VectorJ& qd_, const VectorJ& qdd_, const VectorJ& T, double T_ref,
                          double* x) const {
  const int n = static_cast<int>(q_.size());
  int k = 0;
  if (q)
    for (int j = 0; j < n; ++j) x[k++] = q_[j];
  if (qd)
    for (int j = 0; j < n; ++j) x[k++] = qd_[j];
  if (qdd)
    for (int j = 0; j < n; ++j) x[k++] = qdd_[j];
  if (temperature)
    for (int j = 0; j < n; ++j) x[k++] = T.size() > j && std::isfinite(T[j]) ? T[j] : T_ref;
  if (friction_shape) {
    for (int j = 0; j < n; ++j) x[k++] = std::tanh(qd_[j] / v_scale);
    for (int j = 0; j < n; ++j) {
      const double u = qd_[j] / v_scale;
      x[k++] = std::exp(-u * u) * std::tanh(u);
    }
  }
}

void LearnedModel::evaluate(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& T, VectorJ& out) const {
  const int n = static_cast<int>(q.size());
  x_.resize(inputs.count(n));
  inputs.build(q, qd, qdd, T, temperature_ref, x_.data());
  out.resize(n);
  net.predict(x_.data(), out.data());
}

std::string LearnedModel::to_json() const {
  nlohmann::json j;
  j["role"] = role == LearnedRole::Current ? "current" : "residual";
  j["inputs"] = inputs.to_string();
  j["v_scale"] = inputs.v_scale;
  j["temperature_ref"] = temperature_ref;
  j["qd_smoothing"] = {{"filter", "savitzky_golay"}, {"window", sg_window}, {"order", sg_order}};
  j["validation_rmse"] = validation_rmse;
  j["network"] = nlohmann::json::parse(net.to_json());
  return j.dump();
}

LearnedModel LearnedModel::from_json(const std::string& text, const std::string& origin, int n_dof) {
  const std::string p = "learned.";
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw ParseError(origin, 0, "learned", fmt::format("not valid JSON: {}", e.what()));
  }
  try {
    LearnedModel m;
    const std::string role = j.value("role", "");
    if (role == "current") m.role = LearnedRole::Current;
    else if (role == "residual") m.role = LearnedRole::Residual;
    else throw ParseError(origin, 0, p + "role", fmt::format("expected \"current\" or \"residual\", got \"{}\"", role));
    if (!j.contains("inputs")) throw ParseError(origin, 0, p + "inputs", "missing required field");
    try {
      m.inputs = LearnedInputs::parse(j["inputs"].get<std::string>());
      m.inputs.v_scale = j.value("v_scale", m.inputs.v_scale);
      m.inputs.validate();
    } catch (const InvalidArgument& e) {
      throw ParseError(origin, 0, p + "inputs", e.what());
    }
    m.temperature_ref = j.value("temperature_ref", 35.0);
    if (j.contains("qd_smoothing")) {
      const nlohmann::json& sg = j["qd_smoothing"];
      if (!sg.is_object()) throw ParseError(origin, 0, p + "qd_smoothing", fmt::format("expected an object, got {}", sg.type_name()));
      if (sg.contains("window")) m.sg_window = json_whole(sg.at("window"), origin, p + "qd_smoothing.window");
      if (sg.contains("order")) m.sg_order = json_whole(sg.at("order"), origin, p + "qd_smoothing.order");
    }
    m.validation_rmse = j.value("validation_rmse", std::vector<double>{});
    if (!j.contains("network")) throw ParseError(origin, 0, p + "network", "missing required field");
    m.net = Mlp::from_json(j["network"].dump(), origin, p + "network.");
    if (m.net.n_inputs() != m.inputs.count(n_dof))
      throw ParseError(origin, 0, p + "network.inputs",
                       fmt::format("expected {} (inputs '{}' for {} joints), got {}", m.inputs.count(n_dof), m.inputs.to_string(), n_dof,
                                   m.net.n_inputs()));
    if (m.net.n_outputs() != n_dof)
      throw ParseError(origin, 0, p + "network.outputs", fmt::format("expected {} (one per joint), got {}", n_dof, m.net.n_outputs()));
    return m;
  } catch (const nlohmann::json::type_error& e) {
    throw ParseError(origin, 0, "learned", fmt::format("wrong type: {}", e.what()));
  }
}

}  // namespace twinwatch::ident
