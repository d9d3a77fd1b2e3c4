#include "twinwatch/model/robot_model.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::model {

namespace {
// tolerance for symmetry / triangle inequality of inertia tensors, relative to their trace:
// loose enough for values published with 4-7 significant digits.
constexpr double kInertiaRelTol = 1e-6;
// tolerance on R^T R = I for placement rotations given with ~9 digits (e.g. rpy of pi/2).
constexpr double kRotationTol = 1e-6;

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return S;
}
}  // namespace

StandardParameters RigidBodyInertia::to_standard_parameters() const {
  // Steiner: I_o = I_c + m * (c^T c * 1 - c c^T) = I_c - m [c]x [c]x
  const Eigen::Matrix3d S = skew(com);
  const Eigen::Matrix3d I_o = inertia_com - mass * S * S;
  StandardParameters pi;
  pi << mass, mass * com.x(), mass * com.y(), mass * com.z(), I_o(0, 0), I_o(0, 1), I_o(0, 2), I_o(1, 1),
      I_o(1, 2), I_o(2, 2);
  return pi;
}

RigidBodyInertia RigidBodyInertia::from_standard_parameters(const StandardParameters& pi) {
  RigidBodyInertia b;
  b.mass = pi(0);
  b.com = pi(0) != 0.0 ? Eigen::Vector3d(pi.segment<3>(1) / pi(0)) : Eigen::Vector3d::Zero();
  Eigen::Matrix3d I_o;
  I_o << pi(4), pi(5), pi(6), pi(5), pi(7), pi(8), pi(6), pi(8), pi(9);
  const Eigen::Matrix3d S = skew(b.com);
  b.inertia_com = I_o + b.mass * S * S;
  return b;
}

RigidBodyInertia RigidBodyInertia::expressed_in(const Eigen::Isometry3d& F_T_this) const {
  RigidBodyInertia b;
  const Eigen::Matrix3d R = F_T_this.linear();
  b.mass = mass;
  b.com = F_T_this * com;
  b.inertia_com = R * inertia_com * R.transpose();
  return b;
}

RigidBodyInertia RigidBodyInertia::operator+(const RigidBodyInertia& o) const {
  // add standard parameters: they are linear in the bodies (all about the same origin)
  return from_standard_parameters(to_standard_parameters() + o.to_standard_parameters());
}

void RigidBodyInertia::validate(const std::string& what) const {
  if (!std::isfinite(mass) || mass < 0.0)
    throw InvalidArgument(fmt::format("mass of {} is {}, must be >= 0", what, mass));
  if (!com.allFinite())
    throw InvalidArgument(fmt::format("centre of mass of {} is not finite", what));
  if (!inertia_com.allFinite())
    throw InvalidArgument(fmt::format("inertia of {} is not finite", what));
  const double scale = std::max(inertia_com.trace(), 1e-12);
  const double asym = (inertia_com - inertia_com.transpose()).cwiseAbs().maxCoeff();
  if (asym > kInertiaRelTol * scale)
    throw InvalidArgument(fmt::format("inertia of {} is not symmetric (max |I - I^T| = {:.3g})", what, asym));
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(inertia_com);
  const Eigen::Vector3d ev = es.eigenvalues();
  if (ev.minCoeff() < -kInertiaRelTol * scale)
    throw InvalidArgument(fmt::format(
        "inertia of {} is not positive semi-definite (smallest eigenvalue {:.6g}, must be >= 0)", what,
        ev.minCoeff()));
  // triangle inequality of principal moments: each <= sum of the other two
  for (int k = 0; k < 3; ++k) {
    const double others = ev.sum() - ev(k);
    if (ev(k) > others + kInertiaRelTol * scale)
      throw InvalidArgument(fmt::format(
          "inertia of {} violates the triangle inequality (principal moment {:.6g} > {:.6g}, the sum of the "
          "other two)",
          what, ev(k), others));
  }
}

bool DriveParams::gains_known() const { return std::isfinite(gear_ratio) && std::isfinite(torque_constant); }

RobotModel::RobotModel(RobotDescription description) : description_(std::move(description)) {
  const auto n = static_cast<int>(description_.joints.size());
  if (n < 1 || n > kMaxDof)
    throw InvalidArgument(fmt::format("robot '{}' has {} joints, expected 1 to {}", description_.name, n, kMaxDof));
  n_dof_ = n;
  for (int i = 0; i < n; ++i) {
    const Joint& j = description_.joints[static_cast<size_t>(i)];
    const std::string who = fmt::format("joint {} ('{}')", i + 1, j.name);  // (numbered from 1, as everywhere users read)
    j.body.validate("link of " + who);
    const Eigen::Matrix3d R = j.placement.linear();
    if (!j.placement.matrix().allFinite() ||
        (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > kRotationTol ||
        R.determinant() < 0.0)
      throw InvalidArgument(fmt::format("placement of {} is not a rigid transform", who));
    const JointLimits& l = j.limits;
    if (std::isnan(l.q_min) || std::isnan(l.q_max) || !(l.q_min < l.q_max))
      throw InvalidArgument(
          fmt::format("position limits of {} are [{}, {}], expected q_min < q_max", who, l.q_min, l.q_max));
    if (!(l.qd_max > 0.0))
      throw InvalidArgument(fmt::format("velocity limit of {} is {}, must be > 0", who, l.qd_max));
    if (!(l.qdd_max > 0.0))
      throw InvalidArgument(fmt::format("acceleration limit of {} is {}, must be > 0", who, l.qdd_max));
    if (!(l.torque_max > 0.0))
      throw InvalidArgument(fmt::format("torque limit of {} is {}, must be > 0", who, l.torque_max));
    const DriveParams& d = j.drive;
    if (!std::isnan(d.gear_ratio) && !(d.gear_ratio > 0.0))
      throw InvalidArgument(fmt::format("gear ratio of {} is {}, must be > 0 (or null if unknown)", who, d.gear_ratio));
    if (!std::isnan(d.torque_constant) && !(d.torque_constant > 0.0))
      throw InvalidArgument(
          fmt::format("torque constant of {} is {}, must be > 0 (or null if unknown)", who, d.torque_constant));
    if (!(d.efficiency > 0.0 && d.efficiency <= 1.0))
      throw InvalidArgument(fmt::format("efficiency of {} is {}, must be in (0, 1]", who, d.efficiency));
    if (!(d.efficiency_reverse > 0.0 && d.efficiency_reverse <= 1.0))
      throw InvalidArgument(
          fmt::format("reverse efficiency of {} is {}, must be in (0, 1]", who, d.efficiency_reverse));
    if (!(d.current_limit > 0.0))
      throw InvalidArgument(fmt::format("current limit of {} is {}, must be > 0", who, d.current_limit));
  }
  if (!description_.gravity.allFinite()) throw InvalidArgument("gravity vector is not finite");
  if (!std::isnan(description_.rated_payload) && !(description_.rated_payload > 0.0 && std::isfinite(description_.rated_payload)))
    throw InvalidArgument(fmt::format("rated payload of robot '{}' is {} kg, must be > 0 (or not given)", description_.name,
                                      description_.rated_payload));
  rebuild_cache();
}

double RobotModel::payload_limit() const {
  if (std::isfinite(description_.rated_payload)) return description_.rated_payload;
  double moving = 0.0;
  for (const Joint& j : description_.joints) moving += j.body.mass;
  return moving;
}

std::string RobotModel::payload_limit_text() const {
  return std::isfinite(description_.rated_payload)
             ? fmt::format("the rated payload of {}", description_.name)
             : fmt::format("the moving mass of {}: its description gives no rated payload", description_.name);
}

void RobotModel::set_payload(const RigidBodyInertia& payload_in_flange) {
  payload_in_flange.validate("payload");
  payload_ = payload_in_flange;
  rebuild_cache();
}

void RobotModel::set_link_inertia(int i, const RigidBodyInertia& body) {
  if (i < 0 || i >= n_dof_)
    throw InvalidArgument(fmt::format("link index is {}, expected 0 to {}", i, n_dof_ - 1));
  body.validate(fmt::format("link {}", i));
  description_.joints[static_cast<size_t>(i)].body = body;
  standard_override_.resize(0);
  rebuild_cache();
}

void RobotModel::set_standard_parameters(const Eigen::VectorXd& pi) {
  if (pi.size() != 10 * n_dof_)
    throw InvalidArgument(fmt::format("standard parameter vector has size {}, expected {} (10 per link)", pi.size(), 10 * n_dof_));
  for (Eigen::Index k = 0; k < pi.size(); ++k)
    if (!std::isfinite(pi(k)))
      throw InvalidArgument(fmt::format("standard parameter {} (link {}, column {}) is {}, expected a finite number", k, k / 10, k % 10, pi(k)));
  standard_override_ = pi;
  rebuild_cache();
}

void RobotModel::rebuild_cache() {
  placements_about_x_ = true;
  for (int i = 0; i < n_dof_; ++i) {
    const Joint& j = description_.joints[static_cast<size_t>(i)];
    const bool payload_here = i == n_dof_ - 1 && (payload_.mass > 0.0 || !payload_.inertia_com.isZero(0.0));
    StandardParameters pi;
    if (standard_override_.size() > 0) {
      pi = standard_override_.segment<10>(10 * i);
      if (payload_here) pi += payload_.expressed_in(description_.flange).to_standard_parameters();
    } else {
      RigidBodyInertia body = j.body;
      // merge the payload into the last link: flange frame -> last body frame
      if (payload_here) body = body + payload_.expressed_in(description_.flange);
      pi = body.to_standard_parameters();
    }
    detail::LinkCache& c = cache_[static_cast<size_t>(i)];
    c.R0 = j.placement.linear();
    c.p = j.placement.translation();
    c.q_offset = j.q_offset;
    c.m = pi(0);
    c.h = pi.segment<3>(1);
    c.I_o << pi(4), pi(5), pi(6), pi(5), pi(7), pi(8), pi(6), pi(8), pi(9);
    // R0 = Rx(alpha) exactly (as the DH and MDH loaders build it): the kernels may then use
    // (cos alpha, sin alpha) alone and get the same products as with the full matrix
    const Eigen::Matrix3d& R0 = c.R0;
    c.cos_alpha = R0(1, 1);
    c.sin_alpha = R0(2, 1);
    const bool about_x = R0(0, 0) == 1.0 && R0(1, 0) == 0.0 && R0(2, 0) == 0.0 && R0(0, 1) == 0.0 &&
                         R0(0, 2) == 0.0 && R0(2, 2) == R0(1, 1) && R0(1, 2) == -R0(2, 1);
    placements_about_x_ = placements_about_x_ && about_x;
  }
}

}  // namespace twinwatch::model
