#include "twinwatch/friction/decoupling.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::friction {

namespace {

// columns of the rigid-body regressor [qdd, sin q, cos q, 1] and the nuisance [sign(qd), qd]
constexpr int kRigidColumns = 4;
constexpr int kNuisanceColumns = 2;
// rank threshold on the singular values of the column-scaled regressor, relative to the largest:
// well above double rounding (1e-16) times the row count, well below any physical conditioning
constexpr double kRankTolerance = 1e-9;

void check_window(int window, const char* what) {
  if (window < 1 || window % 2 == 0)
    throw InvalidArgument(fmt::format("{} is {}, must be an odd number >= 1", what, window));
}

}  // namespace

void JointRecord::validate(std::string_view what, long min_samples) const {
  if (!std::isfinite(dt) || dt <= 0.0) throw InvalidArgument(fmt::format("{}.dt is {}, must be > 0 [s]", what, dt));
  if (qd.size() != q.size())
    throw InvalidArgument(fmt::format("{}.qd has size {}, expected {} (size of {}.q)", what, qd.size(), q.size(), what));
  if (tau.size() != q.size())
    throw InvalidArgument(fmt::format("{}.tau has size {}, expected {} (size of {}.q)", what, tau.size(), q.size(), what));
  if (size() < min_samples)
    throw InvalidArgument(fmt::format("{} has {} samples, expected at least {}", what, size(), min_samples));
  for (std::size_t k = 0; k < q.size(); ++k) {
    if (!std::isfinite(q[k])) throw InvalidArgument(fmt::format("{}.q[{}] is {}, must be finite", what, k, q[k]));
    if (!std::isfinite(qd[k])) throw InvalidArgument(fmt::format("{}.qd[{}] is {}, must be finite", what, k, qd[k]));
    if (!std::isfinite(tau[k])) throw InvalidArgument(fmt::format("{}.tau[{}] is {}, must be finite", what, k, tau[k]));
  }
}

std::vector<double> moving_average(std::span<const double> x, int window) {
  check_window(window, "moving-average window");
  const auto n = static_cast<long>(x.size());
  const long half = window / 2;
  std::vector<double> out(x.size());
  // prefix sums: each output is the mean of the samples within +-half that exist
  std::vector<double> c(x.size() + 1, 0.0);
  for (long k = 0; k < n; ++k) c[static_cast<std::size_t>(k + 1)] = c[static_cast<std::size_t>(k)] + x[static_cast<std::size_t>(k)];
  for (long k = 0; k < n; ++k) {
    const long a = std::max(0L, k - half), b = std::min(n - 1, k + half);
    out[static_cast<std::size_t>(k)] =
        (c[static_cast<std::size_t>(b + 1)] - c[static_cast<std::size_t>(a)]) / static_cast<double>(b - a + 1);
  }
  return out;
}

std::vector<double> joint_acceleration(std::span<const double> qd, double dt, int window) {
  check_window(window, "acceleration window");
  const std::size_t n = qd.size();
  std::vector<double> qdd(n, 0.0);
  if (n < 2) return qdd;
  // central difference, one-sided at the ends: qdd_k = (qd_{k+1} - qd_{k-1}) / (2 dt)
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t a = k == 0 ? 0 : k - 1, b = k + 1 == n ? k : k + 1;
    qdd[k] = (qd[b] - qd[a]) / (static_cast<double>(b - a) * dt);
  }
  return moving_average(qdd, window);
}

void RigidBodyFitOptions::validate() const {
  if (!std::isfinite(reversal_threshold) || reversal_threshold < 0.0)
    throw InvalidArgument(fmt::format("rigid-body reversal_threshold is {}, must be >= 0 [rad/s]", reversal_threshold));
  check_window(acceleration_window, "rigid-body acceleration_window");
}

std::vector<double> RigidBodyFit::torque(const JointRecord& r) const {
  const std::vector<double> qdd = joint_acceleration(r.qd, r.dt, options.acceleration_window);
  std::vector<double> out(r.q.size());
  for (std::size_t k = 0; k < out.size(); ++k)
    out[k] = inertia * qdd[k] + gravity_sin * std::sin(r.q[k]) + gravity_cos * std::cos(r.q[k]) + offset;
  return out;
}

FrictionRecord RigidBodyFit::residual(const JointRecord& r) const {
  FrictionRecord f;
  f.dt = r.dt;
  f.qd = r.qd;
  const std::vector<double> rb = torque(r);
  f.tau.resize(rb.size());
  for (std::size_t k = 0; k < rb.size(); ++k) f.tau[k] = r.tau[k] - rb[k];
  return f;
}

std::string RigidBodyFit::equation() const {
  return fmt::format("tau_rb = {:.5g}*qdd + {:.5g}*sin(q) + {:.5g}*cos(q) + {:.5g}", inertia, gravity_sin, gravity_cos,
                     offset);
}

RigidBodyFit fit_rigid_body(std::span<const JointRecord* const> records, const RigidBodyFitOptions& options) {
  options.validate();
  if (records.empty()) throw InvalidArgument("rigid-body fit needs at least one record, got 0");
  for (std::size_t i = 0; i < records.size(); ++i) records[i]->validate(fmt::format("records[{}]", i));
  const int cols = kRigidColumns + (options.friction_nuisance ? kNuisanceColumns : 0);
  // stack the regressor rows of every record; mark the retained (screened) rows
  long n_all = 0;
  for (const JointRecord* r : records) n_all += r->size();
  Eigen::MatrixXd Y(n_all, cols);
  Eigen::VectorXd tau(n_all);
  std::vector<char> keep(static_cast<std::size_t>(n_all));
  long row = 0;
  for (const JointRecord* r : records) {
    const std::vector<double> qdd = joint_acceleration(r->qd, r->dt, options.acceleration_window);
    for (std::size_t k = 0; k < r->q.size(); ++k, ++row) {
      Y(row, 0) = qdd[k];
      Y(row, 1) = std::sin(r->q[k]);
      Y(row, 2) = std::cos(r->q[k]);
      Y(row, 3) = 1.0;
      if (options.friction_nuisance) {
        Y(row, 4) = r->qd[k] > 0.0 ? 1.0 : (r->qd[k] < 0.0 ? -1.0 : 0.0);
        Y(row, 5) = r->qd[k];
      }
      tau(row) = r->tau[k];
      keep[static_cast<std::size_t>(row)] = std::abs(r->qd[k]) >= options.reversal_threshold;
    }
  }
  RigidBodyFit fit;
  fit.options = options;
  fit.columns = cols;
  for (char c : keep) fit.samples += c;
  if (fit.samples < cols)
    throw InvalidArgument(fmt::format("rigid-body fit keeps {} samples with |qd| >= {} rad/s, expected at least {}",
                                      fit.samples, options.reversal_threshold, cols));
  Eigen::MatrixXd W(fit.samples, cols);
  Eigen::VectorXd y(fit.samples);
  for (long k = 0, i = 0; k < n_all; ++k)
    if (keep[static_cast<std::size_t>(k)]) {
      W.row(i) = Y.row(k);
      y(i++) = tau(k);
    }
  // column scaling, then the SVD: rank, condition number and the minimum-norm solution
  Eigen::VectorXd scale = W.colwise().norm().transpose();
  for (int j = 0; j < cols; ++j)
    if (scale(j) == 0.0) scale(j) = 1.0;
  const Eigen::MatrixXd Ws = W * scale.cwiseInverse().asDiagonal();
  Eigen::BDCSVD<Eigen::MatrixXd> svd(Ws, Eigen::ComputeThinU | Eigen::ComputeThinV);
  svd.setThreshold(kRankTolerance);
  fit.rank = static_cast<int>(svd.rank());
  const Eigen::VectorXd s = svd.singularValues();
  fit.log10_condition = s(cols - 1) > 0.0 ? std::log10(s(0) / s(cols - 1)) : std::numeric_limits<double>::infinity();
  const Eigen::VectorXd p = scale.cwiseInverse().asDiagonal() * svd.solve(y);
  fit.inertia = p(0);
  fit.gravity_sin = p(1);
  fit.gravity_cos = p(2);
  fit.offset = p(3);
  if (options.friction_nuisance) {
    fit.coulomb = p(4);
    fit.viscous = p(5);
  }
  // fit quality of the whole model (with the nuisance friction) on all and on the retained rows
  const Eigen::VectorXd e = tau - Y * p;
  double s_all = 0.0, s_ret = 0.0;
  for (long k = 0; k < n_all; ++k) {
    s_all += e(k) * e(k);
    if (keep[static_cast<std::size_t>(k)]) s_ret += e(k) * e(k);
  }
  fit.rmse_all = std::sqrt(s_all / static_cast<double>(n_all));
  fit.rmse_retained = std::sqrt(s_ret / static_cast<double>(fit.samples));
  return fit;
}

}  // namespace twinwatch::friction
