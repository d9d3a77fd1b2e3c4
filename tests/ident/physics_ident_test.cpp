// Identification from simulated recordings only: the twin never sees the simulator's truth; the
// test (evaluation code) compares what came out with it.
#include "twinwatch/ident/physics_ident.hpp"
#include "twinwatch/device/recording.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <numeric>
#include <random>

#include "twinwatch/core/error.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "twinwatch/signal/metrics.hpp"
#include "error_text.hpp"

namespace twinwatch::ident {
namespace {

device::Recording simulate(const std::string& scenario, double duration) {
  sim::Scenario s = sim::load_scenario(std::string(TWINWATCH_SOURCE_DIR) + "/scenarios/ur3e/" + scenario + ".yaml");
  s.options.duration = duration;
  device::Recording rec;
  rec.path = scenario;
  rec.n_dof = 6;
  rec.present = sim::Simulator::fields();
  sim::make_simulator(s)->run([&](const RobotSample& x) { rec.samples.push_back(x); });
  return rec;
}

struct Fixture : ::testing::Test {
  static void SetUpTestSuite() {
    excitation = new device::Recording(simulate("excitation", 60));
    figure8 = new device::Recording(simulate("nominal_figure_eight", 40));
    model::RigidBodyInertia p;
    p.mass = 0.5;
    p.com = Eigen::Vector3d(0, 0, 0.04);
    fit_report = new IdentReport;
    twin = new TwinModel(identify_physics("ur3e", {{excitation, {}}, {figure8, p}}, IdentOptions{}, *fit_report));
    twin_joint = twin;
    IdentReport alt_report;
    IdentOptions alternating;
    alternating.efficiency_fit = EfficiencyFit::Alternating;
    twin_alt = new TwinModel(identify_physics("ur3e", {{excitation, {}}, {figure8, p}}, alternating, alt_report));
  }
  static void TearDownTestSuite() {
    delete excitation;
    delete figure8;
    delete twin;
    delete twin_alt;
    delete fit_report;
  }
  static device::Recording* excitation;
  static device::Recording* figure8;
  static TwinModel* twin;        // the default identification (c_gen fitted jointly, EfficiencyFit::Joint)
  static TwinModel* twin_joint;  // the same twin, named where the test compares the two fits
  static TwinModel* twin_alt;    // c_gen fitted by alternating passes (the first version)
  static IdentReport* fit_report;  // the default identification's report
};
device::Recording* Fixture::excitation = nullptr;
device::Recording* Fixture::figure8 = nullptr;
TwinModel* Fixture::twin = nullptr;
TwinModel* Fixture::twin_joint = nullptr;
TwinModel* Fixture::twin_alt = nullptr;
IdentReport* Fixture::fit_report = nullptr;

// audit of session 22: a known payload fixes the torque scale only where it differs between the
// recordings. Carried in every one, it is part of the last link to the fit: a single recording with
// its 0.5 kg gave J2-J5 gains of 0.95-2.0 N·m/A marked as identified (11.4 from a pair), and the
// monitor then read a 0.8 N·m resistance as 0.17 N·m. A payload declared on a recording that does
// not carry it fixes nothing either (every gain unidentified, the monitor used 1 N·m/A and printed
// N·m). Both are relative twins now, with a note saying why.
TEST_F(Fixture, AKnownPayloadFixesTheGainsOnlyWhereTheRecordingsDifferInIt) {
  model::RigidBodyInertia p;
  p.mass = 0.5;
  p.com = Eigen::Vector3d(0, 0, 0.04);
  const auto has_note = [](const IdentReport& r, const std::string& text) {
    return std::any_of(r.notes.begin(), r.notes.end(), [&](const std::string& n) { return n.find(text) != std::string::npos; });
  };
  IdentReport same;
  const TwinModel one = identify_physics("ur3e", {{figure8, p}}, IdentOptions{}, same);
  EXPECT_FALSE(one.gains_known());
  for (const auto& d : one.joints) EXPECT_FALSE(d.gain_identified);
  EXPECT_TRUE(has_note(same, "every recording carries the same known payload (0.50 kg)"));
  // the pair the monitor tests use is absolute, as before
  EXPECT_TRUE(twin->gains_known());
  // declared on the excitation, which carries none, and not on a copy of it: no current to show it
  IdentReport none;
  device::Recording copy = *excitation;
  copy.path = "copy";
  const TwinModel declared = identify_physics("ur3e", {{excitation, {}}, {&copy, p}}, IdentOptions{}, none);
  EXPECT_FALSE(declared.gains_known());
  EXPECT_TRUE(has_note(none, "the known payload's current stands out on no joint"));
}

// the training fit gets close to the measurement noise of each joint (DESIGN.md rule 4 levels);
// what is left is the truth the twin does not model (Stribeck, pre-sliding, ripple: DESIGN.md rule 2)
TEST_F(Fixture, TrainingFitReachesTheNoiseFloor) {
  const sim::PlantTruth truth = sim::default_truth(twin->robot(), 1);
  for (int j = 0; j < 6; ++j) {
    const double sigma = truth.joints[static_cast<size_t>(j)].current_sigma;
    EXPECT_LT(twin->joints[static_cast<size_t>(j)].rmse, 1.8 * sigma) << "joint " << j;
  }
}

// drive gains of the joints the payload loads (J2-J4) come out near the simulator's kt N eta:
// measured -0.01 %, +0.07 %, +2.4 % (session 51; J4 carries the least of the payload's torque), held
// to 1 %, 1 %, 5 % (the test held 25 % before)
TEST_F(Fixture, KnownPayloadIdentifiesTheDriveGains) {
  ASSERT_TRUE(twin->gains_known());
  const sim::PlantTruth truth = sim::default_truth(twin->robot(), 1);
  const double tolerance[] = {0.01, 0.01, 0.05};
  for (int j = 1; j <= 3; ++j) {
    const auto& jt = truth.joints[static_cast<size_t>(j)];
    const double g_true = jt.kt * jt.gear_ratio * jt.eta;
    EXPECT_NEAR(twin->joints[static_cast<size_t>(j)].gain, g_true, tolerance[j - 1] * g_true) << "joint " << j;
  }
}

// the back-driven factor c_gen = eta * eta_rev of the simulator's drive (UR3e eq. 3) is recovered
// on the joints that are back-driven often (gravity-loaded J2-J4: 40-55 % of the samples); an
// alternating fit of c_gen and theta (the first version) stops at 0.98 on J2
// against 0.765
TEST_F(Fixture, RecoversTheBackDrivenEfficiencyOfTheSimulatedDrives) {
  const sim::PlantTruth truth = sim::default_truth(twin->robot(), 1);
  EXPECT_GT(twin_alt->joints[1].c_gen, 0.95);  // the alternating fit's known bias (documented, not a goal)
  for (int j = 1; j <= 3; ++j) {
    const auto& jt = truth.joints[static_cast<size_t>(j)];
    const double c_true = jt.eta * jt.eta_rev;
    // J4's wrist load is small next to its friction: wider band
    const double tol = j == 3 ? 0.12 : 0.04;
    EXPECT_NEAR(twin_joint->joints[static_cast<size_t>(j)].c_gen, c_true, tol * c_true) << "joint " << j;
  }
  // and the joint fit predicts the training runs better on the back-driven joints J2-J4
  for (int j = 1; j <= 3; ++j) {
    EXPECT_LT(twin_joint->joints[static_cast<size_t>(j)].rmse, 0.97 * twin_alt->joints[static_cast<size_t>(j)].rmse) << "joint " << j;
  }
}

// the joint fit flags the gains the known payload does not fix: the payload's COM lies on the J6
// axis (no torque), J1 sees only its small inertia; the flag survives the twin file
TEST_F(Fixture, GainsTheKnownPayloadDoesNotLoadAreFlagged) {
  const sim::PlantTruth truth = sim::default_truth(twin->robot(), 1);
  for (int j = 1; j <= 2; ++j) {
    const auto& jt = truth.joints[static_cast<size_t>(j)];
    const double g_true = jt.kt * jt.gear_ratio * jt.eta;
    EXPECT_TRUE(twin_joint->joints[static_cast<size_t>(j)].gain_identified) << "joint " << j;
    EXPECT_NEAR(twin_joint->joints[static_cast<size_t>(j)].gain, g_true, 0.03 * g_true) << "joint " << j;
  }
  EXPECT_FALSE(twin_joint->joints[0].gain_identified);
  EXPECT_FALSE(twin_joint->joints[5].gain_identified);
  const TwinModel back = TwinModel::from_json(twin_joint->to_json(), "twin.json");
  for (int j = 0; j < 6; ++j)
    EXPECT_EQ(back.joints[static_cast<size_t>(j)].gain_identified, twin_joint->joints[static_cast<size_t>(j)].gain_identified) << j;
}

// a synthetic recording made by a known twin (the twin's own model, other c_gen, gains and
// Gaussian current noise) on the states of the fixture's runs: the fit returns the factors it
// was made with, including a drive without loss (c_gen = 1)
device::Recording with_currents_of(const device::Recording& rec, const TwinModel& truth_twin, const model::RigidBodyInertia& payload,
                                   double sigma, unsigned seed) {
  device::Recording out = rec;
  TwinModel t = truth_twin;
  t.set_payload(payload);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  const std::vector<VectorJ> qdd = joint_accelerations(rec);
  VectorJ i;
  FrictionMemory memory;
  for (size_t k = 0; k < out.samples.size(); ++k) {
    RobotSample& s = out.samples[k];
    t.advance(memory, s.q);
    t.predict_current(s.q, s.qd, qdd[k], s.temperature, i, &memory);
    for (int j = 0; j < 6; ++j) s.current[j] = i[j] + noise(rng);
  }
  return out;
}

TEST_F(Fixture, RecoversAKnownBackDrivenFactorFromASyntheticRecording) {
  constexpr unsigned kSeed = 17;
  constexpr double kSigma = 0.02;  // [A] DESIGN.md rule 4 level
  TwinModel truth_twin = *twin_joint;
  truth_twin.learned.reset();
  for (JointDrive& d : truth_twin.joints) d.presliding = d.stribeck = 0.0;  // plain Coulomb: c_gen is the subject here
  const double c_set[6] = {1.0, 0.62, 1.0, 0.8, 1.0, 1.0};
  const double g_set[6] = {11.0, 12.0, 9.0, 9.0, 7.0, 7.0};
  for (int j = 0; j < 6; ++j) {
    truth_twin.joints[static_cast<size_t>(j)].c_gen = c_set[j];
    truth_twin.joints[static_cast<size_t>(j)].gain = g_set[j];
  }
  model::RigidBodyInertia p;
  p.mass = 0.5;
  p.com = Eigen::Vector3d(0, 0, 0.04);
  const device::Recording ex = with_currents_of(*excitation, truth_twin, {}, kSigma, kSeed);
  const device::Recording f8 = with_currents_of(*figure8, truth_twin, p, kSigma, kSeed + 1);
  IdentOptions o;
  o.decimate = 2;
  o.efficiency_fit = EfficiencyFit::Joint;
  IdentReport report;
  const TwinModel fit = identify_physics("ur3e", {{&ex, {}}, {&f8, p}}, o, report);
  // J2 (strongly back-driven, 0.62) and J3 (lossless, 1.0) to 2 %, J4 (small load) to 5 %
  const double tol[6] = {0, 0.02, 0.02, 0.05, 0, 0};
  for (int j = 1; j <= 3; ++j) {
    // a lossless drive may fit a hair above 1 and is then pinned to the bound 1
    if (c_set[j] < 1.0) {
      ASSERT_TRUE(report.c_gen_identified[static_cast<size_t>(j)]) << "joint " << j << ", seed " << kSeed;
    }
    EXPECT_NEAR(fit.joints[static_cast<size_t>(j)].c_gen, c_set[j], tol[j] * c_set[j]) << "joint " << j << ", seed " << kSeed;
    // the payload fixes the gains of the joints it loads
    EXPECT_NEAR(fit.joints[static_cast<size_t>(j)].gain, g_set[j], 0.05 * g_set[j]) << "joint " << j << ", seed " << kSeed;
    // and the fit reaches the noise it was given
    EXPECT_LT(fit.joints[static_cast<size_t>(j)].rmse, 1.1 * kSigma) << "joint " << j;
  }
  // J1 and J6 are (almost) never back-driven on these runs: c_gen is not fitted and says so
  EXPECT_FALSE(report.c_gen_identified[5]);
  EXPECT_LT(report.generating_fraction[5], 0.02);
}

TEST_F(Fixture, PredictsAnUntrainedRunWithAnotherSeed) {
  sim::Scenario s = sim::load_scenario(std::string(TWINWATCH_SOURCE_DIR) + "/scenarios/ur3e/nominal_figure_eight.yaml");
  s.options.seed = 99;
  s.options.duration = 16;
  std::vector<RobotSample> rec;
  sim::make_simulator(s)->run([&](const RobotSample& x) { rec.push_back(x); });
  TwinModel t = *twin;
  t.set_payload(s.options.payload);
  std::vector<double> meas, pred;
  VectorJ i;
  for (const auto& x : rec) {
    t.predict_current(x.q, x.qd, x.target_qdd, x.temperature, i);
    meas.push_back(x.current[1]);
    pred.push_back(i[1]);
  }
  const auto m = signal::fit_metrics(meas, pred);
  EXPECT_GT(m.r2, 0.98);
  EXPECT_LT(m.rmse, 0.05);
}

// A twin of an arm with joint torque sensors (session 54): the sensors sit between gear and link, so
// the recordings carry the link side's torque, M qdd + h, and no drive. Identified with
// IdentOptions::joint_torque on simulated sensors (their noise 0.2 % of the torque limit): every gain
// and c_gen stays 1 and the scale is absolute without a known payload; the drive's friction, which
// the motor current carries (UR3e: Coulomb 0.4-0.75 N·m), is not in the sensors and comes out near
// 0; an untrained run at another seed is predicted to within twice the sensors' noise plus what the
// acceleration estimate leaves; it predicts with the link's acceleration, not the target; the file
// keeps the signal and refuses a gain of another value.
TEST(JointTorqueTwin, IsIdentifiedOnTheSensorsWithoutADrive) {
  auto sensed = [](const std::string& name, double duration, unsigned seed) {
    sim::Scenario s = sim::load_scenario(std::string(TWINWATCH_SOURCE_DIR) + "/scenarios/ur3e/" + name + ".yaml");
    s.options.duration = duration;
    s.options.seed = seed;
    s.options.joint_torque_sensors = true;
    device::Recording rec;
    rec.path = name;
    rec.n_dof = 6;
    const auto sim = sim::make_simulator(s);
    rec.present = device::read_as_joint_torque(sim->sample_fields());  // (as the reader reads a file for the twin)
    sim->run([&](const RobotSample& x) {
      rec.samples.push_back(x);
      device::read_as_joint_torque(rec.samples.back());
    });
    return std::make_pair(rec, s);
  };
  const auto [exc, exc_s] = sensed("excitation", 40, 1);
  const auto [fig, fig_s] = sensed("nominal_figure_eight", 30, 2);
  IdentOptions o;
  o.joint_torque = true;
  IdentReport report;
  const TwinModel t0 = identify_physics("ur3e", {{&exc, {}}, {&fig, fig_s.options.payload}}, o, report);
  EXPECT_TRUE(t0.measures_torque());
  EXPECT_TRUE(t0.gains_known());
  EXPECT_STREQ(t0.channel_unit(), "N·m");
  for (const JointDrive& d : t0.joints) {
    EXPECT_EQ(d.gain, 1.0);
    EXPECT_EQ(d.c_gen, 1.0);
    EXPECT_TRUE(d.gain_identified);
    EXPECT_LT(std::abs(d.friction[kCoulomb]), 0.15) << "the sensor sees no drive friction";
  }
  for (const std::string& n : report.notes) EXPECT_THAT(n, ::testing::Not(::testing::HasSubstr("known payload")));
  // an untrained run
  const auto [val, val_s] = sensed("nominal_figure_eight", 16, 99);
  TwinModel t = t0;
  t.set_payload(val_s.options.payload);
  const double sigma[6] = {0.108, 0.108, 0.056, 0.018, 0.018, 0.018};
  const std::vector<VectorJ> qdd = joint_accelerations(val);
  for (int j = 0; j < 6; ++j) {
    std::vector<double> meas, pred;
    VectorJ i;
    for (size_t k = 0; k < val.samples.size(); ++k) {
      const RobotSample& x = val.samples[k];
      t.predict_current(x.q, x.qd, qdd[k], x.temperature, i);
      meas.push_back(x.current[j]);
      pred.push_back(i[j]);
    }
    EXPECT_LT(signal::fit_metrics(meas, pred).rmse, 2.0 * sigma[j] + 0.05) << "J" << j + 1;
  }
  // The sensors read the link's acceleration, not the controller's target (session 55): read for the
  // twin, the run has no target_qdd, and the twin takes the acceleration from actual_qd. On an
  // excitation at another noise seed, its largest 0.1 s mean error on J1-J3 (where inertia is large;
  // the sensor noise averages out to ~0.015 N·m) is about half of what it is with the target, which
  // trails or leads the link (measured: 0.054/0.058/0.034 against 0.102/0.121/0.062 N·m). With the
  // target, the library's excitation raised a false alarm on J2 (ratio 1.07; 0.57 without).
  const auto [ex, ex_s] = sensed("excitation", 20, 98);
  EXPECT_FALSE(ex.present & kFieldTargetQdd);
  const std::vector<VectorJ> link_qdd = joint_accelerations(ex);
  const auto worst_mean_error = [&](int j, bool target) {
    std::vector<double> e;
    VectorJ i;
    for (size_t k = 0; k < ex.samples.size(); ++k) {
      const RobotSample& x = ex.samples[k];
      t0.predict_current(x.q, x.qd, target ? x.target_qdd : link_qdd[k], x.temperature, i);  // (the target is still in the sample)
      e.push_back(x.current[j] - i[j]);
    }
    constexpr size_t kSpan = 50;  // 0.1 s at 500 Hz
    double sum = std::accumulate(e.begin(), e.begin() + kSpan, 0.0), worst = std::abs(sum) / kSpan;
    for (size_t k = kSpan; k < e.size(); ++k) {
      sum += e[k] - e[k - kSpan];
      worst = std::max(worst, std::abs(sum) / kSpan);
    }
    return worst;
  };
  for (int j = 0; j < 3; ++j) {
    const double link = worst_mean_error(j, false), target = worst_mean_error(j, true);
    EXPECT_LT(link, 0.7 * target) << "J" << j + 1;
    EXPECT_LT(link, 0.08) << "J" << j + 1;
  }
  // the file: the signal kept, a gain of another value refused with the joint named
  const TwinModel back = TwinModel::from_json(t0.to_json(), "t.json");
  EXPECT_TRUE(back.measures_torque());
  nlohmann::json j = nlohmann::json::parse(t0.to_json());
  j["joints"][2]["gain"] = 2.0;
  const std::string e = twinwatch::test::error_text<ParseError>([&] { TwinModel::from_json(j.dump(), "t.json"); });
  EXPECT_THAT(e, ::testing::HasSubstr("t.json: field 'joints[2]'"));
  EXPECT_THAT(e, ::testing::HasSubstr("expected gain 1 and c_gen 1"));
  // the acceleration window: absent unless set, kept, and one beyond 0.1 s refused
  EXPECT_FALSE(nlohmann::json::parse(t0.to_json()).contains("acceleration_window"));
  TwinModel w = t0;
  w.acceleration_window = 0.015;
  EXPECT_EQ(TwinModel::from_json(w.to_json(), "t.json").acceleration_window, 0.015);
  j = nlohmann::json::parse(w.to_json());
  j["acceleration_window"] = 0.5;
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { TwinModel::from_json(j.dump(), "t.json"); }),
              ::testing::HasSubstr("field 'acceleration_window': expected a half window in (0, 0.1] s"));
  j = nlohmann::json::parse(t0.to_json());
  j["signal"] = "torque";
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { TwinModel::from_json(j.dump(), "t.json"); }),
              ::testing::HasSubstr("expected \"current\" (motor currents) or \"joint_torque\""));
}

// The velocity's lag is measured on recordings against the central difference of the positions.
// A synthetic joint on a 500 Hz clock, q = 0.5 sin(2 pi 0.7 t) quantised to a 20-bit encoder
// count, streams as its velocity (a) the backward difference of the counts, which lags half a period
// (1 ms), (b) the exact derivative at the sample, no lag, (c) the exact derivative 4 ms late (a
// filter), and (d) in deg/s (a wrong unit), which is refused by its scale against the positions'
// derivative; (e) a joint at constant speed has no acceleration to measure it by. The identified twin of the fixture (simulated UR3e, which
// streams the backward difference) has 1 ms.
TEST_F(Fixture, TheStreamedVelocitysLagIsMeasuredAgainstThePositions) {
  EXPECT_NEAR(twin->velocity_lag, 0.001, 0.00005);
  EXPECT_NEAR(fit_report->velocity_lag.seconds, 0.001, 0.00005);
  EXPECT_NEAR(fit_report->velocity_lag.period, 0.002, 1e-9);
  const double dt = 0.002, w = 2.0 * M_PI * 0.7, lsb = 2.0 * M_PI / (1 << 20);
  const auto make = [&](int kind) {
    device::Recording rec;
    rec.path = "synthetic.csv";
    rec.n_dof = 1;
    rec.present = kFieldActualQd | kFieldTargetQdd;
    rec.median_period = dt;
    double q_prev = 0.0;
    for (int k = 0; k < 5000; ++k) {
      const double t = k * dt;
      RobotSample s = RobotSample::empty(1);
      s.timestamp = t;
      s.present = rec.present;
      const bool still = kind == 4;
      const double q = still ? 0.3 * t : 0.5 * std::sin(w * t);
      s.q[0] = std::round(q / lsb) * lsb;
      const double v = still ? 0.3 : 0.5 * w * std::cos(w * t), v_late = 0.5 * w * std::cos(w * (t - 0.004));
      s.target_qdd[0] = still ? 0.0 : -0.5 * w * w * std::sin(w * t);
      s.qd[0] = kind == 0 ? (k == 0 ? v : (s.q[0] - q_prev) / dt) : kind == 1 || kind == 4 ? v : kind == 2 ? v_late : v * 180.0 / M_PI;
      q_prev = s.q[0];
      rec.samples.push_back(s);
    }
    std::vector<std::vector<VectorJ>> acc{joint_accelerations(rec)};
    return estimate_velocity_lag({&rec}, acc);
  };
  const VelocityLag backward = make(0), exact = make(1), late = make(2), degrees = make(3), still = make(4);
  EXPECT_NEAR(backward.seconds, 0.001, 0.00003) << backward.note;
  EXPECT_TRUE(backward.note.empty());
  EXPECT_LT(backward.stderr_s, 0.0001);
  EXPECT_NEAR(exact.seconds, 0.0, 0.00003);
  EXPECT_NEAR(late.seconds, 0.004, 0.0001);
  EXPECT_EQ(degrees.seconds, 0.0);
  EXPECT_THAT(degrees.note, ::testing::HasSubstr("actual_qd is 57.3 x the derivative of actual_q"));
  EXPECT_EQ(still.seconds, 0.0);
  EXPECT_THAT(still.note, ::testing::HasSubstr("acceleration rms 0 rad/s²"));
  // a lag the user gives is taken as given; out of range is refused
  IdentOptions given;
  given.velocity_lag = 0.0;
  IdentReport rep;
  model::RigidBodyInertia p;
  p.mass = 0.5;
  p.com = Eigen::Vector3d(0, 0, 0.04);
  EXPECT_EQ(identify_physics("ur3e", {{excitation, {}}, {figure8, p}}, given, rep).velocity_lag, 0.0);
  EXPECT_TRUE(rep.velocity_lag.given);
  given.velocity_lag = 0.5;
  EXPECT_THROW(given.validate(), InvalidArgument);
}

// Near standstill the streamed velocity is 0 for as long as a joint moves less than an encoder
// count a period; the drive's direction is then read on the controller's target, carried by the
// joint's measured lead, with a blend as wide as the joint's tracking error there.
TEST_F(Fixture, HowCloselyAJointFollowsItsTargetIsMeasuredNearStandstill) {
  // the simulated UR3e: its joints follow their targets within a few ms; J2 at a slow reversal within
  // a mrad/s, more at a fast one (it sticks and breaks away)
  ASSERT_FALSE(twin->target_direction.empty()) << fit_report->target_direction.note;
  for (int j = 0; j < 6; ++j) {
    EXPECT_LT(std::abs(twin->target_direction.lead[j]), 0.01) << "J" << j + 1;
    EXPECT_LE(twin->target_direction.width[j], TwinModel::kTargetDirectionWidthMax);
  }
  EXPECT_LT(twin->target_direction.width[1], 0.002) << "J2 follows its target near standstill within 2 mrad/s";
  ASSERT_EQ(fit_report->target_direction.switches.size(), 6u);
  EXPECT_GE(fit_report->target_direction.switches[1], 5) << "J2's current steps at its loaded reversals";
  EXPECT_GE(twin->target_direction.width_time[1], 0.005) << "its switch falls ms from the target's crossing";
  EXPECT_LE(twin->target_direction.width_time[1], 0.04);
  // a synthetic joint: positions = the target's, 3 ms late, plus a tracking error whose velocity has
  // rms sqrt(w^2 + (tau qdd)^2), w = 2 mrad/s, tau = 10 ms; reversals at 0.08 rad/s² (first half) and
  // 1.26 rad/s² (second half), so that the two parts of the width can be told apart
  const double dt = 0.002, A = 0.2, late = 0.003, w0 = 0.002, tau = 0.01;
  const auto make = [&](int kind) {
    device::Recording rec;
    rec.path = "synthetic.csv";
    rec.n_dof = 1;
    rec.present = kFieldActualQd | kFieldTargetQdd | (kind == 1 ? 0u : kFieldTargetQd);
    rec.median_period = dt;
    std::mt19937 rng(7);
    std::normal_distribution<double> normal;
    double drift = 0.0, phase = 0.0;
    for (int k = 0; k < 40000; ++k) {
      const double t = k * dt, om = 2.0 * M_PI * (k < 20000 ? 0.1 : 0.4);
      phase += om * dt;
      RobotSample s = RobotSample::empty(1);
      s.timestamp = t;
      s.present = rec.present;
      // kind 2: a target that is not this joint's (another joint's column)
      s.target_qd[0] = kind == 2 ? A * om * std::cos(1.7 * phase + 1.0) : A * om * std::cos(phase);
      s.target_qdd[0] = -A * om * om * std::sin(phase);
      // the error's increments: the central difference of positions averages two of them
      drift += std::sqrt(2.0) * std::hypot(w0, tau * s.target_qdd[0]) * dt * normal(rng);
      s.q[0] = A * std::sin(phase - om * late) + drift;
      s.qd[0] = A * om * std::cos(phase - om * late);
      rec.samples.push_back(s);
    }
    return rec;
  };
  const device::Recording tracked = make(0), no_target = make(1), other = make(2);
  const TargetDirectionFit fit = estimate_target_direction({&tracked});
  ASSERT_FALSE(fit.direction.empty()) << fit.note;
  EXPECT_NEAR(fit.direction.lead[0], -late, 0.0003);
  EXPECT_NEAR(fit.direction.width[0], w0, 0.0003);
  EXPECT_NEAR(fit.direction.width_time[0], tau, 0.002);
  EXPECT_EQ(fit.samples, 39998);
  const TargetDirectionFit none = estimate_target_direction({&tracked, &no_target});
  EXPECT_TRUE(none.direction.empty());
  EXPECT_THAT(none.note, ::testing::HasSubstr("synthetic.csv has no target_qd"));
  const TargetDirectionFit wrong = estimate_target_direction({&other});
  EXPECT_TRUE(wrong.direction.empty());
  EXPECT_THAT(wrong.note, ::testing::HasSubstr("J1 is"));
  EXPECT_THAT(wrong.note, ::testing::HasSubstr("rms off its target_qd (expected at most 0.05: is target_qd that joint's, in rad/s?)"));
  // identify without it: the twin of before
  IdentOptions off;
  off.target_direction = false;
  IdentReport rep;
  model::RigidBodyInertia p;
  p.mass = 0.5;
  p.com = Eigen::Vector3d(0, 0, 0.04);
  EXPECT_TRUE(identify_physics("ur3e", {{excitation, {}}, {figure8, p}}, off, rep).target_direction.empty());
}

TEST_F(Fixture, TwinFileRoundTrips) {
  const TwinModel back = TwinModel::from_json(twin->to_json(), "twin.json");
  VectorJ a, b;
  const RobotSample& s = figure8->samples[1234];
  twin->predict_current(s.q, s.qd, s.target_qdd, s.temperature, a);
  back.predict_current(s.q, s.qd, s.target_qdd, s.temperature, b);
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(TwinFile, MalformedFilesNameTheField) {
  EXPECT_THAT([] {
    try {
      TwinModel::from_json("{\"format\": \"other\"}", "t.json");
    } catch (const ParseError& e) {
      return std::string(e.what());
    }
    return std::string();
  }(), ::testing::HasSubstr("field 'format'"));
  EXPECT_THAT([] {
    nlohmann::json j = nlohmann::json::parse(TwinModel("ur3e", model::load_robot("ur3e")).to_json());
    j["joints"] = nlohmann::json::array();
    try {
      TwinModel::from_json(j.dump(), "t.json");
    } catch (const ParseError& e) {
      return std::string(e.what());
    }
    return std::string();
  }(), ::testing::HasSubstr("expected 6 joints"));
}

// audit of session 16: the 200-sample floor was checked before decimation and the reversal
// screen, so a fit on 0 or 1 sample was written as a twin with RMSE 0
TEST_F(Fixture, TooFewSamplesLeftAfterDecimationOrScreeningAreRefused) {
  IdentReport rep;
  IdentOptions o;
  o.decimate = 100000;
  try {
    identify_physics("ur3e", {{excitation, {}}}, o, rep);
    FAIL() << "a fit on one sample per joint passed";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("identify: J1 keeps 1 of 30000 samples after decimation by 100000"));
  }
  o.decimate = 1;
  o.reversal_screen = 100.0;
  EXPECT_THROW(identify_physics("ur3e", {{excitation, {}}}, o, rep), InvalidArgument);
}

// validate reads a recording row by row: its accelerations come a few samples late from a stream,
// which must give what the zero-phase smoothing over the whole recording gives (written out here as
// it was before the stream: a centred mean of qd over +-3 samples cut at the ends, then central
// differences on the timestamps), every sample once and in order, whatever the recording's length
// A 1 kHz velocity with noise (a Panda's dq, session 54): differenced over the default +-3 samples its
// noise dominates the acceleration; the half window a twin keeps (TwinModel::acceleration_window)
// smooths it to the motion's own, and the stream gives what the whole recording does at any width.
TEST(JointAccelerations, AWiderWindowTakesTheVelocitysNoiseOutOfTheAcceleration) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 0.01);  // [rad/s]
  device::Recording rec;
  rec.n_dof = 1;
  rec.present = kFieldActualQd;
  rec.median_period = 0.001;
  std::vector<double> truth;
  for (int k = 0; k < 5000; ++k) {
    RobotSample s = RobotSample::empty(1);
    s.timestamp = 0.001 * k;
    s.qd[0] = 0.5 * std::sin(2.0 * s.timestamp) + g(rng);
    truth.push_back(1.0 * std::cos(2.0 * s.timestamp));
    rec.samples.push_back(s);
  }
  TwinModel t;
  EXPECT_EQ(t.acceleration_half_width(0.001), 3);
  t.acceleration_window = 0.015;
  EXPECT_EQ(t.acceleration_half_width(0.001), 15);
  EXPECT_EQ(t.acceleration_half_width(0.002), 8);  // (7.5 rounds up)
  auto rms_error = [&](int half) {
    const std::vector<VectorJ> a = joint_accelerations(rec, half);
    double e2 = 0.0;
    for (size_t k = 100; k + 100 < a.size(); ++k) e2 += std::pow(a[k][0] - truth[k], 2);
    return std::sqrt(e2 / static_cast<double>(a.size() - 200));
  };
  const double narrow = rms_error(3), wide = rms_error(15);
  // the mean's central difference takes two samples in and two out of 2h + 1: its noise is
  // 2 sigma / ((2h + 1) 2 dt), 1.43 rad/s^2 at h = 3 and 0.32 at h = 15 (the motion's own change over
  // the window adds 1 % of the amplitude)
  EXPECT_NEAR(narrow, 2 * 0.01 / (7 * 0.002), 0.15);
  EXPECT_NEAR(wide, 2 * 0.01 / (31 * 0.002), 0.05);
  // the stream at that width gives the whole recording's values
  JointAccelerationStream stream(1, rec.present, 15);
  std::vector<VectorJ> streamed;
  const JointAccelerationStream::Ready take = [&](const RobotSample&, const VectorJ& qdd) { streamed.push_back(qdd); };
  for (const auto& x : rec.samples) stream.push(x, take);
  stream.finish(take);
  EXPECT_EQ(streamed, joint_accelerations(rec, 15));
}

TEST(JointAccelerations, StreamedTheyAreTheWholeRecordingsZeroPhaseDifferences) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  for (const size_t N : {size_t{1}, size_t{2}, size_t{3}, size_t{4}, size_t{7}, size_t{8}, size_t{9}, size_t{500}}) {
    device::Recording rec;
    rec.n_dof = 2;
    rec.present = kFieldActualQd;
    double t = 0.0;
    for (size_t k = 0; k < N; ++k) {
      RobotSample s = RobotSample::empty(2);
      t += k == N / 2 ? 0.006 : 0.002;  // one gap: the differences take the timestamps
      s.timestamp = t;
      s.qd << std::sin(3.0 * t) + 0.01 * g(rng), g(rng);
      rec.samples.push_back(s);
    }
    std::vector<VectorJ> expected(N);
    std::vector<VectorJ> qs(N);
    for (size_t k = 0; k < N; ++k) {
      VectorJ sum = VectorJ::Zero(2);
      int cnt = 0;
      for (long m = static_cast<long>(k) - 3; m <= static_cast<long>(k) + 3; ++m)
        if (m >= 0 && m < static_cast<long>(N)) sum += rec.samples[static_cast<size_t>(m)].qd, ++cnt;
      qs[k] = sum / cnt;
    }
    for (size_t k = 0; k < N; ++k) {
      const size_t a = k == 0 ? 0 : k - 1, b = std::min(N - 1, k + 1);
      const double dt = rec.samples[b].timestamp - rec.samples[a].timestamp;
      expected[k] = dt > 0 ? VectorJ((qs[b] - qs[a]) / dt) : VectorJ(VectorJ::Zero(2));
    }
    JointAccelerationStream stream(2, rec.present);
    std::vector<double> order;
    std::vector<VectorJ> got;
    size_t most_waiting = 0, pushed = 0;
    const JointAccelerationStream::Ready take = [&](const RobotSample& s, const VectorJ& qdd) {
      order.push_back(s.timestamp);
      got.push_back(qdd);
    };
    for (const RobotSample& s : rec.samples) {
      stream.push(s, take);
      most_waiting = std::max(most_waiting, ++pushed - got.size());
    }
    stream.finish(take);
    ASSERT_EQ(got.size(), N);
    EXPECT_LE(most_waiting, 5u) << "the smoothing looks 4 samples ahead, no more";
    for (size_t k = 0; k < N; ++k) {
      EXPECT_EQ(order[k], rec.samples[k].timestamp) << "sample " << k << " of " << N;
      EXPECT_EQ(got[k], expected[k]) << "sample " << k << " of " << N;
    }
    EXPECT_EQ(joint_accelerations(rec), expected);
  }
  // with the controller's target_qdd, that, at once
  device::Recording rec;
  rec.n_dof = 1;
  rec.present = kFieldActualQd | kFieldTargetQdd;
  JointAccelerationStream stream(1, rec.present);
  RobotSample s = RobotSample::empty(1);
  s.target_qdd << 0.7;
  int handed = 0;
  stream.push(s, [&](const RobotSample&, const VectorJ& qdd) { handed += qdd[0] == 0.7 ? 1 : 100; });
  EXPECT_EQ(handed, 1);
}

TEST(Identify, RejectsRecordingsWithoutCurrent) {
  device::Recording r;
  r.path = "nocurrent.csv";
  r.n_dof = 6;
  r.present = 0;
  try {
    IdentReport rep;
    identify_physics("ur3e", {{&r, {}}}, IdentOptions{}, rep);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("nocurrent.csv: no actual_current_* columns"));
  }
}

}  // namespace
}  // namespace twinwatch::ident

namespace twinwatch::ident {
namespace {
// the fast prediction path (RNEA on base parameters mapped to standard ones) equals the regressor
// form Y_b beta + Y_last pi_payload + friction, with and without a payload, after beta changes
TEST_F(Fixture, PredictionEqualsTheRegressorForm) {
  TwinModel t = *twin;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> N(0.0, 1.0);
  for (int trial = 0; trial < 30; ++trial) {
    model::RigidBodyInertia p;
    if (trial % 2) {
      p.mass = 0.5 + 0.1 * trial;
      p.com = Eigen::Vector3d(0.01, -0.02, 0.04);
    }
    t.set_payload(p);
    if (trial == 10) t.beta *= 1.1;
    VectorJ q(6), qd(6), qdd(6), temp = VectorJ::Constant(6, 40.0);
    for (int j = 0; j < 6; ++j) q[j] = 2 * N(rng), qd[j] = N(rng), qdd[j] = 3 * N(rng);
    VectorJ tau, cur;
    t.predict(q, qd, qdd, temp, tau, cur);
    model::RegressorMatrix Y;
    VectorJ tau_p;
    t.regress(q, qd, qdd, Y, tau_p);
    for (int j = 0; j < 6; ++j) {
      double expect = tau_p[j];
      for (size_t c = 0; c < t.base_columns.size(); ++c) expect += Y(j, t.base_columns[c]) * t.beta(static_cast<Eigen::Index>(c));
      Eigen::Matrix<double, kFrictionColumns, 1> f;
      t.friction_row(j, qd, qdd, temp, f);
      expect += f.dot(t.joints[static_cast<size_t>(j)].friction);
      // without a memory, the pre-sliding term is at its steady value (0); the Stribeck rise stays
      const JointDrive& d = t.joints[static_cast<size_t>(j)];
      expect += d.stribeck * stribeck_shape(qd[j], d.stribeck_velocity);
      EXPECT_NEAR(tau[j], expect, 1e-9 * (1 + std::abs(expect))) << "trial " << trial << " joint " << j;
    }
  }
}

// predict_pair (the monitor's prediction and its observer's torque in one call) is predict() at the
// first acceleration and predict_torque() at the second, with payload, memory and armature
TEST_F(Fixture, PairedPredictionEqualsTwoPredictions) {
  TwinModel t = *twin;
  for (auto& d : t.joints) d.friction(kArmature) = 0.02;  // the armature term changes with the acceleration
  std::mt19937_64 rng(5);
  std::normal_distribution<double> N(0.0, 1.0);
  FrictionMemory mem;
  VectorJ q = VectorJ::Zero(6);
  t.advance(mem, q);
  for (int trial = 0; trial < 30; ++trial) {
    model::RigidBodyInertia p;
    if (trial % 2) {
      p.mass = 0.3 + 0.1 * trial;
      p.com = Eigen::Vector3d(0.02, 0.01, 0.05);
    }
    t.set_payload(p);
    VectorJ qd(6), qdd(6), qdd2(6), temp = VectorJ::Constant(6, 35.0);
    for (int j = 0; j < 6; ++j) q[j] += 1e-4 * N(rng), qd[j] = 0.2 * N(rng), qdd[j] = 3 * N(rng), qdd2[j] = qdd[j] + 2 * N(rng);
    t.advance(mem, q);
    VectorJ tau, cur, tau2, tau_ref, cur_ref, tau2_ref;
    t.predict_pair(q, qd, qdd, qdd2, temp, tau, cur, tau2, &mem);
    t.predict(q, qd, qdd, temp, tau_ref, cur_ref, &mem);
    t.predict_torque(q, qd, qdd2, temp, tau2_ref, &mem);
    for (int j = 0; j < 6; ++j) {
      EXPECT_NEAR(tau[j], tau_ref[j], 1e-12 * (1 + std::abs(tau_ref[j]))) << "trial " << trial << " joint " << j;
      EXPECT_NEAR(cur[j], cur_ref[j], 1e-12 * (1 + std::abs(cur_ref[j]))) << "trial " << trial << " joint " << j;
      EXPECT_NEAR(tau2[j], tau2_ref[j], 1e-10 * (1 + std::abs(tau2_ref[j]))) << "trial " << trial << " joint " << j;
    }
    EXPECT_GT((tau2 - tau).cwiseAbs().maxCoeff(), 1e-3);
  }
}

// The low-speed friction the twin fits on its main fit's residual, on a recording whose currents a
// known twin made (pre-sliding 0.6 N·m over 0.5 mrad and a Stribeck rise of 0.25 N·m below
// 0.04 rad/s, both on the fitting grid): on J2-J4 identify picks those shapes (v_s to one grid step)
// and recovers the levels to 15 %.
TEST_F(Fixture, RecoversAKnownLowSpeedFrictionFromASyntheticRecording) {
  TwinModel truth_twin = *twin_joint;
  truth_twin.learned.reset();
  for (int j = 0; j < 6; ++j) {
    JointDrive& d = truth_twin.joints[static_cast<size_t>(j)];
    d.presliding_alpha = 2000.0;
    d.presliding = 0.6 * d.gain / 10.0;  // the twin's torque scale is its gain's
    d.stribeck_velocity = 0.04;
    d.stribeck = 0.25 * d.gain / 10.0;
  }
  // the fit splits the samples into motoring and back-driven by a hard switch; a truth with the
  // blended switch puts its blend (|qd| < ~0.01 rad/s, where the Stribeck shape is ~1) into J3's
  // Stribeck level (0.17 for 0.25 N·m, measured): the recovery is checked on the switch the fit models
  truth_twin.direction_blend = 0.0;
  model::RigidBodyInertia p;
  p.mass = 0.5;
  p.com = Eigen::Vector3d(0, 0, 0.04);
  const device::Recording ex = with_currents_of(*excitation, truth_twin, {}, 0.02, 31);
  const device::Recording f8 = with_currents_of(*figure8, truth_twin, p, 0.02, 32);
  IdentReport report;
  // (and on the measured velocity, as the truth switches: read with the target, the split differs
  // from the truth's near standstill, where the Stribeck shape is ~1: J2 0.23 for 0.29)
  IdentOptions measured_switch;
  measured_switch.target_direction = false;
  const TwinModel fit = identify_physics("ur3e", {{&ex, {}}, {&f8, p}}, measured_switch, report);
  for (int j = 1; j <= 3; ++j) {
    const JointDrive& d = fit.joints[static_cast<size_t>(j)];
    const JointDrive& t = truth_twin.joints[static_cast<size_t>(j)];
    EXPECT_EQ(d.presliding_alpha, 2000.0) << "joint " << j;
    // v_s within one grid step (J3 of seed 31: 0.02 with the level 0.268 for 0.251)
    EXPECT_GE(d.stribeck_velocity, 0.02) << "joint " << j;
    EXPECT_LE(d.stribeck_velocity, 0.08) << "joint " << j;
    // in the fit's own torque scale (gain ratio), to 15 %
    const double scale = d.gain / t.gain;
    EXPECT_NEAR(d.presliding, t.presliding * scale, 0.15 * t.presliding * scale) << "joint " << j;
    EXPECT_NEAR(d.stribeck, t.stribeck * scale, 0.15 * t.stribeck * scale) << "joint " << j;
  }
  // the file keeps it
  const TwinModel back = TwinModel::from_json(fit.to_json(), "twin.json");
  EXPECT_EQ(back.joints[2].presliding_alpha, fit.joints[2].presliding_alpha);
  EXPECT_EQ(back.joints[2].stribeck, fit.joints[2].stribeck);
}

// The memory itself: a joint that stops keeps the friction of the direction it came from; a
// reversal turns it over within a few pre-sliding distances; encoder flicker at rest hardly moves it.
TEST(FrictionMemory, HoldsTheLastDirectionAtRestAndTurnsOverWithDisplacement) {
  double h = 0.0;
  for (int k = 0; k < 100; ++k) h = presliding_step(h, 1e-3, 2000.0);  // moving + (1 mrad a sample)
  EXPECT_NEAR(h, 1.0, 1e-9);
  for (int k = 0; k < 100; ++k) h = presliding_step(h, 0.0, 2000.0);  // standing still
  EXPECT_NEAR(h, 1.0, 1e-9);
  // one 20-bit encoder count back and forth: 2.4 % of the held level (2 alpha lsb), not a flip
  const double lsb = 2 * M_PI / (1 << 20);
  h = presliding_step(presliding_step(h, -lsb, 2000.0), lsb, 2000.0);
  EXPECT_NEAR(h, 1.0 - 2.0 * 2000.0 * lsb, 0.05 * 2.0 * 2000.0 * lsb);
  // reversal: after 1/alpha of travel back h = -1 + 2/e (crossed zero), after 10/alpha it is -1
  h = presliding_step(1.0, -0.5e-3, 2000.0);
  EXPECT_NEAR(h, -1.0 + 2.0 * std::exp(-1.0), 1e-6);  // the step uses a single-precision exp
  h = presliding_step(h, -5e-3, 2000.0);  // 10 distances more: slid
  EXPECT_NEAR(h, -1.0, 1e-4);
}

// A joint the recordings never move is refused, naming it: fitted anyway, its twin predicted a
// constant (R² 0 on every joint of a resting log) and the monitor then read its motion as 10^5 N.
TEST_F(Fixture, AJointTheRecordingsNeverMoveIsRefused) {
  device::Recording still = *excitation;
  for (RobotSample& s : still.samples) {
    s.q[2] = still.samples.front().q[2];
    s.qd[2] = 0.003 * std::sin(s.timestamp);  // encoder noise, no motion
  }
  EXPECT_THAT(test::error_text<InvalidArgument>([&] {
                IdentReport report;
                identify_physics("ur3e", {{&still, {}}}, IdentOptions{}, report);
              }),
              ::testing::HasSubstr("identify: J3 never moves in the recordings (|qd| at most 0.0030 rad/s"));
}

// Viscous friction against temperature (the column qd (T - T_ref)) needs recordings whose temperature
// varies. The fixture's two runs stay within 0.3 °C of 35 °C (0.1 °C steps): fitted anyway, the
// column took up the model misfit (J3 +0.068 N·m·s/rad/°C, friction rising with temperature; the
// simulator has -0.011), which a monitor then read as wear on a robot that cooled. Not fitted:
// 0 on every joint, and the report says why and how to fit it.
TEST_F(Fixture, ViscousFrictionAgainstTemperatureIsNotFittedWhereTheRecordingsDoNotVaryIt) {
  for (int j = 0; j < 6; ++j) {
    EXPECT_EQ(twin->joints[static_cast<size_t>(j)].friction(kViscousTemperature), 0.0) << "J" << j + 1;
  }
  EXPECT_THAT(fit_report->notes,
              ::testing::Contains(::testing::AllOf(::testing::StartsWith("J1, J2, J3, J4, J5, J6: viscous friction against temperature not fitted"),
                                                   ::testing::HasSubstr("spans 0."), ::testing::HasSubstr(">= 2 °C"))));
}

// With a warm-up from cold in the recordings (22 -> 30+ °C) the column is fitted, and it comes out as
// the simulator's law, Fv(T) = Fv exp(-k (T - T_ref)) ~ Fv (1 - k (T - T_ref)): negative (friction
// falls as the joint warms), -k Fv within 40 % on every joint (measured: 12-32 % high; the linear
// column against the exponential law over the 13 °C between the cold run and the warm ones).
TEST_F(Fixture, ViscousFrictionAgainstTemperatureIsFittedOnAWarmUpFromCold) {
  const device::Recording cold = simulate("cold_start", 400);
  model::RigidBodyInertia p;
  p.mass = 0.5;
  p.com = Eigen::Vector3d(0, 0, 0.04);
  IdentReport report;
  const TwinModel t = identify_physics("ur3e", {{excitation, {}}, {figure8, p}, {&cold, p}}, IdentOptions{}, report);
  const sim::PlantTruth truth = sim::default_truth(t.robot(), 1);
  int fitted = 0;
  for (int j = 0; j < 6; ++j) {
    const auto& jt = truth.joints[static_cast<size_t>(j)];
    double lo = 1e9, hi = -1e9;
    for (const device::Recording* r : {static_cast<const device::Recording*>(excitation), static_cast<const device::Recording*>(figure8), &cold})
      for (const RobotSample& s : r->samples) {
        lo = std::min(lo, s.temperature[j]);
        hi = std::max(hi, s.temperature[j]);
      }
    const auto& d = t.joints[static_cast<size_t>(j)];
    if (hi - lo < 2.0) {
      EXPECT_EQ(d.friction(kViscousTemperature), 0.0) << "J" << j + 1;
      continue;
    }
    ++fitted;
    // in the current domain: a joint whose gain the payload does not fix has its torque scale along
    // a flat direction of the fit, its current prediction does not
    const double k = d.friction(kViscousTemperature) / d.gain;
    const double k_true = -jt.visc_temp_coeff * jt.Fv / (jt.kt * jt.gear_ratio * jt.eta);
    EXPECT_NEAR(k, k_true, 0.4 * std::abs(k_true)) << "J" << j + 1 << ", span " << hi - lo << " °C";
  }
  EXPECT_GE(fitted, 3);
}

// UR3e acceptance on the stops (docs/validation.md, issue 5): on an untrained triangle run with a
// stop at every corner, the twin with low-speed friction predicts J1, J3 and J6 at least 15 % better
// than the plain-Coulomb twin from the same recordings, and below UR3e Table 3 there.
// Friction opposes the motion: a recording whose current on J4 falls with speed more than any
// friction could (0.15 A·s/rad taken off, three times the drive's viscous friction in current:
// 0.45 N·m·s/rad / 8.85 N·m/A = 0.051) would make the unconstrained viscous coefficient negative
// (about -0.9 N·m·s/rad), and that twin could not be saved. The bounded fit holds it at 0, says so,
// writes a twin that loads, and leaves the other joints where the plain data put them.
TEST_F(Fixture, FrictionThatWouldPushTheMotionAlongIsHeldAtZeroAndReported) {
  constexpr int kJ = 3;  // J4
  auto with_falling_current = [](const device::Recording& r) {
    device::Recording out = r;
    for (RobotSample& s : out.samples) s.current[kJ] -= 0.15 * s.qd[kJ];
    return out;
  };
  const device::Recording exc = with_falling_current(*excitation), fig = with_falling_current(*figure8);
  model::RigidBodyInertia p;
  p.mass = 0.5;
  p.com = Eigen::Vector3d(0, 0, 0.04);
  IdentReport report;
  const TwinModel t = identify_physics("ur3e", {{&exc, {}}, {&fig, p}}, IdentOptions{}, report);
  const auto& j4 = t.joints[static_cast<size_t>(kJ)];
  EXPECT_EQ(j4.friction(kViscous), 0.0);
  EXPECT_GE(j4.friction(kCoulomb), 0.0);
  EXPECT_GE(j4.presliding, 0.0);
  EXPECT_GE(j4.stribeck, 0.0);
  EXPECT_THAT(report.notes, ::testing::Contains(::testing::HasSubstr("J4: viscous friction held at 0")));
  for (const std::string& note : report.notes) {
    if (note.find("held at 0") != std::string::npos) {
      EXPECT_EQ(note.rfind("J4:", 0), 0u) << note;
    }
  }
  // the twin loads back (the file check refuses negative friction) and predicts as it did
  const TwinModel back = TwinModel::from_json(t.to_json(), "bounded.json");
  VectorJ a, b;
  const RobotSample& s = fig.samples[1234];
  t.predict_current(s.q, s.qd, s.target_qdd, s.temperature, a);
  back.predict_current(s.q, s.qd, s.target_qdd, s.temperature, b);
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-12);
  // the joints whose gain the payload fixes (J2, J3; J1, J5, J6 are flagged not identified and move
  // along the flat directions that leaves) keep their drive and friction
  for (int j : {1, 2}) {
    const auto& x = t.joints[static_cast<size_t>(j)];
    const auto& y = twin->joints[static_cast<size_t>(j)];
    EXPECT_NEAR(x.gain, y.gain, 0.03 * y.gain) << "J" << j + 1;
    EXPECT_NEAR(x.friction(kViscous), y.friction(kViscous), 0.05 * y.friction(kViscous) + 0.01) << "J" << j + 1;
  }
}

TEST_F(Fixture, LowSpeedFrictionPredictsTheTriangleStops) {
  model::RigidBodyInertia p;
  p.mass = 0.5;
  p.com = Eigen::Vector3d(0, 0, 0.04);
  IdentOptions plain;
  plain.low_speed_friction = false;
  IdentReport report;
  const TwinModel without = identify_physics("ur3e", {{excitation, {}}, {figure8, p}}, plain, report);
  sim::Scenario s = sim::load_scenario(std::string(TWINWATCH_SOURCE_DIR) + "/scenarios/ur3e/validation/triangle_no_payload.yaml");
  s.options.duration = 12;
  device::Recording tri;
  tri.n_dof = 6;
  tri.present = sim::Simulator::fields();
  sim::make_simulator(s)->run([&](const RobotSample& x) { tri.samples.push_back(x); });
  const std::vector<VectorJ> qdd = joint_accelerations(tri);
  auto rmse = [&](const TwinModel& t) {
    VectorJ sse = VectorJ::Zero(6), i;
    FrictionMemory memory;
    for (size_t k = 0; k < tri.samples.size(); ++k) {
      const RobotSample& x = tri.samples[k];
      t.advance(memory, x.q);
      t.predict_current(x.q, x.qd, qdd[k], x.temperature, i, &memory);
      sse += (x.current - i).cwiseAbs2();
    }
    return VectorJ((sse / static_cast<double>(tri.samples.size())).cwiseSqrt());
  };
  const VectorJ with_memory = rmse(*twin), plain_rmse = rmse(without);
  const double table3[6] = {0.036, 0.041, 0.032, 0.046, 0.023, 0.025};  // UR3e Table 3 RMSE [A]
  for (int j : {0, 2, 5}) {
    EXPECT_LT(with_memory[j], 0.85 * plain_rmse[j]) << "joint " << j + 1;
    EXPECT_LT(with_memory[j], table3[j]) << "joint " << j + 1;
  }
}

// found by fuzzing (fuzz/regressions/twin_model): json type_error / out_of_range escaped, and
// get<int>() of 1e20 was undefined
TEST(TwinFile, NonObjectsOverflowsAndHugeIndicesAreParseErrors) {
  const auto error_of = [](const std::string& text) {
    return twinwatch::test::error_text<ParseError>([&] { TwinModel::from_json(text, "t.json"); });
  };
  EXPECT_THAT(error_of("[1, 2, 3]"), ::testing::HasSubstr("t.json: expected a JSON object (a twin file from twinwatch identify), got array"));
  EXPECT_THAT(error_of(R"({"format": 7})"), ::testing::HasSubstr("field 'format': expected \"twinwatch-twin\""));
  EXPECT_THAT(error_of(R"({"format": "twinwatch-twin", "robot": "ur3e", "temperature_ref": 1e400})"),
              ::testing::HasSubstr("expected numbers within the range of a double"));
  TwinModel twin("ur3e", model::load_robot("ur3e"));
  twin.joints.resize(6);
  std::string text = twin.to_json();
  const std::string key = "\"base_columns\": [";  // empty for an unfitted twin
  ASSERT_NE(text.find(key + "]"), std::string::npos);
  text.insert(text.find(key) + key.size(), "1e20");
  EXPECT_THAT(error_of(text), ::testing::HasSubstr("field 'base_columns[0]': expected a whole number, got 1e+20"));
}

}  // namespace
}  // namespace twinwatch::ident
