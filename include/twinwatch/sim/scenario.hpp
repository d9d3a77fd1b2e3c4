#pragma once
/// @file scenario.hpp
/// Scenario files (YAML): robot, payload, trajectory, duration, rate, noise, seed, faults — the
/// rehearsal a user wants to run on the virtual robot. See docs/scenarios.md for every field.
/// Every malformed field is reported as ParseError(file, line, field, "expected X, got Y").
#include <memory>
#include <string>
#include <vector>

#include "twinwatch/sim/simulator.hpp"

namespace twinwatch::sim {

struct Scenario {
  std::string name;
  std::string path;
  std::string robot = "ur3e";
  SimOptions options;
  std::shared_ptr<const Trajectory> trajectory;
  std::vector<FaultSpec> faults;
  std::vector<double> current_sigma;  ///< per-joint override of the truth's noise (empty: defaults)
  std::string trajectory_type;
  unsigned serial = 1;  ///< which physical robot (hidden parameters); the seed only changes noise
};

/// Loads and validates a scenario file (needs the robot to build Cartesian trajectories).
Scenario load_scenario(const std::string& path);
/// Same from YAML text; `origin` names it in errors.
Scenario parse_scenario(const std::string& text, const std::string& origin);

/// Builds the simulator for a scenario (nominal robot loaded by name/path).
std::unique_ptr<Simulator> make_simulator(const Scenario& s);

/// Ground-truth labels of a scenario as JSON text (fault intervals, magnitudes, units).
/// Only evaluation code may read them (DESIGN.md rule 1).
std::string labels_json(const Scenario& s);

}  // namespace twinwatch::sim
