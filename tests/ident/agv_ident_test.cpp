#include "twinwatch/ident/agv_ident.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include "twinwatch/core/error.hpp"
#include "twinwatch/device/agv_tests.hpp"
#include "twinwatch/sim/agv.hpp"
#include "error_text.hpp"

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

// tau counts from the step's instant (one logging period before its first row), whatever the log's
// clock origin; a step cut off before it settles is refused (review, session 47: +2 s on the clock
// gave tau 2.17 s and J 13x; a step cut at 0.3 s gave tau 0.116 s, exit 0)
TEST(AgvIdent, TheStepIsTimedFromItsOnsetAndMustHaveSettled) {
  const auto rows = sim::simulate_agv_tests(sim::AgvParams{}, 2);
  auto shifted = rows, cut = rows;
  for (auto& r : shifted)
    if (r.test == "step") r.time += 2.0;
  for (const char* m : {"right", "left"}) {
    const auto a = fit_agv_motor(rows, m), b = fit_agv_motor(shifted, m);
    EXPECT_NEAR(b.tau, a.tau, 1e-9) << m;
    EXPECT_NEAR(b.params.J, a.params.J, 1e-12) << m;
    // the time constant of AGV Table 1's motor, J Ra / (B Ra + k^2), within the encoder's resolution
    const auto t = std::string(m) == "right" ? model::agv_table1_right() : model::agv_table1_left();
    EXPECT_NEAR(a.tau, t.J * t.Ra / (t.B * t.Ra + t.k * t.k), 0.01) << m;
  }
  cut.erase(std::remove_if(cut.begin(), cut.end(), [](const AgvTestRow& r) { return r.test == "step" && r.time > 0.3; }), cut.end());
  EXPECT_THAT([&] { fit_agv_motor(cut, "right"); },
              testing::ThrowsMessage<InvalidArgument>(testing::HasSubstr("right motor: the step response has not settled")));
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
  // a trailing comma is a seventh cell (it was dropped unsaid); blanks around a number are read
  std::ofstream(bad) << "motor,test,voltage_V,current_A,speed_rad_s,time_s\nright,steady,1.0,0.1,2,0,\n";
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { device::read_agv_tests(bad); }),
              ::testing::HasSubstr("agv_ident_bad.csv:2: expected 6 cells (motor,test,voltage_V,current_A,speed_rad_s,time_s), got 7"));
  std::ofstream(bad) << "motor,test,voltage_V,current_A,speed_rad_s,time_s\nright,steady, 1.0,0.1 ,2,0\n";
  const auto blanks = device::read_agv_tests(bad);
  ASSERT_EQ(blanks.size(), 1u);
  EXPECT_EQ(blanks[0].voltage, 1.0);
  EXPECT_EQ(blanks[0].current, 0.1);
}

// a CRLF file (and one with a byte-order mark) reads as the LF file does
TEST(AgvIdent, CrlfTestFileReadsLikeTheLfOne) {
  const std::string lf = ::testing::TempDir() + "agv_lf.csv", crlf = ::testing::TempDir() + "agv_crlf.csv";
  device::write_agv_tests(lf, sim::simulate_agv_tests(sim::AgvParams{}, 5));
  {
    std::ifstream in(lf);
    std::ofstream out(crlf, std::ios::binary);
    out << "\xEF\xBB\xBF";
    for (std::string line; std::getline(in, line);) out << line << "\r\n";
  }
  const auto a = device::read_agv_tests(lf), b = device::read_agv_tests(crlf);
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].test, b[k].test) << k;
    EXPECT_EQ(a[k].time, b[k].time) << k;
    EXPECT_EQ(a[k].voltage, b[k].voltage) << k;
  }
  EXPECT_EQ(fit_agv_motor(a, "left").params.J, fit_agv_motor(b, "left").params.J);
}

// nan, inf and absurd magnitudes stop at the reader with the file, line and column (they used to
// reach the fit and come out as "plant gain g_p is -nan")
TEST(AgvIdent, NonFiniteAndAbsurdCellsAreNamed) {
  const std::string bad = ::testing::TempDir() + "agv_nonfinite.csv";
  const auto error_of = [&](const std::string& row) {
    std::ofstream(bad) << "motor,test,voltage_V,current_A,speed_rad_s,time_s\r\nright,steady,1.0,0.1,2,0\r\n" << row << "\r\n";
    return twinwatch::test::error_text<ParseError>([&] { device::read_agv_tests(bad); });
  };
  EXPECT_THAT(error_of("right,steady,2.4,nan,5.2,0"), ::testing::HasSubstr("agv_nonfinite.csv:3: field 'current_A': expected a finite number, got 'nan'"));
  EXPECT_THAT(error_of("right,steady,2.4,0.1,inf,0"), ::testing::HasSubstr("agv_nonfinite.csv:3: field 'speed_rad_s': expected a finite number, got 'inf'"));
  EXPECT_THAT(error_of("right,steady,-1e300,0.1,5.2,0"),
              ::testing::HasSubstr("agv_nonfinite.csv:3: field 'voltage_V': expected a number within +-1e+06, got '-1e300'"));
  // a log's clock from any origin, as the help says (it refused a negative one); other units named
  // (audit of session 56: mA, degrees/s and ms were fitted as a physically wrong motor, exit 0)
  EXPECT_EQ(error_of("right,step,6,0.1,5.2,-0.005"), "no error");
  EXPECT_THAT(error_of("right,steady,2.4,65.1,5.2,0"),
              ::testing::HasSubstr("agv_nonfinite.csv:3: field 'current_A': expected a wheel drive's current within ±50 A, got '65.1' (in mA? give A)"));
  EXPECT_THAT(error_of("right,steady,2.4,0.1,297.9,0"),
              ::testing::HasSubstr("agv_nonfinite.csv:3: field 'speed_rad_s': expected a wheel's speed within ±200 rad/s, got '297.9' (in degrees/s"));
  EXPECT_THAT(error_of("right,step,6,0.1,5.2,5\r\nright,step,6,0.1,5.2,10\r\nright,step,6,0.1,5.2,15"),
              ::testing::HasSubstr("agv_nonfinite.csv:3: field 'time_s': the right motor's step rows are 5 s apart (median), expected a logger's "
                                   "period of at most 0.5 s (in ms? give s)"));
  EXPECT_THAT(error_of("right,step,6,0.1,5.2,0.005\r\nright,step,6.5,0.1,5.2,0.010"),
              ::testing::HasSubstr("agv_nonfinite.csv:4: field 'voltage_V': the right motor's step test holds one voltage (within 5 %): this "
                                   "row has 6.5, its first step row (line 3) 6 V"));
  EXPECT_EQ(error_of("right,step,6,0.1,5.2,0.005\r\nright,step,6.01,0.1,5.2,0.010"), "no error");  // (a measured voltage)
  std::ofstream(bad) << "motor,test,voltage_V,current_A,speed_rad_s,time_s\n";
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { device::read_agv_tests(bad); }),
              ::testing::HasSubstr("agv_nonfinite.csv:2: no data rows after the header"));
}

// a step that turns the wheel backwards is another test than the forward steady fit (audit of session
// 56: J 1.455e-3 for 3.39e-3, exit 0); its negated copy is the forward test
TEST(AgvIdent, AStepThatTurnsTheWheelBackwardsIsRefused) {
  auto rows = sim::simulate_agv_tests(sim::AgvParams{}, 6);
  const ident::AgvMotorFit forward = ident::fit_agv_motor(rows, "right");
  for (auto& r : rows)
    if (r.test == "step") r.speed = -r.speed;
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { ident::fit_agv_motor(rows, "right"); }),
              ::testing::MatchesRegex("right motor: the step response settles at -[0-9.]+ rad/s under [0-9.]+ V, expected the wheel turning "
                                      "forwards .*"));
  EXPECT_GT(forward.tau, 0.0);
}

// a file whose rows were written twice: the step rows repeat their times, which the fit would have
// interleaved into one response (audit, session 37: accepted); repeated steady rows are repeated
// measurements and stay welcome
TEST(AgvIdent, AStepTestWithARepeatedTimeIsNamed) {
  const std::string path = ::testing::TempDir() + "agv_twice.csv";
  auto rows = sim::simulate_agv_tests(sim::AgvParams{}, 6);
  const size_t n = rows.size();
  for (size_t k = 0; k < n; ++k) rows.push_back(rows[k]);
  device::write_agv_tests(path, rows);
  const std::string e = twinwatch::test::error_text<ParseError>([&] { device::read_agv_tests(path); });
  EXPECT_THAT(e, ::testing::HasSubstr("agv_twice.csv:"));
  EXPECT_THAT(e, ::testing::HasSubstr("field 'time_s': the "));
  EXPECT_THAT(e, ::testing::HasSubstr("motor's step test has a row at "));
  EXPECT_THAT(e, ::testing::HasSubstr("expected one step test per motor, one row per time (are the file's rows repeated?)"));
  // the steady rows alone, twice: read, and fitted as the single set is
  std::vector<device::AgvTestRow> steady;
  for (const auto& r : rows) if (r.test == "steady") steady.push_back(r);
  device::write_agv_tests(path, steady);
  EXPECT_EQ(device::read_agv_tests(path).size(), steady.size());
}

// a write that fails (here a full device) is an error naming the path, not "wrote /dev/full"
TEST(AgvIdent, WriteErrorNamesThePath) {
  if (!std::ifstream("/dev/full")) GTEST_SKIP() << "no /dev/full here";
  EXPECT_THAT(twinwatch::test::error_text<std::runtime_error>(
                  [] { device::write_agv_tests("/dev/full", sim::simulate_agv_tests(sim::AgvParams{}, 1)); }),
              ::testing::HasSubstr("/dev/full: write error"));
}

// rows that give a non-physical motor are refused by the fit, not handed to the controller tuning
TEST(AgvIdent, NonPhysicalFitIsRefused) {
  // the voltage falls as the wheel speeds up: the fitted k (intercept of U/w over i/w) is negative
  std::vector<device::AgvTestRow> rows;
  for (int k = 1; k <= 5; ++k) rows.push_back({"right", "steady", 6.0 - k, 0.1 * k, 2.0 * k, 0.0});
  for (int k = 1; k <= 100; ++k) rows.push_back({"right", "step", 6.0, 0.1, 10.0 * (1 - std::exp(-k * 0.02 / 0.2)), k * 0.02});  // (settled: 10 tau)
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { fit_agv_motor(rows, "right"); }),
              ::testing::AllOf(::testing::HasSubstr("right motor: "), ::testing::HasSubstr("must be > 0"),
                               ::testing::HasSubstr("(fitted from 5 steady-state and 100 step rows: they do not describe a DC motor")));
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

// a test run backwards is said as such, not as a wheel at rest (audit, session 37: every speed negated
// read "0 steady-state points with the wheel turning")
TEST(AgvIdent, ABackwardTestIsSaid) {
  auto rows = sim::simulate_agv_tests(sim::AgvParams{}, 1);
  int steady = 0;
  for (auto& r : rows)
    if (r.motor == "left" && r.test == "steady") r.speed = -r.speed, r.voltage = -r.voltage, r.current = -r.current, ++steady;
  EXPECT_NO_THROW(fit_agv_motor(rows, "right"));
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { fit_agv_motor(rows, "left"); }),
              ::testing::AllOf(::testing::HasSubstr("left motor: 0 steady-state points with the wheel turning forwards"),
                               ::testing::ContainsRegex("; 1[0-9] steady rows turn backwards \\(negative speed\\)")));
  EXPECT_GE(steady, 13);
}

}  // namespace
}  // namespace twinwatch::ident
