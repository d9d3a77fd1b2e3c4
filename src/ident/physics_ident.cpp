#include "twinwatch/ident/physics_ident.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
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
// half-width of the centred moving average applied to qd before differentiating [samples]
constexpr int kSmoothHalfWidth = 3;

std::string now_iso() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}
}  // namespace

void IdentOptions::validate() const {
  if (!(reversal_screen >= 0.0)) throw InvalidArgument(fmt::format("reversal_screen is {}, must be >= 0", reversal_screen));
  if (efficiency_passes < 0) throw InvalidArgument(fmt::format("efficiency_passes is {}, must be >= 0", efficiency_passes));
  if (decimate < 1) throw InvalidArgument(fmt::format("decimate is {}, must be >= 1", decimate));
}

std::vector<VectorJ> joint_accelerations(const device::Recording& rec) {
  const size_t N = rec.samples.size();
  std::vector<VectorJ> out(N);
  if (rec.present & kFieldTargetQdd) {
    for (size_t k = 0; k < N; ++k) out[k] = rec.samples[k].target_qdd;
    return out;
  }
  // zero-phase: centred moving average of qd, then central differences on the time axis
  const int n = rec.n_dof;
  std::vector<VectorJ> qs(N);
  for (size_t k = 0; k < N; ++k) {
    VectorJ acc = VectorJ::Zero(n);
    int cnt = 0;
    for (long m = static_cast<long>(k) - kSmoothHalfWidth; m <= static_cast<long>(k) + kSmoothHalfWidth; ++m) {
      if (m < 0 || m >= static_cast<long>(N)) continue;
      const RobotSample& s = rec.samples[static_cast<size_t>(m)];
      acc += (rec.present & kFieldActualQd) ? s.qd : VectorJ::Zero(n);
      ++cnt;
    }
    qs[k] = acc / cnt;
  }
  for (size_t k = 0; k < N; ++k) {
    const size_t a = k == 0 ? 0 : k - 1, b = std::min(N - 1, k + 1);
    const double dt = rec.samples[b].timestamp - rec.samples[a].timestamp;
    out[k] = dt > 0 ? VectorJ((qs[b] - qs[a]) / dt) : VectorJ(VectorJ::Zero(n));
  }
  return out;
}

TwinModel identify_physics(const std::string& robot, const std::vector<TrainingRun>& runs, const IdentOptions& o,
                           IdentReport& report, const std::function<void(double)>& progress) {
  o.validate();
  if (runs.empty()) throw InvalidArgument("identify: no recordings given");
  const model::RobotModel rm = model::load_robot(robot);
  const int n = rm.n_dof();
  long total = 0;
  for (const TrainingRun& r : runs) {
    if (r.recording->n_dof != n)
      throw InvalidArgument(fmt::format("{}: {} joints, but robot '{}' has {}", r.recording->path, r.recording->n_dof, robot, n));
    if (!(r.recording->present & kFieldActualCurrent))
      throw InvalidArgument(fmt::format("{}: no actual_current_* columns: the current-domain twin needs motor currents",
                                        r.recording->path));
    total += static_cast<long>(r.recording->samples.size());
  }
  if (total < 200) throw InvalidArgument(fmt::format("identify: {} samples in all, expected at least 200", total));

  TwinModel twin(robot, rm);
  twin.temperature_ref = o.temperature_ref;
  twin.created = now_iso();
  for (const TrainingRun& r : runs) twin.recordings.push_back(r.recording->path);
  const model::BaseParameters base = model::compute_base_parameters(rm);
  twin.base_columns = base.independent;
  const int nb = base.rank;
  const int nf = kFrictionColumns;
  const int p = nb + nf * n;  // unknowns of the torque-domain linear step
  twin.beta = Eigen::VectorXd::Zero(nb);
  twin.joints.assign(static_cast<size_t>(n), JointDrive{});
  bool any_payload = false;
  for (const auto& r : runs) any_payload |= r.payload.mass > 0.0;

  std::vector<std::vector<VectorJ>> qdds;
  for (const TrainingRun& r : runs) qdds.push_back(joint_accelerations(*r.recording));

  // sufficient statistics of one pass over the data: the linear step in (beta, friction) and the
  // per-joint gain step only need these sums, so the alternating least squares of the bilinear
  // model  g_j i_j / c_jk = r_jk . theta + tau_payload_jk  runs without revisiting the samples
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(p);
  model::RegressorMatrix Y;
  VectorJ tau_p;
  Eigen::VectorXd r(p);
  Eigen::Matrix<double, kFrictionColumns, 1> f;
  const int passes = 1 + o.efficiency_passes;
  report = IdentReport{};
  report.samples_used.assign(static_cast<size_t>(n), 0);
  report.rmse.assign(static_cast<size_t>(n), 0.0);
  report.r2.assign(static_cast<size_t>(n), 0.0);
  for (int pass = 0; pass <= passes; ++pass) {
    const bool final_stats = pass == passes;
    std::vector<Eigen::MatrixXd> A(static_cast<size_t>(n), Eigen::MatrixXd::Zero(p, p));
    std::vector<Eigen::VectorXd> cp(static_cast<size_t>(n), Eigen::VectorXd::Zero(p));
    std::vector<Eigen::VectorXd> b(static_cast<size_t>(n), Eigen::VectorXd::Zero(p));
    std::vector<double> d(static_cast<size_t>(n), 0.0), e(static_cast<size_t>(n), 0.0), pp(static_cast<size_t>(n), 0.0);
    std::vector<double> gen_num(static_cast<size_t>(n), 0.0), gen_den(static_cast<size_t>(n), 0.0);
    std::vector<double> sse(static_cast<size_t>(n), 0.0), si(static_cast<size_t>(n), 0.0), si2(static_cast<size_t>(n), 0.0);
    std::vector<long> cnt(static_cast<size_t>(n), 0);
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
          JointDrive& jd = twin.joints[static_cast<size_t>(j)];
          r.setZero();
          for (int c = 0; c < nb; ++c) r(c) = Y(j, twin.base_columns[static_cast<size_t>(c)]);
          twin.friction_row(j, s.qd, qdd, s.temperature, f);
          r.segment(nb + nf * j, nf) = f;
          const double i = s.current[j];
          // the previous pass's torque decides the drive direction (first pass: motoring)
          const double tau_hat = r.dot(theta) + tau_p[j];
          const bool gen = pass > 0 && tau_hat * s.qd[j] < 0.0;
          const double c = gen ? jd.c_gen : 1.0;
          if (final_stats) {
            const double err = i - c * tau_hat / jd.gain;
            sse[static_cast<size_t>(j)] += err * err;
            si[static_cast<size_t>(j)] += i;
            si2[static_cast<size_t>(j)] += i * i;
            ++cnt[static_cast<size_t>(j)];
            continue;
          }
          if (gen) {
            gen_num[static_cast<size_t>(j)] += i * tau_hat / jd.gain;
            gen_den[static_cast<size_t>(j)] += (tau_hat / jd.gain) * (tau_hat / jd.gain);
          }
          const double w = i / c;  // current as the motoring drive would draw it
          A[static_cast<size_t>(j)].selfadjointView<Eigen::Lower>().rankUpdate(r);
          b[static_cast<size_t>(j)] += r * w;
          cp[static_cast<size_t>(j)] += r * tau_p[j];
          d[static_cast<size_t>(j)] += w * tau_p[j];
          e[static_cast<size_t>(j)] += w * w;
          pp[static_cast<size_t>(j)] += tau_p[j] * tau_p[j];
        }
        if (progress && (++done % 20000) == 0)
          progress((pass + static_cast<double>(done) * o.decimate / static_cast<double>(total)) / (passes + 1));
      }
    }
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
    for (int j = 0; j < n; ++j) A[static_cast<size_t>(j)] = A[static_cast<size_t>(j)].selfadjointView<Eigen::Lower>();
    std::vector<double> h(static_cast<size_t>(n));
    for (int j = 0; j < n; ++j) h[static_cast<size_t>(j)] = 1.0 / twin.joints[static_cast<size_t>(j)].gain;
    auto sse_of = [&](const Eigen::VectorXd& th, const std::vector<double>& hh) {
      double sum = 0.0;
      for (int j = 0; j < n; ++j) {
        const size_t J = static_cast<size_t>(j);
        const double num = b[J].dot(th) + d[J];
        const double den = th.dot(A[J] * th) + 2.0 * th.dot(cp[J]) + pp[J];
        sum += e[J] - 2.0 * hh[J] * num + hh[J] * hh[J] * den;
      }
      return sum;
    };
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
    double mu = 1e-3, obj = sse_of(theta, h);
    for (int it = 0; it < 100; ++it) {
      const int m = p + n;
      Eigen::MatrixXd H = Eigen::MatrixXd::Zero(m, m);
      Eigen::VectorXd grad = Eigen::VectorXd::Zero(m);  // half gradient of the SSE
      for (int j = 0; j < n; ++j) {
        const size_t J = static_cast<size_t>(j);
        const Eigen::VectorXd At = A[J] * theta + cp[J];  // sum r tau_hat
        const double num = b[J].dot(theta) + d[J];
        const double den = theta.dot(At) + theta.dot(cp[J]) + pp[J];
        H.topLeftCorner(p, p) += h[J] * h[J] * A[J];
        H.block(0, p + j, p, 1) = h[J] * At;
        H.block(p + j, 0, 1, p) = h[J] * At.transpose();
        H(p + j, p + j) = den;
        grad.head(p) += -h[J] * b[J] + h[J] * h[J] * At;
        grad(p + j) = -num + h[J] * den;
      }
      const Eigen::VectorXd D = H.diagonal().cwiseMax(1e-300).cwiseSqrt();
      bool accepted = false;
      for (int tries = 0; tries < 20 && !accepted; ++tries) {
        Eigen::MatrixXd Hs = D.asDiagonal().inverse() * H * D.asDiagonal().inverse();
        Hs.diagonal().array() += mu + kRidge;
        const Eigen::VectorXd step = -(D.asDiagonal().inverse() * Hs.ldlt().solve(D.asDiagonal().inverse() * grad));
        Eigen::VectorXd th2 = theta + step.head(p);
        std::vector<double> h2 = h;
        for (int j = 0; j < n; ++j) h2[static_cast<size_t>(j)] += step(p + j);
        if (!any_payload) {
          // no absolute scale: keep prod g = 1 (h and theta trade along the flat direction)
          double lh = 0.0;
          bool ok = true;
          for (double v : h2) ok &= v > 0.0, lh += std::log(std::abs(v));
          if (ok) {
            const double sc = std::exp(lh / n);
            for (double& v : h2) v /= sc;
            th2 *= sc;
          }
        }
        // drive gains are positive: a step that flips one is rejected like a worse one
        bool positive = true;
        for (double v : h2) positive &= v > 0.0;
        const double obj2 = positive ? sse_of(th2, h2) : std::numeric_limits<double>::infinity();
        if (obj2 <= obj) {
          const double gain = obj - obj2;
          theta = th2;
          h = h2;
          obj = obj2;
          mu = std::max(mu / 3.0, 1e-9);
          accepted = true;
          if (gain < 1e-12 * std::max(obj, 1e-30)) it = 100;  // converged
        } else {
          mu *= 5.0;
        }
      }
      if (!accepted) break;
    }
    std::vector<double> g(static_cast<size_t>(n));
    for (int j = 0; j < n; ++j) g[static_cast<size_t>(j)] = 1.0 / h[static_cast<size_t>(j)];
    for (int j = 0; j < n; ++j) twin.joints[static_cast<size_t>(j)].gain = g[static_cast<size_t>(j)];
    twin.beta = theta.head(nb);
    for (int j = 0; j < n; ++j) twin.joints[static_cast<size_t>(j)].friction = theta.segment(nb + nf * j, nf);
  }
  twin.gains_absolute = any_payload;
  for (const auto& jd : twin.joints)
    if (!(jd.gain > 0.0)) throw InvalidArgument("identify: a drive gain came out <= 0; the recordings do not excite that joint enough");
  if (!any_payload)
    report.notes.push_back("no recording with a known payload: current-to-torque gains are relative (torque outputs disabled); "
                           "add one with --known-payload FILE=MASS,CX,CY,CZ");
  twin.set_payload(model::RigidBodyInertia{});
  if (progress) progress(1.0);
  return twin;
}

}  // namespace twinwatch::ident
