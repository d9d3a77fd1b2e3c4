// The twin file (format version 2): every field the writer always writes is required, each value
// is checked, unknown and repeated keys are refused, and every message names the file, the JSON
// path, the expected and the actual value. Version-1 files load with the defaults of the fields
// their writers lacked and one warning. save() reports a failed write.
#include "twinwatch/ident/twin_model.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/log.hpp"
#include "twinwatch/model/description_io.hpp"
#include "error_text.hpp"

namespace twinwatch::ident {
namespace {

using ::testing::HasSubstr;
using nlohmann::json;

// a complete twin file as the writer writes it: UR3e, one base parameter, a low-speed friction on J3
json valid_twin() {
  TwinModel t("ur3e", model::load_robot("ur3e"));
  t.joints.resize(6);
  t.base_columns = {10};
  t.beta = Eigen::VectorXd::Constant(1, 0.1);
  t.joints[2].presliding_alpha = 5000.0;
  t.joints[2].presliding = 0.3;
  t.joints[2].stribeck_velocity = 0.04;
  t.joints[2].stribeck = 0.1;
  t.monitor_json = R"({"static_level_A": [0.1, 0.1, 0.1, 0.1, 0.1, 0.1]})";  // opaque here
  return json::parse(t.to_json());
}

std::string error_of(const json& j) {
  return twinwatch::test::error_text<ParseError>([&] { TwinModel::from_json(j.dump(1), "twin.json"); });
}

// the log warnings a call leaves
template <class F>
std::vector<std::string> warnings_of(F&& f) {
  std::vector<std::string> out;
  log::set_sink([&](log::Level level, std::string_view m) {
    if (level == log::Level::Warn) out.emplace_back(m);
  });
  f();
  log::set_sink(nullptr);
  return out;
}

TEST(TwinFile, TheWriterWritesVersion2AndItLoadsBackWithoutAWarning) {
  const json j = valid_twin();
  EXPECT_EQ(j["version"], kTwinFormatVersion);
  EXPECT_EQ(kTwinFormatVersion, 2);
  ASSERT_TRUE(j["joints"][0].contains("low_speed_friction")) << "written for every joint, all zero when none";
  TwinModel back;
  EXPECT_TRUE(warnings_of([&] { back = TwinModel::from_json(j.dump(), "twin.json"); }).empty());
  EXPECT_EQ(back.origin, "twin.json");
  EXPECT_DOUBLE_EQ(back.joints[2].presliding, 0.3);
  EXPECT_EQ(back.joints[0].presliding_alpha, 0.0);
}

TEST(TwinFile, AMissingFieldOfAVersion2FileIsNamedWithItsPath) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"joints", "2", "c_gen"}, "twin.json: field 'joints[2].c_gen': missing required field"},
      {{"joints", "2", "low_speed_friction"}, "twin.json: field 'joints[2].low_speed_friction': missing required field"},
      {{"joints", "2", "low_speed_friction", "stribeck"}, "twin.json: field 'joints[2].low_speed_friction.stribeck': missing required field"},
      {{"joints", "4", "gain_identified"}, "twin.json: field 'joints[4].gain_identified': missing required field"},
      {{"direction_blend"}, "twin.json: field 'direction_blend': missing required field"},
      {{"temperature_ref"}, "twin.json: field 'temperature_ref': missing required field"},
      {{"payload"}, "twin.json: field 'payload': missing required field"},
      {{"payload", "com"}, "twin.json: field 'payload.com': missing required field"},
      {{"method"}, "twin.json: field 'method': missing required field"},
      {{"gains_absolute"}, "twin.json: field 'gains_absolute': missing required field"},
      {{"version"}, "twin.json: field 'version': missing required field"},
  };
  for (const auto& [path, message] : cases) {
    json j = valid_twin();
    json* o = &j;
    for (size_t k = 0; k + 1 < path.size(); ++k) o = o->is_array() ? &(*o)[std::stoul(path[k])] : &(*o)[path[k]];
    o->erase(path.back());
    EXPECT_THAT(error_of(j), HasSubstr(message));
  }
}

TEST(TwinFile, AVersion1FileLoadsWithTheDefaultsItsWritersAssumedAndOneWarning) {
  json j = valid_twin();
  j["version"] = 1;
  j.erase("direction_blend");
  j["joints"][1].erase("gain_identified");
  j["joints"][3].erase("low_speed_friction");
  j["joints"][2]["c_gen"] = 0.8;
  TwinModel t;
  const auto w = warnings_of([&] { t = TwinModel::from_json(j.dump(), "old.json"); });
  ASSERT_EQ(w.size(), 1u);
  EXPECT_THAT(w[0], HasSubstr("old.json: a version-1 twin file"));
  EXPECT_THAT(w[0], HasSubstr("direction_blend = 0"));
  EXPECT_THAT(w[0], HasSubstr("joints[1].gain_identified = true"));
  EXPECT_THAT(w[0], HasSubstr("joints[3].low_speed_friction = none"));
  EXPECT_THAT(w[0], HasSubstr("re-identify"));
  EXPECT_EQ(t.direction_blend, 0.0);
  EXPECT_TRUE(t.joints[1].gain_identified);
  EXPECT_EQ(t.joints[3].presliding_alpha, 0.0);
  EXPECT_EQ(t.joints[3].stribeck_velocity, 0.0);
  EXPECT_DOUBLE_EQ(t.joints[2].presliding, 0.3) << "a field the file has is read, not defaulted";
  EXPECT_DOUBLE_EQ(t.joints[2].c_gen, 0.8);
  // what every version-1 writer wrote is required there too
  j["joints"][2].erase("c_gen");
  EXPECT_THAT(error_of(j), HasSubstr("twin.json: field 'joints[2].c_gen': missing required field"));
  // a complete version-1 file still says what it is
  json full = valid_twin();
  full["version"] = 1;
  full.erase("monitor");  // (valid_twin's block has only what the monitor's tests need)
  const auto w1 = warnings_of([&] { TwinModel::from_json(full.dump(), "v1.json"); });
  ASSERT_EQ(w1.size(), 1u);
  EXPECT_THAT(w1[0], HasSubstr("v1.json: a version-1 twin file, read as version 2 with every field present"));
  // saved again, it is a version-2 file with the defaults written out
  const json again = json::parse(t.to_json());
  EXPECT_EQ(again["version"], 2);
  EXPECT_EQ(again["direction_blend"], 0.0);
  EXPECT_TRUE(again["joints"][3].contains("low_speed_friction"));
}

TEST(TwinFile, TheVersionMustBeAWholeNumberTheProgramReads) {
  json j = valid_twin();
  j["version"] = "1";
  EXPECT_THAT(error_of(j), HasSubstr("twin.json: field 'version': expected a whole number from 1 to 2, got \"1\""));
  j["version"] = 1.5;
  EXPECT_THAT(error_of(j), HasSubstr("field 'version': expected a whole number from 1 to 2, got 1.5"));
  j["version"] = 99;
  EXPECT_THAT(error_of(j), HasSubstr("field 'version': expected 1 to 2, got 99"));
  j["version"] = 0;
  EXPECT_THAT(error_of(j), HasSubstr("field 'version': expected 1 to 2, got 0"));
}

TEST(TwinFile, UnknownKeysAreNamedWithTheKeysTheObjectHas) {
  json j = valid_twin();
  j["bogus_key"] = 1;
  EXPECT_THAT(error_of(j), HasSubstr("twin.json: field 'bogus_key': unknown key, expected one of: format, version, robot, method"));
  j = valid_twin();
  j["joints"][2]["gian"] = 9.0;
  EXPECT_THAT(error_of(j), HasSubstr("field 'joints[2].gian': unknown key, expected one of: gain, c_gen, gain_identified"));
  j = valid_twin();
  j["joints"][2]["low_speed_friction"]["stribek"] = 0.1;
  EXPECT_THAT(error_of(j), HasSubstr("field 'joints[2].low_speed_friction.stribek': unknown key"));
  j = valid_twin();
  j["payload"]["inertia"] = json::array();
  EXPECT_THAT(error_of(j), HasSubstr("field 'payload.inertia': unknown key, expected one of: mass, com"));
}

TEST(TwinFile, TheMethodIsOneTheProgramWritesAndMatchesTheBlocks) {
  json j = valid_twin();
  j["method"] = "bogus";
  EXPECT_THAT(error_of(j), HasSubstr("twin.json: field 'method': expected one of \"physics\", \"mlp\", \"hybrid\", \"sequential\", got \"bogus\""));
  j["method"] = "hybrid";
  EXPECT_THAT(error_of(j), HasSubstr("field 'method': method \"hybrid\" expects a \"learned\" block with role \"residual\", got neither block"));
}

TEST(TwinFile, ARepeatedKeyIsNamedInsteadOfOneValueWinning) {
  std::string text = valid_twin().dump(1);
  text.insert(text.find("\"version\""), "\"version\": 1,\n ");
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { TwinModel::from_json(text, "twin.json"); }),
              HasSubstr("twin.json: field 'version': the key appears twice in its object, expected once"));
  text = valid_twin().dump(1);
  const std::string c_gen = "\"c_gen\":";
  size_t at = text.find(c_gen);
  at = text.find(c_gen, at + 1);
  at = text.find(c_gen, at + 1);  // joints[2]
  text.insert(at, "\"c_gen\": 0.5, ");
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { TwinModel::from_json(text, "twin.json"); }),
              HasSubstr("twin.json: field 'joints[2].c_gen': the key appears twice"));
}

TEST(TwinFile, ValuesOutOfTheirRangeAreNamedWithExpectedAndActual) {
  const auto with = [](const std::function<void(json&)>& edit) {
    json j = valid_twin();
    edit(j);
    return error_of(j);
  };
  EXPECT_THAT(with([](json& j) { j["joints"][2]["c_gen"] = 0.0; }),
              HasSubstr("twin.json: field 'joints[2].c_gen': expected a number in (0, 10] (the current factor when back-driven; 1: as when motoring), got 0"));
  EXPECT_THAT(with([](json& j) { j["joints"][2]["c_gen"] = -0.5; }), HasSubstr("field 'joints[2].c_gen': expected a number in (0, 10]"));
  EXPECT_THAT(with([](json& j) { j["joints"][2]["c_gen"] = 50.0; }), HasSubstr("got 50"));
  EXPECT_THAT(with([](json& j) { j["joints"][2]["gain"] = nullptr; }), HasSubstr("twin.json: field 'joints[2].gain': expected a number, got null"));
  EXPECT_THAT(with([](json& j) { j["joints"][2]["friction"][0] = -5.0; }),
              HasSubstr("field 'joints[2].friction[0]': expected coulomb friction >= 0 (friction opposes the motion), got -5"));
  EXPECT_THAT(with([](json& j) { j["joints"][2]["friction"][1] = -0.1; }), HasSubstr("field 'joints[2].friction[1]': expected viscous friction >= 0"));
  EXPECT_THAT(with([](json& j) { j["joints"][2]["friction"][3] = nullptr; }), HasSubstr("field 'joints[2].friction[3]': expected a number, got null"));
  EXPECT_THAT(with([](json& j) { j["joints"][2]["friction_columns"][0] = "bogus"; }),
              HasSubstr("field 'joints[2].friction_columns': expected [\"coulomb\", \"viscous\", \"offset\", \"armature\", \"viscous_temperature\"]"));
  EXPECT_THAT(with([](json& j) { j["joints"][2]["low_speed_friction"]["presliding_alpha"] = 0.0; }),
              HasSubstr("field 'joints[2].low_speed_friction.presliding_alpha': expected a number > 0 [1/rad] when presliding is nonzero (0.3), got 0"));
  EXPECT_THAT(with([](json& j) { j["joints"][2]["low_speed_friction"]["stribeck_velocity"] = 0.0; }),
              HasSubstr("field 'joints[2].low_speed_friction.stribeck_velocity': expected a number > 0 [rad/s] when stribeck is nonzero (0.1), got 0"));
  EXPECT_THAT(with([](json& j) { j["joints"][2]["low_speed_friction"]["stribeck_velocity"] = -0.04; }),
              HasSubstr("field 'joints[2].low_speed_friction.stribeck_velocity': expected a number >= 0, got -0.04"));
  EXPECT_THAT(with([](json& j) { j["payload"]["mass"] = -1.0; }), HasSubstr("twin.json: field 'payload.mass': expected a number >= 0, got -1"));
  EXPECT_THAT(with([](json& j) { j["payload"]["com"] = {0.0, 0.04}; }), HasSubstr("twin.json: field 'payload.com': expected 3 values, got 2"));
  EXPECT_THAT(with([](json& j) { j["direction_blend"] = -1.0; }), HasSubstr("twin.json: field 'direction_blend': expected a number >= 0, got -1"));
  EXPECT_THAT(with([](json& j) { j["velocity_lag"] = 1.0; }),
              HasSubstr("twin.json: field 'velocity_lag': expected a lag in seconds within +-0.1 s (the streamed velocity against its sample's "
                        "instant), got 1"));
  EXPECT_THAT(with([](json& j) { j["velocity_lag"] = "1 ms"; }), HasSubstr("twin.json: field 'velocity_lag': expected a number, got \"1 ms\""));
  const auto direction = [](json& j) {
    j["target_direction"] = {{"lead_s", {0.001, 0.001, 0.0, -0.003, 0.0, 0.0}},
                             {"width", {0.004, 0.0007, 0.009, 0.002, 0.014, 0.013}},
                             {"width_s", {0.0, 0.006, 0.003, 0.02, 0.0, 0.0}}};
  };
  EXPECT_THAT(with([&](json& j) {
                direction(j);
                j["target_direction"]["width"][1] = 0.0;
              }),
              HasSubstr("twin.json: field 'target_direction.width[1]': expected a tracking error in (0, 0.05] rad/s, got 0"));
  EXPECT_THAT(with([&](json& j) {
                direction(j);
                j["target_direction"]["lead_s"][3] = -0.3;
              }),
              HasSubstr("field 'target_direction.lead_s[3]': expected a lead in seconds within +-0.1 s (the joint's velocity against its "
                        "target), got -0.3"));
  EXPECT_THAT(with([&](json& j) {
                direction(j);
                j["target_direction"]["width_s"][0] = -0.001;
              }),
              HasSubstr("field 'target_direction.width_s[0]': expected a time in [0, 0.1] s (the tracking error per unit of acceleration), "
                        "got -0.001"));
  EXPECT_THAT(with([&](json& j) {
                direction(j);
                j["target_direction"]["width_s"] = {0.0, 0.0};
              }),
              HasSubstr("field 'target_direction.width_s': expected 6 values, got 2"));
  EXPECT_THAT(with([&](json& j) {
                direction(j);
                j["target_direction"]["lag"] = 0.0;
              }),
              HasSubstr("target_direction.lag"));
  EXPECT_THAT(with([](json& j) { j["temperature_ref"] = "hot"; }), HasSubstr("twin.json: field 'temperature_ref': expected a number, got \"hot\""));
  EXPECT_THAT(with([](json& j) { j["gains_absolute"] = "yes"; }), HasSubstr("twin.json: field 'gains_absolute': expected true or false, got \"yes\""));
  EXPECT_THAT(with([](json& j) {
                j["base_columns"] = {10, 12, 10};
                j["beta"] = {0.1, 0.2, 0.3};
              }),
              HasSubstr("twin.json: field 'base_columns[2]': expected each standard column once, got column 10 again (also at base_columns[0])"));
  EXPECT_THAT(with([](json& j) { j["monitor"] = 3; }), HasSubstr("twin.json: field 'monitor': expected an object, got 3"));
}

// The velocity lag (session 26) round-trips and may be absent (a twin from before reads the streamed
// velocity as it is: 0); a twin without one writes no key (older readers refuse unknown keys). The
// drive's direction is read on qd + lag qdd: a joint still moving forward at one count (3 mrad/s)
// but decelerating at 5 rad/s² is, 1 ms later, at -2 mrad/s, so the positive torque of its Coulomb
// friction is back-driven there: the current is c_gen tau / g with the lag, tau / g without.
TEST(TwinFile, TheVelocityLagRoundTripsMayBeAbsentAndTurnsTheDrivesDirection) {
  json j = valid_twin();
  j["direction_blend"] = 0.0;  // the hard switch: the factor is exactly 1 or c_gen
  j["velocity_lag"] = 0.001;
  for (auto& e : j["joints"]) {
    e["c_gen"] = 0.7;
    e["friction"][0] = 1.0;  // Coulomb: tau = +1 while qd > 0
  }
  TwinModel t = TwinModel::from_json(j.dump(), "twin.json");
  EXPECT_EQ(t.velocity_lag, 0.001);
  EXPECT_EQ(json::parse(t.to_json())["velocity_lag"], 0.001);
  EXPECT_DOUBLE_EQ(t.direction_velocity(0.003, -5.0), -0.002);
  j.erase("velocity_lag");
  TwinModel before = TwinModel::from_json(j.dump(), "twin.json");
  EXPECT_EQ(before.velocity_lag, 0.0);
  EXPECT_FALSE(json::parse(before.to_json()).contains("velocity_lag"));
  const int n = t.n_dof();
  VectorJ q = VectorJ::Zero(n), qd = VectorJ::Zero(n), qdd = VectorJ::Zero(n), temp = VectorJ::Constant(n, 35.0), tau, cur, tau0, cur0;
  qd.setConstant(0.003);
  qdd.setConstant(-5.0);
  t.predict(q, qd, qdd, temp, tau, cur);
  before.predict(q, qd, qdd, temp, tau0, cur0);
  for (int k = 0; k < n; ++k) {
    const JointDrive& d = t.joints[static_cast<size_t>(k)];
    ASSERT_DOUBLE_EQ(tau[k], tau0[k]) << "the torque does not depend on the lag, J" << k + 1;
    ASSERT_GT(tau[k], 0.5) << "the Coulomb friction of a joint moving forward, J" << k + 1;
    EXPECT_NEAR(cur[k] / cur0[k], 0.7, 1e-12) << "back-driven with the lag, motoring without, J" << k + 1;
    const double back = tau[k] > 0.0 ? d.c_gen : 1.0;  // with the lag: v < 0, so tau > 0 is back-driven
    EXPECT_NEAR(cur[k], back * tau[k] / d.gain, 1e-12) << "J" << k + 1;
    EXPECT_NEAR(cur0[k], (tau[k] > 0.0 ? 1.0 : d.c_gen) * tau[k] / d.gain, 1e-12) << "J" << k + 1;
  }
}

// The drive's direction read on the controller's target (session 31) round-trips and may be absent
// (a twin from before reads the measured velocity alone). A loaded joint crawling through a reversal
// while its encoder reads 0: the measured velocity leaves the twin halfway between motoring and
// back-driven; the target says which side of its crossing the joint is on. A measured count adds
// its own evidence, and a target the joint does not follow (stopped against something) is not read.
TEST(TwinFile, TheDrivesDirectionIsReadOnTheTargetWhereTheEncoderReadsNothing) {
  json j = valid_twin();
  j["direction_blend"] = 0.005;
  for (auto& e : j["joints"]) {
    e["c_gen"] = 0.7;
    e["friction"][2] = 1.0;  // an offset: a torque of about 1 N·m on every joint at rest
  }
  j["target_direction"] = {{"lead_s", {0.001, 0.001, 0.001, 0.001, 0.001, 0.001}},
                           {"width", {0.001, 0.001, 0.001, 0.001, 0.001, 0.001}},
                           {"width_s", {0.005, 0.005, 0.005, 0.005, 0.005, 0.005}}};
  const TwinModel t = TwinModel::from_json(j.dump(), "twin.json");
  ASSERT_FALSE(t.target_direction.empty());
  const json back = json::parse(t.to_json());
  EXPECT_EQ(back["target_direction"]["width_s"][2], 0.005);
  EXPECT_EQ(TwinModel::from_json(back.dump(), "twin.json").target_direction.lead[4], 0.001);
  j.erase("target_direction");
  const TwinModel before = TwinModel::from_json(j.dump(), "twin.json");
  EXPECT_TRUE(before.target_direction.empty());
  EXPECT_FALSE(json::parse(before.to_json()).contains("target_direction"));
  EXPECT_NEAR(t.target_direction.width_at(0, 0.2), std::hypot(0.001, 0.001), 1e-15);

  const int n = t.n_dof();
  RobotSample s = RobotSample::empty(n);
  s.present = kFieldActualQd | kFieldTargetQd | kFieldTargetQdd;
  s.q.setZero();
  s.qd.setZero();  // the encoder: no count this period
  s.target_qdd.setConstant(-0.1);
  const VectorJ qdd = s.target_qdd, temp = VectorJ::Constant(n, 35.0);
  VectorJ tau, cur, tau0, cur0;
  const auto currents = [&](double target_qd, double qd) {
    s.target_qd.setConstant(target_qd);
    s.qd.setConstant(qd);
    FrictionMemory m, m0;
    t.advance(m, s, qdd);
    before.advance(m0, s, qdd);
    t.predict(s.q, s.qd, qdd, temp, tau, cur, &m);
    before.predict(s.q, s.qd, qdd, temp, tau0, cur0, &m0);
    return m;
  };
  // 5 ms before the target crosses zero (0.5 mrad/s), and 5 ms after
  for (const double target : {0.0006, -0.0004}) {
    const FrictionMemory m = currents(target, 0.0);
    for (int k = 0; k < n; ++k) {
      const JointDrive& d = t.joints[static_cast<size_t>(k)];
      ASSERT_FALSE(std::isnan(m.direction[k]));
      ASSERT_GT(std::abs(tau[k]), 0.1) << "J" << k + 1;
      EXPECT_NEAR(cur0[k] / (tau[k] / d.gain), 0.85, 1e-9) << "the measured velocity alone: halfway, J" << k + 1;
      const double v = target - 0.0001;  // carried by the lead, 1 ms x -0.1 rad/s²
      const double x = v / std::hypot(0.001, 0.0005);
      const double back = 0.5 * (1.0 - std::tanh(tau[k] >= 0.0 ? x : -x));
      EXPECT_NEAR(cur[k] / (tau[k] / d.gain), 1.0 - 0.3 * back, 1e-9) << "J" << k + 1 << " at target " << target;
      EXPECT_EQ((cur[k] / (tau[k] / d.gain) < 0.85), (tau[k] * v < 0.0)) << "the side of the crossing, J" << k + 1;
    }
  }
  // a count back (-3 mrad/s) while the target still says forward: the count's evidence is added
  const FrictionMemory counted = currents(0.0006, -0.003);
  EXPECT_NEAR(counted.direction[1], 0.0005 / std::hypot(0.001, 0.0005) - 0.003 / 0.005, 1e-9);
  // a joint that does not follow its target (target 0.05 rad/s, joint at rest): the measured velocity
  const FrictionMemory stalled = currents(0.05, 0.0);
  EXPECT_TRUE(std::isnan(stalled.direction[1]));
  EXPECT_NEAR(cur[1], cur0[1], 1e-12);
  // a stream without target velocities: the measured velocity's blend, as the twin of before
  // predicts it; kept where it is in doubt (|x| <= kDoubtArgument, session 33), NaN elsewhere
  s.present = kFieldActualQd;
  s.qd << 0.0, 0.003, -0.006, 0.0075, 0.05, -1.0;
  FrictionMemory plain;
  t.advance(plain, s, qdd);
  ASSERT_EQ(plain.direction.size(), n);
  EXPECT_TRUE(plain.measured);
  for (int k = 0; k < n; ++k) {
    const double x = t.direction_velocity(s.qd[k], qdd[k]) / t.direction_blend;
    if (std::abs(x) <= TwinModel::kDoubtArgument) {
      EXPECT_EQ(plain.direction[k], x) << k;
      EXPECT_EQ(plain.crossing[k], 1.0) << k;
    } else {
      EXPECT_TRUE(std::isnan(plain.direction[k])) << k;
      EXPECT_EQ(plain.crossing[k], 0.0) << k;
    }
  }
  EXPECT_EQ(plain.crossing.head(2).sum(), 2.0);
  EXPECT_EQ(plain.crossing.tail(2).sum(), 0.0);
  t.predict(s.q, s.qd, qdd, temp, tau, cur, &plain);
  FrictionMemory none = plain;
  none.direction.resize(0);
  t.predict(s.q, s.qd, qdd, temp, tau0, cur0, &none);
  EXPECT_EQ(cur, cur0) << "the same prediction with or without the kept direction";
}

// the values the identifier itself writes load: a hard switch, no low-speed friction, c_gen up to
// the alternating fit's 6.8 (runs/s8), a payload of zero mass
TEST(TwinFile, ValuesTheIdentifierWritesLoad) {
  json j = valid_twin();
  j["direction_blend"] = 0.0;
  j["joints"][0]["c_gen"] = 6.79;
  j["joints"][1]["c_gen"] = 0.25;
  j["joints"][1]["friction"] = {0.0, 0.0, -47.0, -9.6e7, -1.5e8};  // offset, armature, temperature term: any sign
  j["payload"]["mass"] = 0.0;
  EXPECT_EQ(error_of(j), "no error");
}

TEST(TwinFile, SaveReportsAFailedWriteAndLeavesNoTemporaryFile) {
  TwinModel t = TwinModel::from_json(valid_twin().dump(), "twin.json");
  // (only where /dev/full is the device: where it is missing, saving would create a file there)
  if (std::filesystem::is_character_file("/dev/full")) {
    try {
      t.save("/dev/full");
      ADD_FAILURE() << "saving to /dev/full did not throw";
    } catch (const std::runtime_error& e) {
      EXPECT_THAT(e.what(), HasSubstr("/dev/full: cannot write the twin file: No space left on device"));
    }
  }
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "twinwatch_twin_model_test";
  std::filesystem::remove_all(dir);
  EXPECT_THAT(twinwatch::test::error_text<std::runtime_error>([&] { t.save((dir / "twin.json").string()); }),
              HasSubstr("twin.json: cannot open for writing: No such file or directory"));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "twin.json").string();
  std::ofstream(path) << "the old twin";
  t.save(path);
  EXPECT_EQ(TwinModel::load(path).robot_name(), "ur3e");
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), std::filesystem::directory_iterator{}), 1) << "no temporary file left";
  std::filesystem::remove_all(dir);
}

TEST(TwinFile, SaveRefusesATwinThatWouldNotLoadBack) {
  TwinModel t = TwinModel::from_json(valid_twin().dump(), "twin.json");
  t.joints[1].c_gen = 0.0;
  const std::string path = (std::filesystem::temp_directory_path() / "twinwatch_twin_model_test_refused.json").string();
  std::filesystem::remove(path);
  EXPECT_THAT(twinwatch::test::error_text<std::runtime_error>([&] { t.save(path); }),
              HasSubstr("twinwatch_twin_model_test_refused.json: not written, the twin would not load back: "));
  EXPECT_THAT(twinwatch::test::error_text<std::runtime_error>([&] { t.save(path); }), HasSubstr("field 'joints[1].c_gen'"));
  EXPECT_FALSE(std::filesystem::exists(path));
}


// the motion the twin was identified on: written when known, read back, checked; a file without it
// (written before session 17) still loads, with an empty envelope
TEST(TwinFile, TheMotionEnvelopeRoundTripsIsCheckedAndMayBeAbsent) {
  TwinModel t("ur3e", model::load_robot("ur3e"));
  t.joints.resize(6);
  t.base_columns = {10};
  t.beta = Eigen::VectorXd::Constant(1, 0.1);
  EXPECT_FALSE(json::parse(t.to_json()).contains("motion_envelope")) << "an unknown envelope is not written as one";
  VectorJ q(6), qd(6);
  q << 0.1, -1.0, 1.2, -1.5, -1.6, 0.0;
  qd << 0.5, -0.2, 0.0, 0.3, -0.9, 0.1;
  t.envelope.include(q, qd);
  t.envelope.include(-q, 0.5 * qd);
  json j = json::parse(t.to_json());
  ASSERT_TRUE(j.contains("motion_envelope"));
  const TwinModel back = TwinModel::from_json(j.dump(), "twin.json");
  ASSERT_FALSE(back.envelope.empty());
  EXPECT_DOUBLE_EQ(back.envelope.q_min[1], -1.0);
  EXPECT_DOUBLE_EQ(back.envelope.q_max[1], 1.0);
  EXPECT_DOUBLE_EQ(back.envelope.qd_max[4], 0.9);  // the largest |qd|, whichever its sign
  j["motion_envelope"]["q_min"][2] = 3.0;
  EXPECT_THAT(error_of(j), HasSubstr("twin.json: field 'motion_envelope.q_min[2]': expected at most q_max[2] = 1.2, got 3"));
  j = json::parse(t.to_json());
  j["motion_envelope"]["qd_max"][0] = -0.1;
  EXPECT_THAT(error_of(j), HasSubstr("field 'motion_envelope.qd_max[0]': expected a speed >= 0 [rad/s], got -0.1"));
  j = json::parse(t.to_json());
  j["motion_envelope"]["qd_max"].erase(5);
  EXPECT_THAT(error_of(j), HasSubstr("motion_envelope.qd_max"));
  j = json::parse(t.to_json());
  j["motion_envelope"]["q_mid"] = 0;
  EXPECT_THAT(error_of(j), HasSubstr("q_mid"));
  j = json::parse(t.to_json());
  j.erase("motion_envelope");
  EXPECT_TRUE(TwinModel::from_json(j.dump(), "twin.json").envelope.empty());
}

}  // namespace
}  // namespace twinwatch::ident
