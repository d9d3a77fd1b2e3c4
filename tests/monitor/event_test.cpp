#include "twinwatch/monitor/event.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "twinwatch/core/error.hpp"

namespace twinwatch::monitor {
namespace {

TEST(Event, JsonLineCarriesClassJointMagnitudeAndDuration) {
  Event e;
  e.t_start = 8.5;
  e.t_end = 9.25;
  e.open = false;
  e.fault = FaultClass::PayloadChange;
  e.magnitude = -0.48;
  e.units = "kg";
  e.detail = "payload -0.48 kg";
  const auto j = nlohmann::json::parse(e.to_json_line());
  EXPECT_EQ(j["class"], "payload_change");
  EXPECT_DOUBLE_EQ(j["duration_s"].get<double>(), 0.75);
  EXPECT_DOUBLE_EQ(j["magnitude"].get<double>(), -0.48);
  EXPECT_EQ(e.to_json_line().find('\n'), std::string::npos);
  EXPECT_TRUE(j["other_links"].is_array());
  EXPECT_TRUE(j["other_links"].empty());
  e.fault = FaultClass::Collision;
  e.link = 4;
  e.other_links = {5};
  const auto c = nlohmann::json::parse(e.to_json_line());
  EXPECT_EQ(c["link"], 4);
  EXPECT_EQ(c["other_links"], nlohmann::json::array({5}));
}

TEST(FaultClass, RoundTripsAndRejectsUnknownNames) {
  for (FaultClass c : {FaultClass::Collision, FaultClass::Resistance, FaultClass::PayloadChange, FaultClass::SensorFault,
                       FaultClass::StreamFault, FaultClass::Wear, FaultClass::Unknown})
    EXPECT_EQ(fault_class_from_string(to_string(c)), c);
  try {
    fault_class_from_string("earthquake");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("'earthquake' is unknown"));
  }
}

TEST(EventStore, PersistsEventsAcrossReopen) {
  const auto path = std::filesystem::temp_directory_path() / "twinwatch_event_store_test.db";
  std::filesystem::remove(path);
  {
    EventStore store(path.string());
    Event e;
    e.fault = FaultClass::Collision;
    store.insert(e, "rec.csv");
    store.insert(e, "rec.csv");
    EXPECT_EQ(store.count(), 2);
  }
  EventStore again(path.string());
  EXPECT_EQ(again.count(), 2);
  std::filesystem::remove(path);
}

TEST(EventStore, UnopenablePathNamesTheFile) {
  try {
    EventStore store("/nonexistent-dir/events.db");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("/nonexistent-dir/events.db"));
  }
}

}  // namespace
}  // namespace twinwatch::monitor
