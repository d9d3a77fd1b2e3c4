#include "twinwatch/ident/excitation.hpp"

#include <fmt/format.h>
#include <nlopt.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>

#include "twinwatch/core/error.hpp"
#include "twinwatch/model/dynamics.hpp"

namespace twinwatch::ident {

namespace {

// cond(W) reported for a rank-deficient W (a candidate that does not excite some parameter)
constexpr double kCondInfinite = 1e16;
// the dense-grid rescale aims this far inside the limit, so round-off cannot land on the wrong side
constexpr double kRescaleSafety = 1e-9;
// passes of the whole-trajectory rescale onto the Cartesian limits on the dense grid (each leaves
// a fraction of the last excess: the pose moves little as the trajectory shrinks)
constexpr int kSpeedPasses = 20;
// ... aimed this far inside the limits: a program sampled between the dense grid's points (urscript
// samples every 2 ms, the dense grid a period / check_samples) sees at most ~ (2 pi L / check_samples)^2 / 8
// more (3e-4 for L = 20 harmonics), so the design it refuses is not the one excite wrote
constexpr double kSpeedSafety = 1e-3;
// NLopt stops a step when the relative change of log cond(W) falls below this
constexpr double kFtolRel = 1e-6;

// the height constraint (ExcitationOptions::min_height) is a penalty on the design grid: a design
// below it scores above any design that keeps it (log cond(W) <= log kCondInfinite ~ 37), and the
// further below the worse (one unit per cm), so that the derivative-free search is led up and out.
// It is held kHeightMargin above the asked height, for what happens between grid points.
constexpr double kHeightPenalty = 40.0;
constexpr double kHeightScale = 0.01;  // [m]
constexpr double kHeightMargin = 0.01;  // [m]

// excitation_raised_centre: the weight of the bodies' mean height next to the lowest one's, and the
// search's budget (a 6-joint pose settles in a few hundred evaluations)
constexpr double kCentreTieBreak = 0.1;
// ... and a pull back to the middle of the ranges [m/rad²]: joints that do not change the height
// stay there, and a UR's upper arm stands up at -pi/2, not at the equivalent 3 pi/2
constexpr double kCentreStay = 0.002;
// the search's first step [rad] (NLopt's default, a fraction of a 4 pi range, jumps to far poses)
constexpr double kCentreStep = 0.2;
constexpr int kCentreEvaluations = 3000;

// heights of the body origins after the first (the first turns about the base's own axis), the
// flange and the tool points (flange frame), at the configuration forward_kinematics last computed
// into d: the lowest (z [m], body: 1..n_dof-1 the origin of that body, n_dof the flange, n_dof+1+k
// tool point k) and the mean of the bodies and the flange [m] (the raised centre's tie-break; a tool
// point is a constraint, not a reason to stand the arm up)
struct BodyHeights {
  double lowest = std::numeric_limits<double>::infinity();
  int body = -1;
  double mean = 0.0;
};
BodyHeights body_heights(const model::RobotModel& m, const model::DynamicsData& d, const std::vector<Eigen::Vector3d>& tool) {
  BodyHeights h;
  for (int b = 1; b <= m.n_dof(); ++b) {
    const double z = b < m.n_dof() ? d.oMi[static_cast<size_t>(b)].translation().z() : d.oMf.translation().z();
    if (z < h.lowest) h.lowest = z, h.body = b;
    h.mean += z;
  }
  h.mean /= m.n_dof();
  for (size_t k = 0; k < tool.size(); ++k)
    if (const double z = (d.oMf * tool[k]).z(); z < h.lowest) h.lowest = z, h.body = m.n_dof() + 1 + static_cast<int>(k);
  return h;
}

// a tool point farther than this from the flange [m] is a typing error (a value in mm), not a tool
constexpr double kToolPointMax = 2.0;

void validate_tool_points(const std::vector<Eigen::Vector3d>& tool) {
  for (size_t k = 0; k < tool.size(); ++k) {
    const Eigen::Vector3d& p = tool[k];
    if (!p.allFinite())
      throw InvalidArgument(fmt::format("tool_points[{}] is ({}, {}, {}), must be finite [m]", k, p.x(), p.y(), p.z()));
    if (p.norm() > kToolPointMax)
      throw InvalidArgument(fmt::format("tool_points[{}] is ({:g}, {:g}, {:g}) m, {:.3g} m from the flange: expected at most {:g} m "
                                        "(a value in mm?)",
                                        k, p.x(), p.y(), p.z(), p.norm(), kToolPointMax));
  }
}

// free coefficients per joint: a_2..a_L and b_3..b_L
int free_per_joint(int L) { return 2 * L - 3; }

// the per-joint limits the design enforces
struct Limits {
  VectorJ lo, hi, vl, al;  // position deviation bounds (lo < 0 < hi) [rad], |qd| [rad/s], |qdd| [rad/s²]
};

Limits make_limits(const model::RobotModel& m, const ExcitationOptions& o, const VectorJ& q0) {
  const int n = m.n_dof();
  Limits L;
  L.lo.resize(n), L.hi.resize(n), L.vl.resize(n), L.al.resize(n);
  for (int j = 0; j < n; ++j) {
    const model::JointLimits& jl = m.joint(j).limits;
    // position: inside [q_min + margin, q_max - margin] (shrunk by limit_fraction about q0) and q0 +- amplitude
    const double up = std::isfinite(jl.q_max) ? o.limit_fraction * (jl.q_max - o.position_margin - q0[j]) : o.amplitude;
    const double dn = std::isfinite(jl.q_min) ? o.limit_fraction * (jl.q_min + o.position_margin - q0[j]) : -o.amplitude;
    L.hi[j] = std::min(o.amplitude, up);
    L.lo[j] = std::max(-o.amplitude, dn);
    if (!(L.hi[j] > 0.0) || !(L.lo[j] < 0.0))
      throw InvalidArgument(fmt::format("q0[{}] = {} leaves no room inside joint {}'s limits [{}, {}] with a margin of {} rad",
                                        j, q0[j], j + 1, jl.q_min, jl.q_max, o.position_margin));
    L.vl[j] = o.limit_fraction * (std::isfinite(jl.qd_max) ? jl.qd_max : 1.0);
    L.al[j] = o.limit_fraction * (std::isfinite(jl.qdd_max) ? jl.qdd_max : o.default_qdd_max);
  }
  return L;
}

// the trajectory evaluator on a fixed time grid, with the boundary-condition elimination
class Design {
 public:
  Design(const model::RobotModel& m, const ExcitationOptions& o, const VectorJ& q0, Limits lim)
      : m_(m), o_(o), n_(m.n_dof()), L_(o.harmonics), lim_(std::move(lim)), d_(m) {
    w_ = 2.0 * M_PI * o.base_frequency;
    traj_.w_f = w_;
    traj_.q0 = q0;
    traj_.a.setZero(n_, L_);
    traj_.b.setZero(n_, L_);
    base_ = model::compute_base_parameters(m, o.friction);
    grid(o.samples, S_, C_);
    // variable scale per harmonic: the largest coefficient one harmonic alone may carry
    scale_.resize(n_, L_);
    for (int j = 0; j < n_; ++j)
      for (int k = 1; k <= L_; ++k)
        scale_(j, k - 1) = std::min({lim_.vl[j], lim_.al[j] / (k * w_), std::min(lim_.hi[j], -lim_.lo[j]) * k * w_});
  }

  int n_vars() const { return n_ * free_per_joint(L_); }
  int columns() const { return base_.rank; }
  const Limits& limits() const { return lim_; }

  // x in [-1, 1]^n_vars -> coefficients satisfying the end conditions
  void coefficients(const double* x, ExcitationTrajectory& t) const {
    const int F = free_per_joint(L_);
    for (int j = 0; j < n_; ++j) {
      const double* xj = x + j * F;
      // free coefficients
      for (int k = 2; k <= L_; ++k) t.a(j, k - 1) = xj[k - 2] * scale_(j, k - 1);
      for (int k = 3; k <= L_; ++k) t.b(j, k - 1) = xj[(L_ - 1) + (k - 3)] * scale_(j, k - 1);
      // qd(0) = 0:                sum_k a_k = 0
      double sa = 0.0;
      for (int k = 2; k <= L_; ++k) sa += t.a(j, k - 1);
      t.a(j, 0) = -sa;
      // qdd(0) = 0 and q(0) = q0: sum_k k b_k = 0, sum_k b_k / k = 0  ->  solve for b_1, b_2
      double s1 = 0.0, s2 = 0.0;
      for (int k = 3; k <= L_; ++k) s1 += k * t.b(j, k - 1), s2 += t.b(j, k - 1) / k;
      t.b(j, 1) = 2.0 / 3.0 * (s2 - s1);
      t.b(j, 0) = -s2 - 0.5 * t.b(j, 1);
    }
  }

  // per joint: largest ratio of |deviation|, |qd|, |qdd| to its limit on a grid
  VectorJ ratios(const ExcitationTrajectory& t, const Eigen::MatrixXd& S, const Eigen::MatrixXd& C) const {
    VectorJ r = VectorJ::Zero(n_);
    for (Eigen::Index m = 0; m < S.rows(); ++m)
      for (int j = 0; j < n_; ++j) {
        double dq = 0.0, v = 0.0, acc = 0.0;
        for (int k = 1; k <= L_; ++k) {
          const double a = t.a(j, k - 1), b = t.b(j, k - 1), s = S(m, k - 1), c = C(m, k - 1), kw = k * w_;
          dq += (a * s - b * c) / kw;
          v += a * c + b * s;
          acc += kw * (b * c - a * s);
        }
        const double rp = dq >= 0.0 ? dq / lim_.hi[j] : dq / lim_.lo[j];
        r[j] = std::max({r[j], rp, std::abs(v) / lim_.vl[j], std::abs(acc) / lim_.al[j]});
      }
    return r;
  }

  // scales joints that exceed a limit on the grid back onto it (keeps the end conditions)
  void project(ExcitationTrajectory& t, const Eigen::MatrixXd& S, const Eigen::MatrixXd& C, double safety) const {
    const VectorJ r = ratios(t, S, C);
    for (int j = 0; j < n_; ++j)
      if (r[j] > 1.0) {
        const double s = (1.0 - safety) / r[j];
        t.a.row(j) *= s;
        t.b.row(j) *= s;
      }
  }

  // cond(W) from the eigenvalues of W^T W (cheap; the final value is recomputed by SVD)
  double cond_fast(const ExcitationTrajectory& t) {
    build_W(t, W_);
    const Eigen::MatrixXd G = W_.transpose() * W_;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(G, Eigen::EigenvaluesOnly);
    const double lmin = es.eigenvalues()(0), lmax = es.eigenvalues()(G.rows() - 1);
    if (!(lmin > lmax / (kCondInfinite * kCondInfinite)) || !(lmax > 0.0)) return kCondInfinite;
    return std::sqrt(lmax / lmin);
  }

  // the largest ratio of the Cartesian figures (tool, elbow speed, momentum) to their limits on a grid
  // (0 when none is limited), and the peaks
  double speed_ratio(const ExcitationTrajectory& t, const Eigen::MatrixXd& S, const Eigen::MatrixXd& C, model::CartesianSpeeds* peak = nullptr) {
    if (!limits_speeds() && !peak) return 0.0;
    double r = 0.0;
    VectorJ q(n_), qd(n_), qdd(n_);
    for (Eigen::Index m = 0; m < S.rows(); ++m) {
      state(t, S, C, m, q, qd, qdd);
      const model::CartesianSpeeds c = model::cartesian_speeds(m_, d_, q, qd, o_.tool_points, o_.carried);
      r = std::max({r, c.tool / o_.tool_speed_max, n_ >= 3 ? c.elbow / o_.elbow_speed_max : 0.0, c.momentum / o_.momentum_max});
      if (peak) {
        if (c.tool > peak->tool) peak->tool = c.tool, peak->tool_point = c.tool_point;
        peak->elbow = n_ >= 3 ? std::max(peak->elbow, c.elbow) : c.elbow;  // (NaN: no elbow)
        peak->momentum = std::max(peak->momentum, c.momentum);
      }
    }
    return r;
  }
  bool limits_speeds() const {
    return std::isfinite(o_.tool_speed_max) || std::isfinite(o_.elbow_speed_max) || std::isfinite(o_.momentum_max);
  }
  // scales the whole trajectory (every joint alike, so the path's shape is kept) until the Cartesian
  // figures keep their limits on the grid. They are linear in qd at a fixed pose; the pose moves
  // towards q0 as the trajectory shrinks, so the ratio is taken again (a few passes, each within a
  // fraction of the last). Scaling down keeps the joint limits, which are homogeneous about q0.
  void project_speeds(ExcitationTrajectory& t, const Eigen::MatrixXd& S, const Eigen::MatrixXd& C, double safety, int passes) {
    if (!limits_speeds()) return;
    for (int p = 0; p < passes; ++p) {
      const double r = speed_ratio(t, S, C);
      if (r <= 1.0 - safety) return;
      const double s = (1.0 - 2.0 * safety) / r;
      t.a *= s;
      t.b *= s;
    }
  }

  double objective(const double* x) {
    coefficients(x, traj_);
    project(traj_, S_, C_, 0.0);
    project_speeds(traj_, S_, C_, 0.0, 1);
    ++evaluations;
    double f = std::log(cond_fast(traj_));
    if (std::isfinite(o_.min_height)) {
      const double below = o_.min_height + kHeightMargin - lowest_on_grid(traj_);
      if (below > 0.0) f += kHeightPenalty + below / kHeightScale;
    }
    return f;
  }

  // q, qd, qdd at point m of the design grid
  void grid_state(const ExcitationTrajectory& t, Eigen::Index m, VectorJ& q, VectorJ& qd, VectorJ& qdd) const {
    state(t, S_, C_, m, q, qd, qdd);
  }
  // ... and of any grid (S, C from grid())
  void state(const ExcitationTrajectory& t, const Eigen::MatrixXd& S, const Eigen::MatrixXd& C, Eigen::Index m, VectorJ& q, VectorJ& qd,
             VectorJ& qdd) const {
    q = t.q0;
    qd.setZero(n_);
    qdd.setZero(n_);
    for (int j = 0; j < n_; ++j)
      for (int k = 1; k <= L_; ++k) {
        const double a = t.a(j, k - 1), b = t.b(j, k - 1), s = S(m, k - 1), c = C(m, k - 1), kw = k * w_;
        q[j] += (a * s - b * c) / kw;
        qd[j] += a * c + b * s;
        qdd[j] += kw * (b * c - a * s);
      }
  }

  // the lowest point (body_heights) over the design grid [m]
  double lowest_on_grid(const ExcitationTrajectory& t) {
    double low = std::numeric_limits<double>::infinity();
    VectorJ q(n_), qd(n_), qdd(n_);
    for (Eigen::Index m = 0; m < S_.rows(); ++m) {
      grid_state(t, m, q, qd, qdd);
      model::forward_kinematics(m_, d_, q);
      low = std::min(low, body_heights(m_, d_, o_.tool_points).lowest);
    }
    return low;
  }

  void build_W(const ExcitationTrajectory& t, Eigen::MatrixXd& W) {
    const Eigen::Index M = S_.rows();
    W.resize(M * n_, base_.rank);
    VectorJ q(n_), qd(n_), qdd(n_);
    for (Eigen::Index m = 0; m < M; ++m) {
      grid_state(t, m, q, qd, qdd);
      model::regressor(m_, d_, q, qd, qdd, Y_, o_.friction);
      for (int c = 0; c < base_.rank; ++c) W.block(m * n_, c, n_, 1) = Y_.col(base_.independent[static_cast<size_t>(c)]);
    }
  }

  // sin(k w t_m), cos(k w t_m) on M points of one period
  void grid(int M, Eigen::MatrixXd& S, Eigen::MatrixXd& C) const {
    S.resize(M, L_), C.resize(M, L_);
    const double T = 2.0 * M_PI / w_;
    for (int m = 0; m < M; ++m)
      for (int k = 1; k <= L_; ++k) {
        const double ph = k * w_ * (T * m / M);
        S(m, k - 1) = std::sin(ph), C(m, k - 1) = std::cos(ph);
      }
  }

  int evaluations = 0;

 private:
  const model::RobotModel& m_;
  const ExcitationOptions& o_;
  int n_, L_;
  double w_ = 0.0;
  Limits lim_;
  model::DynamicsData d_;
  model::BaseParameters base_;
  model::RegressorMatrix Y_;
  Eigen::MatrixXd S_, C_, W_, scale_;
  ExcitationTrajectory traj_;
};

struct NloptContext {
  Design* design;
  std::vector<double> best_x;
  double best_f = std::numeric_limits<double>::infinity();
  int total = 1;
  const std::function<void(double, double)>* progress;
};

double nlopt_objective(unsigned n, const double* x, double* grad, void* data) {
  (void)grad;  // derivative-free algorithms only
  auto* c = static_cast<NloptContext*>(data);
  const double f = c->design->objective(x);
  if (f < c->best_f) {
    c->best_f = f;
    c->best_x.assign(x, x + n);
  }
  if (c->progress && *c->progress && c->design->evaluations % 50 == 0)
    (*c->progress)(std::min(1.0, static_cast<double>(c->design->evaluations) / c->total), std::exp(c->best_f));
  return f;
}

void run_nlopt(nlopt_algorithm alg, int budget, NloptContext& ctx) {
  if (budget <= 0) return;
  const unsigned nv = static_cast<unsigned>(ctx.best_x.size());
  nlopt_opt opt = nlopt_create(alg, nv);
  const std::vector<double> lo(nv, -1.0), hi(nv, 1.0);
  nlopt_set_lower_bounds(opt, lo.data());
  nlopt_set_upper_bounds(opt, hi.data());
  nlopt_set_min_objective(opt, nlopt_objective, &ctx);
  nlopt_set_maxeval(opt, budget);
  nlopt_set_ftol_rel(opt, kFtolRel);
  std::vector<double> x = ctx.best_x;
  double f = 0.0;
  nlopt_optimize(opt, x.data(), &f);  // the best point is tracked in ctx whatever the status
  nlopt_destroy(opt);
}

}  // namespace

void ExcitationOptions::validate(int n_dof) const {
  if (harmonics < 3 || harmonics > 20) throw InvalidArgument(fmt::format("harmonics is {}, must be in [3, 20]", harmonics));
  if (!(base_frequency > 0.0 && base_frequency <= 10.0))
    throw InvalidArgument(fmt::format("base_frequency is {} Hz, must be in (0, 10]", base_frequency));
  if (samples < 10) throw InvalidArgument(fmt::format("samples is {}, must be >= 10", samples));
  if (check_samples < samples)
    throw InvalidArgument(fmt::format("check_samples is {}, must be >= samples ({})", check_samples, samples));
  if (q0.size() != 0 && q0.size() != n_dof)
    throw InvalidArgument(fmt::format("q0 has {} values, expected {} (model.n_dof) or none", q0.size(), n_dof));
  for (Eigen::Index j = 0; j < q0.size(); ++j)
    if (!std::isfinite(q0[j])) throw InvalidArgument(fmt::format("q0[{}] is {}, must be finite", j, q0[j]));
  if (!(amplitude > 0.0)) throw InvalidArgument(fmt::format("amplitude is {} rad, must be > 0", amplitude));
  if (!(position_margin >= 0.0)) throw InvalidArgument(fmt::format("position_margin is {} rad, must be >= 0", position_margin));
  if (!(limit_fraction > 0.0 && limit_fraction <= 1.0))
    throw InvalidArgument(fmt::format("limit_fraction is {}, must be in (0, 1]", limit_fraction));
  if (!(default_qdd_max > 0.0)) throw InvalidArgument(fmt::format("default_qdd_max is {} rad/s², must be > 0", default_qdd_max));
  if (std::isnan(min_height)) throw InvalidArgument("min_height is NaN, must be a height [m] or -infinity (none)");
  validate_tool_points(tool_points);
  for (const auto& [name, v] : {std::pair{"tool_speed_max", tool_speed_max}, std::pair{"elbow_speed_max", elbow_speed_max},
                                std::pair{"momentum_max", momentum_max}})
    if (!(v > 0.0)) throw InvalidArgument(fmt::format("{} is {}, must be > 0 (or infinity: none)", name, v));
  if (!(std::isfinite(carried.mass) && carried.mass >= 0.0 && carried.com.allFinite()))
    throw InvalidArgument(fmt::format("carried is {} kg at ({}, {}, {}) m, must be a mass >= 0 at a finite point", carried.mass,
                                      carried.com.x(), carried.com.y(), carried.com.z()));
  if (std::isfinite(elbow_speed_max) && n_dof < 3)
    throw InvalidArgument(fmt::format("elbow_speed_max is {}, but an arm of {} joints has no elbow (the third joint)", elbow_speed_max, n_dof));
  if (global_evaluations < 0) throw InvalidArgument(fmt::format("global_evaluations is {}, must be >= 0", global_evaluations));
  if (local_evaluations < 0) throw InvalidArgument(fmt::format("local_evaluations is {}, must be >= 0", local_evaluations));
}

void ExcitationTrajectory::evaluate(double t, VectorJ& q, VectorJ& qd, VectorJ& qdd) const {
  const int n = static_cast<int>(q0.size());
  q = q0;
  qd.setZero(n);
  qdd.setZero(n);
  for (int k = 1; k <= a.cols(); ++k) {
    const double kw = k * w_f, s = std::sin(kw * t), c = std::cos(kw * t);
    for (int j = 0; j < n; ++j) {
      q[j] += (a(j, k - 1) * s - b(j, k - 1) * c) / kw;
      qd[j] += a(j, k - 1) * c + b(j, k - 1) * s;
      qdd[j] += kw * (b(j, k - 1) * c - a(j, k - 1) * s);
    }
  }
}

double excitation_condition_number(const model::RobotModel& model, const ExcitationTrajectory& t, int samples,
                                   model::FrictionColumns friction) {
  const int n = model.n_dof();
  if (t.q0.size() != n) throw InvalidArgument(fmt::format("trajectory has {} joints, model.n_dof is {}", t.q0.size(), n));
  if (samples < 1) throw InvalidArgument(fmt::format("samples is {}, must be >= 1", samples));
  const model::BaseParameters base = model::compute_base_parameters(model, friction);
  model::DynamicsData d(model);
  model::RegressorMatrix Y;
  Eigen::MatrixXd W(static_cast<Eigen::Index>(samples) * n, base.rank);
  VectorJ q, qd, qdd;
  for (int m = 0; m < samples; ++m) {
    t.evaluate(t.period() * m / samples, q, qd, qdd);
    model::regressor(model, d, q, qd, qdd, Y, friction);
    W.middleRows(static_cast<Eigen::Index>(m) * n, n) = base.base_regressor(Y);
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(W);
  const auto& sv = svd.singularValues();
  const double smin = sv(sv.size() - 1), smax = sv(0);
  return smin > smax / kCondInfinite ? smax / smin : kCondInfinite;
}

ExcitationResult design_excitation(const model::RobotModel& model, const ExcitationOptions& o,
                                   const std::function<void(double, double)>& progress) {
  o.validate(model.n_dof());
  const int n = model.n_dof();
  // centre: the middle of each joint's range (0 where unbounded) unless given
  VectorJ q0 = o.q0;
  if (q0.size() == 0) {
    q0.resize(n);
    for (int j = 0; j < n; ++j) {
      const auto& l = model.joint(j).limits;
      q0[j] = std::isfinite(l.q_min) && std::isfinite(l.q_max) ? 0.5 * (l.q_min + l.q_max) : 0.0;
    }
  }
  Design design(model, o, q0, make_limits(model, o, q0));
  const int nv = design.n_vars();

  // random start (seeded), projected onto the limits
  NloptContext ctx{&design, {}, std::numeric_limits<double>::infinity(),
                   std::max(1, o.global_evaluations + o.local_evaluations + 1), &progress};
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ctx.best_x.resize(static_cast<size_t>(nv));
  for (double& v : ctx.best_x) v = u(rng);
  const std::vector<double> x_start = ctx.best_x;
  ExcitationResult res;
  ExcitationTrajectory t;
  t.w_f = 2.0 * M_PI * o.base_frequency;
  t.q0 = q0;
  t.a.setZero(n, o.harmonics);
  t.b.setZero(n, o.harmonics);
  Eigen::MatrixXd Sg, Cg;
  design.grid(o.samples, Sg, Cg);
  auto finish = [&](const std::vector<double>& x) {
    design.coefficients(x.data(), t);
    design.project(t, Sg, Cg, 0.0);
    design.project_speeds(t, Sg, Cg, 0.0, 1);
    return excitation_condition_number(model, t, o.samples, o.friction);
  };
  ctx.best_f = design.objective(x_start.data());
  res.cond_start = finish(x_start);

  // global step, then local refinement from the best point found
  nlopt_srand(o.seed);
  run_nlopt(NLOPT_GN_CRS2_LM, o.global_evaluations, ctx);
  res.cond_global = finish(ctx.best_x);
  run_nlopt(NLOPT_LN_SBPLX, o.local_evaluations, ctx);

  // final coefficients, re-checked on the dense grid
  design.coefficients(ctx.best_x.data(), t);
  design.project(t, Sg, Cg, 0.0);
  design.project_speeds(t, Sg, Cg, 0.0, 1);
  Eigen::MatrixXd Sd, Cd;
  design.grid(o.check_samples, Sd, Cd);
  design.project(t, Sd, Cd, kRescaleSafety);
  design.project_speeds(t, Sd, Cd, kSpeedSafety, kSpeedPasses);
  if (design.limits_speeds() && design.speed_ratio(t, Sd, Cd) > 1.0)
    throw InvalidArgument(fmt::format("the design could not be brought within the tool, elbow speed and momentum limits in {} passes",
                                      kSpeedPasses));
  res.trajectory = t;
  res.cond_final = excitation_condition_number(model, t, o.samples, o.friction);
  res.evaluations = design.evaluations;
  res.base_columns = design.columns();
  const Limits& lim = design.limits();
  res.q_lo = q0 + lim.lo;
  res.q_hi = q0 + lim.hi;
  res.qd_lim = lim.vl;
  res.qdd_lim = lim.al;
  // extremes on the dense grid (and the end point)
  res.q_min_seen = VectorJ::Constant(n, std::numeric_limits<double>::infinity());
  res.q_max_seen = VectorJ::Constant(n, -std::numeric_limits<double>::infinity());
  res.qd_peak = VectorJ::Zero(n);
  res.qdd_peak = VectorJ::Zero(n);
  VectorJ q, qd, qdd;
  for (int m = 0; m <= o.check_samples; ++m) {
    t.evaluate(t.period() * m / o.check_samples, q, qd, qdd);
    res.q_min_seen = res.q_min_seen.cwiseMin(q);
    res.q_max_seen = res.q_max_seen.cwiseMax(q);
    res.qd_peak = res.qd_peak.cwiseMax(qd.cwiseAbs());
    res.qdd_peak = res.qdd_peak.cwiseMax(qdd.cwiseAbs());
  }
  res.lowest = excitation_lowest_point(model, t, o.check_samples, o.tool_points);
  design.speed_ratio(t, Sd, Cd, &res.speed_peak);
  if (progress) progress(1.0, res.cond_final);
  return res;
}

VectorJ excitation_raised_centre(const model::RobotModel& model, const ExcitationOptions& o) {
  o.validate(model.n_dof());
  const int n = model.n_dof();
  std::vector<double> lo(static_cast<size_t>(n)), hi(static_cast<size_t>(n)), x(static_cast<size_t>(n));
  for (int j = 0; j < n; ++j) {
    const auto& l = model.joint(j).limits;
    const size_t i = static_cast<size_t>(j);
    lo[i] = std::isfinite(l.q_min) ? l.q_min + o.position_margin : -M_PI;
    hi[i] = std::isfinite(l.q_max) ? l.q_max - o.position_margin : M_PI;
    if (!(lo[i] < hi[i]))
      throw InvalidArgument(fmt::format("joint {}'s limits [{}, {}] leave no room with a margin of {} rad", j + 1, l.q_min, l.q_max,
                                        o.position_margin));
    x[i] = std::isfinite(l.q_min) && std::isfinite(l.q_max) ? 0.5 * (l.q_min + l.q_max) : 0.0;
  }
  struct Ctx {
    const model::RobotModel* m;
    model::DynamicsData d;
    VectorJ mid;
    const std::vector<Eigen::Vector3d>* tool;
  } ctx{&model, model::DynamicsData(model), Eigen::Map<const Eigen::VectorXd>(x.data(), n), &o.tool_points};
  const auto height = [](unsigned nv, const double* v, double* grad, void* data) {
    (void)grad;  // derivative-free
    auto* c = static_cast<Ctx*>(data);
    const VectorJ q = Eigen::Map<const Eigen::VectorXd>(v, static_cast<Eigen::Index>(nv));
    model::forward_kinematics(*c->m, c->d, q);
    const BodyHeights h = body_heights(*c->m, c->d, *c->tool);
    return h.lowest + kCentreTieBreak * h.mean - kCentreStay * (q - c->mid).squaredNorm();
  };
  nlopt_opt opt = nlopt_create(NLOPT_LN_SBPLX, static_cast<unsigned>(n));
  nlopt_set_lower_bounds(opt, lo.data());
  nlopt_set_upper_bounds(opt, hi.data());
  nlopt_set_max_objective(opt, height, &ctx);
  nlopt_set_maxeval(opt, kCentreEvaluations);
  nlopt_set_xtol_abs1(opt, 1e-4);
  nlopt_set_initial_step1(opt, kCentreStep);
  double f = 0.0;
  nlopt_optimize(opt, x.data(), &f);  // x holds the best point whatever the status
  nlopt_destroy(opt);
  return Eigen::Map<const Eigen::VectorXd>(x.data(), n);
}

ExcitationLowestPoint excitation_lowest_point(const model::RobotModel& model, const ExcitationTrajectory& t, int samples,
                                              const std::vector<Eigen::Vector3d>& tool_points) {
  if (samples < 1) throw InvalidArgument(fmt::format("samples is {}, must be >= 1", samples));
  validate_tool_points(tool_points);
  model::DynamicsData d(model);
  ExcitationLowestPoint low;
  VectorJ q, qd, qdd;
  for (int m = 0; m <= samples; ++m) {
    const double time = t.period() * m / samples;
    t.evaluate(time, q, qd, qdd);
    model::forward_kinematics(model, d, q);
    if (const BodyHeights h = body_heights(model, d, tool_points); h.lowest < low.z) low = {h.lowest, time, h.body};
  }
  return low;
}

std::string excitation_scenario_yaml(const ExcitationTrajectory& t, const std::string& robot, int cycles,
                                     const std::string& comment) {
  if (cycles < 1) throw InvalidArgument(fmt::format("cycles is {}, must be >= 1", cycles));
  std::ostringstream os;
  std::istringstream cs(comment);
  std::string line;
  while (std::getline(cs, line)) os << "# " << line << "\n";
  auto row = [](const auto& v) {
    std::string s = "[";
    for (Eigen::Index i = 0; i < v.size(); ++i) s += fmt::format("{}{:.17g}", i ? ", " : "", v(i));
    return s + "]";
  };
  // scenario name from the robot's name or file stem ("panda", "data/robots/kinova_gen3.urdf" -> "kinova_gen3")
  std::string stem = robot.substr(robot.find_last_of('/') == std::string::npos ? 0 : robot.find_last_of('/') + 1);
  if (const auto dot = stem.find_last_of('.'); dot != std::string::npos && dot > 0) stem = stem.substr(0, dot);
  os << fmt::format("name: excitation_{}\n", stem);
  os << fmt::format("robot: {}\n", robot);
  os << fmt::format("cycles: {}\n", cycles);
  os << "trajectory:\n";
  os << "  type: fourier_series\n";
  os << fmt::format("  base_frequency: {:.17g}  # [Hz]; period {:.6g} s\n", t.w_f / (2.0 * M_PI), t.period());
  os << fmt::format("  q0: {}  # [rad], start = end\n", row(t.q0));
  os << "  a:  # [rad/s], one row per joint, harmonics 1..L\n";
  for (Eigen::Index j = 0; j < t.a.rows(); ++j) os << "    - " << row(Eigen::VectorXd(t.a.row(j).transpose())) << "\n";
  os << "  b:  # [rad/s]\n";
  for (Eigen::Index j = 0; j < t.b.rows(); ++j) os << "    - " << row(Eigen::VectorXd(t.b.row(j).transpose())) << "\n";
  return os.str();
}

}  // namespace twinwatch::ident
