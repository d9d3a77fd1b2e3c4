// The monitoring loop end to end on the virtual robot: a twin identified from healthy runs only,
// thresholds learned on other healthy runs, then faults the twin has never seen.
#include "twinwatch/monitor/monitor.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <regex>

#include "twinwatch/core/error.hpp"
#include "twinwatch/ident/physics_ident.hpp"
#include "monitor/simulated_run.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "error_text.hpp"

namespace twinwatch::monitor {
namespace {

using test::run;
using test::scenario;

struct MonitorLoop : ::testing::Test {
  static void SetUpTestSuite() {
    const auto exc = run("robot: ur3e\nseed: 501\nduration: 60\ntrajectory: {type: fourier, amplitude: 0.9, period: 10, harmonics: 5, seed: 3}\n");
    const auto fig = run(scenario(502, 40, 0.5));
    payload.mass = 0.5;
    payload.com = Eigen::Vector3d(0, 0, 0.04);
    ident::IdentReport rep;
    twin = new ident::TwinModel(ident::identify_physics("ur3e", {{&exc, {}}, {&fig, payload}}, ident::IdentOptions{}, rep));
    const auto h1 = run(scenario(503, 24, 0.5));
    const auto h2 = run(scenario(504, 16, 0.0));
    config = new MonitorConfig(learn_thresholds(*twin, {{&h1, payload}, {&h2, {}}}));
  }
  static void TearDownTestSuite() {
    delete twin;
    delete config;
  }
  static std::vector<Event> monitor(const device::Recording& rec, double declared_payload) {
    ident::TwinModel t = *twin;
    if (declared_payload > 0) t.set_payload(payload);
    Monitor m(t, *config);
    for (const auto& s : rec.samples) m.push(s);
    m.finish();
    return m.events();
  }
  static ident::TwinModel* twin;
  static MonitorConfig* config;
  static model::RigidBodyInertia payload;
};
ident::TwinModel* MonitorLoop::twin = nullptr;
MonitorConfig* MonitorLoop::config = nullptr;
model::RigidBodyInertia MonitorLoop::payload;

TEST_F(MonitorLoop, NoFalseAlarmOnHealthyRunsWithNewSeeds) {
  EXPECT_TRUE(monitor(run(scenario(601, 40, 0.5)), 0.5).empty());
  EXPECT_TRUE(monitor(run(scenario(602, 40, 0.0)), 0.0).empty());
}

// UR3e §4.2: J5 resistance is detected and attributed to J5 (the paper could not isolate it)
TEST_F(MonitorLoop, J5ResistanceIsDetectedAndAttributedToJ5) {
  const auto ev = monitor(run(scenario(603, 16, 0.5, "  - {type: resistance, joint: 5, onset: 6, ramp: 0.2, magnitude: 0.8}\n")), 0.5);
  ASSERT_FALSE(ev.empty());
  EXPECT_GE(ev.front().t_start, 6.0);
  EXPECT_EQ(ev.front().fault, FaultClass::Resistance) << ev.front().detail;
  EXPECT_EQ(ev.front().joint, 4) << ev.front().detail;
  EXPECT_NEAR(ev.front().magnitude, 0.8, 0.3) << ev.front().detail;
}

// audit of session 16: a persistent fault dips below its threshold at reversals; each raise within
// the merge gap continues the same event, and that event used to be reported closed at every dip
// (five records of one J5 resistance in the events file and the store). Its first, short-window
// diagnosis also split the extra friction into Coulomb +4.8 N·m and viscous -16 N·m·s/rad.
TEST_F(MonitorLoop, AContinuedAlertIsReportedClosedOnceWithFrictionThatOpposesMotion) {
  const auto rec = run(scenario(603, 30, 0.5, "  - {type: resistance, joint: 5, onset: 6, ramp: 0.2, magnitude: 0.8}\n"));
  ident::TwinModel t = *twin;
  t.set_payload(payload);
  Monitor m(t, *config);
  std::vector<Event> closed;
  int resistance_updates = 0;
  const std::regex split(R"(Coulomb (-?[0-9.]+) N·m, viscous (-?[0-9.]+) N·m·s/rad)");
  m.on_event = [&](const Event& e) {
    if (!e.open) closed.push_back(e);
    std::smatch g;
    if (e.fault == FaultClass::Resistance && std::regex_search(e.detail, g, split)) {
      ++resistance_updates;
      EXPECT_GE(std::stod(g[1]), 0.0) << e.detail;
      EXPECT_GE(std::stod(g[2]), 0.0) << e.detail;
    }
  };
  for (const auto& s : rec.samples) m.push(s);
  m.finish();
  const auto& ev = m.events();
  ASSERT_FALSE(ev.empty());
  EXPECT_GE(resistance_updates, 2);
  // one closed record per event, the event's final state
  ASSERT_EQ(closed.size(), ev.size());
  for (size_t k = 0; k < ev.size(); ++k) {
    EXPECT_EQ(closed[k].t_start, ev[k].t_start);
    EXPECT_EQ(closed[k].t_end, ev[k].t_end);
  }
  EXPECT_EQ(ev.front().fault, FaultClass::Resistance) << ev.front().detail;
  EXPECT_GT(ev.front().duration(), 10.0) << "the J5 alert should span the dips, not end at the first";
}

// UR3e §4.3: 0.5 kg payload loss detected within 100 ms, classified, mass within +-20 %
TEST_F(MonitorLoop, PayloadLossIsDetectedFastAndSized) {
  const auto ev = monitor(run(scenario(604, 12, 0.5, "  - {type: payload_loss, onset: 8.5}\n")), 0.5);
  ASSERT_FALSE(ev.empty());
  EXPECT_LT(ev.front().t_detected - 8.5, 0.1);
  EXPECT_EQ(ev.front().fault, FaultClass::PayloadChange) << ev.front().detail;
  EXPECT_NEAR(ev.front().magnitude, -0.5, 0.1) << ev.front().detail;
}

TEST_F(MonitorLoop, CollisionIsDetectedAsAPulse) {
  const auto ev = monitor(run(scenario(605, 12, 0.5,
                                      "  - {type: collision, link: 2, onset: 9.3, magnitude: 10, duration: 0.05, "
                                      "point: [-0.12, 0.0, 0.1], direction: [0.3, 1.0, -0.2]}\n")),
                          0.5);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_LT(ev.front().t_detected - 9.3, 0.05);
  EXPECT_EQ(ev.front().fault, FaultClass::Collision) << ev.front().detail;
  EXPECT_LT(ev.front().duration(), 0.5);
}

TEST_F(MonitorLoop, StreamGapsAndFrozenChannelsAreTheirOwnEvents) {
  const auto ev = monitor(run(scenario(606, 12, 0.5,
                                      "  - {type: dropped_samples, onset: 5, magnitude: 5, end: 5.1}\n"
                                      "  - {type: stuck_current, joint: 3, onset: 8, end: 9}\n")),
                          0.5);
  bool gap = false, stuck = false;
  for (const auto& e : ev) {
    gap |= e.fault == FaultClass::StreamFault && e.magnitude == 5.0;
    stuck |= e.fault == FaultClass::SensorFault && e.joint == 2;
  }
  EXPECT_TRUE(gap);
  EXPECT_TRUE(stuck);
}

// The false-alarm margin a healthy run reports (Monitor::track_margin) is exactly the sensitivity of
// its first alarm: every threshold scaled by a factor just above it raises nothing, just below it raises.
TEST_F(MonitorLoop, TheMarginOfAHealthyRunIsTheSensitivityOfItsFirstAlarm) {
  const auto rec = run(scenario(607, 16, 0.5));
  ident::TwinModel t = *twin;
  t.set_payload(payload);
  const auto alerts = [&](double sensitivity, double* margin) {
    MonitorConfig c = *config;
    c.sensitivity = VectorJ::Constant(t.n_dof(), sensitivity);
    Monitor m(t, c);
    m.track_margin();
    for (const auto& s : rec.samples) m.push(s);
    m.finish();
    if (margin) *margin = std::max(m.margin_current().maxCoeff(), m.margin_observer().maxCoeff());
    return m.events().size();
  };
  double margin = 0.0;
  EXPECT_EQ(alerts(1.0, &margin), 0u);
  EXPECT_GT(margin, 0.3) << "a healthy run uses a fair part of its thresholds";
  ASSERT_LT(margin, 1.0);
  EXPECT_EQ(alerts(margin * 1.001, nullptr), 0u);
  EXPECT_GE(alerts(margin * 0.999, nullptr), 1u);
  Monitor late(t, *config);
  late.push(rec.samples.front());
  EXPECT_THROW(late.track_margin(), InvalidArgument);
}

// The observer's debounce per joint, chosen on a healthy validation run the thresholds were not
// learned on. Checked: one exceedance's peak is never below two's (the run-minimum of two samples);
// the chosen count of every joint is the smallest whose validation ratio is below 1 and below the
// worst joint's at the shared count; a monitor with the choice shows each joint the margin of its own
// count, so the run's largest observer ratio is no larger than with the shared count (the margin is
// kept) while at least one joint is debounced less. A twin without an observer, a user's explicit
// count and no validation run are refused; learning the thresholds again drops the choice.
TEST_F(MonitorLoop, TheObserverDebouncePerJointKeepsTheSharedCountsMargin) {
  const auto val = run(scenario(608, 40, 0.5));
  const ObserverDebounceChoice choice = choose_observer_debounce(*twin, *config, {{&val, payload}});
  const int n = twin->n_dof();
  ASSERT_EQ(choice.ratio.size(), 2u) << "one row per count up to the shared 2";
  ASSERT_EQ(choice.raise_after.size(), static_cast<size_t>(n));
  EXPECT_NEAR(choice.seconds, 40.0, 0.01);
  const double worst = choice.ratio[1].maxCoeff();
  EXPECT_GT(worst, 0.3) << "a healthy run uses a fair part of its observer thresholds";
  EXPECT_LT(worst, 1.0);
  int fewer = 0;
  for (int j = 0; j < n; ++j) {
    EXPECT_GE(choice.ratio[0][j], choice.ratio[1][j]) << "J" << j + 1;
    const bool one_fits = choice.ratio[0][j] < 1.0 && choice.ratio[0][j] <= worst;
    EXPECT_EQ(choice.raise_after[static_cast<size_t>(j)], one_fits ? 1 : 2) << "J" << j + 1;
    fewer += one_fits;
  }
  EXPECT_GE(fewer, 1) << "no joint keeps the worst joint's margin with one sample: nothing to check";
  ident::TwinModel t = *twin;
  t.set_payload(payload);
  MonitorConfig chosen = *config;
  chosen.observer_choice.raise_after = choice.raise_after;
  Monitor m(t, chosen);
  m.track_margin();
  for (const auto& s : val.samples) m.push(s);
  m.finish();
  const VectorJ seen = m.margin_observer();
  for (int j = 0; j < n; ++j)
    EXPECT_DOUBLE_EQ(seen[j], choice.ratio[static_cast<size_t>(choice.raise_after[static_cast<size_t>(j)] - 1)][j]) << "J" << j + 1;
  EXPECT_LE(seen.maxCoeff(), worst);
  EXPECT_TRUE(m.events().empty());
  // the explicit count overrides the per-joint one, and a choice under it is refused
  chosen.observer_raise_after = 2;
  EXPECT_EQ(chosen.observer_debounce(0), 2);
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { choose_observer_debounce(*twin, chosen, {{&val, payload}}); }),
              ::testing::HasSubstr("observer_raise_after is set (2)"));
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { choose_observer_debounce(*twin, *config, {}); }),
              ::testing::HasSubstr("no healthy validation runs"));
  MonitorConfig no_observer = *config;
  no_observer.observer_level.resize(0);
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { choose_observer_debounce(*twin, no_observer, {{&val, payload}}); }),
              ::testing::HasSubstr("no thresholds"));
  MonitorConfig relearned = *config;
  relearned.observer_choice = choice;
  relearned = learn_thresholds(*twin, {{&val, payload}}, relearned);
  EXPECT_TRUE(relearned.observer_choice.raise_after.empty()) << "a choice belongs to the thresholds it was made for";
  EXPECT_TRUE(relearned.observer_choice.ratio.empty());
}

TEST(MonitorConfig, ValidationNamesTheField) {
  MonitorConfig c;
  c.static_level = VectorJ::Ones(6);
  c.use_dynamic = false;
  c.sensitivity = VectorJ::Ones(5);
  try {
    c.validate(6);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("sensitivity has size 5, expected 6"));
  }
}

TEST(MonitorConfig, ObserverRaiseAfterIsValidatedAndStored) {
  MonitorConfig c;
  c.static_level = VectorJ::Ones(6);
  c.use_dynamic = false;
  c.observer_raise_after = -1;
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { c.validate(6); }), ::testing::HasSubstr("observer_raise_after is -1, must be >= 1"));
  c.observer_raise_after = 0;  // the default: the current channel's raise_after, not written
  EXPECT_EQ(c.to_json().find("observer_raise_after"), std::string::npos);
  c.observer_raise_after = 1;
  const MonitorConfig back = MonitorConfig::from_json(c.to_json(), "twin.json");
  EXPECT_EQ(back.observer_raise_after, 1);
  EXPECT_EQ(back.raise_after, c.raise_after);
}

// The per-joint observer debounce: validated (one entry per joint, each >= 1), stored with its
// validation ratios in the default set and in a program's set, and taken with the program's thresholds
// (a program without a choice of its own uses the shared count, not the default set's choice).
TEST(MonitorConfig, ObserverDebouncePerJointIsValidatedStoredAndFollowsTheProgram) {
  MonitorConfig c;
  c.static_level = VectorJ::Ones(6);
  c.use_dynamic = false;
  c.observer_level = VectorJ::Constant(6, 2.0);
  c.observer_choice.raise_after = {1, 1, 2};
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { c.validate(6); }),
              ::testing::HasSubstr("monitor observer_raise_after_joint has 3 entries, expected 6 (one per joint)"));
  c.observer_choice.raise_after = {1, 1, 0, 2, 1, 1};
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { c.validate(6); }),
              ::testing::HasSubstr("observer_raise_after_joint of joint 3 is 0, must be 1 to 1000"));
  c.observer_choice.raise_after = {1, 1, 1, 2, 1, 1};
  c.observer_choice.ratio = {VectorJ::Constant(6, 0.8), VectorJ::Constant(5, 0.7)};
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { c.validate(6); }),
              ::testing::HasSubstr("monitor observer_validation_ratio row 2 has 5 entries, expected 6"));
  c.observer_choice.ratio = {VectorJ::Constant(6, 0.8), VectorJ::Constant(6, 0.7)};
  MonitorConfig no_observer = c;
  no_observer.observer_level.resize(0);
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { no_observer.validate(6); }),
              ::testing::HasSubstr("monitor has an observer debounce choice (observer_raise_after_joint) but no observer thresholds"));
  ThresholdSet tri;
  tri.static_level = VectorJ::Ones(6);
  tri.observer_level = VectorJ::Constant(6, 3.0);
  c.programs["triangle"] = tri;
  ThresholdSet p2p = tri;
  p2p.observer_choice.raise_after = {2, 2, 2, 2, 2, 1};
  c.programs["point_to_point"] = p2p;
  c.validate(6);
  EXPECT_EQ(c.observer_debounce(0), 1);
  EXPECT_EQ(c.observer_debounce(3), 2);
  const MonitorConfig back = MonitorConfig::from_json(c.to_json(), "twin.json");
  EXPECT_EQ(back.observer_choice.raise_after, c.observer_choice.raise_after);
  ASSERT_EQ(back.observer_choice.ratio.size(), 2u);
  EXPECT_DOUBLE_EQ(back.observer_choice.ratio[1][5], 0.7);
  EXPECT_EQ(back.programs.at("point_to_point").observer_choice.raise_after, p2p.observer_choice.raise_after);
  MonitorConfig on_p2p = back;
  on_p2p.select_program("point_to_point");
  EXPECT_EQ(on_p2p.observer_debounce(5), 1);
  EXPECT_EQ(on_p2p.observer_debounce(0), 2);
  MonitorConfig on_tri = back;
  on_tri.select_program("triangle");
  EXPECT_EQ(on_tri.observer_debounce(0), on_tri.raise_after) << "the default set's choice is not the triangle's";
  c.programs["point_to_point"].observer_choice.raise_after = {2, 2};
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { c.validate(6); }),
              ::testing::HasSubstr("program 'point_to_point' observer_raise_after_joint has 2 entries"));
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] {
                MonitorConfig::from_json(R"({"static_level_A": [1], "observer_raise_after_joint": [1, 1.5]})", "twin.json");
              }),
              ::testing::HasSubstr("observer_raise_after_joint[1] must be a whole number within +-2147483647, got 1.5"));
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] {
                MonitorConfig::from_json(R"({"static_level_A": [1], "observer_raise_after_joint": [4294967297]})", "twin.json");
              }),
              ::testing::HasSubstr("observer_raise_after_joint[0] must be a whole number within +-2147483647, got 4294967297"));
}

// found by fuzzing (fuzz/regressions/monitor_config): 9 values overflowed a VectorJ (stack buffer
// overflow), and get<int>() of 1e20 was undefined
TEST(MonitorConfig, FromJsonRejectsMoreValuesThanJointsAndHugeCounts) {
  const auto error_of = [](const std::string& text) {
    return twinwatch::test::error_text<ParseError>([&] { MonitorConfig::from_json(text, "twin.json"); });
  };
  EXPECT_THAT(error_of(R"({"static_level_A": [1, 2, 3, 4, 5, 6, 7, 8, 9]})"),
              ::testing::HasSubstr("twin.json: field 'monitor': malformed monitor thresholds: static_level_A: expected at most 7 values (one per joint), got 9"));
  EXPECT_THAT(error_of(R"({"static_level_A": [1], "raise_after": 1e20})"),
              ::testing::HasSubstr("raise_after: expected a whole number within +-2147483647, got 1e+20"));
  EXPECT_THAT(error_of(R"({"static_level_A": [1], "trend": {"history": 2.5}})"), ::testing::HasSubstr("trend.history: expected a whole number"));
}

}  // namespace
}  // namespace twinwatch::monitor
