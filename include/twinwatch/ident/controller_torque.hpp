#pragma once
// Which arm a recording comes from, as its controller says it: the controller computes its torque
// (RTDE target_moment) with its own model of the arm it drives, along its targets (target_q, _qd,
// _qdd) and with the payload its program declares. The arm's description reproduces that torque up
// to friction and the feedback (relative rms 0.05-0.17 on the virtual UR3e and UR5e), another arm's
// does not (0.6-2.2: a UR5e's shoulder carries 20-35 N·m more than a UR3e's). identify checks the
// robot it is given, or its default, against the recordings with it (session 46: a UR5e's
// recordings identified with the default --robot ur3e gave a twin whose gains were 15-45 % low, with
// nothing said).
#include <string>
#include <vector>

#include "twinwatch/core/types.hpp"
#include "twinwatch/device/recording.hpp"
#include "twinwatch/model/robot_model.hpp"

namespace twinwatch::ident {

struct ControllerTorqueFit {
  /// sqrt(sum over samples and joints of (target_moment - RNEA(targets))^2 / sum of target_moment^2)
  double relative_rms = 0.0;
  VectorJ rms;          ///< [N·m] per joint
  size_t samples = 0;   ///< the samples compared (0: the recordings carry no targets and torque, or a torque of zeros)
};

/// The fit of `robot` to the controller's torque over `recordings` (at most `max_samples`, spread
/// evenly over them; samples without finite targets or torque are left out). The declared payload
/// (kFieldPayload) is attached where the recording carries it, else none. Recordings of another
/// joint count than the robot's, or without target_q/_qd/_qdd and target_moment, give samples 0.
ControllerTorqueFit controller_torque_fit(const model::RobotModel& robot, const std::vector<const device::Recording*>& recordings,
                                          size_t max_samples = 20000);

}  // namespace twinwatch::ident
