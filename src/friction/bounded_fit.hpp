#pragma once
/// @file bounded_fit.hpp
/// Private: the global + local least-squares machinery shared by the physical baselines
/// (HESR §V-C: a bounded global search on the mean-square error, eq. 18, refined by local least
/// squares). Parameters are searched in coordinates u, with p = exp(u) for strictly positive
/// parameters spanning decades (stiffness, Stribeck velocity) and p = u otherwise.
#include <ceres/ceres.h>

#include <Eigen/Dense>

#include <cmath>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "twinwatch/friction/friction_model.hpp"

namespace twinwatch::friction::detail {

/// Bounds of one parameter, in parameter units; `log` searches u = ln p.
struct Bound {
  double lo = 0.0;
  double hi = 1.0;
  bool log = false;
  double u_lo() const { return log ? std::log(lo) : lo; }
  double u_hi() const { return log ? std::log(hi) : hi; }
};

/// p from u for one coordinate (works for doubles and ceres::Jet).
template <class T>
T to_param(const Bound& b, const T& u) {
  using std::exp;
  return b.log ? T(exp(u)) : u;
}

/// u from p, clamped into the bounds.
double to_search(const Bound& b, double p);

/// Best point of the global search, in search coordinates.
struct GlobalResult {
  std::vector<double> u;
  double mse = 0.0;
  long evaluations = 0;
};

/// NLopt GN_CRS2_LM (controlled random search with local mutation [Kaelo2006]) on mse(p) over
/// the box of `bounds`, at most `max_evaluations` calls, seeded; starts from `u0` when given.
/// Non-finite objective values count as +inf.
GlobalResult global_search(std::span<const Bound> bounds,
                           const std::function<double(std::span<const double> p)>& mse,
                           int max_evaluations, unsigned seed, std::span<const double> u0 = {});

/// Result of the local least-squares stage.
struct LocalResult {
  bool converged = false;
  long iterations = 0;
  std::string message;
};

/// Levenberg-Marquardt (Ceres, dense QR) of `cost` (one residual block, one parameter block u of
/// size bounds.size()) within the box of `bounds`; u is updated in place. Does not take ownership.
LocalResult local_least_squares(ceres::CostFunction& cost, std::span<const Bound> bounds,
                                std::vector<double>& u, int max_iterations);

/// Result of global_then_local().
struct BoundedFitResult {
  std::vector<double> p;  ///< best parameters (parameter units)
  double mse = 0.0;
  bool converged = false;
  long evaluations = 0;
  std::string message;
};

/// The part of a model searched globally: the parameters that enter nonlinearly. `project` maps
/// them to the full parameter vector (solving for the linear ones by least squares, variable
/// projection [Golub1973]) and returns the mean-square error there.
struct ProjectedSearch {
  std::vector<Bound> bounds;  ///< of the nonlinear parameters
  std::function<double(std::span<const double> nonlinear, std::vector<double>& full)> project;
};

/// The baselines' fit (HESR §V-C): global search (CRS2) over the nonlinear parameters of `search`,
/// then Levenberg-Marquardt over all parameters from its optimum and from `extra_starts` further
/// projected points drawn uniformly in the nonlinear box (seeded); the lowest mse wins.
/// `cost` gives the residuals tau_k - model_k in search coordinates of `bounds` (all parameters);
/// `mse` the mean-square error in parameter units.
BoundedFitResult global_then_local(const ProjectedSearch& search, std::span<const Bound> bounds,
                                   const std::function<double(std::span<const double> p)>& mse,
                                   ceres::CostFunction& cost, int global_evaluations,
                                   int local_iterations, int extra_starts, unsigned seed);

/// Least squares min |A x - y| with x_i >= 0 where nonneg[i], from the normal equations
/// (AtA = A^T A, Aty = A^T y, yty = y^T y) by enumerating active sets (for a handful of unknowns).
/// Returns the sum of squared residuals; x gets the solution.
double small_nonneg_least_squares(const Eigen::MatrixXd& AtA, const Eigen::VectorXd& Aty, double yty,
                                  const std::vector<bool>& nonneg, Eigen::VectorXd& x);

/// sqrt(mean r^2) of tau - prediction.
double rmse(std::span<const double> tau, std::span<const double> prediction);

/// Robust scales of a record used to place bounds: 99th percentile of |tau| [N·m] and of |qd|
/// [rad/s] (both floored at tiny positive values).
struct RecordScale {
  double tau = 1.0;
  double qd = 1.0;
};
RecordScale record_scale(const FrictionRecord& record);

}  // namespace twinwatch::friction::detail
