// The scenario's motion as a program for a real UR arm (sim/robot_program.hpp): the closed forms are
// the trajectories, the program's motion starts and ends at rest and is the trajectory in between,
// and the URScript text, run by a 32-bit interpreter of the subset it is written in, commands that
// motion every 2 ms.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "error_text.hpp"
#include "twinwatch/core/error.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "twinwatch/sim/robot_program.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "urscript_interpreter.hpp"

namespace twinwatch::sim {
namespace {

using ::testing::HasSubstr;

VectorJ v6(double a, double b, double c, double d, double e, double f) {
  VectorJ v(6);
  v << a, b, c, d, e, f;
  return v;
}

const VectorJ kStart = v6(0.0, -1.0, 1.0, -1.57, 0.0, 0.0);

// random coefficients (which start moving), or made to start at rest as excite's do (sum_l a_l = 0)
std::unique_ptr<Trajectory> fourier(unsigned seed, bool at_rest = true) {
  FourierCoefficients c = random_fourier(kStart, 0.6, 10.0, 5, seed);
  if (at_rest) c.a.col(0) = -c.a.rightCols(4).rowwise().sum();
  return make_fourier(c);
}
std::unique_ptr<Trajectory> sine() {
  return make_sine(kStart, v6(1.2, 0.3, 0.3, 0.8, 1.0, 1.5), v6(0.35, 0.23, 0.29, 0.19, 0.27, 0.31), v6(0.0, 0.4, -1.1, 2.0, 0.0, 3.0));
}
std::unique_ptr<Trajectory> chirp() { return make_chirp(kStart, v6(0.3, 0.2, 0.2, 0.3, 0.3, 0.4), 0.1, 1.0, 20.0); }

ProgramOptions options(double duration) {
  ProgramOptions o;
  o.duration = duration;
  o.name = "test motion";
  return o;
}

TEST(RobotProgram, TheClosedFormIsTheTrajectory) {
  std::mt19937 rng(7);
  for (const auto& [what, traj] : std::vector<std::pair<std::string, std::shared_ptr<Trajectory>>>{
           {"fourier", fourier(3, false)}, {"sine", sine()}, {"chirp", chirp()}}) {
    const auto form = traj->closed_form();
    ASSERT_TRUE(form) << what;
    // three periods, the chirp's wrap and fades included
    std::uniform_real_distribution<double> u(0.0, 3.0 * traj->period());
    VectorJ q, qd, qdd, fq, fqd, fqdd;
    for (int k = 0; k < 2000; ++k) {
      const double t = k < 3 ? std::array{0.0, 0.02, traj->period() - 0.03}[static_cast<size_t>(k)] : u(rng);
      traj->evaluate(t, q, qd, qdd);
      form->evaluate(t, fq, fqd, fqdd);
      ASSERT_LT((q - fq).cwiseAbs().maxCoeff(), 1e-12) << what << " t = " << t;
      ASSERT_LT((qd - fqd).cwiseAbs().maxCoeff(), 1e-11) << what << " t = " << t;
      ASSERT_LT((qdd - fqdd).cwiseAbs().maxCoeff(), 1e-10) << what << " t = " << t;
    }
  }
  // a path through inverse kinematics and piecewise segments have none
  EXPECT_FALSE(parse_scenario("robot: ur3e\nduration: 8\ntrajectory: {type: figure_eight, size: [0.12, 0.08], period: 8}\n", "f8.yaml")
                   .trajectory->closed_form());
  EXPECT_FALSE(make_point_to_point({kStart, kStart + VectorJ::Constant(6, 0.2)}, {2.0, 2.0})->closed_form());
}

TEST(RobotProgram, TheMotionStartsAndEndsAtRestAndIsTheTrajectoryInBetween) {
  VectorJ q, qd, qdd, tq, tqd, tqdd;
  // a sine starts and ends moving: the clock rises over 2 s and falls over 2 s
  const auto s = sine();
  const ProgramMotion m(*s->closed_form(), options(30.0));
  EXPECT_DOUBLE_EQ(m.ramp_in(), 2.0);
  EXPECT_DOUBLE_EQ(m.ramp_out(), 2.0);
  EXPECT_EQ(m.steps(), 16000);  // 30 s of the sine's time and half of each ramp
  EXPECT_NEAR(m.clock(m.total()), 30.0, 1e-12);
  m.evaluate(0.0, q, qd, qdd);
  s->evaluate(0.0, tq, tqd, tqdd);
  EXPECT_LT((q - tq).cwiseAbs().maxCoeff(), 1e-15) << "it starts where the trajectory starts";
  EXPECT_GT(tqd.cwiseAbs().maxCoeff(), 2.0) << "the sine itself starts at 2.6 rad/s";
  EXPECT_LT(qd.cwiseAbs().maxCoeff(), 1e-15) << "the program's target starts at rest";
  EXPECT_LT(qdd.cwiseAbs().maxCoeff(), 1e-12);
  m.evaluate(m.total(), q, qd, qdd);
  s->evaluate(30.0, tq, tqd, tqdd);
  EXPECT_LT((q - tq).cwiseAbs().maxCoeff(), 1e-12) << "it ends where the trajectory is at its duration";
  EXPECT_LT(qd.cwiseAbs().maxCoeff(), 1e-15) << "and at rest";
  // between the ramps it is the trajectory, late by half the first ramp
  for (double t = 2.0; t <= m.total() - 2.0; t += 0.137) {
    m.evaluate(t, q, qd, qdd);
    s->evaluate(t - 1.0, tq, tqd, tqdd);
    ASSERT_LT((q - tq).cwiseAbs().maxCoeff(), 1e-12) << t;
    ASSERT_LT((qd - tqd).cwiseAbs().maxCoeff(), 1e-11) << t;
    ASSERT_LT((qdd - tqdd).cwiseAbs().maxCoeff(), 1e-10) << t;
  }
  // its velocity and acceleration are the derivatives of its position, in the ramps too
  const double h = 1e-5;
  for (double t : {0.3, 1.0, 1.7, 2.0, 29.5, 30.9, 31.6}) {
    VectorJ qm, qp, qdm, qdp, dummy;
    m.evaluate(t - h, qm, qdm, dummy);
    m.evaluate(t + h, qp, qdp, dummy);
    m.evaluate(t, q, qd, qdd);
    EXPECT_LT(((qp - qm) / (2 * h) - qd).cwiseAbs().maxCoeff(), 1e-7) << t;
    EXPECT_LT(((qdp - qdm) / (2 * h) - qdd).cwiseAbs().maxCoeff(), 1e-5) << t;
  }
  // the ramp adds at most the trajectory's speed times the rate's slope pi / 2R to its acceleration
  VectorJ qd_max = VectorJ::Zero(6), qdd_max = VectorJ::Zero(6), prog_qdd = VectorJ::Zero(6);
  for (double t = 0.0; t <= 30.0; t += 0.001) {
    s->evaluate(t, tq, tqd, tqdd);
    qd_max = qd_max.cwiseMax(tqd.cwiseAbs());
    qdd_max = qdd_max.cwiseMax(tqdd.cwiseAbs());
  }
  for (double t = 0.0; t <= m.total(); t += 0.001) {
    m.evaluate(t, q, qd, qdd);
    prog_qdd = prog_qdd.cwiseMax(qdd.cwiseAbs());
  }
  for (int j = 0; j < 6; ++j) EXPECT_LE(prog_qdd[j], qdd_max[j] + qd_max[j] * M_PI / 4.0 + 1e-9) << "J" << j + 1;
  // a Fourier excitation over whole periods starts and ends at rest: run as it is
  const auto f = fourier(5);
  const ProgramMotion whole(*f->closed_form(), options(20.0));
  EXPECT_EQ(whole.ramp_in(), 0.0);
  EXPECT_EQ(whole.ramp_out(), 0.0);
  for (double t = 0.0; t <= 20.0; t += 0.0913) {
    whole.evaluate(t, q, qd, qdd);
    f->evaluate(t, tq, tqd, tqdd);
    ASSERT_LT((q - tq).cwiseAbs().maxCoeff(), 1e-13) << t;
  }
  // stopped part-way through a period it ends moving: only the end is ramped
  const ProgramMotion cut(*f->closed_form(), options(13.0));
  EXPECT_EQ(cut.ramp_in(), 0.0);
  EXPECT_DOUBLE_EQ(cut.ramp_out(), 2.0);
  cut.evaluate(cut.total(), q, qd, qdd);
  EXPECT_LT(qd.cwiseAbs().maxCoeff(), 1e-15);
  // a chirp fades in and out of each sweep: two sweeps run as they are
  const ProgramMotion sweeps(*chirp()->closed_form(), options(40.0));
  EXPECT_EQ(sweeps.ramp_in() + sweeps.ramp_out(), 0.0);
}

TEST(RobotProgram, OptionsAndMotionsARobotCannotRunAreRefusedByName) {
  const auto form = *sine()->closed_form();
  auto refused = [&](ProgramOptions o) { return twinwatch::test::error_text<InvalidArgument>([&] { ProgramMotion(form, o); }); };
  ProgramOptions o = options(30.0);
  o.ramp = 0.0;
  EXPECT_THAT(refused(o), HasSubstr("ramp: the target does not start at rest, and a ramp of 0 s would make the arm take a step of velocity"));
  o = options(1.5);
  EXPECT_THAT(refused(o), HasSubstr("duration: 1.5 s is shorter than half the ramps: expected at least 2 s of the trajectory, or a shorter ramp"));
  o.slow_down = 2.0;  // (the ramps stretch with the program; the duration is the trajectory's: both said in its clock)
  EXPECT_THAT(refused(o), HasSubstr("duration: 1.5 s is shorter than half the ramps: expected at least 2 s of the trajectory (half its ramps "
                                    "take 4 s of the program, 2 times slower)"));
  o = options(30.0);
  o.declare_payload = true;  // (no payload in the options)
  EXPECT_THAT(refused(o), HasSubstr("payload: the motion carries no payload, so there is none to declare"));
  o = options(30.0);
  o.target_payload = true;  // (how to declare, with nothing declared)
  EXPECT_THAT(refused(o), HasSubstr("target_payload: it says how the payload is declared, and none is"));
  o = options(30.0);
  o.lookahead = 0.5;
  EXPECT_THAT(refused(o), HasSubstr("lookahead: expected 0.03 to 0.2 s (servoj's range), got 0.5"));
  o = options(30.0);
  o.gain = 50;
  EXPECT_THAT(refused(o), HasSubstr("gain: expected 100 to 2000"));
  o = options(std::nan(""));
  EXPECT_THAT(refused(o), HasSubstr("duration: expected a time > 0 s"));
  ClosedForm bad = form;
  bad.s(2, 2) = std::numeric_limits<double>::infinity();
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { ProgramMotion(bad, options(30.0)); }), HasSubstr("not finite"));
  // a motion beyond the robot's speed limits is seen before anything is written (the verb refuses it)
  const model::RobotModel ur3e = model::load_robot("ur3e");
  const auto fast = make_sine(kStart, v6(1.2, 0, 0, 0, 0, 0), v6(0.5, 0.1, 0.1, 0.1, 0.1, 0.1), VectorJ::Zero(6));
  const ProgramMotion too_fast(*fast->closed_form(), options(30.0));
  EXPECT_THAT(joint_limit_violation(too_fast, ur3e, too_fast.total(), 500.0),
              HasSubstr("joint 1 target velocity reaches"));
}

// What the URScript program commands, run by the 32-bit interpreter, against the motion it was
// written from: the movej to the start pose, one servoj every 2 ms, each target within a fraction of
// a milliradian of the motion (the floats' phase drift) and its step-to-step change the motion's
// velocity (no jitter a servo would feel), then stopj.
struct ProgramRun {
  double worst_q = 0.0;      // |target - motion| [rad]
  double worst_qd = 0.0;     // |difference of targets / dt - motion's qd| [rad/s]
  double worst_jerk = 0.0;   // |second difference of (target - motion)| [rad]
  urscript_test::Trace trace;
};

ProgramRun run_program(const ProgramMotion& m, const ProgramOptions& o) {
  const model::RobotModel ur3e = model::load_robot("ur3e");
  const std::string text = urscript_program(m, o, ur3e, {"a test"});
  urscript_test::Interpreter interp(text);
  EXPECT_EQ(interp.called(), o.call);
  {  // the arm stands 0.3 rad from the start pose on J2 (within the approach's 0.5 rad)
    VectorJ q0, qd0, qdd0;
    m.evaluate(0.0, q0, qd0, qdd0);
    std::vector<float> arm(q0.data(), q0.data() + 6);
    arm[1] += 0.3f;
    interp.arm_at(arm);
  }
  ProgramRun r;
  r.trace = interp.run();
  const auto& targets = r.trace.servo_targets;
  EXPECT_EQ(static_cast<long>(targets.size()), m.steps());
  VectorJ q, qd, qdd;
  std::vector<double> prev_err(6, 0.0), prev_err2(6, 0.0);
  for (size_t k = 0; k < targets.size(); ++k) {
    const double t = static_cast<double>(k + 1) * m.servo_period();
    m.evaluate(t, q, qd, qdd);
    for (int j = 0; j < 6; ++j) {
      const double err = targets[k][static_cast<size_t>(j)] - q[j];
      r.worst_q = std::max(r.worst_q, std::abs(err));
      if (k > 0) {
        const double step = (targets[k][static_cast<size_t>(j)] - targets[k - 1][static_cast<size_t>(j)]) / m.servo_period();
        VectorJ qm, qdm, qddm;  // the motion's mean velocity over the step
        m.evaluate(t - m.servo_period(), qm, qdm, qddm);
        r.worst_qd = std::max(r.worst_qd, std::abs(step - (q[j] - qm[j]) / m.servo_period()));
      }
      if (k > 1) r.worst_jerk = std::max(r.worst_jerk, std::abs(err - 2 * prev_err[static_cast<size_t>(j)] + prev_err2[static_cast<size_t>(j)]));
      prev_err2[static_cast<size_t>(j)] = prev_err[static_cast<size_t>(j)];
      prev_err[static_cast<size_t>(j)] = err;
    }
  }
  return r;
}

TEST(RobotProgram, TheURScriptCommandsTheMotionEvery2msIn32BitFloats) {
  struct Case {
    std::string what;
    std::shared_ptr<Trajectory> traj;
    double duration;
  };
  // a 2 min Fourier excitation (whole periods), a sine swing with both ramps, a chirp over 2.5 sweeps
  // (its wrap and fades), a Fourier run cut part-way (the falling clock alone)
  for (const Case& c : std::vector<Case>{{"fourier", fourier(11), 120.0}, {"sine", sine(), 40.0}, {"chirp", chirp(), 50.0},
                                         {"fourier cut", fourier(12), 25.0}}) {
    ProgramOptions o = options(c.duration);
    o.declare_payload = c.what == "sine" || c.what == "fourier cut";
    o.target_payload = c.what == "fourier cut";  // (set_target_payload, with the inertia about the CoG)
    o.call = c.what == "chirp";  // (a Script node's file)
    o.payload.mass = 2.0;
    o.payload.com = Eigen::Vector3d(0.06, 0.04, 0.05);
    o.payload.inertia_com << 0.004, 0.0001, -0.0002, 0.0001, 0.005, 0.0003, -0.0002, 0.0003, 0.006;
    const ProgramMotion m(*c.traj->closed_form(), o);
    const ProgramRun r = run_program(m, o);
    const auto& calls = r.trace.calls;
    ASSERT_GE(calls.size(), 4u) << c.what;
    // the arm's pose read, textmsg, [set_payload,] movej to the start pose, textmsg, servoj..., stopj, textmsg
    EXPECT_EQ(calls[0].name, "get_actual_joint_positions") << c.what;
    EXPECT_FALSE(r.trace.halted) << c.what;
    size_t k = 2;
    if (o.declare_payload) {
      ASSERT_EQ(calls[k].name, o.target_payload ? "set_target_payload" : "set_payload") << c.what;
      EXPECT_FLOAT_EQ(calls[k].args.at(0).as_float(), 2.0f);
      EXPECT_FLOAT_EQ(calls[k].args.at(1).list.at(0).as_float(), 0.06f);
      EXPECT_FLOAT_EQ(calls[k].args.at(1).list.at(2).as_float(), 0.05f);
      if (o.target_payload) {  // URScript's order: Ixx, Iyy, Izz, Ixy, Ixz, Iyz
        const std::vector<float> want{0.004f, 0.005f, 0.006f, 0.0001f, -0.0002f, 0.0003f};
        for (size_t i = 0; i < 6; ++i) EXPECT_FLOAT_EQ(calls[k].args.at(2).list.at(i).as_float(), want[i]) << i;
      }
      ++k;
    }
    ASSERT_EQ(calls[k].name, "movej") << c.what;
    VectorJ q0, qd, qdd;
    m.evaluate(0.0, q0, qd, qdd);
    for (int j = 0; j < 6; ++j) EXPECT_NEAR(calls[k].args.at(0).list.at(static_cast<size_t>(j)).as_float(), q0[j], 1e-6) << c.what;
    EXPECT_FLOAT_EQ(calls[k].named.at("v").as_float(), 0.25f);
    EXPECT_FLOAT_EQ(calls[k].named.at("a").as_float(), 0.5f);
    const auto servo = std::find_if(calls.begin(), calls.end(), [](const urscript_test::Call& x) { return x.name == "servoj"; });
    ASSERT_NE(servo, calls.end());
    EXPECT_FLOAT_EQ(servo->named.at("t").as_float(), 0.002f);
    EXPECT_FLOAT_EQ(servo->named.at("lookahead_time").as_float(), 0.1f);
    EXPECT_FLOAT_EQ(servo->named.at("gain").as_float(), 300.0f);
    EXPECT_EQ(calls[calls.size() - 2].name, "stopj") << c.what;
    // the targets: the motion within 0.05 mrad (measured 1-9 µrad; summed plainly, without the
    // compensation, 0.9-2.0 mrad), and no step a servo would feel (second differences within 5 µrad:
    // a 32-bit clock's sin(omega t) at 600 s would jitter by 0.1 mrad a step)
    EXPECT_LT(r.worst_q, 5e-5) << c.what;
    EXPECT_LT(r.worst_qd, 0.002) << c.what;
    EXPECT_LT(r.worst_jerk, 5e-6) << c.what;
    // and the first target is one step from the start pose at the motion's first velocity
    EXPECT_LT(std::abs(r.trace.servo_targets.front()[0] - q0[0]), 0.01) << c.what;
  }
}

// Ten minutes of excitation (300000 steps; a 32-bit clock's own resolution at 600 s is 61 µs, where
// sin(omega t) in floats would jitter by 0.1 mrad a step): the compensated phases stay on the motion.
TEST(RobotProgram, TenMinutesOfExcitationStayOnTheMotion) {
  const auto f = fourier(21);
  const ProgramOptions o = options(600.0);
  const ProgramMotion m(*f->closed_form(), o);
  const ProgramRun r = run_program(m, o);
  EXPECT_LT(r.worst_q, 5e-5);
  EXPECT_LT(r.worst_qd, 0.002);
  EXPECT_LT(r.worst_jerk, 5e-6);
}

// The virtual robot rehearsing the program (simulate --as-program) starts the swing at rest, where the
// scenario itself starts J1 at its sine's 2.6 rad/s; after the rise it runs the scenario's motion, late
// by half the ramp, and the faults keep their times.
TEST(RobotProgram, TheVirtualRobotRehearsesTheProgramFromRest) {
  const std::string yaml =
      "robot: ur3e\nseed: 4\nduration: 8\n"
      "trajectory: {type: sine, start: [0, -1.0, 1.0, -1.57, 0, 0], amplitude: [1.2, 0.3, 0.3, 0.8, 1.0, 1.5], "
      "frequency: [0.35, 0.23, 0.29, 0.19, 0.27, 0.31]}\n"
      "faults:\n  - {type: collision, link: 3, onset: 5.0, magnitude: 5, duration: 0.05, point: [-0.1, 0, 0.03], direction: [0.3, 1, -0.2]}\n";
  auto first = [](const Scenario& sc, double* duration) {
    std::vector<RobotSample> out;
    make_simulator(sc)->run([&](const RobotSample& x) { out.push_back(x); });
    *duration = static_cast<double>(out.size()) / sc.options.rate;
    return out;
  };
  Scenario raw = parse_scenario(yaml, "swing.yaml"), rehearsed = parse_scenario(yaml, "swing.yaml");
  ProgramOptions o = options(8.0);
  const auto motion = rehearse_as_program(rehearsed, o);
  EXPECT_DOUBLE_EQ(rehearsed.options.duration, 10.0);
  double d_raw = 0, d_reh = 0;
  const auto a = first(raw, &d_raw), b = first(rehearsed, &d_reh);
  EXPECT_NEAR(d_reh, 10.0, 0.01);
  EXPECT_GT(std::abs(a.front().qd[0]), 2.5) << "the scenario starts J1 moving";
  EXPECT_LT(b.front().qd.cwiseAbs().maxCoeff(), 0.01) << "the program starts the arm at rest";
  EXPECT_LT(b.back().target_qd.cwiseAbs().maxCoeff(), 1e-4) << "and ends it at rest (the last sample is one period before the end)";
  // between the ramps, the scenario's target half a ramp later
  for (size_t k = 1500; k < 3500; k += 250) EXPECT_LT((b[k].target_q - a[k - 500].target_q).cwiseAbs().maxCoeff(), 1e-9) << k;
  EXPECT_EQ(rehearsed.faults.size(), 1u);
  EXPECT_DOUBLE_EQ(rehearsed.faults[0].onset, 5.0);
  Scenario f8 = parse_scenario("robot: ur3e\nduration: 8\ntrajectory: {type: figure_eight, size: [0.12, 0.08], period: 8}\n", "f8.yaml");
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { rehearse_as_program(f8, o); }),
              HasSubstr("f8.yaml:3: trajectory 'figure_eight' has no closed form"));
}

// A fast sine travels 3140 rad of phase in 100 s (500 wraps). Kahan's sum errs by at most 2 eps of
// that (eps = 2^-24): 0.37 mrad of phase at most, a frequency error below 1.2e-7 that grows smoothly
// (measured 0.16 mrad of J1 at the end); a plain float sum errs by up to n eps times it.
TEST(RobotProgram, AFastSineDriftsNoMoreThanTheFloatsFrequencyError) {
  const auto fast = make_sine(kStart, v6(1.0, 0, 0, 0, 0, 0), v6(5.0, 0.1, 0.1, 0.1, 0.1, 0.1), VectorJ::Zero(6));
  const ProgramOptions o = options(100.0);
  const ProgramMotion m(*fast->closed_form(), o);
  const ProgramRun r = run_program(m, o);
  const double travelled = 2 * M_PI * 5.0 * 100.0, eps = std::ldexp(1.0, -24);
  EXPECT_LT(r.worst_q, 2 * eps * travelled * 1.0);
  EXPECT_LT(r.worst_jerk, 5e-6) << "and it drifts smoothly";
}

// The same path K times slower: q'(t) = q(t / K), qd' = qd / K, qdd' = qdd / K², for the Fourier
// series, the sine and the chirp (its sweep, wrap and fades); the program then runs K times the
// trajectory's time, and its tool and elbow speed and momentum fall by K.
TEST(RobotProgram, ASlowDownRunsTheSamePathSlower) {
  std::mt19937 rng(3);
  for (const auto& [what, traj] : std::vector<std::pair<std::string, std::shared_ptr<Trajectory>>>{
           {"fourier", fourier(3, false)}, {"sine", sine()}, {"chirp", chirp()}}) {
    const ClosedForm f = *traj->closed_form();
    for (const double K : {1.7, 3.0}) {
      const ClosedForm g = f.slowed(K);
      std::uniform_real_distribution<double> u(0.0, 3.0 * traj->period() * K);
      VectorJ q, qd, qdd, p, pd, pdd;
      for (int k = 0; k < 500; ++k) {
        const double t = u(rng);
        g.evaluate(t, q, qd, qdd);
        f.evaluate(t / K, p, pd, pdd);
        EXPECT_LT((q - p).cwiseAbs().maxCoeff(), 1e-10) << what << " " << K << " " << t;
        EXPECT_LT((qd - pd / K).cwiseAbs().maxCoeff(), 1e-10) << what;
        EXPECT_LT((qdd - pdd / (K * K)).cwiseAbs().maxCoeff(), 1e-9) << what;
      }
    }
  }
  EXPECT_THROW(sine()->closed_form()->slowed(0.0), InvalidArgument);
  const model::RobotModel ur3e = model::load_robot("ur3e");
  ProgramOptions o = options(20.0);
  o.ramp = 0.5;
  const auto f = fourier(9);  // (at rest at its ends: no ramp)
  const ProgramMotion normal(*f->closed_form(), o);
  o.slow_down = 2.5;
  const ProgramMotion slow(*f->closed_form(), o);
  EXPECT_NEAR(slow.total(), 2.5 * normal.total(), 1e-9);
  const SafetyPeaks a = safety_peaks(normal, ur3e, {}, {}), b = safety_peaks(slow, ur3e, {}, {});
  EXPECT_NEAR(b.tool_speed, a.tool_speed / 2.5, 1e-3 * a.tool_speed);  // (sampled every 2 ms on both clocks)
  EXPECT_NEAR(b.elbow_speed, a.elbow_speed / 2.5, 1e-3 * a.elbow_speed);
  EXPECT_NEAR(b.momentum, a.momentum / 2.5, 1e-3 * a.momentum);
  // a sine starts and ends moving: its ramps stretch too, so the whole program is K times slower
  ProgramOptions so = options(20.0);
  const ProgramMotion sn(*sine()->closed_form(), so);
  so.slow_down = 2.5;
  const ProgramMotion ss(*sine()->closed_form(), so);
  EXPECT_NEAR(ss.total(), 2.5 * sn.total(), 1e-9);
  EXPECT_NEAR(ss.ramp_in(), 2.5 * sn.ramp_in(), 1e-9);
  const SafetyPeaks c = safety_peaks(sn, ur3e, {}, {}), e = safety_peaks(ss, ur3e, {}, {});
  EXPECT_NEAR(e.tool_speed, c.tool_speed / 2.5, 1e-3 * c.tool_speed);
  EXPECT_NEAR(e.tool_t, 2.5 * c.tool_t, 0.01);
  o.slow_down = 0.5;
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { ProgramMotion(*f->closed_form(), o); }), HasSubstr("slow_down"));
}

// The approach is a movej from wherever the arm stands: farther than max_approach from the start pose
// on any joint (either side), the program says which joint and how far, shows an error popup and halts
// before anything moves; nearer, it moves.
TEST(RobotProgram, TheProgramHaltsBeforeMovingWhenTheArmStandsFarFromTheStartPose) {
  const auto f = fourier(5);
  ProgramOptions o = options(4.0);
  const ProgramMotion m(*f->closed_form(), o);
  const model::RobotModel ur3e = model::load_robot("ur3e");
  VectorJ q0, qd, qdd;
  m.evaluate(0.0, q0, qd, qdd);
  auto run_from = [&](int joint, double offset, double max_approach) {
    o.max_approach = max_approach;
    urscript_test::Interpreter interp(urscript_program(m, o, ur3e));
    std::vector<float> arm(q0.data(), q0.data() + 6);
    arm[static_cast<size_t>(joint)] += static_cast<float>(offset);
    interp.arm_at(arm);
    return interp.run();
  };
  auto called = [](const urscript_test::Trace& t, const std::string& name) {
    return std::count_if(t.calls.begin(), t.calls.end(), [&](const urscript_test::Call& c) { return c.name == name; });
  };
  for (const auto& [joint, offset] : std::vector<std::pair<int, double>>{{2, 0.55}, {2, -0.55}, {0, 0.8}, {5, -3.0}}) {
    const urscript_test::Trace t = run_from(joint, offset, 0.5);
    EXPECT_TRUE(t.halted) << joint << " " << offset;
    EXPECT_EQ(called(t, "movej"), 0) << "nothing moves";
    EXPECT_EQ(called(t, "servoj"), 0);
    EXPECT_EQ(called(t, "popup"), 1);
    const auto msg = std::find_if(t.calls.begin(), t.calls.end(), [](const urscript_test::Call& c) { return c.name == "textmsg"; });
    ASSERT_NE(msg, t.calls.end());
    EXPECT_THAT(msg->args.at(0).s, HasSubstr("not started"));
    EXPECT_EQ(msg->args.at(1).i, joint + 1) << "names the farthest joint";
    const auto by = std::next(msg);
    EXPECT_NEAR(by->args.at(1).as_float(), std::abs(offset), 1e-5) << "and how far";
    const auto pop = std::find_if(t.calls.begin(), t.calls.end(), [](const urscript_test::Call& c) { return c.name == "popup"; });
    EXPECT_TRUE(pop->named.at("error").b);
    EXPECT_THAT(pop->args.at(0).s, HasSubstr("nothing moved"));
  }
  for (const auto& [joint, offset, limit] : std::vector<std::tuple<int, double, double>>{{2, 0.45, 0.5}, {2, -0.45, 0.5}, {0, 0.8, 1.0}}) {
    const urscript_test::Trace t = run_from(joint, offset, limit);
    EXPECT_FALSE(t.halted) << joint << " " << offset;
    EXPECT_EQ(called(t, "movej"), 1);
    EXPECT_EQ(called(t, "popup"), 0);
    EXPECT_EQ(called(t, "servoj"), m.steps());
  }
  o.max_approach = 0.0;
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] { ProgramMotion(*f->closed_form(), o); }), HasSubstr("max_approach"));
}

// The figures the installation's safety limits bound, against finite differences of the forward
// kinematics (no Jacobian): the flange's and the elbow's speed (the faster end of its housing on the
// elbow's axis, 0.027 and 0.120 m out on a UR3e), and the momentum as the total mass times the
// velocity of the centre of mass of links and payload; a tool point far out is faster than the
// flange; J1 alone moves the elbow at qd1 times the farther housing end's distance from the base axis.
TEST(RobotProgram, SafetyPeaksAreTheKinematicsSpeedsAndTheArmsMomentum) {
  const model::RobotModel ur3e = model::load_robot("ur3e");
  model::RigidBodyInertia payload;
  payload.mass = 1.5;
  payload.com = Eigen::Vector3d(0.02, 0.0, 0.08);
  const std::vector<Eigen::Vector3d> tool{Eigen::Vector3d(0.0, 0.0, 0.3)};
  const ProgramMotion m(*sine()->closed_form(), options(12.0));
  const SafetyPeaks flange = safety_peaks(m, ur3e, {}, payload), with_tool = safety_peaks(m, ur3e, tool, payload);
  model::DynamicsData d(ur3e);
  struct Points {
    Eigen::Vector3d flange, elbow_near, elbow_far, mass_moment;  // (sum m c)
  };
  const Eigen::Vector2d housing = ur3e.description().elbow_housing;
  EXPECT_EQ(housing, Eigen::Vector2d(0.027, 0.120));
  auto points = [&](double t) {
    VectorJ q, qd, qdd;
    m.evaluate(t, q, qd, qdd);
    model::forward_kinematics(ur3e, d, q);
    const Eigen::Vector3d o = d.oMi[2].translation(), z = d.oMi[2].linear().col(2);
    Points p{d.oMf.translation(), o + housing[0] * z, o + housing[1] * z, Eigen::Vector3d::Zero()};
    for (int b = 0; b < 6; ++b) p.mass_moment += ur3e.joint(b).body.mass * (d.oMi[static_cast<size_t>(b)] * ur3e.joint(b).body.com);
    p.mass_moment += payload.mass * (d.oMf * payload.com);
    return p;
  };
  const double h = 1e-6;
  double tool_fd = 0, elbow_fd = 0, momentum_fd = 0;
  for (long k = 1; k < m.steps(); ++k) {
    const double t = static_cast<double>(k) * m.servo_period();
    const Points a = points(t - h), b = points(t + h);
    tool_fd = std::max(tool_fd, (b.flange - a.flange).norm() / (2 * h));
    elbow_fd = std::max({elbow_fd, (b.elbow_near - a.elbow_near).norm() / (2 * h), (b.elbow_far - a.elbow_far).norm() / (2 * h)});
    momentum_fd = std::max(momentum_fd, (b.mass_moment - a.mass_moment).norm() / (2 * h));
  }
  EXPECT_GT(flange.tool_speed, 1.0) << "the swing moves the flange fast";
  EXPECT_NEAR(flange.tool_speed, tool_fd, 1e-6 * tool_fd);
  EXPECT_EQ(flange.tool_point, -1);
  EXPECT_NEAR(flange.elbow_speed, elbow_fd, 1e-6 * elbow_fd);
  EXPECT_NEAR(flange.momentum, momentum_fd, 1e-6 * momentum_fd);
  EXPECT_GT(with_tool.tool_speed, flange.tool_speed * 1.1) << "the tool point 0.3 m out is faster";
  EXPECT_EQ(with_tool.tool_point, 0);
  EXPECT_EQ(with_tool.elbow_speed, flange.elbow_speed);
  const SafetyPeaks light = safety_peaks(m, ur3e, {}, model::RigidBodyInertia{});
  EXPECT_LT(light.momentum, flange.momentum) << "the payload's momentum counts";

  // J1 alone: the elbow moves on a circle about the base's z axis
  const auto j1 = make_sine(kStart, v6(0.5, 0, 0, 0, 0, 0), v6(0.2, 0.1, 0.1, 0.1, 0.1, 0.1), VectorJ::Zero(6));
  const ProgramMotion spin(*j1->closed_form(), options(10.0));
  const SafetyPeaks sp = safety_peaks(spin, ur3e, {}, model::RigidBodyInertia{});
  const MotionPeaks pk = motion_peaks(spin);
  model::forward_kinematics(ur3e, d, kStart);
  const Eigen::Vector3d o = d.oMi[2].translation(), z = d.oMi[2].linear().col(2);
  const double radius = std::max((o + housing[0] * z).head<2>().norm(), (o + housing[1] * z).head<2>().norm());
  EXPECT_GT(radius, 1.3 * o.head<2>().norm()) << "the upper arm's end of the housing lies 0.12 m out along the axis";
  EXPECT_NEAR(sp.elbow_speed, pk.qd[0] * radius, 1e-9);
  EXPECT_NEAR(sp.tool_speed, pk.qd[0] * d.oMf.translation().head<2>().norm(), 1e-9);
  EXPECT_THAT(twinwatch::test::error_text<InvalidArgument>([&] {
                safety_peaks(spin, ur3e, {Eigen::Vector3d(std::nan(""), 0, 0)}, {});
              }),
              HasSubstr("tool point 1 is not finite"));
}

}  // namespace
}  // namespace twinwatch::sim
