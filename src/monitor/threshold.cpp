#include "twinwatch/monitor/threshold.hpp"

#include <ClpSimplex.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "twinwatch/core/error.hpp"

namespace twinwatch::monitor {

namespace {

// 1.4826 * MAD is a consistent estimate of sigma for Gaussian noise and ignores the rare peaks
// (reversals) that the dynamic part of the threshold is there to cover.
constexpr double kMadToSigma = 1.4826;
// auto margin: three robust standard deviations above the healthy residual
constexpr double kAutoMarginSigmas = 3.0;

double robust_sigma(std::vector<double> v) {
  if (v.empty()) return 0.0;
  auto mid = v.begin() + static_cast<long>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  const double med = *mid;
  for (double& x : v) x = std::abs(x - med);
  std::nth_element(v.begin(), mid, v.end());
  return kMadToSigma * *mid;
}

}  // namespace

StaticThreshold StaticThreshold::learn(const std::vector<std::vector<VectorJ>>& runs, double k_sigma) {
  if (runs.empty()) throw InvalidArgument("static threshold: no healthy runs given, expected at least 1");
  if (!(k_sigma >= 0.0)) throw InvalidArgument(fmt::format("static threshold: k_sigma is {}, must be >= 0", k_sigma));
  long n = -1;
  for (size_t r = 0; r < runs.size(); ++r) {
    if (runs[r].empty()) throw InvalidArgument(fmt::format("static threshold: healthy run {} is empty", r));
    for (size_t k = 0; k < runs[r].size(); ++k) {
      const VectorJ& v = runs[r][k];
      if (n < 0) n = v.size();
      if (v.size() != n)
        throw InvalidArgument(fmt::format("static threshold: a residual of run {} has size {}, expected {}", r, v.size(), n));
      // one nan would make every level nan, and a nan threshold never trips
      if (!v.allFinite())
        throw InvalidArgument(fmt::format("static threshold: residual {} of healthy run {} is not finite ({}); expected finite "
                                          "residuals from finite signals",
                                          k, r, fmt::join(v, " ")));
    }
  }
  // max over runs of the per-run MAE, plus k sigma of all healthy residuals pooled
  StaticThreshold t;
  t.level = VectorJ::Zero(n);
  VectorJ sum = VectorJ::Zero(n), sum2 = VectorJ::Zero(n);
  double count = 0.0;
  for (const auto& run : runs) {
    VectorJ mae = VectorJ::Zero(n);
    for (const VectorJ& v : run) {
      mae += v.cwiseAbs();
      sum += v;
      sum2 += v.cwiseProduct(v);
    }
    count += static_cast<double>(run.size());
    mae /= static_cast<double>(run.size());
    t.level = t.level.cwiseMax(mae);
  }
  const VectorJ mean = sum / count;
  const VectorJ var = (sum2 / count - mean.cwiseProduct(mean)).cwiseMax(0.0);
  t.level += k_sigma * var.cwiseSqrt();
  return t;
}

void DynamicThresholdOptions::validate() const {
  if (!std::isfinite(margin)) throw InvalidArgument(fmt::format("margin is {}, must be finite", margin));
  if (rho_grid.empty()) throw InvalidArgument("rho_grid is empty, expected at least one rho > 0");
  for (size_t i = 0; i < rho_grid.size(); ++i)
    if (!(rho_grid[i] > 0.0)) throw InvalidArgument(fmt::format("rho_grid[{}] is {}, must be > 0", i, rho_grid[i]));
  if (max_samples < 10) throw InvalidArgument(fmt::format("max_samples is {}, must be >= 10", max_samples));
  if (!(mean_gap_weight >= 0.0))
    throw InvalidArgument(fmt::format("mean_gap_weight is {}, must be >= 0", mean_gap_weight));
}

void DynamicThreshold::evaluate(const VectorJ& qd, const VectorJ& qdd, VectorJ& level) const {
  for (size_t i = 0; i < joints.size(); ++i) {
    const auto j = static_cast<Eigen::Index>(i);
    level[j] = joints[i].evaluate(qd[j], qdd[j]);
  }
}

namespace {

// Solves the LP of [Cao eq. 26] for one rho. Columns: psi1, psi2, psi3, upsilon, alpha.
//   rows k:  psi.u_k + upsilon            >= xi + |r_k|
//            psi.u_k + upsilon - alpha    <= |r_k|
//   min alpha + w * mean_k(psi.u_k + upsilon)
bool solve_lp(const std::vector<double>& ar, const std::vector<double>& aqd, const std::vector<double>& aqdd,
              double rho, double xi, double w, DynamicThresholdJoint& out, double& objective) {
  const int K = static_cast<int>(ar.size());
  const int ncols = 5;
  const int nrows = 2 * K;
  // column-major sparse matrix
  std::vector<CoinBigIndex> start(ncols + 1);
  std::vector<int> index;
  std::vector<double> value;
  index.reserve(static_cast<size_t>(nrows) * 4 + static_cast<size_t>(K));
  value.reserve(index.capacity());
  std::vector<double> u3(static_cast<size_t>(K));
  for (int k = 0; k < K; ++k) u3[static_cast<size_t>(k)] = std::exp(-rho * aqd[static_cast<size_t>(k)]);
  const std::vector<double>* cols[3] = {&aqdd, &aqd, &u3};
  std::vector<double> obj(ncols, 0.0);
  for (int c = 0; c < 3; ++c) {
    start[static_cast<size_t>(c)] = static_cast<CoinBigIndex>(index.size());
    double s = 0.0;
    for (int k = 0; k < K; ++k) {
      const double v = (*cols[c])[static_cast<size_t>(k)];
      s += v;
      index.push_back(2 * k);
      value.push_back(v);
      index.push_back(2 * k + 1);
      value.push_back(v);
    }
    obj[static_cast<size_t>(c)] = w * s / K;
  }
  start[3] = static_cast<CoinBigIndex>(index.size());
  for (int k = 0; k < K; ++k) {
    index.push_back(2 * k);
    value.push_back(1.0);
    index.push_back(2 * k + 1);
    value.push_back(1.0);
  }
  obj[3] = w;
  start[4] = static_cast<CoinBigIndex>(index.size());
  for (int k = 0; k < K; ++k) {
    index.push_back(2 * k + 1);
    value.push_back(-1.0);
  }
  obj[4] = 1.0;
  start[5] = static_cast<CoinBigIndex>(index.size());

  const double inf = COIN_DBL_MAX;
  std::vector<double> collb{0.0, 0.0, 0.0, 0.0, 0.0}, colub{inf, inf, inf, inf, inf};
  std::vector<double> rowlb(static_cast<size_t>(nrows)), rowub(static_cast<size_t>(nrows));
  for (int k = 0; k < K; ++k) {
    rowlb[static_cast<size_t>(2 * k)] = xi + ar[static_cast<size_t>(k)];
    rowub[static_cast<size_t>(2 * k)] = inf;
    rowlb[static_cast<size_t>(2 * k + 1)] = -inf;
    rowub[static_cast<size_t>(2 * k + 1)] = ar[static_cast<size_t>(k)];
  }
  ClpSimplex lp;
  lp.setLogLevel(0);
  lp.loadProblem(ncols, nrows, start.data(), index.data(), value.data(), collb.data(), colub.data(), obj.data(),
                 rowlb.data(), rowub.data());
  lp.setOptimizationDirection(1.0);
  lp.dual();
  if (lp.status() != 0) return false;
  // every column is bounded below by 0, which Clp holds to its primal tolerance (1e-7): a basic
  // variable at the bound can come out a rounding error below it, and the twin file takes >= 0
  const double* x = lp.primalColumnSolution();
  out.psi_qdd = std::max(0.0, x[0]);
  out.psi_qd = std::max(0.0, x[1]);
  out.psi_rev = std::max(0.0, x[2]);
  out.upsilon = std::max(0.0, x[3]);
  out.alpha = std::max(0.0, x[4]);
  out.rho = rho;
  out.margin = xi;
  objective = lp.objectiveValue();
  return true;
}

}  // namespace

DynamicThresholdFit fit_dynamic_threshold(std::span<const double> r, std::span<const double> qd,
                                          std::span<const double> qdd, const DynamicThresholdOptions& options) {
  options.validate();
  if (qd.size() != r.size() || qdd.size() != r.size())
    throw InvalidArgument(fmt::format("dynamic threshold: r, qd, qdd have sizes {}, {}, {}, expected equal", r.size(),
                                      qd.size(), qdd.size()));
  if (r.size() < 10)
    throw InvalidArgument(fmt::format("dynamic threshold: {} healthy samples, expected at least 10", r.size()));
  // the LP solvers assert on non-finite coefficients (CLP aborts the process): refuse them here
  for (size_t k = 0; k < r.size(); ++k)
    if (!std::isfinite(r[k]) || !std::isfinite(qd[k]) || !std::isfinite(qdd[k]))
      throw InvalidArgument(fmt::format("dynamic threshold: healthy sample {} is not finite (r {}, qd {}, qdd {}); expected finite "
                                        "residuals, velocities and accelerations",
                                        k, r[k], qd[k], qdd[k]));

  // decimate uniformly, but always keep the largest residuals: they bind the constraints
  const size_t N = r.size();
  const size_t K = std::min(N, static_cast<size_t>(options.max_samples));
  std::vector<size_t> keep;
  keep.reserve(K + 64);
  for (size_t k = 0; k < K; ++k) keep.push_back(k * N / K);
  std::vector<size_t> order(N);
  std::iota(order.begin(), order.end(), 0);
  const size_t top = std::min<size_t>(N, 64);
  std::partial_sort(order.begin(), order.begin() + static_cast<long>(top), order.end(),
                    [&](size_t a, size_t b) { return std::abs(r[a]) > std::abs(r[b]); });
  keep.insert(keep.end(), order.begin(), order.begin() + static_cast<long>(top));
  std::sort(keep.begin(), keep.end());
  keep.erase(std::unique(keep.begin(), keep.end()), keep.end());

  std::vector<double> ar, aqd, aqdd, rv;
  for (size_t k : keep) {
    ar.push_back(std::abs(r[k]));
    aqd.push_back(std::abs(qd[k]));
    aqdd.push_back(std::abs(qdd[k]));
    rv.push_back(r[k]);
  }
  double xi = options.margin;
  if (xi <= 0.0) xi = kAutoMarginSigmas * robust_sigma(rv);

  DynamicThresholdFit best;
  best.message = "linear program infeasible or unbounded for every rho";
  // rho is chosen by the LP's own objective (max gap + weighted mean level). Near-ties (often:
  // the max gap is set by one binding sample for every rho) keep the earlier rho of the grid, so
  // the choice does not flip on rounding differences in the residuals.
  double best_obj = 0.0;
  for (double rho : options.rho_grid) {
    DynamicThresholdJoint p;
    double obj = 0.0;
    if (!solve_lp(ar, aqd, aqdd, rho, xi, options.mean_gap_weight, p, obj)) continue;
    if (!best.ok || obj < best_obj - 1e-6 * std::max(1e-12, std::abs(best_obj))) {
      best_obj = obj;
      best.ok = true;
      best.params = p;
      best.message = "optimal";
    }
  }
  return best;
}

}  // namespace twinwatch::monitor
