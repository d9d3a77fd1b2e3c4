// Scenario labels (evaluation only): labels_json and parse_labels agree, and a bad labels file is
// named by file, field, expected and actual value (it gave raw library messages, and an empty file,
// an unknown fault type, an end before the onset or a negative onset went through).
#include "twinwatch/sim/scenario.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "twinwatch/core/error.hpp"
#include "error_text.hpp"

namespace twinwatch::sim {
namespace {

using ::testing::HasSubstr;
using nlohmann::json;

const char* kScenario = R"(name: labelled
robot: ur3e
seed: 202
duration: 20
trajectory: {type: figure_eight, period: 8}
faults:
  - {type: collision, onset: 11.3, link: 2, magnitude: 10, point: [0, 0, 0.1], direction: [1, 0, 0]}
  - {type: resistance, onset: 2, ramp: 1, end: 6, joint: 5, magnitude: 1.5}
  - {type: friction_growth, onset: 12, ramp: 4, joint: 2, magnitude: 0.3}
)";

json labels() { return json::parse(labels_json(parse_scenario(kScenario, "labelled.yaml"))); }

std::string error_of(const std::string& text) {
  return twinwatch::test::error_text<ParseError>([&] { parse_labels(text, "r.labels.json"); });
}
std::string error_of(const std::function<void(json&)>& edit) {
  json j = labels();
  edit(j);
  return error_of(j.dump());
}

TEST(Labels, WhatLabelsJsonWritesParsesBack) {
  const Labels l = parse_labels(labels().dump(), "r.labels.json");
  EXPECT_EQ(l.scenario, "labelled");
  EXPECT_EQ(l.seed, 202u);
  EXPECT_EQ(l.duration, 20.0);
  ASSERT_EQ(l.faults.size(), 3u);
  EXPECT_EQ(l.faults[0].type, FaultType::Collision);
  EXPECT_EQ(l.faults[0].link, 1);
  EXPECT_EQ(l.faults[0].joint, -1);
  EXPECT_EQ(l.faults[2].type, FaultType::FrictionGrowth);
  EXPECT_FALSE(std::isfinite(l.faults[2].end)) << "null: to the end of the run";
  EXPECT_EQ(l.faults[2].units, "relative");
  EXPECT_EQ(l.faults[1].type, FaultType::Resistance);
  EXPECT_EQ(l.faults[1].joint, 4);
  EXPECT_EQ(l.faults[1].end, 6.0);
  EXPECT_EQ(l.faults[1].units, "N·m");
}

TEST(Labels, AMalformedFileIsNamedWithTheFieldAndTheValue) {
  EXPECT_THAT(error_of(""), HasSubstr("r.labels.json: the file is empty, expected the labels JSON"));
  EXPECT_THAT(error_of("[]"), HasSubstr("r.labels.json: expected a JSON object (the labels twinwatch simulate writes), got []"));
  EXPECT_THAT(error_of(R"({"faults": [)"), HasSubstr("r.labels.json: not valid JSON"));
  EXPECT_THAT(error_of([](json& j) { j.erase("faults"); }), HasSubstr("r.labels.json: field 'faults': missing required field"));
  EXPECT_THAT(error_of([](json& j) { j["faults"] = "x"; }), HasSubstr("r.labels.json: field 'faults': expected an array of faults, got \"x\""));
  EXPECT_THAT(error_of([](json& j) { j["faults"][0].erase("onset"); }), HasSubstr("r.labels.json: field 'faults[0].onset': missing required field"));
  EXPECT_THAT(error_of([](json& j) { j["faults"][0]["onset"] = "x"; }), HasSubstr("field 'faults[0].onset': expected a number, got \"x\""));
  EXPECT_THAT(error_of([](json& j) { j["faults"][0]["onset"] = -5; }), HasSubstr("field 'faults[0].onset': expected a number >= 0, got -5"));
  EXPECT_THAT(error_of([](json& j) { j["faults"][1]["end"] = 1.0; }),
              HasSubstr("field 'faults[1].end': expected null or a time after onset (2 s), got 1"));
  EXPECT_THAT(error_of([](json& j) { j["faults"][0]["type"] = "meteor"; }),
              HasSubstr("field 'faults[0].type': expected one of resistance, friction_growth, payload_pick, payload_loss, collision, "
                        "current_offset, stuck_current, dropped_samples, timestamp_jitter, missed_pick; got \"meteor\""));
  EXPECT_THAT(error_of([](json& j) { j["faults"][0].erase("type"); }), HasSubstr("field 'faults[0].type': missing required field"));
  EXPECT_THAT(error_of([](json& j) { j["faults"][1]["joint"] = 0; }), HasSubstr("field 'faults[1].joint': expected null or a whole number from 1 to"));
  EXPECT_THAT(error_of([](json& j) { j["faults"][1]["units"] = "A"; }),
              HasSubstr("field 'faults[1].units': expected \"N·m\" (the units of resistance), got \"A\""));
  EXPECT_THAT(error_of([](json& j) { j["bogus"] = 1; }),
              HasSubstr("r.labels.json: field 'bogus': unknown key, expected one of: scenario, seed, duration, rate, faults"));
  EXPECT_THAT(error_of([](json& j) { j["rate"] = -5; }), HasSubstr("field 'rate': expected a number > 0, got -5"));
  std::string twice = labels().dump();
  twice.insert(1, R"("rate": 250, )");
  EXPECT_THAT(error_of(twice), HasSubstr("r.labels.json: field 'rate': the key appears twice in its object"));
}

}  // namespace
}  // namespace twinwatch::sim
