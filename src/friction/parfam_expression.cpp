#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "parfam_family.hpp"
#include "twinwatch/core/error.hpp"
#include "twinwatch/friction/parfam.hpp"

namespace twinwatch::friction {

namespace {

constexpr const char* kInputNames[3] = {"qd", "h", "hd"};

/// "c1*n1 - c2*n2 + c0": the terms in order, zero ones left out, an empty name is a constant
/// ("0" when every term is zero).
std::string linear_combination(const std::vector<std::pair<double, std::string>>& terms, int digits) {
  std::string s;
  for (const auto& [c, name] : terms) {
    if (c == 0.0) continue;
    const std::string num = fmt::format("{:.{}g}", std::abs(c), digits);
    const std::string body = name.empty() ? num : (num == "1" ? name : num + "*" + name);
    if (s.empty())
      s = (c < 0.0 ? "-" : "") + body;
    else
      s += (c < 0.0 ? " - " : " + ") + body;
  }
  return s.empty() ? "0" : s;
}

}  // namespace

std::string_view to_string(UnaryOp op) noexcept {
  switch (op) {
    case UnaryOp::Sin:
      return "sin";
    case UnaryOp::Cos:
      return "cos";
    case UnaryOp::Exp:
      return "exp";
    case UnaryOp::Tanh:
      return "tanh";
    case UnaryOp::Stribeck:
      return "stribeck";
  }
  return "?";
}

std::optional<UnaryOp> unary_op_from_string(std::string_view name) noexcept {
  for (UnaryOp op : {UnaryOp::Sin, UnaryOp::Cos, UnaryOp::Exp, UnaryOp::Tanh, UnaryOp::Stribeck})
    if (to_string(op) == name) return op;
  return std::nullopt;
}

bool is_odd(UnaryOp op) noexcept { return op == UnaryOp::Sin || op == UnaryOp::Tanh || op == UnaryOp::Stribeck; }

void ParFamExpression::validate() const {
  if (dim != 1 && dim != 3) throw InvalidArgument(fmt::format("ParFam expression dim is {}, must be 1 or 3", dim));
  if (functions.empty() || static_cast<int>(functions.size()) > detail::kMaxUnits)
    throw InvalidArgument(fmt::format("ParFam expression has {} functions, expected 1..{}", functions.size(),
                                      detail::kMaxUnits));
  const int expected = parameter_count(dim, static_cast<int>(functions.size()));
  check_size("ParFam expression theta", static_cast<long>(theta.size()), expected,
             "parameter_count(dim, functions.size())");
  for (std::size_t i = 0; i < theta.size(); ++i)
    if (!std::isfinite(theta[i]))
      throw InvalidArgument(fmt::format("ParFam expression theta[{}] is {}, must be finite", i, theta[i]));
  if (!std::isfinite(denominator_floor) || denominator_floor <= 0.0)
    throw InvalidArgument(fmt::format("ParFam expression denominator_floor is {}, must be > 0", denominator_floor));
  if (input_min.size() != input_max.size())
    throw InvalidArgument(fmt::format("ParFam expression input_max has size {}, expected {} (size of input_min)",
                                      input_max.size(), input_min.size()));
  if (!input_min.empty()) {
    check_size("ParFam expression input_min", static_cast<long>(input_min.size()), dim, "dim");
    for (std::size_t i = 0; i < input_min.size(); ++i)
      if (!(input_min[i] <= input_max[i]) || !std::isfinite(input_min[i]) || !std::isfinite(input_max[i]))
        throw InvalidArgument(fmt::format("ParFam expression input guard {} is [{}, {}], expected finite min <= max", i,
                                          input_min[i], input_max[i]));
  }
}

double ParFamExpression::operator()(const double* x) const noexcept {
  const detail::Layout L{dim, static_cast<int>(functions.size())};
  bool rational = false;
  for (int i = L.den(); i < L.size(); ++i) rational = rational || theta[static_cast<std::size_t>(i)] != 0.0;
  detail::Cache c;
  if (input_min.empty()) return detail::forward(L, functions.data(), theta.data(), x, rational, denominator_floor, c);
  // the input guard
  double xg[3];
  for (int i = 0; i < dim; ++i)
    xg[i] = std::clamp(x[i], input_min[static_cast<std::size_t>(i)], input_max[static_cast<std::size_t>(i)]);
  return detail::forward(L, functions.data(), theta.data(), xg, rational, denominator_floor, c);
}

int ParFamExpression::active_coefficients() const noexcept {
  int n = 0;
  for (double t : theta) n += t != 0.0;
  return n;
}

std::string ParFamExpression::to_string(int digits) const {
  const detail::Layout L{dim, static_cast<int>(functions.size())};
  const auto th = [&](int i) { return theta[static_cast<std::size_t>(i)]; };
  using Terms = std::vector<std::pair<double, std::string>>;
  // c . x (+ constant) for the linear part starting at `lin`
  const auto inputs = [&](int lin, Terms& t) {
    for (int i = 0; i < L.d; ++i) t.emplace_back(th(lin + i), kInputNames[i]);
  };
  // w_j g_j(a_j . x + b_j) for the weights starting at `weights`
  const auto units = [&](int weights, Terms& t) {
    for (int j = 0; j < L.k; ++j) {
      if (th(weights + j) == 0.0) continue;
      Terms arg;
      inputs(L.inner(j), arg);
      arg.emplace_back(th(L.inner(j) + L.d), "");
      t.emplace_back(th(weights + j), fmt::format("{}({})", friction::to_string(functions[static_cast<std::size_t>(j)]),
                                                  linear_combination(arg, digits)));
    }
  };
  // numerator in HESR Table VII order: inputs, constant, functions
  Terms num;
  inputs(L.num() + 1, num);
  num.emplace_back(th(L.num()), "");
  units(L.num() + 1 + L.d, num);
  bool rational = false;
  for (int i = L.den(); i < L.size(); ++i) rational = rational || th(i) != 0.0;
  if (!rational) return linear_combination(num, digits);
  // denominator: 1, inputs, functions
  Terms den{{1.0, ""}};
  inputs(L.den(), den);
  units(L.den() + L.d, den);
  return fmt::format("({}) / ({})", linear_combination(num, digits), linear_combination(den, digits));
}

CompiledExpression::CompiledExpression(const ParFamExpression& e) {
  e.validate();
  const detail::Layout L{e.dim, static_cast<int>(e.functions.size())};
  const auto th = [&](int i) { return e.theta[static_cast<std::size_t>(i)]; };
  c0_ = th(L.num());
  floor_ = e.denominator_floor;
  // the input guard (h and hd stay unbounded for a velocity-only expression: they are ignored)
  for (std::size_t i = 0; i < e.input_min.size(); ++i) {
    lo_[i] = e.input_min[i];
    hi_[i] = e.input_max[i];
  }
  for (int i = 0; i < L.d; ++i) {
    c_[i] = th(L.num() + 1 + i);
    e_[i] = th(L.den() + i);
    rational_ = rational_ || e_[i] != 0.0;
  }
  // keep the units that reach the numerator or the denominator
  for (int j = 0; j < L.k; ++j) {
    const double w = th(L.num() + 1 + L.d + j), v = th(L.den() + L.d + j);
    if (w == 0.0 && v == 0.0) continue;
    Unit& u = units_[n_units_++];
    for (int i = 0; i < L.d; ++i) u.a[i] = th(L.inner(j) + i);
    u.b = th(L.inner(j) + L.d);
    u.w = w;
    u.v = v;
    u.op = e.functions[static_cast<std::size_t>(j)];
    rational_ = rational_ || v != 0.0;
  }
}

double CompiledExpression::operator()(double qd, double h, double hd) const noexcept {
  qd = std::clamp(qd, lo_[0], hi_[0]);
  h = std::clamp(h, lo_[1], hi_[1]);
  hd = std::clamp(hd, lo_[2], hi_[2]);
  double num = c0_ + c_[0] * qd + c_[1] * h + c_[2] * hd;
  double den = 1.0 + e_[0] * qd + e_[1] * h + e_[2] * hd;
  for (int j = 0; j < n_units_; ++j) {
    const Unit& u = units_[j];
    const double arg = u.a[0] * qd + u.a[1] * h + u.a[2] * hd + u.b;
    double g;
    switch (u.op) {
      case UnaryOp::Sin:
        g = std::sin(arg);
        break;
      case UnaryOp::Cos:
        g = std::cos(arg);
        break;
      case UnaryOp::Exp:
        g = std::exp(std::min(arg, detail::kExpCap));
        break;
      case UnaryOp::Stribeck:
        g = detail::stribeck_unit(arg);
        break;
      default:
        g = std::tanh(arg);
        break;
    }
    num += u.w * g;
    den += u.v * g;
  }
  if (!rational_) return num;
  // protected division, as during identification
  if (std::abs(den) < floor_) den = std::copysign(floor_, den);
  return num / den;
}

}  // namespace twinwatch::friction
