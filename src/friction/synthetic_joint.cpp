#include "twinwatch/friction/synthetic_joint.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <random>

#include "twinwatch/core/error.hpp"

namespace twinwatch::friction {

namespace {
constexpr double kTwoPi = 2.0 * std::numbers::pi;
}  // namespace

VelocityProfile sine_profile(double f, double v_amp, double duration) {
  VelocityProfile p;
  p.name = fmt::format("sine {:.3g} Hz", f);
  p.duration = duration;
  p.qd = [f, v_amp](double t) { return v_amp * std::sin(kTwoPi * f * t); };
  p.frequency = [f](double) { return f; };
  return p;
}

VelocityProfile sweep_and_crawls_profile(double f, double v_amp, double sweep_time, const std::vector<double>& crawls,
                                         double crawl_time, double blend) {
  if (!(f > 0.0) || !(sweep_time >= 0.0) || !(crawl_time > 0.0) || !(blend >= 0.0 && blend <= crawl_time) || crawls.empty())
    throw InvalidArgument(fmt::format("sweep_and_crawls_profile: f {}, sweep_time {}, crawl_time {}, blend {}, {} crawls: expected "
                                      "f > 0, sweep_time >= 0, crawl_time > 0, 0 <= blend <= crawl_time, at least one crawl",
                                      f, sweep_time, crawl_time, blend, crawls.size()));
  const double periods = sweep_time * f;
  if (std::abs(periods - std::round(periods)) > 1e-9)
    throw InvalidArgument(fmt::format("sweep_and_crawls_profile: sweep_time {} s is {} periods of {} Hz, expected a whole number",
                                      sweep_time, periods, f));
  VelocityProfile p;
  p.name = fmt::format("sine {:.3g} Hz + {} crawls", f, crawls.size());
  p.duration = sweep_time + crawl_time * static_cast<double>(crawls.size());
  p.qd = [=](double t) {
    if (t < sweep_time) return v_amp * std::sin(kTwoPi * f * t);
    const double u = t - sweep_time;
    const auto i = std::min(static_cast<std::size_t>(u / crawl_time), crawls.size() - 1);
    const double from = i == 0 ? 0.0 : crawls[i - 1], to = crawls[i];
    const double into = u - crawl_time * static_cast<double>(i);
    if (into >= blend) return to;
    return from + (to - from) * 0.5 * (1.0 - std::cos(M_PI * into / blend));
  };
  return p;
}

VelocityProfile fourier_profile(int harmonics, double f_base, double v_amp, double duration, unsigned seed) {
  if (harmonics < 1) throw InvalidArgument(fmt::format("Fourier harmonics is {}, must be >= 1", harmonics));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> a(static_cast<std::size_t>(harmonics)), b(a.size());
  for (std::size_t l = 0; l < a.size(); ++l) {
    a[l] = u(rng);
    b[l] = u(rng);
  }
  const auto raw = [a, b, f_base](double t) {
    double v = 0.0;
    for (std::size_t l = 0; l < a.size(); ++l) {
      const double w = kTwoPi * static_cast<double>(l + 1) * f_base * t;
      v += a[l] * std::sin(w) + b[l] * std::cos(w);
    }
    return v;
  };
  // scale to max |qd| = v_amp over one fundamental period
  constexpr int kScanPoints = 4000;
  double peak = 0.0;
  for (int i = 0; i < kScanPoints; ++i) peak = std::max(peak, std::abs(raw(i / (f_base * kScanPoints))));
  const double scale = peak > 0.0 ? v_amp / peak : 0.0;
  VelocityProfile p;
  p.name = fmt::format("Fourier {} harmonics of {:.3g} Hz", harmonics, f_base);
  p.duration = duration;
  p.qd = [raw, scale](double t) { return scale * raw(t); };
  return p;
}

VelocityProfile chirp_profile(double f0, double f1, double v_amp, double duration) {
  VelocityProfile p;
  p.name = fmt::format("chirp {:.3g}-{:.3g} Hz", f0, f1);
  p.duration = duration;
  const double rate = (f1 - f0) / duration;
  p.qd = [=](double t) { return v_amp * std::sin(kTwoPi * (f0 * t + 0.5 * rate * t * t)); };
  p.frequency = [=](double t) { return f0 + rate * t; };
  return p;
}

void SyntheticJointOptions::validate() const {
  if (!std::isfinite(dt) || dt <= 0.0) throw InvalidArgument(fmt::format("synthetic joint dt is {}, must be > 0 [s]", dt));
  if (substeps < 1) throw InvalidArgument(fmt::format("synthetic joint substeps is {}, must be >= 1", substeps));
  if (!std::isfinite(encoder_lsb) || encoder_lsb < 0.0)
    throw InvalidArgument(fmt::format("synthetic joint encoder_lsb is {}, must be >= 0 [rad]", encoder_lsb));
  if (!std::isfinite(torque_noise) || torque_noise < 0.0)
    throw InvalidArgument(fmt::format("synthetic joint torque_noise is {}, must be >= 0 [N·m]", torque_noise));
}

SyntheticRecord simulate_joint(const MaxwellSlipParams& truth, const VelocityProfile& profile,
                               const SyntheticJointOptions& options) {
  MaxwellSlipFriction relaxed(truth);
  return simulate_joint(relaxed, profile, options);
}

SyntheticRecord simulate_joint(MaxwellSlipFriction& gms, const VelocityProfile& profile,
                               const SyntheticJointOptions& options) {
  options.validate();
  if (!profile.qd) throw InvalidArgument(fmt::format("velocity profile '{}' has no qd(t)", profile.name));
  if (!std::isfinite(profile.duration) || profile.duration <= options.dt)
    throw InvalidArgument(fmt::format("velocity profile '{}' duration is {}, must be > dt ({})", profile.name,
                                      profile.duration, options.dt));
  const auto n = static_cast<std::size_t>(std::floor(profile.duration / options.dt)) + 1;
  SyntheticRecord out;
  out.record.dt = options.dt;
  out.record.qd.resize(n);
  out.record.tau.resize(n);
  out.true_tau.resize(n);
  out.true_qd.resize(n);
  if (profile.frequency) out.frequency.resize(n);
  std::vector<double> q(n);
  out.true_qdd.resize(n);
  const double h = options.dt / options.substeps;
  // sample 0: the given state (relaxed elements for a fresh joint), the velocity of t = 0
  double pos = 0.0;
  out.true_qd[0] = profile.qd(0.0);
  out.true_tau[0] = gms.torque(out.true_qd[0]);
  // integrate the truth over the substeps with the mid-step velocity; position by Simpson's rule
  for (std::size_t k = 1; k < n; ++k) {
    for (int s = 0; s < options.substeps; ++s) {
      const double t0 = static_cast<double>(k - 1) * options.dt + s * h;
      const double v0 = profile.qd(t0), vm = profile.qd(t0 + 0.5 * h), v1 = profile.qd(t0 + h);
      gms.step(vm, h);
      pos += h / 6.0 * (v0 + 4.0 * vm + v1);
    }
    const double t = static_cast<double>(k) * options.dt;
    q[k] = pos;
    out.true_qd[k] = profile.qd(t);
    out.true_tau[k] = gms.torque(out.true_qd[k]);
  }
  // true acceleration by a central difference of the profile (step far below the sample time)
  constexpr double kAccStep = 1e-5;  // [s]
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * options.dt;
    out.true_qdd[k] = (profile.qd(t + kAccStep) - profile.qd(std::max(0.0, t - kAccStep))) / (t + kAccStep - std::max(0.0, t - kAccStep));
  }
  out.true_q = q;
  // measurement: quantised encoder, central differences (one-sided at the ends), noisy torque
  for (double& v : q)
    if (options.encoder_lsb > 0.0) v = std::round(v / options.encoder_lsb) * options.encoder_lsb;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t a = k == 0 ? 0 : k - 1, b = k + 1 == n ? k : k + 1;
    out.record.qd[k] = (q[b] - q[a]) / (static_cast<double>(b - a) * options.dt);
  }
  out.q = q;
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (std::size_t k = 0; k < n; ++k) {
    out.record.tau[k] = out.true_tau[k] + options.torque_noise * noise(rng);
    if (profile.frequency) out.frequency[k] = profile.frequency(static_cast<double>(k) * options.dt);
  }
  return out;
}

}  // namespace twinwatch::friction
