#pragma once
/// @file robot_model.hpp
/// The fixed description of a serial robot arm and its drives.
///
/// Frame conventions (read this before adding a loader):
/// - The base frame is the world frame; `gravity` is given in it (default (0, 0, -9.81) m/s²).
/// - Every joint is revolute about the **z axis of its joint frame**. Joint i's frame is placed in
///   its parent body's frame (the base for joint 0) by the constant `placement`. The body frame of
///   the link that joint i moves is `placement * Rz(q_i + q_offset_i)`: it rotates with the joint
///   and its origin lies on the joint axis.
/// - Standard DH (UR): T_i = Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i). Body i is then the frame *before*
///   Tz Tx Rx, i.e. placement_{i+1} = Tz(d_i) Tx(a_i) Rx(α_i), and UR's published COMs/inertias (given
///   in DH frame i) are re-expressed in body i by that same constant transform (see
///   description_io.hpp). The flange is placement_{n+1}.
/// - Modified DH (Craig, Franka): T_i = Rx(α_{i-1}) Tx(a_{i-1}) Rz(θ_i) Tz(d_i), so
///   placement_i = Rx(α_{i-1}) Tx(a_{i-1}) Tz(d_i) and body i is MDH frame i.
/// - URDF: placement = joint origin (xyz, rpy) followed by a rotation taking z onto the joint axis.
/// - Inertial data of a body: mass [kg], centre of mass [m] in the body frame, rotational inertia
///   [kg·m²] about the centre of mass with axes of the body frame.
/// - A payload is a rigid body fixed to the flange; its COM and inertia are given in the flange
///   frame. It is merged into the last link for dynamics and can change at run time.
#include <Eigen/Geometry>
#include <array>
#include <limits>
#include <string>
#include <vector>

#include "twinwatch/core/types.hpp"

namespace twinwatch::model {

/// The 10 standard inertial parameters of a link [m, m·cx, m·cy, m·cz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz],
/// with the inertia about the **body-frame origin** (not the COM). Units kg, kg·m, kg·m².
using StandardParameters = Eigen::Matrix<double, 10, 1>;

/// A payload's centre of mass farther than this from the flange is no part an arm carries (a UR arm
/// reaches 0.5-1.3 m): most likely a value in mm. Scenarios and --known-payload refuse it, the monitor
/// does not take such a declaration (monitor::kDeclaredCogMax) [m]
constexpr double kPayloadComMax = 1.0;

/// Inertial parameters of one rigid body, expressed in that body's frame.
struct RigidBodyInertia {
  double mass = 0.0;                                        ///< [kg]
  Eigen::Vector3d com = Eigen::Vector3d::Zero();            ///< [m] in the body frame
  Eigen::Matrix3d inertia_com = Eigen::Matrix3d::Zero();    ///< [kg·m²] about the COM, body axes

  /// The 10 standard parameters (inertia about the body origin, Steiner's theorem).
  StandardParameters to_standard_parameters() const;
  /// Inverse of to_standard_parameters(). A zero mass gives a zero COM.
  static RigidBodyInertia from_standard_parameters(const StandardParameters& pi);
  /// The same body expressed in another frame F, where `F_T_this` maps this frame's
  /// coordinates into F's.
  RigidBodyInertia expressed_in(const Eigen::Isometry3d& F_T_this) const;
  /// Two bodies rigidly joined (both expressed in the same frame).
  RigidBodyInertia operator+(const RigidBodyInertia& other) const;
  /// Throws InvalidArgument naming `what` when the mass is negative or not finite, or the inertia
  /// is not symmetric, not positive semi-definite or violates the triangle inequality.
  void validate(const std::string& what) const;
};

/// Limits of one joint.
struct JointLimits {
  double q_min = -std::numeric_limits<double>::infinity();   ///< [rad]
  double q_max = std::numeric_limits<double>::infinity();    ///< [rad]
  double qd_max = std::numeric_limits<double>::infinity();   ///< [rad/s], > 0
  double qdd_max = std::numeric_limits<double>::infinity();  ///< [rad/s²], > 0 (infinite: not published)
  double torque_max = std::numeric_limits<double>::infinity();  ///< [N·m] joint side, > 0
};

/// Drive train of one joint: motor current ↔ joint torque (UR3e paper eq. 3):
///   tau = i * kt * N * eta
/// with eta the motoring efficiency when power flows from motor to load (sign(tau) == sign(qd))
/// and `efficiency_reverse` when the load back-drives the motor.
/// Unknown values are NaN and must be identified (twinwatch identify); never invent them.
struct DriveParams {
  double gear_ratio = std::numeric_limits<double>::quiet_NaN();       ///< N [-]
  double torque_constant = std::numeric_limits<double>::quiet_NaN();  ///< kt [N·m/A], motor side
  double efficiency = 1.0;          ///< eta, motoring, in (0, 1]
  double efficiency_reverse = 1.0;  ///< eta when back-driven, in (0, 1]
  double current_limit = std::numeric_limits<double>::infinity();  ///< [A]

  /// True when both N and kt are known numbers.
  bool gains_known() const;
};

/// One revolute joint and the link it moves.
struct Joint {
  std::string name;
  Eigen::Isometry3d placement = Eigen::Isometry3d::Identity();  ///< parent body → joint frame at q = 0
  double q_offset = 0.0;   ///< body = placement * Rz(q + q_offset) [rad]
  RigidBodyInertia body;   ///< the link moved by this joint, in its body frame
  JointLimits limits;
  DriveParams drive;
};

/// Plain description data, as loaded from a file; turned into a RobotModel to be used.
struct RobotDescription {
  std::string name;                 ///< e.g. "ur3e"
  std::string source;               ///< file it was loaded from ("" if built in code)
  std::vector<Joint> joints;        ///< base to tip
  Eigen::Isometry3d flange = Eigen::Isometry3d::Identity();  ///< last body → flange (tool0)
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};                  ///< [m/s²] in the base frame
  /// [kg] the manufacturer's rated payload (the description's "rated_payload"); NaN: not given
  double rated_payload = std::numeric_limits<double>::quiet_NaN();
  /// [m] where the elbow's housing lies along the elbow joint's axis (the third joint's z), from the
  /// point where the kinematic chain crosses it to its far end: the description's "elbow_housing"
  /// [from, to]. A UR's upper arm and forearm are offset sideways from that point (UR3e: forearm
  /// 0.027 m, upper arm 0.120 m), and the housing joins them. {0, 0}: the chain's point itself.
  Eigen::Vector2d elbow_housing = Eigen::Vector2d::Zero();
};

namespace detail {
/// Hot-path cache of one link, rebuilt whenever the description or payload changes.
struct LinkCache {
  Eigen::Matrix3d R0;   ///< placement rotation (parent → joint frame)
  Eigen::Vector3d p;    ///< placement translation [m], in the parent frame
  double q_offset;      ///< [rad]
  double m;             ///< [kg] (payload merged on the last link)
  Eigen::Vector3d h;    ///< first moment m·c [kg·m], body frame
  Eigen::Matrix3d I_o;  ///< inertia about the body origin [kg·m²], body frame
  double cos_alpha;     ///< R0 = Rx(alpha) when RobotModel::placements_about_x(): its cos and sin
  double sin_alpha;
};
}  // namespace detail

/// A validated robot description with its hot-path caches and the current payload.
class RobotModel {
 public:
  /// Validates the description (≥ 1 and ≤ kMaxDof joints, valid inertias and limits, unit
  /// rotations) and builds the caches. Throws InvalidArgument naming the joint and field.
  explicit RobotModel(RobotDescription description);

  int n_dof() const { return n_dof_; }
  const std::string& name() const { return description_.name; }
  const RobotDescription& description() const { return description_; }
  const Joint& joint(int i) const { return description_.joints.at(static_cast<size_t>(i)); }
  const Eigen::Vector3d& gravity() const { return description_.gravity; }
  /// Sets the gravity vector [m/s²] in the base frame (e.g. a tilted mounting).
  void set_gravity(const Eigen::Vector3d& g) { description_.gravity = g; }

  /// Attaches a payload (COM and inertia in the flange frame); replaces any previous one.
  /// Throws InvalidArgument if the payload is not physical.
  void set_payload(const RigidBodyInertia& payload_in_flange);
  /// Removes the payload (equivalent to a zero-mass payload).
  void clear_payload() { set_payload(RigidBodyInertia{}); }
  /// The current payload, in the flange frame.
  const RigidBodyInertia& payload() const { return payload_; }

  /// Replaces link i's inertial parameters (body frame), e.g. after identification. Clears any
  /// parameters set by set_standard_parameters().
  void set_link_inertia(int i, const RigidBodyInertia& body);

  /// Replaces the dynamic parameters of every link by a standard-parameter vector (10 per link, in
  /// regressor column order: m, m·c, inertia about the body origin xx xy xz yy yz zz) that need not
  /// be physical — e.g. a base-parameter fit mapped to standard parameters, so that RNEA evaluates
  /// Y(q,qd,qdd)·pi exactly (the dynamics are linear in these parameters). The payload is still
  /// added on the last link. Kinematics are unchanged. Only the inverse-dynamics kernels (rnea,
  /// gravity, nonlinear effects) are meaningful with non-physical parameters. Throws
  /// InvalidArgument on a size mismatch or a non-finite value.
  void set_standard_parameters(const Eigen::VectorXd& pi);

  /// True when every placement rotation is exactly Rx(alpha) (DH and modified DH descriptions);
  /// the forward pass then rotates with 12 instead of 15 flops per vector.
  bool placements_about_x() const { return placements_about_x_; }

  /// The largest payload a program may declare or a scenario may carry [kg]: the rated payload, or
  /// for a description without one the mass of the links the joints move (a payload heavier than the
  /// arm itself is a typo, not a program). payload_limit_text() says which, e.g. "the rated payload
  /// of ur3e".
  double payload_limit() const;
  std::string payload_limit_text() const;

  /// Cached per-link data for the dynamics kernels.
  const detail::LinkCache& link_cache(int i) const { return cache_[static_cast<size_t>(i)]; }

 private:
  void rebuild_cache();

  RobotDescription description_;
  RigidBodyInertia payload_;
  Eigen::VectorXd standard_override_;  // empty: parameters come from the description
  int n_dof_ = 0;
  bool placements_about_x_ = false;
  std::array<detail::LinkCache, kMaxDof> cache_{};
};

}  // namespace twinwatch::model
