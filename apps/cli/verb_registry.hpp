#pragma once
// Self-registering CLI verbs. Each verb lives in apps/cli/verbs/<verb>.cpp and registers itself
// with a static VerbRegistrar, so adding a verb never touches main.cpp:
//
//   static twinwatch::cli::VerbRegistrar reg{"model", 20, [](CLI::App& app) {
//     auto* sub = app.add_subcommand("model", "Inspect robot descriptions");
//     ...
//     sub->callback([opts] { twinwatch::cli::set_exit_code(run(*opts)); });
//   }};
//
// The `order` sorts verbs in --help (foundation 10-19, simulator 20-29, ...).
#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <limits>
#include <initializer_list>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "twinwatch/model/robot_model.hpp"
#include "twinwatch/sim/robot_program.hpp"

namespace twinwatch::cli {

using VerbSetup = std::function<void(CLI::App&)>;

struct VerbRegistrar {
  VerbRegistrar(std::string name, int order, VerbSetup setup);
};

/// The exit statuses every verb's --help ends with (a verb that sets a footer of its own appends it:
/// a subcommand's footer replaces the one it inherits).
inline constexpr const char* kExitStatusHelp =
    "Exit status: 0 success; 2 bad usage or bad input (an option, a file's content, an output path), the\n"
    "message naming it; 1 any other failure while running (e.g. a robot that stops answering, a recipe the\n"
    "controller refuses).";

/// A verb's own --help footer with the exit statuses after it.
inline std::string with_exit_status(const std::string& footer) { return footer + "\n\n" + kExitStatusHelp; }

/// Exit code the process returns after the chosen verb ran (0 = success).
void set_exit_code(int code);
int exit_code();

/// Long-running verbs (serve-robot, record, live monitor): Ctrl-C / SIGTERM set a flag that the
/// verb polls, so it can stop cleanly (flush files, say goodbye to clients) instead of dying. A
/// second signal ends the process at once, as an uncaught signal does.
void install_interrupt_handler();
bool interrupted();
/// The signal that set interrupted() (SIGINT, SIGTERM, SIGHUP; 0: none)
int interrupt_signal();

/// Option checks with a readable message: CLI11's PositiveNumber and NonNegativeNumber said
/// "Value 0 not in range 0.000000 to 1797693134862315708...", a 300-digit bound (audit, session 22).
/// The message CLI11 prefixes with the option: "--cycle-period: expected a number > 0, got 0".
const CLI::Validator& positive_number();
const CLI::Validator& nonnegative_number();
/// A whole number from lo to hi: CLI11's Range on an int option said "Value 2.5 not in range 1 to
/// 1000" for 2.5, which is in range and not whole.
CLI::Validator whole_number(long lo, long hi);
/// A finite number from lo to hi [unit]: "expected a number from 0 to 0.1 s, got 'abc'"
CLI::Validator number_in(double lo, double hi, const char* unit);

/// A library's message that begins with one of its fields ("ramp: expected ...", "q0 has 3 values")
/// said with the option the user typed instead ("--ramp: expected ..."): the first `fields` pair
/// (field, option) whose field begins the message, followed by no letter, digit or '_', is replaced.
std::string with_option_names(std::string message, std::initializer_list<std::pair<std::string_view, std::string_view>> fields);

/// An option that does nothing in this run is refused, not ignored (audit, session 34: '--links 9'
/// without --sweep-collisions, '--robot panda' with a --twin file, '--prune' with the physics method
/// were taken without a word). When `applies` is false and any of `options` was given on the command
/// line, throws InvalidArgument "--a, --b apply only WHERE" (an option with a default counts only
/// when given).
void refuse_unless(std::initializer_list<const CLI::Option*> options, bool applies, std::string_view where);

/// --tool-point X Y Z (a point of the tool in the flange frame [m]), repeatable: three numbers an
/// occurrence (CLI11 refuses two), appended to `values`. excite and urscript take it alike.
CLI::Option* add_tool_point_option(CLI::App* sub, std::vector<double>& values, const std::string& help);
/// The --tool-point values as points [m, flange frame].
std::vector<Eigen::Vector3d> tool_points(const std::vector<double>& values);

/// The installation's Robot Limits (PolyScope: Installation > Safety > Robot Limits) that excite
/// designs within and urscript checks, and the tool the flange carries. UR's safety system keeps a
/// motion below each limit by its accuracy (e-Series user manual, functional safety table: speed
/// 50 mm/s, momentum 3 kg·m/s; the CB3 manual's "Tolerances": "the maximum operational speed will
/// be 250 - 150 = 100 mm/s" for its 150 mm/s), slowing the arm before the entered value: a motion
/// is kept within the operational value, the limit less that tolerance.
struct SafetyLimitOptions {
  double tool_speed = 0.0, elbow_speed = 0.0, momentum = 0.0;  ///< as entered; 0: not given
  double speed_tolerance = 0.05;   ///< [m/s] --speed-tolerance
  double momentum_tolerance = 3.0;  ///< [kg·m/s] --momentum-tolerance
  double tool_mass = 0.0;           ///< [kg] --tool-mass: the gripper or tool on the flange
  std::vector<double> tool_cog;     ///< [m] --tool-cog X Y Z, flange frame (default: the flange's centre)
};
/// --tool-speed-limit, --elbow-speed-limit, --momentum-limit, the two tolerances and --tool-mass/--tool-cog.
/// `purpose`: what the verb does with a limit ("keep the design within" / "refuse a program beyond").
void add_safety_limit_options(CLI::App* sub, SafetyLimitOptions& o, const std::string& purpose);
/// One limit the motion is held to: the entered value, the tolerance and the operational value.
struct OperationalLimit {
  const char* option;  ///< "--tool-speed-limit"
  double entered = 0.0, tolerance = 0.0;
  double value() const { return entered - tolerance; }  ///< (infinity when not given)
  bool given() const { return entered > 0.0 && std::isfinite(entered); }
  /// "1.45 m/s (the --tool-speed-limit 1.5 less the safety system's 0.05 m/s tolerance)"
  std::string text(const char* unit) const;
};
/// The three limits as the motion must keep them. Throws InvalidArgument naming the option when a
/// limit is no more than its tolerance (nothing can be kept below it), or when --tool-cog is given
/// without --tool-mass.
std::vector<OperationalLimit> operational_limits(const SafetyLimitOptions& o);
/// What the flange carries: the tool (--tool-mass, a point mass at --tool-cog) joined with `payload`
/// (a scenario's; none for excite), validated, and refused beyond the robot's payload limit naming
/// both. The momentum and the torque count it, and a declared payload is it (URScript's payload is
/// everything on the flange).
model::RigidBodyInertia carried_on_flange(const SafetyLimitOptions& o, const model::RobotModel& robot,
                                          const model::RigidBodyInertia& payload = {});

/// For a program whose motion leaves the joint limits: "; --slow-down K.KK keeps every joint within
/// its speed and acceleration limits (…)" with the factor sim::slow_down_for_joint_limits gives
/// (times the slow-down `given` already applied), or "" when slowing cannot help (a joint's range is
/// left) or needs more than 100 (the option's bound). urscript and simulate --as-program append it.
/// `qdd_cap` as sim::slow_down_for_joint_limits'. The factor is checked on the program built at it
/// (`violation_at(K)`: the program with --slow-down K, its limit violation as text, empty when none)
/// and raised by 1 % until it passes: short ramps are rounded to whole servo periods, so their
/// accelerations do not scale exactly as 1/K² (a review found a suggested factor refused again).
/// When no factor up to 100 fits, or a joint's range is left, it says so instead.
std::string slow_down_remedy(const sim::ProgramMotion& motion, const model::RobotModel& robot, double given, double qdd_cap,
                             const std::function<std::string(double)>& violation_at);

/// Registers every verb on `app`, sorted by order. Called once by main().
void register_all_verbs(CLI::App& app);

}  // namespace twinwatch::cli
