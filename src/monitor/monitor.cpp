#include "twinwatch/monitor/monitor.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <limits>
#include <cmath>
#include <nlohmann/json.hpp>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/json_fields.hpp"
#include "twinwatch/core/numbers.hpp"
#include "twinwatch/ident/physics_ident.hpp"
#include "twinwatch/monitor/declaration.hpp"

namespace twinwatch::monitor {

namespace {
// persistent faults (not a pulse) are diagnosed again on this much residual after the raise [s]:
// friction and payload signatures need motion in both directions to tell them apart
constexpr double kLongWindow = 2.5;
// an exceedance longer than this [s] is no collision pulse (50 ms pulse + filter + debounce tail)
constexpr double kPulseMax = 0.5;
// observer history before the diagnosis window that the contact isolation uses as its healthy
// reference (the noise of a pulse-long impulse just before the contact) [s]
constexpr double kContactReference = 0.5;
// a program declares its pick up to this long after the gripper closed on it (a gripper's URCap
// declares once it has seen the grip), or before it closes: the payload change raised in between is
// the pick the program declared, not a fault, and is withdrawn (declared_pick_candidate,
// declared_pick_explains) [s]
constexpr double kDeclarationLag = 1.0;
// a declaration this close to a raise leaves a step shorter than a diagnosis window, which reads as
// a pulse (a contact where the part hangs) or is not yet diagnosed [s]
constexpr double kShortStep = 0.25;
constexpr double kDeclaredForceShare = 2.5;  // a contact read from a declared part's step: at most this many times its weight
constexpr double kDeclaredPickShare = 0.5;  // a payload change within this share of a declared change is that pick (declared_pick_candidate)
// a payload change the monitor follows (MonitorConfig::follow_payload) that leaves a mass within this
// share of the change, or this many kg, of zero (either side) is the whole payload lost: the longer
// look's estimate errs by about 12 % (-0.44 kg for a 0.5 kg loss, docs/validation.md)
constexpr double kPayloadFollowShare = 0.3, kPayloadFollowFloor = 0.05;
// a payload change is followed when the gripper's outputs changed in its window or the payload
// signature explains this share of the residual (dropped parts 0.88-0.89; a held push 0.76)
constexpr double kPayloadFollowExplained = 0.85;
// how far before an alert's exceedance began [s] a change of the gripper's outputs counts as the
// evidence of a payload change (a vacuum valve or jaws take tens to a few hundred ms)
constexpr double kPayloadIoLookback = 0.5;
// a followed payload whose alert is still up this long [s] after it was not the payload: undone
constexpr double kPayloadFollowSettle = 0.5;
// a gripper output that changes this long [s] after a payload change's alert began ends that change
// (split_payload_change); sooner, it is the same handling (a vacuum gripper's blow-off pulse after the
// release), and the estimate would have too little motion to go on
constexpr double kPayloadSplitAfter = 0.5;
// watch_on_top: a residual on top of a payload change's rises when it is above its threshold and
// this share of the threshold above its mean over the last kOnTopRise [s]
constexpr double kOnTopRise = 0.1, kOnTopRiseShare = 0.5;
constexpr double kOnTopMoving = 0.05;  // [s] a joint that rested is judged once it has moved on this long
// check_payload_after_output, measured at 319 output changes with no part on healthy runs of every
// program and on 0.15 kg parts (docs/validation.md, session 28):
// - kOutputCheckAfter [s]: the window after the output change (1 s: healthy at most 0.061 kg, 0.9 %
//   explained; parts 0.134-0.157 kg, 24-48 %); looked at again every kOutputCheckAgain while it is
//   mostly at rest or holds less than kOutputCheckMoving [s] of moving samples, up to kLongWindow;
// - kOutputCheckMinSpeed [rad/s]: a slower joint is left out of the fit (at rest its static friction
//   holds part of the step: with rests in, healthy pick-and-place read up to 0.15 kg at 2.5 s);
// - kOutputCheckMass [kg], kOutputCheckExplained: what a part needs;
// - the span left out around an alert in the window [s]
constexpr double kOutputCheckAfter = 1.0, kOutputCheckAgain = 0.5, kOutputCheckMoving = 0.5, kOutputCheckMinSpeed = 0.05;
constexpr double kOutputCheckMass = 0.1, kOutputCheckExplained = 0.1;
constexpr double kOutputCheckAlertBefore = 0.05, kOutputCheckAlertAfter = 0.3;
// finish(): with the default set in use, a program whose thresholds would not have raised at least
// this share of at least this many alerts is named in a note
constexpr int kProgramHintRaises = 3;
constexpr double kProgramHintShare = 2.0 / 3.0;
// the stream's timestamp jitter (Monitor::track_jitter): steps averaged over (at most), steps before it
// applies, and the growth of the widened factor that is said again in a note
constexpr double kJitterWindow = 500.0;
constexpr long kJitterMinSteps = 100;
constexpr double kJitterNoteStep = 1.1;
// joint j's threshold at (qd, qdd) times its sensitivity: the dynamic one (Cao eq. 24) when in use
// and learned, else the static level (push for the set in use, check_program_sets for the others)
inline double level_at(bool use_dynamic, const std::vector<DynamicThresholdJoint>& dynamic, const VectorJ& static_level, int j,
                       double qd, double qdd, double sensitivity) {
  return sensitivity * (use_dynamic && !dynamic.empty() ? dynamic[static_cast<size_t>(j)].evaluate(qd, qdd) : static_level[j]);
}
// a raise within this long [s] after an alert closed continues it (persistent faults dip at reversals)
constexpr double kMergeGap = 1.0;
// the velocity width [rad/s] of the doubt about a drive's direction at a reversal (reversal_load,
// threshold.hpp): at least this, else twice the twin's own blend of the motoring/back-driven switch.
// Measured on the virtual UR3e (3 mrad/s a count at 500 Hz): the drive still switched back and
// forth while the measured velocity read one count; at 1 / 2 / 3 counts the doubt is 0.71 / 0.46 / 0.28
constexpr double kReversalWidthMin = 0.01;
double reversal_width(const ident::TwinModel& twin) { return std::max(kReversalWidthMin, 2.0 * twin.direction_blend); }
// after a stream gap, a joint at rest decides again once it has moved this many pre-sliding
// distances (1 / presliding_alpha): by then the twin's memory is that of the motion it sees (the
// Dahl state is within exp(-3) = 5 % of saturation)
constexpr double kMemoryRestore = 3.0;
// samples at the start of a run (residual filter and acceleration estimate settling, the joint
// breaking away from rest) that neither the threshold learning nor the decision uses: 0.1 s at 500 Hz
constexpr long kSettleSamples = 50;
// the unseen rest's thresholds hold this long after the arm moves on [s]: the joints break away from
// static friction together, which a program that never rests never shows either
constexpr double kUnseenRestAfter = 0.5;
// an alert that began this long before a rest the thresholds never saw so long may be the rest's own [s]
// (the debounce and the last samples of the deceleration)
constexpr double kUnseenRestLead = 0.02;
// Cao's static rule: a margin above the largest healthy residual
constexpr double kStaticPeakMargin = 1.1;
// the velocity below which a joint counts as at rest for the frozen-channel check [rad/s]
constexpr double kMovingVelocity = 0.01;

// the largest residual filter cut-off a twin file may hold [Hz]: the Nyquist frequency of the
// fastest stream the monitor reads (1 kHz, e.g. Franka's FCI; RTDE streams at 500 Hz). Above it the
// first-order filter passes everything on any recording (a = 1 - exp(-2 pi fc T) > 0.96), so such
// a value is a slip, not a setting
constexpr double kMaxFilterCutoffHz = 500.0;

double iir_alpha(double cutoff_hz, double period) {
  // y += a (x - y), a = 1 - exp(-2 pi fc T)
  return 1.0 - std::exp(-2.0 * M_PI * cutoff_hz * period);
}

}  // namespace

RestBaseline::RestBaseline(int n) : run_(static_cast<size_t>(n), 0), sum_(VectorJ::Zero(n)), base_(VectorJ::Zero(n)) {}

void RestBaseline::apply(const RobotSample& s, VectorJ& value) {
  const bool target = s.has(kFieldTargetQd) && s.target_qd.size() == value.size();
  for (int j = 0; j < value.size(); ++j) {
    int& run = run_[static_cast<size_t>(j)];
    const bool rest = target && std::abs(s.target_qd[j]) < kTargetRest && std::abs(s.qd[j]) < kMeasuredRest;
    if (!rest) {
      run = 0;
      sum_[j] = 0.0;
      continue;
    }
    if (run < kSettle) {
      sum_[j] += value[j];
      if (++run == kSettle) base_[j] = sum_[j] / kSettle;
      continue;
    }
    // then the baseline follows slowly (kTrackSamples): a joint held off target by static friction
    // after a contact carries a current that its controller's integrator keeps ramping until
    // breakaway; a frozen baseline turned that healthy creep into an alert every few hundred ms
    // (scenarios/ur3e/heldout3_collisions, hcollision_6Nm_link6_a: J5 1.6 mrad off target, 11 false
    // alarms; following with 2 s left one, 0.5 s none). A step (a contact, a dropped payload) still
    // shows in full: the baseline takes 0.5 s to follow it, the debounce raises within milliseconds.
    const double v = value[j];
    value[j] -= base_[j];
    base_[j] += (v - base_[j]) / kTrackSamples;
  }
}

namespace {

nlohmann::json vec_json(const VectorJ& v) {
  nlohmann::json a = nlohmann::json::array();
  for (int i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}
// a per-joint vector of the block at path `field`: `n` finite numbers (at most kMaxDof, VectorJ's
// capacity: more would write past its inline storage), each > 0 when `positive`
VectorJ joint_array(const nlohmann::json& a, const std::string& origin, const std::string& field, int n, bool positive) {
  if (!a.is_array()) throw ParseError(origin, 0, field, fmt::format("expected an array of numbers (one per joint), got {}", json_brief(a)));
  if (a.size() > static_cast<size_t>(kMaxDof))
    throw ParseError(origin, 0, field, fmt::format("expected at most {} values (one per joint), got {}", kMaxDof, a.size()));
  if (static_cast<int>(a.size()) != n) throw ParseError(origin, 0, field, fmt::format("expected {} values (one per joint), got {}", n, a.size()));
  VectorJ v(n);
  for (int i = 0; i < n; ++i) {
    const std::string f = json_element(field, static_cast<size_t>(i));
    v[i] = json_number(a[static_cast<size_t>(i)], origin, f);
    if (positive && !(v[i] > 0.0)) throw ParseError(origin, 0, f, fmt::format("expected a number > 0, got {}", v[i]));
  }
  return v;
}
VectorJ joint_values(const JsonFields& o, const char* key, int n, bool positive) {
  return joint_array(o.need(key), o.origin(), o.field(key), n, positive);
}
VectorJ nonnegative_joint_values(const JsonFields& o, const char* key, int n) {
  VectorJ v = joint_values(o, key, n, false);
  for (int i = 0; i < n; ++i)
    if (!(v[i] >= 0.0))
      throw ParseError(o.origin(), 0, json_element(o.field(key), static_cast<size_t>(i)), fmt::format("expected a number >= 0, got {}", v[i]));
  return v;
}

// MonitorConfig::residual_filter: 0, 1 or n entries, each "iir" or "fir"
void check_residual_filter(const MonitorConfig& c, int n) {
  if (c.residual_filter.size() > 1 && static_cast<int>(c.residual_filter.size()) != n)
    throw InvalidArgument(fmt::format("residual_filter (--filter) has {} entries, expected 0, 1 or {} (one per joint)", c.residual_filter.size(), n));
  for (size_t j = 0; j < c.residual_filter.size(); ++j)
    if (c.residual_filter[j] != "iir" && c.residual_filter[j] != "fir")
      throw InvalidArgument(fmt::format("residual_filter (--filter) of J{} is '{}', expected 'iir' or 'fir'", j + 1, c.residual_filter[j]));
}

// the residual filter kind of joint j (MonitorConfig::residual_filter)
const std::string& filter_kind(const MonitorConfig& c, int j) {
  static const std::string kIir = "iir";
  if (c.residual_filter.empty()) return kIir;
  return c.residual_filter.size() == 1 ? c.residual_filter[0] : c.residual_filter[static_cast<size_t>(j)];
}

// Cao eq. (29) FIR for the joints configured "fir"; joints without taps use the IIR
std::vector<signal::FirFilter> make_fir_filters(const MonitorConfig& c, int n) {
  check_residual_filter(c, n);
  std::vector<signal::FirFilter> f(static_cast<size_t>(n));
  for (int j = 0; j < n; ++j)
    if (filter_kind(c, j) == "fir") f[static_cast<size_t>(j)] = signal::FirFilter(signal::cao_torque_fir_taps());
  return f;
}

// A twin's windowed acceleration at this sample period, none without an acceleration window: as
// many samples per mean as the identification's half window and one, restarted by a step longer
// than that many gap steps (Monitor's, and the thresholds' learner's through MonitorAcceleration)
std::optional<WindowedAcceleration> windowed_acceleration(const ident::TwinModel& twin, int n, double period, double gap_factor) {
  if (!(twin.acceleration_window > 0.0)) return std::nullopt;
  const int w = twin.acceleration_half_width(period) + 1;
  return WindowedAcceleration(n, w, w * gap_factor * period);
}

// The monitor's joint acceleration a sample at a time (Monitor::judge), for the thresholds' learner:
// the controller's target where the recording has one, else the twin's windowed estimate, else the
// causal IIR-smoothed difference of the measured velocity (a gap holds it; a threshold learned on a
// zero-phase derivative would not be the one the monitor's residual meets). The reference is valid
// while `s` is.
class MonitorAcceleration {
 public:
  /// `windowed`: windowed_acceleration's (used where the recording has no target acceleration)
  MonitorAcceleration(int n, std::uint32_t present, double alpha, double gap_period, std::optional<WindowedAcceleration> windowed = {})
      : target_(present & kFieldTargetQdd), alpha_(alpha), gap_period_(gap_period), qdd_(VectorJ::Zero(n)) {
    if (!target_) windowed_ = std::move(windowed);
  }
  /// the estimate is one the monitor judges on: not a windowed one still held after a (re)start, nor
  /// within kWindowSettle samples after it became whole (the residual filter's tail)
  bool settled() const { return !windowed_ || since_ready_ > kWindowSettle; }
  const VectorJ& push(const RobotSample& s) {
    if (target_) return s.target_qdd;  // (as ident::joint_accelerations takes it)
    if (windowed_) {  // (as Monitor::judge: its own restart)
      const VectorJ& a = windowed_->push(s.timestamp, s.qd);
      since_ready_ = windowed_->ready() ? since_ready_ + 1 : 0;
      return a;
    }
    if (started_) {
      const double dt = s.timestamp - previous_t_;
      if (dt > 0.0 && dt <= gap_period_ && !s.gap_before) qdd_ += alpha_ * ((s.qd - previous_qd_) / dt - qdd_);
    }
    started_ = true;
    previous_t_ = s.timestamp;
    previous_qd_ = s.qd;
    return qdd_;
  }

 private:
  bool target_;
  double alpha_, gap_period_;
  std::optional<WindowedAcceleration> windowed_;
  long since_ready_ = 0;
  VectorJ qdd_, previous_qd_;
  double previous_t_ = 0.0;
  bool started_ = false;
};

}  // namespace

// The drive's direction in doubt. The drive switches hard between its motoring and back-driven
// levels when the joint's velocity crosses zero, at an instant the twin cannot place closer than
// its blend's width (the target's crossing within the joint's tracking error, or a count of the
// encoder); there the blended prediction sits between the two levels, and while the current is at
// either it leaves up to half the drive's step in the residual (J2 of a slow loaded figure-eight
// switched 7 ms before its target's crossing: 0.16 A against a 0.149 A threshold). Where the blend
// is in doubt (TwinModel::drive_in_doubt) the residual is the current's distance to the level it is
// nearer to: the drive's state read on the current itself. A fault pushing the current toward the
// other level is read as the switch only up to the step, and only inside the doubt.
void resolve_drive_doubt(const ident::TwinModel& twin, const VectorJ& tau, const ident::FrictionMemory& memory, VectorJ& r) {
  const int n = twin.n_dof();
  double to_motoring = 0.0, to_back_driven = 0.0;
  for (int j = 0; j < n; ++j) {
    if (!twin.drive_in_doubt(j, tau[j], memory, to_motoring, to_back_driven)) continue;
    const double a = r[j] - to_motoring, b = r[j] - to_back_driven;
    r[j] = std::abs(a) <= std::abs(b) ? a : b;
  }
}

namespace {

// The residual the monitor decides on, a sample at a time, as learn_thresholds learns it: the
// twin's current residual, temperature-compensated, IIR- or FIR-filtered, its rest baseline taken
// off. push() hands the twin's torque too; the run's payload (PayloadTimeline) is set on the twin
// by the caller, which says when it changed.
class LearnedResidual {
 public:
  LearnedResidual(const ident::TwinModel& twin, const MonitorConfig& c, double alpha)
      : c_(c), alpha_(alpha), fir_(make_fir_filters(c, twin.n_dof())), rest_(twin.n_dof()) {}
  /// `restarted`: the twin took another payload at this sample
  const VectorJ& push(ident::TwinModel& twin, const RobotSample& s, const VectorJ& qdd, bool restarted) {
    // a payload the twin takes: the filter starts again from zero and the rest is measured again
    // (Monitor::restart_estimators, Monitor::carry)
    if (restarted) {
      restarted_ = true;
      rest_ = RestBaseline(twin.n_dof());
      for (auto& f : fir_) f.reset();
    }
    twin.advance(memory_, s, qdd);
    twin.predict(s.q, s.qd, qdd, s.temperature, tau_, i_, &memory_);
    r_ = s.current - i_;
    // the monitor's temperature compensation (Monitor::push), so thresholds learned on a warm-up
    // from cold see the residual the monitor will see. (Not the drive's doubt, resolve_drive_doubt:
    // the thresholds keep the margin of the blended residual. Learned on the resolved one, the
    // observer's J2/J3 levels fell by a third and a contact 0.3 s after an undeclared pick read as a
    // second payload step, six false alarms after it; docs/validation.md, session 32)
    if (c_.trend.temperature_slope.size() == r_.size())
      for (int j = 0; j < r_.size(); ++j)
        if (s.temperature.size() > j && std::isfinite(s.temperature[j]))
          r_[j] -= c_.trend.temperature_slope[j] * s.qd[j] * (s.temperature[j] - c_.trend.temperature_ref);
    if (first_) rf_ = r_;
    else if (restarted_) rf_ = alpha_ * r_;  // (from zero: rf = 0 + alpha (r - 0))
    else rf_ += alpha_ * (r_ - rf_);
    first_ = false;
    restarted_ = false;
    for (size_t j = 0; j < fir_.size(); ++j)
      if (!fir_[j].taps().empty()) rf_[static_cast<int>(j)] = fir_[j].push(r_[static_cast<int>(j)]);
    decided_ = rf_;  // what the decision sees (Monitor::push)
    rest_.apply(s, decided_);
    return decided_;
  }
  const VectorJ& torque() const { return tau_; }  ///< the twin's, at the last push

 private:
  const MonitorConfig& c_;
  double alpha_;
  std::vector<signal::FirFilter> fir_;
  RestBaseline rest_;
  ident::FrictionMemory memory_;
  VectorJ i_, tau_, r_, rf_, decided_;
  bool first_ = true, restarted_ = false;
};

// The drive torque of the viscous friction's temperature dependence that the twin leaves out:
// g_j s_j qd_j (T_j - T_ref), with s the slope learned on a healthy warm-up [A·s/rad/°C] (trend.hpp)
// and g_j the twin's gain (the momentum observer works in the twin's torque units). Zero for a
// joint without a temperature reading or without a slope. Allocation-free.
void temperature_drive_torque(const ident::TwinModel& twin, const VectorJ& slope, double t_ref, const RobotSample& s,
                              VectorJ& out) {
  const int n = twin.n_dof();
  for (int j = 0; j < n; ++j) {
    const bool known = slope.size() == n && s.temperature.size() > j && std::isfinite(s.temperature[j]);
    out[j] = known ? twin.joints[static_cast<size_t>(j)].gain * slope[j] * s.qd[j] * (s.temperature[j] - t_ref) : 0.0;
  }
}

nlohmann::json trend_json(const TrendConfig& t) {
  nlohmann::json j{{"enabled", t.enabled}, {"window_s", t.window_s}, {"cycle_period", t.cycle_period}, {"v_min", t.v_min},
                   {"min_moving_fraction", t.min_moving_fraction}, {"baseline_windows", t.baseline_windows},
                   {"min_windows", t.min_windows}, {"history", t.history}, {"z_crit", t.z_crit},
                   {"min_rate_pct_per_h", t.min_rate_pct_per_h}, {"persist", t.persist}, {"temperature_ref", t.temperature_ref}};
  if (t.temperature_slope.size()) j["temperature_slope"] = vec_json(t.temperature_slope);
  return j;
}
// the trend block (every field the writer writes; temperature_slope only once learned)
TrendConfig trend_from_json(const JsonFields& j, int n) {
  j.only({"enabled", "window_s", "cycle_period", "v_min", "min_moving_fraction", "baseline_windows", "min_windows", "history", "z_crit",
          "min_rate_pct_per_h", "persist", "temperature_ref", "temperature_slope"});
  TrendConfig t;
  t.enabled = j.boolean("enabled");
  t.window_s = j.positive("window_s");
  t.cycle_period = j.nonnegative("cycle_period");
  t.v_min = j.positive("v_min");
  t.min_moving_fraction = j.number("min_moving_fraction");
  if (!(t.min_moving_fraction > 0.0 && t.min_moving_fraction <= 1.0))
    j.fail("min_moving_fraction", fmt::format("expected a number in (0, 1], got {}", t.min_moving_fraction));
  t.baseline_windows = j.whole("baseline_windows");
  if (t.baseline_windows < 1) j.fail("baseline_windows", fmt::format("expected a whole number >= 1, got {}", t.baseline_windows));
  t.min_windows = j.whole("min_windows");
  if (t.min_windows < 3 || t.min_windows < t.baseline_windows)
    j.fail("min_windows", fmt::format("expected a whole number >= 3 and >= baseline_windows ({}), got {}", t.baseline_windows, t.min_windows));
  t.history = j.whole("history");
  if (t.history < t.min_windows) j.fail("history", fmt::format("expected a whole number >= min_windows ({}), got {}", t.min_windows, t.history));
  t.z_crit = j.positive("z_crit");
  t.min_rate_pct_per_h = j.nonnegative("min_rate_pct_per_h");
  t.persist = j.whole("persist");
  if (t.persist < 1) j.fail("persist", fmt::format("expected a whole number >= 1, got {}", t.persist));
  t.temperature_ref = j.number("temperature_ref");
  if (j.has("temperature_slope")) t.temperature_slope = joint_values(j, "temperature_slope", n, false);
  return t;
}

nlohmann::json dynamic_json(const std::vector<DynamicThresholdJoint>& dynamic) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& d : dynamic)
    a.push_back({{"psi_qdd", d.psi_qdd}, {"psi_qd", d.psi_qd}, {"psi_rev", d.psi_rev}, {"upsilon", d.upsilon},
                 {"rho", d.rho}, {"margin", d.margin}, {"alpha", d.alpha}});
  return a;
}
// a dynamic threshold per joint [Cao eq. 24]: the LP of eq. 26 bounds psi and upsilon below by 0
// (threshold.cpp), and its max gap alpha and the margin xi are >= 0 too; rho > 0 (the grid's).
// `allow_empty`: none learned is an empty array (a set the monitor does not need them for)
std::vector<DynamicThresholdJoint> dynamic_from_json(const JsonFields& o, const char* key, int n, bool allow_empty) {
  const nlohmann::json& a = o.need(key);
  if (!a.is_array() || (static_cast<int>(a.size()) != n && !(allow_empty && a.empty())))
    o.fail(key, fmt::format("expected {} thresholds (one per joint){}, got {}", n, allow_empty ? " or none" : "",
                            a.is_array() ? std::to_string(a.size()) : json_brief(a)));
  std::vector<DynamicThresholdJoint> out;
  for (size_t i = 0; i < a.size(); ++i) {
    const JsonFields d(a[i], o.origin(), json_element(o.field(key), i));
    d.only({"psi_qdd", "psi_qd", "psi_rev", "upsilon", "rho", "margin", "alpha"});
    out.push_back({d.nonnegative("psi_qdd"), d.nonnegative("psi_qd"), d.nonnegative("psi_rev"), d.nonnegative("upsilon"), d.positive("rho"),
                   d.nonnegative("margin"), d.nonnegative("alpha")});
  }
  return out;
}

// the sizes of one threshold set ("what" names it in the message)
void check_levels(const VectorJ& static_level, const std::vector<DynamicThresholdJoint>& dynamic, bool use_dynamic, int n,
                  const std::string& what) {
  if (static_level.size() != n)
    throw InvalidArgument(fmt::format("{} static_level has size {}, expected {}", what, static_level.size(), n));
  if (use_dynamic && static_cast<int>(dynamic.size()) != n)
    throw InvalidArgument(fmt::format("{} dynamic thresholds: {} joints, expected {}", what, dynamic.size(), n));
}

// the largest debounce count accepted in a file (the CLI's --raise-after range): each count is a ring of
// that many ratios when the margin is tracked
constexpr int kMaxDebounce = 1000;

// a per-joint observer debounce choice with its validation ratios; only where the set has observer thresholds
void check_choice(const ObserverDebounceChoice& choice, bool has_observer, int n, const std::string& where) {
  const auto& d = choice.raise_after;
  const auto& ratio = choice.ratio;
  if (d.empty() && ratio.empty()) return;
  if (!has_observer)
    throw InvalidArgument(fmt::format("{} has an observer debounce choice (observer_raise_after_joint) but no observer thresholds", where));
  if (static_cast<int>(d.size()) != n)
    throw InvalidArgument(fmt::format("{} observer_raise_after_joint has {} entries, expected {} (one per joint)", where, d.size(), n));
  for (size_t j = 0; j < d.size(); ++j)
    if (d[j] < 1 || d[j] > kMaxDebounce)
      throw InvalidArgument(fmt::format("{} observer_raise_after_joint of joint {} is {}, must be 1 to {}", where, j + 1, d[j], kMaxDebounce));
  for (size_t r = 0; r < ratio.size(); ++r)
    if (ratio[r].size() != n)
      throw InvalidArgument(fmt::format("{} observer_validation_ratio row {} has {} entries, expected {}", where, r + 1, ratio[r].size(), n));
}

// a choice into the JSON object of its threshold set (nothing when none was chosen)
void put_choice(nlohmann::json& j, const ObserverDebounceChoice& choice) {
  if (!choice.raise_after.empty()) j["observer_raise_after_joint"] = choice.raise_after;
  if (choice.ratio.empty()) return;
  nlohmann::json& rows = j["observer_validation_ratio"] = nlohmann::json::array();
  for (const auto& r : choice.ratio) rows.push_back(vec_json(r));
}

// a debounce count of the block: a whole number from `lo` to kMaxDebounce
int debounce_count(const JsonFields& o, const char* key, int lo) {
  const int x = o.whole(key);
  if (x < lo || x > kMaxDebounce) o.fail(key, fmt::format("expected a whole number from {} to {}, got {}", lo, kMaxDebounce, x));
  return x;
}

// the per-joint observer debounce choice of the threshold set `j`, when it has one
ObserverDebounceChoice get_choice(const JsonFields& j, int n) {
  ObserverDebounceChoice c;
  if (j.has("observer_raise_after_joint")) {
    const nlohmann::json& a = j.need("observer_raise_after_joint");
    if (!a.is_array() || static_cast<int>(a.size()) != n)
      j.fail("observer_raise_after_joint", fmt::format("expected {} counts (one per joint), got {}", n, a.is_array() ? std::to_string(a.size()) : json_brief(a)));
    for (size_t i = 0; i < a.size(); ++i) {
      const std::string f = json_element(j.field("observer_raise_after_joint"), i);
      // whole_int: get<int>() would wrap 4294967297 to 1
      const std::optional<int> x = a[i].is_number_integer() ? whole_int(a[i].get<double>()) : std::nullopt;
      if (!x) throw ParseError(j.origin(), 0, f, fmt::format("expected a whole number within +-{}, got {}", std::numeric_limits<int>::max(), json_brief(a[i])));
      if (*x < 1 || *x > kMaxDebounce) throw ParseError(j.origin(), 0, f, fmt::format("expected a whole number from 1 to {}, got {}", kMaxDebounce, *x));
      c.raise_after.push_back(*x);
    }
  }
  if (j.has("observer_validation_ratio")) {
    const nlohmann::json& a = j.need("observer_validation_ratio");
    if (!a.is_array()) j.fail("observer_validation_ratio", fmt::format("expected an array of per-joint arrays, got {}", json_brief(a)));
    for (size_t r = 0; r < a.size(); ++r)
      c.ratio.push_back(joint_array(a[r], j.origin(), json_element(j.field("observer_validation_ratio"), r), n, false));
  }
  return c;
}

}  // namespace

void check_program_name(const std::string& name, const std::string& what) {
  if (name.empty()) throw InvalidArgument(fmt::format("{}: the program name is empty", what));
  for (char ch : name)
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '_' && ch != '-' && ch != '.')
      throw InvalidArgument(fmt::format("{}: program name '{}' has the character '{}'; use letters, digits, '_', '-', '.'", what,
                                        name, ch));
}

void MonitorConfig::select_program(const std::string& name) {
  if (name.empty()) return;
  const auto it = programs.find(name);
  if (it == programs.end()) {
    std::vector<std::string> known;
    for (const auto& [k, v] : programs) known.push_back(k);
    throw InvalidArgument(fmt::format("no thresholds learned for program '{}' (known: {}); learn them with 'twinwatch thresholds "
                                      "--program {} HEALTHY.csv...' or run without --program for the default set",
                                      name, known.empty() ? "none" : fmt::format("{}", fmt::join(known, ", ")), name));
  }
  static_level = it->second.static_level;
  dynamic = it->second.dynamic;
  payload_max = it->second.payload_max;
  reversal_load_max = it->second.reversal_load_max;
  crawl_max = it->second.crawl_max;
  longest_rest = it->second.longest_rest;
  if (it->second.observer_level.size() != 0) {
    observer_level = it->second.observer_level;
    observer_dynamic = it->second.observer_dynamic;
    // the debounce chosen for these thresholds (none chosen: the shared count)
    observer_choice = it->second.observer_choice;
  }
  program = name;
}

namespace {
// MonitorConfig::reversal_load_max: empty, or one finite value >= 0 per joint
void check_reversal_load(const VectorJ& v, int n, const std::string& what) {
  if (v.size() == 0) return;
  if (v.size() != n) throw InvalidArgument(fmt::format("{} reversal_load_max has size {}, expected {} (one per joint)", what, v.size(), n));
  for (int j = 0; j < n; ++j)
    if (!(v[j] >= 0.0) || !std::isfinite(v[j]))
      throw InvalidArgument(fmt::format("{} reversal_load_max of joint {} is {}, must be a finite number >= 0", what, j + 1, v[j]));
}
}  // namespace

void MonitorConfig::validate(int n) const {
  check_levels(static_level, dynamic, use_dynamic, n, "monitor");
  for (const auto& [name, set] : programs) check_levels(set.static_level, set.dynamic, use_dynamic, n, fmt::format("program '{}'", name));
  if (!(filter_cutoff_hz > 0.0)) throw InvalidArgument(fmt::format("filter_cutoff_hz is {}, must be > 0", filter_cutoff_hz));
  if (raise_after < 1) throw InvalidArgument(fmt::format("raise_after is {}, must be >= 1", raise_after));
  if (clear_after < 1) throw InvalidArgument(fmt::format("clear_after is {}, must be >= 1", clear_after));
  if (!(resume_widen >= 1.0 && std::isfinite(resume_widen)))
    throw InvalidArgument(fmt::format("resume_widen is {}, must be finite and >= 1", resume_widen));
  if (!part_com_in_reach(part_com))
    throw InvalidArgument(fmt::format("part_com_m is ({:g}, {:g}, {:g}) m, {:g} m from the flange: expected a centre of mass within {:g} m of it "
                                      "(in mm? give metres)",
                                      part_com.x(), part_com.y(), part_com.z(), part_com.norm(), model::kPayloadComMax));
  if (observer_raise_after < 0)
    throw InvalidArgument(fmt::format("observer_raise_after is {}, must be >= 1 (or 0: raise_after)", observer_raise_after));
  check_choice(observer_choice, observer_level.size() != 0, n, "monitor");
  for (const auto& [name, set] : programs) check_choice(set.observer_choice, set.observer_level.size() != 0, n, fmt::format("program '{}'", name));
  if (sensitivity.size() != 0 && sensitivity.size() != n)
    throw InvalidArgument(fmt::format("sensitivity has size {}, expected {} (one per joint)", sensitivity.size(), n));
  for (int j = 0; j < sensitivity.size(); ++j)
    // (1e9 was taken: the thresholds a billion times wider, the joint blind without a word)
    if (!(sensitivity[j] > 0.0 && sensitivity[j] <= kMaxSensitivity))
      throw InvalidArgument(fmt::format("sensitivity (--sensitivity) of joint {} is {}, expected a factor > 0 and at most {:g} (thresholds that "
                                        "much wider than learned; more leaves the joint blind)",
                                        j + 1, sensitivity[j], kMaxSensitivity));
  if (!(nominal_period > 0.0)) throw InvalidArgument(fmt::format("nominal_period is {}, must be > 0", nominal_period));
  check_residual_filter(*this, n);
  check_reversal_load(reversal_load_max, n, "monitor");
  if (crawl_max.size() && crawl_max.size() != n)
    throw InvalidArgument(fmt::format("monitor crawl_max has size {}, expected {} (one per joint)", crawl_max.size(), n));
  for (const auto& [name, set] : programs) check_reversal_load(set.reversal_load_max, n, fmt::format("program '{}'", name));
  trend.validate(n);
  if (observer_level.size() != 0) {
    if (!(observer_gain > 0.0)) throw InvalidArgument(fmt::format("observer_gain is {} 1/s, must be > 0", observer_gain));
    if (observer_level.size() != n)
      throw InvalidArgument(fmt::format("monitor observer_level has size {}, expected {}", observer_level.size(), n));
    if (use_dynamic && !observer_dynamic.empty() && static_cast<int>(observer_dynamic.size()) != n)
      throw InvalidArgument(fmt::format("monitor observer_dynamic thresholds: {} joints, expected {}", observer_dynamic.size(), n));
  }
}

std::string MonitorConfig::to_json() const {
  nlohmann::json j;
  j["static_level_A"] = vec_json(static_level);
  if (!dynamic.empty()) j["dynamic"] = dynamic_json(dynamic);
  j["use_dynamic"] = use_dynamic;
  j["filter_cutoff_hz"] = filter_cutoff_hz;
  j["raise_after"] = raise_after;
  j["clear_after"] = clear_after;
  if (observer_raise_after > 0) j["observer_raise_after"] = observer_raise_after;
  put_choice(j, observer_choice);
  if (sensitivity.size()) j["sensitivity"] = vec_json(sensitivity);
  j["nominal_period"] = nominal_period;
  if (!residual_filter.empty()) j["residual_filter"] = residual_filter;
  j["trend"] = trend_json(trend);
  if (std::isfinite(payload_max)) j["payload_max_kg"] = payload_max;
  if (reversal_load_max.size()) j["reversal_load_max"] = vec_json(reversal_load_max);
  if (crawl_max.size()) j["crawl_max_s"] = vec_json(crawl_max);
  if (std::isfinite(longest_rest)) j["longest_rest_s"] = longest_rest;
  if (part_com != default_part_com()) j["part_com_m"] = {part_com.x(), part_com.y(), part_com.z()};
  for (const auto& [name, set] : programs) {
    j["programs"][name] = {{"static_level_A", vec_json(set.static_level)}, {"dynamic", dynamic_json(set.dynamic)},
                           {"runs", set.runs}, {"seconds", set.seconds}};
    if (std::isfinite(set.payload_max)) j["programs"][name]["payload_max_kg"] = set.payload_max;
    if (set.reversal_load_max.size()) j["programs"][name]["reversal_load_max"] = vec_json(set.reversal_load_max);
    if (set.crawl_max.size()) j["programs"][name]["crawl_max_s"] = vec_json(set.crawl_max);
    if (std::isfinite(set.longest_rest)) j["programs"][name]["longest_rest_s"] = set.longest_rest;
  }
  for (const auto& [name, set] : programs)
    if (set.observer_level.size() != 0) {
      j["programs"][name]["observer_level_Nm"] = vec_json(set.observer_level);
      j["programs"][name]["observer_dynamic"] = dynamic_json(set.observer_dynamic);
      put_choice(j["programs"][name], set.observer_choice);
    }
  j["observer_gain"] = observer_gain;
  j["observer_alerts"] = observer_alerts;
  if (observer_level.size()) j["observer_level_Nm"] = vec_json(observer_level);
  for (const auto& d : observer_dynamic)
    j["observer_dynamic"].push_back({{"psi_qdd", d.psi_qdd}, {"psi_qd", d.psi_qd}, {"psi_rev", d.psi_rev}, {"upsilon", d.upsilon},
                                     {"rho", d.rho}, {"margin", d.margin}, {"alpha", d.alpha}});
  return j.dump();
}

MonitorConfig MonitorConfig::from_json(const std::string& text, const std::string& origin, int n_dof) {
  const nlohmann::json j = parse_json(text, origin, "monitor");
  try {
    const JsonFields m(j, origin, "monitor");
    m.only({"static_level_A", "dynamic", "use_dynamic", "filter_cutoff_hz", "raise_after", "clear_after", "observer_raise_after",
            "observer_raise_after_joint", "observer_validation_ratio", "sensitivity", "nominal_period", "residual_filter", "trend", "programs",
            "observer_gain", "observer_alerts", "observer_level_Nm", "observer_dynamic", "payload_max_kg", "reversal_load_max",
            "longest_rest_s", "crawl_max_s", "part_com_m"});
    // the joint count: the twin's, or (a block read on its own) that of the static levels
    const nlohmann::json& levels = m.need("static_level_A");
    const int n = n_dof > 0 ? n_dof : levels.is_array() ? static_cast<int>(std::min<size_t>(levels.size(), kMaxDof + 1)) : 0;
    if (n < 1) m.fail("static_level_A", "expected at least 1 value (one per joint), got 0");
    MonitorConfig c;
    // the default threshold set; the dynamic thresholds are written when learned
    c.static_level = joint_values(m, "static_level_A", n, true);
    c.use_dynamic = m.boolean("use_dynamic");
    if (m.has("dynamic")) c.dynamic = dynamic_from_json(m, "dynamic", n, false);
    else if (c.use_dynamic) m.fail("dynamic", "missing required field (use_dynamic is true)");
    c.filter_cutoff_hz = m.positive("filter_cutoff_hz");
    if (c.filter_cutoff_hz > kMaxFilterCutoffHz)
      m.fail("filter_cutoff_hz", fmt::format("expected a number in (0, {}] Hz, got {}", kMaxFilterCutoffHz, c.filter_cutoff_hz));
    c.raise_after = debounce_count(m, "raise_after", 1);
    c.clear_after = debounce_count(m, "clear_after", 1);
    // written when set; 0 means raise_after, as in validate() (the session-13 sweep twins hold a 0)
    if (m.has("observer_raise_after")) c.observer_raise_after = debounce_count(m, "observer_raise_after", 0);
    c.observer_choice = get_choice(m, n);
    if (m.has("sensitivity")) c.sensitivity = joint_values(m, "sensitivity", n, true);
    c.nominal_period = m.positive("nominal_period");
    if (m.has("residual_filter")) {
      c.residual_filter = m.texts("residual_filter");
      if (c.residual_filter.size() != 1 && static_cast<int>(c.residual_filter.size()) != n)
        m.fail("residual_filter", fmt::format("expected 1 or {} entries (one per joint), got {}", n, c.residual_filter.size()));
      for (size_t k = 0; k < c.residual_filter.size(); ++k)
        if (c.residual_filter[k] != "iir" && c.residual_filter[k] != "fir")
          throw ParseError(origin, 0, json_element(m.field("residual_filter"), k), fmt::format("expected \"iir\" or \"fir\", got \"{}\"", c.residual_filter[k]));
    }
    c.trend = trend_from_json(m.object("trend"), n);
    if (m.has("payload_max_kg")) c.payload_max = m.nonnegative("payload_max_kg");
    if (m.has("reversal_load_max")) c.reversal_load_max = nonnegative_joint_values(m, "reversal_load_max", n);
    if (m.has("crawl_max_s")) c.crawl_max = nonnegative_joint_values(m, "crawl_max_s", n);
    if (m.has("longest_rest_s")) c.longest_rest = m.nonnegative("longest_rest_s");
    if (m.has("part_com_m")) {
      const nlohmann::json& a = m.need("part_com_m");
      if (!a.is_array() || a.size() != 3)
        m.fail("part_com_m", fmt::format("expected 3 numbers (x, y, z in the flange frame, m), got {}", json_brief(a)));
      for (int k = 0; k < 3; ++k) c.part_com[k] = json_number(a[static_cast<size_t>(k)], origin, json_element(m.field("part_com_m"), static_cast<size_t>(k)));
      if (!part_com_in_reach(c.part_com))
        m.fail("part_com_m", fmt::format("expected a point within {:g} m of the flange, got {:g} m away (in mm? give metres)", model::kPayloadComMax,
                                         c.part_com.norm()));
    }
    // the sets learned per program
    if (m.has("programs")) {
      const JsonFields programs = m.object("programs");
      for (const auto& [name, value] : programs.json().items()) {
        try {
          check_program_name(name);
        } catch (const InvalidArgument& e) {
          programs.fail(name, e.what());
        }
        const JsonFields p(value, origin, programs.field(name));
        p.only({"static_level_A", "dynamic", "runs", "seconds", "observer_level_Nm", "observer_dynamic", "observer_raise_after_joint",
                "observer_validation_ratio", "payload_max_kg", "reversal_load_max", "longest_rest_s", "crawl_max_s"});
        ThresholdSet set;
        set.static_level = joint_values(p, "static_level_A", n, true);
        set.dynamic = dynamic_from_json(p, "dynamic", n, !c.use_dynamic);
        set.runs = p.whole("runs");
        if (set.runs < 0) p.fail("runs", fmt::format("expected a whole number >= 0, got {}", set.runs));
        set.seconds = p.nonnegative("seconds");
        if (p.has("payload_max_kg")) set.payload_max = p.nonnegative("payload_max_kg");
        if (p.has("reversal_load_max")) set.reversal_load_max = nonnegative_joint_values(p, "reversal_load_max", n);
        if (p.has("crawl_max_s")) set.crawl_max = nonnegative_joint_values(p, "crawl_max_s", n);
        if (p.has("longest_rest_s")) set.longest_rest = p.nonnegative("longest_rest_s");
        // the observer's set comes whole (written together)
        if (p.has("observer_level_Nm") || p.has("observer_dynamic")) {
          set.observer_level = joint_values(p, "observer_level_Nm", n, true);
          set.observer_dynamic = dynamic_from_json(p, "observer_dynamic", n, true);
        }
        set.observer_choice = get_choice(p, n);
        c.programs[name] = std::move(set);
      }
    }
    // the momentum observer: on when its thresholds were learned
    c.observer_gain = m.positive("observer_gain");
    c.observer_alerts = m.boolean("observer_alerts");
    if (m.has("observer_level_Nm")) c.observer_level = joint_values(m, "observer_level_Nm", n, true);
    if (m.has("observer_dynamic")) {
      if (!m.has("observer_level_Nm")) m.fail("observer_level_Nm", "missing required field (observer_dynamic is there)");
      c.observer_dynamic = dynamic_from_json(m, "observer_dynamic", n, true);
    }
    // what validate() checks across fields (the per-field checks above already name the field)
    try {
      c.validate(n);
    } catch (const InvalidArgument& e) {
      throw ParseError(origin, 0, "monitor", e.what());
    }
    return c;
  } catch (const nlohmann::json::exception& e) {  // (every field is type-checked above: a safety net for the fuzzer's contract)
    throw ParseError(origin, 0, "monitor", fmt::format("wrong type: {}", e.what()));
  }
}

MonitorConfig MonitorConfig::from_twin(const ident::TwinModel& twin) {
  const std::string origin = twin.origin.empty() ? std::string("the twin") : twin.origin;
  if (twin.monitor_json.empty())
    throw InvalidArgument(fmt::format("{} has no monitor thresholds: learn them with 'twinwatch thresholds --twin {} HEALTHY.csv...'", origin, origin));
  return from_json(twin.monitor_json, origin, twin.n_dof());
}

namespace {

// the longest stretch of consecutive samples for which a condition holds [s] (learning): see()
// each sample's timestamp and whether it holds, in order
class LongestStretch {
 public:
  void see(double t, bool holds) {
    if (!holds) {
      began_ = std::numeric_limits<double>::quiet_NaN();
      return;
    }
    if (std::isnan(began_)) began_ = t;
    longest_ = std::max(longest_, t - began_);
  }
  double longest() const { return longest_; }

 private:
  double longest_ = 0.0, began_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace

MonitorConfig learn_thresholds(const ident::TwinModel& twin, const std::vector<HealthyRun>& given, const MonitorConfig& settings,
                               const LearnOptions& options) {
  std::vector<std::unique_ptr<device::HeldSamples>> store;
  const std::vector<const device::SampleSource*> runs = samples_of(given, store, "learn thresholds");
  if (runs.empty()) throw InvalidArgument("learn thresholds: no healthy runs given");
  const int n = twin.n_dof();
  MonitorConfig c = settings;
  // the residual filter at each run's own rate, as the monitor runs it (a 1 kHz log filtered with a
  // 500 Hz coefficient is smoothed half as much, and its thresholds come out too low)
  if (runs.front()->median_period() > 0.0) c.nominal_period = runs.front()->median_period();
  const auto period_of = [&](const device::SampleSource& src) { return src.median_period() > 0.0 ? src.median_period() : c.nominal_period; };
  VectorJ peak = VectorJ::Zero(n), obs_peak = VectorJ::Zero(n), load = VectorJ::Zero(n), crawl = VectorJ::Zero(n);
  double longest_rest = 0.0;
  const bool with_observer = c.observer_gain > 0.0;
  const double width = reversal_width(twin);
  c.payload_max = 0.0;  // (the heaviest payload of these runs, declared ones included)
  // The runs are read twice, and never held (a shift of healthy recordings is 1.7 GB per robot hour):
  // first each run's payload from sample to sample, its crawls and rests, and how many samples the
  // monitor decides on; then the residuals and the observer, from which the thresholds keep sums and
  // the samples the dynamic fit uses (its uniform decimation needs their count beforehand).
  std::vector<PayloadTimeline> timelines;
  std::vector<size_t> skips;
  // a twin's windowed acceleration judges a sample only once it is whole (MonitorAcceleration::settled):
  // per run, the samples it is not (empty: every one is)
  std::vector<std::vector<char>> unsettled(runs.size());
  size_t judged = 0, judged_observer = 0;
  for (size_t i = 0; i < runs.size(); ++i) {
    const device::SampleSource& src = *runs[i];
    PayloadTimeline payload(twin, given[i].payload, c.follow_payload && (src.present() & kFieldPayload));
    // skip the filter's start-up
    const size_t skip = std::min(src.size(), static_cast<size_t>(kSettleSamples));
    // each joint's longest crawl (its direction in doubt), and the arm's longest rest after the
    // start-up (commanded; on a run without target velocities, measured: RestBaseline::arm_rest)
    std::vector<LongestStretch> crawls(static_cast<size_t>(n));
    LongestStretch rest;
    std::optional<MonitorAcceleration> acc;
    if (!(src.present() & kFieldTargetQdd))
      if (auto w = windowed_acceleration(twin, n, period_of(src), c.gap_factor)) {
        acc.emplace(n, src.present(), 1.0, c.gap_factor * period_of(src), std::move(w));
        unsettled[i].assign(src.size(), 0);
      }
    src.replay([&](size_t k, const RobotSample& s) {
      payload.see(k, s);
      if (acc) {
        acc->push(s);
        unsettled[i][k] = acc->settled() ? 0 : 1;
      }
      if (k < skip) return;
      for (int j = 0; j < n; ++j) crawls[static_cast<size_t>(j)].see(s.timestamp, std::abs(s.qd[j]) < width);
      rest.see(s.timestamp, RestBaseline::arm_rest(s));
    });
    payload.finish(src.size(), period_of(src));
    for (int j = 0; j < n; ++j) crawl[j] = std::max(crawl[j], crawls[static_cast<size_t>(j)].longest());
    longest_rest = std::max(longest_rest, rest.longest());
    c.payload_max = std::max(c.payload_max, payload.heaviest());
    for (size_t k = skip; k < src.size(); ++k) {
      judged += payload.judged(k) && (unsettled[i].empty() || !unsettled[i][k]) ? 1 : 0;
      judged_observer += payload.judged_observer(k) ? 1 : 0;
    }
    timelines.push_back(std::move(payload));
    skips.push_back(skip);
  }
  if (judged == 0) {
    // (every run was the residual filter's start-up, or a payload change's settling, alone)
    std::vector<std::string> what;
    for (const device::SampleSource* src : runs)
      what.push_back(fmt::format("{} ({} samples)", src->path().empty() ? std::string("a run") : src->path(), src->size()));
    throw InvalidArgument(fmt::format("learn thresholds: no sample of the healthy run(s) to learn from: {}; each needs more than the "
                                      "residual filter's {} start-up samples ({:g} s), with samples not settling after a payload change",
                                      fmt::join(what, ", "), kSettleSamples, static_cast<double>(kSettleSamples) * c.nominal_period));
  }
  StaticThresholdAccumulator level, observer_level;
  std::vector<DynamicThresholdSampler> dynamic, observer_dynamic;
  for (int j = 0; j < n; ++j) dynamic.emplace_back(judged, options.dynamic);
  if (with_observer && judged_observer > 0) {
    try {
      for (int j = 0; j < n; ++j) observer_dynamic.emplace_back(judged_observer, options.dynamic);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(fmt::format("observer {}", e.what()));  // (too few samples the observer is judged at)
    }
  }
  for (size_t i = 0; i < runs.size(); ++i) {
    const device::SampleSource& src = *runs[i];
    PayloadTimeline& payload = timelines[i];
    const size_t skip = skips[i];
    ident::TwinModel t = twin;
    payload.start(t);
    const double alpha = iir_alpha(c.filter_cutoff_hz, period_of(src));
    MonitorAcceleration accelerations(n, src.present(), alpha, c.gap_factor * period_of(src),
                                      windowed_acceleration(twin, n, period_of(src), c.gap_factor));
    LearnedResidual residual(t, c, alpha);
    // the momentum observer, sample by sample exactly as the monitor runs it (its samples have their
    // own qd, qdd: it is judged from later after a payload change)
    std::optional<TwinMomentumObserver> obs;
    if (with_observer) obs.emplace(n, c.observer_gain);
    VectorJ warm = VectorJ::Zero(n), o(n);
    RestBaseline observer_rest(n);
    TemperatureHold hold;
    double previous_t = 0.0;
    src.replay([&](size_t k, const RobotSample& given_sample) {
      const RobotSample& s = hold.apply(given_sample);
      const VectorJ& qdd = accelerations.push(s);
      const bool changed = payload.advance(k, t);
      const VectorJ& rf = residual.push(t, s, qdd, changed);
      if (k >= skip && payload.judged(k) && accelerations.settled()) {
        level.add(rf);
        peak = peak.cwiseMax(rf.cwiseAbs());
        for (int j = 0; j < n; ++j) {
          load[j] = std::max(load[j], reversal_load(residual.torque()[j], s.qd[j], width));
          dynamic[static_cast<size_t>(j)].add(rf[j], s.qd[j], qdd[j]);
        }
      }
      if (with_observer) {
        const double dt = k == 0 ? c.nominal_period : s.timestamp - previous_t;
        if (changed) {  // (Monitor::restart_estimators, Monitor::carry)
          obs->restart();
          observer_rest = RestBaseline(n);
        }
        temperature_drive_torque(t, c.trend.temperature_slope, c.trend.temperature_ref, s, warm);
        o = obs->update(t, s, dt, &warm);
        observer_rest.apply(s, o);
        if (k >= skip && payload.judged_observer(k)) {
          observer_level.add(o);
          obs_peak = obs_peak.cwiseMax(o.cwiseAbs());
          for (int j = 0; j < n; ++j) observer_dynamic[static_cast<size_t>(j)].add(o[j], s.qd[j], qdd[j]);
        }
      }
      previous_t = s.timestamp;
    });
    level.end_run();  // (a run of settling samples alone teaches nothing)
    observer_level.end_run();
  }
  c.static_level = level.learn(options.k_sigma).level.cwiseMax(kStaticPeakMargin * peak);
  c.dynamic.clear();
  for (int j = 0; j < n; ++j) {
    const auto fit = dynamic[static_cast<size_t>(j)].fit();
    if (!fit.ok) throw InvalidArgument(fmt::format("dynamic threshold of joint {}: {}", j + 1, fit.message));
    c.dynamic.push_back(fit.params);
  }
  c.observer_level.resize(0);
  c.observer_dynamic.clear();
  if (with_observer) {
    c.observer_level = observer_level.learn(options.k_sigma).level.cwiseMax(kStaticPeakMargin * obs_peak);
    for (int j = 0; j < n; ++j) {
      const auto fit = observer_dynamic[static_cast<size_t>(j)].fit();
      if (!fit.ok) throw InvalidArgument(fmt::format("observer dynamic threshold of joint {}: {}", j + 1, fit.message));
      c.observer_dynamic.push_back(fit.params);
    }
  }
  c.observer_choice = {};  // a per-joint debounce belongs to the thresholds it was chosen for
  c.reversal_load_max = load.array().isFinite().all() ? load : VectorJ();  // (a non-finite torque: not recorded)
  c.crawl_max = c.reversal_load_max.size() ? crawl : VectorJ();
  c.longest_rest = longest_rest;
  return c;
}

ObserverDebounceChoice choose_observer_debounce(const ident::TwinModel& twin, const MonitorConfig& config,
                                                const std::vector<HealthyRun>& validation) {
  if (validation.empty()) throw InvalidArgument("observer debounce: no healthy validation runs given");
  const int n = twin.n_dof();
  if (config.observer_level.size() != n || !(config.observer_gain > 0.0))
    throw InvalidArgument("observer debounce: the momentum observer has no thresholds (learn them first)");
  if (!config.observer_alerts) throw InvalidArgument("observer debounce: the observer raises no alerts (observer_alerts is off)");
  if (config.observer_raise_after > 0)
    throw InvalidArgument(fmt::format("observer debounce: observer_raise_after is set ({}) and would override a per-joint choice",
                                      config.observer_raise_after));
  std::vector<std::unique_ptr<device::HeldSamples>> store;
  const std::vector<const device::SampleSource*> runs = samples_of(validation, store, "observer debounce");
  const int shared = config.observer_debounce();
  ObserverDebounceChoice out;
  out.ratio.assign(static_cast<size_t>(shared), VectorJ::Zero(n));
  for (size_t i = 0; i < runs.size(); ++i) {
    const device::SampleSource& src = *runs[i];
    out.seconds += src.seconds();
    ident::TwinModel t = twin;
    t.set_payload(validation[i].payload);
    // the monitor with each debounce d = 1..D, all over one reading of the run
    std::vector<std::unique_ptr<Monitor>> monitors;
    for (int d = 1; d <= shared; ++d) {
      MonitorConfig c = config;
      c.observer_choice = {};
      c.observer_raise_after = d;
      // the recording's own period, as the monitor command uses it (a 125 Hz log is no stream of gaps)
      if (src.median_period() > 0.0) c.nominal_period = src.median_period();
      monitors.push_back(std::make_unique<Monitor>(t, c));
      monitors.back()->track_margin();
    }
    src.replay([&](size_t, const RobotSample& x) {
      for (auto& m : monitors) m->push(x);
    });
    for (int d = 1; d <= shared; ++d) {
      Monitor& m = *monitors[static_cast<size_t>(d - 1)];
      m.finish();
      VectorJ& row = out.ratio[static_cast<size_t>(d - 1)];
      row = row.cwiseMax(m.margin_observer());
    }
  }
  const double worst = std::max(out.ratio.back().maxCoeff(), kObserverRatioFloor);
  out.raise_after.assign(static_cast<size_t>(n), shared);
  for (int j = 0; j < n; ++j)
    for (int d = 1; d < shared; ++d) {
      const double r = out.ratio[static_cast<size_t>(d - 1)][j];
      if (r < 1.0 && r <= worst) {
        out.raise_after[static_cast<size_t>(j)] = d;
        break;
      }
    }
  return out;
}

void learn_program_thresholds(MonitorConfig& config, const std::string& name, const ident::TwinModel& twin,
                              const std::vector<HealthyRun>& runs, const LearnOptions& options) {
  check_program_name(name);
  const MonitorConfig learned = learn_thresholds(twin, runs, config, options);
  ThresholdSet set;
  set.static_level = learned.static_level;
  set.dynamic = learned.dynamic;
  set.observer_level = learned.observer_level;
  set.observer_dynamic = learned.observer_dynamic;
  set.payload_max = learned.payload_max;
  set.reversal_load_max = learned.reversal_load_max;
  set.crawl_max = learned.crawl_max;
  set.longest_rest = learned.longest_rest;
  // no per-joint observer debounce: a choice belongs to the thresholds it was made for (choose_observer_debounce)
  set.runs = static_cast<int>(runs.size());
  for (const auto& r : runs) set.seconds += r.samples != nullptr ? r.samples->seconds() : device::HeldSamples(*r.recording).seconds();
  config.programs[name] = std::move(set);
}

Monitor::Monitor(const ident::TwinModel& twin, MonitorConfig config)
    : twin_(twin), cfg_(std::move(config)), n_(twin.n_dof()), obs_(std::max(1, twin.n_dof()), cfg_.observer_gain > 0.0 ? cfg_.observer_gain : 1.0) {
  cfg_.validate(n_);
  gap_factor_ = cfg_.gap_factor;
  settle_until_ = kObserverSettle;
  memory_unsure_.assign(static_cast<size_t>(n_), 0.0);
  memory_from_ = VectorJ::Zero(n_);
  obs_on_ = cfg_.observer_level.size() == n_;
  obs_level_ = obs_warm_ = obs_ref_ = tau_obs_ = rf_dec_ = obs_dec_ = VectorJ::Zero(n_);
  rest_rf_ = RestBaseline(n_);
  rest_obs_ = RestBaseline(n_);
  // the observer runs in the twin's torque units; the diagnosis needs N·m (implausible gains, see
  // torque_gain, are replaced there as for the current residual)
  tau_gain_ = VectorJ::Ones(n_);
  for (int j = 0; j < n_; ++j) tau_gain_[j] = twin_.trusted_gain(j);
  obs_to_nm_ = VectorJ::Ones(n_);
  for (int j = 0; j < n_; ++j) obs_to_nm_[j] = torque_gain(j) / twin_.joints[static_cast<size_t>(j)].gain;
  // breakaway friction: the Coulomb level plus the Stribeck rise, in N·m like the observer's estimate
  static_friction_ = VectorJ::Zero(n_);
  for (int j = 0; j < n_; ++j) {
    const ident::JointDrive& d = twin_.joints[static_cast<size_t>(j)];
    const double f = (std::abs(d.friction[ident::kCoulomb]) + std::max(0.0, d.stribeck)) * obs_to_nm_[j];
    static_friction_[j] = std::isfinite(f) ? f : 0.0;  // 0: unknown (a sequential twin has no Coulomb column here)
  }
  if (cfg_.sensitivity.size() == 0) cfg_.sensitivity = VectorJ::Ones(n_);
  alpha_ = iir_alpha(cfg_.filter_cutoff_hz, cfg_.nominal_period);
  // a twin with an acceleration window (a noisy velocity): the windowed estimate where the stream has
  // no target acceleration, over as many samples as the identification's half window
  windowed_ = windowed_acceleration(twin_, n_, cfg_.nominal_period, gap_factor_);
  // reversals under more load than the thresholds were learned with (widen_for_load)
  load_band_cur_ = load_band_obs_ = VectorJ::Zero(n_);
  reversal_width_ = reversal_width(twin_);
  obs_band_alpha_ = 1.0 - std::exp(-cfg_.observer_gain * cfg_.nominal_period);
  load_band_on_ = cfg_.reversal_load_max.size() == n_;
  crawl_since_ = VectorJ::Constant(n_, std::numeric_limits<double>::quiet_NaN());
  // a rest longer than the thresholds in use saw is judged with the sets that saw long ones too (longest_rest)
  if (std::isfinite(cfg_.longest_rest))
    for (const auto& [name, set] : cfg_.programs)
      if (name != cfg_.program && std::isfinite(set.longest_rest) && set.longest_rest >= kMinDonorRest &&
          set.longest_rest > cfg_.longest_rest &&
          set.static_level.size() == n_ && (!cfg_.use_dynamic || static_cast<int>(set.dynamic.size()) == n_))
        rest_donors_.push_back(set);  // (a copy: a moved or copied Monitor keeps its own)
  rest_level_ = VectorJ::Zero(n_);
  rest_obs_level_ = VectorJ::Zero(n_);
  // the switch's step per unit of excess load. The current for a torque tau is f tau / g, f = 1
  // motoring and c_gen back-driven: the twin's blended f is off the drive's by at most |1 - c_gen|,
  // |1 - c_gen| tau / g in the current residual. The observer converts the measured current back to
  // torque with a hard switch on the measured velocity's sign (measured_drive_torque), which leaves
  // (c_gen - 1) tau or (1/c_gen - 1) tau. (A non-finite factor, c_gen or gain 0: none.)
  load_step_cur_ = load_step_obs_ = VectorJ::Zero(n_);
  for (int j = 0; j < n_; ++j) {
    const ident::JointDrive& d = twin_.joints[static_cast<size_t>(j)];
    const double cur = std::abs(1.0 - d.c_gen) / d.gain, obs = std::max(std::abs(1.0 - d.c_gen), std::abs(1.0 / d.c_gen - 1.0));
    load_step_cur_[j] = std::isfinite(cur) ? cur : 0.0;
    load_step_obs_[j] = std::isfinite(obs) ? obs : 0.0;
  }
  fir_ = make_fir_filters(cfg_, n_);
  fir_band_ = make_fir_filters(cfg_, n_);
  no_temp_ = VectorJ::Constant(n_, std::numeric_limits<double>::quiet_NaN());
  deb_.assign(static_cast<size_t>(n_), Debouncer(cfg_.raise_after, cfg_.clear_after));
  deb_obs_.clear();
  for (int j = 0; j < n_; ++j) deb_obs_.emplace_back(cfg_.observer_debounce(j), cfg_.clear_after);
  joint_active_.assign(static_cast<size_t>(n_), 0);
  below_program_.assign(cfg_.programs.size(), 0);  // (allocated here: push allocates nothing)
  i_hat_ = tau_hat_ = r_ = rf_ = level_ = qdd_ = qd_prev_ = frozen_val_ = VectorJ::Zero(n_);
  temperature_ok_ = VectorJ::Constant(n_, std::numeric_limits<double>::quiet_NaN());
  temperature_run_.assign(static_cast<size_t>(n_), 0);
  frozen_run_.assign(static_cast<size_t>(n_), 0);
  frozen_event_.assign(static_cast<size_t>(n_), -1);
  frozen_since_ = VectorJ::Zero(n_);
  const size_t cap = static_cast<size_t>(std::ceil((kContactReference + cfg_.diagnosis_pre + kLongWindow + 0.2) / cfg_.nominal_period));
  ring_.resize(cap);
  for (auto& d : ring_) {
    d.q = d.qd = d.qdd = d.r_tau = d.current = d.tau_ext = d.tau_ext_level = d.presliding = VectorJ::Zero(n_);
  }
  window_.reserve(cap);
  reference_.reserve(cap);
  events_.reserve(64);
  // slow-wear trend in torque units when the drive gains are known
  VectorJ g = VectorJ::Ones(n_);
  if (twin_.gains_known())
    for (int j = 0; j < n_; ++j) g[j] = torque_gain(j);
  // the loop compensates the residual for temperature itself (push), the detector gets it compensated
  temp_slope_ = cfg_.trend.temperature_slope.size() == n_ ? cfg_.trend.temperature_slope : VectorJ(VectorJ::Zero(n_));
  TrendConfig tc = cfg_.trend;
  tc.temperature_slope = VectorJ::Zero(n_);
  trend_ = TrendDetector(twin_, tc, g, twin_.gains_known() ? "N·m" : "A");
  trend_.set_temperature_compensated(cfg_.trend.temperature_slope.size() == n_);
}

double Monitor::torque_gain(int j) const { return tau_gain_[j]; }

double Monitor::load_excess(int j, double qd, double load_max) const {
  // (most samples end here, without the tanh of reversal_load: the load is at most
  // |tau| 2 / (exp(2x) + 1) <= |tau| / (1 + x), x = |qd| / width; evaluated for every joint below
  // 0.2 rad/s, the tanh cost ~60 ns a sample)
  const double atau = std::abs(tau_hat_[j]);
  if (atau <= load_max * (1.0 + std::abs(qd) / reversal_width_)) return 0.0;
  const double excess = reversal_load(tau_hat_[j], qd, reversal_width_) - load_max;
  return excess > 0.0 && std::isfinite(excess) ? excess : 0.0;
}

// Where a joint reverses under more load than any reversal the thresholds were learned on, the
// drive's motoring/back-driven step the twin cannot time (reversal_load, threshold.hpp) is larger
// than any they saw: both thresholds grow by the step the excess load can put into each residual
// (load_excess times the joint's step, load_step_cur_ / load_step_obs_), times the joint's
// sensitivity like the rest of its threshold, low-passed so that the widening lasts as long as the
// step's trace in the residual does: through the residual's IIR
// (a first-order low-pass of a bound bounds the low-pass of what it bounds; a joint on Cao's FIR,
// -3 dB at 42.8 Hz against the IIR's 40, gets the same IIR: close, not a strict bound) and the
// observer's own bandwidth. Nothing changes within the learned loads. The cost is sensitivity where
// a joint reverses or stands still under more load than they were learned with: a stop is a
// reversal whose direction stays in doubt (measured on the virtual UR3e: a joint stopped under
// 3 kg stick-slips, its current hopping 0.34-0.50 A for as long as it stands; leaving stops out
// of the widening raised 5 false alarms at triangle corners where widening them raised none), and
// there the rest baseline (RestBaseline) does not take the hopping up.
void Monitor::widen_for_load(const VectorJ& qd, double t) {
  const bool crawls_known = cfg_.crawl_max.size() == n_;
  for (int j = 0; j < n_; ++j) {
    double& cur = load_band_cur_[j];
    double& obs = load_band_obs_[j];
    // a joint crawling longer than any crawl the thresholds saw: the whole step, not its excess
    // (MonitorConfig::crawl_max)
    double& since = crawl_since_[j];
    if (!(std::abs(qd[j]) < reversal_width_)) since = std::numeric_limits<double>::quiet_NaN();
    else if (std::isnan(since)) since = t;
    const bool unseen_crawl = crawls_known && t - since > cfg_.crawl_max[j];
    const double excess = load_excess(j, qd[j], unseen_crawl ? 0.0 : cfg_.reversal_load_max[j]);
    // a joint on Cao's FIR widens through the same taps as its residual: all positive, so the
    // filtered bound bounds the filtered step (through the IIR it was close, not strict). Its
    // memory is the taps' length: it takes every sample (6 multiply-adds)
    signal::FirFilter& band = fir_band_[static_cast<size_t>(j)];
    signal::FirFilter* fir = band.taps().empty() ? nullptr : &band;
    if (fir == nullptr && excess == 0.0 && cur < 1e-12 && obs < 1e-12) {  // (most samples: no excess, the bands decayed)
      cur = obs = 0.0;
      continue;
    }
    if (fir != nullptr) cur = fir->push(load_step_cur_[j] * excess);
    else cur += alpha_ * (load_step_cur_[j] * excess - cur);
    obs += obs_band_alpha_ * (load_step_obs_[j] * excess - obs);
    level_[j] += cfg_.sensitivity[j] * cur;
    if (obs_on_) obs_level_[j] += cfg_.sensitivity[j] * obs;
  }
}

void Monitor::carry(const model::RigidBodyInertia& payload, double t) {
  twin_.set_payload(payload);
  // what a resting joint is held at was measured with the old payload: it is measured again
  rest_rf_ = RestBaseline(n_);
  rest_obs_ = RestBaseline(n_);
  check_payload_envelope(t);
}

void Monitor::check_payload_envelope(double t) {
  const double mass = twin_.payload().mass, learned = cfg_.payload_max;
  const double margin = payload_envelope_margin(cfg_);
  const bool beyond = std::isfinite(learned) && mass > learned + margin;
  // what was measured for thresholds of this kind (kPayloadEnvelopeMargin*)
  const char* measured = load_band_on_ ? "thresholds learned at 0-0.5 kg, widened where a joint reverses under more load, raised no false "
                                         "alarm in 0.67 h of held-out runs at 1.5-3 kg (docs/validation.md)"
                                       : "thresholds learned at 0-0.5 kg raised 4 false alarms a minute at 1.5 and 2 kg; thresholds "
                                         "learned again with this twinwatch also widen where a joint reverses under more load";
  if (beyond && !payload_beyond_)
    add_note(t, fmt::format("the twin predicts with {:.2f} kg, more than {:g} kg above the {:.2f} kg of the heaviest healthy run its "
                            "thresholds{} were learned on: its model error grows with the payload (on the virtual UR3e, {}), and an "
                            "alert raised now may be that. Learn thresholds on a healthy run with this payload: twinwatch thresholds "
                            "--twin TWIN --payload-mass {:.2f} --program NAME HEALTHY.csv, then monitor --program NAME",
                            mass, margin, learned, cfg_.program.empty() ? "" : " (program '" + cfg_.program + "')", measured, mass));
  payload_beyond_ = beyond;
}

bool Monitor::carries_declared() const {
  // (a followed change within its error of the declaration takes the declared mass: follow_payload)
  return declaration_taken() && std::abs(twin_.payload().mass - declared_mass_) <= kPayloadFollowFloor;
}

void Monitor::open_event(int joint, double start, double t, const char* channel) {
  report_held();
  Event e = new_event();
  e.t_start = start;
  e.t_end = t;
  e.t_detected = t;
  e.open = true;
  e.joint = joint;
  e.fault = FaultClass::Unknown;
  // (which channel raised it: a contact's momentum observer on J1 read "residual above threshold on
  // J1" while J1's current residual was a third of its threshold; review, session 47)
  e.detail = fmt::format("{} above threshold on J{}", channel, joint + 1);
  events_.push_back(e);
  open_ = static_cast<int>(events_.size()) - 1;
  diagnosed_ = false;
  rediagnosed_ = false;
  followed_ = false;
  raise_time_ = t;
  check_program_sets();
  // (raised where its joint crawls through a reversal: the end-of-run hint on slower programs)
  ++alerts_raised_;
  if (ring_count_ > 0 && std::abs(ring_at(ring_count_ - 1).qd[joint]) < reversal_width_) ++crawl_raises_;
  if (on_event) on_event(events_.back());
}

void Monitor::check_program_sets() {
  if (!cfg_.program.empty() || cfg_.programs.empty() || ring_count_ == 0) return;
  ++raises_;
  // the raising sample: would any joint of either channel be above that program's thresholds?
  const DiagnosisSample& d = ring_at(ring_count_ - 1);
  const bool observer = obs_on_ && cfg_.observer_alerts;
  size_t k = 0;
  for (const auto& [name, set] : cfg_.programs) {
    // (a set learned without observer thresholds uses the default set's, as select_program does)
    const bool own_obs = set.observer_level.size() != 0;
    const auto& obs_dyn = own_obs ? set.observer_dynamic : cfg_.observer_dynamic;
    const VectorJ& obs_static = own_obs ? set.observer_level : cfg_.observer_level;
    // the set's own widening at loaded reversals (widen_for_load), at this sample, unfiltered
    const bool widens = set.reversal_load_max.size() == n_;
    bool over = false;
    for (int j = 0; j < n_ && !over; ++j) {
      const double sens = cfg_.sensitivity[j];
      const double excess = widens ? load_excess(j, d.qd[j], set.reversal_load_max[j]) : 0.0;
      const double cur = sens * load_step_cur_[j] * excess, obs = sens * load_step_obs_[j] * excess;
      over = std::abs(rf_dec_[j]) > level_at(cfg_.use_dynamic, set.dynamic, set.static_level, j, d.qd[j], qdd_[j], sens) + cur ||
             (observer && std::abs(obs_dec_[j]) > level_at(cfg_.use_dynamic, obs_dyn, obs_static, j, d.qd[j], qdd_[j], sens) + obs);
    }
    below_program_[k++] += over ? 0 : 1;
  }
}

void Monitor::fill_window(double from, double until) {
  window_.clear();
  reference_.clear();
  for (size_t k = 0; k < ring_count_; ++k) {
    const DiagnosisSample& d = ring_at(k);
    if (d.t >= until) break;
    if (d.t >= from) window_.push_back(d);
    else if (obs_on_ && d.t >= from - kContactReference) reference_.push_back(d);
  }
  // the reference's residual is read as the window's (its noise is what a hypothesis fitted on
  // the window absorbs without explaining anything, diagnose)
  recompute_residual(reference_);
  recompute_residual(window_);
}

void Monitor::recompute_residual(std::vector<DiagnosisSample>& samples) {
  // the stretch is complete, so the residual can use the actual (not the target) acceleration:
  // a centred difference of qd over +-kDiagHalfWidth samples. Then r = tau_meas - tau_hat is the
  // external/fault torque itself, not the controller's reaction to it.
  constexpr long kDiagHalfWidth = 3;
  const long W = static_cast<long>(samples.size());
  VectorJ tau, cur;
  for (long k = 0; k < W; ++k) {
    const long a = std::max(0L, k - kDiagHalfWidth), b = std::min(W - 1, k + kDiagHalfWidth);
    const double span = samples[static_cast<size_t>(b)].t - samples[static_cast<size_t>(a)].t;
    if (span > 0.0) samples[static_cast<size_t>(k)].qdd = (samples[static_cast<size_t>(b)].qd - samples[static_cast<size_t>(a)].qd) / span;
  }
  ident::FrictionMemory at;  // the stream's memory as it was at each sample
  at.primed = true;
  VectorJ tau_meas;
  for (auto& d : samples) {
    at.h = d.presliding;
    at.direction = d.direction;
    twin_.predict(d.q, d.qd, d.qdd, no_temp_, tau, cur, &at);
    // r_tau: the current residual times the gain, what the hypotheses are scored on; r_drive: the
    // measured drive torque through the twin's own current model, back-driven phases included (as
    // the observer reads it), less the twin's torque, in N·m through the trusted gains, what sizes
    // a payload change (r_tau reads it 10-15 % small: a back-driven joint's torque c_gen low).
    // Scoring on r_drive too turned a resistance's onset into a short "contact" (session 21). Its
    // direction stays the hard switch on actual_qd: read with the target (session 31) a 0.25 kg drop
    // at a triangle's corner was sized -0.195 kg, outside the 20 % (MonitorLoop.ASmallPartsStep...)
    measured_drive_torque(twin_, d.current, d.qd, tau_meas);
    d.r_drive.resize(n_);
    for (int j = 0; j < n_; ++j) {
      d.r_tau[j] = torque_gain(j) * (d.current[j] - cur[j]);
      d.r_drive[j] = obs_to_nm_[j] * (tau_meas[j] - tau[j]);
    }
  }
}

void Monitor::check_payload_after_output(double t) {
  const double taken = look_for_part(t);
  // the look is over (none is due again): an alert held as the part's step is settled by what it found
  if (!std::isfinite(output_check_at_)) settle_part_steps(t, taken);
}

double Monitor::look_for_part(double t) {
  constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  // A part lighter than the thresholds see (0.15 kg on the virtual UR3e: two of 12 raised anything at
  // their grip or drop) is never taken by the twin, and what it leaves raises short "contacts on link
  // 6" at the motion's peaks. A second of motion carries it nonetheless: fitted on the moving joints,
  // 0.15 kg parts read 0.134-0.157 kg and explain 24-48 % of the residual, against at most 0.061 kg
  // and 0.9 % at 319 output changes with no part on healthy runs of every program (kOutputCheck*).
  // No alert is raised (no threshold was crossed): the twin takes the part, with a note. A program
  // that declares its payload is believed instead
  const double from = output_check_from_;
  const double looked = output_check_at_;
  output_check_at_ = std::numeric_limits<double>::infinity();
  if (!finds_parts()) return kNone;
  // (an alert up, or a window mostly at rest, a part gripped at the program's stop: looked at again
  // later, up to kLongWindow after the output changed)
  const auto again = [&] {
    if (looked + kOutputCheckAgain - from <= kLongWindow + 1e-9) output_check_at_ = looked + kOutputCheckAgain;
    return kNone;
  };
  if (open_ >= 0 || pending_close_ >= 0 || background_ >= 0 || held_ >= 0) return again();
  // a payload change in the window: its own looks decided (it is followed there). Any other alert
  // (closed: none is open here) is left out, with what it leaves in the filters after it: a contact,
  // or the part's own step read otherwise in a short window (a 0.15 kg drop: "extra resistance on
  // J3" 0.64 s after it)
  for (const Event& e : events_)
    if (e.fault == FaultClass::PayloadChange && e.t_end >= from) return kNone;
  fill_window(from, std::numeric_limits<double>::infinity());
  for (const Event& e : events_)
    if (e.fault != FaultClass::Wear && e.t_end + kOutputCheckAlertAfter >= from)
      std::erase_if(window_, [&](const DiagnosisSample& d) { return d.t >= e.t_start - kOutputCheckAlertBefore && d.t <= e.t_end + kOutputCheckAlertAfter; });
  // (the moving samples: at least half the window, and kOutputCheckMoving of them)
  const auto moving = std::count_if(window_.begin(), window_.end(), [](const DiagnosisSample& d) { return d.qd.cwiseAbs().maxCoeff() >= kOutputCheckMinSpeed; });
  if (2 * moving < static_cast<long>(window_.size()) || static_cast<double>(moving) * cfg_.nominal_period < kOutputCheckMoving) return again();
  const Hypothesis h = fit_payload_change(twin_.robot(), window_, payload_com_in_link(), kOutputCheckMinSpeed);
  if (h.fault != FaultClass::PayloadChange || !(std::abs(h.magnitude) >= kOutputCheckMass) || !(h.explained >= kOutputCheckExplained)) return kNone;
  bool as_declared = false;
  const double mass = followed_mass(h.magnitude, as_declared);
  if (std::isnan(mass) || mass > twin_.robot().payload_limit()) return kNone;
  const double had = twin_.payload().mass;
  const ident::TwinModel& before = scratch_twin();
  carry(payload_of(mass, as_declared), t);
  rebase_on(before, from);
  const std::string what = mass > 0.0 ? fmt::format("a {:.2f} kg payload", mass) : std::string("no payload");
  const std::string after = from == output_changed_at_ ? fmt::format("a gripper output changed at {:.3f} s", from)
                                                       : fmt::format("the arm moved on at {:.3f} s from the rest in which a gripper output "
                                                                     "changed at {:.3f} s",
                                                                     from, output_changed_at_);
  add_note(t, fmt::format("the twin now predicts with {} (it had {:.2f} kg): in the {:.1f} s after {}, the moving joints' residual "
                          "carried {:+.2f} kg (the payload explains {:.0f} % of it), below the alarm thresholds; monitor --keep-payload "
                          "keeps the declared one",
                          what, had, t - from, after, h.magnitude, 100.0 * h.explained));
  return mass - had;
}

void Monitor::run_diagnosis(double t, bool long_look, double until) {
  Event& e = events_[static_cast<size_t>(open_)];
  const Event earlier = e;  // what an earlier look said (Unknown before the first)
  fill_window(e.t_start - cfg_.diagnosis_pre, until);
  DiagnosisOptions o;
  o.frozen_samples = cfg_.frozen_samples;
  o.raised_at = raise_time_;
  o.payload_com = payload_com_in_link();
  // (joint torque sensors read a resting joint's load: no friction hides it from them)
  if (!twin_.measures_torque()) o.static_friction = static_friction_;
  o.rest_visible = twin_.measures_torque();
  o.channel = twin_.channel_name();
  o.channel_unit = twin_.channel_unit();
  const double duration = t - e.t_start;
  const auto hyps = diagnose(twin_.robot(), window_, duration, e.joint, o, obs_on_ ? &reference_ : nullptr);
  // A split on a rise (watch_on_top) ends a change whose samples before the rise stayed within the
  // thresholds less the watched payload: that payload explains them. A small part's change reads in
  // such a window as a force where the part hangs, or on an inner link (a 0.2 kg drop: "contact on
  // link 5, 2.8 N; link 6 is also possible"; a 0.2 kg pick: "link 1, 1.0 N"), which the longer look
  // then calls the payload change it was, with the contact after it gone into that change. So the
  // split takes the watched change when the window's payload hypothesis agrees with it (within the
  // follow's tolerance); follow_payload still asks for its evidence
  const Hypothesis* best = &hyps.front();
  if (splitting_on_top_ && best->fault != FaultClass::PayloadChange)
    for (const Hypothesis& x : hyps)
      if (x.fault == FaultClass::PayloadChange) {
        if (std::abs(x.magnitude - on_top_change_) <= std::max(kPayloadFollowFloor, kPayloadFollowShare * std::abs(on_top_change_))) best = &x;
        break;
      }
  const Hypothesis& h = *best;
  e.fault = h.fault;
  if (h.joint >= 0) e.joint = h.joint;
  // a payload change belongs to no joint (the one that happened to raise first is no property of it)
  if (h.fault == FaultClass::PayloadChange) e.joint = -1;
  e.link = h.link;
  e.other_links = h.other_links;
  e.contact = h.contact;
  e.magnitude = h.magnitude;
  e.units = h.units;
  e.explained = h.explained;
  // the confidence: for a contact the explained share times the named link's posterior (session 39:
  // ECE 0.114 -> 0.046 on 587 contacts); for the other classes the share of the energy beyond the
  // window's noise the signature explains (session 40: a right J5 resistance near its threshold read
  // 16 % on the whole energy; over the collision, payload, wear, stop and resistance sets ECE
  // 0.41 -> 0.06 on 31 resistances, 0.16 -> 0.05 on 292 payload changes; on contacts the same
  // reading was overconfident, 0.083 -> 0.140: docs/validation.md, "A resistance read as a contact")
  // (a link posterior that is not a number says nothing about the link: no confidence in it)
  const double fit = h.fault != FaultClass::Collision && std::isfinite(h.beyond_noise) ? h.beyond_noise : h.explained;
  e.confidence = std::clamp(fit * (std::isfinite(h.link_share) ? h.link_share : 0.0), 0.0, 1.0);
  e.detail = h.detail;
  if (best != &hyps.front())
    e.detail += fmt::format(" (the change watched; the samples before the rise alone read as {}: {})", to_string(hyps.front().fault), hyps.front().detail);
  if (payload_beyond_)
    e.detail += fmt::format("; raised with a {:.2f} kg payload, heavier than the thresholds were learned with ({:.2f} kg): it may be the "
                            "twin's model error",
                            twin_.payload().mass, cfg_.payload_max);
  // a twin identified without a known payload has an arbitrary torque scale: its N·m, N and kg are
  // not physical (an extra 0.8 N·m of friction read as 0.11), which the event says instead of
  // presenting them as sizes
  if (!twin_.gains_known() && (e.units == "N·m" || e.units == "N" || e.units == "kg")) {
    e.units += " (relative)";
    e.detail += "; sizes in the twin's relative torque units, not physical: it was identified without a known payload that fixes its gains";
  }
  diagnosed_ = true;
  if (background_ >= 0 && open_ != background_ && earlier.fault == FaultClass::Collision && e.fault != FaultClass::Collision) {
    // a contact the first look reported, whose alert the parked fault's residual kept up until this
    // look: it stays the contact it was reported as (it must not vanish into the parked fault)
    const double end = e.t_end;
    e = earlier;
    e.t_end = end;
    return;
  }
  if (background_ >= 0 && open_ != background_ && e.fault != FaultClass::Collision && e.fault != FaultClass::PayloadChange) {
    // not a contact (nor a payload change, which belongs to no joint): the persistent fault seen on
    // another joint; the raise's event goes
    Event& old = events_[static_cast<size_t>(background_)];
    old.peak_residual = std::max(old.peak_residual, e.peak_residual);
    drop_open_event();
    resume_background();
    return;
  }
  if (merge_into_ >= 0) {
    const int into = merge_into_;
    merge_into_ = -1;
    if (e.fault == FaultClass::Collision) {
      // a contact of its own: the earlier alert ended where it ended
      pending_close_ = into;
      report_pending_close();
    } else {
      // the earlier fault dipping below its threshold: it continues, as it was diagnosed, and
      // this raise's own event goes (it was only ever shown as a raise, never stored)
      unsplit_payload_change(into, t);
      Event& old = events_[static_cast<size_t>(into)];
      old.open = true;
      old.t_end = e.t_end;
      old.peak_residual = std::max(old.peak_residual, e.peak_residual);
      drop_open_event();
      open_ = into;
      diagnosed_ = merged_diagnosed_;
      rediagnosed_ = merged_rediagnosed_;
      raise_time_ = merged_raise_time_;
      if (on_event) on_event(events_[static_cast<size_t>(open_)]);
      return;
    }
  }
  if (const PartStep kind = long_look ? PartStep::None : part_step_candidate(e); kind != PartStep::None) return hold_part_step(t, kind);
  if (long_look && e.fault == FaultClass::PayloadChange && cfg_.follow_payload)
    follow_payload(e, t, std::min(t, until) - cfg_.diagnosis_pre - kContactReference);
  if (!long_look && cfg_.follow_payload) {
    if (e.fault == FaultClass::PayloadChange) {
      start_on_top(e, e.magnitude);
    } else if (e.fault == FaultClass::Collision && at_last_link(e) && output_changed_for(e)) {
      // a small part dropped reads as a contact where it hung in the first look's short window (a
      // 0.3 kg loss: "contact on link 6, 4.8 N"; a 0.3 kg pick: "link 5, link 6 is also possible"),
      // which the longer look calls a payload change: with
      // a gripper output changed, its payload hypothesis is watched on as well
      for (const Hypothesis& x : hyps)
        if (x.fault == FaultClass::PayloadChange) {
          start_on_top(e, x.magnitude);
          break;
        }
    }
  }
  if (on_event) on_event(e);
}

bool Monitor::declared_pick_candidate(const Event& e, double declared_at, double change) const {
  // an alert raised within kDeclarationLag of a declaration, diagnosed as that part's weight: before
  // the declaration the arm already carries it (+change), after it the arm does not yet (-change).
  // A step shorter than a diagnosis window reads as a pulse, a contact where the part hangs (the
  // last link): taken within kShortStep of the declaration when its force is the part's weight. An
  // undiagnosed alert is none (a 4 ms hit on the forearm near a grip was withdrawn as one, review)
  if (!std::isfinite(declared_at) || change == 0.0 || std::abs(e.t_start - declared_at) > kDeclarationLag) return false;
  if (background_ >= 0 || merge_into_ >= 0 || followed_) return false;
  if (e.fault == FaultClass::PayloadChange) {
    // (within half the declared change: the first look reads a step at a rest short, +0.67 kg for 1 kg)
    const double expected = e.t_start < declared_at ? change : -change;
    return std::abs(e.magnitude - expected) <= std::max(kPayloadFollowFloor, kDeclaredPickShare * std::abs(change));
  }
  // (a contact's force no more than kDeclaredForceShare times the part's weight: a hit on the
  // gripper reads tens of newtons against the 2-10 N of a part; the declared parts' steps read
  // 1.7-2.0 times their weight)
  const bool short_step = std::abs(e.t_start - declared_at) <= kShortStep;
  const bool weight_sized = e.units == "N" && e.magnitude <= kDeclaredForceShare * std::abs(change) * twin_.robot().gravity().norm();
  return short_step && e.fault == FaultClass::Collision && at_last_link(e) && weight_sized;
}

bool Monitor::at_last_link(const Event& e) const {
  return e.link == n_ - 1 || std::find(e.other_links.begin(), e.other_links.end(), n_ - 1) != e.other_links.end();
}

bool Monitor::declared_pick_explains(double t) const {
  // the candidate cleared soon after both the declaration and the grip (a gripper output change
  // around it) had happened: the twin's declared payload and the arm's load agree again, and what
  // was raised in between was their timing, not a fault. A missed grip does not clear, a part lost
  // has no output change, and both stay events
  const Event& e = events_[static_cast<size_t>(open_)];
  if (!declared_pick_candidate(e, declared_at_, declared_change_) || t - std::max(declared_at_, e.t_start) > kDeclarationLag + kPulseMax)
    return false;
  // The grip raised it, apart from the declaration: for a late declaration the gripper closed before
  // the alert began (within kPayloadIoLookback: at a rest the step shows when the arm moves on), not
  // after it (a release after a part lost in transit, then a declaration of none, is no pick); for
  // an early one it closed after the alert began, or just before it while the decisions still
  // waited out the declaration (kDeclarationSettle). A grip in the declaration's own sample leaves
  // no step, and an alert after it is something else (a contact at the gripper stays an event)
  const double half = 0.5 * cfg_.nominal_period;
  return e.t_start < declared_at_ ? gripped_before(e, declared_at_)
                                  : outputs_changed_within(std::max(declared_at_ + half, e.t_start - kDeclarationSettle - 2 * cfg_.nominal_period), t);
}

bool Monitor::gripped_before(const Event& e, double declared_at) const {
  // a gripper output changed within kPayloadIoLookback before the alert began, and before the
  // declaration's own sample
  const double half = 0.5 * cfg_.nominal_period;
  return outputs_changed_within(e.t_start - kPayloadIoLookback, std::min(e.t_start + half, declared_at - half));
}

bool Monitor::late_declared_pick(const Event& e, double t, double change) const {
  // the pick the declaration at t comes late for: the alert began at its grip, before t
  return e.t_start < t && declared_pick_candidate(e, t, change) && gripped_before(e, t);
}

bool Monitor::outputs_changed_within(double from, double to) const {
  bool have = false;
  std::uint64_t prev = 0;
  for (size_t k = 0; k < ring_count_; ++k) {
    const DiagnosisSample& d = ring_at(k);
    if (d.t < from || d.t > to) continue;
    if (have && d.digital_outputs != prev) return true;
    prev = d.digital_outputs;
    have = true;
  }
  return false;
}

void Monitor::withdraw_open_alert(bool announce) {
  if (announce) drop_open_event();
  else drop_event(open_);  // (held: its consumers keep it open until it is settled, settle_part_steps)
  reset_decisions();
  diagnosed_ = rediagnosed_ = false;
}

void Monitor::reset_decisions() {
  for (auto& d : deb_) d.reset();
  for (auto& d : deb_obs_) d.reset();
  std::fill(joint_active_.begin(), joint_active_.end(), 0);
}

void Monitor::take_declared_payload(const RobotSample& s) {
  const double t = s.timestamp;
  const double m = s.payload;
  const double* c = s.payload_cog;
  if (!declaration_readable(s)) return;
  // (push calls this only for a declaration that differs from the last: same_declaration)
  const bool first = !have_declared_;
  const double was = declared_mass_;
  have_declared_ = true;
  declared_mass_ = m;
  std::copy(c, c + 3, declared_cog_);
  const model::RigidBodyInertia had = twin_.payload();
  const model::RigidBodyInertia now = declared_inertia(s, had);
  // the first declaration is news only where it differs from what the twin was given
  if (first && same_payload(had, now)) {
    declared_taken_ = true;
    return;
  }
  const std::string what = m > 0.0 ? fmt::format("{:.2f} kg at ({:.3f}, {:.3f}, {:.3f}) m", m, c[0], c[1], c[2]) : std::string("no payload");
  if (const std::string refusal = declaration_refusal(twin_, s); !refusal.empty()) {
    // a twin-wide reason is said once; a declaration refused for its own values, each time
    const bool twin_wide = !twin_.gains_known() || !twin_.predicts_payload();
    if (!(twin_wide && declared_refused_))
      add_note(t, fmt::format("the controller declares {}, which the twin does not take: {}; it predicts with {:.2f} kg, and a change "
                              "of what the arm carries shows as a payload change",
                              what, refusal, twin_.payload().mass));
    declared_refused_ = true;
    declared_taken_ = false;
    declared_change_ = 0.0;  // (no declared pick to explain an alert by: the twin did not take it)
    return;
  }
  declared_taken_ = true;
  // a payload change waiting for its longer look (a part dropped, then the next one picked and
  // declared) ends here, sized on the samples before the declaration, as at a gripper output's
  // change (split_payload_change): else the look would measure the drop partly against the new part
  // an alert raised at a grip shortly before and already cleared (a pick at a rest: the held-at-rest
  // baseline took it up), waiting for its merge gap: the pick this declares, declared late
  // (the change against what the twin predicted with: an alert measures the arm against the twin)
  const double change = now.mass - had.mass;
  const auto withdraw_late_pick = [&](int index, double picked) {
    if (index < 0 || !late_declared_pick(events_[static_cast<size_t>(index)], t, picked)) return;
    const Event& e = events_[static_cast<size_t>(index)];
    add_note(t, fmt::format("the alert raised at {:.3f} s ({}) was the pick the program declares now, after the gripper closed: "
                            "withdrawn, not an event",
                            e.t_detected, e.detail));
    retract_event(index);
  };
  // a followed change held for this (may_be_declared_late): the pick, measured against what the
  // twin carried before it followed the change
  withdraw_late_pick(held_, now.mass - held_from_.mass);
  withdraw_late_pick(pending_close_, change);
  // (an alert raised at a grip shortly before: the pick this declares, declared late, which its close
  // decides: declared_pick_explains)
  if (payload_change_waits(t) && !late_declared_pick(events_[static_cast<size_t>(open_)], t, change)) {
    declaring_ = true;
    split_payload_change(t, "the program declared its next payload, which the twin predicts with from there");
    declaring_ = false;
  }
  declared_at_ = t;
  declared_change_ = change;
  // a diagnosed change the twin followed is superseded: the program has said what it carries (and a
  // split on a rise stands: the twin is not put back behind the declaration, unsplit_payload_change)
  followed_ = false;
  split_.reset();
  // the observer integrates the twin's torque, which changes in one step (as at a split,
  // split_payload_change)
  if (have_prev_) restart_estimators(false);
  // the controller's feed-forward changed with the declaration: a tracking error its position loop
  // carried for a payload it did not know (a part dropped undeclared) unwinds over the loop's
  // settling time, an acceleration the target the twin predicts with does not show. That transient
  // is the controller's, not a fault, and decisions wait it out (without the wait a 6-10 ms
  // "contact" followed 7 of 9 declared picks after an undeclared 0.5 kg drop, session 23 review)
  settle_until_ = std::max(settle_until_, n_samples_ + static_cast<long>(std::ceil(kDeclarationSettle / cfg_.nominal_period)));
  add_note(t, first ? fmt::format("the controller declares {} (the twin had {:.2f} kg): the twin predicts with the declaration", what, had.mass)
                    : fmt::format("the program declared {} (it had declared {:.2f} kg): the twin predicts with it, and a part lost or "
                                  "never picked shows as a payload change",
                                  what, was));
  carry(now, t);
}

void Monitor::follow_payload(Event& e, double t, double rebase_from) {
  // (a split on a rise, split_payload_change's on_top, that cannot follow goes back to the first
  // look and says nothing: the longer look decides, and says why then)
  const auto refuse = [&](const std::string& text) {
    if (!splitting_on_top_) add_note(t, text);
  };
  // the controller declared its payload after this alert began: the declaration is what the twin
  // carries now, and the diagnosed change (measured partly against the old payload) is not added to
  // it. (An alert that began after the declaration measures against it: a pick declared with no part
  // in the gripper reads as the declared mass lost, and is followed as one.)
  if (declared_at_ > e.t_start) {
    refuse( fmt::format("the payload change of the alert raised at {:.3f} s is not followed: the controller declared its payload at "
                            "{:.3f} s, and the twin predicts with that",
                            e.t_detected, declared_at_));
    return;
  }
  // what the diagnosis fitted: a point mass change at o.payload_com (run_diagnosis), the declared
  // payload's centre of mass or, with none declared, a part gripped at MonitorConfig::part_com
  const model::RigidBodyInertia had = twin_.payload();  // a copy: set_payload below replaces it
  const double change = e.magnitude;
  // kg in the twin's relative units (no known payload fixed its gains) are no mass to carry
  if (!twin_.gains_known() || !twin_.predicts_payload() || !std::isfinite(change)) {
    refuse( fmt::format("the payload change of the alert raised at {:.3f} s is not followed: {}; the alert stays open while the "
                    "robot runs with it",
                    e.t_detected,
                    !twin_.gains_known() ? "the twin's torques are relative (it was identified without a known payload that fixes its gains)"
                                         : "the twin's prediction does not carry a payload (method '" + twin_.method + "')"));
    return;
  }
  bool as_declared = false;
  const double mass = followed_mass(change, as_declared);
  if (std::isnan(mass)) {
    refuse( fmt::format("the payload change of the alert raised at {:.3f} s ({:+.2f} kg) is not followed: it is more than the {:.2f} kg "
                    "payload the twin carried; the alert stays open",
                    e.t_detected, change, had.mass));
    return;
  }
  // a payload beyond the arm's limit is no payload: a sustained push read as one (a 20 N·m push on
  // the flange fits a 3.85 kg "payload", session 21 review)
  const double limit = twin_.robot().payload_limit();
  if (mass > limit) {
    refuse( fmt::format("the payload change of the alert raised at {:.3f} s ({:+.2f} kg) is not followed: it would make a {:.2f} kg "
                    "payload, above {:g} kg ({}); the alert stays open",
                    e.t_detected, change, mass, limit, twin_.robot().payload_limit_text()));
    return;
  }
  // the evidence that it is the payload: the gripper's outputs changed in the window, or the payload
  // signature explains the residual nearly alone (a dropped part reads 88-89 %; a 12 N·m push on the
  // flange held for 6 s, 76 %: not followed, so the alert stays open and ends with the push)
  // (a gripper's output changes before the part moves: its valve or jaws take tens of ms, so the
  // look goes back kPayloadIoLookback before the exceedance began)
  if (!payload_evidence(e)) {
    refuse( fmt::format("the payload change of the alert raised at {:.3f} s ({:+.2f} kg) is not followed: no gripper output changed "
                    "and the payload explains {:.0f} % of the residual (following needs {:.0f} %); the alert stays open",
                    e.t_detected, change, 100.0 * e.explained, 100.0 * kPayloadFollowExplained));
    return;
  }
  followed_from_ = had;
  // the residual filter, the observer and the ring's estimates go on as if the twin had carried the
  // payload all along (rebase_on, from a copy of the twin as it was). Left as they were, they kept
  // the old payload's residual, which decays with their lags: where the alert had cleared first (a
  // pick at a rest, followed on its final look), that decay raised a 2 ms "contact" right after the
  // follow
  const ident::TwinModel& before = scratch_twin();
  carry(payload_of(mass, as_declared), t);
  rebased_from_ = rebase_from;
  rebase_on(before, rebase_from);
  followed_ = true;
  followed_at_ = t;
  const std::string what = mass > 0.0 ? fmt::format("a {:.2f} kg payload", mass) : std::string("no payload");
  // ended by the program's next declaration (take_declared_payload), which the twin takes at once:
  // the followed payload is never predicted with, and is not said to be
  if (declaring_) return;
  e.detail += fmt::format("; from {:.3f} s the twin predicts with {} and monitoring goes on with it", t, what);
  add_note(t, fmt::format("the twin now predicts with {} (it had {:.2f} kg; the payload change of the alert raised at {:.3f} s); "
                  "monitor --keep-payload keeps the declared one",
                  what, had.mass, e.t_detected));
}

double Monitor::followed_mass(double change, bool& as_declared) const {
  const double had = twin_.payload().mass;
  double mass = had + change;
  // a loss within the estimate's error of the payload held is that payload lost, all of it (the
  // longer look reads a 0.5 kg loss as -0.44 kg: a 0.06 kg part is not left); a loss much larger
  // than the payload held is no payload change the twin could carry
  const double tolerance = std::max(kPayloadFollowFloor, kPayloadFollowShare * std::abs(change));
  as_declared = false;
  if (!std::isfinite(change) || mass < -tolerance) return std::numeric_limits<double>::quiet_NaN();
  if (mass <= tolerance) mass = 0.0;
  // a change that lands within the estimate's error of the declared payload is the declared part
  // (the retry after a missed grip, which declares what was declared already): the twin takes the
  // declaration, not the estimate (0.98 kg for a declared 1 kg)
  as_declared = have_declared_ && declared_taken_ && std::abs(mass - declared_mass_) <= tolerance;
  return as_declared ? declared_mass_ : mass;
}

Eigen::Vector3d Monitor::payload_com() const {
  // a payload change is most likely the declared payload (or one gripped at the flange)
  return twin_.payload().mass > 0.0 ? twin_.payload().com : cfg_.part_com;
}

Eigen::Vector3d Monitor::payload_com_in_link() const { return twin_.robot().description().flange * payload_com(); }

model::RigidBodyInertia Monitor::payload_of(double mass, bool as_declared) const {
  // what the diagnosis fitted: a point mass change at o.payload_com (run_diagnosis), the declared
  // payload's centre of mass or, with none declared, a part gripped at MonitorConfig::part_com
  const model::RigidBodyInertia& had = twin_.payload();
  model::RigidBodyInertia now;
  if (mass > 0.0) {
    now.mass = mass;
    if (as_declared) {
      now.com = Eigen::Vector3d(declared_cog_[0], declared_cog_[1], declared_cog_[2]);
    } else {
      now.com = payload_com();
      // the declared payload's shape at the new mass; a part picked without one: a point mass
      if (had.mass > 0.0) now.inertia_com = had.inertia_com * (mass / had.mass);
    }
  }
  return now;
}

bool Monitor::output_changed_for(const Event& e) const {
  // (an output changed at a rest shows when the arm moves on, output_shown_at_: it counts for an alert
  // begun up to kLongWindow after that, as for one begun after it)
  return outputs_changed_within(e.t_start - kPayloadIoLookback, std::numeric_limits<double>::infinity()) ||
         output_shown_at_ >= e.t_start - kLongWindow;
}

bool Monitor::finds_parts() const {
  // (a stream that declares its payload is believed instead: take_declared_payload; kg in a twin's
  // relative units are no mass to carry)
  return cfg_.follow_payload && twin_.gains_known() && twin_.predicts_payload() && !have_declared_;
}

std::string Monitor::held_reason(const HeldStep& h) {
  return h.moving ? "raised soon after a gripper output changed" : "raised while the arm rested after a gripper output changed";
}

Monitor::PartStep Monitor::part_step_candidate(const Event& e) const {
  if (!finds_parts() || background_ >= 0 || e.fault == FaultClass::SensorFault) return PartStep::None;
  // raised in the rest in which an output changed (from kPayloadIoLookback before the change)
  if (arm_rests_ && !std::isnan(output_at_rest_) && e.t_start >= rest_since_ && e.t_start >= output_at_rest_ - kPayloadIoLookback)
    return PartStep::AtRest;
  // or, while the check after an output change is due, an alert that cleared before its first look
  // and read as a pulse where the part hangs, or as a resistance: a part's step near the
  // thresholds (a 0.3 kg part dropped at a rest and still carried by the twin: "contact on link 6,
  // 4.5 N" 0.7 s after the arm moved on; a 0.3 kg pick: "extra resistance on J3, 0.98 N·m", 24 ms).
  // (Cleared: a contact at the gripper soon after a part was picked stays an event when its alert
  // stood past the first look; holding those too lost 3 of the 29 contacts found in
  // scenarios/ur3e/payload_at_rest_contact. A resistance held when its residual had only been below
  // the thresholds for 20 ms lost a contact after a 0.25 kg pick read first as one, MonitorLoop test
  // ASmallPartsStepThatClearsWithinAPulseIsFollowed, seed 953)
  const bool cleared = std::none_of(joint_active_.begin(), joint_active_.end(), [](char a) { return a != 0; });
  const bool part_like = (e.fault == FaultClass::Collision && at_last_link(e)) || e.fault == FaultClass::Resistance;
  const bool due = std::isfinite(output_check_at_) && e.t_start >= output_check_from_ - kPayloadIoLookback;
  return due && part_like && cleared ? PartStep::InCheck : PartStep::None;
}

bool Monitor::grip_step(const Event& e) const {
  // A part's step read at its grip or release, as a pulse where the part hangs whose alert stood past
  // its first look (a 0.45 kg pick 0.2 s before the arm stops: "contact on link 5, 6.9 N; link 6 is
  // also possible" 16 ms after the output changed; a 0.15 kg pick: "contact on link 5, 6.1 N", 34 ms):
  // begun within kShortStep of the output's change, as a declared pick's step (declared_pick_candidate),
  // while the check after that change is due. Held like the pulses part_step_candidate holds, and
  // dropped only for a change whose weight it could be; a contact later than that stays an event
  // (holding every contact at the gripper while the check is due lost 3 of 29 in
  // scenarios/ur3e/payload_at_rest_contact, 0.2-1.4 s after the arm moved on)
  if (!finds_parts() || background_ >= 0) return false;
  const bool due = std::isfinite(output_check_at_) || !std::isnan(output_at_rest_);
  return due && e.fault == FaultClass::Collision && at_last_link(e) && e.t_start >= output_changed_at_ - cfg_.nominal_period &&
         e.t_start <= output_changed_at_ + kShortStep;
}

void Monitor::hold_part_step(double t, PartStep kind) {
  const Event& e = events_[static_cast<size_t>(open_)];
  const bool at_rest = kind == PartStep::AtRest;
  // a raise again at the same rest is the same step (on a stream without target velocities, where
  // the rest's raises are not held back); anything else is held on its own
  const auto same = std::find_if(held_steps_.begin(), held_steps_.end(),
                                 [&](const HeldStep& h) { return at_rest && !h.moving && h.event.t_start >= rest_since_; });
  if (same != held_steps_.end()) {
    same->event.t_end = std::max(same->event.t_end, e.t_end);
  } else {
    held_steps_.push_back({e, !at_rest});
    if (at_rest)
      add_note(t, fmt::format("the alert raised at {:.3f} s came {:.2f} s after a gripper output changed while the arm rests: it may be "
                              "the part's step, which static friction holds in part at a rest (read now as {}). It is held, and "
                              "reported only if no payload change shows once the arm has moved on",
                              e.t_detected, std::max(0.0, e.t_start - output_at_rest_), e.detail));
    else
      add_note(t, fmt::format("the alert raised at {:.3f} s ({}) is held until the payload check after the gripper output's change at "
                              "{:.3f} s: a part's step near the thresholds reads as such a pulse",
                              e.t_detected, e.detail, output_changed_at_));
  }
  withdraw_open_alert(false);
}

void Monitor::settle_part_steps(double t, double taken) {
  if (held_steps_.empty()) return;
  const double g = twin_.robot().gravity().norm();
  std::vector<HeldStep> held;
  held.swap(held_steps_);
  for (HeldStep& h : held) {
    Event& e = h.event;
    // what would explain it: the part the check took, a payload change raised since it began (open
    // or closed; not one it rose on top of), or a payload the program declared and the twin took. A
    // pulse held in motion only by a change whose weight it could be (a part's step reads as at most
    // kDeclaredForceShare times its weight, as at a declared pick). An alert held at the rest by any:
    // the part's jolt there reads as a contact anywhere (a 0.6 kg drop: "contact on link 5, 15.1 N",
    // 2.6 times its weight; 0.45-1 kg picks: "contact on link 1, 1.5-3.2 N·m"), so a contact at the
    // rest in which a gripper output changed is taken for the part's step when a payload change shows
    std::vector<double> changes;
    if (std::isfinite(taken)) changes.push_back(taken);
    if (declared_taken_ && declared_at_ >= e.t_start) changes.push_back(declared_change_);
    for (const Event& x : events_)
      if (x.fault == FaultClass::PayloadChange && x.t_start >= e.t_start) changes.push_back(x.magnitude);
    const bool explained = std::any_of(changes.begin(), changes.end(), [&](double c) {
      return !h.moving || e.fault != FaultClass::Collision || e.units != "N" || e.magnitude <= kDeclaredForceShare * std::abs(c) * g;
    });
    if (explained) {
      add_note(t, fmt::format("the alert held at {:.3f} s was the part's step: a payload change showed {}, and it is not an event of "
                              "its own",
                              e.t_detected, h.moving ? "in the check after the gripper output's change" : "once the arm moved on"));
      announce_withdrawal(e);  // (announced open when it was raised, and kept so while held: it ends here)
      continue;
    }
    e.open = false;
    e.detail += fmt::format("; {}, held, and reported at {:.3f} s: no payload change {}", held_reason(h), t,
                            h.moving ? "of a weight it could be showed after it" : "showed once the arm moved on");
    events_.push_back(e);
    if (on_event) on_event(events_.back());
  }
}

void Monitor::report_held_steps() {
  for (HeldStep& h : held_steps_) {
    Event& e = h.event;
    e.open = false;
    e.active_at_stop = true;
    e.detail += fmt::format("; {}, and held: monitoring stopped before {}", held_reason(h),
                            !h.moving && arm_rests_ && e.t_start >= rest_since_ ? "the arm moved on" : h.moving ? "the payload check after it"
                                                                                                          : "the payload check after the arm moved on");
    events_.push_back(e);
    if (on_event) on_event(events_.back());
  }
  held_steps_.clear();
}

void Monitor::track_rest(const RobotSample& s, double t, bool output_changed) {
  // A part gripped or released while the arm rests: static friction holds its step in part (a 1.2
  // N·m step stays within J2's rest band, docs/validation.md session 22), and what shows, shows when
  // the arm moves on, after a rest of any length (pick-and-place dwells of 0.8-2.5 s: a 0.3 kg part's
  // alert then came 0.8-6 s after its output changed, too late for kPayloadIoLookback). So an output
  // changed during a rest counts as changed when the arm moves on, and the payload check after it
  // looks at the motion from there
  // (the program's rest, where the stream has the target: a part dropped jolts the wrist to 0.06
  // rad/s, which is no move on; without it, no joint faster than kOutputCheckMinSpeed)
  const bool target = s.has(kFieldTargetQd) && s.target_qd.size() == s.qd.size();
  const bool rests = target ? RestBaseline::commanded_rest(s) : s.qd.cwiseAbs().maxCoeff() < kOutputCheckMinSpeed;
  rest_by_target_ = target;
  if (rests && !arm_rests_) {
    rest_since_ = t;
    // an output changed just before the arm came to rest, whose check is still due: its window would
    // be mostly the rest (a part released 0.25 s before the arm stopped at a 1.5 s rest was never
    // taken): it counts from when the arm moves on, as one changed at the rest
    if (std::isfinite(output_check_at_) && output_check_from_ == output_changed_at_ && t < output_check_at_) {
      output_at_rest_ = output_changed_at_;
      output_check_at_ = std::numeric_limits<double>::infinity();
    }
  }
  arm_rests_ = rests;
  if (output_changed) {
    // (the alerts held for the last change are settled first: its check is replaced by this one's)
    settle_part_steps(t, std::numeric_limits<double>::quiet_NaN());
    output_changed_at_ = t;
    if (rests) {
      output_at_rest_ = t;
      output_check_at_ = std::numeric_limits<double>::infinity();  // (scheduled when the arm moves on)
    } else {
      output_check_from_ = t;
      output_check_at_ = t + kOutputCheckAfter;
    }
  }
  if (!rests && !std::isnan(output_at_rest_)) {
    output_at_rest_ = std::numeric_limits<double>::quiet_NaN();
    output_shown_at_ = t;
    output_check_from_ = t;
    output_check_at_ = t + kOutputCheckAfter;
  }
}

bool Monitor::payload_evidence(const Event& e) const {
  // a gripper output changed just before, or in the part check's time before it: a light part's
  // step shows where the motion's accelerations weigh it, which can be 0.75 s after its grip (a
  // 0.15 kg pick, MonitorLoop.APartTooLightToRaiseAnAlertIsTakenAfterItsGripperOutputChanged: read
  // as "contact on link 6" it was held as the part's step, read as the "+0.15 kg" it was it was
  // left open, unfollowed, and the part's check then skipped it as decided by its own looks)
  // (no change yet: output_changed_at_ is -inf, which no alert begins within kLongWindow after)
  const bool in_part_check =
      finds_parts() && e.t_start >= output_changed_at_ - kPayloadIoLookback && e.t_start <= output_changed_at_ + kLongWindow;
  return output_changed_for(e) || in_part_check || e.explained >= kPayloadFollowExplained;
}

ident::TwinModel& Monitor::scratch_twin() {
  if (scratch_twin_) *scratch_twin_ = twin_;
  else scratch_twin_.emplace(twin_);
  return *scratch_twin_;
}

void Monitor::start_on_top(const Event& e, double change) {
  on_top_ = false;
  // only a change the longer look would follow (follow_payload's conditions): the split follows it
  if (!twin_.gains_known() || !twin_.predicts_payload() || declared_at_ > e.t_start || background_ >= 0 || merge_into_ >= 0 || followed_)
    return;
  if (!payload_evidence(e)) return;
  bool as_declared = false;
  const double mass = followed_mass(change, as_declared);
  if (std::isnan(mass) || mass > twin_.robot().payload_limit()) return;
  // (a copy of the twin once per payload change; per sample only its prediction)
  ident::TwinModel& watched = scratch_twin();
  watched.set_payload(payload_of(mass, as_declared));
  // (one prediction now, on a sample that diagnoses anyway: the copy builds its model with the
  // payload here, not in the per-sample watch, which then allocates nothing)
  const DiagnosisSample& now = ring_newest();
  watched.predict(now.q, now.qd, now.qdd, no_temp_, on_top_tau_, on_top_i_, &memory_);
  on_top_slow_alpha_ = 1.0 - std::exp(-cfg_.nominal_period / kOnTopRise);
  on_top_change_ = change;
  on_top_ = true;
  on_top_fresh_ = true;
  on_top_start_ = e.t_start;
  on_top_run_.assign(static_cast<size_t>(n_), 0);
  on_top_run_obs_.assign(static_cast<size_t>(n_), 0);
  on_top_from_.setZero(n_);
  on_top_from_obs_.setZero(n_);
  on_top_df_.setZero(n_);
  on_top_dobs_.setZero(n_);
  on_top_slow_.setZero(n_);
  on_top_slow_obs_.setZero(n_);
  on_top_moving_since_ = VectorJ::Constant(n_, -std::numeric_limits<double>::infinity());
  // (a joint resting when the watch starts: its baseline took up the step already)
  on_top_rested_.assign(static_cast<size_t>(n_), 0);
  for (int j = 0; j < n_; ++j) on_top_rested_[static_cast<size_t>(j)] = rest_rf_.settled(j) ? 1 : 0;
}

void Monitor::watch_on_top(const RobotSample& s, double t, bool settled, bool observer_decides) {
  const auto payload_like = [&](const Event& e) {
    return e.fault == FaultClass::PayloadChange || (e.fault == FaultClass::Collision && at_last_link(e));
  };
  const bool waiting = open_ >= 0 && events_[static_cast<size_t>(open_)].t_start == on_top_start_ &&
                       payload_like(events_[static_cast<size_t>(open_)]) && diagnosed_ && !rediagnosed_ && !followed_ &&
                       background_ < 0 && merge_into_ < 0 &&
                       // (a declaration since the first look: the twin predicts with it, not the copy)
                       declared_at_ <= on_top_start_ &&
                       // (a pick the program declared before its grip reads as the part lost until the grip,
                       // where the residual falls back and the alert is withdrawn: declared_pick_explains.
                       // Less the "loss", the grip itself would rise here)
                       !declared_pick_candidate(events_[static_cast<size_t>(open_)], declared_at_, declared_change_);
  if (!waiting) {
    on_top_ = false;
    return;
  }
  // the residual with the diagnosed payload is rf - (i_payload - i_hat): the difference filtered as
  // the residual is (a slow signal: started at its value)
  // and the observer's less the payload's torque, through the observer's own lag (its estimate is
  // a first-order lag of the torque the twin does not predict: TwinMomentumObserver)
  scratch_twin_->predict(s.q, s.qd, qdd_, s.temperature, on_top_tau_, on_top_i_, &memory_);
  double onset = std::numeric_limits<double>::infinity();
  const auto count = [&](bool over, int& run, double& from, int needed) {
    if (!over) {
      run = 0;
      return;
    }
    if (run == 0) from = t;
    run = std::min(run + 1, needed);
    if (run >= needed) onset = std::min(onset, from);
  };
  // what rises: above the threshold, and by half of it within about kOnTopRise (its slow mean).
  // The first look's payload is an estimate (-0.38 kg for a 0.5 kg drop, drop_then_declared_pick):
  // what it leaves grows as the pose changes, over the motion's time scale, and crossed the
  // threshold 0.5 s after the raise; a contact rises within tens of milliseconds
  const double slow = on_top_slow_alpha_;
  const auto rises = [](double r, double mean, double level) {
    return std::abs(r) > level && std::abs(r - mean) > kOnTopRiseShare * level;
  };
  for (int j = 0; j < n_; ++j) {
    const double d = on_top_i_[j] - i_hat_[j];
    const double dtau = on_top_tau_[j] - tau_hat_[j];
    on_top_df_[j] = on_top_fresh_ ? d : on_top_df_[j] + alpha_ * (d - on_top_df_[j]);
    // (through the observer's lag: obs_band_alpha_, its coefficient)
    on_top_dobs_[j] = on_top_fresh_ ? dtau : on_top_dobs_[j] + obs_band_alpha_ * (dtau - on_top_dobs_[j]);
    // (the observer's estimate rises as the twin's torque does: + the payload's torque)
    const double rc = rf_dec_[j] - on_top_df_[j], rc_obs = obs_dec_[j] + on_top_dobs_[j];
    on_top_slow_[j] = on_top_fresh_ ? rc : on_top_slow_[j] + slow * (rc - on_top_slow_[j]);
    on_top_slow_obs_[j] = on_top_fresh_ ? rc_obs : on_top_slow_obs_[j] + slow * (rc_obs - on_top_slow_obs_[j]);
    // a resting joint is left out: static friction holds a payload's step there (the residual does
    // not show it, and less the payload's current it would read as the opposite step)
    // Nor a joint that has just started moving: while it rested, its held-at-rest baseline took up
    // the payload's step with the friction it held, and both leave the residual as it breaks away (a
    // 1 kg pick at a rest read -0.46 A on J3 0.3 s later, against -0.2 A of payload: a false
    // "contact" where the arm moved on)
    // (a rest is one whose held-at-rest baseline was set, RestBaseline::settled, before or during
    // the watch; a reversal is none)
    const size_t J = static_cast<size_t>(j);
    const bool still = std::abs(s.qd[j]) < RestBaseline::kMeasuredRest;
    if (rest_rf_.settled(j)) {
      on_top_rested_[J] = 1;
    } else if (!still && on_top_rested_[J]) {
      on_top_rested_[J] = 0;
      on_top_moving_since_[j] = t;
    }
    const bool judged = !still && t - on_top_moving_since_[j] >= kOnTopMoving && memory_unsure_[J] == 0.0 && frozen_event_[J] < 0;
    count(judged && settled && rises(rc, on_top_slow_[j], level_[j]), on_top_run_[J], on_top_from_[j], cfg_.raise_after);
    count(judged && observer_decides && rises(rc_obs, on_top_slow_obs_[j], obs_level_[j]), on_top_run_obs_[J], on_top_from_obs_[j],
          cfg_.observer_debounce(j));
  }
  on_top_fresh_ = false;
  if (!std::isfinite(onset)) return;
  on_top_ = false;
  split_payload_change(t, "a residual rose above what the payload change explains (an alert of its own)", onset, true);
  if (open_ >= 0) return;  // (not split: the change was not followed, a note says why)
  // the runs that rose count toward the new alert's debounce, from where they began: it raises on
  // this sample's decision if the residual, now on the followed payload, is still above (re-counted
  // from the split, the new alert came 2-10 ms later than the same contact on a run without the change)
  for (size_t J = 0; J < static_cast<size_t>(n_); ++J) {
    const int j = static_cast<int>(J);
    // (this sample is in the run and the decision below counts it: the run less one)
    for (int k = 1; k < std::min(on_top_run_[J], cfg_.raise_after); ++k) deb_[J].update(true, on_top_from_[j]);
    for (int k = 1; k < std::min(on_top_run_obs_[J], cfg_.observer_debounce(j)); ++k) deb_obs_[J].update(true, on_top_from_obs_[j]);
  }
}

void Monitor::undo_follow(double t) {
  // the residual did not fall back when the twin took the payload: the change was not (only) the
  // payload, and the twin goes back to what it carried
  followed_ = false;
  const ident::TwinModel& before = scratch_twin();
  carry(followed_from_, t);
  rebase_on(before, rebased_from_);
  Event& e = events_[static_cast<size_t>(open_)];
  const std::string what = followed_from_.mass > 0.0 ? fmt::format("its {:.2f} kg payload", followed_from_.mass) : std::string("no payload");
  e.detail += fmt::format("; at {:.3f} s the residual had not fallen back, so the twin predicts with {} again", t, what);
  add_note(t, fmt::format("the payload change of the alert raised at {:.3f} s is undone: {:.1f} s after the twin took it the alert "
                          "was still up (not a payload the twin can carry); the twin predicts with {} again",
                          e.t_detected, t - followed_at_, what));
}

bool Monitor::payload_change_waits(double t) const {
  return open_ >= 0 && cfg_.follow_payload && diagnosed_ && !rediagnosed_ && !followed_ && background_ < 0 && merge_into_ < 0 &&
         events_[static_cast<size_t>(open_)].fault == FaultClass::PayloadChange &&
         t - events_[static_cast<size_t>(open_)].t_start >= kPayloadSplitAfter;
}

void Monitor::split_payload_change(double t, const char* where, double until, bool on_top) {
  // the window ends before the output changed: the samples after it belong to the next payload
  const double end = std::isnan(until) ? t : until;
  const Event first_look = events_[static_cast<size_t>(open_)];
  const int index = open_;
  splitting_on_top_ = on_top;
  run_diagnosis(t, true, end);
  splitting_on_top_ = false;
  if (open_ < 0 || !followed_) {
    // not followed (a note says why, or no payload change on the samples so far): the alert goes
    // on, and its longer look sees everything. A split on a rise goes back to what the first look
    // said, so that the longer look is not told otherwise by a shorter window
    if (on_top && open_ == index) {
      events_[static_cast<size_t>(open_)] = first_look;
      events_[static_cast<size_t>(open_)].t_end = t;
      if (on_event) on_event(events_[static_cast<size_t>(open_)]);
    }
    return;
  }
  rediagnosed_ = true;
  Event& done = events_[static_cast<size_t>(open_)];
  done.open = false;
  done.t_end = std::max(done.t_start, std::min({last_over_, t_prev_, end}));
  done.detail += fmt::format("; it ended at {:.3f} s, where {}", end, where);
  followed_ = false;
  cleared_at_ = t;
  if (on_top) {
    // something new on top of the payload change (watch_on_top): the filter and the observer go on
    // with what the followed payload changes in the twin's prediction taken out (restarted, the
    // observer was blind for its start-up samples and its estimate rose from zero in the new alert's
    // diagnosis window: a contact 0.3-2 s after a drop was named on the right link in 11 of 30 runs).
    // The change is closed tentatively, as an alert that clears is (pending_close_): the new alert
    // is diagnosed first (merge_into_). A contact ends it; anything else was the change itself still
    // growing (a push on the flange that a payload fitted at its start, which had left the twin
    // with 1.45 kg for a 0.5 kg part), and it continues as it was (unsplit_payload_change)
    // (follow_payload shifted them: rebase_on)
    split_ = first_look;
    split_from_ = followed_from_;
    pending_close_ = open_;
    merged_diagnosed_ = true;
    merged_rediagnosed_ = false;
    merged_raise_time_ = raise_time_;
    open_ = -1;
    return reset_decisions();
  }
  if (on_event) on_event(done);
  open_ = -1;
  // the twin's torque changed in one step: the observer, which integrates it, and the residual
  // filters start again on it (their states held the old payload's residual, which raised a 2 ms
  // "contact" on the next samples when the output change was no part: a vacuum gripper's blow-off
  // 0.6 s after a drop). The current channel decides on, the observer after its start-up samples
  restart_estimators(false);
  // every joint starts over: a residual still above its threshold is the next change's, and raises
  // an alert of its own (its diagnosis window sees the samples before t through the new payload)
  reset_decisions();
}

void Monitor::unsplit_payload_change(int into, double t) {
  Event& old = events_[static_cast<size_t>(into)];
  if (!split_ || old.t_start != split_->t_start) return;
  // the alert after a tentative split (split_payload_change) is no contact: the change goes on as
  // its first look said, to its longer look, on the twin it had
  const double followed = twin_.payload().mass;
  const ident::TwinModel& before = scratch_twin();
  carry(split_from_, t);
  rebase_on(before, rebased_from_);
  Event restored = *split_;
  restored.t_end = old.t_end;
  restored.peak_residual = std::max(old.peak_residual, restored.peak_residual);
  old = restored;
  split_.reset();
  add_note(t, fmt::format("what rose at {:.3f} s on top of the payload change of the alert raised at {:.3f} s was no contact: the change "
                          "goes on, and the twin predicts with {:.2f} kg again (not {:.2f} kg) until its longer look",
                          rebased_from_ + cfg_.diagnosis_pre + kContactReference, old.t_detected, twin_.payload().mass, followed));
}

void Monitor::rebase_on(const ident::TwinModel& before, double from) {
  // twin_ now predicts otherwise than `before` (another payload): the current residual's filter and
  // the observer's estimate, and this sample's decisions, as if twin_ had predicted all along (the
  // change is the payload's torque, slow against both lags). The newest ring sample is this one (or,
  // from a declaration, the one before: take_declared_payload runs before the ring takes the sample,
  // and a restart of the estimators follows there)
  const DiagnosisSample& now = ring_newest();
  VectorJ tau_before, i_before, tau_now, i_now;
  before.predict(now.q, now.qd, now.qdd, no_temp_, tau_before, i_before, &memory_);
  twin_.predict(now.q, now.qd, now.qdd, no_temp_, tau_now, i_now, &memory_);
  rf_ -= i_now - i_before;
  rf_dec_ -= i_now - i_before;
  if (obs_on_) {
    obs_.shift(tau_now - tau_before);
    obs_dec_ += tau_now - tau_before;
    // the observer's estimates the ring holds from `from` on, which the next diagnosis reads before
    // and around its alert's start (the current residual it computes again from the samples). Left
    // as they were, the payload's torque before a split read as a change on the last joints: a
    // contact on link 2 or 3 named link 4 or 5. (Two predictions a sample: about 0.4 s of them.)
    for (size_t k = 0; k < ring_count_; ++k) {
      DiagnosisSample& d = ring_slot(k);
      if (d.t < from || d.tau_ext.size() != n_) continue;
      before.predict_torque(d.q, d.qd, d.qdd, no_temp_, tau_before);
      twin_.predict_torque(d.q, d.qd, d.qdd, no_temp_, tau_now);
      d.tau_ext += (tau_now - tau_before).cwiseProduct(obs_to_nm_);
    }
  }
  // (a joint on Cao's FIR restarts it: its output is the taps over raw residuals, no state to shift)
  for (auto& f : fir_) f.reset();
}

void Monitor::track_margin(bool on) {
  if (n_samples_ > 0) throw InvalidArgument("Monitor::track_margin must be called before the first sample");
  margin_cur_.clear();
  margin_obs_.clear();
  if (!on) return;
  margin_cur_.assign(static_cast<size_t>(n_), DebouncedPeak(cfg_.raise_after));
  for (int j = 0; j < n_; ++j) margin_obs_.emplace_back(cfg_.observer_debounce(j));
}

VectorJ Monitor::peaks(const std::vector<DebouncedPeak>& channel) const {
  VectorJ v = VectorJ::Zero(n_);
  for (size_t j = 0; j < channel.size(); ++j) v[static_cast<int>(j)] = channel[j].peak();
  return v;
}

VectorJ Monitor::margin_current() const { return peaks(margin_cur_); }

VectorJ Monitor::margin_observer() const { return peaks(margin_obs_); }

bool Monitor::skip_invalid(const RobotSample& s) {
  // a sample that does not advance the controller's clock: a resend (or a clock fault). Processed
  // again, it would count twice in every debounce and filter.
  if (have_prev_ && !(s.timestamp > t_prev_)) {
    ++n_repeated_;
    return true;
  }
  // a position, velocity or current that is not a number: the recursive filters and the observer
  // would carry it forever (abs(nan) > level is never true: the joint would go blind). One beyond
  // any reading a joint gives (a corrupted word: 1.7e308 A) is no reading either: its square
  // overflowed the diagnosis's fits, and the monitor stopped with an error mid-run.
  constexpr double kMaxReading = 1e4;  // [rad], [rad/s], [A]
  const auto unreadable = [](double x) { return !(std::abs(x) <= kMaxReading); };
  int bad = -1;
  const char* what = "";
  double v = 0.0;
  for (int j = 0; j < n_ && bad < 0; ++j) {
    if (unreadable(s.q[j])) bad = j, what = "position", v = s.q[j];
    else if (unreadable(s.qd[j])) bad = j, what = "velocity", v = s.qd[j];
    else if (unreadable(s.current[j])) bad = j, what = twin_.channel_name(), v = s.current[j];
  }
  if (bad < 0) {
    invalid_run_ = false;
    return false;
  }
  ++n_invalid_;
  if (!invalid_run_) {
    Event f = new_event();
    f.t_start = f.t_end = f.t_detected = s.timestamp;
    f.open = false;
    f.fault = FaultClass::SensorFault;
    f.joint = bad;
    f.units = "";
    f.confidence = 1.0;
    f.detail = std::isfinite(v) ? fmt::format("the stream's J{} {} is {:g}, beyond {:g} (no joint reads that): samples are skipped until "
                                              "every value is a reading again",
                                              bad + 1, what, v, kMaxReading)
                                : fmt::format("the stream's J{} {} is {}: samples are skipped until every value is finite again", bad + 1, what, v);
    events_.push_back(f);
    if (on_event) on_event(f);
  }
  invalid_run_ = true;
  // the clock went on: the next sample is no stream gap, but what was estimated across the
  // skipped ones restarts as after one
  t_prev_ = s.timestamp;
  restart_pending_ = have_prev_;
  return true;
}

void Monitor::restart_estimators(bool settle) {
  obs_.reset();
  obs_samples_ = 0;
  // with the start-up wait, the residual filter starts on the first sample's residual, as at the
  // start of a run; without it (a payload change the twin takes, where decisions go on) it starts
  // from zero and follows the residual with its own time constant: started on one raw sample, its
  // noise alone went over a threshold (a 4 ms "contact" right after a declared pick, session 23)
  filter_started_ = !settle;
  if (!settle) rf_.setZero(n_);
  for (auto& f : fir_) f.reset();
  if (settle) settle_until_ = n_samples_ + kObserverSettle;
}

void Monitor::restart_after_gap(const RobotSample& s, bool memory_lost) {
  // what was estimated across the gap is stale: the observer starts again (its first difference
  // would span the gap and jump by half the drive torque's change across it), the residual filter
  // and the acceleration estimate restart, frozen-channel runs compare nothing across it, and
  // decisions wait the start-up samples again, as at the beginning of a run
  restart_estimators();
  std::fill(frozen_run_.begin(), frozen_run_.end(), 0);
  // the twin's pre-sliding memory cannot follow motion it did not see: a reversal inside the gap
  // leaves it on the wrong side, and a joint that stands still after the gap (at a turning point)
  // shows twice its pre-sliding level as a residual
  if (memory_lost && memory_.primed) guess_memory(s);
}

void Monitor::guess_memory(const RobotSample& s) {
  // A moving joint has slid in its direction; for the others the memory is unknown, and their
  // decisions wait until they have moved far enough to have set it again (kMemoryRestore
  // pre-sliding distances)
  for (int j = 0; j < n_; ++j) {
    const double alpha = twin_.joints[static_cast<size_t>(j)].presliding_alpha;
    if (!(alpha > 0.0)) continue;  // no memory in this twin's joint
    if (std::abs(s.qd[j]) > kMovingVelocity) {
      memory_.h[j] = s.qd[j] > 0.0 ? 1.0 : -1.0;
    } else {
      memory_unsure_[static_cast<size_t>(j)] = kMemoryRestore / alpha;
      memory_from_[j] = s.q[j];
    }
  }
  memory_.q_prev = s.q;
}

bool Monitor::temperature_implausible(const RobotSample& s) {
  if (!s.has(kFieldTemperature)) return false;
  const int m = std::min<int>(n_, static_cast<int>(s.temperature.size()));
  bool any = false;
  for (int j = 0; j < m; ++j) {
    const double T = s.temperature[j];
    if (!plausible_temperature(T)) {
      any = true;
    } else if (std::isfinite(T)) {
      temperature_ok_[j] = T;
      temperature_run_[static_cast<size_t>(j)] = 0;
    }
  }
  return any;
}

void Monitor::hold_temperature(RobotSample& held) {
  const int m = std::min<int>(n_, static_cast<int>(held.temperature.size()));
  for (int j = 0; j < m; ++j) {
    const double T = held.temperature[j];
    if (plausible_temperature(T)) continue;
    held.temperature[j] = temperature_ok_[j];
    if (temperature_run_[static_cast<size_t>(j)]) continue;
    temperature_run_[static_cast<size_t>(j)] = 1;
    Event f = new_event();
    f.t_start = f.t_end = f.t_detected = held.timestamp;
    f.open = false;
    f.fault = FaultClass::SensorFault;
    f.joint = j;
    f.magnitude = T;
    f.units = "°C";
    f.confidence = 1.0;
    f.detail = fmt::format("the stream's J{} temperature reads {:g} °C, which no joint reads ({:g} to {:g} °C): the samples are judged with "
                           "{} until it reads plausibly again",
                           j + 1, T, kTemperatureMin, kTemperatureMax,
                           std::isfinite(temperature_ok_[j]) ? fmt::format("its last plausible reading ({:g} °C)", temperature_ok_[j])
                                                             : std::string("no temperature (none plausible read yet)"));
    events_.push_back(f);
    if (on_event) on_event(f);
  }
}

void Monitor::push(const RobotSample& s) {
  if (skip_invalid(s)) return;
  if (temperature_implausible(s)) {
    RobotSample held = s;  // (a copy only for such a sample)
    hold_temperature(held);
    return judge(held);
  }
  judge(s);
}

void Monitor::judge(const RobotSample& s) {
  const double t = s.timestamp;
  ++n_samples_;
  if (n_samples_ == 1) check_payload_envelope(t);
  // stream: gaps in the controller timestamp are events of their own, never interpolated
  const double dt = have_prev_ ? t - t_prev_ : cfg_.nominal_period;
  const bool gap = have_prev_ && (s.gap_before || dt > gap_factor_ * cfg_.nominal_period);
  if (have_prev_ && !gap && !cfg_.gaps_judged) track_jitter(dt, t);
  const bool restart = gap || restart_pending_;
  if (restart) {
    restart_after_gap(s);
    restart_pending_ = false;
  }
  if (gap) {
    ++n_gaps_;
    Event g = new_event();
    g.t_start = t_prev_;
    g.t_end = t;
    g.t_detected = t;
    g.open = false;
    g.fault = FaultClass::StreamFault;
    g.magnitude = std::round(dt / cfg_.nominal_period) - 1.0;
    g.units = "samples";
    g.confidence = 1.0;
    // a gap the source flagged (a reconnection) whose stamps are a period apart lost no sample the
    // stamps can show: said so, not "0 sample(s) missing" (audit of session 22)
    // samples the live source dropped (RobotSample::dropped_before: the monitor fell behind) are this
    // computer's gap, not the controller's (soak audit, session 39)
    g.detail = s.dropped_before > 0
                   ? fmt::format("{:.0f} sample(s) missing ({:.1f} ms gap): {} of them dropped on this computer, where the monitor fell "
                                 "behind the stream (the controller sent them; a slow disk or a loaded machine?)",
                                 g.magnitude, 1000 * dt, s.dropped_before)
               : g.magnitude >= 1.0
                   ? fmt::format("{:.0f} sample(s) missing ({:.1f} ms gap in the controller timestamp)", g.magnitude, 1000 * dt)
                   : fmt::format("the stream was interrupted before this sample (flagged by its source; the timestamps are {:.1f} ms "
                                 "apart, no sample missing by them)",
                                 1000 * dt);
    if (outage_ >= 0) {
      close_outage(g);
    } else {
      events_.push_back(g);
      if (on_event) on_event(g);
    }
  }
  // the controller does not drive the arm (power off, brakes on, a protective or emergency stop):
  // the twin's prediction is a driven arm's, so nothing is judged until it drives it again
  if (!s.driven()) {
    pause_watch(s, t, dt);
    return;
  }
  if (paused_) resume_watch(s, t);
  driven_seen_ = true;
  // the payload the program declares, when the stream carries it (before the prediction uses it)
  // (per sample the declaration is compared in line; only a new one costs the call)
  if (cfg_.follow_payload && s.has(kFieldPayload) && !same_declaration(s)) take_declared_payload(s);
  // acceleration: the controller's target when streamed, else a filtered difference of qd
  if (s.has(kFieldTargetQdd)) {
    qdd_ = s.target_qdd;
  } else if (windowed_) {
    qdd_ = windowed_->push(t, s.qd);  // (a gap restarts it only beyond its own span: it reads the samples' times)
    // held after a (re)start until both means are whole: no decision on it, nor in the residual
    // filter's tail after (a log that starts mid-motion raised a false contact at 50 ms: the held 0
    // left M qdd out of the twin)
    if (!windowed_->ready()) settle_until_ = std::max(settle_until_, n_samples_ + kWindowSettle);
  } else if (have_prev_ && !restart) {  // (not across a gap or skipped samples)
    qdd_ += alpha_ * ((s.qd - qd_prev_) / dt - qdd_);
  }
  const bool first_memory = !memory_.primed;
  twin_.advance(memory_, s, qdd_);
  // a monitor that joins an arm in motion (a live robot mid-program, a recording cut from a longer
  // one) has not seen how its joints came to where they are: a joint at a turning point or held at
  // a station holds the friction of a direction the memory's start (h = 0) does not know, which
  // raised false contacts on the healthy figure-eight (10 of 200 start points, audit of session 38).
  // It starts as after a gap, an arm at rest too: met at a triangle's corner, its joints hold the
  // friction of the edge before it (1 false contact in 225 start points). A run that starts from
  // standstill loses only the decisions of a joint until it has moved three pre-sliding distances
  // (the library's and held-out sets score identically either way)
  if (first_memory) guess_memory(s);
  // the observer's twin torque (at its own, unfiltered acceleration) comes with the prediction
  const VectorJ* qdd_obs = obs_on_ ? obs_.acceleration(s, dt) : nullptr;
  if (qdd_obs != nullptr)
    twin_.predict_pair(s.q, s.qd, qdd_, *qdd_obs, s.temperature, tau_hat_, i_hat_, tau_obs_, &memory_);
  else
    twin_.predict(s.q, s.qd, qdd_, s.temperature, tau_hat_, i_hat_, &memory_);
  r_ = s.current - i_hat_;
  // temperature: the viscous friction's slope learned on a healthy warm-up (trend.hpp), so that
  // neither the thresholds nor the wear trend see a cooling or warming joint as a fault
  for (int j = 0; j < n_; ++j)
    if (s.temperature.size() > j && std::isfinite(s.temperature[j]))
      r_[j] -= temp_slope_[j] * s.qd[j] * (s.temperature[j] - cfg_.trend.temperature_ref);
  // the drive's direction in doubt at a reversal: the level the current says (resolve_drive_doubt)
  if (cfg_.drive_doubt) resolve_drive_doubt(twin_, tau_hat_, memory_, r_);
  if (!filter_started_) {
    rf_ = r_;
    filter_started_ = true;
  } else {
    rf_ += alpha_ * (r_ - rf_);
  }
  for (size_t j = 0; j < fir_.size(); ++j)
    if (!fir_[j].taps().empty()) rf_[static_cast<int>(j)] = fir_[j].push(r_[static_cast<int>(j)]);
  i_total_ = s.current.cwiseAbs().sum();
  // second residual: the momentum observer's external-torque estimate (no acceleration estimate)
  if (obs_on_) {
    temperature_drive_torque(twin_, temp_slope_, cfg_.trend.temperature_ref, s, obs_warm_);
    // (a drive's direction in doubt: the level nearer the twin's torque at the prediction's
    // acceleration, as the current residual takes the level nearer the current; the encoder
    // difference the observer's own torque uses is too noisy to choose a level on)
    obs_ref_ = tau_hat_ + obs_warm_;
    obs_.update_with_torque(twin_, s, dt, tau_obs_, &obs_warm_, &memory_, cfg_.drive_doubt ? &obs_ref_ : nullptr);
    if (obs_samples_ < kObserverSettle) ++obs_samples_;
  }
  // thresholds
  for (int j = 0; j < n_; ++j) {
    level_[j] = level_at(cfg_.use_dynamic, cfg_.dynamic, cfg_.static_level, j, s.qd[j], qdd_[j], cfg_.sensitivity[j]);
    // the observer's threshold is evaluated even when it raises no alert (the trace and the
    // diagnosis show it); only the decisions below depend on observer_alerts
    if (obs_on_)
      obs_level_[j] = level_at(cfg_.use_dynamic, cfg_.observer_dynamic, cfg_.observer_level, j, s.qd[j], qdd_[j], cfg_.sensitivity[j]);
  }
  if (load_band_on_) widen_for_load(s.qd, t);
  // ring buffer for the diagnosis (torque-domain residual through the drive gains)
  DiagnosisSample& ds = ring_[ring_head_];
  ds.t = t;
  ds.q = s.q;
  ds.qd = s.qd;
  ds.qdd = qdd_;
  for (int j = 0; j < n_; ++j) ds.r_tau[j] = torque_gain(j) * rf_[j];
  ds.current = s.current;
  ds.tau_ext = observer_torque();
  ds.tau_ext_level = observer_torque_threshold();
  ds.presliding = memory_.h;
  ds.direction = memory_.direction;
  ds.digital_outputs = s.digital_outputs;
  ds.gap_before = false;  // gaps are reported as their own events
  ring_head_ = (ring_head_ + 1) % ring_.size();
  ring_count_ = std::min(ring_count_ + 1, ring_.size());

  // frozen current channel while the joint moves: a sensor fault even below the threshold. One
  // event per frozen stretch, raised once the joint has moved frozen_samples samples on it (a
  // joint at rest pauses the count: a resting joint's current may be steady) and closed when the
  // value changes, with the stretch's true start and end
  for (int j = 0; j < n_; ++j) {
    const size_t J = static_cast<size_t>(j);
    int& run = frozen_run_[J];
    if (s.current[j] != frozen_val_[j]) {
      if (frozen_event_[J] >= 0) close_frozen(j);
      run = 0;
      frozen_since_[j] = t;
    } else if (std::abs(s.qd[j]) > kMovingVelocity) {
      run = std::min(run + 1, cfg_.frozen_samples + 1);  // (saturated: a channel frozen for weeks must not overflow)
    }
    frozen_val_[j] = s.current[j];
    if (run == cfg_.frozen_samples && frozen_event_[J] < 0) {
      Event f = new_event();
      f.t_start = frozen_since_[j];
      f.t_end = t;
      f.t_detected = t;
      f.open = true;
      f.fault = FaultClass::SensorFault;
      f.joint = j;
      f.units = "samples";
      f.confidence = 1.0;
      f.detail = fmt::format("{} channel of J{} frozen at {:.4f} {} while the joint moves", twin_.channel_name(), j + 1, s.current[j], twin_.channel_unit());
      events_.push_back(f);
      frozen_event_[J] = static_cast<int>(events_.size()) - 1;
      if (on_event) on_event(f);
    }
    if (frozen_event_[J] >= 0) {
      Event& f = events_[static_cast<size_t>(frozen_event_[J])];
      f.t_end = t;
      f.magnitude = std::round((t - f.t_start) / cfg_.nominal_period) + 1.0;
      // (as every alert's: the largest |filtered current residual| of any joint during it; it read 0.0
      // while the frozen J2 was 0.53 A off its prediction; review, session 47)
      if (rf_.size() == n_) f.peak_residual = std::max(f.peak_residual, rf_.cwiseAbs().maxCoeff());
    }
  }

  // decisions, on the residuals less what a resting joint is held at (RestBaseline)
  rf_dec_ = rf_;
  rest_rf_.apply(s, rf_dec_);
  obs_dec_ = obs_.residual();
  rest_obs_.apply(s, obs_dec_);
  bool any_active = false, background_active = false;
  // the thresholds were learned without each run's first kObserverSettle samples (filter and
  // observer start-up), so they do not apply there
  const bool settled = n_samples_ > settle_until_;
  if (settled) ++n_judged_;
  const bool observer_decides = settled && obs_on_ && cfg_.observer_alerts && obs_samples_ >= kObserverSettle;
  // (a gripper output changed at this sample)
  const bool output_changed = have_prev_ && s.digital_outputs != outputs_prev_;
  track_rest(s, t, output_changed);
  // a rest longer than the thresholds in use saw (MonitorConfig::longest_rest), timed from the
  // sample the learner starts at (kSettleSamples): a run that starts at rest (the Panda log's 44 ms)
  // was said to rest longer than its own training, "at most 0.00 s" (audit of session 56)
  if (std::isfinite(cfg_.longest_rest) && n_samples_ > kSettleSamples) watch_unseen_rest(s, t);
  // (an alert held at this rest, which the stream's targets say is one: the part's step, looked at
  // when the arm moves on)
  const bool rest_held = arm_rests_ && rest_by_target_ && std::any_of(held_steps_.begin(), held_steps_.end(), [&](const HeldStep& h) {
    return !h.moving && h.event.t_start >= rest_since_;
  });
  if (on_top_) watch_on_top(s, t, settled, observer_decides);
  // the first motion after a powered resume on a stream without targets (MonitorConfig::resume_widen)
  if (resume_pending_ && s.qd.cwiseAbs().maxCoeff() > kMovingVelocity) {
    resume_pending_ = false;
    resume_until_ = t + kResumeWindow;
  }
  const double widen = t <= resume_until_ ? cfg_.resume_widen : 1.0;
  for (int j = 0; j < n_; ++j) {
    double& unsure = memory_unsure_[static_cast<size_t>(j)];
    if (unsure > 0.0 && std::abs(s.q[j] - memory_from_[j]) >= unsure) unsure = 0.0;
    // (nor does a frozen current channel: its residual is the channel's fault, already reported)
    const bool decides = unsure == 0.0 && frozen_event_[static_cast<size_t>(j)] < 0;
    const bool over_current = settled && decides && !rest_held && std::abs(rf_dec_[j]) > widen * level_[j];
    const bool over_observer = observer_decides && decides && !rest_held && std::abs(obs_dec_[j]) > widen * obs_level_[j];
    if (over_current || over_observer) (j == background_joint_ && background_ >= 0 ? background_last_over_ : last_over_) = t;
    Debouncer& dc = deb_[static_cast<size_t>(j)];
    Debouncer& dob = deb_obs_[static_cast<size_t>(j)];
    dc.update(over_current, t);
    dob.update(over_observer, t);
    if (!margin_cur_.empty()) {
      margin_cur_[static_cast<size_t>(j)].update(settled && level_[j] > 0.0 ? std::abs(rf_dec_[j]) / (widen * level_[j]) : 0.0);
      margin_obs_[static_cast<size_t>(j)].update(observer_decides && obs_level_[j] > 0.0 ? std::abs(obs_dec_[j]) / (widen * obs_level_[j]) : 0.0);
    }
    // the joint's alert is active while either channel's is; it is raised when the first one raises
    const bool active = dc.active() || dob.active();
    const bool raised = active && !joint_active_[static_cast<size_t>(j)];
    // an alert starts where the first of its channels went over
    const auto raise_start = [&] {
      return dc.active() && dob.active() ? std::min(dc.start(), dob.start()) : (dc.active() ? dc.start() : dob.start());
    };
    const auto raised_by = [&]() -> std::string {
      const std::string residual = fmt::format("{} residual", twin_.channel_name());  // (a joint-torque twin's: "torque residual")
      return dc.active() && dob.active() ? residual + " and momentum observer" : dc.active() ? residual : std::string("momentum observer");
    };
    joint_active_[static_cast<size_t>(j)] = active;
    if (raised && open_ >= 0 && background_ < 0 && diagnosed_ && j != events_[static_cast<size_t>(open_)].joint &&
        events_[static_cast<size_t>(open_)].joint >= 0 &&
        (events_[static_cast<size_t>(open_)].fault == FaultClass::Resistance ||
         events_[static_cast<size_t>(open_)].fault == FaultClass::SensorFault)) {
      // a persistent alert is open on its joint and another joint raises: park it, look at this raise
      background_ = open_;
      background_joint_ = events_[static_cast<size_t>(open_)].joint;
      background_rediagnosed_ = rediagnosed_;
      background_raise_time_ = raise_time_;
      background_last_over_ = last_over_;
      open_event(j, raise_start(), t, raised_by().c_str());
      last_over_ = t;
    } else if (raised && open_ < 0) {
      // a persistent fault dips below the threshold at velocity reversals: a raise shortly after
      // the last alert closed continues that alert when it is on the alert's joint. A raise on
      // another joint is looked at on its own first (merge_into_), so that a contact during a
      // persistent fault is not taken for its dip.
      const bool recent = pending_close_ >= 0 && t - cleared_at_ < kMergeGap;
      if (recent && events_[static_cast<size_t>(pending_close_)].joint == j) {
        open_ = pending_close_;
        pending_close_ = -1;
        events_[static_cast<size_t>(open_)].open = true;
        diagnosed_ = merged_diagnosed_;
        rediagnosed_ = merged_rediagnosed_;
        raise_time_ = merged_raise_time_;
      } else {
        if (recent) {
          merge_into_ = pending_close_;
          pending_close_ = -1;
        } else {
          report_pending_close();
        }
        open_event(j, raise_start(), t, raised_by().c_str());
      }
    }
    if (background_ >= 0 && j == background_joint_) {
      background_active = active;
    } else {
      any_active |= active;
    }
  }
  if (background_ >= 0) {
    Event& b = events_[static_cast<size_t>(background_)];
    if (background_active) b.t_end = t;
  }
  // a gripper output changes while a payload change waits for its longer look: a part swapped (a
  // drop and a pick 1 s apart, a dual gripper tending a machine). Left to the longer look, one
  // window held both changes, which no single signature fits (it read as a contact on link 6 that
  // never cleared, and hid what came after it)
  if (output_changed && payload_change_waits(t) &&
      !declared_pick_candidate(events_[static_cast<size_t>(open_)], declared_at_, declared_change_))
    split_payload_change(t, "a gripper output changed again");
  if (open_ >= 0) {
    Event& e = events_[static_cast<size_t>(open_)];
    e.t_end = t;
    e.peak_residual = std::max(e.peak_residual, rf_.cwiseAbs().maxCoeff());
    if (!diagnosed_ && t - raise_time_ >= cfg_.diagnosis_delay) run_diagnosis(t);
    // an alert still active after kLongWindow is no pulse: a second, longer look
    if (diagnosed_ && !rediagnosed_ && t - raise_time_ >= kLongWindow) {
      run_diagnosis(t, true);
      rediagnosed_ = true;
    }
    const bool parked = background_ >= 0;
    // (an alert that clears before its diagnosis gets it first: the withdrawal goes by its class)
    if (open_ >= 0 && !any_active && !diagnosed_) run_diagnosis(t);
    if (!any_active && open_ >= 0 && declared_pick_explains(t)) {
      const Event& w = events_[static_cast<size_t>(open_)];
      add_note(t, fmt::format("the alert raised at {:.3f} s ({}) was the pick the program declared at {:.3f} s, {} the gripper closed: "
                              "the twin's payload and the arm's load agree again, so it is withdrawn, not an event",
                              w.t_detected, w.detail, declared_at_,
                              declared_at_ < w.t_start ? "before" : "after"));
      withdraw_open_alert();
    } else if (!any_active && open_ >= 0) {
      // an alert that lasted well beyond a pulse gets its final look with everything seen (a raise
      // that parked a persistent alert may merge back into it there). A payload change it finds is
      // followed there too: in a program that rests between moves, the held-at-rest baseline takes
      // up the residual and the alert clears before the longer look
      const Event& ending = events_[static_cast<size_t>(open_)];
      const bool beyond_pulse = t - ending.t_start > kPulseMax;
      // A payload change with a gripper output changed (from kPayloadIoLookback before it began) is a
      // step, not a pulse, however briefly it stood above the thresholds: a small part's step near
      // them dips below them within a pulse's time (a 0.25 kg drop on the triangle: 0.1-0.4 s), and
      // left unfollowed it rose again and again, as alerts that no longer saw the output change, and
      // a contact went into one of them
      const bool step = ending.fault == FaultClass::PayloadChange && cfg_.follow_payload && output_changed_for(ending);
      // (diagnosed by now: just above)
      if (!rediagnosed_ && (beyond_pulse || step)) run_diagnosis(t, true);
    }
    if (followed_ && any_active && t - followed_at_ >= kPayloadFollowSettle) undo_follow(t);
    if (open_ < 0) {
      // withdrawn above
    } else if (!any_active && parked && background_ >= 0) {
      // the contact that parked a persistent alert has cleared: the parked alert is the open one again
      Event& done = events_[static_cast<size_t>(open_)];
      done.open = false;
      done.t_end = std::max(done.t_start, last_over_);
      if (on_event) on_event(done);
      followed_ = false;
      resume_background();
    } else if (!any_active && !parked) {
      Event& done = events_[static_cast<size_t>(open_)];
      done.open = false;
      // it ended at its last exceedance, not when the clearing debounce (clear_after samples) ran out
      done.t_end = std::max(done.t_start, last_over_);
      cleared_at_ = t;
      if (done.fault == FaultClass::Collision || followed_) {
        // a contact, or a payload change the twin now carries: nothing after it continues it (a
        // pick right after a followed drop is a change of its own, to be followed in turn)
        if (followed_ && may_be_declared_late(done, t)) hold(open_);
        else if (!followed_ && grip_step(done)) hold_part_step(t, PartStep::InCheck);
        else if (on_event) on_event(done);
        followed_ = false;
      } else {
        pending_close_ = open_;
        merged_diagnosed_ = diagnosed_;
        merged_rediagnosed_ = rediagnosed_;
        merged_raise_time_ = raise_time_;
      }
      open_ = -1;
    }
  }
  if (pending_close_ >= 0 && t - cleared_at_ >= kMergeGap) report_pending_close();
  if (held_ >= 0 && t >= held_until_) report_held();
  if (t >= output_check_at_) check_payload_after_output(t);
  // slow wear: per-window friction trend (samples of an open alert are left out)
  if (trend_.push(t, s.qd, r_, rf_, level_, s.temperature, i_total_, open_ >= 0 || background_ >= 0)) {
    events_.push_back(trend_.warning());
    if (on_event) on_event(events_.back());
  }
  if (std::string note; trend_.take_note(note)) add_note(t, note);
  qd_prev_ = s.qd;
  outputs_prev_ = s.digital_outputs;
  t_prev_ = t;
  have_prev_ = true;
}

void Monitor::track_jitter(double dt, double t) {
  // a stream whose stamps jitter (a logger's or a PC's clock rather than the controller's): a late
  // stamp followed by an early one is no lost sample. The mean absolute deviation of the steps from
  // the period (exponentially weighted) gives their spread (sqrt(pi/2) x it for Gaussian steps), and
  // a step counts as lost samples only 5 spreads above the period, as the recording reader does for
  // files (device::jitter_gap_factor). A controller's own clock: spread ~0, the
  // configured factor. Measured: the simulator's 0.25 ms timestamp jitter at 500 Hz gave ~70
  // "1 sample missing" in 60 s with the configured 1.5 periods, none with this (MonitorLoop test)
  const double dev = std::abs(dt - cfg_.nominal_period);
  // (a running mean over the first kJitterWindow steps, then exponential; one multiply per sample)
  jitter_mad_ += (dev - jitter_mad_) * (jitter_steps_ < kJitterWindow ? 1.0 / (jitter_steps_ + 1.0) : 1.0 / kJitterWindow);
  ++jitter_steps_;
  if (jitter_steps_ < kJitterMinSteps) return;
  const double spread = std::sqrt(M_PI / 2.0) * jitter_mad_;
  const double widened = device::jitter_gap_factor(spread, cfg_.nominal_period, cfg_.gap_factor);
  if (widened > gap_factor_ * kJitterNoteStep) {
    add_note(t, fmt::format("the stream's timestamps jitter (spread {:.2f} ms around the {:.2f} ms period: a logger's clock, not the "
                            "controller's?): a step counts as lost samples only above {:.1f} ms; shorter losses cannot be told from "
                            "the jitter",
                            1000.0 * spread, 1000.0 * cfg_.nominal_period, 1000.0 * widened * cfg_.nominal_period));
    gap_factor_ = widened;
  } else if (widened < gap_factor_) {
    gap_factor_ = widened;
  }
}

void Monitor::add_note(double t, const std::string& text) {
  notes_.push_back(text);
  if (on_note) on_note(t, text);
}

void Monitor::drop_open_event() { retract_event(open_); }

void Monitor::retract_event(int index) {
  announce_withdrawal(events_[static_cast<size_t>(index)]);
  drop_event(index);
}

void Monitor::announce_withdrawal(const Event& e) const {
  if (!on_withdraw) return;
  Event w = e;
  w.open = false;
  w.withdrawn = true;
  on_withdraw(w);
}

void Monitor::drop_event(int index) {
  // the indices kept into events_ after it move down by one, one that pointed at it is cleared
  events_.erase(events_.begin() + index);
  for (int* k : event_indices())
    if (*k == index) *k = -1;
    else if (*k > index) --*k;
  for (int& k : frozen_event_)
    if (k == index) k = -1;
    else if (k > index) --k;
}

long Monitor::forget_events_before(double t) {
  long n = 0;
  // the front event is referenced: still watched (open, parked, held, merged into, frozen channel)
  const auto front_referenced = [&] {
    const auto indices = event_indices();
    return std::any_of(indices.begin(), indices.end(), [](const int* k) { return *k == 0; }) ||
           std::find(frozen_event_.begin(), frozen_event_.end(), 0) != frozen_event_.end();
  };
  // oldest first, and only from the front: the list stays in order, the indices kept into it are
  // shifted by drop_event
  while (!events_.empty() && !events_.front().open && events_.front().t_end < t && !front_referenced()) {
    drop_event(0);
    ++n;
  }
  n_forgotten_ += n;
  return n;
}

void Monitor::resume_background() {
  open_ = background_;
  background_ = -1;
  background_joint_ = -1;
  diagnosed_ = true;
  rediagnosed_ = background_rediagnosed_;
  raise_time_ = background_raise_time_;
  last_over_ = std::max(last_over_, background_last_over_);
  events_[static_cast<size_t>(open_)].open = true;
}

bool Monitor::may_be_declared_late(const Event& e, double t) const {
  // a stream that declares its payload, no declaration since the change began, a gripper output
  // changed just before it (a pick or a release), and within the time a program declares its pick in
  return have_declared_ && e.fault == FaultClass::PayloadChange && declared_at_ < e.t_start && t < e.t_start + kDeclarationLag &&
         gripped_before(e, std::numeric_limits<double>::infinity());
}

void Monitor::hold(int index) {
  report_held();
  held_ = index;
  held_until_ = events_[static_cast<size_t>(index)].t_start + kDeclarationLag;
  held_from_ = followed_from_;
}

void Monitor::report_held() {
  if (held_ < 0) return;
  const Event& e = events_[static_cast<size_t>(held_)];
  held_ = -1;
  if (on_event) on_event(e);
}

void Monitor::report_pending_close() {
  if (pending_close_ < 0) return;
  const Event& e = events_[static_cast<size_t>(pending_close_)];
  if (split_ && e.t_start == split_->t_start) split_.reset();  // (a split that stands)
  pending_close_ = -1;
  if (on_event) on_event(e);
}

// a stream fault for `seconds` without data after the last sample: its size in samples missed
Event Monitor::silence_event(double seconds, bool open) {
  Event g = new_event();
  g.t_start = t_prev_;
  g.t_end = t_prev_ + seconds;
  g.t_detected = g.t_end;
  g.open = open;
  g.fault = FaultClass::StreamFault;
  g.magnitude = std::round(seconds / cfg_.nominal_period);
  g.units = "samples";
  g.confidence = 1.0;
  return g;
}

void Monitor::stream_silent(double seconds) {
  if (!have_prev_ || !(seconds > 0.0)) return;
  ++n_gaps_;
  Event g = silence_event(seconds, false);
  g.detail = fmt::format("no data for the last {:.1f} s of monitoring (the connection was lost and not restored): nothing after "
                         "{:.3f} s was watched",
                         seconds, t_prev_);
  if (outage_ >= 0) {
    close_outage(g);
    return;
  }
  events_.push_back(g);
  if (on_event) on_event(g);
}

void Monitor::stream_outage(double seconds) {
  if (!have_prev_ || !(seconds > 0.0) || outage_ >= 0) return;
  Event g = silence_event(seconds, true);
  g.detail = fmt::format("no data for {:.1f} s (the connection is lost or the controller stopped sending): nothing after {:.3f} s is "
                         "watched until the stream is back",
                         seconds, t_prev_);
  events_.push_back(g);
  outage_ = static_cast<int>(events_.size()) - 1;
  if (on_event) on_event(g);
}

void Monitor::close_outage(Event closed) {
  Event& g = events_[static_cast<size_t>(outage_)];
  outage_ = -1;
  closed.t_detected = g.t_detected;  // (the open line's name: its closing line ends it)
  closed.serial = g.serial;          // (and the same alert's number)
  g = std::move(closed);
  if (on_event) on_event(g);
}

void Monitor::close_frozen(int j, bool at_stop, const std::string& why) {
  const size_t J = static_cast<size_t>(j);
  Event& f = events_[static_cast<size_t>(frozen_event_[J])];
  frozen_event_[J] = -1;
  f.open = false;
  f.active_at_stop = at_stop;
  f.t_end = t_prev_;  // the last sample that still held the value
  f.magnitude = std::round((f.t_end - f.t_start) / cfg_.nominal_period) + 1.0;
  f.detail = fmt::format("{} channel of J{} frozen at {:.4f} {} while the joint moves ({:.0f} samples){}", twin_.channel_name(), j + 1,
                         frozen_val_[j], twin_.channel_unit(),
                         f.magnitude, at_stop ? (why.empty() ? std::string("; still frozen when monitoring stopped") : why) : std::string());
  if (on_event) on_event(f);
  // the observer and the residual filter integrated the frozen value for the whole stretch: they
  // restart as after a gap (the release read as a contact on link 1 in stream_and_sensor_faults)
  if (!at_stop) restart_estimators();
}

namespace {

// RTDE robot_mode and safety_mode in words (../shared/reference/rtde-protocol.md)
std::string robot_mode_words(std::int32_t m) {
  static const char* const names[] = {"no controller", "disconnected", "confirm safety", "booting", "power off",
                                      "power on",      "idle (brakes on)", "backdrive",   "running", "updating firmware"};
  return m >= -1 && m <= 8 ? names[m + 1] : fmt::format("robot mode {}", m);
}

std::string safety_mode_words(std::int32_t m) {
  static const char* const names[] = {"normal", "reduced", "protective stop", "recovery", "safeguard stop",
                                      "system emergency stop", "robot emergency stop", "violation", "fault",
                                      "validate joint id", "undefined", "automatic mode safeguard stop",
                                      "three-position enabling stop"};
  return m >= 1 && m <= 13 ? names[m - 1] : fmt::format("safety mode {}", m);
}

// what the controller reports when it does not drive the arm, e.g. "protective stop (safety_mode 3)"
std::string not_driven_words(const RobotSample& s) {
  std::string w;
  if (s.has(kFieldSafetyMode) && s.safety_mode != kSafetyModeNormal && s.safety_mode != kSafetyModeReduced)
    w = fmt::format("{} (safety_mode {})", safety_mode_words(s.safety_mode), s.safety_mode);
  if (s.has(kFieldRobotMode) && s.robot_mode != kRobotModeRunning)
    w += fmt::format("{}{} (robot_mode {})", w.empty() ? "" : ", ", robot_mode_words(s.robot_mode), s.robot_mode);
  return w;
}

}  // namespace

void Monitor::watch_unseen_rest(const RobotSample& s, double t) {
  // (the whole arm commanded to rest, as the thresholds' longest rest was measured: track_rest ran for
  // this sample; on a stream without targets every joint measured still, RestBaseline::arm_rest)
  if (!(rest_by_target_ ? arm_rests_ : RestBaseline::arm_rest(s))) {
    if (rest_unseen_) rest_left_at_ = t_prev_;
    rest_began_at_ = std::numeric_limits<double>::quiet_NaN();
    rest_unseen_ = false;
    if (!rest_donors_.empty() && t - rest_left_at_ < kUnseenRestAfter) {
      donor_levels(s);
      apply_donor_levels();
    }
    return;
  }
  if (std::isnan(rest_began_at_)) rest_began_at_ = t, rest_within_donors_ = true;
  const bool was_unseen = rest_unseen_;
  rest_unseen_ = t - rest_began_at_ > cfg_.longest_rest;
  if (rest_donors_.empty()) {
    if (rest_unseen_ && !rest_unseen_said_)
      add_note(t, fmt::format("the arm rests ({}) longer than in any run the thresholds in use were learned on "
                              "(at most {:.2f} s), and no program set of the twin saw longer rests: an alert at this rest may be false. "
                              "Learn the program's thresholds on runs that rest as it does ('twinwatch thresholds --program')",
                              rest_by_target_ ? "every target velocity 0" : "every joint still", cfg_.longest_rest));
    rest_unseen_said_ |= rest_unseen_;
    return;
  }
  donor_levels(s);
  if (!rest_unseen_) {
    // (still a rest the thresholds saw: are the decisions within the rest-tested levels too?)
    for (int j = 0; j < n_; ++j)
      if (std::abs(rf_dec_[j]) > rest_level_[j] || (obs_on_ && std::abs(obs_dec_[j]) > rest_obs_level_[j])) rest_within_donors_ = false;
    return;
  }
  apply_donor_levels();
  // the rest has just outlasted every rest the thresholds saw: an alert raised as it began (the drives
  // taking up the holding torque as the whole arm stops), whose decisions stayed within the rest-tested
  // levels, was this rest, not a fault
  if (!was_unseen && rest_within_donors_ && open_ >= 0 && background_ < 0 && merge_into_ < 0 && !split_ && !diagnosed_ && !followed_ &&
      events_[static_cast<size_t>(open_)].t_start >= rest_began_at_ - kUnseenRestLead) {
    add_note(t, fmt::format("the alert raised at {:.3f} s came as the arm came to rest, a rest longer than any the thresholds in use were "
                            "learned on (at most {:.2f} s); the levels of the program sets that saw such rests were not exceeded: "
                            "withdrawn, not an event",
                            events_[static_cast<size_t>(open_)].t_detected, cfg_.longest_rest));
    withdraw_open_alert();
  }
}

void Monitor::apply_donor_levels() {
  level_ = level_.cwiseMax(rest_level_);
  if (obs_on_) obs_level_ = obs_level_.cwiseMax(rest_obs_level_);
}

void Monitor::donor_levels(const RobotSample& s) {
  for (int j = 0; j < n_; ++j) {
    rest_level_[j] = 0.0, rest_obs_level_[j] = 0.0;
    for (const ThresholdSet& d : rest_donors_) {
      rest_level_[j] = std::max(rest_level_[j], level_at(cfg_.use_dynamic, d.dynamic, d.static_level, j, s.qd[j], qdd_[j], cfg_.sensitivity[j]));
      if (obs_on_ && d.observer_level.size() == n_)
        rest_obs_level_[j] = std::max(rest_obs_level_[j], level_at(cfg_.use_dynamic, d.observer_dynamic, d.observer_level, j, s.qd[j],
                                                                   qdd_[j], cfg_.sensitivity[j]));
    }
    // (a donor without the observer's thresholds leaves the observer's own)
    if (rest_obs_level_[j] == 0.0) rest_obs_level_[j] = obs_level_[j];
  }
}

void Monitor::pause_watch(const RobotSample& s, double t, double dt) {
  ++n_not_driven_;
  if (paused_) not_driven_s_ += dt;
  const bool changed = !paused_ || s.robot_mode != paused_robot_mode_ || s.safety_mode != paused_safety_mode_;
  if (!paused_) {
    // what was open is closed with what was seen up to the last driven sample, as at the end of a run
    // (a contact that made the controller stop the arm is reported with its own start and size)
    close_open(fmt::format("; still active when the controller stopped driving the arm at {:.3f} s ({})", t, not_driven_words(s)));
    if (std::isfinite(output_check_at_))
      add_note(t, fmt::format("the payload check after the gripper output changed at {:.3f} s is not made: the controller stopped "
                              "driving the arm first",
                              output_changed_at_));
    output_check_at_ = std::numeric_limits<double>::infinity();
    paused_at_ = t;
  }
  if (changed)
    add_note(t, fmt::format("{} {}", paused_ ? "the controller now reports" : "monitoring paused, the controller reports",
                            not_driven_words(s)) +
                    (paused_ ? std::string()
                             : "; the twin predicts a driven arm, so no residual is judged until the arm runs again under normal or "
                               "reduced safety"));
  paused_ = true;
  paused_robot_mode_ = s.robot_mode;
  paused_safety_mode_ = s.safety_mode;
  // the twin's pre-sliding memory follows the encoders (a stop decelerates, a brake release sags);
  // the outputs are not taken: one changed while the arm stood (a part removed by hand) shows at the
  // first driven sample, as an output change there
  twin_.advance(memory_, s.q);
  paused_unpowered_ |= s.has(kFieldRobotMode) && s.robot_mode != kRobotModeRunning;
  // (a stream that starts stopped: its outputs are where the watch starts, not a change at the first
  // driven sample)
  if (!driven_seen_) outputs_prev_ = s.digital_outputs;
  qd_prev_ = s.qd;  // (the velocity difference of a stream without target accelerations goes on)
  t_prev_ = t;
  have_prev_ = true;
}

void Monitor::resume_watch(const RobotSample& s, double t) {
  paused_ = false;
  resume_pending_ = !paused_unpowered_ && !s.has(kFieldTargetQdd) && cfg_.resume_widen > 1.0;
  add_note(t, fmt::format("monitoring resumed: the controller drives the arm again, {:.1f} s after it stopped at {:.3f} s; decisions wait "
                          "for the estimators' start-up{}{}",
                          t - paused_at_, paused_at_,
                          paused_unpowered_ ? ", and a joint at rest until it has moved (its friction state after the power was off is "
                                              "unknown), as after a stream gap"
                                            : "",
                          resume_pending_ ? fmt::format("; the first {:g} s of motion are judged against thresholds {:g} times as wide (the "
                                                        "resumed program's acceleration steps show in the encoders samples late, and "
                                                        "this stream has no targets)",
                                                        kResumeWindow, cfg_.resume_widen)
                                          : ""));
  // the estimators start again; after power off and brakes the twin's pre-sliding memory is unknown
  // for a joint at rest, as after a gap (with power on it followed the encoders through the stop)
  restart_after_gap(s, paused_unpowered_);
  paused_unpowered_ = false;
  if (!s.has(kFieldTargetQdd)) qdd_.setZero();
  trend_.resume_at(t_prev_);  // (the stop is no window time: the trend's energy counts driven samples)
  // nothing seen before the stop is compared with what comes after it: the diagnosis window, the
  // debouncers, the rest baselines, the rest the thresholds never saw
  rest_began_at_ = std::numeric_limits<double>::quiet_NaN();
  rest_unseen_ = false;
  rest_within_donors_ = true;
  rest_left_at_ = -std::numeric_limits<double>::infinity();
  crawl_since_.setConstant(std::numeric_limits<double>::quiet_NaN());
  ring_count_ = 0;
  reset_decisions();
  rest_rf_ = RestBaseline(n_);
  rest_obs_ = RestBaseline(n_);
  on_top_ = false;
  followed_ = false;
  split_.reset();
  splitting_on_top_ = false;
  merge_into_ = -1;
}

void Monitor::close_open(const std::string& why) {
  for (int j = 0; j < n_; ++j)
    if (frozen_event_[static_cast<size_t>(j)] >= 0) close_frozen(j, true, why);
  report_pending_close();
  report_held();
  // (the open alert's first look first: it may hold it too)
  if (open_ >= 0 && !diagnosed_) run_diagnosis(t_prev_);
  report_held_steps();
  if (open_ < 0) return;
  for (const int k : {open_, background_}) {
    if (k < 0) continue;
    Event& e = events_[static_cast<size_t>(k)];
    e.open = false;
    e.active_at_stop = true;
    e.detail += why;  // its end is the run's, not the fault's
    if (on_event) on_event(e);
  }
  open_ = background_ = background_joint_ = -1;
}

void Monitor::finish() {
  if (outage_ >= 0) {  // (an outage no stream_silent closed: what was seen of it)
    Event g = events_[static_cast<size_t>(outage_)];
    g.open = false;
    g.active_at_stop = true;
    g.detail = fmt::format("no data for {:.1f} s when monitoring stopped: nothing after {:.3f} s was watched", g.t_end - g.t_start,
                           g.t_start);
    close_outage(g);
  }
  for (int j = 0; j < n_; ++j)
    if (frozen_event_[static_cast<size_t>(j)] >= 0) close_frozen(j, true);
  // the default set on a run that looks like one of the twin's programs: most alerts would not have
  // been raised by that program's thresholds (a pick-and-place watched with the default set: 26
  // events, 23 of them "contacts" at its stops; docs/validation.md, session 22). Said, not acted on:
  // which program runs is the user's to say
  if (raises_ >= kProgramHintRaises) {
    size_t k = 0;
    for (const auto& [name, set] : cfg_.programs) {
      const int below = below_program_[k++];
      if (below >= kProgramHintShare * raises_)
        add_note(t_prev_, fmt::format("{} of the {} alerts of this run were below the thresholds learned for program '{}' (the default "
                                      "set is in use): if the robot ran that program, monitor with --program {}",
                                      below, raises_, name, name));
    }
  }
  // most alerts raised where their joint crawled through a reversal: the drive's motoring/back-driven
  // step there is what a program run slower than the thresholds' runs shows (docs/validation.md, "A
  // program run slower than its thresholds saw"). Said, not acted on: only the user knows the speed
  if (alerts_raised_ >= kProgramHintRaises && crawl_raises_ >= kProgramHintShare * alerts_raised_)
    add_note(t_prev_, fmt::format("{} of the {} alerts of this run were raised where their joint crawled through a reversal (|qd| below "
                                  "{:.3f} rad/s): if the program ran slower than the healthy runs its thresholds were learned on (the "
                                  "speed slider turned down), learn them on healthy runs at this speed ('twinwatch thresholds --program "
                                  "NAME') and monitor with --program NAME",
                                  crawl_raises_, alerts_raised_, reversal_width_));
  close_open("; still active when monitoring stopped");
}

}  // namespace twinwatch::monitor
