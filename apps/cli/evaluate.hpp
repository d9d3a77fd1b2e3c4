#pragma once
// Shared by `twinwatch evaluate` and `twinwatch demo`: train a reference twin on simulated healthy
// runs, then monitor scenarios and score the events against their labels (evaluation code: the
// only place that reads labels, DESIGN.md rule 1).
#include <string>
#include <vector>

#include "twinwatch/ident/twin_model.hpp"

namespace twinwatch::cli {

/// Simulates healthy training runs (seeds not used by the scenario library), identifies the twin
/// and learns the thresholds on further healthy runs. Prints progress unless quiet.
/// residual_filter: the monitor's residual filter the thresholds are learned with (MonitorConfig).
ident::TwinModel train_reference(const std::string& robot, bool quiet, const std::vector<std::string>& residual_filter = {});

struct ScenarioScore {
  std::string name, fault, predicted_class, detail;
  bool has_fault = false, detected = false, class_ok = false, joint_ok = false;
  double delay_ms = 0.0, magnitude = 0.0, true_magnitude = 0.0;
  int false_alarms = 0;
  double duration_s = 0.0;
};

struct Evaluation {
  std::vector<ScenarioScore> scores;
  int false_alarms = 0;
  double monitored_hours = 0.0;
  double false_alarms_per_hour() const { return monitored_hours > 0 ? false_alarms / monitored_hours : 0.0; }
};

/// Runs every scenario file: simulate, monitor with `twin`, score against the labels.
/// `max_duration` skips longer scenarios (0: none skipped). `report_dir` (may be empty) gets one
/// HTML report per scenario.
Evaluation evaluate_scenarios(const ident::TwinModel& twin, const std::vector<std::string>& files, bool static_threshold,
                              double max_duration, bool quiet, const std::string& report_dir = "");

void print_evaluation(const Evaluation& e);
std::string evaluation_json(const Evaluation& e);

/// Writes a self-contained HTML report for one recording monitored by the twin (UR3e Fig. 8-13
/// style plots and Tables 3/5).
void write_report(const ident::TwinModel& twin, const std::string& recording, double payload_mass,
                  const std::vector<double>& payload_com, const std::string& out, const std::string& labels_json = "");

}  // namespace twinwatch::cli
