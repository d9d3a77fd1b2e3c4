#include "twinwatch/friction/protocol.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "twinwatch/core/error.hpp"
#include "twinwatch/friction/synthetic_joint.hpp"

namespace twinwatch::friction {

namespace {

double rmse(std::span<const double> y, std::span<const double> yhat, const std::vector<char>* mask = nullptr) {
  double s = 0.0;
  long n = 0;
  for (std::size_t k = 0; k < y.size(); ++k) {
    if (mask && !(*mask)[k]) continue;
    s += (y[k] - yhat[k]) * (y[k] - yhat[k]);
    ++n;
  }
  return n ? std::sqrt(s / static_cast<double>(n)) : std::numeric_limits<double>::quiet_NaN();
}

void say(const ProtocolOptions& o, std::string_view msg) {
  if (o.progress) o.progress(msg);
}

/// The study data: every record decoupled by `rigid`, the chirp frequency given or estimated.
FrictionStudyData residual_data(const ProtocolRecords& r, const RigidBodyFit& rigid, const std::vector<double>& chirp_f) {
  FrictionStudyData d;
  d.joint = r.joint;
  d.train = rigid.residual(r.train);
  d.fourier = rigid.residual(r.fourier);
  if (r.chirp.size() > 0) d.chirp = rigid.residual(r.chirp);
  d.chirp_frequency = chirp_f;
  return d;
}

JointRecord smoothed(const JointRecord& r, int window) {
  JointRecord s = r;
  if (r.size() == 0) return s;
  s.qd = moving_average(r.qd, window);
  s.tau = moving_average(r.tau, window);
  return s;
}

RigidBodyFit fit_on(const ProtocolRecords& r, const RigidBodyFitOptions& o) {
  std::vector<const JointRecord*> recs{&r.train, &r.fourier};
  if (r.chirp.size() > 0) recs.push_back(&r.chirp);
  return fit_rigid_body(recs, o);
}

}  // namespace

void ProtocolOptions::validate() const {
  study.validate();
  rigid.validate();
  for (std::size_t i = 0; i < screening_thresholds.size(); ++i)
    if (!std::isfinite(screening_thresholds[i]) || screening_thresholds[i] < 0.0)
      throw InvalidArgument(fmt::format("protocol screening_thresholds[{}] is {}, must be >= 0 [rad/s]", i,
                                        screening_thresholds[i]));
  for (std::size_t i = 0; i < smoothing_windows.size(); ++i)
    if (smoothing_windows[i] < 1 || smoothing_windows[i] % 2 == 0)
      throw InvalidArgument(fmt::format("protocol smoothing_windows[{}] is {}, must be an odd number >= 1", i,
                                        smoothing_windows[i]));
  for (std::size_t i = 0; i < uncertainty_levels.size(); ++i)
    if (!std::isfinite(uncertainty_levels[i]) || uncertainty_levels[i] < 0.0)
      throw InvalidArgument(fmt::format("protocol uncertainty_levels[{}] is {}, must be >= 0", i, uncertainty_levels[i]));
  if (trials < 1) throw InvalidArgument(fmt::format("protocol trials is {}, must be >= 1", trials));
}

std::vector<double> frequency_from_reversals(std::span<const double> qd, double dt, double threshold) {
  // reversal instants: sign changes after an excursion beyond the threshold
  std::vector<long> at;
  int armed = 0;
  for (std::size_t k = 0; k < qd.size(); ++k) {
    const double v = qd[k];
    if (armed != 0 && armed * v < 0.0) {
      at.push_back(static_cast<long>(k));
      armed = 0;
    }
    if (armed == 0 && std::abs(v) > threshold) armed = v > 0.0 ? 1 : -1;
  }
  if (at.size() < 2)
    throw InvalidArgument(fmt::format("chirp record has {} velocity reversals (|qd| > {} rad/s), expected at least 2 "
                                      "to estimate its frequency",
                                      at.size(), threshold));
  std::vector<double> f(qd.size());
  // half a period between consecutive reversals, placed at the interval's midpoint; linear
  // between midpoints, held before the first and after the last
  std::vector<double> mid, fi;
  for (std::size_t i = 0; i + 1 < at.size(); ++i) {
    mid.push_back(0.5 * static_cast<double>(at[i] + at[i + 1]));
    fi.push_back(1.0 / (2.0 * static_cast<double>(at[i + 1] - at[i]) * dt));
  }
  std::size_t i = 0;
  for (std::size_t k = 0; k < f.size(); ++k) {
    const auto x = static_cast<double>(k);
    while (i + 1 < mid.size() && mid[i + 1] <= x) ++i;
    if (x <= mid.front()) f[k] = fi.front();
    else if (i + 1 >= mid.size()) f[k] = fi.back();
    else f[k] = fi[i] + (fi[i + 1] - fi[i]) * (x - mid[i]) / (mid[i + 1] - mid[i]);
  }
  return f;
}

ProtocolResult run_hesr_protocol(const ProtocolRecords& r, const ProtocolOptions& o) {
  o.validate();
  r.train.validate(r.joint + " train");
  r.fourier.validate(r.joint + " fourier");
  if (r.chirp.size() > 0) r.chirp.validate(r.joint + " chirp");
  std::vector<double> chirp_f = r.chirp_frequency;
  if (r.chirp.size() > 0 && chirp_f.empty())
    chirp_f = frequency_from_reversals(r.chirp.qd, r.chirp.dt, o.study.reversal_threshold);
  check_size("chirp_frequency", static_cast<long>(chirp_f.size()), r.chirp.size(), "size of chirp.q");
  ProtocolResult out;
  // 1. nominal decoupling and the model comparison (Tables VIII, IX, chirp, VI)
  say(o, fmt::format("{}: rigid-body decoupling (screening {} rad/s)", r.joint, o.rigid.reversal_threshold));
  out.rigid = fit_on(r, o.rigid);
  const FrictionStudyData data = residual_data(r, out.rigid, chirp_f);
  say(o, fmt::format("{}: fitting LuGre, Stribeck, RBFNN, RBFNN-H, ParFam-V, ParFam-H", r.joint));
  out.study = run_friction_study(data, o.study);
  // 2. Table III: the rigid-body fit at each screening threshold
  for (double th : o.screening_thresholds) {
    RigidBodyFitOptions ro = o.rigid;
    ro.reversal_threshold = th;
    const RigidBodyFit f = fit_on(r, ro);
    out.screening.push_back({th, f.samples, f.rank, f.rmse_all, f.rmse_retained, f.log10_condition});
  }
  // 3. Table IV: ParFam-H re-identified after smoothing every record
  const ModelStudy& ph = out.study.model("ParFam-H");
  out.smoothing.push_back({1, ph.fourier_rmse, ph.reversal_rmse, out.study.reversal_samples});
  for (int w : o.smoothing_windows) {
    say(o, fmt::format("{}: smoothing window {}: decoupling and ParFam-H again", r.joint, w));
    ProtocolRecords s = r;
    s.train = smoothed(r.train, w);
    s.fourier = smoothed(r.fourier, w);
    s.chirp = smoothed(r.chirp, w);
    const RigidBodyFit rf = fit_on(s, o.rigid);
    const FrictionStudyData sd = residual_data(s, rf, chirp_f);
    ParFamOptions po = o.study.parfam;
    po.input = ParFamInput::Hysteresis;
    ParFamModel m(po);
    try {
      m.fit(sd.train);
    } catch (const InvalidArgument&) {
      // no reversal for Stage 1: the same fallback as the study (defaults, refined by Stage 3)
      po.hysteresis = po.prior.fallback();
      m = ParFamModel(po);
      m.fit(sd.train);
    }
    SmoothingRow row;
    row.window = w;
    if (m.fitted()) {
      int reversals = 0;
      const std::vector<char> rev = reversal_window_mask(sd.fourier.qd, sd.fourier.dt, o.study.reversal_window,
                                                         o.study.reversal_threshold, &reversals);
      for (char c : rev) row.reversal_samples += c;
      const std::vector<double> p = m.predict(sd.fourier);
      row.fourier_rmse = rmse(sd.fourier.tau, p);
      row.reversal_rmse = rmse(sd.fourier.tau, p, &rev);
    } else {
      row.fourier_rmse = row.reversal_rmse = std::numeric_limits<double>::quiet_NaN();
    }
    out.smoothing.push_back(row);
  }
  // 4. Table V: Monte Carlo perturbation of the validation residual (eq. 17), models fixed
  say(o, fmt::format("{}: Monte Carlo, {} trials per level", r.joint, o.trials));
  const std::vector<char> rev = reversal_window_mask(data.fourier.qd, data.fourier.dt, o.study.reversal_window,
                                                     o.study.reversal_threshold);
  double tau_rms = 0.0;
  for (double t : data.fourier.tau) tau_rms += t * t;
  tau_rms = std::sqrt(tau_rms / static_cast<double>(data.fourier.tau.size()));
  int ph_index = -1;
  for (std::size_t i = 0; i < out.study.models.size(); ++i)
    if (out.study.models[i].name == "ParFam-H") ph_index = static_cast<int>(i);
  out.uncertainty.push_back({0.0, ph.fourier_rmse, 0.0, ph.reversal_rmse, 0.0, 0.0});
  {
    bool first = true;
    for (const ModelStudy& m : out.study.models)
      if (m.model && m.name != "ParFam-H" && m.reversal_rmse <= ph.reversal_rmse) first = false;
    out.uncertainty.front().first_share = first ? 1.0 : 0.0;
  }
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<double> tau_mc(data.fourier.tau.size());
  for (double level : o.uncertainty_levels) {
    double f_sum = 0.0, f_sq = 0.0, r_sum = 0.0, r_sq = 0.0;
    int firsts = 0;
    for (int t = 0; t < o.trials; ++t) {
      // tau_f^mc = (1 + s) tau_f + eps
      const double s = level * gauss(rng);
      for (std::size_t k = 0; k < tau_mc.size(); ++k) tau_mc[k] = (1.0 + s) * data.fourier.tau[k] + level * tau_rms * gauss(rng);
      double best_other = std::numeric_limits<double>::infinity(), ph_rev = 0.0, ph_all = 0.0;
      for (std::size_t i = 0; i < out.study.models.size(); ++i) {
        const ModelStudy& m = out.study.models[i];
        if (!m.model) continue;
        const double rr = rmse(tau_mc, m.fourier_prediction, &rev);
        if (static_cast<int>(i) == ph_index) {
          ph_rev = rr;
          ph_all = rmse(tau_mc, m.fourier_prediction);
        } else {
          best_other = std::min(best_other, rr);
        }
      }
      f_sum += ph_all;
      f_sq += ph_all * ph_all;
      r_sum += ph_rev;
      r_sq += ph_rev * ph_rev;
      firsts += ph_rev < best_other;
    }
    const double n = o.trials;
    UncertaintyRow row;
    row.level = level;
    row.fourier_mean = f_sum / n;
    // (a spread of NaN, not 0, when a trial had nothing to score: std::max(0.0, NaN) is 0)
    const auto spread = [n](double mean, double sq) {
      return std::isfinite(mean) ? std::sqrt(std::max(0.0, sq / n - mean * mean)) : std::numeric_limits<double>::quiet_NaN();
    };
    row.fourier_std = spread(row.fourier_mean, f_sq);
    row.reversal_mean = r_sum / n;
    row.reversal_std = spread(row.reversal_mean, r_sq);
    row.first_share = firsts / n;
    out.uncertainty.push_back(row);
  }
  return out;
}

SimulatedRigidBody simulated_rigid_body(const SimulatedJoint& joint) {
  // in the spirit of a base, shoulder and elbow joint
  return joint.name == "J1"   ? SimulatedRigidBody{0.45, 0.0, 0.0, 0.3}
         : joint.name == "J2" ? SimulatedRigidBody{0.60, -22.0, 2.5, -0.4}
                              : SimulatedRigidBody{0.20, -7.0, 0.8, 0.2};
}

ProtocolRecords simulated_protocol_records(const SimulatedJoint& joint, unsigned seed, TrainingExcitation training) {
  const SimulatedRigidBody rb = simulated_rigid_body(joint);
  // the same profiles and seeds as simulated_study_data()
  constexpr double kDuration = 20.0, kVelocity = 1.2, kFourierBase = 0.1;
  constexpr int kHarmonics = 5;
  SyntheticJointOptions o;
  o.torque_noise = joint.torque_noise;
  const auto make = [&](const VelocityProfile& p, unsigned s, std::vector<double>* freq) {
    o.seed = s;
    SyntheticRecord sr = simulate_joint(joint.truth, p, o);
    JointRecord jr;
    jr.dt = sr.record.dt;
    jr.q = sr.q;
    jr.qd = sr.record.qd;
    jr.tau.resize(sr.q.size());
    // measured torque: rigid body at the true state plus the noisy friction measurement
    for (std::size_t k = 0; k < jr.tau.size(); ++k)
      jr.tau[k] = rb.inertia * sr.true_qdd[k] + rb.gravity_sin * std::sin(sr.true_q[k]) +
                  rb.gravity_cos * std::cos(sr.true_q[k]) + rb.offset +
                  sr.record.tau[k];
    if (freq) *freq = sr.frequency;
    return jr;
  };
  ProtocolRecords r;
  r.joint = joint.name;
  r.train = make(training_profile(training, seed), seed * 3 + 1, nullptr);
  r.fourier = make(fourier_profile(kHarmonics, kFourierBase, kVelocity, kDuration, seed), seed * 3 + 2, nullptr);
  r.chirp = make(chirp_profile(0.1, 1.0, kVelocity, kDuration), seed * 3 + 3, &r.chirp_frequency);
  return r;
}

}  // namespace twinwatch::friction
