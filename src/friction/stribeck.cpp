#include "twinwatch/friction/stribeck.hpp"

#include <fmt/format.h>

#include <array>
#include <chrono>
#include <cmath>

#include "bounded_fit.hpp"
#include "twinwatch/core/error.hpp"

namespace twinwatch::friction {

namespace {

constexpr int kNumParams = 5;  // Fc, Fs, vs, sigma2, offset

double sgn(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }

/// tau_f of HESR eq. 3 plus viscous and offset, for doubles and Jets; p = (Fc, Fs, vs, sigma2, offset).
template <class T>
T stribeck_tau(const T* p, double qd) {
  using std::exp;
  const T x = qd / p[2];
  return sgn(qd) * (p[0] + (p[1] - p[0]) * exp(-x * x)) + p[3] * qd + p[4];
}

/// Residuals tau_k - tau_f(qd_k) in search coordinates u (Ceres autodiff functor).
struct StribeckResidual {
  const FrictionRecord* record;
  std::array<detail::Bound, kNumParams> bounds;
  template <class T>
  bool operator()(const T* u, T* r) const {
    T p[kNumParams];
    for (int i = 0; i < kNumParams; ++i) p[i] = detail::to_param(bounds[static_cast<std::size_t>(i)], u[i]);
    for (std::size_t k = 0; k < record->qd.size(); ++k) r[k] = record->tau[k] - stribeck_tau(p, record->qd[k]);
    return true;
  }
};

}  // namespace

void ParametricFitOptions::validate() const {
  if (global_evaluations < 10)
    throw InvalidArgument(fmt::format("global_evaluations is {}, must be >= 10", global_evaluations));
  if (local_iterations < 1)
    throw InvalidArgument(fmt::format("local_iterations is {}, must be >= 1", local_iterations));
  if (local_starts < 0) throw InvalidArgument(fmt::format("local_starts is {}, must be >= 0", local_starts));
}

void StribeckParams::validate() const {
  if (!std::isfinite(Fc) || Fc < 0.0) throw InvalidArgument(fmt::format("Stribeck Fc is {}, must be >= 0 [N·m]", Fc));
  if (!std::isfinite(Fs) || Fs < 0.0) throw InvalidArgument(fmt::format("Stribeck Fs is {}, must be >= 0 [N·m]", Fs));
  if (!std::isfinite(vs) || vs <= 0.0) throw InvalidArgument(fmt::format("Stribeck vs is {}, must be > 0 [rad/s]", vs));
  if (!std::isfinite(sigma2) || sigma2 < 0.0)
    throw InvalidArgument(fmt::format("Stribeck sigma2 is {}, must be >= 0 [N·m·s/rad]", sigma2));
  if (!std::isfinite(offset)) throw InvalidArgument(fmt::format("Stribeck offset is {}, must be finite", offset));
}

StribeckModel::StribeckModel(ParametricFitOptions options) : options_(options) { options_.validate(); }

StribeckModel::StribeckModel(const StribeckParams& params) : params_(params), fitted_(true) { params_.validate(); }

double StribeckModel::evaluate(const StribeckParams& p, double qd) noexcept {
  const double a[kNumParams] = {p.Fc, p.Fs, p.vs, p.sigma2, p.offset};
  return stribeck_tau(a, qd);
}

FitSummary StribeckModel::fit(const FrictionRecord& record) {
  record.validate("training record", kNumParams + 1);
  const auto t0 = std::chrono::steady_clock::now();
  // bounds from the record's scales: positive friction levels, Stribeck velocity over decades
  const detail::RecordScale s = detail::record_scale(record);
  const std::array<detail::Bound, kNumParams> bounds{{{0.0, 2.0 * s.tau, false},
                                                      {0.0, 3.0 * s.tau, false},
                                                      {1e-3 * s.qd, s.qd, true},
                                                      {0.0, 4.0 * s.tau / s.qd, false},
                                                      {-s.tau, s.tau, false}}};
  // mean-square error (HESR eq. 18)
  const auto mse = [&](std::span<const double> p) {
    double acc = 0.0;
    for (std::size_t k = 0; k < record.qd.size(); ++k) {
      const double e = record.tau[k] - stribeck_tau(p.data(), record.qd[k]);
      acc += e * e;
    }
    return acc / static_cast<double>(record.qd.size());
  };
  // variable projection: given vs, tau is linear in (Fc, Fs, sigma2, offset), the first three >= 0
  detail::ProjectedSearch search;
  search.bounds = {bounds[2]};
  const double yty = Eigen::Map<const Eigen::VectorXd>(record.tau.data(), record.size()).squaredNorm();
  search.project = [&](std::span<const double> q, std::vector<double>& full) {
    Eigen::Matrix4d AtA = Eigen::Matrix4d::Zero();
    Eigen::Vector4d Aty = Eigen::Vector4d::Zero();
    for (std::size_t k = 0; k < record.qd.size(); ++k) {
      const double v = record.qd[k], x = v / q[0], e = std::exp(-x * x);
      const Eigen::Vector4d a(sgn(v) * (1.0 - e), sgn(v) * e, v, 1.0);
      AtA.selfadjointView<Eigen::Upper>().rankUpdate(a);
      Aty += a * record.tau[k];
    }
    AtA = AtA.selfadjointView<Eigen::Upper>();
    Eigen::VectorXd x;
    const double sse = detail::small_nonneg_least_squares(AtA, Aty, yty, {true, true, true, false}, x);
    full = {x[0], x[1], q[0], x[2], x[3]};
    return sse / static_cast<double>(record.qd.size());
  };
  // global search over vs, then local least squares over all parameters, multi-start
  ceres::AutoDiffCostFunction<StribeckResidual, ceres::DYNAMIC, kNumParams> cost(
      new StribeckResidual{&record, bounds}, static_cast<int>(record.qd.size()));
  const detail::BoundedFitResult r =
      detail::global_then_local(search, bounds, mse, cost, options_.global_evaluations, options_.local_iterations,
                                options_.local_starts, options_.seed);
  if (r.p.empty()) {
    FitSummary failed;
    failed.message = "no start gave a finite mean-square error";
    failed.evaluations = r.evaluations;
    return failed;
  }
  const std::vector<double>& p = r.p;
  params_ = {p[0], p[1], p[2], p[3], p[4]};
  fitted_ = true;
  FitSummary out;
  out.status = r.converged ? FitStatus::Converged : FitStatus::BudgetExhausted;
  out.rmse = std::sqrt(r.mse);
  out.evaluations = r.evaluations;
  out.message = r.message;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

void StribeckModel::start(double dt) {
  if (!fitted_) throw InvalidArgument("Stribeck model is not fitted: call fit() first");
  if (!std::isfinite(dt) || dt <= 0.0) throw InvalidArgument(fmt::format("sample time dt is {}, must be > 0", dt));
}

std::string StribeckModel::equation() const {
  const StribeckParams& p = params_;
  return fmt::format("tau_f = sgn(qd)*({:.6g} + {:.6g}*exp(-(qd/{:.6g})^2)) + {:.6g}*qd + {:.6g}", p.Fc, p.Fs - p.Fc, p.vs,
                     p.sigma2, p.offset);
}

}  // namespace twinwatch::friction
