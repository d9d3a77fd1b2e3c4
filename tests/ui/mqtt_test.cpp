// ui::MqttPublisher and its settings: the address and option checks, and what it does while no
// broker answers (tests/cli/mqtt.sh runs it against a real broker and subscriber).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "twinwatch/core/error.hpp"
#include "twinwatch/ui/mqtt.hpp"

using namespace twinwatch;
using ::testing::HasSubstr;

namespace {
std::string parse_error(const std::string& text) {
  ui::MqttSettings s;
  try {
    ui::parse_mqtt_address(text, s);
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}
std::string validate_error(const ui::MqttSettings& s) {
  try {
    s.validate();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}
// a loopback port nothing listens on: the kernel refuses the connection at once (port 1 is
// privileged and unused on the build machines)
constexpr int kClosedPort = 1;
}  // namespace

TEST(MqttSettings, AddressesWithAndWithoutPortIpv6InBrackets) {
  ui::MqttSettings s;
  ui::parse_mqtt_address("broker.plant.local", s);
  EXPECT_EQ(s.host, "broker.plant.local");
  EXPECT_EQ(s.effective_port(), 1883);
  EXPECT_EQ(s.address(), "broker.plant.local:1883");
  ui::parse_mqtt_address("10.0.0.5:1884", s);
  EXPECT_EQ(s.host, "10.0.0.5");
  EXPECT_EQ(s.port, 1884);
  ui::MqttSettings v6;
  ui::parse_mqtt_address("[::1]:8884", v6);
  EXPECT_EQ(v6.host, "::1");
  EXPECT_EQ(v6.port, 8884);
  EXPECT_EQ(v6.address(), "[::1]:8884");
  ui::MqttSettings tls;
  tls.host = "b";
  tls.cafile = "/etc/ssl/certs/ca-certificates.crt";
  EXPECT_EQ(tls.effective_port(), 8883);  // TLS's own port when none is given
}

TEST(MqttSettings, BadAddressesAreNamed) {
  EXPECT_THAT(parse_error(""), HasSubstr("the broker's host is empty"));
  EXPECT_THAT(parse_error(":1883"), HasSubstr("the broker's host is empty"));
  EXPECT_THAT(parse_error("host:"), HasSubstr("the port after ':' is empty"));
  EXPECT_THAT(parse_error("host:0"), HasSubstr("the port must be a whole number from 1 to 65535, got '0'"));
  EXPECT_THAT(parse_error("host:65536"), HasSubstr("got '65536'"));
  EXPECT_THAT(parse_error("host:18x3"), HasSubstr("got '18x3'"));
  EXPECT_THAT(parse_error("::1"), HasSubstr("an IPv6 address goes in brackets"));
  EXPECT_THAT(parse_error("[::1"), HasSubstr("needs its ']'"));
  EXPECT_THAT(parse_error("[::1]1883"), HasSubstr("expected ':PORT' after ']'"));
}

TEST(MqttSettings, EachCheckNamesItsField) {
  ui::MqttSettings s;
  s.host = "localhost";
  EXPECT_EQ(validate_error(s), "");
  auto with = [&](auto change) {
    ui::MqttSettings x = s;
    change(x);
    return validate_error(x);
  };
  EXPECT_THAT(with([](auto& x) { x.host.clear(); }), HasSubstr("the host is empty"));
  EXPECT_THAT(with([](auto& x) { x.topic = "plant/#"; }), HasSubstr("MQTT topic prefix 'plant/#': it holds a wildcard"));
  EXPECT_THAT(with([](auto& x) { x.topic = "plant/+/ur3e"; }), HasSubstr("wildcard"));
  EXPECT_THAT(with([](auto& x) { x.topic = "/plant"; }), HasSubstr("starts or ends with '/'"));
  EXPECT_THAT(with([](auto& x) { x.topic = "plant/"; }), HasSubstr("starts or ends with '/'"));
  EXPECT_THAT(with([](auto& x) { x.topic = "plant//ur3e"; }), HasSubstr("an empty level"));
  EXPECT_THAT(with([](auto& x) { x.topic = ""; }), HasSubstr("it is empty"));
  EXPECT_THAT(with([](auto& x) { x.topic = "plant/\xff"; }), HasSubstr("not valid UTF-8"));
  EXPECT_THAT(with([](auto& x) { x.topic = "$SYS/twinwatch"; }), HasSubstr("starts with '$'"));
  EXPECT_THAT(with([](auto& x) { x.topic = "plant/\tcell"; }), HasSubstr("a control character"));
  EXPECT_THAT(with([](auto& x) { x.client_id = "cell\xff"; }), HasSubstr("MQTT client id 'cell\xff': expected up to 65535 bytes of UTF-8"));
  EXPECT_THAT(with([](auto& x) { x.client_id = std::string(70000, 'a'); }), HasSubstr("expected up to 65535 bytes"));
  EXPECT_EQ(with([](auto& x) { x.client_id = "twinwatch-cell3-ur3e"; }), "");
  EXPECT_THAT(with([](auto& x) { x.qos = 3; }), HasSubstr("QoS is 3, must be 0, 1 or 2"));
  EXPECT_THAT(with([](auto& x) { x.keepalive_s = 2; }), HasSubstr("keep-alive is 2 s"));
  EXPECT_THAT(with([](auto& x) { x.outbox_limit = 0; }), HasSubstr("outbox limit is 0"));
  EXPECT_THAT(with([](auto& x) { x.password = "pw"; }), HasSubstr("password given without a user name"));
  EXPECT_THAT(with([](auto& x) { x.cafile = "/nonexistent/ca.pem"; }), HasSubstr("CA file '/nonexistent/ca.pem': cannot be read"));
  // the publisher refuses them too, before any thread or socket
  ui::MqttSettings bad = s;
  bad.qos = -1;
  EXPECT_THROW(ui::MqttPublisher{bad}, InvalidArgument);
}

TEST(MqttPublisher, WithoutABrokerPublishingDoesNotBlockAndEverythingWaits) {
  ui::MqttSettings s;
  s.host = "127.0.0.1";
  s.port = kClosedPort;
  ui::MqttPublisher pub(s);
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 100; ++i) pub.publish_event("collision", "{\"i\":" + std::to_string(i) + "}");
  pub.publish_status(R"({"state":"monitoring"})");
  pub.publish_status(R"({"state":"finished"})");  // supersedes the first: only the newest state waits
  const double queued_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(queued_s, 5.0) << "publishing must not wait for the broker";  // (generous: a loaded machine; it takes microseconds)
  EXPECT_EQ(pub.drain(std::chrono::milliseconds(300)), 101);  // 100 events + the newest state
  const ui::MqttCounters c = pub.counters();
  EXPECT_EQ(c.published, 102);
  EXPECT_EQ(c.waiting, 101);
  EXPECT_EQ(c.superseded, 1);
  EXPECT_EQ(c.delivered, 0);
  EXPECT_EQ(c.connects, 0);
  EXPECT_FALSE(c.connected);
  // the refusal is said once, not at every retry
  const auto notes = pub.take_notes();
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_THAT(notes[0], HasSubstr("cannot reach the broker at 127.0.0.1:1: Connection refused"));
  EXPECT_THAT(notes[0], HasSubstr("events are kept until it takes them"));
}

TEST(MqttPublisher, AFullOutboxDropsTheOldestEventsAndCountsThem) {
  ui::MqttSettings s;
  s.host = "127.0.0.1";
  s.port = kClosedPort;
  s.outbox_limit = 10;
  ui::MqttPublisher pub(s);
  pub.publish_status(R"({"state":"monitoring"})");
  for (int i = 0; i < 25; ++i) pub.publish_event("resistance", "{}");
  const ui::MqttCounters c = pub.counters();
  EXPECT_EQ(c.waiting, 10);   // the limit holds
  EXPECT_EQ(c.dropped, 16);   // 26 messages, 10 kept; the state is not among those dropped
  bool said = false;
  for (const auto& n : pub.take_notes()) said = said || n.find("oldest event line(s) dropped") != std::string::npos;
  EXPECT_TRUE(said);
}
