#pragma once
/// @file recording.hpp
/// Recordings: CSV files whose header uses RTDE output names, one row per controller cycle —
/// the same files a real robot (twinwatch record) and the simulator (twinwatch simulate) write.
///
/// Columns (n = number of joints, inferred from the header):
///   timestamp, actual_q_0..n-1, actual_qd_*, target_q_*, target_qd_*, target_qdd_*,
///   actual_current_*, target_current_*, target_moment_*, joint_temperatures_*,
///   actual_joint_torque_* (joint torque sensors, a twinwatch name), actual_current_as_torque_*,
///   actual_digital_output_bits, robot_mode, safety_mode, stream_gap (1 where the source lost samples just before
///   this row: RTDE gaps and reconnects)
/// Only timestamp and actual_q_* are required; absent groups are NaN and flagged absent in
/// RobotSample::present. Foreign logs load through a ColumnMap (their column -> RTDE name, scale).
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "twinwatch/core/sample.hpp"

namespace twinwatch::device {

/// Maps a foreign CSV's columns onto RTDE names: value_rtde = value_file * scale.
struct ColumnMap {
  struct Entry {
    std::string rtde_name;  ///< e.g. "actual_q_3"
    double scale = 1.0;     ///< e.g. pi/180 for degrees
  };
  std::map<std::string, Entry> columns;  ///< file column name -> entry
  std::string path;                      ///< the map file ("" if built in code), for error messages
  std::map<std::string, int> lines;      ///< file column name -> line of the map file
  /// The twin compares joint torque sensors, not motor currents (ident::TwinModel::Signal::JointTorque):
  /// the reader puts the actual_joint_torque_* group [N·m] where the monitor and the fit read the
  /// measured channel (RobotSample::current, flagged kFieldActualCurrent), and leaves the file's own
  /// actual_current_* columns unread. A file without actual_joint_torque_* is then refused at its
  /// header. Set by the verbs from the twin (or identify --signal), never by a map file.
  /// The controller's target acceleration (target_qdd_*) is not read either: a sensor behind the gear
  /// reads the link's own motion, M q̈ + h with the q̈ the link had, and the twin then takes q̈ from
  /// actual_qd as for a log without targets. On the simulated UR3e the target trails or leads the
  /// link's q̈ by up to 0.26 rad/s² on the excitation's J2, which with the target raised a false alarm
  /// (docs/validation.md, "A torque twin reads the link's acceleration", session 55).
  bool joint_torque_as_current = false;
  /// Loads "file_column,rtde_name[,scale]" lines ('#' comments). Throws ParseError with the line
  /// for a wrong number of cells, a scale that is not a finite non-zero number, an unknown RTDE
  /// name or a file column mapped twice. See docs/recordings.md.
  static ColumnMap load(const std::string& path);
};

/// A loaded recording.
struct Recording {
  std::string path;
  int n_dof = 0;
  std::vector<RobotSample> samples;
  std::uint32_t present = 0;  ///< fields present in the file (SampleField flags)
  int gaps = 0;               ///< timestamp steps > gap_factor x the median period (marked gap_before)
  double median_period = 0.0; ///< [s]
  double period_jitter = 0.0; ///< [s] robust spread of the timestamp steps (1.4826 x their MAD)
  /// a step longer than gap_factor x median_period is a gap: 1.5, more for a jittery clock
  double gap_factor = 1.5;
};

/// The gap factor for a clock whose timestamp steps spread `spread` [s] around `period` [s]: a step
/// counts as lost samples only 5 spreads above the period (a late stamp followed by an early one is
/// no loss), and never below `floor` periods. Shared by the recording reader (Recording::gap_factor)
/// and the live monitor (Monitor's jitter estimate).
double jitter_gap_factor(double spread, double period, double floor);

/// Reads a recording. Throws twinwatch::ParseError naming the file, line and column for a
/// non-numeric or non-finite cell (nan, inf), a wrong number of cells, a missing required column,
/// a column that names a signal another column already carries, a timestamp that goes backwards,
/// or a column map entry whose file column is not in the header. A UTF-8 byte-order mark before
/// the header is skipped. Timestamp gaps are not errors: they are marked (gap_before) and counted.
Recording read_recording(const std::string& path, const ColumnMap* map = nullptr);

/// A sample in memory (the simulator's) as a joint-torque twin reads it: what
/// ColumnMap::joint_torque_as_current does to a file's columns. The sensors' torque goes where the
/// current is (flagged kFieldActualCurrent), and the sensors' own group and the target acceleration
/// are no longer present. `present`: a Recording's flags, changed the same way.
void read_as_joint_torque(RobotSample& s);
std::uint32_t read_as_joint_torque(std::uint32_t present);

/// Reads a recording row by row, without holding its rows: what read_recording reads, with the same
/// checks and messages (the header's when constructed, each row's in next()). An offline monitor
/// of a day's recording holds one row at a time instead of the ~0.9 kB per sample of a Recording.
/// Timestamp gaps are not marked here (they need the median step of the whole file:
/// recording_timing); gap_before is the file's stream_gap column.
class RecordingReader {
 public:
  /// Opens the file and reads its header; throws ParseError as read_recording does.
  explicit RecordingReader(const std::string& path, const ColumnMap* map = nullptr);
  int n_dof() const;
  std::uint32_t present() const;  ///< fields present in the file (SampleField flags)
  const std::string& file() const { return path; }
  /// The next row into `s`; false at the end of the file (a last row cut off mid-write is dropped,
  /// and said: one without a line end that is short of cells, or whose last cell is cut mid-number). Throws ParseError naming the file, line and column for a bad row.
  bool next(RobotSample& s);
  /// Reads on without saying a cut-off last row again (a second pass over a file already read)
  void quiet() { say_cut_ = false; }
  /// A hash of the rows read so far, as written (a second pass checks it read the rows the first did)
  std::uint64_t rows_hash() const { return hash_; }

 private:
  struct Target {
    int group;
    int joint;
  };
  bool reads(size_t column) const;  // whether a column's cells are read (not an unknown column)
  std::string path;
  std::ifstream f;
  std::vector<std::string> header;
  std::vector<double> scale;
  std::vector<Target> target;
  int ts_col = -1, do_col = -1, mode_col = -1, safety_col = -1, gap_col = -1, payload_col = -1;
  int cog_col[3] = {-1, -1, -1};  // payload_cog_0..2
  int n = 0;
  std::uint32_t present_ = 0;
  int ln = 1;
  long rows = 0;
  double last_timestamp = 0.0;
  bool say_cut_ = true;
  int last_cell_decimals_ = -1;  // the decimals of the last column in the last row (-1: no row yet)
  bool fixed_decimals_ = true;   // every row so far had that many
  std::uint64_t hash_ = 14695981039346656037ull;
  std::string line_;
  std::vector<std::string_view> cells_;
};

/// The timing of a recording's timestamp steps `dts` [s]: the median period, its jitter and the gap
/// factor a step must exceed to count as lost samples (Recording's fields of the same names). A
/// jittery clock is said once, naming `path`.
struct RecordingTiming {
  double median_period = 0.0;
  double period_jitter = 0.0;
  double gap_factor = 1.5;
  bool is_gap(double dt) const { return dt > gap_factor * median_period; }
};
RecordingTiming recording_timing(const std::string& path, std::vector<double> dts);

/// Reads every row left in `reader`, handing each to `each`: how many there were, and the timing of
/// their steps (recording_timing). Throws ParseError for a file without data rows, and what next()
/// throws. read_recording holds the rows; the offline monitor's first pass only checks them.
struct RecordingScan {
  RecordingTiming timing;
  long rows = 0;
  int n_dof = 0;              ///< the reader's, to check the second pass against
  std::uint32_t present = 0;  ///< the reader's
  std::uint64_t rows_hash = 0;  ///< the reader's RecordingReader::rows_hash after the last row
};
RecordingScan scan_rows(RecordingReader& reader, const std::function<void(const RobotSample&)>& each);

/// The second pass over a recording read twice and never held (offline monitor, report, validate):
/// the rows the scan checked, from a reader opened again, each with gap_before marked from the scan's
/// timing (as read_recording marks it), handed to `each`. Returns how many there were: fewer than
/// scan.rows when the file was cut in between (the caller says so; a file still being written has
/// more, left unread). Throws std::runtime_error naming the file when its header changed since the
/// scan, or, once all rows are read, when they are not the rows the scan read (the file replaced or
/// rewritten by another program: what `each` was handed is not what was checked), and what next()
/// throws.
long replay_rows(RecordingReader& again, const RecordingScan& scan, const std::function<void(RobotSample&)>& each);

/// Throws InvalidArgument naming `path` unless it is a file that can be read twice (a regular file,
/// or a link to one): `user` (e.g. "report") reads a recording twice or more and never holds it, which a pipe,
/// a process substitution or /dev/stdin cannot give.
void require_rereadable(const std::string& path, const std::string& user);

/// The stretches of a recording in which the controller drives the arm (RobotSample::driven: robot_mode
/// RUNNING, safety_mode NORMAL or REDUCED, where the file has those columns), each as a recording of
/// its own with the same path. A twin models a driven arm: a stop's deceleration under a protective
/// or emergency stop, a powered-off arm on its brakes (currents near 0 while gravity pulls) or a brake
/// release would be fitted, or learned as healthy, as if it were. Stretches shorter than
/// `min_seconds` are left out too. A recording driven throughout comes back whole. `left_out` (may be
/// null) gets a sentence for the user when anything was left out, else "".
std::vector<Recording> driven_segments(const Recording& rec, double min_seconds, std::string* left_out);

/// driven_segments sample by sample, for a recording read row by row and not held: see() each sample
/// in order, then finish(); stretches() are then the driven ones as sample ranges [begin, end).
class DrivenStretches {
 public:
  struct Stretch {
    size_t begin = 0, end = 0;
    double first = 0.0, last = 0.0;  ///< the timestamps of its first and last sample [s]
  };
  explicit DrivenStretches(double min_seconds) : min_seconds_(min_seconds) {}
  void see(const RobotSample& s);
  void finish();
  /// driven in every sample (driven_segments then gives the recording whole, however short)
  bool whole() const { return not_driven_ == 0; }
  /// the driven stretches at least min_seconds long (none shorter is used; the last is known at finish())
  const std::vector<Stretch>& stretches() const { return stretches_; }
  /// what driven_segments gives: the whole recording when it is driven throughout, else stretches()
  std::vector<Stretch> used() const;
  /// driven_segments' sentence for the user when anything was left out (`period`: the recording's
  /// median period, for the seconds), else ""
  std::string note(const std::string& path, double period) const;

 private:
  void close();
  double min_seconds_;
  size_t k_ = 0;
  bool in_ = false;
  size_t begin_ = 0;
  double began_ = 0.0, last_ = 0.0, first_sample_ = 0.0, last_sample_ = 0.0;
  long not_driven_ = 0, short_samples_ = 0;
  int short_stretches_ = 0;
  std::vector<Stretch> stretches_;
};

/// A recording's samples in order from the first, as often as a reader asks: held in memory
/// (HeldSamples), or read again from its file on every replay and never held (FileSamples). The
/// learners of the monitor's thresholds and temperature slope read their runs through it two or
/// three times each; `twinwatch thresholds` hands them files, so that a shift of healthy recordings
/// is learned from without holding it (1.7 GB per robot hour at 500 Hz).
class SampleSource {
 public:
  virtual ~SampleSource() = default;
  const std::string& path() const { return path_; }
  int n_dof() const { return n_dof_; }
  std::uint32_t present() const { return present_; }  ///< SampleField flags
  double median_period() const { return median_period_; }  ///< [s]
  size_t size() const { return size_; }  ///< samples
  /// from the first sample's timestamp to the last's [s] (0 with fewer than two)
  double seconds() const { return seconds_; }
  /// hands every sample to `each` in order, k counting from 0; throws what reading throws
  virtual void replay(const std::function<void(size_t k, const RobotSample& s)>& each) const = 0;

 protected:
  std::string path_;
  int n_dof_ = 0;
  std::uint32_t present_ = 0;
  double median_period_ = 0.0, seconds_ = 0.0;
  size_t size_ = 0;
};

/// A held recording as a SampleSource (it must outlive this)
class HeldSamples : public SampleSource {
 public:
  explicit HeldSamples(const Recording& rec);
  void replay(const std::function<void(size_t k, const RobotSample& s)>& each) const override;

 private:
  const Recording* rec_;
};

/// The driven stretches of a recording file that scan_rows checked (DrivenStretches::used()), each a
/// run of its own read again on every replay: the samples driven_segments gives (`whole`: the
/// recording driven throughout, given whole; else each stretch's first sample is marked as no gap,
/// the stretch starts there). The stretches of one file share its reading: replayed in order, as the
/// learners read their runs, each pass reads the file once (a shift with a stop a minute is read as
/// often as one without); replaying a stretch behind the reading opens the file again. The rows are
/// checked as replay_rows checks them, the hash when the last stretch's replay has read to the end:
/// a file cut, rewritten or replaced since the scan throws std::runtime_error naming it.
class FileSamples : public SampleSource {
 public:
  /// the stretches `driven` found in the scan (finished); `map` (may be null) must outlive them
  static std::vector<std::unique_ptr<FileSamples>> of(const std::string& path, const ColumnMap* map, const RecordingScan& scan,
                                                      const DrivenStretches& driven);
  void replay(const std::function<void(size_t k, const RobotSample& s)>& each) const override;

 private:
  struct Reading;  // the file's reader and where it is
  FileSamples(std::shared_ptr<Reading> reading, DrivenStretches::Stretch stretch, bool whole, bool last);
  std::shared_ptr<Reading> reading_;
  DrivenStretches::Stretch stretch_;
  bool whole_, last_;
};

/// Throws twinwatch::ParseError (line 1, the first missing group's column) unless every group in
/// `fields` (SampleField flags) is present in the recording; `user` says who needs them, e.g.
/// "the monitor", so that a recording without currents is refused instead of watched blind.
void require_fields(const Recording& rec, std::uint32_t fields, const std::string& user);
/// The same on the header a reader read (a recording read row by row)
void require_fields(const RecordingReader& reader, std::uint32_t fields, const std::string& user);

/// Streaming writer. Each write() appends one row with full double precision (round-trips).
class RecordingWriter {
 public:
  /// Creates/truncates the file and writes the header for n joints and the given fields
  /// (SampleField flags; timestamp, actual_q and actual_qd are always written).
  RecordingWriter(const std::string& path, int n_dof, std::uint32_t fields);
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  /// Throws std::runtime_error naming the path as soon as a write fails (disk full).
  void write(const RobotSample& s);
  /// Flushes and closes; throws std::runtime_error naming the path on an I/O error.
  void close();
  long rows() const { return rows_; }

 private:
  std::string path_;
  std::FILE* f_ = nullptr;
  int n_;
  std::uint32_t fields_;
  long rows_ = 0;
  std::string line_;
};

/// A recording written as one file, or, with `every_s` > 0, as a new file each time that much
/// controller time has gone by since the current one's first sample: rec.csv -> rec.000.csv,
/// rec.001.csv, ... (split_recording_name). Each file has the header and reads on its own; together
/// they hold every sample once, in order. A recording left running writes 1.74 GB per robot hour at
/// 500 Hz, which one file makes hard to copy, open or monitor in part.
class SplitRecordingWriter {
 public:
  /// every_s: 0 (one file at `path`) or a finite time >= 1 s (InvalidArgument otherwise). The first
  /// file is created here (PathError if it cannot be).
  SplitRecordingWriter(const std::string& path, int n_dof, std::uint32_t fields, double every_s = 0.0);
  /// Throws std::runtime_error naming the file as soon as a write fails (disk full), and
  /// std::logic_error after close(). A sample whose timestamp is not after the previous one (the
  /// controller restarted) starts a new file when splitting.
  void write(const RobotSample& s);
  /// Flushes and closes the current file (once; again is a no-op); throws std::runtime_error naming
  /// it on an I/O error.
  void close();
  /// 0 (one file) or a finite time >= 1 s: the intervals the constructor takes
  static bool valid_interval(double every_s) { return every_s == 0.0 || (every_s >= 1.0 && every_s <= std::numeric_limits<double>::max()); }
  /// The first file written for `path` (rec.csv, or rec.000.csv when splitting): the one to check
  /// before a run starts
  static std::string first_file(const std::string& path, double every_s);
  /// The files written so far, in order (the one being written last).
  const std::vector<std::string>& files() const { return files_; }
  /// Rows written over all files.
  long rows() const { return rows_; }

 private:
  std::string path_;
  int n_;
  std::uint32_t fields_;
  double every_;
  double file_start_;
  double last_t_ = -std::numeric_limits<double>::infinity();
  std::vector<std::string> files_;
  std::unique_ptr<RecordingWriter> writer_;
  long rows_ = 0;
};

/// The k-th file of a split recording: rec.csv -> rec.000.csv (k = 0), rec.001.csv, ...
std::string split_recording_name(const std::string& path, long k);

/// Column names for n joints and the given fields, in file order.
std::vector<std::string> recording_columns(int n_dof, std::uint32_t fields);

}  // namespace twinwatch::device
