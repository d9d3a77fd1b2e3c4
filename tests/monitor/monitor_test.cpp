// The monitoring loop end to end on the virtual robot: a twin identified from healthy runs only,
// thresholds learned on other healthy runs, then faults the twin has never seen.
#include "twinwatch/monitor/monitor.hpp"
#include "twinwatch/monitor/momentum_observer.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <map>

#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <regex>
#include <filesystem>
#include <unistd.h>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/log.hpp"
#include "twinwatch/device/recording.hpp"
#include "twinwatch/monitor/declaration.hpp"
#include "twinwatch/monitor/trend.hpp"
#include "twinwatch/ident/physics_ident.hpp"
#include "twinwatch/model/description_io.hpp"
#include "monitor/simulated_run.hpp"
#include "twinwatch/signal/fir.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "error_text.hpp"

namespace twinwatch::monitor {
namespace {

using test::run;
using test::scenario;
using test::undeclared;

// a complete monitor block as the writer writes it: default set with dynamic thresholds, the
// observer's, and a program's set
nlohmann::json valid_block() {
  MonitorConfig c;
  c.static_level = VectorJ::Constant(6, 0.1);
  c.dynamic.assign(6, DynamicThresholdJoint{0.01, 0.02, 0.03, 0.04, 5.0, 0.02, 0.1});
  c.observer_level = VectorJ::Constant(6, 1.0);
  c.observer_dynamic = c.dynamic;
  ThresholdSet s;
  s.static_level = VectorJ::Constant(6, 0.3);
  s.dynamic = c.dynamic;
  s.runs = 2;
  s.seconds = 40.0;
  c.programs["chirp"] = s;
  return nlohmann::json::parse(c.to_json());
}

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
  // the twin carrying a part of `mass` kg at the test payload's centre of mass (0: none)
  static ident::TwinModel carrying(double mass) {
    ident::TwinModel t = *twin;
    if (mass > 0.0) {
      model::RigidBodyInertia part = payload;
      part.mass = mass;
      t.set_payload(part);
    }
    return t;
  }
  // the twin with the 0.5 kg payload the test scenarios declare
  static ident::TwinModel declared_twin() {
    ident::TwinModel t = *twin;
    t.set_payload(payload);
    return t;
  }
  // the test config with thresholds learned for `program` on one healthy run of it (seed, duration
  // [s]), selected as "pick_place"
  static MonitorConfig with_program_thresholds(const std::string& program, unsigned seed, int duration) {
    MonitorConfig c = *config;
    const auto healthy = run(fmt::format("robot: ur3e\nseed: {}\nduration: {}\n", seed, duration) + program);
    learn_program_thresholds(c, "pick_place", *twin, {{&healthy, {}}});
    c.select_program("pick_place");
    return c;
  }
  // the fixture's thresholds learned on its healthy runs as a log without the controller's targets
  // would hold them (streams_targets: false), once for the tests that need them
  static const MonitorConfig& config_without_targets() {
    static const MonitorConfig c = [] {
      const auto h1 = run(scenario(503, 24, 0.5) + kNoTargets), h2 = run(scenario(504, 16, 0.0) + kNoTargets);
      return learn_thresholds(*twin, {{&h1, payload}, {&h2, {}}});
    }();
    return c;
  }
  static constexpr const char* kNoTargets = "streams_targets: false\n";
  static ident::TwinModel* twin;
  static MonitorConfig* config;
  static model::RigidBodyInertia payload;
};
ident::TwinModel* MonitorLoop::twin = nullptr;
MonitorConfig* MonitorLoop::config = nullptr;
model::RigidBodyInertia MonitorLoop::payload;

// a part of `mass` kg lost (the run carries it from the start) or picked at `onset` [s], with gripper
// output 0 changing there: the scenario's fault line
std::string part_change(bool loss, double mass, double onset) {
  return loss ? fmt::format("  - {{type: payload_loss, onset: {}, io_bit: 0}}\n", onset)
              : fmt::format("  - {{type: payload_pick, onset: {}, io_bit: 0, mass: {}, com: [0, 0, 0.04]}}\n", onset, mass);
}

// the long runs' pick-and-place between two stations (scenarios/ur3e/long/long_pick_place_*): down
// and up `move` s, a rest of `rest` s at each station, `transfer` s between them
std::string pick_and_place(double move, double rest, double transfer) {
  return fmt::format(
      "trajectory: {{type: point_to_point, waypoints: [[-0.6, -1.4, 1.3, -1.5, -1.3, 0.3], [-0.6, -1.2, 1.45, -1.8, -1.3, 0.3], "
      "[-0.6, -1.2, 1.45, -1.8, -1.3, 0.3], [-0.6, -1.4, 1.3, -1.5, -1.3, 0.3], [0.6, -1.4, 1.3, -1.5, -1.85, -0.3], "
      "[0.6, -1.2, 1.45, -1.8, -1.85, -0.3], [0.6, -1.2, 1.45, -1.8, -1.85, -0.3], [0.6, -1.4, 1.3, -1.5, -1.85, -0.3]], "
      "durations: [{0}, {1}, {0}, {2}, {0}, {1}, {0}, {2}]}}\n",
      move, rest, transfer);
}

// every event on a line of its own (start-end, class, text), for a failure's message
std::string listing(const std::vector<Event>& events) {
  std::string all;
  for (const auto& e : events) all += fmt::format("\n{:.3f}-{:.3f} s {}: {}", e.t_start, e.t_end, to_string(e.fault), e.detail);
  return all;
}

// Two monitors fed one recording sample by sample: joint j's filtered current residual and
// observer residual in each, and the largest difference of the current residuals over the samples
// where `far` holds (away from what the two differ in)
struct SideBySide {
  std::vector<double> ra, rb, oa, ob;
  double far_diff = 0.0;
};
template <class Far>
SideBySide side_by_side(Monitor& a, Monitor& b, const device::Recording& rec, int j, Far far) {
  SideBySide out;
  for (const auto& x : rec.samples) {
    a.push(x);
    b.push(x);
    out.ra.push_back(a.filtered_residual()[j]);
    out.rb.push_back(b.filtered_residual()[j]);
    out.oa.push_back(a.observer_residual()[j]);
    out.ob.push_back(b.observer_residual()[j]);
    if (far(x)) out.far_diff = std::max(out.far_diff, std::abs(out.ra.back() - out.rb.back()));
  }
  return out;
}

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

// session 40: a resistance near its joint's threshold raises on noise peaks, and its looks fit the
// window's residual. A contact's force is free at every sample, so its fit absorbed the other
// joints' noise as well: a 1 N·m J2 resistance that ended after 3 s was a "contact on link 1" and a
// "contact on link 4" on its last looks (explained 0.93 against the resistance's 0.62), and a
// 0.35 N·m one on J5 explained 15-25 % of a window that is mostly J1-J3's noise, "no signature
// explains the residual well". The contact is scored on what it explains beyond the noise it
// absorbs, and the Unknown test and the confidence are on the energy the noise leaves to explain.
TEST_F(MonitorLoop, AResistanceNearItsThresholdIsNeitherAContactNorUnknown) {
  struct Case {
    int joint;
    double magnitude, end;
    unsigned seed;
  };
  for (const Case c : {Case{2, 1.0, 15.0, 5}, Case{3, 0.8, 15.0, 5}, Case{5, 0.35, 0.0, 5}, Case{2, 1.0, 19.0, 6}, Case{3, 0.8, 19.0, 6},
                       Case{5, 0.5, 19.0, 6}}) {
    const std::string fault = fmt::format("  - {{type: resistance, joint: {}, onset: 12, ramp: 0.2, magnitude: {}{}}}\n", c.joint,
                                          c.magnitude, c.end > 0.0 ? fmt::format(", end: {}", c.end) : "");
    const auto ev = monitor(run(scenario(c.seed, 20, 0.5, fault)), 0.5);
    SCOPED_TRACE(fault + listing(ev));
    ASSERT_FALSE(ev.empty());
    // sized within 25 % on its longest event; a short one's size is the level read before its raise
    // (0.58 N·m of the 1 N·m on J2, seed 6, while it ramps in)
    const auto longest = std::max_element(ev.begin(), ev.end(), [](const Event& a, const Event& b) { return a.duration() < b.duration(); });
    EXPECT_NEAR(longest->magnitude, c.magnitude, 0.25 * c.magnitude);
    for (const Event& e : ev) {
      EXPECT_GE(e.t_start, 12.0);
      EXPECT_EQ(e.fault, FaultClass::Resistance);
      EXPECT_EQ(e.joint, c.joint - 1);
      EXPECT_GT(e.magnitude, 0.5 * c.magnitude);
      EXPECT_LT(e.magnitude, 2.0 * c.magnitude);
      // its confidence is the share of the energy beyond the window's noise it explains: read on
      // the whole energy, the J5 resistance's was 0.30 while right (docs/validation.md)
      EXPECT_GT(e.confidence, 0.5);
    }
  }
}

// A resistance on a joint that moves one way, stops, and moves on is no current offset: the stop
// does not tell them apart (the friction that stops the joint holds the controller's position
// error, and the residual stays at about 60 % of its level), only a reversal does. Read with the
// rest as the tie-break, a J4 resistance on the figure-eight was "constant offset on the J4 current
// channel" (held-out set resistance_heldout, docs/validation.md). A true offset is still one: the
// library's stream_and_sensor_faults, cli tests.
TEST_F(MonitorLoop, AResistanceOnAJointThatStopsBetweenMovesIsNoCurrentOffset) {
  struct Case {
    double onset, magnitude, end;
    unsigned seed;
  };
  for (const Case c : {Case{10.54, 0.73, 13.11, 40127}, Case{10.6, 0.6, 14.0, 7}}) {
    const std::string fault = fmt::format("  - {{type: resistance, joint: 4, onset: {}, ramp: 0.2, magnitude: {}, end: {}}}\n", c.onset,
                                          c.magnitude, c.end);
    const auto ev = monitor(run(scenario(c.seed, 18, 0.5, fault)), 0.5);
    SCOPED_TRACE(fault + listing(ev));
    ASSERT_FALSE(ev.empty());
    for (const Event& e : ev) {
      EXPECT_GE(e.t_start, c.onset);
      EXPECT_EQ(e.fault, FaultClass::Resistance);
      EXPECT_EQ(e.joint, 3);
      EXPECT_NEAR(e.magnitude, c.magnitude, 0.5 * c.magnitude);
    }
  }
}

// A constant offset on one current channel (a drifting sensor) is no resistance: an offset aids the
// motion half of the time, and friction that opposes motion explains none of it. Scored on the free
// fit of a Coulomb and a viscous term, the same window read "extra friction on J4 ≈ 0.00 N·m" (the
// library's stream_and_sensor_faults): a resistance is scored on the non-negative fit it reports
TEST_F(MonitorLoop, AConstantOffsetOnACurrentChannelIsASensorFaultNotAResistance) {
  const auto ev = monitor(run(scenario(19, 30, 0.5, "  - {type: current_offset, joint: 4, onset: 22, magnitude: 0.3}\n")), 0.5);
  SCOPED_TRACE(listing(ev));
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].fault, FaultClass::SensorFault);
  EXPECT_EQ(ev[0].joint, 3);
  EXPECT_GE(ev[0].t_start, 22.0);
  EXPECT_LT(ev[0].t_detected - 22.0, 0.1);
}

// audit of session 16: a persistent fault dips below its threshold at reversals; each raise within
// the merge gap continues the same event, and that event used to be reported closed at every dip
// (five records of one J5 resistance in the events file and the store). Its first, short-window
// diagnosis also split the extra friction into Coulomb +4.8 N·m and viscous -16 N·m·s/rad.
TEST_F(MonitorLoop, AContinuedAlertIsReportedClosedOnceWithFrictionThatOpposesMotion) {
  const auto rec = run(scenario(603, 30, 0.5, "  - {type: resistance, joint: 5, onset: 6, ramp: 0.2, magnitude: 0.8}\n"));
  ident::TwinModel t = declared_twin();
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

// the events of a monitored recording, and the events in the order they were reported closed
std::pair<std::vector<Event>, std::vector<Event>> events_and_closings(const device::Recording& rec) {
  ident::TwinModel t = MonitorLoop::declared_twin();
  Monitor m(t, *MonitorLoop::config);
  std::vector<Event> closed;
  m.on_event = [&](const Event& e) {
    if (!e.open) closed.push_back(e);
  };
  for (const auto& s : rec.samples) m.push(s);
  m.finish();
  return {m.events(), closed};
}

// review of session 18: a raise within the merge gap continued the earlier alert whatever it was,
// so a 10 N·m contact 0.6 s after a J5 resistance ended vanished into the resistance event. A raise
// on another joint is now looked at on its own first; the resistance's own dips still continue it.
TEST_F(MonitorLoop, AContactRightAfterAPersistentFaultIsAnEventOfItsOwn) {
  const auto rec = run(scenario(153, 20, 0.5,
                                "  - {type: resistance, joint: 5, onset: 9, ramp: 0.2, magnitude: 0.8, end: 12}\n"
                                "  - {type: collision, link: 3, onset: 12.6, magnitude: 10, duration: 0.05, "
                                "point: [-0.1, 0.0, 0.03], direction: [0.3, 1.0, -0.2]}\n"));
  const auto [ev, closed] = events_and_closings(rec);
  ASSERT_EQ(ev.size(), 2u);
  EXPECT_EQ(ev[0].fault, FaultClass::Resistance) << ev[0].detail;
  EXPECT_EQ(ev[0].joint, 4);
  EXPECT_LT(ev[0].t_end, 12.6) << "the resistance ended before the contact";
  // an event ends at its last exceedance, not when the clearing debounce runs out (50 samples later)
  EXPECT_NEAR(ev[0].t_end, 12.0, 0.05);
  EXPECT_EQ(ev[1].fault, FaultClass::Collision) << ev[1].detail;
  EXPECT_LT(ev[1].t_detected - 12.6, 0.05);
  EXPECT_LT(ev[1].duration(), 0.15);  // a 50 ms contact (through the residual filter)
  // each reported closed once, the earlier first
  ASSERT_EQ(closed.size(), 2u);
  EXPECT_EQ(closed[0].fault, FaultClass::Resistance);
  EXPECT_EQ(closed[1].fault, FaultClass::Collision);
}

// A contact DURING a persistent fault (session 19, the output audit): the monitor kept one open
// event, and a 20 N·m contact on link 2 while a J5 resistance was open was reported nowhere. The
// resistance is parked while the raise is looked at on its own: a contact is its own event, and
// the resistance goes on, one event, still open at the stop.
TEST_F(MonitorLoop, AContactDuringAPersistentFaultIsAnEventOfItsOwn) {
  const auto rec = run(scenario(153, 20, 0.5,
                                "  - {type: resistance, joint: 5, onset: 6, ramp: 0.2, magnitude: 0.8}\n"
                                "  - {type: collision, link: 2, onset: 15.3, magnitude: 20, duration: 0.05, "
                                "point: [-0.12, 0.0, 0.1], direction: [0.3, 1.0, -0.2]}\n"));
  const auto [ev, closed] = events_and_closings(rec);
  const std::string all = listing(ev);
  ASSERT_EQ(ev.size(), 2u) << all;
  EXPECT_EQ(ev[0].fault, FaultClass::Resistance) << ev[0].detail;
  EXPECT_EQ(ev[0].joint, 4);
  EXPECT_NEAR(ev[0].t_end, 20.0, 0.01) << "the resistance goes on past the contact";
  EXPECT_THAT(ev[0].detail, ::testing::HasSubstr("still active when monitoring stopped"));
  EXPECT_TRUE(ev[0].active_at_stop);
  EXPECT_EQ(ev[1].fault, FaultClass::Collision) << ev[1].detail;
  EXPECT_FALSE(ev[1].active_at_stop);
  EXPECT_EQ(ev[1].link, 1);  // link 2
  EXPECT_LT(ev[1].t_detected - 15.3, 0.02);
  EXPECT_LT(ev[1].duration(), 0.15);
  // the contact is reported when it ends, the resistance at the stop
  ASSERT_EQ(closed.size(), 2u);
  EXPECT_EQ(closed[0].fault, FaultClass::Collision);
  EXPECT_EQ(closed[1].fault, FaultClass::Resistance);
}

// the samples of `rec` without those in [from, from + seconds) for each (from, seconds): stream gaps
device::Recording without(const device::Recording& rec, const std::vector<std::pair<double, double>>& cuts) {
  device::Recording out = rec;
  out.samples.clear();
  for (const auto& s : rec.samples) {
    bool cut = false;
    for (const auto& [from, len] : cuts) cut |= s.timestamp >= from && s.timestamp < from + len;
    if (!cut) out.samples.push_back(s);
  }
  return out;
}

// review of session 18: after a stream gap (an RTDE reconnect, a stalled network) the observer's
// first difference spanned the gap, and the twin's pre-sliding memory had not seen a reversal
// inside it: gaps of 0.5 s and more were followed by false "collisions" and "sensor faults"
TEST_F(MonitorLoop, AStreamGapIsAStreamFaultAndNothingElse) {
  const auto healthy = run(scenario(610, 40, 0.5));
  const auto gappy = without(healthy, {{4.0, 0.2}, {8.0, 0.5}, {13.0, 1.0}, {19.0, 2.0}, {25.0, 3.0}, {31.9, 1.37}});
  const auto ev = monitor(gappy, 0.5);
  ASSERT_EQ(ev.size(), 6u);
  for (const auto& e : ev) EXPECT_EQ(e.fault, FaultClass::StreamFault) << e.t_start << " s: " << e.detail;
  // and a contact 0.4 s after a 2 s gap is still found, as a contact
  const auto hit = without(run(scenario(611, 14, 0.5,
                                        "  - {type: collision, link: 2, onset: 10.4, magnitude: 10, duration: 0.05, "
                                        "point: [-0.12, 0.0, 0.1], direction: [0.3, 1.0, -0.2]}\n")),
                           {{8.0, 2.0}});
  const auto ev2 = monitor(hit, 0.5);
  ASSERT_EQ(ev2.size(), 2u);
  EXPECT_EQ(ev2[0].fault, FaultClass::StreamFault);
  EXPECT_EQ(ev2[1].fault, FaultClass::Collision) << ev2[1].detail;
  EXPECT_LT(ev2[1].t_detected - 10.4, 0.05);
  // a gap its source flagged (a reconnection) on evenly spaced stamps: said as an interruption, not
  // "0 sample(s) missing" (audit of session 22)
  auto flagged = healthy;
  for (auto& x : flagged.samples)
    if (std::abs(x.timestamp - 6.0) < 1e-4) x.gap_before = true;
  const auto ev3 = monitor(flagged, 0.5);
  ASSERT_EQ(ev3.size(), 1u);
  EXPECT_EQ(ev3[0].fault, FaultClass::StreamFault);
  EXPECT_EQ(ev3[0].magnitude, 0.0);
  EXPECT_THAT(ev3[0].detail, ::testing::HasSubstr("interrupted before this sample")) << ev3[0].detail;
  // samples the live source dropped because the monitor fell behind (its queue full): the gap is
  // this computer's, and its event says so instead of blaming the controller's timestamps (soak
  // audit, session 39: 14857 such events read "gap in the controller timestamp")
  auto dropped = without(healthy, {{6.0, 0.1}});
  for (auto& x : dropped.samples)
    if (std::abs(x.timestamp - 6.1) < 1e-4) x.gap_before = true, x.dropped_before = 50;  // as the RTDE client marks it
  const auto ev4 = monitor(dropped, 0.5);
  ASSERT_EQ(ev4.size(), 1u);
  EXPECT_EQ(ev4[0].fault, FaultClass::StreamFault);
  EXPECT_EQ(ev4[0].magnitude, 50.0);
  EXPECT_THAT(ev4[0].detail, ::testing::HasSubstr("50 of them dropped on this computer")) << ev4[0].detail;
}

// review of session 49: a live outage was said only when the stream came back (or monitoring
// stopped); a consumer of open events (--events-open, the dashboard) saw nothing while it lasted.
// stream_outage raises an open stream fault once per outage; the gap when samples return closes
// it under the same t_detected, with the gap's own detail, as one event; so do stream_silent and
// finish when they do not return
TEST_F(MonitorLoop, AnOutageIsAnOpenStreamFaultWhileItLastsAndOneEventWhenItEnds) {
  const auto healthy = run(scenario(610, 12, 0.5));
  ident::TwinModel t = *twin;
  t.set_payload(payload);
  const auto watch = [&](double silent_at, bool returns, bool at_end) {
    Monitor m(t, *config);
    std::vector<Event> seen;
    m.on_event = [&](const Event& e) { seen.push_back(e); };
    m.stream_outage(2.0);  // (before the first sample: nothing)
    bool raised = false;
    for (const auto& s : healthy.samples) {
      if (s.timestamp >= silent_at && s.timestamp < silent_at + 3.0) {  // 3 s without samples
        if (!raised) {
          m.stream_outage(1.6);
          m.stream_outage(2.4);  // still the same outage
          raised = true;
        }
        continue;
      }
      if (!returns && s.timestamp >= silent_at) break;
      m.push(s);
    }
    if (at_end) m.stream_silent(3.0);
    m.finish();
    return std::make_pair(seen, m.events());
  };
  // samples return: one open line, one closing line of the same name (t_detected), one event
  {
    const auto [seen, events] = watch(6.0, true, false);
    ASSERT_EQ(seen.size(), 2u) << (seen.empty() ? "" : seen[0].detail);
    EXPECT_TRUE(seen[0].open);
    EXPECT_EQ(seen[0].fault, FaultClass::StreamFault);
    EXPECT_NEAR(seen[0].t_start, 6.0, 0.003);
    EXPECT_NEAR(seen[0].t_detected, seen[0].t_start + 1.6, 1e-9);
    EXPECT_THAT(seen[0].detail, ::testing::HasSubstr("no data for 1.6 s"));
    EXPECT_FALSE(seen[1].open);
    EXPECT_EQ(seen[1].fault, FaultClass::StreamFault);
    EXPECT_EQ(seen[1].t_detected, seen[0].t_detected);
    EXPECT_NEAR(seen[1].t_end, 9.0, 0.003);
    EXPECT_NEAR(seen[1].magnitude, 1499.0, 1.0);  // 3 s at 500 Hz
    EXPECT_THAT(seen[1].detail, ::testing::HasSubstr("sample(s) missing"));
    ASSERT_EQ(events.size(), 1u);
    EXPECT_FALSE(events[0].open);
  }
  // not back before the end: stream_silent closes it
  {
    const auto [seen, events] = watch(6.0, false, true);
    ASSERT_EQ(seen.size(), 2u);
    EXPECT_TRUE(seen[0].open);
    EXPECT_FALSE(seen[1].open);
    EXPECT_EQ(seen[1].t_detected, seen[0].t_detected);
    EXPECT_THAT(seen[1].detail, ::testing::HasSubstr("no data for the last 3.0 s of monitoring"));
    ASSERT_EQ(events.size(), 1u);
  }
  // nor said by stream_silent: finish closes it as active at the stop
  {
    const auto [seen, events] = watch(6.0, false, false);
    ASSERT_EQ(seen.size(), 2u);
    EXPECT_FALSE(seen[1].open);
    EXPECT_TRUE(seen[1].active_at_stop);
    EXPECT_THAT(seen[1].detail, ::testing::HasSubstr("no data for 1.6 s when monitoring stopped"));
    ASSERT_EQ(events.size(), 1u);
  }
}

// A live monitor lets go of events it handed out long ago (soak audit, session 39: 0.6 kB an event,
// kept for the whole run): what it reports afterwards is exactly what it reports keeping them all,
// here with the two gap events let go a second after them, and a contact found after that.
TEST_F(MonitorLoop, LettingGoOfOldEventsChangesNothingItReportsLater) {
  const auto rec = without(run(scenario(611, 14, 0.5,
                                        "  - {type: collision, link: 2, onset: 10.4, magnitude: 10, duration: 0.05, "
                                        "point: [-0.12, 0.0, 0.1], direction: [0.3, 1.0, -0.2]}\n")),
                           {{4.0, 0.2}, {8.0, 2.0}});
  const auto closed_events = [&](bool forget) {
    ident::TwinModel t = *twin;
    t.set_payload(payload);
    Monitor m(t, *config);
    std::vector<std::string> seen;
    m.on_event = [&](const Event& e) {
      if (!e.open) seen.push_back(fmt::format("{:.4f} {} {} {:.6g} {}", e.t_start, to_string(e.fault), e.link, e.magnitude, e.detail));
    };
    for (const auto& s : rec.samples) {
      m.push(s);
      if (forget) m.forget_events_before(s.timestamp - 1.0);
    }
    m.finish();
    if (forget) {
      EXPECT_EQ(m.events_forgotten(), 3);  // the run goes on 3.5 s after the contact
      EXPECT_TRUE(m.events().empty());
    }
    return seen;
  };
  const auto all = closed_events(false);
  ASSERT_EQ(all.size(), 3u);
  EXPECT_NE(all[2].find("collision"), std::string::npos) << all[2];
  EXPECT_EQ(closed_events(true), all);
}

// Session 38 (audit of the live path): a monitor that joins a healthy arm in motion (a live robot
// mid-program; a recording cut from a longer one) raised false contacts and current offsets on a
// joint it met at a turning point: the twin's pre-sliding memory started at h = 0 where the joint
// held the friction of the direction it came from (10 of 200 start points of the figure-eight). It
// now starts as after a gap: a moving joint's memory is its direction's, a resting joint decides
// once it has moved. Every start where a joint turns while others move is tried, none raises
// anything, and a contact after such a start is still found
TEST_F(MonitorLoop, JoiningAnArmInMotionAtAJointsTurningPointRaisesNothing) {
  const auto healthy = run(scenario(620, 20, 0.5));
  const auto& x = healthy.samples;
  // the starts: a sample where some joint's velocity is at most 0.01 rad/s, having moved more than
  // 2 mrad (many pre-sliding distances) within the last 0.5 s (a turning point), while another joint moves
  std::vector<size_t> starts;
  for (size_t k = 250; k + 1500 < x.size(); ++k) {
    bool turning = false;
    for (int j = 0; j < 6 && !turning; ++j) {
      if (std::abs(x[k].qd[j]) > 0.01) continue;
      for (size_t b = k - 250; b < k && !turning; ++b) turning = std::abs(x[b].q[j] - x[k].q[j]) > 0.002;
    }
    if (turning && x[k].qd.cwiseAbs().maxCoeff() > 0.1 && (starts.empty() || k - starts.back() > 50)) starts.push_back(k);
  }
  ASSERT_GE(starts.size(), 4u) << "the figure-eight has turning points";
  for (size_t k : starts) {
    device::Recording cut = healthy;
    cut.samples.assign(x.begin() + static_cast<long>(k), x.begin() + static_cast<long>(k + 1500));
    const auto ev = monitor(cut, 0.5);
    EXPECT_TRUE(ev.empty()) << "joined at " << x[k].timestamp << " s:" << listing(ev);
  }
  // a contact 2 s after joining at the first such start is found, as a contact
  const double t0 = x[starts.front()].timestamp;
  const auto hit = run(scenario(620, 20, 0.5,
                                fmt::format("  - {{type: collision, link: 3, onset: {}, magnitude: 8, duration: 0.05, "
                                            "point: [0.1, 0.0, 0.03], direction: [0.2, 1.0, 0.1]}}\n",
                                            t0 + 2.0)));
  device::Recording cut = hit;
  cut.samples.assign(hit.samples.begin() + static_cast<long>(starts.front()), hit.samples.end());
  const auto ev = monitor(cut, 0.5);
  ASSERT_EQ(ev.size(), 1u) << listing(ev);
  EXPECT_EQ(ev[0].fault, FaultClass::Collision) << ev[0].detail;
  EXPECT_LT(ev[0].t_detected - (t0 + 2.0), 0.03);
}

// The same for an arm met at rest: at a triangle's corner every joint holds the friction of the edge
// it came along (the long triangle cut every 0.5 s: a false contact on J4 at 1 of 225 starts, on the
// evaluate twin). Every corner of a healthy triangle is a start here; none raises anything
TEST_F(MonitorLoop, JoiningAnArmAtRestAtATriangleCornerRaisesNothing) {
  const std::string program = "trajectory: {type: triangle, side: 0.15, speed: 0.2}\n";
  const MonitorConfig c = with_program_thresholds(program, 2760, 30);
  const auto healthy = run("robot: ur3e\nseed: 2761\nduration: 26\n" + program);
  const auto& x = healthy.samples;
  // the corners: the first sample of each rest after the first edge (every joint below 0.01 rad/s)
  std::vector<size_t> corners;
  bool moving = false;
  for (size_t k = 1; k + 1500 < x.size(); ++k) {
    const bool rests = x[k].qd.cwiseAbs().maxCoeff() <= 0.01;
    if (rests && moving && x[k].timestamp > 1.0) corners.push_back(k);
    moving = !rests;
  }
  ASSERT_GE(corners.size(), 6u) << "a triangle stops at its corners";
  for (size_t k : corners) {
    device::Recording cut = healthy;
    cut.samples.assign(x.begin() + static_cast<long>(k), x.begin() + static_cast<long>(k + 1500));
    Monitor m(*twin, c);
    for (const auto& smp : cut.samples) m.push(smp);
    m.finish();
    EXPECT_TRUE(m.events().empty()) << "joined at the corner at " << x[k].timestamp << " s:" << listing(m.events());
  }
}

// Session 21: a live stream whose stamps jitter (a logger's clock; the recording reader widens the
// gap factor for files, the live path had no estimate): with the configured 1.5 periods the
// simulator's 0.25 ms jitter read as dozens of "1 sample missing". The monitor now estimates the
// spread of the steps and says so once; a real loss of 5 samples is still a stream fault.
TEST_F(MonitorLoop, AJitteryLiveClockIsNotReadAsLostSamples) {
  const auto rec = run(scenario(158, 30, 0.5,
                                "  - {type: timestamp_jitter, onset: 0, magnitude: 0.00025}\n"
                                "  - {type: dropped_samples, onset: 20, magnitude: 5, end: 20.1}\n"));
  ident::TwinModel t = declared_twin();
  MonitorConfig c = *config;
  c.gap_factor = 1.5;  // what a live run starts from (no recording to measure the clock on)
  Monitor m(t, c);
  long over = 0;
  for (size_t k = 1; k < rec.samples.size(); ++k)
    over += rec.samples[k].timestamp - rec.samples[k - 1].timestamp > 1.5 * c.nominal_period ? 1 : 0;
  EXPECT_GT(over, 10) << "the jitter must put steps beyond the configured factor, or the test shows nothing";
  for (const auto& s : rec.samples) m.push(s);
  m.finish();
  const std::string all = listing(m.events());
  ASSERT_EQ(m.events().size(), 1u) << all;
  EXPECT_EQ(m.events()[0].fault, FaultClass::StreamFault) << all;
  EXPECT_NEAR(m.events()[0].t_start, 20.0, 0.02) << all;
  EXPECT_GE(m.events()[0].magnitude, 4.0) << all;
  ASSERT_FALSE(m.notes().empty());
  EXPECT_THAT(m.notes().front(), ::testing::HasSubstr("the stream's timestamps jitter (spread 0.3"));
}

// a controller that resends a sample: processed twice it counted twice in every debounce
TEST_F(MonitorLoop, ASampleSentTwiceIsProcessedOnce) {
  const auto rec = run(scenario(612, 14, 0.5,
                                "  - {type: collision, link: 3, onset: 9.3, magnitude: 5, duration: 0.05, "
                                "point: [-0.1, 0.0, 0.03], direction: [0.3, 1.0, -0.2]}\n"));
  ident::TwinModel t = declared_twin();
  Monitor once(t, *config), twice(t, *config);
  for (const auto& s : rec.samples) {
    once.push(s);
    twice.push(s);
    twice.push(s);
  }
  once.finish();
  twice.finish();
  EXPECT_EQ(twice.repeated(), static_cast<long>(rec.samples.size()));
  EXPECT_EQ(twice.samples(), once.samples());
  ASSERT_EQ(twice.events().size(), once.events().size());
  ASSERT_FALSE(once.events().empty());
  for (size_t k = 0; k < once.events().size(); ++k) {
    EXPECT_EQ(twice.events()[k].t_detected, once.events()[k].t_detected);
    EXPECT_EQ(twice.events()[k].detail, once.events()[k].detail);
  }
}

// a value that is not a number (a live stream is not checked like a recording): the recursive
// filters and the observer kept it forever and the joint, or every joint, went blind
TEST_F(MonitorLoop, ANonFiniteValueIsASensorFaultAndDoesNotBlindTheMonitor) {
  auto rec = run(scenario(603, 16, 0.5, "  - {type: resistance, joint: 5, onset: 6, ramp: 0.2, magnitude: 0.8}\n"));
  long spoiled = 0;
  for (auto& s : rec.samples) {
    if (std::abs(s.timestamp - 3.0) < 1e-4) s.current[4] = std::numeric_limits<double>::quiet_NaN(), ++spoiled;
    if (s.timestamp > 4.0 && s.timestamp < 4.01) s.qd[0] = std::numeric_limits<double>::infinity(), ++spoiled;  // a run of them
    // a corrupted word: finite, no reading (its square overflowed the diagnosis's fit: an error mid-run)
    if (std::abs(s.timestamp - 5.0) < 1e-4) s.current[2] = 1.7e308, ++spoiled;
  }
  ASSERT_GE(spoiled, 4);
  ident::TwinModel t = declared_twin();
  Monitor m(t, *config);
  for (const auto& s : rec.samples) m.push(s);
  m.finish();
  EXPECT_EQ(m.invalid(), spoiled);
  const auto& ev = m.events();
  std::string all;
  for (const auto& e : ev) all += fmt::format("{:.3f} s {}: {}\n", e.t_start, to_string(e.fault), e.detail);
  ASSERT_EQ(ev.size(), 4u) << all;
  EXPECT_EQ(ev[0].fault, FaultClass::SensorFault);
  EXPECT_EQ(ev[0].joint, 4);
  EXPECT_THAT(ev[0].detail, ::testing::HasSubstr("J5 current is nan"));
  EXPECT_EQ(ev[1].fault, FaultClass::SensorFault);
  EXPECT_EQ(ev[1].joint, 0);
  EXPECT_THAT(ev[1].detail, ::testing::HasSubstr("J1 velocity is inf"));
  EXPECT_EQ(ev[2].fault, FaultClass::SensorFault);
  EXPECT_EQ(ev[2].joint, 2);
  EXPECT_THAT(ev[2].detail, ::testing::HasSubstr("J3 current is 1.7e+308, beyond 10000"));
  EXPECT_EQ(ev[3].fault, FaultClass::Resistance) << ev[3].detail;
  EXPECT_EQ(ev[3].joint, 4);
}

// UR3e §4.3: 0.5 kg payload loss detected within 100 ms, classified, mass within +-20 %
TEST_F(MonitorLoop, PayloadLossIsDetectedFastAndSized) {
  const auto ev = monitor(run(scenario(604, 12, 0.5, "  - {type: payload_loss, onset: 8.5}\n")), 0.5);
  ASSERT_FALSE(ev.empty());
  EXPECT_LT(ev.front().t_detected - 8.5, 0.1);
  EXPECT_EQ(ev.front().fault, FaultClass::PayloadChange) << ev.front().detail;
  EXPECT_NEAR(ev.front().magnitude, -0.5, 0.1) << ev.front().detail;
}

// Session 21: after a payload change the twin kept the declared payload, so the residual of the
// part it no longer held kept the alert open for the rest of the run, and a contact after a
// dropped part was part of the payload event (reported nowhere). On the alert's longer look the
// twin now takes the diagnosed payload: the alert clears, and the next pick, the drop and a
// contact are events of their own, each sized.
TEST_F(MonitorLoop, AFollowedPayloadChangeLeavesTheMonitorWatching) {
  // (a stream without the controller's declared payload: its picks are the monitor's to find)
  const auto rec = undeclared(run(scenario(154, 24, 0.0,
                                "  - {type: payload_pick, onset: 6.1, io_bit: 0, mass: 0.5, com: [0, 0, 0.04]}\n"
                                "  - {type: payload_loss, onset: 13.7, io_bit: 0}\n"
                                "  - {type: collision, link: 3, onset: 19.3, magnitude: 10, duration: 0.05, "
                                "point: [-0.1, 0.0, 0.03], direction: [0.3, 1.0, -0.2]}\n")));
  const auto watch = [&](bool follow, double* payload_at_end, std::vector<std::string>* notes) {
    MonitorConfig c = *config;
    c.follow_payload = follow;
    Monitor m(*twin, c);  // no payload declared: the program picks its part
    for (const auto& s : rec.samples) m.push(s);
    m.finish();
    if (payload_at_end) *payload_at_end = m.twin().payload().mass;
    if (notes) *notes = m.notes();
    return m.events();
  };
  double at_end = -1.0;
  std::vector<std::string> notes;
  const auto ev = watch(true, &at_end, &notes);
  ASSERT_EQ(ev.size(), 3u) << ev.back().detail;
  // the pick: sized within 20 %, and the alert clears once the twin carries the part
  EXPECT_EQ(ev[0].fault, FaultClass::PayloadChange) << ev[0].detail;
  EXPECT_LT(ev[0].t_detected - 6.1, 0.1);
  EXPECT_NEAR(ev[0].magnitude, 0.5, 0.1) << ev[0].detail;
  EXPECT_LT(ev[0].t_end, 6.1 + 3.0) << "the pick's alert closed once followed";
  EXPECT_THAT(ev[0].detail, ::testing::HasSubstr("monitoring goes on with it"));
  // the drop: found on the twin that carries the part, and the whole part taken off again
  EXPECT_EQ(ev[1].fault, FaultClass::PayloadChange) << ev[1].detail;
  EXPECT_LT(ev[1].t_detected - 13.7, 0.1);
  EXPECT_LT(ev[1].magnitude, -0.3) << ev[1].detail;
  EXPECT_THAT(ev[1].detail, ::testing::HasSubstr("predicts with no payload"));
  EXPECT_EQ(at_end, 0.0);
  // the contact after it: its own event, on its link, in time
  EXPECT_EQ(ev[2].fault, FaultClass::Collision) << ev[2].detail;
  EXPECT_EQ(ev[2].link, 2);  // link 3
  EXPECT_LT(ev[2].t_detected - 19.3, 0.02);
  EXPECT_EQ(notes.size(), 2u);
  // keeping the declared payload (none): the pick's alert stays open while the part is held, and
  // the twin ends as it started
  const auto kept = watch(false, &at_end, nullptr);
  ASSERT_FALSE(kept.empty());
  EXPECT_EQ(kept[0].fault, FaultClass::PayloadChange) << kept[0].detail;
  EXPECT_GT(kept[0].t_end, 13.0) << kept[0].detail;
  EXPECT_EQ(at_end, 0.0);
}

// Where an undeclared part sits (session 52). A 0.8 kg part held 15 cm out along the flange axis is
// picked with no payload declared. Followed at the default point (4 cm out), the twin's wrist torques
// miss the part's lever, and what is left peaks higher against the wrist joints' thresholds; told
// where parts sit (MonitorConfig::part_com), the twin follows the part there and the wrist's residual
// after the follow stays as far below its thresholds as the arm's healthy motion leaves it.
TEST_F(MonitorLoop, APartFollowedWhereItSitsLeavesTheWristLessModelError) {
  const double onset = 6.3, mass = 0.8;
  const auto rec = undeclared(run(scenario(5301, 16, 0.0, "  - {type: payload_pick, onset: 6.3, io_bit: 0, mass: 0.8, com: [0, 0, 0.15]}\n")));
  struct Watched {
    std::vector<Event> events;
    model::RigidBodyInertia payload;
    double wrist_peak = 0.0;  // the largest |residual| / threshold of J4-J6 from 3.5 s after the pick
  };
  const auto watch = [&](const Eigen::Vector3d& part) {
    MonitorConfig c = *config;
    c.part_com = part;
    Monitor m(*twin, c);
    Watched w;
    for (const auto& s : rec.samples) {
      m.push(s);
      if (s.timestamp < onset + 3.5) continue;
      for (int j = 3; j < 6; ++j)
        if (m.level()[j] > 0.0) w.wrist_peak = std::max(w.wrist_peak, std::abs(m.filtered_residual()[j]) / m.level()[j]);
    }
    m.finish();
    w.events = m.events();
    w.payload = m.twin().payload();
    return w;
  };
  const Watched assumed = watch(MonitorConfig::default_part_com());
  const Watched told = watch(Eigen::Vector3d(0.0, 0.0, 0.15));
  // both find the pick and follow it, each at the point it was given
  for (const Watched* w : {&assumed, &told}) {
    ASSERT_FALSE(w->events.empty());
    EXPECT_EQ(w->events[0].fault, FaultClass::PayloadChange) << w->events[0].detail;
    EXPECT_LT(w->events[0].t_detected - onset, 0.1);
    EXPECT_NEAR(w->events[0].magnitude, mass, 0.2 * mass) << w->events[0].detail;
  }
  EXPECT_EQ(assumed.payload.com, Eigen::Vector3d(0.0, 0.0, 0.04));
  EXPECT_EQ(told.payload.com, Eigen::Vector3d(0.0, 0.0, 0.15));
  EXPECT_NEAR(told.payload.mass, mass, 0.1 * mass);
  // told where it sits: the pick is the run's only event, and the wrist's residual peaks lower
  EXPECT_EQ(told.events.size(), 1u) << told.events.back().detail;
  EXPECT_LT(told.wrist_peak, 1.0);
  EXPECT_LT(told.wrist_peak, 0.8 * assumed.wrist_peak) << "told " << told.wrist_peak << ", assumed " << assumed.wrist_peak;
  std::printf("part at 0.15 m: wrist peak ratio %.3f told, %.3f assumed at 0.04 m; events %zu / %zu; mass %.3f / %.3f kg\n", told.wrist_peak,
              assumed.wrist_peak, told.events.size(), assumed.events.size(), told.payload.mass, assumed.payload.mass);
}

// The part's point is stored in the twin's monitor block when it is not the default, read back, and
// a point beyond a metre from the flange (millimetres given) is refused naming the field.
TEST(MonitorConfig, ThePartsPointIsStoredWhenSetAndCheckedOnReading) {
  MonitorConfig c;
  c.static_level = VectorJ::Ones(6);
  c.use_dynamic = false;
  EXPECT_EQ(c.to_json().find("part_com_m"), std::string::npos) << "the default is not written";
  EXPECT_EQ(MonitorConfig::from_json(c.to_json(), "twin.json").part_com, Eigen::Vector3d(0.0, 0.0, 0.04));
  c.part_com = Eigen::Vector3d(0.02, -0.01, 0.15);
  EXPECT_EQ(MonitorConfig::from_json(c.to_json(), "twin.json").part_com, c.part_com);
  c.part_com = Eigen::Vector3d(0.0, 0.0, 150.0);
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { c.validate(6); }), ::testing::HasSubstr("part_com_m is (0, 0, 150) m"));
  std::string text = c.to_json();
  const std::string far = twinwatch::test::error_text<ParseError>([&] { MonitorConfig::from_json(text, "twin.json"); });
  EXPECT_THAT(far, ::testing::HasSubstr("monitor.part_com_m"));
  EXPECT_THAT(far, ::testing::HasSubstr("expected a point within 1 m of the flange, got 150 m away (in mm? give metres)"));
  c.part_com = Eigen::Vector3d(0.0, 0.0, 0.1);
  nlohmann::json j = nlohmann::json::parse(c.to_json());
  j["part_com_m"] = 0.1;  // a number, not a point
  text = j.dump();
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { MonitorConfig::from_json(text, "twin.json"); }),
              ::testing::HasSubstr("monitor.part_com_m"));
}

// Review of session 21: what following a payload change must not do. A sustained push on the
// flange fits a payload too (a 12 N·m push for 6 s: "+2 kg", 76 % explained): with no gripper output
// changing and the payload explaining less than 85 %, it is not followed, so its alert ends with
// the push and a contact after it is found. A pick 3 s after a followed drop (within the old merge
// gap of its clearing) is a change of its own and is followed in turn. Both sized on the drive
// torque, back-driven phases included (the current residual times the gain read them 10-15 % small).
TEST_F(MonitorLoop, APushIsNotFollowedAsAPayloadAndAPickAfterADropIsFollowedInTurn) {
  const auto push = monitor(run(scenario(155, 24, 0.5,
                                         "  - {type: collision, link: 6, onset: 8.5, magnitude: 12, duration: 6, "
                                         "point: [0, 0, 0.04], direction: [0, 0, -1]}\n"
                                         "  - {type: collision, link: 3, onset: 19.3, magnitude: 10, duration: 0.05, "
                                         "point: [-0.1, 0.0, 0.03], direction: [0.3, 1.0, -0.2]}\n")),
                            0.5);
  const std::string push_listing = listing(push);
  ASSERT_EQ(push.size(), 2u) << push_listing;
  EXPECT_THAT(push[0].detail, ::testing::Not(::testing::HasSubstr("the twin predicts with"))) << push_listing;
  EXPECT_LT(push[0].t_end, 15.0) << "the push's alert ends with the push" << push_listing;
  EXPECT_EQ(push[1].fault, FaultClass::Collision) << push_listing;
  EXPECT_LT(push[1].t_detected - 19.3, 0.02);

  const auto swap = monitor(undeclared(run(scenario(156, 24, 0.5,
                                         "  - {type: payload_loss, onset: 8.5, io_bit: 0}\n"
                                         "  - {type: payload_pick, onset: 11.5, io_bit: 1, mass: 1.0, com: [0, 0, 0.04]}\n"
                                         "  - {type: collision, link: 3, onset: 19.3, magnitude: 10, duration: 0.05, "
                                         "point: [-0.1, 0.0, 0.03], direction: [0.3, 1.0, -0.2]}\n"))),
                            0.5);
  const std::string swap_listing = listing(swap);
  ASSERT_EQ(swap.size(), 3u) << swap_listing;
  EXPECT_EQ(swap[0].fault, FaultClass::PayloadChange) << swap_listing;
  EXPECT_NEAR(swap[0].magnitude, -0.5, 0.05) << swap_listing;
  EXPECT_EQ(swap[1].fault, FaultClass::PayloadChange) << swap_listing;
  EXPECT_NEAR(swap[1].magnitude, 1.0, 0.1) << swap_listing;
  EXPECT_THAT(swap[1].detail, ::testing::ContainsRegex("the twin predicts with a (0\\.9|1\\.0)[0-9] kg payload"));
  EXPECT_EQ(swap[2].fault, FaultClass::Collision) << swap_listing;
}

// Session 27: a contact within the 2.5 s between a payload change's first look and its longer look
// (where the twin follows the change) was part of the payload event and reported nowhere: 0 of 30
// such contacts (5 N·m, links 2, 3, 5, 0.3-2 s after a 0.5 kg drop or pick) were found. Now the
// current residual less what the first look's payload explains is watched on the moving joints;
// what rises there ends the payload change before it and raises an alert of its own. The payload
// is still sized within 20 %, the contact found within 20 ms on its link, and a change with nothing
// on top is one event as before.
TEST_F(MonitorLoop, AContactSoonAfterAPayloadChangeIsAnEventOfItsOwn) {
  const std::string contact3 = "  - {type: collision, link: 3, onset: 9.5, magnitude: 5, duration: 0.05, "
                               "point: [-0.1, 0.0, 0.03], direction: [0.3, 1.0, -0.2]}\n";
  const auto drop = monitor(undeclared(run(scenario(911, 14, 0.5, "  - {type: payload_loss, onset: 8.5, io_bit: 0}\n" + contact3))), 0.5);
  const std::string drop_listing = listing(drop);
  ASSERT_EQ(drop.size(), 2u) << drop_listing;
  EXPECT_EQ(drop[0].fault, FaultClass::PayloadChange) << drop_listing;
  EXPECT_NEAR(drop[0].magnitude, -0.5, 0.1) << drop_listing;
  EXPECT_THAT(drop[0].detail, ::testing::HasSubstr("predicts with no payload")) << drop_listing;
  EXPECT_GT(drop[0].t_end, 9.49) << "the drop's event ends where the contact begins" << drop_listing;
  EXPECT_LT(drop[0].t_end, 9.53) << "the drop's event ends where the contact begins" << drop_listing;
  EXPECT_EQ(drop[1].fault, FaultClass::Collision) << drop_listing;
  EXPECT_GT(drop[1].t_detected, 9.5) << drop_listing;
  EXPECT_LT(drop[1].t_detected - 9.5, 0.02) << drop_listing;
  // as the same contact is found on a run whose payload did not change (on this twin, link 4 at 65 %
  // with link 5 also possible, for the link-3 contact: a pose where the joint torques of the two
  // links are alike; the pick below is named right)
  const auto same = monitor(undeclared(run(scenario(911, 14, 0.5, contact3))), 0.5);
  ASSERT_EQ(same.size(), 1u) << listing(same);
  EXPECT_EQ(same[0].link, drop[1].link) << listing(same) << drop_listing;
  EXPECT_NEAR(same[0].t_detected, drop[1].t_detected, 0.0045) << listing(same) << drop_listing;
  EXPECT_NEAR(same[0].magnitude, drop[1].magnitude, 0.1 * same[0].magnitude) << listing(same) << drop_listing;

  // a part picked with none declared, a wrist contact 0.7 s later
  const auto pick = monitor(undeclared(run(scenario(912, 14, 0.0,
                                                    "  - {type: payload_pick, onset: 8.5, io_bit: 0, mass: 0.5, com: [0, 0, 0.04]}\n"
                                                    "  - {type: collision, link: 5, onset: 9.2, magnitude: 5, duration: 0.05, "
                                                    "point: [-0.05, 0.0, 0.03], direction: [0.3, 1.0, -0.2]}\n"))),
                            0.0);
  const std::string pick_listing = listing(pick);
  ASSERT_EQ(pick.size(), 2u) << pick_listing;
  EXPECT_EQ(pick[0].fault, FaultClass::PayloadChange) << pick_listing;
  EXPECT_NEAR(pick[0].magnitude, 0.5, 0.1) << pick_listing;
  EXPECT_EQ(pick[1].fault, FaultClass::Collision) << pick_listing;
  EXPECT_EQ(pick[1].link, 4) << pick_listing;  // link 5
  EXPECT_GT(pick[1].t_detected, 9.2) << pick_listing;
  EXPECT_LT(pick[1].t_detected - 9.2, 0.02) << pick_listing;
  EXPECT_GT(pick[0].t_end, 9.19) << pick_listing;

  // the drop alone: one event, followed on its longer look, not ended early
  const auto alone = monitor(undeclared(run(scenario(911, 14, 0.5, "  - {type: payload_loss, onset: 8.5, io_bit: 0}\n"))), 0.5);
  const std::string alone_listing = listing(alone);
  ASSERT_EQ(alone.size(), 1u) << alone_listing;
  EXPECT_THAT(alone[0].detail, ::testing::Not(::testing::HasSubstr("rose above"))) << alone_listing;
  EXPECT_THAT(alone[0].detail, ::testing::HasSubstr("from 11.0")) << alone_listing;
}

// Session 22: a part swapped (a drop, then a pick 1 s later on another gripper output, as a dual
// gripper tending a machine does) put both changes in the longer look's window; no single signature
// fits that, and it read as one contact on link 6 that stayed open to the end, hiding the contact
// after it. The second output change now ends the first change there (followed on the samples
// before it), and the pick is an alert of its own.
TEST_F(MonitorLoop, APartSwappedWithinTheLongerLookIsTwoPayloadChanges) {
  const auto rec = undeclared(run(scenario(158, 24, 0.5,
                                "  - {type: payload_loss, onset: 8.5, io_bit: 0}\n"
                                "  - {type: payload_pick, onset: 9.5, io_bit: 1, mass: 1.0, com: [0, 0, 0.04]}\n"
                                "  - {type: collision, link: 3, onset: 17.3, magnitude: 10, duration: 0.05, "
                                "point: [-0.1, 0.0, 0.03], direction: [0.3, 1.0, -0.2]}\n")));
  const auto watch = [&](bool follow, double* payload_at_end) {
    MonitorConfig c = *config;
    c.follow_payload = follow;
    Monitor m(declared_twin(), c);
    for (const auto& s : rec.samples) m.push(s);
    m.finish();
    *payload_at_end = m.twin().payload().mass;
    return m.events();
  };
  double at_end = -1.0;
  const auto ev = watch(true, &at_end);
  const std::string all = listing(ev);
  ASSERT_EQ(ev.size(), 3u) << all;
  EXPECT_EQ(ev[0].fault, FaultClass::PayloadChange) << all;
  EXPECT_NEAR(ev[0].magnitude, -0.5, 0.1) << all;
  EXPECT_NEAR(ev[0].t_end, 9.5, 0.02) << "the drop ends where the pick's output changed" << all;
  EXPECT_EQ(ev[1].fault, FaultClass::PayloadChange) << all;
  EXPECT_NEAR(ev[1].t_start, 9.5, 0.05) << all;
  EXPECT_NEAR(ev[1].magnitude, 1.0, 0.1) << all;
  EXPECT_FALSE(ev[1].open) << all;
  EXPECT_NEAR(at_end, 1.0, 0.1);
  EXPECT_EQ(ev[2].fault, FaultClass::Collision) << all;
  EXPECT_EQ(ev[2].link, 2) << all;  // link 3
  EXPECT_LT(ev[2].t_detected - 17.3, 0.02) << all;
  // keeping the declared payload, the swap is one payload event (the net change) that stays open
  const auto kept = watch(false, &at_end);
  ASSERT_FALSE(kept.empty());
  EXPECT_EQ(at_end, 0.5);
  EXPECT_GT(kept[0].t_end, 17.0) << listing(kept);
  // an output pulse that is no part (a vacuum gripper's blow-off 0.6 s after the drop) ends the drop
  // there and raises nothing after it: the observer and the residual filter restart on the new
  // payload (their old states raised a 2 ms "contact on link 1" at the split)
  auto blow = run(scenario(159, 14, 0.5, "  - {type: payload_loss, onset: 8.5, io_bit: 0}\n"));
  for (auto& s : blow.samples)
    if (s.timestamp >= 9.1 && s.timestamp < 9.3) s.digital_outputs |= 8u;
  Monitor m(declared_twin(), *config);
  for (const auto& s : blow.samples) m.push(s);
  m.finish();
  const std::string blown = listing(m.events());
  ASSERT_EQ(m.events().size(), 1u) << blown;
  EXPECT_EQ(m.events()[0].fault, FaultClass::PayloadChange) << blown;
  EXPECT_NEAR(m.events()[0].magnitude, -0.5, 0.1) << blown;
  EXPECT_EQ(m.twin().payload().mass, 0.0);
}

// A followed payload change that was not one is undone: a gripper output toggles (no part) and a
// push on the flange held for 2.8 s reads as a payload gain, which is followed; when the push ends
// the alert does not fall back, and the twin returns to the payload it carried
TEST_F(MonitorLoop, AFollowedPayloadThatWasNotOneIsUndone) {
  const auto rec = undeclared(run(scenario(157, 20, 0.5,
                                "  - {type: payload_pick, onset: 8.3, io_bit: 1, mass: 0.5, com: [0, 0, 0.04]}\n"
                                "  - {type: collision, link: 6, onset: 8.5, magnitude: 8, duration: 2.8, "
                                "point: [0, 0, 0.04], direction: [0, 0, -1]}\n")));
  ident::TwinModel t = declared_twin();
  Monitor m(t, *config);
  for (const auto& s : rec.samples) m.push(s);
  m.finish();
  const std::string all = listing(m.events());
  ASSERT_FALSE(m.events().empty());
  const Event& e = m.events().front();
  EXPECT_EQ(e.fault, FaultClass::PayloadChange) << all;
  EXPECT_THAT(e.detail, ::testing::HasSubstr("the twin predicts with a")) << all;
  EXPECT_THAT(e.detail, ::testing::HasSubstr("the residual had not fallen back, so the twin predicts with its 0.50 kg payload again")) << all;
  EXPECT_EQ(m.twin().payload().mass, 0.5);
  // (session 27) the push grows past what the first look fitted, which splits the change off
  // tentatively (watch_on_top); the alert after it is no contact, so the change goes on as one
  // event. Without the merge back: three events, the twin left with 1.45 kg
  EXPECT_EQ(m.events().size(), 1u) << all;
  EXPECT_THAT(m.notes(), ::testing::Contains(::testing::HasSubstr("was no contact: the change goes on"))) << all;
}

// Session 23: the payload the controller declares (RTDE payload / payload_cog, kFieldPayload). A
// pick the program declares (set_payload) is taken by the twin as it happens: no alert (the same
// run without the declaration in the stream raises one, AFollowedPayloadChangeLeavesTheMonitorWatching).
// A part lost without a declaration is still a payload change. A pick declared with nothing in the
// gripper (a missed grip: the controller believes it carries 1 kg) is one too, sized as the mass
// the arm lacks, and followed, so that a contact after it is found.
TEST_F(MonitorLoop, ADeclaredPickRaisesNothingAndAMissedPickIsAPayloadChange) {
  const auto rec = run(scenario(154, 24, 0.0,
                                "  - {type: payload_pick, onset: 6.1, io_bit: 0, mass: 0.5, com: [0, 0, 0.04]}\n"
                                "  - {type: payload_loss, onset: 13.7, io_bit: 0}\n"
                                "  - {type: collision, link: 3, onset: 19.3, magnitude: 10, duration: 0.05, "
                                "point: [-0.1, 0.0, 0.03], direction: [0.3, 1.0, -0.2]}\n"));
  ASSERT_TRUE(rec.samples.front().has(kFieldPayload));
  EXPECT_EQ(rec.samples.back().payload, 0.5) << "the controller still declares the part it lost";
  Monitor m(*twin, *config);  // no payload given: the stream says what the program declares
  for (const auto& s : rec.samples) m.push(s);
  m.finish();
  const std::string all = listing(m.events());
  ASSERT_EQ(m.events().size(), 2u) << all;
  const Event& loss = m.events()[0];
  EXPECT_EQ(loss.fault, FaultClass::PayloadChange) << all;
  EXPECT_LT(loss.t_detected - 13.7, 0.1) << all;
  EXPECT_NEAR(loss.magnitude, -0.5, 0.1) << all;
  EXPECT_EQ(m.events()[1].fault, FaultClass::Collision) << all;
  EXPECT_EQ(m.events()[1].link, 2) << all;  // link 3
  EXPECT_LT(m.events()[1].t_detected - 19.3, 0.02) << all;
  EXPECT_THAT(m.notes(), ::testing::Contains(::testing::HasSubstr("the program declared 0.50 kg at (0.000, 0.000, 0.040) m")));
  EXPECT_EQ(m.twin().payload().mass, 0.0) << "the loss was followed";
  // with follow_payload off the twin keeps what it was given and takes no declaration either
  MonitorConfig keep = *config;
  keep.follow_payload = false;
  Monitor k(*twin, keep);
  for (const auto& s : rec.samples) k.push(s);
  k.finish();
  ASSERT_FALSE(k.events().empty());
  EXPECT_EQ(k.events()[0].fault, FaultClass::PayloadChange) << listing(k.events());
  EXPECT_NEAR(k.events()[0].t_start, 6.1, 0.1) << listing(k.events());

  // a missed grip: the program declares 1 kg at 9.5 s and closes the gripper on nothing
  auto miss = run(scenario(160, 22, 0.0,
                           "  - {type: collision, link: 3, onset: 17.3, magnitude: 10, duration: 0.05, "
                           "point: [-0.1, 0.0, 0.03], direction: [0.3, 1.0, -0.2]}\n"));
  for (auto& s : miss.samples)
    if (s.timestamp >= 9.5) {
      s.payload = 1.0;
      s.payload_cog[2] = 0.04;
      s.digital_outputs |= 2u;
    }
  Monitor mm(*twin, *config);
  for (const auto& s : miss.samples) mm.push(s);
  mm.finish();
  const std::string missed = listing(mm.events());
  ASSERT_EQ(mm.events().size(), 2u) << missed;
  const Event& lack = mm.events()[0];
  EXPECT_EQ(lack.fault, FaultClass::PayloadChange) << missed;
  EXPECT_GE(lack.t_start, 9.5 - 0.002) << missed;
  EXPECT_LT(lack.t_detected - 9.5, 0.1) << missed;
  EXPECT_NEAR(lack.magnitude, -1.0, 0.2) << missed;
  // the contact after it: found in time (at this pose links 3 and 4 read almost alike: 48 / 52 %)
  const Event& contact = mm.events()[1];
  EXPECT_EQ(contact.fault, FaultClass::Collision) << missed;
  EXPECT_LT(contact.t_detected - 17.3, 0.02) << missed;
  EXPECT_TRUE(contact.link == 2 || std::find(contact.other_links.begin(), contact.other_links.end(), 2) != contact.other_links.end()) << missed;
  EXPECT_EQ(mm.twin().payload().mass, 0.0) << "the twin follows what the arm carries, not the declaration";
}

// A part dropped without a declaration, then the next one picked and declared: the controller's
// feed-forward changes with the declaration, and the tracking error its position loop carried for
// the lost part unwinds over the loop's settling time, which the twin (at the target acceleration)
// does not predict. Decisions wait it out (kDeclarationSettle): without the wait a 6-10 ms
// "contact" followed the declaration at most pick times (session 23 review: 7 of 9 onsets)
TEST_F(MonitorLoop, ADeclarationAfterAnUndeclaredDropRaisesNoContact) {
  for (const double onset : {9.05, 9.2, 9.7, 10.3}) {
    const auto rec = run(scenario(2303, 13, 0.5,
                                  "  - {type: payload_loss, onset: 8.5, io_bit: 0}\n"
                                  "  - {type: payload_pick, onset: " + fmt::format("{}", onset) +
                                      ", io_bit: 1, mass: 1.0, com: [0, 0, 0.04]}\n"));
    Monitor m(*twin, *config);
    for (const auto& s : rec.samples) m.push(s);
    m.finish();
    const std::string all = listing(m.events());
    ASSERT_EQ(m.events().size(), 1u) << "pick at " << onset << " s\n" << all;
    EXPECT_EQ(m.events()[0].fault, FaultClass::PayloadChange) << all;
    EXPECT_NEAR(m.events()[0].magnitude, -0.5, 0.1) << all;
    EXPECT_EQ(m.twin().payload().mass, 1.0) << "the declaration";
  }
}

// A declared centre of mass no part has (40 "m": a value in mm) is not taken: the twin keeps its
// payload, a note says why, and the pick is found as a payload change (taken, it made the monitor
// blind to the part lost and a contact after it, session 23 review)
TEST_F(MonitorLoop, ADeclaredCentreOfMassInMillimetresIsNotTaken) {
  auto rec = run(scenario(154, 12, 0.0, "  - {type: payload_pick, onset: 6.1, io_bit: 0, mass: 0.5, com: [0, 0, 0.04]}\n"));
  for (auto& s : rec.samples)
    if (s.payload > 0.0) s.payload_cog[2] = 40.0;
  Monitor m(*twin, *config);
  for (const auto& s : rec.samples) m.push(s);
  m.finish();
  const std::string all = listing(m.events());
  EXPECT_THAT(m.notes(), ::testing::Contains(::testing::HasSubstr("its centre of mass is 40 m from the flange, more than 1 m")));
  EXPECT_FALSE(m.declaration_taken());
  ASSERT_EQ(m.events().size(), 1u) << all;
  EXPECT_EQ(m.events()[0].fault, FaultClass::PayloadChange) << all;
  EXPECT_LT(m.events()[0].t_detected - 6.1, 0.1) << all;
  EXPECT_NEAR(m.events()[0].magnitude, 0.5, 0.1) << all;
}

// The thresholds remember the heaviest payload they were learned on (payload_max_kg in the twin
// file, per program too). A payload more than 1.5 kg heavier is beyond them (0.5 kg for thresholds
// that do not widen with the load): the twin's model error grows with the payload (thresholds
// learned at 0-0.5 kg, widened at loaded reversals, raised 1 false alarm in 0.67 h of held-out runs
// at 1.5-3 kg on the virtual UR3e), which a note says once, naming the remedy, and every alert
// raised then says too. A twin file from before session 24 keeps working without the note.
TEST_F(MonitorLoop, APayloadHeavierThanTheThresholdsWereLearnedWithIsSaid) {
  EXPECT_EQ(config->payload_max, 0.5);
  const MonitorConfig back = MonitorConfig::from_json(config->to_json(), "twin.json", 6);
  EXPECT_EQ(back.payload_max, 0.5);
  auto block = nlohmann::json::parse(config->to_json());
  block["payload_max_kg"] = -1.0;
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { MonitorConfig::from_json(block.dump(), "twin.json", 6); }),
              ::testing::HasSubstr("twin.json: field 'monitor.payload_max_kg': expected a number >= 0, got -1"));
  block.erase("payload_max_kg");
  EXPECT_TRUE(std::isnan(MonitorConfig::from_json(block.dump(), "twin.json", 6).payload_max));
  // a program's set carries its own
  MonitorConfig programs = *config;
  programs.programs["light"].static_level = config->static_level;
  programs.programs["light"].dynamic = config->dynamic;
  programs.programs["light"].payload_max = 0.0;
  MonitorConfig light = MonitorConfig::from_json(programs.to_json(), "twin.json", 6);
  light.select_program("light");
  EXPECT_EQ(light.payload_max, 0.0);

  // a healthy run carrying `mass`, the twin given it (no declaration in the stream)
  const auto watch = [&](double mass, const MonitorConfig& c) {
    const auto rec = undeclared(run(scenario(2401, 6, mass)));
    ident::TwinModel t = *twin;
    model::RigidBodyInertia p = payload;
    p.mass = mass;
    t.set_payload(p);
    auto m = std::make_unique<Monitor>(t, c);
    for (const auto& x : rec.samples) m->push(x);
    m->finish();
    return m;
  };
  const auto heavy = watch(2.5, *config);
  EXPECT_TRUE(heavy->payload_beyond_thresholds());
  EXPECT_THAT(heavy->notes(), ::testing::Contains(::testing::HasSubstr(
                                  "the twin predicts with 2.50 kg, more than 1.5 kg above the 0.50 kg of the heaviest healthy run")));
  for (const Event& e : heavy->events())
    if (e.fault != FaultClass::StreamFault) {
      EXPECT_THAT(e.detail, ::testing::HasSubstr("heavier than the thresholds were learned with"));
    }
  EXPECT_FALSE(watch(2.0, *config)->payload_beyond_thresholds());
  // thresholds that do not widen with the load (a twin file from before session 25) keep the 0.5 kg margin
  MonitorConfig unwidened = *config;
  unwidened.reversal_load_max.resize(0);
  const auto narrow = watch(1.5, unwidened);
  EXPECT_TRUE(narrow->payload_beyond_thresholds());
  EXPECT_THAT(narrow->notes(), ::testing::Contains(::testing::HasSubstr("more than 0.5 kg above the 0.50 kg")));
  EXPECT_FALSE(watch(1.5, *config)->payload_beyond_thresholds());
  MonitorConfig unknown = *config;
  unknown.payload_max = std::numeric_limits<double>::quiet_NaN();
  const auto old = watch(2.5, unknown);
  EXPECT_FALSE(old->payload_beyond_thresholds());
  EXPECT_THAT(old->notes(), ::testing::Not(::testing::Contains(::testing::HasSubstr("heaviest healthy run"))));
}

// The monitor predicts with each payload the stream declares (take_declared_payload); the thresholds
// are learned with it too. Before session 33 they were learned with the payload the learner was
// told alone: `thresholds` on healthy runs from a controller declaring 0.5 kg, without
// --payload-mass, gave J2/J3 thresholds six times too wide (0.46/0.48 A against 0.08/0.07 A).
TEST_F(MonitorLoop, ThresholdsAreLearnedWithThePayloadTheStreamDeclares) {
  // the fixture's own runs: 0.5 kg declared in h1's stream, none in h2's. Told nothing, the learner
  // reads the declaration and learns the fixture's thresholds, which it was told the payload for
  const auto h1 = run(scenario(503, 24, 0.5)), h2 = run(scenario(504, 16, 0.0));
  const MonitorConfig read = learn_thresholds(*twin, {{&h1, {}}, {&h2, {}}});
  EXPECT_EQ(read.payload_max, 0.5);
  for (int j = 0; j < 6; ++j) {
    EXPECT_NEAR(read.static_level[j], config->static_level[j], 1e-9) << "J" << j + 1;
    EXPECT_NEAR(read.dynamic[static_cast<size_t>(j)].evaluate(0.0, 0.0), config->dynamic[static_cast<size_t>(j)].evaluate(0.0, 0.0), 1e-9)
        << "J" << j + 1;
    EXPECT_NEAR(read.observer_level[j], config->observer_level[j], 1e-9) << "J" << j + 1;
  }
  // without the declaration (an older controller) the learner predicts h1 without its part: J2 and
  // J3 hold it, and their thresholds swallow its weight
  const auto h1_undeclared = undeclared(h1);
  const MonitorConfig blind = learn_thresholds(*twin, {{&h1_undeclared, {}}, {&h2, {}}});
  EXPECT_EQ(blind.payload_max, 0.0);
  for (int j : {1, 2}) EXPECT_GT(blind.static_level[j], 2.0 * config->static_level[j]) << "J" << j + 1;
  // a declaration changes the prediction in the run: a part picked and declared at 8 s. Followed, the
  // thresholds are those of the same program run once without and once with the part (measured: J2
  // 0.082 and 0.082 A, J3 0.071 and 0.070 A); with the monitor told to keep its payload
  // (follow_payload off, `--keep-payload`) the learner keeps it too, and learns the part's step
  // (0.26 and 0.27 A)
  const auto pick = run(scenario(505, 16, 0.0, part_change(false, 0.5, 8.0)));
  const auto plain = run(scenario(505, 16, 0.0)), loaded = run(scenario(505, 16, 0.5));
  const MonitorConfig followed = learn_thresholds(*twin, {{&pick, {}}});
  // (the slope's learner reads a run once and asks whether a sample is judged as soon as it has seen
  // it: the same answer as the whole run's timeline, the settling after the pick included)
  {
    const PayloadTimeline whole(*twin, HealthyRun{&pick, {}}, true, 0.002);
    ASSERT_EQ(whole.steps(), 2u);
    PayloadTimeline seen(*twin, model::RigidBodyInertia{}, true);
    size_t settling = 0;
    for (size_t k = 0; k < pick.samples.size(); ++k) {
      seen.see(k, pick.samples[k]);
      ASSERT_EQ(seen.judged_seen(k, pick.median_period), whole.judged(k)) << "sample " << k;
      settling += whole.judged(k) ? 0 : 1;
    }
    EXPECT_EQ(settling, 25u) << "0.05 s at 500 Hz after the pick";
  }
  const MonitorConfig apart = learn_thresholds(*twin, {{&plain, {}}, {&loaded, {}}});
  MonitorConfig keep;
  keep.follow_payload = false;
  const MonitorConfig kept = learn_thresholds(*twin, {{&pick, {}}}, keep);
  EXPECT_EQ(followed.payload_max, 0.5);
  EXPECT_EQ(kept.payload_max, 0.0);
  for (int j : {1, 2}) {
    EXPECT_LT(followed.static_level[j], 1.1 * apart.static_level[j]) << "J" << j + 1;
    EXPECT_GT(kept.static_level[j], 2.0 * apart.static_level[j]) << "J" << j + 1;
  }
  // and the run it was learned on raises nothing, its pick included
  Monitor m(*twin, followed);
  for (const auto& x : pick.samples) m.push(x);
  m.finish();
  EXPECT_TRUE(m.events().empty()) << listing(m.events());
}

// At a reversal the drive goes from motoring to back-driven (or back), and its current for the same
// torque steps by (1 - c_gen); the measured velocity cannot time it (a count is 3 mrad/s), so the
// twin's blended prediction misses part of the step. The step grows with the load: thresholds
// learned at 0-0.5 kg raised false contacts at J4's reversals under a 2 kg payload (4 a minute on
// the virtual UR3e, session 24). They now remember the largest reversal load they saw per joint and
// widen by (1 - c_gen) times the excess, through each channel's filter; within what they saw they
// are untouched, and a contact under the heavy payload is still found.
TEST_F(MonitorLoop, ThresholdsWidenAtReversalsUnderMoreLoadThanTheyWereLearnedWith) {
  ASSERT_EQ(config->reversal_load_max.size(), 6);
  for (int j = 0; j < 6; ++j) EXPECT_TRUE(config->reversal_load_max[j] >= 0.0 && std::isfinite(config->reversal_load_max[j])) << j;
  // the shoulder and elbow hold the arm: they reverse under the most load
  EXPECT_GT(std::min(config->reversal_load_max[1], config->reversal_load_max[2]), 2.0 * config->reversal_load_max[3]);
  // the twin file keeps it; a bad value is named; a file from before has none (no widening)
  const MonitorConfig back = MonitorConfig::from_json(config->to_json(), "twin.json", 6);
  EXPECT_TRUE(back.reversal_load_max.isApprox(config->reversal_load_max, 1e-12));
  auto block = nlohmann::json::parse(config->to_json());
  block["reversal_load_max"][1] = -1.0;
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { MonitorConfig::from_json(block.dump(), "twin.json", 6); }),
              ::testing::HasSubstr("twin.json: field 'monitor.reversal_load_max[1]': expected a number >= 0, got -1"));
  block["reversal_load_max"] = {1.0, 2.0};
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { MonitorConfig::from_json(block.dump(), "twin.json", 6); }),
              ::testing::HasSubstr("field 'monitor.reversal_load_max': expected 6 values (one per joint), got 2"));
  block.erase("reversal_load_max");
  EXPECT_EQ(MonitorConfig::from_json(block.dump(), "twin.json", 6).reversal_load_max.size(), 0);
  MonitorConfig old = *config;
  old.reversal_load_max.resize(0);

  // a run the thresholds were learned on: not one sample's threshold changes
  {
    const auto rec = run(scenario(503, 24, 0.5));
    Monitor a(declared_twin(), *config), b(declared_twin(), old);
    int widened = 0;
    for (const auto& x : rec.samples) {
      a.push(x);
      b.push(x);
      if (a.level() != b.level() || a.observer_threshold() != b.observer_threshold()) ++widened;
    }
    EXPECT_EQ(widened, 0);
  }
  // a healthy run with 2 kg: false contacts at the loaded reversals before, none now. (Before: also a
  // twin that reads the drive's direction on actual_qd alone, as on a log without target_qd, and no
  // reading of the doubt; with the direction read on the target, session 31, or the doubt read on the
  // current, sessions 32-33, the same run raises none even without the widening.)
  const auto watch = [&](const device::Recording& rec, MonitorConfig c) {
    ident::TwinModel t = *twin;
    if (c.reversal_load_max.size() == 0) {
      t.target_direction = {};
      c.drive_doubt = false;
    }
    model::RigidBodyInertia p = payload;
    p.mass = 2.0;
    t.set_payload(p);
    Monitor m(t, c);
    for (const auto& x : rec.samples) m.push(x);
    m.finish();
    return m.events();
  };
  const auto heavy = undeclared(run(scenario(2501, 30, 2.0)));
  EXPECT_GE(watch(heavy, old).size(), 1u) << "the case this guards against";
  EXPECT_TRUE(watch(heavy, *config).empty()) << listing(watch(heavy, *config));
  // the widening is never more than the switch's step for the largest excess load of the run
  // (the twin's torque as the monitor predicts it: measured q, qd, the controller's target qdd)
  const auto widening = [&](const device::Recording& rec, const std::string& what) {
    ident::TwinModel t = *twin;
    model::RigidBodyInertia p = payload;
    p.mass = 2.0;
    t.set_payload(p);
    // (the load's widening alone: without the longest crawls, session 30, which widen by the whole
    // step where a joint crawls longer than the learned runs did; bounded by the whole load below)
    MonitorConfig load_only = *config;
    load_only.crawl_max.resize(0);
    Monitor a(t, load_only), b(t, old), full(t, *config);
    ident::FrictionMemory memory;
    VectorJ tau, cur, tau_max = VectorJ::Zero(6), wc = VectorJ::Zero(6), wo = VectorJ::Zero(6), wfc = VectorJ::Zero(6),
                      wfo = VectorJ::Zero(6);
    for (const auto& x : rec.samples) {
      a.push(x);
      b.push(x);
      full.push(x);
      t.advance(memory, x.q);
      t.predict(x.q, x.qd, x.target_qdd, x.temperature, tau, cur, &memory);
      tau_max = tau_max.cwiseMax(tau.cwiseAbs());
      wc = wc.cwiseMax(a.level() - b.level());
      wo = wo.cwiseMax(a.observer_threshold() - b.observer_threshold());
      wfc = wfc.cwiseMax(full.level() - b.level());
      wfo = wfo.cwiseMax(full.observer_threshold() - b.observer_threshold());
    }
    for (int j = 0; j < 6; ++j) {
      const ident::JointDrive& d = twin->joints[static_cast<size_t>(j)];
      const double excess = std::max(0.0, tau_max[j] - config->reversal_load_max[j]);
      const double obs_step = std::max(std::abs(1.0 - d.c_gen), std::abs(1.0 / d.c_gen - 1.0));
      EXPECT_LE(wc[j], std::abs(1.0 - d.c_gen) * excess / d.gain + 1e-12) << what << " J" << j + 1;
      EXPECT_LE(wo[j], obs_step * excess + 1e-12) << what << " J" << j + 1;
      EXPECT_LE(wfc[j], std::abs(1.0 - d.c_gen) * tau_max[j] / d.gain + 1e-12) << what << " J" << j + 1 << " (with the crawls)";
      EXPECT_LE(wfo[j], obs_step * tau_max[j] + 1e-12) << what << " J" << j + 1 << " (with the crawls)";
    }
    EXPECT_GT(wo.maxCoeff(), 0.0) << what << ": nothing widened";
  };
  widening(heavy, "figure-eight");
  // (session 27) a joint on Cao's FIR widens through the same taps (all positive: the filtered bound
  // bounds its filtered residual), not through the IIR: J2's widening on the FIR is the taps over the
  // step the IIR's widening recovers, to round-off
  {
    ident::TwinModel t = *twin;
    model::RigidBodyInertia p = payload;
    p.mass = 2.0;
    t.set_payload(p);
    MonitorConfig fir_cfg = *config, fir_old = old;
    fir_cfg.residual_filter = {"iir", "fir", "iir", "iir", "iir", "iir"};
    fir_old.residual_filter = fir_cfg.residual_filter;
    Monitor iw(t, *config), in(t, old), fw(t, fir_cfg), fn(t, fir_old);
    const double a = 1.0 - std::exp(-2.0 * M_PI * config->filter_cutoff_hz * config->nominal_period);
    const std::vector<double> taps = signal::cao_torque_fir_taps();
    std::vector<double> u;
    double w_prev = 0.0, worst = 0.0, widest = 0.0;
    for (const auto& x : heavy.samples) {
      for (Monitor* m : {&iw, &in, &fw, &fn}) m->push(x);
      const double w_iir = iw.level()[1] - in.level()[1], w_fir = fw.level()[1] - fn.level()[1];
      u.push_back(w_prev + (w_iir - w_prev) / a);  // the step times the excess, as the IIR took it
      w_prev = w_iir;
      if (u.size() < 10) continue;
      double expect = 0.0;
      for (size_t i = 0; i < taps.size(); ++i) expect += taps[i] * u[u.size() - 1 - i];
      worst = std::max(worst, std::abs(w_fir - expect));
      widest = std::max(widest, w_fir);
    }
    EXPECT_GT(widest, 0.01) << "J2 widened [A]";
    EXPECT_LT(worst, 1e-9) << "J2's widening on the FIR against the taps over the step [A]";
  }
  widening(undeclared(run("robot: ur3e\nseed: 2503\nduration: 8\ntrajectory: {type: point_to_point, waypoints: [[-0.6, -1.4, 1.3, "
                          "-1.5, -1.3, 0.3], [-0.6, -1.2, 1.45, -1.8, -1.3, 0.3], [-0.6, -1.2, 1.45, -1.8, -1.3, 0.3], [0.6, -1.4, 1.3, "
                          "-1.5, -1.85, -0.3]], durations: [1.2, 0.8, 1.2, 1.5]}\npayload: {mass: 2.0, com: [0, 0, 0.04]}\n")),
           "pick-and-place with 1.2 s rests");
  // a 3 N·m contact on the forearm under the 2 kg payload: found within 20 ms, on its link
  const auto hit = undeclared(run(scenario(2502, 12, 2.0,
                                           "  - {type: collision, link: 3, onset: 6.03, magnitude: 3, duration: 0.05, "
                                           "point: [-0.175, -0.028, 0.041], direction: [-0.327, 0.43, 0.841]}\n")));
  const auto ev = watch(hit, *config);
  ASSERT_EQ(ev.size(), 1u) << listing(ev);
  EXPECT_EQ(ev[0].fault, FaultClass::Collision) << listing(ev);
  EXPECT_LE(ev[0].t_detected - 6.03, 0.020) << listing(ev);
  EXPECT_EQ(ev[0].link, 2) << listing(ev);
}

// The drive's current factor switches (motoring 1, back-driven c_gen) when a joint's velocity
// crosses zero. The simulator streams actual_qd as a backward difference of the encoder, half a
// period late, and the twin was identified with that lag measured on its recordings (1 ms at
// 500 Hz). Reading the drive's direction in the predicted current on the velocity carried forward
// by it puts the switch in the right sample. On a fast 2 kg figure-eight the shoulder (J2) reverses
// under ~15 N·m at 2.7 rad/s², where the lag is about one encoder count of velocity. Within +-10 ms
// of those reversals, against the same twin reading the streamed velocity as it is (velocity_lag
// 0), the largest filtered current residual falls by more than a third (measured 0.073 vs
// 0.129 A). Away from reversals nothing changes: at |qd| > 0.2 rad/s the two current residuals agree
// to 1e-9 A; at rest too, where the lead is none (TwinModel::kDirectionLeadMin); and the observer,
// which reads the streamed velocity, is the same throughout.
TEST_F(MonitorLoop, TheDrivesDirectionIsReadOnTheVelocityAtTheSamplesInstant) {
  EXPECT_NEAR(twin->velocity_lag, 0.001, 0.0001) << "half the 2 ms period: the backward difference's lag";
  ident::TwinModel lagged = *twin;
  lagged.target_direction = {};  // (the lag alone: the direction read on the target is the next test's)
  model::RigidBodyInertia p = payload;
  p.mass = 2.0;
  lagged.set_payload(p);
  ident::TwinModel as_is = lagged;
  as_is.velocity_lag = 0.0;
  const auto rec = undeclared(run("robot: ur3e\nseed: 2601\nduration: 30\ntrajectory: {type: figure_eight, size: [0.12, 0.08], period: 6, "
                                  "tilt: [0.5, 0.6, 0.8]}\npayload: {mass: 2.0, com: [0, 0, 0.04]}\n"));
  // (the prediction's switch itself: without reading the doubt on the current, session 33's reading
  // of it on a stream without targets)
  MonitorConfig blended = *config;
  blended.drive_doubt = false;
  Monitor a(lagged, blended), b(as_is, blended);
  const size_t N = rec.samples.size();
  const auto [ra, rb, oa, ob, far_diff] = side_by_side(a, b, rec, 1, [](const RobotSample& x) { return std::abs(x.qd[1]) > 0.2; });
  double peak_a = 0.0, peak_b = 0.0, obs_diff = 0.0;
  int reversals = 0;
  for (size_t k = 1; k < N; ++k) {
    const double v0 = rec.samples[k - 1].target_qd[1], v1 = rec.samples[k].target_qd[1];
    if (!(v0 * v1 < 0.0 || (v0 != 0.0 && v1 == 0.0)) || rec.samples[k].timestamp < 1.0) continue;
    ++reversals;
    for (size_t i = k > 5 ? k - 5 : 0; i < std::min(N, k + 6); ++i) {
      peak_a = std::max(peak_a, std::abs(ra[i]));
      peak_b = std::max(peak_b, std::abs(rb[i]));
      obs_diff = std::max(obs_diff, std::abs(oa[i] - ob[i]));
    }
  }
  ASSERT_GE(reversals, 6) << "the figure-eight reverses J2 twice a loop";
  EXPECT_LT(peak_a, 0.67 * peak_b) << "current residual at J2's reversals [A]: " << peak_a << " vs " << peak_b;
  EXPECT_EQ(obs_diff, 0.0) << "the observer reads the streamed velocity";
  EXPECT_LT(far_diff, 1e-9);
  // at rest the lead is none: on a pick-and-place under 2 kg with 1.2 s rests, the current residual
  // once every joint's target has stood still for 0.2 s is the same with and without the lag (a
  // lead from the target acceleration's noise, 0.05 rad/s², would move the blended switch there)
  EXPECT_EQ(lagged.direction_velocity(0.0, 0.05), 0.0);
  EXPECT_NEAR(lagged.direction_velocity(0.0, -2.7), -0.0027, 0.0001);
  const auto rests = undeclared(run("robot: ur3e\nseed: 2602\nduration: 8\ntrajectory: {type: point_to_point, waypoints: [[-0.6, -1.4, 1.3, "
                                    "-1.5, -1.3, 0.3], [-0.6, -1.2, 1.45, -1.8, -1.3, 0.3], [-0.6, -1.2, 1.45, -1.8, -1.3, 0.3], [0.6, -1.4, "
                                    "1.3, -1.5, -1.85, -0.3]], durations: [1.2, 0.8, 1.2, 1.5]}\npayload: {mass: 2.0, com: [0, 0, 0.04]}\n"));
  Monitor c(lagged, blended), d(as_is, blended);
  int resting = 0;
  double rest_diff = 0.0, still_since = 0.0;
  for (const auto& x : rests.samples) {
    c.push(x);
    d.push(x);
    // (after 0.2 s of rest: the filtered residual carries the approach for a while)
    if (x.target_qd.cwiseAbs().maxCoeff() >= 1e-4) still_since = x.timestamp;
    if (x.timestamp - still_since > 0.2) {
      ++resting;
      rest_diff = std::max(rest_diff, (c.residual() - d.residual()).cwiseAbs().maxCoeff());
    }
  }
  EXPECT_GT(resting, 500) << "the rests";
  EXPECT_LT(rest_diff, 1e-9) << "the current residual at rest [A]";
}

// At a slow reversal under gravity J2's encoder reads 0 for tens of ms (less than a count a period)
// while its drive switches from back-driven to motoring (c_gen: the current steps by about a
// quarter). Read on the measured velocity alone, the twin predicts halfway between the two levels
// for as long as the encoder reads 0: half the step in the residual on each side of the switch (a
// figure-eight run at a third of its speed raised false contacts there, session 30). Read with the
// controller's target, whose velocity has no counts, the twin is on the right side of the switch
// except within the switch's timing (identify measures it on the current's own steps).
TEST_F(MonitorLoop, ADrivesSwitchWhereTheEncoderReadsNothingIsTimedByTheTarget) {
  ASSERT_FALSE(twin->target_direction.empty());
  ident::TwinModel target = declared_twin(), measured = target;
  measured.target_direction = {};
  const auto rec = run("robot: ur3e\nseed: 3101\nduration: 60\ntrajectory: {type: figure_eight, size: [0.12, 0.08], period: 20, "
                       "tilt: [0.3, 0.4, 0.5]}\npayload: {mass: 0.5, com: [0, 0, 0.04]}\n");
  // (the measured velocity's blend as it was: without the doubt read on the current, which since
  // session 33 covers these reversals without targets too)
  MonitorConfig blended = *config;
  blended.drive_doubt = false;
  Monitor a(target, *config), b(measured, blended);
  const size_t N = rec.samples.size();
  const SideBySide both = side_by_side(a, b, rec, 1, [](const RobotSample& x) { return x.qd.cwiseAbs().minCoeff() > 0.05; });
  const std::vector<double>& ra = both.ra;
  const std::vector<double>& rb = both.rb;
  const double far_diff = both.far_diff;
  a.finish();
  // J2's reversals: the target crosses zero; within +-60 ms, how long the encoder read 0 and the
  // mean |filtered current residual|
  int reversals = 0;
  double sum_a = 0.0, sum_b = 0.0, zero_ms = 0.0;
  for (size_t k = 1; k + 30 < N; ++k) {
    const double v0 = rec.samples[k - 1].target_qd[1], v1 = rec.samples[k].target_qd[1];
    if (!(v0 * v1 < 0.0) || rec.samples[k].timestamp < 1.0 || k < 30) continue;
    ++reversals;
    for (size_t i = k - 30; i < k + 30; ++i) {
      sum_a += std::abs(ra[i]);
      sum_b += std::abs(rb[i]);
      zero_ms += rec.samples[i].qd[1] == 0.0 ? 2.0 : 0.0;
    }
  }
  ASSERT_GE(reversals, 5) << "the figure-eight reverses J2 twice a loop";
  EXPECT_GT(zero_ms / reversals, 20.0) << "ms of 0 counts around a reversal";
  const double mean_a = sum_a / (60.0 * reversals), mean_b = sum_b / (60.0 * reversals);
  EXPECT_LT(mean_a, 0.6 * mean_b) << "mean |J2 residual| around its reversals [A]: " << mean_a << " read with the target, " << mean_b
                                   << " on the measured velocity";
  EXPECT_LT(far_diff, 1e-6) << "away from standstill both read the same direction";
  EXPECT_TRUE(a.events().empty()) << listing(a.events());
}

// The drive switches hard between its motoring and back-driven levels when the joint's velocity
// crosses zero; where the twin cannot place that instant (a slow loaded reversal: the target's
// crossing within the joint's tracking error) its blend sits between the levels, while the current
// is at one of them. Read on the current (resolve_drive_doubt), the residual there is the current's
// distance to the nearer level: at the noise, where the blend left up to half the step. A current
// beyond a level keeps all of its excess (a contact is read as the switch only up to the step), and a
// joint resting on its target is not in doubt (its held current sits anywhere between the levels).
TEST_F(MonitorLoop, ADrivesSwitchTheTwinCannotTimeIsReadOnTheCurrent) {
  const ident::TwinModel t = declared_twin();
  ASSERT_FALSE(t.target_direction.empty());
  // a figure-eight at twice the thresholds' period with the payload: J2 reverses under load at 0.14 rad/s²
  const auto rec = run("robot: ur3e\nseed: 3102\nduration: 48\ntrajectory: {type: figure_eight, size: [0.12, 0.08], period: 16, "
                       "tilt: [0.3, 0.4, 0.5]}\npayload: {mass: 0.5, com: [0, 0, 0.04]}\n");
  ident::FrictionMemory memory;
  VectorJ tau, i_hat;
  double doubt_raw = 0.0, doubt_read = 0.0, away = 0.0, step = 0.0;
  long n_doubt = 0, n_away = 0, rest_doubt = 0, crossing_doubt = 0, observer_off = 0;
  double beyond_err = 0.0;
  for (size_t k = 0; k < rec.samples.size(); ++k) {
    const RobotSample& s = rec.samples[k];
    if (s.timestamp < 1.0) {
      t.advance(memory, s, s.target_qdd);
      continue;
    }
    t.advance(memory, s, s.target_qdd);
    t.predict(s.q, s.qd, s.target_qdd, s.temperature, tau, i_hat, &memory);
    const VectorJ raw = s.current - i_hat;
    VectorJ read = raw;
    resolve_drive_doubt(t, tau, memory, read);
    double to_m = 0.0, to_b = 0.0;
    if (t.drive_in_doubt(1, tau[1], memory, to_m, to_b)) {
      doubt_raw += raw[1] * raw[1];
      doubt_read += read[1] * read[1];
      step = std::max(step, std::abs(to_m - to_b));
      ++n_doubt;
      // a current 0.5 A beyond the level farther from the other one: all of it stays
      VectorJ over = raw;
      const double far = std::abs(to_m) > std::abs(to_b) ? to_m : to_b;
      over[1] = far + (far > 0.0 ? 0.5 : -0.5);
      resolve_drive_doubt(t, tau, memory, over);
      beyond_err = std::max(beyond_err, std::abs(std::abs(over[1]) - 0.5));
      // the observer's measured torque: one of the two levels' torques, the one nearer the twin's
      VectorJ tau_m(6);
      measured_drive_torque(t, s.current, s.qd, tau_m, &memory, &tau);
      const ident::JointDrive& d = t.joints[1];
      const double motoring = d.gain * s.current[1], back_driven = motoring / d.c_gen;
      const double nearer = std::abs(back_driven - tau[1]) < std::abs(motoring - tau[1]) ? back_driven : motoring;
      if (tau_m[1] != nearer) ++observer_off;
    } else if (std::abs(s.qd[1]) > 0.05) {
      away += raw[1] * raw[1];
      ++n_away;
    }
    // the same sample with J2's target resting at zero velocity (no acceleration), and crossing it
    RobotSample held = s;
    held.qd[1] = held.target_qd[1] = held.target_qdd[1] = 0.0;
    ident::FrictionMemory m = memory;
    t.advance(m, held, held.target_qdd);
    if (t.drive_in_doubt(1, tau[1], m, to_m, to_b)) ++rest_doubt;
    held.target_qdd[1] = -0.1;
    m = memory;
    t.advance(m, held, held.target_qdd);
    if (t.drive_in_doubt(1, tau[1], m, to_m, to_b)) ++crossing_doubt;
  }
  ASSERT_GE(n_doubt, 100) << "J2's reversals in doubt (3 figure-eights, 2 reversals each)";
  const double rms_raw = std::sqrt(doubt_raw / n_doubt), rms_read = std::sqrt(doubt_read / n_doubt), rms_away = std::sqrt(away / n_away);
  EXPECT_GT(step, 0.2) << "J2's step under load [A]";
  EXPECT_GT(rms_raw, 2.0 * rms_away) << "the blend between the levels [A]: " << rms_raw << " vs the noise " << rms_away;
  EXPECT_LT(rms_read, 1.3 * rms_away) << "read on the current [A]: " << rms_read << " vs the noise " << rms_away;
  EXPECT_LT(beyond_err, 1e-12) << "a current beyond a level keeps its excess";
  EXPECT_EQ(observer_off, 0) << "the observer's torque at the level nearer the twin's";
  EXPECT_EQ(rest_doubt, 0) << "a joint resting on its target is not in doubt";
  EXPECT_GT(crossing_doubt, 0);
  // a stream without the targets (session 33): in doubt where the measured velocity's own blend is,
  // within two counts of zero (direction_blend 5 mrad/s, a count 3 mrad/s), resting or not; the
  // prediction is the blend's, as before
  RobotSample plain = rec.samples[1000];
  plain.present &= ~(kFieldTargetQ | kFieldTargetQd | kFieldTargetQdd);
  double to_m = 0.0, to_b = 0.0;
  ASSERT_NEAR(t.direction_blend, 0.005, 0.002);
  for (const double counts : {0.0, 1.0, 2.0, 3.0, 10.0}) {
    plain.qd[1] = counts * 2.0 * M_PI / (1 << 20) / 0.002;
    ident::FrictionMemory pm;
    t.advance(pm, plain, VectorJ::Zero(6));
    EXPECT_EQ(t.drive_in_doubt(1, 10.0, pm, to_m, to_b), counts <= 2.0) << counts << " counts";
    EXPECT_TRUE(pm.measured);
    ident::FrictionMemory none = pm;  // (the same pre-sliding state, no direction kept)
    none.direction.resize(0);
    VectorJ with_memory, without;
    t.predict(plain.q, plain.qd, VectorJ::Zero(6), plain.temperature, tau, with_memory, &pm);
    t.predict(plain.q, plain.qd, VectorJ::Zero(6), plain.temperature, tau, without, &none);
    EXPECT_EQ(with_memory[1], without[1]) << "the prediction is the measured velocity's blend, " << counts << " counts";
  }
}

// A program declares its pick when it is done: a gripper's URCap once it has seen the grip (after
// it), or a program that declares and then closes the gripper (before it). Between the two the
// twin's payload and the arm's load differ, which raised a payload change or a contact at the
// gripper at every pick (47 false alarms in 52 timing runs, session 24). Such an alert is withdrawn
// when both have happened and it clears; a missed grip (it does not clear) and a contact at the
// gripper after a pick declared with its grip stay events.
TEST_F(MonitorLoop, APickDeclaredBeforeOrAfterTheGripRaisesNothing) {
  for (const double delay : {-0.5, -0.05, 0.05, 0.3, 0.9}) {
    const auto rec = run(scenario(2420, 12, 0.0,
                                  "  - {type: payload_pick, onset: 6.1, io_bit: 0, mass: 0.5, com: [0, 0, 0.04], declare_delay: " +
                                      fmt::format("{}", delay) + "}\n"));
    Monitor m(*twin, *config);
    // what a consumer of open alerts sees (--events-open, the dashboard): every alert announced open
    // ends, the withdrawn one through on_withdraw (before session 53 it stayed open for good)
    std::map<double, int> open_alerts;  // raise time -> open announcements
    int withdrawn = 0;
    m.on_event = [&](const Event& e) {
      if (e.open) ++open_alerts[e.t_detected];
      else open_alerts.erase(e.t_detected);
    };
    m.on_withdraw = [&](const Event& e) {
      EXPECT_TRUE(e.withdrawn);
      EXPECT_FALSE(e.open);
      EXPECT_EQ(open_alerts.erase(e.t_detected), 1u) << "withdrew an alert never announced, raised at " << e.t_detected;
      ++withdrawn;
    };
    for (const auto& x : rec.samples) m.push(x);
    m.finish();
    EXPECT_TRUE(m.events().empty()) << "declared " << delay << " s after the grip\n" << listing(m.events());
    EXPECT_THAT(m.notes(), ::testing::Contains(::testing::HasSubstr("withdrawn, not an event"))) << delay;
    EXPECT_GE(withdrawn, 1) << delay;
    EXPECT_TRUE(open_alerts.empty()) << "declared " << delay << " s after the grip: " << open_alerts.size()
                                     << " alert(s) announced open never ended, the first raised at " << open_alerts.begin()->first;
    EXPECT_EQ(m.twin().payload().mass, 0.5);
  }
  // a missed grip declared before the gripper closes on nothing (1 kg declared at 9.5 s, the output at 9.8 s)
  auto miss = run(scenario(160, 16, 0.0));
  for (auto& x : miss.samples) {
    if (x.timestamp >= 9.5) x.payload = 1.0, x.payload_cog[2] = 0.04;
    if (x.timestamp >= 9.8) x.digital_outputs |= 2u;
  }
  Monitor mm(*twin, *config);
  for (const auto& x : miss.samples) mm.push(x);
  mm.finish();
  ASSERT_EQ(mm.events().size(), 1u) << listing(mm.events());
  EXPECT_EQ(mm.events()[0].fault, FaultClass::PayloadChange) << listing(mm.events());
  EXPECT_NEAR(mm.events()[0].magnitude, -1.0, 0.2) << listing(mm.events());
  // a contact at the gripper 0.1 s after a pick declared with its grip
  const auto bump = run(scenario(2421, 10, 0.0,
                                 "  - {type: payload_pick, onset: 6.1, io_bit: 0, mass: 0.5, com: [0, 0, 0.04]}\n"
                                 "  - {type: collision, link: 6, onset: 6.2, magnitude: 5, duration: 0.05, point: [0, 0, 0.05], "
                                 "direction: [0, 1, 0]}\n"));
  Monitor mb(*twin, *config);
  for (const auto& x : bump.samples) mb.push(x);
  mb.finish();
  ASSERT_EQ(mb.events().size(), 1u) << listing(mb.events());
  EXPECT_EQ(mb.events()[0].fault, FaultClass::Collision) << listing(mb.events());
  EXPECT_NEAR(mb.events()[0].t_start, 6.2, 0.02) << listing(mb.events());
  // (a review's cases, each withdrawn before the fix) a 4 ms hit on the forearm 30 ms after the grip
  // of a pick declared 0.2 s early: it cleared before its diagnosis, and an undiagnosed alert was taken
  // for the part; and a hit on the wrist of 34 N, with the part weighing 2 N
  const auto contacts_near_a_pick = [&](const std::string& fault) {
    const auto r = run(scenario(2402, 10, 0.0,
                                "  - {type: payload_pick, onset: 7.3, io_bit: 1, mass: 0.2, com: [0, 0, 0.04], declare_delay: -0.2}\n" + fault));
    Monitor mc(*twin, *config);
    for (const auto& x : r.samples) mc.push(x);
    mc.finish();
    int contacts = 0;
    for (const Event& e : mc.events()) contacts += e.fault == FaultClass::Collision && e.t_start > 7.3;
    return std::make_pair(contacts, listing(mc.events()));
  };
  for (const std::string fault : {"  - {type: collision, link: 3, onset: 7.33, magnitude: 12, duration: 0.004, point: [-0.1, 0.0, 0.03], "
                                  "direction: [1.0, 0.3, 0.0]}\n",
                                  "  - {type: collision, link: 6, onset: 7.33, magnitude: 6, duration: 0.05, point: [0.0, 0.0, 0.05], "
                                  "direction: [1.0, 0.3, 0.0]}\n"}) {
    const auto [contacts, all] = contacts_near_a_pick(fault);
    EXPECT_EQ(contacts, 1) << fault << all;
  }
  // a part lost in transit (no output change), then the gripper opened and no payload declared: the
  // release after the loss is no grip that raised it
  auto lost = run(scenario(2403, 12, 1.0, "  - {type: payload_loss, onset: 7.0, io_bit: 3}\n"));
  for (auto& x : lost.samples) {
    x.digital_outputs |= 8u;  // the gripper holds the part until 7.5 s, when the program opens it
    if (x.timestamp >= 7.5) x.digital_outputs &= ~8u;
    if (x.timestamp >= 7.7) x.payload = 0.0, x.payload_cog[2] = 0.0;
  }
  ident::TwinModel held = *twin;
  model::RigidBodyInertia part = payload;
  part.mass = 1.0;
  held.set_payload(part);
  Monitor ml(held, *config);
  for (const auto& x : lost.samples) ml.push(x);
  ml.finish();
  ASSERT_FALSE(ml.events().empty()) << "the loss was withdrawn";
  EXPECT_EQ(ml.events()[0].fault, FaultClass::PayloadChange) << listing(ml.events());
  EXPECT_NEAR(ml.events()[0].t_start, 7.0, 0.02) << listing(ml.events());
}

// Session 27: a pick at a rest clears soon (the held-at-rest baseline takes the part's weight up)
// and was followed and reported at once, 0.5-0.9 s after the grip; a program that declared its part
// 0.7-0.95 s after the grip then came too late to withdraw it (8 of 24 timing runs of the
// pick-and-place program with 0.5 kg parts: one false alarm each). On a stream that declares its
// payload, a followed change after a gripper output's change is now held until 1 s after it began,
// and the declaration of that part withdraws it; undeclared, it is reported when the second ends.
TEST_F(MonitorLoop, APickFollowedBeforeItsLateDeclarationIsWithdrawn) {
  const std::string program = pick_and_place(0.6, 0.3, 1.2);
  const MonitorConfig c = with_program_thresholds(program, 2710, 22);
  // the part gripped at 6.4 s, during the 0.6 s rest at the pick point; declared 0.8 s later
  const auto rec = run("robot: ur3e\nseed: 2711\nduration: 12\n" + program +
                       "faults:\n  - {type: payload_pick, onset: 6.4, io_bit: 0, mass: 0.5, com: [0, 0, 0.04], declare_delay: 0.8}\n");
  const auto watch = [&](const device::Recording& r, double* reported_at) {
    Monitor m(*twin, c);
    double t = 0.0;
    m.on_event = [&](const Event& e) {
      if (!e.open && e.fault == FaultClass::PayloadChange && reported_at) *reported_at = t;
    };
    for (const auto& x : r.samples) {
      t = x.timestamp;
      m.push(x);
    }
    m.finish();
    return std::make_pair(m.events(), m.notes());
  };
  // a 1 kg part, never declared: followed on its longer look, and nothing else. The watch for a
  // contact on top of it (watch_on_top) took J3's breakaway from the rest where the part was
  // gripped for a contact (a 14 ms "contact on link 1" at 7.204 s) until it judged a joint that
  // rested only 50 ms after it moved on (kOnTopMoving)
  // (gripped 0.45 s into the rest, 6.75 s, the watch raises nothing either; the follow on the final
  // look then reads +0.79 kg, and the 0.2 kg it leaves raises an 18 ms "contact" 0.23 s later: the
  // limit of a pick sized at a rest, docs/validation.md)
  for (const double grip : {6.4}) {
    auto heavy = run("robot: ur3e\nseed: 2711\nduration: 12\n" + program + "faults:\n  - {type: payload_pick, onset: " +
                     fmt::format("{}", grip) + ", io_bit: 0, mass: 1.0, com: [0, 0, 0.04], declare_delay: 0.8}\n");
    for (auto& x : heavy.samples) x.payload = 0.0, x.payload_cog[2] = 0.0;
    const auto events = watch(heavy, nullptr).first;
    ASSERT_EQ(events.size(), 1u) << grip << listing(events);
    EXPECT_NEAR(events[0].magnitude, 1.0, 0.2) << grip << listing(events);
  }
  const auto [declared, notes] = watch(rec, nullptr);
  EXPECT_TRUE(declared.empty()) << listing(declared);
  EXPECT_THAT(notes, ::testing::Contains(::testing::HasSubstr("withdrawn, not an event")));
  // the same pick never declared (the stream still declares its payload: none): an event, held past
  // its close, and reported when the second after it began has passed or the next alert is raised,
  // whichever comes first (here a 6 ms "contact" as the arm moves on: the part's mass read short at
  // the rest, +0.41 kg, the limit of a pick at a rest noted in docs/validation.md)
  auto never = rec;
  for (auto& x : never.samples) x.payload = 0.0, x.payload_cog[2] = 0.0;
  double reported_at = -1.0;
  const auto [found, unused] = watch(never, &reported_at);
  ASSERT_FALSE(found.empty());
  EXPECT_EQ(found[0].fault, FaultClass::PayloadChange) << listing(found);
  EXPECT_NEAR(found[0].magnitude, 0.5, 0.1) << listing(found);
  EXPECT_LT(found[0].t_end, found[0].t_start + 0.7) << "followed well within the second" << listing(found);
  const double next = found.size() > 1 ? found[1].t_detected : std::numeric_limits<double>::infinity();
  EXPECT_GT(reported_at, found[0].t_end + 0.1) << "held past its close" << listing(found);
  EXPECT_NEAR(reported_at, std::min(found[0].t_start + 1.0, next), 0.0021) << listing(found);
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
  // its confidence is how likely class and link are right: the share of the residual the contact
  // explains times the named link's probability (the detail's "% likely"), not the share alone
  // (which ran 11 points above how often the link was right: docs/validation.md)
  const std::string& d = ev.front().detail;
  const size_t likely = d.find(" % likely");
  ASSERT_NE(likely, std::string::npos) << d;
  const double share = std::stod(d.substr(d.rfind(' ', likely - 1) + 1)) / 100.0;
  EXPECT_GT(ev.front().explained, 0.5) << d;
  EXPECT_NEAR(ev.front().confidence, ev.front().explained * share, 0.006) << d;
}

TEST_F(MonitorLoop, StreamGapsAndFrozenChannelsAreTheirOwnEvents) {
  const auto ev = monitor(run(scenario(606, 12, 0.5,
                                      "  - {type: dropped_samples, onset: 5, magnitude: 5, end: 5.1}\n"
                                      "  - {type: stuck_current, joint: 3, onset: 8, end: 9}\n")),
                          0.5);
  // one event per fault (review of session 18: the stuck channel gave three overlapping ones, the
  // frozen run restarting whenever the joint paused and the threshold alert reporting it again)
  ASSERT_EQ(ev.size(), 2u);
  EXPECT_EQ(ev[0].fault, FaultClass::StreamFault);
  EXPECT_EQ(ev[0].magnitude, 5.0);
  EXPECT_EQ(ev[1].fault, FaultClass::SensorFault) << ev[1].detail;
  EXPECT_EQ(ev[1].joint, 2);
  EXPECT_FALSE(ev[1].open);
  // with the stretch's true extent: the channel holds one value from about 8 s to 9 s
  EXPECT_NEAR(ev[1].t_start, 8.0, 0.0041);
  EXPECT_NEAR(ev[1].t_end, 9.0, 0.0041);
  EXPECT_LT(ev[1].t_detected - 8.0, 0.2);
}

// When a frozen current channel comes back, the observer and the residual filter have integrated
// the frozen value for the whole stretch; they restart as after a gap, and the stretch stays the one
// event. (The reference twin's release read as a contact on link 1: cli.evaluate_stuck_channel_release.)
TEST_F(MonitorLoop, AFrozenChannelThatComesBackIsNoContact) {
  const auto ev = monitor(run(scenario(19, 20, 0.5, "  - {type: stuck_current, joint: 2, onset: 14, end: 16}\n")), 0.5);
  ASSERT_EQ(ev.size(), 1u) << ev.back().detail;
  EXPECT_EQ(ev[0].fault, FaultClass::SensorFault);
  EXPECT_EQ(ev[0].joint, 1);
  EXPECT_NEAR(ev[0].t_end, 16.0, 0.0041);
}

// The false-alarm margin a healthy run reports (Monitor::track_margin) is exactly the sensitivity of
// its first alarm: every threshold scaled by a factor just above it raises nothing, just below it raises.
TEST_F(MonitorLoop, TheMarginOfAHealthyRunIsTheSensitivityOfItsFirstAlarm) {
  const auto rec = run(scenario(607, 16, 0.5));
  ident::TwinModel t = declared_twin();
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

// review of session 18: thresholds were learned with the residual filter of the twin's stored
// rate (500 Hz) whatever the recording's, and with a zero-phase acceleration where the monitor uses
// a causal one: on a 250 Hz log without target accelerations the static thresholds, at least 1.1x
// the training peak by construction, were exceeded on the very recording they were learned on
TEST_F(MonitorLoop, ThresholdsLearnedAtARecordingsOwnRateHoldOnThatRecording) {
  const auto full = run(scenario(613, 24, 0.5));
  device::Recording slow = full;
  slow.samples.clear();
  for (size_t k = 0; k < full.samples.size(); k += 2) slow.samples.push_back(full.samples[k]);
  slow.median_period = 0.004;
  slow.present &= ~kFieldTargetQdd;  // a foreign log: the monitor differentiates qd itself
  MonitorConfig learned = learn_thresholds(*twin, {{&slow, payload}});
  EXPECT_DOUBLE_EQ(learned.nominal_period, 0.004);
  learned.use_dynamic = false;  // the static level: 1.1x the training peak at least
  ident::TwinModel t = declared_twin();
  Monitor m(t, learned);
  m.track_margin();
  for (const auto& s : slow.samples) m.push(s);
  m.finish();
  EXPECT_TRUE(m.events().empty()) << m.events().front().detail;
  EXPECT_LE(m.margin_current().maxCoeff(), 1.0 / 1.1 + 1e-9);
}

// The observer's debounce per joint, chosen on a healthy validation run the thresholds were not
// learned on. Checked: one exceedance's peak is never below two's (the run-minimum of two samples);
// the chosen count of every joint is the smallest whose validation ratio is below 1 and below the
// worst joint's at the shared count or kObserverRatioFloor; a monitor with the choice shows each
// joint the margin of its own count, so the run's largest observer ratio is no larger than with the
// shared count or the floor (the margin is kept) while at least one joint is debounced less. A twin without an observer, a user's explicit
// count and no validation run are refused; learning the thresholds again drops the choice.
TEST_F(MonitorLoop, TheObserverDebouncePerJointKeepsTheSharedCountsMargin) {
  const auto val = run(scenario(608, 40, 0.5));
  const ObserverDebounceChoice choice = choose_observer_debounce(*twin, *config, {{&val, payload}});
  const int n = twin->n_dof();
  ASSERT_EQ(choice.ratio.size(), 2u) << "one row per count up to the shared 2";
  ASSERT_EQ(choice.raise_after.size(), static_cast<size_t>(n));
  EXPECT_NEAR(choice.seconds, 40.0, 0.01);
  const double worst = choice.ratio[1].maxCoeff(), bound = std::max(worst, kObserverRatioFloor);
  EXPECT_GT(worst, 0.3) << "a healthy run uses a fair part of its observer thresholds";
  EXPECT_LT(worst, 1.0);
  int fewer = 0;
  for (int j = 0; j < n; ++j) {
    EXPECT_GE(choice.ratio[0][j], choice.ratio[1][j]) << "J" << j + 1;
    const bool one_fits = choice.ratio[0][j] < 1.0 && choice.ratio[0][j] <= bound;
    EXPECT_EQ(choice.raise_after[static_cast<size_t>(j)], one_fits ? 1 : 2) << "J" << j + 1;
    fewer += one_fits;
  }
  EXPECT_GE(fewer, 1) << "no joint keeps the worst joint's margin with one sample: nothing to check";
  ident::TwinModel t = declared_twin();
  MonitorConfig chosen = *config;
  chosen.observer_choice.raise_after = choice.raise_after;
  Monitor m(t, chosen);
  m.track_margin();
  for (const auto& s : val.samples) m.push(s);
  m.finish();
  const VectorJ seen = m.margin_observer();
  for (int j = 0; j < n; ++j)
    EXPECT_DOUBLE_EQ(seen[j], choice.ratio[static_cast<size_t>(choice.raise_after[static_cast<size_t>(j)] - 1)][j]) << "J" << j + 1;
  EXPECT_LE(seen.maxCoeff(), bound);
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
  nlohmann::json bad = nlohmann::json::parse(back.to_json());
  bad["observer_raise_after_joint"] = {1, 1.5, 1, 1, 1, 1};
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { MonitorConfig::from_json(bad.dump(), "twin.json"); }),
              ::testing::HasSubstr("twin.json: field 'monitor.observer_raise_after_joint[1]': expected a whole number within +-2147483647, got 1.5"));
  bad["observer_raise_after_joint"] = {4294967297, 1, 1, 1, 1, 1};
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { MonitorConfig::from_json(bad.dump(), "twin.json"); }),
              ::testing::HasSubstr("twin.json: field 'monitor.observer_raise_after_joint[0]': expected a whole number within +-2147483647, got 4294967297"));
}

// found by fuzzing (fuzz/regressions/monitor_config): 9 values overflowed a VectorJ (stack buffer
// overflow), and get<int>() of 1e20 was undefined
TEST(MonitorConfig, FromJsonRejectsMoreValuesThanJointsAndHugeCounts) {
  const auto error_of = [](const nlohmann::json& j) {
    return twinwatch::test::error_text<ParseError>([&] { MonitorConfig::from_json(j.dump(), "twin.json"); });
  };
  nlohmann::json j = valid_block();
  j["static_level_A"] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  EXPECT_THAT(error_of(j), ::testing::HasSubstr("twin.json: field 'monitor.static_level_A': expected at most 7 values (one per joint), got 9"));
  j = valid_block();
  j["raise_after"] = 1e20;
  EXPECT_THAT(error_of(j), ::testing::HasSubstr("twin.json: field 'monitor.raise_after': expected a whole number within +-2147483647, got 1e+20"));
  j = valid_block();
  j["trend"]["history"] = 2.5;
  EXPECT_THAT(error_of(j), ::testing::HasSubstr("field 'monitor.trend.history': expected a whole number"));
}

// every error of the twin's monitor block names the twin file and the field's path, the expected
// and the actual value (they named neither: "clear_after is -1, must be >= 1")
TEST(MonitorConfig, ErrorsOfTheTwinsBlockNameTheFileAndThePath) {
  ident::TwinModel twin("ur3e", model::load_robot("ur3e"));
  twin.origin = "twin.json";
  const auto error_of = [&](const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json j = valid_block();
    edit(j);
    twin.monitor_json = j.dump();
    return twinwatch::test::error_text<ParseError>([&] { MonitorConfig::from_twin(twin); });
  };
  EXPECT_EQ(error_of([](nlohmann::json&) {}), "no error");
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["dynamic"][1].erase("rho"); }),
              ::testing::HasSubstr("twin.json: field 'monitor.dynamic[1].rho': missing required field"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["clear_after"] = -1; }),
              ::testing::HasSubstr("twin.json: field 'monitor.clear_after': expected a whole number from 1 to 1000, got -1"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["static_level_A"].erase(5); }),
              ::testing::HasSubstr("twin.json: field 'monitor.static_level_A': expected 6 values (one per joint), got 5"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["static_level_A"][2] = 0.0; }),
              ::testing::HasSubstr("twin.json: field 'monitor.static_level_A[2]': expected a number > 0, got 0"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["dynamic"][3]["alpha"] = -1.0; }),
              ::testing::HasSubstr("twin.json: field 'monitor.dynamic[3].alpha': expected a number >= 0, got -1"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["dynamic"][0]["psi_qd"] = -0.01; }),
              ::testing::HasSubstr("field 'monitor.dynamic[0].psi_qd': expected a number >= 0, got -0.01"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["dynamic"][0]["rho"] = 0.0; }), ::testing::HasSubstr("field 'monitor.dynamic[0].rho': expected a number > 0, got 0"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["dynamic"].erase(5); }),
              ::testing::HasSubstr("field 'monitor.dynamic': expected 6 thresholds (one per joint), got 5"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["filter_cutoff_hz"] = 1e9; }),
              ::testing::HasSubstr("twin.json: field 'monitor.filter_cutoff_hz': expected a number in (0, 500] Hz, got 1000000000"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["filter_cutoff_hz"] = 0; }), ::testing::HasSubstr("field 'monitor.filter_cutoff_hz': expected a number > 0, got 0"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["raise_aftr"] = 5; }),
              ::testing::HasSubstr("twin.json: field 'monitor.raise_aftr': unknown key, expected one of: static_level_A, dynamic, use_dynamic, "
                                   "filter_cutoff_hz, raise_after"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j.erase("raise_after"); }), ::testing::HasSubstr("twin.json: field 'monitor.raise_after': missing required field"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j.erase("observer_gain"); }), ::testing::HasSubstr("field 'monitor.observer_gain': missing required field"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["trend"].erase("window_s"); }),
              ::testing::HasSubstr("twin.json: field 'monitor.trend.window_s': missing required field"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j.erase("trend"); }), ::testing::HasSubstr("field 'monitor.trend': missing required field"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["trend"]["window_s"] = 0; }),
              ::testing::HasSubstr("field 'monitor.trend.window_s': expected a number > 0, got 0"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j.erase("dynamic"); }),
              ::testing::HasSubstr("field 'monitor.dynamic': missing required field (use_dynamic is true)"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["observer_level_Nm"] = {1, 1, 1, 1}; }),
              ::testing::HasSubstr("field 'monitor.observer_level_Nm': expected 6 values (one per joint), got 4"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["programs"]["chirp"].erase("dynamic"); }),
              ::testing::HasSubstr("twin.json: field 'monitor.programs.chirp.dynamic': missing required field"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["programs"]["chirp"]["static_level_A"][0] = -0.1; }),
              ::testing::HasSubstr("field 'monitor.programs.chirp.static_level_A[0]': expected a number > 0, got -0.1"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["residual_filter"] = {"iir", "butter"}; }),
              ::testing::HasSubstr("field 'monitor.residual_filter': expected 1 or 6 entries (one per joint), got 2"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["gain"] = nullptr; }), ::testing::HasSubstr("field 'monitor.gain': unknown key"));
  EXPECT_THAT(error_of([](nlohmann::json& j) { j["use_dynamic"] = nullptr; }),
              ::testing::HasSubstr("field 'monitor.use_dynamic': expected true or false, got null"));
  EXPECT_EQ(error_of([](nlohmann::json& j) { j["observer_raise_after"] = 0; }), "no error") << "0: raise_after";
  twin.monitor_json.clear();
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { MonitorConfig::from_twin(twin); }),
              ::testing::HasSubstr("twin.json has no monitor thresholds"));
}

// a version-1 twin written before the trend and the observer existed reads their defaults: those
// of the day version 2 came (twin_model.cpp, upgrade_version_1), still the ones of TrendConfig and
// MonitorConfig (if they change, old twins keep the values they were read with until then)
TEST(MonitorConfig, AVersion1TwinWithoutTrendOrObserverReadsTheDefaults) {
  ident::TwinModel t("ur3e", model::load_robot("ur3e"));
  t.joints.resize(6);
  nlohmann::json block = valid_block();
  block.erase("trend");
  block.erase("observer_gain");
  block.erase("observer_alerts");
  t.monitor_json = block.dump();
  nlohmann::json file = nlohmann::json::parse(t.to_json());
  file["version"] = 1;
  std::vector<std::string> warnings;
  log::set_sink([&](log::Level level, std::string_view m) {
    if (level == log::Level::Warn) warnings.emplace_back(m);
  });
  const ident::TwinModel old = ident::TwinModel::from_json(file.dump(), "old.json");
  log::set_sink(nullptr);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], ::testing::HasSubstr("monitor.trend = the defaults"));
  EXPECT_THAT(warnings[0], ::testing::HasSubstr("monitor.observer_gain = 150 1/s"));
  EXPECT_THAT(warnings[0], ::testing::HasSubstr("monitor.observer_alerts = true"));
  const MonitorConfig c = MonitorConfig::from_twin(old);
  const MonitorConfig d;
  const TrendConfig& a = c.trend;
  const TrendConfig& b = d.trend;
  EXPECT_EQ(a.enabled, b.enabled);
  EXPECT_EQ(a.window_s, b.window_s);
  EXPECT_EQ(a.cycle_period, b.cycle_period);
  EXPECT_EQ(a.v_min, b.v_min);
  EXPECT_EQ(a.min_moving_fraction, b.min_moving_fraction);
  EXPECT_EQ(a.baseline_windows, b.baseline_windows);
  EXPECT_EQ(a.min_windows, b.min_windows);
  EXPECT_EQ(a.history, b.history);
  EXPECT_EQ(a.z_crit, b.z_crit);
  EXPECT_EQ(a.min_rate_pct_per_h, b.min_rate_pct_per_h);
  EXPECT_EQ(a.persist, b.persist);
  EXPECT_EQ(a.temperature_ref, b.temperature_ref);
  EXPECT_EQ(a.temperature_slope.size(), 0);
  EXPECT_EQ(c.observer_gain, d.observer_gain);
  EXPECT_EQ(c.observer_alerts, d.observer_alerts);
  // and the same block in a version-2 file is refused
  file["version"] = 2;
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { MonitorConfig::from_twin(ident::TwinModel::from_json(file.dump(), "new.json")); }),
              ::testing::HasSubstr("new.json: field 'monitor.trend': missing required field"));
}

// A small part (0.2 kg) changed, then a contact 0.9 s later. The first look reads the part's step in
// its short window as a contact where the part hangs ("link 5; link 6 is also possible"), and so did
// the split on the contact's rise, on the samples before it (or on an inner link: "link 1, 1.0 N");
// the change was then not followed there, the split went back, and the contact went into the payload
// change (3 of these 12 runs, before session 28). The watch starts on the last-link contact's payload
// hypothesis when a gripper output changed, and the split takes the watched change when the window's
// payload hypothesis agrees with it.
TEST_F(MonitorLoop, AContactSoonAfterASmallPartReadAsAContactIsAnEventOfItsOwn) {
  int first_look_at_last_link = 0;
  for (const bool loss : {true, false})
    for (const double mass : {0.2, 0.3})
      for (unsigned seed = 921; seed <= 960; ++seed) {
        std::string f = part_change(loss, mass, 8.5);
        f += "  - {type: collision, link: 3, onset: 9.4, magnitude: 4, duration: 0.05, point: [-0.1, 0.0, 0.03], direction: [0.3, 1.0, -0.2]}\n";
        const auto rec = undeclared(run(scenario(seed, 13, loss ? mass : 0.0, f)));
        Monitor m(carrying(loss ? mass : 0.0), *config);
        bool first = true;
        m.on_event = [&](const Event& e) {
          // the payload change's first look (the alert raised by the part, before the contact)
          if (first && e.fault != FaultClass::Unknown && e.t_start < 9.3) {
            first = false;
            if (e.fault == FaultClass::Collision && (e.link == 5 || std::count(e.other_links.begin(), e.other_links.end(), 5) > 0))
              ++first_look_at_last_link;
          }
        };
        for (const auto& s : rec.samples) m.push(s);
        m.finish();
        const auto& ev = m.events();
        const std::string all = fmt::format("{} {} kg, seed {}:{}", loss ? "loss" : "pick", mass, seed, listing(ev));
        ASSERT_EQ(ev.size(), 2u) << all;
        EXPECT_EQ(ev[0].fault, FaultClass::PayloadChange) << all;
        EXPECT_NEAR(ev[0].magnitude, loss ? -mass : mass, 0.05) << all;
        EXPECT_EQ(ev[1].fault, FaultClass::Collision) << all;
        EXPECT_GT(ev[1].t_detected, 9.4) << all;
        EXPECT_LT(ev[1].t_detected - 9.4, 0.02) << all;
        EXPECT_NEAR(m.twin().payload().mass, loss ? 0.0 : mass, 0.05) << all;
      }
  // the path this is about: on this twin the first look reads some of the changes as a contact at
  // the last link (link 6 named or also possible): 2 of these 160 runs (0.2 kg picks, seeds 931 and
  // 948). (Until session 39 the split also took the watched change where the samples before the
  // rise alone read as a contact; since the contact is scored on what it explains beyond the noise
  // it absorbs, and a window's shape is read on the joint that stands out from its own noise, they
  // read as the payload change themselves, and the first look reads fewer parts as contacts: 13 of
  // the first 80 runs with the noise-aware score alone, 7 in session 40, 1 since the shape is read
  // on a joint that crossed its threshold (session 41), hence 160 runs.)
  // Seed 957 (a 0.2 kg drop) is the case of session 41: its first look read the drop's step, 0.14 s
  // old at the raise, as "extra resistance on J3 that stood before the raise" (offset_raise), a
  // persistent alert; the drop was then reported twice, the second time as a 4 ms payload change
  // after the contact. A gripper output changed there, so that rule no longer applies.
  EXPECT_GE(first_look_at_last_link, 1);
}

// A contact on the wrist 0.15 s after an undeclared 0.6 kg pick (the set grip_contact). Its window
// holds the followed part's misfit on J1-J3 (0.3-0.5 N·m) around a 3.6 N·m pulse on J5: scored with
// every joint in units of its noise (tried in session 41 against what resting joints hold), the
// contact explained a fifth of it, the alert went back into the pick, and the contact was lost.
// Scored in N·m (resting joints shrunk to what friction leaves of them), it is an event of its own,
// on link 5.
TEST_F(MonitorLoop, AContactRightAfterAPickIsNotLostInThePicksMisfit) {
  for (unsigned seed : {29959u, 29960u, 29961u}) {
    const std::string f =
        "  - {type: payload_pick, onset: 8.3, io_bit: 0, mass: 0.6, com: [0, 0, 0.04]}\n"
        "  - {type: collision, link: 5, onset: 8.450, magnitude: 4.0, duration: 0.05, point: [0.021, -0.005, 0.018], "
        "direction: [0.953, 0.729, -0.318]}\n";
    const auto rec = undeclared(run(scenario(seed, 12, 0.0, f)));
    Monitor m(carrying(0.0), *config);
    for (const auto& s : rec.samples) m.push(s);
    m.finish();
    const auto& ev = m.events();
    const std::string all = fmt::format("seed {}:{}", seed, listing(ev));
    const auto contact = std::find_if(ev.begin(), ev.end(), [](const Event& e) { return e.fault == FaultClass::Collision && e.t_start > 8.44; });
    ASSERT_NE(contact, ev.end()) << all;
    EXPECT_LT(contact->t_detected - 8.45, 0.02) << all;
    EXPECT_EQ(contact->link, 4) << all;
    const auto pick = std::find_if(ev.begin(), ev.end(), [](const Event& e) { return e.fault == FaultClass::PayloadChange; });
    ASSERT_NE(pick, ev.end()) << all;
    EXPECT_NEAR(pick->magnitude, 0.6, 0.15) << all;
  }
}

// A small part's step near the thresholds dips below them within a pulse's time (0.1 s for a 0.25 kg
// drop on the triangle, with thresholds learned for the triangle). Before session 28 such an alert
// was closed as a payload change but not followed (only an alert beyond kPulseMax got the look that
// follows): the twin kept the part, the residual rose again as alerts that no longer saw the gripper
// output change, and a contact 0.6 s after the drop went into one of them. With a gripper output
// changed, a payload change is a step and is followed when its alert clears, however briefly it stood.
TEST_F(MonitorLoop, ASmallPartsStepThatClearsWithinAPulseIsFollowed) {
  MonitorConfig tri = *config;
  const auto t1 = run("robot: ur3e\nseed: 941\nduration: 24\ntrajectory: {type: triangle, side: 0.15, speed: 0.2}\npayload: {mass: 0.5, com: [0, 0, 0.04]}\n");
  const auto t2 = run("robot: ur3e\nseed: 942\nduration: 12\ntrajectory: {type: triangle, side: 0.15, speed: 0.3}\npayload: {mass: 0.5, com: [0, 0, 0.04]}\n");
  const auto t3 = run("robot: ur3e\nseed: 943\nduration: 20\ntrajectory: {type: triangle, side: 0.15, speed: 0.12}\n");
  learn_program_thresholds(tri, "triangle", *twin, {{&t1, payload}, {&t2, payload}, {&t3, {}}});
  tri.select_program("triangle");
  int within_a_pulse = 0, two_events = 0;
  // a 0.25 kg part dropped or picked at 8.3 s, a contact `gap` later
  const auto check = [&](const MonitorConfig& cfg, const std::string& trajectory, const std::string& contact, double gap, unsigned seed, bool loss) {
    std::string y = "robot: ur3e\nseed: " + std::to_string(seed) + "\nduration: 13\ntrajectory: " + trajectory + "\n";
    if (loss) y += "payload: {mass: 0.25, com: [0, 0, 0.04]}\n";
    y += "faults:\n";
    y += part_change(loss, 0.25, 8.3);
    y += fmt::format("  - {{type: collision, onset: {}, duration: 0.05, {}}}\n", 8.3 + gap, contact);
    const auto rec = undeclared(run(y));
    Monitor m(carrying(loss ? 0.25 : 0.0), cfg);
    for (const auto& s : rec.samples) m.push(s);
    m.finish();
    const auto& ev = m.events();
    const std::string all = fmt::format("{}, {}, contact {} s after, seed {}:{}", trajectory, loss ? "loss" : "pick", gap, seed, listing(ev));
    // the contact, once, within 20 ms; everything else the part's change, sized within 0.05 kg
    int contacts = 0;
    for (const Event& e : ev) {
      if (e.fault == FaultClass::Collision) {
        ++contacts;
        EXPECT_GT(e.t_detected, 8.3 + gap) << all;
        EXPECT_LT(e.t_detected - (8.3 + gap), 0.02) << all;
      } else {
        EXPECT_EQ(e.fault, FaultClass::PayloadChange) << all;
        EXPECT_NEAR(e.magnitude, loss ? -0.25 : 0.25, 0.05) << all;
        // (cleared before kPulseMax: the last exceedance plus the clearing debounce, 0.1 s)
        if (e.t_end - e.t_start < 0.4) ++within_a_pulse;
      }
    }
    EXPECT_EQ(contacts, 1) << all;
    if (ev.size() == 2u) ++two_events;
    EXPECT_NEAR(m.twin().payload().mass, loss ? 0.0 : 0.25, 0.05) << all;
  };
  for (const bool loss : {true, false})
    for (const unsigned seed : {931u, 932u, 933u}) {
      // the triangle with its own thresholds
      for (const double gap : {0.6, 1.4})
        check(tri, "{type: triangle, side: 0.15, speed: 0.25}",
              "link: 3, magnitude: 4, point: [-0.1, 0.0, 0.03], direction: [0.3, 1.0, -0.2]", gap, seed, loss);
      // a fast figure-eight (5 s) with the default set: before, the part's step rose two to four
      // times as payload changes of their own
      for (const double gap : {0.5, 0.8})
        check(*config, "{type: figure_eight, size: [0.12, 0.08], period: 5, tilt: [0.3, 0.4, 0.5]}",
              "link: 4, magnitude: 3, point: [0.0, 0.02, 0.02], direction: [0.3, 1.0, -0.2]", gap, seed + 20, loss);
    }
  // the path this is about: steps that cleared within a pulse's time
  EXPECT_GE(within_a_pulse, 6);
  // the change one event and the contact another, in all but one of the 24 runs: on the fast
  // figure-eight's seed 953 (the pick, contact 0.8 s after) the first look parks the step as a
  // persistent alert and a raise on another joint is a second payload event (+0.27 kg, 56 ms)
  EXPECT_GE(two_events, 23);
}

// A part lighter than the thresholds see (0.15 kg), gripped or dropped with a gripper output change
// and never declared: no alert is raised at it, and before session 28 the twin never took it (on the
// library twin what it left raised short "contacts on link 6" later). A second after the output
// change, the payload fitted on the moving joints' residual is taken, with a note and no event. An
// output toggled with no part changes nothing.
TEST_F(MonitorLoop, APartTooLightToRaiseAnAlertIsTakenAfterItsGripperOutputChanged) {
  int quiet_runs = 0;
  for (const bool loss : {true, false})
    for (const unsigned seed : {961u, 962u}) {
      const auto rec = undeclared(run(scenario(seed, 14, loss ? 0.15 : 0.0, part_change(loss, 0.15, 8.3))));
      Monitor m(carrying(loss ? 0.15 : 0.0), *config);
      std::vector<double> noted_at;
      m.on_note = [&](double at, const std::string& text) {
        if (text.find("after a gripper output changed at 8.30") != std::string::npos) noted_at.push_back(at);
      };
      for (const auto& s : rec.samples) m.push(s);
      m.finish();
      const std::string all = fmt::format("{}, seed {}:{}\nnotes: {}", loss ? "loss" : "pick", seed, listing(m.events()), fmt::join(m.notes(), "\n"));
      EXPECT_NEAR(m.twin().payload().mass, loss ? 0.0 : 0.15, 0.02) << all;
      // where the part's step raised an alert of its own at the motion's peak (pick, seed 961: 0.75 s
      // after the grip), that alert is the part: a payload change of its size, followed, and nothing
      // else (since session 40; before, read as "contact on link 6", it was held and the check took it)
      if (m.events().size() == 1 && m.events().front().fault == FaultClass::PayloadChange) {
        EXPECT_TRUE(noted_at.empty()) << all;
        EXPECT_NEAR(m.events().front().magnitude, loss ? -0.15 : 0.15, 0.03) << all;
        EXPECT_GE(m.events().front().t_start, 8.3) << all;
        EXPECT_LE(m.events().front().t_start, 8.3 + 2.5) << all;
        continue;
      }
      ASSERT_EQ(noted_at.size(), 1u) << all;
      // a second after the output change, or, past an alert the part raised itself, half a second later
      EXPECT_GE(noted_at[0], 9.3) << all;
      EXPECT_LE(noted_at[0], 10.81) << all;
      if (m.events().empty()) ++quiet_runs;
      for (const Event& e : m.events()) EXPECT_LT(e.t_start, noted_at[0]) << "nothing after the twin took the part: " << all;
    }
  EXPECT_GE(quiet_runs, 2);
  // the part's step read otherwise first (a 6 s figure-eight, seed 968): "contact on link 6" at the
  // grip, then "extra resistance on J3"; before session 29 the twin kept no payload and two
  // "contacts" followed at 13.1 s; sessions 29-39 held both until the check and dropped them as the
  // part's step. Since session 40 the grip's own alert reads as the payload change it is (+0.16 kg:
  // the contact's per-sample force no longer scores the noise it absorbs) and is followed: one
  // event, the part's, and nothing after it
  {
    const auto rec = undeclared(run("robot: ur3e\nseed: 968\nduration: 14\ntrajectory: {type: figure_eight, size: [0.12, 0.08], period: 6, "
                                    "tilt: [0.3, 0.4, 0.5]}\nfaults:\n" + part_change(false, 0.15, 8.3)));
    Monitor m(carrying(0.0), *config);
    for (const auto& s : rec.samples) m.push(s);
    m.finish();
    const std::string all = listing(m.events());
    ASSERT_EQ(m.events().size(), 1u) << all;
    EXPECT_EQ(m.events().front().fault, FaultClass::PayloadChange) << all;
    EXPECT_NEAR(m.events().front().magnitude, 0.15, 0.03) << all;
    EXPECT_GE(m.events().front().t_start, 8.3) << all;
    EXPECT_NEAR(m.twin().payload().mass, 0.15, 0.02) << all;
  }
  // the output toggled with no part: nothing taken
  for (const unsigned seed : {961u, 962u}) {
    auto toggled = run(scenario(seed, 14, 0.15));
    for (auto& s : toggled.samples)
      if (s.timestamp >= 8.3 && s.timestamp < 8.5) s.digital_outputs |= 1u;
    const auto plain = undeclared(toggled);
    Monitor quiet(carrying(0.15), *config);
    for (const auto& s : plain.samples) quiet.push(s);
    quiet.finish();
    EXPECT_TRUE(quiet.events().empty()) << listing(quiet.events());
    EXPECT_EQ(quiet.twin().payload().mass, 0.15) << fmt::format("{}", fmt::join(quiet.notes(), "\n"));
  }
}

// Session 29: a part gripped or released while the arm rests at a station. Static friction holds its
// step in part, so what the monitor read at the rest was a wrong size or a short "contact" (a 1 kg
// pick followed as +0.44 kg at the rest, a "contact on link 1" after it and +0.55 kg more when the
// arm moved on; a 0.6 kg drop: "contact on link 5, 12.8 N"), and a light part's alert came when the
// arm moved on, seconds after its output changed, too late to count it as evidence (0.3 kg: not
// followed, or an "extra resistance on J3"). Now an alert at the rest after the output changed is
// held until the arm has moved on, the output counts from there, and the payload check looks at the
// motion after the rest: one payload event per part (or, below the thresholds, a note), nothing else
TEST_F(MonitorLoop, APartGrippedOrReleasedAtARestIsSizedWhenTheArmMovesOn) {
  // pick-and-place with 1.5 s rests at the stations (a 9.4 s cycle)
  const std::string program = pick_and_place(0.8, 1.5, 1.6);
  const MonitorConfig c = with_program_thresholds(program, 2910, 28);
  struct Watched {
    std::vector<Event> events;
    std::vector<std::string> notes;
    double carried_between = -1.0;  // the twin's payload at 14 s, between the pick and the drop
    double carried_after = -1.0;
  };
  const auto watch = [&](const device::Recording& r) {
    Watched w;
    Monitor m(*twin, c);
    for (const auto& x : r.samples) {
      m.push(x);
      if (w.carried_between < 0.0 && x.timestamp >= 14.0) w.carried_between = m.twin().payload().mass;
    }
    m.finish();
    w.events = m.events();
    w.notes = m.notes();
    w.carried_after = m.twin().payload().mass;
    return w;
  };
  // the part gripped `into` s into the pick station's rest of the second cycle (10.2-11.7 s) and
  // released as far into the place station's (14.9-16.4 s); -0.25: just before the arm stops (a
  // 0.3 kg part released there was never taken: the check's window was mostly the rest)
  for (const double mass : {1.0, 0.6, 0.3})
    for (const double into : {0.05, 0.3, -0.25}) {
      const auto rec = undeclared(run(fmt::format("robot: ur3e\nseed: {}\nduration: 20\n", 2911 + static_cast<int>(10 * mass + 100 * into)) +
                                      program + "faults:\n" + part_change(false, mass, 10.2 + into) +
                                      part_change(true, mass, 14.9 + into)));
      const Watched w = watch(rec);
      const std::string all = fmt::format("{} kg, {} s into the rests:{}\nnotes: {}", mass, into, listing(w.events), fmt::join(w.notes, "\n"));
      for (const Event& e : w.events) EXPECT_EQ(e.fault, FaultClass::PayloadChange) << all;
      EXPECT_LE(w.events.size(), 2u) << "one payload event per part, at most" << all;
      // (a change just before the arm stops is followed on the little motion before the rest, and read
      // short, +0.46-0.72 kg for 0.6-1 kg parts: the check after the rest puts the twin right, with a note)
      for (const Event& e : w.events)
        if (into > 0.0) EXPECT_NEAR(std::abs(e.magnitude), mass, 0.2 * mass) << all;
        else EXPECT_GT(std::abs(e.magnitude), 0.5 * mass) << all;
      EXPECT_NEAR(w.carried_between, mass, 0.2 * mass) << all;
      EXPECT_NEAR(w.carried_after, 0.0, 0.05) << all;
    }
  // the output flipped at every rest with no part: no alert held, nothing taken, no event
  auto toggled = run("robot: ur3e\nseed: 2930\nduration: 24\n" + program);
  bool bit = false, flipped = false;
  double rest_since = -1.0;
  int flips = 0;
  for (auto& x : toggled.samples) {
    const bool rests = x.target_qd.cwiseAbs().maxCoeff() < 1e-3;
    if (!rests) rest_since = -1.0, flipped = false;
    else if (rest_since < 0.0) rest_since = x.timestamp;
    if (rests && !flipped && x.timestamp - rest_since >= 0.1) bit = !bit, flipped = true, ++flips;
    x.digital_outputs = bit ? 1u : 0u;
  }
  ASSERT_GE(flips, 4);
  const Watched quiet = watch(undeclared(toggled));
  EXPECT_TRUE(quiet.events.empty()) << listing(quiet.events);
  EXPECT_EQ(quiet.carried_after, 0.0) << fmt::format("{}", fmt::join(quiet.notes, "\n"));
  EXPECT_THAT(quiet.notes, ::testing::Not(::testing::Contains(::testing::HasSubstr("is held"))));
}

// Session 29 review: an alert held at a rest is never lost. A contact at a rest right after a gripper
// output changed with no part is held with the part's steps; no payload change shows when the arm
// moves on, so it is reported then, as it was read, with its own start; one near the end of a run
// whose arm never moves on again is reported when monitoring stops
TEST_F(MonitorLoop, AContactHeldAtARestIsReportedWhenNoPartShows) {
  const std::string program = pick_and_place(0.8, 1.5, 1.6);
  const MonitorConfig c = with_program_thresholds(program, 2910, 28);
  // the output flipped 0.1 s into the pick station's rest (10.2-11.7 s), a 6 N·m contact on link 3
  // 0.1 s later; the run ends at 10.9 s (still at the rest) or goes on to 16 s
  for (const double end : {16.0, 10.9}) {
    auto rec = run(fmt::format("robot: ur3e\nseed: 2940\nduration: {}\n", end) + program +
                   "faults:\n  - {type: collision, link: 3, onset: 10.4, magnitude: 6, duration: 0.05, point: [-0.1, 0.0, 0.03], "
                   "direction: [0.3, 1.0, -0.2]}\n");
    for (auto& x : rec.samples) x.digital_outputs = x.timestamp >= 10.3 ? 1u : 0u;
    const auto plain = undeclared(rec);
    Monitor m(*twin, c);
    double reported_at = -1.0;
    double t = 0.0;
    m.on_event = [&](const Event& e) {
      if (!e.open && e.fault == FaultClass::Collision) reported_at = t;
    };
    for (const auto& x : plain.samples) {
      t = x.timestamp;
      m.push(x);
    }
    m.finish();
    const std::string all = fmt::format("run to {} s:{}\nnotes: {}", end, listing(m.events()), fmt::join(m.notes(), "\n"));
    ASSERT_EQ(m.events().size(), 1u) << all;
    const Event& e = m.events()[0];
    EXPECT_EQ(e.fault, FaultClass::Collision) << all;
    EXPECT_NEAR(e.t_start, 10.4, 0.03) << all;
    EXPECT_THAT(m.notes(), ::testing::Contains(::testing::HasSubstr("It is held, and reported only if no payload change shows"))) << all;
    if (end > 12.0) {
      // held past the move on (11.7 s) until the check a second later
      EXPECT_THAT(e.detail, ::testing::HasSubstr("held, and reported at")) << all;
      EXPECT_GT(reported_at, 12.6) << all;
      EXPECT_FALSE(e.active_at_stop) << all;
    } else {
      EXPECT_THAT(e.detail, ::testing::HasSubstr("monitoring stopped before the arm moved on")) << all;
      EXPECT_TRUE(e.active_at_stop) << all;
    }
    EXPECT_EQ(m.twin().payload().mass, 0.0) << all;
  }
}

// Session 29: a part's step read at its grip as a contact where the part hangs, whose alert stood
// past its first look (a 0.45 kg pick 0.2 s before the arm stops: "contact on link 5, 6.9 N; link 6
// is also possible", 16 ms after the output changed), is held until the payload check and dropped
// when the part it could be the weight of is taken; a contact on the last links later stays an event
TEST_F(MonitorLoop, APartsStepReadAtItsGripAsAContactIsNotAnEvent) {
  const std::string program = pick_and_place(0.8, 1.0, 1.6);
  const MonitorConfig c = with_program_thresholds(program, 2950, 24);
  int grips_held = 0;
  for (const double mass : {0.45, 0.8})
    for (const unsigned seed : {2951u, 2952u, 2953u}) {
      // (picked at 9.0 s, 0.2 s before the arm stops at the pick station; released 0.2 s before it
      // stops at the place station, 13.2 s)
      const auto rec = undeclared(run(fmt::format("robot: ur3e\nseed: {}\nduration: 16\n", seed) + program + "faults:\n" +
                                      part_change(false, mass, 9.0) + part_change(true, mass, 13.2)));
      Monitor m(*twin, c);
      for (const auto& x : rec.samples) m.push(x);
      m.finish();
      const std::string all = fmt::format("{} kg, seed {}:{}\nnotes: {}", mass, seed, listing(m.events()), fmt::join(m.notes(), "\n"));
      for (const Event& e : m.events()) EXPECT_EQ(e.fault, FaultClass::PayloadChange) << all;
      for (const std::string& n : m.notes()) grips_held += n.find("is held until the payload check") != std::string::npos;
      EXPECT_NEAR(m.twin().payload().mass, 0.0, 0.05) << all;
    }
  EXPECT_GE(grips_held, 1);
  // a hard contact where the part hangs while the pick's check is still due (it waits for the alert
  // the part raises when the arm moves on, 10.2 s): more than the part's weight could make, an event
  const auto hit = undeclared(run("robot: ur3e\nseed: 2951\nduration: 16\n" + program + "faults:\n" + part_change(false, 0.45, 9.0) +
                                  "  - {type: collision, link: 6, onset: 11.5, magnitude: 10, duration: 0.05, point: [0.0, 0.02, 0.03], "
                                  "direction: [0.3, 1.0, -0.2]}\n"));
  Monitor m(*twin, c);
  for (const auto& x : hit.samples) m.push(x);
  m.finish();
  const auto contacts = std::count_if(m.events().begin(), m.events().end(), [](const Event& e) {
    return e.fault == FaultClass::Collision && std::abs(e.t_start - 11.5) < 0.05;
  });
  EXPECT_EQ(contacts, 1) << listing(m.events()) << "\nnotes: " << fmt::format("{}", fmt::join(m.notes(), "\n"));
}

// Session 30: an arm the controller does not drive. Under a protective stop, powered off on its brakes
// after an emergency stop, or idle before its brakes are released, the twin's prediction (a driven
// arm) is not what the arm draws: judged, the power-off read as a payload change of -1.6 kg and the
// brake release as a 47 N contact. The stream says it (robot_mode, safety_mode): nothing is judged
// then, what was open is closed with what was seen, and after the stop the monitor starts again as
// after a stream gap.
TEST_F(MonitorLoop, AnArmTheControllerDoesNotDriveIsNotJudged) {
  const std::string program = pick_and_place(0.8, 1.0, 1.6);
  const MonitorConfig c = with_program_thresholds(program, 3101, 30);
  const std::string stops = "stops:\n  - {kind: protective, at: 6.3, hold: 3}\n  - {kind: emergency, at: 15.2, hold: 6}\n";
  const std::string contact = "  - {type: collision, link: 2, onset: 25.7, magnitude: 10, duration: 0.05, point: [-0.12, 0.0, 0.1], "
                              "direction: [0.3, 1.0, -0.2]}\n";
  const auto rec = run("robot: ur3e\nseed: 3102\nduration: 30\n" + program + stops + "faults:\n" + contact);
  const auto watch = [&](const device::Recording& r, std::vector<std::string>* notes) {
    Monitor m(*twin, c);
    for (const auto& s : r.samples) m.push(s);
    m.finish();
    if (notes) *notes = m.notes();
    return m.events();
  };
  std::vector<std::string> notes;
  const auto ev = watch(rec, &notes);
  ASSERT_EQ(ev.size(), 1u) << listing(ev);
  EXPECT_EQ(ev[0].fault, FaultClass::Collision) << listing(ev);
  EXPECT_LT(ev[0].t_detected - 25.7, 0.03) << "a contact after the stops is found as before";
  std::string all;
  for (const auto& n : notes) all += n + "\n";
  EXPECT_THAT(all, ::testing::HasSubstr("monitoring paused, the controller reports protective stop (safety_mode 3)"));
  EXPECT_THAT(all, ::testing::HasSubstr("robot emergency stop (safety_mode 7), power off (robot_mode 3)"));
  EXPECT_THAT(all, ::testing::HasSubstr("idle (brakes on) (robot_mode 5)"));
  EXPECT_THAT(all, ::testing::HasSubstr("monitoring resumed: the controller drives the arm again, 5.0 s after it stopped at 15.2"));
  // the same stream without its modes (a recording or a foreign log without them): the stopped arm
  // is judged and cries wolf. The modes are what keeps it quiet
  auto blind = rec;
  for (auto& s : blind.samples) s.present &= ~(kFieldRobotMode | kFieldSafetyMode);
  EXPECT_GT(watch(blind, nullptr).size(), 1u);
  // a stream that starts stopped (brakes on) with a gripper output already set: the first driven
  // sample is no output change (review of session 30), and nothing is judged before it
  auto late = rec;
  for (auto& s : late.samples) s.digital_outputs = 1;
  for (size_t k = 0; k < 1000; ++k) late.samples[k].robot_mode = 5;
  std::vector<std::string> late_notes;
  const auto late_ev = watch(late, &late_notes);
  ASSERT_EQ(late_ev.size(), 1u) << listing(late_ev);
  for (const auto& n : late_notes) EXPECT_THAT(n, ::testing::Not(::testing::HasSubstr("output changed"))) << n;
}

// A contact that makes the controller stop the arm (its own collision detection) is reported with what
// was seen before the stop, and says that the stop cut it short.
TEST_F(MonitorLoop, AContactTheControllerStoppedTheArmForIsReported) {
  const std::string program = pick_and_place(0.8, 1.0, 1.6);
  const MonitorConfig c = with_program_thresholds(program, 3101, 30);
  const auto rec = run("robot: ur3e\nseed: 3103\nduration: 16\n" + program +
                       "stops:\n  - {kind: protective, at: 11.34, hold: 3}\nfaults:\n"
                       "  - {type: collision, link: 3, onset: 11.3, magnitude: 10, duration: 0.3, point: [0.1, 0.0, 0.05], "
                       "direction: [0.0, 0.3, 1.0]}\n");
  Monitor m(*twin, c);
  for (const auto& s : rec.samples) m.push(s);
  m.finish();
  const auto& ev = m.events();
  ASSERT_EQ(ev.size(), 1u) << listing(ev);
  EXPECT_EQ(ev[0].fault, FaultClass::Collision) << listing(ev);
  EXPECT_LT(ev[0].t_detected - 11.3, 0.04);
  EXPECT_TRUE(ev[0].active_at_stop);
  EXPECT_THAT(ev[0].detail, ::testing::HasSubstr("still active when the controller stopped driving the arm at 11.34"));
}

// Session 30: the operator pauses a program that never rests (the figure-eight). Its thresholds were
// learned on motion only, and a held arm's drives switch between motoring and back-driven current as
// the joints creep under gravity: every pause of the stop set raised a false contact. A rest longer
// than the thresholds saw (MonitorConfig::longest_rest) is judged with the levels of the twin's
// program sets that saw long rests; with none, the monitor says so once.
// a 5 N·m contact on link 3 at 8.6 s, during the first of `pauses`, watched by `watch(scenario text)`:
// one event, a contact, found within 30 ms
template <class Watch>
void expect_contact_found_during_a_pause(Watch watch, const std::string& pauses) {
  const auto hit = watch(scenario(3113, 30, 0.5,
                                  "  - {type: collision, link: 3, onset: 8.6, magnitude: 5, duration: 0.05, point: [0.1, 0.0, 0.05], "
                                  "direction: [0.0, 0.3, 1.0]}\n") +
                         pauses);
  ASSERT_EQ(hit.size(), 1u) << listing(hit);
  EXPECT_EQ(hit[0].fault, FaultClass::Collision) << listing(hit);
  EXPECT_LT(hit[0].t_detected - 8.6, 0.03);
}

TEST_F(MonitorLoop, APauseOnAProgramThatNeverRestsIsJudgedWithTheRestTestedThresholds) {
  MonitorConfig c = *config;
  ASSERT_TRUE(std::isfinite(c.longest_rest));
  EXPECT_LT(c.longest_rest, Monitor::kMinDonorRest) << "the figure-eight never rests";
  const auto rests = run("robot: ur3e\nseed: 3111\nduration: 30\n" + pick_and_place(0.8, 1.0, 1.6));
  learn_program_thresholds(c, "pick_place", *twin, {{&rests, {}}});
  EXPECT_GT(c.programs["pick_place"].longest_rest, 0.9) << "a pick-and-place rests 1 s at each station";
  EXPECT_LT(c.programs["pick_place"].longest_rest, 1.05);  // (and the few ms its moves start and end at rest)
  // (the JSON keeps it)
  EXPECT_EQ(MonitorConfig::from_json(c.to_json(), "t", 6).programs["pick_place"].longest_rest, c.programs["pick_place"].longest_rest);
  EXPECT_EQ(MonitorConfig::from_json(c.to_json(), "t", 6).longest_rest, c.longest_rest);
  const std::string pauses = "stops:\n  - {kind: pause, at: 7.3, hold: 3}\n  - {kind: pause, at: 17.9, hold: 2.5}\n";
  const auto watch = [&](const MonitorConfig& cfg, const std::string& yaml, std::vector<std::string>* notes) {
    Monitor m(declared_twin(), cfg);
    for (const auto& x : run(yaml).samples) m.push(x);
    m.finish();
    if (notes) *notes = m.notes();
    return m.events();
  };
  const std::string paused = scenario(3112, 30, 0.5) + pauses;
  EXPECT_TRUE(watch(c, paused, nullptr).empty()) << listing(watch(c, paused, nullptr));
  // without a set that rested, the pauses are judged with the figure-eight's thresholds, and said
  std::vector<std::string> notes;
  const auto alone = watch(*config, paused, &notes);
  EXPECT_FALSE(alone.empty()) << "the figure-eight's thresholds at a pause";
  EXPECT_THAT(fmt::format("{}", fmt::join(notes, "\n")), ::testing::HasSubstr("longer than in any run the thresholds in use were learned on"));
  // a contact while the arm is paused is still found, as a contact
  expect_contact_found_during_a_pause([&](const std::string& yaml) { return watch(c, yaml, nullptr); }, pauses);
}

// The same on a log without the controller's targets (session 33): there the rest is the arm
// measured still (every |qd| below RestBaseline::kMeasuredRest), learned and watched alike. Before,
// such thresholds recorded no rest and every pause was judged with the figure-eight's levels: 35
// false events in the 0.45 h of the stop set without targets, 1 now (docs/validation.md).
TEST_F(MonitorLoop, APauseOnAStreamWithoutTargetsIsJudgedWithTheRestTestedThresholds) {
  const std::string bare = kNoTargets;
  ASSERT_FALSE(run(scenario(503, 1, 0.5) + bare).present & kFieldTargetQd);
  MonitorConfig c = config_without_targets();
  ASSERT_TRUE(std::isfinite(c.longest_rest));
  EXPECT_LT(c.longest_rest, Monitor::kMinDonorRest) << "the figure-eight never rests";
  const auto rests = run("robot: ur3e\nseed: 3111\nduration: 30\n" + pick_and_place(0.8, 1.0, 1.6) + bare);
  learn_program_thresholds(c, "pick_place", *twin, {{&rests, {}}});
  // (a pick-and-place rests 1 s at each station; measured, a little longer: the joints are below 3
  // counts a period in the last ms of the move into it and the first of the move out: 1.064 s)
  EXPECT_GT(c.programs["pick_place"].longest_rest, 0.95);
  EXPECT_LT(c.programs["pick_place"].longest_rest, 1.1);
  const std::string pauses = "stops:\n  - {kind: pause, at: 7.3, hold: 3}\n  - {kind: pause, at: 17.9, hold: 2.5}\n";
  const auto watch = [&](const MonitorConfig& cfg, const std::string& yaml) {
    Monitor m(declared_twin(), cfg);
    for (const auto& x : run(yaml).samples) m.push(x);
    m.finish();
    return m.events();
  };
  const std::string paused = scenario(3112, 30, 0.5) + pauses + bare;
  const auto events = watch(c, paused);
  EXPECT_TRUE(events.empty()) << listing(events);
  // the rule alone (without the drive's doubt read on the current, which at these pauses also holds
  // the resting joints on a level): none; without the rests recorded either (thresholds learned on
  // such logs before session 33), the pauses are judged with the figure-eight's levels
  MonitorConfig rule_alone = c;
  rule_alone.drive_doubt = false;
  const auto alone = watch(rule_alone, paused);
  EXPECT_TRUE(alone.empty()) << listing(alone);
  MonitorConfig unrecorded = rule_alone;
  unrecorded.longest_rest = std::numeric_limits<double>::quiet_NaN();
  for (auto& [name, set] : unrecorded.programs) set.longest_rest = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(watch(unrecorded, paused).empty()) << "the figure-eight's thresholds at a pause";
  // a contact while the arm is paused is still found, as a contact
  expect_contact_found_during_a_pause([&](const std::string& yaml) { return watch(c, yaml); }, pauses + bare);
}

// On a log without the controller's targets nothing times the drive's switch at a slow reversal:
// the measured velocity reads 0 or a count for 0.1-1.9 s around it (the slow sets), while the
// drive steps between its levels. Session 33 reads the direction's doubt there on the current too,
// with the measured velocity's blend (TwinModel::advance). On the slow sets without targets 37 false
// contacts went (docs/validation.md); here the figure-eight at twice its thresholds' period with
// 0.5 kg comes within 1 % of an alarm at the elbow's reversals with the blend, and stays below 0.6.
TEST_F(MonitorLoop, ASlowReversalOnAStreamWithoutTargetsIsReadOnTheCurrent) {
  const std::string bare = kNoTargets;
  const MonitorConfig& c = config_without_targets();
  const auto slow = run("robot: ur3e\nseed: 3131\nduration: 80\ntrajectory: {type: figure_eight, size: [0.12, 0.08], period: 16, "
                        "tilt: [0.3, 0.4, 0.5]}\npayload: {mass: 0.5, com: [0, 0, 0.04]}\n" + bare);
  const auto watch = [&](const MonitorConfig& cfg) {
    auto m = std::make_unique<Monitor>(declared_twin(), cfg);
    m->track_margin();
    for (const auto& x : slow.samples) m->push(x);
    m->finish();
    return m;
  };
  MonitorConfig blended = c;
  blended.drive_doubt = false;
  const auto before = watch(blended), now = watch(c);
  // the largest |residual| / threshold a debounce run exceeded, per joint (1: an alarm). Measured:
  // J3, the elbow, reversing under the arm's weight, 0.94 / 0.99 (current / observer) with the
  // blend, 0.59 / 0.58 read on the current; the joints that never reverse slowly are unchanged
  const auto peak = [](const Monitor& m) { return std::max(m.margin_current().maxCoeff(), m.margin_observer().maxCoeff()); };
  EXPECT_GT(peak(*before), 0.9) << "the case: the blend between the levels at the slow reversals, " << before->margin_current().transpose()
                                << " / " << before->margin_observer().transpose();
  EXPECT_LT(peak(*now), 0.75) << now->margin_current().transpose() << " / " << now->margin_observer().transpose();
  EXPECT_LT(now->margin_current()[2], 0.7 * before->margin_current()[2]);
  EXPECT_LT(now->margin_observer()[2], 0.7 * before->margin_observer()[2]);
  EXPECT_EQ(now->margin_current()[0], before->margin_current()[0]) << "J1 reverses fast";
  EXPECT_TRUE(now->events().empty()) << listing(now->events());
}

// Session 30: a program run slower than its thresholds were learned at (the speed slider at a fifth):
// J2 crawls through its reversals under gravity for longer than any crawl the thresholds saw, and the
// drive's motoring/back-driven step shows for as long; judged with the learned levels it read as
// contacts. Beyond the longest crawl the thresholds saw (MonitorConfig::crawl_max) the joint's
// thresholds widen by the whole step.
TEST_F(MonitorLoop, AJointCrawlingLongerThanTheThresholdsSawIsNotAFault) {
  ASSERT_EQ(config->crawl_max.size(), 6);
  const std::string slow = "robot: ur3e\nseed: 3121\nduration: 80\ntrajectory: {type: figure_eight, size: [0.12, 0.08], period: 40, "
                           "tilt: [0.3, 0.4, 0.5]}\npayload: {mass: 0.5, com: [0, 0, 0.04]}\n";
  const auto rec = run(slow);
  const auto watch = [&](const MonitorConfig& c) {
    Monitor m(declared_twin(), c);
    for (const auto& x : rec.samples) m.push(x);
    m.finish();
    return m.events();
  };
  // (the reversals' alerts; a 2 ms "unknown" at 2.3 s, in the first slow start of the run, is not
  // one of them and stays either way)
  const auto after = [](const std::vector<Event>& ev) {
    std::vector<Event> out;
    for (const auto& e : ev)
      if (e.t_start > 5.0) out.push_back(e);
    return out;
  };
  EXPECT_TRUE(after(watch(*config)).empty()) << listing(watch(*config));
  MonitorConfig before = *config;
  before.crawl_max.resize(0);
  // Without the crawl widening this run raised 2 or more false contacts at its slow reversals until
  // session 31; since session 32 the drive's direction in doubt there is read on the current
  // (resolve_drive_doubt), and the learned levels alone keep it clean too: the two remedies overlap
  // on a stream that carries the controller's targets (docs/validation.md, session 32)
  EXPECT_TRUE(after(watch(before)).empty()) << "the learned levels alone at the slow reversals" << listing(watch(before));
  // (the JSON keeps it)
  EXPECT_EQ(MonitorConfig::from_json(config->to_json(), "t", 6).crawl_max, config->crawl_max);
  // a contact at the slow motion is still found
  const auto hit = run(slow + "faults:\n  - {type: collision, link: 3, onset: 31.0, magnitude: 5, duration: 0.05, point: [0.1, 0.0, 0.05], "
                              "direction: [0.0, 0.3, 1.0]}\n");
  Monitor m(declared_twin(), *config);
  for (const auto& x : hit.samples) m.push(x);
  m.finish();
  const auto found = after(m.events());
  ASSERT_EQ(found.size(), 1u) << listing(m.events());
  EXPECT_EQ(found[0].fault, FaultClass::Collision);
  EXPECT_LT(found[0].t_detected - 31.0, 0.03);
}

// A joint temperature no joint reads (a 0xFFFF/10 overflow, 6553.5 °C) went into the residual's
// temperature compensation: one such sample raised "contact on link 3, ≈ 40 N, 82 %" (session 34
// audit). It is a sensor fault of that channel now: one event however long it lasts, and the samples
// are judged with the joint's last plausible reading, so every residual stays where the clean run's is.
TEST_F(MonitorLoop, AnImplausibleTemperatureIsASensorFaultNotAContact) {
  const auto clean = run(scenario(3141, 12, 0.5));
  auto glitch = clean;
  ASSERT_TRUE(glitch.present & kFieldTemperature);
  for (size_t k = 3000; k < 3003; ++k) glitch.samples[k].temperature[2] = 6553.5;  // J3, three samples at 6 s
  glitch.samples[4000].temperature[4] = -300.0;                                    // J5, once at 8 s
  const auto watch = [&](const device::Recording& rec) {
    auto m = std::make_unique<Monitor>(declared_twin(), *config);
    m->track_margin();
    for (const auto& x : rec.samples) m->push(x);
    m->finish();
    return m;
  };
  const auto a = watch(clean), b = watch(glitch);
  std::vector<Event> faults, others;
  for (const auto& e : b->events()) (e.fault == FaultClass::SensorFault ? faults : others).push_back(e);
  ASSERT_EQ(faults.size(), 2u) << listing(b->events());
  EXPECT_EQ(faults[0].joint, 2);
  EXPECT_EQ(faults[0].magnitude, 6553.5);
  EXPECT_EQ(faults[0].units, "°C");
  EXPECT_EQ(faults[0].t_start, glitch.samples[3000].timestamp);
  EXPECT_THAT(faults[0].detail, ::testing::HasSubstr("judged with its last plausible reading"));
  EXPECT_EQ(faults[1].joint, 4);
  EXPECT_EQ(faults[1].t_start, glitch.samples[4000].timestamp);
  EXPECT_EQ(others.size(), a->events().size()) << listing(b->events());
  // the held reading is the previous sample's, which the clean run's differs from by at most its
  // 0.1 °C resolution: the residuals' margins are the clean run's to well within a percent
  for (int j = 0; j < 6; ++j) {
    EXPECT_NEAR(b->margin_current()[j], a->margin_current()[j], 0.01 * a->margin_current()[j]) << "J" << j + 1;
    EXPECT_NEAR(b->margin_observer()[j], a->margin_observer()[j], 0.01 * a->margin_observer()[j]) << "J" << j + 1;
  }
}

// The learners hold an implausible temperature in a training recording as the monitor holds it in a
// stream: one 6553.5 °C sample went into the temperature compensation of every residual learned on,
// and the thresholds with it. Learned on a run with such readings (and an infinite one, which the
// monitor's check took for a reading until session 35), the levels are the clean run's.
TEST_F(MonitorLoop, ImplausibleTemperaturesInATrainingRunAreHeldAsTheMonitorHoldsThem) {
  const auto h1 = run(scenario(503, 24, 0.5));
  auto glitch = h1;
  ASSERT_TRUE(glitch.present & kFieldTemperature);
  for (size_t k = 3000; k < 3003; ++k) glitch.samples[k].temperature[2] = 6553.5;
  glitch.samples[5000].temperature[4] = -300.0;
  glitch.samples[6000].temperature[1] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(implausible_temperatures(glitch), 5u);
  EXPECT_EQ(implausible_temperatures(h1), 0u);
  const auto held = hold_implausible_temperatures(glitch);
  EXPECT_EQ(implausible_temperatures(held), 0u);
  EXPECT_EQ(held.samples[3002].temperature[2], glitch.samples[2999].temperature[2]) << "the joint's last plausible reading";
  EXPECT_EQ(held.samples[6000].temperature[1], glitch.samples[5999].temperature[1]);
  // a trend temperature slope on a compensated twin: the compensation is what a glitch reaches
  MonitorConfig settings = *config;
  settings.trend.temperature_slope = Eigen::VectorXd::Constant(6, -2e-3);
  settings.trend.temperature_ref = twin->temperature_ref;
  const auto a = learn_thresholds(declared_twin(), {{&h1, payload}}, settings);
  const auto b = learn_thresholds(declared_twin(), {{&glitch, payload}}, settings);
  for (int j = 0; j < 6; ++j) {
    EXPECT_NEAR(b.static_level[j], a.static_level[j], 0.01 * a.static_level[j]) << "J" << j + 1;
    EXPECT_NEAR(b.observer_level[j], a.observer_level[j], 0.01 * a.observer_level[j]) << "J" << j + 1;
  }
  // and the 1 % above can see a temperature reach the levels: the same samples read wrong but within
  // the plausible range (taken as readings, not held) move J3's static level by 1.5 % (session 51)
  auto wrong = h1;
  for (size_t k = 3000; k < 3003; ++k) wrong.samples[k].temperature[2] = kTemperatureMax - 1.0;
  const auto c = learn_thresholds(declared_twin(), {{&wrong, payload}}, settings);
  EXPECT_GT(std::abs(c.static_level[2] - a.static_level[2]), 0.01 * a.static_level[2]);
  // a run whose every sample is the filter's start-up says which run and why
  device::Recording stub = h1;
  stub.samples.resize(3);
  stub.path = "two_rows.csv";
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { learn_thresholds(declared_twin(), {{&stub, payload}}, settings); }),
              ::testing::HasSubstr("two_rows.csv (3 samples)"));
}

// `twinwatch thresholds` hands the learners each recording as FileSamples, read again on every pass
// and never held (a shift of healthy recordings is 1.7 GB per robot hour at 500 Hz). Learned so from
// a file with a stop in it (two driven stretches) and implausible temperatures, the thresholds, the
// observer's debounce and the temperature slope are the ones learned on the same runs held, to the
// bit; a file rewritten between two passes is refused by name.
TEST_F(MonitorLoop, ThresholdsLearnedFromFilesReadAgainAreTheOnesLearnedFromTheHeldRuns) {
  auto rec = run(scenario(503, 24, 0.5));
  ASSERT_TRUE(rec.present & kFieldRobotMode);
  for (size_t k = 5000; k < 5400; ++k) rec.samples[k].robot_mode = 5;  // a stop: the arm not driven
  for (size_t k = 3000; k < 3003; ++k) rec.samples[k].temperature[2] = 6553.5;
  const std::string path = (std::filesystem::temp_directory_path() / fmt::format("twinwatch_file_samples_{}.csv", ::getpid())).string();
  const auto write = [&](const device::Recording& r) {
    device::RecordingWriter w(path, 6, r.present);
    for (const auto& s : r.samples) w.write(s);
    w.close();
  };
  write(rec);
  const std::vector<device::Recording> held = device::driven_segments(device::read_recording(path), 1.0, nullptr);
  ASSERT_EQ(held.size(), 2u);
  device::RecordingReader reader(path);
  device::DrivenStretches driven(1.0);
  const device::RecordingScan scan = device::scan_rows(reader, [&](const RobotSample& s) { driven.see(s); });
  driven.finish();
  ASSERT_EQ(driven.used().size(), 2u);
  const std::vector<std::unique_ptr<device::FileSamples>> files = device::FileSamples::of(path, nullptr, scan, driven);
  std::vector<HealthyRun> held_runs, file_runs;
  std::vector<TrendRun> held_trend, file_trend;
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(files[i]->size(), held[i].samples.size());
    EXPECT_EQ(files[i]->seconds(), held[i].samples.back().timestamp - held[i].samples.front().timestamp);
    held_runs.push_back({&held[i], payload});
    file_runs.push_back({nullptr, payload, files[i].get()});
    held_trend.push_back({&held[i], payload});
    file_trend.push_back({nullptr, payload, 0, files[i].get()});
  }
  MonitorConfig settings = *config;
  settings.trend.temperature_slope = Eigen::VectorXd::Constant(6, -2e-3);
  settings.trend.temperature_ref = twin->temperature_ref;
  const MonitorConfig a = learn_thresholds(*twin, held_runs, settings), b = learn_thresholds(*twin, file_runs, settings);
  EXPECT_EQ(a.to_json(), b.to_json());
  const ObserverDebounceChoice da = choose_observer_debounce(*twin, a, held_runs), db = choose_observer_debounce(*twin, b, file_runs);
  EXPECT_EQ(da.raise_after, db.raise_after);
  EXPECT_EQ(da.seconds, db.seconds);
  ASSERT_EQ(da.ratio.size(), db.ratio.size());
  for (size_t d = 0; d < da.ratio.size(); ++d) EXPECT_EQ(da.ratio[d], db.ratio[d]) << "debounce " << d + 1;
  // (24 s may span too little temperature for a slope: then the same refusal)
  const auto slope = [&](const std::vector<TrendRun>& runs) {
    try {
      const TrendConfig t = learn_trend_temperature(*twin, runs);
      std::string out;
      for (int j = 0; j < 6; ++j) out += fmt::format("{:.17g} ", t.temperature_slope[j]);
      return out;
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
  };
  EXPECT_EQ(slope(held_trend), slope(file_trend));
  // the stretches share the file's reading: read in order, a pass reads it once; a stretch read
  // again (the second before the first) opens it again and hands the same samples
  std::vector<double> second, again;
  files[1]->replay([&](size_t, const RobotSample& s) { second.push_back(s.current[1]); });
  files[0]->replay([](size_t, const RobotSample&) {});
  files[1]->replay([&](size_t, const RobotSample& s) { again.push_back(s.current[1]); });
  EXPECT_EQ(second, again);
  EXPECT_EQ(second.size(), held[1].samples.size());
  // rewritten between two passes (as many rows): refused by name once the pass reads to the end
  rec.samples[100].current[1] += 0.5;
  write(rec);
  EXPECT_THAT(twinwatch::test::error_text<std::runtime_error>([&] {
                files[0]->replay([](size_t, const RobotSample&) {});
                files[1]->replay([](size_t, const RobotSample&) {});
              }),
              ::testing::AllOf(::testing::HasSubstr(path), ::testing::HasSubstr("its rows changed while it was read")));
  // cut: refused by name
  rec.samples.resize(8000);
  write(rec);
  EXPECT_THAT(twinwatch::test::error_text<std::runtime_error>([&] { files[1]->replay([](size_t, const RobotSample&) {}); }),
              ::testing::AllOf(::testing::HasSubstr(path), ::testing::HasSubstr("8000 of the 12000 rows checked")));
  std::filesystem::remove(path);
}

// A current reading that jumps and is back at the next sample (an electrical spike, a corrupted
// sample) read as "contact on link 3, ≈ 361 N, 100 %" for one 20 A sample on J3 (session-34 audit).
// No contact shows so: the drive's current answers an external torque through the joint's motion and
// its controller, over tens of ms. It is a sensor fault of that channel now, sized in A; a real blow
// as short as two samples is still a contact.
TEST_F(MonitorLoop, AOneSampleCurrentSpikeIsASensorFaultNotAContact) {
  const auto clean = run(scenario(3151, 12, 0.5));
  auto glitch = clean;
  glitch.samples[1500].current[2] = 20.0;                                  // J3, once at 3 s
  glitch.samples[3000].current[1] += 4.0;                                  // J2, +4 A at 6 s
  glitch.samples[4500].current[4] -= 3.0;                                  // J5, two samples at 9 s
  glitch.samples[4501].current[4] -= 3.0;
  const auto a = monitor(clean, 0.5), b = monitor(glitch, 0.5);
  std::vector<Event> faults, others;
  for (const auto& e : b) (e.fault == FaultClass::SensorFault ? faults : others).push_back(e);
  ASSERT_EQ(faults.size(), 3u) << listing(b);
  const int joints[] = {2, 1, 4};
  const size_t at[] = {1500, 3000, 4500};
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(faults[i].joint, joints[i]) << listing(b);
    EXPECT_EQ(faults[i].units, "A");
    EXPECT_LE(faults[i].t_start, glitch.samples[at[i]].timestamp);
    const double read = faults[i].magnitude;  // the reading itself (of a two-sample glitch, the one further out)
    EXPECT_TRUE(read == glitch.samples[at[i]].current[joints[i]] || read == glitch.samples[at[i] + 1].current[joints[i]]) << read;
    EXPECT_THAT(faults[i].detail, ::testing::HasSubstr("glitch on the J" + std::to_string(joints[i] + 1) + " current channel"));
  }
  EXPECT_EQ(others.size(), a.size()) << listing(b);
  // a blow of two samples (4 ms) is a contact: the joint moves, and the controller's answer lasts
  const auto hit = run(scenario(3151, 12, 0.5, "  - {type: collision, link: 3, onset: 6.0, magnitude: 40, duration: 0.004, "
                                                "point: [0.1, 0.0, 0.05], direction: [0.0, 0.3, 1.0]}\n"));
  const auto found = monitor(hit, 0.5);
  const auto contact = std::find_if(found.begin(), found.end(), [](const Event& e) { return std::abs(e.t_start - 6.0) < 0.1; });
  ASSERT_NE(contact, found.end()) << listing(found);
  EXPECT_EQ(contact->fault, FaultClass::Collision) << listing(found);
}

// A protective stop's resume on a stream without the controller's targets: the resumed program's ramp
// steps the acceleration, which the encoders show samples late, and the residual overshoots for a few
// samples. On the target-less stop sets this raised a false contact in 6 of 144 runs (session 35). The
// first MonitorConfig::resume_widen window of motion after a powered resume is judged against wider
// thresholds; a real contact in it is still found.
TEST_F(MonitorLoop, AProtectiveStopsResumeWithoutTargetsIsNoContact) {
  const std::string p2p = "{type: point_to_point, waypoints: [[-0.6, -1.4, 1.3, -1.5, -1.3, 0.3], [-0.6, -1.2, 1.45, -1.8, -1.3, 0.3], "
                          "[-0.6, -1.2, 1.45, -1.8, -1.3, 0.3], [-0.6, -1.4, 1.3, -1.5, -1.3, 0.3], [0.6, -1.4, 1.3, -1.5, -1.85, -0.3], "
                          "[0.6, -1.2, 1.45, -1.8, -1.85, -0.3], [0.6, -1.2, 1.45, -1.8, -1.85, -0.3], [0.6, -1.4, 1.3, -1.5, -1.85, -0.3]], "
                          "durations: [0.8, 0.4, 0.8, 1.6, 0.8, 0.4, 0.8, 1.6]}";
  const auto pick = [&](unsigned seed, double duration, const std::string& extra) {
    return run("robot: ur3e\nseed: " + std::to_string(seed) + "\nduration: " + std::to_string(duration) + "\ntrajectory: " + p2p +
               "\npayload: {mass: 0.5, com: [0, 0, 0.04]}\nstreams_targets: false\n" + extra);
  };
  // thresholds learned on the program's target-less healthy runs
  const auto h1 = pick(601, 30, ""), h2 = pick(602, 20, "");
  ASSERT_FALSE(h1.present & kFieldTargetQdd);
  const MonitorConfig learned = learn_thresholds(*twin, {{&h1, payload}, {&h2, payload}});
  // the case, found among 20 such runs: the program resumes at 8.62 s with a 0.15 s ramp
  const double resume = 8.62;
  const std::string stop = "stops:\n  - {kind: protective, at: 6.12, hold: 2.5, stopping_time: 0.15}\n";
  const auto watch = [&](const device::Recording& rec, double widen) {
    MonitorConfig c = learned;
    c.resume_widen = widen;
    auto m = std::make_unique<Monitor>(declared_twin(), c);
    for (const auto& x : rec.samples) m->push(x);
    m->finish();
    return m;
  };
  const auto rec = pick(9104, 12, stop);
  const auto before = watch(rec, 1.0);
  ASSERT_EQ(before->events().size(), 1u) << "the case: a false contact on the resume ramp" << listing(before->events());
  EXPECT_GE(before->events()[0].t_start, resume - 0.01);
  EXPECT_LE(before->events()[0].t_start, resume + 0.25);
  const auto now = watch(rec, MonitorConfig{}.resume_widen);
  EXPECT_TRUE(now->events().empty()) << listing(now->events());
  bool said = false;
  for (const auto& n : now->notes()) said |= n.find("2 times as wide") != std::string::npos;
  EXPECT_TRUE(said) << "the resume note says the window";
  // a contact inside the window is still found, at once
  const auto hit = pick(9104, 12, stop + "faults:\n  - {type: collision, link: 3, onset: 8.72, magnitude: 10, duration: 0.05, "
                                         "point: [0.1, 0.0, 0.05], direction: [0.0, 0.3, 1.0]}\n");
  const auto found = watch(hit, MonitorConfig{}.resume_widen);
  ASSERT_EQ(found->events().size(), 1u) << listing(found->events());
  EXPECT_EQ(found->events()[0].fault, FaultClass::Collision);
  EXPECT_LT(found->events()[0].t_detected - 8.72, 0.02);
}

}  // namespace
}  // namespace twinwatch::monitor
