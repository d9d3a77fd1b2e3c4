// Cao's sequential identification: each step against synthetic recordings whose answer is known,
// then end to end on simulated recordings (the twin reads recordings only; the test compares).
#include "twinwatch/ident/sequential_ident.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "twinwatch/core/error.hpp"
#include "twinwatch/sim/scenario.hpp"
#include "twinwatch/signal/metrics.hpp"

namespace twinwatch::ident {
namespace {

using ::testing::HasSubstr;

constexpr double kDt = 0.002;  // 500 Hz, like RTDE

device::Recording synthetic(int n) {
  device::Recording r;
  r.path = "synthetic.csv";
  r.n_dof = n;
  r.present = kFieldActualQd | kFieldTargetQ | kFieldTargetQd | kFieldActualCurrent;
  return r;
}

RobotSample sample(int n, double t) {
  RobotSample s;
  s.timestamp = t;
  s.q = s.qd = s.target_q = s.target_qd = s.target_qdd = s.current = VectorJ::Zero(n);
  s.temperature = VectorJ::Constant(n, std::nan(""));
  return s;
}

TEST(CandidateLibrary, HasCaoDimensionsAndNamedTerms) {
  CandidateLibrary lib{{}, {1, 2}, 2};
  EXPECT_EQ(lib.size_a(6), 27);  // (n^2 + 3n) / 2
  EXPECT_EQ(lib.size_b(), 25);   // (2m + 1)^2
  EXPECT_EQ(lib.size(6), 675);
  // every candidate equals the product its name says, on a random state
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-2, 2);
  VectorJ q(6), qd(6), qdd(6);
  for (int j = 0; j < 6; ++j) q[j] = U(rng), qd[j] = U(rng), qdd[j] = U(rng);
  Eigen::VectorXd g(675);
  lib.row(q, qd, qdd, g);
  EXPECT_EQ(lib.name(6, 0), "qdd1");
  EXPECT_DOUBLE_EQ(g(0), qdd[0]);
  const int k1 = 1 * 25 + 1 * 5 + 4;  // qdd2 * sin(q2) * cos(2 q3)
  EXPECT_EQ(lib.name(6, k1), "qdd2*sin(q2)*cos(2q3)");
  EXPECT_NEAR(g(k1), qdd[1] * std::sin(q[1]) * std::cos(2 * q[2]), 1e-14);
  const int k2 = 7 * 25 + 2 * 5 + 3;  // A[7] = qd1*qd2, cos(q2) * sin(2 q3)
  EXPECT_EQ(lib.name(6, k2), "qd1*qd2*cos(q2)*sin(2q3)");
  EXPECT_NEAR(g(k2), qd[0] * qd[1] * std::cos(q[1]) * std::sin(2 * q[2]), 1e-14);
  EXPECT_EQ(lib.name(6, 26 * 25 + 24), "qd6*qd6*cos(2q2)*cos(2q3)");
  EXPECT_NEAR(g(26 * 25 + 24), qd[5] * qd[5] * std::cos(2 * q[1]) * std::cos(2 * q[2]), 1e-14);
}

TEST(CandidateLibrary, FullKroneckerOverSixJointsIsRejected) {
  CandidateLibrary lib{{}, {0, 1, 2, 3, 4, 5}, 2};  // 27 x 5^6 = 421875 candidates
  try {
    lib.validate(6);
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("421875 candidates"));
  }
}

TEST(CandidateLibrary, ValidationNamesTheField) {
  try {
    CandidateLibrary{{}, {1, 7}, 2}.validate(6);
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("config_joints[1] is joint 8, must be in 1..6"));
  }
  try {
    CandidateLibrary{{0, 0}, {1}, 2}.validate(6);
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("motion_joints: joint 1 appears twice"));
  }
  try {
    CandidateLibrary{{}, {1}, 0}.validate(6);
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("harmonics is 0, must be in 1..10"));
  }
}

// Cao eq. 14: holds reached from below and from above; the current carries gravity plus a
// Coulomb term of the approach direction, which the pair average cancels
TEST(SequentialSteps, PairedHoldsCancelCoulombFriction) {
  const int n = 2;
  device::Recording rec = synthetic(n);
  auto gravity = [](const VectorJ& q) { return VectorJ((Eigen::Vector2d(1.3 * std::cos(q[0]), -0.4 * std::sin(q[1] + 0.3)))); };
  const Eigen::Vector2d fc(0.35, 0.2);
  double t = 0.0;
  const std::vector<Eigen::Vector2d> poses{{0.1, -0.5}, {0.8, 0.4}, {-0.6, 1.0}};
  for (const auto& p : poses) {
    for (int dir : {+1, -1}) {
      // creep towards the pose for 0.5 s, then hold 1 s
      for (int k = 0; k < 250; ++k, t += kDt) {
        RobotSample s = sample(n, t);
        s.target_qd = s.qd = VectorJ::Constant(n, 0.05 * dir);
        s.q = s.target_q = p - s.qd * (250 - k) * kDt;
        s.current = gravity(s.q) + dir * fc;
        rec.samples.push_back(s);
      }
      for (int k = 0; k < 500; ++k, t += kDt) {
        RobotSample s = sample(n, t);
        s.q = s.target_q = p;
        s.current = gravity(s.q) + dir * fc;  // the bristles keep the approach's friction
        rec.samples.push_back(s);
      }
    }
  }
  SequentialOptions o;
  const auto gs = paired_holds(rec, o);
  ASSERT_EQ(gs.size(), poses.size());
  for (size_t k = 0; k < gs.size(); ++k) {
    EXPECT_NEAR((gs[k].q - VectorJ(poses[k])).norm(), 0.0, 1e-12);
    EXPECT_NEAR((gs[k].current - gravity(gs[k].q)).norm(), 0.0, 1e-12) << "pose " << k;
  }
}

// Cao eq. 15: a sine on both joints, current = friction (odd in qd) + terms even about each
// turning point (gravity, inertia); the half differences of mirrored samples give the friction
TEST(SequentialSteps, SinePairsRecoverCoulombAndViscousFriction) {
  const int n = 2;
  device::Recording rec = synthetic(n);
  const double w = 2 * M_PI * 0.25;
  const Eigen::Vector2d A(0.8, 0.5), Fc(0.4, 0.25), Fv(0.9, 0.3);
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, 0.02);
  for (int k = 0; k < 8000; ++k) {
    const double t = k * kDt;
    RobotSample s = sample(n, t);
    for (int j = 0; j < n; ++j) {
      s.q[j] = s.target_q[j] = A[j] * std::sin(w * t);
      s.qd[j] = s.target_qd[j] = A[j] * w * std::cos(w * t);
      const double qdd = -A[j] * w * w * std::sin(w * t);
      s.current[j] = Fc[j] * (s.qd[j] > 0 ? 1 : -1) + Fv[j] * s.qd[j] + 0.7 * qdd + 1.1 * std::cos(s.q[0]) + noise(rng);
    }
    rec.samples.push_back(s);
  }
  SequentialOptions o;
  for (int j = 0; j < n; ++j) {
    const auto pr = sine_pairs(rec, j, o);
    ASSERT_GT(pr.size(), 1000u);
    Eigen::MatrixXd X(static_cast<long>(pr.size()), 2);
    Eigen::VectorXd y(static_cast<long>(pr.size()));
    for (size_t k = 0; k < pr.size(); ++k) {
      X(static_cast<long>(k), 0) = pr[k].first > 0 ? 1 : -1;
      X(static_cast<long>(k), 1) = pr[k].first;
      y(static_cast<long>(k)) = pr[k].second;
    }
    const Eigen::Vector2d f = X.colPivHouseholderQr().solve(y);
    EXPECT_NEAR(f(0), Fc[j], 0.01) << "joint " << j;
    EXPECT_NEAR(f(1), Fv[j], 0.01) << "joint " << j;
  }
}

TEST(SequentialSteps, SineFrictionKeepsBothLevelsOfOneSignWhicheverWayTheChannelCounts) {
  // a healthy joint: the free fit is feasible and returned as is, in either current direction
  std::vector<std::pair<double, double>> pr;
  for (int k = 0; k < 400; ++k) {
    const double v = (k % 2 ? 1.0 : -1.0) * (0.05 + 1.5 * k / 400.0);
    pr.emplace_back(v, 0.4 * (v > 0 ? 1 : -1) + 0.9 * v);
  }
  const SineFriction f = fit_sine_friction(pr);
  EXPECT_NEAR(f.coulomb, 0.4, 1e-9);
  EXPECT_NEAR(f.viscous, 0.9, 1e-9);
  EXPECT_EQ(f.orientation, 1.0);
  EXPECT_FALSE(f.coulomb_held || f.viscous_held);
  for (auto& p : pr) p.second = -p.second;  // a channel that counts the other way
  const SineFriction r = fit_sine_friction(pr);
  EXPECT_NEAR(r.coulomb, -0.4, 1e-9);
  EXPECT_NEAR(r.viscous, -0.9, 1e-9);
  EXPECT_EQ(r.orientation, -1.0);
  EXPECT_FALSE(r.coulomb_held || r.viscous_held);

  // a sine that only reaches 0.45-0.55 rad/s: sign(qd) and qd are nearly collinear, and noise
  // splits 0.5 A of friction into a large Coulomb level and a negative viscous one (or the reverse)
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.05);
  int held = 0;
  for (int trial = 0; trial < 40; ++trial) {
    std::vector<std::pair<double, double>> narrow;
    for (int k = 0; k < 200; ++k) {
      const double v = (k % 2 ? 1.0 : -1.0) * (0.45 + 0.1 * (k % 50) / 50.0);
      narrow.emplace_back(v, 0.5 * (v > 0 ? 1 : -1) + 0.02 * v + noise(rng));
    }
    const SineFriction n = fit_sine_friction(narrow);
    EXPECT_GE(n.coulomb, 0.0);
    EXPECT_GE(n.viscous, 0.0);
    if (n.coulomb_held || n.viscous_held) {
      ++held;
      // the free fit had one level negative, and the held fit still carries the friction
      EXPECT_LT(std::min(n.free_coulomb, n.free_viscous), 0.0);
      EXPECT_NEAR(n.coulomb + 0.5 * n.viscous, 0.5 + 0.02 * 0.5, 0.03);
    }
  }
  EXPECT_GT(held, 5);  // the narrow sine does produce the case
}

// --- end to end on the virtual UR3e ------------------------------------------------------------

device::Recording simulate(const std::string& file, double duration) {
  sim::Scenario s = sim::load_scenario(std::string(TWINWATCH_SOURCE_DIR) + "/scenarios/ur3e/" + file);
  s.options.duration = duration;
  device::Recording rec;
  rec.path = file;
  rec.n_dof = 6;
  rec.present = sim::Simulator::fields();
  sim::make_simulator(s)->run([&](const RobotSample& x) { rec.samples.push_back(x); });
  return rec;
}

// recordings are simulated once per process; the identification runs in one test (ctest runs
// each test in its own process, so splitting it would repeat the Lasso for every check)
struct Sequential : ::testing::Test {
  static void SetUpTestSuite() {
    qs = new device::Recording(simulate("validation/quasi_static_train.yaml", 16 * 7.6));  // the first 16 poses
    sine = new device::Recording(simulate("validation/sine_train.yaml", 20));
    exc = new device::Recording(simulate("validation/excitation_train.yaml", 40));
  }
  static void TearDownTestSuite() {
    delete qs;
    delete sine;
    delete exc;
  }
  static device::Recording *qs, *sine, *exc;
};
device::Recording *Sequential::qs = nullptr, *Sequential::sine = nullptr, *Sequential::exc = nullptr;

TEST_F(Sequential, IdentifiesFromRecordingsAndPredictsAnUntrainedTrajectory) {
  const device::Recording fig = simulate("validation/figure_eight_fast_payload.yaml", 12);
  SequentialOptions o;
  o.nlambda = 40;  // keeps the test short; the CLI uses 100 lambdas, 10 folds, every 2nd sample
  o.nfolds = 5;
  o.decimate = 4;
  SequentialReport report;
  // the Lasso needs varied states: one periodic excitation alone lets it fit proxies that
  // extrapolate badly (docs/validation.md), so the sine and quasi-static runs join it
  const TwinModel twin = identify_sequential("ur3e", {qs}, {sine}, {{exc, {}}, {sine, {}}, {qs, {}}}, o, report);

  // every step finds its data
  EXPECT_EQ(report.poses, 16);
  for (int j = 0; j < 6; ++j) {
    EXPECT_GT(report.friction_pairs[static_cast<size_t>(j)], 1000) << "joint " << j;
    // paired holds are averages of hundreds of samples: the gravity fit is far below the noise
    EXPECT_LT(report.gravity_rmse[static_cast<size_t>(j)], 0.01) << "joint " << j;
    EXPECT_GT(report.nonzero[static_cast<size_t>(j)], 0) << "joint " << j;
    EXPECT_LT(report.nonzero[static_cast<size_t>(j)], report.candidates) << "joint " << j;
  }
  ASSERT_TRUE(twin.sequential.has_value());
  EXPECT_EQ(twin.method, "sequential");
  // friction comes out positive (the simulator's truth has Coulomb > 0 on every joint)
  for (const auto& jm : twin.sequential->joints) EXPECT_GT(jm.coulomb, 0.0);

  // the untrained figure-eight carries 0.5 kg that the training runs did not: leave the loaded
  // shoulder and elbow out; the other joints must follow it
  const auto qdd = joint_accelerations(fig);
  std::vector<std::vector<double>> meas(6), pred(6);
  VectorJ i;
  const VectorJ nan = VectorJ::Constant(6, std::nan(""));
  for (size_t k = 0; k < fig.samples.size(); ++k) {
    const RobotSample& s = fig.samples[k];
    twin.predict_current(s.q, s.qd, qdd[k], nan, i);
    for (int j = 0; j < 6; ++j) meas[static_cast<size_t>(j)].push_back(s.current[j]), pred[static_cast<size_t>(j)].push_back(i[j]);
  }
  for (int j : {0, 3, 4, 5}) {
    const auto m = signal::fit_metrics(meas[static_cast<size_t>(j)], pred[static_cast<size_t>(j)]);
    // the physics twin reaches 0.018-0.036 A on these joints (docs/validation.md)
    EXPECT_LT(m.rmse, 0.06) << "joint " << j + 1;
  }

  // the twin file round-trips the prediction
  const TwinModel back = TwinModel::from_json(twin.to_json(), "mem");
  ASSERT_TRUE(back.sequential.has_value());
  VectorJ a, b;
  for (size_t k = 0; k < exc->samples.size(); k += 997) {
    const RobotSample& s = exc->samples[k];
    twin.predict_current(s.q, s.qd, s.target_qdd, nan, a);
    back.predict_current(s.q, s.qd, s.target_qdd, nan, b);
    EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-12);
  }

  // and a bad twin file names the field
  std::string text = twin.to_json();
  const auto pos = text.find("\"lasso_index\": [");
  ASSERT_NE(pos, std::string::npos);
  text.insert(pos + 16, "99999, ");
  try {
    TwinModel::from_json(text, "bad.json");
    ADD_FAILURE();
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("sequential.joints[0].lasso_"));
  }
  // friction that pushes the motion along at some speeds (levels of opposite sign) is refused
  text = twin.to_json();
  const auto v = text.find("\"viscous\": ");
  ASSERT_NE(v, std::string::npos);
  text.insert(v + 11, "-");
  try {
    TwinModel::from_json(text, "bad.json");
    ADD_FAILURE();
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("sequential.joints[0].viscous"));
    EXPECT_THAT(e.what(), HasSubstr("expected the sign of coulomb"));
  }
}

TEST_F(Sequential, MissingRolesAreNamed) {
  SequentialReport r;
  try {
    identify_sequential("ur3e", {}, {sine}, {{exc, {}}}, SequentialOptions{}, r);
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("--quasi-static FILE"));
  }
  try {
    identify_sequential("ur3e", {qs}, {}, {{exc, {}}}, SequentialOptions{}, r);
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("--sine FILE"));
  }
}

TEST_F(Sequential, WrongRecordingsForAStepAreNamed) {
  SequentialReport r;
  try {
    identify_sequential("ur3e", {exc}, {sine}, {{exc, {}}}, SequentialOptions{}, r);
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("excitation_train.yaml (quasi-static recording): no pose held"));
  }
  try {
    identify_sequential("ur3e", {qs}, {exc}, {{exc, {}}}, SequentialOptions{}, r);
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("(sine recording): "));
    EXPECT_THAT(e.what(), HasSubstr("mirrored sample pairs for joint"));
  }
}

TEST(SequentialOptions, ValidationNamesTheField) {
  SequentialOptions o;
  o.decimate = 0;
  EXPECT_THROW(
      try { o.validate(6); } catch (const InvalidArgument& e) {
        EXPECT_THAT(e.what(), HasSubstr("decimate is 0, must be >= 1"));
        throw;
      },
      InvalidArgument);
  o = SequentialOptions{};
  o.min_hold = 0;
  EXPECT_THROW(
      try { o.validate(6); } catch (const InvalidArgument& e) {
        EXPECT_THAT(e.what(), HasSubstr("min_hold is 0 s, must be > 0"));
        throw;
      },
      InvalidArgument);
  o = SequentialOptions{};
  o.prune_ratio = 1.0;
  EXPECT_THROW(
      try { o.validate(6); } catch (const InvalidArgument& e) {
        EXPECT_THAT(e.what(), HasSubstr("prune_ratio is 1, must be in [0, 1)"));
        throw;
      },
      InvalidArgument);
}

}  // namespace
}  // namespace twinwatch::ident
