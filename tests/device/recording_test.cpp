#include "twinwatch/device/recording.hpp"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include <sys/stat.h>
#include <unistd.h>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/log.hpp"
#include "error_text.hpp"

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
  return twinwatch::test::error_text<ParseError>([&] { read_recording(p); });
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

// the offline monitor reads a recording twice, row by row, without holding it (session 40): the
// reader gives read_recording's rows one at a time, with the same values and the same errors, and
// recording_timing marks the gaps read_recording marks; a second pass says a cut-off row no more
// A split recording holds every sample once, in order, each part readable on its own: a new part
// each `every` s of controller time, and one where the controller's clock went back (a restart
// during a reconnection: one file's timestamps would no longer increase and no reader takes it)
TEST(Recording, ASplitRecordingHoldsEverySampleOnceInPartsThatReadOnTheirOwn) {
  const std::string p = tmp("split.csv");
  for (long k = 0; k < 6; ++k) std::remove(split_recording_name(p, k).c_str());
  SplitRecordingWriter w(p, 1, 0, 1.0);
  std::vector<double> written;
  auto put = [&](double t) {
    RobotSample s;
    s.timestamp = t;
    s.q = VectorJ::Constant(1, t);
    s.qd = VectorJ::Zero(1);
    w.write(s);
    written.push_back(t);
  };
  for (int k = 0; k < 1250; ++k) put(0.002 * k);  // 2.5 s: parts 000, 001, 002
  for (int k = 0; k < 100; ++k) put(0.5 + 0.002 * k);  // the clock restarted: part 003
  w.close();
  w.close();  // again: nothing
  ASSERT_EQ(w.files().size(), 4u);
  EXPECT_EQ(w.files()[0], split_recording_name(p, 0));
  EXPECT_EQ(w.rows(), 1350);
  std::vector<double> read;
  for (const auto& f : w.files()) {
    const Recording r = read_recording(f);
    for (const auto& s : r.samples) read.push_back(s.timestamp);
  }
  EXPECT_EQ(read, written);
  RobotSample s;
  s.timestamp = 9.0;
  s.q = s.qd = VectorJ::Zero(1);
  EXPECT_THROW(w.write(s), std::logic_error);
  EXPECT_THROW(SplitRecordingWriter(p, 1, 0, 0.5), InvalidArgument);
  EXPECT_EQ(split_recording_name("a/rec.csv", 12), "a/rec.012.csv");
}

TEST(Recording, TheRowReaderGivesWhatReadRecordingHolds) {
  std::string csv = "timestamp,actual_q_0,actual_qd_0,actual_current_0,stream_gap\n";
  for (int k = 0; k < 40; ++k)
    if (k != 10 && k != 11 && k != 25)
      csv += fmt::format("{},{},{},{},{}\n", 0.002 * k, 0.1 + 0.01 * k, 0.5, 0.25 * k, k == 30 ? 1 : 0);
  csv += "0.090,0.1";  // cut off mid-write
  const std::string p = tmp("rows.csv");
  std::ofstream(p) << csv;
  std::string warned;
  log::set_sink([&](log::Level, std::string_view m) { warned += std::string(m) + "\n"; });
  const Recording whole = read_recording(p);
  RecordingReader reader(p);
  EXPECT_EQ(reader.n_dof(), whole.n_dof);
  EXPECT_EQ(reader.present(), whole.present);
  std::vector<RobotSample> rows;
  std::vector<double> dts;
  for (RobotSample s; reader.next(s);) {
    if (!rows.empty()) dts.push_back(s.timestamp - rows.back().timestamp);
    rows.push_back(s);
  }
  RecordingReader again(p);
  again.quiet();
  for (RobotSample s; again.next(s);) {
  }
  log::set_sink(nullptr);
  // what the file holds: rows 0-39 less 10, 11 and 25, the cut-off row dropped
  ASSERT_EQ(rows.size(), 37u);
  EXPECT_DOUBLE_EQ(rows[10].timestamp, 0.024);
  EXPECT_DOUBLE_EQ(rows[10].q[0], 0.22);
  EXPECT_DOUBLE_EQ(rows[36].current[0], 9.75);
  EXPECT_TRUE(rows[27].gap_before);  // the stream_gap column (k = 30)
  ASSERT_EQ(rows.size(), whole.samples.size());
  const RecordingTiming timing = recording_timing(p, dts);
  EXPECT_NEAR(timing.median_period, 0.002, 1e-12);
  EXPECT_TRUE(timing.is_gap(0.006));    // two rows lost
  EXPECT_FALSE(timing.is_gap(0.0025));  // a late stamp on a steady clock is still one step
  EXPECT_EQ(timing.median_period, whole.median_period);
  EXPECT_EQ(timing.gap_factor, whole.gap_factor);
  int gaps = 0;
  for (size_t k = 0; k < rows.size(); ++k) {
    EXPECT_EQ(rows[k].timestamp, whole.samples[k].timestamp);
    EXPECT_EQ(rows[k].q, whole.samples[k].q);
    EXPECT_EQ(rows[k].current, whole.samples[k].current);
    const bool gap = rows[k].gap_before || (k > 0 && timing.is_gap(dts[k - 1]));
    EXPECT_EQ(gap, whole.samples[k].gap_before) << k;
    gaps += gap ? 1 : 0;
  }
  EXPECT_EQ(gaps, whole.gaps);
  EXPECT_EQ(gaps, 3);  // two timestamp jumps and the stream_gap marker
  EXPECT_TRUE(whole.samples[10].gap_before && whole.samples[23].gap_before && whole.samples[27].gap_before);
  // said twice: by read_recording and the first reader, not by the quiet second one
  size_t said = 0;
  for (size_t at = warned.find("the last row is cut off"); at != std::string::npos; at = warned.find("the last row is cut off", at + 1)) ++said;
  EXPECT_EQ(said, 2u);
  // a bad row is the reader's error, with file, line and column, when it reaches it
  std::ofstream(tmp("rows_bad.csv")) << "timestamp,actual_q_0\n0.0,0.1\n0.002,abc\n";
  RecordingReader bad(tmp("rows_bad.csv"));
  RobotSample s;
  EXPECT_TRUE(bad.next(s));
  try {
    bad.next(s);
    ADD_FAILURE() << "a non-numeric cell was read";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("rows_bad.csv:3: field 'actual_q_0': expected a number, got 'abc'"));
  }
}

// the offline monitor and the report read a recording twice and never hold it: the second pass must
// hand over exactly the rows the first checked, with the gaps read_recording marks
TEST(Recording, ASecondPassGivesTheRowsTheScanCheckedWithTheirGaps) {
  std::string csv = "timestamp,actual_q_0,actual_qd_0,actual_current_0,stream_gap\n";
  for (int k = 0; k < 40; ++k)
    if (k != 10 && k != 11 && k != 25) csv += fmt::format("{},{},{},{},{}\n", 0.002 * k, 0.1, 0.5, 0.25 * k, k == 30 ? 1 : 0);
  const std::string p = tmp("twice.csv");
  std::ofstream(p) << csv;
  const Recording whole = read_recording(p);
  RecordingReader first(p);
  const RecordingScan scan = scan_rows(first, [](const RobotSample&) {});
  EXPECT_EQ(scan.rows, 37);
  std::vector<RobotSample> rows;
  RecordingReader again(p);
  EXPECT_EQ(replay_rows(again, scan, [&](RobotSample& s) { rows.push_back(s); }), 37);
  ASSERT_EQ(rows.size(), whole.samples.size());
  for (size_t k = 0; k < rows.size(); ++k) {
    EXPECT_EQ(rows[k].timestamp, whole.samples[k].timestamp);
    EXPECT_EQ(rows[k].gap_before, whole.samples[k].gap_before) << k;
  }
  // a file still being written has more rows by the second pass: those are left for next time
  std::ofstream(p, std::ios::app) << "0.080,0.1,0.5,1,0\n0.082,0.1,0.5,1,0\n";
  RecordingReader grown(p);
  EXPECT_EQ(replay_rows(grown, scan, [](RobotSample&) {}), 37);
  // one cut (or replaced by a shorter one) gives fewer, for the caller to say
  std::ofstream(p) << csv.substr(0, csv.find("0.04,"));
  RecordingReader cut(p);
  EXPECT_EQ(replay_rows(cut, scan, [](RobotSample&) {}), 18);  // rows 0-19 less 10 and 11
  // one rewritten with as many rows under the same header (another run on the same clock): what the
  // second pass handed over is not what the first checked
  std::string other_run = csv;
  other_run.replace(other_run.find(",0.1,0.5,"), 9, ",0.2,0.5,");
  std::ofstream(p) << other_run;
  RecordingReader rewritten(p);
  EXPECT_THAT(twinwatch::test::error_text<std::runtime_error>([&] { replay_rows(rewritten, scan, [](RobotSample&) {}); }),
              HasSubstr("twice.csv: its rows changed while it was read"));
  // a pipe cannot be read twice: refused by name before any pass
  const std::string fifo = tmp("pipe.csv");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { require_rereadable(fifo, "report"); }),
              HasSubstr("pipe.csv: report reads a recording twice"));
  ::unlink(fifo.c_str());
  EXPECT_NO_THROW(require_rereadable(p, "report"));
  // one with another header was replaced by another recording
  std::ofstream(p) << "timestamp,actual_q_0,actual_q_1\n0,0.1,0.2\n";
  RecordingReader other(p);
  EXPECT_THAT(twinwatch::test::error_text<std::runtime_error>([&] { replay_rows(other, scan, [](RobotSample&) {}); }),
              HasSubstr("twice.csv: its header changed while it was read"));
}

// a recorder killed mid-write leaves its last row cut off, without a line end: that row is dropped
// and said; a short row anywhere else (or ended by a newline) is still an error
TEST(Recording, ALastRowCutOffMidWriteIsDroppedAndSaid) {
  const std::string p = tmp("cut.csv");
  std::ofstream(p) << "timestamp,actual_q_0,actual_q_1\n0.000,0.1,0.2\n0.002,0.1,0.2\n0.004,0.1";
  std::string warned;
  log::set_sink([&](log::Level, std::string_view m) { warned += std::string(m); });
  const Recording r = read_recording(p);
  log::set_sink(nullptr);
  EXPECT_EQ(r.samples.size(), 2u);
  EXPECT_THAT(warned, HasSubstr("cut.csv:4: the last row is cut off (2 of 3 cells, no line end): dropped"));
  EXPECT_THAT(error_of("timestamp,actual_q_0,actual_q_1\n0.000,0.1,0.2\n0.002,0.1\n"), HasSubstr("bad.csv:3: expected 3 cells"));
  EXPECT_THAT(error_of("timestamp,actual_q_0,actual_q_1\n0.000,0.1\n0.002,0.1,0.2"), HasSubstr("bad.csv:2: expected 3 cells"));
}

// ... and so is a last row that has all its cells but the last one cut mid-number: one that ends
// as no number does, or a fixed-decimals writer's cell with fewer decimals than every row before.
// A shortest-form cell cut after a digit cannot be told from a shorter number: read as it is
TEST(Recording, ALastRowCutMidNumberIsDroppedAndSaid) {
  std::string rows = "timestamp,actual_q_0,actual_q_1\n";
  for (int k = 0; k < 12; ++k) rows += fmt::format("{:.3f},0.100000,{:.6f}\n", 0.002 * k, 0.2 + 0.001 * k);
  const auto read = [&](const std::string& last, std::string& warned) {
    const std::string p = tmp("cutcell.csv");
    std::ofstream(p) << rows << last;
    warned.clear();
    log::set_sink([&](log::Level, std::string_view m) { warned += std::string(m); });
    const Recording r = read_recording(p);
    log::set_sink(nullptr);
    return r;
  };
  std::string warned;
  for (const std::string cut : {"0.", "", "1.5e", "1.5e-", "-"}) {
    const Recording r = read(fmt::format("0.024,0.100000,{}", cut), warned);
    EXPECT_EQ(r.samples.size(), 12u) << cut;
    EXPECT_THAT(warned, HasSubstr(fmt::format("cutcell.csv:14: the last row is cut off (its last cell '{}' ends mid-number, no line end): dropped", cut)));
  }
  Recording r = read("0.024,0.100000,0.2119", warned);  // of 0.211900
  EXPECT_EQ(r.samples.size(), 12u);
  EXPECT_THAT(warned, HasSubstr("cutcell.csv:14: the last row is cut off (its last cell '0.2119' has 4 decimal(s), every row before had 6,"));
  // whole: the row is kept, without a word
  r = read("0.024,0.100000,0.212000", warned);
  ASSERT_EQ(r.samples.size(), 13u);
  EXPECT_DOUBLE_EQ(r.samples.back().q[1], 0.212);
  EXPECT_EQ(warned, "");
  // a shortest-form writer's ("%g": trailing zeros dropped) whole last cell is kept: its rows' decimals
  // differ, so a shorter one says nothing (the Panda log's -0.19871 was dropped: review of session 56)
  {
    const std::string saved = rows;
    rows = "timestamp,actual_q_0,actual_q_1\n";
    for (int k = 0; k < 12; ++k) rows += fmt::format("{:.3f},0.1,{:g}\n", 0.002 * k, k % 2 ? 0.212345 : 0.2123);
    r = read("0.024,0.1,0.19871", warned);
    EXPECT_EQ(r.samples.size(), 13u);
    EXPECT_EQ(warned, "");
    rows = saved;
  }
  // a shorter cell ended by a line end is a number, as written
  r = read("0.024,0.100000,0.2119\n", warned);
  EXPECT_EQ(r.samples.size(), 13u);
  EXPECT_EQ(warned, "");
  // a cell that is no number, with its line end, is an error as before
  EXPECT_THAT(error_of(rows + "0.024,0.100000,1.5e\n"), HasSubstr(":14: field 'actual_q_1': expected a number, got '1.5e'"));
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

// a joint-torque twin's reading (session 54): the sensors' columns fill the measured channel, the
// motor currents a Kinova logs beside them are not read, nor the target acceleration (session 55),
// and a file without the sensors is refused at its header, naming the column
TEST(Recording, AJointTorqueTwinReadsTheSensorsWhereTheCurrentIs) {
  const std::string p = tmp("both.csv");
  std::ofstream(p) << "timestamp,actual_q_0,actual_q_1,actual_current_0,actual_current_1,tau0,tau1,target_qdd_0,target_qdd_1\n"
                      "0.0,0.1,0.2,1.5,-0.5,12.25,-3.5,0.5,0.25\n0.002,0.1,0.2,1.6,-0.4,12.5,-3.75,0.5,0.25\n";
  const std::string mp = tmp("both.map");
  std::ofstream(mp) << "tau0,actual_joint_torque_0\ntau1,actual_joint_torque_1\n";
  ColumnMap map = ColumnMap::load(mp);
  {  // (as mapped: both signals, each in its place)
    const Recording r = read_recording(p, &map);
    EXPECT_EQ(r.samples[1].current[0], 1.6);
    EXPECT_EQ(r.samples[1].joint_torque[1], -3.75);
    EXPECT_TRUE(r.present & kFieldTargetQdd);
  }
  map.joint_torque_as_current = true;
  const Recording r = read_recording(p, &map);
  ASSERT_TRUE(r.present & kFieldActualCurrent);
  EXPECT_FALSE(r.present & kFieldJointTorque);
  // the sensors read the link's acceleration: the controller's target is not read (session 55)
  EXPECT_FALSE(r.present & kFieldTargetQdd);
  EXPECT_FALSE(r.samples[0].has(kFieldTargetQdd));
  // a sample in memory (the simulator's), read the same way
  RobotSample sim = r.samples[0];
  sim.joint_torque = sim.current;
  sim.current.setConstant(1.0);
  sim.present = kFieldActualQd | kFieldActualCurrent | kFieldJointTorque | kFieldTargetQdd;
  read_as_joint_torque(sim);
  EXPECT_EQ(sim.present, kFieldActualQd | kFieldActualCurrent);
  EXPECT_EQ(sim.current[0], 12.25);
  EXPECT_EQ(read_as_joint_torque(std::uint32_t{kFieldActualQd | kFieldActualCurrent}), std::uint32_t{kFieldActualQd})
      << "no sensors: no measured channel";
  EXPECT_EQ(r.samples[0].current[0], 12.25);
  EXPECT_EQ(r.samples[1].current[1], -3.75);
  // a file in twinwatch's own names, read without a map of its own
  const std::string own = tmp("own.csv");
  std::ofstream(own) << "timestamp,actual_q_0,actual_joint_torque_0\n0.0,0.1,7.5\n0.002,0.1,7.25\n";
  ColumnMap only;
  only.joint_torque_as_current = true;
  EXPECT_EQ(read_recording(own, &only).samples[1].current[0], 7.25);
  // no sensors: refused, with the column and why
  const std::string none = tmp("none.csv");
  std::ofstream(none) << "timestamp,actual_q_0,actual_current_0\n0.0,0.1,1.0\n0.002,0.1,1.1\n";
  const std::string e = twinwatch::test::error_text<ParseError>([&] { read_recording(none, &only); });
  EXPECT_THAT(e, HasSubstr("none.csv:1: field 'actual_joint_torque_0'"));
  EXPECT_THAT(e, HasSubstr("the twin compares joint torque sensors"));
}

// the format's names as a header line, as docs/recordings.md writes the format, are no mapping (the
// map was refused on them: 'rtde_name' is no RTDE name)
TEST(Recording, ColumnMapWithTheFormatsHeaderLoads) {
  for (const char* head : {"file_column,rtde_name,scale\n", "# mine\nfile_column,rtde_name\n"}) {
    const std::string mp = tmp("head.map");
    std::ofstream(mp) << head << "t_s,timestamp\nq1_deg,actual_q_0,0.017453292519943295\n";
    const ColumnMap map = ColumnMap::load(mp);
    EXPECT_EQ(map.columns.size(), 2u) << head;
    EXPECT_EQ(map.columns.count("file_column"), 0u);
  }
}

std::string map_error(const std::string& content) {
  const std::string mp = tmp("bad.map");
  std::ofstream(mp) << content;
  return twinwatch::test::error_text<ParseError>([&] { ColumnMap::load(mp); });
}

TEST(Recording, ColumnMapUnknownRtdeNameNamesTheLine) {
  EXPECT_THAT(map_error("t,timestamp\nq1,actual_qq_0\n"), HasSubstr("bad.map:2: field 'rtde_name': unknown name 'actual_qq_0'"));
}

TEST(Recording, ColumnMapBadScaleNamesTheLine) {
  EXPECT_THAT(map_error("t,timestamp,abc\n"), HasSubstr("bad.map:1: field 'scale': expected a finite non-zero number, got 'abc'"));
  EXPECT_THAT(map_error("\nt,timestamp,0\n"), HasSubstr("bad.map:2: field 'scale'"));
}

TEST(Recording, ColumnMapWrongCellCountNamesTheLine) {
  EXPECT_THAT(map_error("# c\nt\n"), HasSubstr("bad.map:2: expected 'file_column,rtde_name[,scale]', got 1 cells"));
}

// an empty map (or comments and the header only) mapped nothing and read the recording as if none
// had been given
TEST(Recording, ColumnMapThatMapsNothingIsRefused) {
  EXPECT_THAT(map_error(""), HasSubstr("bad.map: the column map maps no column"));
  EXPECT_THAT(map_error("# only a comment\nfile_column,rtde_name,scale\n"), HasSubstr("bad.map:2: the column map maps no column"));
}

TEST(Recording, ColumnMapDuplicateColumnNamesBothLines) {
  EXPECT_THAT(map_error("q1,actual_q_0\nq1,actual_q_1\n"), HasSubstr("bad.map:2: field 'file_column': 'q1' is already mapped on line 1"));
}

// A logger's own clock stamps 500 Hz samples with +-0.9 ms of jitter: no sample is lost, and the
// 1.5-period rule counted 374 "lost samples" in such a log. The spread raises the gap factor (said
// in a warning), so only the real loss of 10 samples is a gap.
TEST(Recording, AJitteryLoggerClockIsNotReadAsLostSamples) {
  const std::string p = tmp("jitter.csv");
  {
    std::ofstream f(p);
    f << "timestamp,actual_q_0\n";
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-0.0009, 0.0009);
    for (int k = 0; k < 5000; ++k) {
      if (k >= 3000 && k < 3010) continue;  // ten samples lost
      f << 0.002 * k + u(rng) << "," << 0.001 * k << "\n";
    }
  }
  const Recording rec = read_recording(p);
  EXPECT_NEAR(rec.median_period, 0.002, 1e-4);
  EXPECT_GT(rec.gap_factor, 2.0);
  EXPECT_EQ(rec.gaps, 1);
  EXPECT_TRUE(rec.samples[3000].gap_before);
}

// a map saved by a spreadsheet program (byte-order mark, CRLF) loads as the recordings do
TEST(Recording, ColumnMapWithAByteOrderMarkAndCrlfLoads) {
  const std::string mp = tmp("bom.map");
  std::ofstream(mp) << "\xEF\xBB\xBFTime,timestamp,0.001\r\nq1,actual_q_0\r\n";
  const ColumnMap map = ColumnMap::load(mp);
  ASSERT_EQ(map.columns.count("Time"), 1u);
  EXPECT_EQ(map.columns.at("Time").scale, 0.001);
  EXPECT_EQ(map.columns.at("q1").rtde_name, "actual_q_0");
}

// a file another separator splits (a European spreadsheet's ';', tabs) or with quoted names says so,
// instead of only "missing required column" for a name that is visibly in its header
TEST(Recording, AnotherSeparatorOrQuotedNamesAreNamedAsTheCause) {
  EXPECT_THAT(error_of("timestamp;actual_q_0;actual_qd_0\n0;0.1;0\n"), HasSubstr("the header is one cell, its names separated by ';'"));
  EXPECT_THAT(error_of("timestamp\tactual_q_0\n0\t0.1\n"), HasSubstr("separated by tabs"));
  EXPECT_THAT(error_of("\"timestamp\",\"actual_q_0\"\n0,0.1\n"), HasSubstr("the header's names are quoted"));
}

TEST(Recording, ColumnMapColumnAbsentFromTheFileIsAnError) {
  const std::string p = tmp("foreign.csv");
  std::ofstream(p) << "Time,q1\n0,1\n1,2\n";
  const std::string mp = tmp("foreign.map");
  std::ofstream(mp) << "Time,timestamp,0.001\nq1,actual_q_0\ntau1,actual_joint_torque_0\n";
  const ColumnMap map = ColumnMap::load(mp);
  try {
    read_recording(p, &map);
    FAIL() << "expected ParseError";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("foreign.csv:1: field 'tau1'"));
    EXPECT_THAT(e.what(), HasSubstr("foreign.map line 3"));
  }
  // the same file separated by ';': the cause is named as without a map (audit of session 56)
  std::ofstream(p) << "Time;q1;tau1\n0;1;0\n1;2;0\n";
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { read_recording(p, &map); }),
              HasSubstr("but the header has no such column: the header is one cell, its names separated by ';'"));
}

TEST(Recording, ColumnMapLoadsTorqueSensorAndTimeInAnotherUnit) {
  const std::string p = tmp("kinova.csv");
  std::ofstream(p) << "Time,Position1,Torque1,TorqueCur1\n0,0.5,1.25,1.5\n1,0.6,1.5,x\n";
  const std::string mp = tmp("kinova.map");
  std::ofstream(mp) << "Time,timestamp,0.001\nPosition1,actual_q_0\nTorque1,actual_joint_torque_0\nTorqueCur1,actual_current_as_torque_0\n";
  const ColumnMap map = ColumnMap::load(mp);
  try {
    read_recording(p, &map);
    FAIL() << "expected ParseError";
  } catch (const ParseError& e) {
    // the error names the file's own column, not the RTDE name
    EXPECT_THAT(e.what(), HasSubstr("kinova.csv:3: field 'TorqueCur1': expected a number, got 'x'"));
  }
  std::ofstream(p) << "Time,Position1,Torque1,TorqueCur1\n0,0.5,1.25,1.5\n1,0.6,1.5,1.75\n";
  const Recording r = read_recording(p, &map);
  ASSERT_EQ(r.samples.size(), 2u);
  EXPECT_DOUBLE_EQ(r.samples[1].timestamp, 0.001);
  EXPECT_TRUE(r.present & kFieldJointTorque);
  EXPECT_TRUE(r.present & kFieldCurrentAsTorque);
  EXPECT_DOUBLE_EQ(r.samples[1].joint_torque[0], 1.5);
  EXPECT_DOUBLE_EQ(r.samples[1].current_as_torque[0], 1.75);
}

TEST(Recording, MissingFileIsNamed) { EXPECT_THROW(read_recording("/nonexistent/rec.csv"), ParseError); }

// found by fuzzing (fuzz/regressions/recording): an int conversion of the joint index overflowed
// and the row indexed a negative joint
TEST(Recording, JointIndexTooLargeForAnIntNamesTheColumn) {
  EXPECT_THAT(error_of("timestamp,actual_q_0,actual_q_4000641156\n0,0,0\n"),
              HasSubstr("bad.csv:1: field 'actual_q_4000641156': expected a joint 0 to 6 (at most 7 joints supported), got 'actual_q_4000641156'"));
  EXPECT_THAT(error_of("timestamp,actual_q_0,actual_q_7\n0,0,0\n"), HasSubstr("field 'actual_q_7': expected a joint 0 to 6"));
  // other groups' joints beyond the positions' are refused too (they were dropped without a word),
  // however large
  EXPECT_THAT(error_of("timestamp,actual_q_0,actual_current_99999999999\n0,0,1\n0.002,0,1\n"),
              HasSubstr("field 'actual_current_99999999999': column 3 is 'actual_current_99999999999'"));
  EXPECT_THAT(error_of("timestamp,actual_q_0,actual_q_1,actual_current_0,actual_current_1,actual_current_2\n0,0,0,0,0,0\n0.002,0,0,0,0,0\n"),
              HasSubstr("bad.csv:1: field 'actual_current_2': column 6 is 'actual_current_2', joint index 2, but the recording's "
                        "positions are actual_q_0..actual_q_1 (2 joints): expected an index below 2"));
}

// found by fuzzing (fuzz/regressions/recording): casting 1e20 or -1 to the integer fields was undefined
TEST(Recording, RobotModeAndDigitalOutputsMustBeWholeNumbersInRange) {
  EXPECT_THAT(error_of("timestamp,actual_q_0,robot_mode\n0,0,1e20\n"),
              HasSubstr("bad.csv:2: field 'robot_mode': expected a whole number (an RTDE robot mode), got '1e20'"));
  EXPECT_THAT(error_of("timestamp,actual_q_0,robot_mode\n0,0,7.5\n"), HasSubstr("field 'robot_mode': expected a whole number"));
  EXPECT_THAT(error_of("timestamp,actual_q_0,actual_digital_output_bits\n0,0,-1\n"),
              HasSubstr("bad.csv:2: field 'actual_digital_output_bits': expected a whole number 0 to 2^64-1 (a bit mask), got '-1'"));
  EXPECT_THAT(error_of("timestamp,actual_q_0,actual_digital_output_bits\n0,0,nan\n"), HasSubstr("got 'nan'"));
  // the full 64-bit range loads exactly
  const std::string p = tmp("bits.csv");
  std::ofstream(p) << "timestamp,actual_q_0,actual_digital_output_bits,robot_mode\n0,0,18446744073709551615,-1\n";
  const Recording r = read_recording(p);
  EXPECT_EQ(r.samples[0].digital_outputs, 18446744073709551615ull);
  EXPECT_EQ(r.samples[0].robot_mode, -1);
}

// Session 30: safety_mode is read and written like robot_mode, and a recording is cut into the
// stretches in which the controller drives the arm for identification and threshold learning
TEST(Recording, SafetyModeRoundTripsAndDrivenStretchesAreCutOut) {
  EXPECT_THAT(error_of("timestamp,actual_q_0,safety_mode\n0,0,3.5\n"),
              HasSubstr("bad.csv:2: field 'safety_mode': expected a whole number (an RTDE safety mode), got '3.5'"));
  const std::string p = tmp("modes.csv");
  {
    RecordingWriter w(p, 1, kFieldRobotMode | kFieldSafetyMode);
    // 0-2 s driven, 2-3 s protective stop, 3-3.5 s driven (short), 3.5-4 s power off, 4-6 s driven
    for (int k = 0; k < 3000; ++k) {
      RobotSample s = RobotSample::empty(1);
      s.timestamp = 0.002 * k;
      s.q[0] = s.qd[0] = s.current[0] = 0.0;
      s.safety_mode = s.timestamp >= 2.0 && s.timestamp < 3.0 ? 3 : 1;
      s.robot_mode = s.timestamp >= 3.5 && s.timestamp < 4.0 ? 3 : 7;
      w.write(s);
    }
    w.close();
  }
  const Recording r = read_recording(p);
  ASSERT_EQ(r.present & (kFieldRobotMode | kFieldSafetyMode), kFieldRobotMode | kFieldSafetyMode);
  EXPECT_EQ(r.samples[1100].safety_mode, 3);
  EXPECT_EQ(r.samples[1800].robot_mode, 3);
  EXPECT_FALSE(r.samples[1100].driven());
  EXPECT_TRUE(r.samples[1600].driven());
  std::string note;
  const auto segs = driven_segments(r, 1.0, &note);
  ASSERT_EQ(segs.size(), 2u);
  EXPECT_EQ(segs[0].samples.size(), 1000u);
  EXPECT_EQ(segs[1].samples.front().timestamp, 4.0);
  EXPECT_EQ(segs[1].samples.size(), 1000u);
  EXPECT_EQ(segs[1].path, r.path);
  EXPECT_THAT(note, HasSubstr("750 sample(s) (1.5 s) in which the controller did not drive the arm"));
  EXPECT_THAT(note, HasSubstr("1 driven stretch(es) shorter than 1 s (250 samples)"));
  // a recording driven throughout comes back whole, without a note; without the columns, every sample is driven
  auto all = r;
  for (auto& s : all.samples) s.present &= ~(kFieldRobotMode | kFieldSafetyMode);
  EXPECT_EQ(driven_segments(all, 1.0, &note).front().samples.size(), 3000u);
  EXPECT_EQ(note, "");
}

// audit of session 16: one nan or inf cell used to load and then blind the monitor for the rest
// of the recording (the filter and observer states stayed nan); now the reader names it
TEST(Recording, NonFiniteCellsAreRefusedWithFileLineAndColumn) {
  EXPECT_THAT(error_of("timestamp,actual_q_0,actual_current_0\n0,0,1\n0.002,nan,1\n"),
              HasSubstr("bad.csv:3: field 'actual_q_0': expected a finite number, got 'nan'"));
  EXPECT_THAT(error_of("timestamp,actual_q_0,actual_current_0\n0,0,1\n0.002,0,-inf\n"),
              HasSubstr("bad.csv:3: field 'actual_current_0': expected a finite number, got '-inf'"));
  EXPECT_THAT(error_of("timestamp,actual_q_0\ninf,0\n"), HasSubstr("bad.csv:2: field 'timestamp': expected a finite number, got 'inf'"));
  EXPECT_THAT(error_of("timestamp,actual_q_0\n0,infinity\n"), HasSubstr("got 'infinity'"));
  // a finite cell that a column map's scale takes beyond a double
  const std::string m = tmp("huge.map");
  std::ofstream(m) << "Position1,actual_q_0,1e300\n";
  const ColumnMap map = ColumnMap::load(m);
  const std::string p = tmp("huge.csv");
  std::ofstream(p) << "timestamp,Position1\n0,1e10\n";
  try {
    read_recording(p, &map);
    ADD_FAILURE() << "a scaled cell beyond a double loaded";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("huge.csv:2: field 'Position1': expected a finite number, got '1e10' (after the column map's scale)"));
  }
}

// session 23: the payload the controller declares (RTDE payload / payload_cog) has columns of its
// own, written and read back exactly; its mass and centre of mass come together, the mass is >= 0
TEST(Recording, TheDeclaredPayloadRoundTripsAndComesWithItsCentreOfMass) {
  const std::string p = tmp("payload.csv");
  {
    RecordingWriter w(p, 2, kFieldPayload);
    for (int k = 0; k < 3; ++k) {
      RobotSample s = RobotSample::empty(2);
      s.timestamp = 0.002 * k;
      s.q.setZero(2);
      s.qd.setZero(2);
      s.payload = k < 2 ? 0.0 : 1.25;
      s.payload_cog[0] = 0.0;
      s.payload_cog[1] = -0.001;
      s.payload_cog[2] = k < 2 ? 0.0 : 0.0437;
      w.write(s);
    }
    w.close();
  }
  std::ifstream in(p);
  std::string header;
  std::getline(in, header);
  EXPECT_THAT(header, ::testing::EndsWith(",payload,payload_cog_0,payload_cog_1,payload_cog_2"));
  const Recording r = read_recording(p);
  EXPECT_TRUE(r.present & kFieldPayload);
  ASSERT_EQ(r.samples.size(), 3u);
  EXPECT_TRUE(r.samples[2].has(kFieldPayload));
  EXPECT_EQ(r.samples[0].payload, 0.0);
  EXPECT_EQ(r.samples[2].payload, 1.25);
  EXPECT_EQ(r.samples[2].payload_cog[1], -0.001);
  EXPECT_EQ(r.samples[2].payload_cog[2], 0.0437);
  // a file without the columns: no declaration, NaN
  const std::string q = tmp("none.csv");
  std::ofstream(q) << "timestamp,actual_q_0\n0,0\n";
  const Recording none = read_recording(q);
  EXPECT_FALSE(none.present & kFieldPayload);
  EXPECT_TRUE(std::isnan(none.samples[0].payload));
  // half a declaration, a negative mass, the same column twice
  EXPECT_THAT(error_of("timestamp,actual_q_0,payload\n0,0,1\n"),
              HasSubstr("bad.csv:1: field 'payload_cog_*': the declared payload needs its mass and centre of mass together: expected the "
                        "columns payload, payload_cog_0, payload_cog_1 and payload_cog_2, the header has payload and 0 of the three"));
  EXPECT_THAT(error_of("timestamp,actual_q_0,payload_cog_0,payload_cog_1,payload_cog_2\n0,0,0,0,0\n"),
              HasSubstr("field 'payload': the declared payload needs its mass and centre of mass together"));
  EXPECT_THAT(error_of("timestamp,actual_q_0,payload,payload_cog_0,payload_cog_1,payload_cog_2\n0,0,-0.5,0,0,0\n"),
              HasSubstr("bad.csv:2: field 'payload': expected a payload mass >= 0 kg, got '-0.5'"));
  EXPECT_THAT(error_of("timestamp,actual_q_0,payload,payload_cog_0,payload_cog_1,payload_cog_2\n0,0,0.5,0,nan,0\n"),
              HasSubstr("bad.csv:2: field 'payload_cog_1': expected a finite number, got 'nan'"));
  EXPECT_THAT(error_of("timestamp,actual_q_0,payload,payload_cog_0,payload_cog_1,payload_cog_2,payload\n0,0,0.5,0,0,0,0.5\n"),
              HasSubstr("column 7 is 'payload' again"));
}

TEST(Recording, ASignalInTwoColumnsIsRefusedNamingBoth) {
  EXPECT_THAT(error_of("timestamp,actual_q_0,actual_current_0,actual_current_0\n0,0,1,0\n"),
              HasSubstr("bad.csv:1: field 'actual_current_0': column 4 is 'actual_current_0' again (column 3 is 'actual_current_0')"));
  EXPECT_THAT(error_of("timestamp,timestamp,actual_q_0\n0,0,0\n"), HasSubstr("column 2 is 'timestamp' again"));
  // unknown columns are ignored, so two of them are no conflict
  EXPECT_EQ(error_of("timestamp,actual_q_0,note,note\n0,0,1,2\n0.002,0,1,2\n"), "no error");
  // two file columns a map gives one name: named as the map names them, with the map's lines, also
  // for a torque twin, whose reading renames the sensors' group (it said 'actual_current_1': audit of
  // session 55)
  const std::string p = tmp("typo.csv");
  std::ofstream(p) << "t,q0,q1,T0,T1\n0,0,0,1,2\n0.002,0,0,1,2\n";
  const std::string mp = tmp("typo.map");
  std::ofstream(mp) << "t,timestamp\nq0,actual_q_0\nq1,actual_q_1\nT0,actual_joint_torque_1\nT1,actual_joint_torque_1\n";
  ColumnMap map = ColumnMap::load(mp);
  for (bool torque : {false, true}) {
    map.joint_torque_as_current = torque;
    const std::string e = twinwatch::test::error_text<ParseError>([&] { read_recording(p, &map); });
    EXPECT_THAT(e, HasSubstr("typo.csv:1: field 'T1': column 5 is 'actual_joint_torque_1' again (column 4 is 'T0'; the column map "));
    EXPECT_THAT(e, HasSubstr("typo.map maps both, lines 4 and 5)"));
  }
}

TEST(Recording, AByteOrderMarkBeforeTheHeaderIsSkipped) {
  const std::string p = tmp("bom.csv");
  std::ofstream(p) << "\xEF\xBB\xBFtimestamp,actual_q_0\r\n0,0.5\r\n0.002,0.25\r\n";
  const Recording r = read_recording(p);
  ASSERT_EQ(r.samples.size(), 2u);
  EXPECT_DOUBLE_EQ(r.samples[1].q[0], 0.25);
}

TEST(Recording, RequireFieldsNamesTheFirstMissingGroupAndWhoNeedsIt) {
  const std::string p = tmp("noqd.csv");
  std::ofstream(p) << "timestamp,actual_q_0,actual_q_1,actual_current_0,actual_current_1\n0,0,0,1,1\n";
  const Recording r = read_recording(p);
  EXPECT_NO_THROW(require_fields(r, kFieldActualCurrent, "the monitor"));
  try {
    require_fields(r, kFieldActualQd | kFieldActualCurrent, "the monitor");
    ADD_FAILURE() << "a recording without actual_qd passed";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("noqd.csv:1: field 'actual_qd_0': missing required column: the monitor needs "
                                    "actual_qd_0..actual_qd_1, the header has none of them"));
  }
}

}  // namespace
}  // namespace twinwatch::device

