// Collision physics of the monitor (issue 7): drive gains of every joint from a payload pair, the
// generalized-momentum observer on the identified twin, and contact isolation on links.
// The twin is identified from recordings only; the simulator's truth (drive constants, the contact's
// force) is read here, by the test, to score it.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "monitor/simulated_run.hpp"
#include "twinwatch/core/error.hpp"
#include "twinwatch/ident/physics_ident.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "twinwatch/monitor/diagnosis.hpp"
#include "twinwatch/monitor/momentum_observer.hpp"
#include "twinwatch/monitor/monitor.hpp"
#include "twinwatch/sim/simulator.hpp"

namespace twinwatch::monitor {
namespace {

using test::run;
using test::scenario;

// the payload-pair program of scenarios/ur3e/train/swing_train*.yaml
const char* kSwing =
    "{type: sine, start: [0, -1.0, 1.0, -1.57, 0, 0], amplitude: [1.2, 0.3, 0.3, 0.8, 1.0, 1.5], "
    "frequency: [0.35, 0.23, 0.29, 0.19, 0.27, 0.31]}";

struct Collisions : ::testing::Test {
  static void SetUpTestSuite() {
    const auto exc = run("robot: ur3e\nseed: 701\nduration: 40\ntrajectory: {type: fourier, amplitude: 0.9, period: 10, harmonics: 5, seed: 3}\n");
    const auto fig = run(scenario(702, 24, 0.5));
    const auto sw0 = run(std::string("robot: ur3e\nseed: 703\nduration: 30\ntrajectory: ") + kSwing + "\n");
    const auto sw1 = run(std::string("robot: ur3e\nseed: 704\nduration: 30\ntrajectory: ") + kSwing +
                         "\npayload: {mass: 2.0, com: [0.06, 0.04, 0.05]}\n");
    payload.mass = 0.5;
    payload.com = Eigen::Vector3d(0, 0, 0.04);
    model::RigidBodyInertia weight;  // the known test weight
    weight.mass = 2.0;
    weight.com = Eigen::Vector3d(0.06, 0.04, 0.05);
    ident::IdentOptions io;
    io.efficiency_passes = 20;
    io.decimate = 3;  // test time
    ident::IdentReport rep;
    twin = new ident::TwinModel(ident::identify_physics("ur3e", {{&exc, {}}, {&fig, payload}, {&sw0, {}}, {&sw1, weight}}, io, rep));
    const auto h1 = run(scenario(705, 16, 0.5));
    const auto h2 = run(scenario(706, 10, 0.0));
    MonitorConfig settings;
    settings.observer_alerts = true;
    config = new MonitorConfig(learn_thresholds(*twin, {{&h1, payload}, {&h2, {}}}, settings));
  }
  static void TearDownTestSuite() {
    delete twin;
    delete config;
  }
  // The 3 N·m contacts of issue 7's 20 ms goal (50 ms half-sine), on links 2 and 3; seeds and onsets
  // differ from the threshold training and from the library.
  struct ThreeNmContact {
    int link;
    double onset;
    const char* point;
    unsigned seed;
  };
  static constexpr ThreeNmContact kThreeNmContacts[] = {{2, 5.71, "[-0.12, 0.0, 0.1]", 720}, {3, 6.53, "[-0.1, 0.0, 0.03]", 721}};
  static device::Recording record(const ThreeNmContact& c) {
    return run(scenario(c.seed, 8, 0.5,
                        "  - {type: collision, link: " + std::to_string(c.link) + ", onset: " + std::to_string(c.onset) +
                            ", magnitude: 3, duration: 0.05, point: " + c.point + ", direction: [0.3, 1.0, -0.2]}\n"));
  }
  // the events of monitoring `rec` with the fixture's twin (declared payload) and `cfg`
  static std::vector<Event> monitor(const device::Recording& rec, const MonitorConfig& cfg) {
    ident::TwinModel t = *twin;
    t.set_payload(payload);
    Monitor mon(t, cfg);
    for (const auto& s : rec.samples) mon.push(s);
    mon.finish();
    return mon.events();
  }
  static ident::TwinModel* twin;
  static MonitorConfig* config;
  static model::RigidBodyInertia payload;
};
ident::TwinModel* Collisions::twin = nullptr;
MonitorConfig* Collisions::config = nullptr;
model::RigidBodyInertia Collisions::payload;

// The payload pair makes every drive gain identifiable: within 8 % of the simulator's kt N eta
// (without it J1, J5, J6 came out at 2.7e5, 60 and 150 N·m/A, truth 8.6-11.4).
TEST_F(Collisions, PayloadPairIdentifiesEveryDriveGain) {
  const model::RobotModel m = model::load_robot("ur3e");
  const sim::PlantTruth truth = sim::default_truth(m, 0);
  for (int j = 0; j < 6; ++j) {
    const sim::JointTruth& jt = truth.joints[static_cast<size_t>(j)];
    const double g = jt.kt * jt.gear_ratio * jt.eta;
    EXPECT_NEAR(twin->joints[static_cast<size_t>(j)].gain / g, 1.0, 0.08) << "J" << j + 1 << " truth " << g;
    // back-driven current factor: eta * eta_rev; J6 (gravity-free, its torque is friction, which
    // never back-drives) has no back-driven samples to fit it from: the joint fit leaves it at 1
    if (j < 5) {
      EXPECT_NEAR(twin->joints[static_cast<size_t>(j)].c_gen, jt.eta * jt.eta_rev, 0.15) << "J" << j + 1;
    }
  }
}

// At rest the observer is a first-order lag of the external torque with time constant 1/K: the
// drive torque steps by -tau_ext (the drives hold the pose against it), r follows 1 - exp(-K t).
TEST_F(Collisions, ObserverConvergesToAConstantExternalTorqueWithTimeConstantOneOverK) {
  ident::TwinModel t = *twin;
  const int n = t.n_dof();
  const double K = 100.0, dt = 0.002;
  TwinMomentumObserver obs(n, K);
  RobotSample s = RobotSample::empty(n);
  s.q << 0.3, -1.2, 1.1, -1.4, -1.5, 0.2;
  s.qd.setZero();
  s.temperature.setConstant(t.temperature_ref);
  VectorJ tau0(n), i0(n);
  t.predict(s.q, s.qd, VectorJ::Zero(n), s.temperature, tau0, i0);
  VectorJ tau_ext(n);
  tau_ext << 2.0, -3.0, 1.5, 0.8, -0.5, 0.3;
  const int k0 = 50;  // the external torque starts at sample k0 (t = 0.1 s)
  const double a = 1.0 - std::exp(-K * dt);
  for (int k = 0; k <= 300; ++k) {
    s.timestamp = k * dt;
    for (int j = 0; j < n; ++j) s.current[j] = (tau0[j] - (k >= k0 ? tau_ext[j] : 0.0)) / t.joints[static_cast<size_t>(j)].gain;
    const VectorJ& r = obs.update(t, s, dt);
    if (k < k0) {
      EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-9) << "no external torque, no residual (k = " << k << ")";
      continue;
    }
    // the measured drive torque enters as the mean of two samples, so the step counts half at k0;
    // from there r decays towards tau_ext as exp(-K t) (zero-order-hold discretisation)
    const double expect = 1.0 - (1.0 - 0.5 * a) * std::exp(-K * (k - k0) * dt);
    for (int j = 0; j < n; ++j) EXPECT_NEAR(r[j] / tau_ext[j], expect, 1e-9) << "J" << j + 1 << " k - k0 = " << k - k0;
    // one time constant 1/K after the step: 1 - 1/e of the way (up to the half-sample start)
    if (k - k0 == static_cast<int>(std::lround(1.0 / (K * dt)))) {
      for (int j = 0; j < n; ++j) EXPECT_NEAR(r[j] / tau_ext[j], 1.0 - std::exp(-1.0), 0.5 * a);
    }
  }
}

// The same on the moving robot: a long contact (1 s half-sine) on link 3 during the figure-eight;
// near the pulse's peak the observer's estimate equals J^T F of the simulated force.
TEST_F(Collisions, ObserverEstimatesTheSimulatedContactTorqueWhileMoving) {
  const double onset = 6.0, dur = 1.0, mag = 8.0;
  const Eigen::Vector3d point(-0.1, 0.0, 0.03), dir = Eigen::Vector3d(0.3, 1.0, -0.2).normalized();
  const auto rec = run(scenario(707, 8, 0.5,
                                "  - {type: collision, link: 3, onset: 6.0, magnitude: 8, duration: 1.0, point: [-0.1, 0.0, 0.03], "
                                "direction: [0.3, 1.0, -0.2]}\n"));
  ident::TwinModel t = *twin;
  t.set_payload(payload);
  TwinMomentumObserver obs(t.n_dof(), 150.0);
  const model::RobotModel m = model::load_robot("ur3e");
  model::DynamicsData d(m);
  Matrix6J J;
  double worst = 0.0;
  int checked = 0;
  for (size_t k = 0; k < rec.samples.size(); ++k) {
    const RobotSample& s = rec.samples[k];
    const VectorJ& r = obs.update(t, s, k == 0 ? 0.002 : s.timestamp - rec.samples[k - 1].timestamp);
    const double phase = (s.timestamp - onset) / dur;
    if (phase < 0.35 || phase > 0.65) continue;  // the flat top of the half-sine (>= 89 % of the peak)
    model::forward_kinematics(m, d, s.q);
    model::point_jacobian(m, d, 2, point, J);
    const VectorJ unit = J.topRows<3>().transpose() * dir;
    const VectorJ truth = mag * std::sin(M_PI * phase) / unit.cwiseAbs().maxCoeff() * unit;
    worst = std::max(worst, (r - truth).cwiseAbs().maxCoeff());
    ++checked;
  }
  ASSERT_GT(checked, 100);
  // 8 N·m peak: the estimate is within 1.2 N·m on every joint (model error and noise)
  EXPECT_LT(worst, 1.2);
}

// A contact on link k is named on link k with its force; links 2 and 3 (the upper and fore arm) at
// 10 N·m. Wrist links: see docs/validation.md (not isolated reliably yet).
TEST_F(Collisions, ContactIsIsolatedToItsLinkWithItsForce) {
  struct Case {
    int link;
    const char* point;
    Eigen::Vector3d p;
  };
  const Case cases[] = {{2, "[-0.12, 0.0, 0.1]", {-0.12, 0.0, 0.1}}, {3, "[-0.1, 0.0, 0.03]", {-0.1, 0.0, 0.03}}};
  const model::RobotModel m = model::load_robot("ur3e");
  model::DynamicsData d(m);
  Matrix6J J;
  unsigned seed = 710;
  for (const Case& c : cases) {
    const double onset = 7.3, mag = 10.0;
    const auto rec = run(scenario(seed++, 9, 0.5,
                                  "  - {type: collision, link: " + std::to_string(c.link) + ", onset: 7.3, magnitude: 10, duration: 0.05, point: " +
                                      c.point + ", direction: [0.3, 1.0, -0.2]}\n"));
    ident::TwinModel t = *twin;
    t.set_payload(payload);
    Monitor mon(t, *config);
    double force = 0.0;
    for (const auto& s : rec.samples) {
      mon.push(s);
      if (std::abs(s.timestamp - (onset + 0.025)) < 1e-3) {
        // truth: the peak force of the pulse, |F| = magnitude / max |J^T dir|
        model::forward_kinematics(m, d, s.q);
        model::point_jacobian(m, d, c.link - 1, c.p, J);
        force = mag / (J.topRows<3>().transpose() * Eigen::Vector3d(0.3, 1.0, -0.2).normalized()).cwiseAbs().maxCoeff();
      }
    }
    mon.finish();
    // one event: the contact's (none at start-up, see Monitor::push)
    const std::vector<Event>& ev = mon.events();
    ASSERT_EQ(ev.size(), 1u) << "link " << c.link << ": " << (ev.empty() ? "" : ev.front().detail);
    const Event& e = ev.front();
    EXPECT_EQ(e.fault, FaultClass::Collision) << e.detail;
    EXPECT_EQ(e.link, c.link - 1) << e.detail;
    EXPECT_LT(e.t_detected - onset, 0.03) << e.detail;
    ASSERT_GT(force, 0.0);
    if (c.link == 2) {
      // two joints carry a force on link 2: its size is what they require at least (the smallest of
      // the points that fit; the force at the link's centre of mass once read 90x the truth, session 22)
      EXPECT_THAT(e.detail, ::testing::HasSubstr("at least")) << e.detail;
      EXPECT_LT(e.magnitude / force, 1.35) << e.detail << " truth " << force << " N";
      EXPECT_GT(e.magnitude / force, 0.3) << e.detail << " truth " << force << " N";
    } else {
      EXPECT_NEAR(e.magnitude / force, 1.0, 0.35) << e.detail << " truth " << force << " N";
    }
  }
}

// Issue 7's collision goal: a 3 N·m joint-equivalent contact (50 ms half-sine) is detected within
// 20 ms with the dynamic thresholds and the momentum observer, as a collision, and nothing else is
// raised in the run. Seeds and onsets differ from the threshold training and from the library.
TEST_F(Collisions, ThreeNewtonMetreContactIsDetectedWithinTwentyMilliseconds) {
  for (const ThreeNmContact& c : kThreeNmContacts) {
    const std::vector<Event> ev = monitor(record(c), *config);
    ASSERT_EQ(ev.size(), 1u) << "link " << c.link << ": " << (ev.empty() ? "no event" : ev.front().detail);
    EXPECT_EQ(ev.front().fault, FaultClass::Collision) << ev.front().detail;
    EXPECT_GE(ev.front().t_detected, c.onset) << "raised before the contact";
    EXPECT_LE(ev.front().t_detected - c.onset, 0.020 + 1e-9) << "link " << c.link << ": " << ev.front().detail;
  }
}

// The observer channel has its own debounce (MonitorConfig::observer_raise_after). The same 3 N·m
// contacts raised by one observer exceedance instead of two: the alert starts at the same first
// exceedance and is raised no later, at most one sample earlier (the observer channel raised it) and
// never more (the current channel keeps raise_after); at least one of the two is raised earlier.
TEST_F(Collisions, ASingleSampleObserverDebounceRaisesTheSameContactOneSampleEarlier) {
  int earlier = 0;
  for (const ThreeNmContact& c : kThreeNmContacts) {
    const auto rec = record(c);
    auto first_event = [&](int observer_raise_after) {
      MonitorConfig cfg = *config;
      cfg.observer_raise_after = observer_raise_after;
      const std::vector<Event> ev = monitor(rec, cfg);
      EXPECT_EQ(ev.size(), 1u) << "link " << c.link << ", observer_raise_after " << observer_raise_after;
      return ev.empty() ? Event{} : ev.front();
    };
    const Event two = first_event(0), one = first_event(1);
    ASSERT_EQ(two.fault, FaultClass::Collision) << two.detail;
    ASSERT_EQ(one.fault, FaultClass::Collision) << one.detail;
    EXPECT_DOUBLE_EQ(one.t_start, two.t_start) << "link " << c.link;
    const double gain = two.t_detected - one.t_detected;
    EXPECT_GE(gain, -1e-9) << "link " << c.link;
    EXPECT_LE(gain, config->nominal_period + 1e-9) << "link " << c.link;
    earlier += gain > 0.5 * config->nominal_period;
    EXPECT_EQ(one.link, two.link) << "the diagnosis window moves by one sample at most";
  }
  EXPECT_GE(earlier, 1);
}

// Per-joint observer debounce (MonitorConfig::observer_choice): one sample on joint k and
// the shared two elsewhere. Each such alert starts at the same first exceedance and is raised between
// the shared two-sample and one-sample raises; the earliest of the six is the one-sample raise (the
// joint whose observer crossed first raised it), and with every joint at one it is the one-sample
// alert exactly.
TEST_F(Collisions, APerJointObserverDebounceRaisesOnTheJointThatCrossedFirst) {
  for (const ThreeNmContact& c : kThreeNmContacts) {
    const auto rec = record(c);
    auto first_event = [&](int shared, std::vector<int> per_joint) {
      MonitorConfig cfg = *config;
      cfg.observer_raise_after = shared;
      cfg.observer_choice.raise_after = std::move(per_joint);
      const std::vector<Event> ev = monitor(rec, cfg);
      EXPECT_EQ(ev.size(), 1u) << "link " << c.link;
      return ev.empty() ? Event{} : ev.front();
    };
    const int n = twin->n_dof();
    const Event two = first_event(2, {}), one = first_event(1, {});
    const Event all_one = first_event(0, std::vector<int>(static_cast<size_t>(n), 1));
    EXPECT_DOUBLE_EQ(all_one.t_detected, one.t_detected) << "link " << c.link;
    EXPECT_EQ(all_one.link, one.link);
    double earliest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < n; ++k) {
      std::vector<int> d(static_cast<size_t>(n), 2);
      d[static_cast<size_t>(k)] = 1;
      const Event e = first_event(0, d);
      EXPECT_DOUBLE_EQ(e.t_start, two.t_start) << "link " << c.link << ", J" << k + 1 << " at one sample";
      EXPECT_GE(e.t_detected, one.t_detected - 1e-9) << "link " << c.link << ", J" << k + 1;
      EXPECT_LE(e.t_detected, two.t_detected + 1e-9) << "link " << c.link << ", J" << k + 1;
      earliest = std::min(earliest, e.t_detected);
    }
    EXPECT_DOUBLE_EQ(earliest, one.t_detected) << "link " << c.link;
  }
}

// A contact that pushes a resting joint leaves it held off target by static friction (the PD holds a
// current against it for the rest of the run). That is one collision, not a stream of new alerts:
// the held residual is the resting joint's new baseline (RestBaseline). Held-out case of
// scenarios/ur3e/heldout_collisions (6 N·m on link 6, triangle, J5 at rest), which raised 4 more
// "contacts" before.
TEST_F(Collisions, AContactThatLeavesARestingJointHeldOffTargetIsOneEvent) {
  const auto rec = run("robot: ur3e\nseed: 6062\nduration: 16\ntrajectory: {type: triangle, side: 0.15, speed: 0.2}\n"
                       "payload: {mass: 0.5, com: [0, 0, 0.04]}\nfaults:\n"
                       "  - {type: collision, link: 6, onset: 13.383, magnitude: 6, duration: 0.05, point: [-0.018, -0.034, 0.088], "
                       "direction: [-0.123, -0.483, 0.867]}\n");
  // the triangle's own thresholds (its corners are not in the fixture's figure-eight set), learned on
  // two healthy triangle runs of other seeds, as a user does per program
  const auto tri = "trajectory: {type: triangle, side: 0.15, speed: 0.2}\n";
  const auto h1 = run(std::string("robot: ur3e\nseed: 731\nduration: 16\n") + tri + "payload: {mass: 0.5, com: [0, 0, 0.04]}\n");
  const auto h2 = run(std::string("robot: ur3e\nseed: 732\nduration: 12\n") + tri);
  MonitorConfig cfg = *config;
  learn_program_thresholds(cfg, "triangle", *twin, {{&h1, payload}, {&h2, {}}});
  cfg.select_program("triangle");
  const std::vector<Event> ev = monitor(rec, cfg);
  // the wrist stays off target after the contact (what the baseline absorbs): measured, not assumed
  const RobotSample& last = rec.samples.back();
  EXPECT_GT(std::abs(last.target_q[4] - last.q[4]), 5e-4) << "the contact no longer leaves J5 displaced";
  ASSERT_EQ(ev.size(), 1u) << (ev.size() > 1 ? ev[1].detail : "");
  EXPECT_EQ(ev.front().fault, FaultClass::Collision);
  EXPECT_NEAR(ev.front().t_detected, 13.383, 0.02);
}

// RestBaseline: set after kSettle samples at rest (then following slowly), a step at rest still shows, motion drops it.
// The contact isolation weighs what the contact does to every joint with one time profile, not
// what else the observer shows: (1) a joint reversing during the contact, whose twin friction
// misfit drifts by 0.8 N·m over 0.16 s (the size measured at the UR3e wrist reversals of
// scenarios/ur3e/heldout_collisions), must not be taken for the contact's own joint; (2) a joint
// held at rest by static friction, whose estimate flips with the encoder-step velocity, carries no
// information. Before the detrended, profile-projected impulse, (1) named link 5 for a link-3 contact.
// The twin's low-speed friction (pre-sliding memory + Stribeck, issue 5) is what the observer's
// healthy misfit at stops and reversals was made of: on an untrained healthy triangle run (a stop at
// every corner), the observer's external-torque estimate -- pure model misfit here, no contact --
// is smaller with it than with the plain-Coulomb twin from the same recordings, on the slow samples.
TEST_F(Collisions, LowSpeedFrictionShrinksTheObserversHealthyMisfitAtStops) {
  const auto exc = run("robot: ur3e\nseed: 701\nduration: 40\ntrajectory: {type: fourier, amplitude: 0.9, period: 10, harmonics: 5, seed: 3}\n");
  const auto fig = run(scenario(702, 24, 0.5));
  const auto sw0 = run(std::string("robot: ur3e\nseed: 703\nduration: 30\ntrajectory: ") + kSwing + "\n");
  const auto sw1 = run(std::string("robot: ur3e\nseed: 704\nduration: 30\ntrajectory: ") + kSwing +
                       "\npayload: {mass: 2.0, com: [0.06, 0.04, 0.05]}\n");
  model::RigidBodyInertia weight;
  weight.mass = 2.0;
  weight.com = Eigen::Vector3d(0.06, 0.04, 0.05);
  ident::IdentOptions io;
  io.efficiency_passes = 20;
  io.decimate = 3;
  io.low_speed_friction = false;
  ident::IdentReport rep;
  const ident::TwinModel plain = ident::identify_physics("ur3e", {{&exc, {}}, {&fig, payload}, {&sw0, {}}, {&sw1, weight}}, io, rep);
  const auto tri = run("robot: ur3e\nseed: 707\nduration: 14\ntrajectory: {type: triangle, side: 0.15, speed: 0.2}\n");
  auto slow_misfit = [&](const ident::TwinModel& t) {
    TwinMomentumObserver obs(6, 150.0);
    VectorJ ss = VectorJ::Zero(6);
    VectorJ cnt = VectorJ::Zero(6);
    for (size_t k = 0; k < tri.samples.size(); ++k) {
      const RobotSample& s = tri.samples[k];
      const VectorJ& r = obs.update(t, s, k == 0 ? 0.002 : s.timestamp - tri.samples[k - 1].timestamp);
      if (k < 250) continue;  // observer start-up
      for (int j = 0; j < 6; ++j)
        if (std::abs(s.qd[j]) < 0.05) ss[j] += r[j] * r[j], cnt[j] += 1;
    }
    return VectorJ((ss.array() / cnt.array().max(1.0)).sqrt());
  };
  // measured (seed 707): J1-J6 0.30/0.24/0.35/0.10/0.04/0.10 N·m with, 0.55/0.50/0.58/0.37/0.05/0.41
  // without; J5 hardly moves on this path and carries little friction either way
  const VectorJ with = slow_misfit(*twin), without = slow_misfit(plain);
  for (int j : {0, 1, 2, 3, 5}) EXPECT_LT(with[j], 0.7 * without[j]) << "J" << j + 1;
  EXPECT_LT(with[4], 1.1 * without[4]) << "J5";
}

// A synthetic observer estimate at a fixed configuration: 250 samples of healthy reference (noise
// 0.02 N·m) and an 80-sample window with a 50 ms contact of joint torque `contact` seen through a
// first-order observer of bandwidth 150/s starting 30 ms in; `extra(k, t, tau)` adds other effects.
struct SyntheticWindow {
  std::vector<DiagnosisSample> ref, win;
};
SyntheticWindow synthetic_contact(const VectorJ& q, const VectorJ& qd, const VectorJ& contact, unsigned seed,
                                  const std::function<void(int, double, VectorJ&)>& extra = {}) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.02);
  const double dt = 0.002;
  auto sample = [&](double t, const VectorJ& tau) {
    DiagnosisSample s;
    s.t = t;
    s.q = q;
    s.qd = qd;
    s.qdd = VectorJ::Zero(6);
    s.tau_ext = tau;
    for (int j = 0; j < 6; ++j) s.tau_ext[j] += noise(rng);
    s.r_tau = s.tau_ext;
    s.current = VectorJ::Constant(6, t);  // changing: no frozen channel
    s.tau_ext_level = VectorJ::Constant(6, 1.0);
    return s;
  };
  SyntheticWindow w;
  for (int k = 0; k < 250; ++k) w.ref.push_back(sample(k * dt, VectorJ::Zero(6)));
  const double t0 = 250 * dt, onset = t0 + 0.03, pulse = 0.05;
  double lagged = 0.0;
  for (int k = 0; k < 80; ++k) {
    const double t = t0 + k * dt;
    const double shape = (t >= onset && t < onset + pulse) ? std::sin(M_PI * (t - onset) / pulse) : 0.0;
    lagged += 150.0 * dt * (shape - lagged);
    VectorJ tau = lagged * contact;
    if (extra) extra(k, t - onset, tau);
    w.win.push_back(sample(t, tau));
  }
  return w;
}

// joint torque of a force along `direction` at `point` (body frame of `link`, 0-based) scaled to a
// peak joint torque of `peak` N·m
VectorJ contact_torque(const model::RobotModel& m, const VectorJ& q, int link, const Eigen::Vector3d& point,
                       const Eigen::Vector3d& direction, double peak) {
  model::DynamicsData d(m);
  model::forward_kinematics(m, d, q);
  Matrix6J J;
  model::point_jacobian(m, d, link, point, J);
  const VectorJ unit = J.topRows<3>().transpose() * direction.normalized();
  return peak / unit.cwiseAbs().maxCoeff() * unit;
}

TEST(ContactIsolation, ADriftOnAReversingWristAndAStuckJointDoNotMoveTheContactLink) {
  const model::RobotModel m = model::load_robot("ur3e");
  VectorJ q(6), qd(6);
  q << 0.3, -1.2, 1.4, -1.6, 0.9, 0.2;
  qd << 0.4, 0.3, -0.35, 0.25, 0.3, 0.0;  // J6 at rest
  // on the forearm (link 3), body frame; 6 N·m peak joint torque
  const VectorJ contact = contact_torque(m, q, 2, Eigen::Vector3d(-0.1, 0.0, 0.03), Eigen::Vector3d(0.3, 1.0, -0.2), 6.0);
  ASSERT_NEAR(contact.tail<3>().norm(), 0.0, 1e-12);  // a link-3 contact: J4-J6 feel nothing
  const SyntheticWindow w = synthetic_contact(q, qd, contact, 11, [](int k, double since_onset, VectorJ& tau) {
    // (1) J5 reverses: the misfit rises smoothly by 0.8 N·m over 0.16 s around the contact
    const double x = std::clamp((since_onset + 0.05) / 0.16, 0.0, 1.0);
    tau[4] += 0.8 * x * x * (3.0 - 2.0 * x);
    // (2) J6 stuck: the twin's friction flips with the velocity's encoder-step toggling
    tau[5] += (k / 3) % 2 ? 0.4 : -0.4;
  });
  const auto hyps = diagnose(m, w.win, 0.06, 2, DiagnosisOptions{}, &w.ref);
  ASSERT_FALSE(hyps.empty());
  EXPECT_EQ(hyps.front().fault, FaultClass::Collision) << hyps.front().detail;
  EXPECT_EQ(hyps.front().link, 2) << hyps.front().detail;
  // a twin that knows no friction level (a sequential twin: zeros) leaves the stuck J6 out as well,
  // instead of trusting its toggling estimate
  DiagnosisOptions zero;
  zero.static_friction = VectorJ::Zero(6);
  const Hypothesis hz = diagnose(m, w.win, 0.06, 2, zero, &w.ref).front();
  EXPECT_EQ(hz.link, 2) << hz.detail;
  EXPECT_GT(hz.contact.sigma[5], 100.0 * hz.contact.sigma[2]) << "J6 at rest is left out";
  // a friction vector of the wrong size or a negative level is refused
  DiagnosisOptions bad;
  bad.static_friction = VectorJ::Zero(5);
  EXPECT_THROW(diagnose(m, w.win, 0.06, 2, bad, &w.ref), InvalidArgument);
  bad.static_friction = VectorJ::Constant(6, -0.1);
  EXPECT_THROW(diagnose(m, w.win, 0.06, 2, bad, &w.ref), InvalidArgument);
}

// A contact on the forearm (link 3) whose force line passes near J3's axis puts little torque on J3
// (here 0.05 of 6 N·m, below what the observer's noise and model error resolve): in the joint
// torques it is also a contact on the upper arm (link 2). The diagnosis names one of the two and
// reports the other; a forearm contact that loads J3 gets no upper-arm alternative. (One whose force
// passes exactly through J3's axis is a link-2 contact as far as any joint torque can tell, and every
// contact named on link l is also one on link l + 1 through J(l+1)'s axis: those are not reported,
// or every event would carry one.)
TEST(ContactIsolation, AContactThatLeavesItsOwnJointUntouchedReportsTheLinkBeforeItToo) {
  const model::RobotModel m = model::load_robot("ur3e");
  VectorJ q(6), qd(6);
  q << 0.3, -1.2, 1.4, -1.6, 0.9, 0.2;
  qd << 0.4, 0.3, -0.35, 0.25, 0.3, 0.2;
  model::DynamicsData d(m);
  model::forward_kinematics(m, d, q);
  Matrix6J J;
  const Eigen::Vector3d point(-0.1, 0.0, 0.03);
  model::point_jacobian(m, d, 2, point, J);
  // a direction with no moment about J3's axis: orthogonal to J3's linear Jacobian column
  const Eigen::Vector3d col3 = J.block<3, 1>(0, 2);
  const Eigen::Vector3d through_axis = col3.cross(Eigen::Vector3d(0.2, -0.5, 1.0)).normalized();
  ASSERT_LT(std::abs(contact_torque(m, q, 2, point, through_axis, 6.0)[2]), 1e-9);  // exactly through: J3 feels nothing
  // tilt it towards J3's lever until J3 takes 0.8 % of the peak joint torque
  const double peak0 = (J.topRows<3>().transpose() * through_axis).cwiseAbs().maxCoeff();
  const Eigen::Vector3d near_axis = through_axis + 0.008 * peak0 / col3.squaredNorm() * col3;
  const VectorJ blind = contact_torque(m, q, 2, point, near_axis, 6.0);
  ASSERT_NEAR(std::abs(blind[2]), 0.05, 0.01);  // J3 feels little
  ASSERT_GT(std::abs(blind[1]), 1.0);           // J2 does
  const VectorJ loaded = contact_torque(m, q, 2, point, col3, 6.0);  // along J3's lever: J3 loaded most
  ASSERT_GT(std::abs(loaded[2]), 3.0);
  for (unsigned seed : {3u, 5u, 7u}) {
    const SyntheticWindow b = synthetic_contact(q, qd, blind, seed);
    const Hypothesis hb = diagnose(m, b.win, 0.06, 1, DiagnosisOptions{}, &b.ref).front();
    ASSERT_EQ(hb.fault, FaultClass::Collision) << hb.detail;
    ASSERT_TRUE(hb.link == 1 || hb.link == 2) << hb.detail;
    ASSERT_EQ(hb.other_links.size(), 1u) << hb.detail;
    EXPECT_EQ(hb.other_links.front(), hb.link == 1 ? 2 : 1) << hb.detail;
    EXPECT_NE(hb.detail.find(fmt::format("link {} is also possible", hb.other_links.front() + 1)), std::string::npos) << hb.detail;
    // the doubt is in the named link's probability, which the detail prints and the event's
    // confidence carries: below 1 by at least the other link's share
    EXPECT_NE(hb.detail.find(fmt::format("{:.0f} % likely", 100.0 * hb.link_share)), std::string::npos) << hb.detail;
    const size_t at = hb.detail.find("also possible (");
    ASSERT_NE(at, std::string::npos) << hb.detail;
    const double other = std::stod(hb.detail.substr(at + 15)) / 100.0;
    EXPECT_GT(other, 0.0) << hb.detail;
    EXPECT_LE(hb.link_share + other, 1.0 + 0.01) << hb.detail;

    const SyntheticWindow l = synthetic_contact(q, qd, loaded, seed);
    const Hypothesis hl = diagnose(m, l.win, 0.06, 2, DiagnosisOptions{}, &l.ref).front();
    EXPECT_EQ(hl.link, 2) << hl.detail;
    for (int o : hl.other_links) EXPECT_GT(o, 2) << hl.detail;  // never the upper arm
    EXPECT_NE(hl.detail.find(fmt::format("{:.0f} % likely", 100.0 * hl.link_share)), std::string::npos) << hl.detail;
  }
}

TEST(RestBaseline, FreezesAtRestKeepsStepsAndForgetsOnMotion) {
  RobotSample s = RobotSample::empty(2);
  s.present = kFieldTargetQd;
  s.target_qd = VectorJ::Zero(2);
  s.qd = VectorJ::Zero(2);
  s.target_qd[1] = 0.5;  // joint 2 commanded to move: never at rest
  s.qd[1] = 0.5;
  RestBaseline b(2);
  VectorJ v(2);
  for (int k = 0; k < RestBaseline::kSettle; ++k) {
    v << 0.3, 0.3;
    b.apply(s, v);
    EXPECT_DOUBLE_EQ(v[0], 0.3) << "settling: unchanged";
  }
  v << 0.3, 0.3;
  b.apply(s, v);
  EXPECT_NEAR(v[0], 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(v[1], 0.3);
  v << 0.8, 0.3;  // a step while resting
  b.apply(s, v);
  EXPECT_NEAR(v[0], 0.5, 1e-12);
  s.qd[0] = 0.05;  // the joint moves: baseline dropped
  v << 0.8, 0.3;
  b.apply(s, v);
  EXPECT_DOUBLE_EQ(v[0], 0.8);
  s.qd[0] = 0.0;
  s.present = 0;  // no target velocity streamed: never at rest
  for (int k = 0; k < 2 * RestBaseline::kSettle; ++k) {
    v << 0.8, 0.3;
    b.apply(s, v);
  }
  EXPECT_DOUBLE_EQ(v[0], 0.8);
}

// After settling the baseline follows slowly: a held current that the controller's integrator ramps
// (healthy creep against static friction after a contact) stays within rate x time constant, while
// a step still shows in full at once and mostly for the next 0.1 s (held-out set 3's false alarms)
TEST(RestBaseline, FollowsARampAtRestButNotAStep) {
  RobotSample s = RobotSample::empty(1);
  s.present = kFieldTargetQd;
  s.target_qd = VectorJ::Zero(1);
  s.qd = VectorJ::Zero(1);
  RestBaseline b(1);
  VectorJ v(1);
  for (int k = 0; k < RestBaseline::kSettle; ++k) {
    v << 0.2;
    b.apply(s, v);
  }
  // a ramp of 0.1 per second at 500 Hz for 5 s: a frozen baseline would leave 0.5
  const double rate = 0.1 / 500.0;
  double worst = 0.0;
  for (int k = 1; k <= 2500; ++k) {
    v << 0.2 + rate * k;
    b.apply(s, v);
    worst = std::max(worst, std::abs(v[0]));
  }
  EXPECT_LT(worst, 1.05 * rate * RestBaseline::kTrackSamples);  // the lag of a first-order follower
  EXPECT_GT(worst, 0.9 * rate * RestBaseline::kTrackSamples);
  // a step of 0.4: all of it on the first sample, still > 80 % after 0.1 s (50 samples)
  const double level = 0.2 + rate * 2500;
  v << level + 0.4;
  b.apply(s, v);
  const double first = v[0];
  for (int k = 1; k < 50; ++k) {
    v << level + 0.4;
    b.apply(s, v);
  }
  EXPECT_NEAR(first, 0.4 + rate * RestBaseline::kTrackSamples, 0.01);
  EXPECT_GT(v[0], 0.8 * 0.4);
}

TEST(TwinMomentumObserver, RejectsBadGainAndJointCount) {
  EXPECT_THROW(TwinMomentumObserver(6, 0.0), InvalidArgument);
  EXPECT_THROW(TwinMomentumObserver(6, -5.0), InvalidArgument);
  EXPECT_THROW(TwinMomentumObserver(0, 100.0), InvalidArgument);
}

// A joint at rest during a contact is held by static friction: its estimate flips with the twin's
// friction and a contact torque below the breakaway level never reaches its current. But it is not
// blind: what the contact put on it beyond what friction holds does show. With the friction levels
// known (DiagnosisOptions::static_friction, from the twin), a resting joint counts with that much
// more noise. (Before session 12 a resting joint's row was dropped: with every joint but J1 at rest
// all six links fitted a J1-only pattern equally, and the named link was a tie's accident; the
// simulated collision sets had three such link-1 contacts, all named link 2.)
TEST(ContactIsolation, JointsAtRestCountUpToTheFrictionTheyHold) {
  const model::RobotModel m = model::load_robot("ur3e");
  VectorJ q(6), qd(6);
  q << 0.3, -1.2, 1.4, -1.6, 0.9, 0.2;
  qd << 0.3, 0.0, 0.0, 0.0, 0.0, 0.0;  // only the base turns
  DiagnosisOptions o;
  o.static_friction = VectorJ(6);
  o.static_friction << 0.65, 0.77, 0.70, 0.50, 0.35, 0.39;  // the identified twin's Coulomb levels [N·m]
  const auto toggling = [](int k, double, VectorJ& tau) {
    // the resting joints' estimates flip with the encoder-step toggling of their velocity
    for (int j = 1; j < 6; ++j) tau[j] += ((k + j) / 3) % 2 ? 0.3 : -0.3;
  };
  // (1) on the shoulder link (link 1): only J1 feels it, and nothing on the resting joints needs
  // another link
  const VectorJ shoulder = contact_torque(m, q, 0, Eigen::Vector3d(0.02, -0.03, 0.0), Eigen::Vector3d(1.0, 0.4, 0.2), 6.0);
  ASSERT_NEAR(shoulder.tail<5>().norm(), 0.0, 1e-12);
  // (2) on the upper arm (link 2), pushing J2 with 6 N·m while its drive holds it still: far more
  // than the 0.77 N·m friction holds, so the resting J2 says the contact is past J1
  model::DynamicsData d(m);
  model::forward_kinematics(m, d, q);
  Matrix6J J;
  const Eigen::Vector3d point = m.joint(1).body.com;
  model::point_jacobian(m, d, 1, point, J);
  const VectorJ upper = contact_torque(m, q, 1, point, J.block<3, 1>(0, 1) + 0.5 * J.block<3, 1>(0, 0), 6.0);
  ASSERT_GT(std::abs(upper[1]), 5.0);
  for (unsigned seed : {31u, 32u, 33u}) {
    const SyntheticWindow a = synthetic_contact(q, qd, shoulder, seed, toggling);
    const Hypothesis ha = diagnose(m, a.win, 0.06, 0, o, &a.ref).front();
    EXPECT_EQ(ha.fault, FaultClass::Collision) << ha.detail;
    EXPECT_EQ(ha.link, 0) << ha.detail;
    // not a tie resolved towards link 1: the choice the diagnosis read gives it a clear majority
    ASSERT_EQ(ha.contact.impulse.size(), 6);
    EXPECT_GT(contact_link_posterior(m, ha.contact.q, ha.contact.impulse, ha.contact.sigma)[0], 0.5) << ha.detail;
    const SyntheticWindow b = synthetic_contact(q, qd, upper, seed, toggling);
    const Hypothesis hb = diagnose(m, b.win, 0.06, 1, o, &b.ref).front();
    EXPECT_EQ(hb.fault, FaultClass::Collision) << hb.detail;
    EXPECT_EQ(hb.link, 1) << hb.detail;
  }
}

// The link choice as a function (what `evaluate --link-ceiling` calls on the true impulse): a
// posterior over the links that sums to 1; a noise-free forearm contact that loads J3 is named on
// the forearm; a link-1 pattern (J1 only) is named on link 1 when every joint is read; bad input
// is refused.
TEST(ContactIsolation, TheLinkPosteriorNamesANoiseFreeContactAndRefusesBadInput) {
  const model::RobotModel m = model::load_robot("ur3e");
  VectorJ q(6);
  q << 0.3, -1.2, 1.4, -1.6, 0.9, 0.2;
  model::DynamicsData d(m);
  model::forward_kinematics(m, d, q);
  Matrix6J J;
  const Eigen::Vector3d point(-0.1, 0.0, 0.03);
  model::point_jacobian(m, d, 2, point, J);
  const VectorJ forearm = 0.05 * contact_torque(m, q, 2, point, J.block<3, 1>(0, 2), 6.0);  // [N·m·s]
  const VectorJ sd = VectorJ::Constant(6, 0.002);
  const std::vector<double> post = contact_link_posterior(m, q, forearm, sd);
  ASSERT_EQ(post.size(), 6u);
  double sum = 0.0;
  for (double p : post) sum += p;
  EXPECT_NEAR(sum, 1.0, 1e-12);
  EXPECT_EQ(std::max_element(post.begin(), post.end()) - post.begin(), 2);
  EXPECT_GT(post[2], 0.5);
  VectorJ base = VectorJ::Zero(6);
  base[0] = 0.3;
  const std::vector<double> pb = contact_link_posterior(m, q, base, sd);
  EXPECT_EQ(std::max_element(pb.begin(), pb.end()) - pb.begin(), 0);
  VectorJ bad = sd;
  bad[3] = 0.0;
  EXPECT_THROW(contact_link_posterior(m, q, forearm, bad), InvalidArgument);
  EXPECT_THROW(contact_link_posterior(m, q, forearm, sd, -0.01), InvalidArgument);
  EXPECT_THROW(contact_link_posterior(m, q.head(5), forearm, sd), InvalidArgument);
  // told a 4 cm cube around the forearm's centre of mass (a test generator's), still the forearm
  const std::vector<double> cube = contact_link_posterior(m, q, forearm, sd, 0.04);
  EXPECT_EQ(std::max_element(cube.begin(), cube.end()) - cube.begin(), 2);
}

// The link is chosen by its evidence over where on the link a contact can be: the contact point is
// integrated over the link's equivalent inertia box (30-39 cm along the UR3e upper arm), not fixed
// near the centre of mass. A push near either end of the upper arm, in three directions that load
// J2, is named on the upper arm (link 2): no other link's box produces that torque pattern as often.
TEST(ContactIsolation, APushNearEitherEndOfTheUpperArmIsNamedOnTheUpperArm) {
  const model::RobotModel m = model::load_robot("ur3e");
  VectorJ q(6), qd(6);
  q << -0.4, -1.3, 1.2, -1.4, -1.2, 0.3;
  qd << -0.3, 0.35, 0.3, -0.2, 0.25, -0.3;
  const Eigen::Vector3d com = m.joint(1).body.com;
  model::DynamicsData d(m);
  model::forward_kinematics(m, d, q);
  Matrix6J J;
  unsigned seed = 21;
  for (double along : {-0.09, 0.09}) {
    const Eigen::Vector3d point = com + Eigen::Vector3d(along, 0.0, 0.02);
    model::point_jacobian(m, d, 1, point, J);
    const Eigen::Vector3d lever = J.block<3, 1>(0, 1).normalized();  // the direction J2 feels most
    for (const Eigen::Vector3d& tilt : {Eigen::Vector3d(0.5, 0.0, 0.0), Eigen::Vector3d(0.0, 0.5, 0.0), Eigen::Vector3d(0.0, 0.0, -0.5)}) {
      const Eigen::Vector3d dir = (lever + tilt).normalized();
      const VectorJ tau = contact_torque(m, q, 1, point, dir, 5.0);
      ASSERT_GT(std::abs(tau[1]), 0.5);  // J2 takes a real share (above the observer noise)
      const SyntheticWindow w = synthetic_contact(q, qd, tau, ++seed);
      const Hypothesis h = diagnose(m, w.win, 0.06, 1, DiagnosisOptions{}, &w.ref).front();
      EXPECT_EQ(h.fault, FaultClass::Collision) << h.detail;
      EXPECT_EQ(h.link, 1) << "point " << along << " m along the arm, direction " << dir.transpose() << ": " << h.detail;
    }
  }
}

// A worn joint whose extra friction has crept up to under its observer threshold crosses it on a
// noise peak (the +30 % wear ramps of scenarios/ur3e/wear, after ~1.6 h). Nothing new arrived: the
// crossing is the resistance that was there before the raise, on that joint, not a contact on a
// neighbouring link (what the diagnosis said before session 20). A contact on top of the same
// offset is still a contact; an offset that aids the motion, or one seen across a reversal less than
// 0.1 s before, is not read as resistance by this rule.
TEST(ContactIsolation, ANoisePeakOnAWornJointsSteadyOffsetIsItsResistanceNotAContact) {
  const model::RobotModel m = model::load_robot("ur3e");
  VectorJ q(6), qd(6);
  q << 0.3, -1.2, 1.4, -1.6, 0.9, 0.2;
  qd << -0.3, -0.6, 0.8, -0.35, -0.3, 0.15;
  // J3's estimate: -0.45 N·m (against its +0.8 rad/s) with 0.1 N·m of noise, threshold 0.8 N·m; the
  // other joints read noise under a 1 N·m threshold. One window sample peaks at -0.86.
  auto worn = [&](unsigned seed, const VectorJ& contact, double offset, const std::function<double(double)>& qd3) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0.0, 1.0);
    SyntheticWindow w;
    const double dt = 0.002;
    double lagged = 0.0;
    for (int k = 0; k < 250 + 71; ++k) {
      const double t = k * dt;
      DiagnosisSample s;
      s.t = t;
      s.q = q;
      s.qd = qd;
      s.qd[2] = qd3(t);
      s.qdd = VectorJ::Zero(6);
      s.tau_ext = VectorJ::Zero(6);
      for (int j = 0; j < 6; ++j) s.tau_ext[j] = (j == 2 ? 0.1 : 0.05) * std::max(-2.5, std::min(2.5, noise(rng)));
      s.tau_ext[2] += offset;
      if (k == 250 + 20) s.tau_ext[2] = offset > 0 ? 0.86 : -0.86;
      const double since = t - (250 + 10) * dt;  // a 50 ms half-sine from 20 ms into the window
      const double shape = since >= 0.0 && since < 0.05 ? std::sin(M_PI * since / 0.05) : 0.0;
      lagged += 150.0 * dt * (shape - lagged);
      s.tau_ext += lagged * contact;
      s.r_tau = s.tau_ext;
      s.current = VectorJ::Constant(6, t);
      s.tau_ext_level = VectorJ::Constant(6, 1.0);
      s.tau_ext_level[2] = 0.8;
      (k < 250 ? w.ref : w.win).push_back(s);
    }
    return w;
  };
  const auto steady = [&](double) { return qd[2]; };
  for (unsigned seed : {31u, 32u, 33u}) {
    const SyntheticWindow w = worn(seed, VectorJ::Zero(6), -0.45, steady);
    const Hypothesis h = diagnose(m, w.win, 0.0, 2, DiagnosisOptions{}, &w.ref).front();
    EXPECT_EQ(h.fault, FaultClass::Resistance) << "seed " << seed << ": " << h.detail;
    EXPECT_EQ(h.joint, 2) << h.detail;
    EXPECT_NEAR(h.magnitude, 0.45, 0.05) << h.detail;
    EXPECT_EQ(h.units, "N·m");
  }
  // a 3 N·m contact on the forearm on top of the same offset departs from it by far more than noise
  const VectorJ forearm = contact_torque(m, q, 2, Eigen::Vector3d(-0.1, 0.0, 0.03), Eigen::Vector3d(0.3, 1.0, -0.2), 3.0);
  {
    const SyntheticWindow w = worn(34, forearm, -0.45, steady);
    const Hypothesis h = diagnose(m, w.win, 0.06, 2, DiagnosisOptions{}, &w.ref).front();
    EXPECT_EQ(h.fault, FaultClass::Collision) << h.detail;
  }
  // an offset with the motion is no resistance; one measured across J3's reversal is no steady level
  const auto not_the_rule = [](const Hypothesis& h) { return h.detail.find("before the raise") == std::string::npos; };
  {
    const SyntheticWindow w = worn(35, VectorJ::Zero(6), 0.45, steady);
    const Hypothesis h = diagnose(m, w.win, 0.0, 2, DiagnosisOptions{}, &w.ref).front();
    EXPECT_TRUE(not_the_rule(h)) << h.detail;
  }
  {
    const SyntheticWindow w = worn(36, VectorJ::Zero(6), -0.45, [](double t) { return t < 0.46 ? -0.3 : 0.8; });
    const Hypothesis h = diagnose(m, w.win, 0.0, 2, DiagnosisOptions{}, &w.ref).front();
    EXPECT_TRUE(not_the_rule(h)) << h.detail;
  }
  // a joint that started this way 0.3 s before the window (a pick-and-place move from rest): the
  // level since it started is the steady one
  {
    const SyntheticWindow w = worn(37, VectorJ::Zero(6), -0.45, [](double t) { return t < 0.2 ? 0.0 : 0.8; });
    const Hypothesis h = diagnose(m, w.win, 0.0, 2, DiagnosisOptions{}, &w.ref).front();
    EXPECT_EQ(h.fault, FaultClass::Resistance) << h.detail;
    EXPECT_NEAR(h.magnitude, 0.45, 0.05) << h.detail;
    EXPECT_GT(h.explained, 0.5) << "the offset is most of what the joints read, in units of their thresholds";
  }
}

// A reference of 250 samples and a window of `samples` after it, at 500 Hz: `fill(i, s)` sets each
// sample's q, qd and tau_ext (i < 0: the reference; qdd and tau_ext start at zero); r_tau is tau_ext,
// the current changes (no frozen channel) and the observer's levels are `level`
SyntheticWindow synthetic_window(int samples, const VectorJ& level, const std::function<void(int, DiagnosisSample&)>& fill) {
  SyntheticWindow w;
  for (int k = 0; k < 250 + samples; ++k) {
    const int i = k - 250;  // window sample
    DiagnosisSample s;
    s.t = k * 0.002;
    s.qdd = VectorJ::Zero(6);
    s.tau_ext = VectorJ::Zero(6);
    fill(i, s);
    s.r_tau = s.tau_ext;
    s.current = VectorJ::Constant(6, s.t);
    s.tau_ext_level = level;
    (i < 0 ? w.ref : w.win).push_back(s);
  }
  return w;
}

// The shape of an alert is read on a joint that crossed its threshold. A wrist resistance's onset on
// the triangle (J6, 0.29 N·m over a 0.25 N·m threshold) was read as a pulse on J4: at rest, far
// under its own threshold, with so little noise that a 0.1 N·m blip stood out more than J6's step;
// the window was then a "contact on link 1", whose per-sample force fits the twin's misfit on J1 as
// well (held-out set resistance_heldout, docs/validation.md). Without the rule 4 of these 6 windows
// are Unknown (a contact at 55-59 %).
TEST(ContactIsolation, AnAlertsShapeIsReadOnAJointThatCrossedItsThreshold) {
  const model::RobotModel m = model::load_robot("ur3e");
  VectorJ q(6), qd(6);
  q << 0.3, -1.2, 1.4, -1.6, 0.9, 0.2;
  qd << 0.07, 0.08, -0.08, 0.0, 0.0, 0.07;
  for (unsigned seed : {41u, 42u, 43u, 44u, 45u, 46u}) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0.0, 1.0);
    const VectorJ sd = (VectorJ(6) << 0.2, 0.2, 0.2, 0.004, 0.004, 0.1).finished();
    const SyntheticWindow w = synthetic_window(81, (VectorJ(6) << 1.0, 1.5, 1.0, 0.2, 0.2, 0.25).finished(), [&](int i, DiagnosisSample& s) {
      s.q = q + qd * s.t;
      s.qd = qd;
      for (int j = 0; j < 6; ++j) s.tau_ext[j] = sd[j] * std::max(-2.0, std::min(2.0, noise(rng)));
      s.tau_ext[0] += 0.15;  // the twin's misfit on a moving J1, under its threshold
      if (i >= 0) s.tau_ext[5] += 0.3;  // J6's extra friction, there since just before the raise
      if (i >= 5 && i < 15) s.tau_ext[3] -= 0.12 * std::sin(M_PI * (i - 5) / 10.0);  // J4's blip, under its threshold
    });
    const Hypothesis h = diagnose(m, w.win, 0.12, 5, DiagnosisOptions{}, &w.ref).front();
    EXPECT_EQ(h.fault, FaultClass::Resistance) << "seed " << seed << ": " << h.detail;
    EXPECT_EQ(h.joint, 5) << h.detail;
    EXPECT_NEAR(h.magnitude, 0.3, 0.06) << h.detail;
  }
}

// A joint at rest through the window holds what its static friction holds. At each stop of a
// pick-and-place the shoulder and elbow hold 0.4-0.7 N·m, under their thresholds; scored in N·m
// that was most of the window, a contact's per-sample force fitted it, and a wrist resistance that
// raised the alert explained a tenth of the window: "contact on link 1", or "payload -0.03 kg" with
// five false alarms (held-out set resistance_heldout, docs/validation.md). With a resting joint's
// residual shrunk to what it is in units of the friction it may hold (times its noise at rest) the
// resistance is what the window shows. Unshrunk, each of these windows reads "payload +0.18 kg".
TEST(ContactIsolation, WhatRestingJointsHoldDoesNotHideAWristResistance) {
  const model::RobotModel m = model::load_robot("ur3e");
  VectorJ q(6), qd(6);
  q << -0.6, -1.4, 1.3, -1.5, -1.3, 0.3;
  qd << 0.9, 0.0, 0.0, 0.0, 0.45, -0.5;  // a transfer: J1 and the wrist move, the arm rests
  DiagnosisOptions options;
  options.static_friction = (VectorJ(6) << 0.9, 0.9, 0.7, 0.5, 0.5, 0.4).finished();
  for (unsigned seed : {51u, 52u, 53u, 54u}) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0.0, 1.0);
    // the reference: the arm moving (its noise is the moving joints'), the window: at rest
    const VectorJ sd = (VectorJ(6) << 0.15, 0.25, 0.2, 0.05, 0.05, 0.05).finished();
    const SyntheticWindow w = synthetic_window(83, (VectorJ(6) << 1.2, 1.4, 1.2, 0.5, 0.45, 0.45).finished(), [&](int i, DiagnosisSample& s) {
      s.qd = qd;
      if (i < 0) s.qd[1] = 0.3, s.qd[2] = -0.3;
      s.q = q + s.qd * s.t;
      for (int j = 0; j < 6; ++j) s.tau_ext[j] = (i >= 0 && (j == 1 || j == 2) ? 0.02 : sd[j]) * std::max(-2.5, std::min(2.5, noise(rng)));
      if (i >= 0) {
        s.tau_ext[1] -= 0.65, s.tau_ext[2] -= 0.5;  // held since the arm stopped
        s.tau_ext[4] += 0.6;                         // J5's extra friction (it moves +)
      }
    });
    const Hypothesis h = diagnose(m, w.win, 0.12, 4, options, &w.ref).front();
    EXPECT_EQ(h.fault, FaultClass::Resistance) << "seed " << seed << ": " << h.detail;
    EXPECT_EQ(h.joint, 4) << h.detail;
    EXPECT_NEAR(h.magnitude, 0.6, 0.1) << h.detail;
  }
}

// A window and its reference as the monitor handed them to diagnose, with the options and the
// alert's duration and joint (tests/data/monitor_res*_window.csv, written from diagnose()'s
// arguments while the evaluate twin of session 39 watched a resistance_heldout scenario)
struct RecordedWindow {
  std::vector<DiagnosisSample> ref, win;
  DiagnosisOptions options;
  double duration = 0.0;
  int joint = -1;
  std::vector<Hypothesis> diagnose() const { return monitor::diagnose(model::load_robot("ur3e"), win, duration, joint, options, &ref); }
};
RecordedWindow recorded_window(const std::string& name) {
  RecordedWindow r;
  std::ifstream f(std::string(TWINWATCH_SOURCE_DIR) + "/tests/data/" + name);
  if (!f) throw std::runtime_error("cannot open tests/data/" + name);
  const auto vec = [](const std::vector<double>& c, size_t at) {
    VectorJ v(6);
    for (int j = 0; j < 6; ++j) v[j] = c[at + static_cast<size_t>(j)];
    return v;
  };
  for (std::string line; std::getline(f, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    std::string kind, cell;
    std::getline(ss, kind, ',');
    std::vector<double> c;
    while (std::getline(ss, cell, ',')) c.push_back(std::stod(cell));
    if (kind == "options") {
      r.duration = c[0], r.joint = static_cast<int>(c[1]), r.options.min_explained = c[2], r.options.collision_max_duration = c[3];
      r.options.frozen_samples = static_cast<int>(c[4]);
    } else if (kind == "payload_com") {
      r.options.payload_com = Eigen::Vector3d(c[0], c[1], c[2]);
    } else if (kind == "static_friction") {
      r.options.static_friction = vec(c, 0);
    } else {
      if (c.size() != 51u) throw std::runtime_error(name + ": a sample of " + std::to_string(c.size()) + " numbers, expected 51");
      DiagnosisSample x;
      x.t = c[0], x.q = vec(c, 1), x.qd = vec(c, 7), x.qdd = vec(c, 13), x.r_tau = vec(c, 19), x.r_drive = vec(c, 25);
      x.current = vec(c, 31), x.tau_ext = vec(c, 37), x.tau_ext_level = vec(c, 43);
      x.digital_outputs = static_cast<std::uint64_t>(c[49]), x.gap_before = c[50] != 0.0;
      (kind == "ref" ? r.ref : r.win).push_back(x);
    }
  }
  return r;
}

// the hypotheses ranked, one a line, for a failure's message
std::string ranked(const std::vector<Hypothesis>& h) {
  std::string out;
  for (const Hypothesis& x : h) out += fmt::format("\n{} ({:.3f}): {}", to_string(x.fault), x.explained, x.detail);
  return out;
}

// What a resting joint holds is uncertain by the friction that may hold it (variance F^2 / 3) as
// well as by its noise: both are the noise a signature cannot explain in the shrunk residual. With
// its noise alone, J2 holding -0.68 N·m at a stop, more than its breakaway friction, stayed signal,
// which a contact's per-sample force on link 1 claimed beside a 0.5 N·m J6 resistance: "contact on
// link 1, 23 %", and a false alarm (resistance_heldout res_23, sessions 41-42: its longer look). The
// evaluate twin's residuals, which a test twin does not reproduce; the UR3e's nominal kinematics
// stand in for the twin's.
TEST(ContactIsolation, WhatARestingJointHoldsBeyondItsBreakawayIsNoContact) {
  const RecordedWindow w = recorded_window("monitor_res23_window.csv");
  ASSERT_EQ(w.ref.size(), 250u);
  ASSERT_EQ(w.win.size(), 553u);
  const std::vector<Hypothesis> h = w.diagnose();
  SCOPED_TRACE(ranked(h));
  EXPECT_NE(h.front().fault, FaultClass::Collision);
  // the J6 resistance is the signature ranked first
  const auto first = std::find_if(h.begin(), h.end(), [](const Hypothesis& x) { return x.fault != FaultClass::Unknown; });
  ASSERT_NE(first, h.end());
  EXPECT_EQ(first->fault, FaultClass::Resistance);
  EXPECT_EQ(first->joint, 5);
  EXPECT_NEAR(first->magnitude, 0.5, 0.1);
}

// A one-joint hypothesis is fitted on the joint's own residual in N·m, and its share is of the
// window's weighted energy: rescaled by the joint's weight over the weighted total. Left as a share
// of the unweighted energy, a 0.63 N·m J5 resistance on the pick-and-place (its first look, the
// shoulder and elbow at rest) read as "payload -0.03 kg", with five false alarms after it
// (resistance_heldout res_22, session 42).
TEST(ContactIsolation, AOneJointResistanceIsScoredOnTheWeightedEnergy) {
  const RecordedWindow w = recorded_window("monitor_res22_window.csv");
  ASSERT_FALSE(w.win.empty());
  const std::vector<Hypothesis> h = w.diagnose();
  SCOPED_TRACE(ranked(h));
  // (its size is the longer look's: this first look reads the level the joint stood at before the raise)
  EXPECT_EQ(h.front().fault, FaultClass::Resistance);
  EXPECT_EQ(h.front().joint, 4);
  EXPECT_EQ(std::count_if(h.begin(), h.end(), [](const Hypothesis& x) { return x.fault == FaultClass::PayloadChange && x.explained > 0.3; }), 0);
}

}  // namespace
}  // namespace twinwatch::monitor

namespace twinwatch::monitor {

// A frozen channel explains an alert only when it was frozen at the alert's raise (session 55): a
// persistent alert looked at again later took a stretch that froze long after its raise, in its
// window, for its cause (a real Kinova log: a J5 alert raised at 0.05 s became "J1 frozen for 87
// samples", beside the freeze's own event). Without the raise time, any run in the window counts.
TEST(Diagnosis, AFrozenChannelExplainsAnAlertOnlyWhenFrozenAtItsRaise) {
  const model::RobotModel m = model::load_robot("ur3e");
  std::vector<DiagnosisSample> win;
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (int k = 0; k < 200; ++k) {
    DiagnosisSample s;
    s.t = 0.002 * k;
    s.q = VectorJ::Constant(6, 0.3);
    s.qd = VectorJ::Constant(6, 0.5);
    s.qdd = VectorJ::Zero(6);
    s.r_tau = VectorJ::Zero(6);
    for (int j = 0; j < 6; ++j) s.r_tau[j] = noise(rng);
    s.r_tau[4] += 2.0;  // (the alert's own residual, on J5)
    s.current = VectorJ::Constant(6, 1.0) + 0.01 * k * VectorJ::Ones(6);
    if (k >= 120 && k < 180) s.current[0] = 2.25;  // J1 frozen from 0.24 to 0.358 s while it moves
    win.push_back(s);
  }
  const auto frozen = [&](double raised_at) {
    DiagnosisOptions o;
    o.raised_at = raised_at;
    for (const Hypothesis& h : diagnose(m, win, 0.4, 4, o, nullptr))
      if (h.fault == FaultClass::SensorFault && h.joint == 0 && h.detail.find("frozen") != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(frozen(std::numeric_limits<double>::quiet_NaN())) << "any time: the run counts";
  EXPECT_TRUE(frozen(0.30)) << "raised while J1 was frozen";
  EXPECT_FALSE(frozen(0.02)) << "raised long before J1 froze";
  EXPECT_FALSE(frozen(0.39)) << "raised after J1 came back";
}

}  // namespace twinwatch::monitor
