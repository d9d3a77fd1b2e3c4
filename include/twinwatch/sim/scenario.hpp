#pragma once
/// @file scenario.hpp
/// Scenario files (YAML): robot, payload, trajectory, duration, rate, noise, seed, faults — the
/// rehearsal a user wants to run on the virtual robot. See docs/scenarios.md for every field.
/// Every malformed field is reported as ParseError(file, line, field, "expected X, got Y"), and so is
/// a scenario the robot cannot run: a trajectory beyond its joint position or velocity limits, a
/// payload above model::RobotModel::payload_limit() (the rated payload, else the moving mass), a
/// fault that would start after the end, a repeated key.
#include <limits>
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
  std::vector<double> joint_torque_sigma;  ///< [N·m] per-joint override of the torque sensors' noise (empty: defaults)
  std::string trajectory_type;
  /// The robot program this run is (the file's optional `program`): whose threshold set `evaluate`
  /// monitors it with, as 'monitor --program' would; empty: the trajectory type's set, if the twin
  /// has one, else the default set
  std::string program;
  int trajectory_line = 0;  ///< line of `trajectory:` in the file (0: unknown), for later errors
  unsigned serial = 1;  ///< which physical robot (hidden parameters); the seed only changes noise
};

/// Loads and validates a scenario file (needs the robot to build Cartesian trajectories). `robot`
/// (a name or description file) runs it on another robot than the file's `robot`, validated for
/// that one (its joint limits, its rated payload); empty: the file's. `trajectory_limits` false
/// leaves out the check of the trajectory against the joint limits, for a caller that runs the
/// motion as a robot program and checks the program's own motion (slowed, ramped: urscript,
/// simulate --as-program; a UR3e swing at 2.64 rad/s runs on a UR10e's 2.09 rad/s base only slowed).
Scenario load_scenario(const std::string& path, const std::string& robot = "", bool trajectory_limits = true);
/// Same from YAML text; `origin` names it in errors.
Scenario parse_scenario(const std::string& text, const std::string& origin, const std::string& robot = "",
                        bool trajectory_limits = true);

/// Replaces the scenario's duration [s] by a command-line override and checks it as the file's own:
/// duration_problem() and the trajectory's joint limits over the new run. A fault that starts at or
/// after the new end stays in the scenario (and its labels) but does not fire: a warning is logged.
/// @param option the override's name in errors, e.g. "--duration". Throws InvalidArgument.
/// @param trajectory_limits false: the joint limits are left to the caller's check of the program
/// it runs (as load_scenario's).
void override_duration(Scenario& s, double duration, const std::string& option, bool trajectory_limits = true);

/// Builds the simulator for a scenario (nominal robot loaded by name/path).
std::unique_ptr<Simulator> make_simulator(const Scenario& s);

/// Ground-truth labels of a scenario as JSON text (fault intervals, magnitudes, units).
/// Only evaluation code may read them (DESIGN.md rule 1).
std::string labels_json(const Scenario& s);

/// One fault of a labels file, as labels_json writes it.
struct FaultLabel {
  FaultType type = FaultType::Resistance;
  double onset = 0.0;  ///< [s]
  double ramp = 0.0;   ///< [s]
  double end = std::numeric_limits<double>::infinity();  ///< [s] (infinity: to the end of the run)
  double magnitude = 0.0;  ///< in `units`
  int joint = -1;      ///< 0-based (-1: none)
  int link = -1;       ///< 0-based (-1: none)
  std::string units;
};

/// A labels file (labels_json).
struct Labels {
  std::string scenario;
  unsigned seed = 0;
  double duration = 0.0;  ///< [s]
  double rate = 0.0;      ///< [Hz]
  std::vector<FaultLabel> faults;
};

/// Reads the text of a labels file (labels_json); `origin` names it in errors. Every field
/// labels_json writes is required, a key it does not write is an error, and each value is checked
/// (a known fault type, onset >= 0, end after onset or null, joint and link from 1 or null, the
/// type's units). Only evaluation code may read labels (DESIGN.md rule 1).
/// Throws ParseError(origin, 0, JSON path, "expected X, got Y").
Labels parse_labels(const std::string& text, const std::string& origin);

}  // namespace twinwatch::sim
