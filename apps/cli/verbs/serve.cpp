// `twinwatch serve`: the monitor with its live dashboard (DESIGN.md, "Interfaces users touch"). The
// loop is monitor's (monitor_run.hpp): the same alerts, events, event store and exit status; the
// dashboard is one more front end of it, fed through MonitorHooks.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <charconv>
#include <chrono>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "twinwatch/core/error.hpp"
#include "recordings.hpp"
#include "monitor_run.hpp"
#include "verb_registry.hpp"

#ifdef TWINWATCH_HAVE_DASHBOARD
#include "twinwatch/ui/dashboard.hpp"
#endif

namespace {

using namespace twinwatch;

struct ServeOptions {
  std::string listen = "127.0.0.1:8080";
  double speed = 1.0;     // a recording's replay: x real time (0: as fast as it is read)
  double window = 120.0;  // [s] of signals the page keeps
  bool exit_when_done = false;
};

#ifdef TWINWATCH_HAVE_DASHBOARD
// "HOST:PORT", "PORT" or "[V6]:PORT" -> host, port
std::pair<std::string, unsigned short> split_listen(const std::string& s) {
  std::string host = "127.0.0.1", port = s;
  const size_t colon = s.rfind(':');
  if (colon != std::string::npos) {
    host = s.substr(0, colon);
    port = s.substr(colon + 1);
    if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
    if (host.empty()) throw InvalidArgument(fmt::format("--listen {}: no host before ':' (e.g. 127.0.0.1:8080, 0.0.0.0:8080 or 8080)", s));
  }
  unsigned value = 0;
  const auto [p, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (port.empty() || ec != std::errc() || p != port.data() + port.size() || value > 65535)
    throw InvalidArgument(fmt::format("--listen {}: the port must be a whole number from 0 to 65535, got '{}'", s, port));
  return {host, static_cast<unsigned short>(value)};
}

bool loopback(const std::string& host) { return host == "localhost" || host.rfind("127.", 0) == 0 || host == "::1"; }

int run_serve(const cli::MonitorOptions& mo, const ServeOptions& so) {
  const auto [host, port] = split_listen(so.listen);
  const ident::TwinModel twin = cli::load_twin(mo.twin);
  const int n_dof = twin.n_dof();
  ui::DashboardSetup setup;
  setup.channel = twin.measures_torque() ? "joint torque" : "current";
  setup.channel_unit = twin.channel_unit();
  setup.title = mo.twin;
  setup.source = mo.rtde.empty() ? fmt::format("{}", fmt::join(mo.recordings, " ")) : "rtde://" + mo.rtde;
  setup.n_dof = n_dof;
  setup.window_s = so.window;
  setup.live = !mo.rtde.empty();
  ui::DashboardFeed feed(setup);
  // listening first: an address in use is said before a long check of the recording or a --wait
  ui::DashboardServer server(feed, host, port);
  const std::string url = fmt::format("http://{}:{}/", host.find(':') != std::string::npos ? "[" + host + "]" : host, server.port());
  cli::install_interrupt_handler();

  cli::MonitorHooks hooks;
  // the address once the options and outputs passed their checks (it was said before an input
  // refused at once, e.g. RECORDING and --rtde both given: audit of session 56), and before the
  // recording's check or the connection, whose progress the page shows
  hooks.on_checked = [&, host = host] {
    if (mo.quiet) return;
    fmt::print(stderr, "dashboard: {}  (open it in a browser; Ctrl-C stops)\n", url);
    if (!loopback(host))
      fmt::print(stderr, "note: {} serves every machine that reaches it, without a password (the page only reads)\n", host);
  };
  using clock = std::chrono::steady_clock;
  clock::time_point wall0;
  double t0 = 0.0;
  bool started = false;
  if (mo.rtde.empty() && so.speed > 0.0)
    hooks.before_sample = [&](const RobotSample& s) {
      // a replay at its own pace: sample k when (t_k - t_0) / speed has passed (a gap in the file is
      // waited through in slices, so that Ctrl-C still stops it)
      if (!started) {
        started = true;
        t0 = s.timestamp;
        wall0 = clock::now();
        return;
      }
      const auto due = wall0 + std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>((s.timestamp - t0) / so.speed));
      while (!cli::interrupted() && clock::now() < due)
        std::this_thread::sleep_until(std::min(due, clock::now() + std::chrono::milliseconds(100)));
    };
  VectorJ observer, observer_threshold;
  hooks.after_sample = [&](const monitor::Monitor& mon, const RobotSample& s) {
    observer = mon.observer_torque();
    observer_threshold = mon.observer_torque_threshold();
    ui::DashboardSignals x;
    x.t = s.timestamp;
    x.measured = s.current.size() == n_dof ? s.current.data() : nullptr;
    x.predicted = mon.predicted_current().size() == n_dof ? mon.predicted_current().data() : nullptr;
    if (mon.filtered_residual().size() == n_dof && mon.level().size() == n_dof) {
      x.residual = mon.filtered_residual().data();
      x.threshold = mon.level().data();
    }
    if (observer.size() == n_dof && observer_threshold.size() == n_dof) {
      x.observer = observer.data();
      x.observer_threshold = observer_threshold.data();
    }
    x.total_current = mon.total_current();
    feed.push(x);
  };
  hooks.on_event = [&](const monitor::Event& e) { feed.event(e.to_json_line(), e.open, e.t_detected, e.withdrawn); };
  hooks.on_note = [&](double t, const std::string& text) { feed.note(t, text); };
  hooks.on_status = [&](const monitor::Monitor& mon, const std::string& state, const std::string& stream) {
    nlohmann::json c = {{"samples", mon.samples()},
                        {"gaps", mon.gaps()},
                        {"events", mon.events_seen()}};
    if (!stream.empty()) c["stream"] = stream;
    feed.status(state, c.dump());
  };
  hooks.stop_requested = [] { return cli::interrupted(); };
  feed.status(mo.rtde.empty() ? "checking the recording" : "connecting", "{}");
  const int code = cli::run_monitor(mo, hooks);
  // a replay's page stays up to be looked at, until Ctrl-C
  if (mo.rtde.empty() && !so.exit_when_done && !cli::interrupted()) {
    if (!mo.quiet) fmt::print(stderr, "replayed; the dashboard stays at {} until Ctrl-C\n", url);
    while (!cli::interrupted()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  server.stop();
  return code;
}
#endif

twinwatch::cli::VerbRegistrar reg_serve{"serve", 44, [](CLI::App& app) {
  auto mo = std::make_shared<cli::MonitorOptions>();
  auto so = std::make_shared<ServeOptions>();
  auto* sub = app.add_subcommand("serve", "Monitor as 'monitor' does and show it live in a browser: residuals, thresholds, alerts, events");
  sub->footer(cli::with_exit_status(
      "The dashboard is one HTML page served by this process (no internet needed): per joint the filtered\n"
      "current residual and its threshold, measured and predicted current, or the momentum observer and\n"
      "its threshold, over the last seconds; I_total; the open alerts; the events; the notes. A script reads\n"
      "the same as JSON: GET /api/state?since=CURSOR (the cursor of the last answer; 0 for everything kept).\n"
      "Alerts, events, --events, --db and the exit status are those of 'twinwatch monitor' with the same options,\n"
      "but Ctrl-C, SIGTERM or SIGHUP, the way a serve ends, exit 0 on a recording too (4 after a live stream's\n"
      "silence of more than 1.5 s before the stop).\n"
      "Examples:\n"
      "  twinwatch serve --twin twin.json --rtde 192.168.1.10              # a robot, page at http://127.0.0.1:8080/\n"
      "  twinwatch serve --twin twin.json rec.csv --speed 5 --listen 0.0.0.0:8080"));
  const auto check = cli::add_monitor_options(sub, mo);
  sub->add_option("--listen", so->listen, "Address of the page: HOST:PORT, or PORT on 127.0.0.1 (0.0.0.0:PORT: every network of this machine)")
      ->capture_default_str();
  auto* speed = sub->add_option("--speed", so->speed,
                                "A recording replays at this multiple of its own pace (1: as it was recorded; 0: as fast as it is read)")
                    ->check(cli::nonnegative_number())
                    ->capture_default_str();
  sub->add_option("--window", so->window, "Seconds of signals the page keeps and can show")
      ->check(CLI::Range(1.0, 3600.0))
      ->capture_default_str();
  auto* done = sub->add_flag("--exit-when-done", so->exit_when_done,
                             "With a recording: exit once it is replayed (default: the page stays up until Ctrl-C)");
  sub->callback([=] {
    check();
    cli::refuse_unless({speed, done}, mo->rtde.empty(), "with a RECORDING; a live robot sets its own pace");
#ifdef TWINWATCH_HAVE_DASHBOARD
    cli::set_exit_code(run_serve(*mo, *so));
#else
    throw InvalidArgument("this twinwatch was built without the dashboard (cmake -DBUILD_DASHBOARD=ON); 'twinwatch monitor' watches without it");
#endif
  });
}};

}  // namespace
