#include "twinwatch/ident/learned_ident.hpp"

#include <fmt/format.h>

#include <cmath>

#include "twinwatch/core/error.hpp"
#include "twinwatch/signal/metrics.hpp"
#include "twinwatch/signal/savitzky_golay.hpp"

namespace twinwatch::ident {

namespace {
// share of the progress bar taken by the physics step (one pass of least squares, fast)
constexpr double kPhysicsShare = 0.1;
}  // namespace

void LearnedIdentOptions::validate() const {
  mlp.validate();
  inputs.validate();
  physics.validate();
  if (sg_window != 0) {
    if (sg_window < 3 || sg_window % 2 == 0) throw InvalidArgument(fmt::format("sg_window is {}, must be 0 (off) or odd and >= 3", sg_window));
    if (sg_order < 0 || sg_order >= sg_window)
      throw InvalidArgument(fmt::format("sg_order is {}, must be in [0, sg_window = {})", sg_order, sg_window));
  }
  if (decimate < 1) throw InvalidArgument(fmt::format("decimate is {}, must be >= 1", decimate));
}

LearnedIdentOptions LearnedIdentOptions::defaults(const std::string& method) {
  LearnedIdentOptions o;
  if (method == "mlp") return o;  // UR3e §3.5: q and SG-smoothed qd, one hidden layer of 15 ReLU units
  if (method == "hybrid") {
    // velocity features only, strongly regularised (docs/validation.md, "Learned reference"):
    // with q as input the network memorises the training programs' configurations and its
    // correction hurts an untrained path (triangle J4 0.035 -> 0.075 A); qdd extrapolates badly
    // (a faster program reaches 1.5-2x the trained accelerations); temperature moves by < 0.5 °C
    // in these runs. What transfers is a friction-like function of the joint velocities.
    o.inputs.q = false;
    o.inputs.friction_shape = true;
    o.mlp.l2 = 1e-2;
    return o;
  }
  throw InvalidArgument(fmt::format("learned method '{}': expected 'mlp' or 'hybrid'", method));
}

TwinModel identify_learned(const std::string& robot, const std::vector<TrainingRun>& runs, LearnedRole role,
                           const LearnedIdentOptions& o, LearnedIdentReport& report, const std::function<void(double)>& progress) {
  o.validate();
  report = LearnedIdentReport{};
  // physics twin first (the hybrid's base; the mlp twin's drive gains)
  TwinModel twin = identify_physics(robot, runs, o.physics, report.physics, [&](double f) {
    if (progress) progress(kPhysicsShare * f);
  });
  const int n = twin.n_dof();
  for (const TrainingRun& r : runs)
    if (o.sg_window > 0 && static_cast<int>(r.recording->samples.size()) < o.sg_window)
      throw InvalidArgument(fmt::format("{}: {} samples, shorter than the Savitzky-Golay window ({})", r.recording->path,
                                        r.recording->samples.size(), o.sg_window));

  // training set: features from (q, SG-smoothed qd, qdd, T); target i (mlp) or i - i_phys (hybrid)
  long N = 0;
  for (const TrainingRun& r : runs) N += static_cast<long>((r.recording->samples.size() + o.decimate - 1) / o.decimate);
  const int n_in = o.inputs.count(n);
  Eigen::MatrixXd X(n_in, N), Y(n, N), I(n, N), P(n, N);  // I measured, P physics prediction
  std::vector<Eigen::Index> ends;
  Eigen::Index col = 0;
  VectorJ tau, i_phys;
  for (const TrainingRun& r : runs) {
    const device::Recording& rec = *r.recording;
    const std::vector<VectorJ> qdd = joint_accelerations(rec, twin.acceleration_half_width(rec.median_period));
    const size_t K = rec.samples.size();
    // zero-phase smoothing of each joint's velocity [UR3e §3.5]
    std::vector<std::vector<double>> qd_s(static_cast<size_t>(n), std::vector<double>(K));
    for (int j = 0; j < n; ++j) {
      for (size_t k = 0; k < K; ++k) qd_s[static_cast<size_t>(j)][k] = rec.samples[k].qd[j];
      if (o.sg_window > 0) {
        const double dt = K > 1 ? (rec.samples.back().timestamp - rec.samples.front().timestamp) / static_cast<double>(K - 1) : 1.0;
        const signal::SavitzkyGolay sg{o.sg_window, o.sg_order, 0, dt > 0 ? dt : 1.0};
        qd_s[static_cast<size_t>(j)] = sg.apply(qd_s[static_cast<size_t>(j)]);
      }
    }
    twin.set_payload(r.payload);
    ident::FrictionMemory memory;  // advanced over every sample, used on the kept ones
    for (size_t k = 0; k < K; ++k) {
      const RobotSample& s = rec.samples[k];
      twin.advance(memory, s, qdd[k]);
      if (k % static_cast<size_t>(o.decimate) != 0) continue;
      VectorJ qd = s.qd;
      for (int j = 0; j < n; ++j) qd[j] = qd_s[static_cast<size_t>(j)][k];
      o.inputs.build(s.q, qd, qdd[k], s.temperature, o.physics.temperature_ref, X.col(col).data());
      twin.predict_current(s.q, s.qd, qdd[k], s.temperature, i_phys, &memory);
      I.col(col) = s.current.head(n);
      P.col(col) = i_phys.head(n);
      Y.col(col) = role == LearnedRole::Current ? I.col(col) : Eigen::VectorXd(I.col(col) - P.col(col));
      ++col;
    }
    ends.push_back(col);
  }
  twin.set_payload(model::RigidBodyInertia{});
  if (!X.allFinite()) throw InvalidArgument("identify: a recording has NaN positions, velocities or temperatures in the training samples");
  if (!I.allFinite()) throw InvalidArgument("identify: a recording has NaN motor currents in the training samples");

  // the network
  Mlp net(n_in, n, o.mlp);
  report.fit = net.fit(X, Y, ends, [&](double f) {
    if (progress) progress(kPhysicsShare + (1.0 - kPhysicsShare) * f);
  });
  report.samples = N;

  // the whole twin's fit: on all samples, and on the held-out blocks alone
  const Eigen::MatrixXd out = net.predict(X);
  const Eigen::MatrixXd Ihat = role == LearnedRole::Current ? out : Eigen::MatrixXd(P + out);
  std::vector<bool> held(static_cast<size_t>(N), false);
  for (size_t s = 0; s < ends.size(); ++s) {
    const Eigen::Index begin = s == 0 ? 0 : ends[s - 1];
    const auto nv = static_cast<Eigen::Index>(std::floor(o.mlp.validation_fraction * static_cast<double>(ends[s] - begin)));
    for (Eigen::Index k = ends[s] - nv; k < ends[s]; ++k) held[static_cast<size_t>(k)] = true;
  }
  for (int j = 0; j < n; ++j) {
    std::vector<double> m(static_cast<size_t>(N)), p(static_cast<size_t>(N)), mv, pv;
    for (Eigen::Index k = 0; k < N; ++k) {
      m[static_cast<size_t>(k)] = I(j, k);
      p[static_cast<size_t>(k)] = Ihat(j, k);
      if (held[static_cast<size_t>(k)]) mv.push_back(I(j, k)), pv.push_back(Ihat(j, k));
    }
    const signal::FitMetrics fm = signal::fit_metrics(m, p);
    report.rmse.push_back(fm.rmse);
    report.r2.push_back(fm.r2);
    report.validation_rmse.push_back(mv.empty() ? std::nan("") : signal::fit_metrics(mv, pv).rmse);
    twin.joints[static_cast<size_t>(j)].rmse = fm.rmse;
    twin.joints[static_cast<size_t>(j)].r2 = fm.r2;
  }

  LearnedModel lm;
  lm.role = role;
  lm.inputs = o.inputs;
  lm.net = std::move(net);
  lm.temperature_ref = o.physics.temperature_ref;
  lm.sg_window = o.sg_window;
  lm.sg_order = o.sg_order;
  lm.validation_rmse = report.validation_rmse;
  twin.learned = std::move(lm);
  twin.method = role == LearnedRole::Current ? "mlp" : "hybrid";
  if (role == LearnedRole::Current && !twin.gains_known())
    report.physics.notes.push_back("mlp method without a known payload: the twin predicts currents only (its torque uses relative gains)");
  if (progress) progress(1.0);
  return twin;
}

}  // namespace twinwatch::ident
