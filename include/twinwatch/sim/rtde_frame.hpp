#pragma once
/// @file rtde_frame.hpp
/// What the virtual robot's controller would put on RTDE for one simulated cycle: a full frame
/// of every output in device::rtde::output_fields(), built from a simulator sample.
///
/// Source of each output (everything the simulator does not model is a documented constant, so a
/// client that asks for it gets a plausible value rather than garbage):
///  - timestamp = sample time + boot offset (a real controller has been up for a while; URCL-based
///    drivers treat small timestamps as a just-booted controller), default 42 s;
///  - actual/target q, qd, qdd, currents, target_moment, joint_temperatures, digital outputs: the
///    sample's values; actual_current_as_torque = target_moment (the controller's torque view);
///  - actual_TCP_pose / target_TCP_pose: forward kinematics of the nominal model at actual_q /
///    target_q (position [m] + rotation vector [rad]); actual_TCP_speed / target_TCP_speed: the
///    flange Jacobian times qd (linear [m/s] + angular [rad/s]);
///  - payload / payload_cog / payload_inertia: the nominal model's current payload;
///  - modes: robot_mode and safety_mode as the sample has them (the simulator's stops), joint_mode 253 (RUNNING), safety_status 1
///    (NORMAL), runtime_state 2 (PLAYING), robot_status_bits 0b11 (power on, program running);
///  - speed_scaling = target_speed_fraction = 1, actual_main_voltage = actual_robot_voltage = 48 V,
///    actual_execution_time 0.3 ms;
///  - everything else (robot current, registers, wrenches, analog I/O, accelerometer, elbow): 0.
#include <vector>

#include "twinwatch/core/sample.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "twinwatch/model/robot_model.hpp"

namespace twinwatch::sim {

class RtdeFrameBuilder {
 public:
  /// @param nominal the robot file's model (the controller's own model), 6 joints.
  /// Throws InvalidArgument if the model does not have 6 joints (RTDE vectors are 6 long).
  explicit RtdeFrameBuilder(const model::RobotModel& nominal, double boot_offset_s = 42.0);

  /// Fills the frame for one sample; `frame` holds device::rtde::frame_scalars() values.
  void fill(const RobotSample& s, double* frame);
  std::vector<double>& frame() { return frame_; }
  const double* build(const RobotSample& s) {
    fill(s, frame_.data());
    return frame_.data();
  }

 private:
  model::RobotModel model_;
  model::DynamicsData data_;
  double boot_;
  std::vector<double> frame_;
  Matrix6J J_;
  int timestamp_, q_, qd_, tq_, tqd_, tqdd_, cur_, tcur_, tmom_, cur_torque_, temp_, apose_, aspeed_, tpose_, tspeed_,
      dout_, robot_mode_, safety_mode_, payload_, payload_cog_, payload_inertia_;
};

}  // namespace twinwatch::sim
