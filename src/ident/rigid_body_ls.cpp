#include "twinwatch/ident/rigid_body_ls.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/json_fields.hpp"
#include "json_numbers.hpp"
#include "twinwatch/ident/nonnegative_ls.hpp"
#include "twinwatch/model/dynamics.hpp"

namespace twinwatch::ident {

namespace {

// friction columns per joint: Coulomb, viscous, offset
constexpr int kFric = 3;
// relative ridge on the column-scaled normal equations: guards only against columns that no row
// excites (e.g. a joint that never leaves the reversal screen); far below any identifiable signal
constexpr double kRidge = 1e-12;
// a forward/reverse pair must retrace the same poses within this [rad]
constexpr double kReversePoseTolerance = 0.02;
// fewer rows than this many times the unknowns cannot give a meaningful fit and std
constexpr int kMinRowsPerUnknown = 3;

const VectorJ& torque_of(const RobotSample& s, TorqueSignal sig) {
  switch (sig) {
    case TorqueSignal::JointTorque: return s.joint_torque;
    case TorqueSignal::CurrentAsTorque: return s.current_as_torque;
    case TorqueSignal::TargetMoment: return s.target_moment;
  }
  return s.joint_torque;
}

std::uint32_t flag_of(TorqueSignal sig) {
  switch (sig) {
    case TorqueSignal::JointTorque: return kFieldJointTorque;
    case TorqueSignal::CurrentAsTorque: return kFieldCurrentAsTorque;
    case TorqueSignal::TargetMoment: return kFieldTargetMoment;
  }
  return 0;
}

const char* column_of(TorqueSignal sig) {
  switch (sig) {
    case TorqueSignal::JointTorque: return "actual_joint_torque_*";
    case TorqueSignal::CurrentAsTorque: return "actual_current_as_torque_*";
    case TorqueSignal::TargetMoment: return "target_moment_*";
  }
  return "";
}

double sgn(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }

// column-scaled, ridge-guarded solve of A x = b; also returns A^-1 (unscaled)
Eigen::VectorXd solve_normal(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, Eigen::MatrixXd* inverse, double* cond) {
  const Eigen::VectorXd D = A.diagonal().cwiseMax(1e-300).cwiseSqrt();
  const Eigen::VectorXd Di = D.cwiseInverse();
  Eigen::MatrixXd As = Di.asDiagonal() * A * Di.asDiagonal();
  As.diagonal().array() += kRidge;
  if (cond) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(As, Eigen::EigenvaluesOnly);
    const double lmin = es.eigenvalues()(0), lmax = es.eigenvalues()(As.rows() - 1);
    *cond = lmin > 0 ? std::sqrt(lmax / lmin) : std::numeric_limits<double>::infinity();
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(As);
  if (inverse) *inverse = Di.asDiagonal() * ldlt.solve(Eigen::MatrixXd::Identity(A.rows(), A.cols())) * Di.asDiagonal();
  return Di.asDiagonal() * ldlt.solve(Di.asDiagonal() * b);
}

}  // namespace

const char* to_string(TorqueSignal s) {
  switch (s) {
    case TorqueSignal::JointTorque: return "joint_torque";
    case TorqueSignal::CurrentAsTorque: return "current_as_torque";
    case TorqueSignal::TargetMoment: return "target_moment";
  }
  return "";
}

TorqueSignal torque_signal_from_string(const std::string& s) {
  for (TorqueSignal t : {TorqueSignal::JointTorque, TorqueSignal::CurrentAsTorque, TorqueSignal::TargetMoment})
    if (s == to_string(t)) return t;
  throw InvalidArgument(fmt::format("torque signal '{}' is unknown, expected joint_torque, current_as_torque or target_moment", s));
}

void RigidBodyLsOptions::validate() const {
  if (!(reversal_screen >= 0.0)) throw InvalidArgument(fmt::format("reversal_screen is {}, must be >= 0 rad/s", reversal_screen));
  if (weight_iterations < 0) throw InvalidArgument(fmt::format("weight_iterations is {}, must be >= 0", weight_iterations));
  if (derivative_half_window < 1)
    throw InvalidArgument(fmt::format("derivative_half_window is {}, must be >= 1", derivative_half_window));
  if (derivative_order < 1 || derivative_order > 2 * derivative_half_window)
    throw InvalidArgument(fmt::format("derivative_order is {}, must be in [1, 2 derivative_half_window = {}]", derivative_order,
                                      2 * derivative_half_window));
  if (decimate < 1) throw InvalidArgument(fmt::format("decimate is {}, must be >= 1", decimate));
}

std::vector<double> local_polynomial(const std::vector<double>& t, const std::vector<double>& x, int h, int order, int deriv) {
  const long N = static_cast<long>(t.size());
  if (x.size() != t.size()) throw InvalidArgument(fmt::format("x has {} samples, t has {}", x.size(), t.size()));
  if (h < 1) throw InvalidArgument(fmt::format("half_window is {}, must be >= 1", h));
  if (order < deriv || order > 2 * h) throw InvalidArgument(fmt::format("order is {}, must be in [{}, {}]", order, deriv, 2 * h));
  if (deriv < 0 || deriv > 1) throw InvalidArgument(fmt::format("deriv is {}, must be 0 or 1", deriv));
  if (N < 2L * h + 1) throw InvalidArgument(fmt::format("{} samples, the window needs at least {}", N, 2 * h + 1));
  std::vector<double> out(static_cast<size_t>(N));
  const int m = 2 * h + 1;
  Eigen::MatrixXd V(m, order + 1);
  Eigen::VectorXd y(m);
  for (long k = 0; k < N; ++k) {
    // window of 2h+1 samples around k, shifted inside at the ends
    const long a = std::clamp(k - h, 0L, N - m);
    // polynomial in u = (t - t_k) / s, s the window's time span (keeps V well scaled)
    const double s = std::max(t[static_cast<size_t>(a + m - 1)] - t[static_cast<size_t>(a)], 1e-300);
    for (int i = 0; i < m; ++i) {
      const double u = (t[static_cast<size_t>(a + i)] - t[static_cast<size_t>(k)]) / s;
      double p = 1.0;
      for (int c = 0; c <= order; ++c) V(i, c) = p, p *= u;
      y(i) = x[static_cast<size_t>(a + i)];
    }
    const Eigen::VectorXd c = V.colPivHouseholderQr().solve(y);
    out[static_cast<size_t>(k)] = deriv == 0 ? c(0) : c(1) / s;
  }
  return out;
}

TorqueData torque_data(const Segment& seg, TorqueSignal sig, int h, int order) {
  if (!seg.recording) throw InvalidArgument("segment has no recording");
  const device::Recording& rec = *seg.recording;
  if (!(seg.from >= 0.0 && seg.to <= 1.0 && seg.from < seg.to))
    throw InvalidArgument(fmt::format("{}: segment [{}, {}) must satisfy 0 <= from < to <= 1", rec.path, seg.from, seg.to));
  if (!(rec.present & flag_of(sig)))
    throw InvalidArgument(fmt::format("{}: no {} columns: the '{}' torque signal is not in this recording (map it with a "
                                      "column map, see docs/recordings.md)", rec.path, column_of(sig), to_string(sig)));
  if (!(rec.present & kFieldActualQd))
    throw InvalidArgument(fmt::format("{}: no actual_qd_* columns: the torque-domain fit needs measured joint velocities", rec.path));
  const int n = rec.n_dof;
  const size_t N = rec.samples.size();
  if (h >= 1 && N < 2 * static_cast<size_t>(h) + 1)
    throw InvalidArgument(fmt::format("{}: {} samples, fewer than the {} of one derivative window (half window {} samples: a shorter "
                                      "one, or a longer recording)",
                                      rec.path, N, 2 * h + 1, h));
  std::vector<double> t(N);
  for (size_t k = 0; k < N; ++k) t[k] = rec.samples[k].timestamp;
  // smoothed qd and its derivative, joint by joint, on the whole recording (then cut)
  std::vector<std::vector<double>> qd_s(static_cast<size_t>(n)), qdd_s(static_cast<size_t>(n));
  std::vector<double> x(N);
  for (int j = 0; j < n; ++j) {
    for (size_t k = 0; k < N; ++k) x[k] = rec.samples[k].qd[j];
    qd_s[static_cast<size_t>(j)] = local_polynomial(t, x, h, order, 0);
    qdd_s[static_cast<size_t>(j)] = local_polynomial(t, x, h, order, 1);
  }
  const double t0 = t.front(), D = t.back() - t.front();
  const double ta = t0 + seg.from * D, tb = t0 + seg.to * D;
  TorqueData d;
  for (size_t k = 0; k < N; ++k) {
    if (t[k] < ta || (t[k] >= tb && seg.to < 1.0)) continue;
    const RobotSample& s = rec.samples[k];
    VectorJ qd(n), qdd(n);
    for (int j = 0; j < n; ++j) qd[j] = qd_s[static_cast<size_t>(j)][k], qdd[j] = qdd_s[static_cast<size_t>(j)][k];
    d.t.push_back(t[k]);
    d.q.push_back(s.q);
    d.qd.push_back(qd);
    d.qdd.push_back(qdd);
    d.tau.push_back(torque_of(s, sig));
  }
  return d;
}

VectorJ RigidBodyModel::predict(const model::RobotModel& model, model::DynamicsData& data, const VectorJ& q, const VectorJ& qd,
                                const VectorJ& qdd) const {
  model::RegressorMatrix Y;
  model::regressor(model, data, q, qd, qdd, Y);
  const int n = model.n_dof();
  VectorJ tau = VectorJ::Zero(n);
  for (size_t c = 0; c < base_columns.size(); ++c) tau += Y.col(base_columns[c]) * beta(static_cast<Eigen::Index>(c));
  for (int j = 0; j < n; ++j) tau[j] += friction(j, 0) * sgn(qd[j]) + friction(j, 1) * qd[j] + friction(j, 2);
  return tau;
}

std::string RigidBodyModel::to_json() const {
  nlohmann::json j;
  j["kind"] = "rigid_body_torque";
  j["robot"] = robot;
  j["signal"] = to_string(signal);
  j["base_columns"] = base_columns;
  j["beta"] = std::vector<double>(beta.data(), beta.data() + beta.size());
  j["beta_std"] = std::vector<double>(beta_std.data(), beta_std.data() + beta_std.size());
  for (Eigen::Index r = 0; r < friction.rows(); ++r) {
    j["friction"].push_back({{"coulomb", friction(r, 0)}, {"viscous", friction(r, 1)}, {"offset", friction(r, 2)},
                             {"coulomb_std", friction_std(r, 0)}, {"viscous_std", friction_std(r, 1)},
                             {"offset_std", friction_std(r, 2)}, {"coulomb_held", bool(friction_held(r, 0))},
                             {"viscous_held", bool(friction_held(r, 1))}});
  }
  j["sigma"] = sigma;
  j["rows_rigid"] = rows_rigid;
  j["rows_friction"] = rows_friction;
  j["cond"] = std::isfinite(cond) ? nlohmann::json(cond) : nlohmann::json(nullptr);
  j["averaged_forward_reverse"] = averaged;
  j["derivative"] = {{"half_window", derivative_half_window}, {"order", derivative_order}};
  return j.dump(2);
}

RigidBodyModel RigidBodyModel::from_json(const std::string& text, const std::string& origin, int n_dof) {
  const nlohmann::json j = parse_json(text, origin);
  const JsonFields top(j, origin, "");
  // (the kind first: a twin file or another JSON file is named as such, not by its first strange key)
  if (!top.has("kind")) top.fail("kind", "missing: expected 'rigid_body_torque' (a model from 'twinwatch identify-torque'; a twin file is not one)");
  if (const std::string kind = top.text("kind"); kind != "rigid_body_torque")
    top.fail("kind", fmt::format("expected 'rigid_body_torque' (a model from 'twinwatch identify-torque'), got '{}'", kind));
  top.only({"kind", "robot", "signal", "base_columns", "beta", "beta_std", "friction", "sigma", "rows_rigid", "rows_friction", "cond",
            "averaged_forward_reverse", "derivative"});
  RigidBodyModel m;
  m.robot = top.text("robot");
  try {
    m.signal = torque_signal_from_string(top.text("signal"));
  } catch (const InvalidArgument& e) {
    top.fail("signal", e.what());
  }
  // the friction rows fix the joint count when the caller does not (n_dof 0)
  const nlohmann::json& f = top.need("friction");
  if (!f.is_array() || f.empty()) top.fail("friction", fmt::format("expected an array of one object per joint, got {}", json_brief(f)));
  const int n = n_dof > 0 ? n_dof : static_cast<int>(f.size());
  if (static_cast<int>(f.size()) != n) top.fail("friction", fmt::format("expected {} rows (one per joint of {}), got {}", n, m.robot, f.size()));
  // base parameters: each standard column (10 per joint) once, one value and one std per column
  m.base_columns = json_wholes(top.need("base_columns"), origin, "base_columns");
  std::vector<int> first(static_cast<size_t>(10 * n), -1);
  for (size_t i = 0; i < m.base_columns.size(); ++i) {
    const int c = m.base_columns[i];
    if (c < 0 || c >= 10 * n)
      throw ParseError(origin, 0, json_element("base_columns", i), fmt::format("expected a column 0..{} ({} joints), got {}", 10 * n - 1, n, c));
    if (first[static_cast<size_t>(c)] >= 0)
      throw ParseError(origin, 0, json_element("base_columns", i),
                       fmt::format("expected each standard column once, got column {} again (also at base_columns[{}])", c, first[static_cast<size_t>(c)]));
    first[static_cast<size_t>(c)] = static_cast<int>(i);
  }
  const std::vector<double> b = top.numbers("beta", m.base_columns.size());
  m.beta = Eigen::Map<const Eigen::VectorXd>(b.data(), static_cast<Eigen::Index>(b.size()));
  const std::vector<double> bs = top.has("beta_std") ? top.numbers("beta_std", b.size()) : std::vector<double>(b.size(), 0.0);
  m.beta_std = Eigen::Map<const Eigen::VectorXd>(bs.data(), static_cast<Eigen::Index>(bs.size()));
  m.friction.resize(n, kFric);
  m.friction_std.setZero(n, kFric);
  m.friction_held.setConstant(n, 2, false);
  for (int r = 0; r < n; ++r) {
    const JsonFields fr(f[static_cast<size_t>(r)], origin, json_element("friction", static_cast<size_t>(r)));
    fr.only({"coulomb", "viscous", "offset", "coulomb_std", "viscous_std", "offset_std", "coulomb_held", "viscous_held"});
    m.friction(r, 0) = fr.number("coulomb");
    m.friction(r, 1) = fr.number("viscous");
    m.friction(r, 2) = fr.number("offset");
    m.friction_std(r, 0) = fr.has("coulomb_std") ? fr.nonnegative("coulomb_std") : 0.0;
    m.friction_std(r, 1) = fr.has("viscous_std") ? fr.nonnegative("viscous_std") : 0.0;
    m.friction_std(r, 2) = fr.has("offset_std") ? fr.nonnegative("offset_std") : 0.0;
    m.friction_held(r, 0) = fr.has("coulomb_held") && fr.boolean("coulomb_held");
    m.friction_held(r, 1) = fr.has("viscous_held") && fr.boolean("viscous_held");
  }
  if (top.has("derivative")) {
    const JsonFields d = top.object("derivative");
    d.only({"half_window", "order"});
    m.derivative_half_window = d.whole("half_window");
    m.derivative_order = d.whole("order");
    if (m.derivative_half_window < 1 || m.derivative_half_window > 10000)
      d.fail("half_window", fmt::format("expected 1..10000 samples, got {}", m.derivative_half_window));
    if (m.derivative_order < 1 || m.derivative_order > 2 * m.derivative_half_window)
      d.fail("order", fmt::format("expected 1..{} (2 half_window), got {}", 2 * m.derivative_half_window, m.derivative_order));
  }
  if (top.has("sigma")) m.sigma = top.numbers("sigma");
  if (top.has("averaged_forward_reverse")) m.averaged = top.boolean("averaged_forward_reverse");
  return m;
}

RigidBodyModel identify_rigid_body(const model::RobotModel& model, const std::string& robot, const std::vector<Segment>& segments,
                                   const RigidBodyLsOptions& o, const std::function<void(double)>& progress) {
  o.validate();
  if (segments.empty()) throw InvalidArgument("identify: no recordings given");
  const int n = model.n_dof();
  for (const Segment& s : segments) {
    if (!s.recording) throw InvalidArgument("identify: a segment has no recording");
    if (s.recording->n_dof != n)
      throw InvalidArgument(fmt::format("{}: {} joints, but robot '{}' has {}", s.recording->path, s.recording->n_dof, robot, n));
    if (s.reverse && s.reverse->n_dof != n)
      throw InvalidArgument(fmt::format("{}: {} joints, but robot '{}' has {}", s.reverse->path, s.reverse->n_dof, robot, n));
  }
  const model::BaseParameters base = model::compute_base_parameters(model);
  const int nb = base.rank;
  const int p = nb + kFric * n;
  model::DynamicsData dd(model);
  model::RegressorMatrix Y, Y2;

  // the data of every segment (and of its time-reversed partner)
  std::vector<TorqueData> fwd, rev;
  bool averaged = false;
  for (const Segment& s : segments) {
    fwd.push_back(torque_data(s, o.signal, o.derivative_half_window, o.derivative_order));
    if (s.reverse) {
      Segment r = s;
      r.recording = s.reverse;
      r.from = 1.0 - s.to;
      r.to = 1.0 - s.from;
      rev.push_back(torque_data(r, o.signal, o.derivative_half_window, o.derivative_order));
      averaged = true;
    } else {
      rev.emplace_back();
    }
  }

  // per-joint sufficient statistics of the rigid-body fit: A_j = sum r r^T, b_j = sum r tau, c_j = sum tau^2
  std::vector<Eigen::MatrixXd> A(static_cast<size_t>(n), Eigen::MatrixXd::Zero(p, p));
  std::vector<Eigen::VectorXd> b(static_cast<size_t>(n), Eigen::VectorXd::Zero(p));
  std::vector<double> c(static_cast<size_t>(n), 0.0);
  std::vector<long> rows(static_cast<size_t>(n), 0);
  Eigen::VectorXd r(p);
  long total = 0, done = 0;
  for (const auto& d : fwd) total += static_cast<long>(d.t.size());
  for (size_t si = 0; si < fwd.size(); ++si) {
    const TorqueData& d = fwd[si];
    const TorqueData& dr = rev[si];
    const double T0 = segments[si].recording->samples.front().timestamp;
    const double Tend = segments[si].recording->samples.back().timestamp;
    for (size_t k = 0; k < d.t.size(); k += static_cast<size_t>(o.decimate)) {
      if (progress && (++done % 5000) == 0) progress(0.8 * static_cast<double>(done) * o.decimate / static_cast<double>(total));
      model::regressor(model, dd, d.q[k], d.qd[k], d.qdd[k], Y);
      VectorJ tau = d.tau[k];
      bool avg = false;
      if (!dr.t.empty()) {
        // partner: the reverse sample nearest the mirrored time t_rev - T0_rev = Tend - t
        // (binary search on its increasing time axis)
        const double T0r = segments[si].reverse->samples.front().timestamp;
        const double want = T0r + (Tend - d.t[k]);
        const auto it = std::lower_bound(dr.t.begin(), dr.t.end(), want);
        size_t rk = static_cast<size_t>(std::min<std::ptrdiff_t>(it - dr.t.begin(), static_cast<std::ptrdiff_t>(dr.t.size()) - 1));
        if (rk > 0 && std::abs(dr.t[rk - 1] - want) < std::abs(dr.t[rk] - want)) --rk;
        if ((dr.q[rk] - d.q[k]).cwiseAbs().maxCoeff() > kReversePoseTolerance)
          throw InvalidArgument(fmt::format("{} is not {} played backwards: at t = {:.4f} s the poses differ by {:.4f} rad (> {} rad)",
                                            segments[si].reverse->path, segments[si].recording->path, d.t[k] - T0,
                                            (dr.q[rk] - d.q[k]).cwiseAbs().maxCoeff(), kReversePoseTolerance));
        model::regressor(model, dd, dr.q[rk], dr.qd[rk], dr.qdd[rk], Y2);
        Y = 0.5 * (Y + Y2);
        tau = 0.5 * (tau + dr.tau[rk]);
        avg = true;
      }
      for (int j = 0; j < n; ++j) {
        if (!std::isfinite(tau[j])) continue;
        // reversal screen: the rigid-body fit only sees |qd| >= screen [HESR §III-E]
        if (std::abs(d.qd[k][j]) < o.reversal_screen) continue;
        r.setZero();
        for (int col = 0; col < nb; ++col) r(col) = Y(j, base.independent[static_cast<size_t>(col)]);
        // averaged rows carry no Coulomb/viscous friction (odd in qd), only the offset
        if (!avg) {
          r(nb + kFric * j) = sgn(d.qd[k][j]);
          r(nb + kFric * j + 1) = d.qd[k][j];
        }
        r(nb + kFric * j + 2) = 1.0;
        A[static_cast<size_t>(j)].selfadjointView<Eigen::Lower>().rankUpdate(r);
        b[static_cast<size_t>(j)] += r * tau[j];
        c[static_cast<size_t>(j)] += tau[j] * tau[j];
        ++rows[static_cast<size_t>(j)];
      }
    }
  }
  long all_rows = 0;
  for (int j = 0; j < n; ++j) {
    A[static_cast<size_t>(j)] = A[static_cast<size_t>(j)].selfadjointView<Eigen::Lower>();
    all_rows += rows[static_cast<size_t>(j)];
  }
  if (all_rows < kMinRowsPerUnknown * p) {
    // (how many there were to screen: a --segment or --decimate that left one sample was blamed on
    // the screen; audit of session 56)
    size_t samples = 0;
    for (const TorqueData& d : fwd) samples += (d.t.size() + static_cast<size_t>(o.decimate) - 1) / static_cast<size_t>(o.decimate);
    throw InvalidArgument(fmt::format("identify: {} joint rows of {} sample(s) x {} joints pass the reversal screen of {} rad/s, expected at "
                                      "least {} ({} x {} unknowns){}",
                                      all_rows, samples, n, o.reversal_screen, kMinRowsPerUnknown * p, kMinRowsPerUnknown, p,
                                      samples * static_cast<size_t>(n) < static_cast<size_t>(kMinRowsPerUnknown * p)
                                          ? ": too few samples before any screening (--segment, --decimate?)"
                                          : ""));
  }

  // OLS, then weighted LS with w_j = 1 / sigma_j^2 re-estimated from the residuals [Gautier1990]
  std::vector<double> w(static_cast<size_t>(n), 1.0), ss(static_cast<size_t>(n), 0.0);
  Eigen::VectorXd theta;
  Eigen::MatrixXd Ainv;
  double cond = 0.0;
  const int iterations = o.weighted ? 1 + o.weight_iterations : 1;
  for (int it = 0; it < iterations; ++it) {
    Eigen::MatrixXd Aw = Eigen::MatrixXd::Zero(p, p);
    Eigen::VectorXd bw = Eigen::VectorXd::Zero(p);
    for (int j = 0; j < n; ++j) Aw += w[static_cast<size_t>(j)] * A[static_cast<size_t>(j)], bw += w[static_cast<size_t>(j)] * b[static_cast<size_t>(j)];
    theta = solve_normal(Aw, bw, &Ainv, &cond);
    for (int j = 0; j < n; ++j) {
      const size_t J = static_cast<size_t>(j);
      ss[J] = std::max(0.0, c[J] - 2.0 * theta.dot(b[J]) + theta.dot(A[J] * theta));
      // residual variance of joint j (its share of the unknowns subtracted)
      const double dof = std::max(1.0, static_cast<double>(rows[J]) - static_cast<double>(p) / n);
      if (o.weighted) w[J] = dof / std::max(ss[J], 1e-300);
    }
  }
  // covariance s^2 (W^T W)^-1 of the (weighted) system
  double sw = 0.0;
  for (int j = 0; j < n; ++j) sw += w[static_cast<size_t>(j)] * ss[static_cast<size_t>(j)];
  const double s2 = sw / std::max(1.0, static_cast<double>(all_rows - p));
  RigidBodyModel m;
  m.robot = robot;
  m.signal = o.signal;
  m.base_columns = base.independent;
  m.beta = theta.head(nb);
  m.beta_std = (s2 * Ainv.diagonal().head(nb)).cwiseMax(0.0).cwiseSqrt();
  m.friction.resize(n, kFric);
  m.friction_std.resize(n, kFric);
  m.friction_held.setConstant(n, 2, false);
  for (int j = 0; j < n; ++j)
    for (int f = 0; f < kFric; ++f) {
      m.friction(j, f) = theta(nb + kFric * j + f);
      m.friction_std(j, f) = std::sqrt(std::max(0.0, s2 * Ainv(nb + kFric * j + f, nb + kFric * j + f)));
    }
  m.rows_rigid = rows;
  m.cond = cond;
  m.averaged = averaged;
  m.derivative_half_window = o.derivative_half_window;
  m.derivative_order = o.derivative_order;
  m.sigma.assign(static_cast<size_t>(n), 0.0);
  for (int j = 0; j < n; ++j)
    m.sigma[static_cast<size_t>(j)] = std::sqrt(ss[static_cast<size_t>(j)] / std::max(1.0, static_cast<double>(rows[static_cast<size_t>(j)])));

  // friction re-estimated on every row (also |qd| < screen), rigid body fixed; forced when the
  // rigid-body rows were averaged (they carry no Coulomb/viscous information)
  m.rows_friction = rows;
  const Eigen::MatrixXd cov_beta = s2 * Ainv.topLeftCorner(nb, nb);
  if (o.refit_friction || averaged) {
    std::vector<Eigen::Matrix3d> F(static_cast<size_t>(n), Eigen::Matrix3d::Zero());
    std::vector<Eigen::Vector3d> g(static_cast<size_t>(n), Eigen::Vector3d::Zero());
    std::vector<double> e(static_cast<size_t>(n), 0.0);
    std::vector<long> cnt(static_cast<size_t>(n), 0);
    // F^T Y_b,j: how the friction estimate moves with beta (for the std propagation below)
    std::vector<Eigen::MatrixXd> FY(static_cast<size_t>(n), Eigen::MatrixXd::Zero(kFric, nb));
    Eigen::VectorXd yb(nb);
    auto add = [&](const TorqueData& d) {
      for (size_t k = 0; k < d.t.size(); k += static_cast<size_t>(o.decimate)) {
        model::regressor(model, dd, d.q[k], d.qd[k], d.qdd[k], Y);
        for (int j = 0; j < n; ++j) {
          if (!std::isfinite(d.tau[k][j])) continue;
          for (int col = 0; col < nb; ++col) yb(col) = Y(j, base.independent[static_cast<size_t>(col)]);
          const double res = d.tau[k][j] - yb.dot(m.beta);
          const Eigen::Vector3d x(sgn(d.qd[k][j]), d.qd[k][j], 1.0);
          F[static_cast<size_t>(j)] += x * x.transpose();
          FY[static_cast<size_t>(j)] += x * yb.transpose();
          g[static_cast<size_t>(j)] += x * res;
          e[static_cast<size_t>(j)] += res * res;
          ++cnt[static_cast<size_t>(j)];
        }
      }
    };
    for (size_t si = 0; si < fwd.size(); ++si) {
      add(fwd[si]);
      if (!rev[si].t.empty()) add(rev[si]);
      if (progress) progress(0.8 + 0.2 * static_cast<double>(si + 1) / static_cast<double>(fwd.size()));
    }
    for (int j = 0; j < n; ++j) {
      const size_t J = static_cast<size_t>(j);
      Eigen::MatrixXd Fi;
      Eigen::VectorXd x = solve_normal(F[J], g[J], &Fi, nullptr);
      if (x(0) < 0.0 || x(1) < 0.0) {
        // friction that would push the motion along: Coulomb and viscous are held >= 0 (the
        // offset stays free) and the rest is fitted on the face the bounds leave, as identify's
        // current-domain fit does. The held coefficient has no spread of its own (std 0, marked).
        const Eigen::VectorXd xb = nonnegative_ls_normal(F[J], g[J], {true, true, false});
        std::vector<Eigen::Index> keep;
        for (Eigen::Index f = 0; f < kFric; ++f) {
          const bool held = f < 2 && xb(f) == 0.0;
          if (f < 2) m.friction_held(j, f) = held;
          if (!held) keep.push_back(f);
        }
        const auto K = static_cast<Eigen::Index>(keep.size());
        Eigen::MatrixXd Fk(K, K), Fik;
        Eigen::VectorXd gk(K);
        for (Eigen::Index a = 0; a < K; ++a) {
          gk(a) = g[J](keep[static_cast<size_t>(a)]);
          for (Eigen::Index c = 0; c < K; ++c) Fk(a, c) = F[J](keep[static_cast<size_t>(a)], keep[static_cast<size_t>(c)]);
        }
        const Eigen::VectorXd xk = solve_normal(Fk, gk, &Fik, nullptr);
        x.setZero();
        Fi.setZero(kFric, kFric);
        for (Eigen::Index a = 0; a < K; ++a) {
          x(keep[static_cast<size_t>(a)]) = xk(a);
          for (Eigen::Index c = 0; c < K; ++c) Fi(keep[static_cast<size_t>(a)], keep[static_cast<size_t>(c)]) = Fik(a, c);
        }
      }
      const double sse = std::max(0.0, e[J] - 2.0 * x.dot(g[J]) + x.dot(F[J] * x));
      const double s2j = sse / std::max(1.0, static_cast<double>(cnt[J] - kFric));
      // Cov(x) = s_j^2 (F^T F)^-1 + H Cov(beta) H^T,  H = (F^T F)^-1 F^T Y_b,j: the conditional
      // spread plus what the rigid-body uncertainty passes on (e.g. offset vs gravity terms)
      const Eigen::MatrixXd H = Fi * FY[J];
      const Eigen::MatrixXd cov = s2j * Fi + H * cov_beta * H.transpose();
      for (int f = 0; f < kFric; ++f) {
        m.friction(j, f) = x(f);
        m.friction_std(j, f) = std::sqrt(std::max(0.0, cov(f, f)));
      }
      m.rows_friction[J] = cnt[J];
    }
  }
  if (progress) progress(1.0);
  return m;
}

std::vector<signal::FitMetrics> torque_metrics(const TorqueData& d, const std::function<VectorJ(size_t)>& predict) {
  if (d.t.empty()) throw InvalidArgument("torque_metrics: the segment holds no samples");
  const int n = static_cast<int>(d.tau.front().size());
  std::vector<std::vector<double>> y(static_cast<size_t>(n)), yh(static_cast<size_t>(n));
  for (size_t k = 0; k < d.t.size(); ++k) {
    const VectorJ p = predict(k);
    for (int j = 0; j < n; ++j) y[static_cast<size_t>(j)].push_back(d.tau[k][j]), yh[static_cast<size_t>(j)].push_back(p[j]);
  }
  std::vector<signal::FitMetrics> out;
  for (int j = 0; j < n; ++j) out.push_back(signal::fit_metrics(y[static_cast<size_t>(j)], yh[static_cast<size_t>(j)]));
  return out;
}

}  // namespace twinwatch::ident
