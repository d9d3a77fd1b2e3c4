// The HESR baselines (Stribeck, LuGre, RBFNN, RBFNN-H): parameter recovery when the data come from
// the model's own family, sensible behaviour when they do not, and input validation.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "test_records.hpp"
#include "twinwatch/core/error.hpp"
#include "twinwatch/friction/hysteresis.hpp"
#include "twinwatch/friction/lugre.hpp"
#include "twinwatch/friction/rbf_network.hpp"
#include "twinwatch/friction/stribeck.hpp"

namespace twinwatch::friction {
namespace {

using ::testing::HasSubstr;
using testing::kDt;
using testing::make_record;
using testing::rmse_of;
using testing::sine_velocity;
using testing::two_tone_velocity;

constexpr double kNoise = 0.02;  // [N·m] torque noise of the synthetic records

const StribeckParams kStribeckTruth{2.0, 3.0, 0.08, 1.5, 0.1};
// pre-sliding displacement Fc/sigma0 = 4 mrad: the transition spans ~15 samples at 200 Hz
const LugreParams kLugreTruth{500.0, 0.5, 1.5, 2.0, 3.0, 0.08, 0.1};

FrictionRecord lugre_record(const std::vector<double>& qd, unsigned seed) {
  LugreModel truth(kLugreTruth);
  truth.start(kDt);
  return make_record(qd, [&](double v) { return truth.step(v); }, kNoise, seed);
}

TEST(Stribeck, RecoversItsOwnParametersFromNoisyData) {
  const unsigned seed = 11;
  const FrictionRecord rec =
      make_record(sine_velocity(20.0), [](double v) { return StribeckModel::evaluate(kStribeckTruth, v); }, kNoise, seed);
  StribeckModel m;
  const FitSummary s = m.fit(rec);
  ASSERT_NE(s.status, FitStatus::Failed) << s.brief_report();
  const StribeckParams& p = m.params();
  EXPECT_NEAR(p.Fc, kStribeckTruth.Fc, 0.02 * kStribeckTruth.Fc) << "seed " << seed << " " << m.equation();
  EXPECT_NEAR(p.Fs, kStribeckTruth.Fs, 0.03 * kStribeckTruth.Fs) << m.equation();
  EXPECT_NEAR(p.vs, kStribeckTruth.vs, 0.05 * kStribeckTruth.vs) << m.equation();
  EXPECT_NEAR(p.sigma2, kStribeckTruth.sigma2, 0.02 * kStribeckTruth.sigma2) << m.equation();
  EXPECT_NEAR(p.offset, kStribeckTruth.offset, 0.01) << m.equation();
  EXPECT_NEAR(s.rmse, kNoise, 0.1 * kNoise) << s.brief_report();
}

TEST(LuGre, ExactStateUpdateMatchesFineIntegrationOfEq2) {
  // independent method: RK4 on zd = qd - sigma0 |qd| / g z with 200 substeps, qd held per sample
  const LugreParams& p = kLugreTruth;
  LugreModel m(p);
  m.start(kDt);
  const std::vector<double> qd = two_tone_velocity(6.0);
  double z = 0.0;
  constexpr int kSub = 200;
  for (double v : qd) {
    const double g = p.Fc + (p.Fs - p.Fc) * std::exp(-(v / p.vs) * (v / p.vs));
    const auto f = [&](double zz) { return v - p.sigma0 * std::abs(v) / g * zz; };
    const double h = kDt / kSub;
    for (int i = 0; i < kSub; ++i) {
      const double k1 = f(z), k2 = f(z + 0.5 * h * k1), k3 = f(z + 0.5 * h * k2), k4 = f(z + h * k3);
      z += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
    const double tau = m.step(v);
    ASSERT_NEAR(m.z(), z, 1e-9);
    ASSERT_NEAR(tau, p.sigma0 * z + p.sigma1 * f(z) + p.sigma2 * v + p.offset, 1e-6);
  }
}

TEST(LuGre, BristleStateStaysWithinTheStribeckBound) {
  // |z| <= max g / sigma0 (the invariant set of eq. 2 with z(0) = 0)
  LugreModel m(kLugreTruth);
  m.start(kDt);
  const double bound = std::max(kLugreTruth.Fc, kLugreTruth.Fs) / kLugreTruth.sigma0;
  for (double v : two_tone_velocity(10.0)) {
    m.step(v);
    ASSERT_LE(std::abs(m.z()), bound * (1.0 + 1e-12));
  }
}

TEST(LuGre, RecoversItsOwnParametersFromNoisyData) {
  const unsigned seed = 12;
  const FrictionRecord rec = lugre_record(sine_velocity(20.0), seed);
  LugreModel m;
  const FitSummary s = m.fit(rec);
  ASSERT_NE(s.status, FitStatus::Failed) << s.brief_report();
  const LugreParams& p = m.params();
  EXPECT_NEAR(p.sigma0, kLugreTruth.sigma0, 0.05 * kLugreTruth.sigma0) << "seed " << seed << " " << m.equation();
  EXPECT_NEAR(p.Fc, kLugreTruth.Fc, 0.03 * kLugreTruth.Fc) << m.equation();
  EXPECT_NEAR(p.Fs, kLugreTruth.Fs, 0.05 * kLugreTruth.Fs) << m.equation();
  EXPECT_NEAR(p.vs, kLugreTruth.vs, 0.1 * kLugreTruth.vs) << m.equation();
  EXPECT_NEAR(p.sigma2, kLugreTruth.sigma2, 0.03 * kLugreTruth.sigma2) << m.equation();
  EXPECT_NEAR(s.rmse, kNoise, 0.1 * kNoise) << s.brief_report();
  // and it generalises to another velocity profile of the same joint
  const FrictionRecord val = lugre_record(two_tone_velocity(10.0), seed + 1);
  EXPECT_LT(rmse_of(m, val), 1.3 * kNoise);
}

TEST(Stribeck, CannotFollowHysteresisThatLuGreCaptures) {
  // data with pre-sliding memory (LuGre truth) are not in the static family: the Stribeck fit is
  // left with the reversal transients, the LuGre fit reaches the noise
  const FrictionRecord rec = lugre_record(sine_velocity(20.0), 13);
  StribeckModel s;
  s.fit(rec);
  EXPECT_GT(rmse_of(s, rec), 3.0 * kNoise) << s.equation();
  LugreModel l;
  l.fit(rec);
  EXPECT_LT(rmse_of(l, rec), 1.2 * kNoise) << l.equation();
}

TEST(LuGre, FitsMemorylessStribeckDataWithAStiffBristle) {
  // not in the LuGre family (no pre-sliding at all): a stiff bristle reproduces the static curve
  const FrictionRecord rec =
      make_record(sine_velocity(20.0), [](double v) { return StribeckModel::evaluate(kStribeckTruth, v); }, kNoise, 14);
  LugreModel l;
  const FitSummary s = l.fit(rec);
  EXPECT_LT(s.rmse, 2.0 * kNoise) << s.brief_report() << " " << l.equation();
  EXPECT_GT(l.params().sigma0, 2000.0) << l.equation();  // pre-sliding below 1 mrad
}

TEST(Rbfnn, ReproducesAGaussianSumInItsFamily) {
  // truth: bias + three Gaussian bumps in qd -- the RBFNN family
  const auto truth = [](double v) {
    return 0.3 + 2.0 * std::exp(-(v - 0.6) * (v - 0.6) / 0.08) - 1.5 * std::exp(-(v + 0.5) * (v + 0.5) / 0.05) +
           0.8 * std::exp(-v * v / 0.3);
  };
  const FrictionRecord rec = make_record(sine_velocity(20.0), truth, kNoise, 15);
  RbfNetwork m;
  const FitSummary s = m.fit(rec);
  ASSERT_NE(s.status, FitStatus::Failed) << s.brief_report();
  EXPECT_EQ(m.name(), "RBFNN");
  EXPECT_LT(s.rmse, 1.1 * kNoise) << s.brief_report();
  // the function itself, on a fresh noise-free grid inside the training range
  m.start(kDt);
  for (double v = -1.1; v <= 1.1; v += 0.05) EXPECT_NEAR(m.step(v), truth(v), 5.0 * kNoise) << "qd " << v;
}

TEST(Rbfnn, VelocityOnlyNetworkAveragesTheHysteresisLoopAndTheAugmentedOneDoesNot) {
  // LuGre data are multi-valued in qd: RBFNN cannot follow them; RBFNN-H with h, hd can do better
  const FrictionRecord rec = lugre_record(sine_velocity(20.0), 16);
  RbfNetwork v;
  v.fit(rec);
  RbfOptions o;
  o.input = RbfInput::Hysteresis;
  o.hysteresis = {20.0, 200.0};
  RbfNetwork h(o);
  const FitSummary sh = h.fit(rec);
  EXPECT_EQ(h.name(), "RBFNN-H");
  EXPECT_GT(rmse_of(v, rec), 3.0 * kNoise);
  EXPECT_LT(sh.rmse, 0.6 * rmse_of(v, rec)) << sh.brief_report();
}

TEST(Rbfnn, FitIsDeterministicForAGivenSeed) {
  const FrictionRecord rec = lugre_record(sine_velocity(10.0), 17);
  RbfNetwork a, b;
  a.fit(rec);
  b.fit(rec);
  EXPECT_EQ(a.predict(rec), b.predict(rec));
  EXPECT_EQ(a.equation(), b.equation());
}

TEST(FrictionRecord, SizeMismatchIsNamed) {
  FrictionRecord r;
  r.qd = {0.0, 1.0, 2.0};
  r.tau = {0.0, 1.0};
  try {
    r.validate("train");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("train.tau has size 2, expected 3"));
  }
}

TEST(FrictionRecord, NonFiniteSampleIsNamedWithItsIndex) {
  FrictionRecord r;
  r.qd = {0.0, NAN, 2.0};
  r.tau = {0.0, 1.0, 2.0};
  EXPECT_THAT([&] { r.validate("train"); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("train.qd[1] is nan")));
}

TEST(FrictionRecord, NonPositiveSampleTimeIsRejected) {
  FrictionRecord r;
  r.dt = 0.0;
  EXPECT_THAT([&] { r.validate("val"); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("val.dt is 0")));
}

TEST(FrictionRecord, TooShortForTheModelIsRejected) {
  FrictionRecord r;
  r.qd = {0.0, 1.0, 2.0};
  r.tau = {0.0, 1.0, 2.0};
  LugreModel m;
  EXPECT_THAT([&] { m.fit(r); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("training record has 3 samples, expected at least 8")));
}

TEST(Baselines, InvalidParametersAreNamed) {
  EXPECT_THAT([] { StribeckModel(StribeckParams{1.0, 1.0, -0.1, 0.0, 0.0}); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("Stribeck vs is -0.1")));
  LugreParams p = kLugreTruth;
  p.sigma0 = 0.0;
  EXPECT_THAT([&] { LugreModel{p}; }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("LuGre sigma0 is 0, must be > 0")));
  p = kLugreTruth;
  p.Fs = -1.0;
  EXPECT_THAT([&] { LugreModel{p}; }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("LuGre Fs is -1")));
}

TEST(Baselines, InvalidOptionsAreNamed) {
  EXPECT_THAT([] { LugreModel(ParametricFitOptions{5, 10, 1}); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("global_evaluations is 5, must be >= 10")));
  RbfOptions o;
  o.centers = 0;
  EXPECT_THAT([&] { RbfNetwork{o}; }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("RBF centers is 0")));
  o = {};
  o.spread_max = 0.01;
  EXPECT_THAT([&] { RbfNetwork{o}; },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("RBF spread_max is 0.01, must be > spread_min")));
  o = {};
  o.input = RbfInput::Hysteresis;
  o.hysteresis.alpha = -2.0;
  EXPECT_THAT([&] { RbfNetwork{o}; }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("alpha is -2")));
}

TEST(Baselines, UnfittedModelsRefuseToStart) {
  StribeckModel s;
  EXPECT_THAT([&] { s.start(kDt); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("not fitted")));
  LugreModel l;
  EXPECT_THROW(l.start(kDt), InvalidArgument);
  RbfNetwork r;
  EXPECT_THAT([&] { r.start(kDt); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("RBFNN is not fitted")));
}

TEST(Baselines, HysteresisNetworkRefusesAnUnstableSampleTime) {
  RbfOptions o;
  o.input = RbfInput::Hysteresis;
  o.hysteresis = {20.0, 200.0};
  RbfNetwork m(o);
  m.fit(lugre_record(sine_velocity(5.0), 18));
  EXPECT_THAT([&] { m.start(0.1); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("alpha*dt is 2")));
}

}  // namespace
}  // namespace twinwatch::friction
