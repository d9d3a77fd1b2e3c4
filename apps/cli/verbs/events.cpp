// `twinwatch events`: the event history that `twinwatch monitor` keeps in its SQLite store.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "twinwatch/core/error.hpp"
#include "twinwatch/monitor/event.hpp"
#include "recordings.hpp"
#include "verb_registry.hpp"

namespace {

using namespace twinwatch;

struct EventsOptions {
  std::string db = "events.db";
  std::string fault;   // only this class ("" = all)
  std::string source;  // only events whose source contains this text
  int last = 0;        // only the newest N (0 = all)
  long run = 0;        // only this monitoring run (0 = all)
  bool json = false;
  bool runs = false;   // the monitoring runs instead of the events
  bool fault_given = false;  // --class '' (an unset variable) listed every class
};

// "3" or "3 (or 4)": the contact link and the one the joint torques cannot rule out (1-based)
std::string link_text(const monitor::Event& e) {
  if (e.link < 0) return "-";
  std::string s = std::to_string(e.link + 1);
  for (int l : e.other_links) s += fmt::format(" (or {})", l + 1);
  return s;
}

// A stored source as the table shows it: a file below the working directory relative to it (monitor
// stores absolute paths), anything else whole
std::string shown_source(const std::string& source) {
  if (source.rfind("rtde://", 0) == 0) return source;
  std::error_code ec;
  const std::filesystem::path p(source);
  if (p.is_absolute()) {
    const auto cwd = std::filesystem::current_path(ec);
    if (ec || cwd == cwd.root_path()) return source;
    const auto rel = std::filesystem::proximate(p, cwd, ec);
    if (!ec && !rel.empty() && *rel.begin() != "..") return rel.string();
  }
  return source;
}

// `s` cut from the left to `width` characters, so that the file name stays
std::string cut_left(const std::string& s, size_t width) {
  return s.size() > width ? "…" + s.substr(s.size() - (width - 1)) : s;
}

// `events --runs`: one line per monitoring run, the event-free ones included
void list_runs(const monitor::EventStore& store, const EventsOptions& o) {
  auto runs = store.read_runs();
  std::erase_if(runs, [&](const monitor::StoredRun& r) {
    return (!o.source.empty() && r.source.find(o.source) == std::string::npos) || (o.run > 0 && r.id != o.run);
  });
  if (o.last > 0 && runs.size() > static_cast<size_t>(o.last)) runs.erase(runs.begin(), runs.end() - o.last);
  const auto utc = [](const std::string& t) { return t.empty() ? nlohmann::json(nullptr) : nlohmann::json(t + " UTC"); };
  const auto count = [](long n) { return n < 0 ? nlohmann::json(nullptr) : nlohmann::json(n); };
  if (o.json) {
    for (const auto& r : runs)
      fmt::print("{}\n", nlohmann::json{{"run", r.id}, {"started_at", utc(r.started_at)}, {"ended_at", utc(r.ended_at)},
                                         {"source", r.source}, {"twin", r.twin},
                                         {"program", r.program.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.program)},
                                         {"samples", count(r.samples)}, {"events", count(r.events)},
                                         {"status", r.status.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.status)}}
                                .dump());
    return;
  }
  fmt::print("{:>4} {:<19} {:<19} {:>10} {:>6} {:<15} {}\n", "run", "started (UTC)", "ended (UTC)", "samples", "events", "status", "source");
  for (const auto& r : runs)
    fmt::print("{:>4} {:<19} {:<19} {:>10} {:>6} {:<15} {}{}\n", r.id, r.started_at, r.ended_at.empty() ? "-" : r.ended_at,
               r.samples < 0 ? "-" : std::to_string(r.samples), r.events < 0 ? "-" : std::to_string(r.events),
               // a run whose end is not on record: still running, or killed
               r.status.empty() ? "not ended" : r.status, shown_source(r.source), r.program.empty() ? "" : " (program " + r.program + ")");
  fmt::print("{} run(s) of {} stored in {}{}\n", runs.size(), store.read_runs().size(), o.db,
             std::any_of(runs.begin(), runs.end(), [](const monitor::StoredRun& r) { return r.status.empty(); })
                 ? " ('not ended': still running, or the monitor was killed before it could store the end)"
                 : "");
}

void run_events(const EventsOptions& o) {
  if (o.fault_given && o.fault.empty())
    throw InvalidArgument("--class is empty: give one of collision, resistance, payload_change, sensor_fault, stream_fault, wear, unknown");
  if (!o.fault.empty()) monitor::fault_class_from_string(o.fault);  // names the valid classes when unknown
  if (!std::filesystem::exists(o.db))
    throw InvalidArgument(fmt::format("{}: no such event store ('twinwatch monitor --db {}' writes one)", o.db, o.db));
  if (o.last < 0) throw InvalidArgument(fmt::format("--last is {}, must be >= 0", o.last));
  const monitor::EventStore store(o.db, monitor::EventStore::Mode::Read);
  // a run the store does not hold (it printed "0 event(s) of 4", as for a run without events: audit
  // of session 56)
  if (o.run > 0) {
    const auto runs = store.read_runs();
    if (std::none_of(runs.begin(), runs.end(), [&](const monitor::StoredRun& r) { return r.id == o.run; }))
      throw InvalidArgument(fmt::format("--run {}: {} holds no such run ({}; 'twinwatch events --db {} --runs' lists them)", o.run, o.db,
                                        runs.empty() ? std::string("it holds none")
                                                     : fmt::format("its runs are {} to {}", runs.front().id, runs.back().id),
                                        o.db));
  }
  if (o.runs) {
    if (!o.fault.empty()) throw InvalidArgument("--class filters events; --runs lists the monitoring runs: give one of them");
    list_runs(store, o);
    return;
  }
  auto rows = store.read();
  std::erase_if(rows, [&](const monitor::StoredEvent& r) {
    return (!o.fault.empty() && monitor::to_string(r.event.fault) != o.fault) ||
           (!o.source.empty() && r.source.find(o.source) == std::string::npos) || (o.run > 0 && r.run != o.run);
  });
  if (o.last > 0 && rows.size() > static_cast<size_t>(o.last)) rows.erase(rows.begin(), rows.end() - o.last);
  if (o.json) {
    for (const auto& [source, recorded_at, e, run] : rows) {
      nlohmann::json j = nlohmann::json::parse(e.to_json_line());
      j["source"] = source;
      j["run"] = run > 0 ? nlohmann::json(run) : nlohmann::json(nullptr);
      j["recorded_at"] = recorded_at.empty() ? nlohmann::json(nullptr) : nlohmann::json(recorded_at + " UTC");
      fmt::print("{}\n", j.dump());
    }
    return;
  }
  // (when it was stored: two runs of the same recording give the same rows otherwise)
  // the source column as wide as the longest source shown, up to kSourceWidth
  constexpr size_t kSourceWidth = 48;
  std::vector<std::string> shown;
  shown.reserve(rows.size());
  size_t width = 6;
  for (const auto& r : rows) {
    shown.push_back(shown_source(r.source));
    width = std::max(width, std::min(shown.back().size(), kSourceWidth));
  }
  // the wall-clock time of the start, a column where a row has one (a live robot's events, or a
  // recording watched with --started-at): "2026-12-03 19:02:11.234"
  const bool any_wall = std::any_of(rows.begin(), rows.end(), [](const monitor::StoredEvent& r) { return std::isfinite(r.event.wall_offset); });
  const auto wall_cell = [&](const monitor::Event& e) -> std::string {
    if (!any_wall) return "";
    std::string w = e.wall_time(e.t_start);
    if (w.empty()) return fmt::format("{:<23} ", "-");
    w[10] = ' ';
    w.pop_back();  // (the 'Z': the column says UTC)
    return w + " ";
  };
  fmt::print("{:<19} {:>4} {:<{}} {}{:>9} {:>8} {:<15} {:>5} {:>10} {:>12}  {}\n", "stored (UTC)", "run", "source", width,
             any_wall ? fmt::format("{:<23} ", "started (UTC)") : "", "t [s]", "dur ms", "class", "joint", "link", "magnitude", "detail");
  for (size_t k = 0; k < rows.size(); ++k) {
    const auto& [source, recorded_at, e, run] = rows[k];
    fmt::print("{:<19} {:>4} {:<{}} {}{:>9.3f} {:>8.0f} {:<15} {:>5} {:>10} {:>12}  {}\n", recorded_at.empty() ? "-" : recorded_at,
               run > 0 ? std::to_string(run) : "-", cut_left(shown[k], width), width, wall_cell(e), e.t_start, 1000.0 * e.duration(),
               monitor::to_string(e.fault), e.joint >= 0 ? fmt::format("J{}", e.joint + 1) : "-", link_text(e),
               cli::magnitude_text(e.magnitude, e.units), e.detail);
  }
  fmt::print("{} event(s) of {} stored in {}\n", rows.size(), store.count(), o.db);
}

twinwatch::cli::VerbRegistrar reg{"events", 44, [](CLI::App& app) {
  auto o = std::make_shared<EventsOptions>();
  auto* sub = app.add_subcommand("events", "List the events 'twinwatch monitor' stored (SQLite): class, joint, contact link, magnitude, detail");
  sub->add_option("--db", o->db, "Event store written by 'twinwatch monitor --db'")->capture_default_str();
  auto* cls = sub->add_option("--class", o->fault,
                  "Only this class: collision, resistance, payload_change, sensor_fault, stream_fault, wear, unknown");
  sub->add_option("--source", o->source, "Only events whose source contains this text (monitor stores a recording by its absolute path, a robot as rtde://HOST)");
  sub->add_option("--last", o->last, "Only the newest N events (0: all)")->capture_default_str();
  sub->add_option("--run", o->run, "Only the events of this monitoring run (the number 'monitor' prints with its summary; 0: all)")
      ->check(twinwatch::cli::whole_number(0, 1'000'000'000'000L))
      ->capture_default_str();
  sub->add_flag("--runs", o->runs, "List the monitoring runs instead (started, ended, samples, events, status, source), those without events "
                                   "included; --source, --run, --last and --json apply");
  sub->add_flag("--json", o->json, "One JSON object per line (the monitor's --events format, wall_start/wall_detected/wall_end included, plus \"source\", \"recorded_at\" and \"run\", null for rows from before runs were stored)");
  sub->footer(twinwatch::cli::with_exit_status(
      "A contact's link reads '3 (or 4)' when the joint torques cannot tell link 3 from link 4 (a force whose line\n"
      "passes near the contact link's own joint axis); --json gives it as \"other_links\". Joints and links are\n"
      "numbered from 1 everywhere (J5 is \"joint\": 5; none is null), as in the scenario labels. A store written\n"
      "before this numbering (0-based) is read as such and renumbered the next time 'twinwatch monitor' writes to it.\n"
      "An event's confidence is how likely its class and place are right: for a contact, the share of the residual\n"
      "its fit explains times the named link's probability (the detail's '% likely'); for the other classes, the\n"
      "share of the residual beyond the healthy noise before the alert that the diagnosis explains (of the whole\n"
      "residual where the twin has no momentum observer)."));
  sub->callback([o, cls] {
    o->fault_given = cls->count() > 0;
    run_events(*o);
  });
}};

}  // namespace
