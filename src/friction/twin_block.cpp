#include "twinwatch/friction/twin_block.hpp"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/numbers.hpp"

namespace twinwatch::friction {

namespace {

UnaryOp parse_op(const std::string& s, const std::string& origin, const std::string& field) {
  if (const auto op = unary_op_from_string(s)) return *op;
  throw ParseError(origin, 0, field, fmt::format("unknown function '{}', expected sin, cos, exp, tanh or stribeck", s));
}

const nlohmann::json& need(const nlohmann::json& j, const char* key, const std::string& prefix, const std::string& origin) {
  if (!j.contains(key)) throw ParseError(origin, 0, prefix + key, "missing field");
  return j[key];
}

double positive(const nlohmann::json& j, const char* key, const std::string& prefix, const std::string& origin) {
  const nlohmann::json& v = need(j, key, prefix, origin);
  if (!v.is_number()) throw ParseError(origin, 0, prefix + key, fmt::format("expected a number, got {}", v.dump()));
  const double x = v.get<double>();
  if (!std::isfinite(x) || x <= 0.0) throw ParseError(origin, 0, prefix + key, fmt::format("must be > 0, got {}", x));
  return x;
}

// a whole number that fits an int (get<int>() of 1e20 would be undefined behaviour)
int whole_number(const nlohmann::json& j, const char* key, const std::string& prefix, const std::string& origin) {
  const nlohmann::json& v = need(j, key, prefix, origin);
  const std::optional<int> x = v.is_number() ? whole_int(v.get<double>()) : std::nullopt;
  if (!x) throw ParseError(origin, 0, prefix + key, fmt::format("expected a whole number, got {}", v.dump()));
  return *x;
}

}  // namespace

JointFrictionEquation friction_equation_of(const ParFamModel& model, int joint) {
  if (!model.fitted()) throw InvalidArgument(fmt::format("{} of joint {} is not fitted", model.name(), joint));
  JointFrictionEquation e;
  e.joint = joint;
  e.expression = model.expression();
  e.hysteresis = model.hysteresis();
  return e;
}

std::string friction_block_to_json(const std::vector<JointFrictionEquation>& equations) {
  nlohmann::json out = nlohmann::json::array();
  for (const JointFrictionEquation& e : equations) {
    nlohmann::json j;
    j["joint"] = e.joint;
    j["model"] = e.expression.dim == 3 ? "ParFam-H" : "ParFam-V";
    j["dim"] = e.expression.dim;
    for (UnaryOp op : e.expression.functions) j["functions"].push_back(std::string(to_string(op)));
    j["theta"] = e.expression.theta;
    j["denominator_floor"] = e.expression.denominator_floor;
    if (!e.expression.input_min.empty()) {
      j["input_min"] = e.expression.input_min;
      j["input_max"] = e.expression.input_max;
    }
    if (e.expression.dim == 3) {
      j["alpha"] = e.hysteresis.alpha;
      j["beta"] = e.hysteresis.beta;
      j["memory"] = to_string(e.hysteresis.drive);
    }
    j["equation"] = "tau_f = " + e.expression.to_string();
    out.push_back(j);
  }
  return out.dump();
}

std::vector<JointFrictionEquation> friction_block_from_json(const std::string& text, const std::string& origin) {
  nlohmann::json js;
  try {
    js = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw ParseError(origin, 0, "friction_models", fmt::format("not JSON: {}", e.what()));
  } catch (const nlohmann::json::out_of_range& e) {  // a number beyond a double ("1e400")
    throw ParseError(origin, 0, "friction_models", fmt::format("expected numbers within the range of a double: {}", e.what()));
  }
  if (!js.is_array()) throw ParseError(origin, 0, "friction_models", fmt::format("expected an array, got {}", js.type_name()));
  std::vector<JointFrictionEquation> out;
  for (std::size_t k = 0; k < js.size(); ++k) {
    const std::string p = fmt::format("friction_models[{}].", k);
    const nlohmann::json& j = js[k];
    if (!j.is_object()) throw ParseError(origin, 0, p.substr(0, p.size() - 1), "expected an object");
    try {
      JointFrictionEquation e;
      e.joint = whole_number(j, "joint", p, origin);
      if (e.joint < 1) throw ParseError(origin, 0, p + "joint", fmt::format("must be >= 1, got {}", e.joint));
      e.expression.dim = whole_number(j, "dim", p, origin);
      if (e.expression.dim != 1 && e.expression.dim != 3)
        throw ParseError(origin, 0, p + "dim", fmt::format("expected 1 or 3, got {}", e.expression.dim));
      const nlohmann::json& f = need(j, "functions", p, origin);
      if (!f.is_array() || f.empty()) throw ParseError(origin, 0, p + "functions", "expected a non-empty array of names");
      for (const auto& name : f) e.expression.functions.push_back(parse_op(name.get<std::string>(), origin, p + "functions"));
      const nlohmann::json& th = need(j, "theta", p, origin);
      if (!th.is_array()) throw ParseError(origin, 0, p + "theta", "expected an array of numbers");
      for (const auto& v : th) {
        if (!v.is_number()) throw ParseError(origin, 0, p + "theta", fmt::format("expected numbers, got {}", v.dump()));
        e.expression.theta.push_back(v.get<double>());
      }
      const int k_units = static_cast<int>(e.expression.functions.size());
      const int expected = ParFamExpression::parameter_count(e.expression.dim, k_units);
      if (static_cast<int>(e.expression.theta.size()) != expected)
        throw ParseError(origin, 0, p + "theta",
                         fmt::format("expected {} values (dim {}, {} functions), got {}", expected, e.expression.dim,
                                     k_units, e.expression.theta.size()));
      for (double v : e.expression.theta)
        if (!std::isfinite(v)) throw ParseError(origin, 0, p + "theta", "values must be finite numbers");
      e.expression.denominator_floor = j.contains("denominator_floor") ? positive(j, "denominator_floor", p, origin) : 0.05;
      if (e.expression.dim == 3) {
        e.hysteresis = {positive(j, "alpha", p, origin), positive(j, "beta", p, origin)};
        // the memory clock of h; files written before it existed used HESR's time clock
        if (j.contains("memory")) {
          const std::string m = j.at("memory").get<std::string>();
          if (m == "displacement")
            e.hysteresis.drive = HysteresisDrive::Displacement;
          else if (m != "time")
            throw ParseError(origin, 0, p + "memory", fmt::format("expected 'time' or 'displacement', got '{}'", m));
        }
      }
      // the optional input guard: both bounds, dim finite numbers each, min <= max
      if (j.contains("input_min") || j.contains("input_max")) {
        e.expression.input_min = need(j, "input_min", p, origin).get<std::vector<double>>();
        e.expression.input_max = need(j, "input_max", p, origin).get<std::vector<double>>();
        try {
          e.expression.validate();
        } catch (const InvalidArgument& err) {
          throw ParseError(origin, 0, p + "input_min", err.what());
        }
      }
      out.push_back(std::move(e));
    } catch (const nlohmann::json::type_error& err) {
      throw ParseError(origin, 0, p.substr(0, p.size() - 1), fmt::format("wrong type: {}", err.what()));
    }
  }
  return out;
}

}  // namespace twinwatch::friction
