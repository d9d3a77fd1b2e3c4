#pragma once
/// @file trend.hpp
/// Slow-wear trend detection (issue 7): per cycle window, per joint, the extra friction seen in the
/// current residual, compensated for joint temperature, the residual energy and the total current
/// [UR3e Fig. 12]; a robust trend test over the history of windows raises a `wear` warning when the
/// trend — not a threshold — says the joint is degrading.
///
/// Cycle windows. A window is `window_s` seconds of samples, rounded to a whole number of program
/// periods when the period is given (`cycle_period`, the robot program's cycle time). The friction
/// fit is a per-sample regression, so it needs no phase alignment with the program; whole periods
/// make every window see the same velocity distribution, so the model misfit the fit absorbs is the
/// same in every window (and without a period the partial-cycle effect is at most period/window).
///
/// Per window and joint j, least squares over the samples where the joint moves (|qd| > v_min):
///   r_j - k_T,j qd_j (T_j - T_ref) = a_j sign(qd_j) + b_j qd_j + c_j          (Coulomb, viscous, offset)
/// where r = i - i_hat is the current residual [A] and k_T,j the temperature slope of the viscous
/// friction learned on a healthy warm-up (learn_trend_temperature); a_j, b_j (the Coulomb/viscous
/// split) are kept in the history. The trended extra friction of the window is the mean
/// compensated residual in the direction of motion over the same samples,
///   f_j = mean( (r_j - k_T,j qd_j (T_j - T_ref)) sign(qd_j) )   [A] (x drive gain: [N·m] when known)
/// = extra Coulomb + extra viscous x mean|qd_j| (+ a misfit constant over whole cycles): one
/// well-conditioned number per window (a + b v alone swings with the collinearity of sign(qd) and
/// qd). Its nominal is the twin's friction at v_ref,j = the mean |qd_j| of the first windows. Also
/// per window: residual energy E_j = sum r_j^2 dt [A²·s] and the mean total current
/// I_total = sum_j |i_j| [A].
///
/// Trend test per joint over the last `history` windows: the Mann–Kendall statistic
/// [Mann1945, Kendall1975] z of the series and the Theil–Sen slope [Sen1968] (median of pairwise
/// slopes). A joint is degrading when z >= z_crit and the slope, relative to the twin's nominal
/// friction at v_ref, is at least `min_rate_pct_per_h`, in `persist` consecutive windows. The
/// warning names the joint, the rate and the time until the excess reaches the alarm threshold
/// (the smallest headroom level - rf sign(qd) of the filtered residual over the last window,
/// divided by the slope).
///
/// push() is allocation-free; closing a window allocates nothing either (history and scratch are
/// reserved at construction).
#include <fmt/format.h>

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/types.hpp"
#include "twinwatch/device/recording.hpp"
#include "twinwatch/ident/twin_model.hpp"
#include "twinwatch/monitor/event.hpp"

namespace twinwatch::monitor {

/// Settings and the learned temperature slopes; stored in the twin file with the thresholds.
struct TrendConfig {
  bool enabled = true;
  double window_s = 30.0;        ///< [s] window length (rounded to whole periods if cycle_period > 0)
  double cycle_period = 0.0;     ///< [s] program period; 0: unknown, plain windows of window_s
  double v_min = 0.05;           ///< [rad/s] samples slower than this are left out (static friction, reversals)
  double min_moving_fraction = 0.2;  ///< a joint's window counts if it moved in this fraction of its samples
  int baseline_windows = 4;      ///< windows that fix v_ref (and need no test)
  int min_windows = 12;          ///< windows in the history before the test runs
  int history = 240;             ///< windows the test looks back over (240 x 30 s = 2 h)
  double z_crit = 4.0;           ///< Mann–Kendall z above which the trend is significant (one-sided)
  double min_rate_pct_per_h = 4.0;  ///< smallest friction growth worth a warning [% of nominal per hour]
  int persist = 3;               ///< consecutive significant windows before the warning
  VectorJ temperature_slope;     ///< k_T per joint [A·s/rad/°C] (empty: no compensation)
  double temperature_ref = 35.0; ///< [°C]

  /// Throws InvalidArgument naming the first field out of range (n_dof: expected slope size).
  void validate(int n_dof) const;
};

/// Statistics of one closed window for one joint.
struct TrendPoint {
  double t = 0.0;            ///< [s] window end
  double friction = 0.0;     ///< f_j, temperature-compensated extra friction [A or N·m]
  double coulomb = 0.0;      ///< a_j
  double viscous = 0.0;      ///< b_j [per rad/s]
  double energy = 0.0;       ///< sum r^2 dt [A²·s]
  double temperature = 0.0;  ///< mean joint temperature [°C] (NaN if not streamed)
  bool valid = false;        ///< the joint moved enough for a fit
};

/// Mann–Kendall trend statistic z (continuity-corrected, no tie correction) of y in order.
/// Returns 0 for fewer than 3 points.
double mann_kendall_z(const std::vector<double>& y);
/// Theil–Sen slope of (x, y): the median of (y_j - y_i) / (x_j - x_i) over pairs with x_j != x_i.
/// `scratch` is reused (reserve n (n - 1) / 2 to stay allocation-free). Returns 0 for < 2 points.
double theil_sen_slope(const std::vector<double>& x, const std::vector<double>& y, std::vector<double>& scratch);

class TrendDetector {
 public:
  TrendDetector() = default;
  /// @param twin the reference model (nominal friction for the relative rate)
  /// @param gain drive gain per joint [N·m/A] used for the reported units; all ones: amperes
  /// @param units "N·m" or "A"
  /// Throws InvalidArgument when the config is invalid or the sizes differ from twin.n_dof().
  TrendDetector(const ident::TwinModel& twin, TrendConfig config, const VectorJ& gain, std::string units);

  /// One sample: time [s], joint velocity [rad/s], raw residual r [A], filtered residual rf [A],
  /// threshold level [A], joint temperatures [°C] (may be empty / NaN), total current [A], and
  /// whether an alert is open (those samples are left out of the fit). Returns true when a window
  /// closed and raised a warning; take it with take_warning().
  bool push(double t, const VectorJ& qd, const VectorJ& r, const VectorJ& rf, const VectorJ& level,
            const VectorJ& temperature, double i_total, bool alert_open);

  /// The warning raised by the last push (valid when push returned true).
  const Event& warning() const { return warning_; }
  /// A note instead of a warning, once per joint: without a learned temperature slope, a friction
  /// rise over windows in which the joint cooled by 1 °C or more is what cooling does
  /// to a healthy joint's viscous friction, not evidence of wear. True (and the note) once after the
  /// push that found it.
  bool take_note(std::string& note);
  /// Whether the residuals pushed are compensated for temperature (default: when the config has a
  /// slope; an owner that compensates them itself and passes a zero slope says so here).
  void set_temperature_compensated(bool on) { compensated_ = on; }
  /// The stream goes on from a stop the monitor did not judge (Monitor::resume_watch): the next
  /// sample's step counts from `t` [s], not from the last sample before the stop.
  void resume_at(double t) {
    if (started_) t_prev_ = t;
  }
  /// Per-window history of joint j (oldest first; bounded by config.history).
  const std::vector<TrendPoint>& history(int j) const { return hist_[static_cast<size_t>(j)]; }
  /// Mean total current of each closed window [A] (UR3e Fig. 12), oldest first.
  const std::vector<double>& total_current() const { return itot_; }
  /// Window end times [s] matching total_current().
  const std::vector<double>& window_times() const { return twin_t_; }
  /// Last Mann–Kendall z and Theil–Sen slope [units/h] of joint j.
  double z(int j) const { return z_[j]; }
  double slope_per_hour(int j) const { return slope_[j]; }
  /// Whether joint j has been warned about.
  bool warned(int j) const { return warned_[static_cast<size_t>(j)]; }
  int windows() const { return windows_; }
  int n_dof() const { return n_; }
  const TrendConfig& config() const { return cfg_; }

 private:
  void close_window(double t);
  bool test_joint(int j, double t);

  TrendConfig cfg_;
  int n_ = 0;
  double window_ = 30.0;
  VectorJ gain_, nominal_, v_ref_, z_, slope_, twin_fc_, twin_fv_;
  std::string units_;
  std::string residual_units_;  // the twin's channel (Event::peak_residual_units of the warning)
  // accumulators of the open window, per joint: normal equations of [sign, qd, 1]
  std::vector<Eigen::Matrix3d> ata_;
  std::vector<Eigen::Vector3d> atb_;
  VectorJ energy_, temp_sum_, speed_sum_, dissip_, headroom_;
  std::vector<long> moving_, temp_n_;
  std::vector<double> margins_;  // last threshold margins per joint (debounce-aware headroom)
  long samples_ = 0;
  double itot_sum_ = 0.0, t_open_ = 0.0, t_prev_ = 0.0;
  bool started_ = false;
  int windows_ = 0;
  std::vector<std::vector<TrendPoint>> hist_;
  std::vector<double> itot_, twin_t_;
  std::vector<int> streak_;
  std::vector<bool> warned_, noted_;
  std::vector<double> xs_, ys_, ts_, scratch_;
  std::string note_;
  bool compensated_ = false;
  Event warning_;
  bool warn_pending_ = false;
};

/// Learns the temperature slope k_T of the viscous friction per joint from healthy runs that span
/// a range of joint temperatures (per program a warm-up from cold and a cool-down from warm): the
/// pooled least squares of the twin's current residual on [sign(qd), qd, 1] of each program (its
/// own misfit) and one shared qd (T - T_ref), over the moving samples. Fast programs give the slope
/// its leverage. Returns `settings` with temperature_slope and temperature_ref (the twin's) set.
/// Throws InvalidArgument when no run carries temperatures or a joint's temperature does not vary
/// (span < 1 °C over the runs: nothing to learn from).
struct TrendRun {
  const device::Recording* recording = nullptr;
  model::RigidBodyInertia payload;
  int program = 0;  ///< runs of one program share its Coulomb/viscous/offset misfit (0-based)
  const device::SampleSource* samples = nullptr;  ///< instead of `recording`: a run read and not held
};
/// (follow_payload: a run whose stream declares its payload is predicted with each declaration the
/// twin takes, as the monitor does with MonitorConfig::follow_payload; else with TrendRun::payload alone)
TrendConfig learn_trend_temperature(const ident::TwinModel& twin, const std::vector<TrendRun>& runs,
                                    const TrendConfig& settings = {}, bool follow_payload = true);

/// The joint temperatures a joint can read [°C]. Outside them a reading is none (a 0xFFFF/10
/// overflow, a broken sensor): it went into the residual's temperature compensation, and one such
/// sample raised a contact (session-34 audit).
inline constexpr double kTemperatureMin = -40.0, kTemperatureMax = 150.0;

/// Whether `celsius` is a reading a joint can have, or none (NaN: unknown, the compensation leaves
/// it out). Infinite is no reading.
bool plausible_temperature(double celsius);

/// How many joint temperature readings of `rec` are not plausible_temperature.
std::size_t implausible_temperatures(const device::Recording& rec);
/// The same of one sample
std::size_t implausible_temperatures(const RobotSample& s);

/// `rec` with every implausible joint temperature replaced by that joint's last plausible reading
/// (NaN before the first), as the monitor judges such samples (Monitor::push): what the learners
/// (learn_thresholds, learn_trend_temperature) learn from, so that a training recording's glitch
/// does not widen the thresholds or tilt the slope.
device::Recording hold_implausible_temperatures(const device::Recording& rec);

/// hold_implausible_temperatures a sample at a time, for a run read and not held: the sample as
/// given while its temperatures are plausible, else a copy with them held.
class TemperatureHold {
 public:
  const RobotSample& apply(const RobotSample& s);

 private:
  std::vector<double> last_;
  RobotSample held_;
};

/// The samples of each of `runs` (anything with `const device::Recording* recording` and `const
/// device::SampleSource* samples`: a held recording, or samples read as often as asked), the held
/// ones read through a HeldSamples kept in `store`. Throws InvalidArgument naming `who` for a run
/// with neither.
template <class Run>
std::vector<const device::SampleSource*> samples_of(const std::vector<Run>& runs, std::vector<std::unique_ptr<device::HeldSamples>>& store,
                                                    const std::string& who) {
  std::vector<const device::SampleSource*> out;
  for (size_t i = 0; i < runs.size(); ++i) {
    const Run& r = runs[i];
    if (r.samples != nullptr) {
      out.push_back(r.samples);
    } else if (r.recording != nullptr) {
      store.push_back(std::make_unique<device::HeldSamples>(*r.recording));
      out.push_back(store.back().get());
    } else {
      throw InvalidArgument(fmt::format("{}: run {} has no recording", who, i + 1));
    }
  }
  return out;
}

}  // namespace twinwatch::monitor
