#pragma once
// What the verbs that read twins and recordings share: loading a twin, the payload options, the
// checks of a recording's units and training content (scanned row by row, never held), the driven
// stretches, column maps, and a few formatting helpers.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "twinwatch/device/recording.hpp"
#include "twinwatch/ident/controller_torque.hpp"
#include "twinwatch/ident/twin_model.hpp"
#include "twinwatch/model/robot_model.hpp"

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
/// `torque`: the measured channel holds joint torque sensors (device::ColumnMap::joint_torque_as_current),
/// judged against twice the robot's torque limits (N·mm read as N·m) instead of kUnitsCurrentMax.
void check_units(const device::Recording& rec, const model::RobotModel& robot, bool torque = false);
/// Throws InvalidArgument naming `path` when its samples are not a controller's 0.0001-0.5 s apart
/// (a time column in milliseconds or microseconds): the one units check that needs no robot.
void check_sample_period(const std::string& path, double median_period);
/// [rad/s] faster than any arm joint turns (a UR wrist's limit is 6.28): speeds in degrees/s, for a
/// verb without the arm's description
inline constexpr double kUnitsAnyJointSpeedMax = 20.0;
/// Positions and speeds in different units, told from the recording alone (no arm needed): per
/// joint, over stretches of kAgreeStretch of controller time, the change of the position against the
/// speed's integral (trapezoid). Where at least kAgreeMinStretches stretches move both by
/// kAgreeMinTravel and kAgreeShare of them put that ratio near 57.3 (positions in degrees, speeds in
/// rad/s), near 1/57.3 (speeds in degrees/s), near -1 (speeds of the other sign) or near -57.3 or
/// -1/57.3 (either unit with the other sign), finish() throws
/// InvalidArgument naming the file, the joint, the typical ratio and the column map scale that fixes
/// it (docs/recordings.md). A range check misses these when the motion is small or slow (5 deg/s
/// read as 5 rad/s is within twice a UR joint's limit; a few degrees read as radians are within
/// its ±2π). A filtered or lagging speed moves the ratio by tens of percent, not by these factors,
/// and a channel frozen or offset by a fault gives no such ratio in most stretches.
/// add() per sample in time order; a step of more than kAgreeMaxStep, back in time, or to a value
/// that is not a number starts a new stretch (a lost sample or two does not: the trapezoid spans it).
/// Each file is judged on its own: one with less than about 2 s of motion (a part of --split-every 1)
/// is not judged.
inline constexpr double kAgreeStretch = 0.5;     ///< [s]
inline constexpr double kAgreeMaxStep = 0.25;    ///< [s]
inline constexpr double kAgreeMinTravel = 0.005; ///< [rad] in a stretch, position change and speed integral both
inline constexpr int kAgreeMinStretches = 4;
inline constexpr double kAgreeShare = 0.75;
inline constexpr double kAgreeBand = 1.6;  ///< a ratio within this factor of 57.3, 1/57.3, -1, -57.3 or -1/57.3
inline constexpr int kAgreeSignatures = 5;
class PositionSpeedCheck {
 public:
  PositionSpeedCheck(std::string path, int n_dof);
  void add(const RobotSample& s);
  void finish() const;

 private:
  void close_stretch();
  struct Joint {
    double moved = 0.0, integral = 0.0;  // [rad] this stretch: position change, speed integral
    long stretches = 0;                  // that moved both by kAgreeMinTravel
    long in_band[kAgreeSignatures] = {};      // of those: near each signature (recordings.cpp)
    double log_sum[kAgreeSignatures] = {};    // their log |ratio|, for the typical one
    double first_t[kAgreeSignatures] = {};    // [s] the first such stretch's start
  };
  std::string path_;
  std::vector<Joint> joints_;
  bool has_prev_ = false;
  VectorJ prev_q_, prev_qd_;
  double prev_t_ = 0.0, t0_ = 0.0, stretch_start_ = 0.0, stretch_len_ = 0.0;
};

/// check_units a sample at a time, for a recording read row by row (monitor): the joint count at
/// construction, check_period once the median period is known, add() per sample (positions and
/// speeds at once; the currents kept in single precision, 24 bytes a sample for six joints), finish()
/// for the currents' percentile. Throws InvalidArgument as check_units does.
class UnitsCheck {
 public:
  UnitsCheck(const std::string& path, int n_dof, std::uint32_t present, const model::RobotModel& robot, bool torque = false);
  void check_period(double median_period) const;
  void add(const RobotSample& s);
  void finish();

 private:
  std::string path_;
  const model::RobotModel& robot_;
  std::uint32_t present_;
  bool torque_;
  int n_;
  long samples_ = 0;
  double t0_ = 0.0;
  std::vector<std::vector<float>> currents_;
  PositionSpeedCheck agree_;
};
inline constexpr double kUnitsCurrentMax = 100.0;  ///< [A] a joint's 99th-percentile |current| (mA read as A)

/// A warning on stderr when the verdict says the recording at `path` is another built-in arm's than
/// `robot`, or fits it beyond 0.3 (ident::ArmCheck); `user` names who reads it ("the monitor").
void warn_if_another_arm(const std::string& path, const model::RobotModel& robot, const ident::ArmVerdict& v, const std::string& user);

/// The first pass over a recording that monitor, report and validate read twice and never hold: one
/// that cannot be read twice is refused for `verb` (device::require_rereadable), one without
/// actual_qd / actual_current for `user` (device::require_fields); then every row is checked, its
/// units too (UnitsCheck, with the median period of the steps), and handed to `each` (may be empty).
/// Returns what the second pass needs (device::replay_rows).
device::RecordingScan scan_recording(const std::string& path, const device::ColumnMap* map, const model::RobotModel& robot,
                                     const std::string& verb, const std::string& user,
                                     const std::function<void(const RobotSample&)>& each = {});

/// What scan_recording checks before its first row, for every file: rereadable, its header (and the
/// map's columns), actual_qd / actual_current present, the robot's joint count. Reads one line of
/// each: a verb that says something before the whole-file check (serve's address) refuses these first.
void check_headers(const std::vector<std::string>& files, const device::ColumnMap* map, const model::RobotModel& robot,
                   const std::string& verb, const std::string& user);

/// Several recordings read as one stream in the order given (monitor's and report's RECORDING...: the
/// parts `record --split-every` writes, or a shift's files): each is checked on its own
/// (scan_recording; `before_each` is called with its path first, may be empty), then they must share
/// their columns and follow each other in time (InvalidArgument naming the file otherwise); a file at
/// another rate than the first is a warning. The step from one file's last sample to the next one's
/// first is judged as any other step: a jump is a gap.
struct StreamScan {
  std::vector<device::RecordingScan> scans;  ///< per file, in order
  std::vector<double> first_t, last_t;       ///< [s] per file: its first and last timestamp
  double gap_factor = 0.0;                   ///< the largest of the files' (a jittery logger clock)
  /// Where a replay ended early: a file with fewer rows than were checked (cut or replaced meanwhile).
  struct Cut {
    long file = -1;  ///< its index (-1: none)
    long rows = 0;   ///< the rows it had
  };
  /// The second pass over every file, in order (device::replay_rows), a jump between two files marked
  /// as a gap (gap_before) as the first file's timing measures one; `each` may throw to stop. Returns
  /// the rows replayed; a cut file ends the replay there, said in `cut` (may be null).
  long replay(const std::vector<std::string>& files, const device::ColumnMap* map, const std::function<void(RobotSample&)>& each,
              Cut* cut = nullptr) const;
  /// The index of the file in which controller time `t` lies (0 before the first).
  size_t file_at(double t) const;
};
StreamScan scan_stream(const std::vector<std::string>& files, const device::ColumnMap* map, const model::RobotModel& robot,
                       const std::string& verb, const std::string& user,
                       const std::function<void(const std::string&)>& before_each = {});

inline constexpr double kTrainingCurrentMax = 1000.0;  ///< [A] any one sample's |current| in a training run

/// For the learners (identify, thresholds): check_units, and then a current beyond
/// kTrainingCurrentMax in any sample (a corrupted word), or a payload the recording declares that the monitor would
/// not take (more than the robot carries, e.g. grams; a centre of mass beyond kPayloadComMax, e.g.
/// mm; not finite) is an error naming the file, the column, the time and sample, and `what` learns
/// from it. The monitor notes such a declaration and keeps its payload; a healthy run learned with
/// it would carry the wrong payload into every residual.
void check_training_recording(const device::Recording& rec, const model::RobotModel& robot, const std::string& what, bool torque = false);
/// check_training_recording's checks of each sample (not its units: UnitsCheck) a sample at a time,
/// for a recording read row by row: add() each in order, then finish() throws the first failure
/// (after the units check: a current in mA is said as such, not as a corrupted word)
class TrainingCheck {
 public:
  /// `torque`: as for UnitsCheck (the messages name the joint torque columns)
  TrainingCheck(std::string path, const model::RobotModel& robot, std::string what, bool torque = false);
  void add(const RobotSample& s);
  void finish() const;

 private:
  std::string check(const RobotSample& s);  // what is wrong with sample k_, or ""
  std::string failure_;
  std::string path_, what_;
  const model::RobotModel* robot_;
  bool torque_;
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
/// load_column_map for a verb that compares `twin`'s measured channel: for a joint-torque twin
/// (TwinModel::measures_torque) the map, an empty one when `path` is empty, reads the joint torque
/// sensors in the current's place (device::ColumnMap::joint_torque_as_current)
std::optional<device::ColumnMap> load_column_map(const std::string& path, const ident::TwinModel& twin);
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
  /// `joint_torque`: the verb compares a joint-torque twin's channel, and every recording is read with
  /// device::ColumnMap::joint_torque_as_current (one without a map with an empty map that does only that).
  ColumnMaps(const std::vector<std::string>& values, const std::vector<std::string>& recordings, bool joint_torque = false);
  /// The map to read `recording` with (nullptr: its own column names).
  const device::ColumnMap* of(const std::string& recording) const;
  /// The map files read, a shipped map's as its file (inputs an output must not replace).
  const std::vector<std::string>& files() const { return files_; }

 private:
  std::optional<device::ColumnMap> all_;
  std::vector<std::pair<std::string, device::ColumnMap>> own_;  // (recording, its map)
  std::vector<std::string> files_;
};

}  // namespace twinwatch::cli
