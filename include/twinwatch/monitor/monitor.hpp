#pragma once
/// @file monitor.hpp
/// The condition-monitoring loop: sample -> residual -> decision -> event.
///
/// Per sample (allocation-free): predicted current from the twin, residual r = i - i_hat [A],
/// first-order IIR filter [AGV §4.3], state-dependent threshold [Cao eq. 24] (or the static one
/// [UR3e §4.1]), counter debounce [AGV §5] per joint, stream-gap and frozen-channel checks. When an
/// alert is raised, the residual window around it is handed to the signature diagnosis
/// (diagnosis.hpp) once `diagnosis_delay` seconds of it are available; the event is reported when
/// raised (class pending), when diagnosed, and when cleared.
#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "twinwatch/core/sample.hpp"
#include "twinwatch/device/recording.hpp"
#include "twinwatch/ident/twin_model.hpp"
#include "twinwatch/model/robot_model.hpp"
#include "twinwatch/monitor/acceleration.hpp"
#include "twinwatch/monitor/debounce.hpp"
#include "twinwatch/monitor/diagnosis.hpp"
#include "twinwatch/monitor/event.hpp"
#include "twinwatch/monitor/momentum_observer.hpp"
#include "twinwatch/monitor/threshold.hpp"
#include "twinwatch/signal/fir.hpp"
#include "twinwatch/monitor/trend.hpp"

namespace twinwatch::monitor {

/// The momentum observer's debounce count per joint chosen for one threshold set on healthy
/// validation runs (choose_observer_debounce), with the ratios it was chosen from. Empty: none chosen,
/// the shared count applies. It belongs to the thresholds it was chosen for: learning them again drops it.
/// Stored in the twin file as observer_raise_after_joint and observer_validation_ratio.
struct ObserverDebounceChoice {
  std::vector<int> raise_after;  ///< per joint
  std::vector<VectorJ> ratio;    ///< row d-1: validation ratio per joint at debounce d
  double seconds = 0.0;          ///< validation time [s] (not stored)
};

/// The thresholds learned for one program (the motion the robot repeats): healthy residuals differ
/// between programs (speeds, reversals, payload, warm-up), and one set learned over all of them is
/// as wide as the widest program needs, which costs sensitivity on the quiet ones.
struct ThresholdSet {
  VectorJ static_level;                       ///< [A] per joint (UR3e §4.1)
  std::vector<DynamicThresholdJoint> dynamic; ///< [A] per joint (Cao eq. 24)
  VectorJ observer_level;                              ///< [N·m] momentum observer, static (empty: the default set's)
  std::vector<DynamicThresholdJoint> observer_dynamic; ///< [N·m] momentum observer, Cao eq. 24
  int runs = 0;                               ///< healthy runs it was learned on
  double seconds = 0.0;                       ///< their total duration [s]
  ObserverDebounceChoice observer_choice;     ///< the observer's debounce per joint for these thresholds (empty: the shared count)
  /// the heaviest payload [kg] of the runs it was learned on (NaN: not recorded, a twin from before session 24)
  double payload_max = std::numeric_limits<double>::quiet_NaN();
  /// per joint, the largest reversal load of the runs it was learned on (MonitorConfig::reversal_load_max; empty: not recorded)
  VectorJ reversal_load_max;
  /// per joint, the longest crawl in the runs it was learned on [s] (MonitorConfig::crawl_max; empty: not recorded)
  VectorJ crawl_max;
  /// the longest whole-arm rest in the runs it was learned on [s] (MonitorConfig::longest_rest; NaN: not recorded)
  double longest_rest = std::numeric_limits<double>::quiet_NaN();
};

/// Learned thresholds and user settings; stored in the twin file under "monitor".
struct MonitorConfig {
  VectorJ static_level;                       ///< [A] per joint
  std::vector<DynamicThresholdJoint> dynamic; ///< [A] per joint (Cao eq. 24)
  bool use_dynamic = true;
  double filter_cutoff_hz = 40.0;             ///< first-order IIR on the current residual
  /// consecutive exceedances of the current residual's threshold that raise an alert [AGV §5] (and of
  /// the observer's, unless observer_raise_after or a per-joint choice, observer_choice, is set); 2 since 2026-11-23 (3 cost 2 ms on every
  /// collision; 2 raised no new false alarm in 8 h of long runs and wear ramps: docs/validation.md)
  int raise_after = 2;
  int clear_after = 50;                       ///< consecutive samples below that clear it
  /// consecutive exceedances of the momentum observer's threshold that raise an alert; 0: raise_after.
  /// Each channel counts its own run; a joint's alert is active while either channel's is. 1 raises
  /// contacts one sample earlier (all 288 of the collision sets 0-6 within 20 ms) but leaves healthy
  /// observer peaks within 1.0 % of the threshold instead of 9.1 % (evaluate reports it; docs/validation.md,
  /// "Observer debounce"), so it is not the default
  int observer_raise_after = 0;
  /// The observer channel's debounce per joint, chosen on healthy validation runs that the thresholds
  /// were not learned on (choose_observer_debounce): a joint whose healthy observer peaks stay as far
  /// below its threshold with fewer samples as the worst joint's do with the shared count gets fewer.
  /// Empty: the shared count. observer_raise_after, when set, overrides it.
  ObserverDebounceChoice observer_choice;
  /// The observer channel's debounce count in effect for joint j: observer_raise_after, else the
  /// chosen per-joint count, else raise_after.
  int observer_debounce(int j) const {
    const auto& d = observer_choice.raise_after;
    if (observer_raise_after > 0) return observer_raise_after;
    if (j >= 0 && static_cast<size_t>(j) < d.size()) return d[static_cast<size_t>(j)];
    return raise_after;
  }
  /// The shared count (no per-joint choice): observer_raise_after, else raise_after.
  int observer_debounce() const { return observer_raise_after > 0 ? observer_raise_after : raise_after; }
  VectorJ sensitivity;                        ///< multiplies each joint's threshold (empty: 1), each in (0, kMaxSensitivity]
  static constexpr double kMaxSensitivity = 10.0;
  double nominal_period = 0.002;              ///< [s]
  double gap_factor = 1.5;                    ///< dt > gap_factor * period is a stream gap
  /// The source judged the gaps itself, with its whole stream's jitter (a recording: the reader marks
  /// gap_before by the file's spread, and gap_factor is the file's): the monitor then neither widens
  /// gap_factor by the jitter it sees nor says so. (A Panda log's notes said "only above 1.9 ms" and
  /// "2.1 ms" while its 1.8 ms steps, past the file's 1.7, were reported as gaps: audit of session 55.)
  /// Not stored in the twin: it is the source's.
  bool gaps_judged = false;
  double diagnosis_delay = 0.12;              ///< [s] of residual after the raise used by the diagnosis
  double diagnosis_pre = 0.04;                ///< [s] before the raise
  int frozen_samples = 25;                    ///< identical consecutive currents while moving: stuck channel
  /// Causal filter on each joint's current residual: "iir" (first order at filter_cutoff_hz
  /// [AGV §4.3], the default) or "fir" (the six taps of Cao eq. 29: -3 dB at 42.8 Hz at 500 Hz,
  /// -20 dB above 92 Hz, 2.5-sample delay). Empty: "iir" on every joint; one entry: every joint;
  /// else one entry per joint. Thresholds must be learned with the same filters.
  std::vector<std::string> residual_filter;
  TrendConfig trend;                          ///< slow-wear trend per cycle window (trend.hpp)
  /// Threshold sets per program, by name (e.g. the scenario's trajectory type or the name of the
  /// robot program); static_level/dynamic above are the default set for any other program.
  std::map<std::string, ThresholdSet> programs;
  std::string program;                        ///< the set in use ("": the default); not stored
  /// A payload change diagnosed on the alert's longer look (2.5 s after the raise, when the estimate
  /// has seen the motion both ways) becomes the twin's payload: the mass it had plus the change, at
  /// the same centre of mass, when the twin's torques are physical and its prediction carries a
  /// payload. The alert then clears and monitoring goes on with what the robot now holds: a contact
  /// or the next pick after a dropped part is an event of its own. Before that look, what rises
  /// above what the first look's payload explains (a contact 0.3-2 s after a drop) ends the change
  /// there and is an alert of its own (Monitor::watch_on_top). Off: the twin keeps the declared
  /// payload and the alert stays open while the robot runs without it (before session 21, with
  /// everything after it, e.g. a contact, read as part of it). Not stored.
  /// Also: when the stream carries the payload the controller is told (kFieldPayload: the program's
  /// set_payload, RTDE payload / payload_cog), the twin takes the first declaration that differs from
  /// its payload and every change of it, so a pick the program declares raises no alert, and what
  /// the arm carries is then checked against what the controller believes (a part lost, or a pick
  /// declared with no part in the gripper, is a payload change). Off: the twin keeps its payload.
  bool follow_payload = true;
  /// Where a part the robot picks sits when the twin holds no payload to take its centre of mass
  /// from (none declared, none in the twin; with one, a change is fitted at the payload's centre of
  /// mass, Monitor::payload_com) [m, flange frame]: a payload change is fitted at it and,
  /// followed, predicted with a point mass there. Default 4 cm out along the flange axis. A part that
  /// sits farther out and is followed at the default leaves a model error at the wrist joints: on the
  /// virtual UR3e, 0.6 kg picked at 0.15 m raised 3 false alarms in the 5 s after the follow, 1.0 kg
  /// at 0.15 m was followed and dropped again (docs/validation.md, "Where a part sits", session 52).
  /// In the twin file: "part_com_m" (written when not the default); monitor --part-com.
  static constexpr double kDefaultPartComZ = 0.04;
  static Eigen::Vector3d default_part_com() { return {0.0, 0.0, kDefaultPartComZ}; }
  /// A point a part can sit at: finite and within model::kPayloadComMax of the flange (the twin
  /// file's reader, validate() and the CLI options each say so in their own words)
  static bool part_com_in_reach(const Eigen::Vector3d& c) { return c.allFinite() && c.norm() <= model::kPayloadComMax; }
  Eigen::Vector3d part_com = default_part_com();
  /// Where the drive's direction is in doubt (ident::TwinModel::drive_in_doubt), read the current on
  /// the nearer of its two levels and the observer's torque on the level nearer the twin's
  /// (resolve_drive_doubt, measured_drive_torque). Off: the blended prediction and, without targets,
  /// the observer's hard switch, as before session 32. For comparisons; not stored in the twin file.
  bool drive_doubt = true;
  /// On a stream without the controller's targets, the first Monitor::kResumeWindow of motion after
  /// the controller drives the arm again after a stop with the power on (a protective or safeguard
  /// stop) is judged against both thresholds times this factor. The resumed program's ramp steps the
  /// acceleration, which the encoders show samples late (no causal estimate from positions sees it
  /// sooner: session 35), and a protective stop's resume raised a false contact on 6 of the target-less
  /// stop sets' 144 runs. 1: off. For comparisons; not stored in the twin file.
  double resume_widen = 2.0;
  /// second detector: generalized-momentum observer (momentum_observer.hpp) with bandwidth
  /// observer_gain [1/s]; on when observer_level is set (learned with the current thresholds)
  double observer_gain = 150.0;
  /// the observer's threshold raises alerts too (else the observer only feeds the contact isolation).
  /// On by default since its residual is temperature-compensated like the current residual and its
  /// dynamic threshold hugs the misfit (threshold.hpp): 3 N·m contacts in 20 ms, 0 false alarms in
  /// the 2.07 h of nominal long runs (docs/validation.md)
  bool observer_alerts = true;
  VectorJ observer_level;                              ///< [N·m] static threshold per joint (empty: off)
  std::vector<DynamicThresholdJoint> observer_dynamic; ///< [N·m] Cao eq. 24 on the observer output
  /// The heaviest payload [kg] of the healthy runs the thresholds in use were learned on (NaN: not
  /// recorded, a twin from before session 24). The twin's model error grows with the payload, and
  /// thresholds learned light do not cover a heavy one (on the virtual UR3e, thresholds learned at
  /// 0-0.5 kg: no false alarm at 1.0 kg, 4 a minute at 1.5 and 2 kg, before reversal_load_max):
  /// the monitor says so when its payload is more than Monitor::payload_envelope_margin heavier,
  /// and marks the alerts raised then.
  double payload_max = std::numeric_limits<double>::quiet_NaN();
  /// Per joint, the largest reversal load (threshold.hpp, reversal_load: the twin's |torque| at a
  /// reversal, weighted by how much the drive's direction is in doubt) of the healthy runs the
  /// thresholds in use were learned on [the twin's torque units: N·m when its gains are known].
  /// Where a joint reverses under more, the monitor widens both of its thresholds by the step the
  /// drive's motoring/back-driven switch can put into each residual for the excess
  /// (Monitor::widen_for_load: |1 - c_gen| times it in the current, max(|1 - c_gen|, |1/c_gen - 1|)
  /// in the observer), low-passed like the residual: that step is larger there than any the
  /// thresholds saw. A joint standing still counts as reversing (its direction stays in doubt). Measured on the virtual UR3e with thresholds
  /// learned at 0-0.5 kg: a 1.5-2 kg payload raised 4 false alarms a minute at J4's loaded
  /// reversals before, none with it (docs/validation.md, "Thresholds that grow with the load").
  /// Empty: not recorded (a twin from before session 25): no widening.
  VectorJ reversal_load_max;
  /// Per joint, the longest stretch in which the joint crawled, its direction in doubt (|qd| below the
  /// reversal width, threshold.hpp), in the healthy runs the thresholds in use were learned on [s]
  /// (empty: not recorded, a twin from before session 30). A joint that crawls longer than that (a
  /// program run slower, a slow reversal under gravity) shows the drive's motoring/back-driven step for
  /// longer than any the thresholds saw: on the virtual UR3e a figure-eight at a half to a fifth of the
  /// speed its thresholds were learned at raised 2-3 false contacts a run at J2's slow reversals. Beyond
  /// it the joint's thresholds widen by the whole step (Monitor::widen_for_load with no learned load).
  VectorJ crawl_max;
  /// The longest whole-arm rest (RestBaseline::arm_rest: every |target qd| < RestBaseline::kTargetRest,
  /// on runs without target velocities every |qd| < kMeasuredRest; after each run's start-up) in the
  /// healthy runs the thresholds in use were learned on [s] (NaN: not recorded, a twin from before
  /// session 30, or, before session 33, runs without target velocities). Thresholds learned on a program that
  /// never rests (the figure-eight) have not seen what the drives do when they hold the arm still: on
  /// the virtual UR3e a paused figure-eight raised a false contact at every pause. A rest that lasts
  /// longer than this is judged, from then until 0.5 s after the arm moves on, with each joint's
  /// threshold no tighter than those of the twin's program sets that saw rests of kMinDonorRest or
  /// more, and longer (Monitor::rest_donors_); with none, the monitor says so once.
  double longest_rest = std::numeric_limits<double>::quiet_NaN();

  /// Makes the set learned for `name` the active one (static_level, dynamic). Empty: keep the
  /// default. Throws InvalidArgument naming the known programs when there is no such set.
  void select_program(const std::string& name);
  void validate(int n_dof) const;
  /// The twin file's monitor block (JSON text).
  std::string to_json() const;
  /// Reads a monitor block written by to_json(). Every field to_json() always writes is required,
  /// each value is checked for its type and range (thresholds > 0, Cao eq. 26 coefficients >= 0,
  /// debounce counts 1 to 1000, filter_cutoff_hz up to 500 Hz), and a key the block does not have is
  /// an error. `origin` names the file, `n_dof` the joints (0: as many as static_level_A has).
  /// Throws ParseError(origin, 0, "monitor.<path>", "expected X, got Y").
  static MonitorConfig from_json(const std::string& text, const std::string& origin, int n_dof = 0);
  /// from_json of a twin's monitor block (TwinModel::monitor_json) for its joints, naming the file
  /// the twin was read from. Throws InvalidArgument when the twin has no monitor block.
  static MonitorConfig from_twin(const ident::TwinModel& twin);
};

/// A joint held at rest by its controller (target velocity ~0) keeps whatever current the static
/// friction leaves it: after a stop, or after a contact pushed it and friction now holds it off its
/// target (measured: a 6 N·m contact on a resting UR3e wrist left J5 1.2 mrad off target and 0.03 A
/// held for the rest of the run, re-raised as new "contacts" every few hundred ms). Once a joint has
/// rested kSettle samples, the residual's mean over those samples becomes its baseline and the
/// decision sees the residual minus it; the baseline then follows the residual slowly
/// (kTrackSamples: the controller's integrator ramps the held current until breakaway) and is
/// dropped when the joint moves. A step while resting (a dropped payload, a contact) still shows
/// against it. Learning and
/// monitor apply it alike. Allocation-free after construction.
class RestBaseline {
 public:
  static constexpr int kSettle = 50;                 ///< samples at rest before the baseline is set (0.1 s at 500 Hz)
  static constexpr double kTargetRest = 1e-3;        ///< |target qd| below this: commanded to rest [rad/s]
  /// The whole arm is commanded to rest: the sample has target velocities, every one below kTargetRest.
  static bool commanded_rest(const RobotSample& s) {
    return s.has(kFieldTargetQd) && s.target_qd.size() == s.qd.size() && s.target_qd.cwiseAbs().maxCoeff() < kTargetRest;
  }
  static constexpr double kMeasuredRest = 0.01;      ///< |qd| below this: not moving (encoder flicker 0.003 rad/s)
  /// The whole arm rests: commanded to (commanded_rest) where the stream has target velocities, else
  /// every measured velocity below kMeasuredRest (a log without the controller's targets)
  static bool arm_rest(const RobotSample& s) {
    if (s.has(kFieldTargetQd)) return commanded_rest(s);
    return s.qd.size() > 0 && s.qd.cwiseAbs().maxCoeff() < kMeasuredRest;
  }
  static constexpr double kTrackSamples = 250.0;     ///< after settling, the baseline follows with this time constant [samples] (0.5 s at 500 Hz)
  explicit RestBaseline(int n = 0);
  /// Returns value minus the baseline of each settled joint (value unchanged elsewhere).
  /// Joints without a streamed target velocity are never at rest here.
  void apply(const RobotSample& s, VectorJ& value);
  /// Whether joint j's baseline is set (it has rested kSettle samples up to the last apply).
  bool settled(int j) const { return run_[static_cast<size_t>(j)] >= kSettle; }

 private:
  std::vector<int> run_;
  VectorJ sum_, base_;
};

struct LearnOptions {
  double k_sigma = 3.0;   ///< UR3e §4.1
  DynamicThresholdOptions dynamic;
};

/// A healthy run for threshold learning.
struct HealthyRun {
  const device::Recording* recording = nullptr;
  model::RigidBodyInertia payload;
  /// instead of `recording`: a run read as often as the learner asks and not held (learn_thresholds
  /// reads it twice, choose_observer_debounce once)
  const device::SampleSource* samples = nullptr;
};

/// Learns static and dynamic thresholds from healthy runs with the twin's residuals (temperature-
/// compensated with settings.trend.temperature_slope when it is set, as the monitor does).
/// The static level is max(max-MAE + k sigma [UR3e], 1.1 x max healthy |r| [Cao]) so that the
/// training data itself never trips it.
MonitorConfig learn_thresholds(const ident::TwinModel& twin, const std::vector<HealthyRun>& runs,
                               const MonitorConfig& settings = {}, const LearnOptions& options = {});

/// choose_observer_debounce: a validation peak at fewer samples up to this share of the threshold is
/// never too close. (Without it a twin whose worst joint improved slowed every other one: with the
/// drive's direction read on the target (session 31) J4's shared-count peak fell from 0.92 to 0.69,
/// and J2, J3, J5 went from one sample to two, though at one they peaked at 0.71-0.78: a 3 N·m
/// contact of held-out set 8 was then found in 21 ms. The long runs' largest observer peak sits about
/// as high as the 1200 s validation runs' worst joint's.)
inline constexpr double kObserverRatioFloor = 0.8;

/// The observer's debounce per joint, chosen on healthy validation runs that the thresholds in
/// `config` (its selected program's, or the default set) were not learned on. The monitor runs each
/// validation run for every debounce d = 1..D (D: the shared count, MonitorConfig::observer_debounce())
/// and keeps each joint's healthy margin: the largest ratio |observer| / threshold that a whole run
/// of d decisions exceeded (Monitor::track_margin). Joint j gets the smallest d whose ratio is below 1
/// and no larger than the worst joint's ratio at D, or than kObserverRatioFloor: a joint debounced less
/// never comes closer to its threshold than the shared count already lets the worst joint come, and one
/// that stays below 0.8 of it is never too close. Why validation runs and not a
/// cross-validation of the (short) threshold runs: the largest healthy peak grows with the time
/// watched, and blocks of a minute did not rank the joints the way hours of operation do (measured:
/// docs/validation.md, "Observer debounce per joint"). Throws InvalidArgument without validation runs,
/// with the observer off or not raising alerts, or with observer_raise_after set (it overrides any choice).
ObserverDebounceChoice choose_observer_debounce(const ident::TwinModel& twin, const MonitorConfig& config,
                                                const std::vector<HealthyRun>& validation);

/// Throws InvalidArgument "WHAT: program name 'a b' has the character ' '; ..." unless `name` is
/// a program name a threshold set can have (letters, digits, '_', '-', '.').
void check_program_name(const std::string& name, const std::string& what = "threshold set");

/// Learns the thresholds of one program on its healthy runs and stores them in config.programs
/// under `name` (replacing an earlier set of that name); config's other settings are used as is.
/// Throws InvalidArgument for an empty name or one with characters other than [A-Za-z0-9_.-].
void learn_program_thresholds(MonitorConfig& config, const std::string& name, const ident::TwinModel& twin,
                              const std::vector<HealthyRun>& runs, const LearnOptions& options = {});

class Monitor {
 public:
  Monitor(const ident::TwinModel& twin, MonitorConfig config);

  /// Processes one sample. Calls on_event for every raise and diagnosis (open events) and once
  /// for each event's end (closed). An alert that falls back is closed only after a merge gap
  /// (1 s) without a new raise, since a raise within it continues the same event; collisions,
  /// which are never continued, and stream faults close at once.
  void push(const RobotSample& s);
  /// Closes an open alert at the end of a run.
  void finish();
  /// The stream went silent for its last `seconds` (a live connection lost and not restored before
  /// monitoring ended): a StreamFault event from the last sample over that time, so that the event
  /// history does not read as watched. Call before finish(); nothing before the first sample.
  void stream_silent(double seconds);
  /// Live, while it lasts: no sample for `seconds` since the last one (an outage the source is
  /// still reconnecting through). The first call of an outage raises an open StreamFault from the
  /// last sample (t_detected = its time + `seconds`), so that a consumer of open events sees it
  /// while it lasts; later calls change nothing. It is closed, with the same t_detected, by the
  /// gap event when samples return, by stream_silent at the end, or by finish(). Nothing before
  /// the first sample.
  void stream_outage(double seconds);

  std::function<void(const Event&)> on_event;
  /// An alert announced open (on_event) that ends without an event of its own: withdrawn (an alert
  /// raised as a pause began, a pick the program declares late) or merged into another alert (a
  /// raise that was the earlier fault dipping below its threshold). The alert as last announced,
  /// with open false and withdrawn true; nothing is called for it on on_event after this. A consumer
  /// of open alerts (a dashboard, --events-open) ends it here.
  std::function<void(const Event&)> on_withdraw;
  /// What the monitor has to say that is no event (e.g. a friction trend it cannot tell from
  /// cooling): controller time [s] and the text. Also kept in notes().
  std::function<void(double, const std::string&)> on_note;
  const std::vector<std::string>& notes() const { return notes_; }

  /// Outputs of the last sample.
  const VectorJ& predicted_current() const { return i_hat_; }
  const VectorJ& residual() const { return r_; }
  const VectorJ& filtered_residual() const { return rf_; }
  const VectorJ& level() const { return level_; }
  /// Momentum-observer estimate of the external joint torque [N·m] and its threshold (zero when the observer is off;
  /// evaluated even when observer_alerts is off).
  const VectorJ& observer_residual() const { return obs_.residual(); }
  const VectorJ& observer_threshold() const { return obs_level_; }
  /// The same two in N·m through the trusted drive gains (what the diagnosis reads; the twin's own
  /// units differ on a joint whose gain the recordings did not fix).
  VectorJ observer_torque() const { return obs_.residual().cwiseProduct(obs_to_nm_); }
  VectorJ observer_torque_threshold() const { return obs_level_.cwiseProduct(obs_to_nm_); }
  double total_current() const { return i_total_; }
  /// Turns on the false-alarm margin (off by default: it costs a little per sample). From then on each
  /// joint and channel keeps the largest ratio |residual| / threshold that its debounce's raise_after
  /// consecutive decisions all exceeded (DebouncedPeak): on a healthy run, the sensitivity below which
  /// that channel would first raise. Call before the first sample.
  void track_margin(bool on = true);
  /// Those peaks per joint for the current residual and the momentum observer (zero when off).
  VectorJ margin_current() const;
  VectorJ margin_observer() const;
  /// All events so far (closed and open), less those forget_events_before() let go.
  const std::vector<Event>& events() const { return events_; }
  /// Live monitoring, where every closed event has been handed to on_event (stored, written): lets
  /// go of the closed events that ended before `t` and that nothing the monitor still watches refers
  /// to, oldest first, so that a monitor running for months holds a bounded list (0.6 kB an event;
  /// soak audit, session 39). The monitor's own look-backs span seconds; callers keep minutes.
  /// Returns how many it let go; events_forgotten() counts them all.
  long forget_events_before(double t);
  long events_forgotten() const { return n_forgotten_; }
  /// Every event so far: those kept (events()) and those let go (events_forgotten()).
  long events_seen() const { return static_cast<long>(events_.size()) + n_forgotten_; }
  /// Samples processed; gaps in the controller timestamp; samples skipped because their timestamp
  /// did not advance (a resend); samples skipped because a position, velocity or current was not
  /// finite (each run of them is one SensorFault event).
  long samples() const { return n_samples_; }
  long gaps() const { return n_gaps_; }
  long repeated() const { return n_repeated_; }
  long invalid() const { return n_invalid_; }
  /// Samples on which decisions were made: driven, after the estimators' start-up (0 for a
  /// recording shorter than it: nothing was judged, which is no clean bill of health).
  long judged() const { return n_judged_; }
  /// How long the first motion after a powered resume is judged wider on a stream without targets
  /// (MonitorConfig::resume_widen) [s]: the stop sets' resume ramps (0.15-0.6 s) step the
  /// acceleration at their start and their end
  static constexpr double kResumeWindow = 0.3;
  /// Samples in which the controller did not drive the arm (RobotSample::driven() false: power off,
  /// brakes on, a protective or emergency stop, ...): not judged, and their total time [s].
  long not_driven() const { return n_not_driven_; }
  double not_driven_seconds() const { return not_driven_s_; }
  /// The slow-wear trend detector (per-window friction, residual energy, I_total history).
  const TrendDetector& trend() const { return trend_; }
  /// The twin with the monitor's payload (set it when the program changes the payload; the monitor
  /// changes it itself when it follows a diagnosed payload change, MonitorConfig::follow_payload).
  ident::TwinModel& twin() { return twin_; }
  /// The payload mass [kg] the controller declared last (the stream's kFieldPayload); NaN when the
  /// stream carried no declaration.
  double declared_payload() const { return have_declared_ ? declared_mass_ : std::numeric_limits<double>::quiet_NaN(); }
  /// Whether the twin took the controller's last declaration (false: it refused it, a note says why,
  /// or the stream carried none).
  bool declaration_taken() const { return have_declared_ && declared_taken_; }
  /// Whether the twin took the last declaration and its payload mass is the declared one (within
  /// 0.05 kg); false without a declaration.
  bool carries_declared() const;
  /// A program set whose runs held the arm still this long [s] judges the rests longer than the
  /// thresholds in use saw (MonitorConfig::longest_rest).
  static constexpr double kMinDonorRest = 0.25;
  /// A payload this much heavier [kg] than MonitorConfig::payload_max is beyond what the thresholds
  /// were learned on. Measured with thresholds learned up to 0.5 kg: 1.0 kg raised no false alarm
  /// and 1.5 kg did (4 a minute, session 24).
  static constexpr double kPayloadEnvelopeMargin = 0.5;
  /// The same for thresholds that widen at reversals under more load than they saw
  /// (MonitorConfig::reversal_load_max set): with thresholds learned up to 0.5 kg, 1.5-3 kg raised
  /// 1 false alarm in 0.67 h of held-out runs of four programs (docs/validation.md, "Thresholds that
  /// grow with the load"); 1.5 leaves 2.5 kg, where the design set's healthy peaks came within 6 %
  /// of the thresholds, to the note.
  static constexpr double kPayloadEnvelopeMarginWidened = 1.5;
  /// The margin that applies to `config`: kPayloadEnvelopeMarginWidened when its thresholds widen
  /// with the load, else kPayloadEnvelopeMargin.
  static double payload_envelope_margin(const MonitorConfig& config) {
    return config.reversal_load_max.size() != 0 ? kPayloadEnvelopeMarginWidened : kPayloadEnvelopeMargin;
  }
  /// Whether the twin's payload is now beyond what the thresholds were learned on (payload_max
  /// + payload_envelope_margin); false when payload_max is not recorded.
  bool payload_beyond_thresholds() const { return payload_beyond_; }
  const ident::TwinModel& twin() const { return twin_; }

 private:
  void open_event(int joint, double start, double t, const char* channel);  // channel: what raised it, for the detail
  bool skip_invalid(const RobotSample& s);  // true: the sample is not processed (repeated time, non-finite value)
  // A joint temperature no joint can have (kTemperatureMin..kTemperatureMax: a 0xFFFF/10 overflow, a
  // sensor fault) is not taken: the sample is judged with the joint's last plausible reading, and the
  // first of a run is a sensor-fault event
  bool temperature_implausible(const RobotSample& s);  // (and notes the plausible readings)
  void hold_temperature(RobotSample& held);
  void judge(const RobotSample& s);  // push() of a checked sample
  // (memory_lost: the twin's pre-sliding memory did not follow the motion, as across a gap)
  void restart_after_gap(const RobotSample& s, bool memory_lost = true);
  /// the twin's pre-sliding memory where the motion before `s` was not seen (a gap, or a monitor that
  /// joins a moving arm): a moving joint's is its direction's; a resting joint's is unknown, and it
  /// decides again once it has moved kMemoryRestore pre-sliding distances
  void guess_memory(const RobotSample& s);
  /// observer, residual filter and FIR restart; with `settle`, every decision waits the start-up
  /// samples (without: the observer's alone, as it always does after its start)
  void restart_estimators(bool settle = true);
  /// the diagnosis window: the ring's samples from `from` up to `until` (and, with the observer, the
  /// kContactReference before them), with their residuals through the twin as it is now
  void fill_window(double from, double until);
  /// each sample's residual torque (r_tau, r_drive) through the twin as it is now, with the
  /// acceleration read on the stretch itself (fill_window)
  void recompute_residual(std::vector<DiagnosisSample>& samples);
  /// long_look: the alert's second, longer look (kLongWindow after the raise), the one a payload
  /// change is followed on (follow_payload). The window holds the ring's samples from before the
  /// alert's start up to, not including, `until` [s] (default: all of them)
  void run_diagnosis(double t, bool long_look = false, double until = std::numeric_limits<double>::infinity());
  // a gripper output changed at output_changed_at_ [s]: at output_check_at_ (infinity: none due) the
  // payload fitted on the samples since output_check_from_, the change or, for a change made while
  // the arm rested, the time it moved on (check_payload_after_output)
  void check_payload_after_output(double t);
  double output_changed_at_ = -std::numeric_limits<double>::infinity(), output_check_at_ = std::numeric_limits<double>::infinity(),
         output_check_from_ = 0.0;
  // At a rest static friction holds a part's step (the residual shows it when the arm moves on): an
  // output that changed while the arm rested (output_at_rest_, NaN: none since it last moved) counts
  // as changed when the arm moved on again (output_shown_at_; output_changed_for). arm_rests_: every
  // joint's target velocity below RestBaseline::kTargetRest at the last sample (rest_by_target_;
  // without targets, no joint faster than kOutputCheckMinSpeed), since rest_since_
  bool arm_rests_ = false, rest_by_target_ = false;
  double rest_since_ = 0.0;
  double output_at_rest_ = std::numeric_limits<double>::quiet_NaN();
  double output_shown_at_ = -std::numeric_limits<double>::infinity();
  /// the arm's rest at sample time t, and an output changed (output_changed: at this sample) during a
  /// rest shown when it moves on
  void track_rest(const RobotSample& s, double t, bool output_changed);
  // An alert raised while the arm rests, after a gripper output changed in that rest, may be the
  // part's step, which static friction holds in part: read at rest it is a wrong size (+0.44 kg
  // for a 1 kg pick) or a short "contact" (a 0.6 kg drop: "contact on link 5, 12 N"). It is held
  // (held_steps_), not reported, and, on a stream with target velocities, no alert is raised for the
  // rest of that rest; when the arm moves on, the step's own alert or the payload check after the
  // output sizes the part, and the held alert is settled when that check is over, or when the next
  // output change replaces it (settle_part_steps): dropped when a payload change showed since it
  // began, else reported as it was read. So is, in motion while that check is due, an alert that
  // cleared before its first look and read as a pulse where the part hangs or as a resistance (a
  // light part's step near the thresholds), a pulse in newtons dropped only for a change whose weight
  // it could be
  struct HeldStep {
    Event event;
    bool moving = false;  // held in the check's window after the rest (or after a change in motion)
  };
  std::vector<HeldStep> held_steps_;
  /// why an alert was held, for its event when it is reported
  static std::string held_reason(const HeldStep& h);
  /// the monitor looks for parts itself (follows payload changes, on a twin with known gains that
  /// predicts the payload, on a stream that does not declare it)
  bool finds_parts() const;
  enum class PartStep { None, AtRest, InCheck };
  PartStep part_step_candidate(const Event& e) const;
  /// a contact where the part hangs, begun at a gripper output's change: held when its alert closes
  bool grip_step(const Event& e) const;
  void hold_part_step(double t, PartStep kind);
  /// taken: the change of payload the check took [kg] (NaN: none)
  void settle_part_steps(double t, double taken);
  /// at the end of monitoring: the alerts still held, reported as read
  void report_held_steps();
  /// check_payload_after_output's look: the change of payload it took [kg] (NaN: none)
  double look_for_part(double t);
  /// A gripper output changed at t while the open alert's payload change waits for its longer look:
  /// the change so far is followed on the samples before t and its event ends there, so that what
  /// the new output brings (a part picked right after one was dropped) is an alert of its own
  /// until: the diagnosis window's end, when the next change began before t (watch_on_top).
  /// on_top: split by watch_on_top. The residual filter and the observer are then not restarted:
  /// follow_payload shifted them by what the followed payload changes in the twin's prediction
  /// (rebase_on), so they keep what is new on top of the payload, a contact's onset. The split is tentative until the
  /// next alert's diagnosis (unsplit_payload_change); with no alert within the merge gap it stands
  /// (the followed payload explains the residual). When the samples before the rise give no payload
  /// the twin can follow, the event goes back to what its first look said, without a note.
  void split_payload_change(double t, const char* where, double until = std::numeric_limits<double>::quiet_NaN(),
                            bool on_top = false);
  /// A payload change diagnosed on the alert's first look (or, with a gripper output changed, a
  /// contact on the last link, which a small part dropped reads as in the short window, with the
  /// first look's payload hypothesis) is a payload the twin could carry (followed_mass, payload_of): from then
  /// to its longer look, the current residual less what that payload
  /// explains is watched on the moving joints (watch_on_top). What rises above the thresholds there
  /// is something new on top of the payload change (a contact soon after a part was dropped or
  /// picked): the change is split off before it began (split_payload_change) and the new residual
  /// raises an alert of its own. Before, everything within the 2.5 s to the longer look was part of
  /// the payload event (a contact there was never reported).
  void start_on_top(const Event& e, double change);  // change: the first look's payload change [kg]
  /// The alert raised after a tentative split (split_payload_change from watch_on_top) was not a
  /// contact and merges back into the payload change `into`: the change is restored as its first
  /// look said, and the twin to the payload it had. Nothing when `into` was no split.
  void unsplit_payload_change(int into, double t);
  /// The twin now predicts otherwise than `before` (another payload): the residual filter, the
  /// observer, this sample's decisions and the observer's estimates in the ring are shifted by the
  /// difference, as if the twin had predicted so all along.
  void rebase_on(const ident::TwinModel& before, double from);  // from: the first ring sample [s] shifted
  void watch_on_top(const RobotSample& s, double t, bool settled, bool observer_decides);
  /// The mass [kg] the twin carries after a diagnosed change of `change` kg: the mass it had plus
  /// the change; within the estimate's error of zero, none; within it of the declared mass, the
  /// declared one (as_declared). NaN when that is clearly negative (more than it carried).
  double followed_mass(double change, bool& as_declared) const;
  /// That mass as a payload: at the declaration's centre of mass (as_declared), else at the twin's
  /// or, with none, at MonitorConfig::part_com, the twin's shape scaled to the mass.
  model::RigidBodyInertia payload_of(double mass, bool as_declared) const;
  /// The evidence that an alert's change is the payload: a gripper output changed from
  /// kPayloadIoLookback before it began, or the payload signature explains kPayloadFollowExplained of it.
  bool payload_evidence(const Event& e) const;
  /// a gripper output changed from kPayloadIoLookback before e began until now
  bool output_changed_for(const Event& e) const;
  /// the centre of mass a payload change is fitted and followed at: the twin's payload's or, with
  /// none, MonitorConfig::part_com [m, flange frame]; and in the last link's frame
  Eigen::Vector3d payload_com() const;
  Eigen::Vector3d payload_com_in_link() const;
  /// scratch_twin_ made a copy of the twin as it is now (kept between calls: its allocations are reused)
  ident::TwinModel& scratch_twin();
  /// the open alert is a payload change diagnosed once and waiting for its longer look, at least
  /// kPayloadSplitAfter old: a gripper output's change or a new declaration ends it (split_payload_change)
  bool payload_change_waits(double t) const;
  /// The twin takes the payload change event e diagnosed (cfg_.follow_payload); says so in e's
  /// detail and a note. Nothing when the change cannot be a payload the twin predicts.
  void follow_payload(Event& e, double t, double rebase_from);  // rebase_from: rebase_on's first ring sample [s]
  VectorJ peaks(const std::vector<DebouncedPeak>& channel) const;  // DebouncedPeak::peak per joint (0 when off)
  double torque_gain(int j) const;   // current -> torque per joint (tau_gain_, set once)

  ident::TwinModel twin_;
  /// A new event, its residual in the twin's channel units (every event the monitor raises starts here)
  Event new_event() {
    Event e;
    e.serial = ++serials_;
    e.peak_residual_units = twin_.channel_unit();
    return e;
  }
  std::uint64_t serials_ = 0;  // (new_event's count: Event::serial)
  MonitorConfig cfg_;
  int n_;
  double alpha_ = 1.0;  // IIR coefficient
  std::vector<Debouncer> deb_, deb_obs_;  // per joint: current residual, observer
  std::vector<char> joint_active_;        // either channel of the joint active (last sample)
  std::vector<DebouncedPeak> margin_cur_, margin_obs_;  // per joint, when track_margin (else empty)
  TwinMomentumObserver obs_;
  bool obs_on_ = false;
  int obs_samples_ = 0;  // observer updates so far (alerts wait for its start-up)
  VectorJ obs_level_, obs_to_nm_;
  VectorJ static_friction_;  ///< [N·m] per joint, what friction holds at rest (DiagnosisOptions::static_friction)
  VectorJ obs_warm_;  // the observer's temperature compensation of the sample [N·m] (scratch)
  VectorJ obs_ref_;   // the twin's torque at the prediction's acceleration, with obs_warm_ (scratch)
  VectorJ tau_obs_;   // the twin's torque at the observer's acceleration (scratch)
  RestBaseline rest_rf_, rest_obs_;  // held-at-rest baselines of the two residuals (decision only)
  VectorJ rf_dec_, obs_dec_;         // the residuals the decision compares with the thresholds
  VectorJ i_hat_, tau_hat_, r_, rf_, level_, qdd_, qd_prev_, frozen_val_;
  std::optional<WindowedAcceleration> windowed_;  // the twin's windowed acceleration (a stream without target_qdd)
  ident::FrictionMemory memory_;  // the twin's pre-sliding state on this stream
  std::vector<int> frozen_run_;
  std::vector<int> frozen_event_;  // per joint: index of its open frozen-channel event (-1: none)
  VectorJ frozen_since_;           // per joint: when the channel took its present value
  void close_frozen(int j, bool at_stop = false, const std::string& why = "");
  double i_total_ = 0.0, t_prev_ = 0.0;
  bool have_prev_ = false, filter_started_ = false;
  long n_samples_ = 0, n_gaps_ = 0, n_repeated_ = 0, n_invalid_ = 0;
  long n_forgotten_ = 0;  // events let go by forget_events_before
  bool invalid_run_ = false;  // the last sample was skipped as non-finite (one event per run)
  VectorJ temperature_ok_;    // per joint: the last plausible temperature reading (NaN: none yet)
  std::vector<char> temperature_run_;  // per joint: its reading is implausible (one event per run)
  // the controller stopped driving the arm (RobotSample::driven): nothing is judged until it drives
  // it again (pause_watch, resume_watch)
  bool paused_ = false, paused_unpowered_ = false;  // (unpowered: robot_mode not RUNNING at a sample of the stop)
  bool driven_seen_ = false;  // a driven sample has been pushed
  int alerts_raised_ = 0, crawl_raises_ = 0;  // alerts raised, and those where their joint crawled (finish's hint)
  double paused_at_ = 0.0, not_driven_s_ = 0.0;
  // a powered resume on a stream without targets: the first motion's window is judged wider
  // (MonitorConfig::resume_widen) until resume_until_ [s]; pending until the arm moves
  bool resume_pending_ = false;
  double resume_until_ = -std::numeric_limits<double>::infinity();
  long n_not_driven_ = 0;
  long n_judged_ = 0;  // samples decided on (after the estimators' start-up)
  std::int32_t paused_robot_mode_ = kRobotModeRunning, paused_safety_mode_ = kSafetyModeNormal;
  bool restart_pending_ = false;  // samples were skipped: the next one restarts the estimators
  long settle_until_ = 0;     // decisions start after this many samples (kObserverSettle; again after a gap)
  std::vector<double> memory_unsure_;  // per joint: [rad] it must move after a gap before it decides again (0: decides)
  VectorJ memory_from_;                // where it stood after the gap
  // ring buffer of recent samples for the diagnosis
  std::vector<DiagnosisSample> ring_;
  size_t ring_head_ = 0, ring_count_ = 0;
  /// the k-th oldest sample the ring holds (k < ring_count_)
  const DiagnosisSample& ring_at(size_t k) const { return ring_[(ring_head_ + ring_.size() - ring_count_ + k) % ring_.size()]; }
  DiagnosisSample& ring_slot(size_t k) { return ring_[(ring_head_ + ring_.size() - ring_count_ + k) % ring_.size()]; }
  const DiagnosisSample& ring_newest() const { return ring_at(ring_count_ - 1); }
  std::vector<Event> events_;
  std::vector<std::string> notes_;
  int open_ = -1;             // index of the open event
  // a closed alert (not a collision) whose closing is reported only once no raise within
  // kMergeGap continues it: a persistent fault that dips at reversals is one event, reported once
  int pending_close_ = -1;
  void report_pending_close();
  bool diagnosed_ = false, rediagnosed_ = false;
  // the open alert's payload change is followed (follow_payload): since followed_at_ [s] the twin
  // carries it instead of followed_from_; reported when it clears (or held for a late declaration:
  // may_be_declared_late), undone if it does not
  bool followed_ = false;
  double followed_at_ = 0.0;
  std::uint64_t outputs_prev_ = 0;  // the last sample's digital outputs (split_payload_change)
  // with the default set in use and sets learned for programs: the alerts raised, and per program
  // (cfg_.programs' order) how many of them its thresholds would not have raised at that sample. A
  // program that would have raised few of them is probably the one the robot runs: finish() says so
  int raises_ = 0;
  std::vector<int> below_program_;
  void check_program_sets();
  model::RigidBodyInertia followed_from_;
  void undo_follow(double t);
  // a copy of the twin (scratch_twin): while watch_on_top runs, with the payload the first look
  // diagnosed; at a follow, an undo or an unsplit, the twin as it was (rebase_on)
  std::optional<ident::TwinModel> scratch_twin_;
  VectorJ no_temp_;  // NaN per joint: the twin's reference temperature
  // watch_on_top: the alert it watches (its start), what that payload changes in the predicted
  // current (filtered as the residual is), and per joint the run of samples above the threshold and
  // where it began; on_top_slow_alpha_: the coefficient of the rise's mean (kOnTopRise);
  // on_top_change_: the payload change watched [kg]
  bool on_top_ = false, on_top_fresh_ = false;
  double on_top_start_ = 0.0, on_top_slow_alpha_ = 0.0, on_top_change_ = 0.0;
  VectorJ on_top_i_, on_top_tau_, on_top_df_, on_top_dobs_, on_top_from_, on_top_from_obs_, on_top_slow_, on_top_slow_obs_, on_top_moving_since_;
  std::vector<int> on_top_run_, on_top_run_obs_;
  std::vector<char> on_top_rested_;  // per joint: its held-at-rest baseline was set (kOnTopMoving)
  // a tentative split: the payload change's event as its first look said, and the payload the twin
  // had before the split followed it (unsplit_payload_change)
  std::optional<Event> split_;
  model::RigidBodyInertia split_from_;
  // a followed payload change whose report waits for a late declaration (may_be_declared_late),
  // until held_until_ [s]; held_from_: the payload the twin had before it followed the change
  int held_ = -1;
  double held_until_ = 0.0;
  model::RigidBodyInertia held_from_;
  double rebased_from_ = 0.0;  // the ring's samples from here on were shifted at the last follow (rebase_on)
  // a split on a rise (split_payload_change's on_top) is being diagnosed: follow_payload says nothing
  // when it does not follow, and run_diagnosis takes the watched change when the window agrees
  bool splitting_on_top_ = false;
  // the payload the controller declares (RobotSample::payload, kFieldPayload): the program's
  // set_payload. The twin takes each new declaration (take_declared_payload); declared_at_ [s] is when
  // it last did, so that an alert raised before it is not followed on top of it
  bool have_declared_ = false;
  double declared_mass_ = 0.0, declared_cog_[3] = {0.0, 0.0, 0.0};
  double declared_at_ = -std::numeric_limits<double>::infinity();
  bool declared_refused_ = false;  // a declaration the twin cannot take was said once
  bool declared_taken_ = false;    // the twin took the last declaration (else it was refused)
  bool declaring_ = false;         // a declaration ends a waiting payload change (follow_payload words it)
  double declared_change_ = 0.0;   // the change of the declared mass at the last declaration the twin took [kg]
  // the declaration's timing against the grip (kDeclarationLag): a payload change raised between the
  // two is the declared pick and is withdrawn
  bool declared_pick_candidate(const Event& e, double declared_at, double change) const;
  bool declared_pick_explains(double t) const;
  bool at_last_link(const Event& e) const;  // a contact named on the last link, or that lists it as also possible
  /// A followed payload change that closed at t may be a pick the program has not declared yet (a
  /// pick at a rest clears and is followed within 0.5-0.9 s of the grip; a program declared its part
  /// 0.7-0.95 s after the grip, which then came after a reported event, session 24): its report is
  /// held until kDeclarationLag after it began (hold), when a declaration of that part withdraws it
  /// (take_declared_payload). Only on a stream that declares its payload, after a gripper output
  /// changed, with no declaration since the change began.
  bool may_be_declared_late(const Event& e, double t) const;
  void hold(int index);
  /// The held change is an event after all: its time passed, a new alert is raised (which keeps
  /// the events in order, but a transient alert before a late declaration then leaves the pick
  /// reported), or the run ends.
  void report_held();
  bool gripped_before(const Event& e, double declared_at) const;
  bool late_declared_pick(const Event& e, double t, double change) const;
  void reset_decisions();  // every joint's debouncers start over
  bool outputs_changed_within(double from, double to) const;
  // the open alert goes without an event of its own (announce: on_withdraw; false: held, still open to
  // its consumers until settle_part_steps reports or withdraws it)
  void withdraw_open_alert(bool announce = true);
  void drop_event(int index);  // erases events_[index], keeping the indices into events_ right
  // the indices kept into events_ (-1: none), frozen_event_'s aside
  std::array<int*, 6> event_indices() { return {&open_, &pending_close_, &merge_into_, &background_, &held_, &outage_}; }
  int outage_ = -1;  // the open StreamFault of an outage that still lasts (stream_outage)
  void close_outage(Event closed);  // the gap or silence event takes the outage's place and t_detected
  Event silence_event(double seconds, bool open);  // a stream fault: no data for seconds after the last sample
  // the twin's payload against the heaviest the thresholds were learned on (payload_max): checked
  // at the first sample and whenever the payload changes, said in a note each time it goes beyond
  bool payload_beyond_ = false;
  void check_payload_envelope(double t);
  void take_declared_payload(const RobotSample& s);
  // the sample declares what was declared last (compared per sample in push)
  bool same_declaration(const RobotSample& s) const {
    return have_declared_ && s.payload == declared_mass_ && s.payload_cog[0] == declared_cog_[0] && s.payload_cog[1] == declared_cog_[1] &&
           s.payload_cog[2] == declared_cog_[2];
  }
  // the twin predicts with `payload` from t: held-at-rest baselines measured again, the envelope checked
  void carry(const model::RigidBodyInertia& payload, double t);
  // the stream's timestamp jitter: the mean absolute deviation of the steps from the period, the
  // steps seen, and the gap factor in effect (cfg_.gap_factor, widened for a jittery clock)
  double jitter_mad_ = 0.0;
  long jitter_steps_ = 0;
  double gap_factor_ = 1.5;
  // a sample in which the controller does not drive the arm: what was open is closed as at the end
  // of a run, the twin's memory follows the encoders, nothing is judged (pause_watch); the first
  // driven sample after it restarts the estimators and decisions as after a gap (resume_watch)
  // a rest longer than the thresholds in use saw (MonitorConfig::longest_rest): from when it outlasts
  // them until kUnseenRestAfter after the arm moves on, level_ / obs_level_ no tighter than the donors'
  // (apply_donor_levels); an alert raised as it began, within the donors' levels, is withdrawn
  void watch_unseen_rest(const RobotSample& s, double t);
  void donor_levels(const RobotSample& s);  // rest_level_, rest_obs_level_ at this sample
  void apply_donor_levels();                // level_, obs_level_ no tighter than rest_level_, rest_obs_level_
  void pause_watch(const RobotSample& s, double t, double dt);
  void resume_watch(const RobotSample& s, double t);
  // closes what is open at the end of a run or when the controller stops driving the arm; `why`
  // is added to an alert's detail
  void close_open(const std::string& why);
  void track_jitter(double dt, double t);
  void add_note(double t, const std::string& text);  // into notes() and on_note
  double raise_time_ = 0.0;
  // a raise within kMergeGap of the pending alert opens an event of its own first: its first
  // diagnosis decides. A collision stays separate (and the earlier alert is reported closed);
  // anything else is the earlier fault dipping below its threshold and continues it, with the
  // diagnosis state it had (merged_*)
  int merge_into_ = -1;
  double last_over_ = 0.0;   // [s] the last sample any joint's decision exceeded its threshold
  double cleared_at_ = 0.0;  // [s] when the last alert cleared (the merge gap counts from here)
  bool merged_diagnosed_ = false, merged_rediagnosed_ = false;
  double merged_raise_time_ = 0.0;
  // a persistent alert on one joint (resistance, a sensor offset) that is open when another joint
  // raises is parked (background_): the raise opens an event of its own, whose first diagnosis
  // decides. A collision stays its own event while the parked one stays open (updated on its
  // joint); anything else is the persistent fault spreading and merges back into it. When the
  // collision clears, the parked alert is the open one again. (Before: a contact during a J5
  // resistance was not reported at all, session 19.)
  int background_ = -1, background_joint_ = -1;
  bool background_rediagnosed_ = false;
  double background_raise_time_ = 0.0, background_last_over_ = 0.0;
  void resume_background();
  void drop_open_event();  // retracts the open event (a raise merged into an earlier alert, withdrawn); open_ = -1
  // an announced alert that goes without an event of its own: on_withdraw with it, then drop_event
  void retract_event(int index);
  // on_withdraw with the alert as last announced, marked closed and withdrawn
  void announce_withdrawal(const Event& e) const;
  // the thresholds' widening at reversals under more load than they were learned with
  // (MonitorConfig::reversal_load_max), per joint, after each channel's filter: current [A],
  // observer [twin torque]; the velocity width of the direction's doubt [rad/s]; the observer's
  // per-sample filter coefficient
  VectorJ load_band_cur_, load_band_obs_;
  double reversal_width_ = 0.01, obs_band_alpha_ = 0.0;
  bool load_band_on_ = false;
  // the program sets whose thresholds judge a rest that the thresholds in use never saw
  // (MonitorConfig::longest_rest), and the commanded rest's times
  std::vector<ThresholdSet> rest_donors_;
  double rest_began_at_ = std::numeric_limits<double>::quiet_NaN();  // the commanded rest's first sample (NaN: not resting)
  double rest_left_at_ = -std::numeric_limits<double>::infinity();   // the last sample of a rest longer than the thresholds saw
  bool rest_unseen_said_ = false;  // the thresholds never saw a rest and no set did: said once
  bool rest_unseen_ = false;         // the commanded rest has outlasted every rest the thresholds saw
  bool rest_within_donors_ = true;   // the decisions stayed within the donors' levels since the rest began
  VectorJ rest_level_, rest_obs_level_;  // the donors' levels at the sample (donor_levels)
  // the drive switch's step per unit of excess load, per joint (set once): in the current residual
  // [A per twin torque unit] and the observer's [1]
  VectorJ load_step_cur_, load_step_obs_;
  void widen_for_load(const VectorJ& qd, double t);
  VectorJ crawl_since_;  // per joint: when it began to crawl (|qd| < reversal width; NaN: it moves)
  // joint j's reversal load at this sample beyond load_max (0: none, or not finite)
  double load_excess(int j, double qd, double load_max) const;
  std::vector<signal::FirFilter> fir_;   // per joint; no taps: the joint uses the IIR
  std::vector<signal::FirFilter> fir_band_;  // the same, for a FIR joint's widening at loaded reversals (widen_for_load)
  TrendDetector trend_;
  VectorJ tau_gain_;    // [N·m/A] torque_gain per joint
  VectorJ temp_slope_;  // [A·s/rad/°C] residual temperature compensation (cfg_.trend)
  std::vector<DiagnosisSample> window_;     // scratch for diagnosis (reserved once)
  std::vector<DiagnosisSample> reference_;  // observer history before the window (contact isolation)
};

/// The current residual r (measured - predicted, per joint) where a joint's drive direction is in
/// doubt (ident::TwinModel::drive_in_doubt at the twin's torque tau, the stream's memory advanced to
/// the sample): the current's distance to the nearer of the drive's two levels, in place.
/// Monitor::push calls it; the thresholds are learned on the blended residual (its margin kept).
/// Allocation-free.
void resolve_drive_doubt(const ident::TwinModel& twin, const VectorJ& tau, const ident::FrictionMemory& memory, VectorJ& r);

}  // namespace twinwatch::monitor
