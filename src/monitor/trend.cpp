#include "twinwatch/monitor/trend.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "twinwatch/core/error.hpp"
#include "twinwatch/ident/physics_ident.hpp"
#include "twinwatch/monitor/declaration.hpp"

namespace twinwatch::monitor {

namespace {
constexpr double kSecondsPerHour = 3600.0;
// ridge on the window's normal equations, relative to their trace: keeps the 3x3 solve defined
// when a joint's speed barely varies in a window (sign(qd) and qd then nearly collinear)
constexpr double kRidge = 1e-9;
// a joint needs this many moving samples in a window for a fit (3 unknowns, noisy samples)
constexpr long kMinFitSamples = 50;
// consecutive exceedances the monitor needs to raise an alert (MonitorConfig::raise_after default)
constexpr int kDebounce = 2;
// temperature span [°C] a learning run must cover for a slope to be learnable
constexpr double kMinTemperatureSpan = 1.0;
// cooling [°C] over the trend windows that, without a learned temperature slope, explains a rise
// of the friction estimate (TrendDetector::take_note)
constexpr double kUncompensatedSpan = 1.0;
// the largest relative change of viscous friction per °C taken as cooling alone [1/°C]: twice the
// virtual robot's 2 %/°C; gear oils lose about half their viscosity per 15-20 °C
constexpr double kMaxViscousPerDegree = 0.04;

double sgn(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }
}  // namespace

void TrendConfig::validate(int n) const {
  if (!(window_s > 0.0)) throw InvalidArgument(fmt::format("trend window_s is {}, must be > 0", window_s));
  if (!(cycle_period >= 0.0)) throw InvalidArgument(fmt::format("trend cycle_period is {}, must be >= 0 (0: unknown)", cycle_period));
  if (!(v_min > 0.0)) throw InvalidArgument(fmt::format("trend v_min is {}, must be > 0", v_min));
  if (!(min_moving_fraction > 0.0 && min_moving_fraction <= 1.0))
    throw InvalidArgument(fmt::format("trend min_moving_fraction is {}, must be in (0, 1]", min_moving_fraction));
  if (baseline_windows < 1) throw InvalidArgument(fmt::format("trend baseline_windows is {}, must be >= 1", baseline_windows));
  if (min_windows < 3 || min_windows < baseline_windows)
    throw InvalidArgument(fmt::format("trend min_windows is {}, must be >= 3 and >= baseline_windows ({})", min_windows, baseline_windows));
  if (history < min_windows) throw InvalidArgument(fmt::format("trend history is {}, must be >= min_windows ({})", history, min_windows));
  if (!(z_crit > 0.0)) throw InvalidArgument(fmt::format("trend z_crit is {}, must be > 0", z_crit));
  if (!(min_rate_pct_per_h >= 0.0)) throw InvalidArgument(fmt::format("trend min_rate_pct_per_h is {}, must be >= 0", min_rate_pct_per_h));
  if (persist < 1) throw InvalidArgument(fmt::format("trend persist is {}, must be >= 1", persist));
  if (temperature_slope.size() != 0 && temperature_slope.size() != n)
    throw InvalidArgument(fmt::format("trend temperature_slope has size {}, expected {} (one per joint)", temperature_slope.size(), n));
  for (int j = 0; j < temperature_slope.size(); ++j)
    if (!std::isfinite(temperature_slope[j]))
      throw InvalidArgument(fmt::format("trend temperature_slope of joint {} is {}, must be finite", j + 1, temperature_slope[j]));
}

double mann_kendall_z(const std::vector<double>& y) {
  const size_t n = y.size();
  if (n < 3) return 0.0;
  // S = sum_{i<j} sign(y_j - y_i), var S = n (n - 1) (2n + 5) / 18
  double S = 0.0;
  for (size_t i = 0; i + 1 < n; ++i)
    for (size_t j = i + 1; j < n; ++j) S += sgn(y[j] - y[i]);
  const double N = static_cast<double>(n);
  const double var = N * (N - 1.0) * (2.0 * N + 5.0) / 18.0;
  // continuity correction
  if (S > 0) return (S - 1.0) / std::sqrt(var);
  if (S < 0) return (S + 1.0) / std::sqrt(var);
  return 0.0;
}

double theil_sen_slope(const std::vector<double>& x, const std::vector<double>& y, std::vector<double>& scratch) {
  assert(x.size() == y.size());
  scratch.clear();
  for (size_t i = 0; i + 1 < x.size(); ++i)
    for (size_t j = i + 1; j < x.size(); ++j)
      if (x[j] != x[i]) scratch.push_back((y[j] - y[i]) / (x[j] - x[i]));
  if (scratch.empty()) return 0.0;
  // median of the pairwise slopes
  const size_t m = scratch.size() / 2;
  std::nth_element(scratch.begin(), scratch.begin() + static_cast<long>(m), scratch.end());
  double med = scratch[m];
  if (scratch.size() % 2 == 0) med = 0.5 * (med + *std::max_element(scratch.begin(), scratch.begin() + static_cast<long>(m)));
  return med;
}

TrendDetector::TrendDetector(const ident::TwinModel& twin, TrendConfig config, const VectorJ& gain, std::string units)
    : cfg_(std::move(config)), n_(twin.n_dof()), units_(std::move(units)), residual_units_(twin.channel_unit()) {
  cfg_.validate(n_);
  if (gain.size() != n_) throw InvalidArgument(fmt::format("trend gain has size {}, expected {} (twin.n_dof)", gain.size(), n_));
  for (int j = 0; j < n_; ++j)
    if (!(gain[j] > 0.0)) throw InvalidArgument(fmt::format("trend gain of joint {} is {}, must be > 0", j + 1, gain[j]));
  gain_ = gain;
  compensated_ = cfg_.temperature_slope.size() == n_;
  if (cfg_.temperature_slope.size() == 0) cfg_.temperature_slope = VectorJ::Zero(n_);
  // window: whole program periods when the period is known
  window_ = cfg_.window_s;
  if (cfg_.cycle_period > 0.0) window_ = std::max(1.0, std::round(cfg_.window_s / cfg_.cycle_period)) * cfg_.cycle_period;
  nominal_ = v_ref_ = z_ = slope_ = VectorJ::Zero(n_);
  ata_.assign(static_cast<size_t>(n_), Eigen::Matrix3d::Zero());
  atb_.assign(static_cast<size_t>(n_), Eigen::Vector3d::Zero());
  energy_ = temp_sum_ = speed_sum_ = dissip_ = VectorJ::Zero(n_);
  headroom_ = VectorJ::Constant(n_, std::numeric_limits<double>::infinity());
  moving_.assign(static_cast<size_t>(n_), 0);
  margins_.assign(static_cast<size_t>(kDebounce * n_), -std::numeric_limits<double>::infinity());
  temp_n_.assign(static_cast<size_t>(n_), 0);
  hist_.resize(static_cast<size_t>(n_));
  const size_t H = static_cast<size_t>(cfg_.history);
  for (auto& h : hist_) h.reserve(H + 1);
  itot_.reserve(H + 1);
  twin_t_.reserve(H + 1);
  streak_.assign(static_cast<size_t>(n_), 0);
  warned_.assign(static_cast<size_t>(n_), false);
  noted_.assign(static_cast<size_t>(n_), false);
  xs_.reserve(H + 1);
  ys_.reserve(H + 1);
  scratch_.reserve(H * (H + 1) / 2);
  // nominal friction of the twin per joint, in current [A] at a speed set once v_ref is known
  // (Coulomb + viscous / gain in the twin's own units: the current is meaningful either way)
  twin_fc_ = VectorJ::Zero(n_);
  twin_fv_ = VectorJ::Zero(n_);
  for (int j = 0; j < n_; ++j) {
    const auto& jd = twin.joints[static_cast<size_t>(j)];
    twin_fc_[j] = std::abs(jd.friction(ident::kCoulomb)) / jd.gain;
    twin_fv_[j] = std::abs(jd.friction(ident::kViscous)) / jd.gain;
  }
}

bool TrendDetector::push(double t, const VectorJ& qd, const VectorJ& r, const VectorJ& rf, const VectorJ& level,
                         const VectorJ& temperature, double i_total, bool alert_open) {
  if (!cfg_.enabled) return false;
  if (!started_) {
    started_ = true;
    t_open_ = t;
    t_prev_ = t;
  }
  const double dt = std::max(0.0, t - t_prev_);
  t_prev_ = t;
  // accumulate the window (samples during an open alert belong to that alert, not to wear)
  if (!alert_open) {
    ++samples_;
    itot_sum_ += i_total;
    for (int j = 0; j < n_; ++j) {
      energy_[j] += r[j] * r[j] * dt;
      const bool has_T = temperature.size() > j && std::isfinite(temperature[j]);
      if (has_T) {
        temp_sum_[j] += temperature[j];
        ++temp_n_[static_cast<size_t>(j)];
      }
      if (std::abs(qd[j]) <= cfg_.v_min) continue;
      // temperature-compensated residual: r - k_T qd (T - T_ref)
      const double dT = has_T ? temperature[j] - cfg_.temperature_ref : 0.0;
      const double y = r[j] - cfg_.temperature_slope[j] * qd[j] * dT;
      const Eigen::Vector3d phi(sgn(qd[j]), qd[j], 1.0);
      ata_[static_cast<size_t>(j)].noalias() += phi * phi.transpose();
      atb_[static_cast<size_t>(j)].noalias() += phi * y;
      dissip_[j] += y * phi(0);
      speed_sum_[j] += std::abs(qd[j]);
      ++moving_[static_cast<size_t>(j)];
      // headroom before the threshold trips in the direction friction pushes the residual: the
      // margin must be exceeded kDebounce samples in a row, so the largest of the last ones counts
      double* mh = &margins_[static_cast<size_t>(kDebounce * j)];
      for (int k = kDebounce - 1; k > 0; --k) mh[k] = mh[k - 1];
      mh[0] = level[j] - rf[j] * sgn(qd[j]);
      headroom_[j] = std::min(headroom_[j], *std::max_element(mh, mh + kDebounce));
    }
  }
  if (t - t_open_ < window_) return false;
  close_window(t);
  if (!warn_pending_) return false;
  warn_pending_ = false;
  return true;
}

void TrendDetector::close_window(double t) {
  ++windows_;
  // per joint: solve the window's Coulomb/viscous/offset fit
  for (int j = 0; j < n_; ++j) {
    const size_t J = static_cast<size_t>(j);
    TrendPoint p;
    p.t = t;
    p.energy = energy_[j];
    p.temperature = temp_n_[J] > 0 ? temp_sum_[j] / static_cast<double>(temp_n_[J]) : std::numeric_limits<double>::quiet_NaN();
    const long m = moving_[J];
    if (samples_ > 0 && m >= kMinFitSamples && static_cast<double>(m) >= cfg_.min_moving_fraction * static_cast<double>(samples_)) {
      Eigen::Matrix3d A = ata_[J];
      A.diagonal().array() += kRidge * A.trace();
      const Eigen::Vector3d x = A.ldlt().solve(atb_[J]);
      // the reference speed is the mean speed of the baseline windows
      if (windows_ <= cfg_.baseline_windows) {
        const double v = speed_sum_[j] / static_cast<double>(m);
        v_ref_[j] = v_ref_[j] > 0.0 ? 0.5 * (v_ref_[j] + v) : v;
        nominal_[j] = gain_[j] * (twin_fc_[j] + twin_fv_[j] * v_ref_[j]);
      }
      p.coulomb = gain_[j] * x(0);
      p.viscous = gain_[j] * x(1);
      // the trended scalar: the mean residual in the direction of motion, mean(y sign(qd)) = extra
      // Coulomb + extra viscous * mean|qd| (+ a constant misfit term over whole cycles). One number
      // per window, far better conditioned than a + b v from the collinear sign(qd)/qd fit
      p.friction = gain_[j] * dissip_[j] / static_cast<double>(m);
      p.valid = true;
    }
    auto& h = hist_[J];
    if (static_cast<int>(h.size()) >= cfg_.history) h.erase(h.begin());  // no reallocation: capacity is kept
    h.push_back(p);
    if (p.valid && windows_ > cfg_.baseline_windows && test_joint(j, t)) warn_pending_ = true;
    // reset the joint's accumulators
    ata_[J].setZero();
    atb_[J].setZero();
    energy_[j] = temp_sum_[j] = speed_sum_[j] = dissip_[j] = 0.0;
    moving_[J] = temp_n_[J] = 0;
    headroom_[j] = std::numeric_limits<double>::infinity();
  }
  if (static_cast<int>(itot_.size()) >= cfg_.history) {
    itot_.erase(itot_.begin());
    twin_t_.erase(twin_t_.begin());
  }
  itot_.push_back(samples_ > 0 ? itot_sum_ / static_cast<double>(samples_) : 0.0);
  twin_t_.push_back(t);
  itot_sum_ = 0.0;
  samples_ = 0;
  t_open_ = t;
}

bool TrendDetector::test_joint(int j, double t) {
  const size_t J = static_cast<size_t>(j);
  // the valid windows after the baseline (v_ref is settled from there on)
  xs_.clear();
  ys_.clear();
  ts_.clear();
  const auto& h = hist_[J];
  const long skip = std::max(0L, static_cast<long>(cfg_.baseline_windows) - static_cast<long>(windows_ - static_cast<int>(h.size())));
  for (size_t k = static_cast<size_t>(std::max(0L, skip)); k < h.size(); ++k)
    if (h[k].valid) {
      xs_.push_back(h[k].t / kSecondsPerHour);
      ys_.push_back(h[k].friction);
      ts_.push_back(h[k].temperature);
    }
  if (static_cast<int>(xs_.size()) < cfg_.min_windows - cfg_.baseline_windows) return false;
  z_[j] = mann_kendall_z(ys_);
  slope_[j] = theil_sen_slope(xs_, ys_, scratch_);
  const double rate_pct = nominal_[j] > 0.0 ? 100.0 * slope_[j] / nominal_[j] : 0.0;
  const bool significant = z_[j] >= cfg_.z_crit && rate_pct >= cfg_.min_rate_pct_per_h;
  streak_[J] = significant ? streak_[J] + 1 : 0;
  if (warned_[J] || streak_[J] < cfg_.persist) return false;
  // no temperature slope learned: a joint that cooled over these windows has a healthy viscous
  // friction that rose with it (a program lighter than the one before it, a robot that started
  // warm). A rise no larger than cooling could cause at kMaxViscousPerDegree is not taken for wear:
  // said once, instead of a warning. A larger one is still warned about.
  if (!compensated_) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    bool all = !ts_.empty();
    for (const double T : ts_) {
      all &= std::isfinite(T);
      lo = std::min(lo, T);
      hi = std::max(hi, T);
    }
    const double cooled = all && theil_sen_slope(xs_, ts_, scratch_) < 0.0 ? hi - lo : 0.0;
    const double rise = slope_[j] * (xs_.back() - xs_.front());
    const double by_cooling = kMaxViscousPerDegree * cooled * gain_[j] * twin_fv_[j] * v_ref_[j];
    if (cooled >= kUncompensatedSpan && rise <= by_cooling) {
      if (!noted_[J]) {
        noted_[J] = true;
        note_ = fmt::format("J{}: friction rising {:+.1f} %/h of nominal while the joint cooled from {:.1f} to {:.1f} °C; the twin has "
                            "no temperature slope of its viscous friction, so this may be the cooling, not wear: no wear warning "
                            "(learn the slope on a warm-up from cold: 'twinwatch thresholds --twin TWIN COLD.csv WARM.csv')",
                            j + 1, rate_pct, ts_.front(), ts_.back());
      }
      return false;
    }
  }
  warned_[J] = true;
  // the warning: joint, rate, projected time until the excess reaches the threshold
  Event& e = warning_;
  e = Event{};
  e.peak_residual_units = residual_units_;
  e.t_start = xs_.front() * kSecondsPerHour;
  e.t_end = t;
  e.t_detected = t;
  e.open = false;
  e.fault = FaultClass::Wear;
  e.joint = j;
  e.magnitude = rate_pct;
  e.units = "%/h";
  e.confidence = std::min(1.0, 0.5 * (1.0 + std::erf(z_[j] / std::sqrt(2.0))));
  const double headroom = gain_[j] * headroom_[j];
  const double eta_h = std::isfinite(headroom) && slope_[j] > 0.0 ? std::max(0.0, headroom) / slope_[j] : std::numeric_limits<double>::infinity();
  e.detail = fmt::format(
      "wear trend on J{}: friction rising {:+.1f} %/h of nominal ({:+.4f} {}/h, Mann-Kendall z = {:.1f} over {} windows); "
      "at this rate the residual reaches the alarm threshold in {}",
      j + 1, rate_pct, slope_[j], units_, z_[j], xs_.size(),
      std::isfinite(eta_h) ? fmt::format("{:.1f} h", eta_h) : std::string("(no threshold headroom measured)"));
  return true;
}

bool TrendDetector::take_note(std::string& note) {
  if (note_.empty()) return false;
  note = std::move(note_);
  note_.clear();
  return true;
}

bool plausible_temperature(double celsius) { return std::isnan(celsius) || (celsius >= kTemperatureMin && celsius <= kTemperatureMax); }

std::size_t implausible_temperatures(const RobotSample& s) {
  std::size_t count = 0;
  if (s.has(kFieldTemperature))
    for (Eigen::Index j = 0; j < s.temperature.size(); ++j) count += plausible_temperature(s.temperature[j]) ? 0 : 1;
  return count;
}

std::size_t implausible_temperatures(const device::Recording& rec) {
  std::size_t count = 0;
  for (const RobotSample& s : rec.samples) count += implausible_temperatures(s);
  return count;
}

device::Recording hold_implausible_temperatures(const device::Recording& rec) {
  device::Recording out = rec;
  TemperatureHold hold;
  for (RobotSample& s : out.samples) s = hold.apply(s);
  return out;
}

const RobotSample& TemperatureHold::apply(const RobotSample& s) {
  if (!s.has(kFieldTemperature)) return s;
  const auto m = static_cast<std::size_t>(s.temperature.size());
  if (last_.size() < m) last_.resize(m, std::numeric_limits<double>::quiet_NaN());
  bool held = false;
  for (std::size_t j = 0; j < m; ++j) {
    const double T = s.temperature[static_cast<Eigen::Index>(j)];
    if (plausible_temperature(T)) {
      if (!std::isnan(T)) last_[j] = T;
      continue;
    }
    if (!held) {
      held_ = s;
      held = true;
    }
    held_.temperature[static_cast<Eigen::Index>(j)] = last_[j];
  }
  return held ? held_ : s;
}

TrendConfig learn_trend_temperature(const ident::TwinModel& twin, const std::vector<TrendRun>& given, const TrendConfig& settings,
                                    bool follow_payload) {
  std::vector<std::unique_ptr<device::HeldSamples>> store;
  const std::vector<const device::SampleSource*> runs = samples_of(given, store, "learn trend temperature");
  const int n = twin.n_dof();
  settings.validate(n);
  if (runs.empty()) throw InvalidArgument("learn trend temperature: no healthy runs given");
  TrendConfig c = settings;
  c.temperature_ref = twin.temperature_ref;
  c.temperature_slope = VectorJ::Zero(n);
  const int R = static_cast<int>(runs.size());
  // columns: [sign, qd, 1] per program (its own misfit), one shared qd (T - T_ref)
  int programs = 0;
  for (const TrendRun& run : given) {
    if (run.program < 0) throw InvalidArgument(fmt::format("learn trend temperature: program index {} must be >= 0", run.program));
    programs = std::max(programs, run.program + 1);
  }
  const int P = 3 * programs + 1;
  std::vector<Eigen::MatrixXd> A(static_cast<size_t>(n), Eigen::MatrixXd::Zero(P, P));
  std::vector<Eigen::VectorXd> b(static_cast<size_t>(n), Eigen::VectorXd::Zero(P));
  VectorJ tmin = VectorJ::Constant(n, std::numeric_limits<double>::infinity()), tmax = -tmin;
  Eigen::VectorXd phi = Eigen::VectorXd::Zero(P);
  VectorJ i_hat;
  for (int ri = 0; ri < R; ++ri) {
    const device::SampleSource& src = *runs[static_cast<size_t>(ri)];
    const TrendRun& run = given[static_cast<size_t>(ri)];
    if (!(src.present() & kFieldTemperature))
      throw InvalidArgument(fmt::format("learn trend temperature: recording {} has no joint temperatures", src.path()));
    ident::TwinModel t = twin;
    // (the payload the stream declares, as the monitor predicts with it: PayloadTimeline)
    // (read once: the accelerations are zero-phase, each sample handed over a few samples after it
    // was seen, and whether it is judged looks back only)
    PayloadTimeline payload(twin, run.payload, follow_payload && (src.present() & kFieldPayload));
    const double period = src.median_period() > 0.0 ? src.median_period() : MonitorConfig{}.nominal_period;
    ident::JointAccelerationStream accelerations(src.n_dof(), src.present(), twin.acceleration_half_width(period));
    ident::FrictionMemory memory;
    TemperatureHold hold;
    size_t k = 0;
    const ident::JointAccelerationStream::Ready learn = [&](const RobotSample& s, const VectorJ& qdd) {
      const size_t at = k++;
      if (at == 0) payload.start(t);  // (after the first sample's declaration was seen)
      payload.advance(at, t);
      t.advance(memory, s, qdd);
      if (!payload.judged_seen(at, period)) return;
      t.predict_current(s.q, s.qd, qdd, s.temperature, i_hat, &memory);
      for (int j = 0; j < n; ++j) {
        if (std::abs(s.qd[j]) <= c.v_min || !std::isfinite(s.temperature[j])) continue;
        tmin[j] = std::min(tmin[j], s.temperature[j]);
        tmax[j] = std::max(tmax[j], s.temperature[j]);
        // pooled normal equations of r = a sign(qd) + b qd + c + k_T qd (T - T_ref)
        const int g = 3 * run.program;
        phi.setZero();
        phi(g) = sgn(s.qd[j]);
        phi(g + 1) = s.qd[j];
        phi(g + 2) = 1.0;
        phi(P - 1) = s.qd[j] * (s.temperature[j] - c.temperature_ref);
        A[static_cast<size_t>(j)].noalias() += phi * phi.transpose();
        b[static_cast<size_t>(j)].noalias() += phi * (s.current[j] - i_hat[j]);
      }
    };
    src.replay([&](size_t i, const RobotSample& s) {
      payload.see(i, s);
      accelerations.push(hold.apply(s), learn);
    });
    accelerations.finish(learn);
  }
  for (int j = 0; j < n; ++j) {
    if (!(tmax[j] - tmin[j] >= kMinTemperatureSpan))
      throw InvalidArgument(fmt::format("learn trend temperature: joint {} temperature spans {:.1f} °C over the runs, need >= {:.1f} °C "
                                        "(give a warm-up from cold)",
                                        j + 1, std::isfinite(tmax[j] - tmin[j]) ? tmax[j] - tmin[j] : 0.0, kMinTemperatureSpan));
    Eigen::MatrixXd M = A[static_cast<size_t>(j)];
    M.diagonal().array() += kRidge * M.trace();
    c.temperature_slope[j] = M.ldlt().solve(b[static_cast<size_t>(j)])(P - 1);
  }
  return c;
}

}  // namespace twinwatch::monitor
