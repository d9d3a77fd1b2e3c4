#pragma once
// Shared by `twinwatch evaluate`, `twinwatch report` and `twinwatch demo`: train a reference twin on
// simulated healthy runs, then monitor scenarios and score the events against their labels
// (evaluation code: the only place that reads labels, DESIGN.md rule 1), and write the HTML report.
// What every verb that reads recordings shares is in recordings.hpp.
#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "twinwatch/device/recording.hpp"
#include "twinwatch/ident/controller_torque.hpp"
#include "twinwatch/ident/twin_model.hpp"
#include "twinwatch/monitor/monitor.hpp"
#include "twinwatch/sim/scenario.hpp"

namespace twinwatch::cli {

/// Simulates healthy training runs (seeds not used by the scenario library), identifies the twin
/// and learns the thresholds on further healthy runs. Prints progress unless quiet.
/// residual_filter: the monitor's residual filter the thresholds are learned with (MonitorConfig).
/// joint_torque: the simulated arm has joint torque sensors, and the twin compares them
/// (ident::TwinModel::Signal::JointTorque) instead of the motor currents.
ident::TwinModel train_reference(const std::string& robot, bool quiet, const std::vector<std::string>& residual_filter = {},
                                 bool all_programs = false, bool joint_torque = false);

/// One link choice on a contact's true joint impulse (evaluate --link-ceiling): the share of noise
/// draws it names right, and whether it does without noise (1 right, 0 wrong, -1 not run).
struct LinkReference {
  double noisy = std::numeric_limits<double>::quiet_NaN();
  int exact = -1;
};
/// The link choices of ScenarioScore::link_reference: their JSON keys and their descriptions.
inline constexpr std::array<const char*, 4> kLinkReferenceKeys{"monitor", "monitor_cube", "bayes", "bayes_rest"};
inline constexpr std::array<const char*, 4> kLinkReferenceNames{
    "the monitor's choice, every joint read", "the same, told the generator's point cube",
    "Bayes choice for the generator, every joint read", "Bayes choice for the generator, resting joints hidden by friction"};

struct ScenarioScore {
  std::string name, fault, predicted_class, detail;
  bool has_fault = false, detected = false, class_ok = false, joint_ok = false;
  /// a payload_pick the program declared on a stream that carries the declaration (the scenario's
  /// streams_payload): the twin takes it, so no alert is expected and any event in its window is a
  /// false alarm
  bool declared = false;
  bool has_link = false;  ///< the fault has a link (a contact): link_in_candidates applies
  double delay_ms = 0.0, magnitude = 0.0, true_magnitude = 0.0;
  std::string magnitude_units;  ///< the detecting event's units (N, N·m, kg, A, ...; Event::units)
  double confidence = 0.0;      ///< the detecting event's confidence (Event::confidence)
  int false_alarms = 0;
  int wear_false_alarms = 0;   ///< false alarms that were wear warnings
  double duration_s = 0.0;
  double t_first_wear = std::numeric_limits<double>::quiet_NaN();   ///< [s] first wear warning
  /// healthy scenario: its own false-alarm margin per joint (Monitor::track_margin); empty otherwise
  std::vector<double> margin_current, margin_observer;
  double t_first_alert = std::numeric_limits<double>::quiet_NaN();  ///< [s] first threshold alert (no stream gaps)
  std::string wear_detail;
  int predicted_link = -1;  ///< contact link of the detecting event (0-based; -1: none)
  /// other links the event says fit the joint torques as well (Event::other_links, 0-based)
  std::vector<int> other_links;
  /// a contact whose true link is the named one or one of other_links
  bool link_in_candidates = false;
  /// collisions (evaluation only): the contact's torque on its own link's joint over its largest
  /// joint torque, at the middle of the pulse (near 0: the contact acts like one on the link before)
  double own_joint_share = std::numeric_limits<double>::quiet_NaN();
  /// collisions (evaluation only): the contact's true peak force [N] at the middle of the pulse
  /// (the label's joint-equivalent magnitude over the largest joint torque per newton), and the
  /// force the detecting event reported (NaN: none, e.g. its size was a joint torque)
  double true_force = std::numeric_limits<double>::quiet_NaN(), force = std::numeric_limits<double>::quiet_NaN();
  /// collisions, with evaluate_scenarios' `link_ceiling` (evaluation only): link choices on the true
  /// joint impulse (LinkReference), in the order of kLinkReferences
  std::array<LinkReference, 4> link_reference;
};

struct Evaluation {
  std::vector<ScenarioScore> scores;
  std::vector<std::string> skipped;  // scenarios longer than max_duration (not run)
  int false_alarms = 0, wear_false_alarms = 0;
  double monitored_hours = 0.0;
  /// False-alarm margin over the scenarios without faults (Monitor::track_margin): per joint, the
  /// largest ratio |residual| / threshold that a whole debounce run exceeded, for the current residual
  /// and the momentum observer. Every threshold scaled by a sensitivity below the largest of them
  /// raises an alert on those runs; 1 or more is an alarm at the twin's own sensitivity.
  int healthy_runs = 0;
  double healthy_hours = 0.0;
  std::vector<double> margin_current, margin_observer;
  std::string channel = "current";  ///< the twin's residual, as the margin row names it ("torque": joint torque sensors)
  /// the sensitivity per joint the margins were measured at (the twin's, or evaluate --sensitivity)
  std::vector<double> sensitivity;
  double false_alarms_per_hour() const { return monitored_hours > 0 ? false_alarms / monitored_hours : 0.0; }
};

/// Whether `--max-duration` (0: none) skips scenario `s` in evaluate_scenarios (and so in demo).
inline bool longer_than_max(const sim::Scenario& s, double max_duration) { return max_duration > 0 && s.options.duration > max_duration; }

/// The header of `evaluate --trend-csv`'s file. One row per scenario, joint and closed trend window
/// (monitor::TrendPoint): the window's end [s], its temperature-compensated extra friction and that
/// friction's Coulomb and viscous parts (in the twin's residual unit: A, or N·m for a torque twin),
/// the residual energy sum r² dt, the mean joint temperature [°C], whether the joint moved enough
/// for a fit (1/0), and the window's mean total current I_total [A] (UR3e Fig. 12).
inline constexpr const char* kTrendCsvHeader = "scenario,t,joint,friction,coulomb,viscous,energy,temperature,valid,i_total\n";

/// Runs every scenario file: simulate, monitor with `twin`, score against the labels.
/// `max_duration` skips longer scenarios (0: none skipped). `trend_csv` (may be empty) gets the
/// per-window wear-trend history of every scenario appended. (A report of one run is `twinwatch
/// report`'s, on a recording: `simulate` writes the scenario's.)
/// `link_ceiling` > 0 (evaluation only): for every detected contact the diagnosis isolated, also
/// name the link from the simulator's true joint impulse (J^T F over the pulse), exact and plus white
/// noise at the sd the observer's estimate had on that contact, by the choices of kLinkReferenceNames:
/// the monitor's (every joint read as if moving), the monitor's told the contact generator's point
/// cube (half extent `link_ceiling` [m] around the link's centre of mass), and the Bayes choice for
/// the generator's distribution (that cube, isotropic direction, peak torque log-uniform over the
/// scenarios' range) with every joint read and with resting joints as uncertain as the friction
/// they hold. The last is what the joint torques carry at that noise (docs/validation.md).
Evaluation evaluate_scenarios(const ident::TwinModel& twin, const std::vector<std::string>& files, bool static_threshold,
                              double max_duration, bool quiet, const std::string& trend_csv = "",
                              double link_ceiling = -1.0);

/// Collision-sensitivity sweep [Cao §5]: contacts of decreasing magnitude on several links, each
/// run monitored with the static [UR3e §4.1] and the dynamic [Cao eq. 24] threshold.
struct SweepOptions {
  std::vector<int> links{2, 3, 5};  ///< 1-based links
  std::vector<double> magnitudes{10, 8, 6, 5, 4, 3, 2.5, 2, 1.5, 1.25, 1, 0.75, 0.5};  ///< [N·m] joint-equivalent peak
  unsigned seed = 7000;             ///< first noise seed (one per run; the library and training do not use 7000+)
  double max_delay = 0.2;           ///< [s] an alert later than this after the onset is not a detection of the pulse
  void validate() const;
};
struct SweepRun {
  int link = 0;
  double magnitude = 0.0;
  unsigned seed = 0;
  bool detected[2] = {false, false};           ///< [0] static, [1] dynamic
  double delay_ms[2] = {0.0, 0.0};
  int false_alarms[2] = {0, 0};
};
struct Sweep {
  std::vector<SweepRun> runs;
  /// Per threshold ([0] static, [1] dynamic) and link: the smallest magnitude from which every
  /// larger one in the sweep was detected (NaN: not even the largest).
  std::vector<std::vector<double>> limit;
  /// Per threshold: the smallest magnitude detected on every link (max over links of limit).
  double every_link[2] = {0.0, 0.0};
};
Sweep sweep_collisions(const ident::TwinModel& twin, const SweepOptions& o, bool quiet);
void print_sweep(const Sweep& s, const SweepOptions& o);
std::string sweep_json(const Sweep& s, const SweepOptions& o);

void print_evaluation(const Evaluation& e);
std::string evaluation_json(const Evaluation& e);

/// Writes a self-contained HTML report for recordings monitored by the twin (UR3e Fig. 8-13 style
/// plots and Tables 3/5); several are read as one stream, as `monitor` reads them (StreamScan: the
/// parts `record --split-every` writes); `labels` (evaluation only, one recording): the true faults,
/// shaded.
/// `map`: a foreign log's column map (none: RTDE column names). `keep_payload`: as `monitor
/// --keep-payload` (MonitorConfig::follow_payload off). `adjust`: the user's alert settings over the
/// twin's (monitor's --sensitivity, --static, --raise-after, ...), applied after the program's set.
void write_report(const ident::TwinModel& twin, const std::vector<std::string>& recordings, const model::RigidBodyInertia& payload,
                  const std::string& out, const std::optional<sim::Labels>& labels = std::nullopt, const device::ColumnMap* map = nullptr,
                  const std::string& program = "", bool keep_payload = false,
                  const std::function<void(monitor::MonitorConfig&)>& adjust = {});

}  // namespace twinwatch::cli
