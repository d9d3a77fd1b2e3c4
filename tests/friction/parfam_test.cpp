// ParFam-V / ParFam-H (HESR §IV-C): derivatives against finite differences, the three stages on
// data from known expressions, the printed equation, the compiled evaluator, validation errors.
#include "twinwatch/friction/parfam.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "friction/parfam_family.hpp"
#include "friction/parfam_stage3.hpp"
#include "test_records.hpp"
#include "twinwatch/core/error.hpp"
#include "twinwatch/friction/hysteresis_prior.hpp"

namespace twinwatch::friction {
namespace {

using ::testing::HasSubstr;
using testing::kDt;
using testing::make_record;
using testing::sine_velocity;
using testing::two_tone_velocity;

constexpr double kNoise = 0.02;  // [N·m]
const std::vector<UnaryOp> kAllOps{UnaryOp::Sin, UnaryOp::Cos, UnaryOp::Exp, UnaryOp::Tanh};

std::vector<double> random_theta(int size, unsigned seed, double scale) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-scale, scale);
  std::vector<double> t(static_cast<std::size_t>(size));
  for (double& v : t) v = u(rng);
  return t;
}

// the family's reverse pass (parameters theta and inputs x) against central differences at one point
void expect_gradient_matches_differences(const detail::Layout& L, const UnaryOp* ops, const std::vector<double>& th,
                                         const std::vector<double>& xv, unsigned seed) {
  detail::Cache c;
  detail::forward(L, ops, th.data(), xv.data(), true, 1e-3, c);
  std::vector<double> grad(static_cast<std::size_t>(L.size()), 0.0);
  double gx[3] = {0.0, 0.0, 0.0};
  detail::backward(L, th.data(), xv.data(), true, c, 1.0, grad.data(), gx);
  constexpr double kStep = 1e-6, kTol = 1e-6;
  for (int i = 0; i < L.size(); ++i) {
    std::vector<double> tp = th, tm = th;
    tp[static_cast<std::size_t>(i)] += kStep;
    tm[static_cast<std::size_t>(i)] -= kStep;
    detail::Cache cp, cm;
    const double fd = (detail::forward(L, ops, tp.data(), xv.data(), true, 1e-3, cp) -
                       detail::forward(L, ops, tm.data(), xv.data(), true, 1e-3, cm)) /
                      (2.0 * kStep);
    EXPECT_NEAR(grad[static_cast<std::size_t>(i)], fd, kTol * std::max(1.0, std::abs(fd))) << "seed " << seed << " theta " << i;
  }
  for (int i = 0; i < 3; ++i) {
    std::vector<double> xp = xv, xm = xv;
    xp[static_cast<std::size_t>(i)] += kStep;
    xm[static_cast<std::size_t>(i)] -= kStep;
    detail::Cache cp, cm;
    const double fd = (detail::forward(L, ops, th.data(), xp.data(), true, 1e-3, cp) -
                       detail::forward(L, ops, th.data(), xm.data(), true, 1e-3, cm)) /
                      (2.0 * kStep);
    EXPECT_NEAR(gx[i], fd, kTol * std::max(1.0, std::abs(fd))) << "seed " << seed << " x " << i;
  }
}

TEST(ParFamFamily, ReverseModeMatchesFiniteDifferences) {
  // d f / d theta and d f / d x of the rational family at random points
  const detail::Layout L{3, 4};
  for (unsigned seed = 1; seed <= 5; ++seed) {
    std::vector<double> th = random_theta(L.size(), seed, 0.6);
    const std::vector<double> xv = random_theta(3, seed + 100, 1.0);
    expect_gradient_matches_differences(L, kAllOps.data(), th, xv, seed);
  }
}

void check_stage3_jacobian(HysteresisDrive drive, double alpha, const double (&sx)[3]) {
  const detail::Layout L{3, 4};
  const std::vector<double> qd = two_tone_velocity(3.0);
  const std::vector<double> y(qd.size(), 0.3);
  const std::vector<double> theta = random_theta(L.size(), 7, 0.5);
  std::vector<int> active;
  for (int i = 0; i < L.size(); ++i) active.push_back(i);
  const detail::Stage3Cost cost(qd, kDt, sx, y, L, kAllOps.data(), true, 1e-3, theta, active, drive);
  std::vector<double> ab{std::log(alpha), std::log(40.0)};
  std::vector<double> th = theta;
  const auto n = qd.size();
  std::vector<double> r(n), J0(n * 2), J1(n * th.size());
  const double* params[2] = {ab.data(), th.data()};
  double* jac[2] = {J0.data(), J1.data()};
  ASSERT_TRUE(cost.Evaluate(params, r.data(), jac));
  // central differences on every parameter, compared at every residual
  constexpr double kStep = 1e-6, kTol = 2e-5;
  const auto column_fd = [&](std::vector<double>& block, std::size_t i) {
    std::vector<double> rp(n), rm(n);
    const double keep = block[i];
    block[i] = keep + kStep;
    cost.Evaluate(params, rp.data(), nullptr);
    block[i] = keep - kStep;
    cost.Evaluate(params, rm.data(), nullptr);
    block[i] = keep;
    std::vector<double> fd(n);
    for (std::size_t k = 0; k < n; ++k) fd[k] = (rp[k] - rm[k]) / (2.0 * kStep);
    return fd;
  };
  for (std::size_t i = 0; i < 2; ++i) {
    const std::vector<double> fd = column_fd(ab, i);
    for (std::size_t k = 0; k < n; k += 7)
      ASSERT_NEAR(J0[k * 2 + i], fd[k], kTol * std::max(1.0, std::abs(fd[k]))) << "hysteresis param " << i << " k " << k;
  }
  for (std::size_t i = 0; i < th.size(); ++i) {
    const std::vector<double> fd = column_fd(th, i);
    for (std::size_t k = 0; k < n; k += 7)
      ASSERT_NEAR(J1[k * th.size() + i], fd[k], kTol * std::max(1.0, std::abs(fd[k]))) << "theta " << i << " k " << k;
  }
}

TEST(ParFamStage3, JacobianThroughTheHysteresisRecursionMatchesFiniteDifferences) {
  check_stage3_jacobian(HysteresisDrive::Time, 14.0, {0.7, 0.8, 9.0});
}

TEST(ParFamStage3, JacobianThroughTheDisplacementClockMatchesFiniteDifferences) {
  // alpha |qd| dt reaches ~1 here: the exact exponential step, not the Euler regime
  check_stage3_jacobian(HysteresisDrive::Displacement, 300.0, {0.7, 0.8, 90.0});
}

TEST(ParFamExpression, PrintsTheActiveTermsInTableViiOrder) {
  ParFamExpression e;
  e.dim = 3;
  e.functions = {UnaryOp::Sin, UnaryOp::Tanh};
  const detail::Layout L{3, 2};
  e.theta.assign(static_cast<std::size_t>(L.size()), 0.0);
  // tanh unit: 0.193 qd - 0.606 h + 0.064 hd + 0.057
  e.theta[4] = 0.193;
  e.theta[5] = -0.606;
  e.theta[6] = 0.064;
  e.theta[7] = 0.057;
  // numerator: 16.237 h - 0.163 hd - 2.128 + 37.715 tanh(.)
  e.theta[static_cast<std::size_t>(L.num())] = -2.128;
  e.theta[static_cast<std::size_t>(L.num() + 2)] = 16.237;
  e.theta[static_cast<std::size_t>(L.num() + 3)] = -0.163;
  e.theta[static_cast<std::size_t>(L.num() + 5)] = 37.715;
  EXPECT_EQ(e.to_string(5), "16.237*h - 0.163*hd - 2.128 + 37.715*tanh(0.193*qd - 0.606*h + 0.064*hd + 0.057)");
  EXPECT_EQ(e.active_coefficients(), 8);
  // a denominator term turns it into a quotient
  e.theta[static_cast<std::size_t>(L.den())] = 0.5;
  EXPECT_THAT(e.to_string(5), HasSubstr(") / (1 + 0.5*qd)"));
}

TEST(ParFamExpression, CompiledEvaluatorMatchesTheExpressionIncludingProtections) {
  for (bool rational : {false, true}) {
    ParFamExpression e;
    e.functions = kAllOps;
    e.theta = random_theta(ParFamExpression::parameter_count(3, 4), rational ? 3 : 4, 1.5);
    if (!rational)
      for (int i = detail::Layout{3, 4}.den(); i < detail::Layout{3, 4}.size(); ++i) e.theta[static_cast<std::size_t>(i)] = 0.0;
    e.theta[3] = 40.0;  // b of the sin unit ... exp unit argument pushed past the cap below
    e.theta[11] = 35.0;
    const CompiledExpression c(e);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-2.0, 2.0);
    for (int i = 0; i < 1000; ++i) {
      const double x[3] = {u(rng), u(rng), 20.0 * u(rng)};
      const double ref = e(x);
      ASSERT_TRUE(std::isfinite(ref));
      ASSERT_NEAR(c(x[0], x[1], x[2]), ref, 1e-12 * std::max(1.0, std::abs(ref))) << "rational " << rational;
    }
  }
}

TEST(ParFamH, RecoversAKnownExpressionWithKnownHysteresis) {
  // truth in the family: tau = 0.8 qd + 3 h + 2 tanh(1.5 qd - 0.5 h), (alpha, beta) = (12, 150);
  // trained on a two-tone record, checked noise-free on a sine it never saw
  const HysteresisParams hp{12.0, 150.0};
  const auto truth = [](double qd, const HysteresisSample& s) { return 0.8 * qd + 3.0 * s.h + 2.0 * std::tanh(1.5 * qd - 0.5 * s.h); };
  HysteresisState st(hp, kDt);
  const FrictionRecord train =
      make_record(two_tone_velocity(20.0), [&](double v) { return truth(v, st.step(v)); }, kNoise, 21);
  ParFamOptions o;
  o.hysteresis = hp;
  o.refine_hysteresis = false;
  ParFamModel m(o);
  const FitSummary s = m.fit(train);
  ASSERT_EQ(s.status, FitStatus::Converged) << s.brief_report();
  EXPECT_EQ(m.name(), "ParFam-H");
  EXPECT_LT(s.rmse, 1.2 * kNoise) << s.brief_report() << "\n" << m.equation();
  EXPECT_LE(m.expression().active_coefficients(), 12) << m.equation();
  const std::vector<double> qd = sine_velocity(10.0, 0.4, 1.0);
  HysteresisState st2(hp, kDt);
  const std::vector<double> pred = m.predict(qd, kDt);
  double sse = 0.0;
  for (std::size_t k = 0; k < qd.size(); ++k) {
    const double e = pred[k] - truth(qd[k], st2.step(qd[k]));
    sse += e * e;
  }
  EXPECT_LT(std::sqrt(sse / static_cast<double>(qd.size())), 2.0 * kNoise) << m.equation();
}

TEST(ParFamH, Stage3RecoversTheHysteresisParametersFromAWrongStart) {
  // tau = 4 h + qd with (alpha, beta) = (12, 150); stage 2 starts from (20, 60)
  const HysteresisParams truth{12.0, 150.0};
  HysteresisState st(truth, kDt);
  const FrictionRecord train =
      make_record(two_tone_velocity(20.0), [&](double v) { return 4.0 * st.step(v).h + v; }, kNoise, 22);
  ParFamOptions o;
  o.hysteresis = HysteresisParams{20.0, 60.0};
  o.functions = {UnaryOp::Tanh};
  ParFamModel m(o);
  const FitSummary s = m.fit(train);
  EXPECT_NEAR(m.hysteresis().alpha, truth.alpha, 0.03 * truth.alpha) << s.brief_report() << "\n" << m.equation();
  EXPECT_NEAR(m.hysteresis().beta, truth.beta, 0.15 * truth.beta) << m.equation();
  EXPECT_LT(s.rmse, 1.1 * kNoise) << s.brief_report();
}

TEST(HysteresisPrior, FindsTheGridPointOfAPureHysteresisLoop) {
  // tau proportional to h(alpha0, beta0): the descriptors of tau and h coincide at the truth
  const HysteresisParams truth{10.0, 100.0};
  HysteresisState st(truth, kDt);
  const FrictionRecord rec = make_record(sine_velocity(20.0), [&](double v) { return 5.0 * st.step(v).h; }, kNoise, 23);
  const HysteresisPrior p = calibrate_hysteresis_prior(rec);
  // the 16-point log grids have steps of 1.36 (alpha) and 1.36 (beta)
  EXPECT_LT(std::abs(std::log(p.params.alpha / truth.alpha)), std::log(1.5)) << p.params.alpha;
  EXPECT_LT(std::abs(std::log(p.params.beta / truth.beta)), std::log(2.0)) << p.params.beta;
  EXPECT_GT(p.measured.reversals, 6);
  EXPECT_GT(p.measured.width, 0.1);  // a real loop
}

TEST(HysteresisPrior, DisplacementClockFindsTheDahlStateUnderViscousFriction) {
  // tau = 5 h + 4 qd with h a Dahl state (displacement clock, 1/alpha = 2.2 mrad, sign-like beta):
  // with the viscous slope removed Stage 1 finds alpha within a grid step and a sign-like beta;
  // without it the viscous part widens tau's range, the loop looks narrower than a saturating h,
  // and the grid drifts to a small beta (h no longer saturating) -- the bias the option removes
  const HysteresisParams truth{447.0, 400.0, HysteresisDrive::Displacement};
  HysteresisState st(truth, kDt);
  const FrictionRecord rec =
      make_record(sine_velocity(20.0), [&](double v) { return 5.0 * st.step(v).h + 4.0 * v; }, kNoise, 29);
  HysteresisPriorOptions o;
  o.drive = HysteresisDrive::Displacement;
  o.remove_viscous = true;
  const HysteresisPrior p = calibrate_hysteresis_prior(rec, o);
  EXPECT_EQ(p.params.drive, HysteresisDrive::Displacement);
  EXPECT_LT(std::abs(std::log(p.params.alpha / truth.alpha)), std::log(1.6)) << p.params.alpha;
  // sign-like at the reversal threshold v_ref = 0.12 rad/s: tanh(beta v_ref) > 0.99 (beta beyond
  // that is not identifiable from the loop descriptors)
  EXPECT_GT(std::tanh(p.params.beta * 0.12), 0.99) << p.params.beta;
  o.remove_viscous = false;
  const HysteresisPrior q = calibrate_hysteresis_prior(rec, o);
  EXPECT_LT(std::tanh(q.params.beta * 0.12), 0.9) << q.params.beta;
  EXPECT_GT(q.cost, p.cost);
}

TEST(HysteresisPrior, LoopDescriptorsOfASingleValuedCurveHaveNoWidth) {
  const std::vector<double> qd = sine_velocity(20.0);
  std::vector<double> y(qd.size());
  for (std::size_t k = 0; k < qd.size(); ++k) y[k] = std::tanh(20.0 * qd[k]);
  const LoopDescriptors d = loop_descriptors(qd, y, 0.1);
  EXPECT_NEAR(d.width, 0.0, 1e-3);
  EXPECT_EQ(d.reversals, 9);
  EXPECT_GT(d.slope, 0.4);  // tanh(20 * 0.1) = 0.96: most of the transition within v_ref
}

TEST(HysteresisPrior, RecordWithoutReversalIsRejected) {
  FrictionRecord r;
  r.qd.assign(100, 0.5);
  r.tau.assign(100, 1.0);
  EXPECT_THAT([&] { calibrate_hysteresis_prior(r); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("never reverses")));
}

TEST(ParFamV, SeesTheVelocityOnly) {
  // a static curve is what ParFam-V can fit
  const FrictionRecord train = make_record(
      two_tone_velocity(20.0), [](double v) { return 2.0 * std::tanh(8.0 * v) + 1.2 * v + 0.3; }, kNoise, 24);
  ParFamOptions o;
  o.input = ParFamInput::Velocity;
  ParFamModel m(o);
  const FitSummary s = m.fit(train);
  EXPECT_EQ(m.name(), "ParFam-V");
  EXPECT_LT(s.rmse, 1.2 * kNoise) << s.brief_report() << "\n" << m.equation();
  EXPECT_THAT(m.equation(), ::testing::Not(HasSubstr("*h")));
  EXPECT_THAT(m.equation(), ::testing::Not(HasSubstr("hd")));
  EXPECT_THAT(m.equation(), ::testing::Not(HasSubstr("alpha")));
}

TEST(ParFam, FitIsDeterministicForAGivenSeed) {
  HysteresisState st(HysteresisParams{15.0, 100.0}, kDt);
  const FrictionRecord train =
      make_record(sine_velocity(5.0), [&](double v) { return 3.0 * st.step(v).h + 0.5 * v; }, kNoise, 25);
  ParFamOptions o;
  o.hops = 2;
  o.refine_evaluations = 50;
  ParFamModel a(o), b(o);
  a.fit(train);
  b.fit(train);
  EXPECT_EQ(a.equation(), b.equation());
}

TEST(ParFam, InvalidOptionsAreNamed) {
  ParFamOptions o;
  o.functions.clear();
  EXPECT_THAT([&] { ParFamModel{o}; }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("ParFam functions has 0 entries")));
  o = {};
  o.l1 = -1.0;
  EXPECT_THAT([&] { ParFamModel{o}; }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("ParFam l1 is -1")));
  o = {};
  o.prune_thresholds = {0.01, -0.2};
  EXPECT_THAT([&] { ParFamModel{o}; },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("ParFam prune_thresholds[1] is -0.2")));
  o = {};
  o.hysteresis = HysteresisParams{10.0, -5.0};
  EXPECT_THAT([&] { ParFamModel{o}; }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("beta is -5")));
  o = {};
  o.prior.grid = 1;
  EXPECT_THAT([&] { ParFamModel{o}; }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("prior grid is 1")));
  o = {};
  o.prior.displacement_alpha_min = 0.0;
  EXPECT_THAT([&] { ParFamModel{o}; },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("prior displacement_alpha_min is 0, must be > 0")));
  o = {};
  o.prior.displacement_alpha_max = 5.0;
  EXPECT_THAT([&] { ParFamModel{o}; }, ::testing::ThrowsMessage<InvalidArgument>(
                                           HasSubstr("prior displacement_alpha_max is 5, must be > displacement_alpha_min (10)")));
}

TEST(ParFam, DisplacementClockNeedsNoEulerStabilityAndSaysSoInTheEquation) {
  // alpha*dt = 1.5 is unstable for eq. 11 in time, but alpha [1/rad] of the displacement clock has
  // no such limit (exact step); the fitted equation names the clock
  ParFamOptions o;
  o.hysteresis = HysteresisParams{300.0, 100.0, HysteresisDrive::Displacement};
  o.hops = 2;
  ParFamModel m(o);
  const FrictionRecord train = make_record(sine_velocity(5.0), [](double v) { return v; }, kNoise, 26);
  ASSERT_NE(m.fit(train).status, FitStatus::Failed);
  EXPECT_EQ(m.hysteresis().drive, HysteresisDrive::Displacement);
  EXPECT_THAT(m.equation(), HasSubstr("displacement clock"));
  // the fallback start of a record without reversals is in the displacement units
  HysteresisPriorOptions po;
  po.drive = HysteresisDrive::Displacement;
  EXPECT_EQ(po.fallback().drive, HysteresisDrive::Displacement);
  EXPECT_NEAR(po.fallback().alpha, std::sqrt(10.0 * 3000.0), 1e-9);
}

TEST(ParFam, InvalidExpressionIsNamed) {
  ParFamExpression e;
  e.functions = {UnaryOp::Tanh};
  e.theta = {1.0, 2.0};
  EXPECT_THAT([&] { CompiledExpression{e}; },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("ParFam expression theta has size 2, expected 13")));
  e.dim = 2;
  EXPECT_THAT([&] { e.validate(); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("dim is 2, must be 1 or 3")));
}

TEST(ParFam, UnfittedModelRefusesToStartAndUnstableSampleTimeIsRejected) {
  ParFamModel m;
  EXPECT_THAT([&] { m.start(kDt); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("ParFam-H is not fitted")));
  ParFamOptions o;
  o.hysteresis = HysteresisParams{300.0, 100.0};
  ParFamModel u(o);
  const FrictionRecord train = make_record(sine_velocity(5.0), [](double v) { return v; }, kNoise, 26);
  EXPECT_THAT([&] { u.fit(train); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("alpha*dt is 1.5")));
}

}  // namespace
}  // namespace twinwatch::friction

namespace twinwatch::friction {
namespace {

// the input guard: inside the identified domain the guarded expression is the expression; outside
// it is the value at the nearest domain point (no extrapolation), in both evaluators
TEST(ParFamExpression, InputGuardClampsOutsideTheDomainOnly) {
  ParFamExpression e;
  e.functions = {UnaryOp::Exp, UnaryOp::Tanh};
  e.theta.assign(static_cast<std::size_t>(ParFamExpression::parameter_count(3, 2)), 0.0);
  e.theta[2] = 0.5;   // a_1 hd: exp(0.5 hd)
  e.theta[12] = 1.0;  // w_1 (layout d = 3, k = 2: a_j at 4 j, c_0 at 8, w at 12)
  e.theta[4] = 3.0;   // a_2 qd: tanh(3 qd)
  e.theta[13] = 2.0;  // w_2
  ParFamExpression g = e;
  g.input_min = {-1.0, -1.0, -4.0};
  g.input_max = {1.0, 1.0, 4.0};
  const CompiledExpression ce(e), cg(g);
  const double inside[3] = {0.3, 0.2, 2.0};
  EXPECT_DOUBLE_EQ(g(inside), e(inside));
  EXPECT_DOUBLE_EQ(cg(0.3, 0.2, 2.0), ce(0.3, 0.2, 2.0));
  const double outside[3] = {0.3, 0.2, 40.0}, edge[3] = {0.3, 0.2, 4.0};
  EXPECT_DOUBLE_EQ(g(outside), e(edge));
  EXPECT_DOUBLE_EQ(cg(0.3, 0.2, 40.0), ce(0.3, 0.2, 4.0));
  EXPECT_GT(e(outside), 1e8);  // unguarded: exp(20) runs away
  g.input_max = {1.0, 1.0};
  EXPECT_THAT([&] { g.validate(); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("input_max has size 2, expected 3")));
}

}  // namespace
}  // namespace twinwatch::friction

namespace twinwatch::friction {
namespace {

TEST(ParFam, ReversalWeightBelowOneIsNamed) {
  ParFamOptions o;
  o.reversal_weight = 0;
  EXPECT_THAT([&] { o.validate(); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("ParFam reversal_weight is 0, must be >= 1")));
}

}  // namespace
}  // namespace twinwatch::friction

namespace twinwatch::friction {
namespace {

// the Stribeck unit sgn(u) (1 - exp(-u^2)): odd, bounded by 1, flat at 0 (~ u |u|, where tanh is
// linear), its derivative 2 |u| exp(-u^2) against central differences, on seeded random arguments
TEST(ParFamStribeckUnit, IsOddBoundedFlatAtZeroAndMatchesItsDerivative) {
  constexpr unsigned kSeed = 31;
  std::mt19937 rng(kSeed);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  constexpr double kStep = 1e-6, kTol = 1e-8;
  for (int i = 0; i < 500; ++i) {
    const double x = u(rng);
    double g = 0.0, gp = 0.0, gm = 0.0, gpm = 0.0, ga = 0.0, gb = 0.0, unused = 0.0;
    detail::unary(UnaryOp::Stribeck, x, g, gp);
    detail::unary(UnaryOp::Stribeck, -x, gm, gpm);
    EXPECT_DOUBLE_EQ(gm, -g) << "seed " << kSeed << " u " << x;
    EXPECT_DOUBLE_EQ(gpm, gp) << "seed " << kSeed << " u " << x;  // even derivative of an odd function
    EXPECT_LT(std::abs(g), 1.0);
    detail::unary(UnaryOp::Stribeck, x + kStep, ga, unused);
    detail::unary(UnaryOp::Stribeck, x - kStep, gb, unused);
    EXPECT_NEAR(gp, (ga - gb) / (2.0 * kStep), kTol) << "seed " << kSeed << " u " << x;
    EXPECT_DOUBLE_EQ(detail::stribeck_unit(x), g);
  }
  // flat at zero: g(u) = u |u| - u^3 |u| / 2 + ..., slope 0; tanh has slope 1 there
  for (double x : {1e-3, 1e-2, 0.1}) {
    double g = 0.0, gp = 0.0;
    detail::unary(UnaryOp::Stribeck, x, g, gp);
    EXPECT_NEAR(g, x * x, 0.5 * std::pow(x, 4) + 1e-18) << x;
    EXPECT_NEAR(gp, 2.0 * x, 1e-12 + 2.0 * std::pow(x, 3)) << x;
  }
  double g0 = 1.0, gp0 = 1.0;
  detail::unary(UnaryOp::Stribeck, 0.0, g0, gp0);
  EXPECT_EQ(g0, 0.0);
  EXPECT_EQ(gp0, 0.0);
  // saturates: 1 - g(3) = exp(-9)
  double g3 = 0.0, gp3 = 0.0;
  detail::unary(UnaryOp::Stribeck, 3.0, g3, gp3);
  EXPECT_NEAR(1.0 - g3, std::exp(-9.0), 1e-15);
}

// the family's reverse pass through a Stribeck unit against finite differences, and the compiled
// evaluator against the expression
TEST(ParFamStribeckUnit, FamilyGradientAndCompiledEvaluatorIncludeIt) {
  const std::vector<UnaryOp> ops{UnaryOp::Tanh, UnaryOp::Stribeck, UnaryOp::Sin};
  const detail::Layout L{3, 3};
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const std::vector<double> th = random_theta(L.size(), seed + 40, 0.8);
    const std::vector<double> xv = random_theta(3, seed + 140, 1.0);
    expect_gradient_matches_differences(L, ops.data(), th, xv, seed);
    ParFamExpression e;
    e.functions = ops;
    e.theta = th;
    const CompiledExpression ce(e);
    EXPECT_NEAR(ce(xv[0], xv[1], xv[2]), e(xv.data()), 1e-12) << "seed " << seed;
  }
  ParFamExpression e;
  e.functions = {UnaryOp::Stribeck};
  e.dim = 1;
  e.theta.assign(static_cast<std::size_t>(ParFamExpression::parameter_count(1, 1)), 0.0);
  e.theta[0] = 12.5;  // a_1 qd
  e.theta[4] = -2.0;  // w_1 (d = 1, k = 1: a at 0, b at 1, c_0 at 2, c at 3, w at 4)
  EXPECT_EQ(e.to_string(), "-2*stribeck(12.5*qd)");
}

TEST(ParFam, OddSymmetryNeedsOddFunctionsAndNoDenominator) {
  ParFamOptions o;
  o.odd = true;  // the library's sin, cos, exp, tanh
  EXPECT_THAT([&] { o.validate(); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("ParFam odd is set but functions[1] is cos")));
  o.functions = {UnaryOp::Tanh, UnaryOp::Stribeck, UnaryOp::Sin};
  EXPECT_NO_THROW(o.validate());
  o.rational = true;
  EXPECT_THAT([&] { o.validate(); }, ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("ParFam odd is set with rational = true")));
}

}  // namespace
}  // namespace twinwatch::friction
