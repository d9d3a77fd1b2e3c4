#pragma once
/// @file hysteresis_prior.hpp
/// Stage 1 of HESR (§IV-C): pre-calibration of the hysteresis parameters (alpha, beta) by a
/// bounded grid on loop descriptors,
///
///   J_h(alpha, beta) = w_a |D_tau - D_h| + w_s |s_tau - s_h|                      (HESR eq. 13)
///
/// where D is the normalised loop width at velocity reversals and s the normalised slope near
/// qd = 0, of the measured tau_f-qd loop and of the generated h-qd loop (eq. 11). The paper names
/// the descriptors but not their formulas; ours are:
///
/// - reversals: sign changes of qd between excursions beyond +-v_ref (noise-proof);
/// - width D = (mean y at downward zero crossings - mean y at upward zero crossings) / range(y):
///   the height of the loop at qd = 0 (0 for a single-valued curve, 1 for a full jump);
/// - slope s = mean over reversals of sgn(new qd) (y(|qd| reaches v_ref) - y(qd = 0)) / range(y):
///   how much of the transition happens within v_ref of the reversal.
///
/// range(y) is the 1st-99th percentile spread; y at qd = 0 is interpolated between samples, and tau_f
/// is smoothed by a 5-sample centred moving average for the descriptors only.
#include <span>

#include "twinwatch/friction/friction_model.hpp"
#include "twinwatch/friction/hysteresis.hpp"

namespace twinwatch::friction {

/// Loop descriptors of a y-qd loop.
struct LoopDescriptors {
  double width = 0.0;  ///< D, normalised loop width at qd = 0 [-]
  double slope = 0.0;  ///< s, normalised transition within v_ref [-]
  int reversals = 0;   ///< velocity reversals used
};

/// Descriptors of y against qd (equal sizes >= 3) with the reversal threshold v_ref [rad/s] > 0.
/// reversals = 0 (and width = slope = 0) when qd never reverses. Throws InvalidArgument on sizes
/// or v_ref.
LoopDescriptors loop_descriptors(std::span<const double> qd, std::span<const double> y, double v_ref);

struct HysteresisPriorOptions {
  /// The memory clock of h (hysteresis.hpp); selects the alpha range below.
  HysteresisDrive drive = HysteresisDrive::Time;
  double alpha_min = 1.0;      ///< [1/s], > 0 (Time)
  double alpha_max = 100.0;    ///< [1/s], > alpha_min; clipped to 0.9/dt (stability of eq. 11) (Time)
  /// Displacement clock: 1/alpha is the pre-sliding distance, here 0.3 mrad .. 0.1 rad.
  double displacement_alpha_min = 10.0;    ///< [1/rad], > 0
  double displacement_alpha_max = 3000.0;  ///< [1/rad], > displacement_alpha_min
  double beta_min = 10.0;      ///< [s/rad], > 0
  double beta_max = 1000.0;    ///< [s/rad], > beta_min
  int grid = 16;               ///< log-spaced points per axis, >= 2
  double weight_width = 1.0;   ///< w_a, >= 0
  double weight_slope = 1.0;   ///< w_s, >= 0 (w_a + w_s > 0)
  double v_ref_fraction = 0.1; ///< v_ref = this * 99th percentile of |qd|, in (0, 1)
  /// Remove the viscous part of tau_f before its descriptors: c1 of the least-squares fit
  /// tau_f ~ c0 + c1 qd + c2 sgn(qd) on the sliding samples (|qd| >= v_ref), c1 qd subtracted.
  /// h has no viscous part, so without this the measured loop is compared with h over a range
  /// stretched by c1 * 2 max|qd| (the width of a saturating h then never matches, and the grid
  /// drifts to the smallest beta, where h stops saturating).
  bool remove_viscous = false;
  /// Throws InvalidArgument naming the first field out of range.
  void validate() const;
  /// The start when Stage 1 cannot run (no reversal in the record): HysteresisParams' defaults
  /// (10 1/s, 100 s/rad) in the time clock; in the displacement clock the geometric middle of
  /// the displacement alpha range, beta 100 s/rad.
  HysteresisParams fallback() const noexcept;
};

/// Result of Stage 1.
struct HysteresisPrior {
  HysteresisParams params;     ///< the grid point of least J_h
  double cost = 0.0;           ///< J_h there
  LoopDescriptors measured;    ///< of tau_f
  LoopDescriptors generated;   ///< of h at `params`
};

/// Stage 1 on a residual-torque record. Throws InvalidArgument on a bad record/options, or when
/// qd never reverses (no loop to calibrate on).
HysteresisPrior calibrate_hysteresis_prior(const FrictionRecord& record, const HysteresisPriorOptions& options = {});

}  // namespace twinwatch::friction
