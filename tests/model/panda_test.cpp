// The Franka Panda description against the real robot: at rest, the measured joint torques of
// the Gaz 2019 excitation log (joint torque sensors) equal the gravity torque of the model
// (friction is small at rest; the sensor offsets are a few tenths of N·m).
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"

namespace twinwatch::model {
namespace {

// largest |tau_measured - g(q)| accepted at rest [N·m]: sensor offset plus static friction
constexpr double kRestTolerance = 0.6;

TEST(Panda, ZeroPoseFlangeIsTheDatasheetOne) {
  const RobotModel m = load_robot("panda");
  DynamicsData d(m);
  const Eigen::Vector3d p = forward_kinematics(m, d, VectorJ::Zero(7)).translation();
  EXPECT_NEAR(p.x(), 0.088, 1e-12);
  EXPECT_NEAR(p.y(), 0.0, 1e-12);
  EXPECT_NEAR(p.z(), 0.926, 1e-12);
}

TEST(Panda, GravityTorqueMatchesTheRealRobotAtRest) {
  const std::string path = std::string(TWINWATCH_SHARED_DIR) + "/data/real/franka_panda_gaz2019_excitation/panda_excitation_combined.csv";
  std::ifstream f(path);
  if (!f) GTEST_SKIP() << "real data not found at " << path;
  std::string header, line;
  std::getline(f, header);
  std::getline(f, line);  // first sample: the robot is at rest (|dq| < 3e-3 rad/s)
  std::stringstream ss(line);
  std::vector<double> v;
  for (std::string c; std::getline(ss, c, ',');) v.push_back(std::stod(c));
  ASSERT_EQ(v.size(), 22u);
  VectorJ q(7), tau(7);
  for (int j = 0; j < 7; ++j) q[j] = v[static_cast<size_t>(1 + j)], tau[j] = v[static_cast<size_t>(15 + j)];
  const RobotModel m = load_robot("panda");
  DynamicsData d(m);
  const VectorJ g = gravity_torque(m, d, q);
  for (int j = 0; j < 7; ++j) EXPECT_NEAR(g[j], tau[j], kRestTolerance) << "joint " << j + 1;
  EXPECT_GT(std::abs(g[1]), 10.0) << "the pose must load the shoulder for the check to mean something";
}

}  // namespace
}  // namespace twinwatch::model
