#pragma once
/// @file dynamics.hpp
/// Kinematics and rigid-body dynamics of a serial chain of revolute joints.
///
/// All kernels take the fixed description (RobotModel) and a mutable workspace (DynamicsData)
/// allocated once; they allocate nothing and return references into the workspace, valid until
/// the next call that writes the same field.
///
/// References:
/// - [Featherstone2008] R. Featherstone, Rigid Body Dynamics Algorithms, Springer 2008:
///   RNEA (ch. 5.3), CRBA (ch. 6.2).
/// - [Luh1980] J. Y. S. Luh, M. W. Walker, R. P. C. Paul, "On-line computational scheme for
///   mechanical manipulators", J. Dyn. Sys. Meas. Control 102(2), 1980 — the recursive
///   Newton-Euler algorithm in link frames used here.
#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <array>
#include <vector>

#include "twinwatch/core/types.hpp"
#include "twinwatch/model/robot_model.hpp"

namespace twinwatch::model {

/// Workspace for the kernels below. Construct once per model (n_dof is fixed), reuse per sample.
struct DynamicsData {
  explicit DynamicsData(const RobotModel& model);

  int n_dof;
  // per-body recursion state, body frames
  std::array<Eigen::Matrix3d, kMaxDof> R;   ///< parent_R_body at the current q
  std::array<Eigen::Vector3d, kMaxDof> w;   ///< angular velocity [rad/s]
  std::array<Eigen::Vector3d, kMaxDof> wd;  ///< angular acceleration [rad/s²]
  std::array<Eigen::Vector3d, kMaxDof> a;   ///< linear acceleration of the body origin incl. -g [m/s²]
  std::array<Eigen::Vector3d, kMaxDof> f;   ///< force from parent onto body [N]
  std::array<Eigen::Vector3d, kMaxDof> n;   ///< moment from parent onto body about its origin [N·m]
  // composite rigid bodies (CRBA)
  std::array<double, kMaxDof> mc;
  std::array<Eigen::Vector3d, kMaxDof> hc;
  std::array<Eigen::Matrix3d, kMaxDof> Ic;
  // world poses after forward_kinematics()
  std::array<Eigen::Isometry3d, kMaxDof> oMi;  ///< base → body i
  Eigen::Isometry3d oMf;                        ///< base → flange
  // outputs
  VectorJ tau;   ///< joint torques [N·m]
  VectorJ qdd;   ///< joint accelerations [rad/s²]
  MatrixJ M;     ///< joint-space mass matrix [kg·m²]
  Eigen::LLT<MatrixJ> llt;
};

/// Forward kinematics: fills data.R, data.oMi (base → each body) and data.oMf (base → flange).
/// @param q joint positions [rad], size n_dof. Throws InvalidArgument on a size mismatch.
/// @return data.oMf
const Eigen::Isometry3d& forward_kinematics(const RobotModel& model, DynamicsData& data, const VectorJ& q);

/// Geometric Jacobian of a point fixed on body `link` (0-based), expressed in the base frame:
/// rows 0-2 map qd to the point's linear velocity [m/s], rows 3-5 to the body's angular velocity
/// [rad/s]. Columns of joints after `link` are zero. Uses data.oMi, so call forward_kinematics first.
/// @param point point on the body, in the body frame [m]
/// @param J output, resized to 6 × n_dof
void point_jacobian(const RobotModel& model, const DynamicsData& data, int link, const Eigen::Vector3d& point,
                    Matrix6J& J);

/// The linear speeds and the momentum a UR installation's safety limits bound (PolyScope:
/// Installation > Safety > Robot Limits: tool speed, elbow speed, momentum), at one state. Each is
/// linear in qd at a fixed q. Calls forward_kinematics.
struct CartesianSpeeds {
  double tool = 0.0;     ///< [m/s] the largest linear speed of the flange's centre and the tool points
  int tool_point = -1;   ///< which: -1 the flange's centre, k tool point k
  /// [m/s] the speed of the elbow: the larger of the speeds at the two ends of its housing on the
  /// elbow joint's axis (RobotDescription::elbow_housing; a point's speed is affine along the axis,
  /// so no point of the housing's axis between them is faster); NaN for an arm of fewer than three
  /// joints, which has none
  double elbow = 0.0;
  double momentum = 0.0;  ///< [kg·m/s] |sum m v| over the links' centres of mass and the payload's
};
/// @param tool_points points of the tool in the flange frame [m]
/// @param payload the part the flange carries (flange frame), counted in the momentum
/// Throws InvalidArgument on a size mismatch.
CartesianSpeeds cartesian_speeds(const RobotModel& model, DynamicsData& data, const VectorJ& q, const VectorJ& qd,
                                 const std::vector<Eigen::Vector3d>& tool_points, const RigidBodyInertia& payload);

/// Recursive Newton-Euler inverse dynamics [Luh1980]:
///   tau = M(q) qdd + C(q, qd) qd + g(q)
/// @param q [rad], qd [rad/s], qdd [rad/s²], each size n_dof
/// @return data.tau [N·m]
const VectorJ& rnea(const RobotModel& model, DynamicsData& data, const VectorJ& q, const VectorJ& qd,
                    const VectorJ& qdd);

/// Inverse dynamics at two accelerations of the same state: returns data.tau = rnea(q, qd, qdd)
/// and writes tau2 = rnea(q, qd, qdd2), for about 1.5 RNEAs. Torques only: unlike rnea, it leaves
/// the rest of the workspace (body motion and wrenches) as it was
/// (tau2 = tau + M(q) (qdd2 - qdd) by a Newton-Euler pass over the first pass's rotations).
const VectorJ& rnea_pair(const RobotModel& model, DynamicsData& data, const VectorJ& q, const VectorJ& qd, const VectorJ& qdd,
                         const VectorJ& qdd2, VectorJ& tau2);

/// Gravity torque g(q) [N·m] (RNEA with qd = qdd = 0). @return data.tau
const VectorJ& gravity_torque(const RobotModel& model, DynamicsData& data, const VectorJ& q);

/// Nonlinear effects C(q, qd) qd + g(q) [N·m] (RNEA with qdd = 0). @return data.tau
const VectorJ& nonlinear_effects(const RobotModel& model, DynamicsData& data, const VectorJ& q, const VectorJ& qd);

/// Coriolis and centrifugal torque C(q, qd) qd [N·m], without gravity. @return data.tau
const VectorJ& coriolis_torque(const RobotModel& model, DynamicsData& data, const VectorJ& q, const VectorJ& qd);

/// Joint-space mass matrix M(q) by the composite-rigid-body algorithm [Featherstone2008, ch. 6.2].
/// Fills the full symmetric matrix. @return data.M [kg·m²]
const MatrixJ& crba(const RobotModel& model, DynamicsData& data, const VectorJ& q);

/// Forward dynamics qdd = M(q)^-1 (tau - C(q, qd) qd - g(q)) by CRBA + Cholesky.
/// @param tau applied joint torques [N·m]. @return data.qdd [rad/s²]
const VectorJ& forward_dynamics(const RobotModel& model, DynamicsData& data, const VectorJ& q, const VectorJ& qd,
                                const VectorJ& tau);

/// Kinetic energy 1/2 qd^T M qd [J].
double kinetic_energy(const RobotModel& model, DynamicsData& data, const VectorJ& q, const VectorJ& qd);

/// Potential energy -sum_i m_i g^T c_i [J], zero at the base origin.
double potential_energy(const RobotModel& model, DynamicsData& data, const VectorJ& q);

}  // namespace twinwatch::model
