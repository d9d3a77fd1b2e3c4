#pragma once
// The virtual UR3e as a recording in memory, for the monitor tests (shared by several test files).
#include <string>

#include "twinwatch/device/recording.hpp"
#include "twinwatch/sim/scenario.hpp"

namespace twinwatch::monitor::test {

inline const char* kFig8 = "{type: figure_eight, size: [0.12, 0.08], period: 8, tilt: [0.3, 0.4, 0.5]}";

/// Runs a YAML scenario text and keeps every sample (500 Hz).
inline device::Recording run(const std::string& yaml) {
  const sim::Scenario s = sim::parse_scenario(yaml, "test");
  device::Recording rec;
  rec.n_dof = 6;
  rec.median_period = 0.002;
  const auto simulator = sim::make_simulator(s);
  rec.present = simulator->sample_fields();
  simulator->run([&](const RobotSample& x) { rec.samples.push_back(x); });
  return rec;
}

/// The same recording without the payload the controller declares (a controller before 5.5.1, or a
/// recording without the payload columns): the program's picks are then the monitor's to find.
inline device::Recording undeclared(device::Recording rec) {
  rec.present &= ~kFieldPayload;
  for (auto& s : rec.samples) s.present &= ~kFieldPayload;
  return rec;
}

/// Figure-eight scenario text with a seed, duration [s], payload [kg] at (0, 0, 0.04) m and faults.
inline std::string scenario(unsigned seed, double duration, double payload, const std::string& faults = "") {
  std::string y = "robot: ur3e\nseed: " + std::to_string(seed) + "\nduration: " + std::to_string(duration) + "\ntrajectory: " + kFig8 + "\n";
  if (payload > 0) y += "payload: {mass: " + std::to_string(payload) + ", com: [0, 0, 0.04]}\n";
  if (!faults.empty()) y += "faults:\n" + faults;
  return y;
}

}  // namespace twinwatch::monitor::test
