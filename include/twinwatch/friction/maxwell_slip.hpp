#pragma once
/// @file maxwell_slip.hpp
/// A truth friction model for simulated joints: the generalized Maxwell-slip (GMS) model
/// [AlBender2005] with a Stribeck curve and viscous friction. It has rate-independent pre-sliding
/// hysteresis with non-local memory (elasto-plastic elements that stick and slip one after the
/// other, Masing behaviour) and frictional lag in sliding -- and it is none of the families the twin
/// fits (not LuGre, not Stribeck, not an h-driven expression): DESIGN.md rule 2.
///
/// M elements, element i with stiffness k_i and a share w_i of the Stribeck curve
/// s(v) = Fc + (Fs - Fc) exp(-|v / vs|^delta), sum w_i = 1:
///
///   sticking:  dF_i/dt = k_i v,  until |F_i| reaches w_i s(v); then it slips
///   slipping:  F_i relaxes towards sgn(v) w_i s(v) with time constant T_lag (frictional lag),
///              until v changes sign; then it sticks again at its current force
///   tau_f = sum_i F_i + sigma2 v
///
/// Used by the evaluation code only (the twin never sees it: DESIGN.md rule 1).
#include <vector>

namespace twinwatch::friction {

/// One elasto-slide element.
struct MaxwellSlipElement {
  double stiffness = 1e4;  ///< k_i [N·m/rad], > 0
  double weight = 1.0;     ///< w_i, share of the Stribeck curve, > 0 (weights sum to 1)
  bool operator==(const MaxwellSlipElement&) const = default;
};

struct MaxwellSlipParams {
  std::vector<MaxwellSlipElement> elements;  ///< M >= 1
  double Fc = 1.0;        ///< Coulomb level [N·m], > 0
  double Fs = 1.2;        ///< static (break-away) level [N·m], >= Fc... any > 0
  double vs = 0.05;       ///< Stribeck velocity [rad/s], > 0
  double delta = 2.0;     ///< Stribeck shape exponent, > 0
  double sigma2 = 0.0;    ///< viscous coefficient [N·m·s/rad], >= 0
  double lag_time = 0.0;  ///< frictional-lag time constant T_lag of slipping elements [s], >= 0
  /// The same joint: every parameter equal.
  bool operator==(const MaxwellSlipParams&) const = default;

  /// Throws InvalidArgument naming the field (elements[i].stiffness etc.) and its value; the
  /// weights must sum to 1 within 1e-9.
  void validate() const;

  /// Displacement after a reversal at which element i breaks away at the Coulomb level:
  /// 2 w_i Fc / k_i [rad] (from -w_i Fc to +w_i Fc).
  double breakaway_displacement(int i) const;
};

/// The GMS state machine. step() is O(M), never throws, never allocates.
class MaxwellSlipFriction {
 public:
  /// Validates the parameters; all elements start relaxed (F_i = 0, sticking).
  explicit MaxwellSlipFriction(MaxwellSlipParams params);

  /// Relaxes every element.
  void reset() noexcept;

  /// Advances by h [s] (> 0) with the joint velocity v [rad/s] held, returns tau_f [N·m].
  double step(double v, double h) noexcept;

  /// tau_f at the current state and velocity v without advancing.
  double torque(double v) const noexcept;

  const MaxwellSlipParams& params() const noexcept { return params_; }
  /// Element forces F_i [N·m].
  const std::vector<double>& element_forces() const noexcept { return force_; }

 private:
  double stribeck(double v) const noexcept;
  MaxwellSlipParams params_;
  std::vector<double> force_;
  std::vector<signed char> slip_dir_;  ///< 0 sticking, +-1 slipping in that direction
};

}  // namespace twinwatch::friction
