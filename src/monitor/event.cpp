#include "twinwatch/monitor/event.hpp"

#include <fmt/format.h>
#include <sqlite3.h>

#include <array>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "twinwatch/core/error.hpp"

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

std::string Event::to_json_line() const {
  nlohmann::json j;
  j["t_start"] = t_start;
  j["t_end"] = t_end;
  j["t_detected"] = t_detected;
  j["duration_s"] = duration();
  j["open"] = open;
  j["class"] = std::string(to_string(fault));
  j["joint"] = joint;
  j["link"] = link;
  j["other_links"] = other_links;
  j["magnitude"] = magnitude;
  j["units"] = units;
  j["confidence"] = confidence;
  j["peak_residual"] = peak_residual;
  j["detail"] = detail;
  return j.dump();
}

struct EventStore::Impl {
  sqlite3* db = nullptr;
  sqlite3_stmt* insert = nullptr;
  std::string path;
};

EventStore::EventStore(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  if (sqlite3_open(path.c_str(), &impl_->db) != SQLITE_OK) {
    const std::string msg = impl_->db ? sqlite3_errmsg(impl_->db) : "out of memory";
    sqlite3_close(impl_->db);
    impl_->db = nullptr;
    throw std::runtime_error(fmt::format("{}: cannot open event store: {}", path, msg));
  }
  const char* schema =
      "CREATE TABLE IF NOT EXISTS events ("
      " id INTEGER PRIMARY KEY AUTOINCREMENT, source TEXT, t_start REAL, t_end REAL, duration_s REAL,"
      " class TEXT, joint INTEGER, link INTEGER, magnitude REAL, units TEXT, confidence REAL,"
      " peak_residual REAL, detail TEXT, recorded_at TEXT DEFAULT CURRENT_TIMESTAMP);";
  char* err = nullptr;
  if (sqlite3_exec(impl_->db, schema, nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    sqlite3_close(impl_->db);
    impl_->db = nullptr;
    throw std::runtime_error(fmt::format("{}: cannot create the events table: {}", path, msg));
  }
  const char* ins =
      "INSERT INTO events (source, t_start, t_end, duration_s, class, joint, link, magnitude, units, confidence,"
      " peak_residual, detail) VALUES (?,?,?,?,?,?,?,?,?,?,?,?);";
  if (sqlite3_prepare_v2(impl_->db, ins, -1, &impl_->insert, nullptr) != SQLITE_OK) {
    const std::string msg = sqlite3_errmsg(impl_->db);
    sqlite3_close(impl_->db);
    impl_->db = nullptr;
    throw std::runtime_error(fmt::format("{}: cannot prepare insert: {}", path, msg));
  }
}

EventStore::~EventStore() {
  if (impl_->insert) sqlite3_finalize(impl_->insert);
  if (impl_->db) sqlite3_close(impl_->db);
}

void EventStore::insert(const Event& e, const std::string& source) {
  sqlite3_stmt* s = impl_->insert;
  sqlite3_reset(s);
  sqlite3_bind_text(s, 1, source.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_double(s, 2, e.t_start);
  sqlite3_bind_double(s, 3, e.t_end);
  sqlite3_bind_double(s, 4, e.duration());
  const std::string cls(to_string(e.fault));
  sqlite3_bind_text(s, 5, cls.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_int(s, 6, e.joint);
  sqlite3_bind_int(s, 7, e.link);
  sqlite3_bind_double(s, 8, e.magnitude);
  sqlite3_bind_text(s, 9, e.units.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_double(s, 10, e.confidence);
  sqlite3_bind_double(s, 11, e.peak_residual);
  sqlite3_bind_text(s, 12, e.detail.c_str(), -1, SQLITE_TRANSIENT);
  if (sqlite3_step(s) != SQLITE_DONE)
    throw std::runtime_error(fmt::format("{}: cannot insert event: {}", impl_->path, sqlite3_errmsg(impl_->db)));
}

long EventStore::count() const {
  sqlite3_stmt* s = nullptr;
  sqlite3_prepare_v2(impl_->db, "SELECT COUNT(*) FROM events;", -1, &s, nullptr);
  long n = 0;
  if (sqlite3_step(s) == SQLITE_ROW) n = sqlite3_column_int64(s, 0);
  sqlite3_finalize(s);
  return n;
}

}  // namespace twinwatch::monitor
