#pragma once
// Builds an Orocos KDL chain from a twinwatch model: the independent oracle used by tests and
// benchmarks only (never by the library).
//
// KDL segment i (Joint RotZ) has its tip at body_i * placement_{i+1}; KDL expresses a segment's
// inertia in its tip frame, so each body is re-expressed there. A first fixed segment carries
// placement_0. Joint offsets are applied by the caller (q_kdl = q + q_offset).
#include <kdl/chain.hpp>
#include <kdl/frames.hpp>
#include <kdl/jntarray.hpp>
#include <kdl/rigidbodyinertia.hpp>
#include <kdl/rotationalinertia.hpp>

#include "twinwatch/model/robot_model.hpp"

namespace twinwatch::testing_support {

inline KDL::Frame to_kdl(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d& R = T.linear();
  return KDL::Frame(KDL::Rotation(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)),
                    KDL::Vector(T.translation().x(), T.translation().y(), T.translation().z()));
}

inline KDL::Chain to_kdl_chain(const model::RobotModel& m) {
  KDL::Chain chain;
  chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), to_kdl(m.joint(0).placement)));
  for (int i = 0; i < m.n_dof(); ++i) {
    const Eigen::Isometry3d tip =
        i + 1 < m.n_dof() ? m.joint(i + 1).placement : Eigen::Isometry3d(Eigen::Isometry3d::Identity());
    // the body as the dynamics sees it (payload merged on the last link)
    const auto& c = m.link_cache(i);
    model::StandardParameters pi;
    pi << c.m, c.h, c.I_o(0, 0), c.I_o(0, 1), c.I_o(0, 2), c.I_o(1, 1), c.I_o(1, 2), c.I_o(2, 2);
    const model::RigidBodyInertia b = model::RigidBodyInertia::from_standard_parameters(pi).expressed_in(tip.inverse());
    const Eigen::Matrix3d& I = b.inertia_com;
    const KDL::RigidBodyInertia inertia(b.mass, KDL::Vector(b.com.x(), b.com.y(), b.com.z()),
                                        KDL::RotationalInertia(I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2)));
    chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotZ), to_kdl(tip), inertia));
  }
  return chain;
}

}  // namespace twinwatch::testing_support
