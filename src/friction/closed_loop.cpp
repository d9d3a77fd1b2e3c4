#include "twinwatch/friction/closed_loop.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <random>

#include "twinwatch/core/error.hpp"
#include "twinwatch/friction/protocol.hpp"
#include "twinwatch/friction/study.hpp"
#include "twinwatch/signal/savitzky_golay.hpp"

namespace twinwatch::friction {

namespace {

void check_positive(const char* what, double v) {
  if (!std::isfinite(v) || v <= 0.0) throw InvalidArgument(fmt::format("closed-loop {} is {}, must be > 0", what, v));
}

void check_nonnegative(const char* what, double v) {
  if (!std::isfinite(v) || v < 0.0) throw InvalidArgument(fmt::format("closed-loop {} is {}, must be >= 0", what, v));
}

}  // namespace

double AdaptivePdGains::kp(double qd_d) const noexcept {
  return kp_min + (kp_max - kp_min) * std::exp(-lambda * std::abs(qd_d));
}

double AdaptivePdGains::kd(double qd_d) const noexcept {
  return kd_min + (kd_max - kd_min) * std::exp(-lambda * std::abs(qd_d));
}

void AdaptivePdGains::validate() const {
  check_nonnegative("gains.kp_min", kp_min);
  check_nonnegative("gains.kp_max", kp_max);
  check_nonnegative("gains.kd_min", kd_min);
  check_nonnegative("gains.kd_max", kd_max);
  check_nonnegative("gains.lambda", lambda);
  if (kp_min > kp_max) throw InvalidArgument(fmt::format("closed-loop gains.kp_min is {}, must be <= kp_max ({})", kp_min, kp_max));
  if (kd_min > kd_max) throw InvalidArgument(fmt::format("closed-loop gains.kd_min is {}, must be <= kd_max ({})", kd_min, kd_max));
}

void ClosedLoopOptions::validate() const {
  check_positive("inertia", inertia);
  check_positive("model_inertia", model_inertia);
  check_positive("kv", kv);
  check_nonnegative("ki", ki);
  check_positive("dt", dt);
  if (substeps < 1) throw InvalidArgument(fmt::format("closed-loop substeps is {}, must be >= 1", substeps));
  check_nonnegative("torque_noise", torque_noise);
  check_positive("derivative_filter", derivative_filter);
  check_nonnegative("torque_filter", torque_filter);
  check_positive("reversal_window", reversal_window);
  check_positive("segment", segment);
  gains.validate();
}

ClosedLoopRun run_closed_loop(const MaxwellSlipParams& truth, const VelocityProfile& desired, FrictionModel* model,
                              const ClosedLoopOptions& o, bool feedforward, const MaxwellSlipFriction* plant_start) {
  o.validate();
  if (!desired.qd) throw InvalidArgument(fmt::format("desired profile '{}' has no qd(t)", desired.name));
  if (!std::isfinite(desired.duration) || desired.duration <= o.dt)
    throw InvalidArgument(fmt::format("desired profile '{}' duration is {}, must be > dt ({})", desired.name,
                                      desired.duration, o.dt));
  if (plant_start && plant_start->params() != truth)
    throw InvalidArgument("closed-loop plant_start is the state of another joint (its Maxwell-slip parameters differ from the truth's)");
  MaxwellSlipFriction plant_friction = plant_start ? *plant_start : MaxwellSlipFriction(truth);
  // the truth along qd_d, from the same state: scores f_hat (evaluation only)
  MaxwellSlipFriction desired_friction = plant_friction;
  double ff_sse = 0.0, slow_sse = 0.0;
  long slow_n = 0;
  if (model) model->start(o.dt);
  ClosedLoopRun run;
  run.compensation = !feedforward ? "None" : (model ? std::string(model->name()) : "Baseline");
  const auto n = static_cast<std::size_t>(std::floor(desired.duration / o.dt)) + 1;
  run.q_d.resize(n);
  run.q.resize(n);
  std::vector<double> qd_d(n);
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> noise(0.0, o.torque_noise);
  const double h = o.dt / o.substeps;
  constexpr double kAccStep = 1e-5;  // [s] central difference of the desired velocity
  constexpr double kRampIn = 1.0;    // [s] from rest to the profile's start, not scored
  constexpr double kSlow = 0.1;      // [rad/s] the slow band of feedforward_rmse_slow
  // The trial starts from rest: a ramp-in of kRampIn seconds before t = 0 (a cubic Hermite in
  // velocity matching qd_d(0) and qdd_d(0)) runs the same controller but is not scored. Starting the
  // 10 s profile from rest at a nonzero qd_d(0) would put a velocity step at t = 0 whose transient,
  // integrated by eq. 19 into a lasting command offset, outweighs any model.
  const double v0 = desired.qd(0.0);
  const double a0 = (desired.qd(kAccStep) - v0) / kAccStep;
  const auto vel = [&](double t) {
    if (t >= 0.0) return desired.qd(t);
    const double x = (t + kRampIn) / kRampIn;
    return v0 * x * x * (3.0 - 2.0 * x) + a0 * kRampIn * x * x * (x - 1.0);
  };
  const auto acc = [&](double t) {
    if (t < 0.0) {
      const double x = (t + kRampIn) / kRampIn;
      return (v0 * 6.0 * x * (1.0 - x) + a0 * kRampIn * (3.0 * x * x - 2.0 * x)) / kRampIn;
    }
    return (desired.qd(t + kAccStep) - desired.qd(std::max(0.0, t - kAccStep))) /
           (t + kAccStep - std::max(0.0, t - kAccStep));
  };
  const auto ramp = static_cast<std::size_t>(std::lround(kRampIn / o.dt));
  double q = 0.0, qd = 0.0, integral = 0.0, u = 0.0, qdes = 0.0;
  // a joint that another motion left at rest with stressed elements is held there by its velocity
  // loop: the integrator starts at the torque the elements hold (from relaxed elements: zero)
  if (o.ki > 0.0) integral = plant_friction.torque(0.0) / o.ki;
  // the inverse feed-forward knows the loop it drives: its integrator share starts at what the
  // integrator holds (else it would feed tau_d on top of the held torque)
  double e_prev = 0.0, de_filtered = 0.0, tau_filtered = 0.0, tau_d_filtered = 0.0, x_integral = integral;
  double u_mean = o.ki * integral, tau_d_prev = 0.0;  // the torque of the "last period": what the loop held
  bool first = true;
  // record_measurements: encoder position at each period start and the period's noisy mean torque
  // (its own noise stream, so that the run is the same with and without the record)
  std::vector<double> q_enc, tau_rec;
  std::mt19937_64 rec_rng(o.seed + 7919u);
  std::normal_distribution<double> rec_noise(0.0, o.torque_noise);  // own object: a distribution caches draws
  constexpr double kEncoderStep = 2.0 * M_PI / 1048576.0;  // 20-bit encoder [rad]
  for (std::size_t kk = 0; kk < ramp + n; ++kk) {
    const bool scored = kk >= ramp;
    const std::size_t k = scored ? kk - ramp : 0;
    const double t = (static_cast<double>(kk) - static_cast<double>(ramp)) * o.dt;
    // desired state at the command instant
    const double v_d = vel(t);
    if (scored) {
      qd_d[k] = v_d;
      run.q_d[k] = qdes;
      run.q[k] = q;
    }
    // The command is held over the period (zero-order hold), so it is the period's mean desired
    // velocity (the same trapezoid as q_d: the held command integrates to q_d at every sample) and
    // the torque of the period's midpoint; a held qd_d(t_k) would lag the path by dt/2.
    double mean_v = 0.0;
    for (int s = 0; s < o.substeps; ++s) mean_v += 0.5 * (vel(t + s * h) + vel(t + (s + 1) * h)) / o.substeps;
    const double v_mid = vel(t + 0.5 * o.dt);
    double qd_cmd = mean_v;
    // eq. 19-20: torque error between the model torque and the measured (noisy) motor torque
    if (feedforward) {
      const double f_hat = model ? model->step(v_mid) : 0.0;
      if (model) {
        const double f_true = desired_friction.step(v_mid, o.dt);
        if (scored) {
          ff_sse += (f_hat - f_true) * (f_hat - f_true);
          if (std::abs(v_mid) < kSlow) {
            slow_sse += (f_hat - f_true) * (f_hat - f_true);
            ++slow_n;
          }
        }
      }
      const double tau_d = o.model_inertia * acc(t + 0.5 * o.dt) + f_hat;
      // the current-based torque estimate of the last period (its mean motor torque, noisy), compared
      // with the tau_d of that period (time-aligned), both low-passed by the same filter
      const double tau_raw = u_mean + noise(rng);
      const double tau_d_then = first ? tau_d : tau_d_prev;
      tau_d_prev = tau_d;
      const double alpha = o.dt / (o.torque_filter + o.dt);
      tau_filtered = first ? tau_raw : tau_filtered + alpha * (tau_raw - tau_filtered);
      tau_d_filtered = first ? tau_d_then : tau_d_filtered + alpha * (tau_d_then - tau_d_filtered);
      const double e = (o.matched_filter ? tau_d_filtered : tau_d_then) - tau_filtered;
      // first-order filtered derivative of e_tau (the current-based torque is noisy)
      const double de = first ? 0.0 : (e - e_prev) / o.dt;
      first = false;
      const double a = o.dt / (o.derivative_filter + o.dt);
      de_filtered += a * (de - de_filtered);
      e_prev = e;
      if (o.inverse_feedforward) {
        // the velocity offset that makes the inner PI loop deliver tau_d while the joint follows qd_d:
        // kv x + ki X = tau_d, X = int x dt (X: the share of the inner integrator this offset fills)
        const double x_ff = (tau_d - o.ki * x_integral) / (o.kv + o.ki * o.dt);
        x_integral += x_ff * o.dt;
        qd_cmd += x_ff;
      }
      qd_cmd += o.gains.kp(v_mid) * e + o.gains.kd(v_mid) * de_filtered;
    }
    if (o.record_measurements) q_enc.push_back(std::round(q / kEncoderStep) * kEncoderStep);
    // plant and inner PI velocity loop over one command period (semi-implicit Euler)
    u_mean = 0.0;
    for (int s = 0; s < o.substeps; ++s) {
      const double err = qd_cmd - qd;
      integral += err * h;
      u = o.kv * err + o.ki * integral;
      u_mean += u / o.substeps;
      const double tau_f = plant_friction.step(qd, h);
      qd += h * (u - tau_f) / o.inertia;
      q += h * qd;
      // the desired position by the trapezoidal rule on the substeps
      const double ts = t + s * h;
      qdes += 0.5 * h * (vel(ts) + vel(ts + h));
    }
    if (o.record_measurements) tau_rec.push_back(u_mean + rec_noise(rec_rng));
  }
  if (o.record_measurements) {
    q_enc.push_back(std::round(q / kEncoderStep) * kEncoderStep);
    const std::size_t m = tau_rec.size();  // periods; q_enc has m + 1 boundaries
    run.measured.dt = o.dt;
    run.measured.qd.resize(m);
    run.measured.tau.resize(m);
    // boundary velocity by encoder central differences (one-sided at the ends)
    const std::vector<double> v = signal::central_difference(q_enc, o.dt);
    for (std::size_t k = 0; k < m; ++k) {
      run.measured.qd[k] = (q_enc[k + 1] - q_enc[k]) / o.dt;
      // I qdd = u - tau_f over the period: mean tau_f = mean u - I (qd(end) - qd(start)) / dt
      run.measured.tau[k] = tau_rec[k] - o.model_inertia * (v[k + 1] - v[k]) / o.dt;
    }
  }
  // Table X: tracking RMSE; Table XI: per-segment RMSE mean, +-window at desired reversals
  double s_all = 0.0;
  for (std::size_t k = 0; k < n; ++k) s_all += (run.q_d[k] - run.q[k]) * (run.q_d[k] - run.q[k]);
  run.rmse = std::sqrt(s_all / static_cast<double>(n));
  run.feedforward_rmse = model && feedforward ? std::sqrt(ff_sse / static_cast<double>(n))
                                              : std::numeric_limits<double>::quiet_NaN();
  run.feedforward_rmse_slow = model && feedforward && slow_n ? std::sqrt(slow_sse / static_cast<double>(slow_n))
                                                             : std::numeric_limits<double>::quiet_NaN();
  const auto seg = static_cast<std::size_t>(std::lround(o.segment / o.dt));
  double seg_sum = 0.0;
  int segs = 0;
  for (std::size_t a = 0; a + seg <= n; a += seg) {
    double s = 0.0;
    for (std::size_t k = a; k < a + seg; ++k) s += (run.q_d[k] - run.q[k]) * (run.q_d[k] - run.q[k]);
    seg_sum += std::sqrt(s / static_cast<double>(seg));
    ++segs;
  }
  run.segment_average = segs ? seg_sum / segs : run.rmse;
  const std::vector<char> mask = reversal_window_mask(qd_d, o.dt, o.reversal_window, 0.0, &run.reversals);
  double s_rev = 0.0;
  long n_rev = 0;
  for (std::size_t k = 0; k < n; ++k)
    if (mask[k]) {
      s_rev += (run.q_d[k] - run.q[k]) * (run.q_d[k] - run.q[k]);
      ++n_rev;
    }
  run.reversal_rmse = n_rev ? std::sqrt(s_rev / static_cast<double>(n_rev)) : 0.0;
  return run;
}

ClosedLoopOptions closed_loop_options_for(const SimulatedJoint& joint, double model_inertia) {
  if (!std::isfinite(model_inertia) || model_inertia <= 0.0)
    throw InvalidArgument(fmt::format("{}: model inertia is {}, must be > 0 [kg·m^2]", joint.name, model_inertia));
  // inner loop bandwidth typical of a commercial joint velocity loop (~9 Hz), PI zero at 1 Hz
  constexpr double kBandwidth = 55.0;  // [rad/s]
  constexpr double kIntegralRatio = 6.0;  // ki / kv [1/s]
  ClosedLoopOptions o;
  o.inertia = simulated_rigid_body(joint).inertia;
  o.model_inertia = model_inertia;
  o.kv = kBandwidth * o.inertia;
  o.ki = kIntegralRatio * o.kv;
  // eq. 20 gains from the stability of the torque loop alone, the same for every model: through the
  // sampled, unfiltered current-based torque, qd_comp = K_p e_tau closes a one-sample loop of gain
  // kv K_p that goes unstable at kv K_p = 1; K_p^max keeps a gain margin of 2 there, K_p^min and
  // K_d^max keep the previous ratios (1/10 and 1/130 s of K_p^max)
  o.gains.kp_max = 0.5 / o.kv;
  o.gains.kp_min = 0.1 * o.gains.kp_max;
  o.gains.kd_min = 0.0;
  o.gains.kd_max = o.gains.kp_max / 130.0;
  o.gains.lambda = 4.0;
  o.torque_noise = joint.torque_noise;
  return o;
}

double identified_inertia(const SimulatedJoint& joint, unsigned seed, TrainingExcitation training) {
  const ProtocolRecords r = simulated_protocol_records(joint, seed, training);
  const JointRecord* recs[] = {&r.train, &r.fourier, &r.chirp};
  return fit_rigid_body(recs).inertia;
}

VelocityProfile closed_loop_profile(unsigned seed) {
  constexpr int kHarmonics = 5;
  constexpr double kBase = 0.1, kPeak = 1.0, kDuration = 10.0;  // [Hz], [rad/s], [s]
  return fourier_profile(kHarmonics, kBase, kPeak, kDuration, seed + 100);
}

MaxwellSlipOracle::MaxwellSlipOracle(MaxwellSlipParams truth) : gms_(std::move(truth)) {}

FitSummary MaxwellSlipOracle::fit(const FrictionRecord&) {
  FitSummary s;
  s.status = FitStatus::Converged;
  s.message = "oracle: the simulator's truth, nothing fitted";
  return s;
}

void MaxwellSlipOracle::start(double dt) {
  if (!std::isfinite(dt) || dt <= 0.0) throw InvalidArgument(fmt::format("oracle dt is {}, must be > 0 [s]", dt));
  dt_ = dt;
  gms_.reset();
}

double MaxwellSlipOracle::step(double qd) noexcept { return gms_.step(qd, dt_); }

}  // namespace twinwatch::friction
