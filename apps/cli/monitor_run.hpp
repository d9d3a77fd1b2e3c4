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
#include "twinwatch/ident/twin_model.hpp"
#include "twinwatch/monitor/event.hpp"
#include "twinwatch/monitor/monitor.hpp"
#include "mqtt_sink.hpp"

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
  std::vector<double> part_com;  // where an undeclared part sits [m, flange frame] (empty: the twin's)
  std::vector<double> sensitivity;
  int raise_after = 0, observer_raise_after = 0;  // debounce overrides (0: the twin's)
  std::string filter;  // residual filter: "iir", "fir" or one per joint "iir,iir,iir,iir,fir,iir"
  std::string program;  // threshold set of this program ("" = the default set)
  std::string started_at;  // a recording: the wall-clock time of its first sample (ISO 8601 with zone)
  bool static_threshold = false, quiet = false, json = false, no_reconnect = false, keep_payload = false;
  bool events_open = false;  // --events-open: a line at each raise and re-diagnosis too ("open": true)
  bool events_append = false;  // --events-append: add to the --events file instead of replacing it
  MqttCliOptions mqtt;       // --mqtt: the events and the run's state to a broker
  std::vector<std::string> fail_on;  // --fail-on: event classes (or "any") that make the exit status 3
};
/// monitor's exit status when an event of a --fail-on class was found (and the run otherwise ended 0)
inline constexpr int kExitEventsFound = 3;
/// monitor --rtde's exit status when a signal stopped it while the stream was silent (the robot
/// switched off, a cable pulled): an operator's stop, not a failure, but the silence before it was not
/// watched (a stream_fault event says so). Its own status, so that a service manager can take it as a
/// clean stop (the systemd unit's SuccessExitStatus) while a connection lost at --duration's end stays 1
inline constexpr int kExitStoppedInOutage = 4;

/// What another front end sees of the loop (each may be empty). Called on the loop's thread.
struct MonitorHooks {
  /// the options, the twin and every output path passed their checks; nothing read or connected yet
  /// (serve says its address here, not before an input that is refused in a second)
  std::function<void()> on_checked;
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

// What monitor's options share with `report` and `evaluate` (verbs/evaluate.cpp), which apply them
// to the run they make: the help texts, the --program check, the filter list, the alert settings.
inline const CLI::Validator kProgramNameGiven(  // --program '' (an unset $PROG) named no program and silently meant the default set
    [](std::string& v) { return v.empty() ? std::string("the program name is empty (an unset variable?); leave --program out for the default set") : std::string(); },
    "NAME");
inline constexpr const char* kColumnMapHelp =
    "CSV map 'file_column,rtde_name[,scale]' for foreign logs (docs/recordings.md), as given to 'twinwatch identify'; a bare "
    "name is one of the maps twinwatch ships (e.g. kinova_gen3_chiha)";
inline constexpr const char* kSensitivityHelp =
    "Threshold factor (< 1: more sensitive): one value, or one per joint separated by commas (0.9,0.9,1,1,1,1)";
inline constexpr const char* kFilterHelp =
    "Residual filter: 'iir' (first order at the twin's filter_cutoff_hz, AGV §4.3), 'fir' (Cao eq. 29: 6 taps, "
    "-3 dB at 42.8 Hz at 500 Hz, 2.5-sample delay), or one per joint, e.g. iir,iir,iir,iir,fir,iir";
inline constexpr const char* kRaiseAfterHelp =
    "Consecutive samples over the current-residual threshold that raise an alert (default: the twin's, 2); the momentum "
    "observer's channel then uses it too, instead of the twin's per-joint count, unless --observer-raise-after is given or the "
    "twin sets observer_raise_after";
inline constexpr const char* kObserverRaiseAfterHelp =
    "Consecutive samples over the momentum observer's threshold that raise an alert, on every joint (default: the twin's "
    "count per joint, chosen on healthy validation runs ('thresholds --debounce-validation'); else --raise-after). 1 "
    "raises contacts one sample earlier but leaves less margin against false alarms (docs/validation.md, 'Observer debounce')";
/// --filter "iir" | "fir" | "k1,k2,...,kn" -> MonitorConfig::residual_filter (checked by validate())
std::vector<std::string> split_filter(const std::string& s);
inline constexpr const char* kPartComHelp =
    "Where a part the robot picks sits when the twin holds no payload (none declared; with one, a change is fitted at "
    "its centre of mass) [m, flange frame; 3 numbers] (default: the twin's "
    "part_com_m, else 0 0 0.04): a payload change is fitted there and, followed, predicted as a point mass there. A part "
    "held farther out than assumed leaves a model error at the wrist after the twin follows it (false alarms)";
/// --part-com X Y Z: where a part picked with no payload declared sits (MonitorConfig::part_com) over
/// the twin's; empty: keep it. Throws InvalidArgument naming the option for a point beyond 1 m.
void apply_part_com(monitor::MonitorConfig& cfg, const std::vector<double>& xyz);
/// The twin's monitor block; throws InvalidArgument naming `path` when it has none
monitor::MonitorConfig config_of(const ident::TwinModel& twin, const std::string& path);
/// --sensitivity, --raise-after, --observer-raise-after: user settings over the twin's monitor block
/// (0 / empty: keep the twin's); validated with the rest of the configuration
void apply_alert_settings(monitor::MonitorConfig& cfg, int n_dof, const std::vector<double>& sensitivity, int raise_after,
                          int observer_raise_after);

/// Adds monitor's options to `sub` and returns the callback's checks of them (run it first).
std::function<void()> add_monitor_options(CLI::App* sub, const std::shared_ptr<MonitorOptions>& o);
/// The loop; the exit status (0, or 1: the robot stopped answering before the end).
int run_monitor(const MonitorOptions& o, const MonitorHooks& hooks = {});

}  // namespace twinwatch::cli
