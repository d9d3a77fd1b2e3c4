// `twinwatch monitor` and `twinwatch thresholds`: the condition-monitoring loop on recordings and
// live streams, and threshold re-learning (evaluate and report: verbs/evaluate.cpp).
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <exception>
#include <functional>
#include <filesystem>
#include <cerrno>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <nlohmann/json.hpp>

#include "twinwatch/core/file_io.hpp"
#include "twinwatch/core/error.hpp"
#include "twinwatch/core/log.hpp"
#include "twinwatch/core/wall_clock.hpp"
#include "twinwatch/device/recording.hpp"
#include "twinwatch/ident/physics_ident.hpp"
#include "twinwatch/monitor/envelope.hpp"
#include "twinwatch/monitor/monitor.hpp"
#include "twinwatch/device/rtde_client.hpp"
#include "rtde_source.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "twinwatch/ui/html_report.hpp"
#include "evaluate.hpp"
#include "recordings.hpp"
#include "monitor_run.hpp"
#include "verb_registry.hpp"

namespace {

// The path a recording's events are stored under: absolute and normalised (symbolic links resolved
// where the file exists), so that one file is one source whatever path it was given by
std::string stored_path(const std::string& file) {
  std::error_code ec;
  const auto absolute = std::filesystem::absolute(file, ec);
  if (ec) return file;
  const auto p = std::filesystem::weakly_canonical(absolute, ec);
  return ec ? absolute.lexically_normal().string() : p.string();
}

using namespace twinwatch;

// Before a long check of a recording (7 s per hour of 500 Hz CSV) the user is told what is read:
// "checking shift.000.csv (1.73 GB) ..." on stderr, for a file of 100 MB and more.
void say_checking(const std::string& path) {
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(path, ec);
  if (!ec && bytes >= 100'000'000) fmt::print(stderr, "checking {} ({:.2f} GB) ...\n", path, static_cast<double>(bytes) / 1e9);
}

using cli::MonitorOptions;
using cli::MonitorHooks;
using cli::apply_alert_settings;
using cli::config_of;
using cli::kColumnMapHelp;
using cli::kFilterHelp;
using cli::kObserverRaiseAfterHelp;
using cli::kProgramNameGiven;
using cli::kRaiseAfterHelp;
using cli::kSensitivityHelp;
using cli::split_filter;

// a replay stopped at the user's request (MonitorHooks::stop_requested under serve; a signal under monitor)
struct ReplayStopped {};

// `path` with every "{start}" replaced by this run's start on this machine's clock, in UTC without
// separators (20261208T031500Z): --record and --events of a service that systemd starts again write
// new files instead of replacing the last run's (audit of session 57)
std::string with_start_time(const std::string& path, double unix_now) {
  static const std::string kField = "{start}";
  if (path.find(kField) == std::string::npos) return path;
  std::string stamp;
  for (const char c : iso_utc(std::floor(unix_now)).substr(0, 19))  // 2026-12-08T03:15:00
    if (c != '-' && c != ':') stamp += c;
  stamp += 'Z';
  std::string out = path;
  for (size_t at = out.find(kField); at != std::string::npos; at = out.find(kField, at + stamp.size()))
    out.replace(at, kField.size(), stamp);
  return out;
}

int run_monitor_impl(const MonitorOptions& given, const MonitorHooks& hooks) {
  const MonitorOptions o = [&] {
    MonitorOptions c = given;
    const double now = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
    c.record_to = with_start_time(c.record_to, now);
    c.events_path = with_start_time(c.events_path, now);
    return c;
  }();
  if (o.quiet) log::set_level(log::Level::Warn);  // "print nothing": no info lines either (warnings still show)
  // (checked before anything is read)
  const double started_at = o.started_at.empty() ? std::numeric_limits<double>::quiet_NaN() : parse_iso_time(o.started_at, "--started-at");
  ident::TwinModel twin = cli::load_twin(o.twin);
  // the declared payload is checked before anything is read or connected
  twin.set_payload(cli::payload_for(twin, o.twin, o.payload_mass, o.payload_com));
  monitor::MonitorConfig cfg = config_of(twin, o.twin);
  if (o.static_threshold) cfg.use_dynamic = false;
  cfg.follow_payload = !o.keep_payload;
  cli::apply_part_com(cfg, o.part_com);
  if (twin.payload().mass > 0.0 && cfg.part_com != monitor::MonitorConfig::default_part_com() && !o.quiet && !o.json)
    fmt::print(stderr, "note: the twin holds a {:.2f} kg payload: a payload change is fitted at its centre of mass; the part's point ({:g}, {:g}, {:g}) m "
                       "({}) applies once it holds none\n",
               twin.payload().mass, cfg.part_com.x(), cfg.part_com.y(), cfg.part_com.z(), o.part_com.empty() ? "the twin's part_com_m" : "--part-com");
  cfg.select_program(o.program);
  if (!o.quiet && !o.json && !cfg.programs.empty())
    fmt::print(stderr, "thresholds: {}\n",
               o.program.empty() ? fmt::format("the default set ({} has sets for {} program(s); choose one with --program)", o.twin,
                                               cfg.programs.size())
                                 : fmt::format("learned for program '{}'", o.program));
  if (!o.filter.empty()) {
    const auto learned = cfg.residual_filter;
    cfg.residual_filter = split_filter(o.filter);
    cfg.validate(twin.n_dof());
    // compare per joint: empty means "iir" everywhere, one entry means that kind everywhere
    const auto per_joint = [n = static_cast<size_t>(twin.n_dof())](const std::vector<std::string>& v) {
      std::vector<std::string> out(n, v.empty() ? "iir" : v.front());
      if (v.size() == n) out = v;
      return out;
    };
    if (per_joint(cfg.residual_filter) != per_joint(learned) && !o.quiet && !o.json)
      fmt::print(stderr, "note: the thresholds in {} were learned with residual filter '{}'; re-learn them with "
                         "'twinwatch thresholds --filter {}' for this filter\n",
                 o.twin, learned.empty() ? "iir" : fmt::format("{}", fmt::join(learned, ",")), o.filter);
  }
  if (o.cycle_period > 0) cfg.trend.cycle_period = o.cycle_period;
  apply_alert_settings(cfg, twin.n_dof(), o.sensitivity, o.raise_after, o.observer_raise_after);
  if (!o.quiet && !o.json && cfg.observer_alerts && cfg.observer_raise_after == 0 && !cfg.observer_choice.raise_after.empty())
    fmt::print(stderr, "observer debounce per joint: {} sample(s) (chosen on healthy validation runs; --observer-raise-after N "
                       "sets one count for all)\n",
               fmt::join(cfg.observer_choice.raise_after, " "));
  if (o.recordings.empty() == o.rtde.empty())
    throw InvalidArgument("give either RECORDING(s) or --rtde HOST[:PORT] (exactly one input)");
  cli::require_distinct(o.recordings, "RECORDING");
  std::unique_ptr<device::rtde::Client> client;
  // a file is stored by its absolute path: `events` then tells one file given as j5.csv and as
  // ./logs/../j5.csv for what it is, and two files of one name in two folders apart. Of several
  // files watched as one stream, an event is stored under the one it started in.
  std::vector<std::pair<double, std::string>> sources;  // (first timestamp, stored path) per file, in order
  if (!o.rtde.empty()) sources.push_back({-std::numeric_limits<double>::infinity(), "rtde://" + o.rtde});
  const auto source_of = [&](const monitor::Event& e) -> const std::string& {
    size_t i = 0;
    while (i + 1 < sources.size() && sources[i + 1].first <= e.t_start) ++i;
    return sources[i].second;
  };
  std::vector<std::string> inputs = o.recordings;
  inputs.push_back(o.twin);
  inputs.push_back(o.column_map);
  // the residual filter and the acceleration estimate run at the data's rate; thresholds learned
  // at another one do not fit them (a 1 kHz log against a 500 Hz set is filtered differently)
  const auto use_rate = [&](double period, const std::string& what) {
    if (std::abs(period / cfg.nominal_period - 1.0) > 0.05)
      log::warn(fmt::format("{} runs at {:.0f} Hz and the thresholds were learned at {:.0f} Hz: they may not fit; learn a set at this "
                            "rate ('twinwatch thresholds --twin {} HEALTHY.csv...')",
                            what, 1.0 / period, 1.0 / cfg.nominal_period, o.twin));
    cfg.nominal_period = period;
  };
  // every output path is checked before the robot is connected (or the recording read): a typo
  // found after a long --wait or the first samples of a live run costs the run
  cli::check_split_every(o.split_every);
  // (with --split-every, --record's first file is rec.000.csv)
  const std::string record_first = o.record_to.empty() ? o.record_to : device::SplitRecordingWriter::first_file(o.record_to, o.split_every);
  for (const std::string* out : {&o.events_path, &o.trace, &record_first, &o.db_path})
    if (!out->empty()) require_output(*out, inputs);
  // nor one output another's file: events over the trace's rows, a store that is a JSON-lines file
  const std::pair<const char*, const std::string*> outs[] = {
      {"--events", &o.events_path}, {"--trace", &o.trace}, {"--record", &record_first}, {"--db", &o.db_path}};
  for (size_t a = 0; a < std::size(outs); ++a)
    for (size_t b = a + 1; b < std::size(outs); ++b)
      if (!outs[a].second->empty() && !outs[b].second->empty() && same_file(*outs[a].second, *outs[b].second))
        throw PathError(fmt::format("{} and {} name the same file {}: each writes its own", outs[a].first, outs[b].first, *outs[a].second));
  // the inputs' cheap checks too (a recording's header, the twin against RTDE), before serve says its
  // address; the whole-file check comes after it, and the page shows its progress
  std::optional<device::ColumnMap> map;
  if (o.rtde.empty()) {
    map = cli::load_column_map(o.column_map, twin);
    cli::check_headers(o.recordings, map ? &*map : nullptr, twin.robot(), "monitor", "the monitor");
  } else {
    if (!o.column_map.empty())
      throw InvalidArgument("--column-map applies to a RECORDING; an RTDE stream carries the controller's own field names");
    // (the signal first: a Panda's torque twin is refused for what it compares, not for its 7 joints)
    if (twin.measures_torque())
      throw InvalidArgument(fmt::format("the twin {} compares joint torque sensors (signal joint_torque), which RTDE does not stream (a UR "
                                        "arm has none): monitor a recording of them, or a twin identified on the motor currents",
                                        o.twin));
    if (twin.n_dof() != 6) throw InvalidArgument(fmt::format("RTDE streams 6 joints; the twin {} has {}", o.twin, twin.n_dof()));
  }
  if (hooks.on_checked) hooks.on_checked();
  // A recording is read twice, row by row, and never held: first to check every row, its units and
  // the timing of its steps (the median period a gap is measured in needs the whole file), then to
  // monitor it. Held whole it took ~0.9 kB a sample (1.6 GB per hour at 500 Hz: a day's recording
  // did not fit this 24 GB machine); the first pass keeps 32 bytes a sample (the steps, and the
  // currents for the units check), the second one row (docs/validation.md, "A soak audit").
  // Several files are one stream in the order given (the parts `--split-every` writes, or a shift's
  // recordings): each is checked on its own, then they must share their columns and follow each other
  // in time; the step from one file's last sample to the next one's first is judged as any other step
  // (a jump is a gap, a stream fault), and the estimators and the wear trend go on across it.
  cli::StreamScan stream;
  // the wall clock: Unix time − controller time (NaN: unknown). A recording's is --started-at's; a
  // live stream's is read against this machine's clock as the samples come (StreamWallClock)
  double wall_offset = std::numeric_limits<double>::quiet_NaN();
  StreamWallClock live_clock;
  if (o.rtde.empty()) {
    stream = cli::scan_stream(o.recordings, map ? &*map : nullptr, twin.robot(), "monitor", "the monitor", [&](const std::string& f) {
      if (!o.quiet && !o.json) say_checking(f);
    });
    for (size_t i = 0; i < o.recordings.size(); ++i) sources.push_back({stream.first_t[i], stored_path(o.recordings[i])});
    // a logger's jittery clock: steps the reader did not count as gaps are none to the monitor either
    cfg.gap_factor = std::max(cfg.gap_factor, stream.gap_factor);
    cfg.gaps_judged = true;  // (by the reader, with the whole files' jitter: one rule, said once)
    if (stream.scans.front().timing.median_period > 0) use_rate(stream.scans.front().timing.median_period, o.recordings.front());
    if (std::isfinite(started_at)) wall_offset = started_at - sources.front().first;
  } else {
    cli::RtdeSourceOptions so;
    so.endpoint = o.rtde;
    so.wait_s = o.wait;
    so.reconnect = !o.no_reconnect;
    cli::install_interrupt_handler();
    client = cli::open_rtde(so);
    use_rate(1.0 / client->stats().frequency, "the stream");
    if (!o.quiet && !o.json)
      fmt::print(stderr, "monitoring {} ({}){}; Ctrl-C stops\n", o.rtde, cli::describe(*client),
                 o.duration > 0 ? fmt::format(" for {:g} s", o.duration) : "");
  }
  monitor::Monitor mon(twin, cfg);
  const std::string source = o.rtde.empty() ? fmt::format("{}", fmt::join(o.recordings, " ")) : "rtde://" + o.rtde;
  if (hooks.on_start) hooks.on_start(mon, source);
  std::ofstream jl;
  if (!o.events_path.empty()) {
    // (appending after a last line that an earlier run left without its line end, a full disk or a
    // power loss, glued the first new event onto it: both lost to a JSON-lines reader; review of
    // session 57)
    bool cut_line = false;
    if (o.events_append) {
      std::ifstream old(o.events_path, std::ios::binary | std::ios::ate);
      if (old && old.tellg() > 0) {
        old.seekg(-1, std::ios::end);
        cut_line = old.get() != '\n';
      }
    }
    jl.open(o.events_path, o.events_append ? std::ios::app : std::ios::trunc);
    if (!jl) throw PathError(o.events_path + ": cannot open for writing");
    if (cut_line) {
      log::warn(fmt::format("{}: its last line has no line end (an earlier run cut off: a full disk, a power loss); the lines of this run "
                            "start on a new line",
                            o.events_path));
      jl << '\n';
    }
  }
  std::unique_ptr<monitor::EventStore> store;
  if (!o.db_path.empty()) {
    store = std::make_unique<monitor::EventStore>(o.db_path);
    std::string watched;
    for (const auto& source : sources) watched += (watched.empty() ? "" : " ") + source.second;
    store->begin_run(watched, stored_path(o.twin), o.program);
  }
  // A recording watched by `monitor` itself (under serve its hooks stop it): from here, where the run
  // has its row in the store, Ctrl-C, SIGTERM and SIGHUP stop the replay in order. What was watched
  // is reported and stored, the run's status is 'stopped' (it stayed 'running' when the signal ended
  // the process), and the exit status is the one the signal gives (128 + its number: 130 for Ctrl-C),
  // for the recording was not watched to its end. (Before here, in the check, the signal ends it.)
  const bool own_stop = !client && !hooks.stop_requested;
  if (own_stop) cli::install_interrupt_handler();
  const std::function<bool()> stop_requested = own_stop ? std::function<bool()>([] { return cli::interrupted(); }) : hooks.stop_requested;
  // Events the store was locked for (another connection holding a transaction: 'sqlite3 events.db',
  // a dashboard), oldest first. Before, a lock held over 10 s stopped a live monitor with exit 1 and
  // stalled it for those 10 s (soak audit, session 39); now an event waits here, in memory and in
  // --events, and is stored once the lock is free: retried at the next event, every second of
  // samples, and at the end for up to 10 s, after which what is still unstored is an error.
  std::deque<monitor::Event> unstored;
  bool lock_said = false;
  const auto store_waiting = [&](int wait_ms) {
    while (!unstored.empty() && store->try_insert(unstored.front(), source_of(unstored.front()), wait_ms)) unstored.pop_front();
    if (unstored.empty() && lock_said) {
      log::warn(fmt::format("{}: the store is free again; the events that waited are stored", o.db_path));
      lock_said = false;
    } else if (!unstored.empty() && !lock_said) {
      log::warn(fmt::format("{}: locked by another connection: events wait to be stored (in memory{}) and monitoring goes on",
                              o.db_path, o.events_path.empty() ? "" : ", and in " + o.events_path));
      lock_said = true;
    }
  };
  constexpr int kLiveLockWaitMs = 200;  // at an event; the stream's queue holds 16 s
  constexpr int kEndLockWaitMs = 10000;
  // the last try, on every way out: an error that ends monitoring (a recipe refused on reconnect, a
  // file that cannot be written) must not lose the events that waited, unsaid
  bool end_tried = false;  // (once: the error it may end in unwinds through the guard below)
  const auto store_the_rest = [&] {
    if (!store || unstored.empty() || end_tried) return;
    end_tried = true;
    log::info(fmt::format("{}: waiting up to {:g} s for the store's lock to store {} event(s)", o.db_path, kEndLockWaitMs / 1000.0,
                          unstored.size()));
    store_waiting(kEndLockWaitMs);
  };
  struct OnUnwind {
    std::function<void()> f;
    ~OnUnwind() {
      if (std::uncaught_exceptions() == 0) return;
      try {
        f();
      } catch (...) {  // (a destructor does not throw; what is unstored is said below)
      }
    }
  } unwind_store{[&] {
    if (!store) return;
    if (!end_tried) {
      store_the_rest();
      if (!unstored.empty())
        fmt::print(stderr, "error: {}: {} event(s) not stored{}\n", o.db_path, unstored.size(),
                   o.events_path.empty() ? "" : " (they are in " + o.events_path + ")");
    }
    // the run's row says it failed (what failed is on stderr)
    store->end_run({mon.samples(), mon.events_seen(), "failed"}, kEndLockWaitMs);
  }};
  // --mqtt: the events and the run's state on a broker (it connects in the background); made after
  // the store's guard, which ends the run's row as failed if this throws
  cli::MqttSink mqtt(o.mqtt, source, stored_path(o.twin), o.program, store ? store->run() : 0);
  constexpr int kMqttEndWaitMs = 10000;  // as long as the store's lock is waited for
  const bool mqtt_quiet = o.quiet || o.json;
  // a Ctrl-C during the wait at the end gives it up; one that ended the run came before the wait (a
  // second signal then ends the process at once, as during the store's wait)
  const auto mqtt_give_up = [] {
    const bool before = cli::interrupted();
    return std::function<bool()>([before] { return !before && cli::interrupted(); });
  };
  // the broker hears that the run failed (and gets the events that wait; not for long: the error is said)
  OnUnwind unwind_mqtt{[&] {
    if (!mqtt.active()) return;
    constexpr int kFailedWaitMs = 2000;
    const cli::MqttSink::Undelivered left = mqtt.finish("failed", mon.samples(), mon.events_seen(),
                                                        kFailedWaitMs, mqtt_quiet, mqtt_give_up());
    if (left.total() > 0) fmt::print(stderr, "error: mqtt {}: {}\n", mqtt.address(), left.describe(kFailedWaitMs));
  }};
  // --fail-on: the closed events of those classes (counted as they close: live, old events leave memory)
  const bool fail_on_any = std::find(o.fail_on.begin(), o.fail_on.end(), "any") != o.fail_on.end();
  std::vector<monitor::FaultClass> fail_classes;
  for (const std::string& c : o.fail_on)
    if (c != "any") fail_classes.push_back(monitor::fault_class_from_string(c));
  const auto fails = [&](monitor::FaultClass c) {
    return fail_on_any || std::find(fail_classes.begin(), fail_classes.end(), c) != fail_classes.end();
  };
  long failing_events = 0;
  // the open alerts already printed, by their numbers: a later line of one is an UPDATE, also after
  // another alert's lines came between (a persistent alert parked under a contact and resumed was
  // printed as a new ALERT at its old time: audit of session 55)
  std::set<std::uint64_t> raises_shown;  // (Event::serial)
  // extrapolation: where the robot moves beyond what the twin was identified on, an alert may be the
  // twin's model error; the alert says so when it was raised there (EnvelopeWatch::alert_note)
  monitor::EnvelopeWatch watch(twin.envelope);
  const bool chatty = !o.quiet && !o.json;
  if (!watch.known() && chatty)
    fmt::print(stderr, "note: {} does not record the motion it was identified on (written before session 17): alerts raised where "
                       "the robot moves beyond it are not marked; identify again to have them marked\n",
               o.twin);
  std::vector<bool> noted(static_cast<size_t>(2 * twin.n_dof()), false);  // per joint: speed, position
  // a line of --events, flushed at once ('tail -f' and a crash must see it); an event lost to a full
  // disk is an error, not a shorter file
  const auto write_event_line = [&](const std::string& line) {
    if (!jl.is_open()) return;
    errno = 0;
    jl << line << '\n';
    jl.flush();
    check_written(jl, o.events_path, true);
  };
  // "19:02:11.234 UTC  " before a printed line's controller time, where the wall clock is known
  const auto wall_prefix = [&](double t) -> std::string {
    if (!std::isfinite(wall_offset)) return {};
    const std::string w = iso_utc(t + wall_offset);
    return w.substr(11, 12) + " UTC  ";
  };
  // --events-open's line of an alert not closed by an event (open, or withdrawn): to the broker first
  // (a file that fails must not cost the broker the line), the file, --json
  const auto write_open_line = [&](const monitor::Event& e) {
    if (!o.events_open) return;
    const std::string line = e.to_json_line();
    mqtt.event(std::string(monitor::to_string(e.fault)), line);
    write_event_line(line);
    if (o.json) {
      fmt::print("{}\n", line);
      std::fflush(stdout);
    }
  };
  std::set<double> open_alerts;  // the raise times of the alerts open now (the broker's state counts them)
  double sample_t = std::numeric_limits<double>::quiet_NaN();  // the latest sample's time (a withdrawal's line)
  mon.on_event = [&](const monitor::Event& raw) {
    if (raw.open) open_alerts.insert(raw.t_detected);
    else open_alerts.erase(raw.t_detected);
    monitor::Event e = raw;
    e.wall_offset = wall_offset;
    e.detail += watch.alert_note(e.t_start, e.t_detected);
    if (hooks.on_event) hooks.on_event(e);
    // an alert that is still open, for a consumer that must see an active fault (a resistance that
    // lasts a shift was seen only when it cleared or monitoring stopped); t_detected names the
    // alert, its closing line ("open": false) ends it
    if (e.open) write_open_line(e);
    if (e.open) {
      if (o.quiet || o.json) return;
      // the raise time (what a detection delay counts to), and when the exceedance began; a later
      // diagnosis of the same alert is printed at the time it was made
      if (e.serial == 0 || raises_shown.insert(e.serial).second)
        fmt::print("{}{:9.3f} s  ALERT  {} ({} {:.3f} s)\n", wall_prefix(e.t_detected), e.t_detected, e.detail,
                   e.fault == monitor::FaultClass::Unknown ? "above the threshold since" : "since", e.t_start);
      else
        fmt::print("{}{:9.3f} s  UPDATE {} (the alert raised at {:.3f} s)\n", wall_prefix(e.t_end), e.t_end, e.detail, e.t_detected);
      std::fflush(stdout);
      return;
    }
    raises_shown.erase(e.serial);
    // stored first, printed after: a terminal that went away (a dropped SSH session) must not cost
    // the event its files
    if (fails(e.fault)) ++failing_events;
    const std::string line = e.to_json_line();
    mqtt.event(std::string(monitor::to_string(e.fault)), line, true, e.t_detected);  // (queued first: a file that fails must not cost the broker the event)
    write_event_line(line);
    if (store) {
      // (behind events already waiting no wait: a burst of events must not stall the stream)
      const int wait_ms = unstored.empty() ? kLiveLockWaitMs : 0;
      unstored.push_back(e);
      store_waiting(wait_ms);
    }
    if (!o.quiet && !o.json)
      fmt::print("{}{:9.3f} s  {:<14} {} (duration {:.3f} s, confidence {:.0f} %)\n", wall_prefix(e.t_start), e.t_start, monitor::to_string(e.fault), e.detail,
                 e.duration(), 100 * e.confidence);
    if (o.json) fmt::print("{}\n", line);
    std::fflush(stdout);  // the same for a pipe or a log file
  };
  // an alert raised that ends without an event of its own (withdrawn, or merged into another): what
  // showed it open ends it (--events-open's line with "withdrawn": true, the broker, the dashboard);
  // nothing is stored, and the closed lines never showed it
  mon.on_withdraw = [&](const monitor::Event& raw) {
    open_alerts.erase(raw.t_detected);
    raises_shown.erase(raw.serial);
    monitor::Event e = raw;
    e.wall_offset = wall_offset;
    if (hooks.on_event) hooks.on_event(e);
    write_open_line(e);
    if (o.quiet || o.json) return;
    const double at = std::isfinite(sample_t) ? sample_t : e.t_end;  // (when it was withdrawn, in order with the other lines)
    fmt::print("{}{:9.3f} s  WITHDRAWN the alert raised at {:.3f} s: no event of its own\n", wall_prefix(at), at, e.t_detected);
    std::fflush(stdout);
  };
  mon.on_note = [&](double t, const std::string& note) {
    if (hooks.on_note) hooks.on_note(t, note);
    if (o.quiet || o.json) return;
    fmt::print("{}{:9.3f} s  note: {}\n", wall_prefix(t), t, note);
    std::fflush(stdout);
  };
  // --trace: what the decision saw, per sample and joint (to plot a false alarm or a late detection)
  std::ofstream trace;
  if (!o.trace.empty()) {
    trace.open(o.trace);
    if (!trace) throw PathError(o.trace + ": cannot open for writing");
    trace << "timestamp";
    // (the residual's unit in the names: A, or Nm for a twin of joint torque sensors)
    const char* u = twin.measures_torque() ? "Nm" : "A";
    for (int j = 1; j <= twin.n_dof(); ++j)
      trace << fmt::format(",residual_{0}_{1},threshold_{0}_{1},observer_{0}_Nm,observer_threshold_{0}_Nm", j, u);
    trace << '\n';
  }
  // the RTDE stream's counters for a status line ("" for a recording)
  const auto stream_line = [&]() -> std::string {
    if (!client) return {};
    const auto st = client->stats();
    return fmt::format("{} received, {} lost in {} gaps, {} reconnects", st.received, st.lost, st.gaps, st.reconnects);
  };
  // about once a second: what the broker's client has to say, and the run's state with its counts
  const auto tend_mqtt = [&] {
    mqtt.say(mqtt_quiet);
    mqtt.tick(mon.samples(), mon.events_seen(), static_cast<long>(open_alerts.size()), stream_line());
  };
  long pushed = 0;
  // live, the monitor lets go of events stored and written ten minutes of robot time ago (its own
  // look-backs span seconds): its memory stays bounded however long it runs
  constexpr double kKeepEventsS = 600.0;
  const auto push = [&](const RobotSample& s) {
    if (++pushed % 500 == 0) {  // (about a second at 500 Hz)
      if (!unstored.empty()) store_waiting(0);  // (no wait)
      tend_mqtt();
      if (client && pushed % 5000 == 0) mon.forget_events_before(s.timestamp - kKeepEventsS);
    }
    const monitor::Excursion x = watch.check(s);
    if (!x.inside() && (chatty || hooks.on_note)) {
      auto seen = noted[static_cast<size_t>(2 * x.joint + (x.speed ? 0 : 1))];  // (a vector<bool> reference)
      if (!seen) {
        seen = true;
        const std::string note =
            fmt::format("{}: beyond the motion the twin was identified on; residuals there may be model error", x.describe(watch.envelope()));
        if (hooks.on_note) hooks.on_note(s.timestamp, note);
        if (chatty) fmt::print("{}{:9.3f} s  note: {}\n", wall_prefix(s.timestamp), s.timestamp, note);
      }
    }
    if (hooks.before_sample) hooks.before_sample(s);
    sample_t = s.timestamp;
    mon.push(s);
    if (hooks.after_sample) hooks.after_sample(mon, s);
    if (hooks.on_status && pushed % 500 == 0) hooks.on_status(mon, "monitoring", stream_line());
    if (!trace.is_open()) return;
    trace << fmt::format("{:.6f}", s.timestamp);
    const VectorJ obs = mon.observer_torque(), obs_level = mon.observer_torque_threshold();
    for (int j = 0; j < twin.n_dof(); ++j)
      trace << fmt::format(",{:.6g},{:.6g},{:.6g},{:.6g}", mon.filtered_residual()[j], mon.level()[j], obs[j], obs_level[j]);
    trace << '\n';
  };
  bool silent_gap = false;   // the silence at the end is one of the monitor's gaps (a stream fault)
  bool lost_at_end = false;  // the robot stopped answering before monitoring ended (exit status 1, or 4 below)
  bool stopped_in_outage = false;  // ... and a signal then stopped it (exit status 4: kExitStoppedInOutage)
  bool stopped_by_signal = false;  // a live stream's monitoring ended by Ctrl-C, SIGTERM or SIGHUP
  bool replay_stopped = false;  // a replay stopped at the user's request (serve, Ctrl-C)
  if (!client) {
    double previous = std::numeric_limits<double>::quiet_NaN();
    cli::StreamScan::Cut cut;
    try {
      stream.replay(o.recordings, map ? &*map : nullptr, [&](RobotSample& s) {
        if (stop_requested && stop_requested()) throw ReplayStopped{};
        previous = s.timestamp;
        push(s);
      }, &cut);
    } catch (const ReplayStopped&) {
      replay_stopped = true;
      if (!o.quiet && !o.json)
        fmt::print("stopped {}, in {}: what was watched up to there is reported\n",
                   std::isnan(previous) ? std::string("before the first sample") : fmt::format("at t = {:.3f} s", previous),
                   o.recordings[std::isnan(previous) ? 0 : stream.file_at(previous)]);
    } catch (...) {
      // (the file changed under the second pass: what was watched up to there is still reported)
      mon.finish();
      throw;
    }
    if (cut.file >= 0)
      log::warn(fmt::format("{}: {} of the {} rows checked were there to monitor (the file was cut or replaced while it was read): "
                            "monitoring ends at t = {:.3f} s",
                            o.recordings[static_cast<size_t>(cut.file)], cut.rows, stream.scans[static_cast<size_t>(cut.file)].rows, previous));
  } else {
    std::unique_ptr<device::SplitRecordingWriter> copy;
    if (!o.record_to.empty()) copy = std::make_unique<device::SplitRecordingWriter>(o.record_to, 6, client->sample_fields(), o.split_every);
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.duration > 0 ? o.duration : 1e9);
    RobotSample s;
    auto last_sample = std::chrono::steady_clock::now();
    // (a controller whose clock restarted, a reboot behind a reconnection: said once per restart; a
    // stream that runs at another pace than this machine's clock, a replay faster than real time:
    // no wall-clock time while it does, StreamWallClock)
    const auto read_wall_clock = [&](double t) {
      const double now = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
      const bool had = std::isfinite(wall_offset);
      const std::string at = iso_utc(now).substr(11, 12) + " UTC  ";
      switch (live_clock.sample(t, now)) {
        case StreamWallClock::Change::started:
          if (had && chatty)
            fmt::print("{}{:9.3f} s  note: the controller's clock jumped (a restart?): wall-clock times are read afresh from here\n", at, t);
          break;
        case StreamWallClock::Change::off_pace:
          if (chatty)
            fmt::print("{}{:9.3f} s  note: the controller's clock runs {:.2f} times as fast as this machine's (a replay at another speed, "
                       "or a monitor that falls behind its stream): events carry no wall-clock time while it does\n",
                       at, t, live_clock.pace());
          break;
        case StreamWallClock::Change::on_pace:
          if (chatty) fmt::print("{}{:9.3f} s  note: the controller's clock is back in pace with this machine's: wall-clock times again\n", at, t);
          break;
        case StreamWallClock::Change::none: break;
      }
      wall_offset = live_clock.offset();
    };
    // Is the stream the twin's arm? A UR5e streamed to a UR3e's twin read as a payload change and
    // said nothing else (review of session 48): its controller's torque along its targets is fitted
    // to this arm's model and the other built-in arms' (ident::ArmCheck, 20 samples a second at
    // 500 Hz) over the first 10 s of the stream in which the controller drives the arm, and a
    // warning names the arm it fits, as a recording's scan does
    std::optional<ident::ArmCheck> arm;
    if (client->sample_fields() & kFieldTargetMoment) arm.emplace(twin.robot(), 25);
    double arm_from = std::numeric_limits<double>::quiet_NaN();
    const auto take = [&](RobotSample& sample) {
      read_wall_clock(sample.timestamp);
      if (arm) {
        arm->add(sample);
        if (std::isnan(arm_from)) arm_from = sample.timestamp;
        if (sample.timestamp - arm_from >= 10.0) {
          if (const ident::ArmVerdict v = arm->verdict(); v.own.samples >= 100) {
            cli::warn_if_another_arm("rtde://" + o.rtde, twin.robot(), v, "the monitor");
            arm.reset();
          }
        }
      }
      push(sample);
      last_sample = std::chrono::steady_clock::now();
      if (copy) copy->write(sample);
    };
    while (!cli::interrupted() && std::chrono::steady_clock::now() < end) {
      if (client->pop(s, std::chrono::milliseconds(50))) {
        take(s);
      } else if (client->finished()) {
        break;
      } else {
        // no samples (an outage): an open stream fault says so while it lasts (--events-open, the
        // dashboard), from as long a silence as the end of a run counts as one; the store is still tried
        const double silent = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_sample).count();
        if (client->stats().received > 0 && silent > cli::outage_limit(client->stats().frequency)) mon.stream_outage(silent);
        if (!unstored.empty()) store_waiting(0);
        tend_mqtt();
      }
    }
    // (read once, where the loop ended: a signal during the stop below did not end the loop, and an
    // outage at --duration's end stays a lost connection)
    stopped_by_signal = cli::interrupted();
    client->stop();
    while (client->pop(s, std::chrono::nanoseconds(0))) take(s);  // what was received is still analysed
    // a connection lost and not restored before the end: that stretch was not watched, and the
    // event history must say so (a gap is otherwise only seen when data come back). With
    // --no-reconnect the loop ends at the disconnection: what is missing runs to the end asked for.
    // An operator's stop (Ctrl-C, SIGTERM, SIGHUP) during an outage ends an unwatched stretch too:
    // it was stored as watched (audit of session 38).
    const cli::EndSilence silence =
        cli::end_silence(std::chrono::steady_clock::now(), end, last_sample, o.duration > 0, client->stats().frequency);
    silent_gap = client->stats().received > 0 && silence.lost;
    if (silent_gap) mon.stream_silent(silence.seconds);
    const bool dropped = o.no_reconnect && client->finished() && !stopped_by_signal;
    if (dropped && !o.quiet && !o.json) fmt::print("the connection was lost; --no-reconnect: monitoring stopped\n");
    lost_at_end = silent_gap || dropped;
    stopped_in_outage = silent_gap && !dropped && stopped_by_signal;
    if (copy) {
      copy->close();
      const auto& files = copy->files();
      if (!o.quiet && !o.json)
        fmt::print("recorded {} samples to {}\n", copy->rows(),
                   files.size() == 1 ? files.front()
                                     : fmt::format("{} files, {} ... {} (a new one every {:g} s)", files.size(), files.front(), files.back(), o.split_every));
    }
    const auto st = client->stats();
    if (!o.quiet && !o.json)
      fmt::print("stream: {} received, {} lost in {} gaps, {} reconnects, {} protocol errors, {} resent, {} dropped by this monitor{}\n",
                 st.received, st.lost, st.gaps, st.reconnects, st.protocol_errors, st.repeated, st.dropped,
                 st.dropped > 0 ? " (the monitor fell behind the stream: a slow disk for --record, or a loaded machine)" : "");
    if (!client->fatal_error().empty()) throw std::runtime_error(client->fatal_error());
  }
  mon.finish();
  const char* status = lost_at_end ? "connection lost" : replay_stopped || stopped_by_signal ? "stopped" : "finished";
  if (hooks.on_status) hooks.on_status(mon, status, stream_line());
  close_written(jl, o.events_path);
  if (store && !unstored.empty()) {
    store_the_rest();
    if (!unstored.empty())
      throw std::runtime_error(fmt::format("{}: {} event(s) not stored: another connection held the store locked to the end{}", o.db_path,
                                           unstored.size(), o.events_path.empty() ? "" : " (they are in " + o.events_path + ")"));
  }
  // the run's row: how it ended, with or without events ('twinwatch events --runs')
  if (store && !store->end_run({mon.samples(), mon.events_seen(), status}, kEndLockWaitMs))
    log::warn(fmt::format("{}: the run's end (samples, events, status) is not stored: another connection held the store locked for {:g} s",
                          o.db_path, kEndLockWaitMs / 1000.0));
  close_written(trace, o.trace);
  // the broker: the run's end, and what waits for it (an error, as an event not stored is)
  const cli::MqttSink::Undelivered undelivered = mqtt.finish(
      status, mon.samples(), mon.events_seen(), kMqttEndWaitMs, mqtt_quiet, mqtt_give_up());
  const long mqtt_left = undelivered.total();
  if (mqtt_left > 0)
    fmt::print(stderr, "error: mqtt {}: {}{}\n", mqtt.address(), undelivered.describe(kMqttEndWaitMs),
               o.events_path.empty() && o.db_path.empty() ? ""
                                                          : fmt::format(" (the events are in {})", o.db_path.empty() ? o.events_path : o.db_path));
  if (chatty && watch.samples_outside() > 0) fmt::print("{}\n", watch.summary());
  const double declared = mon.declared_payload(), ended = mon.twin().payload().mass;
  if (chatty && std::isfinite(declared) && !mon.declaration_taken())
    fmt::print("payload: the controller declares {:.2f} kg, which the twin did not take (see the note); it ended with {:.2f} kg\n", declared,
               ended);
  else if (chatty && std::isfinite(declared) && !mon.carries_declared())
    fmt::print("payload: the twin ended with {:.2f} kg, the controller declares {:.2f} kg: the arm does not carry what its program "
               "declared (a part lost, or a pick with nothing gripped; see the payload events)\n",
               ended, declared);
  else if (chatty && std::isfinite(declared) && ended != twin.payload().mass)
    fmt::print("payload: the twin took the controller's declarations; it ended with {:.2f} kg, as declared\n", ended);
  else if (chatty && ended != twin.payload().mass)
    fmt::print("payload: the twin followed the payload changes it found; it ended with {:.2f} kg (it started with {:.2f} kg)\n", ended,
               twin.payload().mass);
  if (!o.quiet && !o.json)
    fmt::print("{} samples, {} gap(s){}, {} event(s){}{}{}\n", mon.samples(), mon.gaps(),
               silent_gap ? " (the last: the silence at the end, which the stream line does not count)" : "",
               mon.events_seen(),
               mon.repeated() + mon.invalid() > 0
                   ? fmt::format(" ({} skipped: {} with a repeated timestamp, {} with a value that is no reading: not a number or beyond 1e4)", mon.repeated() + mon.invalid(),
                                 mon.repeated(), mon.invalid())
                   : "",
               mon.not_driven() > 0 ? fmt::format("; {} sample(s) ({:.1f} s) not judged: the controller did not drive the arm (see the notes)",
                                                  mon.not_driven(), mon.not_driven_seconds())
                                    : "",
               o.db_path.empty()     ? ""
               : store && store->run() > 0 ? fmt::format(", stored in {} (run {}: 'twinwatch events --db {} --run {}')", o.db_path, store->run(),
                                                         o.db_path, store->run())
                                           : fmt::format(", stored in {}", o.db_path));
  // (45 rows covering a whole contact read "0 event(s)": nothing had been judged)
  if (mon.judged() == 0 && !o.quiet) {
    std::fflush(stdout);  // (after the summary above)
    fmt::print(stderr, "warning: no sample was judged: the {} sample(s) are all within the estimators' start-up{} — no event is no "
                       "clean bill of health\n",
               mon.samples(), mon.not_driven() > 0 ? " or not driven" : "");
  }
  // (a recording stopped part-way: as the signal would have ended the process, its files now complete)
  if (own_stop && replay_stopped) return 128 + cli::interrupt_signal();
  // (what was received is analysed and stored; a script learns that the end was not watched, or
  // that the broker did not get every event)
  if (mqtt_left > 0) return 1;
  if (lost_at_end) return stopped_in_outage ? cli::kExitStoppedInOutage : 1;
  // (--fail-on: a script's check of a recording or a shift, e.g. '|| notify')
  if (failing_events > 0) {
    std::fflush(stdout);  // (after the summary)
    if (!o.quiet && !o.json)
      fmt::print(stderr, "{} event(s) of the classes --fail-on names ({}): exit status {}\n", failing_events, fmt::join(o.fail_on, ","),
                 cli::kExitEventsFound);
    return cli::kExitEventsFound;
  }
  return 0;
}

struct ThresholdOptions {
  bool progress = false, quiet = false;
  std::string twin, filter, program;
  std::vector<std::string> recordings, debounce_validation, column_maps;
  double payload_mass = std::numeric_limits<double>::quiet_NaN();  // not given: the twin file's payload
  std::vector<double> payload_com;
  std::vector<double> part_com;  // stored in the twin (MonitorConfig::part_com); empty: the twin's kept
};

// The progress of a learner's reading: "  thresholds  37 %" on one line of stderr, rewritten as the
// samples are read (shown on a terminal, or with --progress); a phase an error leaves ends its line
class ReadProgress {
 public:
  explicit ReadProgress(bool shown) : shown_(shown) {}
  ~ReadProgress() { end(); }
  ReadProgress(const ReadProgress&) = delete;
  ReadProgress& operator=(const ReadProgress&) = delete;
  /// `samples`: how many the phase reads in all
  void begin(std::string what, size_t samples) {
    end();
    what_ = std::move(what);
    total_ = std::max<size_t>(samples, 1);
    read_ = 0;
    pct_ = -1;
    open_ = true;
    add(0);
  }
  void add(size_t samples) {
    if (!open_) return;
    read_ += samples;
    const int pct = static_cast<int>(100.0 * static_cast<double>(std::min(read_, total_)) / static_cast<double>(total_));
    if (shown_ && pct != pct_) fmt::print(stderr, "\r  {} {:3d} %", what_, pct);
    pct_ = pct;
  }
  void end() {
    if (open_ && shown_) fmt::print(stderr, "\n");
    open_ = false;
  }

 private:
  bool shown_, open_ = false;
  std::string what_;
  size_t total_ = 1, read_ = 0;
  int pct_ = -1;
};

// A run read through another source, counting what is read on a ReadProgress
class CountedSamples : public device::SampleSource {
 public:
  CountedSamples(const device::SampleSource& inner, ReadProgress& progress) : inner_(&inner), progress_(&progress) {
    path_ = inner.path();
    n_dof_ = inner.n_dof();
    present_ = inner.present();
    median_period_ = inner.median_period();
    size_ = inner.size();
    seconds_ = inner.seconds();
  }
  void replay(const std::function<void(size_t k, const RobotSample& s)>& each) const override {
    constexpr size_t kEvery = 1u << 14;  // (33 s of 500 Hz data)
    inner_->replay([&](size_t k, const RobotSample& s) {
      each(k, s);
      if ((k + 1) % kEvery == 0) progress_->add(kEvery);
    });
    progress_->add(size_ % kEvery);
  }

 private:
  const device::SampleSource* inner_;
  ReadProgress* progress_;
};

// a line of the summary on stdout, unless -q
template <typename... Args>
void say(bool on, fmt::format_string<Args...> f, Args&&... a) {
  if (on) fmt::print(f, std::forward<Args>(a)...);
}

int run_thresholds(const ThresholdOptions& o) {
  // before the learning run, which takes minutes on long recordings
  if (!o.program.empty()) monitor::check_program_name(o.program, "--program");
  cli::require_distinct(o.recordings, "RECORDINGS");
  ident::TwinModel twin = cli::load_twin(o.twin);
  require_writable(o.twin);  // (found after the learning, exit 1: audit of session 56)
  std::vector<std::string> all = o.recordings;
  all.insert(all.end(), o.debounce_validation.begin(), o.debounce_validation.end());
  const cli::ColumnMaps maps(o.column_maps, all, twin.measures_torque());
  // Each recording is checked now (a bad one fails in seconds, not after minutes of learning) and read
  // again by the learners, never held: a shift of healthy recordings at 500 Hz is 1.7 GB per robot
  // hour, which held did not fit the machine (docs/recordings.md)
  std::vector<std::unique_ptr<device::FileSamples>> recs;
  for (const auto& f : o.recordings) {
    std::size_t bad = 0;
    if (!o.quiet) say_checking(f);
    auto runs = cli::scan_training_runs(f, maps.of(f), twin.robot(), "thresholds", "learning thresholds", "thresholds", &bad);
    // (the learners hold them as the monitor does: said here, where the recording has its name)
    if (bad > 0)
      fmt::print(stderr, "note: {}: {} joint temperature reading(s) outside {:g} to {:g} °C, which no joint reads: learned with each "
                         "joint's last plausible reading, as the monitor judges such samples\n",
                 f, bad, monitor::kTemperatureMin, monitor::kTemperatureMax);
    for (auto& r : runs) recs.push_back(std::move(r));
  }
  // the observer's debounce per joint, chosen on healthy recordings the thresholds were not learned on
  std::vector<std::unique_ptr<device::FileSamples>> vrecs;
  for (const auto& f : o.debounce_validation) {
    for (const auto& r : o.recordings)
      if (same_file(f, r))
        throw InvalidArgument(fmt::format("--debounce-validation {} is also one of the recordings the thresholds are learned on; "
                                          "the choice needs healthy runs they were not learned on",
                                          f));
    if (!o.quiet) say_checking(f);
    auto runs = cli::scan_training_runs(f, maps.of(f), twin.robot(), "thresholds", "--debounce-validation", "thresholds --debounce-validation",
                                        nullptr);
    for (auto& r : runs) vrecs.push_back(std::move(r));
  }
  // (a recording with stops in it is learned from as its driven stretches: "1 healthy recording(s) (2 driven stretches)")
  const auto files = [](size_t recordings, size_t stretches, const char* kind) {
    return fmt::format("{} {}recording(s){}", recordings, kind, stretches > recordings ? fmt::format(" ({} driven stretches)", stretches) : "");
  };
  // the progress of each learner's reading, which on a shift's recordings takes minutes
  ReadProgress progress(o.progress || (!o.quiet && isatty(STDERR_FILENO)));
  size_t samples = 0, validation_samples = 0;
  std::vector<std::unique_ptr<CountedSamples>> counted, vcounted;
  for (const auto& r : recs) {
    counted.push_back(std::make_unique<CountedSamples>(*r, progress));
    samples += r->size();
  }
  for (const auto& r : vrecs) {
    vcounted.push_back(std::make_unique<CountedSamples>(*r, progress));
    validation_samples += r->size();
  }
  std::vector<monitor::HealthyRun> runs;
  const model::RigidBodyInertia p = cli::payload_for(twin, o.twin, o.payload_mass, o.payload_com);
  for (const auto& r : counted) runs.push_back({nullptr, p, r.get()});
  // keep the user's settings and the learned temperature slope; only the thresholds are re-learned
  monitor::MonitorConfig settings;
  if (!twin.monitor_json.empty()) settings = monitor::MonitorConfig::from_twin(twin);
  if (!o.filter.empty()) settings.residual_filter = split_filter(o.filter);
  cli::apply_part_com(settings, o.part_com);  // (checked before the learning run)
  // the viscous friction's temperature slope, when these runs span joint temperatures (a warm-up
  // from cold): the monitor and the wear trend compensate with it, and the thresholds below are
  // learned on the compensated residual. Runs at one temperature keep the slope the twin has. Every
  // threshold set shares the one slope, and the others were learned with it: a program's set keeps
  // the twin's (measured: a 300 s pick-and-place from cold moved J2/J3's slope from -1.6e-3 to
  // -3.3e-3 A·s/rad/°C under the default set learned with the first; session 33)
  // (a twin with a default set and no slope: its default set was learned without compensation, and
  // a program's set keeps that too)
  const bool has_default_set = settings.static_level.size() == twin.n_dof();
  const bool has_slope = settings.trend.temperature_slope.size() == twin.n_dof();
  if (!o.program.empty() && (has_slope || has_default_set)) {
    if (has_slope)
      say(!o.quiet, "temperature slope per joint {:.2e} {}·s/rad/°C: the twin's, which every threshold set shares (learn the default set "
                 "again, without --program, on a warm-up from cold to change it)\n",
                 fmt::join(settings.trend.temperature_slope, " "), twin.channel_unit());
    else
      say(!o.quiet, "no temperature slope: the twin's default set was learned without one, and every threshold set shares it (learn the "
                 "default set again, without --program, on a warm-up from cold to learn one)\n");
  } else {
    std::vector<monitor::TrendRun> trend_runs;
    for (const auto& r : runs) trend_runs.push_back({nullptr, r.payload, 0, r.samples});
    try {
      progress.begin("temperature slope", samples);
      settings.trend = monitor::learn_trend_temperature(twin, trend_runs, settings.trend);
      progress.end();
      say(!o.quiet, "temperature slope of the viscous friction per joint {:.2e} {}·s/rad/°C (learned on these recordings; the "
                 "monitor and the wear trend compensate with it)\n",
                 fmt::join(settings.trend.temperature_slope, " "), twin.channel_unit());
    } catch (const InvalidArgument& e) {
      progress.end();
      say(!o.quiet, "note: no temperature slope learned ({}){}\n", e.what(),
                 settings.trend.temperature_slope.size() ? "; the twin's is kept" : "; give a warm-up from cold to learn one");
    }
  }
  // cfg is what is stored: the default set re-learned, or a program's set added with the default
  // set (observer thresholds and debounce included) left as it was
  monitor::MonitorConfig cfg = settings;
  bool program_is_default = false;
  {
    double seconds = 0.0;
    for (const auto& r : recs) seconds += r->seconds();
    if (!o.quiet) fmt::print(stderr, "learning thresholds on {}, {:.0f} s of data (the monitor runs over them, then a linear program per joint) ...\n",
               files(o.recordings.size(), recs.size(), ""), seconds);
  }
  progress.begin("thresholds", 2 * samples);
  if (o.program.empty()) {
    cfg = monitor::learn_thresholds(twin, runs, settings);
  } else {
    monitor::learn_program_thresholds(cfg, o.program, twin, runs);
    if (cfg.static_level.size() == 0) {  // a twin without thresholds: the first program's set is also the default
      cfg.select_program(o.program);
      cfg.program.clear();
      program_is_default = true;
    }
  }
  progress.end();
  monitor::MonitorConfig shown = cfg;  // the set just learned, for the choice and the table below
  shown.select_program(o.program);
  if (!vrecs.empty()) {
    std::vector<monitor::HealthyRun> val;
    for (const auto& r : vcounted) val.push_back({nullptr, p, r.get()});
    if (!o.quiet) fmt::print(stderr, "choosing the observer's debounce per joint: the monitor runs over the {} once per count ...\n",
               files(o.debounce_validation.size(), vrecs.size(), "validation "));
    progress.begin("observer debounce", validation_samples);
    const auto choice = monitor::choose_observer_debounce(twin, shown, val);
    progress.end();
    if (o.program.empty() || program_is_default) cfg.observer_choice = choice;
    if (!o.program.empty()) cfg.programs.at(o.program).observer_choice = choice;
    say(!o.quiet, "observer debounce per joint {} (samples), chosen on {}, {:.0f} s; their healthy observer "
               "ratio per joint at 1 sample {:.3f}, at {} {:.3f}\n",
               fmt::join(choice.raise_after, " "), files(o.debounce_validation.size(), vrecs.size(), "validation "), choice.seconds, fmt::join(choice.ratio.front(), " "),
               choice.ratio.size(), fmt::join(choice.ratio.back(), " "));
  } else if (o.program.empty() ? !settings.observer_choice.raise_after.empty()
                                 : settings.programs.count(o.program) > 0 &&
                                       !settings.programs.at(o.program).observer_choice.raise_after.empty()) {
    say(!o.quiet, "note: the per-joint observer debounce of {} belonged to the old thresholds and is dropped; choose one "
               "for the new ones with --debounce-validation HEALTHY.csv...\n",
               o.program.empty() ? std::string("the default set") : fmt::format("program '{}'", o.program));
  }
  ident::TwinModel out = twin;
  monitor::MonitorConfig stored = cfg;
  stored.program.clear();
  out.monitor_json = stored.to_json();
  out.save(o.twin);
  say(!o.quiet, "thresholds {} learned from {} with residual filter '{}' and stored in {}; the heaviest payload "
             "among them, {:.2f} kg, is recorded (the monitor says when it predicts with more than {:g} kg above it)\n",
             o.program.empty() ? std::string("(default set)") : fmt::format("of program '{}'", o.program),
             files(o.recordings.size(), recs.size(), "healthy "),
             o.filter.empty() ? "iir" : o.filter, o.twin, shown.payload_max, monitor::Monitor::payload_envelope_margin(shown));
  if (!o.part_com.empty())
    say(!o.quiet, "a part picked with no payload declared is fitted and followed at ({:g}, {:g}, {:g}) m in the flange frame (stored)\n",
        cfg.part_com.x(), cfg.part_com.y(), cfg.part_com.z());
  // (a joint-torque twin has no drive whose motoring/back-driven step its thresholds widen by)
  if (shown.reversal_load_max.size() == twin.n_dof() && !twin.measures_torque()) {
    // (stored in the twin's torque scale, the joint's own gain; shown in N·m as the monitor sizes
    // faults, through TwinModel::trusted_gain: a J6 no payload loads fitted a gain of 3080 and its
    // load read 183.71 N·m on a 12 N·m wrist, audit of session 56)
    std::string loads;
    bool relative = false, median = false;
    for (int j = 0; j < twin.n_dof(); ++j) {
      const double own = twin.joints[static_cast<size_t>(j)].gain, used = twin.trusted_gain(j);
      // (without a trusted gain there is no median: the twin's own scale, as before)
      const bool converted = twin.gain_from_median(j) && own > 0.0 && std::isfinite(own);
      median |= converted;
      const bool own_scale = !twin.gains_known() || (!converted && used != own);
      relative |= own_scale;
      loads += fmt::format("{}J{} {:.2f}{}", j ? "  " : "", j + 1, shown.reversal_load_max[j] * (converted ? used / own : 1.0),
                           converted || own_scale ? "*" : "");
    }
    say(!o.quiet, "the largest load each joint reversed under in them [N·m{}{}], beyond which both of its thresholds widen by the drive's "
               "motoring/back-driven step: {}\n",
               relative ? "; *: in the twin's own torque scale, the joint's gain not fixed by a known payload" : "",
               median ? "; *: through the median of the identified gains, the joint's own not fixed by a known payload, as the monitor "
                        "sizes faults"
                      : "",
               loads);
  }
  for (int j = 0; j < twin.n_dof(); ++j) {
    const auto& d = shown.dynamic[static_cast<size_t>(j)];
    say(!o.quiet, "J{}  static {:.4f} {}   dynamic {:.4f}|qdd| + {:.4f}|qd| + {:.4f} exp(-{:g}|qd|) + {:.4f} {}\n", j + 1,
               shown.static_level[j], twin.channel_unit(), d.psi_qdd, d.psi_qd, d.psi_rev, d.rho, d.upsilon, twin.channel_unit());
  }
  return 0;
}

twinwatch::cli::VerbRegistrar reg_monitor{"monitor", 40, [](CLI::App& app) {
  auto o = std::make_shared<MonitorOptions>();
  auto* sub = app.add_subcommand("monitor", "Watch a recording with the twin: residuals, alerts, diagnosis, events");
  sub->footer(twinwatch::cli::with_exit_status(
      "Each event has a class, the joint (or a contact's link), a size with its units, and a confidence: how\n"
      "likely class and place are right. For a contact, the share of the residual its fit explains times the\n"
      "named link's probability (the detail's '% likely'); for the other classes, the share of the residual\n"
      "beyond the healthy noise before the alert that the diagnosis explains (of the whole residual where the\n"
      "twin has no momentum observer; docs/validation.md, 'What an event's confidence means'). Joints and\n"
      "links are numbered from 1, as in the scenario labels.\n"
      "Ctrl-C, SIGTERM or SIGHUP stop it in order: what was watched is reported and stored. Watching a\n"
      "recording, the exit status is then 128 + the signal (130 for Ctrl-C: it was not watched to its end);\n"
      "watching a live stream (--rtde), 0, or 4 when the stream had been silent for more than 1.5 s before\n"
      "the stop (a stream_fault event says so; the systemd unit takes 4 as a clean stop). A second signal\n"
      "ends it at once (128 + the signal). Without a signal, a live stream's monitoring exits 1 when the\n"
      "robot had stopped answering at --duration's end, or when --no-reconnect ended it at a lost connection.\n"
      "With --fail-on CLASSES, 3 when an event of those classes was found and the run otherwise ended 0\n"
      "(1 and 4 come first)."));
  const auto check = twinwatch::cli::add_monitor_options(sub, o);
  sub->callback([=] {
    check();
    twinwatch::cli::set_exit_code(run_monitor_impl(*o, {}));
  });
}};

twinwatch::cli::VerbRegistrar reg_thresholds{"thresholds", 41, [](CLI::App& app) {
  auto o = std::make_shared<ThresholdOptions>();
  auto* sub = app.add_subcommand("thresholds", "Re-learn the monitor's thresholds from healthy recordings (per payload/program)");
  sub->add_option("--twin", o->twin, "Twin file to update")->required()->check(CLI::ExistingFile);
  sub->add_option("RECORDINGS", o->recordings, "Healthy recordings (files: each is read several times and never held)")->required()->check(CLI::ExistingFile);
  sub->add_flag("--progress", o->progress, "Show each learner's progress even when stderr is not a terminal");
  sub->add_flag("-q,--quiet", o->quiet, "Print nothing on success (notes on the recordings and warnings still go to stderr)");
  sub->add_option("--payload-mass", o->payload_mass,
                  "Payload carried in these recordings [kg] (default: the twin file's 'payload'). A recording that carries the payload the controller declares (RTDE "
                  "payload / payload_cog, controllers 5.5.1 and newer; a recording's payload columns) is learned with each "
                  "declaration the twin takes, from its sample on (from the first sample: instead of this), as the monitor predicts "
                  "with it; a twin with relative gains takes none")
      ->check(twinwatch::cli::nonnegative_number());
  sub->add_option("--payload-com", o->payload_com, "Payload COM in the flange frame [m] (3 numbers; with --payload-mass)")->expected(3)->allow_extra_args(false);
  sub->add_option("--part-com", o->part_com,
                  "Store in the twin where a part the robot picks sits when no payload is declared [m, flange frame; 3 numbers]: "
                  "'monitor' fits and follows an undeclared pick there (default 0 0 0.04; 'monitor --part-com' for one run)")
      ->expected(3)
      ->allow_extra_args(false);
  sub->add_option("--filter", o->filter, kFilterHelp);
  sub->add_option("--column-map", o->column_maps,
                  kColumnMapHelp + std::string(". MAP: every recording without one of its own (--debounce-validation's too); REC=MAP: that "
                                               "recording alone (repeat for each; REC is any name of the file)"))
      ->type_name("[REC=]MAP");
  sub->add_option("--debounce-validation", o->debounce_validation,
                  "Healthy recordings NOT among RECORDINGS (same program and payload; the longer the better: the largest "
                  "healthy peak grows with the time watched) on which to choose the momentum observer's debounce per joint: "
                  "each joint gets the smallest count (1 up to the shared one) at which its healthy peaks stay as far below its "
                  "threshold as the worst joint's do with the shared count (docs/validation.md, 'Observer debounce per joint'). Without it the shared count is used")
      ->check(CLI::ExistingFile);
  sub->add_option("--program", o->program,
                  "Store the thresholds as the set of this program (letters, digits, _ - .), selected with 'monitor --program'; "
                  "the default set and the other programs' sets are kept. Without it: re-learn the default set")->check(kProgramNameGiven);
  sub->callback([o] { twinwatch::cli::set_exit_code(run_thresholds(*o)); });
}};

}  // namespace

namespace twinwatch::cli {

std::vector<std::string> split_filter(const std::string& s) {
  std::vector<std::string> out;
  size_t start = 0;
  for (size_t k = 0; k <= s.size(); ++k)
    if (k == s.size() || s[k] == ',') {
      out.push_back(s.substr(start, k - start));
      start = k + 1;
    }
  return out;
}

monitor::MonitorConfig config_of(const ident::TwinModel& twin, const std::string& path) {
  if (twin.monitor_json.empty())
    throw InvalidArgument(fmt::format("{} has no monitor thresholds: learn them with 'twinwatch thresholds --twin {} HEALTHY.csv...'", path, path));
  return monitor::MonitorConfig::from_twin(twin);
}

void apply_part_com(monitor::MonitorConfig& cfg, const std::vector<double>& xyz) {
  if (xyz.empty()) return;
  if (xyz.size() != 3) throw InvalidArgument(fmt::format("--part-com: expected 3 numbers (x y z, m), got {}", xyz.size()));
  const Eigen::Vector3d c(xyz[0], xyz[1], xyz[2]);
  if (!monitor::MonitorConfig::part_com_in_reach(c))
    throw InvalidArgument(fmt::format("--part-com: expected a point within {:g} m of the flange, got ({:g}, {:g}, {:g}), {:g} m away (in mm? give metres)",
                                      model::kPayloadComMax, c.x(), c.y(), c.z(), c.norm()));
  cfg.part_com = c;
}

void apply_alert_settings(monitor::MonitorConfig& cfg, int n_dof, const std::vector<double>& sensitivity, int raise_after,
                          int observer_raise_after) {
  if (!sensitivity.empty()) {
    if (sensitivity.size() == 1) cfg.sensitivity = VectorJ::Constant(n_dof, sensitivity[0]);
    else {
      cfg.sensitivity.resize(static_cast<int>(sensitivity.size()));
      for (size_t k = 0; k < sensitivity.size(); ++k) cfg.sensitivity[static_cast<int>(k)] = sensitivity[k];
    }
  }
  if (raise_after > 0) {
    cfg.raise_after = raise_after;
    // the observer follows the current channel's count (unless observer_raise_after is set), as it did
    // before the twin chose one per joint: the choice was made for the old count and is dropped, in
    // the default set and in every program's
    cfg.observer_choice = {};
    for (auto& [name, set] : cfg.programs) set.observer_choice = {};
  }
  if (observer_raise_after > 0) cfg.observer_raise_after = observer_raise_after;
  cfg.validate(n_dof);
}

std::function<void()> add_monitor_options(CLI::App* sub, const std::shared_ptr<MonitorOptions>& o) {
  sub->add_option("--twin", o->twin, "Twin file from 'twinwatch identify'")->required()->check(CLI::ExistingFile);
  sub->add_option("RECORDING", o->recordings,
                  "Recording CSV (or use --rtde for a live robot); several are watched as one stream in the order given, e.g. the parts "
                  "--split-every writes (rec.000.csv rec.001.csv ...): the estimators and the wear trend go on across them, a jump in "
                  "time between two is a gap, and each event is stored under the file it started in")
      ->check(CLI::ExistingFile);
  sub->add_option("--rtde", o->rtde, "Monitor a live controller at HOST[:PORT] over RTDE instead of a recording");
  auto* duration = sub->add_option("--duration", o->duration, "With --rtde: stop after this many seconds (default: until Ctrl-C)")
                       ->check(positive_number());
  auto* wait = sub->add_option("--wait", o->wait, "With --rtde: keep trying the first connection for this long [s]")
                   ->check(nonnegative_number());
  auto* no_reconnect = sub->add_flag("--no-reconnect", o->no_reconnect,
                "With --rtde: stop at the first disconnection (the rest of --duration is reported as a stream fault) instead of "
                "reconnecting with back-off");
  auto* record = sub->add_option("--record", o->record_to,
                                 "With --rtde: also write the stream to this recording CSV (replaced if it exists; '{start}' in the "
                                 "name is replaced by the run's start, UTC: rec-{start}.csv, so that a service started again keeps "
                                 "the last run's recording)");
  auto* split_every = sub->add_option("--split-every", o->split_every,
                                      "With --record: start a new file each SECONDS of controller time (>= 1): rec.csv -> rec.000.csv, "
                                      "rec.001.csv, ..., each with the header (1.74 GB per robot hour at 500 Hz in one file otherwise)");
  sub->add_option("--column-map", o->column_map, kColumnMapHelp);
  sub->add_option("--events", o->events_path, "Write events as JSON lines to this file (one line per event, when it ends, or when monitoring stops: \"active_at_stop\": true; joints and links numbered from 1 as in the labels: \"joint\": 5 is J5, null none; \"magnitude\" in \"units\"; \"peak_residual\": the largest |filtered residual| of any joint during the alert, in \"peak_residual_units\": A, or N·m for a twin of joint torque sensors). The file is replaced if it exists (--events-append adds to it); the event store (--db) keeps the history across runs. "
                  "'{start}' in the name is replaced by the run's start, UTC (events-{start}.jsonl: events-20261208T031500Z.jsonl)");
  auto* events_append = sub->add_flag("--events-append", o->events_append,
                                       "With --events: add the lines to the file instead of replacing it, e.g. for a service that "
                                       "is started again after a robot was off (live lines carry wall-clock times; docs/events.md)");
  auto* events_open = sub->add_flag("--events-open", o->events_open,
                                     "With --events, --json or --mqtt: also a line when an alert is raised and at each re-diagnosis (\"open\": true, "
                                     "\"class\" \"unknown\" until diagnosed); \"t_detected\" names the alert, and its line with \"open\": "
                                     "false, written when it ends, ends it. Default: one line per event, when it ends. The store (--db) keeps "
                                     "the closed events only");
  sub->add_option("--db", o->db_path, "SQLite event store ('' to disable)")->capture_default_str();
  sub->add_option("--payload-mass", o->payload_mass,
                  "Payload the program declares [kg] (default: the twin file's 'payload', 0 kg as identify writes it). A stream that carries the controller's declared payload (RTDE payload / "
                  "payload_cog, controllers 5.5.1 and newer; a recording's payload columns) overrides it: the twin takes the first "
                  "declaration that differs and every change of it, so a declared pick raises nothing")
      ->check(nonnegative_number());
  sub->add_option("--payload-com", o->payload_com, "Payload COM in the flange frame [m] (3 numbers; with --payload-mass)")->expected(3)->allow_extra_args(false);
  sub->add_option("--part-com", o->part_com, cli::kPartComHelp)->expected(3)->allow_extra_args(false);
  sub->add_option("--sensitivity", o->sensitivity, kSensitivityHelp)->delimiter(',')->allow_extra_args(false);
  sub->add_option("--raise-after", o->raise_after, kRaiseAfterHelp)->check(whole_number(1, 1000));
  sub->add_option("--observer-raise-after", o->observer_raise_after, kObserverRaiseAfterHelp)->check(whole_number(1, 1000));
  sub->add_flag("--static", o->static_threshold, "Use the static threshold (UR3e §4.1) instead of the dynamic one (Cao eq. 24)");
  sub->add_flag("--keep-payload", o->keep_payload,
                "Keep the payload the twin starts with (--payload-mass, else the twin file's) for the whole run. Default: 2.5 s "
                "after a payload change is raised the twin takes the diagnosed payload (a dropped part: none), the alert clears "
                "and monitoring goes on, so that a contact or the next pick is an event of its own; and the twin takes each "
                "payload the stream declares (RTDE payload, controllers 5.5.1+). With this flag neither: a payload change stays "
                "open while the robot runs with it, and a pick the program declares is an alert too");
  sub->add_option("--filter", o->filter, kFilterHelp);
  sub->add_option("--program", o->program,
                  "Use the thresholds learned for this program ('twinwatch thresholds --program NAME'); default: the twin's "
                  "default set")->check(kProgramNameGiven);
  sub->add_option("--cycle-period", o->cycle_period,
                  "Program cycle time [s]: the wear trend's windows become whole cycles (default: plain windows of the twin's "
                  "trend.window_s)")
      ->check(positive_number());
  auto* started = sub->add_option("--started-at", o->started_at,
                  "A recording: the wall-clock time of its first sample, ISO 8601 with its zone (2026-12-03T08:00:00Z, "
                  "2026-12-03T09:00:00.250+01:00; 'twinwatch record' prints it). Events then carry wall-clock times "
                  "(\"wall_start\", \"wall_detected\", \"wall_end\"; the printed lines start with the time of day in UTC). "
                  "Live (--rtde) they always do, read against this machine's clock");
  sub->add_flag("--json", o->json, "Print closed events as JSON lines only (the --events format)");
  sub->add_option("--trace", o->trace,
                  "Write every sample's filtered current residual, threshold, momentum-observer residual and observer threshold "
                  "per joint to this CSV (to see why an alert was raised or late; columns residual_J_A, or residual_J_Nm for a twin "
                  "of joint torque sensors)");
  sub->add_flag("-q,--quiet", o->quiet, "Print nothing (no alerts, notes or summary) but the JSON lines that --json asks for");
  sub->add_option("--fail-on", o->fail_on,
                  fmt::format("Exit with status {} when the run found an event of these classes (comma-separated: collision, resistance, "
                              "payload_change, sensor_fault, stream_fault, wear, unknown; or 'any'), for a script's check of a "
                              "recording or a shift (twinwatch monitor ... --fail-on collision,resistance || notify). A run that "
                              "ends with 1 (a lost stream, an undelivered MQTT message) or a signal's status keeps that status",
                              kExitEventsFound))
      ->delimiter(',')
      ->allow_extra_args(false)
      ->check(CLI::Validator(
          [](std::string& v) {
            if (v == "any") return std::string();
            try {
              (void)monitor::fault_class_from_string(v);
            } catch (const InvalidArgument& e) {
              return std::string(e.what()) + ", or any";
            }
            return std::string();
          },
          "CLASS"));
  const auto mqtt_check = add_mqtt_options(sub, o->mqtt);
  return [=] {
    mqtt_check();
    refuse_unless({events_open}, !o->events_path.empty() || o->json || !o->mqtt.address.empty(), "with --events, --json or --mqtt");
    refuse_unless({events_append}, !o->events_path.empty(), "with --events");
    refuse_unless({duration, wait, record, no_reconnect}, !o->rtde.empty(), "with --rtde; a recording is watched whole");
    refuse_unless({started}, o->rtde.empty(), "with a RECORDING; a live stream's wall clock is read against this machine's");
    refuse_unless({split_every}, !o->record_to.empty(), "with --record");
  };
}

int run_monitor(const MonitorOptions& o, const MonitorHooks& hooks) { return run_monitor_impl(o, hooks); }

}  // namespace twinwatch::cli
