#pragma once
/// @file sample.hpp
/// One sample of what a robot controller streams: the unit that flows through
///   device (RTDE / recording / simulator) -> monitor (residual -> decision -> event).
/// Field names follow the RTDE output names (../shared/reference/rtde-protocol.md) so a sample
/// maps 1:1 onto a recording row. Fields a source does not provide are NaN (vectors) and the
/// matching bit in `present` is clear.
#include <cstdint>
#include <limits>

#include "twinwatch/core/types.hpp"

namespace twinwatch {

/// Which optional fields of a RobotSample are filled.
enum SampleField : std::uint32_t {
  kFieldTargetQ = 1u << 0,
  kFieldTargetQd = 1u << 1,
  kFieldTargetQdd = 1u << 2,
  kFieldActualCurrent = 1u << 3,
  kFieldTargetCurrent = 1u << 4,
  kFieldTemperature = 1u << 5,
  kFieldDigitalOutputs = 1u << 6,
  kFieldRobotMode = 1u << 7,
  kFieldTargetMoment = 1u << 8,
  kFieldActualQd = 1u << 9,
  kFieldStreamGap = 1u << 10,  ///< the source marks stream gaps itself (RTDE client: lost samples, reconnects)
  kFieldJointTorque = 1u << 11,      ///< measured joint torque (joint torque sensors; not an RTDE output)
  kFieldCurrentAsTorque = 1u << 12,  ///< actual_current_as_torque (the controller's current-derived torque)
  kFieldPayload = 1u << 13,  ///< payload + payload_cog: the payload the program declares (RTDE, controller >= 5.5.1)
  kFieldSafetyMode = 1u << 14,  ///< safety_mode (RTDE): normal, reduced, protective stop, emergency stop, ...
};

/// RTDE robot_mode 7: powered, brakes released, the controller drives the joints
/// (../shared/reference/rtde-protocol.md; every other mode: off, booting, idle with brakes on, backdrive).
inline constexpr std::int32_t kRobotModeRunning = 7;
/// RTDE safety_mode 1 (NORMAL) and 2 (REDUCED): the safety system lets the program run; 3 and up are
/// stops (protective, safeguard, emergency), recovery, violation and fault.
inline constexpr std::int32_t kSafetyModeNormal = 1;
inline constexpr std::int32_t kSafetyModeReduced = 2;

/// One controller cycle. Units: rad, rad/s, rad/s², A, °C, N·m, s.
struct RobotSample {
  double timestamp = 0.0;           ///< controller time [s] (RTDE `timestamp`)
  VectorJ q;                        ///< actual_q [rad]
  VectorJ qd;                       ///< actual_qd [rad/s]
  VectorJ target_q;                 ///< target_q [rad]
  VectorJ target_qd;                ///< target_qd [rad/s]
  VectorJ target_qdd;               ///< target_qdd [rad/s²]
  VectorJ current;                  ///< actual_current [A]
  VectorJ target_current;           ///< target_current [A]
  VectorJ target_moment;            ///< target_moment [N·m]
  VectorJ temperature;              ///< joint_temperatures [°C]
  VectorJ joint_torque;             ///< actual_joint_torque [N·m]: joint torque sensors (Panda, Kinova); twinwatch name
  VectorJ current_as_torque;        ///< actual_current_as_torque [N·m] (RTDE; or a foreign log's current-derived torque)
  std::uint64_t digital_outputs = 0;  ///< actual_digital_output_bits
  std::int32_t robot_mode = 7;        ///< robot_mode (7 = RUNNING)
  std::int32_t safety_mode = 1;       ///< safety_mode (1 = NORMAL, 3 = PROTECTIVE_STOP, 7 = ROBOT_EMERGENCY_STOP, ...)
  /// payload [kg] and payload_cog [m, in the tool flange frame]: what the program declares it
  /// carries (set_payload; RTDE outputs of controllers >= 5.5.1). NaN unless kFieldPayload.
  double payload = std::numeric_limits<double>::quiet_NaN();
  double payload_cog[3] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN(),
                           std::numeric_limits<double>::quiet_NaN()};
  std::uint32_t present = 0;          ///< OR of SampleField flags
  bool gap_before = false;            ///< samples were lost just before this one (stream fault marker)
  /// of those, the samples this computer dropped (a live source's queue was full: its consumer fell
  /// behind the stream); the controller sent them
  std::uint32_t dropped_before = 0;

  /// A sample for n joints with every vector sized n and set to NaN, nothing present.
  static RobotSample empty(int n) {
    RobotSample s;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (VectorJ* v : {&s.q, &s.qd, &s.target_q, &s.target_qd, &s.target_qdd, &s.current, &s.target_current,
                       &s.target_moment, &s.temperature, &s.joint_torque, &s.current_as_torque})
      v->setConstant(n, nan);
    return s;
  }
  int n_dof() const { return static_cast<int>(q.size()); }
  bool has(SampleField f) const { return (present & f) != 0; }
  /// The controller drives the arm under normal or reduced safety (robot_mode RUNNING, safety_mode
  /// NORMAL or REDUCED), or the stream does not say otherwise: what a twin of the driven arm predicts.
  bool driven() const {
    return (!has(kFieldRobotMode) || robot_mode == kRobotModeRunning) &&
           (!has(kFieldSafetyMode) || safety_mode == kSafetyModeNormal || safety_mode == kSafetyModeReduced);
  }
};

}  // namespace twinwatch
