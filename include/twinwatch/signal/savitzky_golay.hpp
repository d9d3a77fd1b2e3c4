#pragma once
/// @file savitzky_golay.hpp
/// Savitzky–Golay smoothing and differentiation [Savitzky1964] (UR3e §3.5 smooths qd with it), and
/// central differences (Cao). Batch, zero-phase. Edges as scipy's mode='interp': the polynomial
/// fitted to the first/last window is evaluated there.
#include <span>
#include <vector>

namespace twinwatch::signal {

struct SavitzkyGolay {
  int window = 11;   ///< odd, > order
  int order = 3;     ///< polynomial order
  int deriv = 0;     ///< 0 smooth, 1 first derivative, 2 second
  double delta = 1.0;  ///< sample spacing [s] (derivatives are per unit of delta)
  /// Throws InvalidArgument naming the field: window even or <= order, deriv > order, delta <= 0.
  void validate() const;
  /// Filters x (size >= window). Throws InvalidArgument on a too-short input.
  std::vector<double> apply(std::span<const double> x) const;
};

/// Central differences dx/dt with one-sided ends (sizes >= 2; dt > 0).
std::vector<double> central_difference(std::span<const double> x, double dt);

}  // namespace twinwatch::signal
