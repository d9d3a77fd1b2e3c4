#pragma once
// The same robot described with every body frame turned about its joint axis: the placements
// are then general rotations Rz(-beta) Rx(alpha) instead of Rx(alpha), so the kernels take their
// general path (RobotModel::placements_about_x() is false) while the joint torques are unchanged.
#include <random>

#include "twinwatch/model/robot_model.hpp"

namespace twinwatch::testing_support {

/// Body i's frame becomes body_i * Rz(beta_i), beta_i drawn in [-1, 1] rad from `seed`:
///   q_offset_i += beta_i,  inertia re-expressed,  placement_{i+1} = Rz(-beta_i) placement_{i+1}.
inline model::RobotModel with_turned_body_frames(const model::RobotModel& m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  model::RobotDescription d = m.description();
  for (size_t i = 0; i < d.joints.size(); ++i) {
    const double beta = u(rng);
    // new-frame coordinates from old-frame coordinates: x' = Rz(-beta) x
    const Eigen::Isometry3d new_T_old(Eigen::AngleAxisd(-beta, Eigen::Vector3d::UnitZ()));
    d.joints[i].q_offset += beta;
    d.joints[i].body = d.joints[i].body.expressed_in(new_T_old);
    if (i + 1 < d.joints.size())
      d.joints[i + 1].placement = new_T_old * d.joints[i + 1].placement;
    else
      d.flange = new_T_old * d.flange;
  }
  model::RobotModel turned(d);
  turned.set_payload(m.payload());
  return turned;
}

}  // namespace twinwatch::testing_support
