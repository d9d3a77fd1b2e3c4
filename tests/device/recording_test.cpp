#include "twinwatch/device/recording.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include "twinwatch/core/error.hpp"

namespace twinwatch::device {
namespace {

using ::testing::HasSubstr;

// one file per test: ctest runs the test cases as parallel processes
std::string tmp(const std::string& name) {
  return ::testing::TempDir() + ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" + name;
}

std::string error_of(const std::string& content) {
  const std::string p = tmp("bad.csv");
  std::ofstream(p) << content;
  try {
    read_recording(p);
  } catch (const ParseError& e) {
    return e.what();
  }
  return "no error";
}

TEST(Recording, RoundTripsEveryFieldBitExactly) {
  std::mt19937 rng(4);
  std::normal_distribution<double> g(0.0, 1.0);
  const std::uint32_t fields = kFieldTargetQ | kFieldTargetQd | kFieldTargetQdd | kFieldActualCurrent |
                               kFieldTargetCurrent | kFieldTargetMoment | kFieldTemperature | kFieldDigitalOutputs |
                               kFieldRobotMode;
  std::vector<RobotSample> written;
  {
    RecordingWriter w(tmp("rt.csv"), 6, fields);
    for (int k = 0; k < 100; ++k) {
      RobotSample s = RobotSample::empty(6);
      s.timestamp = 0.002 * k;
      for (VectorJ* v : {&s.q, &s.qd, &s.target_q, &s.target_qd, &s.target_qdd, &s.current, &s.target_current,
                         &s.target_moment, &s.temperature})
        for (int j = 0; j < 6; ++j) (*v)[j] = g(rng) * std::pow(10.0, j - 3);
      s.digital_outputs = k > 50 ? 0x5u : 0u;
      s.robot_mode = 7;
      w.write(s);
      written.push_back(s);
    }
    w.close();
  }
  const Recording r = read_recording(tmp("rt.csv"));
  ASSERT_EQ(r.n_dof, 6);
  ASSERT_EQ(r.samples.size(), written.size());
  EXPECT_EQ(r.present & fields, fields);
  for (size_t k = 0; k < written.size(); ++k) {
    EXPECT_EQ(r.samples[k].timestamp, written[k].timestamp);
    EXPECT_EQ(r.samples[k].current, written[k].current) << "row " << k;
    EXPECT_EQ(r.samples[k].target_qdd, written[k].target_qdd);
    EXPECT_EQ(r.samples[k].temperature, written[k].temperature);
    EXPECT_EQ(r.samples[k].digital_outputs, written[k].digital_outputs);
  }
  EXPECT_EQ(r.gaps, 0);
}

TEST(Recording, MarksTimestampGapsWithoutHidingThem) {
  std::string csv = "timestamp,actual_q_0\n";
  for (int k = 0; k < 20; ++k)
    if (k != 10 && k != 11) csv += std::to_string(0.002 * k) + ",0.1\n";
  const std::string p = tmp("gap.csv");
  std::ofstream(p) << csv;
  const Recording r = read_recording(p);
  EXPECT_EQ(r.samples.size(), 18u);
  EXPECT_EQ(r.gaps, 1);
  EXPECT_TRUE(r.samples[10].gap_before);
  EXPECT_NEAR(r.median_period, 0.002, 1e-12);
}

TEST(Recording, NonNumericCellNamesLineAndColumn) {
  EXPECT_THAT(error_of("timestamp,actual_q_0\n0.0,0.1\n0.002,abc\n"),
              HasSubstr("bad.csv:3: field 'actual_q_0': expected a number, got 'abc'"));
}

TEST(Recording, WrongCellCountNamesLine) {
  EXPECT_THAT(error_of("timestamp,actual_q_0\n0.0,0.1,7\n"), HasSubstr("bad.csv:2: expected 2 cells (as in the header), got 3"));
}

TEST(Recording, MissingRequiredColumn) {
  EXPECT_THAT(error_of("time,actual_q_0\n0.0,0.1\n"), HasSubstr("field 'timestamp': missing required column"));
  EXPECT_THAT(error_of("timestamp,foo\n0.0,0.1\n"), HasSubstr("no actual_q_*"));
}

TEST(Recording, PartialGroupIsAnError) {
  EXPECT_THAT(error_of("timestamp,actual_q_0,actual_q_1,actual_current_0\n0,0,0,0\n"),
              HasSubstr("some joints' columns are missing"));
}

TEST(Recording, TimestampGoingBackwardsIsAnError) {
  EXPECT_THAT(error_of("timestamp,actual_q_0\n0.004,0\n0.002,0\n"), HasSubstr("bad.csv:3: field 'timestamp': timestamp 0.002 does not increase"));
}

TEST(Recording, ColumnMapRenamesAndScalesForeignLogs) {
  const std::string p = tmp("foreign.csv");
  std::ofstream(p) << "t_s,q1_deg,q2_deg\n0.0,90,-45\n0.001,180,0\n";
  const std::string mp = tmp("foreign.map");
  std::ofstream(mp) << "# my logger\nt_s,timestamp\nq1_deg,actual_q_0,0.017453292519943295\nq2_deg,actual_q_1,0.017453292519943295\n";
  const ColumnMap map = ColumnMap::load(mp);
  const Recording r = read_recording(p, &map);
  ASSERT_EQ(r.n_dof, 2);
  EXPECT_NEAR(r.samples[0].q[0], M_PI / 2, 1e-15);
  EXPECT_NEAR(r.samples[0].q[1], -M_PI / 4, 1e-15);
}

TEST(Recording, MissingFileIsNamed) { EXPECT_THROW(read_recording("/nonexistent/rec.csv"), ParseError); }

}  // namespace
}  // namespace twinwatch::device
