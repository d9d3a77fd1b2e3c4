#include "twinwatch/ident/agv_ident.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "twinwatch/core/error.hpp"
#include "twinwatch/sim/agv.hpp"

namespace twinwatch::ident {
namespace {

// identification of noisy simulated tests recovers AGV Table 1 within the noise
TEST(AgvIdent, RecoversTable1FromNoisyTests) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const auto rows = sim::simulate_agv_tests(sim::AgvParams{}, seed);
    for (const char* m : {"right", "left"}) {
      const auto fit = fit_agv_motor(rows, m);
      const auto t = std::string(m) == "right" ? model::agv_table1_right() : model::agv_table1_left();
      EXPECT_NEAR(fit.params.Ra, t.Ra, 0.03 * t.Ra) << m << " seed " << seed;
      EXPECT_NEAR(fit.params.k, t.k, 0.02 * t.k) << m << " seed " << seed;
      EXPECT_NEAR(fit.params.Tq, t.Tq, 0.1 * t.Tq) << m << " seed " << seed;
      EXPECT_NEAR(fit.params.B, t.B, 0.15 * t.B) << m << " seed " << seed;
      EXPECT_NEAR(fit.params.J, t.J, 0.06 * t.J) << m << " seed " << seed;
      // 0.4 V cannot overcome static friction (k U / Ra < Tq): that point is left out
      EXPECT_GE(fit.steady_points, 13);
    }
  }
}

TEST(AgvIdent, TestFileRoundTripsAndBadCellsAreNamed) {
  const std::string path = ::testing::TempDir() + "agv_ident_tests.csv";
  const auto rows = sim::simulate_agv_tests(sim::AgvParams{}, 4);
  device::write_agv_tests(path, rows);
  const auto back = device::read_agv_tests(path);
  ASSERT_EQ(back.size(), rows.size());
  EXPECT_EQ(back[3].motor, rows[3].motor);
  EXPECT_NEAR(back[3].speed, rows[3].speed, 1e-5 * std::abs(rows[3].speed));
  const std::string bad = ::testing::TempDir() + "agv_ident_bad.csv";
  std::ofstream(bad) << "motor,test,voltage_V,current_A,speed_rad_s,time_s\nright,steady,1.0,0.1,abc,0\n";
  try {
    device::read_agv_tests(bad);
    FAIL();
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("agv_ident_bad.csv:2: field 'speed_rad_s': expected a number, got 'abc'"));
  }
  std::ofstream(bad) << "motor,test,voltage_V,current_A,speed_rad_s,time_s\nmiddle,steady,1.0,0.1,2,0\n";
  EXPECT_THROW(device::read_agv_tests(bad), ParseError);
}

TEST(AgvIdent, TooFewSteadyPoints) {
  std::vector<device::AgvTestRow> rows{{"right", "steady", 1.0, 0.1, 2.0, 0.0}};
  try {
    fit_agv_motor(rows, "right");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("right motor: 1 steady-state points"));
  }
}

}  // namespace
}  // namespace twinwatch::ident
