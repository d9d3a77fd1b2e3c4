// tune_in_loop(): a fitted friction model's parameters tuned on the closed loop's tracking error.
// A diagnosis for HESR §V-G: the loop integrates the model error, so the parameters that minimise
// the residual-torque mean-square error (what every fit here minimises) are not those that track
// best. The search is NLopt's BOBYQA (bounded, derivative-free: the objective is a whole simulated
// trial, not differentiable in closed form) in coordinates scaled around the fitted values.
#include <fmt/format.h>
#include <nlopt.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <functional>
#include <memory>
#include <new>
#include <span>

#include "twinwatch/core/error.hpp"
#include "twinwatch/friction/closed_loop.hpp"
#include "twinwatch/friction/lugre.hpp"
#include "twinwatch/friction/parfam.hpp"

namespace twinwatch::friction {
namespace {

// one tuned coordinate: p = p0 * exp(x) (scale) or p0 * (1 + x) (relative) or p0 + x (shift)
enum class Map { Scale, Relative, Shift };
struct Coordinate {
  Map map;
  double p0;
  double lo, hi;  // bounds on x
  double apply(double x) const {
    switch (map) {
      case Map::Scale: return p0 * std::exp(x);
      case Map::Relative: return p0 * (1.0 + x);
      case Map::Shift: return p0 + x;
    }
    return p0;
  }
};

struct Problem {
  std::vector<Coordinate> coords;
  std::function<std::shared_ptr<FrictionModel>(const std::vector<double>& p)> build;
};

Problem lugre_problem(const LugreModel& m) {
  const LugreParams p0 = m.params();
  Problem pr;
  const auto scale = [](double v) { return Coordinate{Map::Scale, v, -1.0, 1.0}; };
  pr.coords = {scale(p0.sigma0), scale(p0.Fc), scale(p0.Fs), scale(p0.vs)};
  const bool has_s1 = p0.sigma1 > 0.0, has_s2 = p0.sigma2 > 0.0;
  if (has_s1) pr.coords.push_back(scale(p0.sigma1));
  if (has_s2) pr.coords.push_back(scale(p0.sigma2));
  pr.coords.push_back({Map::Shift, p0.offset, -0.5, 0.5});
  pr.build = [p0, has_s1, has_s2](const std::vector<double>& v) {
    LugreParams p = p0;
    std::size_t i = 0;
    p.sigma0 = v[i++];
    p.Fc = v[i++];
    p.Fs = v[i++];
    p.vs = v[i++];
    if (has_s1) p.sigma1 = v[i++];
    if (has_s2) p.sigma2 = v[i++];
    p.offset = v[i++];
    return std::make_shared<LugreModel>(p);
  };
  return pr;
}

Problem parfam_problem(const ParFamModel& m) {
  const ParFamExpression e0 = m.expression();
  const HysteresisParams h0 = m.hysteresis();
  const bool hysteresis = e0.dim == 3;
  Problem pr;
  std::vector<std::size_t> active;
  for (std::size_t i = 0; i < e0.theta.size(); ++i)
    if (e0.theta[i] != 0.0) {
      active.push_back(i);
      pr.coords.push_back({Map::Relative, e0.theta[i], -0.5, 0.5});
    }
  if (hysteresis) {
    pr.coords.push_back({Map::Scale, h0.alpha, -1.0, 1.0});
    pr.coords.push_back({Map::Scale, h0.beta, -1.0, 1.0});
  }
  pr.build = [e0, h0, hysteresis, active](const std::vector<double>& v) {
    ParFamExpression e = e0;
    for (std::size_t k = 0; k < active.size(); ++k) e.theta[active[k]] = v[k];
    HysteresisParams h = h0;
    if (hysteresis) {
      h.alpha = v[active.size()];
      h.beta = v[active.size() + 1];
    }
    return std::make_shared<ParFamModel>(ParFamModel::restore(e, h));
  };
  return pr;
}

struct Context {
  const Problem* problem;
  std::function<double(FrictionModel&)> trial;
  double penalty = 0.0;            // objective of parameters the model refuses (finite: BOBYQA's model stays finite)
  nlopt_opt opt = nullptr;
  std::exception_ptr error;        // an unexpected exception, rethrown after the search
  long evaluations = 0;
  std::vector<double> p;
};

// NLopt's C callback must not throw: parameters the model refuses (InvalidArgument from its
// constructor or start()) score the penalty; anything else stops the search and is rethrown
double objective(unsigned n, const double* x, double* /*grad*/, void* data) {
  auto* c = static_cast<Context*>(data);
  ++c->evaluations;
  for (unsigned i = 0; i < n; ++i) c->p[i] = c->problem->coords[i].apply(x[i]);
  try {
    const std::shared_ptr<FrictionModel> m = c->problem->build(c->p);
    const double r = c->trial(*m);
    return std::isfinite(r) ? r : c->penalty;
  } catch (const InvalidArgument&) {
    return c->penalty;
  } catch (...) {
    c->error = std::current_exception();
    nlopt_force_stop(c->opt);
    return c->penalty;
  }
}

}  // namespace

LoopTuning tune_in_loop(const FrictionModel& model, const MaxwellSlipParams& truth, std::span<const VelocityProfile> training,
                        const ClosedLoopOptions& options, const MaxwellSlipFriction* plant_start, int evaluations) {
  if (evaluations < 1) throw InvalidArgument(fmt::format("in-loop tuning evaluations is {}, must be >= 1", evaluations));
  if (training.empty()) throw InvalidArgument("in-loop tuning needs at least one training trajectory");
  if (!model.fitted()) throw InvalidArgument(fmt::format("in-loop tuning: {} is not fitted", model.name()));
  Problem problem;
  if (const auto* l = dynamic_cast<const LugreModel*>(&model))
    problem = lugre_problem(*l);
  else if (const auto* p = dynamic_cast<const ParFamModel*>(&model))
    problem = parfam_problem(*p);
  else
    throw InvalidArgument(fmt::format("in-loop tuning supports LuGre and ParFam models, not {}", model.name()));
  ClosedLoopOptions o = options;
  o.record_measurements = false;
  const auto trials = [&](FrictionModel& m) {
    double ss = 0.0;
    for (const VelocityProfile& t : training) {
      const double r = run_closed_loop(truth, t, &m, o, true, plant_start).rmse;
      ss += r * r;
    }
    return std::sqrt(ss / static_cast<double>(training.size()));
  };
  const auto n = static_cast<unsigned>(problem.coords.size());
  std::vector<double> x(n, 0.0), lo(n), hi(n), p0(n);
  for (unsigned i = 0; i < n; ++i) {
    lo[i] = problem.coords[i].lo;
    hi[i] = problem.coords[i].hi;
    p0[i] = problem.coords[i].apply(0.0);
  }
  LoopTuning out;
  out.parameters = static_cast<int>(n);
  // the fitted parameters, outside the search: a bad option, profile or plant_start throws here
  out.rmse_before = trials(*problem.build(p0));
  constexpr double kPenaltyFactor = 1e3;
  Context ctx{&problem, trials, kPenaltyFactor * std::max(out.rmse_before, 1e-9), nullptr, nullptr, 1, std::vector<double>(n)};
  const std::unique_ptr<nlopt_opt_s, decltype(&nlopt_destroy)> opt(nlopt_create(NLOPT_LN_BOBYQA, n), &nlopt_destroy);
  if (!opt) throw std::bad_alloc();
  ctx.opt = opt.get();
  nlopt_set_lower_bounds(opt.get(), lo.data());
  nlopt_set_upper_bounds(opt.get(), hi.data());
  nlopt_set_min_objective(opt.get(), objective, &ctx);
  nlopt_set_maxeval(opt.get(), evaluations);
  constexpr double kInitialStep = 0.05;  // 5 % of each parameter (0.05 N·m for the offset)
  nlopt_set_initial_step1(opt.get(), kInitialStep);
  double f = out.rmse_before;
  // any stop (budget, tolerance, a forced stop) leaves the best point found in x and its value in f
  nlopt_optimize(opt.get(), x.data(), &f);
  if (ctx.error) std::rethrow_exception(ctx.error);
  out.rmse_after = f;
  if (!(f < out.rmse_before)) {  // no improvement: the fitted parameters
    std::fill(x.begin(), x.end(), 0.0);
    out.rmse_after = out.rmse_before;
  }
  for (unsigned i = 0; i < n; ++i) ctx.p[i] = problem.coords[i].apply(x[i]);
  out.model = problem.build(ctx.p);
  out.evaluations = ctx.evaluations;
  return out;
}

}  // namespace twinwatch::friction
