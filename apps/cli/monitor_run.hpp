#pragma once
// `twinwatch monitor`'s loop, shared with `twinwatch serve` (the live dashboard): one loop over a
// recording or an RTDE stream, its options, and hooks through which another front end watches it.
#include <CLI/CLI.hpp>

#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "twinwatch/core/sample.hpp"
#include "twinwatch/monitor/event.hpp"
#include "twinwatch/monitor/monitor.hpp"

namespace twinwatch::cli {

struct MonitorOptions {
  std::string twin, events_path, db_path = "events.db";
  std::vector<std::string> recordings;  // watched as one stream, in order (the parts --split-every writes)
  std::string column_map;  // foreign logs: CSV column -> RTDE name, scale
  std::string trace;  // per-sample residuals and thresholds as CSV
  std::string rtde, record_to;  // live input: controller address, optional copy of the stream
  double split_every = 0.0;      // [s of controller time] --record: a new file this often (0: one file)
  double duration = 0.0, wait = 0.0;
  double payload_mass = std::numeric_limits<double>::quiet_NaN();  // not given: the twin file's payload
  double cycle_period = 0.0;
  std::vector<double> payload_com;
  std::vector<double> sensitivity;
  int raise_after = 0, observer_raise_after = 0;  // debounce overrides (0: the twin's)
  std::string filter;  // residual filter: "iir", "fir" or one per joint "iir,iir,iir,iir,fir,iir"
  std::string program;  // threshold set of this program ("" = the default set)
  std::string started_at;  // a recording: the wall-clock time of its first sample (ISO 8601 with zone)
  bool static_threshold = false, quiet = false, json = false, no_reconnect = false, keep_payload = false;
  bool events_open = false;  // --events-open: a line at each raise and re-diagnosis too ("open": true)
};

/// What another front end sees of the loop (each may be empty). Called on the loop's thread.
struct MonitorHooks {
  /// the monitor is built and the input open; `source`: the recordings or "rtde://HOST[:PORT]"
  std::function<void(const monitor::Monitor&, const std::string& source)> on_start;
  /// before each sample is judged (a replay's pacing)
  std::function<void(const RobotSample&)> before_sample;
  /// after each sample was judged
  std::function<void(const monitor::Monitor&, const RobotSample&)> after_sample;
  /// an alert raised or re-diagnosed (open) or an event closed, as printed (with the envelope's note)
  std::function<void(const monitor::Event&)> on_event;
  std::function<void(double t, const std::string&)> on_note;
  /// about once a second of samples ("monitoring") and at the end ("finished", "stopped", "connection
  /// lost"); `stream`: the RTDE stream's counters ("" for a recording)
  std::function<void(const monitor::Monitor&, const std::string& state, const std::string& stream)> on_status;
  /// polled at each sample of a recording: true stops the replay there (what was watched is reported)
  std::function<bool()> stop_requested;
};

/// Adds monitor's options to `sub` and returns the callback's checks of them (run it first).
std::function<void()> add_monitor_options(CLI::App* sub, const std::shared_ptr<MonitorOptions>& o);
/// The loop; the exit status (0, or 1: the robot stopped answering before the end).
int run_monitor(const MonitorOptions& o, const MonitorHooks& hooks = {});

}  // namespace twinwatch::cli
