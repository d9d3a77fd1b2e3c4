#include "twinwatch/friction/lugre.hpp"

#include <fmt/format.h>

#include <array>
#include <chrono>
#include <cmath>

#include "bounded_fit.hpp"
#include "twinwatch/core/error.hpp"

namespace twinwatch::friction {

namespace {

constexpr int kNumParams = 7;  // sigma0, sigma1, sigma2, Fc, Fs, vs, offset

double sgn(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }

/// One LuGre sample (HESR eq. 1-3) for doubles and Jets: advances z exactly with qd held over
/// dt and returns tau_f. p = (sigma0, sigma1, sigma2, Fc, Fs, vs, offset).
template <class T>
T lugre_step(const T* p, double qd, double dt, T& z) {
  using std::exp;
  // g(qd) = Fc + (Fs - Fc) exp(-(qd/vs)^2)                                          (eq. 3)
  const T x = qd / p[5];
  const T g = p[3] + (p[4] - p[3]) * exp(-x * x);
  // zd = qd - a z with a = sigma0 |qd| / g: exact step towards z_ss = sgn(qd) g / sigma0 (eq. 2)
  const T a = p[0] * std::abs(qd) / g;
  const T z_ss = sgn(qd) * g / p[0];
  z = z_ss + (z - z_ss) * exp(-a * dt);
  const T zd = qd - a * z;
  // tau_f = sigma0 z + sigma1 zd + sigma2 qd + offset                                (eq. 1)
  return p[0] * z + p[1] * zd + p[2] * qd + p[6];
}

/// Residuals tau_k - tau_f,k along the simulated bristle state, in search coordinates u.
struct LugreResidual {
  const FrictionRecord* record;
  std::array<detail::Bound, kNumParams> bounds;
  template <class T>
  bool operator()(const T* u, T* r) const {
    T p[kNumParams];
    for (int i = 0; i < kNumParams; ++i) p[i] = detail::to_param(bounds[static_cast<std::size_t>(i)], u[i]);
    T z(0.0);
    for (std::size_t k = 0; k < record->qd.size(); ++k)
      r[k] = record->tau[k] - lugre_step(p, record->qd[k], record->dt, z);
    return true;
  }
};

void check_finite_at_least(const char* field, double v, double lo, bool strict, const char* unit) {
  if (!std::isfinite(v) || v < lo || (strict && v == lo))
    throw InvalidArgument(fmt::format("LuGre {} is {}, must be {} {} [{}]", field, v, strict ? ">" : ">=", lo, unit));
}

}  // namespace

void LugreParams::validate() const {
  check_finite_at_least("sigma0", sigma0, 0.0, true, "N·m/rad");
  check_finite_at_least("sigma1", sigma1, 0.0, false, "N·m·s/rad");
  check_finite_at_least("sigma2", sigma2, 0.0, false, "N·m·s/rad");
  check_finite_at_least("Fc", Fc, 0.0, true, "N·m");
  check_finite_at_least("Fs", Fs, 0.0, true, "N·m");
  check_finite_at_least("vs", vs, 0.0, true, "rad/s");
  if (!std::isfinite(offset)) throw InvalidArgument(fmt::format("LuGre offset is {}, must be finite", offset));
}

LugreModel::LugreModel(ParametricFitOptions options) : options_(options) { options_.validate(); }

LugreModel::LugreModel(const LugreParams& params) : params_(params), fitted_(true) { params_.validate(); }

FitSummary LugreModel::fit(const FrictionRecord& record) {
  record.validate("training record", kNumParams + 1);
  const auto t0 = std::chrono::steady_clock::now();
  // bounds: pre-sliding displacement Fc/sigma0 between 1e-6 and 0.1 rad, friction levels and
  // Stribeck velocity over decades of the record's scales
  const detail::RecordScale s = detail::record_scale(record);
  const std::array<detail::Bound, kNumParams> bounds{{{10.0 * s.tau, 1e6 * s.tau, true},
                                                      {0.0, 10.0 * s.tau / s.qd, false},
                                                      {0.0, 4.0 * s.tau / s.qd, false},
                                                      {1e-3 * s.tau, 2.0 * s.tau, true},
                                                      {1e-3 * s.tau, 3.0 * s.tau, true},
                                                      {1e-3 * s.qd, s.qd, true},
                                                      {-s.tau, s.tau, false}}};
  // mean-square error of the simulated model (HESR eq. 18)
  const auto mse = [&](std::span<const double> p) {
    double acc = 0.0, z = 0.0;
    for (std::size_t k = 0; k < record.qd.size(); ++k) {
      const double e = record.tau[k] - lugre_step(p.data(), record.qd[k], record.dt, z);
      acc += e * e;
    }
    return acc / static_cast<double>(record.qd.size());
  };
  // variable projection: given (sigma0, Fc, Fs, vs) the state z is fixed and tau - sigma0 z is
  // linear in (sigma1, sigma2, offset), the first two >= 0
  detail::ProjectedSearch search;
  search.bounds = {bounds[0], bounds[3], bounds[4], bounds[5]};
  search.project = [&](std::span<const double> q, std::vector<double>& full) {
    const double pz[kNumParams] = {q[0], 0.0, 0.0, q[1], q[2], q[3], 0.0};
    Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
    Eigen::Vector3d Aty = Eigen::Vector3d::Zero();
    double yty = 0.0, z = 0.0;
    for (std::size_t k = 0; k < record.qd.size(); ++k) {
      const double v = record.qd[k];
      const double sz = lugre_step(pz, v, record.dt, z);  // sigma0 z (sigma1 = sigma2 = offset = 0)
      const double g = q[1] + (q[2] - q[1]) * std::exp(-(v / q[3]) * (v / q[3]));
      const Eigen::Vector3d a(v - q[0] * std::abs(v) / g * z, v, 1.0);
      const double y = record.tau[k] - sz;
      AtA.selfadjointView<Eigen::Upper>().rankUpdate(a);
      Aty += a * y;
      yty += y * y;
    }
    AtA = AtA.selfadjointView<Eigen::Upper>();
    Eigen::VectorXd x;
    const double sse = detail::small_nonneg_least_squares(AtA, Aty, yty, {true, true, false}, x);
    full = {q[0], x[0], x[1], q[1], q[2], q[3], x[2]};
    return sse / static_cast<double>(record.qd.size());
  };
  // global search, then local least squares through the simulated state (automatic
  // derivatives) over all parameters, multi-start
  ceres::AutoDiffCostFunction<LugreResidual, ceres::DYNAMIC, kNumParams> cost(
      new LugreResidual{&record, bounds}, static_cast<int>(record.qd.size()));
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
  params_ = {p[0], p[1], p[2], p[3], p[4], p[5], p[6]};
  fitted_ = true;
  FitSummary out;
  out.status = r.converged ? FitStatus::Converged : FitStatus::BudgetExhausted;
  out.rmse = std::sqrt(r.mse);
  out.evaluations = r.evaluations;
  out.message = r.message;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

void LugreModel::start(double dt) {
  if (!fitted_) throw InvalidArgument("LuGre model is not fitted: call fit() first");
  if (!std::isfinite(dt) || dt <= 0.0) throw InvalidArgument(fmt::format("sample time dt is {}, must be > 0", dt));
  dt_ = dt;
  z_ = 0.0;
}

double LugreModel::step(double qd) noexcept {
  const double p[kNumParams] = {params_.sigma0, params_.sigma1, params_.sigma2, params_.Fc,
                                params_.Fs,     params_.vs,     params_.offset};
  return lugre_step(p, qd, dt_, z_);
}

std::string LugreModel::equation() const {
  const LugreParams& p = params_;
  return fmt::format(
      "tau_f = {:.6g}*z + {:.6g}*zd + {:.6g}*qd + {:.6g}; zd = qd - {:.6g}*|qd|/g(qd)*z; "
      "g(qd) = {:.6g} + {:.6g}*exp(-(qd/{:.6g})^2)",
      p.sigma0, p.sigma1, p.sigma2, p.offset, p.sigma0, p.Fc, p.Fs - p.Fc, p.vs);
}

}  // namespace twinwatch::friction
