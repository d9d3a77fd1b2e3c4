// Slow-wear trend: the statistics against hand-computed values, the detector on synthetic
// per-cycle series with a known slope, no warning on flat noise, temperature compensation, and a
// shortened simulated friction ramp flagged before any threshold alert.
#include "twinwatch/monitor/trend.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "twinwatch/core/error.hpp"
#include "twinwatch/ident/physics_ident.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/monitor/monitor.hpp"
#include "monitor/simulated_run.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "error_text.hpp"

namespace twinwatch::monitor {
namespace {

using ::testing::HasSubstr;

// synthetic stream: 100 Hz, 8 s cycle, joints phase-shifted sinusoidal velocities
constexpr double kRate = 100.0;
constexpr double kCycle = 8.0;
constexpr double kSpeed = 0.5;      // [rad/s] velocity amplitude
constexpr double kNoise = 0.02;     // [A] residual noise (DESIGN.md rule 4 range)
constexpr double kCoulomb = 0.1;    // [A] the twin's nominal Coulomb friction current
constexpr double kViscous = 0.1;    // [A·s/rad] the twin's nominal viscous friction current

// a twin whose rigid body is zero and whose friction is the nominal one above (gains 1: amperes)
ident::TwinModel friction_only_twin() {
  ident::TwinModel t("ur3e", model::load_robot("ur3e"));
  t.joints.resize(6);
  for (auto& j : t.joints) {
    j.gain = 1.0;
    j.friction(ident::kCoulomb) = kCoulomb;
    j.friction(ident::kViscous) = kViscous;
  }
  return t;
}

struct Synthetic {
  double hours = 2.0;
  int joint = 2;                  // the degrading joint
  double rate_pct_per_h = 0.0;    // friction growth of the nominal friction at the window speed
  double temp_slope = 0.0;        // [A·s/rad/°C] temperature-only viscous drift in the residual
  unsigned seed = 1;
};

// the nominal friction current at the detector's reference speed (mean |qd| above v_min)
double nominal_at_reference(double v_min) {
  // mean of |A sin| over the part of the cycle where it exceeds v_min
  const int N = 100000;
  double s = 0.0;
  int m = 0;
  for (int k = 0; k < N; ++k) {
    const double v = std::abs(kSpeed * std::sin(2 * M_PI * k / N));
    if (v > v_min) {
      s += v;
      ++m;
    }
  }
  return kCoulomb + kViscous * s / m;
}

// joint temperature of a warm start cooling towards its running temperature [°C]
double cooling(double t) { return 25.0 + 10.0 * std::exp(-t / 2400.0); }

std::vector<Event> run_synthetic(const Synthetic& s, TrendConfig cfg, TrendDetector* out = nullptr) {
  const ident::TwinModel twin = friction_only_twin();
  TrendDetector det(twin, cfg, VectorJ::Ones(6), "A");
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> noise(0.0, kNoise);
  const double f_nom = nominal_at_reference(cfg.v_min);
  VectorJ qd(6), r(6), rf(6), level = VectorJ::Constant(6, 0.3), T(6);
  std::vector<Event> ev;
  const long n = static_cast<long>(s.hours * 3600.0 * kRate);
  for (long k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) / kRate;
    for (int j = 0; j < 6; ++j) {
      qd[j] = kSpeed * std::sin(2 * M_PI * t / kCycle + 0.9 * j);
      T[j] = cooling(t);
      const double sgn = qd[j] > 0 ? 1.0 : -1.0;
      // extra friction: the nominal one grown by rate * t, as Coulomb + viscous alike
      const double grow = j == s.joint ? s.rate_pct_per_h / 100.0 * t / 3600.0 : 0.0;
      r[j] = grow * (kCoulomb * sgn + kViscous * qd[j]) + s.temp_slope * qd[j] * (T[j] - 35.0) + noise(rng);
      rf[j] = r[j];
    }
    (void)f_nom;
    if (det.push(t, qd, r, rf, level, T, r.cwiseAbs().sum(), false)) ev.push_back(det.warning());
  }
  if (out) *out = det;
  return ev;
}

TEST(TrendStatistics, MannKendallMatchesHandComputedValue) {
  // y = 1 3 2 4: S = 4 (5 rising pairs, 1 falling), var S = 4*3*13/18, z = (S - 1) / sqrt(var)
  EXPECT_NEAR(mann_kendall_z({1, 3, 2, 4}), 3.0 / std::sqrt(4.0 * 3.0 * 13.0 / 18.0), 1e-12);
  EXPECT_NEAR(mann_kendall_z({4, 2, 3, 1}), -3.0 / std::sqrt(4.0 * 3.0 * 13.0 / 18.0), 1e-12);
  EXPECT_EQ(mann_kendall_z({1, 2}), 0.0);
}

TEST(TrendStatistics, TheilSenIsExactOnALineAndIgnoresOutliers) {
  std::vector<double> x, y, scratch;
  for (int k = 0; k < 30; ++k) {
    x.push_back(k);
    y.push_back(2.5 * k + 1.0);
  }
  EXPECT_NEAR(theil_sen_slope(x, y, scratch), 2.5, 1e-12);
  // a least-squares slope would move with the outliers; the median of pairwise slopes barely does
  y[3] += 500.0;
  y[17] -= 300.0;
  y[25] += 800.0;
  EXPECT_NEAR(theil_sen_slope(x, y, scratch), 2.5, 0.05);
}

TEST(TrendDetector, FlagsAKnownSlopeOnTheRightJointWithItsRate) {
  Synthetic s;
  s.rate_pct_per_h = 15.0;  // +30 % over two hours
  TrendConfig cfg;
  cfg.cycle_period = kCycle;
  TrendDetector det;
  const auto ev = run_synthetic(s, cfg, &det);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].fault, FaultClass::Wear);
  EXPECT_EQ(ev[0].joint, s.joint);
  EXPECT_THAT(ev[0].detail, HasSubstr("J3"));
  // the reported rate is the Theil-Sen slope relative to the nominal friction at v_ref
  EXPECT_NEAR(ev[0].magnitude, 15.0, 2.0) << ev[0].detail;
  // the excess reaches the 0.3 A level at 15 %/h of ~0.135 A: the projected time is finite
  EXPECT_THAT(ev[0].detail, HasSubstr("alarm threshold in"));
  // +15 %/h of ~0.13 A is a 0.6 mA rise per 32 s window against 0.4 mA fit noise: a few minutes
  EXPECT_LT(ev[0].t_detected, 3600.0);
  // the per-window estimate follows the truth: the last window's excess is 15 %/h * t of nominal
  const auto& h = det.history(s.joint);
  const double f_nom = nominal_at_reference(cfg.v_min);
  EXPECT_NEAR(h.back().friction, 0.15 * h.back().t / 3600.0 * f_nom, 0.003);
}

TEST(TrendDetector, NoWarningOnFlatNoisySeries) {
  for (unsigned seed : {11u, 12u, 13u}) {
    Synthetic s;
    s.seed = seed;
    TrendConfig cfg;
    const auto ev = run_synthetic(s, cfg);
    EXPECT_TRUE(ev.empty()) << "seed " << seed << ": " << (ev.empty() ? "" : ev[0].detail);
  }
}

TEST(TrendDetector, TemperatureCompensationRemovesATemperatureOnlyDrift) {
  // cooling 35 -> ~27 °C over two hours with viscous friction 4 %/°C higher when colder
  Synthetic s;
  s.temp_slope = -0.004;
  s.joint = -1;
  TrendConfig cfg;
  const auto raw = run_synthetic(s, cfg);
  ASSERT_FALSE(raw.empty()) << "without compensation the drift must look like wear (else the test proves nothing)";
  cfg.temperature_slope = VectorJ::Constant(6, s.temp_slope);
  const auto comp = run_synthetic(s, cfg);
  EXPECT_TRUE(comp.empty()) << comp[0].detail;
}

// review of session 18: a twin without a learned temperature slope monitoring a robot that cools
// (it started warm, or the program is lighter) warned of wear on healthy joints. A rise within what
// cooling explains (at 4 %/°C of the viscous friction) is a note now; a larger one is still warned
// about (FlagsAKnownSlopeOnTheRightJointWithItsRate cools as well)
TEST(TrendDetector, WithoutATemperatureSlopeACoolingJointIsANoteNotWear) {
  Synthetic s;
  s.temp_slope = -0.002;  // viscous friction 2 %/°C higher when colder, as the virtual robot's
  s.joint = -1;
  TrendConfig cfg;
  TrendDetector det;
  const auto ev = run_synthetic(s, cfg, &det);
  EXPECT_TRUE(ev.empty()) << ev[0].detail;
  std::string note;
  ASSERT_TRUE(det.take_note(note));
  EXPECT_THAT(note, HasSubstr("while the joint cooled from"));
  EXPECT_THAT(note, HasSubstr("no wear warning"));
  // with the slope learned the drift is compensated and nothing is said
  cfg.temperature_slope = VectorJ::Constant(6, s.temp_slope);
  TrendDetector comp;
  EXPECT_TRUE(run_synthetic(s, cfg, &comp).empty());
  EXPECT_FALSE(comp.take_note(note));
}

TEST(TrendLearning, RecoversTheTemperatureSlopeOfTheViscousFriction) {
  // a recording whose current is the twin's friction plus k_T qd (T - T_ref): warm-up from 22 °C
  const ident::TwinModel twin = friction_only_twin();
  const double kT[6] = {-0.004, -0.003, -0.002, -0.001, 0.0, 0.001};
  device::Recording rec;
  rec.n_dof = 6;
  rec.present = kFieldTargetQdd | kFieldActualCurrent | kFieldTemperature | kFieldActualQd;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, kNoise);
  VectorJ i_hat;
  for (long k = 0; k < static_cast<long>(900 * kRate); ++k) {
    RobotSample s = RobotSample::empty(6);
    s.timestamp = k / kRate;
    for (int j = 0; j < 6; ++j) {
      s.q[j] = 0.3 * j;
      s.qd[j] = kSpeed * std::sin(2 * M_PI * s.timestamp / kCycle + 0.9 * j);
      s.target_qdd[j] = 0.0;
      s.temperature[j] = 22.0 + 12.0 * (1.0 - std::exp(-s.timestamp / 600.0));
    }
    s.present = rec.present;
    twin.predict_current(s.q, s.qd, s.target_qdd, s.temperature, i_hat);
    for (int j = 0; j < 6; ++j) s.current[j] = i_hat[j] + kT[j] * s.qd[j] * (s.temperature[j] - 35.0) + noise(rng);
    rec.samples.push_back(s);
  }
  const TrendConfig c = learn_trend_temperature(twin, {{&rec, {}}});
  for (int j = 0; j < 6; ++j) EXPECT_NEAR(c.temperature_slope[j], kT[j], 2e-4) << "joint " << j + 1;
}

TEST(TrendLearning, RejectsRunsWithoutTemperatureChange) {
  const ident::TwinModel twin = friction_only_twin();
  device::Recording rec;
  rec.n_dof = 6;
  rec.present = kFieldTargetQdd | kFieldActualCurrent | kFieldTemperature | kFieldActualQd;
  for (int k = 0; k < 1000; ++k) {
    RobotSample s = RobotSample::empty(6);
    s.timestamp = k / kRate;
    for (int j = 0; j < 6; ++j) {
      s.qd[j] = kSpeed * std::sin(2 * M_PI * s.timestamp / kCycle);
      s.temperature[j] = 35.0;
    }
    rec.samples.push_back(s);
  }
  try {
    learn_trend_temperature(twin, {{&rec, {}}});
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("joint 1 temperature spans 0.0 °C"));
  }
}

TEST(TrendLearning, RejectsRecordingsWithoutTemperatures) {
  const ident::TwinModel twin = friction_only_twin();
  device::Recording rec;
  rec.path = "no_temp.csv";
  rec.n_dof = 6;
  rec.present = kFieldActualCurrent;
  try {
    learn_trend_temperature(twin, {{&rec, {}}});
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("no_temp.csv has no joint temperatures"));
  }
}

// one test per validation error of the options
TEST(TrendConfigValidation, NamesTheFieldAndValue) {
  auto msg = [](auto mutate) {
    TrendConfig c;
    mutate(c);
    return twinwatch::test::error_text<InvalidArgument>([&] { c.validate(6); });
  };
  EXPECT_THAT(msg([](TrendConfig& c) { c.window_s = 0; }), HasSubstr("trend window_s is 0, must be > 0"));
  EXPECT_THAT(msg([](TrendConfig& c) { c.cycle_period = -1; }), HasSubstr("trend cycle_period is -1"));
  EXPECT_THAT(msg([](TrendConfig& c) { c.v_min = 0; }), HasSubstr("trend v_min is 0"));
  EXPECT_THAT(msg([](TrendConfig& c) { c.min_moving_fraction = 1.5; }), HasSubstr("trend min_moving_fraction is 1.5"));
  EXPECT_THAT(msg([](TrendConfig& c) { c.baseline_windows = 0; }), HasSubstr("trend baseline_windows is 0"));
  EXPECT_THAT(msg([](TrendConfig& c) { c.min_windows = 2; }), HasSubstr("trend min_windows is 2"));
  EXPECT_THAT(msg([](TrendConfig& c) { c.history = 5; }), HasSubstr("trend history is 5, must be >= min_windows (12)"));
  EXPECT_THAT(msg([](TrendConfig& c) { c.z_crit = -1; }), HasSubstr("trend z_crit is -1"));
  EXPECT_THAT(msg([](TrendConfig& c) { c.min_rate_pct_per_h = -2; }), HasSubstr("trend min_rate_pct_per_h is -2"));
  EXPECT_THAT(msg([](TrendConfig& c) { c.persist = 0; }), HasSubstr("trend persist is 0"));
  EXPECT_THAT(msg([](TrendConfig& c) { c.temperature_slope = VectorJ::Zero(3); }),
              HasSubstr("trend temperature_slope has size 3, expected 6"));
  EXPECT_THAT(msg([](TrendConfig& c) { c.temperature_slope = VectorJ::Constant(6, NAN); }),
              HasSubstr("trend temperature_slope of joint 1 is nan"));
}

TEST(TrendConfigValidation, DetectorRejectsWrongGainSize) {
  const ident::TwinModel twin = friction_only_twin();
  EXPECT_THROW(
      {
        try {
          TrendDetector d(twin, TrendConfig{}, VectorJ::Ones(4), "A");
        } catch (const InvalidArgument& e) {
          EXPECT_THAT(e.what(), HasSubstr("trend gain has size 4, expected 6"));
          throw;
        }
      },
      InvalidArgument);
}

TEST(TrendConfigJson, RoundTripsThroughTheMonitorConfig) {
  MonitorConfig m;
  m.static_level = VectorJ::Constant(6, 0.1);
  m.use_dynamic = false;
  m.trend.window_s = 20;
  m.trend.z_crit = 3.3;
  m.trend.temperature_slope = VectorJ::LinSpaced(6, -0.003, 0.002);
  const MonitorConfig back = MonitorConfig::from_json(m.to_json(), "test");
  EXPECT_EQ(back.trend.window_s, 20);
  EXPECT_EQ(back.trend.z_crit, 3.3);
  ASSERT_EQ(back.trend.temperature_slope.size(), 6);
  EXPECT_NEAR(back.trend.temperature_slope[0], -0.003, 1e-15);
}

// ---- on the virtual robot: a twin identified from healthy runs, a shortened ramp ----

const auto& simulate = test::run;

const char* kFig8 = "{type: figure_eight, size: [0.12, 0.08], period: 8, tilt: [0.3, 0.4, 0.5]}";

std::string fig8(unsigned seed, double duration, const std::string& faults = "") {
  std::string y = "robot: ur3e\nseed: " + std::to_string(seed) + "\nduration: " + std::to_string(duration) + "\ntrajectory: " + kFig8 +
                  "\npayload: {mass: 0.5, com: [0, 0, 0.04]}\n";
  if (!faults.empty()) y += "faults:\n" + faults;
  return y;
}

TEST(TrendOnVirtualRobot, ShortFrictionRampIsFlaggedBeforeAnyThresholdAndHealthyRunIsNot) {
  // twin and thresholds from healthy runs only (seeds of this test only)
  const auto exc = simulate("robot: ur3e\nseed: 701\nduration: 60\ntrajectory: {type: fourier, amplitude: 0.9, period: 10, harmonics: 5, seed: 3}\n");
  const auto fig = simulate(fig8(702, 40));
  model::RigidBodyInertia p;
  p.mass = 0.5;
  p.com = Eigen::Vector3d(0, 0, 0.04);
  ident::IdentReport rep;
  ident::TwinModel twin = ident::identify_physics("ur3e", {{&exc, {}}, {&fig, p}}, ident::IdentOptions{}, rep);
  // thresholds from two healthy runs: with one (24 s, 3 cycles, 12 reversals per joint) the
  // observer's bound at a J4 reversal was 5 % short of the first reversals of the ramp run (a false
  // contact at 17.45 s, seed 705, with the twin's low-speed friction)
  const auto h = simulate(fig8(703, 24));
  const auto h2 = simulate(fig8(707, 24));
  MonitorConfig cfg = learn_thresholds(twin, {{&h, p}, {&h2, p}});
  // temperature slope from a healthy cool-down of this program (warm start: the joints cool)
  const auto cool = simulate(fig8(704, 480));
  cfg.trend.window_s = 16;
  cfg.trend.cycle_period = 8;
  cfg.trend = learn_trend_temperature(twin, {{&cool, p}}, cfg.trend);
  // the run declares its 0.5 kg in the stream: learned without being told, the slope is the same
  // (the declaration is taken, as the monitor takes it; session 33), and told nothing and following
  // nothing, the part's weight the twin leaves out bends it
  const TrendConfig read = learn_trend_temperature(twin, {{&cool, {}}}, cfg.trend);
  const TrendConfig blind = learn_trend_temperature(twin, {{&cool, {}}}, cfg.trend, false);
  for (int j = 0; j < 6; ++j) EXPECT_NEAR(read.temperature_slope[j], cfg.trend.temperature_slope[j], 1e-12) << "J" << j + 1;
  EXPECT_GT((blind.temperature_slope - cfg.trend.temperature_slope).cwiseAbs().maxCoeff(), 1e-5)
      << blind.temperature_slope.transpose() << " vs " << cfg.trend.temperature_slope.transpose();
  twin.set_payload(p);
  auto monitor = [&](const device::Recording& rec) {
    Monitor m(twin, cfg);
    for (const auto& s : rec.samples) m.push(s);
    m.finish();
    return m.events();
  };
  // +50 % friction on J3 over 8 minutes (the 2-hour +30 % ramp, time-compressed)
  const auto ramp = monitor(simulate(fig8(705, 480, "  - {type: friction_growth, joint: 3, onset: 0, ramp: 480, magnitude: 0.5}\n")));
  double t_wear = NAN, t_alert = NAN;
  for (const auto& e : ramp) {
    if (e.fault == FaultClass::Wear && std::isnan(t_wear)) {
      t_wear = e.t_detected;
      EXPECT_EQ(e.joint, 2) << e.detail;
    }
    if (e.fault != FaultClass::Wear && std::isnan(t_alert)) t_alert = e.t_detected;
  }
  ASSERT_FALSE(std::isnan(t_wear)) << "the ramp was not flagged by the trend";
  if (!std::isnan(t_alert)) {
    EXPECT_LT(t_wear, t_alert);
  }
  // a healthy run (new seed): no wear warning
  // (threshold alerts are the thresholds' business, tested in monitor_test; here: no wear warning)
  for (const auto& e : monitor(simulate(fig8(706, 480)))) EXPECT_NE(e.fault, FaultClass::Wear) << e.detail;
}

}  // namespace
}  // namespace twinwatch::monitor
