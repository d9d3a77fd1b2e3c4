#include "twinwatch/monitor/event.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <thread>
#include <nlohmann/json.hpp>
#include <sqlite3.h>
#include <vector>

#include "twinwatch/core/error.hpp"

namespace twinwatch::monitor {
namespace {

// runs `sql` on the database at `path` as another SQLite client would (a store an older version or
// another program wrote, or a row edited by hand)
void run_sql(const std::filesystem::path& path, const char* sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.string().c_str(), &db), SQLITE_OK);
  EXPECT_EQ(sqlite3_exec(db, sql, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
  sqlite3_close(db);
}

// a raw value of the store, as another SQLite client sees it
std::string raw_cell(const std::filesystem::path& path, const char* sql) {
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open(path.string().c_str(), &db), SQLITE_OK);
  sqlite3_stmt* s = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(db, sql, -1, &s, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
  std::string out = "<no row>";
  if (sqlite3_step(s) == SQLITE_ROW) {
    const auto* t = reinterpret_cast<const char*>(sqlite3_column_text(s, 0));
    out = t ? t : "NULL";
  }
  sqlite3_finalize(s);
  sqlite3_close(db);
  return out;
}

TEST(Event, JsonLineCarriesClassJointMagnitudeAndDuration) {
  Event e;
  e.t_start = 8.5;
  e.t_end = 9.25;
  e.open = false;
  e.fault = FaultClass::PayloadChange;
  e.magnitude = -0.48;
  e.units = "kg";
  e.detail = "payload -0.48 kg";
  const auto j = nlohmann::json::parse(e.to_json_line());
  EXPECT_EQ(j["class"], "payload_change");
  EXPECT_DOUBLE_EQ(j["duration_s"].get<double>(), 0.75);
  EXPECT_DOUBLE_EQ(j["magnitude"].get<double>(), -0.48);
  EXPECT_EQ(e.to_json_line().find('\n'), std::string::npos);
  EXPECT_TRUE(j["other_links"].is_array());
  EXPECT_TRUE(j["other_links"].empty());
  // none is null, not -1
  EXPECT_TRUE(j["joint"].is_null());
  EXPECT_TRUE(j["link"].is_null());
  // a fault still there when monitoring stopped says so (session 22: "open" is false on every line)
  EXPECT_EQ(j["active_at_stop"], false);
  e.active_at_stop = true;
  EXPECT_EQ(nlohmann::json::parse(e.to_json_line())["active_at_stop"], true);
  // numbered from 1 as the labels: index 4 is J5 / link 5
  e.fault = FaultClass::Collision;
  e.joint = 3;
  e.link = 4;
  e.other_links = {5, 0};
  const auto c = nlohmann::json::parse(e.to_json_line());
  EXPECT_EQ(c["joint"], 4);
  EXPECT_EQ(c["link"], 5);
  EXPECT_EQ(c["other_links"], nlohmann::json::array({6, 1}));
}

// the wall clock (session 48): null where the source's is unknown, the three times in UTC where it is
TEST(Event, JsonLineCarriesWallClockTimesWhereTheSourcesClockIsKnown) {
  Event e;
  e.t_start = 54.31;
  e.t_detected = 54.312;
  e.t_end = 54.36;
  e.open = false;
  auto j = nlohmann::json::parse(e.to_json_line());
  for (const char* k : {"wall_start", "wall_detected", "wall_end"}) {
    ASSERT_TRUE(j.contains(k)) << k;
    EXPECT_TRUE(j[k].is_null()) << k;
  }
  EXPECT_EQ(e.wall_time(e.t_start), "");
  e.wall_offset = 1796324562.0 - 54.31;  // 2026-12-03T19:02:42Z at t_start
  j = nlohmann::json::parse(e.to_json_line());
  EXPECT_EQ(j["wall_start"], "2026-12-03T19:02:42.000Z");
  EXPECT_EQ(j["wall_detected"], "2026-12-03T19:02:42.002Z");
  EXPECT_EQ(j["wall_end"], "2026-12-03T19:02:42.050Z");
}

TEST(FaultClass, RoundTripsAndRejectsUnknownNames) {
  for (FaultClass c : {FaultClass::Collision, FaultClass::Resistance, FaultClass::PayloadChange, FaultClass::SensorFault,
                       FaultClass::StreamFault, FaultClass::Wear, FaultClass::Unknown})
    EXPECT_EQ(fault_class_from_string(to_string(c)), c);
  try {
    fault_class_from_string("earthquake");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("'earthquake' is unknown"));
  }
}

TEST(EventStore, PersistsEventsAcrossReopen) {
  const auto path = std::filesystem::temp_directory_path() / "twinwatch_event_store_test.db";
  std::filesystem::remove(path);
  {
    EventStore store(path.string());
    Event e;
    e.fault = FaultClass::Collision;
    e.t_start = 7.25;
    e.t_end = 7.31;
    e.joint = e.link = 4;
    e.other_links = {3};
    e.magnitude = 61.5;
    e.units = "N";
    e.detail = "contact on link 5";
    store.insert(e, "rec.csv");
    e.fault = FaultClass::PayloadChange;
    e.link = -1;
    e.other_links.clear();
    e.active_at_stop = true;
    e.wall_offset = 1796324562.0 - 7.25;  // a live robot's: Unix time − controller time
    e.peak_residual_units = "N·m";  // (a twin of joint torque sensors)
    store.insert(e, "robot 10.0.0.2");
    EXPECT_EQ(store.count(), 2);
  }
  EventStore again(path.string());
  EXPECT_EQ(again.count(), 2);
  const auto rows = again.read();
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].source, "rec.csv");
  EXPECT_EQ(rows[0].event.fault, FaultClass::Collision);
  EXPECT_DOUBLE_EQ(rows[0].event.t_start, 7.25);
  EXPECT_DOUBLE_EQ(rows[0].event.t_end, 7.31);
  EXPECT_EQ(rows[0].event.link, 4);
  EXPECT_EQ(rows[0].event.other_links, std::vector<int>{3});
  EXPECT_DOUBLE_EQ(rows[0].event.magnitude, 61.5);
  EXPECT_EQ(rows[0].event.units, "N");
  EXPECT_EQ(rows[0].event.detail, "contact on link 5");
  EXPECT_EQ(rows[1].source, "robot 10.0.0.2");
  EXPECT_EQ(rows[1].event.fault, FaultClass::PayloadChange);
  EXPECT_TRUE(rows[1].event.other_links.empty());
  EXPECT_FALSE(rows[0].event.active_at_stop);
  EXPECT_TRUE(rows[1].event.active_at_stop);
  EXPECT_EQ(rows[0].event.peak_residual_units, "A");
  EXPECT_EQ(rows[1].event.peak_residual_units, "N·m");
  // the wall clock where it was known, and the start's wall time for a reader of the table
  EXPECT_TRUE(std::isnan(rows[0].event.wall_offset));
  EXPECT_DOUBLE_EQ(rows[1].event.wall_offset, 1796324562.0 - 7.25);
  EXPECT_EQ(raw_cell(path, "SELECT wall_start FROM events WHERE id = 1"), "NULL");
  EXPECT_EQ(raw_cell(path, "SELECT wall_start FROM events WHERE id = 2"), "2026-12-03T19:02:42.000Z");
  // when each was stored (two runs of the same file are told apart by it)
  EXPECT_THAT(rows[0].recorded_at, ::testing::MatchesRegex("[0-9]{4}-[0-9]{2}-[0-9]{2} [0-9]{2}:[0-9]{2}:[0-9]{2}"));
  std::filesystem::remove(path);
}

// review of session 18: while another connection held the lock (a second monitor, 'twinwatch
// events' mid-read), an insert failed at once with "database is locked" and stopped the monitor
TEST(EventStore, AnInsertWaitsForAnotherConnectionsLock) {
  const auto path = std::filesystem::temp_directory_path() / "twinwatch_event_store_lock_test.db";
  std::filesystem::remove(path);
  EventStore store(path.string());
  sqlite3* other = nullptr;
  ASSERT_EQ(sqlite3_open(path.string().c_str(), &other), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(other, "BEGIN IMMEDIATE;", nullptr, nullptr, nullptr), SQLITE_OK);  // holds the write lock
  std::thread release([other] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    sqlite3_exec(other, "COMMIT;", nullptr, nullptr, nullptr);
  });
  Event e;
  e.fault = FaultClass::Collision;
  e.detail = "contact on link 3";
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_NO_THROW(store.insert(e, "live"));
  const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  release.join();
  sqlite3_close(other);
  EXPECT_EQ(store.count(), 1);
  EXPECT_GT(waited, 0.2) << "the insert went through while the lock was held";
  std::filesystem::remove(path);
}

// two monitoring runs into one store are told apart (review, session 47: their rows were alike but
// for the storage time); the run's row is written when the run begins, so that a run without events
// is on record too (review, session 49), and ends with its samples, events and status. While another
// connection holds a reader's transaction the row is not waited for at the start (a live monitor
// must not stall there): it waits with the first event, or for the run's end.
TEST(EventStore, EachRunHasItsRowFromItsStartAndItsEventsCarryItsNumber) {
  const auto path = std::filesystem::temp_directory_path() / "twinwatch_event_store_runs_test.db";
  std::filesystem::remove(path);
  Event e;
  e.fault = FaultClass::Collision;
  e.detail = "contact on link 3";
  const auto hold_reader_lock = [&](sqlite3** other) {
    ASSERT_EQ(sqlite3_open(path.string().c_str(), other), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(*other, "BEGIN; SELECT count(*) FROM events;", nullptr, nullptr, nullptr), SQLITE_OK);
  };
  const auto release = [](sqlite3* other) {
    sqlite3_exec(other, "COMMIT;", nullptr, nullptr, nullptr);
    sqlite3_close(other);
  };
  {
    EventStore store(path.string());
    store.insert(e, "before.csv");  // (no run begun: NULL)
    EXPECT_THROW(store.end_run({}, 0), std::logic_error);
    store.begin_run("rec.csv", "twin.json", "");
    EXPECT_EQ(store.run(), 1) << "a free store gets the run's row at once";
    store.insert(e, "rec.csv");
    store.insert(e, "rec.csv");
    EXPECT_TRUE(store.end_run({25000, 2, "finished"}, 50));
  }
  {
    EventStore store(path.string());
    sqlite3* other = nullptr;
    hold_reader_lock(&other);
    const auto t0 = std::chrono::steady_clock::now();
    store.begin_run("rec.csv", "twin.json", "pick_place");
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0) << "begin_run waited for the lock";
    EXPECT_EQ(store.run(), 0);
    EXPECT_FALSE(store.try_insert(e, "rec.csv", 50));  // locked: neither the run's row nor the event
    EXPECT_EQ(store.run(), 0);
    release(other);
    EXPECT_TRUE(store.try_insert(e, "rec.csv", 50));
    EXPECT_EQ(store.run(), 2);
    EXPECT_TRUE(store.end_run({500, 1, "stopped"}, 50));
  }
  {
    // a run without events, begun and ended while the store is locked: its row waits for the lock
    EventStore store(path.string());
    sqlite3* other = nullptr;
    hold_reader_lock(&other);
    store.begin_run("rtde://10.0.0.7", "twin.json", "");
    EXPECT_FALSE(store.end_run({120000, 0, "connection lost"}, 50));
    EXPECT_EQ(store.run(), 0);
    release(other);
    EXPECT_TRUE(store.end_run({120000, 0, "connection lost"}, 50));
    EXPECT_EQ(store.run(), 3);
  }
  {
    EventStore store(path.string());
    store.begin_run("killed.csv", "twin.json", "");  // (the monitor never ended it)
  }
  const EventStore reader(path.string(), EventStore::Mode::Read);
  const auto rows = reader.read();
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].run, 0);
  EXPECT_EQ(rows[1].run, 1);
  EXPECT_EQ(rows[2].run, 1);
  EXPECT_EQ(rows[3].run, 2);
  const auto runs = reader.read_runs();
  ASSERT_EQ(runs.size(), 4u) << "(the attempts that were locked left no row)";
  EXPECT_EQ(runs[0].id, 1);
  EXPECT_EQ(runs[0].source, "rec.csv");
  EXPECT_EQ(runs[0].twin, "twin.json");
  EXPECT_EQ(runs[0].program, "");
  EXPECT_EQ(runs[0].samples, 25000);
  EXPECT_EQ(runs[0].events, 2);
  EXPECT_EQ(runs[0].status, "finished");
  EXPECT_EQ(runs[0].started_at.size(), 19u);
  EXPECT_GE(runs[0].ended_at, runs[0].started_at);
  EXPECT_EQ(runs[1].program, "pick_place");
  EXPECT_EQ(runs[1].status, "stopped");
  EXPECT_EQ(runs[2].source, "rtde://10.0.0.7");
  EXPECT_EQ(runs[2].events, 0);
  EXPECT_EQ(runs[2].samples, 120000);
  EXPECT_EQ(runs[2].status, "connection lost");
  EXPECT_EQ(runs[3].source, "killed.csv");
  EXPECT_EQ(runs[3].ended_at, "");
  EXPECT_EQ(runs[3].samples, -1);
  EXPECT_EQ(runs[3].status, "");
  std::filesystem::remove(path);
}

// a runs table of sessions 47-49 (no ended_at, samples, events, status) gains the columns, its rows
// read as not ended; a count that is no whole number is named with its row and column
TEST(EventStore, AnOlderRunsTableGainsHowARunEnded) {
  const auto path = std::filesystem::temp_directory_path() / "twinwatch_event_store_old_runs.db";
  std::filesystem::remove(path);
  run_sql(path,
          "CREATE TABLE events (id INTEGER PRIMARY KEY AUTOINCREMENT, source TEXT, t_start REAL, t_end REAL, duration_s REAL,"
          " class TEXT, joint INTEGER, link INTEGER, magnitude REAL, units TEXT, confidence REAL,"
          " peak_residual REAL, detail TEXT, recorded_at TEXT DEFAULT CURRENT_TIMESTAMP, other_links TEXT, t_detected REAL,"
          " active_at_stop INTEGER, run INTEGER, wall_offset REAL, wall_start TEXT);"
          "CREATE TABLE runs (id INTEGER PRIMARY KEY AUTOINCREMENT, started_at TEXT DEFAULT CURRENT_TIMESTAMP,"
          " source TEXT, twin TEXT, program TEXT);"
          "INSERT INTO runs (source, twin, program) VALUES ('old.csv', 'twin.json', NULL);"
          "PRAGMA user_version = 1;");
  {
    const EventStore reader(path.string(), EventStore::Mode::Read);  // (read-only: nothing added)
    const auto runs = reader.read_runs();
    ASSERT_EQ(runs.size(), 1u);
    EXPECT_EQ(runs[0].source, "old.csv");
    EXPECT_EQ(runs[0].samples, -1);
  }
  {
    EventStore store(path.string());
    store.begin_run("new.csv", "twin.json", "");
    EXPECT_EQ(store.run(), 2);
    EXPECT_TRUE(store.end_run({10, 0, "finished"}, 50));
    const auto runs = store.read_runs();
    ASSERT_EQ(runs.size(), 2u);
    EXPECT_EQ(runs[0].ended_at, "");
    EXPECT_EQ(runs[1].samples, 10);
    EXPECT_EQ(runs[1].status, "finished");
  }
  run_sql(path, "UPDATE runs SET samples = 'many' WHERE id = 1;");
  const EventStore reader(path.string(), EventStore::Mode::Read);
  EXPECT_THAT([&] { reader.read_runs(); },
              ::testing::ThrowsMessage<std::runtime_error>(::testing::HasSubstr("runs row 1: column 'samples' holds 'many', expected a whole number")));
  std::filesystem::remove(path);
}

// a store written before other_links existed (the session-9 schema) opens, keeps its rows, gains
// the column, and takes new events with it; a row that cannot be read back names the file and row
TEST(EventStore, AnOlderTableGainsTheOtherLinksColumnAndKeepsItsRows) {
  const auto path = std::filesystem::temp_directory_path() / "twinwatch_event_store_old.db";
  std::filesystem::remove(path);
  {
    const char* old_schema =
        "CREATE TABLE events (id INTEGER PRIMARY KEY AUTOINCREMENT, source TEXT, t_start REAL, t_end REAL, duration_s REAL,"
        " class TEXT, joint INTEGER, link INTEGER, magnitude REAL, units TEXT, confidence REAL,"
        " peak_residual REAL, detail TEXT, recorded_at TEXT DEFAULT CURRENT_TIMESTAMP);"
        "INSERT INTO events (source, t_start, t_end, duration_s, class, joint, link, magnitude, units, confidence,"
        " peak_residual, detail) VALUES ('old.csv', 1.0, 1.05, 0.05, 'collision', 2, 2, 40.0, 'N', 0.9, 1.2, 'old');";
    run_sql(path, old_schema);
  }
  {
    EventStore store(path.string());
    EXPECT_EQ(store.count(), 1);
    Event e;
    e.fault = FaultClass::Collision;
    e.link = 5;
    e.other_links = {4};
    store.insert(e, "new.csv");
    const auto rows = store.read();
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_EQ(rows[0].source, "old.csv");
    EXPECT_EQ(rows[0].event.link, 2);
    EXPECT_TRUE(rows[0].event.other_links.empty());
    EXPECT_EQ(rows[0].event.peak_residual_units, "A");  // (the column added, its old rows NULL: the currents')
    EXPECT_EQ(rows[1].event.other_links, std::vector<int>{4});
  }
  {
    run_sql(path, "UPDATE events SET other_links = '[4,' WHERE source = 'new.csv';");
  }
  EventStore store(path.string());
  try {
    store.read();
    FAIL() << "a malformed other_links was read";
  } catch (const std::runtime_error& x) {
    EXPECT_THAT(x.what(), ::testing::HasSubstr(path.string()));
    EXPECT_THAT(x.what(), ::testing::HasSubstr("row id 2"));
  }
  std::filesystem::remove(path);
}

// audit of session 16: `twinwatch events --db other.db` created an events table in the user's
// database, a text in a number column read as 0, and t_detected read back as t_start
TEST(EventStore, ReadingChangesNothingAndRefusesWhatIsNotAnEventStore) {
  const auto dir = std::filesystem::temp_directory_path();
  const auto other = dir / "twinwatch_not_an_event_store.db";
  std::filesystem::remove(other);
  {
    run_sql(other, "CREATE TABLE parts (id INTEGER);");
  }
  try {
    EventStore store(other.string(), EventStore::Mode::Read);
    FAIL() << "a database without an events table opened";
  } catch (const std::runtime_error& x) {
    EXPECT_THAT(x.what(), ::testing::HasSubstr(other.string() + ": not an event store: it has no events table"));
  }
  EXPECT_EQ(raw_cell(other, "SELECT COUNT(*) FROM sqlite_master WHERE name = 'events';"), "0") << "reading created a table";
  EXPECT_THROW(EventStore((dir / "twinwatch_no_such_store.db").string(), EventStore::Mode::Read), std::runtime_error);
  EXPECT_FALSE(std::filesystem::exists(dir / "twinwatch_no_such_store.db"));
  std::filesystem::remove(other);

  const auto path = dir / "twinwatch_event_store_typed.db";
  std::filesystem::remove(path);
  {
    EventStore store(path.string());
    Event e;
    e.t_start = 12.102;
    e.t_detected = 12.104;
    e.t_end = 40.0;
    e.fault = FaultClass::Resistance;
    e.joint = 4;
    store.insert(e, "j5.csv");
  }
  {
    const EventStore store(path.string(), EventStore::Mode::Read);
    const auto rows = store.read();
    ASSERT_EQ(rows.size(), 1u);
    EXPECT_DOUBLE_EQ(rows[0].event.t_detected, 12.104);
    EXPECT_DOUBLE_EQ(rows[0].event.t_start, 12.102);
  }
  {
    run_sql(path, "UPDATE events SET t_start = 'abc';");
  }
  try {
    EventStore(path.string(), EventStore::Mode::Read).read();
    FAIL() << "a text t_start was read";
  } catch (const std::runtime_error& x) {
    EXPECT_THAT(x.what(), ::testing::HasSubstr("events row id 1: column 't_start': expected a number, got 'abc'"));
  }
  std::filesystem::remove(path);
}

TEST(EventStore, UnopenablePathNamesTheFile) {
  try {
    EventStore store("/nonexistent-dir/events.db");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("/nonexistent-dir/events.db"));
  }
}


// the store keeps what the JSON lines say: joints and links from 1, NULL for none, user_version 1
TEST(EventStore, NumbersJointsAndLinksFromOneAsTheJsonLines) {
  const auto path = std::filesystem::temp_directory_path() / "twinwatch_event_store_numbering.db";
  std::filesystem::remove(path);
  {
    EventStore store(path.string());
    Event e;
    e.fault = FaultClass::Collision;
    e.joint = 2;
    e.link = 4;
    e.other_links = {3};
    store.insert(e, "a.csv");
    e.fault = FaultClass::PayloadChange;
    e.joint = e.link = -1;
    e.other_links.clear();
    store.insert(e, "b.csv");
  }
  EXPECT_EQ(raw_cell(path, "PRAGMA user_version;"), "1");
  EXPECT_EQ(raw_cell(path, "SELECT joint || ',' || link || ',' || other_links FROM events WHERE id = 1;"), "3,5,[4]");
  EXPECT_EQ(raw_cell(path, "SELECT typeof(joint) || ',' || typeof(link) FROM events WHERE id = 2;"), "null,null");
  const auto rows = EventStore(path.string(), EventStore::Mode::Read).read();
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].event.joint, 2);
  EXPECT_EQ(rows[0].event.link, 4);
  EXPECT_EQ(rows[0].event.other_links, std::vector<int>{3});
  EXPECT_EQ(rows[1].event.joint, -1);
  EXPECT_EQ(rows[1].event.link, -1);
  std::filesystem::remove(path);
}

// a store from before session 17 (0-based, -1 for none, user_version 0): read as it is, changed
// by nothing that only reads it, renumbered in place when the monitor writes to it again; a store
// from a newer numbering is refused by name
TEST(EventStore, AZeroBasedStoreIsReadAsSuchAndRenumberedWhenWritten) {
  const auto path = std::filesystem::temp_directory_path() / "twinwatch_event_store_zero_based.db";
  std::filesystem::remove(path);
  {
    const char* old =
        "CREATE TABLE events (id INTEGER PRIMARY KEY AUTOINCREMENT, source TEXT, t_start REAL, t_end REAL, duration_s REAL,"
        " class TEXT, joint INTEGER, link INTEGER, magnitude REAL, units TEXT, confidence REAL,"
        " peak_residual REAL, detail TEXT, recorded_at TEXT DEFAULT CURRENT_TIMESTAMP, other_links TEXT, t_detected REAL);"
        "INSERT INTO events (source, t_start, t_end, duration_s, class, joint, link, magnitude, units, confidence,"
        " peak_residual, detail, other_links, t_detected) VALUES"
        " ('old.csv', 1.0, 1.05, 0.05, 'collision', 2, 4, 40.0, 'N', 0.9, 1.2, 'contact on link 5', '[3]', 1.01),"
        " ('old.csv', 2.0, 2.5, 0.5, 'payload_change', -1, -1, -0.5, 'kg', 0.9, 1.2, 'payload', '[]', 2.05),"
        " ('old.csv', 3.0, 3.5, 0.5, 'resistance', 0, -1, 0.8, 'N·m', 0.9, 1.2, 'extra friction on J1', '[]', 3.1);";
    run_sql(path, old);
  }
  const auto check = [](const std::vector<StoredEvent>& rows) {
    ASSERT_GE(rows.size(), 3u);
    EXPECT_EQ(rows[0].event.joint, 2);
    EXPECT_EQ(rows[0].event.link, 4);
    EXPECT_EQ(rows[0].event.other_links, std::vector<int>{3});
    EXPECT_EQ(rows[1].event.joint, -1);
    EXPECT_EQ(rows[1].event.link, -1);
    EXPECT_EQ(rows[2].event.joint, 0);
    EXPECT_EQ(rows[2].event.link, -1);
  };
  check(EventStore(path.string(), EventStore::Mode::Read).read());
  EXPECT_EQ(raw_cell(path, "PRAGMA user_version;"), "0");  // reading changed nothing
  EXPECT_EQ(raw_cell(path, "SELECT joint FROM events WHERE id = 1;"), "2");
  {
    EventStore store(path.string());
    Event e;
    e.fault = FaultClass::Collision;
    e.joint = e.link = 1;
    store.insert(e, "new.csv");
    const auto rows = store.read();
    ASSERT_EQ(rows.size(), 4u);
    check(rows);
    EXPECT_EQ(rows[3].event.link, 1);
  }
  EXPECT_EQ(raw_cell(path, "PRAGMA user_version;"), "1");
  EXPECT_EQ(raw_cell(path, "SELECT joint || ',' || link || ',' || other_links FROM events WHERE id = 1;"), "3,5,[4]");
  EXPECT_EQ(raw_cell(path, "SELECT typeof(joint) || ',' || typeof(link) FROM events WHERE id = 2;"), "null,null");
  EXPECT_EQ(raw_cell(path, "SELECT joint || ',' || typeof(link) FROM events WHERE id = 3;"), "1,null");
  EXPECT_EQ(raw_cell(path, "SELECT link FROM events WHERE id = 4;"), "2");
  check(EventStore(path.string(), EventStore::Mode::Read).read());  // opened again: not shifted twice
  check(EventStore(path.string()).read());
  {
    run_sql(path, "PRAGMA user_version = 7;");
  }
  for (const auto mode : {EventStore::Mode::Read, EventStore::Mode::Write}) {
    try {
      EventStore store(path.string(), mode);
      ADD_FAILURE() << "a store from a newer numbering was opened";
    } catch (const std::runtime_error& x) {
      EXPECT_THAT(x.what(), ::testing::HasSubstr(path.string()));
      EXPECT_THAT(x.what(), ::testing::HasSubstr("user_version 7"));
    }
  }
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace twinwatch::monitor
