#include "twinwatch/ident/rigid_body_ls.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "twinwatch/core/error.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "twinwatch/signal/savitzky_golay.hpp"
#include "twinwatch/sim/trajectory.hpp"

namespace twinwatch::ident {
namespace {

using ::testing::HasSubstr;

// estimates must land within this many of their own standard deviations of the truth
// (about 60 parameters per fit: 4 sigma keeps the two-sided miss probability per fit ~ 0.4 %)
constexpr double kSigmas = 4.0;
constexpr double kRate = 500.0;  // [Hz] of the synthetic recordings

// known friction of the synthetic plant, per joint: Coulomb [N·m], viscous [N·m·s/rad], offset [N·m]
struct Friction {
  double Fc, Fv, off;
};
const Friction kFriction[6] = {{1.2, 0.9, 0.3}, {1.5, 1.1, -0.4}, {0.9, 0.7, 0.2}, {0.4, 0.3, -0.1}, {0.35, 0.25, 0.05}, {0.3, 0.2, 0.0}};
// per-joint torque noise [N·m]: heteroscedastic on purpose (weighted LS should find these)
const double kNoise[6] = {0.30, 0.40, 0.20, 0.05, 0.04, 0.03};

// a recording made from RNEA of the description's parameters plus friction and noise: an
// independent check (the LS uses the regressor, the data come from the Newton-Euler recursion)
device::Recording synthetic(const model::RobotModel& m, const sim::Trajectory& traj, double duration, unsigned seed,
                            bool reverse, double extra_odd_friction, double j4_viscous_shift = 0.0) {
  device::Recording rec;
  rec.path = reverse ? "reverse.csv" : "forward.csv";
  rec.n_dof = m.n_dof();
  rec.present = kFieldActualQd | kFieldJointTorque;
  model::DynamicsData d(m);
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  const long N = static_cast<long>(duration * kRate);
  VectorJ q, qd, qdd;
  for (long k = 0; k <= N; ++k) {
    const double t = k / kRate;
    traj.evaluate(reverse ? duration - t : t, q, qd, qdd);
    if (reverse) qd = -qd;
    RobotSample s = RobotSample::empty(m.n_dof());
    s.present = rec.present;
    s.timestamp = t;
    s.q = q;
    s.qd = qd;
    VectorJ tau = model::rnea(m, d, q, qd, qdd);
    for (int j = 0; j < m.n_dof(); ++j) {
      const Friction& f = kFriction[j];
      // an odd friction term the Coulomb + viscous model cannot represent (Stribeck-like bump)
      const double odd = extra_odd_friction * std::tanh(qd[j] / 0.05) * std::exp(-std::abs(qd[j]) / 0.3);
      const double fv = f.Fv + (j == 3 ? j4_viscous_shift : 0.0);
      tau[j] += f.Fc * (qd[j] > 0 ? 1.0 : (qd[j] < 0 ? -1.0 : 0.0)) + fv * qd[j] + f.off + odd + kNoise[j] * g(rng);
    }
    s.joint_torque = tau;
    rec.samples.push_back(s);
  }
  return rec;
}

struct Plant {
  model::RobotModel model = model::load_robot("ur3e");
  std::unique_ptr<sim::Trajectory> traj;
  double duration = 0.0;
  Plant() {
    VectorJ q0(6);
    q0 << 0.2, -1.2, 1.0, -1.5, -1.4, 0.3;
    const auto c = sim::random_fourier(q0, 1.2, 10.0, 5, 11);
    traj = sim::make_fourier(c);
    duration = 20.0;
  }
  Eigen::VectorXd beta_true() const {
    const auto base = model::compute_base_parameters(model);
    return base.base_values(model::standard_parameters(model));
  }
};

const Plant& plant() {
  static const Plant s;
  return s;
}

RigidBodyLsOptions accurate_options() {
  RigidBodyLsOptions o;
  o.derivative_half_window = 10;  // 41 ms at 500 Hz
  o.derivative_order = 4;         // exact enough for 0.5 Hz harmonics (bias << noise)
  return o;
}

// largest |estimate - truth| / std over the base parameters
double worst_normalised_error(const RigidBodyModel& m, const Eigen::VectorXd& truth) {
  double worst = 0.0;
  for (Eigen::Index i = 0; i < truth.size(); ++i) worst = std::max(worst, std::abs(m.beta(i) - truth(i)) / m.beta_std(i));
  return worst;
}

TEST(RigidBodyLs, RecoversBaseAndFrictionParametersWithinTheirStandardDeviations) {
  const Plant& s = plant();
  const device::Recording rec = synthetic(s.model, *s.traj, s.duration, 5, false, 0.0);
  const RigidBodyModel m = identify_rigid_body(s.model, "ur3e", {{&rec, 0.0, 1.0, nullptr}}, accurate_options());
  const Eigen::VectorXd truth = s.beta_true();
  ASSERT_EQ(m.beta.size(), truth.size());
  double sum_sq = 0.0;
  for (Eigen::Index i = 0; i < truth.size(); ++i) {
    const double z = (m.beta(i) - truth(i)) / m.beta_std(i);
    EXPECT_LT(std::abs(z), kSigmas) << "base parameter " << i << ": " << m.beta(i) << " vs " << truth(i) << " std " << m.beta_std(i);
    sum_sq += z * z;
  }
  // the standard deviations are honest, not inflated: the normalised errors have RMS ~ 1
  const double rms_z = std::sqrt(sum_sq / static_cast<double>(truth.size()));
  EXPECT_GT(rms_z, 0.4);
  EXPECT_LT(rms_z, 1.8);
  for (int j = 0; j < 6; ++j) {
    EXPECT_LT(std::abs(m.friction(j, 0) - kFriction[j].Fc), kSigmas * m.friction_std(j, 0)) << "Fc joint " << j;
    EXPECT_LT(std::abs(m.friction(j, 1) - kFriction[j].Fv), kSigmas * m.friction_std(j, 1)) << "Fv joint " << j;
    EXPECT_LT(std::abs(m.friction(j, 2) - kFriction[j].off), kSigmas * m.friction_std(j, 2)) << "offset joint " << j;
  }
}

TEST(RigidBodyLs, FrictionThatWouldPushTheMotionAlongIsHeldAtZeroAndMarked) {
  // J4's torque falls with speed (viscous 0.3 - 0.8 = -0.5 N·m·s/rad): no joint does that, and the
  // re-fit holds the viscous level at 0 and fits the rest on that face
  const Plant& s = plant();
  const device::Recording rec = synthetic(s.model, *s.traj, s.duration, 5, false, 0.0, -0.8);
  const RigidBodyModel m = identify_rigid_body(s.model, "ur3e", {{&rec, 0.0, 1.0, nullptr}}, accurate_options());
  EXPECT_TRUE(m.friction_held(3, 1));
  EXPECT_FALSE(m.friction_held(3, 0));
  EXPECT_EQ(m.friction(3, 1), 0.0);
  EXPECT_EQ(m.friction_std(3, 1), 0.0);
  EXPECT_GE(m.friction(3, 0), 0.0);
  // the other joints are the unconstrained fit: within their spread of the truth, nothing held
  for (int j = 0; j < 6; ++j) {
    if (j == 3) continue;
    EXPECT_FALSE(m.friction_held(j, 0) || m.friction_held(j, 1)) << "joint " << j;
    EXPECT_LT(std::abs(m.friction(j, 1) - kFriction[j].Fv), kSigmas * m.friction_std(j, 1)) << "Fv joint " << j;
  }
  // the mark survives the file
  const RigidBodyModel back = RigidBodyModel::from_json(m.to_json(), "m.json");
  EXPECT_TRUE(back.friction_held(3, 1));
  EXPECT_FALSE(back.friction_held(3, 0));
}

TEST(RigidBodyLs, WeightsFindTheNoiseOfEachJoint) {
  const Plant& s = plant();
  const device::Recording rec = synthetic(s.model, *s.traj, s.duration, 6, false, 0.0);
  const RigidBodyModel wls = identify_rigid_body(s.model, "ur3e", {{&rec, 0.0, 1.0, nullptr}}, accurate_options());
  for (int j = 0; j < 6; ++j) EXPECT_NEAR(wls.sigma[static_cast<size_t>(j)], kNoise[j], 0.1 * kNoise[j]) << "joint " << j;
  // weighting by 1/sigma_j^2 lowers the parameter uncertainty against OLS on heteroscedastic noise
  RigidBodyLsOptions o = accurate_options();
  o.weighted = false;
  const RigidBodyModel ols = identify_rigid_body(s.model, "ur3e", {{&rec, 0.0, 1.0, nullptr}}, o);
  double lw = 0.0, lo = 0.0;
  for (Eigen::Index i = 0; i < wls.beta.size(); ++i) lw += std::log(wls.beta_std(i)), lo += std::log(ols.beta_std(i));
  EXPECT_LT(lw, lo);
  EXPECT_LT(worst_normalised_error(ols, s.beta_true()), kSigmas);
}

TEST(RigidBodyLs, ForwardReverseAveragingCancelsOddFrictionTheModelCannotRepresent) {
  const Plant& s = plant();
  const double bump = 3.0;  // [N·m] odd, unmodelled friction near zero velocity
  const device::Recording fwd = synthetic(s.model, *s.traj, s.duration, 7, false, bump);
  const device::Recording rev = synthetic(s.model, *s.traj, s.duration, 8, true, bump);
  RigidBodyLsOptions o = accurate_options();
  o.reversal_screen = 0.0;  // keep every row: the averaging alone must remove the friction
  const RigidBodyModel avg = identify_rigid_body(s.model, "ur3e", {{&fwd, 0.0, 1.0, &rev}}, o);
  // the forward run alone, fitted with the Coulomb + viscous model: the bump leaks into beta
  const RigidBodyModel plain = identify_rigid_body(s.model, "ur3e", {{&fwd, 0.0, 1.0, nullptr}}, o);
  EXPECT_TRUE(avg.averaged);
  EXPECT_FALSE(plain.averaged);
  const Eigen::VectorXd truth = s.beta_true();
  const double e_avg = worst_normalised_error(avg, truth);
  EXPECT_LT(e_avg, kSigmas);
  // errors on the same scale (the averaged fit's std): the plain fit is biased well beyond it
  double e_plain = 0.0;
  for (Eigen::Index i = 0; i < truth.size(); ++i) e_plain = std::max(e_plain, std::abs(plain.beta(i) - truth(i)) / avg.beta_std(i));
  EXPECT_GT(e_plain, 2.0 * kSigmas);
  for (int j = 0; j < 6; ++j)
    EXPECT_LT(std::abs(avg.friction(j, 2) - kFriction[j].off), kSigmas * avg.friction_std(j, 2) + 0.02) << "offset joint " << j;
}

TEST(RigidBodyLs, MismatchedReversePairIsRejected) {
  const Plant& s = plant();
  const device::Recording fwd = synthetic(s.model, *s.traj, s.duration, 7, false, 0.0);
  const device::Recording other = synthetic(s.model, *s.traj, s.duration, 8, false, 0.0);  // not reversed
  try {
    identify_rigid_body(s.model, "ur3e", {{&fwd, 0.0, 1.0, &other}}, accurate_options());
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("is not forward.csv played backwards"));
  }
}

TEST(RigidBodyLs, PredictionOnAHeldOutSegmentMatchesTheNoiseLevel) {
  const Plant& s = plant();
  const device::Recording rec = synthetic(s.model, *s.traj, s.duration, 9, false, 0.0);
  const RigidBodyLsOptions o = accurate_options();
  const RigidBodyModel m = identify_rigid_body(s.model, "ur3e", {{&rec, 0.0, 0.6, nullptr}}, o);
  const TorqueData val = torque_data({&rec, 0.6, 1.0, nullptr}, o.signal, o.derivative_half_window, o.derivative_order);
  model::DynamicsData d(s.model);
  const auto metrics = torque_metrics(val, [&](size_t k) { return m.predict(s.model, d, val.q[k], val.qd[k], val.qdd[k]); });
  for (int j = 0; j < 6; ++j) EXPECT_LT(metrics[static_cast<size_t>(j)].rmse, 1.15 * kNoise[j]) << "joint " << j;
  // JSON round trip keeps the prediction
  const RigidBodyModel back = RigidBodyModel::from_json(m.to_json(), "m.json");
  const VectorJ a = m.predict(s.model, d, val.q[5], val.qd[5], val.qdd[5]);
  const VectorJ b = back.predict(s.model, d, val.q[5], val.qd[5], val.qdd[5]);
  for (int j = 0; j < 6; ++j) EXPECT_NEAR(a[j], b[j], 1e-9 * (1 + std::abs(a[j])));
}

TEST(RigidBodyLs, LocalPolynomialEqualsSavitzkyGolayOnAUniformGrid) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<double> t(200), x(200);
  for (size_t k = 0; k < t.size(); ++k) t[k] = 0.002 * k, x[k] = std::sin(3.0 * t[k]) + 0.01 * g(rng);
  for (int deriv : {0, 1}) {
    signal::SavitzkyGolay sg;
    sg.window = 21;
    sg.order = 3;
    sg.deriv = deriv;
    sg.delta = 0.002;
    const auto ref = sg.apply(x);
    const auto lp = local_polynomial(t, x, 10, 3, deriv);
    for (size_t k = 0; k < t.size(); ++k) EXPECT_NEAR(lp[k], ref[k], 1e-8 * (1 + std::abs(ref[k]))) << "deriv " << deriv << " k " << k;
  }
  // on an irregular axis it still differentiates a polynomial of its order exactly
  std::vector<double> ti(100), xi(100);
  double tt = 0.0;
  std::uniform_real_distribution<double> u(0.0007, 0.0088);
  for (size_t k = 0; k < ti.size(); ++k) tt += u(rng), ti[k] = tt, xi[k] = 1.0 + 2.0 * tt - 3.0 * tt * tt;
  const auto di = local_polynomial(ti, xi, 5, 2, 1);
  for (size_t k = 0; k < ti.size(); ++k) EXPECT_NEAR(di[k], 2.0 - 6.0 * ti[k], 1e-8);
}

TEST(RigidBodyLs, MissingTorqueColumnsAreNamed) {
  const Plant& s = plant();
  device::Recording rec = synthetic(s.model, *s.traj, 2.0, 1, false, 0.0);
  RigidBodyLsOptions o = accurate_options();
  o.signal = TorqueSignal::CurrentAsTorque;
  try {
    identify_rigid_body(s.model, "ur3e", {{&rec, 0.0, 1.0, nullptr}}, o);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("no actual_current_as_torque_* columns"));
  }
  try {
    identify_rigid_body(s.model, "ur3e", {{&rec, 0.7, 0.2, nullptr}}, accurate_options());
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("segment [0.7, 0.2)"));
  }
}

void expect_invalid(const RigidBodyLsOptions& o, const std::string& what) {
  try {
    o.validate();
    FAIL() << "expected InvalidArgument with '" << what << "'";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr(what));
  }
}

TEST(RigidBodyLsOptions, EachBadFieldIsNamed) {
  RigidBodyLsOptions o;
  o.reversal_screen = -0.1;
  expect_invalid(o, "reversal_screen is -0.1");
  o = {};
  o.weight_iterations = -1;
  expect_invalid(o, "weight_iterations is -1");
  o = {};
  o.derivative_half_window = 0;
  expect_invalid(o, "derivative_half_window is 0");
  o = {};
  o.derivative_order = 0;
  expect_invalid(o, "derivative_order is 0");
  o = {};
  o.decimate = 0;
  expect_invalid(o, "decimate is 0");
  EXPECT_THROW(torque_signal_from_string("torque"), InvalidArgument);
  EXPECT_EQ(torque_signal_from_string("target_moment"), TorqueSignal::TargetMoment);
}


// A model file is read as strictly as a twin file (session 34 audit: a base column out of the
// regressor's range made validate-torque read past it and crash): every column within the robot's
// 10 parameters per joint, once; as many values as columns; a twin file named for what it is.
TEST(RigidBodyModelFile, EachBadFieldIsNamedBeforeAPredictionCanUseIt) {
  RigidBodyModel m;
  m.robot = "ur3e";
  m.base_columns = {0, 5, 59};
  m.beta = Eigen::Vector3d(1.0, 2.0, 3.0);
  m.beta_std = Eigen::Vector3d::Zero();
  m.friction = Eigen::MatrixXd::Constant(6, 3, 0.1);
  m.friction_std = Eigen::MatrixXd::Zero(6, 3);
  m.friction_held.setConstant(6, 2, false);
  const std::string good = m.to_json();
  const RigidBodyModel back = RigidBodyModel::from_json(good, "m.json", 6);
  EXPECT_EQ(back.base_columns, m.base_columns);
  EXPECT_EQ(back.beta, m.beta);
  const auto error_of = [&](const std::string& from, const std::string& to, int n_dof = 6) -> std::string {
    std::string text = good;
    const size_t at = text.find(from);
    if (at == std::string::npos) return "the test's text '" + from + "' is not in the file";
    text.replace(at, from.size(), to);
    try {
      RigidBodyModel::from_json(text, "m.json", n_dof);
    } catch (const ParseError& e) {
      return e.what();
    }
    return "no error";
  };
  const std::string columns = good.substr(good.find("\"base_columns\""), good.find(']', good.find("\"base_columns\"")) + 1 - good.find("\"base_columns\""));
  EXPECT_THAT(error_of(columns, "\"base_columns\": [0, 5, 9999]"),
              HasSubstr("m.json: field 'base_columns[2]': expected a column 0..59 (6 joints), got 9999"));
  EXPECT_THAT(error_of(columns, "\"base_columns\": [-1, 5, 59]"), HasSubstr("field 'base_columns[0]': expected a column 0..59 (6 joints), got -1"));
  EXPECT_THAT(error_of(columns, "\"base_columns\": [5, 5, 59]"),
              HasSubstr("field 'base_columns[1]': expected each standard column once, got column 5 again (also at base_columns[0])"));
  EXPECT_THAT(error_of(columns, "\"base_columns\": [0, 5]"), HasSubstr("field 'beta': expected 2 values, got 3"));
  EXPECT_THAT(error_of(columns, "\"base_columns\": [0, 5, 1.5]"), HasSubstr("field 'base_columns[2]': expected a whole number, got 1.5"));
  // (column 59 is the 6th joint's last: a 5-joint robot has no such column)
  EXPECT_THAT(error_of("\"kind\"", "\"other\": 1, \"kind\"", 6), HasSubstr("field 'other': unknown key"));
  EXPECT_THAT(RigidBodyModel::from_json(good, "m.json", 0).base_columns.back(), 59);
  try {
    RigidBodyModel::from_json(good, "m.json", 5);
    ADD_FAILURE() << "a 6-row model read as a 5-joint robot's";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("field 'friction': expected 5 rows (one per joint of ur3e), got 6"));
  }
  EXPECT_THAT(error_of("\"rigid_body_torque\"", "\"twin\""), HasSubstr("field 'kind': expected 'rigid_body_torque' (a model from 'twinwatch identify-torque'), got 'twin'"));
  try {
    RigidBodyModel::from_json("{\"created\": \"x\", \"joints\": []}", "twin.json");
    ADD_FAILURE() << "a twin file read as a torque model";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("twin.json: field 'kind': missing: expected 'rigid_body_torque'"));
  }
}

}  // namespace
}  // namespace twinwatch::ident
