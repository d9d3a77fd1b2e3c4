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
  for (size_t r = 0; r < runs.size(); ++r)
    if (runs[r].empty()) throw InvalidArgument(fmt::format("static threshold: healthy run {} is empty", r));
  StaticThresholdAccumulator acc;
  for (const auto& run : runs) {
    for (const VectorJ& v : run) acc.add(v);
    acc.end_run();
  }
  return acc.learn(k_sigma);
}

void StaticThresholdAccumulator::add(const VectorJ& v) {
  if (n_ < 0) {
    n_ = v.size();
    level_ = sum_ = sum2_ = VectorJ::Zero(n_);
  }
  if (k_ == 0) mae_ = VectorJ::Zero(n_);
  if (v.size() != n_)
    throw InvalidArgument(fmt::format("static threshold: a residual of run {} has size {}, expected {}", runs_, v.size(), n_));
  // one nan would make every level nan, and a nan threshold never trips
  if (!v.allFinite())
    throw InvalidArgument(fmt::format("static threshold: residual {} of healthy run {} is not finite ({}); expected finite "
                                      "residuals from finite signals",
                                      k_, runs_, fmt::join(v, " ")));
  mae_ += v.cwiseAbs();
  sum_ += v;
  sum2_ += v.cwiseProduct(v);
  ++k_;
}

void StaticThresholdAccumulator::end_run() {
  if (k_ == 0) return;
  // max over runs of the per-run MAE
  count_ += static_cast<double>(k_);
  mae_ /= static_cast<double>(k_);
  level_ = level_.cwiseMax(mae_);
  k_ = 0;
  ++runs_;
}

StaticThreshold StaticThresholdAccumulator::learn(double k_sigma) const {
  if (runs_ == 0) throw InvalidArgument("static threshold: no healthy runs given, expected at least 1");
  if (!(k_sigma >= 0.0)) throw InvalidArgument(fmt::format("static threshold: k_sigma is {}, must be >= 0", k_sigma));
  // plus k sigma of all healthy residuals pooled
  StaticThreshold t;
  const VectorJ mean = sum_ / count_;
  const VectorJ var = (sum2_ / count_ - mean.cwiseProduct(mean)).cwiseMax(0.0);
  t.level = level_ + k_sigma * var.cwiseSqrt();
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
  DynamicThresholdSampler sampler(r.size(), options);
  for (size_t k = 0; k < r.size(); ++k) sampler.add(r[k], qd[k], qdd[k]);
  return sampler.fit();
}

namespace {
constexpr size_t kLargestKept = 64;  // the largest |r| kept beside the uniform decimation: they bind the constraints
// the heap's order: the smallest |r| on top (of equal ones, the later sample: the earlier is kept)
template <class Kept>
bool kept_before(const Kept& a, const Kept& b) {
  const double x = std::abs(a.r), y = std::abs(b.r);
  return x > y || (x == y && a.k < b.k);
}
}  // namespace

DynamicThresholdSampler::DynamicThresholdSampler(size_t total, const DynamicThresholdOptions& options)
    : options_(options), total_(total) {
  options.validate();
  if (total < 10) throw InvalidArgument(fmt::format("dynamic threshold: {} healthy samples, expected at least 10", total));
  wanted_ = std::min(total, static_cast<size_t>(options.max_samples));
  uniform_.reserve(wanted_);
  largest_.reserve(kLargestKept);
}

void DynamicThresholdSampler::add(double r, double qd, double qdd) {
  const size_t k = count_;
  if (k >= total_) throw InvalidArgument(fmt::format("dynamic threshold: sample {} of {}: more than were announced", k + 1, total_));
  // the LP solvers assert on non-finite coefficients (CLP aborts the process): refuse them here
  if (!std::isfinite(r) || !std::isfinite(qd) || !std::isfinite(qdd))
    throw InvalidArgument(fmt::format("dynamic threshold: healthy sample {} is not finite (r {}, qd {}, qdd {}); expected finite "
                                      "residuals, velocities and accelerations",
                                      k, r, qd, qdd));
  ++count_;
  const Kept x{k, r, qd, qdd};
  // decimate uniformly (samples i N / K, i < K), but always keep the largest residuals
  if (next_ < wanted_ && next_ * total_ / wanted_ == k) {
    uniform_.push_back(x);
    ++next_;
  }
  const auto cmp = [](const Kept& a, const Kept& b) { return kept_before(a, b); };
  if (largest_.size() < kLargestKept) {
    largest_.push_back(x);
    std::push_heap(largest_.begin(), largest_.end(), cmp);
  } else if (kept_before(x, largest_.front())) {
    std::pop_heap(largest_.begin(), largest_.end(), cmp);
    largest_.back() = x;
    std::push_heap(largest_.begin(), largest_.end(), cmp);
  }
}

DynamicThresholdFit DynamicThresholdSampler::fit() const {
  if (count_ != total_)
    throw InvalidArgument(fmt::format("dynamic threshold: {} healthy samples given of the {} announced", count_, total_));
  std::vector<Kept> keep = uniform_;
  keep.insert(keep.end(), largest_.begin(), largest_.end());
  std::sort(keep.begin(), keep.end(), [](const Kept& a, const Kept& b) { return a.k < b.k; });
  keep.erase(std::unique(keep.begin(), keep.end(), [](const Kept& a, const Kept& b) { return a.k == b.k; }), keep.end());

  std::vector<double> ar, aqd, aqdd, rv;
  for (const Kept& x : keep) {
    ar.push_back(std::abs(x.r));
    aqd.push_back(std::abs(x.qd));
    aqdd.push_back(std::abs(x.qdd));
    rv.push_back(x.r);
  }
  double xi = options_.margin;
  if (xi <= 0.0) xi = kAutoMarginSigmas * robust_sigma(rv);

  DynamicThresholdFit best;
  best.message = "linear program infeasible or unbounded for every rho";
  // rho is chosen by the LP's own objective (max gap + weighted mean level). Near-ties (often:
  // the max gap is set by one binding sample for every rho) keep the earlier rho of the grid, so
  // the choice does not flip on rounding differences in the residuals.
  double best_obj = 0.0;
  for (double rho : options_.rho_grid) {
    DynamicThresholdJoint p;
    double obj = 0.0;
    if (!solve_lp(ar, aqd, aqdd, rho, xi, options_.mean_gap_weight, p, obj)) continue;
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
