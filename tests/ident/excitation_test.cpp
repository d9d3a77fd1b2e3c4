#include "twinwatch/ident/excitation.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "twinwatch/core/error.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "twinwatch/sim/trajectory.hpp"

namespace twinwatch::ident {
namespace {

// end conditions are exact by construction; this bounds the round-off of sums of L terms
constexpr double kEndTolerance = 1e-9;
// dense-grid points per period used by the test (4x the design's own check grid)
constexpr int kDenseSamples = 20000;
// a peak between two dense-grid points of the design's check grid can exceed its value by
// ~ (2 pi L / check_samples)^2 / 8 relative; 1e-4 covers L <= 20 with check_samples = 5000
constexpr double kGridSlack = 1e-4;

ExcitationOptions small_options(unsigned seed) {
  ExcitationOptions o;
  o.harmonics = 4;
  o.base_frequency = 0.2;
  o.seed = seed;
  o.samples = 60;
  o.global_evaluations = 300;
  o.local_evaluations = 300;
  return o;
}

struct Designed {
  model::RobotModel model = model::load_robot("ur3e");
  ExcitationOptions options = small_options(7);
  ExcitationResult result = design_excitation(model, options);
};

const Designed& designed() {
  static const Designed d;
  return d;
}

TEST(Excitation, StartsAndEndsAtRestAtQ0) {
  const auto& d = designed();
  const ExcitationTrajectory& t = d.result.trajectory;
  VectorJ q, qd, qdd;
  for (double time : {0.0, t.period(), 3.0 * t.period()}) {
    t.evaluate(time, q, qd, qdd);
    for (int j = 0; j < d.model.n_dof(); ++j) {
      EXPECT_NEAR(q[j], t.q0[j], kEndTolerance) << "joint " << j << " t " << time;
      EXPECT_NEAR(qd[j], 0.0, kEndTolerance) << "joint " << j << " t " << time;
      EXPECT_NEAR(qdd[j], 0.0, kEndTolerance) << "joint " << j << " t " << time;
    }
  }
  // the trajectory actually moves (the projection did not scale a joint to nothing)
  for (int j = 0; j < d.model.n_dof(); ++j) EXPECT_GT(d.result.qd_peak[j], 0.05 * d.result.qd_lim[j]) << "joint " << j;
}

// The lowest point along a trajectory, against the UR3e's geometry (DH, docs/robot-description.md):
// at q = 0 the arm lies horizontal at the shoulder height d1 = 0.15185 m and the wrist hangs the J6
// axis and the flange d5 = 0.08535 m below it: 0.0665 m. Tilting J2 one way takes the arm (a2 + a3 =
// 0.45675 m) down by sin 0.5 and turns the wrist offset with it: d1 - (a2 + a3) sin 0.5 - d5 cos 0.5
// = -0.1420 m, below the table; the other way raises everything above the shoulder, whose height is
// then the lowest. The design's own result carries the point.
TEST(Excitation, TheLowestPointFollowsTheArmsGeometry) {
  constexpr double d1 = 0.15185, d5 = 0.08535, arm = 0.24355 + 0.2132;
  const model::RobotModel m = model::load_robot("ur3e");
  ExcitationTrajectory t;
  t.w_f = 2.0 * M_PI * 0.2;
  t.q0 = VectorJ::Zero(6);
  t.a = t.b = Eigen::MatrixXd::Zero(6, 3);
  const ExcitationLowestPoint flat = excitation_lowest_point(m, t, 50);
  EXPECT_NEAR(flat.z, d1 - d5, 1e-4);
  EXPECT_GE(flat.body, 5);  // the J6 axis (and the flange, level with it)
  t.q0[1] = 0.5;
  const double a = excitation_lowest_point(m, t, 50).z;
  t.q0[1] = -0.5;
  const double b = excitation_lowest_point(m, t, 50).z;
  EXPECT_NEAR(std::min(a, b), d1 - arm * std::sin(0.5) - d5 * std::cos(0.5), 1e-4);
  EXPECT_NEAR(std::max(a, b), d1, 1e-4);
  // a moving trajectory: the lowest point is found where it happens (J2 swinging by 0.5 rad)
  t.q0[1] = 0.0;
  t.a(1, 0) = 0.5 * t.w_f;  // q2(t) = 0.5 sin(w t) (a / (l w_f) sin(l w_f t), l = 1)
  const ExcitationLowestPoint swing = excitation_lowest_point(m, t, 400);
  EXPECT_NEAR(swing.z, d1 - arm * std::sin(0.5) - d5 * std::cos(0.5), 1e-4);
  EXPECT_GE(designed().result.lowest.body, 1);
  EXPECT_TRUE(std::isfinite(designed().result.lowest.z));
}

// The height constraint is part of the search: from the same raised centre and seed, the design
// without it swings the wrist below the table, with min_height 0.05 m it stays above on the dense
// grid (checked here on 4x that grid). The raised centre itself stands the UR3e up: every body
// origin at or above the shoulder (d1), inside the joint limits. A NaN height is refused.
TEST(Excitation, TheMinimumHeightIsAConstraintOfTheSearch) {
  constexpr double d1 = 0.15185;
  const model::RobotModel m = model::load_robot("ur3e");
  ExcitationOptions o = small_options(5);
  o.amplitude = 2.0;  // room to swing low
  o.q0 = excitation_raised_centre(m, o);
  {
    ExcitationTrajectory still;
    still.w_f = 1.0;
    still.q0 = o.q0;
    still.a = still.b = Eigen::MatrixXd::Zero(6, 3);
    EXPECT_GE(excitation_lowest_point(m, still, 1).z, d1 - 1e-6) << o.q0.transpose();
    for (int j = 0; j < 6; ++j) {
      EXPECT_GE(o.q0[j], m.joint(j).limits.q_min + o.position_margin) << "J" << j + 1;
      EXPECT_LE(o.q0[j], m.joint(j).limits.q_max - o.position_margin) << "J" << j + 1;
    }
  }
  const ExcitationResult free_design = design_excitation(m, o);
  ASSERT_LT(free_design.lowest.z, 0.0) << "the unconstrained design must go low for the test to mean anything";
  o.min_height = 0.05;
  const ExcitationResult held = design_excitation(m, o);
  EXPECT_GE(held.lowest.z, 0.05);
  EXPECT_GE(excitation_lowest_point(m, held.trajectory, kDenseSamples).z, 0.05);
  EXPECT_LT(held.cond_final, 1e6);  // still a usable design
  o.min_height = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(design_excitation(m, o), InvalidArgument);
}

// A tool on the flange reaches lower than the flange, and the check covers it when it is given. At
// q = 0 the UR3e's flange faces sideways (level with the J6 axis, d1 - d5 up): one of its x and y
// axes is vertical, so of four points L out along +-x and +-y one is L lower than the flange, and the
// lowest point is d1 - d5 - L, a tool point (n_dof + 1 + k). In a design, a 0.25 m tool the search
// was not told about swings below the table while the flange stays above 0.05 m; told about it, the
// design keeps the tool tip up on the dense grid. Tool
// points that are not finite or farther than 2 m (a value in mm) are refused.
TEST(Excitation, AToolOnTheFlangeIsKeptAboveTheTableWhenItIsGiven) {
  constexpr double d1 = 0.15185, d5 = 0.08535, L = 0.2;
  const model::RobotModel m = model::load_robot("ur3e");
  ExcitationTrajectory still;
  still.w_f = 1.0;
  still.q0 = VectorJ::Zero(6);
  still.a = still.b = Eigen::MatrixXd::Zero(6, 3);
  const std::vector<Eigen::Vector3d> sideways{Eigen::Vector3d(L, 0, 0), Eigen::Vector3d(-L, 0, 0), Eigen::Vector3d(0, L, 0),
                                              Eigen::Vector3d(0, -L, 0)};
  const ExcitationLowestPoint with_tool = excitation_lowest_point(m, still, 1, sideways);
  EXPECT_NEAR(with_tool.z, d1 - d5 - L, 1e-4);
  EXPECT_GE(with_tool.body, m.n_dof() + 1);
  EXPECT_LE(with_tool.body, m.n_dof() + 4);
  // along the flange's own axis the tool stays level with it
  EXPECT_NEAR(excitation_lowest_point(m, still, 1, {Eigen::Vector3d(0, 0, L)}).z, d1 - d5, 1e-4);

  ExcitationOptions o = small_options(5);
  o.amplitude = 2.0;  // room to swing low
  o.q0 = excitation_raised_centre(m, o);
  o.min_height = 0.05;
  const std::vector<Eigen::Vector3d> tool{Eigen::Vector3d(0, 0, 0.25)};
  const ExcitationResult blind = design_excitation(m, o);
  ASSERT_GE(blind.lowest.z, 0.05);
  ASSERT_LT(excitation_lowest_point(m, blind.trajectory, kDenseSamples, tool).z, 0.05)
      << "the design that does not know the tool must take it low for the test to mean anything";
  o.tool_points = tool;
  const ExcitationResult told = design_excitation(m, o);
  EXPECT_GE(told.lowest.z, 0.05);
  EXPECT_GE(excitation_lowest_point(m, told.trajectory, kDenseSamples, tool).z, 0.05);
  EXPECT_LT(told.cond_final, 1e6);

  for (const Eigen::Vector3d& bad : {Eigen::Vector3d(0, 0, std::numeric_limits<double>::quiet_NaN()), Eigen::Vector3d(0, 0, 150.0)}) {
    o.tool_points = {Eigen::Vector3d(0, 0, 0.1), bad};
    try {
      design_excitation(m, o);
      ADD_FAILURE() << "a tool point " << bad.transpose() << " was taken";
    } catch (const InvalidArgument& e) {
      EXPECT_THAT(e.what(), ::testing::HasSubstr("tool_points[1]"));
    }
    EXPECT_THROW(excitation_lowest_point(m, still, 1, {bad}), InvalidArgument);
  }
}

// The installation's tool speed, elbow speed and momentum limits: a design without them goes beyond
// each; with them, it keeps each on a grid four times the design's own check grid (the figures from
// model::cartesian_speeds at every point, and the tool's at a point 0.2 m out), still starts and ends at
// rest and keeps the joint limits, and still excites the parameters. The result reports the peaks.
TEST(Excitation, TheInstallationsToolElbowAndMomentumLimitsAreKept) {
  const model::RobotModel m = model::load_robot("ur3e");
  ExcitationOptions o = small_options(3);
  o.tool_points = {Eigen::Vector3d(0, 0, 0.2)};
  auto peaks = [&](const ExcitationTrajectory& t, const model::RigidBodyInertia& carried = {}) {
    model::DynamicsData d(m);
    model::CartesianSpeeds p;
    VectorJ q, qd, qdd;
    for (int k = 0; k <= kDenseSamples; ++k) {
      t.evaluate(t.period() * k / kDenseSamples, q, qd, qdd);
      const model::CartesianSpeeds c = model::cartesian_speeds(m, d, q, qd, o.tool_points, carried);
      p.tool = std::max(p.tool, c.tool), p.elbow = std::max(p.elbow, c.elbow), p.momentum = std::max(p.momentum, c.momentum);
    }
    return p;
  };
  const ExcitationResult free = design_excitation(m, o);
  const model::CartesianSpeeds fp = peaks(free.trajectory);
  EXPECT_NEAR(free.speed_peak.tool, fp.tool, kGridSlack * fp.tool) << "the result reports the peaks";
  EXPECT_NEAR(free.speed_peak.elbow, fp.elbow, kGridSlack * fp.elbow);
  EXPECT_NEAR(free.speed_peak.momentum, fp.momentum, kGridSlack * fp.momentum);
  EXPECT_EQ(free.speed_peak.tool_point, 0) << "the point 0.2 m out is the tool's fastest";
  // limits at 60 % of what the free design reaches: each binds
  for (int which = 0; which < 3; ++which) {
    ExcitationOptions lo = o;
    double limit = 0.0;
    if (which == 0) lo.tool_speed_max = limit = 0.6 * fp.tool;
    if (which == 1) lo.elbow_speed_max = limit = 0.6 * fp.elbow;
    if (which == 2) lo.momentum_max = limit = 0.6 * fp.momentum;
    const ExcitationResult r = design_excitation(m, lo);
    const model::CartesianSpeeds p = peaks(r.trajectory);
    const double got = which == 0 ? p.tool : which == 1 ? p.elbow : p.momentum;
    EXPECT_LE(got, limit * (1.0 + kGridSlack)) << which;
    EXPECT_GT(got, 0.5 * limit) << which << ": the design uses what the limit allows";
    VectorJ q, qd, qdd;
    r.trajectory.evaluate(0.0, q, qd, qdd);
    EXPECT_LT(qd.cwiseAbs().maxCoeff(), kEndTolerance) << which;
    EXPECT_LT((r.qd_peak - r.qd_lim).maxCoeff(), 1e-9) << which;
    EXPECT_LT(r.cond_final, 1e4) << which;
  }
  // a tool on the flange (2 kg, 5 cm out) counts in the momentum the limit keeps: with it the design
  // keeps the limit, and the arm alone stays below it by the tool's share
  ExcitationOptions heavy = o;
  heavy.carried.mass = 2.0;
  heavy.carried.com = Eigen::Vector3d(0, 0, 0.05);
  heavy.momentum_max = 0.6 * fp.momentum;
  const ExcitationResult r = design_excitation(m, heavy);
  const model::CartesianSpeeds with = peaks(r.trajectory, heavy.carried), without = peaks(r.trajectory);
  EXPECT_LE(with.momentum, heavy.momentum_max * (1.0 + kGridSlack));
  EXPECT_GT(with.momentum, 0.5 * heavy.momentum_max);
  EXPECT_NEAR(r.speed_peak.momentum, with.momentum, kGridSlack * with.momentum) << "the result reports it with the tool";
  EXPECT_LT(without.momentum, 0.9 * with.momentum) << "2 kg on the flange is a sizeable share of a UR3e's momentum";
  heavy.carried.mass = -1.0;
  EXPECT_THROW(heavy.validate(6), InvalidArgument);
}

TEST(Excitation, MatchesTheSimulatorsIndependentFourierEvaluator) {
  const auto& d = designed();
  const ExcitationTrajectory& t = d.result.trajectory;
  sim::FourierCoefficients c{t.w_f, t.q0, t.a, t.b};
  const auto traj = sim::make_fourier(c);
  VectorJ q, qd, qdd, q2, qd2, qdd2;
  for (int m = 0; m < 97; ++m) {
    const double time = t.period() * m / 97.0;
    t.evaluate(time, q, qd, qdd);
    traj->evaluate(time, q2, qd2, qdd2);
    EXPECT_THAT(std::vector<double>(q.begin(), q.end()), ::testing::Pointwise(::testing::DoubleNear(1e-12), std::vector<double>(q2.begin(), q2.end())));
    EXPECT_THAT(std::vector<double>(qd.begin(), qd.end()), ::testing::Pointwise(::testing::DoubleNear(1e-12), std::vector<double>(qd2.begin(), qd2.end())));
    EXPECT_THAT(std::vector<double>(qdd.begin(), qdd.end()), ::testing::Pointwise(::testing::DoubleNear(1e-12), std::vector<double>(qdd2.begin(), qdd2.end())));
  }
  // derivatives: central finite differences of q and qd
  const double h = 1e-5;
  for (double time : {0.37, 1.9, 4.1}) {
    VectorJ qp, qdp, qddp, qm, qdm, qddm;
    t.evaluate(time, q, qd, qdd);
    t.evaluate(time + h, qp, qdp, qddp);
    t.evaluate(time - h, qm, qdm, qddm);
    for (int j = 0; j < d.model.n_dof(); ++j) {
      EXPECT_NEAR((qp[j] - qm[j]) / (2 * h), qd[j], 1e-6);
      EXPECT_NEAR((qdp[j] - qdm[j]) / (2 * h), qdd[j], 1e-5);
    }
  }
}

TEST(Excitation, RespectsPositionVelocityAndAccelerationLimitsOnADenseGrid) {
  const auto& d = designed();
  const ExcitationTrajectory& t = d.result.trajectory;
  VectorJ q, qd, qdd;
  for (int m = 0; m <= kDenseSamples; ++m) {
    t.evaluate(t.period() * m / kDenseSamples, q, qd, qdd);
    for (int j = 0; j < d.model.n_dof(); ++j) {
      const auto& lim = d.model.joint(j).limits;
      // the enforced (tightened) limits ...
      const double span = d.result.q_hi[j] - d.result.q_lo[j];
      ASSERT_GE(q[j], d.result.q_lo[j] - kGridSlack * span) << "joint " << j << " sample " << m;
      ASSERT_LE(q[j], d.result.q_hi[j] + kGridSlack * span) << "joint " << j << " sample " << m;
      ASSERT_LE(std::abs(qd[j]), d.result.qd_lim[j] * (1 + kGridSlack)) << "joint " << j << " sample " << m;
      ASSERT_LE(std::abs(qdd[j]), d.result.qdd_lim[j] * (1 + kGridSlack)) << "joint " << j << " sample " << m;
      // ... and the description's own limits, with the requested amplitude and default acceleration
      ASSERT_GT(q[j], lim.q_min);
      ASSERT_LT(q[j], lim.q_max);
      ASSERT_LE(std::abs(q[j] - t.q0[j]), d.options.amplitude * (1 + kGridSlack));
      ASSERT_LE(std::abs(qd[j]), lim.qd_max);
      ASSERT_LE(std::abs(qdd[j]), d.options.default_qdd_max);  // UR files publish no qdd_max
    }
  }
}

TEST(Excitation, OptimisedConditionNumberIsLowerThanTheRandomStart) {
  const auto& d = designed();
  EXPECT_LT(d.result.cond_final, d.result.cond_start);
  EXPECT_LE(d.result.cond_final, d.result.cond_global * (1 + 1e-9));
  // the reported value is the SVD condition number of W built independently from sim's evaluator
  const double c = excitation_condition_number(d.model, d.result.trajectory, d.options.samples, d.options.friction);
  EXPECT_NEAR(c, d.result.cond_final, 1e-9 * c);
  // a (rescaled) pure single-harmonic motion excites far worse: the design matters
  ExcitationTrajectory one = d.result.trajectory;
  one.a.setZero();
  one.b.setZero();
  one.a.col(1).setConstant(0.1);
  one.a.col(0).setConstant(-0.1);
  EXPECT_GT(excitation_condition_number(d.model, one, d.options.samples, d.options.friction), d.result.cond_final);
}

TEST(Excitation, PandaUsesItsPublishedAccelerationLimits) {
  const model::RobotModel panda = model::load_robot("panda");
  ExcitationOptions o = small_options(3);
  o.global_evaluations = 60;
  o.local_evaluations = 60;
  const ExcitationResult r = design_excitation(panda, o);
  const double qdd_max[7] = {15, 7.5, 10, 12.5, 15, 20, 20};  // Franka specifications
  for (int j = 0; j < 7; ++j) {
    EXPECT_DOUBLE_EQ(r.qdd_lim[j], o.limit_fraction * qdd_max[j]);
    EXPECT_LE(r.qdd_peak[j], r.qdd_lim[j] * (1 + kGridSlack));
    EXPECT_GT(r.q_min_seen[j], panda.joint(j).limits.q_min);
    EXPECT_LT(r.q_max_seen[j], panda.joint(j).limits.q_max);
  }
}

TEST(Excitation, EmittedScenarioLoadsAndRunsInTheSimulator) {
  const auto& d = designed();
  const std::string yaml = excitation_scenario_yaml(d.result.trajectory, "ur3e", 1, "test\nsecond line");
  const sim::Scenario s = sim::parse_scenario(yaml, "excite.yaml");
  EXPECT_EQ(s.trajectory_type, "fourier_series");
  EXPECT_NEAR(s.options.duration, d.result.trajectory.period(), 1e-9);
  // the scenario's trajectory is the designed one
  VectorJ q, qd, qdd, q2, qd2, qdd2;
  for (double time : {0.0, 1.3, 4.44}) {
    d.result.trajectory.evaluate(time, q, qd, qdd);
    s.trajectory->evaluate(time, q2, qd2, qdd2);
    for (int j = 0; j < 6; ++j) {
      EXPECT_NEAR(q[j], q2[j], 1e-12);
      EXPECT_NEAR(qdd[j], qdd2[j], 1e-9);
    }
  }
  // and the virtual robot follows it
  auto simulator = sim::make_simulator(s);
  long rows = 0;
  double worst = 0.0;
  RobotSample last;
  simulator->run([&](const RobotSample& smp) {
    ++rows;
    worst = std::max(worst, (smp.q - smp.target_q).cwiseAbs().maxCoeff());
    last = smp;
  });
  EXPECT_GT(rows, static_cast<long>(0.99 * s.options.duration * s.options.rate));
  EXPECT_LT(worst, 0.05) << "tracking error [rad]";
  EXPECT_LT(last.target_qd.cwiseAbs().maxCoeff(), 0.02);  // the run ends (almost) at rest
}

TEST(ExcitationScenario, MalformedFourierSeriesNamesTheField) {
  const std::string head = "robot: ur3e\ntrajectory:\n  type: fourier_series\n  base_frequency: 0.1\n  q0: [0, 0, 0, 0, 0, 0]\n";
  try {
    sim::parse_scenario(head + "  a: [[1], [1]]\n  b: [[1], [1], [1], [1], [1], [1]]\n", "x.yaml");
    FAIL() << "expected ParseError";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("trajectory.a"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("expected 6 rows"));
  }
  try {
    sim::parse_scenario(head + "  a: [[1], [1], [1], [1], [1], [1]]\n  b: [[1, 2], [1, 2], [1, 2], [1, 2], [1, 2], [1, 2]]\n",
                        "x.yaml");
    FAIL() << "expected ParseError";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("trajectory.b"));
  }
  try {
    sim::parse_scenario("robot: ur3e\ntrajectory:\n  type: fourier_series\n  base_frequency: -1\n", "x.yaml");
    FAIL() << "expected ParseError";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("base_frequency"));
  }
}

void expect_invalid(const ExcitationOptions& o, int n, const std::string& what) {
  try {
    o.validate(n);
    FAIL() << "expected InvalidArgument with '" << what << "'";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr(what));
  }
}

TEST(ExcitationOptions, EachBadFieldIsNamed) {
  ExcitationOptions o;
  o.harmonics = 2;
  expect_invalid(o, 6, "harmonics is 2");
  o = {};
  o.base_frequency = 0.0;
  expect_invalid(o, 6, "base_frequency is 0");
  o = {};
  o.samples = 5;
  expect_invalid(o, 6, "samples is 5");
  o = {};
  o.check_samples = 50;
  expect_invalid(o, 6, "check_samples is 50");
  o = {};
  o.q0 = VectorJ::Zero(5);
  expect_invalid(o, 6, "q0 has 5 values, expected 6");
  o = {};
  o.amplitude = -1;
  expect_invalid(o, 6, "amplitude is -1");
  o = {};
  o.position_margin = -0.1;
  expect_invalid(o, 6, "position_margin is -0.1");
  o = {};
  o.limit_fraction = 1.5;
  expect_invalid(o, 6, "limit_fraction is 1.5");
  o = {};
  o.default_qdd_max = 0;
  expect_invalid(o, 6, "default_qdd_max is 0");
  o = {};
  o.global_evaluations = -1;
  expect_invalid(o, 6, "global_evaluations is -1");
  o = {};
  o.local_evaluations = -2;
  expect_invalid(o, 6, "local_evaluations is -2");
  o = {};
  o.tool_speed_max = 0.0;
  expect_invalid(o, 6, "tool_speed_max is 0");
  o = {};
  o.elbow_speed_max = -1.0;
  expect_invalid(o, 6, "elbow_speed_max is -1");
  o = {};
  o.momentum_max = std::numeric_limits<double>::quiet_NaN();
  expect_invalid(o, 6, "momentum_max is nan");
}

TEST(ExcitationOptions, CentreOutsideTheLimitsIsRejected) {
  const model::RobotModel panda = model::load_robot("panda");
  ExcitationOptions o = small_options(1);
  o.q0 = VectorJ::Zero(7);  // panda joint 4 range is [-3.07, -0.07]: 0 is outside
  try {
    design_excitation(panda, o);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("q0[3]"));
  }
}

}  // namespace
}  // namespace twinwatch::ident
