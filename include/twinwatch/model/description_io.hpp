#pragma once
/// @file description_io.hpp
/// Loading robot descriptions: the project's JSON format (standard or modified DH, per-link
/// inertials, per-joint drives and limits) and URDF (via urdfdom). See robot_model.hpp for the
/// frame conventions every loader maps onto.
///
/// Errors: a malformed or physically invalid file throws twinwatch::ParseError naming the file,
/// the field path (e.g. "joints[3].inertia") and, where known, the line; an unknown robot name
/// throws InvalidArgument listing the robots that exist.
#include <string>
#include <vector>

#include "twinwatch/model/robot_model.hpp"

namespace twinwatch::model {

/// Loads a description from a JSON file (see docs/robot-description.md for the format).
RobotDescription load_description_json(const std::string& path);

/// Parses a JSON description from a string; `origin` names it in error messages.
RobotDescription parse_description_json(const std::string& text, const std::string& origin);

/// Bound on a description's lengths (DH lengths, offsets, centres of mass) [m]: beyond it a value
/// is a unit slip (mm for m), not a real arm's.
inline constexpr double kMaxDescriptionLength = 5.0;

/// Throws ParseError naming `origin` and the joint when the arm cannot hold its own weight: the
/// gravity torque at poses spread over the joints' ranges more than five times a joint's published
/// torque limit (masses in grams). Both loaders call it.
void check_holds_itself(const RobotDescription& d, const std::string& origin);

/// Loads a serial chain from a URDF file, from `base_link` to `tip_link` (empty: the root, and the
/// leaf below the most revolute/continuous joints; a tie is an error naming the leaves). Fixed
/// joints on the chain are merged; revolute/continuous joints become joints.
RobotDescription load_description_urdf(const std::string& path, const std::string& base_link = "",
                                       const std::string& tip_link = "");

/// Loads a robot by built-in name ("ur3e", "ur5e", "ur10e", "panda": data/robots/<name>.json) or by path
/// to a .json or .urdf file; "FILE.urdf#TIP" takes the chain from the root to the link TIP (without
/// it, the leaf below the most revolute joints).
RobotModel load_robot(const std::string& name_or_path);

/// The description file of a robot reference as load_robot takes it ("arm.urdf#tool0" -> "arm.urdf",
/// "arm.json" -> "arm.json"), or "" for a built-in name; `tip` gets the "#TIP" part ("" without one).
std::string robot_file(const std::string& name_or_path, std::string* tip = nullptr);

/// Names of the built-in robots (files in the data/robots directory).
std::vector<std::string> builtin_robot_names();

/// Directory holding the built-in robot files: data_directory("robots") ($TWINWATCH_DATA_DIR/robots,
/// an installed share/twinwatch/robots, or the source tree's data/robots; core/data_dir.hpp).
std::string robots_directory();

}  // namespace twinwatch::model
