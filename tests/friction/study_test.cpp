// The HESR protocol on simulated joints whose truth is a generalized Maxwell-slip model (not a
// family any model fits), and the acceptance criteria of issue 6 that the data support.
#include "twinwatch/friction/study.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "test_records.hpp"
#include "twinwatch/core/error.hpp"
#include "twinwatch/friction/maxwell_slip.hpp"
#include "twinwatch/friction/parfam.hpp"
#include "twinwatch/friction/synthetic_joint.hpp"

namespace twinwatch::friction {
namespace {

using ::testing::HasSubstr;

constexpr unsigned kSeed = 1;  // seeds the Fourier coefficients and the noise of the three records

TEST(ReversalWindows, SineSweepHasOneWindowPerZeroCrossing) {
  // 0.25 Hz for 20 s: qd = 0 at t = 2, 4, ..., 18 s (t = 0 starts from rest, t = 20 is the end)
  const std::vector<double> qd = testing::sine_velocity(20.0);
  int reversals = 0;
  const std::vector<char> mask = reversal_window_mask(qd, testing::kDt, 0.1, 0.05, &reversals);
  EXPECT_EQ(reversals, 9);
  long n = 0;
  for (char c : mask) n += c;
  EXPECT_EQ(n, 9 * 41);  // +-20 samples around each crossing sample
}

TEST(ReversalWindows, NoiseAroundZeroIsNotAReversal) {
  // a velocity that dithers by 0.01 rad/s around 0 never exceeds the threshold
  std::vector<double> qd(400);
  for (std::size_t k = 0; k < qd.size(); ++k) qd[k] = (k % 2 ? 0.01 : -0.01);
  int reversals = -1;
  reversal_window_mask(qd, testing::kDt, 0.1, 0.05, &reversals);
  EXPECT_EQ(reversals, 0);
}

class SimulatedJointStudy : public ::testing::TestWithParam<int> {};

// What issue 6 asks on joints with pre-sliding hysteresis, as far as it holds here:
// ParFam-H at least 30 % below the velocity-only RBFNN inside the +-0.1 s reversal windows (HESR
// Table IX reports 39-46 %), and below every other velocity-only or black-box model.
TEST_P(SimulatedJointStudy, ParFamHBeatsTheVelocityOnlyAndBlackBoxModelsAtReversals) {
  const SimulatedJoint joint = simulated_study_joints()[static_cast<std::size_t>(GetParam())];
  const JointStudy s = run_friction_study(simulated_study_data(joint, kSeed));
  ASSERT_EQ(s.models.size(), 6u);
  EXPECT_EQ(s.reversals, 8) << joint.name;
  for (const ModelStudy& m : s.models) {
    ASSERT_NE(m.fit.status, FitStatus::Failed) << joint.name << " " << m.name << ": " << m.fit.brief_report();
    EXPECT_TRUE(std::isfinite(m.reversal_rmse)) << m.name;
    // no model can beat the measurement noise on untrained data
    EXPECT_GT(m.fourier_rmse, 0.9 * joint.torque_noise) << m.name;
  }
  const ModelStudy& ph = s.model("ParFam-H");
  EXPECT_LT(ph.reversal_rmse, 0.7 * s.model("RBFNN").reversal_rmse) << joint.name << ": " << ph.equation;
  for (const char* other : {"Stribeck", "RBFNN-H", "ParFam-V"})
    EXPECT_LT(ph.reversal_rmse, s.model(other).reversal_rmse) << joint.name << " vs " << other << ": " << ph.equation;
  // the hysteresis state is what makes the difference: ParFam-V is no better than Stribeck
  EXPECT_GT(s.model("ParFam-V").reversal_rmse, 1.6 * ph.reversal_rmse) << joint.name;
}

// The acceptance goals of issue 6 on this truth (kSeed, study_parfam_options(), friction-only
// records): ParFam-H has the lowest reversal-window RMSE of all six models on every joint
// (measured 0.592 vs LuGre 0.646, 0.580 vs 0.886, 0.261 vs 0.296 N·m), and trained on the 0.25 Hz
// sweep only it stays stable on the 0.6-1.0 Hz half of the chirp (HESR §V-F): out-of-distribution
// RMSE <= 1.5x in-distribution (measured 1.24, 1.07, 1.41). With HESR's time clock and operator
// library neither holds (LuGre lower on J1/J2, ratio 1.75-2.1). This is seed 1; on other seeds the
// goals hold partly (docs/validation.md, "Acceptance of issue 6").
TEST_P(SimulatedJointStudy, ParFamHIsLowestOfAllModelsAndStableOnTheChirp) {
  const SimulatedJoint joint = simulated_study_joints()[static_cast<std::size_t>(GetParam())];
  const JointStudy s = run_friction_study(simulated_study_data(joint, kSeed));
  const ModelStudy& ph = s.model("ParFam-H");
  for (const ModelStudy& m : s.models) {
    if (m.name != ph.name) {
      EXPECT_LT(ph.reversal_rmse, m.reversal_rmse) << joint.name << " vs " << m.name << ": " << ph.equation;
    }
  }
  ASSERT_TRUE(std::isfinite(ph.chirp_id_rmse) && std::isfinite(ph.chirp_ood_rmse)) << joint.name;
  EXPECT_LE(ph.chirp_ood_rmse, 1.5 * ph.chirp_id_rmse) << joint.name << ": " << ph.equation;
  // and it is not "stable" by being uniformly bad: in distribution it is within 2.5x the torque noise
  EXPECT_LT(ph.chirp_id_rmse, 2.5 * joint.torque_noise) << joint.name << ": " << ph.equation;
}

INSTANTIATE_TEST_SUITE_P(Joints, SimulatedJointStudy, ::testing::Values(0, 1, 2),
                         [](const ::testing::TestParamInfo<int>& i) { return "J" + std::to_string(i.param + 1); });

TEST(FrictionStudy, TheExactFrictionLawAtTheRecordRateDoublesItsErrorInTheChirpsUpperBand) {
  // Why the chirp OOD/ID ratio is fragile: the chirp's upper band (>= 0.6 Hz) has about twice the
  // reversals per second of its lower band, and a Maxwell-slip law with sub-mrad pre-sliding stepped
  // once per 5 ms sample (as any model is evaluated on the record) misses part of each reversal
  // transient. The exact law along the exact velocity then errs twice as much out of distribution;
  // stepped on the simulator's 0.5 ms substeps the error nearly vanishes (the cause is the step).
  const SimulatedJoint joint = simulated_study_joints()[0];
  SyntheticJointOptions o;
  o.torque_noise = 0.0;
  const SyntheticRecord c = simulate_joint(joint.truth, chirp_profile(0.1, 1.0, 1.2, 20.0), o);
  MaxwellSlipFriction per_sample(joint.truth), substepped(joint.truth);
  double se[2] = {0.0, 0.0}, ss[2] = {0.0, 0.0};
  long n[2] = {0, 0};
  constexpr int kSub = 10;
  for (std::size_t k = 0; k < c.true_qd.size(); ++k) {
    const double a = per_sample.step(c.true_qd[k], o.dt);
    double b = 0.0;
    for (int s = 1; s <= kSub; ++s) {
      const double v = k == 0 ? c.true_qd[0] : c.true_qd[k - 1] + (c.true_qd[k] - c.true_qd[k - 1]) * s / kSub;
      b = substepped.step(v, o.dt / kSub);
    }
    const int band = c.frequency[k] >= 0.6 ? 1 : 0;
    se[band] += (a - c.true_tau[k]) * (a - c.true_tau[k]);
    ss[band] += (b - c.true_tau[k]) * (b - c.true_tau[k]);
    ++n[band];
  }
  const double id = std::sqrt(se[0] / n[0]), ood = std::sqrt(se[1] / n[1]);
  EXPECT_GT(id, 0.1);  // [N·m], of the order of the torque noise (0.15)
  EXPECT_GT(ood, 1.6 * id);
  EXPECT_LT(std::sqrt(ss[0] / n[0]), 0.2 * id);
  EXPECT_LT(std::sqrt(ss[1] / n[1]), 0.2 * ood);
}

TEST(FrictionStudy, FrictionalLagOnTheSweepHidesTheSteadyStribeckPeakFromParFamH) {
  // Why ParFam-H loses the closed loop's slow crawls (docs/validation.md, "Closed loop"): the truth's
  // slipping elements relax toward the Stribeck curve with a 15-25 ms lag, and the 0.25 Hz sweep
  // crosses the Stribeck band (|qd| < 0.1 rad/s) in ~50 ms, so the training record shows a flattened
  // peak. ParFam-H, static in qd once its displacement-clock h saturates, fits that and
  // under-predicts the steady torque of slow sliding, odd in the direction (sign-coherent with qd,
  // which the loop integrates). The same joint without the lag: the steady peak is found.
  constexpr double kCrawl = 0.03;      // [rad/s] a slow steady slide, within vs (0.05 / 0.08)
  constexpr double kFast = 0.5;        // [rad/s] the approach from the other direction
  constexpr int kSamples = 200;        // 1 s at 200 Hz per phase: 30 mrad, far beyond pre-sliding
  constexpr double kHidden = -0.5;     // [N·m] with the lag: under-predicted by more than this
  constexpr double kFound = 0.3;       // [N·m] without the lag: within this (torque noise 0.15/0.2)
  for (int joint : {0, 1}) {
    for (double lag : {1.0, 0.0}) {
      SimulatedJoint j = simulated_study_joints()[static_cast<std::size_t>(joint)];
      j.truth.lag_time *= lag;
      const FrictionStudyData d = simulated_study_data(j, kSeed);
      ParFamModel m(study_parfam_options());
      ASSERT_EQ(m.fit(d.train).status, FitStatus::Converged);
      double err[2] = {0.0, 0.0};
      for (int side = 0; side < 2; ++side) {
        const double sgn = side == 0 ? 1.0 : -1.0;
        m.start(d.train.dt);
        MaxwellSlipFriction truth(j.truth);
        double f = 0.0, t = 0.0;
        for (int k = 0; k < kSamples; ++k) {
          m.step(-sgn * kFast);
          truth.step(-sgn * kFast, d.train.dt);
        }
        for (int k = 0; k < kSamples; ++k) {
          f = m.step(sgn * kCrawl);
          t = truth.step(sgn * kCrawl, d.train.dt);
        }
        err[side] = sgn * (f - t);  // > 0: over-predicts the magnitude
      }
      const std::string what = j.name + (lag > 0.0 ? " with" : " without") + " lag: " + m.equation();
      if (lag > 0.0) {
        EXPECT_LT(err[0], kHidden) << what;
        EXPECT_LT(err[1], kHidden) << what;
      } else {
        EXPECT_LT(std::abs(err[0]), kFound) << what;
        EXPECT_LT(std::abs(err[1]), kFound) << what;
      }
    }
  }
}

TEST(FrictionStudy, ChirpFrequencySizeMismatchIsNamed) {
  FrictionStudyData d = simulated_study_data(simulated_study_joints()[2], kSeed);
  d.chirp_frequency.pop_back();
  EXPECT_THAT([&] { run_friction_study(d); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("chirp_frequency has size 4000, expected 4001")));
}

TEST(FrictionStudy, InvalidOptionsAreNamed) {
  FrictionStudyOptions o;
  o.reversal_window = 0.0;
  EXPECT_THAT([&] { o.validate(); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("reversal_window is 0")));
  o = {};
  o.chirp_split = -0.6;
  EXPECT_THAT([&] { o.validate(); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("chirp_split is -0.6")));
  o = {};
  o.parfam.hops = -1;
  EXPECT_THAT([&] { o.validate(); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("ParFam hops is -1")));
  o = {};
  o.parfam_v_l1 = -1e-5;
  EXPECT_THAT([&] { o.validate(); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("study parfam_v_l1 is -1e-05")));
}

TEST(FrictionStudy, UnknownModelNameIsNamed) {
  JointStudy s;
  s.joint = "J9";
  EXPECT_THAT([&] { s.model("GPT"); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("joint study 'J9' has no model 'GPT'")));
}

}  // namespace
}  // namespace twinwatch::friction
