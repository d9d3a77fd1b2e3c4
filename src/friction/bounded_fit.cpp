#include "bounded_fit.hpp"

#include <fmt/format.h>
#include <nlopt.h>

#include <algorithm>
#include <limits>
#include <random>

namespace twinwatch::friction::detail {

double to_search(const Bound& b, double p) {
  const double clamped = std::clamp(p, b.lo, b.hi);
  return b.log ? std::log(clamped) : clamped;
}

namespace {

struct GlobalContext {
  std::span<const Bound> bounds;
  const std::function<double(std::span<const double>)>* mse;
  std::vector<double> p;
  long evaluations = 0;
};

double global_objective(unsigned n, const double* u, double* /*grad*/, void* data) {
  auto* ctx = static_cast<GlobalContext*>(data);
  ++ctx->evaluations;
  for (unsigned i = 0; i < n; ++i) ctx->p[i] = to_param(ctx->bounds[i], u[i]);
  const double f = (*ctx->mse)(ctx->p);
  return std::isfinite(f) ? f : std::numeric_limits<double>::max();
}

}  // namespace

GlobalResult global_search(std::span<const Bound> bounds,
                           const std::function<double(std::span<const double>)>& mse,
                           int max_evaluations, unsigned seed, std::span<const double> u0) {
  const auto n = static_cast<unsigned>(bounds.size());
  GlobalContext ctx{bounds, &mse, std::vector<double>(n), 0};
  std::vector<double> lo(n), hi(n), u(n);
  for (unsigned i = 0; i < n; ++i) {
    lo[i] = bounds[i].u_lo();
    hi[i] = bounds[i].u_hi();
    u[i] = u0.size() == n ? std::clamp(u0[i], lo[i], hi[i]) : 0.5 * (lo[i] + hi[i]);
  }
  // controlled random search over the box; deterministic through the seed
  nlopt_srand(seed);
  nlopt_opt opt = nlopt_create(NLOPT_GN_CRS2_LM, n);
  nlopt_set_lower_bounds(opt, lo.data());
  nlopt_set_upper_bounds(opt, hi.data());
  nlopt_set_min_objective(opt, global_objective, &ctx);
  nlopt_set_maxeval(opt, max_evaluations);
  // stop early once the population has collapsed onto one value
  constexpr double kGlobalFtolRel = 1e-10;
  nlopt_set_ftol_rel(opt, kGlobalFtolRel);
  double f = 0.0;
  nlopt_optimize(opt, u.data(), &f);
  nlopt_destroy(opt);
  return {u, f, ctx.evaluations};
}

LocalResult local_least_squares(ceres::CostFunction& cost, std::span<const Bound> bounds,
                                std::vector<double>& u, int max_iterations) {
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  problem.AddResidualBlock(&cost, nullptr, u.data());
  // the search box: Ceres projects trust-region steps onto it
  for (std::size_t i = 0; i < bounds.size(); ++i) {
    const int k = static_cast<int>(i);
    problem.SetParameterLowerBound(u.data(), k, bounds[i].u_lo());
    problem.SetParameterUpperBound(u.data(), k, bounds[i].u_hi());
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.max_num_iterations = max_iterations;
  options.logging_type = ceres::SILENT;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  LocalResult r;
  r.converged = summary.termination_type == ceres::CONVERGENCE;
  r.iterations = static_cast<long>(summary.iterations.size());
  r.message = fmt::format("Levenberg-Marquardt {} after {} iterations", summary.termination_type == ceres::CONVERGENCE ? "converged" : "stopped",
                          r.iterations);
  return r;
}

BoundedFitResult global_then_local(const ProjectedSearch& search, std::span<const Bound> bounds,
                                   const std::function<double(std::span<const double>)>& mse,
                                   ceres::CostFunction& cost, int global_evaluations,
                                   int local_iterations, int extra_starts, unsigned seed) {
  const std::size_t n = bounds.size();
  std::vector<double> full(n);
  const auto projected_mse = [&](std::span<const double> q) { return search.project(q, full); };
  // global search over the nonlinear parameters, the linear ones projected out
  const GlobalResult g = global_search(search.bounds, projected_mse, global_evaluations, seed);
  BoundedFitResult best;
  best.mse = std::numeric_limits<double>::infinity();
  best.evaluations = g.evaluations;
  // local least squares over all parameters from the global optimum, then from the extra starts
  std::mt19937_64 rng(seed);
  int improved_by_restart = 0;
  std::vector<double> q(search.bounds.size());
  for (int s = 0; s <= extra_starts; ++s) {
    for (std::size_t i = 0; i < q.size(); ++i)
      q[i] = to_param(search.bounds[i], s == 0 ? g.u[i]
                                               : std::uniform_real_distribution<double>(search.bounds[i].u_lo(),
                                                                                        search.bounds[i].u_hi())(rng));
    search.project(q, full);
    std::vector<double> u(n);
    for (std::size_t i = 0; i < n; ++i) u[i] = to_search(bounds[i], full[i]);
    const LocalResult l = local_least_squares(cost, bounds, u, local_iterations);
    best.evaluations += l.iterations + 1;
    std::vector<double> p(n);
    for (std::size_t i = 0; i < n; ++i) p[i] = to_param(bounds[i], u[i]);
    const double f = mse(p);
    if (std::isfinite(f) && f < best.mse) {
      if (s > 0) ++improved_by_restart;
      best.mse = f;
      best.p = std::move(p);
      best.converged = l.converged;
    }
  }
  best.message = fmt::format("CRS2 global search on {} projected parameters ({} evaluations, mse {:.4g}) + "
                             "Levenberg-Marquardt from it and {} random starts ({} improved)",
                             search.bounds.size(), g.evaluations, g.mse, extra_starts, improved_by_restart);
  return best;
}

double small_nonneg_least_squares(const Eigen::MatrixXd& AtA, const Eigen::VectorXd& Aty, double yty,
                                  const std::vector<bool>& nonneg, Eigen::VectorXd& x) {
  const auto m = static_cast<int>(Aty.size());
  std::vector<int> constrained;
  for (int i = 0; i < m; ++i)
    if (nonneg[static_cast<std::size_t>(i)]) constrained.push_back(i);
  double best = std::numeric_limits<double>::infinity();
  x = Eigen::VectorXd::Zero(m);
  // every subset of the constrained unknowns pinned at zero; keep the best feasible solution
  for (unsigned mask = 0; mask < (1u << constrained.size()); ++mask) {
    std::vector<int> free;
    for (int i = 0; i < m; ++i) {
      const auto it = std::find(constrained.begin(), constrained.end(), i);
      if (it == constrained.end() || !((mask >> (it - constrained.begin())) & 1u)) free.push_back(i);
    }
    Eigen::VectorXd xs = Eigen::VectorXd::Zero(m);
    if (!free.empty()) {
      const Eigen::MatrixXd Af = AtA(free, free);
      const Eigen::VectorXd bf = Aty(free);
      // tiny relative ridge: columns can be collinear (e.g. a Stribeck curve that is flat)
      constexpr double kRidge = 1e-12;
      Eigen::MatrixXd Ar = Af;
      Ar.diagonal().array() += kRidge * (Af.diagonal().array().abs().maxCoeff() + 1e-300);
      const Eigen::VectorXd sol = Ar.ldlt().solve(bf);
      xs(free) = sol;
    }
    bool feasible = true;
    for (int i : constrained) feasible = feasible && xs[i] >= 0.0;
    if (!feasible || !xs.allFinite()) continue;
    const double sse = yty - 2.0 * xs.dot(Aty) + xs.dot(AtA * xs);
    if (sse < best) {
      best = sse;
      x = xs;
    }
  }
  return std::max(best, 0.0);
}

double rmse(std::span<const double> tau, std::span<const double> prediction) {
  double s = 0.0;
  for (std::size_t k = 0; k < tau.size(); ++k) {
    const double e = tau[k] - prediction[k];
    s += e * e;
  }
  return tau.empty() ? 0.0 : std::sqrt(s / static_cast<double>(tau.size()));
}

namespace {
double percentile_abs(std::span<const double> x, double q) {
  std::vector<double> a(x.size());
  std::transform(x.begin(), x.end(), a.begin(), [](double v) { return std::abs(v); });
  const auto k = static_cast<std::size_t>(q * static_cast<double>(a.size() - 1));
  std::nth_element(a.begin(), a.begin() + static_cast<long>(k), a.end());
  return a[k];
}
}  // namespace

RecordScale record_scale(const FrictionRecord& record) {
  // the 99th percentile ignores single outliers; the floors keep the bounds non-degenerate
  constexpr double kQuantile = 0.99;
  constexpr double kTinyTau = 1e-9, kTinyQd = 1e-6;
  return {std::max(percentile_abs(record.tau, kQuantile), kTinyTau),
          std::max(percentile_abs(record.qd, kQuantile), kTinyQd)};
}

}  // namespace twinwatch::friction::detail
