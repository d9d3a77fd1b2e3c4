#pragma once
/// @file dashboard.hpp
/// The live dashboard (DESIGN.md, "twinwatch serve"): what a running monitor shows a browser.
///
/// - `DashboardFeed` is filled by the monitoring loop, sample by sample, and read by the server's
///   thread. It keeps a window of the recent signals at a display rate (a point per interval, each
///   joint's point the sample of the interval closest to its threshold, so a 16 ms contact pulse is
///   drawn at its peak), the alerts open now, the events closed, the notes and a status line.
/// - `DashboardServer` serves it over HTTP (Boost.Beast): `GET /` the page (one self-contained HTML
///   file, no external URL), `GET /api/state?since=N` what is new since cursor N as JSON.
///
/// The feed knows nothing of the monitor: the loop hands it numbers and the events' JSON lines, so
/// data still flow one way (sample -> residual -> decision -> event -> display).
#include <cstdint>
#include <memory>
#include <string>

namespace twinwatch::ui {

/// What the page says the dashboard watches.
struct DashboardSetup {
  std::string title;           ///< e.g. the twin file
  std::string source;          ///< the recording(s) or "rtde://host:port"
  int n_dof = 6;               ///< joints (1..7)
  double window_s = 120.0;     ///< [s] of signals kept (and drawn); > 0
  double points_per_s = 50.0;  ///< display rate [1/s]; > 0
  bool live = false;           ///< a robot, not a recording replayed
  /// the twin's measured channel, as the page labels it: "current" [A], or "joint torque" [N·m] (a
  /// twin of joint torque sensors, whose signals below are then torques)
  std::string channel = "current";
  std::string channel_unit = "A";

  /// Throws InvalidArgument naming the first field out of range.
  void validate() const;
};

/// One sample's signals as the loop hands them over; each pointer to n_dof values.
struct DashboardSignals {
  double t = 0.0;                          ///< controller time [s]
  const double* measured = nullptr;        ///< actual current [A]
  const double* predicted = nullptr;       ///< the twin's current [A]
  const double* residual = nullptr;        ///< filtered current residual [A]
  const double* threshold = nullptr;       ///< its threshold [A] (> 0)
  const double* observer = nullptr;        ///< momentum-observer residual [N·m]; may be null
  const double* observer_threshold = nullptr;  ///< its threshold [N·m]
  double total_current = 0.0;              ///< I_total = sum |i_j| [A]
};

/// Thread-safe store between the monitoring loop (writer) and the server (readers).
class DashboardFeed {
 public:
  /// Throws InvalidArgument (setup.validate()).
  explicit DashboardFeed(DashboardSetup setup);
  ~DashboardFeed();
  DashboardFeed(const DashboardFeed&) = delete;
  DashboardFeed& operator=(const DashboardFeed&) = delete;

  /// Called for every sample: one point per 1/points_per_s of controller time is kept. Each joint's
  /// residual and threshold come from the sample of the interval with the largest |residual| /
  /// threshold (the observer's likewise), the currents and I_total from the interval's last sample.
  /// A time that goes back (another file, a reconnection) starts a new interval. Allocates only when
  /// a point is kept (the window's deque).
  void push(const DashboardSignals& s);
  /// An alert raised or re-diagnosed (`open`), or an event closed; `json` is the event's JSON line
  /// (monitor::Event::to_json_line), `key` the alert's raise time, which names it while open.
  /// `withdrawn`: the alert ends without an event of its own (monitor::Monitor::on_withdraw): it
  /// leaves the open alerts and is not listed among the events.
  void event(const std::string& json, bool open, double key, bool withdrawn = false);
  /// A note of the monitor (a payload declaration taken, an excursion beyond the identified motion).
  void note(double t, const std::string& text);
  /// The status line: `state` ("monitoring", "finished", "connection lost", ...) and a JSON object of
  /// counters (samples, gaps, events, stream statistics) the page prints as it is.
  void status(const std::string& state, const std::string& counters_json);

  /// Everything newer than `since` (0: the whole window) as a JSON object:
  /// {"cursor": N, "setup": {...}, "status": {...}, "points": {"t": [...], "residual": [[J1...],...], ...},
  ///  "active": [event, ...], "events": [event, ...], "notes": [{"t":..,"text":..}, ...]}.
  /// Pass the returned cursor next time. A cursor from before the window gets the whole window.
  std::string json_since(std::uint64_t since) const;
  /// The cursor of the newest item.
  std::uint64_t cursor() const;
  const DashboardSetup& setup() const { return setup_; }

 private:
  struct State;  // the window, the alerts, the events, the notes, the status (under its mutex)
  DashboardSetup setup_;
  std::unique_ptr<State> st_;
};

/// The HTTP server of a feed: a thread of its own, serving until stopped or destroyed.
class DashboardServer {
 public:
  /// Listens on `host`:`port` (port 0: one the system picks; see port()). Throws PathError when the
  /// address cannot be listened on (in use, not this machine's, no permission), naming it.
  DashboardServer(const DashboardFeed& feed, const std::string& host, unsigned short port);
  ~DashboardServer();
  DashboardServer(const DashboardServer&) = delete;
  DashboardServer& operator=(const DashboardServer&) = delete;

  /// The port listened on.
  unsigned short port() const;
  /// Requests answered so far (any status).
  long requests() const;
  /// Stops listening and closes the connections; idempotent.
  void stop();

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// The page `GET /` serves (web/dashboard.html, compiled in).
const std::string& dashboard_page();

}  // namespace twinwatch::ui
