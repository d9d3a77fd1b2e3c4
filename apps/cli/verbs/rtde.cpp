// RTDE verbs:
//   twinwatch record --rtde HOST[:PORT] --frequency 500 --duration 60 -o rec.csv
//   twinwatch serve-robot SCENARIO.yaml [--port 30004] [--speed 1.0]
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <thread>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"
#include "twinwatch/core/log.hpp"
#include "twinwatch/core/wall_clock.hpp"
#include "twinwatch/device/recording.hpp"
#include "twinwatch/device/rtde_client.hpp"
#include "twinwatch/device/rtde_server.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/sim/rtde_frame.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "rtde_source.hpp"
#include "verb_registry.hpp"

namespace {

using namespace twinwatch;
namespace rtde = device::rtde;
using Clock = std::chrono::steady_clock;

using cli::install_interrupt_handler;
using cli::interrupted;

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::size_t b = 0;
  while (b <= s.size()) {
    const std::size_t e = std::min(s.find(',', b), s.size());
    // "timestamp, actual_q" (a space after the comma): the names, not " actual_q", which no
    // controller has and which was then reported as missing
    std::string item = s.substr(b, e - b);
    const auto first = item.find_first_not_of(" \t"), last = item.find_last_not_of(" \t");
    item = first == std::string::npos ? std::string() : item.substr(first, last - first + 1);
    if (!item.empty()) out.push_back(item);
    b = e + 1;
  }
  return out;
}

// ---- record -------------------------------------------------------------------------------

struct RecordOptions {
  std::string endpoint, output, outputs;
  double frequency = 500.0, duration = 60.0, wait = 0.0;
  double split_every = 0.0;  // [s of controller time] a new file this often (0: one file)
  int protocol = 2;
  bool no_reconnect = false, json = false, quiet = false;
  bool outputs_given = false;  // --outputs '' (an unset variable) recorded the default list unsaid
};

int run_record(const RecordOptions& o) {
  if (o.quiet) log::set_level(log::Level::Warn);  // "print nothing on success": no info lines either
  // (an infinite time would overflow the clock arithmetic below)
  if (!(o.duration > 0.0 && std::isfinite(o.duration)))
    throw InvalidArgument(fmt::format("--duration must be a finite time > 0 s, got {}", o.duration));
  if (!(o.wait >= 0.0 && std::isfinite(o.wait)))
    throw InvalidArgument(fmt::format("--wait must be a finite time >= 0 s, got {}", o.wait));
  cli::check_split_every(o.split_every);
  cli::RtdeSourceOptions so;
  so.endpoint = o.endpoint;
  so.frequency = o.frequency;
  so.wait_s = o.wait;
  so.protocol = o.protocol;
  so.reconnect = !o.no_reconnect;
  so.outputs = split_list(o.outputs);
  if (o.outputs_given) {
    if (so.outputs.empty())
      throw InvalidArgument(fmt::format("--outputs: expected a comma-separated list of RTDE output names, got '{}' (an empty value)", o.outputs));
    const auto items = static_cast<size_t>(std::count(o.outputs.begin(), o.outputs.end(), ',')) + 1;
    if (items != so.outputs.size())
      throw InvalidArgument(fmt::format("--outputs '{}': {} of its {} items are empty (two commas in a row, or one at an end)", o.outputs,
                                        items - so.outputs.size(), items));
  }
  // the recording format always has these columns: without them its rows would be nan there, which
  // every reader refuses (a file recorded for nothing)
  if (!so.outputs.empty()) {
    std::vector<std::string> missing;
    for (const char* need : {"timestamp", "actual_q", "actual_qd"})
      if (std::find(so.outputs.begin(), so.outputs.end(), need) == so.outputs.end()) missing.push_back(need);
    if (!missing.empty())
      throw InvalidArgument(fmt::format("--outputs lacks {}: a recording always has timestamp, actual_q and actual_qd (add them to the list)",
                                        fmt::join(missing, ", ")));
  }
  for (const auto& name : so.outputs)
    if (std::find(rtde::default_outputs().begin(), rtde::default_outputs().end(), name) == rtde::default_outputs().end())
      log::warn(fmt::format("'{}' has no column in the recording format; it is requested but not written", name));
  // before connecting: a bad path must not cost a --wait or a connection
  require_writable(device::SplitRecordingWriter::first_file(o.output, o.split_every));
  install_interrupt_handler();
  const auto client_ptr = cli::open_rtde(so);
  rtde::Client& client = *client_ptr;
  const rtde::ClientOptions& co = client.options();
  if (!o.quiet && !o.json)
    fmt::print(stderr, "recording {}:{} ({}) for {:g} s -> {}\n", co.host, co.port, cli::describe(client), o.duration, o.output);

  // one file, or with --split-every a new one each time that much controller time has gone by
  device::SplitRecordingWriter writer(o.output, 6, client.sample_fields(), o.split_every);
  const auto write = [&](const RobotSample& x) { writer.write(x); };
  const bool bar = !o.quiet && !o.json && isatty(STDERR_FILENO);
  const auto t0 = Clock::now();
  const auto end = t0 + std::chrono::duration<double>(o.duration);
  auto next_status = t0;
  RobotSample s;
  double t_first = std::numeric_limits<double>::quiet_NaN(), t_last = t_first;
  auto last_sample = t0;
  // the wall clock of the first sample, for 'monitor --started-at' (a recording has only the
  // controller's clock, which counts from its boot)
  StreamWallClock wall;
  const auto unix_now = [] { return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(); };
  while (Clock::now() < end && !interrupted()) {
    if (client.pop(s, std::chrono::milliseconds(50))) {
      write(s);
      if (std::isnan(t_first) || s.timestamp - t_first < 30.0) wall.sample(s.timestamp, unix_now());
      if (std::isnan(t_first)) t_first = s.timestamp;
      t_last = s.timestamp;
      last_sample = Clock::now();
    } else if (client.finished()) {
      break;
    }
    if (bar && Clock::now() >= next_status) {
      const rtde::ClientStats st = client.stats();
      const double el = std::chrono::duration<double>(Clock::now() - t0).count();
      std::fprintf(stderr, "\r  %5.1f / %g s  %ld samples  lost %ld in %ld gaps  reconnects %ld%s   ", el, o.duration,
                   writer.rows(), st.lost, st.gaps, st.reconnects, st.connected ? "" : "  (disconnected)");
      next_status += std::chrono::milliseconds(250);
    }
  }
  // the connection lost and not restored (or not reconnected, --no-reconnect) before the end: the
  // recording is shorter than asked, and the summary says by how much
  const auto stopped = Clock::now();
  client.stop();
  while (client.pop(s, std::chrono::nanoseconds(0))) {  // nothing already received is lost
    write(s);
    t_last = s.timestamp;
    last_sample = stopped;
  }
  writer.close();
  const long rows = writer.rows();
  const std::vector<std::string>& files = writer.files();
  // (with --no-reconnect the loop ends at the disconnection: what is missing runs to the end asked
  // for; an operator's stop ends the recording where it was asked to, and an outage before it is
  // still said)
  const cli::EndSilence silence = cli::end_silence(stopped, end, last_sample, true, client.stats().frequency);
  const bool ended_early = rows > 0 && silence.lost;
  if (bar) std::fprintf(stderr, "\n");
  const rtde::ClientStats st = client.stats();
  const std::string fatal = client.fatal_error();
  const double cpu_pct = st.wall_seconds > 0 ? 100.0 * st.cpu_seconds / st.wall_seconds : 0.0;
  // |arrival interval − period| is jitter only when the samples come at the controller's pace; a
  // virtual robot served at --speed 10 delivers every 0.2 ms, which is no network's doing
  const bool jitter = st.arrival_jitter_valid();
  const std::string arrival =
      jitter ? fmt::format("arrival jitter p99 {:.2f} ms", 1e3 * st.arrival_p99_s)
      : st.arrival_interval_s > 0.0
          ? fmt::format("arrival jitter not measured: samples arrived every {:.3f} ms, the controller's period is {:.3f} ms "
                        "(a robot served faster or slower than real time?)",
                        1e3 * st.arrival_interval_s, st.frequency > 0.0 ? 1e3 / st.frequency : 0.0)
          : std::string("arrival jitter not measured (fewer than two samples in a row)");
  const std::string started_at = std::isnan(t_first) || !std::isfinite(wall.offset()) ? std::string() : iso_utc(t_first + wall.offset());
  if (o.json) {
    nlohmann::json j = {{"output", o.output},
                        {"files", files},
                        {"host", co.host},
                        {"port", co.port},
                        {"protocol", st.protocol},
                        {"controller_version", fmt::format("{}.{}.{}.{}", st.controller.major, st.controller.minor,
                                                           st.controller.bugfix, st.controller.build)},
                        {"frequency_hz", st.frequency},
                        {"samples", rows},
                        {"robot_time_s", std::isnan(t_first) ? 0.0 : t_last - t_first},
                        {"started_at", started_at.empty() ? nlohmann::json() : nlohmann::json(started_at)},
                        {"received", st.received},
                        {"lost", st.lost},
                        {"gaps", st.gaps},
                        {"dropped", st.dropped},
                        {"reconnects", st.reconnects},
                        {"protocol_errors", st.protocol_errors},
                        {"resent", st.repeated},
                        {"text_messages", st.text_messages},
                        {"arrival_interval_ms", 1e3 * st.arrival_interval_s},
                        {"arrival_jitter_p99_ms", jitter ? nlohmann::json(1e3 * st.arrival_p99_s) : nlohmann::json()},
                        {"arrival_jitter_max_ms", jitter ? nlohmann::json(1e3 * st.arrival_max_s) : nlohmann::json()},
                        {"client_cpu_percent", cpu_pct},
                        {"interrupted", interrupted()},
                        {"silent_at_end_s", ended_early ? silence.seconds : 0.0},
                        {"error", fatal.empty() ? nlohmann::json() : nlohmann::json(fatal)}};
    fmt::print("{}\n", j.dump());
  } else if (!o.quiet) {
    fmt::print("{}: {} samples ({:.2f} s of controller time) from {}:{}; lost {} samples in {} gaps, {} reconnects, "
               "{} dropped by a slow writer, {} protocol errors; {}; client CPU {:.2f} %{}\n",
               o.split_every != 0.0 ? fmt::format("{} files, {} ... {} (a new one every {:g} s)", files.size(), files.front(), files.back(), o.split_every)
                     : o.output,
               rows, std::isnan(t_first) ? 0.0 : t_last - t_first, co.host, co.port, st.lost, st.gaps,
               st.reconnects, st.dropped, st.protocol_errors, arrival, cpu_pct,
               interrupted() ? fmt::format("; stopped by a signal after {:.1f} of the {:g} s asked for",
                                           std::chrono::duration<double>(stopped - t0).count(), o.duration)
                             : "");
    if (!started_at.empty())
      fmt::print("its first sample was taken at {} by this machine's clock: 'twinwatch monitor --started-at {}' gives its events "
                 "wall-clock times\n",
                 started_at, started_at);
  }
  if (ended_early && !o.quiet)
    log::warn(fmt::format("{}: no data for the last {:.1f} s {} (the connection was lost{}): the recording ends at {:.3f} s of "
                          "controller time",
                          o.output, silence.seconds, interrupted() ? "before the stop" : fmt::format("of the {:g} s asked for", o.duration),
                          o.no_reconnect ? ", and --no-reconnect" : " and not restored", t_last));
  if (!fatal.empty()) {
    std::fprintf(stderr, "error: %s\n", fatal.c_str());
    return 1;
  }
  if (rows == 0) {
    std::fprintf(stderr, "error: no samples received from %s:%u\n", co.host.c_str(), co.port);
    return 1;
  }
  // the robot stopped answering: the recording is written and readable, and shorter than it should
  // be, which a script (record && identify) must learn from the status, as the help says
  return ended_early ? 1 : 0;
}

// ---- serve-robot ----------------------------------------------------------------------------

struct ServeOptions {
  std::string scenario, bind = "127.0.0.1", version = "5.23.0.0";
  int port = rtde::kDefaultPort;
  double speed = 1.0, duration = -1.0, wait_client = 0.0;
  long seed = -1;
  bool seed_given = false, duration_given = false;  // (the values above are then the user's)
  bool json = false, quiet = false;
};

// each part a plain whole number that fits the protocol's uint32 (sscanf's %u took "-1" as
// 4294967295 and wrapped 99999999999)
rtde::ControllerVersion parse_version(const std::string& s) {
  std::uint32_t part[4] = {0, 0, 0, 0};
  const char* p = s.data();
  const char* end = s.data() + s.size();
  for (int k = 0; k < 4; ++k) {
    const auto r = std::from_chars(p, end, part[k]);
    const bool last = k == 3;
    if (r.ec != std::errc() || r.ptr == p || (last ? r.ptr != end : (r.ptr == end || *r.ptr != '.')))
      throw InvalidArgument(fmt::format("--controller-version '{}': expected MAJOR.MINOR.BUGFIX.BUILD, four whole numbers 0 to {}, e.g. "
                                        "5.23.0.0",
                                        s, std::numeric_limits<std::uint32_t>::max()));
    p = r.ptr + (last ? 0 : 1);
  }
  rtde::ControllerVersion v;
  v.major = part[0];
  v.minor = part[1];
  v.bugfix = part[2];
  v.build = part[3];
  return v;
}

int run_serve(const ServeOptions& o) {
  if (o.quiet) log::set_level(log::Level::Warn);  // "print nothing on success": no info lines either
  if (!(o.speed > 0.0 && std::isfinite(o.speed))) throw InvalidArgument(fmt::format("--speed must be a finite factor > 0, got {}", o.speed));
  if (o.port < 0 || o.port > 65535) throw InvalidArgument(fmt::format("--port must be in 0..65535, got {}", o.port));
  if (!(o.wait_client >= 0.0 && std::isfinite(o.wait_client)))
    throw InvalidArgument(fmt::format("--wait-client must be a finite time >= 0 s, got {}", o.wait_client));
  if (o.seed_given && (o.seed < 0 || o.seed > static_cast<long>(std::numeric_limits<unsigned>::max())))
    throw InvalidArgument(fmt::format("--seed: expected 0 to {}, got {}", std::numeric_limits<unsigned>::max(), o.seed));
  sim::Scenario sc = sim::load_scenario(o.scenario);
  if (!sc.options.streams_targets)
    throw InvalidArgument(fmt::format("{}: 'streams_targets: false' is a log without the controller's targets, which an RTDE "
                                      "controller always serves; simulate it to a recording instead ('twinwatch simulate {} -o rec.csv')",
                                      o.scenario, o.scenario));
  if (o.seed_given) sc.options.seed = static_cast<unsigned>(o.seed);
  if (o.duration_given) sim::override_duration(sc, o.duration, "--duration");
  auto simulator = sim::make_simulator(sc);
  model::RobotModel nominal = model::load_robot(sc.robot);  // the controller's own model
  if (sc.options.payload_declared) nominal.set_payload(sc.options.payload);
  sim::RtdeFrameBuilder frames(nominal);

  rtde::ServerOptions so;
  so.bind = o.bind;
  so.port = static_cast<std::uint16_t>(o.port);
  so.version = parse_version(o.version);
  so.base_frequency = sc.options.rate;
  rtde::Server server(so);
  server.start();
  install_interrupt_handler();
  if (!o.quiet)
    fmt::print(stderr, "serving '{}' over RTDE on {}:{} at {:g} Hz x{:g} speed for {:g} s of robot time (Ctrl-C stops)\n",
               sc.name, o.bind, server.port(), sc.options.rate, o.speed, sc.options.duration);
  std::fflush(stderr);

  if (o.wait_client > 0) {  // tests and demos: start the robot when someone is listening
    const auto until = Clock::now() + std::chrono::duration<double>(o.wait_client);
    while (!interrupted() && Clock::now() < until && server.stats().streaming == 0)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    // the robot starts either way: say that nobody is watching its first cycles
    if (!interrupted() && server.stats().streaming == 0 && !o.quiet)
      fmt::print(stderr, "--wait-client {:g} s: no client started streaming (connections so far: {}); the robot runs without one\n",
                 o.wait_client, server.stats().connections);
  }

  const long steps = std::llround(sc.options.duration * sc.options.rate);
  const auto period = std::chrono::duration<double>(1.0 / (sc.options.rate * o.speed));
  const bool bar = !o.quiet && !o.json && isatty(STDERR_FILENO);
  RobotSample s;
  long dropped_by_scenario = 0, late = 0;
  const auto t0 = Clock::now();
  long k = 0;
  for (; k < steps && !interrupted(); ++k) {
    const auto due = t0 + std::chrono::duration_cast<Clock::duration>(period * static_cast<double>(k));
    const auto now = Clock::now();
    if (now < due) std::this_thread::sleep_until(due);
    else if (now - due > period) ++late;  // could not keep the pace (machine too slow for --speed)
    if (simulator->step(s)) server.publish(frames.build(s));
    else ++dropped_by_scenario;  // a stream fault of the scenario: this cycle is not sent
    if (bar && k % static_cast<long>(sc.options.rate / 4) == 0) {
      const rtde::ServerStats st = server.stats();
      std::fprintf(stderr, "\r  t = %7.2f s  clients %d  sent %ld  skipped %ld   ", simulator->time(), st.clients,
                   st.packages_sent, st.packages_skipped);
    }
  }
  server.broadcast({rtde::MessageLevel::Info, interrupted() ? "virtual robot stopped by the operator" : "scenario finished",
                    "twinwatch virtual controller"});
  server.stop();
  if (bar) std::fprintf(stderr, "\n");
  const rtde::ServerStats st = server.stats();
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  if (o.json) {
    nlohmann::json j = {{"scenario", sc.name},
                        {"port", server.port()},
                        {"cycles", k},
                        {"robot_time_s", static_cast<double>(k) / sc.options.rate},
                        {"wall_s", wall},
                        {"connections", st.connections},
                        {"packages_sent", st.packages_sent},
                        {"packages_skipped", st.packages_skipped},
                        {"dropped_by_scenario", dropped_by_scenario},
                        {"late_cycles", late},
                        {"protocol_errors", st.protocol_errors},
                        {"interrupted", interrupted()}};
    fmt::print("{}\n", j.dump());
  } else if (!o.quiet) {
    fmt::print("served {} cycles ({:.2f} s of robot time in {:.2f} s) to {} connection(s): {} packages sent, {} skipped "
               "(slow clients), {} withheld by the scenario's stream faults, {} late cycles, {} protocol errors\n",
               k, static_cast<double>(k) / sc.options.rate, wall, st.connections, st.packages_sent, st.packages_skipped,
               dropped_by_scenario, late, st.protocol_errors);
  }
  return 0;
}

twinwatch::cli::VerbRegistrar reg_record{"record", 30, [](CLI::App& app) {
  auto o = std::make_shared<RecordOptions>();
  auto* sub = app.add_subcommand("record", "Record a robot's RTDE stream to a recording CSV (the simulator's format)");
  sub->footer(twinwatch::cli::with_exit_status(
      "Ctrl-C, SIGTERM or SIGHUP stop it in order: what was received is written and the summary says the\n"
      "run was stopped. The exit status is then 0, or 1 when the stream had been silent for more than 1.5 s\n"
      "before the stop (a warning says for how long), as at the end of --duration. A second signal ends it at\n"
      "once (128 + the signal)."));
  sub->add_option("--rtde", o->endpoint, "Controller address HOST[:PORT] (port 30004 by default)")->required();
  sub->add_option("-o,--output", o->output, "Recording CSV to write")->required();
  sub->add_option("--frequency", o->frequency, "Output rate [Hz], 0 < f <= 500 (CB3: 125)")->capture_default_str();
  sub->add_option("--duration", o->duration, "How long to record [s of wall-clock time]")->capture_default_str();
  sub->add_option("--split-every", o->split_every,
                  "Start a new file each time this much controller time has gone by [s, >= 1]: -o rec.csv writes rec.000.csv, "
                  "rec.001.csv, ..., each with the header (default: one file; 500 Hz is 1.74 GB per hour)");
  auto* outputs = sub->add_option("--outputs", o->outputs,
                  "Comma-separated RTDE output names (default: every recording column: timestamp, actual_q, actual_qd, "
                  "target_q, target_qd, target_qdd, actual_current, target_current, target_moment, joint_temperatures, "
                  "actual_digital_output_bits, robot_mode, safety_mode, and from controller 5.5.1 on the declared payload and payload_cog; a "
                  "list must include timestamp, actual_q and actual_qd)");
  sub->add_option("--wait", o->wait, "Keep trying the first connection for this long [s]")->capture_default_str();
  sub->add_option("--protocol", o->protocol, "Highest RTDE protocol version to ask for (2, or 1 for old controllers)")
      ->check(CLI::IsMember({1, 2}))
      ->capture_default_str();
  sub->add_flag("--no-reconnect", o->no_reconnect, "Stop at the first disconnection instead of reconnecting with back-off");
  sub->add_flag("--json", o->json, "Print the summary as one JSON object");
  sub->add_flag("-q,--quiet", o->quiet, "Print nothing on success but the JSON that --json asks for");
  sub->callback([o, outputs] {
    o->outputs_given = outputs->count() > 0;
    twinwatch::cli::set_exit_code(run_record(*o));
  });
}};

twinwatch::cli::VerbRegistrar reg_serve{"serve-robot", 31, [](CLI::App& app) {
  auto o = std::make_shared<ServeOptions>();
  auto* sub = app.add_subcommand("serve-robot", "Run the virtual robot in real time and serve it over RTDE like a UR e-Series controller");
  sub->footer(twinwatch::cli::with_exit_status(
      "Ctrl-C, SIGTERM or SIGHUP stop it in order (its clients are told, the summary printed): exit status 0.\n"
      "A second signal ends it at once (128 + the signal)."));
  sub->add_option("SCENARIO", o->scenario, "Scenario YAML (see scenarios/ur3e/ and docs/scenarios.md)")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--port", o->port, "TCP port (0: any free port, printed at start)")->capture_default_str();
  sub->add_option("--bind", o->bind, "Address to listen on (0.0.0.0 for other machines)")->capture_default_str();
  sub->add_option("--speed", o->speed, "Real-time factor (2 = twice as fast; timestamps stay in robot time)")->capture_default_str();
  auto* duration = sub->add_option("--duration", o->duration, "Override the scenario's duration [s of robot time]");
  auto* seed = sub->add_option("--seed", o->seed, "Override the scenario's seed");
  sub->add_option("--controller-version", o->version, "Version to report to clients")->capture_default_str();
  sub->add_option("--wait-client", o->wait_client, "Hold the robot until a client starts streaming (a client that only connects does not release it), for at most this long [s]");
  sub->add_flag("--json", o->json, "Print the summary as one JSON object");
  sub->add_flag("-q,--quiet", o->quiet, "Print nothing on success but the JSON that --json asks for");
  sub->callback([o, duration, seed] {
    o->duration_given = duration->count() > 0;
    o->seed_given = seed->count() > 0;
    twinwatch::cli::set_exit_code(run_serve(*o));
  });
}};

}  // namespace
