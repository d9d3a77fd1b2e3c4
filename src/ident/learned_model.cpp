#include "twinwatch/ident/learned_model.hpp"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/json_fields.hpp"

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
  const nlohmann::json j = parse_json(text, origin, "learned");
  try {
    const JsonFields b(j, origin, "learned");
    b.only({"role", "inputs", "v_scale", "temperature_ref", "qd_smoothing", "validation_rmse", "network"});
    LearnedModel m;
    const std::string role = b.text("role");
    if (role == "current") m.role = LearnedRole::Current;
    else if (role == "residual") m.role = LearnedRole::Residual;
    else b.fail("role", fmt::format("expected \"current\" or \"residual\", got \"{}\"", role));
    const std::string inputs = b.text("inputs");
    try {
      m.inputs = LearnedInputs::parse(inputs);
    } catch (const InvalidArgument& e) {
      b.fail("inputs", e.what());
    }
    m.inputs.v_scale = b.positive("v_scale");
    m.temperature_ref = b.number("temperature_ref");
    const JsonFields sg = b.object("qd_smoothing");
    sg.only({"filter", "window", "order"});
    if (const std::string f = sg.text("filter"); f != "savitzky_golay") sg.fail("filter", fmt::format("expected \"savitzky_golay\", got \"{}\"", f));
    m.sg_window = json_whole(sg.need("window"), origin, sg.field("window"));
    m.sg_order = json_whole(sg.need("order"), origin, sg.field("order"));
    // the rules of LearnedIdentOptions (0: off)
    if (m.sg_window != 0 && (m.sg_window < 3 || m.sg_window % 2 == 0))
      sg.fail("window", fmt::format("expected 0 (off) or an odd number >= 3, got {}", m.sg_window));
    if (m.sg_window != 0 && (m.sg_order < 0 || m.sg_order >= m.sg_window))
      sg.fail("order", fmt::format("expected a whole number in [0, window = {}), got {}", m.sg_window, m.sg_order));
    // per joint (none: not validated); null: no held-out samples on the joint
    const nlohmann::json& v = b.need("validation_rmse");
    if (!v.is_array()) b.fail("validation_rmse", fmt::format("expected an array of numbers, got {}", json_brief(v)));
    if (!v.empty() && static_cast<int>(v.size()) != n_dof)
      b.fail("validation_rmse", fmt::format("expected {} values (one per joint) or none, got {}", n_dof, v.size()));
    for (size_t i = 0; i < v.size(); ++i)
      m.validation_rmse.push_back(v[i].is_null() ? std::nan("") : json_number(v[i], origin, json_element(b.field("validation_rmse"), i)));
    m.net = Mlp::from_json(b.need("network").dump(), origin, "learned.network.");
    if (m.net.n_inputs() != m.inputs.count(n_dof))
      b.fail("network.inputs", fmt::format("expected {} (inputs '{}' for {} joints), got {}", m.inputs.count(n_dof), m.inputs.to_string(), n_dof,
                                           m.net.n_inputs()));
    if (m.net.n_outputs() != n_dof) b.fail("network.outputs", fmt::format("expected {} (one per joint), got {}", n_dof, m.net.n_outputs()));
    return m;
  } catch (const nlohmann::json::exception& e) {  // (every field is type-checked above: a safety net for the fuzzer's contract)
    throw ParseError(origin, 0, "learned", fmt::format("wrong type: {}", e.what()));
  }
}

}  // namespace twinwatch::ident
