#pragma once
/// @file parfam.hpp
/// HESR's symbolic residual-torque model (§IV-C): ParFam symbolic regression [Scholl2025] over the
/// velocity (ParFam-V) or the hysteresis-augmented input x = [qd, h, hd] of eq. 11 (ParFam-H).
///
/// The parametric family (HESR eq. 14 with the paper's degree limit 1):
///
///   u_j  = a_j . x + b_j                              j = 1..k, one unit per function g_j
///   f(x) = (c_0 + c . x + sum_j w_j g_j(u_j)) / (1 + e . x + sum_j v_j g_j(u_j))
///
/// with g_j from {sin, cos, exp, tanh} (HESR's library) or the flat-at-zero Stribeck unit
/// stribeck(u) = sgn(u) (1 - exp(-u^2)) (not in HESR; see UnaryOp), and the arithmetic {+, -, x, /}
/// of the rational outer layer. Degree 1 means no products of inputs (no cross-unit terms such as qd * h). Protection:
/// exp(u) uses min(u, 30); a denominator D with |D| < floor is replaced by sign(D) * floor.
/// Identification, three stages:
///
///   1. (alpha, beta) from loop descriptors (hysteresis_prior.hpp, eq. 13);           [ParFam-H]
///   2. theta = argmin  1/N sum (tau_f,i - f_theta(x_i))^2 + gamma |theta|_1            (eq. 15)
///      by basin hopping [Wales1997] with L-BFGS local steps (NLopt LD_LBFGS, analytic gradient,
///      |theta| smoothed as sqrt(theta^2 + eps^2) - eps), coefficients below a threshold pruned,
///      dead units removed, the active expression refined on the mean-square error (plus a tiny
///      ridge that keeps weakly determined coefficients from drifting); a
///      ladder of thresholds is tried and the sparsest expression within a tolerance of the best
///      mean-square error is kept (ParFam's preference for the simplest adequate model);
///   3. min over (alpha, beta, theta_active) of sum (tau_f,i - f(qd_i, h_i, hd_i))^2   (eq. 16)
///      by Levenberg-Marquardt (Ceres), derivatives through the h recursion.      [ParFam-H]
///
/// Inputs and output are scaled to unit RMS during the search; the stored coefficients are in
/// physical units (qd [rad/s], h [-], hd [1/s], tau_f [N·m]).
#include <optional>
#include <string>
#include <vector>

#include "twinwatch/friction/friction_model.hpp"
#include "twinwatch/friction/hysteresis.hpp"
#include "twinwatch/friction/hysteresis_prior.hpp"

namespace twinwatch::friction {

/// The unary functions of the ParFam operator library. Sin, Cos, Exp, Tanh are HESR's; Stribeck is
/// an addition of this library:
///
///   stribeck(u) = sgn(u) (1 - exp(-u^2)),   stribeck'(u) = 2 |u| exp(-u^2)
///
/// odd, C^1, bounded by 1 and flat at u = 0 (stribeck(u) ~ u |u|), so that c h - w stribeck(qd / vs)
/// is the Gaussian Stribeck drop sgn(qd) (Fs - Fc) exp(-(qd/vs)^2) of [Armstrong1994] with h ~ sgn(qd)
/// in sliding. tanh, linear at 0, can only approximate that flat top: a sustained error in slow
/// motion, which a closed loop integrates (docs/validation.md, "Closed loop").
enum class UnaryOp { Sin, Cos, Exp, Tanh, Stribeck };

/// Lower-case name ("sin", "cos", "exp", "tanh", "stribeck").
std::string_view to_string(UnaryOp op) noexcept;

/// The operator named `name` (to_string's inverse); nullopt for any other text.
std::optional<UnaryOp> unary_op_from_string(std::string_view name) noexcept;

/// Whether g(-u) = -g(u) (sin, tanh, stribeck).
bool is_odd(UnaryOp op) noexcept;

/// One member of the family: the functions and the coefficients theta (physical units).
///
/// Layout of theta for input dimension d and k units:
///   [a_1 (d), b_1, ..., a_k (d), b_k,   c_0, c (d), w (k),   e (d), v (k)]
struct ParFamExpression {
  int dim = 3;                       ///< input dimension d: 1 (qd) or 3 (qd, h, hd)
  std::vector<UnaryOp> functions;    ///< g_1..g_k
  std::vector<double> theta;         ///< size parameter_count(dim, k)
  double denominator_floor = 0.05;   ///< protected division threshold, > 0
  /// Input guard: x_i is clamped to [input_min[i], input_max[i]] before evaluation, so the
  /// expression never extrapolates beyond the identified domain (an exp or a steep tanh of hd
  /// would otherwise run away on faster motion). Empty: no guard; else both of size dim.
  std::vector<double> input_min, input_max;

  /// Number of coefficients of the family: k (d + 1) + (1 + d + k) + (d + k).
  static int parameter_count(int dim, int k) noexcept { return k * (dim + 1) + 1 + dim + k + dim + k; }

  /// f(x) with the protections; x has `dim` entries.
  double operator()(const double* x) const noexcept;

  /// Readable equation in the style of HESR Table VII, e.g.
  /// "16.24*h - 0.163*hd - 2.128 + 37.72*tanh(0.193*qd - 0.606*h + 0.064*hd + 0.057)",
  /// zero coefficients omitted; a denominator only when one is active. `digits` significant digits.
  std::string to_string(int digits = 4) const;

  /// Number of non-zero coefficients.
  int active_coefficients() const noexcept;

  /// Throws InvalidArgument naming the field: dim not 1 or 3, no function, theta of the wrong
  /// size, a non-finite coefficient, floor <= 0, a guard of the wrong size or with min > max.
  void validate() const;
};

/// A flat, branch-light evaluator of an expression's active terms (the deployed form). Real-time
/// safe: evaluation is O(active units), no allocation.
class CompiledExpression {
 public:
  CompiledExpression() = default;
  /// Compiles the expression (validated); throws as ParFamExpression::validate().
  explicit CompiledExpression(const ParFamExpression& e);

  /// f(qd, h, hd); h and hd are ignored by a velocity-only expression.
  double operator()(double qd, double h, double hd) const noexcept;

  /// Units (non-zero function terms) kept.
  int units() const noexcept { return n_units_; }

 private:
  static constexpr int kMaxUnits = 8;
  struct Unit {
    double a[3] = {0.0, 0.0, 0.0};
    double b = 0.0;
    double w = 0.0;
    double v = 0.0;
    UnaryOp op = UnaryOp::Tanh;
  };
  Unit units_[kMaxUnits];
  int n_units_ = 0;
  double lo_[3] = {-1e300, -1e300, -1e300};  ///< input guard (no guard: +-1e300)
  double hi_[3] = {1e300, 1e300, 1e300};
  double c0_ = 0.0;
  double c_[3] = {0.0, 0.0, 0.0};
  double e_[3] = {0.0, 0.0, 0.0};
  bool rational_ = false;
  double floor_ = 0.05;
};

/// Which input ParFam sees.
enum class ParFamInput {
  Velocity,    ///< x = [qd]          (ParFam-V, the ablation)
  Hysteresis,  ///< x = [qd, h, hd]   (ParFam-H)
};

struct ParFamOptions {
  ParFamInput input = ParFamInput::Hysteresis;
  std::vector<UnaryOp> functions{UnaryOp::Sin, UnaryOp::Cos, UnaryOp::Exp, UnaryOp::Tanh};  ///< 1..8 units
  /// Include the denominator (the "/" operator). Off by default: on our data the rational outer
  /// layer bloated the expressions (large cancelling numerator/denominator coefficients) and
  /// extrapolated worse; HESR Table VII's equations have no division either.
  bool rational = false;
  /// Odd symmetry f(-x) = -f(x): the constant c_0 and the unit offsets b_j are fixed at 0 (with odd
  /// g_j and the odd inputs qd, h, hd of a symmetric memory the family is then odd). A friction law
  /// is odd in the velocity and the memory unless something breaks the symmetry; without the
  /// constraint the offsets fit noise and record asymmetries into a direction-independent bias.
  /// Needs odd functions only (is_odd) and rational = false.
  bool odd = false;
  double l1 = 1e-5;                   ///< gamma of eq. 15 (on unit-RMS data), >= 0
  double l1_smoothing = 1e-3;         ///< eps of the smoothed |theta|, > 0
  double coefficient_bound = 30.0;    ///< box |theta_i| <= bound during the search (unit-RMS data), > 0
  int starts = 2;                     ///< independent random starts of basin hopping, >= 1
  int hops = 12;                      ///< basin-hopping steps per start, >= 0
  double hop_step = 0.5;              ///< uniform perturbation half-width, > 0
  double hop_temperature = 0.1;       ///< Metropolis temperature relative to the current loss, > 0
  int local_evaluations = 100;        ///< L-BFGS evaluations per local step, >= 10
  int search_stride = 2;              ///< stage 2 global search on every k-th sample (refine: all), >= 1
  /// Pruning ladder: theta is pruned at each threshold (|theta_i| below it, unit-RMS data, set to 0)
  /// and refined; the sparsest result whose mse is within simplicity_tolerance of the best is kept.
  std::vector<double> prune_thresholds{0.01, 0.03, 0.1, 0.3};
  double simplicity_tolerance = 0.05;  ///< relative mse allowance for a sparser expression, >= 0
  int refine_evaluations = 500;       ///< L-BFGS evaluations of the final refine, >= 10
  double refine_ridge = 1e-6;         ///< ridge weight of the final refine (mse + ridge |theta|^2), >= 0
  double denominator_floor = 0.05;    ///< protected division, > 0
  /// Input guard of the identified expression: the training range of each input widened by this
  /// fraction of its width on both sides, >= 0; negative: no guard.
  double input_guard = 0.1;
  /// Reversal-weighted eq. 15: training samples within +-0.1 s of a velocity reversal (|qd| beyond
  /// 0.05 rad/s before the sign change) count this many times in Stage 2 and the refine, >= 1
  /// (1: the plain mean-square error of HESR). Stage 3 stays unweighted.
  int reversal_weight = 1;
  bool refine_hysteresis = true;      ///< run Stage 3 (ParFam-H only)
  int lm_iterations = 50;             ///< Stage 3 Levenberg-Marquardt iterations, >= 1
  HysteresisPriorOptions prior;       ///< Stage 1 grid
  std::optional<HysteresisParams> hysteresis;  ///< fixed (alpha, beta): skips Stage 1
  unsigned seed = 1;                  ///< seeds the random starts and hops
  /// Throws InvalidArgument naming the first field out of range.
  void validate() const;
};

/// ParFam-V / ParFam-H.
class ParFamModel final : public FrictionModel {
 public:
  explicit ParFamModel(ParFamOptions options = {});

  std::string_view name() const noexcept override;
  FitSummary fit(const FrictionRecord& record) override;
  bool fitted() const noexcept override { return fitted_; }
  void start(double dt) override;
  double step(double qd) noexcept override;
  /// A fitted model from a stored expression (e.g. a twin file's friction block): input from
  /// the expression's dim (1: ParFam-V, 3: ParFam-H with `hysteresis`). Throws InvalidArgument
  /// when the expression or the hysteresis parameters are invalid.
  static ParFamModel restore(const ParFamExpression& expression, const HysteresisParams& hysteresis = {});

  /// "tau_f = <expression>" and, for ParFam-H, "; (alpha, beta) = (a, b)".
  std::string equation() const override;

  const ParFamOptions& options() const noexcept { return options_; }
  /// The identified expression (physical units).
  const ParFamExpression& expression() const noexcept { return expression_; }
  /// (alpha, beta) after Stage 3 (ParFam-H).
  const HysteresisParams& hysteresis() const noexcept { return hysteresis_; }
  /// Stage 1 result (ParFam-H fitted without fixed hysteresis parameters).
  const std::optional<HysteresisPrior>& prior() const noexcept { return prior_; }
  /// The compiled evaluator.
  const CompiledExpression& compiled() const noexcept { return compiled_; }

 private:
  ParFamOptions options_;
  ParFamExpression expression_;
  CompiledExpression compiled_;
  HysteresisParams hysteresis_;
  std::optional<HysteresisPrior> prior_;
  std::optional<HysteresisState> state_;
  bool fitted_ = false;
};

}  // namespace twinwatch::friction
