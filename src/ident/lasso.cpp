// Lasso by cyclic coordinate descent [Friedman2010] with glmnet's conventions, and cv.glmnet's
// cross-validation rules.
//
// Why our own numerical core rather than a library: (1) control: the sequential identification
// (Cao eq. 20) fits one Lasso per joint on the same candidate library with the same folds, so the
// fold Gram matrices are computed once from per-fold sufficient statistics and shared by every
// joint and every fold (the training Gram of fold k is the total minus fold k's block), which no
// packaged solver offers; (2) speed: with covariance updates the cost of a coordinate step is p,
// independent of n, so a 10-fold CV over 100 lambdas on 20000 x 225 is dominated by one Gram
// product; (3) glmnet-compatible standardisation (1/n variance, centred y, unpenalised intercept,
// lambda in the units of y, glmnet's thresh and path exits) so that results can be checked
// against glmnet and scikit-learn (tests/ident/lasso_test.cpp, bench/ident/lasso_peers.sh).
// There is no Debian package of a C/C++ Lasso with these conventions either.
#include "twinwatch/ident/lasso.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>

#include "twinwatch/core/error.hpp"

namespace twinwatch::ident {

namespace {

// glmnet.control() defaults: path exits when the explained-deviance gain is below kFdev
// (relative) or the deviance ratio exceeds kDevMax, checked from the kMinLambdas-th lambda on
constexpr double kFdev = 1e-5;
constexpr double kDevMax = 0.999;
constexpr int kMinLambdas = 5;
// glmnet's type.gaussian rule: covariance updates when p < 500
constexpr long kCovarianceMaxP = 500;
// a column whose (1/n) variance is below this fraction of its mean square is constant (glmnet's ju = 0)
constexpr double kConstantColumn = 1e-20;
// rows per block when accumulating the Gram matrix (keeps the block in cache-friendly GEMM sizes)
constexpr long kGramBlockRows = 4096;

// the standardisation of one training set: x~_j = (x_j - xm_j) / xs_j, y~ = (y - ym) / ys
struct Scaling {
  long n = 0;
  Eigen::VectorXd xm, xs, xv;  // xv: (1/n) variance of x~_j (1 when standardised)
  std::vector<char> ju;        // column usable (not constant)
};

// sufficient statistics of a block of rows of the shifted data X - sx, Y - sy
struct Moments {
  long n = 0;
  Eigen::VectorXd sx;   // sum of rows
  Eigen::MatrixXd sxx;  // X'X (full, symmetric)
  Eigen::MatrixXd sxy;  // X'Y [p x m]
  Eigen::VectorXd sy, syy;
  void zero(long p, long m) {
    n = 0;
    sx.setZero(p);
    sxx.setZero(p, p);
    sxy.setZero(p, m);
    sy.setZero(m);
    syy.setZero(m);
  }
  Moments& operator+=(const Moments& o) {
    n += o.n, sx += o.sx, sxx += o.sxx, sxy += o.sxy, sy += o.sy, syy += o.syy;
    return *this;
  }
  Moments& operator-=(const Moments& o) {
    n -= o.n, sx -= o.sx, sxx -= o.sxx, sxy -= o.sxy, sy -= o.sy, syy -= o.syy;
    return *this;
  }
};

// the inner problem of one (training set, response) in standardised units
struct Problem {
  Scaling s;
  double ym = 0.0, ys = 1.0;
  Eigen::VectorXd g0;  // x~'y~ / n
};

// result of one coordinate-descent path in standardised units
struct RawPath {
  Eigen::MatrixXd b;  // p x L
  Eigen::VectorXd rsq;
  int L = 0;          // lambdas solved
  long passes = 0;
  bool converged = true;
};

// --- gradient policies of the coordinate descent -----------------------------------------------

// covariance updates: g = x~'r/n kept through the Gram matrix, g -= del * G(:, k)
struct CovarianceGrad {
  const Eigen::MatrixXd& G;
  Eigen::VectorXd g;
  double value(long k) const { return g(k); }
  void apply(long k, double del) { g.noalias() -= del * G.col(k); }
};

// naive updates: the residual r is kept, g_k = x~_k'r/n computed when needed
struct NaiveGrad {
  const Eigen::MatrixXd& Xs;  // standardised n x p
  Eigen::VectorXd r;
  double inv_n;
  double value(long k) const { return Xs.col(k).dot(r) * inv_n; }
  void apply(long k, double del) { r.noalias() -= del * Xs.col(k); }
};

// Cyclic coordinate descent over the lambda path lam (standardised units), warm started, with an
// active set: a full pass over all columns, then passes over the active columns until the largest
// weighted change max xv_k del_k^2 falls below tol, then a full pass again to confirm (glmnet elnet1).
template <class Grad>
RawPath cd_path(Grad& grad, const Scaling& s, const Eigen::VectorXd& pf, const Eigen::VectorXd& lam,
                const LassoOptions& o, bool exits) {
  const long p = s.xv.size();
  RawPath out;
  out.b.setZero(p, lam.size());
  out.rsq.setZero(lam.size());
  Eigen::VectorXd b = Eigen::VectorXd::Zero(p);
  std::vector<long> active;
  std::vector<char> in_active(static_cast<size_t>(p), 0);
  double rsq = 0.0, rsq_prev = 0.0;
  for (long l = 0; l < lam.size(); ++l) {
    const double al = lam(l);
    // one coordinate update: u = g_k + xv_k b_k, b_k <- S(u, al pf_k) / xv_k
    auto update = [&](long k, double& dlx) {
      const double gk = grad.value(k);
      const double u = gk + s.xv(k) * b(k);
      const double v = std::abs(u) - al * pf(k);
      const double bnew = v > 0.0 ? std::copysign(v, u) / s.xv(k) : 0.0;
      if (bnew == b(k)) return;
      const double del = bnew - b(k);
      rsq += del * (2.0 * gk - del * s.xv(k));
      b(k) = bnew;
      grad.apply(k, del);
      dlx = std::max(dlx, s.xv(k) * del * del);
      if (!in_active[static_cast<size_t>(k)]) {
        in_active[static_cast<size_t>(k)] = 1;
        active.push_back(k);
      }
    };
    bool done = false;
    while (!done) {
      // full pass
      double dlx = 0.0;
      for (long k = 0; k < p; ++k)
        if (s.ju[static_cast<size_t>(k)]) update(k, dlx);
      if (++out.passes > o.max_passes) break;
      if (dlx < o.tol) {
        done = true;
        break;
      }
      // passes over the active set until it converges
      for (;;) {
        dlx = 0.0;
        for (long k : active) update(k, dlx);
        if (++out.passes > o.max_passes || dlx < o.tol) break;
      }
      if (out.passes > o.max_passes) break;
    }
    if (!done) {
      out.converged = false;
      break;
    }
    out.b.col(l) = b;
    out.rsq(l) = rsq;
    out.L = static_cast<int>(l + 1);
    // glmnet's path exits (only on a computed path, never on a user lambda sequence)
    if (exits && l + 1 >= kMinLambdas) {
      if (rsq - rsq_prev < kFdev * rsq) break;
      if (rsq > kDevMax) break;
    }
    rsq_prev = rsq;
  }
  return out;
}

Eigen::VectorXd penalty_of(const LassoOptions& o, long p) {
  if (o.penalty_factor.size() == 0) return Eigen::VectorXd::Ones(p);
  // glmnet rescales the penalty factors to sum to the number of columns
  Eigen::VectorXd pf = o.penalty_factor;
  const double sum = pf.sum();
  if (sum > 0.0) pf *= static_cast<double>(p) / sum;
  return pf;
}

// lambda_max in standardised units: fit the unpenalised columns (lambda = inf), then
// lambda_max = max over penalised usable columns of |g_j| / pf_j
template <class Grad>
double lambda_max_of(Grad grad, const Scaling& s, const Eigen::VectorXd& pf, const LassoOptions& o) {
  const long p = s.xv.size();
  bool any_free = false;
  for (long k = 0; k < p; ++k) any_free |= pf(k) == 0.0 && s.ju[static_cast<size_t>(k)];
  if (any_free) {
    Eigen::VectorXd lam(1);
    lam(0) = std::numeric_limits<double>::max();
    cd_path(grad, s, pf, lam, o, false);
  }
  double lmax = 0.0;
  for (long k = 0; k < p; ++k)
    if (s.ju[static_cast<size_t>(k)] && pf(k) > 0.0) lmax = std::max(lmax, std::abs(grad.value(k)) / pf(k));
  return lmax;
}

// scaling and standardised Gram / gradient of a training set from its moments (shifted data)
void problem_from_moments(const Moments& m, const LassoOptions& o, Scaling& s, Eigen::MatrixXd& G,
                          std::vector<Problem>& probs) {
  const long p = m.sx.size();
  const double n = static_cast<double>(m.n);
  s.n = m.n;
  // the scales are always the centred (1/n) standard deviations; without an intercept glmnet
  // does not centre the data (raw second moments) but still scales by them
  const Eigen::VectorXd mean = m.sx / n;
  const Eigen::VectorXd mu = o.intercept ? mean : Eigen::VectorXd::Zero(p);
  Eigen::MatrixXd C = m.sxx / n;
  C.noalias() -= mu * mu.transpose();
  s.xm = mu;  // relative to the shift; the caller adds it
  s.ju.assign(static_cast<size_t>(p), 1);
  s.xs.resize(p);
  s.xv.resize(p);
  for (long k = 0; k < p; ++k) {
    const double ms = m.sxx(k, k) / n;
    const double var = ms - mean(k) * mean(k);
    s.ju[static_cast<size_t>(k)] = var > kConstantColumn * std::max(ms, 1e-300) && var > 0.0;
    s.xs(k) = o.standardize && s.ju[static_cast<size_t>(k)] ? std::sqrt(var) : 1.0;
  }
  const Eigen::VectorXd inv = s.xs.cwiseInverse();
  G = inv.asDiagonal() * C * inv.asDiagonal();
  for (long k = 0; k < p; ++k) s.xv(k) = s.ju[static_cast<size_t>(k)] ? G(k, k) : 1.0;
  probs.resize(static_cast<size_t>(m.sy.size()));
  for (long r = 0; r < m.sy.size(); ++r) {
    Problem& pr = probs[static_cast<size_t>(r)];
    pr.s = s;
    const double ybar = m.sy(r) / n;
    const double var = m.syy(r) / n - ybar * ybar;
    pr.ym = o.intercept ? ybar : 0.0;
    pr.ys = var > 0.0 ? std::sqrt(var) : 1.0;
    pr.g0 = inv.asDiagonal() * (m.sxy.col(r) / n - mu * pr.ym) / pr.ys;
  }
}

// coefficients on the original scale of the shifted data: b = ys c / xs, a0 = ym - xm'b
void to_original(const Problem& pr, const RawPath& raw, long L, Eigen::MatrixXd& beta, Eigen::VectorXd& a0) {
  const long p = pr.s.xs.size();
  beta.setZero(p, L);
  a0.setConstant(L, pr.ym);
  for (long l = 0; l < std::min<long>(L, raw.L); ++l) {
    beta.col(l) = pr.ys * raw.b.col(l).cwiseQuotient(pr.s.xs);
    a0(l) = pr.ym - pr.s.xm.dot(beta.col(l));
  }
  // cv.glmnet uses the last solution beyond a truncated path
  for (long l = raw.L; l < L && raw.L > 0; ++l) {
    beta.col(l) = beta.col(raw.L - 1);
    a0(l) = a0(raw.L - 1);
  }
}

Eigen::VectorXd lambda_sequence(const LassoOptions& o, double lmax_std, double ys, long n, long p) {
  if (!o.lambda.empty()) {
    Eigen::VectorXd lam(static_cast<long>(o.lambda.size()));
    for (size_t i = 0; i < o.lambda.size(); ++i) lam(static_cast<long>(i)) = o.lambda[i] / ys;
    return lam;
  }
  const double eps = o.lambda_min_ratio > 0 ? o.lambda_min_ratio : (n > p ? 1e-4 : 1e-2);
  Eigen::VectorXd lam(o.nlambda);
  // lambda_l = lambda_max * eps^(l / (L - 1)), computed as glmnet does (repeated product)
  const double alf = o.nlambda > 1 ? std::pow(eps, 1.0 / (o.nlambda - 1)) : 1.0;
  lam(0) = lmax_std;
  for (int l = 1; l < o.nlambda; ++l) lam(l) = lam(l - 1) * alf;
  return lam;
}

bool use_covariance(const LassoOptions& o, long p) {
  return o.algorithm == LassoAlgorithm::Covariance || (o.algorithm == LassoAlgorithm::Auto && p < kCovarianceMaxP);
}

void check_data(const Eigen::Ref<const Eigen::MatrixXd>& X, const Eigen::Ref<const Eigen::MatrixXd>& Y,
                const LassoOptions& o) {
  o.validate();
  if (X.rows() != Y.rows())
    throw InvalidArgument(fmt::format("lasso: X has {} rows, y has {} (one value per sample expected)", X.rows(), Y.rows()));
  if (X.rows() < 2) throw InvalidArgument(fmt::format("lasso: {} samples, expected at least 2", X.rows()));
  if (X.cols() < 1) throw InvalidArgument("lasso: X has no columns");
  if (o.penalty_factor.size() != 0 && o.penalty_factor.size() != X.cols())
    throw InvalidArgument(fmt::format("lasso: penalty_factor has size {}, expected {} (X.cols())", o.penalty_factor.size(), X.cols()));
  for (long c = 0; c < X.cols(); ++c)
    if (!X.col(c).allFinite()) throw InvalidArgument(fmt::format("lasso: column {} of X has a non-finite value", c));
  for (long c = 0; c < Y.cols(); ++c)
    if (!Y.col(c).allFinite()) throw InvalidArgument(fmt::format("lasso: response {} has a non-finite value", c));
}

// the data reordered by fold and shifted (by the column means when there is an intercept), with
// the per-fold moments; rows of fold k are [start[k], start[k+1])
struct FoldData {
  Eigen::MatrixXd X, Y;
  Eigen::VectorXd shift_x, shift_y;
  std::vector<long> start;
  std::vector<Moments> fold;
  Moments total;
};

FoldData fold_data(const Eigen::Ref<const Eigen::MatrixXd>& X, const Eigen::Ref<const Eigen::MatrixXd>& Y,
                   const std::vector<int>& foldid, int K, const LassoOptions& o, bool gram) {
  const long n = X.rows(), p = X.cols(), m = Y.cols();
  FoldData d;
  d.shift_x = o.intercept ? Eigen::VectorXd(X.colwise().mean().transpose()) : Eigen::VectorXd::Zero(p);
  d.shift_y = o.intercept ? Eigen::VectorXd(Y.colwise().mean().transpose()) : Eigen::VectorXd::Zero(m);
  // counting sort of the rows by fold
  d.start.assign(static_cast<size_t>(K + 1), 0);
  for (long i = 0; i < n; ++i) ++d.start[static_cast<size_t>(foldid[static_cast<size_t>(i)] + 1)];
  for (int k = 0; k < K; ++k) d.start[static_cast<size_t>(k + 1)] += d.start[static_cast<size_t>(k)];
  std::vector<long> pos(d.start.begin(), d.start.end() - 1);
  std::vector<long> order(static_cast<size_t>(n));
  for (long i = 0; i < n; ++i) order[static_cast<size_t>(pos[static_cast<size_t>(foldid[static_cast<size_t>(i)])]++)] = i;
  d.X.resize(n, p);
  d.Y.resize(n, m);
  for (long c = 0; c < p; ++c)
    for (long r = 0; r < n; ++r) d.X(r, c) = X(order[static_cast<size_t>(r)], c) - d.shift_x(c);
  for (long c = 0; c < m; ++c)
    for (long r = 0; r < n; ++r) d.Y(r, c) = Y(order[static_cast<size_t>(r)], c) - d.shift_y(c);
  // per-fold moments (the Gram only for covariance updates)
  d.fold.resize(static_cast<size_t>(K));
  d.total.zero(p, m);
  if (!gram) d.total.sxx.resize(0, 0);
  for (int k = 0; k < K; ++k) {
    Moments& f = d.fold[static_cast<size_t>(k)];
    const long a = d.start[static_cast<size_t>(k)], len = d.start[static_cast<size_t>(k + 1)] - a;
    f.zero(p, m);
    f.n = len;
    const auto Xk = d.X.middleRows(a, len);
    const auto Yk = d.Y.middleRows(a, len);
    f.sx = Xk.colwise().sum().transpose();
    f.sy = Yk.colwise().sum().transpose();
    f.syy = Yk.colwise().squaredNorm().transpose();
    f.sxy.noalias() = Xk.transpose() * Yk;
    if (gram) {
      for (long b0 = 0; b0 < len; b0 += kGramBlockRows) {
        const long bl = std::min(kGramBlockRows, len - b0);
        f.sxx.selfadjointView<Eigen::Lower>().rankUpdate(Xk.middleRows(b0, bl).transpose());
      }
      f.sxx.triangularView<Eigen::StrictlyUpper>() = f.sxx.transpose();
      d.total += f;
    } else {
      f.sxx.resize(0, 0);
      d.total.n += f.n, d.total.sx += f.sx, d.total.sxy += f.sxy, d.total.sy += f.sy, d.total.syy += f.syy;
    }
  }
  return d;
}

// naive-update problem of a row set: explicit standardised copy
Scaling naive_scaling(const Eigen::MatrixXd& Xtr, const LassoOptions& o, Eigen::MatrixXd& Xs) {
  const long n = Xtr.rows(), p = Xtr.cols();
  Scaling s;
  s.n = n;
  s.xm = o.intercept ? Eigen::VectorXd(Xtr.colwise().mean().transpose()) : Eigen::VectorXd::Zero(p);
  s.xs.resize(p);
  s.xv.resize(p);
  s.ju.assign(static_cast<size_t>(p), 1);
  Xs.resize(n, p);
  for (long k = 0; k < p; ++k) {
    Xs.col(k) = Xtr.col(k).array() - s.xm(k);
    const double mean = Xtr.col(k).mean();
    const double ms = Xtr.col(k).squaredNorm() / static_cast<double>(n);
    const double var = (Xtr.col(k).array() - mean).square().mean();
    s.ju[static_cast<size_t>(k)] = var > kConstantColumn * std::max(ms, 1e-300) && var > 0.0;
    s.xs(k) = o.standardize && s.ju[static_cast<size_t>(k)] ? std::sqrt(var) : 1.0;
    Xs.col(k) /= s.xs(k);
    s.xv(k) = s.ju[static_cast<size_t>(k)] ? Xs.col(k).squaredNorm() / static_cast<double>(n) : 1.0;
  }
  return s;
}

// fits one path for every response of a training set; lam_orig empty: compute the path
// (per response) and return it in lam_orig
struct TrainSet {
  // covariance: moments; naive: rows
  const Moments* moments = nullptr;
  Eigen::MatrixXd Xtr, Ytr;
};

std::vector<LassoPath> fit_paths(const TrainSet& t, const LassoOptions& o, bool cov,
                                 const std::vector<Eigen::VectorXd>* lam_orig, const Eigen::VectorXd& shift_x,
                                 const Eigen::VectorXd& shift_y) {
  std::vector<LassoPath> out;
  Scaling s;
  Eigen::MatrixXd G, Xs;
  std::vector<Problem> probs;
  long p = 0, n = 0;
  if (cov) {
    problem_from_moments(*t.moments, o, s, G, probs);
    p = t.moments->sx.size();
    n = t.moments->n;
  } else {
    s = naive_scaling(t.Xtr, o, Xs);
    p = t.Xtr.cols();
    n = t.Xtr.rows();
    for (long r = 0; r < t.Ytr.cols(); ++r) {
      Problem pr;
      pr.s = s;
      pr.ym = o.intercept ? t.Ytr.col(r).mean() : 0.0;
      const double var = (t.Ytr.col(r).array() - t.Ytr.col(r).mean()).square().mean();
      pr.ys = var > 0.0 ? std::sqrt(var) : 1.0;
      probs.push_back(pr);
    }
  }
  const Eigen::VectorXd pf = penalty_of(o, p);
  for (size_t r = 0; r < probs.size(); ++r) {
    const Problem& pr = probs[r];
    RawPath raw;
    Eigen::VectorXd lam;
    const bool user = lam_orig != nullptr || !o.lambda.empty();
    auto run = [&](auto& grad) {
      if (lam_orig) {
        lam = (*lam_orig)[r] / pr.ys;
      } else {
        const double lmax = o.lambda.empty() ? lambda_max_of(grad, s, pf, o) : 0.0;
        lam = lambda_sequence(o, lmax, pr.ys, n, p);
      }
      raw = cd_path(grad, s, pf, lam, o, o.early_stop && !user);
    };
    if (cov) {
      CovarianceGrad grad{G, pr.g0};
      run(grad);
    } else {
      NaiveGrad grad{Xs, ((t.Ytr.col(static_cast<long>(r)).array() - pr.ym) / pr.ys).matrix(), 1.0 / static_cast<double>(n)};
      run(grad);
    }
    LassoPath path;
    // a computed path keeps only the lambdas solved; a user/fold path keeps all (last solution repeated)
    const long L = user ? lam.size() : raw.L;
    path.lambda = lam.head(L) * pr.ys;
    Eigen::MatrixXd beta;
    Eigen::VectorXd a0;
    to_original(pr, raw, L, beta, a0);
    // undo the shift: x = x_s + shift_x, y = y_s + shift_y
    path.beta = beta;
    path.a0 = a0.array() + shift_y(static_cast<long>(r));
    for (long l = 0; l < L; ++l) path.a0(l) -= shift_x.dot(beta.col(l));
    path.df.resize(L);
    path.dev_ratio.resize(L);
    for (long l = 0; l < L; ++l) {
      path.df(l) = static_cast<int>((beta.col(l).array() != 0.0).count());
      path.dev_ratio(l) = raw.rsq(std::min<long>(l, std::max(raw.L - 1, 0)));
    }
    path.passes = raw.passes;
    path.converged = raw.converged;
    path.message = raw.converged ? "converged"
                                 : fmt::format("coordinate descent stopped after {} passes (max_passes) at lambda index {}",
                                               raw.passes, raw.L);
    out.push_back(std::move(path));
  }
  return out;
}

// glmnet's lambda.interp: the solution at s is linear in lambda between the two neighbouring
// lambdas of the path; outside the path, the first or last solution
void interpolate_path(const LassoPath& pa, const Eigen::VectorXd& s, Eigen::MatrixXd& B, Eigen::VectorXd& A0) {
  const long L = pa.lambda.size(), p = pa.beta.rows();
  B.resize(p, s.size());
  A0.resize(s.size());
  for (long i = 0; i < s.size(); ++i) {
    long left = 0, right = 0;
    double frac = 1.0;
    if (L == 0) {
      B.col(i).setZero();
      A0(i) = 0.0;
      continue;
    }
    if (s(i) >= pa.lambda(0)) {
      left = right = 0;
    } else if (s(i) <= pa.lambda(L - 1)) {
      left = right = L - 1;
    } else {
      while (right < L && pa.lambda(right) >= s(i)) ++right;
      left = right - 1;
      frac = (s(i) - pa.lambda(right)) / (pa.lambda(left) - pa.lambda(right));
    }
    B.col(i) = frac * pa.beta.col(left) + (1.0 - frac) * pa.beta.col(right);
    A0(i) = frac * pa.a0(left) + (1.0 - frac) * pa.a0(right);
  }
}

}  // namespace

void LassoOptions::validate() const {
  if (lambda.empty() && nlambda < 1) throw InvalidArgument(fmt::format("LassoOptions.nlambda is {}, must be >= 1", nlambda));
  if (!(lambda_min_ratio < 0.0 || (lambda_min_ratio > 0.0 && lambda_min_ratio < 1.0)))
    throw InvalidArgument(fmt::format("LassoOptions.lambda_min_ratio is {}, must be in (0, 1) (or < 0 for the default)", lambda_min_ratio));
  for (size_t i = 0; i < lambda.size(); ++i) {
    if (!(lambda[i] > 0.0) || !std::isfinite(lambda[i]))
      throw InvalidArgument(fmt::format("LassoOptions.lambda[{}] is {}, must be > 0 and finite", i, lambda[i]));
    if (i > 0 && !(lambda[i] < lambda[i - 1]))
      throw InvalidArgument(fmt::format("LassoOptions.lambda[{}] is {}, must be < lambda[{}] = {} (strictly decreasing)", i, lambda[i],
                                        i - 1, lambda[i - 1]));
  }
  if (!(tol > 0.0)) throw InvalidArgument(fmt::format("LassoOptions.tol is {}, must be > 0", tol));
  if (max_passes < 1) throw InvalidArgument(fmt::format("LassoOptions.max_passes is {}, must be >= 1", max_passes));
  for (long k = 0; k < penalty_factor.size(); ++k)
    if (!(penalty_factor(k) >= 0.0) || !std::isfinite(penalty_factor(k)))
      throw InvalidArgument(fmt::format("LassoOptions.penalty_factor[{}] is {}, must be >= 0 and finite", k, penalty_factor(k)));
  if (penalty_factor.size() > 0 && !(penalty_factor.sum() > 0.0))
    throw InvalidArgument("LassoOptions.penalty_factor is all zero, at least one column must be penalised");
}

void LassoCvOptions::validate(long n) const {
  if (foldid.empty()) {
    if (nfolds < 2) throw InvalidArgument(fmt::format("LassoCvOptions.nfolds is {}, must be >= 2", nfolds));
    if (nfolds > n) throw InvalidArgument(fmt::format("LassoCvOptions.nfolds is {}, must be <= the number of samples {}", nfolds, n));
  } else {
    if (static_cast<long>(foldid.size()) != n)
      throw InvalidArgument(fmt::format("LassoCvOptions.foldid has size {}, expected {} (one fold per sample)", foldid.size(), n));
    const int K = *std::max_element(foldid.begin(), foldid.end()) + 1;
    std::vector<long> count(static_cast<size_t>(std::max(K, 1)), 0);
    for (size_t i = 0; i < foldid.size(); ++i) {
      if (foldid[i] < 0) throw InvalidArgument(fmt::format("LassoCvOptions.foldid[{}] is {}, must be >= 0", i, foldid[i]));
      ++count[static_cast<size_t>(foldid[i])];
    }
    if (K < 2) throw InvalidArgument(fmt::format("LassoCvOptions.foldid uses {} fold(s), expected at least 2", K));
    for (int k = 0; k < K; ++k)
      if (count[static_cast<size_t>(k)] == 0)
        throw InvalidArgument(fmt::format("LassoCvOptions.foldid: fold {} is empty (folds must be 0..{} without gaps)", k, K - 1));
  }
  if (!(prune_ratio >= 0.0 && prune_ratio < 1.0))
    throw InvalidArgument(fmt::format("LassoCvOptions.prune_ratio is {}, must be in [0, 1)", prune_ratio));
}

Eigen::VectorXd LassoPath::predict(const Eigen::Ref<const Eigen::MatrixXd>& X, int l) const {
  if (l < 0 || l >= lambda.size()) throw InvalidArgument(fmt::format("lasso predict: path index {} out of range 0..{}", l, lambda.size() - 1));
  check_size("X.cols()", X.cols(), beta.rows(), "number of coefficients");
  return (X * beta.col(l)).array() + a0(l);
}

Eigen::VectorXd LassoCvResult::predict(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  check_size("X.cols()", X.cols(), beta.size(), "number of coefficients");
  return (X * beta).array() + a0;
}

std::vector<int> lasso_folds(long n, int nfolds, unsigned seed) {
  if (nfolds < 2) throw InvalidArgument(fmt::format("lasso_folds: nfolds is {}, must be >= 2", nfolds));
  std::vector<int> f(static_cast<size_t>(n));
  for (long i = 0; i < n; ++i) f[static_cast<size_t>(i)] = static_cast<int>(i % nfolds);
  // Fisher-Yates with mt19937 (the same on every platform, unlike std::shuffle)
  std::mt19937 rng(seed);
  for (long i = n - 1; i > 0; --i) std::swap(f[static_cast<size_t>(i)], f[static_cast<size_t>(rng() % static_cast<unsigned long>(i + 1))]);
  return f;
}

LassoPath lasso_path(const Eigen::Ref<const Eigen::MatrixXd>& X, const Eigen::Ref<const Eigen::VectorXd>& y,
                     const LassoOptions& o) {
  check_data(X, y, o);
  const bool cov = use_covariance(o, X.cols());
  const std::vector<int> one(static_cast<size_t>(X.rows()), 0);
  if (cov) {
    const FoldData d = fold_data(X, y, one, 1, o, true);
    TrainSet t;
    t.moments = &d.total;
    return std::move(fit_paths(t, o, true, nullptr, d.shift_x, d.shift_y).front());
  }
  TrainSet t;
  t.Xtr = X;
  t.Ytr = y;
  return std::move(fit_paths(t, o, false, nullptr, Eigen::VectorXd::Zero(X.cols()), Eigen::VectorXd::Zero(1)).front());
}

LassoCvResult cv_lasso(const Eigen::Ref<const Eigen::MatrixXd>& X, const Eigen::Ref<const Eigen::VectorXd>& y,
                       const LassoOptions& o, const LassoCvOptions& cv) {
  return std::move(cv_lasso_multi(X, Eigen::MatrixXd(y), o, cv).front());
}

std::vector<LassoCvResult> cv_lasso_multi(const Eigen::Ref<const Eigen::MatrixXd>& X, const Eigen::Ref<const Eigen::MatrixXd>& Y,
                                    const LassoOptions& o, const LassoCvOptions& cv) {
  check_data(X, Y, o);
  cv.validate(X.rows());
  const long n = X.rows(), p = X.cols(), m = Y.cols();
  const std::vector<int> foldid = cv.foldid.empty() ? lasso_folds(n, cv.nfolds, cv.seed) : cv.foldid;
  const int K = *std::max_element(foldid.begin(), foldid.end()) + 1;
  const bool cov = use_covariance(o, p);
  const FoldData d = fold_data(X, Y, foldid, K, o, cov);

  // the path on all samples
  TrainSet all;
  if (cov) {
    all.moments = &d.total;
  } else {
    all.Xtr = d.X;
    all.Ytr = d.Y;
  }
  std::vector<LassoPath> full = fit_paths(all, o, cov, nullptr, Eigen::VectorXd::Zero(p), Eigen::VectorXd::Zero(m));
  std::vector<Eigen::VectorXd> lams;
  for (const auto& f : full) lams.push_back(f.lambda);

  // each fold: fit on the others over the same lambdas, squared error on the fold
  std::vector<Eigen::MatrixXd> cvraw(static_cast<size_t>(m));  // K x L per response
  for (long r = 0; r < m; ++r) cvraw[static_cast<size_t>(r)].setZero(K, lams[static_cast<size_t>(r)].size());
  for (int k = 0; k < K; ++k) {
    const long a = d.start[static_cast<size_t>(k)], len = d.start[static_cast<size_t>(k + 1)] - a;
    TrainSet t;
    Moments tr;
    if (cov) {
      tr = d.total;
      tr -= d.fold[static_cast<size_t>(k)];
      t.moments = &tr;
    } else {
      t.Xtr.resize(n - len, p);
      t.Ytr.resize(n - len, m);
      t.Xtr << d.X.topRows(a), d.X.bottomRows(n - a - len);
      t.Ytr << d.Y.topRows(a), d.Y.bottomRows(n - a - len);
    }
    const bool own = cv.alignment == LassoCvAlignment::FoldPaths && o.lambda.empty();
    const std::vector<LassoPath> paths = fit_paths(t, o, cov, own ? nullptr : &lams, Eigen::VectorXd::Zero(p), Eigen::VectorXd::Zero(m));
    const auto Xk = d.X.middleRows(a, len);
    for (long r = 0; r < m; ++r) {
      const LassoPath& pa = paths[static_cast<size_t>(r)];
      Eigen::MatrixXd B;
      Eigen::VectorXd A0;
      if (own) {
        interpolate_path(pa, lams[static_cast<size_t>(r)], B, A0);
      } else {
        B = pa.beta;
        A0 = pa.a0;
      }
      Eigen::MatrixXd pred = Xk * B;
      pred.rowwise() += A0.transpose();
      pred.colwise() -= d.Y.col(r).segment(a, len);
      cvraw[static_cast<size_t>(r)].row(k) = pred.colwise().squaredNorm() / static_cast<double>(len);
    }
  }

  // cv.glmnet's summary: fold-size-weighted mean and standard error, lambda_min and lambda_1se
  std::vector<LassoCvResult> out(static_cast<size_t>(m));
  Eigen::VectorXd w(K);
  for (int k = 0; k < K; ++k) w(k) = static_cast<double>(d.start[static_cast<size_t>(k + 1)] - d.start[static_cast<size_t>(k)]);
  for (long r = 0; r < m; ++r) {
    LassoCvResult& res = out[static_cast<size_t>(r)];
    LassoPath& path = full[static_cast<size_t>(r)];
    // shift back to the original data
    const double sy = d.shift_y(r);
    for (long l = 0; l < path.lambda.size(); ++l) path.a0(l) += sy - d.shift_x.dot(path.beta.col(l));
    const Eigen::MatrixXd& raw = cvraw[static_cast<size_t>(r)];
    const long L = raw.cols();
    res.cvm = (w.transpose() * raw).transpose() / w.sum();
    res.cvsd.resize(L);
    for (long l = 0; l < L; ++l) {
      const double var = (w.array() * (raw.col(l).array() - res.cvm(l)).square()).sum() / w.sum();
      res.cvsd(l) = std::sqrt(var / (K - 1));
    }
    long imin = 0;
    for (long l = 1; l < L; ++l)
      if (res.cvm(l) < res.cvm(imin)) imin = l;
    long i1se = imin;
    for (long l = 0; l <= imin; ++l)
      if (res.cvm(l) <= res.cvm(imin) + res.cvsd(imin)) {
        i1se = l;
        break;
      }
    res.index_min = static_cast<int>(imin);
    res.index_1se = static_cast<int>(i1se);
    res.lambda_min = path.lambda(imin);
    res.lambda_1se = path.lambda(i1se);
    const long pick = cv.use_1se ? i1se : imin;
    res.beta = path.beta.col(pick);
    res.a0 = path.a0(pick);
    res.path = std::move(path);

    // prune coefficients whose standardised size is small, then optionally refit by least squares
    if (cv.prune_ratio > 0.0 || cv.refit) {
      const double nn = static_cast<double>(n);
      const Eigen::VectorXd xm = d.total.sx / nn;  // of the shifted data
      const double ym = d.total.sy(r) / nn;
      const double ysd = std::sqrt(std::max(d.total.syy(r) / nn - ym * ym, 0.0));
      std::vector<long> keep;
      for (long j = 0; j < p; ++j) {
        if (res.beta(j) == 0.0) continue;
        const double xsd = cov ? std::sqrt(std::max(d.total.sxx(j, j) / nn - xm(j) * xm(j), 0.0))
                               : std::sqrt((d.X.col(j).array() - xm(j)).square().mean());
        if (std::abs(res.beta(j)) * xsd < cv.prune_ratio * ysd) {
          res.beta(j) = 0.0;
          ++res.pruned;
        } else {
          keep.push_back(j);
        }
      }
      if (cv.refit && !keep.empty()) {
        const long q = static_cast<long>(keep.size());
        Eigen::MatrixXd A(q, q);
        Eigen::VectorXd rhs(q);
        for (long i = 0; i < q; ++i) {
          const long ji = keep[static_cast<size_t>(i)];
          for (long k2 = 0; k2 < q; ++k2) {
            const long jk = keep[static_cast<size_t>(k2)];
            A(i, k2) = cov ? d.total.sxx(ji, jk) / nn - xm(ji) * xm(jk)
                           : ((d.X.col(ji).array() - xm(ji)) * (d.X.col(jk).array() - xm(jk))).mean();
          }
          rhs(i) = d.total.sxy(ji, r) / nn - xm(ji) * ym;
        }
        if (!o.intercept) {
          // raw moments
          for (long i = 0; i < q; ++i) {
            const long ji = keep[static_cast<size_t>(i)];
            for (long k2 = 0; k2 < q; ++k2) A(i, k2) += xm(ji) * xm(keep[static_cast<size_t>(k2)]);
            rhs(i) += xm(ji) * ym;
          }
        }
        const Eigen::VectorXd bk = A.ldlt().solve(rhs);
        res.beta.setZero();
        for (long i = 0; i < q; ++i) res.beta(keep[static_cast<size_t>(i)]) = bk(i);
      }
      // intercept of the chosen model on the original data
      const Eigen::VectorXd xmean = xm + d.shift_x;
      res.a0 = o.intercept ? (ym + sy) - xmean.dot(res.beta) : 0.0;
    }
  }
  return out;
}

}  // namespace twinwatch::ident
