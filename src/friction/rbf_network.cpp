#include "twinwatch/friction/rbf_network.hpp"

#include <fmt/format.h>
#include <nlopt.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>

#include "bounded_fit.hpp"
#include "twinwatch/core/error.hpp"

namespace twinwatch::friction {

namespace {

// floor of a column's standard deviation: a constant input column is left unscaled
constexpr double kMinStd = 1e-12;

/// Design matrix Phi (rows = samples, columns = bias + M Gaussians) at width s.
Eigen::MatrixXd design(const Eigen::MatrixXd& X, const Eigen::MatrixXd& C, double s) {
  const double inv = 1.0 / (2.0 * s * s);
  Eigen::MatrixXd Phi(X.rows(), C.rows() + 1);
  Phi.col(0).setOnes();
  for (Eigen::Index j = 0; j < C.rows(); ++j)
    Phi.col(j + 1) = (-(X.rowwise() - C.row(j)).rowwise().squaredNorm() * inv).array().exp().matrix();
  return Phi;
}

/// Ridge least squares w = (Phi^T Phi + lambda I)^-1 Phi^T y, lambda relative to the mean diagonal.
Eigen::VectorXd ridge_solve(const Eigen::MatrixXd& Phi, const Eigen::VectorXd& y, double ridge) {
  Eigen::MatrixXd A = Phi.transpose() * Phi;
  const double lambda = ridge * A.diagonal().mean() + std::numeric_limits<double>::min();
  A.diagonal().array() += lambda;
  return A.ldlt().solve(Phi.transpose() * y);
}

/// k-means++ seeding then Lloyd iterations [Arthur2007] on the rows of X.
Eigen::MatrixXd kmeans(const Eigen::MatrixXd& X, int m, int iterations, unsigned seed) {
  std::mt19937_64 rng(seed);
  const Eigen::Index n = X.rows();
  Eigen::MatrixXd C(m, X.cols());
  // seeding: each new centre drawn with probability proportional to D(x)^2
  C.row(0) = X.row(std::uniform_int_distribution<Eigen::Index>(0, n - 1)(rng));
  Eigen::VectorXd d2 = (X.rowwise() - C.row(0)).rowwise().squaredNorm();
  for (int j = 1; j < m; ++j) {
    const double total = d2.sum();
    Eigen::Index pick = std::uniform_int_distribution<Eigen::Index>(0, n - 1)(rng);
    if (total > 0.0) {
      double r = std::uniform_real_distribution<double>(0.0, total)(rng);
      for (Eigen::Index i = 0; i < n; ++i) {
        r -= d2[i];
        if (r <= 0.0) {
          pick = i;
          break;
        }
      }
    }
    C.row(j) = X.row(pick);
    d2 = d2.cwiseMin((X.rowwise() - C.row(j)).rowwise().squaredNorm());
  }
  // lloyd: assign to the nearest centre, move centres to the means (empty clusters stay)
  std::vector<int> label(static_cast<std::size_t>(n), 0);
  for (int it = 0; it < iterations; ++it) {
    for (Eigen::Index i = 0; i < n; ++i) {
      Eigen::Index best = 0;
      (C.rowwise() - X.row(i)).rowwise().squaredNorm().minCoeff(&best);
      label[static_cast<std::size_t>(i)] = static_cast<int>(best);
    }
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(m, X.cols());
    Eigen::VectorXd count = Eigen::VectorXd::Zero(m);
    for (Eigen::Index i = 0; i < n; ++i) {
      sum.row(label[static_cast<std::size_t>(i)]) += X.row(i);
      count[label[static_cast<std::size_t>(i)]] += 1.0;
    }
    for (int j = 0; j < m; ++j)
      if (count[j] > 0.0) C.row(j) = sum.row(j) / count[j];
  }
  return C;
}

struct SpreadSearch {
  const Eigen::MatrixXd* X_train;
  const Eigen::VectorXd* y_train;
  const Eigen::MatrixXd* X_test;
  const Eigen::VectorXd* y_test;
  const Eigen::MatrixXd* C;
  double ridge;
  long evaluations = 0;
};

/// Held-out mean-square error at width exp(u[0]).
double holdout_mse(unsigned /*n*/, const double* u, double* /*grad*/, void* data) {
  auto* s = static_cast<SpreadSearch*>(data);
  ++s->evaluations;
  const double spread = std::exp(u[0]);
  const Eigen::VectorXd w = ridge_solve(design(*s->X_train, *s->C, spread), *s->y_train, s->ridge);
  const double mse = (design(*s->X_test, *s->C, spread) * w - *s->y_test).squaredNorm() /
                     static_cast<double>(s->y_test->size());
  return std::isfinite(mse) ? mse : std::numeric_limits<double>::max();
}

}  // namespace

void RbfOptions::validate() const {
  if (input == RbfInput::Hysteresis) hysteresis.validate();
  if (centers < 1) throw InvalidArgument(fmt::format("RBF centers is {}, must be >= 1", centers));
  if (!std::isfinite(ridge) || ridge < 0.0) throw InvalidArgument(fmt::format("RBF ridge is {}, must be >= 0", ridge));
  if (!std::isfinite(spread_min) || spread_min <= 0.0)
    throw InvalidArgument(fmt::format("RBF spread_min is {}, must be > 0", spread_min));
  if (!std::isfinite(spread_max) || spread_max <= spread_min)
    throw InvalidArgument(fmt::format("RBF spread_max is {}, must be > spread_min ({})", spread_max, spread_min));
  if (spread_evaluations < 4)
    throw InvalidArgument(fmt::format("RBF spread_evaluations is {}, must be >= 4", spread_evaluations));
  if (!std::isfinite(holdout_block) || holdout_block <= 0.0)
    throw InvalidArgument(fmt::format("RBF holdout_block is {}, must be > 0 [s]", holdout_block));
  if (holdout_every < 2) throw InvalidArgument(fmt::format("RBF holdout_every is {}, must be >= 2", holdout_every));
  if (kmeans_iterations < 0)
    throw InvalidArgument(fmt::format("RBF kmeans_iterations is {}, must be >= 0", kmeans_iterations));
}

RbfNetwork::RbfNetwork(RbfOptions options) : options_(options) { options_.validate(); }

std::string_view RbfNetwork::name() const noexcept {
  return options_.input == RbfInput::Velocity ? "RBFNN" : "RBFNN-H";
}

FitSummary RbfNetwork::fit(const FrictionRecord& record) {
  record.validate("training record", static_cast<long>(options_.centers) + 1);
  const auto t0 = std::chrono::steady_clock::now();
  const int d = input_dim();
  const Eigen::Index n = record.size();
  // inputs: qd, or [qd, h, hd] from eq. 11 along the record
  Eigen::MatrixXd X(n, d);
  for (Eigen::Index k = 0; k < n; ++k) X(k, 0) = record.qd[static_cast<std::size_t>(k)];
  if (options_.input == RbfInput::Hysteresis) {
    const HysteresisFeatures f = hysteresis_features(record.qd, record.dt, options_.hysteresis);
    for (Eigen::Index k = 0; k < n; ++k) {
      X(k, 1) = f.h[static_cast<std::size_t>(k)];
      X(k, 2) = f.hd[static_cast<std::size_t>(k)];
    }
  }
  // standardise each column
  mean_.assign(static_cast<std::size_t>(d), 0.0);
  inv_std_.assign(static_cast<std::size_t>(d), 1.0);
  for (int c = 0; c < d; ++c) {
    const double mu = X.col(c).mean();
    const double sd = std::sqrt((X.col(c).array() - mu).square().mean());
    mean_[static_cast<std::size_t>(c)] = mu;
    inv_std_[static_cast<std::size_t>(c)] = 1.0 / std::max(sd, kMinStd);
    X.col(c) = (X.col(c).array() - mu) * inv_std_[static_cast<std::size_t>(c)];
  }
  const Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXd>(record.tau.data(), n);
  // centres
  const Eigen::MatrixXd C = kmeans(X, options_.centers, options_.kmeans_iterations, options_.seed);
  // train/test split by blocks of consecutive samples
  const auto block = std::max<long>(1, std::lround(options_.holdout_block / record.dt));
  std::vector<Eigen::Index> train, test;
  for (Eigen::Index k = 0; k < n; ++k)
    ((k / block) % options_.holdout_every == options_.holdout_every - 1 ? test : train).push_back(k);
  if (test.empty() || static_cast<long>(train.size()) <= options_.centers) {
    train.clear();
    test.clear();
    for (Eigen::Index k = 0; k < n; ++k) (k % options_.holdout_every == options_.holdout_every - 1 ? test : train).push_back(k);
  }
  const Eigen::MatrixXd Xtr = X(train, Eigen::all), Xte = X(test, Eigen::all);
  const Eigen::VectorXd ytr = y(train), yte = y(test);
  // width: global DIRECT-L over log s, then a local Nelder-Mead polish
  SpreadSearch search{&Xtr, &ytr, &Xte, &yte, &C, options_.ridge};
  double lo = std::log(options_.spread_min), hi = std::log(options_.spread_max);
  double u = 0.5 * (lo + hi), f = 0.0;
  nlopt_opt g = nlopt_create(NLOPT_GN_DIRECT_L, 1);
  nlopt_set_lower_bounds(g, &lo);
  nlopt_set_upper_bounds(g, &hi);
  nlopt_set_min_objective(g, holdout_mse, &search);
  nlopt_set_maxeval(g, options_.spread_evaluations);
  nlopt_optimize(g, &u, &f);
  nlopt_destroy(g);
  constexpr int kPolishEvaluations = 20;  // 1-D: a few simplex steps suffice
  constexpr double kPolishTolerance = 1e-3;
  nlopt_opt l = nlopt_create(NLOPT_LN_NELDERMEAD, 1);
  nlopt_set_lower_bounds(l, &lo);
  nlopt_set_upper_bounds(l, &hi);
  nlopt_set_min_objective(l, holdout_mse, &search);
  nlopt_set_maxeval(l, kPolishEvaluations);
  nlopt_set_xtol_abs1(l, kPolishTolerance);
  const nlopt_result lr = nlopt_optimize(l, &u, &f);
  nlopt_destroy(l);
  // final weights on every sample at the chosen width
  spread_ = std::exp(u);
  inv_two_s2_ = 1.0 / (2.0 * spread_ * spread_);
  const Eigen::MatrixXd Phi = design(X, C, spread_);
  const Eigen::VectorXd w = ridge_solve(Phi, y, options_.ridge);
  centers_.assign(C.size(), 0.0);
  for (Eigen::Index j = 0; j < C.rows(); ++j)
    for (int c = 0; c < d; ++c) centers_[static_cast<std::size_t>(j * d + c)] = C(j, c);
  weights_.assign(w.data(), w.data() + w.size());
  FitSummary out;
  out.rmse = std::sqrt((Phi * w - y).squaredNorm() / static_cast<double>(n));
  out.status = std::isfinite(out.rmse) ? (lr > 0 ? FitStatus::Converged : FitStatus::BudgetExhausted) : FitStatus::Failed;
  if (out.status == FitStatus::Failed) weights_.clear();
  out.evaluations = search.evaluations;
  out.message = fmt::format("{} centres, width {:.4g} (held-out rmse {:.4g} on {} samples), ridge least squares",
                            options_.centers, spread_, std::sqrt(f), test.size());
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

void RbfNetwork::start(double dt) {
  if (!fitted()) throw InvalidArgument(fmt::format("{} is not fitted: call fit() first", name()));
  if (options_.input == RbfInput::Hysteresis)
    state_.emplace(options_.hysteresis, dt);
  else if (!std::isfinite(dt) || dt <= 0.0)
    throw InvalidArgument(fmt::format("sample time dt is {}, must be > 0", dt));
}

double RbfNetwork::step(double qd) noexcept {
  // standardised input
  double x[3] = {(qd - mean_[0]) * inv_std_[0], 0.0, 0.0};
  const int d = input_dim();
  if (d == 3) {
    const HysteresisSample s = state_->step(qd);
    x[1] = (s.h - mean_[1]) * inv_std_[1];
    x[2] = (s.hd - mean_[2]) * inv_std_[2];
  }
  // bias + Gaussian neurons
  double y = weights_[0];
  const std::size_t m = weights_.size() - 1;
  for (std::size_t j = 0; j < m; ++j) {
    double r2 = 0.0;
    for (int c = 0; c < d; ++c) {
      const double e = x[c] - centers_[j * static_cast<std::size_t>(d) + static_cast<std::size_t>(c)];
      r2 += e * e;
    }
    y += weights_[j + 1] * std::exp(-r2 * inv_two_s2_);
  }
  return y;
}

std::string RbfNetwork::equation() const {
  const int d = input_dim();
  const char* names[3] = {"qd", "h", "hd"};
  std::string s = fmt::format("tau_f = {:.6g}", weights_.empty() ? 0.0 : weights_[0]);
  for (std::size_t j = 0; j + 1 < weights_.size(); ++j) {
    std::string r2;
    for (int c = 0; c < d; ++c) {
      const auto cs = static_cast<std::size_t>(c);
      // centre back in input units: x = mean + xs / inv_std
      const double centre = mean_[cs] + centers_[j * static_cast<std::size_t>(d) + cs] / inv_std_[cs];
      r2 += fmt::format("{}(({} - {:.6g})*{:.6g})^2", c == 0 ? "" : " + ", names[c], centre, inv_std_[cs]);
    }
    s += fmt::format(" + {:.6g}*exp(-({})/{:.6g})", weights_[j + 1], r2, 2.0 * spread_ * spread_);
  }
  return s;
}

}  // namespace twinwatch::friction
