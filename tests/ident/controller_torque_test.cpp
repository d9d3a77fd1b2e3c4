// ident::ArmCheck / ControllerTorqueAccumulator: which arm a recording comes from, by the controller's
// own torque (target_moment) along its targets, with and without the target acceleration.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "twinwatch/ident/controller_torque.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/sim/scenario.hpp"

using namespace twinwatch;

namespace {
std::vector<RobotSample> simulated(const std::string& robot) {
  sim::Scenario s = sim::load_scenario(std::string(TWINWATCH_SOURCE_DIR) + "/scenarios/ur3e/excitation.yaml");
  s.options.duration = 12;
  s.robot = robot;
  std::vector<RobotSample> out;
  sim::make_simulator(s)->run([&](const RobotSample& x) { out.push_back(x); });
  return out;
}
// the samples as a joint-torque twin reads them: no target_qdd (device::ColumnMap::joint_torque_as_current)
std::vector<RobotSample> without_target_qdd(std::vector<RobotSample> v) {
  for (RobotSample& x : v) x.present &= ~kFieldTargetQdd;
  return v;
}
ident::ControllerTorqueFit fit_of(const std::string& model, const std::vector<RobotSample>& v, size_t stride = 1) {
  ident::ControllerTorqueAccumulator a(model::load_robot(model), stride);
  for (const RobotSample& x : v) a.add(x);
  return a.fit();
}
}  // namespace

// Without target_qdd (session 55: a torque twin's reading leaves it out), the controller's torque is
// compared at the middle of each step, the acceleration the difference of target_qd: the arm's own
// model fits as with the streamed acceleration (within 0.01 relative rms), another arm's does not, and
// the check names the arm as before. Before, a recording without target_qdd was not checked at all.
TEST(ArmCheck, NamesTheArmWithoutTheTargetAcceleration) {
  const std::vector<RobotSample> ur3e = simulated("ur3e"), ur5e = simulated("ur5e");
  const ident::ControllerTorqueFit streamed = fit_of("ur3e", ur3e), differenced = fit_of("ur3e", without_target_qdd(ur3e));
  ASSERT_GT(streamed.samples, 5000u);
  EXPECT_EQ(differenced.samples + 1, streamed.samples) << "every step but the first";
  EXPECT_LT(streamed.relative_rms, 0.3);
  EXPECT_NEAR(differenced.relative_rms, streamed.relative_rms, 0.01);
  EXPECT_GT(fit_of("ur5e", without_target_qdd(ur3e)).relative_rms, 0.5);
  // every 25th sample, as the verbs take them: the step before each is still differenced
  EXPECT_NEAR(fit_of("ur3e", without_target_qdd(ur3e), 25).relative_rms, streamed.relative_rms, 0.02);
  ident::ArmCheck check(model::load_robot("ur3e"), 25);
  for (const RobotSample& x : without_target_qdd(ur5e)) check.add(x);
  const ident::ArmVerdict v = check.verdict();
  EXPECT_TRUE(v.other_arm());
  EXPECT_EQ(v.better, "ur5e");
  // a gap is no step: the sample after it is not compared
  std::vector<RobotSample> gapped = without_target_qdd(ur3e);
  gapped[100].gap_before = true;
  EXPECT_EQ(fit_of("ur3e", gapped).samples + 1, differenced.samples);
}
