#include "twinwatch/sim/rtde_frame.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>

#include "twinwatch/core/error.hpp"
#include "twinwatch/device/rtde_protocol.hpp"

namespace twinwatch::sim {

namespace rtde = device::rtde;

namespace {

int slot_of(const char* name) {
  const rtde::FieldInfo* f = rtde::find_output_field(name);
  if (!f) throw std::logic_error(fmt::format("RTDE output table has no '{}'", name));  // table and builder disagree: a bug
  return f->slot;
}

void put_constant(std::vector<double>& frame, const char* name, double v) {
  const rtde::FieldInfo* f = rtde::find_output_field(name);
  std::fill_n(frame.begin() + f->slot, rtde::value_count(f->type), v);
}

// Position [m] and rotation vector [rad], as UR reports poses.
void put_pose(const Eigen::Isometry3d& T, double* out) {
  const Eigen::AngleAxisd aa(T.linear());
  const Eigen::Vector3d rv = aa.angle() * aa.axis();
  for (int k = 0; k < 3; ++k) {
    out[k] = T.translation()[k];
    out[3 + k] = rv[k];
  }
}

void put6(const VectorJ& v, double* out) {
  for (int k = 0; k < 6; ++k) out[k] = v[k];
}

}  // namespace

RtdeFrameBuilder::RtdeFrameBuilder(const model::RobotModel& nominal, double boot_offset_s)
    : model_(nominal), data_(model_), boot_(boot_offset_s), frame_(static_cast<std::size_t>(rtde::frame_scalars()), 0.0) {
  if (nominal.n_dof() != 6)
    throw InvalidArgument(fmt::format("RTDE serves 6-joint arms; robot '{}' has {} joints", nominal.name(), nominal.n_dof()));
  timestamp_ = slot_of("timestamp");
  q_ = slot_of("actual_q");
  qd_ = slot_of("actual_qd");
  tq_ = slot_of("target_q");
  tqd_ = slot_of("target_qd");
  tqdd_ = slot_of("target_qdd");
  cur_ = slot_of("actual_current");
  tcur_ = slot_of("target_current");
  tmom_ = slot_of("target_moment");
  cur_torque_ = slot_of("actual_current_as_torque");
  temp_ = slot_of("joint_temperatures");
  apose_ = slot_of("actual_TCP_pose");
  aspeed_ = slot_of("actual_TCP_speed");
  tpose_ = slot_of("target_TCP_pose");
  tspeed_ = slot_of("target_TCP_speed");
  dout_ = slot_of("actual_digital_output_bits");
  robot_mode_ = slot_of("robot_mode");
  safety_mode_ = slot_of("safety_mode");
  payload_ = slot_of("payload");
  payload_cog_ = slot_of("payload_cog");
  payload_inertia_ = slot_of("payload_inertia");
  put_constant(frame_, "joint_mode", 253);
  put_constant(frame_, "safety_status", 1);
  put_constant(frame_, "runtime_state", 2);
  put_constant(frame_, "robot_status_bits", 3);
  put_constant(frame_, "speed_scaling", 1.0);
  put_constant(frame_, "target_speed_fraction", 1.0);
  put_constant(frame_, "actual_main_voltage", 48.0);
  put_constant(frame_, "actual_robot_voltage", 48.0);
  put_constant(frame_, "actual_execution_time", 0.3);
}

void RtdeFrameBuilder::fill(const RobotSample& s, double* f) {
  if (f != frame_.data()) std::copy(frame_.begin(), frame_.end(), f);
  f[timestamp_] = s.timestamp + boot_;
  put6(s.q, f + q_);
  put6(s.qd, f + qd_);
  put6(s.target_q, f + tq_);
  put6(s.target_qd, f + tqd_);
  put6(s.target_qdd, f + tqdd_);
  put6(s.current, f + cur_);
  put6(s.target_current, f + tcur_);
  put6(s.target_moment, f + tmom_);
  put6(s.target_moment, f + cur_torque_);
  put6(s.temperature, f + temp_);
  f[dout_] = static_cast<double>(s.digital_outputs);
  f[robot_mode_] = s.robot_mode;
  f[safety_mode_] = s.safety_mode;

  put_pose(model::forward_kinematics(model_, data_, s.q), f + apose_);
  model::point_jacobian(model_, data_, 5, model_.description().flange.translation(), J_);
  Eigen::Map<Eigen::Matrix<double, 6, 1>>(f + aspeed_) = J_ * s.qd;
  put_pose(model::forward_kinematics(model_, data_, s.target_q), f + tpose_);
  model::point_jacobian(model_, data_, 5, model_.description().flange.translation(), J_);
  Eigen::Map<Eigen::Matrix<double, 6, 1>>(f + tspeed_) = J_ * s.target_qd;

  // the payload the program declared: the sample's when the simulator streams it (it follows the
  // program's set_payload at a pick), else the one the controller was set up with
  const model::RigidBodyInertia& p = model_.payload();
  const bool streamed = s.has(kFieldPayload);
  const bool same = !streamed || (s.payload == p.mass && s.payload_cog[0] == p.com[0] && s.payload_cog[1] == p.com[1] &&
                                  s.payload_cog[2] == p.com[2]);
  f[payload_] = streamed ? s.payload : p.mass;
  for (int k = 0; k < 3; ++k) f[payload_cog_ + k] = streamed ? s.payload_cog[k] : p.com[k];
  // payload_inertia: Ixx, Iyy, Izz, Ixy, Ixz, Iyz about the COM [kg·m²] (a declared part other than
  // the set-up one: a point mass, as the simulator's picks are)
  const Eigen::Matrix3d I = same ? p.inertia_com : Eigen::Matrix3d::Zero();
  const double pi[6] = {I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2)};
  std::copy(pi, pi + 6, f + payload_inertia_);
}

}  // namespace twinwatch::sim
