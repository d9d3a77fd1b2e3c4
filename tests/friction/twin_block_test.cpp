// The friction block of the twin file: a fitted ParFam-H equation survives the round trip
// through JSON and through the twin file, and re-loads into an evaluator that predicts the same.
#include "twinwatch/friction/twin_block.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "twinwatch/core/error.hpp"
#include "twinwatch/friction/study.hpp"
#include "twinwatch/ident/twin_model.hpp"
#include "twinwatch/model/description_io.hpp"

namespace twinwatch::friction {
namespace {

using ::testing::HasSubstr;

ParFamModel fitted_parfam_h() {
  const FrictionStudyData d = simulated_study_data(simulated_study_joints()[2], 1);
  ParFamOptions o = study_parfam_options();  // h in the displacement clock: stored with the block
  o.hops = 4;  // a quick fit: the test is about storage, not accuracy
  ParFamModel m(o);
  m.fit(d.train);
  return m;
}

std::string parse_error_of(const std::string& text) {
  try {
    friction_block_from_json(text, "twin.json");
  } catch (const ParseError& e) {
    return e.what();
  }
  return "";
}

TEST(FrictionBlock, RoundTripsThroughTheTwinFileIntoTheCompiledEvaluator) {
  ParFamModel m = fitted_parfam_h();
  ASSERT_TRUE(m.fitted());
  ident::TwinModel twin("ur3e", model::load_robot("ur3e"));
  twin.joints.resize(6);
  twin.friction_json = friction_block_to_json({friction_equation_of(m, 3)});
  const ident::TwinModel back = ident::TwinModel::from_json(twin.to_json(), "twin.json");
  const std::vector<JointFrictionEquation> eqs = friction_block_from_json(back.friction_json, "twin.json");
  ASSERT_EQ(eqs.size(), 1u);
  EXPECT_EQ(eqs[0].joint, 3);
  EXPECT_EQ(eqs[0].expression.theta, m.expression().theta);
  EXPECT_EQ(eqs[0].hysteresis.alpha, m.hysteresis().alpha);
  ASSERT_EQ(m.hysteresis().drive, HysteresisDrive::Displacement);
  EXPECT_EQ(eqs[0].hysteresis.drive, HysteresisDrive::Displacement);
  EXPECT_EQ(eqs[0].expression.input_min, m.expression().input_min);
  EXPECT_EQ(eqs[0].expression.input_max, m.expression().input_max);
  ASSERT_EQ(eqs[0].expression.input_min.size(), 3u);
  ParFamModel restored = eqs[0].model();
  EXPECT_EQ(restored.equation(), m.equation());
  // the same predictions on an untrained record, bit for bit (same compiled terms, same h recursion)
  const FrictionStudyData d = simulated_study_data(simulated_study_joints()[2], 2);
  EXPECT_EQ(restored.predict(d.fourier), m.predict(d.fourier));
}

TEST(FrictionBlock, MalformedBlocksNameTheField) {
  EXPECT_THAT(parse_error_of("{}"), HasSubstr("expected an array"));
  EXPECT_THAT(parse_error_of(R"([{"dim": 3}])"), HasSubstr("friction_models[0].joint"));
  EXPECT_THAT(parse_error_of(R"([{"joint": 1, "dim": 2, "functions": ["tanh"], "theta": []}])"),
              HasSubstr("expected 1 or 3, got 2"));
  EXPECT_THAT(parse_error_of(R"([{"joint": 1, "dim": 1, "functions": ["log"], "theta": []}])"),
              HasSubstr("unknown function 'log'"));
  EXPECT_THAT(parse_error_of(R"([{"joint": 1, "dim": 1, "functions": ["tanh"], "theta": [1, 2]}])"),
              HasSubstr("expected 7 values (dim 1, 1 functions), got 2"));
  EXPECT_THAT(parse_error_of(R"([{"joint": 1, "dim": 3, "functions": ["tanh"], "theta": [0,0,0,0,0,0,0,0,0,0,0,0,0]}])"),
              HasSubstr("friction_models[0].alpha"));
  EXPECT_THAT(parse_error_of(R"([{"joint": 1, "dim": 1, "functions": ["tanh"], "theta": [0,0,0,0,0,0,0],
                                 "input_min": [1], "input_max": [0]}])"),
              HasSubstr("input guard 0 is [1, 0]"));
  EXPECT_THAT(parse_error_of(R"([{"joint": 1, "dim": 3, "functions": ["tanh"], "theta": [0,0,0,0,0,0,0,0,0,0,0,0,0],
                                 "alpha": 300, "beta": 50, "memory": "distance"}])"),
              HasSubstr("friction_models[0].memory': expected 'time' or 'displacement', got 'distance'"));
}

// found by fuzzing (fuzz/regressions/friction_block): json's out_of_range escaped, and get<int>()
// of 1e20 was undefined
TEST(FrictionBlock, OverflowingNumbersAreParseErrors) {
  EXPECT_THAT(parse_error_of(R"([{"joint": 1, "dim": 1, "functions": ["tanh"], "theta": [1e400]}])"),
              HasSubstr("field 'friction_models': expected numbers within the range of a double"));
  EXPECT_THAT(parse_error_of(R"([{"joint": 1e20, "dim": 1}])"), HasSubstr("field 'friction_models[0].joint': expected a whole number, got 1e+20"));
  EXPECT_THAT(parse_error_of(R"([{"joint": 1, "dim": 2.5}])"), HasSubstr("field 'friction_models[0].dim': expected a whole number, got 2.5"));
}

}  // namespace
}  // namespace twinwatch::friction
