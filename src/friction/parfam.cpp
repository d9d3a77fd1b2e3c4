#include "twinwatch/friction/parfam.hpp"

#include <ceres/ceres.h>
#include <fmt/format.h>
#include <nlopt.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>

#include "parfam_family.hpp"
#include "twinwatch/friction/study.hpp"
#include "parfam_stage3.hpp"
#include "twinwatch/core/error.hpp"

namespace twinwatch::friction {

namespace {

using detail::Cache;
using detail::Layout;

// Stage 3 bounds of the hysteresis parameters: beta [s/rad] (tanh(1e5 qd) = sgn(qd) to 1e-12 for
// |qd| >= 1.5e-4 rad/s, below a 20-bit encoder's velocity resolution at 200 Hz) and, in the
// displacement clock, alpha [1/rad] (a pre-sliding distance of 1 urad)
constexpr double kMaxBeta = 1e5;
constexpr double kMaxDisplacementAlpha = 1e6;

// floor of an input/output RMS used for scaling (a constant-zero column stays unscaled)
constexpr double kMinScale = 1e-12;

/// The scaled training data: x row-major n x d, y of size n.
struct ScaledData {
  int n = 0;
  int d = 1;
  std::vector<double> x;
  std::vector<double> y;
};

/// Everything the Stage 2 loss needs; theta is the full vector, `active` the optimised indices.
struct LossContext {
  const ScaledData* data = nullptr;
  Layout L;
  const UnaryOp* ops = nullptr;
  bool rational = true;
  double floor = 0.05;
  double gamma = 0.0;
  double ridge = 0.0;
  double eps = 1e-3;
  std::vector<int> active;
  std::vector<double> theta;
  std::vector<double> grad_full;
  long evaluations = 0;
};

/// HESR eq. 15 on the active coefficients z (smoothed L1), with its analytic gradient.
double stage2_loss(unsigned n, const double* z, double* grad, void* data) {
  auto* c = static_cast<LossContext*>(data);
  ++c->evaluations;
  for (unsigned a = 0; a < n; ++a) c->theta[static_cast<std::size_t>(c->active[a])] = z[a];
  if (grad) std::fill(c->grad_full.begin(), c->grad_full.end(), 0.0);
  // mean-square error and its reverse pass, sample by sample
  const ScaledData& D = *c->data;
  const double inv_n = 1.0 / D.n;
  double mse = 0.0;
  Cache cache;
  for (int k = 0; k < D.n; ++k) {
    const double* x = &D.x[static_cast<std::size_t>(k * D.d)];
    const double r = detail::forward(c->L, c->ops, c->theta.data(), x, c->rational, c->floor, cache) -
                     D.y[static_cast<std::size_t>(k)];
    mse += r * r;
    if (grad) detail::backward(c->L, c->theta.data(), x, c->rational, cache, 2.0 * r * inv_n, c->grad_full.data(), nullptr);
  }
  mse *= inv_n;
  // smoothed L1: |t| ~ sqrt(t^2 + eps^2) - eps
  // plus a ridge term when refining (keeps weakly determined coefficients from drifting)
  double l1 = 0.0, l2 = 0.0;
  for (unsigned a = 0; a < n; ++a) {
    const double s = std::sqrt(z[a] * z[a] + c->eps * c->eps);
    l1 += s - c->eps;
    l2 += z[a] * z[a];
    if (grad) grad[a] = c->grad_full[static_cast<std::size_t>(c->active[a])] + c->gamma * z[a] / s + 2.0 * c->ridge * z[a];
  }
  const double f = mse + c->gamma * l1 + c->ridge * l2;
  return std::isfinite(f) ? f : std::numeric_limits<double>::max();
}

/// L-BFGS (NLopt LD_LBFGS) of the loss from z within |z_i| <= bound; returns the loss.
double local_lbfgs(LossContext& ctx, std::vector<double>& z, double bound, int max_evaluations) {
  const auto n = static_cast<unsigned>(z.size());
  if (n == 0) return stage2_loss(0, nullptr, nullptr, &ctx);
  nlopt_opt opt = nlopt_create(NLOPT_LD_LBFGS, n);
  std::vector<double> lo(n, -bound), hi(n, bound);
  for (unsigned i = 0; i < n; ++i) z[i] = std::clamp(z[i], -bound, bound);
  nlopt_set_lower_bounds(opt, lo.data());
  nlopt_set_upper_bounds(opt, hi.data());
  nlopt_set_min_objective(opt, stage2_loss, &ctx);
  nlopt_set_maxeval(opt, max_evaluations);
  constexpr double kFtolRel = 1e-10;  // relative loss change at which a local step has converged
  nlopt_set_ftol_rel(opt, kFtolRel);
  double f = std::numeric_limits<double>::max();
  const nlopt_result r = nlopt_optimize(opt, z.data(), &f);
  nlopt_destroy(opt);
  if (r < 0 && r != NLOPT_ROUNDOFF_LIMITED) {
    // a failed line search keeps the best point NLopt reached; re-evaluate it
    f = stage2_loss(n, z.data(), nullptr, &ctx);
  }
  return f;
}

/// Stage 2 basin hopping [Wales1997] over every coefficient (the denominator's only when
/// ctx.rational); returns the best full theta.
std::vector<double> basin_hopping(LossContext& ctx, const ParFamOptions& o, double& best_loss) {
  const int P_all = ctx.rational ? ctx.L.size() : ctx.L.den();
  // odd symmetry: the constant c_0 and the offsets b_j stay 0
  ctx.active.clear();
  for (int i = 0; i < P_all; ++i) {
    bool offset = i == ctx.L.num();
    for (int j = 0; j < ctx.L.k; ++j) offset = offset || i == ctx.L.inner(j) + ctx.L.d;
    if (!(o.odd && offset)) ctx.active.push_back(i);
  }
  const auto P = static_cast<int>(ctx.active.size());
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), accept(0.0, 1.0);
  std::vector<double> best;
  best_loss = std::numeric_limits<double>::infinity();
  for (int s = 0; s < o.starts; ++s) {
    // random start in [-1, 1]^P (unit-RMS data), then a local minimum
    std::vector<double> z(static_cast<std::size_t>(P));
    for (double& v : z) v = unit(rng);
    double f = local_lbfgs(ctx, z, o.coefficient_bound, o.local_evaluations);
    if (f < best_loss) {
      best_loss = f;
      best = z;
    }
    // hops: perturb, minimise locally, accept by the Metropolis rule on the relative loss change
    for (int h = 0; h < o.hops; ++h) {
      std::vector<double> trial = z;
      for (double& v : trial) v += o.hop_step * unit(rng);
      const double ft = local_lbfgs(ctx, trial, o.coefficient_bound, o.local_evaluations);
      if (ft < best_loss) {
        best_loss = ft;
        best = trial;
      }
      const double temperature = o.hop_temperature * std::max(f, std::numeric_limits<double>::min());
      if (ft < f || accept(rng) < std::exp(-(ft - f) / temperature)) {
        z = std::move(trial);
        f = ft;
      }
    }
  }
  std::vector<double> theta(static_cast<std::size_t>(ctx.L.size()), 0.0);
  for (std::size_t a = 0; a < best.size(); ++a) theta[static_cast<std::size_t>(ctx.active[a])] = best[a];
  return theta;
}

/// Pruning and simplification of theta: small coefficients to 0; units that reach neither the
/// numerator nor the denominator lose their arguments; units with a constant argument are folded
/// into the constants (the denominator keeps its leading 1 by dividing through).
void prune(const Layout& L, const UnaryOp* ops, double threshold, std::vector<double>& th) {
  const auto at = [&](int i) -> double& { return th[static_cast<std::size_t>(i)]; };
  for (double& t : th)
    if (std::abs(t) < threshold) t = 0.0;
  for (int j = 0; j < L.k; ++j) {
    double& w = at(L.num() + 1 + L.d + j);
    double& v = at(L.den() + L.d + j);
    bool constant_argument = true;
    for (int i = 0; i < L.d; ++i) constant_argument = constant_argument && at(L.inner(j) + i) == 0.0;
    if (w == 0.0 && v == 0.0) {
      for (int i = 0; i <= L.d; ++i) at(L.inner(j) + i) = 0.0;
      continue;
    }
    if (!constant_argument) continue;
    // g_j(b_j) is a constant: fold it
    double g = 0.0, gp = 0.0;
    detail::unary(ops[j], at(L.inner(j) + L.d), g, gp);
    at(L.num()) += w * g;
    w = 0.0;
    const double kappa = 1.0 + v * g;
    v = 0.0;
    at(L.inner(j) + L.d) = 0.0;
    constexpr double kMinKappa = 1e-9;
    if (std::abs(kappa) > kMinKappa && kappa != 1.0) {
      at(L.num()) /= kappa;
      for (int i = 0; i < L.d; ++i) {
        at(L.num() + 1 + i) /= kappa;
        at(L.den() + i) /= kappa;
      }
      for (int q = 0; q < L.k; ++q) {
        at(L.num() + 1 + L.d + q) /= kappa;
        at(L.den() + L.d + q) /= kappa;
      }
    }
  }
}

double rms(const std::vector<double>& v, std::size_t stride, std::size_t offset) {
  double s = 0.0;
  std::size_t n = 0;
  for (std::size_t k = offset; k < v.size(); k += stride, ++n) s += v[k] * v[k];
  return n ? std::sqrt(s / static_cast<double>(n)) : 0.0;
}

}  // namespace

void ParFamOptions::validate() const {
  if (functions.empty() || static_cast<int>(functions.size()) > detail::kMaxUnits)
    throw InvalidArgument(fmt::format("ParFam functions has {} entries, expected 1..{}", functions.size(),
                                      detail::kMaxUnits));
  if (!std::isfinite(l1) || l1 < 0.0) throw InvalidArgument(fmt::format("ParFam l1 is {}, must be >= 0", l1));
  if (!std::isfinite(l1_smoothing) || l1_smoothing <= 0.0)
    throw InvalidArgument(fmt::format("ParFam l1_smoothing is {}, must be > 0", l1_smoothing));
  if (!std::isfinite(coefficient_bound) || coefficient_bound <= 0.0)
    throw InvalidArgument(fmt::format("ParFam coefficient_bound is {}, must be > 0", coefficient_bound));
  if (starts < 1) throw InvalidArgument(fmt::format("ParFam starts is {}, must be >= 1", starts));
  if (hops < 0) throw InvalidArgument(fmt::format("ParFam hops is {}, must be >= 0", hops));
  if (!std::isfinite(hop_step) || hop_step <= 0.0)
    throw InvalidArgument(fmt::format("ParFam hop_step is {}, must be > 0", hop_step));
  if (!std::isfinite(hop_temperature) || hop_temperature <= 0.0)
    throw InvalidArgument(fmt::format("ParFam hop_temperature is {}, must be > 0", hop_temperature));
  if (search_stride < 1) throw InvalidArgument(fmt::format("ParFam search_stride is {}, must be >= 1", search_stride));
  if (local_evaluations < 10)
    throw InvalidArgument(fmt::format("ParFam local_evaluations is {}, must be >= 10", local_evaluations));
  if (prune_thresholds.empty()) throw InvalidArgument("ParFam prune_thresholds is empty, expected at least one");
  for (std::size_t i = 0; i < prune_thresholds.size(); ++i)
    if (!std::isfinite(prune_thresholds[i]) || prune_thresholds[i] < 0.0)
      throw InvalidArgument(fmt::format("ParFam prune_thresholds[{}] is {}, must be >= 0", i, prune_thresholds[i]));
  if (!std::isfinite(simplicity_tolerance) || simplicity_tolerance < 0.0)
    throw InvalidArgument(fmt::format("ParFam simplicity_tolerance is {}, must be >= 0", simplicity_tolerance));
  if (refine_evaluations < 10)
    throw InvalidArgument(fmt::format("ParFam refine_evaluations is {}, must be >= 10", refine_evaluations));
  if (!std::isfinite(denominator_floor) || denominator_floor <= 0.0)
    throw InvalidArgument(fmt::format("ParFam denominator_floor is {}, must be > 0", denominator_floor));
  if (reversal_weight < 1)
    throw InvalidArgument(fmt::format("ParFam reversal_weight is {}, must be >= 1", reversal_weight));
  if (!std::isfinite(input_guard)) throw InvalidArgument(fmt::format("ParFam input_guard is {}, must be finite", input_guard));
  if (!std::isfinite(refine_ridge) || refine_ridge < 0.0)
    throw InvalidArgument(fmt::format("ParFam refine_ridge is {}, must be >= 0", refine_ridge));
  if (lm_iterations < 1) throw InvalidArgument(fmt::format("ParFam lm_iterations is {}, must be >= 1", lm_iterations));
  if (odd) {
    for (std::size_t j = 0; j < functions.size(); ++j)
      if (!is_odd(functions[j]))
        throw InvalidArgument(fmt::format("ParFam odd is set but functions[{}] is {}, expected an odd function "
                                          "(sin, tanh, stribeck)",
                                          j, to_string(functions[j])));
    if (rational) throw InvalidArgument("ParFam odd is set with rational = true, expected rational = false");
  }
  if (input == ParFamInput::Hysteresis) {
    if (hysteresis) hysteresis->validate();
    prior.validate();
  }
}

ParFamModel::ParFamModel(ParFamOptions options) : options_(std::move(options)) { options_.validate(); }

std::string_view ParFamModel::name() const noexcept {
  return options_.input == ParFamInput::Velocity ? "ParFam-V" : "ParFam-H";
}

FitSummary ParFamModel::fit(const FrictionRecord& record) {
  const int d = options_.input == ParFamInput::Velocity ? 1 : 3;
  const Layout L{d, static_cast<int>(options_.functions.size())};
  record.validate("training record", L.size() + 1);
  const auto t0 = std::chrono::steady_clock::now();
  FitSummary out;
  std::string stage1;
  // stage 1: (alpha, beta) from the loop descriptors (or as given)
  if (d == 3) {
    if (options_.hysteresis) {
      hysteresis_ = *options_.hysteresis;
      prior_.reset();
      stage1 = fmt::format("(alpha, beta) fixed at ({:.4g}, {:.4g})", hysteresis_.alpha, hysteresis_.beta);
    } else {
      prior_ = calibrate_hysteresis_prior(record, options_.prior);
      hysteresis_ = prior_->params;
      stage1 = fmt::format("stage 1 ({} clock) (alpha, beta) = ({:.4g}, {:.4g}), J_h {:.3g}",
                           to_string(hysteresis_.drive), hysteresis_.alpha, hysteresis_.beta, prior_->cost);
    }
    HysteresisState(hysteresis_, record.dt);  // throws when eq. 11 is unstable at this dt
  }
  // inputs and output scaled to unit RMS
  ScaledData data;
  data.n = static_cast<int>(record.size());
  data.d = d;
  data.x.resize(static_cast<std::size_t>(data.n * d));
  {
    HysteresisFeatures f;
    if (d == 3) f = hysteresis_features(record.qd, record.dt, hysteresis_);
    for (int k = 0; k < data.n; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      data.x[kk * static_cast<std::size_t>(d)] = record.qd[kk];
      if (d == 3) {
        data.x[kk * 3 + 1] = f.h[kk];
        data.x[kk * 3 + 2] = f.hd[kk];
      }
    }
  }
  double sx[3] = {1.0, 1.0, 1.0};
  for (int i = 0; i < d; ++i) {
    sx[i] = std::max(rms(data.x, static_cast<std::size_t>(d), static_cast<std::size_t>(i)), kMinScale);
    for (int k = 0; k < data.n; ++k) data.x[static_cast<std::size_t>(k * d + i)] /= sx[i];
  }
  const double sy = std::max(rms(record.tau, 1, 0), kMinScale);
  data.y.resize(record.tau.size());
  for (std::size_t k = 0; k < record.tau.size(); ++k) data.y[k] = record.tau[k] / sy;
  // reversal weighting: the samples near reversals appended (weight - 1) more times
  if (options_.reversal_weight > 1) {
    constexpr double kWindow = 0.1, kThreshold = 0.05;  // [s], [rad/s]: HESR's reversal windows
    const std::vector<char> rev = reversal_window_mask(record.qd, record.dt, kWindow, kThreshold);
    const int n0 = data.n;
    for (int w = 1; w < options_.reversal_weight; ++w)
      for (int k = 0; k < n0; ++k) {
        if (!rev[static_cast<std::size_t>(k)]) continue;
        for (int i = 0; i < d; ++i) data.x.push_back(data.x[static_cast<std::size_t>(k * d + i)]);
        data.y.push_back(data.y[static_cast<std::size_t>(k)]);
        ++data.n;
      }
  }
  // stage 2: basin hopping on eq. 15, pruning, final refine on the mean-square error
  LossContext ctx;
  ctx.data = &data;
  ctx.L = L;
  ctx.ops = options_.functions.data();
  ctx.rational = options_.rational;
  ctx.floor = options_.denominator_floor;
  ctx.gamma = options_.l1;
  ctx.eps = options_.l1_smoothing;
  ctx.theta.assign(static_cast<std::size_t>(L.size()), 0.0);
  ctx.grad_full.assign(static_cast<std::size_t>(L.size()), 0.0);
  // the global search runs on every search_stride-th sample
  ScaledData coarse;
  coarse.d = d;
  for (int k = 0; k < data.n; k += options_.search_stride) {
    ++coarse.n;
    coarse.y.push_back(data.y[static_cast<std::size_t>(k)]);
    for (int i = 0; i < d; ++i) coarse.x.push_back(data.x[static_cast<std::size_t>(k * d + i)]);
  }
  ctx.data = &coarse;
  double global_loss = 0.0;
  std::vector<double> theta = basin_hopping(ctx, options_, global_loss);
  ctx.data = &data;
  // pruning at each threshold of the ladder, each survivor refined on the mean-square error;
  // the sparsest whose mse is within simplicity_tolerance of the best wins (Occam)
  struct Candidate {
    std::vector<double> theta;
    std::vector<int> active;
    bool rational = false;
    double mse = 0.0;
    double threshold = 0.0;
  };
  std::vector<Candidate> candidates;
  ctx.gamma = 0.0;
  ctx.ridge = options_.refine_ridge;
  for (double threshold : options_.prune_thresholds) {
    Candidate c;
    c.threshold = threshold;
    c.theta = theta;
    prune(L, ctx.ops, threshold, c.theta);
    for (int i = 0; i < L.size(); ++i)
      if (c.theta[static_cast<std::size_t>(i)] != 0.0) c.active.push_back(i);
    for (int i = L.den(); i < L.size(); ++i) c.rational = c.rational || c.theta[static_cast<std::size_t>(i)] != 0.0;
    // a threshold that prunes nothing more than the previous one gives the same candidate
    if (!candidates.empty() && candidates.back().active == c.active) continue;
    ctx.theta = c.theta;
    ctx.active = c.active;
    ctx.rational = c.rational;
    std::vector<double> z;
    for (int i : c.active) z.push_back(c.theta[static_cast<std::size_t>(i)]);
    local_lbfgs(ctx, z, options_.coefficient_bound, options_.refine_evaluations);
    // the candidates are compared on the mean-square error alone
    ctx.ridge = 0.0;
    c.mse = stage2_loss(static_cast<unsigned>(z.size()), z.data(), nullptr, &ctx);
    ctx.ridge = options_.refine_ridge;
    for (std::size_t a = 0; a < z.size(); ++a) c.theta[static_cast<std::size_t>(c.active[a])] = z[a];
    candidates.push_back(std::move(c));
  }
  double best_mse = std::numeric_limits<double>::infinity();
  for (const Candidate& c : candidates) best_mse = std::min(best_mse, c.mse);
  const Candidate* chosen = nullptr;
  for (const Candidate& c : candidates)
    if (c.mse <= best_mse * (1.0 + options_.simplicity_tolerance) &&
        (!chosen || c.active.size() < chosen->active.size()))
      chosen = &c;
  theta = chosen->theta;
  ctx.active = chosen->active;
  const bool rational = chosen->rational;
  const double refined_mse = chosen->mse;
  std::vector<double> z;
  for (int i : ctx.active) z.push_back(theta[static_cast<std::size_t>(i)]);
  long evaluations = ctx.evaluations;
  std::string stage3 = "stage 3 skipped";
  // stage 3: Levenberg-Marquardt on (alpha, beta, theta_active), eq. 16
  if (d == 3 && options_.refine_hysteresis && !z.empty()) {
    double ab[2] = {std::log(hysteresis_.alpha), std::log(hysteresis_.beta)};
    std::vector<double> active_theta = z;
    ceres::Problem problem;
    problem.AddResidualBlock(new detail::Stage3Cost(record.qd, record.dt, sx, data.y, L, ctx.ops, rational,
                                            options_.denominator_floor, theta, ctx.active, hysteresis_.drive),
                             nullptr, ab, active_theta.data());
    constexpr double kStableFraction = 0.95;  // keep 1 - alpha dt away from 0
    if (hysteresis_.drive == HysteresisDrive::Time)
      problem.SetParameterUpperBound(ab, 0, std::log(kStableFraction / record.dt));
    else
      problem.SetParameterUpperBound(ab, 0, std::log(kMaxDisplacementAlpha));
    // beta beyond this is sign(qd) for every measurable velocity; unbounded, LM drove it to 1e49
    // and beyond (tanh(inf * 0) is NaN at a sample with qd = 0)
    problem.SetParameterUpperBound(ab, 1, std::log(kMaxBeta));
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::DENSE_QR;
    so.max_num_iterations = options_.lm_iterations;
    so.logging_type = ceres::SILENT;
    so.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    if (summary.IsSolutionUsable() && summary.final_cost <= summary.initial_cost) {
      hysteresis_ = {std::exp(ab[0]), std::exp(ab[1]), hysteresis_.drive};
      for (std::size_t a = 0; a < z.size(); ++a) theta[static_cast<std::size_t>(ctx.active[a])] = active_theta[a];
    }
    evaluations += static_cast<long>(summary.iterations.size());
    stage3 = fmt::format("stage 3 LM {} iterations, (alpha, beta) = ({:.4g}, {:.4g}), mse {:.3g} -> {:.3g}",
                         summary.iterations.size(), hysteresis_.alpha, hysteresis_.beta,
                         2.0 * summary.initial_cost / data.n, 2.0 * summary.final_cost / data.n);
  }
  // back to physical units: x = sx xs, tau = sy ys
  for (int j = 0; j < L.k; ++j)
    for (int i = 0; i < d; ++i) theta[static_cast<std::size_t>(L.inner(j) + i)] /= sx[i];
  theta[static_cast<std::size_t>(L.num())] *= sy;
  for (int i = 0; i < d; ++i) {
    theta[static_cast<std::size_t>(L.num() + 1 + i)] *= sy / sx[i];
    theta[static_cast<std::size_t>(L.den() + i)] /= sx[i];
  }
  for (int j = 0; j < L.k; ++j) theta[static_cast<std::size_t>(L.num() + 1 + d + j)] *= sy;
  expression_ = {d, options_.functions, theta, options_.denominator_floor, {}, {}};
  // the input guard: the training range of qd (and h, hd with the final alpha, beta), widened
  if (options_.input_guard >= 0.0) {
    std::vector<std::vector<double>> cols{record.qd};
    if (d == 3) {
      HysteresisFeatures f = hysteresis_features(record.qd, record.dt, hysteresis_);
      cols.push_back(std::move(f.h));
      cols.push_back(std::move(f.hd));
    }
    for (const auto& c : cols) {
      const auto [lo, hi] = std::minmax_element(c.begin(), c.end());
      const double w = *hi - *lo;
      expression_.input_min.push_back(*lo - options_.input_guard * w);
      expression_.input_max.push_back(*hi + options_.input_guard * w);
    }
  }
  compiled_ = CompiledExpression(expression_);
  fitted_ = true;
  // training RMSE of the deployed form
  const std::vector<double> pred = predict(record);
  double sse = 0.0;
  for (std::size_t k = 0; k < pred.size(); ++k) sse += (pred[k] - record.tau[k]) * (pred[k] - record.tau[k]);
  out.rmse = std::sqrt(sse / static_cast<double>(pred.size()));
  out.status = std::isfinite(out.rmse) ? FitStatus::Converged : FitStatus::Failed;
  if (out.status == FitStatus::Failed) fitted_ = false;
  out.evaluations = evaluations;
  out.message = fmt::format("{}{}stage 2 basin hopping ({} starts x {} hops) loss {:.4g}, {} active coefficients, "
                            "refined mse {:.4g} (prune threshold {:.3g}); {}",
                            stage1, stage1.empty() ? "" : "; ", options_.starts, options_.hops, global_loss,
                            expression_.active_coefficients(), refined_mse, chosen->threshold, stage3);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

ParFamModel ParFamModel::restore(const ParFamExpression& expression, const HysteresisParams& hysteresis) {
  expression.validate();
  ParFamOptions o;
  o.input = expression.dim == 1 ? ParFamInput::Velocity : ParFamInput::Hysteresis;
  o.functions = expression.functions;
  o.denominator_floor = expression.denominator_floor;
  if (o.input == ParFamInput::Hysteresis) {
    hysteresis.validate();
    o.hysteresis = hysteresis;
  }
  ParFamModel m(o);
  m.expression_ = expression;
  m.compiled_ = CompiledExpression(expression);
  m.hysteresis_ = hysteresis;
  m.fitted_ = true;
  return m;
}

void ParFamModel::start(double dt) {
  if (!fitted_) throw InvalidArgument(fmt::format("{} is not fitted: call fit() first", name()));
  if (options_.input == ParFamInput::Hysteresis)
    state_.emplace(hysteresis_, dt);
  else if (!std::isfinite(dt) || dt <= 0.0)
    throw InvalidArgument(fmt::format("sample time dt is {}, must be > 0", dt));
}

double ParFamModel::step(double qd) noexcept {
  if (options_.input == ParFamInput::Velocity) return compiled_(qd, 0.0, 0.0);
  const HysteresisSample s = state_->step(qd);
  return compiled_(qd, s.h, s.hd);
}

std::string ParFamModel::equation() const {
  std::string s = "tau_f = " + expression_.to_string();
  if (options_.input == ParFamInput::Hysteresis)
    s += fmt::format("; (alpha, beta) = ({:.4g}, {:.4g}){}", hysteresis_.alpha, hysteresis_.beta,
                     hysteresis_.drive == HysteresisDrive::Displacement ? ", displacement clock" : "");
  return s;
}

}  // namespace twinwatch::friction
