#include "twinwatch/sim/agv.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "twinwatch/core/error.hpp"

namespace twinwatch::sim {
namespace {

// AGV Table 1: tau = J Ra / (B Ra + k^2) gives the measured 0.175 s and 0.2 s
TEST(AgvMotor, TimeConstantsMatchTable1) {
  EXPECT_NEAR(model::agv_table1_right().time_constant(), 0.175, 0.01);
  EXPECT_NEAR(model::agv_table1_left().time_constant(), 0.2, 0.01);
}

TEST(AgvMotor, OpenLoopStepReachesTheFirstOrderFinalSpeed) {
  AgvParams p;
  p.current_noise = 0.0;
  AgvPlant plant(p, 1);
  for (int k = 0; k < 100; ++k) plant.step(6.0, 0.0, 0.04);
  // steady state of J dw/dt = k (U - k w)/Ra - Tq - B w
  const auto& m = p.right;
  const double w_ss = (m.k * 6.0 / m.Ra - m.Tq) / (m.B + m.k * m.k / m.Ra);
  EXPECT_NEAR(plant.true_w_right(), w_ss, 1e-3 * w_ss);
  EXPECT_EQ(plant.true_w_left(), 0.0) << "static friction holds the unpowered wheel";
}

// AGV Table 2: Kc = tau / (g_p (tau_cl + t_d)), Ti = tau
TEST(Imc, FormulasOfTable2) {
  const PiGains g = imc_pi(2.0, 0.175, 0.2, 0.05);
  EXPECT_DOUBLE_EQ(g.Kc, 0.175 / (2.0 * 0.25));
  EXPECT_DOUBLE_EQ(g.Ti, 0.175);
  EXPECT_THROW(imc_pi(0.0, 0.1, 0.2), InvalidArgument);
  try {
    imc_pi(1.0, 0.1, -0.2);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("closed-loop time is -0.2 s, must be > 0"));
  }
}

// closed-loop step to 4 rad/s settles in about 200 ms without overshoot, on both motors
TEST(Imc, ClosedLoopStepSettlesInAbout200msWithoutOvershoot) {
  AgvParams p;
  p.current_noise = 0.0;
  for (int m = 0; m < 2; ++m) {
    const auto& mp = m == 0 ? p.right : p.left;
    PiController pi(imc_pi(mp.gain(), mp.time_constant(), 0.2), p.voltage_limit);
    AgvPlant plant(p, 1);
    double w_meas = 0.0, peak = 0.0, t63 = -1.0;
    for (int k = 1; k <= 50; ++k) {
      const double u = pi.update(4.0, w_meas, 0.04);
      const auto& s = plant.step(m == 0 ? u : 0.0, m == 1 ? u : 0.0, 0.04);
      w_meas = m == 0 ? s.w_right : s.w_left;
      const double w = m == 0 ? plant.true_w_right() : plant.true_w_left();
      peak = std::max(peak, w);
      if (t63 < 0 && w >= 0.632 * 4.0) t63 = k * 0.04;
    }
    EXPECT_LT(peak, 4.0 * 1.03) << "motor " << m << ": overshoot";
    EXPECT_GT(t63, 0.1) << "motor " << m;
    EXPECT_LT(t63, 0.32) << "motor " << m << ": closed-loop time constant should be ~0.2 s";
    EXPECT_NEAR(m == 0 ? plant.true_w_right() : plant.true_w_left(), 4.0, 0.05);
  }
}

TEST(AgvFaults, ForcedZeroVoltageStopsTheWheels) {
  AgvParams p;
  AgvPlant plant(p, 1);
  for (int k = 0; k < 25; ++k) plant.step(6, 6, 0.04);
  plant.set_fault(AgvFault::MotorVoltageZero);
  for (int k = 0; k < 50; ++k) plant.step(6, 6, 0.04);
  EXPECT_EQ(plant.true_w_right(), 0.0);
  EXPECT_EQ(plant.true_w_left(), 0.0);
}

TEST(AgvParams, ValidationNamesTheField) {
  AgvParams p;
  p.left.Ra = -1;
  try {
    p.validate();
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("left motor: Ra is -1, must be > 0"));
  }
}

}  // namespace
}  // namespace twinwatch::sim
