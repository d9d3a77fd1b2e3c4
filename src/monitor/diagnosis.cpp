#include "twinwatch/monitor/diagnosis.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::monitor {

namespace {

// a joint takes part in a contact when its residual RMS is at least this fraction of the
// largest joint's: joints beyond the contact link see only noise and model error.
constexpr double kContactJointFraction = 0.2;
// samples whose residual norm is below this fraction of the window's peak are left out of the
// contact fit (a collision pulse is short; the rest of the window is noise).
constexpr double kPulseFraction = 0.3;
// the residual at the end of the window, relative to its peak, above which a fault persists
constexpr double kPersistentFraction = 0.35;
// a hypothesis with one more parameter must explain this much more to win a tie
constexpr double kComplexityPenalty = 0.02;
// velocity below which a joint is taken as at rest for the frozen-channel check [rad/s]
constexpr double kMovingVelocity = 0.01;

double sq(double x) { return x * x; }

// fraction of sum ||r||^2 explained by the least-squares fit A x = b; returns x too
double ls_explained(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, double total, Eigen::VectorXd& x) {
  if (A.rows() == 0 || total <= 0.0) {
    x = Eigen::VectorXd::Zero(A.cols());
    return 0.0;
  }
  x = A.colPivHouseholderQr().solve(b);
  const double sse = (A * x - b).squaredNorm();
  return std::clamp((b.squaredNorm() - sse) / total, 0.0, 1.0);
}

Hypothesis resistance_hypothesis(const std::vector<DiagnosisSample>& w, int j, double total) {
  const auto K = static_cast<Eigen::Index>(w.size());
  Eigen::MatrixXd A(K, 2);
  Eigen::VectorXd b(K);
  for (Eigen::Index k = 0; k < K; ++k) {
    const double qd = w[static_cast<size_t>(k)].qd[j];
    A(k, 0) = qd > 0 ? 1.0 : (qd < 0 ? -1.0 : 0.0);
    A(k, 1) = qd;
    b(k) = w[static_cast<size_t>(k)].r_tau[j];
  }
  Eigen::VectorXd x;
  Hypothesis h;
  h.fault = FaultClass::Resistance;
  h.joint = j;
  h.explained = ls_explained(A, b, total, x);
  // size: mean extra friction torque along the motion
  h.magnitude = (A * x).cwiseAbs().mean();
  h.units = "N·m";
  // resistance opposes motion: the extra drive torque has the sign of qd (c > 0)
  if (x(0) < 0.0) h.explained *= 0.5;
  h.detail = fmt::format("extra friction on J{} ≈ {:.2f} N·m (Coulomb {:.2f} N·m, viscous {:.2f} N·m·s/rad)", j + 1,
                         h.magnitude, x(0), x(1));
  return h;
}

Hypothesis offset_hypothesis(const std::vector<DiagnosisSample>& w, int j, double total) {
  double mean = 0.0;
  for (const auto& s : w) mean += s.r_tau[j];
  mean /= static_cast<double>(w.size());
  Hypothesis h;
  h.fault = FaultClass::SensorFault;
  h.joint = j;
  h.explained = std::clamp(sq(mean) * static_cast<double>(w.size()) / total, 0.0, 1.0);
  h.magnitude = mean;
  h.units = "N·m";
  h.detail = fmt::format("constant offset on the J{} current channel ≈ {:.2f} N·m equivalent", j + 1, mean);
  return h;
}

Hypothesis payload_hypothesis(const model::RobotModel& m, const std::vector<DiagnosisSample>& w, double total,
                              const Eigen::Vector3d& com) {
  const int n = m.n_dof();
  const int last = n - 1;
  model::DynamicsData d(m);
  Matrix6J J;
  const auto K = static_cast<Eigen::Index>(w.size());
  Eigen::MatrixXd A(K * n, 1);
  Eigen::VectorXd b(K * n);
  for (Eigen::Index k = 0; k < K; ++k) {
    const DiagnosisSample& s = w[static_cast<size_t>(k)];
    // motion of the last link (w, wd, a incl. -g) from the RNEA forward pass
    model::rnea(m, d, s.q, s.qd, s.qdd);
    const Eigen::Vector3d om = d.w[static_cast<size_t>(last)], omd = d.wd[static_cast<size_t>(last)],
                          acc = d.a[static_cast<size_t>(last)];
    model::forward_kinematics(m, d, s.q);
    model::point_jacobian(m, d, last, Eigen::Vector3d::Zero(), J);
    const Eigen::Matrix3d R = d.oMi[static_cast<size_t>(last)].linear();
    // wrench of a unit point mass at `com` on the last link (body frame, about its origin):
    //   F = a + wd x c + w x (w x c),  N = c x a  (the point mass's own inertia terms are second order)
    const Eigen::Vector3d F = acc + omd.cross(com) + om.cross(om.cross(com));
    const Eigen::Vector3d N = com.cross(acc);
    A.col(0).segment(k * n, n) = J.topRows<3>().transpose() * (R * F) + J.bottomRows<3>().transpose() * (R * N);
    b.segment(k * n, n) = s.r_tau;
  }
  Eigen::VectorXd x;
  Hypothesis h;
  h.fault = FaultClass::PayloadChange;
  h.explained = ls_explained(A, b, total, x);
  h.magnitude = x(0);
  h.units = "kg";
  h.detail = fmt::format("payload {:+.2f} kg", x(0));
  return h;
}

Hypothesis contact_hypothesis(const model::RobotModel& m, const std::vector<DiagnosisSample>& w, double total) {
  const int n = m.n_dof();
  // contact link: the most distal joint that carries a real share of the residual
  VectorJ rms = VectorJ::Zero(n);
  double peak = 0.0;
  for (const auto& s : w) {
    rms += s.r_tau.cwiseAbs2();
    peak = std::max(peak, s.r_tau.norm());
  }
  rms = (rms / static_cast<double>(w.size())).cwiseSqrt();
  int link = 0;
  for (int j = 0; j < n; ++j)
    if (rms[j] >= kContactJointFraction * rms.maxCoeff()) link = j;
  model::DynamicsData d(m);
  Matrix6J J;
  double explained = 0.0, fmax = 0.0;
  for (const auto& s : w) {
    if (s.r_tau.norm() < kPulseFraction * peak) continue;
    model::forward_kinematics(m, d, s.q);
    // middle of the link: halfway to the next joint's origin (or the flange)
    const Eigen::Isometry3d& oMl = d.oMi[static_cast<size_t>(link)];
    const Eigen::Vector3d next = link + 1 < n ? d.oMi[static_cast<size_t>(link + 1)].translation() : d.oMf.translation();
    const Eigen::Vector3d p_local = oMl.inverse() * (0.5 * (oMl.translation() + next));
    model::point_jacobian(m, d, link, p_local, J);
    const Eigen::MatrixXd JT = J.topRows<3>().transpose();  // n x 3
    const Eigen::Vector3d F = JT.colPivHouseholderQr().solve(Eigen::VectorXd(s.r_tau));
    explained += (s.r_tau.squaredNorm() - (JT * F - s.r_tau).squaredNorm());
    fmax = std::max(fmax, F.norm());
  }
  Hypothesis h;
  h.fault = FaultClass::Collision;
  h.link = link;
  h.joint = link;
  h.explained = std::clamp(explained / total, 0.0, 1.0);
  h.magnitude = fmax;
  h.units = "N";
  h.detail = fmt::format("contact on link {} (moved by J{}), ≈ {:.1f} N", link + 1, link + 1, fmax);
  return h;
}

}  // namespace

void DiagnosisOptions::validate() const {
  if (!(collision_max_duration > 0.0))
    throw InvalidArgument(fmt::format("collision_max_duration is {}, must be > 0", collision_max_duration));
  if (frozen_samples < 2) throw InvalidArgument(fmt::format("frozen_samples is {}, must be >= 2", frozen_samples));
  if (!(min_explained >= 0.0 && min_explained <= 1.0))
    throw InvalidArgument(fmt::format("min_explained is {}, must be in [0, 1]", min_explained));
}

std::vector<Hypothesis> diagnose(const model::RobotModel& model, const std::vector<DiagnosisSample>& window,
                                 double alert_duration, int alert_joint, const DiagnosisOptions& options) {
  options.validate();
  std::vector<Hypothesis> out;
  if (window.empty()) {
    out.push_back({FaultClass::Unknown, alert_joint, -1, 0.0, "", 0.0, "empty diagnosis window"});
    return out;
  }
  const int n = model.n_dof();
  for (const auto& s : window) check_size("diagnosis sample r_tau", s.r_tau.size(), n, "model.n_dof");

  // stream fault: a gap inside the window explains itself
  int gaps = 0;
  for (const auto& s : window) gaps += s.gap_before ? 1 : 0;
  if (gaps > 0) {
    out.push_back({FaultClass::StreamFault, -1, -1, static_cast<double>(gaps), "gaps", 1.0,
                   fmt::format("{} gap(s) in the sample stream", gaps)});
  }
  // frozen channel: identical consecutive current values while the joint moves
  for (int j = 0; j < n; ++j) {
    int run = 1, best = 1;
    for (size_t k = 1; k < window.size(); ++k) {
      const bool same = window[k].current[j] == window[k - 1].current[j] && std::abs(window[k].qd[j]) > kMovingVelocity;
      run = same ? run + 1 : 1;
      best = std::max(best, run);
    }
    if (best >= options.frozen_samples)
      out.push_back({FaultClass::SensorFault, j, -1, static_cast<double>(best), "samples", 1.0,
                     fmt::format("current channel of J{} frozen for {} samples while the joint moves", j + 1, best)});
  }
  if (!out.empty()) return out;

  double total = 0.0;
  for (const auto& s : window) total += s.r_tau.squaredNorm();
  if (total <= 0.0) {
    out.push_back({FaultClass::Unknown, alert_joint, -1, 0.0, "", 0.0, "no residual energy in the window"});
    return out;
  }
  bool io_change = false;
  for (size_t k = 1; k < window.size(); ++k) io_change |= window[k].digital_outputs != window[k - 1].digital_outputs;

  // score every signature; parameters count as a small penalty
  std::vector<std::pair<double, Hypothesis>> scored;
  // shape: a collision is a pulse that has decayed by the end of the window; a payload change or
  // a resistance persists. Persistence = |mean of the last quarter| / peak on the dominant joint.
  int dom = 0;
  double peak_abs = 0.0;
  for (const auto& s : window)
    for (int j = 0; j < n; ++j)
      if (std::abs(s.r_tau[j]) > peak_abs) peak_abs = std::abs(s.r_tau[j]), dom = j;
  double tail = 0.0;
  const size_t q0 = window.size() - std::max<size_t>(1, window.size() / 4);
  for (size_t k = q0; k < window.size(); ++k) tail += window[k].r_tau[dom];
  tail = std::abs(tail) / static_cast<double>(window.size() - q0);
  const bool pulse = alert_duration < options.collision_max_duration && tail < kPersistentFraction * peak_abs;
  Hypothesis contact = contact_hypothesis(model, window, total);
  scored.emplace_back(contact.explained - (pulse ? 0.0 : 0.3), contact);
  Hypothesis payload = payload_hypothesis(model, window, total, options.payload_com);
  scored.emplace_back(payload.explained - kComplexityPenalty + (io_change ? 0.2 : 0.0) - (pulse ? 0.3 : 0.0), payload);
  for (int j = 0; j < n; ++j) {
    Hypothesis r = resistance_hypothesis(window, j, total);
    scored.emplace_back(r.explained - 2 * kComplexityPenalty - (pulse ? 0.3 : 0.0), r);
    Hypothesis o = offset_hypothesis(window, j, total);
    // without a velocity reversal a constant offset and a Coulomb resistance look alike; extra
    // torque that works against the motion is the common case (UR3e §2.3), so the offset only
    // wins when the joint reverses (or rests) inside the window
    // (each must hold for at least a tenth of the window to count)
    double pos = 0, neg = 0, rest = 0;
    for (const auto& smp : window) {
      if (smp.qd[j] > kMovingVelocity) ++pos;
      else if (smp.qd[j] < -kMovingVelocity) ++neg;
      else ++rest;
    }
    const double tenth = 0.1 * static_cast<double>(window.size());
    const double ambiguity = (pos > tenth && neg > tenth) || rest > tenth ? 0.0 : 0.25;
    scored.emplace_back(o.explained - kComplexityPenalty - ambiguity - (pulse ? 0.3 : 0.0), o);
  }
  std::stable_sort(scored.begin(), scored.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (auto& [score, h] : scored) out.push_back(h);
  if (out.front().explained < options.min_explained) {
    Hypothesis u;
    u.fault = FaultClass::Unknown;
    u.joint = alert_joint;
    u.explained = out.front().explained;
    u.detail = fmt::format("no signature explains the residual well (best: {} at {:.0f} %)",
                           to_string(out.front().fault), 100.0 * out.front().explained);
    out.insert(out.begin(), u);
  }
  return out;
}

MatrixJ residual_velocity_correlation(const std::vector<VectorJ>& residual, const std::vector<VectorJ>& qd) {
  if (residual.size() != qd.size() || residual.empty())
    throw InvalidArgument(fmt::format("correlation: {} residual samples and {} velocity samples, expected equal and > 0",
                                      residual.size(), qd.size()));
  const auto n = residual.front().size();
  const double K = static_cast<double>(residual.size());
  VectorJ mr = VectorJ::Zero(n), mv = VectorJ::Zero(n);
  for (size_t k = 0; k < residual.size(); ++k) {
    mr += residual[k];
    mv += qd[k];
  }
  mr /= K;
  mv /= K;
  MatrixJ cov = MatrixJ::Zero(n, n);
  VectorJ vr = VectorJ::Zero(n), vv = VectorJ::Zero(n);
  for (size_t k = 0; k < residual.size(); ++k) {
    const VectorJ a = residual[k] - mr, b = qd[k] - mv;
    cov += a * b.transpose();
    vr += a.cwiseAbs2();
    vv += b.cwiseAbs2();
  }
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) {
      const double den = std::sqrt(vr[i] * vv[j]);
      cov(i, j) = den > 0.0 ? cov(i, j) / den : 0.0;
    }
  return cov;
}

}  // namespace twinwatch::monitor
