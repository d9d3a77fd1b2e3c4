// HESR §V-G closed loop on the simulated joints: with the true friction as the model the joint must
// track best, the eq. 19 torque-error PD must shrink that error, and the tracking error must grow
// with the model's error.
#include "twinwatch/friction/closed_loop.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>

#include "twinwatch/core/error.hpp"
#include "twinwatch/friction/lugre.hpp"
#include "twinwatch/friction/protocol.hpp"

namespace twinwatch::friction {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

constexpr unsigned kSeed = 1;

TEST(AdaptivePdGains, DecayFromMaxAtRestToMinAtSpeed) {
  AdaptivePdGains g;
  g.kp_min = 0.01;
  g.kp_max = 0.1;
  g.kd_min = 0.0;
  g.kd_max = 0.002;
  g.lambda = 4.0;
  EXPECT_DOUBLE_EQ(g.kp(0.0), 0.1);
  EXPECT_DOUBLE_EQ(g.kd(0.0), 0.002);
  EXPECT_NEAR(g.kp(10.0), 0.01, 1e-12);
  // eq. 20 is even in qd_d and halves the excess over K^min every ln(2)/lambda rad/s
  EXPECT_DOUBLE_EQ(g.kp(-0.3), g.kp(0.3));
  EXPECT_NEAR(g.kp(std::log(2.0) / 4.0) - 0.01, 0.5 * (0.1 - 0.01), 1e-12);
}

// The truth scaled by (1 + eps): a family of models whose only error is eps * tau_f,true.
class ScaledTruth final : public FrictionModel {
 public:
  ScaledTruth(MaxwellSlipParams truth, double eps) : gms_(std::move(truth)), eps_(eps) {}
  std::string_view name() const noexcept override { return "scaled truth"; }
  FitSummary fit(const FrictionRecord&) override { return {}; }
  bool fitted() const noexcept override { return true; }
  void start(double dt) override {
    dt_ = dt;
    gms_.reset();
  }
  double step(double qd) noexcept override { return (1.0 + eps_) * gms_.step(qd, dt_); }
  std::string equation() const override { return "(1 + eps) truth"; }

 private:
  MaxwellSlipFriction gms_;
  double eps_;
  double dt_ = 0.005;
};

// The loop options of a study joint with the inertia the twin identifies from the joint's records
// (one fit per joint), as `friction-study --closed-loop` runs it.
ClosedLoopOptions identified_options(const SimulatedJoint& joint) {
  static std::map<std::string, double> inertia;
  if (!inertia.contains(joint.name)) inertia[joint.name] = identified_inertia(joint, kSeed);
  return closed_loop_options_for(joint, inertia[joint.name]);
}

// The same with the rigid body identified exactly: the cases whose exact answer is known.
ClosedLoopOptions exact_options(const SimulatedJoint& joint) {
  return closed_loop_options_for(joint, simulated_rigid_body(joint).inertia);
}

class ClosedLoopJoint : public ::testing::TestWithParam<int> {};

TEST_P(ClosedLoopJoint, TrueFrictionFeedForwardTracksBest) {
  const SimulatedJoint joint = simulated_study_joints()[static_cast<std::size_t>(GetParam())];
  const ClosedLoopOptions o = identified_options(joint);
  const VelocityProfile desired = closed_loop_profile(kSeed);
  const ClosedLoopRun none = run_closed_loop(joint.truth, desired, nullptr, o, false);
  const ClosedLoopRun baseline = run_closed_loop(joint.truth, desired, nullptr, o, true);
  MaxwellSlipOracle oracle(joint.truth);
  const ClosedLoopRun ideal = run_closed_loop(joint.truth, desired, &oracle, o, true);
  EXPECT_GT(none.reversals, 3) << joint.name;
  // the exact model fed forward removes the torque the inner loop would otherwise build from its
  // own error: what is left is the noise, the sampling and the friction memory along q vs q_d
  EXPECT_LT(ideal.rmse, 0.05 * none.rmse) << joint.name;
  EXPECT_LT(ideal.rmse, baseline.rmse) << joint.name;
  EXPECT_LT(ideal.reversal_rmse, 0.05 * none.reversal_rmse) << joint.name;
  EXPECT_LT(ideal.segment_average, 0.05 * none.segment_average) << joint.name;
  // the rigid body alone: eq. 19 then pulls the motor torque away from the friction it needs
  EXPECT_GT(baseline.rmse, none.rmse) << joint.name;
  // the error is a real tracking error: positions stay within 0.5 rad of the desired path
  for (std::size_t k = 0; k < none.q.size(); ++k) ASSERT_LT(std::abs(none.q_d[k] - none.q[k]), 0.5) << k;
}

TEST_P(ClosedLoopJoint, WithTheExactModelTheTorqueErrorVanishesOnThePath) {
  // with the exact model and a time-aligned e_tau, e_tau = 0 while the joint follows qd_d: the
  // eq. 19 PD has little to add (without noise the error stays near the feed-forward's), and beyond
  // the gain margin (kv K_p^max = 2, past the sampled loop's limit of 1) it destabilises the loop
  const SimulatedJoint joint = simulated_study_joints()[static_cast<std::size_t>(GetParam())];
  ClosedLoopOptions o = identified_options(joint);
  o.torque_noise = 0.0;
  ClosedLoopOptions off = o, high = o;
  off.gains.kp_min = off.gains.kp_max = off.gains.kd_max = 0.0;
  high.gains.kp_min *= 4.0;
  high.gains.kp_max *= 4.0;
  high.gains.kd_max *= 4.0;
  const VelocityProfile desired = closed_loop_profile(kSeed);
  const auto rmse = [&](const ClosedLoopOptions& g) {
    MaxwellSlipOracle oracle(joint.truth);
    return run_closed_loop(joint.truth, desired, &oracle, g, true).rmse;
  };
  const double ff_only = rmse(off), with_pd = rmse(o), too_high = rmse(high);
  EXPECT_LT(ff_only, 5e-4) << joint.name;
  EXPECT_LT(with_pd, 2.0 * ff_only) << joint.name;  // what it adds: the friction memory along q vs q_d at reversals
  EXPECT_GT(too_high, 3.0 * with_pd) << joint.name;
}

TEST_P(ClosedLoopJoint, TrackingErrorGrowsWithTheModelError) {
  // the model's error is the only thing that differs: over- and under-prediction alike
  const SimulatedJoint joint = simulated_study_joints()[static_cast<std::size_t>(GetParam())];
  const ClosedLoopOptions o = identified_options(joint);
  const VelocityProfile desired = closed_loop_profile(kSeed);
  const auto rmse = [&](double eps) {
    ScaledTruth m(joint.truth, eps);
    return run_closed_loop(joint.truth, desired, &m, o, true).rmse;
  };
  const double exact = rmse(0.0);
  for (double sign : {-1.0, 1.0}) {
    const double small = rmse(0.05 * sign), large = rmse(0.2 * sign);
    EXPECT_LT(exact, small) << joint.name << " sign " << sign;
    EXPECT_LT(small, large) << joint.name << " sign " << sign;
  }
}

TEST_P(ClosedLoopJoint, Eq19AloneCannotFeedTheModelForward) {
  // without the inner-loop inverse, e_tau = tau_d - tau_meas with the exact model carries only the
  // tracking error (I (qdd_d - qdd) + f(qd_d) - f(qd)): feedback, no feed-forward, so even the
  // true friction does not beat sending qd_d alone by more than the noise of the comparison; nor,
  // being feedback on the tracking error only, does it make the tracking much worse (measured
  // ideal / none = 1.060, 1.003, 1.009 on J1-J3, session 51)
  const SimulatedJoint joint = simulated_study_joints()[static_cast<std::size_t>(GetParam())];
  ClosedLoopOptions o = identified_options(joint);
  o.inverse_feedforward = false;
  const VelocityProfile desired = closed_loop_profile(kSeed);
  const ClosedLoopRun none = run_closed_loop(joint.truth, desired, nullptr, o, false);
  MaxwellSlipOracle oracle(joint.truth);
  const ClosedLoopRun ideal = run_closed_loop(joint.truth, desired, &oracle, o, true);
  EXPECT_GT(ideal.rmse, 0.9 * none.rmse) << joint.name;
  EXPECT_LT(ideal.rmse, 1.15 * none.rmse) << joint.name;
}

INSTANTIATE_TEST_SUITE_P(Joints, ClosedLoopJoint, ::testing::Values(0, 1, 2),
                         [](const ::testing::TestParamInfo<int>& i) { return "J" + std::to_string(i.param + 1); });

// A study joint whose truth keeps only viscous friction sigma2 (Coulomb and Stribeck levels ~0), with
// the joint's loop options and no torque noise: the cases whose exact answer is known.
struct ViscousJoint {
  MaxwellSlipParams truth;
  ClosedLoopOptions options;
};
ViscousJoint viscous_joint(std::size_t index, double sigma2) {
  const SimulatedJoint joint = simulated_study_joints()[index];
  ViscousJoint v{joint.truth, exact_options(joint)};
  v.truth.Fc = v.truth.Fs = 1e-9;
  v.truth.sigma2 = sigma2;
  v.options.torque_noise = 0.0;
  return v;
}

TEST(ClosedLoop, WithoutFrictionTheRigidBodyIsTheExactModel) {
  // a plant without friction: Baseline's tau_d = I qdd_d is exact, so it tracks far better than None
  const auto [smooth, o] = viscous_joint(2, 0.0);
  const VelocityProfile desired = closed_loop_profile(kSeed);
  const ClosedLoopRun none = run_closed_loop(smooth, desired, nullptr, o, false);
  const ClosedLoopRun baseline = run_closed_loop(smooth, desired, nullptr, o, true);
  EXPECT_LT(baseline.rmse, 0.1 * none.rmse);
  // and with the exact model and no noise e_tau is zero on the path: the eq. 19 PD changes nothing,
  // unless tau_d skips the filter that tau_meas goes through (then e_tau = tau_d - LP(tau_d) != 0)
  ClosedLoopOptions off = o, unaligned = o;
  off.gains.kp_min = off.gains.kp_max = off.gains.kd_max = 0.0;
  unaligned.matched_filter = false;
  const ClosedLoopRun ff_only = run_closed_loop(smooth, desired, nullptr, off, true);
  const ClosedLoopRun lagged = run_closed_loop(smooth, desired, nullptr, unaligned, true);
  EXPECT_NEAR(baseline.rmse, ff_only.rmse, 0.05 * ff_only.rmse);
  EXPECT_GT(lagged.rmse, 2.0 * ff_only.rmse);
}

// What the loop's own sensors record (record_measurements: identification data gathered under
// feedback): on a purely viscous joint without noise the recorded residual torque is sigma2 times the
// recorded velocity, whatever the loop does; and recording does not change the run.
TEST(ClosedLoop, TheMeasuredRecordIsTheFrictionAlongTheMotion) {
  auto [viscous, o] = viscous_joint(1, 3.0);
  const VelocityProfile desired = closed_loop_profile(kSeed);
  const ClosedLoopRun plain = run_closed_loop(viscous, desired, nullptr, o, false);
  EXPECT_EQ(plain.measured.size(), 0);
  o.record_measurements = true;
  const ClosedLoopRun rec = run_closed_loop(viscous, desired, nullptr, o, false);
  EXPECT_DOUBLE_EQ(rec.rmse, plain.rmse) << "recording changed the run";
  // the 1 s ramp-in from rest and the scored 10 s, one sample per command period
  EXPECT_EQ(rec.measured.size(), static_cast<long>(std::lround(1.0 / o.dt) + plain.q.size()));
  double sse = 0.0, peak = 0.0;
  for (long k = 2; k + 2 < rec.measured.size(); ++k) {
    const double e = rec.measured.tau[static_cast<std::size_t>(k)] - viscous.sigma2 * rec.measured.qd[static_cast<std::size_t>(k)];
    sse += e * e;
    peak = std::max(peak, std::abs(viscous.sigma2 * rec.measured.qd[static_cast<std::size_t>(k)]));
  }
  EXPECT_GT(peak, 2.0);  // the joint moved at up to ~1 rad/s
  // what is left is the 20-bit encoder differentiated twice: quantization sd 1.7e-6 rad gives an
  // acceleration sd of 2 x 1.7e-6 / (2 dt^2) = 0.068 rad/s^2 at 200 Hz, x I = 0.6 kg m^2: 0.041 N·m
  // (measured 0.042), against an inertia term of up to about I x 3 rad/s^2 = 2 N·m that it removes.
  EXPECT_LT(std::sqrt(sse / static_cast<double>(rec.measured.size() - 4)), 0.06) << "N·m";
}

// A trial that follows the training motion on the same joint (--loop-training) starts in the state
// the sweep left: at rest its first recorded torque is what the stressed elements hold, not the zero
// of relaxed ones; a relaxed plant_start is the default run bit for bit; a state of another joint
// (another element count, or the same count with other parameters) is refused.
TEST(ClosedLoop, ATrialThatFollowsTheTrainingMotionStartsFromItsState) {
  const SimulatedJoint joint = simulated_study_joints()[1];
  ClosedLoopOptions o = identified_options(joint);
  o.torque_noise = 0.0;
  o.record_measurements = true;
  const VelocityProfile desired = closed_loop_profile(kSeed);
  const MaxwellSlipFriction after = training_end_state(joint, kSeed);
  const double held = after.torque(0.0);
  EXPECT_GT(std::abs(held), 0.5 * joint.truth.Fc) << "the sweep ends at rest with its elements stressed";
  const ClosedLoopRun fresh = run_closed_loop(joint.truth, desired, nullptr, o, false);
  const MaxwellSlipFriction relaxed(joint.truth);
  const ClosedLoopRun same = run_closed_loop(joint.truth, desired, nullptr, o, false, &relaxed);
  EXPECT_EQ(same.q, fresh.q);
  EXPECT_EQ(same.measured.tau, fresh.measured.tau);
  const ClosedLoopRun continued = run_closed_loop(joint.truth, desired, nullptr, o, false, &after);
  // first period: the joint at rest, held by the inner loop's integrator; the recorded torque is
  // the elements' holding torque, the relaxed joint's is zero
  EXPECT_NEAR(continued.measured.tau[1], held, 0.01 * std::abs(held));
  EXPECT_NEAR(fresh.measured.tau[1], 0.0, 0.05);
  // and with the exact friction fed forward (the inverse feed-forward alone, no eq. 19 PD) the trial
  // tracks within a few mrad of a fresh joint: the inverse feed-forward counts the torque the
  // integrator already holds (fed on top of it, the held -11 N·m stays in the command until the
  // velocity error integrates it away: tens of mrad, which a velocity loop never takes back). What is
  // left is the oracle starting from relaxed elements while the plant's are stressed, until the first
  // break-away. (With the PD on, eq. 19 also sees that mismatch as a torque error of ~11 N·m at the
  // start, since the first torque it measures is the held one.)
  o.record_measurements = false;
  o.gains.kp_min = o.gains.kp_max = o.gains.kd_min = o.gains.kd_max = 0.0;
  MaxwellSlipOracle oracle(joint.truth);
  const ClosedLoopRun fresh_ff = run_closed_loop(joint.truth, desired, &oracle, o, true);
  const ClosedLoopRun held_ff = run_closed_loop(joint.truth, desired, &oracle, o, true, &after);
  EXPECT_LT(held_ff.rmse, 10.0 * fresh_ff.rmse) << "rad";
  EXPECT_LT(held_ff.rmse, 0.003) << "rad";
  MaxwellSlipParams other = joint.truth;
  other.elements.pop_back();
  other.elements.back().weight += joint.truth.elements.back().weight;
  const MaxwellSlipFriction wrong(other);
  EXPECT_THAT([&] { run_closed_loop(joint.truth, desired, nullptr, o, false, &wrong); },
              ThrowsMessage<InvalidArgument>(HasSubstr("plant_start is the state of another joint")));
  // the same element count is not enough: J1's state on J2's truth is refused too
  const MaxwellSlipFriction j1_state = training_end_state(simulated_study_joints()[0], kSeed);
  ASSERT_EQ(j1_state.element_forces().size(), joint.truth.elements.size());
  EXPECT_THAT([&] { run_closed_loop(joint.truth, desired, nullptr, o, false, &j1_state); },
              ThrowsMessage<InvalidArgument>(HasSubstr("plant_start is the state of another joint")));
}

// In-loop tuning (--loop-tuning) moves a model's parameters toward what tracks: a LuGre whose viscous
// coefficient is a third short of a viscous joint's recovers it within 10 % from the tracking error
// of trials alone, and the trial tracks at least 3x better; other model types, bad budgets and bad
// profiles are refused by name.
TEST(ClosedLoop, InLoopTuningRecoversAViscousCoefficientFromTheTrackingError) {
  const auto [viscous, o] = viscous_joint(1, 3.0);
  LugreParams p;
  p.sigma0 = 1e4;
  p.Fc = p.Fs = 1e-3;
  p.vs = 0.05;
  p.sigma2 = 2.0;
  const LugreModel model(p);
  const std::vector<VelocityProfile> training{closed_loop_profile(kSeed + 1000)};
  const LoopTuning t = tune_in_loop(model, viscous, training, o, nullptr, 150);
  const auto* tuned = dynamic_cast<const LugreModel*>(t.model.get());
  ASSERT_NE(tuned, nullptr);
  EXPECT_NEAR(tuned->params().sigma2, 3.0, 0.3);
  EXPECT_LT(t.rmse_after, t.rmse_before / 3.0);
  EXPECT_LE(t.evaluations, 151);  // the fitted parameters' evaluation and at most 150 of the search
  EXPECT_EQ(t.parameters, 6);  // sigma0, Fc, Fs, vs, sigma2, offset (sigma1 is zero: not tuned)
  EXPECT_EQ(model.params().sigma2, 2.0) << "the input model is not changed";
  MaxwellSlipOracle oracle(viscous);
  EXPECT_THAT([&] { tune_in_loop(oracle, viscous, training, o, nullptr, 10); },
              ThrowsMessage<InvalidArgument>(HasSubstr("supports LuGre and ParFam models")));
  EXPECT_THAT([&] { tune_in_loop(model, viscous, training, o, nullptr, 0); },
              ThrowsMessage<InvalidArgument>(HasSubstr("evaluations is 0, must be >= 1")));
  EXPECT_THAT([&] { tune_in_loop(model, viscous, {}, o, nullptr, 10); },
              ThrowsMessage<InvalidArgument>(HasSubstr("at least one training trajectory")));
  // a caller's error is reported, not scored as bad parameters
  std::vector<VelocityProfile> no_qd{closed_loop_profile(kSeed)};
  no_qd[0].qd = nullptr;
  EXPECT_THAT([&] { tune_in_loop(model, viscous, no_qd, o, nullptr, 10); },
              ThrowsMessage<InvalidArgument>(HasSubstr("has no qd(t)")));
}

// The controller's rigid body is the twin's: identified from the records within 2 % of the plant's
// inertia on every joint, and it is what tau_d uses. On a frictionless plant Baseline (tau_d =
// I_model qdd_d) is exact only with the plant's I: a model inertia 30 % off leaves a tau_d error of
// 0.3 I qdd_d that the loop must take up, and it tracks measurably worse; a model inertia that is not
// positive is refused by name.
TEST(ClosedLoop, TheControllerUsesTheIdentifiedInertiaNotThePlants) {
  for (const SimulatedJoint& joint : simulated_study_joints()) {
    const double plant = simulated_rigid_body(joint).inertia;
    const ClosedLoopOptions o = identified_options(joint);
    EXPECT_EQ(o.inertia, plant) << joint.name;
    EXPECT_NE(o.model_inertia, plant) << joint.name << ": identified, not copied";
    EXPECT_NEAR(o.model_inertia, plant, 0.02 * plant) << joint.name;
  }
  auto [smooth, o] = viscous_joint(2, 0.0);
  const VelocityProfile desired = closed_loop_profile(kSeed);
  ClosedLoopOptions off = o;
  off.model_inertia = 1.3 * o.inertia;
  const ClosedLoopRun exact = run_closed_loop(smooth, desired, nullptr, o, true);
  const ClosedLoopRun wrong = run_closed_loop(smooth, desired, nullptr, off, true);
  EXPECT_GT(wrong.rmse, 3.0 * exact.rmse);
  EXPECT_THAT([&] { closed_loop_options_for(simulated_study_joints()[0], 0.0); },
              ThrowsMessage<InvalidArgument>(HasSubstr("J1: model inertia is 0, must be > 0")));
  ClosedLoopOptions bad;
  bad.model_inertia = -1.0;
  EXPECT_THAT([&] { bad.validate(); }, ThrowsMessage<InvalidArgument>(HasSubstr("model_inertia is -1")));
}

TEST(ClosedLoop, InvalidOptionsAreNamed) {
  ClosedLoopOptions o;
  o.kv = 0.0;
  EXPECT_THAT([&] { o.validate(); }, ThrowsMessage<InvalidArgument>(HasSubstr("closed-loop kv is 0, must be > 0")));
  o = {};
  o.gains.kp_min = 0.2;
  o.gains.kp_max = 0.1;
  EXPECT_THAT([&] { o.validate(); }, ThrowsMessage<InvalidArgument>(HasSubstr("gains.kp_min is 0.2, must be <= kp_max")));
  o = {};
  o.substeps = 0;
  EXPECT_THAT([&] { o.validate(); }, ThrowsMessage<InvalidArgument>(HasSubstr("substeps is 0")));
}

}  // namespace
}  // namespace twinwatch::friction
