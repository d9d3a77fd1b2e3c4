// ui::MqttPublisher and its settings: the address and option checks, what it does while no broker
// answers, and its fallback to MQTT 3.1.1 with a broker of the test's own (tests/cli/mqtt.cmake runs it
// against a real broker and subscriber).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

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

namespace {
// A broker that speaks MQTT 3.1.1 only, as older brokers do (mosquitto 1.5, many PLC gateways): it
// answers a CONNECT of another protocol level with CONNACK return code 1, "unacceptable protocol
// level", and closes (MQTT 3.1.1 §3.1.2.2); a 3.1.1 CONNECT it accepts, then acknowledges each QoS 1
// PUBLISH (PUBACK) and answers PINGREQ. It records the levels it was asked for and what was published.
// (Debian's mosquitto 2 speaks 5 and cannot be told not to: the fallback needs a broker of its own.)
class Mqtt311Broker {
 public:
  struct Published {
    std::string topic, payload;
    int qos = 0;
    bool retain = false;
  };
  Mqtt311Broker() {
    listener_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = 0;  // (any free port)
    if (listener_ < 0 || ::bind(listener_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(listener_, 4) != 0)
      throw std::runtime_error("the test broker cannot listen");
    socklen_t len = sizeof a;
    ::getsockname(listener_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
    thread_ = std::thread([this] { serve(); });
  }
  ~Mqtt311Broker() {
    stop_ = true;
    thread_.join();  // (its polls time out within 0.1 s and see the stop)
    ::close(listener_);
  }
  int port() const { return port_; }
  std::vector<int> levels() const {
    std::lock_guard lk(mu_);
    return levels_;
  }
  std::vector<Published> published() const {
    std::lock_guard lk(mu_);
    return published_;
  }

 private:
  // one whole packet: its first byte and its body (false: the connection ended)
  bool read_packet(int fd, std::uint8_t& type, std::string& body) {
    auto read_n = [this, fd](void* to, std::size_t n) {
      auto* p = static_cast<char*>(to);
      while (n > 0) {
        if (stop_) return false;  // (a client that neither sends nor closes does not hold the test)
        pollfd pf{fd, POLLIN, 0};
        if (::poll(&pf, 1, 100) <= 0) continue;
        const ssize_t got = ::recv(fd, p, n, 0);
        if (got <= 0) return false;
        p += got;
        n -= static_cast<std::size_t>(got);
      }
      return true;
    };
    if (!read_n(&type, 1)) return false;
    std::size_t length = 0;
    for (int shift = 0; shift < 28; shift += 7) {  // the remaining length: a variable byte integer
      std::uint8_t b = 0;
      if (!read_n(&b, 1)) return false;
      length |= static_cast<std::size_t>(b & 0x7f) << shift;
      if (!(b & 0x80)) break;
    }
    body.assign(length, '\0');
    return length == 0 || read_n(body.data(), length);
  }
  static void send_bytes(int fd, std::initializer_list<std::uint8_t> bytes) {
    const std::vector<std::uint8_t> b(bytes);
    (void)::send(fd, b.data(), b.size(), MSG_NOSIGNAL);
  }
  void serve() {
    while (!stop_) {
      pollfd pf{listener_, POLLIN, 0};
      if (::poll(&pf, 1, 100) <= 0) continue;
      const int fd = ::accept(listener_, nullptr, nullptr);
      if (fd < 0) continue;
      session(fd);
      ::close(fd);
    }
  }
  void session(int fd) {
    std::uint8_t type = 0;
    std::string body;
    if (!read_packet(fd, type, body) || (type >> 4) != 1 || body.size() < 7) return;  // CONNECT
    const int level = static_cast<std::uint8_t>(body[6]);                              // after "\0\4MQTT"
    {
      std::lock_guard lk(mu_);
      levels_.push_back(level);
    }
    if (level != 4) {
      send_bytes(fd, {0x20, 0x02, 0x00, 0x01});  // CONNACK: unacceptable protocol level; then close
      return;
    }
    send_bytes(fd, {0x20, 0x02, 0x00, 0x00});
    while (!stop_ && read_packet(fd, type, body)) {
      const int kind = type >> 4;
      if (kind == 3) {  // PUBLISH
        Published m;
        m.qos = (type >> 1) & 3;
        m.retain = type & 1;
        const std::size_t tlen = (static_cast<std::uint8_t>(body[0]) << 8) | static_cast<std::uint8_t>(body[1]);
        m.topic = body.substr(2, tlen);
        const std::size_t at = 2 + tlen + (m.qos > 0 ? 2 : 0);
        m.payload = body.substr(at);  // (3.1.1: no properties before it)
        {  // (stored before it is acknowledged: the test reads it once the publisher has its PUBACK)
          std::lock_guard lk(mu_);
          published_.push_back(m);
        }
        if (m.qos > 0)
          send_bytes(fd, {0x40, 0x02, static_cast<std::uint8_t>(body[2 + tlen]), static_cast<std::uint8_t>(body[3 + tlen])});  // PUBACK
      } else if (kind == 12) {
        send_bytes(fd, {0xd0, 0x00});  // PINGRESP
      } else if (kind == 14) {
        return;  // DISCONNECT
      }
    }
  }
  int listener_ = -1, port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  mutable std::mutex mu_;
  std::vector<int> levels_;
  std::vector<Published> published_;
};
}  // namespace

// A broker that speaks MQTT 3.1.1 only: the publisher's MQTT 5 CONNECT is refused as an unacceptable
// protocol level, it says so once and connects again with 3.1.1, and the events and the run's state
// (retained, QoS 1) are delivered; under 3.1.1 the acknowledgement is a PUBACK without a reason code
TEST(MqttPublisher, FallsBackToMqtt311WithABrokerThatSpeaksNothingElse) {
  Mqtt311Broker broker;
  ui::MqttSettings s;
  s.host = "127.0.0.1";
  s.port = broker.port();
  s.topic = "cell3/ur3e";
  ui::MqttPublisher pub(s);
  pub.publish_status(R"({"state":"monitoring"})");
  pub.publish_event("collision", R"({"class":"collision","joint":3})");
  EXPECT_EQ(pub.drain(std::chrono::milliseconds(8000)), 0) << "everything delivered after the fallback";
  const ui::MqttCounters c = pub.counters();
  EXPECT_EQ(c.delivered, 2);
  EXPECT_EQ(c.refused, 0);
  EXPECT_EQ(c.connects, 1);
  EXPECT_THAT(broker.levels(), ::testing::ElementsAre(5, 4));  // MQTT 5 asked first, then 3.1.1
  std::string notes;
  for (const auto& n : pub.take_notes()) notes += n + "\n";
  EXPECT_THAT(notes, HasSubstr("speaks MQTT 3.1.1, not 5: publishing with 3.1.1"));
  EXPECT_THAT(notes, ::testing::Not(HasSubstr("refused the connection"))) << "the fallback is no refusal";
  const auto got = broker.published();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].topic, "cell3/ur3e/status");
  EXPECT_EQ(got[0].payload, R"({"state":"monitoring"})");
  EXPECT_TRUE(got[0].retain);
  EXPECT_EQ(got[0].qos, 1);
  EXPECT_EQ(got[1].topic, "cell3/ur3e/events/collision");
  EXPECT_EQ(got[1].payload, R"({"class":"collision","joint":3})");
}
