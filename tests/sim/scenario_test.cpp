#include "twinwatch/sim/scenario.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <utility>

#include "twinwatch/core/error.hpp"
#include "twinwatch/device/recording.hpp"
#include "error_text.hpp"

namespace twinwatch::sim {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

// the message of parsing `yaml` as test.yaml ("no error" if it loads)
std::string error_of(const std::string& yaml) {
  return twinwatch::test::error_text<ParseError>([&] { parse_scenario(yaml, "test.yaml"); });
}

// the simulator's stream at these times (the sample stamped at each)
std::map<double, RobotSample> stream_at(Simulator& sim, std::initializer_list<double> times) {
  std::map<double, RobotSample> at;
  sim.run([&](const RobotSample& x) {
    for (double t : times)
      if (std::abs(x.timestamp - t) < 1e-9) at[t] = x;
  });
  return at;
}

const std::string kSine = "trajectory: {type: sine, amplitude: 0.1, frequency: 0.5}\n";
const std::string kFig8 = "trajectory: {type: figure_eight, size: [0.12, 0.08], period: 8, tilt: [0.3, 0.4, 0.5]}\n";

// audit of session 22: a fault's magnitude was read unchecked (a NaN resistance made a recording of
// NaN from its first sample, before the onset, exit 0), other types' keys were ignored silently,
// and a payload fault's label was not the change the arm saw
TEST(Scenario, AFaultsValuesAreCheckedForItsType) {
  const std::string head = "robot: ur3e\nduration: 10\n" + kFig8 + "faults:\n";
  // (a fault's line, what the error must say)
  const std::pair<const char*, const char*> cases[] = {
      {"{type: resistance, joint: 2, onset: 0.5, magnitude: .nan}", "test.yaml:5: field 'faults[0].magnitude': expected a finite number, got nan"},
      {"{type: current_offset, joint: 2, onset: 0.5, magnitude: .inf}", "field 'faults[0].magnitude': expected a finite number, got inf"},
      {"{type: resistance, joint: 2, onset: 0.5, magnitude: -5}",
       "field 'faults[0].magnitude': expected extra friction > 0 N·m (it opposes the motion), got -5"},
      {"{type: friction_growth, joint: 2, onset: 0.5, magnitude: -2}", "field 'faults[0].magnitude': expected a relative change > -1"},
      {"{type: collision, link: 3, onset: 1, magnitude: 5, point: [.nan, 0, 0]}", "field 'faults[0].point[0]': expected a finite number, got nan"},
      {"{type: payload_pick, onset: 1, mass: 0.5, com: [0, .inf, 0]}", "field 'faults[0].com[1]': expected a finite number, got inf"},
      {"{type: dropped_samples, onset: 1, magnitude: 2.5}", "field 'faults[0].magnitude': expected a whole number of samples >= 1, got 2.5"},
      {"{type: dropped_samples, onset: 1, magnitude: 2, period: -1}", "field 'faults[0].period': expected a repeat period >= 0 s (0: once), got -1"},
      // another type's key
      {"{type: stuck_current, joint: 2, onset: 1, magnitude: 3}",
       "field 'faults[0].magnitude': unknown key 'magnitude', expected one of: end, joint, onset, ramp, type"},
      {"{type: resistance, joint: 2, link: 3, onset: 1, magnitude: 1}", "unknown key 'link'"},
      {"{type: collision, link: 3, onset: 1, end: 2, magnitude: 5}", "unknown key 'end'"},
      {"{type: payload_loss, onset: 1, mass: 2}", "unknown key 'mass'"},
      // a pick or a loss happens at its onset (the simulator ignored an end the label used)
      {"{type: missed_pick, onset: 1, end: 2, mass: 1, io_bit: 1}", "field 'faults[0].end': unknown key 'end', expected one of: com, io_bit, mass, onset, type"},
      {"{type: payload_pick, onset: 1, ramp: 0.5, mass: 1}", "unknown key 'ramp'"},
      // a loss with nothing carried
      {"{type: payload_loss, onset: 1}", "test.yaml:5: field 'faults[0]': a payload_loss at 1 s, but the arm carries nothing then"},
      // faults that would not happen as labelled, and unit slips
      {"{type: resistance, joint: 2, onset: 1, ramp: 1000, magnitude: 1}",
       "field 'faults[0].ramp': the ramp from 1 s over 1000 s ends after the run (10 s): the resistance would never reach its magnitude"},
      {"{type: collision, link: 3, onset: 1, magnitude: 5, duration: 500}", "field 'faults[0].duration': the contact from 1 s for 500 s lasts past the end of the run"},
      {"{type: collision, link: 3, onset: 1, magnitude: 5, point: [-100, 0, 30]}",
       "field 'faults[0].point': expected a contact point within 1 m of the link's frame, got one 104.4 m away (in mm? give metres)"},
      {"{type: dropped_samples, onset: 1, magnitude: 1e9}", "field 'faults[0].magnitude': expected at most the 4500 samples left after the onset"},
      {"{type: current_offset, joint: 2, onset: 1, magnitude: 300}", "field 'faults[0].magnitude': expected a current offset within ±20 A, got 300 (in mA?"},
      // labelled as what never happens (audit of session 56): a jitter of 0, an end after the run
      {"{type: timestamp_jitter, onset: 1, magnitude: 0}", "field 'faults[0].magnitude': expected a jitter sigma above 0"},
      {"{type: resistance, joint: 2, onset: 1, end: 100, magnitude: 1}",
       "test.yaml:5: field 'faults[0].end': the resistance would end at 100 s, after the run (10 s), which its label would claim"},
  };
  for (const auto& [fault, message] : cases) EXPECT_THAT(error_of(head + "  - " + fault + "\n"), HasSubstr(message)) << fault;
}

// a declaration after the run never shows; a part's inertia beyond what its mass can have within a
// metre is a unit slip (audit of session 56: both were taken)
TEST(Scenario, APicksDeclarationAndAPartsInertiaMustBePossible) {
  EXPECT_THAT(error_of("robot: ur3e\nduration: 10\n" + kFig8 + "faults:\n  - {type: payload_pick, onset: 9.5, mass: 0.5, declare_delay: 1}\n"),
              HasSubstr("test.yaml:5: field 'faults[0].declare_delay': the declaration would come at 10.5 s, not before the end of the run (10 s)"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 10\n" + kFig8 + "payload: {mass: 0.5, com: [0, 0, 0.04], inertia: [100, 0, 0, 100, 0, 100]}\n"),
              HasSubstr("test.yaml:4: field 'payload.inertia': a 0.5 kg part has an inertia of at most 0.5 kg m²"));
  EXPECT_EQ(error_of("robot: ur3e\nduration: 10\n" + kFig8 + "payload: {mass: 0.5, com: [0, 0, 0.04], inertia: [0.001, 0, 0, 0.001, 0, 0.001]}\n"),
            "no error");
}

TEST(Scenario, APayloadFaultsLabelIsTheChangeOfTheMassCarried) {
  const std::string head = "robot: ur3e\nduration: 10\n" + kFig8;
  // listed out of order: the labels follow the time they happen
  const Scenario s = parse_scenario(head + "payload: {mass: 2.5}\nfaults:\n"
                                           "  - {type: payload_loss, onset: 6}\n"
                                           "  - {type: payload_pick, onset: 2, mass: 2.0}\n"
                                           "  - {type: payload_pick, onset: 8, mass: 1.0}\n",
                                    "test.yaml");
  ASSERT_EQ(s.faults.size(), 3u);
  EXPECT_DOUBLE_EQ(s.faults[1].magnitude, -0.5);  // 2.5 kg held, 2.0 kg now
  EXPECT_DOUBLE_EQ(s.faults[0].magnitude, -2.0);  // the 2.0 kg dropped
  EXPECT_DOUBLE_EQ(s.faults[2].magnitude, 1.0);
  const Scenario none = parse_scenario(head + "faults:\n  - {type: payload_pick, onset: 1, mass: 1.0}\n  - {type: payload_loss, onset: 2.5}\n",
                                       "test.yaml");
  EXPECT_DOUBLE_EQ(none.faults[1].magnitude, -1.0);  // was -0: the scenario's (absent) payload
}

// session 23: the controller streams the payload its program declares (default), which a pick
// changes and an undeclared loss does not; a missed pick changes the declaration only, and its label
// is the mass the arm carries less than declared. Without the stream a missed pick is refused.
TEST(Scenario, TheDeclaredPayloadIsStreamedAndAMissedPickChangesOnlyIt) {
  const std::string head = "robot: ur3e\nduration: 6\n" + kFig8;
  const Scenario s = parse_scenario(head + "payload: {mass: 0.5, com: [0, 0, 0.04]}\nfaults:\n"
                                           "  - {type: payload_loss, onset: 1}\n"
                                           "  - {type: payload_pick, onset: 2, mass: 1.0, com: [0, 0.01, 0.05], io_bit: 1}\n"
                                           "  - {type: missed_pick, onset: 4, mass: 2.0, io_bit: 2}\n",
                                    "test.yaml");
  ASSERT_EQ(s.faults.size(), 3u);
  EXPECT_TRUE(s.options.streams_payload);
  EXPECT_DOUBLE_EQ(s.faults[2].magnitude, -1.0);  // carries 1.0 kg, declared 2.0 kg
  const auto sim = make_simulator(s);
  EXPECT_TRUE(sim->sample_fields() & kFieldPayload);
  auto at = stream_at(*sim, {0.5, 1.5, 3.0, 5.0});
  ASSERT_EQ(at.size(), 4u);
  EXPECT_TRUE(at[0.5].has(kFieldPayload));
  EXPECT_EQ(at[0.5].payload, 0.5);
  EXPECT_EQ(at[0.5].payload_cog[2], 0.04);
  EXPECT_EQ(at[1.5].payload, 0.5) << "an undeclared loss leaves the declaration";
  EXPECT_EQ(at[3.0].payload, 1.0);
  EXPECT_EQ(at[3.0].payload_cog[1], 0.01);
  EXPECT_EQ(at[5.0].payload, 2.0);
  EXPECT_EQ(at[5.0].digital_outputs & 4u, 4u) << "the gripper closed on nothing";
  EXPECT_EQ(sim->truth_model().payload().mass, 1.0) << "the arm still carries the part picked at 2 s";
  // a controller without the stream
  const Scenario quiet = parse_scenario(head + "streams_payload: false\n", "test.yaml");
  EXPECT_FALSE(make_simulator(quiet)->sample_fields() & kFieldPayload);
  EXPECT_THAT(error_of(head + "streams_payload: false\nfaults:\n  - {type: missed_pick, onset: 1, mass: 1.0}\n"),
              HasSubstr("field 'faults[0].type': a missed_pick is a payload the program declares and the arm does not carry: it needs "
                        "'streams_payload: true'"));
  EXPECT_THAT(error_of(head + "faults:\n  - {type: missed_pick, onset: 1, mass: 0}\n"), HasSubstr("faults[0].mass': must be > 0 kg"));
}

// session 24: a program declares its pick before or after the gripper closes (declare_delay): the
// arm carries the part from the grip (the onset), the stream declares it declare_delay later
TEST(Scenario, APicksDeclarationCanComeBeforeOrAfterTheGrip) {
  const std::string head = "robot: ur3e\nduration: 6\n" + kFig8;
  const Scenario s = parse_scenario(head + "faults:\n"
                                           "  - {type: payload_pick, onset: 1, mass: 1.0, io_bit: 1, declare_delay: 0.3}\n"
                                           "  - {type: payload_loss, onset: 2, io_bit: 1}\n"
                                           "  - {type: payload_pick, onset: 4, mass: 0.5, io_bit: 2, declare_delay: -0.5}\n",
                                    "test.yaml");
  ASSERT_EQ(s.faults.size(), 3u);
  EXPECT_DOUBLE_EQ(s.faults[0].declare_delay, 0.3);
  const auto sim = make_simulator(s);
  auto at = stream_at(*sim, {1.2, 1.4, 3.4, 3.6, 4.2});
  ASSERT_EQ(at.size(), 5u);
  EXPECT_EQ(at[1.2].digital_outputs & 2u, 2u) << "gripped at 1 s";
  EXPECT_EQ(at[1.2].payload, 0.0) << "declared only at 1.3 s";
  EXPECT_EQ(at[1.4].payload, 1.0);
  EXPECT_EQ(at[3.4].payload, 1.0) << "the loss at 2 s is undeclared";
  EXPECT_EQ(at[3.6].payload, 0.5) << "declared at 3.5 s";
  EXPECT_EQ(at[3.6].digital_outputs & 4u, 0u) << "before the gripper closes at 4 s";
  EXPECT_EQ(at[4.2].digital_outputs & 4u, 4u);
  EXPECT_EQ(sim->truth_model().payload().mass, 0.5);
  // what it may be
  const std::string f = head + "faults:\n  - ";
  EXPECT_THAT(error_of(f + "{type: payload_pick, onset: 1, mass: 1, declare_delay: 3}\n"),
              HasSubstr("field 'faults[0].declare_delay': expected a time from -2 to 2 s (the program declares the part this long after "
                        "the grip; negative: before it), got 3"));
  EXPECT_THAT(error_of(f + "{type: payload_pick, onset: 0.5, mass: 1, declare_delay: -1}\n"),
              HasSubstr("field 'faults[0].declare_delay': the declaration would come at -0.5 s, before the run starts"));
  EXPECT_THAT(error_of(f + "{type: payload_pick, onset: 1, mass: 1, declare_delay: .nan}\n"), HasSubstr("faults[0].declare_delay"));
  EXPECT_THAT(error_of(f + "{type: missed_pick, onset: 1, mass: 1, declare_delay: 0.2}\n"), HasSubstr("unknown key 'declare_delay'"));
  EXPECT_THAT(error_of(head + "streams_payload: false\nfaults:\n  - {type: payload_pick, onset: 1, mass: 1, declare_delay: 0.2}\n"),
              HasSubstr("field 'faults[0].declare_delay': a declaration's timing needs 'streams_payload: true'"));
}

// a duration that cannot be run is reported at its own line, with the value
TEST(Scenario, DurationOutOfRangeIsNamedAtItsLine) {
  EXPECT_THAT(error_of("robot: ur3e\nseed: 3\nduration: -5\n" + kSine),
              HasSubstr("test.yaml:3: field 'duration': expected a duration > 0 s, got -5"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 0\n" + kSine), HasSubstr("test.yaml:2: field 'duration': expected a duration > 0 s, got 0"));
  // (.nan and .inf are no value of any field: refused as such, session 34)
  EXPECT_THAT(error_of("robot: ur3e\nduration: .nan\n" + kSine), HasSubstr("test.yaml:2: field 'duration': expected a finite number, got nan"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: .inf\n" + kSine), HasSubstr("test.yaml:2: field 'duration': expected a finite number, got inf"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1e300\n" + kSine),
              HasSubstr("test.yaml:2: field 'duration': expected at most 1e+06 s (the longest run the simulator accepts), got 1e+300"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1e-9\n" + kSine),
              HasSubstr("test.yaml:2: field 'duration': expected at least one sample period (0.002 s at 500 Hz), got 1e-09 s"));
  EXPECT_THAT(error_of("robot: ur3e\nrate: 250\nduration: 0.003\n" + kSine),
              HasSubstr("test.yaml:3: field 'duration': expected at least one sample period (0.004 s at 250 Hz), got 0.003 s"));
  // one sample period is enough
  EXPECT_EQ(error_of("robot: ur3e\nduration: 0.002\n" + kSine), "no error");
}

TEST(Scenario, CyclesOutOfRangeAreNamedAtTheirLine) {
  EXPECT_THAT(error_of("robot: ur3e\nseed: 3\ncycles: -2\n" + kSine),
              HasSubstr("test.yaml:3: field 'cycles': expected a number of trajectory periods > 0, got -2"));
  EXPECT_THAT(error_of("robot: ur3e\ncycles: .inf\n" + kSine), HasSubstr("test.yaml:2: field 'cycles': expected a finite number, got inf"));
  // the sine's period is 2 s: 1e6 cycles last 2e6 s
  EXPECT_THAT(error_of("robot: ur3e\ncycles: 1e6\n" + kSine),
              HasSubstr("test.yaml:2: field 'cycles': 1e+06 cycles of the 2 s period last 2e+06 s: expected at most 1e+06 s (the "
                        "longest run the simulator accepts)"));
}

// the command-line override goes through the same checks and names the option
TEST(Scenario, DurationOverrideIsCheckedAndNamed) {
  const auto error_of_override = [](double d) {
    Scenario s = parse_scenario("robot: ur3e\nduration: 2\n" + kSine, "test.yaml");
    return twinwatch::test::error_text<InvalidArgument>([&] { override_duration(s, d, "--duration"); });
  };
  EXPECT_THAT(error_of_override(-1), HasSubstr("--duration: expected a duration > 0 s, got -1"));
  EXPECT_THAT(error_of_override(0), HasSubstr("--duration: expected a duration > 0 s, got 0"));
  EXPECT_THAT(error_of_override(std::nan("")), HasSubstr("--duration: expected a duration > 0 s, got nan"));
  EXPECT_THAT(error_of_override(INFINITY), HasSubstr("--duration: expected at most 1e+06 s"));
  EXPECT_THAT(error_of_override(1e-9), HasSubstr("--duration: expected at least one sample period (0.002 s at 500 Hz), got 1e-09 s"));
  Scenario s = parse_scenario("robot: ur3e\nduration: 2\n" + kSine, "test.yaml");
  override_duration(s, 0.5, "--duration");
  EXPECT_EQ(s.options.duration, 0.5);
  // the limits are checked over the new duration: a slow sine that passes its joint limit at 3.55 s
  const std::string slow = "robot: ur3e\nduration: 1\ntrajectory: {type: sine, start: [0, 0, 0, 0, 0, 0], amplitude: [7, 0, 0, 0, 0, 0], frequency: 0.05}\n";
  Scenario t = parse_scenario(slow, "slow.yaml");
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { override_duration(t, 5, "--duration"); }),
              AllOf(HasSubstr("--duration 5 s: joint 1 target position reaches"), HasSubstr("outside its range [-6.28319, 6.28319] rad (ur3e)"),
                    HasSubstr("slow.yaml:3, trajectory")));
}

// a commanded trajectory beyond the robot's joint limits is refused before simulating: the message
// names the trajectory's line, the joint, the value reached, when, and the limit
TEST(Scenario, TrajectoryBeyondTheJointLimitsIsRefused) {
  // 0.5 rad at 2 Hz: 6.28 rad/s on every joint, above the UR3e's 3.14 rad/s of J1-J3
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\n"
                       "trajectory: {type: sine, amplitude: 0.5, frequency: 2, phase: 0}\n"),
              HasSubstr("test.yaml:3: field 'trajectory': joint 1 target velocity reaches 6.28319 rad/s at t = 0 s, beyond its "
                        "limit of 3.14159 rad/s (ur3e)"));
  // the audit's 1000 Hz sine: above what a 500 Hz controller can command at all
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\ntrajectory: {type: sine, amplitude: 0.5, frequency: 1000, phase: 0}\n"),
              HasSubstr("test.yaml:3: field 'trajectory.frequency': expected frequencies from 0 to below half the control rate "
                        "(250 Hz at 500 Hz), got 1000 Hz on joint 1"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\ntrajectory: {type: sine, amplitude: 0.1, frequency: -1}\n"),
              HasSubstr("field 'trajectory.frequency': expected frequencies from 0 to below half the control rate (250 Hz at 500 Hz), "
                        "got -1 Hz on joint 1"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\ntrajectory: {type: chirp, amplitude: 0.01, f0: 1, f1: 300, sweep: 1}\n"),
              HasSubstr("field 'trajectory.f1': expected a frequency below half the control rate (250 Hz at 500 Hz), got 300 Hz"));
  // +-90 rad of Fourier excitation leaves the +-2 pi range
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\n"
                       "trajectory:\n  type: fourier\n  amplitude: 90\n  period: 10\n  harmonics: 5\n  seed: 3\n"),
              AllOf(HasSubstr("test.yaml:3: field 'trajectory': joint "), HasSubstr(" target "), HasSubstr(" at t = "),
                    HasSubstr("(ur3e)")));
  // a triangle at 100 m/s needs joint speeds no UR3e has
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\ntrajectory: {type: triangle, side: 0.1, speed: 100}\n"),
              AllOf(HasSubstr("test.yaml:3: field 'trajectory': joint "), HasSubstr(" target velocity reaches "),
                    HasSubstr("rad/s (ur3e)")));
  // only the part of the trajectory that runs is checked: the slow sine reaches 6.28 rad at 3.55 s
  const std::string slow = "trajectory: {type: sine, start: [0, 0, 0, 0, 0, 0], amplitude: [7, 0, 0, 0, 0, 0], frequency: 0.05}\n";
  EXPECT_EQ(error_of("robot: ur3e\nduration: 2\n" + slow), "no error");
  EXPECT_THAT(error_of("robot: ur3e\nduration: 4\n" + slow),
              HasSubstr("test.yaml:3: field 'trajectory': joint 1 target position reaches 6.28"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 4\n" + slow), HasSubstr(" rad at t = 3.548 s"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 4\n" + slow), HasSubstr("outside its range [-6.28319, 6.28319] rad (ur3e)"));
}

// `program` names the threshold set evaluate uses (session 21); a name thresholds --program would not
// take is refused where it is written
TEST(Scenario, ProgramNamesAThresholdSet) {
  EXPECT_EQ(error_of("robot: ur3e\nduration: 1\nprogram: pick_place-2.b\n" + kSine), "no error");
  EXPECT_EQ(parse_scenario("robot: ur3e\nduration: 1\nprogram: palletising\n" + kSine, "test.yaml").program, "palletising");
  EXPECT_EQ(parse_scenario("robot: ur3e\nduration: 1\n" + kSine, "test.yaml").program, "");
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\nprogram: pick place\n" + kSine),
              HasSubstr("test.yaml:3: field 'program': expected a program name of letters, digits, '_', '.' and '-' (as 'twinwatch "
                        "thresholds --program' takes), got 'pick place'"));
}

// payloads above the robot's rated payload (UR3e: 3 kg) are refused, at start and when picked
TEST(Scenario, PayloadAboveTheRatedPayloadIsRefused) {
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\n" + kSine + "payload: {mass: 500, com: [0, 0, 0.04]}\n"),
              HasSubstr("test.yaml:4: field 'payload.mass': expected at most 3 kg (the rated payload of ur3e), got 500 kg"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 4\n" + kSine + "faults:\n  - {type: payload_pick, onset: 1, mass: 3.5}\n"),
              HasSubstr("test.yaml:5: field 'faults[0].mass': expected at most 3 kg (the rated payload of ur3e), got 3.5 kg"));
  EXPECT_EQ(error_of("robot: ur3e\nduration: 1\n" + kSine + "payload: {mass: 3, com: [0, 0, 0.04]}\n"), "no error");
  EXPECT_THAT(error_of("robot: ur5e\nduration: 1\n" + kSine + "payload: {mass: 5.5}\n"),
              HasSubstr("field 'payload.mass': expected at most 5 kg (the rated payload of ur5e), got 5.5 kg"));
}

// jittered timestamps must stay increasing, or the simulator's own reader rejects the recording
TEST(Scenario, TimestampJitterIsBoundedBelowTheSamplePeriod) {
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\n" + kSine + "faults:\n  - {type: timestamp_jitter, onset: 0.2, magnitude: 10}\n"),
              HasSubstr("test.yaml:5: field 'faults[0].magnitude': expected a jitter sigma above 0 and at most 0.00025 s (an eighth of the "
                        "0.002 s sample period), got 10 s"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\n" + kSine + "faults:\n  - {type: timestamp_jitter, onset: 0.2, magnitude: -1e-4}\n"),
              HasSubstr("field 'faults[0].magnitude': expected a jitter sigma above 0 and at most 0.00025 s"));
  // the largest jitter allowed: the recording reads back (every timestamp increases)
  const Scenario s = parse_scenario("robot: ur3e\nseed: 4\nduration: 20\n" + kSine +
                                        "faults:\n  - {type: timestamp_jitter, onset: 0, magnitude: 0.00025}\n",
                                    "test.yaml");
  const std::string path = ::testing::TempDir() + "sim_jitter.csv";
  double smallest_step = 1.0;
  {
    device::RecordingWriter w(path, 6, Simulator::fields());
    double last = -1.0;
    make_simulator(s)->run([&](const RobotSample& x) {
      if (last >= 0.0) smallest_step = std::min(smallest_step, x.timestamp - last);
      last = x.timestamp;
      w.write(x);
    });
    w.close();
  }
  EXPECT_GE(smallest_step, 0.25 * 0.002) << "clipped at 3 sigma, the steps stay above a quarter period";
  EXPECT_LT(smallest_step, 0.002 - 3 * 0.00025) << "the jitter must be there";
  EXPECT_NO_THROW(device::read_recording(path));
}

// io_bit is a bit of actual_digital_output_bits that a UR controller drives (0 to 17)
TEST(Scenario, IoBitOutsideTheDigitalOutputsIsRefused) {
  for (const char* bit : {"99", "-1", "18"})
    EXPECT_THAT(error_of("robot: ur3e\nduration: 1\n" + kSine + "faults:\n  - {type: payload_pick, mass: 1, io_bit: " + bit +
                         ", onset: 0.3}\n"),
                HasSubstr(std::string("test.yaml:5: field 'faults[0].io_bit': expected a digital output bit from 0 to 17 "
                                      "(standard 0-7, configurable 8-15, tool 16-17), got ") + bit))
        << bit;
  const Scenario s = parse_scenario("robot: ur3e\nduration: 1\n" + kSine + "faults:\n  - {type: payload_pick, mass: 1, io_bit: 17, onset: 0.3}\n",
                                    "test.yaml");
  std::uint64_t last = 0;
  make_simulator(s)->run([&](const RobotSample& x) { last = x.digital_outputs; });
  EXPECT_EQ(last, std::uint64_t{1} << 17);
}

// a negative seed or serial used to wrap around to a large unsigned number without a word
TEST(Scenario, NegativeSeedOrSerialIsRefused) {
  EXPECT_THAT(error_of("robot: ur3e\nseed: -3\nduration: 1\n" + kSine), HasSubstr("test.yaml:2: field 'seed': expected a whole number from 0 to 4294967295, got -3"));
  // a seed as 'simulate --seed' takes it, to 2^32 - 1 (it stopped at 2^31 - 1: audit of session 56)
  EXPECT_EQ(error_of("robot: ur3e\nseed: 4294967295\nduration: 1\n" + kSine), "no error");
  EXPECT_THAT(error_of("robot: ur3e\nseed: 4294967296\nduration: 1\n" + kSine), HasSubstr("field 'seed': expected a whole number from 0 to 4294967295"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\nrobot_serial: -1\n" + kSine),
              HasSubstr("test.yaml:3: field 'robot_serial': expected a whole number >= 0, got -1"));
}

// a fault that starts at or after the end of the run would never fire: the scenario says otherwise
TEST(Scenario, FaultOnsetAfterTheEndIsRefused) {
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\n" + kSine +
                       "faults:\n  - {type: resistance, joint: 2, onset: 0.5, magnitude: 1}\n"
                       "  - {type: collision, link: 2, onset: 50, magnitude: 10}\n"),
              HasSubstr("test.yaml:6: field 'faults[1].onset': expected a time before the end of the run (1 s), got 50 s: "
                        "the collision would never fire"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\n" + kSine + "faults:\n  - {type: current_offset, joint: 2, onset: 1, magnitude: 1}\n"),
              HasSubstr("field 'faults[0].onset': expected a time before the end of the run (1 s), got 1 s"));
}

// a shorter run on the command line keeps the faults it cuts off in the scenario (they just do not fire)
TEST(Scenario, DurationOverrideMayCutFaultsOff) {
  Scenario s = parse_scenario("robot: ur3e\nduration: 10\n" + kSine + "faults:\n  - {type: resistance, joint: 2, onset: 5, magnitude: 1}\n",
                              "test.yaml");
  EXPECT_NO_THROW(override_duration(s, 2.0, "--duration"));
  EXPECT_EQ(s.faults.size(), 1u);
}

// rate x substeps >= 2000 Hz: the default substeps meet it at any rate, explicit ones are checked
TEST(Scenario, PhysicsRateRuleIsEnforcedAtTheSubstepsLine) {
  const Scenario s = parse_scenario("robot: ur3e\nduration: 1\nrate: 125\n" + kSine, "test.yaml");
  EXPECT_EQ(s.options.substeps, 16);
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\nrate: 125\nsubsteps: 4\n" + kSine),
              HasSubstr("test.yaml:4: field 'substeps': physics rate is 500 Hz (rate 125 x substeps 4), must be >= 2000 Hz: "
                        "expected substeps >= 16"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\nsubsteps: 0\n" + kSine), HasSubstr("test.yaml:3: field 'substeps': expected >= 1, got 0"));
}

// below 125 Hz (the slowest UR controller) the default joint PD no longer tracks: the rate is refused,
// with the audit's `rate: 100` among the values
TEST(Scenario, ControlRateOutsideItsRangeIsRefused) {
  for (const char* rate : {".nan", ".inf"})
    EXPECT_THAT(error_of(std::string("robot: ur3e\nduration: 1\nrate: ") + rate + "\n" + kSine),
                HasSubstr(std::string("test.yaml:3: field 'rate': expected a finite number, got ")))
        << rate;
  for (const char* rate : {"100", "0", "-1", "1e6"})
    EXPECT_THAT(error_of(std::string("robot: ur3e\nduration: 1\nrate: ") + rate + "\n" + kSine),
                HasSubstr(std::string("test.yaml:3: field 'rate': expected a control rate from 125 to 10000 Hz, got ")))
        << rate;
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\nrate: 100\n" + kSine), HasSubstr("got 100"));
}

// yaml-cpp keeps both entries of a repeated key (and answers the first): every mapping read refuses them
TEST(Scenario, DuplicateKeysAreNamedWithBothLines) {
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\n" + kFig8 + "duration: 3\n"),
              HasSubstr("test.yaml:4: field 'duration': key given twice, on lines 2 and 4; expected it once"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\ntrajectory: {type: sine, amplitude: 0.1, frequency: 0.5, amplitude: 0.2}\n"),
              HasSubstr("test.yaml:3: field 'trajectory.amplitude': key given twice, on lines 3 and 3; expected it once"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\n" + kSine + "payload:\n  mass: 1\n  mass: 2\n"),
              HasSubstr("test.yaml:6: field 'payload.mass': key given twice, on lines 5 and 6; expected it once"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 4\n" + kSine + "faults:\n  - type: resistance\n    joint: 2\n    onset: 1\n"
                       "    magnitude: 1\n    joint: 3\n"),
              HasSubstr("test.yaml:9: field 'faults[0].joint': key given twice, on lines 6 and 9; expected it once"));
}

// a joint fault without its joint says so (it used to say "expected 1 to 6, got 0")
TEST(Scenario, FaultWithoutItsJointOrLinkSaysTheFieldIsMissing) {
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\n" + kSine + "faults:\n  - {type: resistance, onset: 0.2, magnitude: 0.8}\n"),
              HasSubstr("test.yaml:5: field 'faults[0].joint': missing required field"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\n" + kSine + "faults:\n  - {type: collision, onset: 0.2, magnitude: 5}\n"),
              HasSubstr("test.yaml:5: field 'faults[0].link': missing required field"));
}

// every scenario of the library (the collision sets, the long and wear runs, the fault scenarios)
// loads: the checks above refuse none of them
TEST(Scenario, EveryScenarioUnderScenariosLoads) {
  int loaded = 0;
  for (const auto& e : std::filesystem::recursive_directory_iterator(std::string(TWINWATCH_SOURCE_DIR) + "/scenarios")) {
    if (e.path().extension() != ".yaml") continue;
    EXPECT_NO_THROW(load_scenario(e.path().string())) << e.path();
    ++loaded;
  }
  EXPECT_GT(loaded, 400);
}

// a payload's centre of mass metres from the flange is no part an arm carries (most likely mm): the
// run's and a pick's are refused, as the monitor refuses such a declaration (session 34 audit: 50 m ran)
TEST(Scenario, APayloadCentreOfMassMetresAwayIsRefused) {
  EXPECT_THAT(error_of("robot: ur3e\nduration: 1\npayload: {mass: 0.5, com: [0, 0, 50]}\n" + kSine),
              HasSubstr("test.yaml:3: field 'payload.com': expected a centre of mass within 1 m of the flange, got 50 m away (in mm? give metres)"));
  EXPECT_THAT(error_of("robot: ur3e\nduration: 4\n" + kSine + "faults:\n  - {type: payload_pick, onset: 1, mass: 0.5, com: [40, 0, 0]}\n"),
              HasSubstr("field 'faults[0].com': expected a centre of mass within 1 m of the flange, got 40 m away"));
  EXPECT_EQ(error_of("robot: ur3e\nduration: 1\npayload: {mass: 0.5, com: [0, 0.1, 0.3]}\n" + kSine), "no error");
}

}  // namespace
}  // namespace twinwatch::sim
