#pragma once
// Shared by `twinwatch evaluate` and `twinwatch demo`: train a reference twin on simulated healthy
// runs, then monitor scenarios and score the events against their labels (evaluation code: the
// only place that reads labels, DESIGN.md rule 1).
#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "twinwatch/device/recording.hpp"
#include "twinwatch/ident/controller_torque.hpp"
#include "twinwatch/ident/twin_model.hpp"
#include "twinwatch/monitor/monitor.hpp"
#include "twinwatch/sim/scenario.hpp"

namespace twinwatch::cli {

/// The twin file at `path` (ident::TwinModel::load) with its monitor block checked too
/// (monitor::MonitorConfig::from_twin), so that every verb refuses a malformed block, not only the
/// ones that monitor. Throws ParseError naming the file and the field.
ident::TwinModel load_twin(const std::string& path);

/// `--payload-mass` / `--payload-com` of the verbs that run a twin, checked: a centre of mass needs a
/// mass, and a twin identified without a known payload (relative drive gains, an arbitrary torque
/// scale) cannot take a payload in kg: its torque would be added in N·m to a model in other units
/// (0.5 kg read as a -76 kg payload change, a validation RMSE of 228 A). Throws InvalidArgument.
model::RigidBodyInertia payload_for(const ident::TwinModel& twin, const std::string& twin_path, double mass,
                                    const std::vector<double>& com);

/// A recording that cannot be in the robot's units, refused before it is fitted or watched: a joint
/// position beyond the robot's range by more than kUnitsPositionMargin (degrees read as radians), a
/// speed above kUnitsSpeedFactor times the joint's limit, a joint's 99th-percentile |current| above
/// kUnitsCurrentMax (mA read as A), or a median sample period above kUnitsMaxPeriod (milliseconds
/// read as seconds). The message names the file, the joint, the
/// time, the value and the limit, and the column map scale that fixes it (docs/recordings.md).
/// Throws InvalidArgument.
inline constexpr double kUnitsPositionMargin = 0.5;  ///< [rad] beyond q_min / q_max
inline constexpr double kDegree = 0.017453292519943295;  ///< [rad] one degree (a column map's scale for degrees)
inline constexpr double kUnitsSpeedFactor = 2.0;     ///< x qd_max
inline constexpr double kUnitsMaxPeriod = 0.5;       ///< [s] (2 Hz; controllers stream 10-1000 Hz)
inline constexpr double kUnitsMinPeriod = 1e-4;      ///< [s] (10 kHz; controllers stream 10-1000 Hz, a few up to 4 kHz)
void check_units(const device::Recording& rec, const model::RobotModel& robot);
/// check_units a sample at a time, for a recording read row by row (monitor): the joint count at
/// construction, check_period once the median period is known, add() per sample (positions and
/// speeds at once; the currents kept in single precision, 24 bytes a sample for six joints), finish()
/// for the currents' percentile. Throws InvalidArgument as check_units does.
class UnitsCheck {
 public:
  UnitsCheck(const std::string& path, int n_dof, std::uint32_t present, const model::RobotModel& robot);
  void check_period(double median_period) const;
  void add(const RobotSample& s);
  void finish();

 private:
  std::string path_;
  const model::RobotModel& robot_;
  std::uint32_t present_;
  int n_;
  long samples_ = 0;
  double t0_ = 0.0;
  std::vector<std::vector<float>> currents_;
};
inline constexpr double kUnitsCurrentMax = 100.0;  ///< [A] a joint's 99th-percentile |current| (mA read as A)

/// The first pass over a recording that monitor, report and validate read twice and never hold: one
/// that cannot be read twice is refused for `verb` (device::require_rereadable), one without
/// actual_qd / actual_current for `user` (device::require_fields); then every row is checked, its
/// units too (UnitsCheck, with the median period of the steps), and handed to `each` (may be empty).
/// Returns what the second pass needs (device::replay_rows).
/// A warning on stderr when the verdict says the recording at `path` is another built-in arm's than
/// `robot`, or fits it beyond 0.3 (ident::ArmCheck); `user` names who reads it ("the monitor").
void warn_if_another_arm(const std::string& path, const model::RobotModel& robot, const ident::ArmVerdict& v, const std::string& user);

device::RecordingScan scan_recording(const std::string& path, const device::ColumnMap* map, const model::RobotModel& robot,
                                     const std::string& verb, const std::string& user,
                                     const std::function<void(const RobotSample&)>& each = {});

inline constexpr double kTrainingCurrentMax = 1000.0;  ///< [A] any one sample's |current| in a training run

/// For the learners (identify, thresholds): check_units, and then a current beyond
/// kTrainingCurrentMax in any sample (a corrupted word), or a payload the recording declares that the monitor would
/// not take (more than the robot carries, e.g. grams; a centre of mass beyond kPayloadComMax, e.g.
/// mm; not finite) is an error naming the file, the column, the time and sample, and `what` learns
/// from it. The monitor notes such a declaration and keeps its payload; a healthy run learned with
/// it would carry the wrong payload into every residual.
void check_training_recording(const device::Recording& rec, const model::RobotModel& robot, const std::string& what);
/// check_training_recording's checks of each sample (not its units: UnitsCheck) a sample at a time,
/// for a recording read row by row: add() each in order, then finish() throws the first failure
/// (after the units check: a current in mA is said as such, not as a corrupted word)
class TrainingCheck {
 public:
  TrainingCheck(std::string path, const model::RobotModel& robot, std::string what);
  void add(const RobotSample& s);
  void finish() const;

 private:
  std::string check(const RobotSample& s);  // what is wrong with sample k_, or ""
  std::string failure_;
  std::string path_, what_;
  const model::RobotModel* robot_;
  size_t k_ = 0;
  double first_ = 0.0;
};

/// The recordings a twin is fitted or its thresholds learned on, each cut to the stretches in which the
/// controller drives the arm (device::driven_segments, stretches of kMinDrivenStretch s and more): a
/// stop, a powered-off arm on its brakes or a brake release is no healthy driven motion. Says what was
/// left out on stderr (unless quiet). Throws InvalidArgument for a recording with no such stretch.
inline constexpr double kMinDrivenStretch = 1.0;  ///< [s]
std::vector<device::Recording> driven_only(std::vector<device::Recording> recs, bool quiet = false);

/// A learner's recording read row by row and never held (`twinwatch thresholds`: a shift of healthy
/// recordings): scanned as scan_recording does, with check_training_recording's checks of each sample,
/// and given as one device::FileSamples per driven stretch (driven_only's, its note said unless
/// `quiet`). `implausible` (may be null) gets how many joint temperature readings in those stretches
/// are no reading a joint can have (monitor::plausible_temperature), which the learners hold.
std::vector<std::unique_ptr<device::FileSamples>> scan_training_runs(const std::string& path, const device::ColumnMap* map,
                                                                     const model::RobotModel& robot, const std::string& verb,
                                                                     const std::string& user, const std::string& what,
                                                                     std::size_t* implausible, bool quiet = false);
/// For the verbs whose recordings play a role as a whole (a forward/reverse pair, TRAIN VALIDATION
/// CHIRP): throws InvalidArgument naming the first sample in which the controller does not drive the
/// arm, so that a stop is cut out by the user rather than fitted. `user` names the verb.
void require_driven(const device::Recording& rec, const std::string& user);

/// Throws InvalidArgument when two of `files` are the same file (the same name, or another name of
/// it: ./fig.csv and fig.csv): a recording given twice counts twice in a fit (`what` names the list,
/// e.g. "RECORDINGS").
void require_distinct(const std::vector<std::string>& files, const std::string& what);

/// [B] what a verb that holds its recordings whole takes per sample: the sample (~0.95 kB) and what
/// identification keeps beside it (identify on an hour at 500 Hz, 1.8 M samples: 2.52 GB)
inline constexpr double kHeldBytesPerSample = 1400.0;

/// `verb` (identify) holds `files` whole: their samples, estimated from each file's size and its first
/// rows' length, times kHeldBytesPerSample. Throws InvalidArgument naming the files' size and the
/// need when it is more than the machine's memory (it would be stopped part-way), and warns when it
/// is more than is free now. Files it cannot size are left to the reading.
void check_held_size(const std::vector<std::string>& files, const std::string& verb);

/// `--robot`: a built-in name as given, a description file (.json, .urdf) as an absolute path, so
/// that the twin (or model) that stores it still finds it from another working directory.
std::string robot_reference(const std::string& name_or_path);

/// An event's magnitude for a table: 3 significant digits, a whole count in full ("1001 samples",
/// not "1e+03 samples").
std::string magnitude_text(double value, const std::string& units);

/// `--column-map FILE` of the verbs that read recordings: the map of a foreign log's columns to
/// RTDE names (device::ColumnMap::load), none when `path` is empty.
std::optional<device::ColumnMap> load_column_map(const std::string& path);
/// The file `--column-map path` reads: the path itself, or a shipped map's file for a bare name.
/// Throws InvalidArgument (listing the shipped maps) when it is neither.
std::string column_map_file(const std::string& path);

/// `--column-map` of the verbs that read several recordings (identify, thresholds): each value is
/// MAP, the map of every recording that has none of its own, or REC=MAP, the map of that recording
/// alone (a log from another source among the robot's own recordings). Repeatable. MAP is a file or
/// a shipped map's name, as for load_column_map; a value that names an existing file is a MAP even
/// with a '=' in it, and REC is the part before the first '=' that names a recording (its name may
/// hold a '=').
class ColumnMaps {
 public:
  ColumnMaps() = default;
  /// `recordings`: every recording the verb reads. Throws InvalidArgument naming the value: REC not
  /// one of the recordings, a recording given two maps, two maps for all, an empty MAP, a bad map.
  ColumnMaps(const std::vector<std::string>& values, const std::vector<std::string>& recordings);
  /// The map to read `recording` with (nullptr: its own column names).
  const device::ColumnMap* of(const std::string& recording) const;
  /// The map files read, a shipped map's as its file (inputs an output must not replace).
  const std::vector<std::string>& files() const { return files_; }

 private:
  std::optional<device::ColumnMap> all_;
  std::vector<std::pair<std::string, device::ColumnMap>> own_;  // (recording, its map)
  std::vector<std::string> files_;
};

/// Simulates healthy training runs (seeds not used by the scenario library), identifies the twin
/// and learns the thresholds on further healthy runs. Prints progress unless quiet.
/// residual_filter: the monitor's residual filter the thresholds are learned with (MonitorConfig).
ident::TwinModel train_reference(const std::string& robot, bool quiet, const std::vector<std::string>& residual_filter = {},
                                 bool all_programs = false);

/// One link choice on a contact's true joint impulse (evaluate --link-ceiling): the share of noise
/// draws it names right, and whether it does without noise (1 right, 0 wrong, -1 not run).
struct LinkReference {
  double noisy = std::numeric_limits<double>::quiet_NaN();
  int exact = -1;
};
/// The link choices of ScenarioScore::link_reference: their JSON keys and their descriptions.
inline constexpr std::array<const char*, 4> kLinkReferenceKeys{"monitor", "monitor_cube", "bayes", "bayes_rest"};
inline constexpr std::array<const char*, 4> kLinkReferenceNames{
    "the monitor's choice, every joint read", "the same, told the generator's point cube",
    "Bayes choice for the generator, every joint read", "Bayes choice for the generator, resting joints hidden by friction"};

struct ScenarioScore {
  std::string name, fault, predicted_class, detail;
  bool has_fault = false, detected = false, class_ok = false, joint_ok = false;
  /// a payload_pick the program declared on a stream that carries the declaration (the scenario's
  /// streams_payload): the twin takes it, so no alert is expected and any event in its window is a
  /// false alarm
  bool declared = false;
  double delay_ms = 0.0, magnitude = 0.0, true_magnitude = 0.0;
  std::string magnitude_units;  ///< the detecting event's units (N, N·m, kg, A, ...; Event::units)
  double confidence = 0.0;      ///< the detecting event's confidence (Event::confidence)
  int false_alarms = 0;
  int wear_false_alarms = 0;   ///< false alarms that were wear warnings
  double duration_s = 0.0;
  double t_first_wear = std::numeric_limits<double>::quiet_NaN();   ///< [s] first wear warning
  /// healthy scenario: its own false-alarm margin per joint (Monitor::track_margin); empty otherwise
  std::vector<double> margin_current, margin_observer;
  double t_first_alert = std::numeric_limits<double>::quiet_NaN();  ///< [s] first threshold alert (no stream gaps)
  std::string wear_detail;
  int predicted_link = -1;  ///< contact link of the detecting event (0-based; -1: none)
  /// other links the event says fit the joint torques as well (Event::other_links, 0-based)
  std::vector<int> other_links;
  /// a contact whose true link is the named one or one of other_links
  bool link_in_candidates = false;
  /// collisions (evaluation only): the contact's torque on its own link's joint over its largest
  /// joint torque, at the middle of the pulse (near 0: the contact acts like one on the link before)
  double own_joint_share = std::numeric_limits<double>::quiet_NaN();
  /// collisions (evaluation only): the contact's true peak force [N] at the middle of the pulse
  /// (the label's joint-equivalent magnitude over the largest joint torque per newton), and the
  /// force the detecting event reported (NaN: none, e.g. its size was a joint torque)
  double true_force = std::numeric_limits<double>::quiet_NaN(), force = std::numeric_limits<double>::quiet_NaN();
  /// collisions, with evaluate_scenarios' `link_ceiling` (evaluation only): link choices on the true
  /// joint impulse (LinkReference), in the order of kLinkReferences
  std::array<LinkReference, 4> link_reference;
};

struct Evaluation {
  std::vector<ScenarioScore> scores;
  std::vector<std::string> skipped;  // scenarios longer than max_duration (not run)
  int false_alarms = 0, wear_false_alarms = 0;
  double monitored_hours = 0.0;
  /// False-alarm margin over the scenarios without faults (Monitor::track_margin): per joint, the
  /// largest ratio |residual| / threshold that a whole debounce run exceeded, for the current residual
  /// and the momentum observer. Every threshold scaled by a sensitivity below the largest of them
  /// raises an alert on those runs; 1 or more is an alarm at the twin's own sensitivity.
  int healthy_runs = 0;
  double healthy_hours = 0.0;
  std::vector<double> margin_current, margin_observer;
  /// the sensitivity per joint the margins were measured at (the twin's, or evaluate --sensitivity)
  std::vector<double> sensitivity;
  double false_alarms_per_hour() const { return monitored_hours > 0 ? false_alarms / monitored_hours : 0.0; }
};

/// Whether `--max-duration` (0: none) skips scenario `s` in evaluate_scenarios (and so in demo).
inline bool longer_than_max(const sim::Scenario& s, double max_duration) { return max_duration > 0 && s.options.duration > max_duration; }

/// Runs every scenario file: simulate, monitor with `twin`, score against the labels.
/// `max_duration` skips longer scenarios (0: none skipped). `trend_csv` (may be empty) gets the
/// per-window wear-trend history of every scenario appended. (A report of one run is `twinwatch
/// report`'s, on a recording: `simulate` writes the scenario's.)
/// `link_ceiling` > 0 (evaluation only): for every detected contact the diagnosis isolated, also
/// name the link from the simulator's true joint impulse (J^T F over the pulse), exact and plus white
/// noise at the sd the observer's estimate had on that contact, by the choices of kLinkReferenceNames:
/// the monitor's (every joint read as if moving), the monitor's told the contact generator's point
/// cube (half extent `link_ceiling` [m] around the link's centre of mass), and the Bayes choice for
/// the generator's distribution (that cube, isotropic direction, peak torque log-uniform over the
/// scenarios' range) with every joint read and with resting joints as uncertain as the friction
/// they hold. The last is what the joint torques carry at that noise (docs/validation.md).
Evaluation evaluate_scenarios(const ident::TwinModel& twin, const std::vector<std::string>& files, bool static_threshold,
                              double max_duration, bool quiet, const std::string& trend_csv = "",
                              double link_ceiling = -1.0);

/// Collision-sensitivity sweep [Cao §5]: contacts of decreasing magnitude on several links, each
/// run monitored with the static [UR3e §4.1] and the dynamic [Cao eq. 24] threshold.
struct SweepOptions {
  std::vector<int> links{2, 3, 5};  ///< 1-based links
  std::vector<double> magnitudes{10, 8, 6, 5, 4, 3, 2.5, 2, 1.5, 1.25, 1, 0.75, 0.5};  ///< [N·m] joint-equivalent peak
  unsigned seed = 7000;             ///< first noise seed (one per run; the library and training do not use 7000+)
  double max_delay = 0.2;           ///< [s] an alert later than this after the onset is not a detection of the pulse
  void validate() const;
};
struct SweepRun {
  int link = 0;
  double magnitude = 0.0;
  unsigned seed = 0;
  bool detected[2] = {false, false};           ///< [0] static, [1] dynamic
  double delay_ms[2] = {0.0, 0.0};
  int false_alarms[2] = {0, 0};
};
struct Sweep {
  std::vector<SweepRun> runs;
  /// Per threshold ([0] static, [1] dynamic) and link: the smallest magnitude from which every
  /// larger one in the sweep was detected (NaN: not even the largest).
  std::vector<std::vector<double>> limit;
  /// Per threshold: the smallest magnitude detected on every link (max over links of limit).
  double every_link[2] = {0.0, 0.0};
};
Sweep sweep_collisions(const ident::TwinModel& twin, const SweepOptions& o, bool quiet);
void print_sweep(const Sweep& s, const SweepOptions& o);
std::string sweep_json(const Sweep& s, const SweepOptions& o);

void print_evaluation(const Evaluation& e);
std::string evaluation_json(const Evaluation& e);

/// Writes a self-contained HTML report for one recording monitored by the twin (UR3e Fig. 8-13
/// style plots and Tables 3/5); `labels` (evaluation only): the true faults, shaded.
/// `map`: a foreign log's column map (none: RTDE column names). `keep_payload`: as `monitor
/// --keep-payload` (MonitorConfig::follow_payload off). `adjust`: the user's alert settings over the
/// twin's (monitor's --sensitivity, --static, --raise-after, ...), applied after the program's set.
void write_report(const ident::TwinModel& twin, const std::string& recording, const model::RigidBodyInertia& payload,
                  const std::string& out, const std::optional<sim::Labels>& labels = std::nullopt, const device::ColumnMap* map = nullptr,
                  const std::string& program = "", bool keep_payload = false,
                  const std::function<void(monitor::MonitorConfig&)>& adjust = {});

}  // namespace twinwatch::cli
