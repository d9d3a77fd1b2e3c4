#include "twinwatch/ident/physics_ident.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <iterator>
#include <chrono>
#include <cmath>
#include <ctime>
#include <cstdlib>
#include <limits>
#include <random>

#include "twinwatch/core/error.hpp"
#include "twinwatch/model/description_io.hpp"

namespace twinwatch::ident {

namespace {
// a regressor column acts on a joint when it exceeds this anywhere on random states
constexpr double kColumnActive = 1e-9;
// relative ridge on the scaled normal equations: only guards against exactly unused columns
// (e.g. the payload column when no run carried a known payload)
constexpr double kRidge = 1e-10;

// a joint's back-driven factor is fitted only with at least this many back-driven samples, and
// this fraction of its samples (fewer: c_gen stays 1, the direction makes no measurable difference)
constexpr long kMinGeneratingSamples = 500;
constexpr double kMinGeneratingFraction = 0.02;
// physical range of c_gen = eta_motoring * eta_back-driven (each <= 1; harmonic drives reach
// 0.6-0.9 each, so c below 0.25 would mean a model error rather than a drive)
constexpr double kCGenMin = 0.25;
constexpr double kCGenMax = 1.0;
// viscous friction against temperature (the column qd (T - T_ref)) is fitted for a joint only when
// its temperature spans at least this much over the samples used. UR controllers report 0.1 °C
// steps; on the README's four runs (each within 0.3 °C of 35 °C) the column fitted the misfit, not
// the temperature: J3 came out +0.068 N·m·s/rad/°C (viscous friction rising with temperature,
// 6x the simulator's -0.011 and of the wrong sign) and J2 -0.058, and on a healthy 20-min run that
// cooled 3.7 °C the monitor then read J3's mispredicted friction as wear (docs/validation.md)
constexpr double kMinViscousTemperatureSpan = 2.0;
// a joint whose speed never reaches this in any recording is refused [rad/s]
constexpr double kMinJointSpeed = 0.02;
// [rad/s] the temperature span that lets identify fit a joint's viscous-temperature slope is taken
// over the samples where the joint moves at least this fast (review, session 47)
constexpr double kTemperatureSpanSpeed = 0.05;
// a drive gain counts as identified when the known payload's current on the joint (rms) is at
// least this multiple of the joint's fit RMSE. Set on the simulated UR3e (docs/validation.md):
// ratios J2 4.2, J3 5.7, J4 1.9 (gains within 1, 0.3, 12 %) against J5 1.4, J1 0.02, J6 0
// (off by -22, +183, +58 %)
constexpr double kPayloadSignalMin = 1.5;
// Levenberg-Marquardt of the bilinear fit: iteration cap and relative decrease that counts as converged
constexpr int kLmIterations = 200;
constexpr double kLmTolerance = 1e-12;

std::string now_iso() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

// sufficient statistics of one joint's samples of one drive direction
struct Stats {
  Eigen::MatrixXd A;        // sum r r^T
  Eigen::VectorXd cp, b;    // sum r tau_p, sum r i
  double d = 0.0, e = 0.0, pp = 0.0;  // sum i tau_p, sum i^2, sum tau_p^2
  long count = 0;
};

// Levenberg-Marquardt (Gauss-Newton Hessian) of
//   SSE(theta, h) = sum_groups sum_k (i_k - h_g (r_k theta + tau_p,k))^2
// on the groups' statistics; group 2j is joint j motoring, 2j + 1 back-driven (fitted only when
// free_gen[j]; a folded group is empty). Without a known payload the scale of theta and h is
// not identifiable and is fixed by prod_j h_2j = 1.
//
// The coefficients `nonneg` (friction levels: friction opposes the motion) are held >= 0 by a
// projected Levenberg-Marquardt with an active set: a coefficient at 0 whose gradient points below
// 0 is fixed for that step, and every step is projected back onto the bounds. Returns the
// coefficients the bound holds at 0 (the SSE would still fall below it).
std::vector<int> fit_bilinear_bounded(const std::vector<Stats>& st, const std::vector<bool>& free_gen, bool any_payload, bool fixed_h,
                                      Eigen::VectorXd& theta, std::vector<double>& h, const std::vector<int>& nonneg) {
  const int p = static_cast<int>(theta.size());
  const int n = static_cast<int>(free_gen.size());
  std::vector<int> active;  // fitted groups
  for (int g = 0; g < 2 * n; ++g)
    if (g % 2 == 0 || free_gen[static_cast<size_t>(g / 2)]) active.push_back(g);
  const int m = p + static_cast<int>(active.size());
  auto sse_of = [&](const Eigen::VectorXd& th, const std::vector<double>& hh) {
    double sum = 0.0;
    for (int g : active) {
      const Stats& x = st[static_cast<size_t>(g)];
      const double hg = hh[static_cast<size_t>(g)];
      const double num = x.b.dot(th) + x.d;
      const double den = th.dot(x.A * th) + 2.0 * th.dot(x.cp) + x.pp;
      sum += x.e - 2.0 * hg * num + hg * hg * den;
    }
    return sum;
  };
  for (int i : nonneg) theta(i) = std::max(theta(i), 0.0);  // start inside the bounds
  // half gradient of the SSE in theta (for the bounds held at the end)
  auto theta_gradient = [&](const Eigen::VectorXd& th, const std::vector<double>& hh) {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(p);
    for (int grp : active) {
      const Stats& x = st[static_cast<size_t>(grp)];
      const double hg = hh[static_cast<size_t>(grp)];
      g += hg * hg * (x.A * th + x.cp) - hg * x.b;
    }
    return g;
  };
  auto held_at_zero = [&] {
    std::vector<int> held;
    if (nonneg.empty()) return held;
    const Eigen::VectorXd g = theta_gradient(theta, h);
    for (int i : nonneg)
      if (theta(i) <= 0.0 && g(i) > 0.0) held.push_back(i);
    return held;
  };
  double mu = 1e-3, obj = sse_of(theta, h);
  for (int it = 0; it < kLmIterations; ++it) {
    // normal equations J^T J and J^T res of the residuals i - h_g t, t = r theta + tau_p
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(m, m);
    Eigen::VectorXd grad = Eigen::VectorXd::Zero(m);  // half gradient of the SSE
    for (size_t a = 0; a < active.size(); ++a) {
      const Stats& x = st[static_cast<size_t>(active[a])];
      const double hg = h[static_cast<size_t>(active[a])];
      const int col = p + static_cast<int>(a);
      const Eigen::VectorXd At = x.A * theta + x.cp;  // sum r t
      const double num = x.b.dot(theta) + x.d;        // sum i t
      const double den = theta.dot(At) + theta.dot(x.cp) + x.pp;  // sum t^2
      H.topLeftCorner(p, p) += hg * hg * x.A;
      H.block(0, col, p, 1) = hg * At;
      H.block(col, 0, 1, p) = hg * At.transpose();
      H(col, col) = den;
      grad.head(p) += -hg * x.b + hg * hg * At;
      grad(col) = -num + hg * den;
      if (fixed_h) {  // (a joint-torque twin: h stays 1, theta alone is fitted, the linear least squares)
        H.block(0, col, p, 1).setZero();
        H.block(col, 0, 1, p).setZero();
        H(col, col) = 1.0;
        grad(col) = 0.0;
      }
    }
    // the active set: a bounded coefficient at 0 that the SSE would push below 0 stays at 0 this step
    for (int i : nonneg)
      if (theta(i) <= 0.0 && grad(i) > 0.0) {
        H.row(i).setZero();
        H.col(i).setZero();
        H(i, i) = 1.0;
        grad(i) = 0.0;
      }
    // damped, column-scaled step; a step that makes a drive gain or factor <= 0 counts as worse
    const Eigen::VectorXd D = H.diagonal().cwiseMax(1e-300).cwiseSqrt();
    bool accepted = false;
    for (int tries = 0; tries < 20 && !accepted; ++tries) {
      Eigen::MatrixXd Hs = D.asDiagonal().inverse() * H * D.asDiagonal().inverse();
      Hs.diagonal().array() += mu + kRidge;
      const Eigen::VectorXd step = -(D.asDiagonal().inverse() * Hs.ldlt().solve(D.asDiagonal().inverse() * grad));
      Eigen::VectorXd th2 = theta + step.head(p);
      for (int i : nonneg) th2(i) = std::max(th2(i), 0.0);  // projected onto the bounds
      std::vector<double> h2 = h;
      for (size_t a = 0; a < active.size(); ++a) h2[static_cast<size_t>(active[a])] += step(p + static_cast<int>(a));
      bool positive = true;
      for (int g : active) positive &= h2[static_cast<size_t>(g)] > 0.0;
      if (!any_payload && !fixed_h && positive) {
        // no absolute scale: keep prod g = 1 (h and theta trade along the flat direction)
        double lh = 0.0;
        for (int j = 0; j < n; ++j) lh += std::log(h2[static_cast<size_t>(2 * j)]);
        const double sc = std::exp(lh / n);
        for (double& v : h2) v /= sc;
        th2 *= sc;
      }
      const double obj2 = positive ? sse_of(th2, h2) : std::numeric_limits<double>::infinity();
      if (obj2 <= obj) {
        const double gain = obj - obj2;
        theta = th2;
        h = h2;
        obj = obj2;
        mu = std::max(mu / 3.0, 1e-9);
        accepted = true;
        if (gain < kLmTolerance * std::max(obj, 1e-30)) return held_at_zero();  // converged
      } else {
        mu *= 5.0;
      }
    }
    if (!accepted) return held_at_zero();
  }
  return held_at_zero();
}

// The bilinear fit, unconstrained first: on data that determine the friction levels that is the
// result, bit for bit as before the bounds existed. Only when a level in `nonneg` comes out
// negative (data that do not determine it, e.g. a joint moving one way only, where Coulomb, offset
// and gravity share one column: friction pushing the motion along would be written) is the fit
// repeated from the same start with the bounds. Returns the coefficients held at 0.
std::vector<int> fit_bilinear(const std::vector<Stats>& st, const std::vector<bool>& free_gen, bool any_payload, bool fixed_h,
                              Eigen::VectorXd& theta, std::vector<double>& h, const std::vector<int>& nonneg) {
  const Eigen::VectorXd theta0 = theta;
  const std::vector<double> h0 = h;
  fit_bilinear_bounded(st, free_gen, any_payload, fixed_h, theta, h, {});
  if (std::all_of(nonneg.begin(), nonneg.end(), [&](int i) { return theta(i) >= 0.0; })) return {};
  theta = theta0;
  h = h0;
  return fit_bilinear_bounded(st, free_gen, any_payload, fixed_h, theta, h, nonneg);
}

// Grids of the low-speed friction's two shape parameters. 1/alpha: pre-sliding distance 0.02-5 mrad
// (harmonic drives: 0.1-2 mrad at the output [HESR §II]); v_s: 0.005-0.32 rad/s. 0 = term off.
constexpr double kPreslidingAlphas[] = {0.0, 200.0, 500.0, 1000.0, 2000.0, 5000.0, 10000.0, 20000.0, 50000.0};
constexpr double kStribeckVelocities[] = {0.0, 0.005, 0.01, 0.02, 0.04, 0.08, 0.16, 0.32};

// The shapes of each joint's low-speed friction (twin_model.cpp, "Low-speed friction"): on the
// residual current of the plain fit over every sample of every run (the memory needs them all, in
// order), for each (alpha, v_s) on the grid the two levels are a non-negative linear least squares in
// the current domain; the pair with the smallest SSE wins. The levels found here are provisional:
// identify_physics fits them again with everything else.
void choose_low_speed_shapes(TwinModel& twin, const std::vector<TrainingRun>& runs, const std::vector<std::vector<VectorJ>>& qdds) {
  const int n = twin.n_dof();
  struct Column {
    std::vector<double> e, w, qd, dq;
    std::vector<char> start;
  };
  std::vector<Column> col(static_cast<size_t>(n));
  VectorJ tau, cur;
  for (size_t ri = 0; ri < runs.size(); ++ri) {
    const device::Recording& rec = *runs[ri].recording;
    twin.set_payload(runs[ri].payload);
    // (a memory for the drive's direction read on the target, as the prediction reads it; the plain
    // fit has no pre-sliding memory for it to carry)
    FrictionMemory m;
    for (size_t k = 0; k < rec.samples.size(); ++k) {
      const RobotSample& s = rec.samples[k];
      twin.advance(m, s, qdds[ri][k]);
      twin.predict(s.q, s.qd, qdds[ri][k], s.temperature, tau, cur, &m);
      for (int j = 0; j < n; ++j) {
        Column& c = col[static_cast<size_t>(j)];
        const double g = twin.joints[static_cast<size_t>(j)].gain;
        c.e.push_back(s.current[j] - cur[j]);
        // current per N·m of extra friction: the drive factor of this sample over g
        c.w.push_back(tau[j] != 0.0 ? cur[j] / tau[j] : 1.0 / g);
        c.qd.push_back(s.qd[j]);
        c.dq.push_back(k == 0 ? 0.0 : s.q[j] - rec.samples[k - 1].q[j]);
        c.start.push_back(k == 0 ? 1 : 0);
      }
    }
  }
  twin.set_payload(model::RigidBodyInertia{});
  for (int j = 0; j < n; ++j) {
    const Column& c = col[static_cast<size_t>(j)];
    const size_t N = c.e.size();
    if (N == 0) continue;
    // Columns in the current domain: the joint's Coulomb, viscous and offset terms (re-fitted with
    // each candidate, so that they give back what they absorbed of the low-speed friction), the
    // pre-sliding column x1(alpha) and the Stribeck column x2(v_s). Sums that do not depend on the
    // candidate are built once; only x1.x2 is summed per (alpha, v_s) pair.
    constexpr int kBase = 3;
    Eigen::Matrix<double, kBase, kBase> G = Eigen::Matrix<double, kBase, kBase>::Zero();
    Eigen::Matrix<double, kBase, 1> ge = Eigen::Matrix<double, kBase, 1>::Zero();
    std::vector<Eigen::Matrix<double, kBase, 1>> base(N);
    for (size_t k = 0; k < N; ++k) {
      const double sg = c.qd[k] > 0.0 ? 1.0 : (c.qd[k] < 0.0 ? -1.0 : 0.0);
      base[k] << c.w[k] * sg, c.w[k] * c.qd[k], c.w[k];
      G += base[k] * base[k].transpose();
      ge += base[k] * c.e[k];
    }
    constexpr size_t nv = std::size(kStribeckVelocities);
    std::vector<std::vector<double>> x2(nv, std::vector<double>(N, 0.0));
    std::vector<Eigen::Matrix<double, kBase, 1>> g2(nv, Eigen::Matrix<double, kBase, 1>::Zero());
    std::vector<double> a22(nv, 0.0), b2(nv, 0.0);
    for (size_t v = 1; v < nv; ++v)
      for (size_t k = 0; k < N; ++k) {
        const double x = c.w[k] * stribeck_shape(c.qd[k], kStribeckVelocities[v]);
        x2[v][k] = x;
        g2[v] += base[k] * x;
        a22[v] += x * x;
        b2[v] += x * c.e[k];
      }
    std::vector<double> x1(N);
    double best_gain = 0.0, best_alpha = 0.0, best_vs = 0.0;
    Eigen::Vector2d best_c = Eigen::Vector2d::Zero();
    using Mat = Eigen::Matrix<double, kBase + 2, kBase + 2>;
    using Vec = Eigen::Matrix<double, kBase + 2, 1>;
    for (double alpha : kPreslidingAlphas) {
      double h = 0.0, a11 = 0.0, b1 = 0.0;
      Eigen::Matrix<double, kBase, 1> g1 = Eigen::Matrix<double, kBase, 1>::Zero();
      for (size_t k = 0; k < N; ++k) {
        if (c.start[k]) h = 0.0;
        h = presliding_step(h, c.dq[k], alpha);
        const double sg = c.qd[k] > 0.0 ? 1.0 : (c.qd[k] < 0.0 ? -1.0 : 0.0);
        x1[k] = alpha > 0.0 ? c.w[k] * (h - sg) : 0.0;
        a11 += x1[k] * x1[k];
        b1 += x1[k] * c.e[k];
        g1 += base[k] * x1[k];
      }
      for (size_t v = 0; v < nv; ++v) {
        double a12 = 0.0;
        if (v > 0 && alpha > 0.0)
          for (size_t k = 0; k < N; ++k) a12 += x1[k] * x2[v][k];
        // the candidate's normal equations; an unused column gets a unit diagonal and no right side
        Mat A = Mat::Zero();
        Vec b = Vec::Zero();
        A.topLeftCorner<kBase, kBase>() = G;
        b.head<kBase>() = ge;
        A.block<kBase, 1>(0, kBase) = A.block<1, kBase>(kBase, 0).transpose() = g1;
        A.block<kBase, 1>(0, kBase + 1) = A.block<1, kBase>(kBase + 1, 0).transpose() = g2[v];
        A(kBase, kBase) = alpha > 0.0 ? a11 : 1.0;
        A(kBase + 1, kBase + 1) = v > 0 ? a22[v] : 1.0;
        A(kBase, kBase + 1) = A(kBase + 1, kBase) = a12;
        b(kBase) = b1;
        b(kBase + 1) = b2[v];
        const Vec Dg = A.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
        Mat As = Dg.asDiagonal() * A * Dg.asDiagonal();
        As.diagonal().array() += kRidge;
        const Vec x = Dg.asDiagonal() * As.ldlt().solve(Dg.asDiagonal() * b);
        // both levels add friction (a level held at rest, Fs - Fc): a negative one is no candidate
        if ((alpha > 0.0 && !(x(kBase) > 0.0)) || (v > 0 && !(x(kBase + 1) > 0.0))) continue;
        const double gain = 2.0 * b.dot(x) - x.dot(A * x);  // SSE reduction
        if (gain > best_gain) {
          best_gain = gain;
          best_alpha = alpha;
          best_vs = kStribeckVelocities[v];
          best_c = x.tail<2>();
        }
      }
    }
    JointDrive& d = twin.joints[static_cast<size_t>(j)];
    d.presliding_alpha = best_alpha;
    d.presliding = best_alpha > 0.0 ? best_c(0) : 0.0;
    d.stribeck_velocity = best_vs;
    d.stribeck = best_vs > 0.0 ? best_c(1) : 0.0;
  }
}

// The pre-sliding state of every joint at every sample of every run (each run starts at h = 0, as
// a FrictionMemory does), with the twin's alphas.
std::vector<std::vector<VectorJ>> presliding_states(const TwinModel& twin, const std::vector<TrainingRun>& runs) {
  std::vector<std::vector<VectorJ>> out;
  for (const TrainingRun& r : runs) {
    FrictionMemory m;
    std::vector<VectorJ> hs;
    hs.reserve(r.recording->samples.size());
    for (const RobotSample& s : r.recording->samples) {
      twin.advance(m, s.q);
      hs.push_back(m.h);
    }
    out.push_back(std::move(hs));
  }
  return out;
}
}  // namespace

namespace {
// the (upper) median of v, which it reorders; v not empty
double median_in_place(std::vector<double>& v) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}
}  // namespace

// estimate_velocity_lag: a step longer than this many median periods is left out; the least samples
// and acceleration rms [rad/s²] that measure a lag (the largest lag: TwinModel::kVelocityLagMax)
constexpr double kLagStepMax = 1.5;
constexpr long kLagMinSamples = 100;
constexpr double kLagMinAcceleration = 0.05;
// ... and how far the velocity's scale against the positions' derivative may be from 1 (a deg/s
// column read as rad/s is 57)
constexpr double kLagScaleTolerance = 0.05;

void IdentOptions::validate() const {
  if (!(reversal_screen >= 0.0)) throw InvalidArgument(fmt::format("reversal_screen is {}, must be >= 0", reversal_screen));
  if (efficiency_passes < 0) throw InvalidArgument(fmt::format("efficiency_passes is {}, must be >= 0", efficiency_passes));
  if (decimate < 1) throw InvalidArgument(fmt::format("decimate is {}, must be >= 1", decimate));
  if (!(direction_blend >= 0.0) || !std::isfinite(direction_blend))
    throw InvalidArgument(fmt::format("direction_blend is {} rad/s, must be finite and >= 0", direction_blend));
  if (!std::isnan(velocity_lag) && !(std::abs(velocity_lag) <= TwinModel::kVelocityLagMax))
    throw InvalidArgument(fmt::format("velocity_lag is {} s, must be NaN (measure it) or within +-{:g} s", velocity_lag, TwinModel::kVelocityLagMax));
  if (!(acceleration_window >= 0.0 && acceleration_window <= TwinModel::kAccelerationWindowMax))
    throw InvalidArgument(fmt::format("acceleration_window is {} s, must be within 0 (the default) and {:g} s", acceleration_window,
                                      TwinModel::kAccelerationWindowMax));
  if (joint_torque && efficiency_fit != EfficiencyFit::Joint)
    throw InvalidArgument("a joint-torque twin has no drive efficiency to fit: efficiency_fit must be the joint fit (gains and c_gen stay 1)");
}

namespace {
// the recording's median step: the reader's, or measured here (a recording built in memory carries
// none); 0: none
double median_step(const device::Recording& rec) {
  if (rec.median_period > 0.0) return rec.median_period;
  std::vector<double> steps;
  for (size_t k = 1; k < rec.samples.size(); ++k) steps.push_back(rec.samples[k].timestamp - rec.samples[k - 1].timestamp);
  return steps.empty() ? 0.0 : median_in_place(steps);
}
// whether the central difference around sample k (0 < k < N - 1) measures a velocity: no stream gap
// and neither step longer than kLagStepMax median periods
bool central_step(const device::Recording& rec, size_t k, double period) {
  const RobotSample &a = rec.samples[k - 1], &s = rec.samples[k], &b = rec.samples[k + 1];
  return !s.gap_before && !b.gap_before && s.timestamp - a.timestamp <= kLagStepMax * period && b.timestamp - s.timestamp <= kLagStepMax * period;
}
// joint j's velocity at t_k from the positions: the central difference is the velocity at the
// midpoint of the two steps, carried to t_k with the acceleration x when the steps differ (a
// logger's jittery clock)
double central_velocity(const device::Recording& rec, size_t k, int j, double x) {
  const RobotSample &a = rec.samples[k - 1], &s = rec.samples[k], &b = rec.samples[k + 1];
  return (b.q[j] - a.q[j]) / (b.timestamp - a.timestamp) + x * (s.timestamp - 0.5 * (a.timestamp + b.timestamp));
}
}  // namespace

VelocityLag estimate_velocity_lag(const std::vector<const device::Recording*>& recordings,
                                  const std::vector<std::vector<VectorJ>>& accelerations) {
  if (recordings.size() != accelerations.size())
    throw InvalidArgument(fmt::format("estimate_velocity_lag: {} recordings, {} acceleration series", recordings.size(), accelerations.size()));
  VelocityLag lag;
  // least squares of  qd_k = s c_k - m a_k  (s: the velocity's scale against the positions'
  // derivative, 1 for a velocity in rad/s; m = s lambda): the normal equations' sums
  double cc = 0.0, ca = 0.0, aa = 0.0, cv = 0.0, av = 0.0, vv = 0.0;
  std::vector<double> periods;
  for (size_t ri = 0; ri < recordings.size(); ++ri) {
    const device::Recording& rec = *recordings[ri];
    const std::vector<VectorJ>& acc = accelerations[ri];
    if (acc.size() != rec.samples.size())
      throw InvalidArgument(fmt::format("estimate_velocity_lag: {} has {} samples, {} accelerations", rec.path, rec.samples.size(), acc.size()));
    if (!(rec.present & kFieldActualQd) || rec.samples.size() < 3) continue;
    const double period = median_step(rec);
    if (!(period > 0.0)) continue;
    periods.push_back(period);
    for (size_t k = 1; k + 1 < rec.samples.size(); ++k) {
      if (!central_step(rec, k, period)) continue;
      for (int j = 0; j < rec.n_dof; ++j) {
        const double x = acc[k][j], v = rec.samples[k].qd[j];
        const double c = central_velocity(rec, k, j, x);
        if (!std::isfinite(c) || !std::isfinite(x) || !std::isfinite(v)) continue;
        cc += c * c, ca += c * x, aa += x * x, cv += c * v, av += x * v, vv += v * v;
        ++lag.samples;
      }
    }
  }
  if (!periods.empty()) lag.period = median_in_place(periods);
  const double N = static_cast<double>(std::max(1L, lag.samples));
  if (lag.samples >= kLagMinSamples && !(cc > 0.0)) {
    lag.note = "the streamed velocity's lag was not measured: actual_q does not change in the recordings";
    return lag;
  }
  if (lag.samples < kLagMinSamples || !(aa / N >= kLagMinAcceleration * kLagMinAcceleration)) {
    lag.note = fmt::format("the streamed velocity's lag was not measured: {} samples, acceleration rms {:.3g} rad/s² (expected at least {} "
                           "samples and {:g} rad/s²); the velocity is read as at its sample's instant",
                           lag.samples, std::sqrt(aa / N), kLagMinSamples, kLagMinAcceleration);
    return lag;
  }
  // [cc -ca; -ca aa] [s; m] = [cv; -av]
  const double det = cc * aa - ca * ca;
  if (!(det > 0.0)) {
    lag.note = "the streamed velocity's lag was not measured: the positions' velocity and the acceleration move together";
    return lag;
  }
  const double sc = (cv * aa - ca * av) / det;
  const double m = (ca * cv - cc * av) / det;
  if (!(std::abs(sc - 1.0) <= kLagScaleTolerance)) {
    // (a scale on every joint at once may as well be the clock's: a time column mapped with 0.01
    // for 0.001 read as a velocity 0.1 x too small; review, session 47)
    lag.note = fmt::format("actual_qd is {:.4g} x the derivative of actual_q (expected 1: a velocity in rad/s of the same joint): a unit or "
                           "scale of the velocity columns, or of the timestamps (the samples are {:.4g} s apart; for the velocity in "
                           "rad/s they would be {:.4g} s apart)? The streamed velocity's lag was not measured, and the velocity is read "
                           "as at its sample's instant",
                           sc, lag.period, lag.period / sc);
    return lag;
  }
  const double l = m / sc;
  // the fit's residual: its standard error
  const double sse = std::max(0.0, vv - 2.0 * (sc * cv - m * av) + sc * sc * cc - 2.0 * sc * m * ca + m * m * aa);
  lag.stderr_s = std::sqrt(sse / std::max(1.0, N - 2.0) * cc / det) / std::abs(sc);
  if (!(std::abs(l) <= TwinModel::kVelocityLagMax)) {
    lag.note = fmt::format("the streamed velocity came out {:.3g} s late against its positions, beyond +-{:g} s (no controller's): read as "
                           "at its sample's instant",
                           l, TwinModel::kVelocityLagMax);
    return lag;
  }
  lag.seconds = l;
  return lag;
}

// estimate_target_direction: the speed below which a joint is near standstill, where its direction
// is read on the target and its tracking error is measured [rad/s]
constexpr double kTargetStandstill = 0.05;
constexpr int kWidthIterations = 20;

// drive_switch_offsets: the windows around a target crossing [s]: the current's level before (from
// -80 to -30 ms) and after (30 to 80 ms), the search for its step (-60 to 60 ms); a step counts when
// it is at least kSwitchClear times the larger spread of the two levels' samples
constexpr double kSwitchLevelFar = 0.08, kSwitchLevelNear = 0.03, kSwitchSearch = 0.06, kSwitchClear = 4.0;
constexpr size_t kSwitchMin = 5;          // crossings with a clear step that measure the timing
constexpr double kSwitchQuantile = 0.9;   // the timing's share the blend's width covers

// Where the drive's switch fell against the target's crossing, at every crossing of joint j's target
// velocity whose current steps clearly (the drive's motoring/back-driven switch under load): the
// time at which the current (a 3-sample mean) passes halfway between its levels before and after,
// less the crossing's time (interpolated) [s]. From the recordings alone: the current itself shows
// the switch the twin has to time.
std::vector<double> drive_switch_offsets(const device::Recording& rec, int j) {
  std::vector<double> out;
  const auto& S = rec.samples;
  const size_t N = S.size();
  for (size_t k = 1; k + 1 < N; ++k) {
    const double v0 = S[k - 1].target_qd[j], v1 = S[k].target_qd[j];
    if (!(v0 * v1 < 0.0)) continue;
    const double tc = S[k - 1].timestamp + (S[k].timestamp - S[k - 1].timestamp) * v0 / (v0 - v1);
    // the window: driven, no gap, inside the recording
    size_t a = k, b = k;
    while (a > 0 && S[a].timestamp > tc - kSwitchLevelFar) --a;
    while (b + 1 < N && S[b].timestamp < tc + kSwitchLevelFar) ++b;
    if (S[a].timestamp > tc - kSwitchLevelFar || S[b].timestamp < tc + kSwitchLevelFar) continue;
    bool clean = true;
    for (size_t m = a; m <= b && clean; ++m) clean = S[m].driven() && (m == a || !S[m].gap_before) && std::isfinite(S[m].current[j]);
    if (!clean) continue;
    double s0 = 0.0, q0 = 0.0, n0 = 0.0, s1 = 0.0, q1 = 0.0, n1 = 0.0;
    for (size_t m = a; m <= b; ++m) {
      const double dt = S[m].timestamp - tc, i = S[m].current[j];
      if (dt <= -kSwitchLevelNear) s0 += i, q0 += i * i, n0 += 1.0;
      if (dt >= kSwitchLevelNear) s1 += i, q1 += i * i, n1 += 1.0;
    }
    if (n0 < 5.0 || n1 < 5.0) continue;
    const double before = s0 / n0, after = s1 / n1, step = after - before;
    const double spread = std::sqrt(std::max({0.0, q0 / n0 - before * before, q1 / n1 - after * after}));
    if (!(std::abs(step) >= kSwitchClear * spread) || !(spread > 0.0)) continue;
    const double mid = 0.5 * (before + after);
    for (size_t m = a + 2; m <= b; ++m) {
      if (S[m].timestamp < tc - kSwitchSearch) continue;
      if (S[m].timestamp > tc + kSwitchSearch) break;
      const double mean = (S[m].current[j] + S[m - 1].current[j] + S[m - 2].current[j]) / 3.0;
      if ((mean - mid) * step >= 0.0) {
        out.push_back(S[m - 1].timestamp - tc);  // (the 3-sample mean is centred on m - 1)
        break;
      }
    }
  }
  return out;
}

TargetDirectionFit estimate_target_direction(const std::vector<const device::Recording*>& recordings) {
  TargetDirectionFit fit;
  if (recordings.empty()) return fit;
  const int n = recordings.front()->n_dof;
  for (const device::Recording* rec : recordings)
    if (!(rec->present & kFieldTargetQd)) {
      fit.note = fmt::format("{} has no target_qd: the drive's direction is read on actual_qd alone", rec->path);
      return fit;
    }
  // per joint: sums over all samples of y = c - target_qd and x = target_qdd (the lead), and the
  // (x, y) of the samples near standstill (the width)
  Eigen::ArrayXd xx = Eigen::ArrayXd::Zero(n), xy = xx, cnt = xx;
  std::vector<std::vector<std::pair<double, double>>> still(static_cast<size_t>(n));
  for (const device::Recording* rp : recordings) {
    const device::Recording& rec = *rp;
    if (rec.n_dof != n || rec.samples.size() < 3) continue;
    const double period = median_step(rec);
    if (!(period > 0.0)) continue;
    const bool acc = (rec.present & kFieldTargetQdd) != 0;
    fit.with_acceleration = fit.with_acceleration && acc;
    for (size_t k = 1; k + 1 < rec.samples.size(); ++k) {
      const RobotSample& s = rec.samples[k];
      if (!central_step(rec, k, period)) continue;
      if (!rec.samples[k - 1].driven() || !s.driven() || !rec.samples[k + 1].driven()) continue;  // (a stopped arm's targets are where it stands)
      for (int j = 0; j < n; ++j) {
        const double x = acc ? s.target_qdd[j] : 0.0;
        const double y = central_velocity(rec, k, j, x) - s.target_qd[j];
        if (!std::isfinite(y) || !std::isfinite(x)) continue;
        xx[j] += x * x, xy[j] += x * y, cnt[j] += 1.0;
        if (std::abs(s.target_qd[j]) < kTargetStandstill) still[static_cast<size_t>(j)].emplace_back(x, y);
      }
    }
  }
  TargetDirection d;
  d.lead = d.width = d.width_time = VectorJ::Zero(n);
  for (int j = 0; j < n; ++j) {
    if (cnt[j] < kLagMinSamples) {
      fit.note = fmt::format("the drive's direction is read on actual_qd alone: J{} has {} samples to compare with its target (expected at "
                             "least {})", j + 1, static_cast<long>(cnt[j]), kLagMinSamples);
      return fit;
    }
    // the lead only where the target accelerates enough to measure it (as the velocity's lag)
    const double lead = xx[j] / cnt[j] >= kLagMinAcceleration * kLagMinAcceleration ? xy[j] / xx[j] : 0.0;
    d.lead[j] = std::clamp(lead, -TwinModel::kVelocityLagMax, TwinModel::kVelocityLagMax);
    const auto& pts = still[static_cast<size_t>(j)];
    if (static_cast<long>(pts.size()) < kLagMinSamples) {
      fit.note = fmt::format("the drive's direction is read on actual_qd alone: J{} is near standstill (|target_qd| < {:g} rad/s) in {} "
                             "samples (expected at least {}), too few to measure how closely it follows its target there",
                             j + 1, kTargetStandstill, pts.size(), kLagMinSamples);
      return fit;
    }
    // e^2 = w^2 + tau^2 x^2 (e = y - lead x) by iteratively reweighted least squares: e^2 of a normal
    // error has variance 2 sigma^4, so each sample is weighted 1 / sigma^4 of the last estimate. (The
    // plain least squares is ruled by the fast reversals' large errors and put J2's w at 2.3 mrad/s
    // where its slow reversals follow within 0.7.)
    const double L = d.lead[j];
    double w2 = 0.0, t2 = 0.0;
    for (int it = 0; it < kWidthIterations; ++it) {
      double sw = 0.0, swz = 0.0, swz2 = 0.0, swe = 0.0, swze = 0.0;
      for (const auto& [x, y] : pts) {
        const double z = x * x, e = y - L * x, e2 = e * e;
        const double sigma2 = it == 0 ? 1.0 : w2 + t2 * z;
        const double wt = 1.0 / (sigma2 * sigma2);
        sw += wt, swz += wt * z, swz2 += wt * z * z, swe += wt * e2, swze += wt * z * e2;
      }
      const double det = sw * swz2 - swz * swz;
      w2 = swe / sw, t2 = 0.0;
      if (det > 1e-12 * sw * swz2) {
        w2 = (swz2 * swe - swz * swze) / det;
        t2 = (sw * swze - swz * swe) / det;
        if (t2 < 0.0) t2 = 0.0, w2 = swe / sw;                            // no growth with the deceleration
        else if (w2 < 0.0) w2 = 0.0, t2 = swz2 > 0.0 ? swze / swz2 : 0.0;  // all of it
      }
      w2 = std::max(w2, TwinModel::kDirectionLeadMin * TwinModel::kDirectionLeadMin);  // (the weights stay finite)
    }
    d.width[j] = std::max(TwinModel::kDirectionLeadMin, std::sqrt(w2));
    d.width_time[j] = std::min(TwinModel::kVelocityLagMax, std::sqrt(t2));
    // The tracking error near standstill times the switch only where the joint follows its target
    // through it. At a reversal a joint also sticks and breaks away (on the virtual UR3e J2 switched
    // up to 20 ms after its target's crossing in the training runs, and 2-8 ms before it at slow
    // loaded reversals), which the error over all the samples near standstill hides among those
    // away from the crossing. Where the current shows the switch, the blend is at least as wide, in
    // time, as the switch's offset from the (lead-carried) crossing at 90 % of the crossings.
    std::vector<double> offsets;
    for (const device::Recording* rp : recordings)
      if (rp->n_dof == n && (rp->present & kFieldActualCurrent))
        for (const double o : drive_switch_offsets(*rp, j)) offsets.push_back(std::abs(o + d.lead[j]));
    if (offsets.size() >= kSwitchMin) {
      const auto at = offsets.begin() + static_cast<long>(std::floor(kSwitchQuantile * static_cast<double>(offsets.size() - 1)));
      std::nth_element(offsets.begin(), at, offsets.end());
      d.width_time[j] = std::min(TwinModel::kVelocityLagMax, std::max(d.width_time[j], *at));
    }
    fit.switches.push_back(static_cast<long>(offsets.size()));
    if (!(d.width[j] <= TwinModel::kTargetDirectionWidthMax)) {
      fit.note = fmt::format("the drive's direction is read on actual_qd alone: J{} is {:.3g} rad/s rms off its target_qd (expected at most {:g}: "
                             "is target_qd that joint's, in rad/s?)", j + 1, d.width[j], TwinModel::kTargetDirectionWidthMax);
      return fit;
    }
    fit.samples += static_cast<long>(cnt[j]);
  }
  fit.direction = d;
  return fit;
}

std::vector<VectorJ> joint_accelerations(const device::Recording& rec, int half_width) {
  std::vector<VectorJ> out;
  out.reserve(rec.samples.size());
  JointAccelerationStream stream(rec.n_dof, rec.present, half_width);
  const JointAccelerationStream::Ready keep = [&](const RobotSample&, const VectorJ& qdd) { out.push_back(qdd); };
  for (const RobotSample& s : rec.samples) stream.push(s, keep);
  stream.finish(keep);
  return out;
}

JointAccelerationStream::JointAccelerationStream(int n_dof, std::uint32_t present, int half_width)
    : n_(n_dof), target_(present & kFieldTargetQdd), has_qd_(present & kFieldActualQd), half_(std::max(1, half_width)) {}

// zero-phase: a centred moving average of qd (half_ each side, cut at the recording's
// ends), then central differences on the time axis (one-sided at the ends)
void JointAccelerationStream::smooth_up_to(size_t end) {
  for (; qs_end_ < end; ++qs_end_) {
    const long k = static_cast<long>(qs_end_);
    VectorJ acc = VectorJ::Zero(n_);
    int cnt = 0;
    for (long m = k - half_; m <= k + half_; ++m) {
      if (m < 0 || m >= static_cast<long>(total_)) continue;
      acc += has_qd_ ? buf_[static_cast<size_t>(m) - base_].qd : VectorJ::Zero(n_);
      ++cnt;
    }
    qs_.push_back(acc / cnt);
  }
}

void JointAccelerationStream::emit(size_t end, const Ready& ready) {
  for (; next_ < end; ++next_) {
    const size_t k = next_, a = k == 0 ? 0 : k - 1, b = std::min(total_ - 1, k + 1);
    const double dt = buf_[b - base_].timestamp - buf_[a - base_].timestamp;
    ready(buf_[k - base_], dt > 0 ? VectorJ((qs_[b - base_] - qs_[a - base_]) / dt) : VectorJ(VectorJ::Zero(n_)));
  }
  // what a later sample still needs: its own sample and the one before (the difference), and the
  // samples a later smoothing window reaches back to
  const size_t keep_from = std::min(next_ == 0 ? 0 : next_ - 1, qs_end_ < static_cast<size_t>(half_) ? 0 : qs_end_ - half_);
  while (base_ < keep_from) {
    buf_.pop_front();
    qs_.pop_front();
    ++base_;
  }
}

void JointAccelerationStream::push(const RobotSample& s, const Ready& ready) {
  if (target_) {
    ready(s, s.target_qdd);
    return;
  }
  buf_.push_back(s);
  ++total_;
  // a sample's smoothed velocity once its window is in; its acceleration once the next one's is
  if (total_ > static_cast<size_t>(half_)) smooth_up_to(total_ - half_);
  if (qs_end_ >= 2) emit(qs_end_ - 1, ready);
}

void JointAccelerationStream::finish(const Ready& ready) {
  if (target_ || total_ == 0) return;
  smooth_up_to(total_);
  emit(total_, ready);
}

TwinModel identify_physics(const std::string& robot, const std::vector<TrainingRun>& given, const IdentOptions& o,
                           IdentReport& report, const std::function<void(double)>& progress) {
  o.validate();
  if (given.empty()) throw InvalidArgument("identify: no recordings given");
  // the torque scale (the drive gains in N·m/A) is fixed by a known payload only where it differs
  // between recordings: one carried in every recording adds the same mass, centre of mass and
  // inertia to the last link in all of them, which the last link's own parameters absorb, and the
  // gains came out arbitrary (audit of session 22: a single recording with its 0.5 kg gave J2-J5
  // gains of 0.95-2.0 N·m/A, 11.4 N·m/A from a pair, marked as identified). Such a payload is fitted
  // as part of the last link: the relative twin predicts the arm carrying it, undeclared
  bool any_payload = false, contrast = false;
  const model::RigidBodyInertia& a = given.front().payload;
  for (const auto& r : given) {
    const model::RigidBodyInertia& b = r.payload;
    any_payload |= b.mass > 0.0;
    contrast |= a.mass != b.mass || (a.mass > 0.0 && (a.com != b.com || a.inertia_com != b.inertia_com));
  }
  std::vector<TrainingRun> runs = given;
  std::string same_payload_note;  // said with the fit's notes (the fit starts its report afresh)
  if (any_payload && !contrast && !o.joint_torque) {
    same_payload_note = (fmt::format(
        "every recording carries the same known payload ({:.2f} kg): to the fit it is part of the last link, so it fixes no "
        "current-to-torque gain; the gains are relative (torque outputs disabled) and the twin predicts the arm with that payload "
        "held (monitor it without --payload-mass); for gains in N·m/A add a recording with another payload, or one with none "
        "(given without --known-payload)",
        given.front().payload.mass));
    for (auto& r : runs) r.payload = model::RigidBodyInertia{};
  }
  // (a joint-torque sensor reads N·m itself: its scale needs no payload)
  const bool scale_known = o.joint_torque || (any_payload && contrast);
  const model::RobotModel rm = model::load_robot(robot);
  const int n = rm.n_dof();
  long total = 0;
  for (const TrainingRun& r : runs) {
    if (r.recording->n_dof != n)
      throw InvalidArgument(fmt::format("{}: {} joints, but robot '{}' has {}", r.recording->path, r.recording->n_dof, robot, n));
    if (!(r.recording->present & kFieldActualCurrent))
      throw InvalidArgument(fmt::format("{}: no {}_* columns: the {} twin needs them", r.recording->path,
                                        o.joint_torque ? "actual_joint_torque" : "actual_current",
                                        o.joint_torque ? "joint-torque" : "current-domain"));
    total += static_cast<long>(r.recording->samples.size());
  }
  if (total < 200) throw InvalidArgument(fmt::format("identify: {} samples in all, expected at least 200", total));
  // the same floor after decimation and the reversal screen, per joint (each has its own friction
  // columns): a fit on 1 sample would show RMSE 0 and be written as a twin
  for (int j = 0; j < n; ++j) {
    long used = 0;
    for (const TrainingRun& r : runs)
      for (size_t k = 0; k < r.recording->samples.size(); k += static_cast<size_t>(o.decimate))
        used += o.reversal_screen > 0.0 && std::abs(r.recording->samples[k].qd[j]) < o.reversal_screen ? 0 : 1;
    if (used < 200)
      throw InvalidArgument(fmt::format("identify: J{} keeps {} of {} samples after decimation by {} and the reversal screen at "
                                        "{} rad/s, expected at least 200",
                                        j + 1, used, total, o.decimate, o.reversal_screen));
  }

  // one pass over the samples: each joint's fastest speed (a joint the recordings never move has
  // nothing to fit: its twin would predict a constant, R² 0, and a monitor would read every later
  // motion of it as a contact of 10^5 N), and the temperature span of the samples the fit uses
  // (joints whose temperature the recordings do not vary enough keep viscous_temperature at 0)
  VectorJ fastest = VectorJ::Zero(n);
  VectorJ t_lo = VectorJ::Constant(n, std::numeric_limits<double>::infinity()), t_hi = -t_lo;
  for (const TrainingRun& r : runs)
    for (size_t k = 0; k < r.recording->samples.size(); ++k) {
      const RobotSample& s = r.recording->samples[k];
      fastest = fastest.cwiseMax(s.qd.cwiseAbs());
      if (k % static_cast<size_t>(o.decimate) != 0 || s.temperature.size() != n) continue;
      for (int j = 0; j < n; ++j) {
        // (a joint's temperature counts where it moves: viscous friction scales with its speed, and a
        // joint that warmed while at rest in one log says nothing of the slope; a Kinova J5 at 29 °C in
        // one log and at rest at 39 °C in another got a slope that made its held-out error 13x)
        if (!std::isfinite(s.temperature[j]) || std::abs(s.qd[j]) < kTemperatureSpanSpeed ||
            (o.reversal_screen > 0.0 && std::abs(s.qd[j]) < o.reversal_screen))
          continue;
        t_lo[j] = std::min(t_lo[j], s.temperature[j]);
        t_hi[j] = std::max(t_hi[j], s.temperature[j]);
      }
    }
  std::vector<bool> fit_temperature(static_cast<size_t>(n), false);
  for (int j = 0; j < n; ++j) {
    if (!(fastest[j] >= kMinJointSpeed))
      throw InvalidArgument(fmt::format("identify: J{} never moves in the recordings (|qd| at most {:.4f} rad/s, expected at least "
                                        "{:g} somewhere): its friction and drive cannot be identified from them; record motion of "
                                        "every joint (e.g. a trajectory from 'twinwatch excite')",
                                        j + 1, fastest[j], kMinJointSpeed));
    fit_temperature[static_cast<size_t>(j)] = t_hi[j] - t_lo[j] >= kMinViscousTemperatureSpan;
  }

  TwinModel twin(robot, rm);
  twin.temperature_ref = o.temperature_ref;
  twin.direction_blend = o.direction_blend;
  if (o.joint_torque) twin.signal = TwinModel::Signal::JointTorque;
  twin.created = now_iso();
  for (const TrainingRun& r : runs) {
    // (a recording cut into its driven stretches is one recording)
    if (std::find(twin.recordings.begin(), twin.recordings.end(), r.recording->path) == twin.recordings.end())
      twin.recordings.push_back(r.recording->path);
    for (const RobotSample& s : r.recording->samples) twin.envelope.include(s.q, s.qd);
  }
  const model::BaseParameters base = model::compute_base_parameters(rm);
  twin.base_columns = base.independent;
  const int nb = base.rank;
  const int nf = kFrictionColumns;
  const int nfx = kFrictionColumns + 2;  // per joint: the friction columns, then pre-sliding and Stribeck
  const int p = nb + nfx * n;  // unknowns of the torque-domain linear step
  twin.beta = Eigen::VectorXd::Zero(nb);
  twin.joints.assign(static_cast<size_t>(n), JointDrive{});
  // Coulomb and viscous friction and the two low-speed levels (pre-sliding, Stribeck: Fs - Fc) of
  // every joint are held >= 0 (fit_bilinear); `held`: the ones the last fit held at 0
  std::vector<int> nonneg, held;
  for (int j = 0; j < n; ++j)
    for (const int c : {int(kCoulomb), int(kViscous), nf, nf + 1}) nonneg.push_back(nb + nfx * j + c);

  std::vector<std::vector<VectorJ>> qdds;
  twin.acceleration_window = o.acceleration_window;
  for (const TrainingRun& r : runs)
    qdds.push_back(joint_accelerations(*r.recording, twin.acceleration_half_width(median_step(*r.recording))));
  // how late the streamed velocity is: the drive's direction is read on the velocity at each
  // sample's instant, in the fit as in the prediction
  VelocityLag lag;  // (the report is reset per stage below: set at the end)
  if (std::isnan(o.velocity_lag)) {
    std::vector<const device::Recording*> recs;
    for (const TrainingRun& r : runs) recs.push_back(r.recording);
    lag = estimate_velocity_lag(recs, qdds);
  } else {
    lag.seconds = o.velocity_lag;
    lag.given = true;
  }
  twin.velocity_lag = lag.seconds;
  // ... and near standstill on the controller's target, where the streamed velocity is 0 for as long
  // as the joint moves less than a count a period (TwinModel::target_direction)
  TargetDirectionFit target_dir;  // (left empty when asked not to: actual_qd alone)
  if (o.target_direction) {
    std::vector<const device::Recording*> recs;
    for (const TrainingRun& r : runs) recs.push_back(r.recording);
    target_dir = estimate_target_direction(recs);
  }
  twin.target_direction = target_dir.direction;
  // the low-speed columns of joint j at sample k of run ri (zero while its shapes are off)
  std::vector<std::vector<VectorJ>> hs;  // pre-sliding state per run and sample (stage 1)
  auto low_speed_row = [&](size_t ri, size_t k, const VectorJ& qd, int j, Eigen::VectorXd& row) {
    const JointDrive& d = twin.joints[static_cast<size_t>(j)];
    const int at = nb + nfx * j + nf;
    const double sg = qd[j] > 0.0 ? 1.0 : (qd[j] < 0.0 ? -1.0 : 0.0);
    row(at) = d.presliding_alpha > 0.0 ? hs[ri][k][j] - sg : 0.0;
    row(at + 1) = stribeck_shape(qd[j], d.stribeck_velocity);
  };
  // A row of joint j is zero outside the base columns and the joint's own friction block, so its
  // outer product is accumulated on the compact row [base; own block] (nb + nfx values instead of
  // p = nb + nfx n: 4x fewer operations on the UR3e, where it was 60 % of the identification time)
  // and scattered into the p x p statistics once per pass.
  const int pc = nb + nfx;
  Eigen::VectorXd rc(pc);
  auto compact = [&](const Eigen::VectorXd& row, int j) -> const Eigen::VectorXd& {
    rc.head(nb) = row.head(nb);
    rc.tail(nfx) = row.segment(nb + nfx * j, nfx);
    return rc;
  };
  auto scatter = [&](const Eigen::MatrixXd& Ac, int j, Eigen::MatrixXd& A) {  // lower triangles
    const int at = nb + nfx * j;
    A.topLeftCorner(nb, nb).triangularView<Eigen::Lower>() += Ac.topLeftCorner(nb, nb);
    A.block(at, 0, nfx, nb) += Ac.block(nb, 0, nfx, nb);
    A.block(at, at, nfx, nfx).triangularView<Eigen::Lower>() += Ac.block(nb, nb, nfx, nfx);
  };
  // Every design row of a pass: fn(run index, sample, joint, row, payload torque of the sample) for
  // every used sample (decimated, reversal-screened) and joint, with the progress report.
  model::RegressorMatrix Y;
  VectorJ tau_p;
  Eigen::VectorXd r(p);
  Eigen::Matrix<double, kFrictionColumns, 1> f;
  // the fit's stages (the loop below); the progress report spans them
  const int stages = o.low_speed_friction ? 2 : 1;
  int stage = 0;
  auto check_gains = [&] {
    for (const auto& jd : twin.joints)
      if (!(jd.gain > 0.0)) throw InvalidArgument("identify: a drive gain came out <= 0; the recordings do not excite that joint enough");
  };
  auto for_each_row = [&](int pass, int passes, auto&& fn) {
    long done = 0;
    for (size_t ri = 0; ri < runs.size(); ++ri) {
      const device::Recording& rec = *runs[ri].recording;
      twin.set_payload(runs[ri].payload);
      for (size_t k = 0; k < rec.samples.size(); k += static_cast<size_t>(o.decimate)) {
        const RobotSample& s = rec.samples[k];
        const VectorJ& qdd = qdds[ri][k];
        twin.regress(s.q, s.qd, qdd, Y, tau_p);
        for (int j = 0; j < n; ++j) {
          if (o.reversal_screen > 0.0 && std::abs(s.qd[j]) < o.reversal_screen) continue;
          r.setZero();
          for (int c = 0; c < nb; ++c) r(c) = Y(j, twin.base_columns[static_cast<size_t>(c)]);
          twin.friction_row(j, s.qd, qdd, s.temperature, f);
          if (!fit_temperature[static_cast<size_t>(j)]) f(kViscousTemperature) = 0.0;
          r.segment(nb + nfx * j, nf) = f;
          low_speed_row(ri, k, s.qd, j, r);
          double v = 0.0;  // (only its sign splits: a direction read with the target, or the measured velocity)
          if (!twin.target_drive_direction(s, qdd, j, v)) v = twin.direction_velocity(s.qd[j], qdd[j]);
          fn(ri, s, j, static_cast<const Eigen::VectorXd&>(r), static_cast<const VectorJ&>(tau_p), v);
        }
        if (progress && (++done % 20000) == 0)
          progress((stage + (pass + static_cast<double>(done) * o.decimate / static_cast<double>(total)) / (passes + 1)) / stages);
      }
    }
  };

  // stage 0: the fit with plain Coulomb friction; stage 1 (low_speed_friction): the low-speed
  // shapes chosen on stage 0's residual, then the whole fit again with their two columns per joint
  // (the Coulomb and offset terms absorb part of the low-speed friction when it is left out, so a
  // fit of the two levels on the residual alone comes out low: 0.56 for 0.70 N·m on a synthetic twin)
  for (stage = 0; stage < stages; ++stage) {
    if (stage == 1) {
      check_gains();
      choose_low_speed_shapes(twin, runs, qdds);
      hs = presliding_states(twin, runs);
      // the second fit starts where the first did (gains and c_gen 1): the first fit's gains of
      // joints the payload does not load can be far off (10^6 N·m/A with the alternating fit), and
      // its start (the torque-domain LS with b / h) would inherit them
      for (JointDrive& jd : twin.joints) jd.gain = jd.c_gen = 1.0;
    }
    Eigen::VectorXd theta = Eigen::VectorXd::Zero(p);
    const int passes = 1 + o.efficiency_passes;
    // the bounds act on the last fit only: the passes before it only set the drive directions and
    // factors it starts from, and on data that determine the friction they are then never reached
    const std::vector<int> no_bounds;
    auto bounds_of = [&](int pass) -> const std::vector<int>& {
      return stage == stages - 1 && pass == passes - 1 ? nonneg : no_bounds;
    };
    report = IdentReport{};
    report.samples_used.assign(static_cast<size_t>(n), 0);
    report.rmse.assign(static_cast<size_t>(n), 0.0);
    report.r2.assign(static_cast<size_t>(n), 0.0);
    if (o.efficiency_fit == EfficiencyFit::Alternating) {
      // the first version: c_gen re-estimated between passes with theta fixed (kept for the
      // monitor's gain fallback, see IdentOptions::efficiency_fit)
      // sufficient statistics of one pass over the data: the linear step in (beta, friction) and the
      // per-joint gain step only need these sums, so the alternating least squares of the bilinear
      // model  g_j i_j / c_jk = r_jk . theta + tau_payload_jk  runs without revisiting the samples
      report.generating_fraction.assign(static_cast<size_t>(n), std::nan(""));
      report.c_gen_identified.assign(static_cast<size_t>(n), true);
      for (int pass = 0; pass <= passes; ++pass) {
        const bool final_stats = pass == passes;
        std::vector<Eigen::MatrixXd> A(static_cast<size_t>(n), Eigen::MatrixXd::Zero(p, p));
        std::vector<Eigen::MatrixXd> Ac(static_cast<size_t>(n), Eigen::MatrixXd::Zero(pc, pc));  // compact, see scatter
        std::vector<Eigen::VectorXd> cp(static_cast<size_t>(n), Eigen::VectorXd::Zero(p));
        std::vector<Eigen::VectorXd> b(static_cast<size_t>(n), Eigen::VectorXd::Zero(p));
        std::vector<double> d(static_cast<size_t>(n), 0.0), e(static_cast<size_t>(n), 0.0), pp(static_cast<size_t>(n), 0.0);
        std::vector<double> gen_num(static_cast<size_t>(n), 0.0), gen_den(static_cast<size_t>(n), 0.0);
        std::vector<double> sse(static_cast<size_t>(n), 0.0), si(static_cast<size_t>(n), 0.0), si2(static_cast<size_t>(n), 0.0);
        std::vector<long> cnt(static_cast<size_t>(n), 0);
        for_each_row(pass, passes, [&](size_t /*ri*/, const RobotSample& s, int j, const Eigen::VectorXd& r, const VectorJ& tau_p, double v) {
          JointDrive& jd = twin.joints[static_cast<size_t>(j)];
          const double i = s.current[j];
          // the previous pass's torque decides the drive direction (first pass: motoring), on the
          // velocity the prediction reads it on (TwinModel::direction_velocity)
          const double tau_hat = r.dot(theta) + tau_p[j];
          const bool gen = pass > 0 && tau_hat * v < 0.0;
          const double c = gen ? jd.c_gen : 1.0;
          if (final_stats) {
            const double err = i - c * tau_hat / jd.gain;
            sse[static_cast<size_t>(j)] += err * err;
            si[static_cast<size_t>(j)] += i;
            si2[static_cast<size_t>(j)] += i * i;
            ++cnt[static_cast<size_t>(j)];
            return;
          }
          if (gen) {
            gen_num[static_cast<size_t>(j)] += i * tau_hat / jd.gain;
            gen_den[static_cast<size_t>(j)] += (tau_hat / jd.gain) * (tau_hat / jd.gain);
          }
          const double w = i / c;  // current as the motoring drive would draw it
          Ac[static_cast<size_t>(j)].selfadjointView<Eigen::Lower>().rankUpdate(compact(r, j));
          b[static_cast<size_t>(j)] += r * w;
          cp[static_cast<size_t>(j)] += r * tau_p[j];
          d[static_cast<size_t>(j)] += w * tau_p[j];
          e[static_cast<size_t>(j)] += w * w;
          pp[static_cast<size_t>(j)] += tau_p[j] * tau_p[j];
        });
        if (final_stats) {
          for (int j = 0; j < n; ++j) {
            auto& m = twin.joints[static_cast<size_t>(j)];
            const double N = std::max<double>(1.0, static_cast<double>(cnt[static_cast<size_t>(j)]));
            m.rmse = std::sqrt(sse[static_cast<size_t>(j)] / N);
            const double sst = si2[static_cast<size_t>(j)] - si[static_cast<size_t>(j)] * si[static_cast<size_t>(j)] / N;
            m.r2 = sst > 0 ? 1.0 - sse[static_cast<size_t>(j)] / sst : 0.0;
            report.rmse[static_cast<size_t>(j)] = m.rmse;
            report.r2[static_cast<size_t>(j)] = m.r2;
            report.samples_used[static_cast<size_t>(j)] = cnt[static_cast<size_t>(j)];
          }
          break;
        }
        // update the back-driven factor from this pass's directions
        for (int j = 0; j < n; ++j)
          if (pass > 0 && gen_den[static_cast<size_t>(j)] > 0)
            twin.joints[static_cast<size_t>(j)].c_gen = gen_num[static_cast<size_t>(j)] / gen_den[static_cast<size_t>(j)];
        // Levenberg-Marquardt on the bilinear current-domain model, entirely on the sufficient
        // statistics: unknowns x = (theta, h_j = 1 / g_j), residual w_jk - h_j (r_jk theta + tau_p_jk)
        for (int j = 0; j < n; ++j) {
          scatter(Ac[static_cast<size_t>(j)], j, A[static_cast<size_t>(j)]);
          A[static_cast<size_t>(j)] = A[static_cast<size_t>(j)].selfadjointView<Eigen::Lower>();
        }
        std::vector<double> h(static_cast<size_t>(n));
        for (int j = 0; j < n; ++j) h[static_cast<size_t>(j)] = 1.0 / twin.joints[static_cast<size_t>(j)].gain;
        if (pass == 0) {
          // start: theta from the torque-domain LS with the initial gains
          Eigen::MatrixXd Aw = Eigen::MatrixXd::Zero(p, p);
          Eigen::VectorXd rhs = Eigen::VectorXd::Zero(p);
          for (int j = 0; j < n; ++j) {
            Aw += A[static_cast<size_t>(j)];
            rhs += b[static_cast<size_t>(j)] / h[static_cast<size_t>(j)] - cp[static_cast<size_t>(j)];
          }
          const Eigen::VectorXd D = Aw.diagonal().cwiseMax(1e-300).cwiseSqrt();
          Eigen::MatrixXd As = D.asDiagonal().inverse() * Aw * D.asDiagonal().inverse();
          As.diagonal().array() += kRidge;
          theta = D.asDiagonal().inverse() * As.ldlt().solve(D.asDiagonal().inverse() * rhs);
        }
        // the joint fit's Levenberg-Marquardt with only the motoring groups (c_gen folded into w)
        std::vector<Stats> st(static_cast<size_t>(2 * n));
        std::vector<double> hg(static_cast<size_t>(2 * n), 1.0);
        for (int j = 0; j < n; ++j) {
          const size_t J = static_cast<size_t>(j);
          st[2 * J] = Stats{std::move(A[J]), std::move(cp[J]), std::move(b[J]), d[J], e[J], pp[J], cnt[J]};
          st[2 * J + 1] = Stats{Eigen::MatrixXd::Zero(p, p), Eigen::VectorXd::Zero(p), Eigen::VectorXd::Zero(p), 0.0, 0.0, 0.0, 0};
          hg[2 * J] = h[J];
        }
        held = fit_bilinear(st, std::vector<bool>(static_cast<size_t>(n), false), scale_known, false, theta, hg, bounds_of(pass));
        for (int j = 0; j < n; ++j) h[static_cast<size_t>(j)] = hg[static_cast<size_t>(2 * j)];
        std::vector<double> g(static_cast<size_t>(n));
        for (int j = 0; j < n; ++j) g[static_cast<size_t>(j)] = 1.0 / h[static_cast<size_t>(j)];
        for (int j = 0; j < n; ++j) twin.joints[static_cast<size_t>(j)].gain = g[static_cast<size_t>(j)];
        twin.beta = theta.head(nb);
        for (int j = 0; j < n; ++j) {
          JointDrive& jd = twin.joints[static_cast<size_t>(j)];
          jd.friction = theta.segment(nb + nfx * j, nf);
          jd.presliding = jd.presliding_alpha > 0.0 ? theta(nb + nfx * j + nf) : 0.0;
          jd.stribeck = jd.stribeck_velocity > 0.0 ? theta(nb + nfx * j + nf + 1) : 0.0;
        }
      }
    } else {
      // sufficient statistics of one pass over the data, per joint and per drive direction (group 0
      // motoring, group 1 back-driven): the bilinear current-domain model
      //   i_jk = h_jg (r_jk . theta + tau_payload_jk),  h_j0 = 1 / g_j,  h_j1 = c_gen_j / g_j
      // is fitted jointly in (theta, h) by Levenberg-Marquardt on these sums, without revisiting the
      // samples. Fitting c_gen jointly matters: with theta fixed, a wrong c_gen is almost compensated
      // by the Coulomb and gravity terms (i_down / i_up = c (G - Fc) / (G + Fc)), so alternating
      // between the two (the first version) crawled from 1 towards the truth by a few % per pass.
      report.generating_fraction.assign(static_cast<size_t>(n), 0.0);
      report.c_gen_identified.assign(static_cast<size_t>(n), false);
      report.payload_current_rms.assign(static_cast<size_t>(n), 0.0);
      for (int pass = 0; pass <= passes; ++pass) {
        const bool final_stats = pass == passes;
        std::vector<Stats> st(static_cast<size_t>(2 * n));
        std::vector<Eigen::MatrixXd> stc(static_cast<size_t>(2 * n), Eigen::MatrixXd::Zero(pc, pc));  // compact A per group
        for (Stats& x : st) {
          x.A = Eigen::MatrixXd::Zero(p, p);
          x.cp = Eigen::VectorXd::Zero(p);
          x.b = Eigen::VectorXd::Zero(p);
        }
        std::vector<double> sse(static_cast<size_t>(n), 0.0), si(static_cast<size_t>(n), 0.0), si2(static_cast<size_t>(n), 0.0);
        std::vector<long> cnt(static_cast<size_t>(n), 0), gen_cnt(static_cast<size_t>(n), 0);
        std::vector<double> pay2(static_cast<size_t>(n), 0.0);  // sum (tau_payload / g)^2 over runs with a known payload
        std::vector<long> pay_cnt(static_cast<size_t>(n), 0);
        for_each_row(pass, passes, [&](size_t ri, const RobotSample& s, int j, const Eigen::VectorXd& r, const VectorJ& tau_p, double v) {
          const JointDrive& jd = twin.joints[static_cast<size_t>(j)];
          const double i = s.current[j];
          // the previous pass's torque decides the drive direction (first pass: all motoring);
          // back-driven when the motor's power tau qd is negative (UR3e eq. 3; qd as the prediction
          // reads it, TwinModel::direction_velocity)
          const double tau_hat = r.dot(theta) + tau_p[j];
          const bool gen = pass > 0 && tau_hat * v < 0.0;
          gen_cnt[static_cast<size_t>(j)] += gen ? 1 : 0;
          if (final_stats) {
            const double err = i - (gen ? jd.c_gen : 1.0) * tau_hat / jd.gain;
            sse[static_cast<size_t>(j)] += err * err;
            si[static_cast<size_t>(j)] += i;
            si2[static_cast<size_t>(j)] += i * i;
            ++cnt[static_cast<size_t>(j)];
            if (runs[ri].payload.mass > 0.0) {
              pay2[static_cast<size_t>(j)] += (tau_p[j] / jd.gain) * (tau_p[j] / jd.gain);
              ++pay_cnt[static_cast<size_t>(j)];
            }
            return;
          }
          Stats& x = st[static_cast<size_t>(2 * j + (gen ? 1 : 0))];
          stc[static_cast<size_t>(2 * j + (gen ? 1 : 0))].selfadjointView<Eigen::Lower>().rankUpdate(compact(r, j));
          x.b += r * i;
          x.cp += r * tau_p[j];
          x.d += i * tau_p[j];
          x.e += i * i;
          x.pp += tau_p[j] * tau_p[j];
          ++x.count;
        });
        if (final_stats) {
          for (int j = 0; j < n; ++j) {
            const size_t J = static_cast<size_t>(j);
            auto& m = twin.joints[J];
            const double N = std::max<double>(1.0, static_cast<double>(cnt[J]));
            m.rmse = std::sqrt(sse[J] / N);
            const double sst = si2[J] - si[J] * si[J] / N;
            m.r2 = sst > 0 ? 1.0 - sse[J] / sst : 0.0;
            report.rmse[J] = m.rmse;
            report.r2[J] = m.r2;
            report.samples_used[J] = cnt[J];
            report.generating_fraction[J] = static_cast<double>(gen_cnt[J]) / N;
            // the gain is fixed by the known payload only where the payload's current stands out
            // of what the model leaves unexplained
            report.payload_current_rms[J] = pay_cnt[J] > 0 ? std::sqrt(pay2[J] / static_cast<double>(pay_cnt[J])) : 0.0;
            m.gain_identified = o.joint_torque || (scale_known && report.payload_current_rms[J] >= kPayloadSignalMin * m.rmse);
            if (scale_known && !m.gain_identified)
              report.notes.push_back(fmt::format("J{}: the known payload's current on this joint (rms {:.4f} A) is below {} x the fit RMSE "
                                                 "({:.4f} A): its gain {:.3f} N·m/A is not identified (gain_identified false in the twin)",
                                                 j + 1, report.payload_current_rms[J], kPayloadSignalMin, m.rmse, m.gain));
          }
          break;
        }
        for (int g = 0; g < 2 * n; ++g) {
          Stats& x = st[static_cast<size_t>(g)];
          scatter(stc[static_cast<size_t>(g)], g / 2, x.A);
          x.A = x.A.selfadjointView<Eigen::Lower>();
        }
        // which joints' back-driven factor the data can carry: enough back-driven samples; the others
        // keep c_gen = 1 and their back-driven samples join the motoring group
        std::vector<bool> free_gen(static_cast<size_t>(n), false);
        for (int j = 0; j < n; ++j) {
          const Stats& g1 = st[static_cast<size_t>(2 * j + 1)];
          const long all = g1.count + st[static_cast<size_t>(2 * j)].count;
          free_gen[static_cast<size_t>(j)] =
              !o.joint_torque && pass > 0 && g1.count >= kMinGeneratingSamples && g1.count >= kMinGeneratingFraction * static_cast<double>(all);
        }
        // a fixed factor c folds the back-driven group into the motoring one:
        // sum (i - c h t)^2 has the statistics (A c², cp c², b c, d c, e, pp c²)
        auto fold = [&](int j, double c) {
          Stats& g0 = st[static_cast<size_t>(2 * j)];
          Stats& g1 = st[static_cast<size_t>(2 * j + 1)];
          g0.A += c * c * g1.A;
          g0.cp += c * c * g1.cp;
          g0.b += c * g1.b;
          g0.d += c * g1.d;
          g0.e += g1.e;
          g0.pp += c * c * g1.pp;
          g0.count += g1.count;
          g1 = Stats{Eigen::MatrixXd::Zero(p, p), Eigen::VectorXd::Zero(p), Eigen::VectorXd::Zero(p), 0.0, 0.0, 0.0, 0};
        };
        // h per group: h[2j] = 1 / g_j, h[2j + 1] = c_gen_j / g_j
        std::vector<double> h(static_cast<size_t>(2 * n));
        for (int j = 0; j < n; ++j) {
          h[static_cast<size_t>(2 * j)] = 1.0 / twin.joints[static_cast<size_t>(j)].gain;
          h[static_cast<size_t>(2 * j + 1)] = twin.joints[static_cast<size_t>(j)].c_gen * h[static_cast<size_t>(2 * j)];
        }
        if (pass == 0) {
          // start: theta from the torque-domain LS with the initial gains
          Eigen::MatrixXd Aw = Eigen::MatrixXd::Zero(p, p);
          Eigen::VectorXd rhs = Eigen::VectorXd::Zero(p);
          for (int j = 0; j < n; ++j) {
            const Stats& g0 = st[static_cast<size_t>(2 * j)];
            Aw += g0.A;
            rhs += g0.b / h[static_cast<size_t>(2 * j)] - g0.cp;
          }
          const Eigen::VectorXd D = Aw.diagonal().cwiseMax(1e-300).cwiseSqrt();
          Eigen::MatrixXd As = D.asDiagonal().inverse() * Aw * D.asDiagonal().inverse();
          As.diagonal().array() += kRidge;
          theta = D.asDiagonal().inverse() * As.ldlt().solve(D.asDiagonal().inverse() * rhs);
        }
        for (int j = 0; j < n; ++j)
          if (!free_gen[static_cast<size_t>(j)]) fold(j, twin.joints[static_cast<size_t>(j)].c_gen);
        // the fit, then the physical range of c_gen: a factor outside it is pinned to the bound and
        // the joint fitted again with it
        for (int attempt = 0; attempt < 2; ++attempt) {
          held = fit_bilinear(st, free_gen, scale_known, o.joint_torque, theta, h, bounds_of(pass));
          bool refit = false;
          for (int j = 0; j < n; ++j) {
            const size_t J = static_cast<size_t>(j);
            if (!free_gen[J]) continue;
            const double c = h[2 * J + 1] / h[2 * J];
            const double cb = std::clamp(c, kCGenMin, kCGenMax);
            if (cb != c) {
              if (pass == passes - 1)
                report.notes.push_back(fmt::format("J{}: back-driven factor fitted {:.3f}, outside [{}, {}]: pinned to {}", j + 1, c,
                                                   kCGenMin, kCGenMax, cb));
              free_gen[J] = false;
              fold(j, cb);
              twin.joints[J].c_gen = cb;
              refit = true;
            }
          }
          if (!refit) break;
        }
        for (int j = 0; j < n; ++j) {
          const size_t J = static_cast<size_t>(j);
          twin.joints[J].gain = 1.0 / h[2 * J];
          if (free_gen[J]) twin.joints[J].c_gen = h[2 * J + 1] / h[2 * J];
          report.c_gen_identified[J] = free_gen[J];
        }
        twin.beta = theta.head(nb);
        for (int j = 0; j < n; ++j) {
          JointDrive& jd = twin.joints[static_cast<size_t>(j)];
          jd.friction = theta.segment(nb + nfx * j, nf);
          jd.presliding = jd.presliding_alpha > 0.0 ? theta(nb + nfx * j + nf) : 0.0;
          jd.stribeck = jd.stribeck_velocity > 0.0 ? theta(nb + nfx * j + nf + 1) : 0.0;
        }
      }
    }
  }
  report.velocity_lag = lag;
  if (!lag.note.empty()) report.notes.push_back(lag.note);
  report.target_direction = target_dir;
  if (!target_dir.note.empty()) report.notes.push_back(target_dir.note);
  for (int j = 0; j < n && o.efficiency_fit == EfficiencyFit::Joint && !o.joint_torque; ++j)
    if (!report.c_gen_identified[static_cast<size_t>(j)] && report.generating_fraction[static_cast<size_t>(j)] < kMinGeneratingFraction)
      report.notes.push_back(fmt::format("J{}: {:.1f} % of the samples back-driven, too few to fit c_gen (kept at {:.3f})", j + 1,
                                         100.0 * report.generating_fraction[static_cast<size_t>(j)], twin.joints[static_cast<size_t>(j)].c_gen));
  std::vector<std::string> held_at_zero;  // (a joint-torque twin's, said in one note)
  for (int i : held) {
    const int j = (i - nb) / nfx, c = (i - nb) % nfx;
    // a low-speed level held at 0 is no term: its shape goes too (the note below says why)
    JointDrive& jd = twin.joints[static_cast<size_t>(j)];
    if (c == nf) jd.presliding_alpha = 0.0;
    if (c == nf + 1) jd.stribeck_velocity = 0.0;
    const char* what = c == kCoulomb ? "Coulomb friction" : c == kViscous ? "viscous friction" : c == nf ? "pre-sliding friction level" : "Stribeck level";
    if (o.joint_torque) {
      // a sensor behind the gear reads next to no gear friction: a level at 0 is what it should find,
      // not recordings that fail to determine it
      held_at_zero.push_back(fmt::format("J{} {}", j + 1, what));
      continue;
    }
    report.notes.push_back(fmt::format(
        "J{}: {} held at 0: the fit would make it negative (friction pushing the motion along), so the recordings do not "
        "determine it (e.g. the joint moves one way only, or too little); record motion in both directions ('twinwatch excite') "
        "and check the joint with 'twinwatch validate'",
        j + 1, what));
  }
  if (!held_at_zero.empty())
    report.notes.push_back(fmt::format("friction levels at 0 ({}): joint torque sensors behind the gear read next to no gear friction, "
                                       "so these are expected",
                                       fmt::join(held_at_zero, ", ")));
  {
    // one note per temperature span (usually one for every joint; none for a joint-torque twin, whose
    // sensors read no gear friction to vary with temperature)
    std::vector<std::pair<std::string, std::vector<std::string>>> unfitted;  // span text -> joints
    for (int j = 0; j < n; ++j) {
      if (fit_temperature[static_cast<size_t>(j)]) continue;
      twin.joints[static_cast<size_t>(j)].friction(kViscousTemperature) = 0.0;
      const double span = t_hi[j] - t_lo[j];
      const std::string what = std::isfinite(span) ? fmt::format("spans {:.1f} °C", span) : std::string("is not recorded");
      auto it = std::find_if(unfitted.begin(), unfitted.end(), [&](const auto& u) { return u.first == what; });
      if (it == unfitted.end()) it = unfitted.insert(unfitted.end(), {what, {}});
      it->second.push_back(fmt::format("J{}", j + 1));
    }
    if (!o.joint_torque)
      for (const auto& [what, joints] : unfitted)
        report.notes.push_back(fmt::format(
            "{}: viscous friction against temperature not fitted (kept at 0): the recordings' temperature {}, expected a span "
            ">= {:.0f} °C; record a warm-up from cold to fit it, or let the monitor's trend learn it "
            "('twinwatch thresholds --twin TWIN COLD.csv WARM.csv')",
            fmt::join(joints, ", "), what, kMinViscousTemperatureSpan));
  }
  // a payload whose current shows on no joint fixes no gain either (recordings declared without a
  // payload that carry one: the gains came out 430-3660 N·m/A, and the monitor, finding none it
  // could trust, used 1 N·m/A and printed N·m)
  const bool any_identified = std::any_of(twin.joints.begin(), twin.joints.end(), [](const JointDrive& d) { return d.gain_identified; });
  if (scale_known && !any_identified)
    report.notes.push_back("the known payload's current stands out on no joint, so no gain is identified and the gains are relative "
                           "(torque outputs disabled): check that the recordings given without --known-payload carry no payload, and "
                           "that the declared masses are right");
  twin.gains_absolute = scale_known && any_identified;
  check_gains();
  for (int j = 0; j < n && o.low_speed_friction; ++j) {
    const JointDrive& d = twin.joints[static_cast<size_t>(j)];
    // levels in the joint's torque scale: N·m only where the known payload fixed its gain
    const char* units = twin.gains_absolute && d.gain_identified ? "N·m" : "(relative torque units: gain not identified)";
    report.notes.push_back(fmt::format(
        "J{}: low-speed friction: pre-sliding {}, Stribeck {}", j + 1,
        d.presliding_alpha > 0.0 ? fmt::format("{:.3f} {} over {:.2f} mrad", d.presliding, units, 1000.0 / d.presliding_alpha) : std::string("none"),
        d.stribeck_velocity > 0.0 ? fmt::format("{:+.3f} {} below {:.3f} rad/s", d.stribeck, units, d.stribeck_velocity) : std::string("none")));
  }
  if (!same_payload_note.empty()) report.notes.push_back(same_payload_note);
  if (!any_payload && !o.joint_torque)
    report.notes.push_back("no recording with a known payload: current-to-torque gains are relative (torque outputs disabled); "
                           "add one with --known-payload FILE=MASS,CX,CY,CZ");
  twin.set_payload(model::RigidBodyInertia{});
  if (progress) progress(1.0);
  return twin;
}

}  // namespace twinwatch::ident
