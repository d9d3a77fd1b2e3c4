#pragma once
// Which arm a recording comes from, as its controller says it: the controller computes its torque
// (RTDE target_moment) with its own model of the arm it drives, along its targets (target_q, _qd,
// _qdd) and with the payload its program declares. The arm's description reproduces that torque up
// to friction and the feedback (relative rms 0.05-0.17 on the virtual UR3e and UR5e), another arm's
// does not (0.6-2.2: a UR5e's shoulder carries 20-35 N·m more than a UR3e's). identify checks the
// robot it is given, or its default, against each recording with it, and the verbs that read a
// recording with a twin (monitor, validate, report, thresholds) check the twin's arm (session 46: a
// UR5e's recordings identified with the default --robot ur3e gave a twin whose gains were 15-45 %
// low, with nothing said).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "twinwatch/core/sample.hpp"
#include "twinwatch/core/types.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "twinwatch/model/robot_model.hpp"

namespace twinwatch::ident {

struct ControllerTorqueFit {
  /// sqrt(sum over samples and joints of (target_moment - RNEA(targets))^2 / sum of target_moment^2)
  double relative_rms = 0.0;
  VectorJ rms;          ///< [N·m] per joint
  size_t samples = 0;   ///< the samples compared (0: no targets and torque, or a torque of zeros)
};

/// The fit accumulated sample by sample (every `stride`-th sample that carries finite targets and
/// torque, of those where the controller drives the arm: robot_mode RUNNING, safety_mode NORMAL). The declared payload (kFieldPayload) is attached where the sample carries it, else none.
/// A recording without target_qdd (a joint-torque twin reads none: device::ColumnMap::joint_torque_as_current)
/// is compared at the middle of each step between two such samples: the acceleration the difference
/// of target_qd over the step, the positions, velocities and torque the means of its ends (the
/// targets are smooth and noise-free; second order in the 2 ms step).
class ControllerTorqueAccumulator {
 public:
  explicit ControllerTorqueAccumulator(const model::RobotModel& robot, size_t stride = 1);
  void add(const RobotSample& s);
  ControllerTorqueFit fit() const;
  const model::RobotModel& robot() const { return model_; }

 private:
  model::RobotModel model_;
  model::DynamicsData data_;
  size_t stride_, seen_ = 0, samples_ = 0;
  VectorJ e2_;
  // the previous sample's targets and torque (a recording without target_qdd), if it was one to compare
  bool previous_ok_ = false;
  double previous_t_ = 0.0;
  VectorJ previous_q_, previous_qd_, previous_moment_, q_, qd_, qdd_, moment_;
  double t2_ = 0.0, declared_ = -1.0;
  Eigen::Vector3d declared_cog_ = Eigen::Vector3d::Zero();
};

/// A recording's fit to its supposed arm and to every other built-in arm of the same joint count.
struct ArmVerdict {
  ControllerTorqueFit own;
  std::string better;         ///< another built-in arm that fits clearly better (empty: none)
  ControllerTorqueFit theirs; ///< its fit
  /// another arm fits more than 3 times better, below 0.3 (the arm's own: 0.05-0.17)
  bool other_arm() const { return !better.empty(); }
  /// the arm's own model reproduces the torque only beyond 0.3 (another arm, an undeclared payload)
  bool poor() const { return own.samples > 0 && own.relative_rms > 0.3; }
};
class ArmCheck {
 public:
  explicit ArmCheck(const model::RobotModel& robot, size_t stride = 1);
  void add(const RobotSample& s);
  ArmVerdict verdict() const;

 private:
  std::vector<ControllerTorqueAccumulator> fits_;  // [0]: the robot's own
};

}  // namespace twinwatch::ident
