#pragma once
/// @file parfam_family.hpp
/// Private: forward and reverse-mode evaluation of the ParFam family (parfam.hpp) at one sample,
/// shared by the expression, the Stage 2 loss gradient and the Stage 3 Jacobian.
#include <cmath>
#include <vector>

#include "twinwatch/friction/parfam.hpp"

namespace twinwatch::friction::detail {

/// exp(u) is evaluated at min(u, kExpCap): keeps every candidate finite during the search.
constexpr double kExpCap = 30.0;
constexpr int kMaxUnits = 8;

/// Offsets into theta (layout of ParFamExpression).
struct Layout {
  int d = 3;
  int k = 4;
  int inner(int j) const { return j * (d + 1); }  ///< a_j at inner(j) .. +d-1, b_j at inner(j)+d
  int num() const { return k * (d + 1); }         ///< c_0; c at num()+1; w at num()+1+d
  int den() const { return num() + 1 + d + k; }   ///< e at den(); v at den()+d
  int size() const { return den() + d + k; }
};

/// Values kept from the forward pass for the reverse pass.
struct Cache {
  double g[kMaxUnits];
  double gp[kMaxUnits];  ///< g'(u)
  double f = 0.0;
  double inv_d = 1.0;    ///< 1 / protected denominator
  bool clamped = false;  ///< the denominator hit the floor (no derivative through it)
};

/// Stribeck unit sgn(u) (1 - exp(-u^2)) (parfam.hpp), the deployed evaluator's form.
inline double stribeck_unit(double u) noexcept { return std::copysign(-std::expm1(-u * u), u); }

inline void unary(UnaryOp op, double u, double& g, double& gp) {
  switch (op) {
    case UnaryOp::Sin:
      g = std::sin(u);
      gp = std::cos(u);
      return;
    case UnaryOp::Cos:
      g = std::cos(u);
      gp = -std::sin(u);
      return;
    case UnaryOp::Exp:
      if (u > kExpCap) {
        g = std::exp(kExpCap);
        gp = 0.0;
      } else {
        g = std::exp(u);
        gp = g;
      }
      return;
    case UnaryOp::Tanh:
      g = std::tanh(u);
      gp = 1.0 - g * g;
      return;
    case UnaryOp::Stribeck:
      // sgn(u) (1 - exp(-u^2)), derivative 2 |u| exp(-u^2) = 2 |u| (1 - |g|)
      g = stribeck_unit(u);
      gp = 2.0 * std::abs(u) * (1.0 - std::abs(g));
      return;
  }
}

/// f(x); fills `c` for backward(). `rational`: whether the denominator is evaluated at all.
inline double forward(const Layout& L, const UnaryOp* ops, const double* th, const double* x, bool rational,
                      double floor, Cache& c) {
  double num = th[L.num()];
  double den = 1.0;
  for (int i = 0; i < L.d; ++i) {
    num += th[L.num() + 1 + i] * x[i];
    if (rational) den += th[L.den() + i] * x[i];
  }
  // units: u_j = a_j . x + b_j, g_j(u_j) into numerator and denominator
  for (int j = 0; j < L.k; ++j) {
    const double* a = th + L.inner(j);
    double u = a[L.d];
    for (int i = 0; i < L.d; ++i) u += a[i] * x[i];
    unary(ops[j], u, c.g[j], c.gp[j]);
    num += th[L.num() + 1 + L.d + j] * c.g[j];
    if (rational) den += th[L.den() + L.d + j] * c.g[j];
  }
  // protected division: |D| >= floor
  c.clamped = std::abs(den) < floor;
  if (c.clamped) den = std::copysign(floor, den);
  c.inv_d = 1.0 / den;
  c.f = num * c.inv_d;
  return c.f;
}

/// Adds s * df/dtheta to grad (size L.size()) and, when gx != nullptr, s * df/dx to gx (size d).
inline void backward(const Layout& L, const double* th, const double* x, bool rational, const Cache& c, double s,
                     double* grad, double* gx) {
  const double dn = s * c.inv_d;                                        // s df/dN
  const double dd = (rational && !c.clamped) ? -s * c.f * c.inv_d : 0.0;  // s df/dD
  grad[L.num()] += dn;
  for (int i = 0; i < L.d; ++i) {
    grad[L.num() + 1 + i] += dn * x[i];
    if (rational) grad[L.den() + i] += dd * x[i];
    if (gx) gx[i] += dn * th[L.num() + 1 + i] + (rational ? dd * th[L.den() + i] : 0.0);
  }
  for (int j = 0; j < L.k; ++j) {
    grad[L.num() + 1 + L.d + j] += dn * c.g[j];
    double dg = dn * th[L.num() + 1 + L.d + j];
    if (rational) {
      grad[L.den() + L.d + j] += dd * c.g[j];
      dg += dd * th[L.den() + L.d + j];
    }
    // through u_j = a_j . x + b_j
    const double du = dg * c.gp[j];
    if (du == 0.0) continue;
    const int o = L.inner(j);
    grad[o + L.d] += du;
    for (int i = 0; i < L.d; ++i) {
      grad[o + i] += du * x[i];
      if (gx) gx[i] += du * th[o + i];
    }
  }
}

}  // namespace twinwatch::friction::detail
