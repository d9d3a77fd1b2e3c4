#include "twinwatch/monitor/event.hpp"

#include <fmt/format.h>
#include <sqlite3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <memory>
#include <stdexcept>
#include <string_view>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/wall_clock.hpp"

namespace twinwatch::monitor {

namespace {
constexpr std::array<std::pair<FaultClass, std::string_view>, 7> kNames{{
    {FaultClass::Collision, "collision"},
    {FaultClass::Resistance, "resistance"},
    {FaultClass::PayloadChange, "payload_change"},
    {FaultClass::SensorFault, "sensor_fault"},
    {FaultClass::StreamFault, "stream_fault"},
    {FaultClass::Wear, "wear"},
    {FaultClass::Unknown, "unknown"},
}};
}  // namespace

std::string_view to_string(FaultClass c) {
  for (const auto& [k, v] : kNames)
    if (k == c) return v;
  return "unknown";
}

FaultClass fault_class_from_string(std::string_view s) {
  for (const auto& [k, v] : kNames)
    if (v == s) return k;
  throw InvalidArgument(fmt::format("fault class '{}' is unknown, expected one of collision, resistance, "
                                    "payload_change, sensor_fault, stream_fault, wear, unknown",
                                    s));
}

namespace {
// joint/link indices numbered from 1 (`by` = 1) or back to 0-based indices (`by` = -1)
std::vector<int> shifted(std::vector<int> v, int by) {
  for (int& x : v) x += by;
  return v;
}
}  // namespace

std::string Event::wall_time(double t) const {
  if (!std::isfinite(wall_offset) || !std::isfinite(t)) return {};
  return iso_utc(t + wall_offset);
}

std::string Event::to_json_line() const {
  nlohmann::json j;
  j["t_start"] = t_start;
  j["t_end"] = t_end;
  j["t_detected"] = t_detected;
  j["duration_s"] = duration();
  j["open"] = open;
  // written when it ended: one still active when monitoring stopped ended there (open is false)
  j["active_at_stop"] = active_at_stop;
  j["class"] = std::string(to_string(fault));
  // numbered from 1, as the labels and every table; null: none
  const auto number = [](int index) { return index >= 0 ? nlohmann::json(index + 1) : nlohmann::json(nullptr); };
  j["joint"] = number(joint);
  j["link"] = number(link);
  j["other_links"] = shifted(other_links, 1);
  j["magnitude"] = magnitude;
  j["units"] = units;
  j["confidence"] = confidence;
  j["peak_residual"] = peak_residual;  // the largest |filtered current residual| of any joint during the alert
  j["peak_residual_units"] = peak_residual_units;
  j["detail"] = detail;
  // the wall clock of the three times, where the source's is known (null: a recording watched
  // without --started-at)
  const auto wall = [&](double t) {
    const std::string w = wall_time(t);
    return w.empty() ? nlohmann::json(nullptr) : nlohmann::json(w);
  };
  j["wall_start"] = wall(t_start);
  j["wall_detected"] = wall(t_detected);
  j["wall_end"] = wall(t_end);
  // an open alert that ended without an event of its own (on_withdraw): its last line
  j["withdrawn"] = withdrawn;
  return j.dump();
}

struct EventStore::Impl {
  sqlite3* db = nullptr;
  sqlite3_stmt* insert = nullptr;
  std::string path;
  bool has_other_links = false, has_t_detected = false, has_active_at_stop = false, has_recorded_at = false, has_run = false,
       has_wall_offset = false, has_residual_units = false;
  long run = 0;  // the run's id (its row written with its first event), 0: none yet
  bool run_pending = false;  // begin_run was called, its row not yet written
  std::string run_source, run_twin, run_program;
  bool from_one = true;  // joint/link/other_links numbered from 1 (user_version 1); false: a 0-based store from before
};

namespace {
// the store's numbering version (PRAGMA user_version): 0 before session 17 (0-based, -1 none),
// 1 since (from 1, NULL none)
constexpr int kNumberedFromOne = 1;
// [ms] how long a write waits for another connection's lock before it fails
constexpr int kBusyTimeoutMs = 10000;

int user_version(sqlite3* db) {
  sqlite3_stmt* s = nullptr;
  int v = 0;
  if (sqlite3_prepare_v2(db, "PRAGMA user_version;", -1, &s, nullptr) == SQLITE_OK && sqlite3_step(s) == SQLITE_ROW)
    v = sqlite3_column_int(s, 0);
  sqlite3_finalize(s);
  return v;
}
}  // namespace

EventStore::EventStore(const std::string& path, Mode mode) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  // every failure below: close what is open and name the file and the step
  const auto fail = [&](const char* what, const std::string& msg) {
    sqlite3_close(impl_->db);
    impl_->db = nullptr;
    // (a store the user named that cannot be opened or is no event store: bad input)
    throw PathError(fmt::format("{}: {}: {}", path, what, msg));
  };
  // a statement run once; SQLite's own message on failure
  const auto exec = [&](const char* sql, const char* what) {
    char* err = nullptr;
    if (sqlite3_exec(impl_->db, sql, nullptr, nullptr, &err) == SQLITE_OK) return;
    const std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    fail(what, msg);
  };
  // (SQLite says "disk I/O error" of a directory)
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw PathError(fmt::format("{}: cannot open event store: it is a directory, not a file", path));
  const int flags = mode == Mode::Read ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE;
  if (sqlite3_open_v2(path.c_str(), &impl_->db, flags, nullptr) != SQLITE_OK)
    fail("cannot open event store", impl_->db ? sqlite3_errmsg(impl_->db) : "out of memory");
  // another connection (a second monitor, 'twinwatch events', a dashboard) may hold the lock for a
  // moment: wait for it rather than stop monitoring with "database is locked"
  sqlite3_busy_timeout(impl_->db, kBusyTimeoutMs);
  const int version = user_version(impl_->db);
  if (version > kNumberedFromOne)
    fail("cannot use event store", fmt::format("it was written by a newer twinwatch (user_version {}, this one knows 0 and {})",
                                               version, kNumberedFromOne));
  const auto table_exists = [&] {
    sqlite3_stmt* q = nullptr;
    bool found = false;
    if (sqlite3_prepare_v2(impl_->db, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'events';", -1, &q,
                           nullptr) == SQLITE_OK)
      found = sqlite3_step(q) == SQLITE_ROW;
    sqlite3_finalize(q);
    return found;
  };
  const bool existed = table_exists();
  if (mode == Mode::Write)
    exec("CREATE TABLE IF NOT EXISTS events ("
         " id INTEGER PRIMARY KEY AUTOINCREMENT, source TEXT, t_start REAL, t_end REAL, duration_s REAL,"
         " class TEXT, joint INTEGER, link INTEGER, magnitude REAL, units TEXT, confidence REAL,"
         " peak_residual REAL, detail TEXT, recorded_at TEXT DEFAULT CURRENT_TIMESTAMP, other_links TEXT, t_detected REAL,"
         " active_at_stop INTEGER, peak_residual_units TEXT);",
         "cannot create the events table");
  // the table's columns: a table from an older version lacks the later ones
  std::vector<std::string> columns;
  sqlite3_stmt* info = nullptr;
  if (sqlite3_prepare_v2(impl_->db, "PRAGMA table_info(events);", -1, &info, nullptr) == SQLITE_OK)
    while (sqlite3_step(info) == SQLITE_ROW) {
      const auto* name = reinterpret_cast<const char*>(sqlite3_column_text(info, 1));
      if (name) columns.emplace_back(name);
    }
  sqlite3_finalize(info);
  const auto has = [&](const char* c) { return std::find(columns.begin(), columns.end(), c) != columns.end(); };
  // a 0-based store from before session 17: joint/link +1 (-1 -> NULL) and other_links +1, in one
  // transaction; a cell that is not a whole number is left as it is (reading it names the row).
  // On any failure fail() closes the database, which rolls the open transaction back.
  const auto renumber_from_one = [&] {
    constexpr const char* what = "cannot renumber the events from 1";
    exec("BEGIN IMMEDIATE;", what);
    exec("UPDATE events SET"
         " joint = CASE WHEN typeof(joint) != 'integer' THEN joint WHEN joint >= 0 THEN joint + 1 ELSE NULL END,"
         " link = CASE WHEN typeof(link) != 'integer' THEN link WHEN link >= 0 THEN link + 1 ELSE NULL END;",
         what);
    if (has("other_links")) {
      std::vector<std::pair<long, std::string>> lists;
      sqlite3_stmt* q = nullptr;
      if (sqlite3_prepare_v2(impl_->db, "SELECT id, other_links FROM events WHERE other_links IS NOT NULL;", -1, &q,
                             nullptr) != SQLITE_OK)
        fail(what, sqlite3_errmsg(impl_->db));
      while (sqlite3_step(q) == SQLITE_ROW) {
        const auto* t = reinterpret_cast<const char*>(sqlite3_column_text(q, 1));
        lists.emplace_back(sqlite3_column_int64(q, 0), t ? t : "");
      }
      sqlite3_finalize(q);
      sqlite3_stmt* u = nullptr;
      if (sqlite3_prepare_v2(impl_->db, "UPDATE events SET other_links = ? WHERE id = ?;", -1, &u, nullptr) != SQLITE_OK)
        fail(what, sqlite3_errmsg(impl_->db));
      for (const auto& [id, text] : lists) {
        std::vector<int> links;
        try {
          links = nlohmann::json::parse(text).get<std::vector<int>>();
        } catch (const std::exception&) {
          continue;  // malformed: left as it is; read() names the row
        }
        const std::string numbered = nlohmann::json(shifted(links, 1)).dump();
        sqlite3_reset(u);
        sqlite3_bind_text(u, 1, numbered.c_str(), -1, SQLITE_TRANSIENT);
        sqlite3_bind_int64(u, 2, id);
        if (sqlite3_step(u) != SQLITE_DONE) {
          const std::string msg = sqlite3_errmsg(impl_->db);
          sqlite3_finalize(u);
          fail(what, msg);
        }
      }
      sqlite3_finalize(u);
    }
    exec("PRAGMA user_version = 1; COMMIT;", what);
  };
  if (mode == Mode::Read) {
    if (columns.empty()) fail("not an event store", "it has no events table (is it a database 'twinwatch monitor --db' wrote?)");
    for (const char* c : {"id", "source", "t_start", "t_end", "class", "joint", "link", "magnitude", "units", "confidence",
                          "peak_residual", "detail"})
      if (!has(c)) fail("not an event store", fmt::format("its events table has no column '{}'", c));
  } else {
    // a table from before other_links (session 10) or t_detected (session 16) gets the column;
    // its old rows read as none, and as t_start
    if (!has("other_links")) exec("ALTER TABLE events ADD COLUMN other_links TEXT;", "cannot add the other_links column to the events table");
    if (!has("t_detected")) exec("ALTER TABLE events ADD COLUMN t_detected REAL;", "cannot add the t_detected column to the events table");
    // (session 22) whether the fault was still there when monitoring stopped; older rows read as no
    if (!has("active_at_stop"))
      exec("ALTER TABLE events ADD COLUMN active_at_stop INTEGER;", "cannot add the active_at_stop column to the events table");
    // (session 47) the monitoring runs: two runs of one recording into one store were rows alike but
    // for their storage time
    if (!has("run")) exec("ALTER TABLE events ADD COLUMN run INTEGER;", "cannot add the run column to the events table");
    // (session 48) the wall clock, where the source's is known: Unix time minus controller time,
    // and t_start's wall time for a reader of the table
    if (!has("wall_offset"))
      exec("ALTER TABLE events ADD COLUMN wall_offset REAL;", "cannot add the wall_offset column to the events table");
    if (!has("wall_start")) exec("ALTER TABLE events ADD COLUMN wall_start TEXT;", "cannot add the wall_start column to the events table");
    // (session 54) the residual's units: a joint-torque twin's are N·m; older rows read as A
    if (!has("peak_residual_units"))
      exec("ALTER TABLE events ADD COLUMN peak_residual_units TEXT;", "cannot add the peak_residual_units column to the events table");
    exec("CREATE TABLE IF NOT EXISTS runs (id INTEGER PRIMARY KEY AUTOINCREMENT, started_at TEXT DEFAULT CURRENT_TIMESTAMP,"
         " source TEXT, twin TEXT, program TEXT, ended_at TEXT, samples INTEGER, events INTEGER, status TEXT);",
         "cannot create the runs table");
    // (session 50) how a run ended: a runs table from sessions 47-49 gets the columns; its rows read as not ended
    {
      std::vector<std::string> run_columns;
      sqlite3_stmt* q = nullptr;
      if (sqlite3_prepare_v2(impl_->db, "PRAGMA table_info(runs);", -1, &q, nullptr) == SQLITE_OK)
        while (sqlite3_step(q) == SQLITE_ROW) {
          const auto* name = reinterpret_cast<const char*>(sqlite3_column_text(q, 1));
          if (name) run_columns.emplace_back(name);
        }
      sqlite3_finalize(q);
      for (const char* c : {"ended_at TEXT", "samples INTEGER", "events INTEGER", "status TEXT"}) {
        const std::string_view col(c);
        if (std::find(run_columns.begin(), run_columns.end(), col.substr(0, col.find(' '))) != run_columns.end()) continue;
        const std::string sql = fmt::format("ALTER TABLE runs ADD COLUMN {};", c);
        exec(sql.c_str(), "cannot add a column to the runs table");
      }
    }
    if (!existed) {
      exec("PRAGMA user_version = 1;", "cannot mark the event store's numbering");
    } else if (version == 0) {
      renumber_from_one();
    }
  }
  impl_->from_one = mode == Mode::Write || version == kNumberedFromOne;
  impl_->has_other_links = mode == Mode::Write || has("other_links");
  impl_->has_t_detected = mode == Mode::Write || has("t_detected");
  impl_->has_active_at_stop = mode == Mode::Write || has("active_at_stop");
  impl_->has_recorded_at = mode == Mode::Write || has("recorded_at");
  impl_->has_run = mode == Mode::Write || has("run");
  impl_->has_wall_offset = mode == Mode::Write || has("wall_offset");
  impl_->has_residual_units = mode == Mode::Write || has("peak_residual_units");
  if (mode == Mode::Read) return;
  const char* ins =
      "INSERT INTO events (source, t_start, t_end, duration_s, class, joint, link, magnitude, units, confidence,"
      " peak_residual, detail, other_links, t_detected, active_at_stop, run, wall_offset, wall_start, peak_residual_units)"
      " VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?);";
  if (sqlite3_prepare_v2(impl_->db, ins, -1, &impl_->insert, nullptr) != SQLITE_OK) fail("cannot prepare insert", sqlite3_errmsg(impl_->db));
}

EventStore::~EventStore() {
  if (impl_->insert) sqlite3_finalize(impl_->insert);
  if (impl_->db) sqlite3_close(impl_->db);
}

namespace {
// Inserts the run's row (source, twin, program): SQLITE_DONE, or SQLite's code (BUSY/LOCKED: another
// connection holds the store)
int insert_run_row(sqlite3* db, const std::string& source, const std::string& twin, const std::string& program, long* id) {
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(db, "INSERT INTO runs (source, twin, program) VALUES (?,?,?);", -1, &raw, nullptr) != SQLITE_OK)
    return sqlite3_errcode(db);
  sqlite3_bind_text(raw, 1, source.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(raw, 2, twin.c_str(), -1, SQLITE_TRANSIENT);
  if (program.empty()) sqlite3_bind_null(raw, 3);
  else sqlite3_bind_text(raw, 3, program.c_str(), -1, SQLITE_TRANSIENT);
  const int rc = sqlite3_step(raw);
  sqlite3_finalize(raw);
  if (rc == SQLITE_DONE) *id = static_cast<long>(sqlite3_last_insert_rowid(db));
  return rc;
}

bool busy(int rc) { return (rc & 0xff) == SQLITE_BUSY || (rc & 0xff) == SQLITE_LOCKED; }
}  // namespace

void EventStore::insert(const Event& e, const std::string& source) {
  if (!try_insert(e, source, kBusyTimeoutMs))
    throw std::runtime_error(fmt::format("{}: cannot insert event: {} (another connection held it for {:g} s)", impl_->path,
                                         sqlite3_errmsg(impl_->db), kBusyTimeoutMs / 1000.0));
}

bool EventStore::try_insert(const Event& e, const std::string& source, int wait_ms) {
  if (!impl_->insert) throw std::logic_error(fmt::format("{}: the event store was opened for reading", impl_->path));
  sqlite3_busy_timeout(impl_->db, std::max(0, wait_ms));
  // the run's row with its first event: the two in one transaction, or neither (locked: the event
  // waits, and the row with it)
  const bool new_run = impl_->run_pending;
  if (new_run) {
    const int rc = sqlite3_exec(impl_->db, "BEGIN IMMEDIATE;", nullptr, nullptr, nullptr);
    if ((rc & 0xff) == SQLITE_BUSY || (rc & 0xff) == SQLITE_LOCKED) {
      sqlite3_busy_timeout(impl_->db, kBusyTimeoutMs);
      return false;
    }
    if (rc != SQLITE_OK) throw std::runtime_error(fmt::format("{}: cannot begin the run's row: {}", impl_->path, sqlite3_errmsg(impl_->db)));
    long id = 0;
    const int row = insert_run_row(impl_->db, impl_->run_source, impl_->run_twin, impl_->run_program, &id);
    if (row != SQLITE_DONE) {
      const std::string why = sqlite3_errmsg(impl_->db);
      sqlite3_exec(impl_->db, "ROLLBACK;", nullptr, nullptr, nullptr);
      sqlite3_busy_timeout(impl_->db, kBusyTimeoutMs);
      if (busy(row)) return false;
      throw std::runtime_error(fmt::format("{}: cannot store the run's row: {}", impl_->path, why));
    }
    impl_->run = id;
  }
  sqlite3_stmt* s = impl_->insert;
  sqlite3_reset(s);
  sqlite3_bind_text(s, 1, source.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_double(s, 2, e.t_start);
  sqlite3_bind_double(s, 3, e.t_end);
  sqlite3_bind_double(s, 4, e.duration());
  const std::string cls(to_string(e.fault));
  sqlite3_bind_text(s, 5, cls.c_str(), -1, SQLITE_TRANSIENT);
  // numbered from 1, NULL: none (the store's user_version 1)
  if (e.joint >= 0) sqlite3_bind_int(s, 6, e.joint + 1); else sqlite3_bind_null(s, 6);
  if (e.link >= 0) sqlite3_bind_int(s, 7, e.link + 1); else sqlite3_bind_null(s, 7);
  sqlite3_bind_double(s, 8, e.magnitude);
  sqlite3_bind_text(s, 9, e.units.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_double(s, 10, e.confidence);
  sqlite3_bind_double(s, 11, e.peak_residual);
  sqlite3_bind_text(s, 12, e.detail.c_str(), -1, SQLITE_TRANSIENT);
  const std::string others = nlohmann::json(shifted(e.other_links, 1)).dump();
  sqlite3_bind_text(s, 13, others.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_double(s, 14, e.t_detected);
  sqlite3_bind_int(s, 15, e.active_at_stop ? 1 : 0);
  if (impl_->run > 0) sqlite3_bind_int64(s, 16, impl_->run); else sqlite3_bind_null(s, 16);
  const std::string wall_start = e.wall_time(e.t_start);
  if (wall_start.empty()) {
    sqlite3_bind_null(s, 17);
    sqlite3_bind_null(s, 18);
  } else {
    sqlite3_bind_double(s, 17, e.wall_offset);
    sqlite3_bind_text(s, 18, wall_start.c_str(), -1, SQLITE_TRANSIENT);
  }
  sqlite3_bind_text(s, 19, e.peak_residual_units.c_str(), -1, SQLITE_TRANSIENT);
  const int rc = sqlite3_step(s);
  if (new_run) {
    // (the commit waits for readers to let go, as an insert outside a transaction does)
    const int commit = rc == SQLITE_DONE ? sqlite3_exec(impl_->db, "COMMIT;", nullptr, nullptr, nullptr) : rc;
    if (commit == SQLITE_OK) {
      impl_->run_pending = false;
      sqlite3_busy_timeout(impl_->db, kBusyTimeoutMs);
      return true;
    }
    const std::string why = sqlite3_errmsg(impl_->db);
    sqlite3_reset(s);
    sqlite3_exec(impl_->db, "ROLLBACK;", nullptr, nullptr, nullptr);
    impl_->run = 0;
    sqlite3_busy_timeout(impl_->db, kBusyTimeoutMs);
    // locked: the event (and the run's row) wait to be stored
    if ((commit & 0xff) == SQLITE_BUSY || (commit & 0xff) == SQLITE_LOCKED) return false;
    throw std::runtime_error(fmt::format("{}: cannot insert event: {}", impl_->path, why));
  }
  sqlite3_busy_timeout(impl_->db, kBusyTimeoutMs);
  if (rc == SQLITE_DONE) return true;
  // (a busy step leaves the statement to be reset; the event is still the caller's to store)
  if ((rc & 0xff) == SQLITE_BUSY || (rc & 0xff) == SQLITE_LOCKED) {
    sqlite3_reset(s);
    return false;
  }
  throw std::runtime_error(fmt::format("{}: cannot insert event: {}", impl_->path, sqlite3_errmsg(impl_->db)));
}

void EventStore::begin_run(const std::string& source, const std::string& twin, const std::string& program) {
  if (!impl_->insert) throw std::logic_error(fmt::format("{}: the event store was opened for reading", impl_->path));
  impl_->run = 0;
  impl_->run_pending = true;
  impl_->run_source = source;
  impl_->run_twin = twin;
  impl_->run_program = program;
  // the row now if the store is free (no wait: a reader's transaction must not stall a live monitor
  // at its start); locked, it waits for the first event or the run's end
  sqlite3_busy_timeout(impl_->db, 0);
  long id = 0;
  const int rc = insert_run_row(impl_->db, source, twin, program, &id);
  sqlite3_busy_timeout(impl_->db, kBusyTimeoutMs);
  if (rc == SQLITE_DONE) {
    impl_->run = id;
    impl_->run_pending = false;
  } else if (!busy(rc)) {
    throw std::runtime_error(fmt::format("{}: cannot store the run's row: {}", impl_->path, sqlite3_errmsg(impl_->db)));
  }
}

bool EventStore::end_run(const RunEnd& end, int wait_ms) {
  if (!impl_->insert) throw std::logic_error(fmt::format("{}: the event store was opened for reading", impl_->path));
  if (!impl_->run_pending && impl_->run == 0) throw std::logic_error(fmt::format("{}: end_run without begin_run", impl_->path));
  sqlite3_busy_timeout(impl_->db, std::max(0, wait_ms));
  const auto restore = [&] { sqlite3_busy_timeout(impl_->db, kBusyTimeoutMs); };
  if (impl_->run_pending) {
    long id = 0;
    const int rc = insert_run_row(impl_->db, impl_->run_source, impl_->run_twin, impl_->run_program, &id);
    if (rc != SQLITE_DONE) {
      restore();
      if (busy(rc)) return false;
      throw std::runtime_error(fmt::format("{}: cannot store the run's row: {}", impl_->path, sqlite3_errmsg(impl_->db)));
    }
    impl_->run = id;
    impl_->run_pending = false;
  }
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(impl_->db, "UPDATE runs SET ended_at = CURRENT_TIMESTAMP, samples = ?, events = ?, status = ? WHERE id = ?;", -1,
                         &raw, nullptr) != SQLITE_OK) {
    const std::string why = sqlite3_errmsg(impl_->db);
    restore();
    if (busy(sqlite3_errcode(impl_->db))) return false;
    throw std::runtime_error(fmt::format("{}: cannot prepare the run's end: {}", impl_->path, why));
  }
  const std::unique_ptr<sqlite3_stmt, decltype(&sqlite3_finalize)> stmt(raw, &sqlite3_finalize);
  sqlite3_bind_int64(raw, 1, end.samples);
  sqlite3_bind_int64(raw, 2, end.events);
  sqlite3_bind_text(raw, 3, end.status.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_int64(raw, 4, impl_->run);
  const int rc = sqlite3_step(raw);
  restore();
  if (rc == SQLITE_DONE) return true;
  if (busy(rc)) return false;
  throw std::runtime_error(fmt::format("{}: cannot store the run's end: {}", impl_->path, sqlite3_errmsg(impl_->db)));
}

std::vector<StoredRun> EventStore::read_runs() const {
  std::vector<StoredRun> out;
  sqlite3_stmt* q = nullptr;
  if (sqlite3_prepare_v2(impl_->db, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'runs';", -1, &q, nullptr) != SQLITE_OK)
    throw std::runtime_error(fmt::format("{}: cannot read the runs: {}", impl_->path, sqlite3_errmsg(impl_->db)));
  const bool exists = sqlite3_step(q) == SQLITE_ROW;
  sqlite3_finalize(q);
  if (!exists) return out;  // a store from before session 47
  std::vector<std::string> columns;
  if (sqlite3_prepare_v2(impl_->db, "PRAGMA table_info(runs);", -1, &q, nullptr) == SQLITE_OK)
    while (sqlite3_step(q) == SQLITE_ROW) {
      const auto* name = reinterpret_cast<const char*>(sqlite3_column_text(q, 1));
      if (name) columns.emplace_back(name);
    }
  sqlite3_finalize(q);
  const auto col = [&](const char* c) { return std::find(columns.begin(), columns.end(), c) != columns.end() ? c : "NULL"; };
  const std::string sel = fmt::format("SELECT id, started_at, source, twin, program, {}, {}, {}, {} FROM runs ORDER BY id;", col("ended_at"),
                                      col("samples"), col("events"), col("status"));
  if (sqlite3_prepare_v2(impl_->db, sel.c_str(), -1, &q, nullptr) != SQLITE_OK)
    throw std::runtime_error(fmt::format("{}: cannot read the runs: {}", impl_->path, sqlite3_errmsg(impl_->db)));
  const std::unique_ptr<sqlite3_stmt, decltype(&sqlite3_finalize)> stmt(q, &sqlite3_finalize);
  const auto text = [&](int c) {
    const auto* t = reinterpret_cast<const char*>(sqlite3_column_text(q, c));
    return std::string(t ? t : "");
  };
  const auto whole = [&](int c, long id, const char* name) -> long {
    const int type = sqlite3_column_type(q, c);
    if (type == SQLITE_NULL) return -1;
    if (type != SQLITE_INTEGER)
      throw std::runtime_error(fmt::format("{}: runs row {}: column '{}' holds '{}', expected a whole number", impl_->path, id, name, text(c)));
    return static_cast<long>(sqlite3_column_int64(q, c));
  };
  int rc;
  while ((rc = sqlite3_step(q)) == SQLITE_ROW) {
    StoredRun r;
    r.id = static_cast<long>(sqlite3_column_int64(q, 0));
    r.started_at = text(1);
    r.source = text(2);
    r.twin = text(3);
    r.program = text(4);
    r.ended_at = text(5);
    r.samples = whole(6, r.id, "samples");
    r.events = whole(7, r.id, "events");
    r.status = text(8);
    out.push_back(std::move(r));
  }
  if (rc != SQLITE_DONE) throw std::runtime_error(fmt::format("{}: cannot read the runs: {}", impl_->path, sqlite3_errmsg(impl_->db)));
  return out;
}

long EventStore::run() const { return impl_->run; }

long EventStore::count() const {
  sqlite3_stmt* s = nullptr;
  sqlite3_prepare_v2(impl_->db, "SELECT COUNT(*) FROM events;", -1, &s, nullptr);
  long n = 0;
  if (sqlite3_step(s) == SQLITE_ROW) n = sqlite3_column_int64(s, 0);
  sqlite3_finalize(s);
  return n;
}

std::vector<StoredEvent> EventStore::read() const {
  sqlite3_stmt* raw = nullptr;
  const std::string sel = fmt::format(
      "SELECT id, source, t_start, t_end, class, joint, link, magnitude, units, confidence, peak_residual, detail,"
      " {}, {}, {}, {}, {}, {}, {} FROM events ORDER BY id;",
      impl_->has_other_links ? "other_links" : "NULL", impl_->has_t_detected ? "t_detected" : "NULL",
      impl_->has_active_at_stop ? "active_at_stop" : "NULL", impl_->has_recorded_at ? "recorded_at" : "NULL",
      impl_->has_run ? "run" : "NULL", impl_->has_wall_offset ? "wall_offset" : "NULL",
      impl_->has_residual_units ? "peak_residual_units" : "NULL");
  if (sqlite3_prepare_v2(impl_->db, sel.c_str(), -1, &raw, nullptr) != SQLITE_OK)
    throw std::runtime_error(fmt::format("{}: cannot read events: {}", impl_->path, sqlite3_errmsg(impl_->db)));
  const std::unique_ptr<sqlite3_stmt, decltype(&sqlite3_finalize)> stmt(raw, &sqlite3_finalize);
  sqlite3_stmt* s = stmt.get();
  const auto text = [&](int col) {
    const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(s, col));
    return p ? std::string(p) : std::string();
  };
  std::vector<StoredEvent> out;
  int rc = SQLITE_ROW;
  while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
    const long id = sqlite3_column_int64(s, 0);
    // SQLite keeps whatever a row was given: a number column holding text would read as 0
    const auto bad = [&](int col, const std::string& expected) {
      // (a store the user named whose rows are not the monitor's: bad input, exit 2)
      return PathError(fmt::format("{}: events row id {}: column '{}': expected {}, got '{}'", impl_->path, id,
                                   sqlite3_column_name(s, col), expected, text(col)));
    };
    const auto number = [&](int col) {
      const int t = sqlite3_column_type(s, col);
      if (t != SQLITE_FLOAT && t != SQLITE_INTEGER) throw bad(col, "a number");
      return sqlite3_column_double(s, col);
    };
    // a joint or link as the 0-based index in memory: from 1 with NULL for none (user_version 1),
    // or 0-based with -1 for none (a store from before session 17)
    const bool from_one = impl_->from_one;
    const auto index = [&](int col) {
      if (from_one && sqlite3_column_type(s, col) == SQLITE_NULL) return -1;
      if (sqlite3_column_type(s, col) != SQLITE_INTEGER)
        throw bad(col, from_one ? "a whole number or NULL" : "a whole number");
      const long v = sqlite3_column_int64(s, col);
      if (from_one ? v < 1 || v > 64 : v < -1 || v > 63)
        throw bad(col, from_one ? "a joint/link number 1 to 64, or NULL for none" : "-1 or a joint/link index 0 to 63");
      return static_cast<int>(from_one ? v - 1 : v);
    };
    Event e;
    e.open = false;
    e.t_start = number(2);
    e.t_end = number(3);
    e.t_detected = sqlite3_column_type(s, 13) == SQLITE_NULL ? e.t_start : number(13);
    e.joint = index(5);
    e.link = index(6);
    e.magnitude = number(7);
    e.units = text(8);
    e.confidence = number(9);
    e.peak_residual = number(10);
    e.detail = text(11);
    if (sqlite3_column_type(s, 18) != SQLITE_NULL) e.peak_residual_units = text(18);  // (NULL: a row from before session 54, A)
    // values the monitor never writes (a hand-edited row): printed as they were, 1e999 read "null"
    // and a confidence of 7 or an end before the start passed as findings
    if (!std::isfinite(e.t_start)) throw bad(2, "a finite time [s]");
    if (!(std::isfinite(e.t_end) && e.t_end >= e.t_start)) throw bad(3, fmt::format("a finite time [s] not before t_start ({:g})", e.t_start));
    if (!std::isfinite(e.t_detected)) throw bad(13, "a finite time [s]");
    if (!std::isfinite(e.magnitude)) throw bad(7, "a finite number");
    if (!(e.confidence >= 0.0 && e.confidence <= 1.0)) throw bad(9, "a confidence from 0 to 1");
    if (!std::isfinite(e.peak_residual)) throw bad(10, "a finite number");
    e.active_at_stop = sqlite3_column_type(s, 14) == SQLITE_INTEGER && sqlite3_column_int64(s, 14) != 0;
    if (sqlite3_column_type(s, 17) != SQLITE_NULL) {
      e.wall_offset = number(17);
      if (!std::isfinite(e.wall_offset)) throw bad(17, "a finite offset [s] or NULL");
    }
    try {
      e.fault = fault_class_from_string(text(4));
      const std::string others = text(12);
      if (!others.empty()) {
        try {
          e.other_links = nlohmann::json::parse(others).get<std::vector<int>>();
        } catch (const nlohmann::json::exception&) {
          throw std::runtime_error(fmt::format("column 'other_links': expected a list of link numbers such as [2, 3], got '{}'", others));
        }
      }
      for (int& l : e.other_links) {
        if (from_one ? l < 1 || l > 64 : l < 0 || l > 63)
          throw std::runtime_error(fmt::format("column 'other_links': expected link numbers {}, got '{}'",
                                               from_one ? "1 to 64" : "0 to 63", others));
        if (from_one) l -= 1;
      }
    } catch (const std::exception& x) {
      throw PathError(fmt::format("{}: events row id {}: {}", impl_->path, id, x.what()));
    }
    out.push_back({text(1), text(15), std::move(e), sqlite3_column_type(s, 16) == SQLITE_INTEGER ? static_cast<long>(sqlite3_column_int64(s, 16)) : 0L});
  }
  if (rc != SQLITE_DONE) throw std::runtime_error(fmt::format("{}: cannot read events: {}", impl_->path, sqlite3_errstr(rc)));
  return out;
}

}  // namespace twinwatch::monitor
