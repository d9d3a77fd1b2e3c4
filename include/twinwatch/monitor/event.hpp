#pragma once
/// @file event.hpp
/// What the monitor reports: alerts with a diagnosis, written as JSON lines and into an SQLite
/// event store (the last stage of sample -> residual -> decision -> event).
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "twinwatch/core/types.hpp"

namespace twinwatch::monitor {

/// Class of a diagnosed anomaly (UR3e §2.3, §4 sign/shape interpretation).
enum class FaultClass {
  Collision,        ///< short sharp pulse: contact on a link
  Resistance,       ///< persistent positive residual correlated with motion: extra friction / resistance
  PayloadChange,    ///< step-like residual across joints, often with a gripper I/O change
  SensorFault,      ///< one channel jumping or frozen while the physics is consistent
  StreamFault,      ///< timestamp gaps / lost samples
  Wear,             ///< slow trend of friction / residual energy over cycles
  Unknown,          ///< threshold exceeded, no signature fits well
};

/// Stable lower-case name ("collision", "resistance", "payload_change", ...).
std::string_view to_string(FaultClass c);
/// Inverse of to_string; throws InvalidArgument for an unknown name.
FaultClass fault_class_from_string(std::string_view s);

/// A contact pulse's joint impulse as the momentum observer measured it (isolate_contact in
/// diagnosis.cpp), with its noise; all empty when no contact was isolated.
struct ContactImpulse {
  VectorJ q;        ///< [rad] the configuration at the pulse's peak
  VectorJ impulse;  ///< [N·m·s] per joint, over the pulse
  VectorJ noise;    ///< [N·m·s] sd of the same estimate on the healthy reference just before
  VectorJ sigma;    ///< [N·m·s] the sd the link choice gave each joint (noise, model error, rest)
  VectorJ rest_sd;  ///< [N·m·s] the part of sigma for a joint at rest (friction it holds; 0 when moving)
};

/// One alert with its diagnosis.
struct Event {
  /// Which alert of the run this is, 1, 2, … as the monitor raised them (0: not numbered). Its lines
  /// (open, re-diagnosed, closed) share it; t_detected does not tell apart the alerts raised at one
  /// sample (each channel of a log whose every sensor froze at once). Not written to the event files.
  std::uint64_t serial = 0;
  double t_start = 0.0;     ///< [s] controller time of the first exceedance of the alert's run
  double t_end = 0.0;       ///< [s] the last exceedance once closed (the clearing debounce is not counted); the latest sample while open
  double t_detected = 0.0;  ///< [s] when the alert was raised (t_start + debounce): the detection delay counts to here
  bool open = true;         ///< still active
  /// the alert was still active when monitoring stopped (finish() closed it; its t_end is the run's
  /// end, not the fault's)
  bool active_at_stop = false;
  /// an alert raised (announced open) that ends without an event of its own: withdrawn (a pause, a
  /// program's late declaration of a pick) or merged into another alert; Monitor::on_withdraw hands
  /// it over so that a consumer of open alerts sees it end. Never stored
  bool withdrawn = false;
  FaultClass fault = FaultClass::Unknown;
  int joint = -1;           ///< 0-based joint most affected, -1 if none
  int link = -1;            ///< 0-based link for contacts, -1 if none
  /// Contacts: other 0-based links that fit the joint torques as well as `link` (best first);
  /// the joint torques cannot tell them apart (e.g. a force through the link's own joint axis)
  std::vector<int> other_links;
  double magnitude = 0.0;   ///< size of the fault in `units`
  std::string units;        ///< e.g. "N·m", "kg", "N", "A", "samples"
  /// [0, 1] how likely the diagnosis is right, class and place: the share of the alert's
  /// residual its signature explains (`explained`), times, for a contact, the named link's
  /// probability among the links (the detail's "% likely"). The share alone ran 11 points above
  /// how often contacts were named right on the simulated sets; the product runs 4 below
  /// (docs/validation.md, "What an event's confidence means"). Sensor and stream faults: 1.
  double confidence = 0.0;
  /// [0, 1] the share of the alert's residual the diagnosis's signature explains (in memory only;
  /// the payload follow's evidence reads it)
  double explained = 0.0;
  double peak_residual = 0.0;  ///< largest |residual| seen during the alert (residual units)
  /// the residual's units: the twin's measured channel, "A" (motor currents) or "N·m" (joint torque sensors)
  std::string peak_residual_units = "A";
  std::string detail;       ///< human-readable one-liner, e.g. "extra friction on J5 ≈ 0.8 N·m"
  /// contacts: the joint impulse the link was chosen on (in memory only: not in the JSON line or
  /// the event store; `evaluate --link-ceiling` reads its noise)
  ContactImpulse contact;
  /// [s] Unix time minus controller time, where the source's wall clock is known (a live robot:
  /// the monitor reads it against its own clock; a recording watched with `--started-at`); NaN
  /// where it is not. The monitor itself works in controller time; the front end sets this.
  double wall_offset = std::numeric_limits<double>::quiet_NaN();

  double duration() const { return t_end - t_start; }
  /// The wall-clock time of controller time `t` as ISO 8601 UTC with milliseconds
  /// ("2026-12-03T19:02:11.234Z"); "" where wall_offset is not known.
  std::string wall_time(double t) const;
  /// One JSON object on one line (no trailing newline). Joints and links are numbered from 1 there,
  /// as in the scenario labels and every table (J5 is "joint": 5), and none is null; in memory
  /// they are 0-based indices.
  std::string to_json_line() const;
};

/// An event as the store keeps it: the run it came from and when it was stored.
struct StoredEvent {
  std::string source;       ///< the recording file or the robot address
  std::string recorded_at;  ///< when the monitor stored it, "YYYY-MM-DD HH:MM:SS" UTC (SQLite's CURRENT_TIMESTAMP); "" if unknown
  Event event;
  long run = 0;             ///< the monitoring run that stored it (EventStore::begin_run); 0: none (a row from before session 47)
};

/// How a monitoring run ended (EventStore::end_run).
struct RunEnd {
  long samples = 0;    ///< samples the monitor received
  long events = 0;     ///< events it found
  std::string status;  ///< "finished", "stopped" (an operator's stop) or "connection lost"
};

/// A row of the store's `runs` table.
struct StoredRun {
  long id = 0;
  std::string started_at, ended_at;  ///< "YYYY-MM-DD HH:MM:SS" UTC; ended_at "" while running, or when the monitor did not end it (killed, failed)
  std::string source, twin, program;  ///< what was watched, the twin file, the program ("" if none given)
  long samples = -1, events = -1;     ///< -1: not ended
  std::string status;                 ///< RunEnd::status; "" if not ended
};

/// SQLite event store (embedded; default file events.db). Thread-compatible, not for RT loops:
/// the monitor hands events to it from the consumer side.
class EventStore {
 public:
  enum class Mode {
    Write,  ///< open or create the database and its `events` table (the monitor)
    Read,   ///< open an existing store read-only; nothing is created or changed (`twinwatch events`)
  };
  /// Write: opens or creates the database and its `events` table; a table written by an older
  /// version gets the columns it lacks (other_links, t_detected) and its joint/link numbers are
  /// renumbered from 1 (see below). Read: the file must exist and hold an `events` table with the
  /// columns every version wrote; columns added later read as absent; nothing is changed.
  ///
  /// Numbering: the store keeps joint, link and other_links numbered from 1 with NULL for none,
  /// as the JSON lines do, and marks it with `PRAGMA user_version = 1`. A store with user_version 0
  /// was written before session 17 with 0-based indices and -1 for none; it is read as such and,
  /// opened for writing, renumbered in one transaction. A user_version above 1 is refused.
  /// Throws std::runtime_error naming the file when SQLite cannot open it or the table is missing.
  explicit EventStore(const std::string& path, Mode mode = Mode::Write);
  ~EventStore();
  EventStore(const EventStore&) = delete;
  EventStore& operator=(const EventStore&) = delete;

  /// Starts a monitoring run: writes a row of the `runs` table (id, started_at UTC, source, twin,
  /// program), whose id every later event carries in its `run` column, so that two runs of the same
  /// recording into one store are told apart and a run without events is on record too. The row is
  /// written at once if the store is free; when another connection holds it, it is not waited for
  /// (a reader's transaction must not stall a live monitor at its start): it is written with the
  /// first event, under that event's wait, or by end_run().
  void begin_run(const std::string& source, const std::string& twin, const std::string& program);
  /// Ends the run begun: its row gets ended_at (UTC), samples, events and status (written first if
  /// it is still pending). Waits at most `wait_ms` for another connection's lock: false if the store
  /// stayed locked (nothing changed); throws std::runtime_error on any other failure, and
  /// std::logic_error without begin_run.
  bool end_run(const RunEnd& end, int wait_ms);
  /// The run's id once its row is stored; 0 before.
  long run() const;
  /// Every row of the `runs` table, oldest first (empty for a store from before runs were kept; a
  /// row from before session 50 reads as not ended). Throws std::runtime_error naming the file, the
  /// row and the column when a count is not a whole number.
  std::vector<StoredRun> read_runs() const;
  /// Inserts an event (source names the run, e.g. the recording file or the robot address).
  /// Waits up to 10 s for another connection's lock, then throws std::runtime_error naming the file.
  void insert(const Event& e, const std::string& source);
  /// The same, waiting at most `wait_ms` for another connection's lock (a reader holding a
  /// transaction, a second writer): false if the store stayed locked, the event not stored; throws
  /// on any other failure. A live monitor must not stall, or stop, because someone reads its store.
  bool try_insert(const Event& e, const std::string& source, int wait_ms);
  /// Number of stored events.
  long count() const;
  /// Every stored event with its source and storage time, oldest first (open is false; rows from before t_detected
  /// was stored read it as t_start). Throws std::runtime_error naming the file, the row id and the
  /// column when a row cannot be read back (a number column holding text, an unknown class, a
  /// malformed other_links).
  std::vector<StoredEvent> read() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace twinwatch::monitor
