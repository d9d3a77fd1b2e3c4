// RTDE client ↔ virtual controller over loopback TCP, end to end: data arrives intact, gaps are
// counted from the controller timestamp, v1 fallback, NOT_FOUND by name, reconnect after the
// server restarts, a slow consumer never blocks the socket, and corrupt streams from a rogue
// server are survived without losing what was already received.
#include <arpa/inet.h>
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "twinwatch/core/log.hpp"
#include "twinwatch/device/rtde_client.hpp"
#include "twinwatch/device/rtde_server.hpp"

namespace rtde = twinwatch::device::rtde;
using twinwatch::RobotSample;
using namespace std::chrono_literals;

namespace {

// A frame whose values encode the cycle k, so the client's samples can be checked exactly.
struct FrameMaker {
  std::vector<double> f = std::vector<double>(static_cast<std::size_t>(rtde::frame_scalars()), 0.0);
  int ts = rtde::find_output_field("timestamp")->slot;
  int q = rtde::find_output_field("actual_q")->slot;
  int cur = rtde::find_output_field("actual_current")->slot;
  int mode = rtde::find_output_field("robot_mode")->slot;
  int dout = rtde::find_output_field("actual_digital_output_bits")->slot;
  const double* make(long k, double t) {
    f[static_cast<std::size_t>(ts)] = t;
    for (int j = 0; j < 6; ++j) {
      f[static_cast<std::size_t>(q + j)] = 0.001 * static_cast<double>(k) + j;
      f[static_cast<std::size_t>(cur + j)] = -0.5 * j + 1e-6 * static_cast<double>(k);
    }
    f[static_cast<std::size_t>(mode)] = 7;
    f[static_cast<std::size_t>(dout)] = static_cast<double>(k % 4);
    return f.data();
  }
};

rtde::ClientOptions options_for(std::uint16_t port) {
  rtde::ClientOptions o;
  o.port = port;
  o.backoff_initial_s = 0.02;
  o.backoff_max_s = 0.2;
  o.stall_timeout_ms = 300;
  return o;
}

std::vector<RobotSample> drain(rtde::Client& c, std::size_t want, std::chrono::milliseconds timeout = 5000ms) {
  std::vector<RobotSample> out;
  const auto until = std::chrono::steady_clock::now() + timeout;
  RobotSample s;
  while (out.size() < want && std::chrono::steady_clock::now() < until)
    if (c.pop(s, 20ms)) out.push_back(s);
  return out;
}

// Publishes cycles k0..k1-1 with timestamps t0 + k*0.002, skipping those in `skip`, paced so
// that the loopback socket never fills (0.1 ms per cycle).
void publish(rtde::Server& server, long k0, long k1, double t0, const std::vector<long>& skip = {}) {
  FrameMaker fm;
  for (long k = k0; k < k1; ++k) {
    if (std::find(skip.begin(), skip.end(), k) != skip.end()) continue;
    server.publish(fm.make(k, t0 + 0.002 * static_cast<double>(k)));
    std::this_thread::sleep_for(100us);
  }
}

void wait_for_clients(rtde::Server& server, int n) {
  const auto until = std::chrono::steady_clock::now() + 5s;
  while (server.stats().streaming < n && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(2ms);
}

class RtdeLoopback : public ::testing::Test {
 protected:
  void SetUp() override {
    twinwatch::log::set_sink(nullptr);
    rtde::ServerOptions so;
    so.port = 0;
    server = std::make_unique<rtde::Server>(so);
    server->start();
  }
  std::unique_ptr<rtde::Server> server;
};

}  // namespace

TEST_F(RtdeLoopback, SamplesArriveIntactAndInOrder) {
  rtde::Client client(options_for(server->port()));
  client.start();
  wait_for_clients(*server, 1);
  EXPECT_EQ(client.stats().protocol, 2);
  EXPECT_EQ(client.stats().controller.major, 5u);
  publish(*server, 0, 400, 100.0);
  const auto got = drain(client, 400);
  ASSERT_EQ(got.size(), 400u);
  for (std::size_t i = 0; i < got.size(); ++i) {
    const RobotSample& s = got[i];
    const double k = static_cast<double>(i);
    EXPECT_DOUBLE_EQ(s.timestamp, 100.0 + 0.002 * k);
    for (int j = 0; j < 6; ++j) {
      EXPECT_EQ(s.q[j], 0.001 * k + j);
      EXPECT_EQ(s.current[j], -0.5 * j + 1e-6 * k);
    }
    EXPECT_EQ(s.robot_mode, 7);
    EXPECT_EQ(s.digital_outputs, i % 4);
    EXPECT_FALSE(s.gap_before);
    EXPECT_TRUE(s.has(twinwatch::kFieldActualCurrent));
    EXPECT_TRUE(s.has(twinwatch::kFieldStreamGap));
  }
  const auto st = client.stats();
  EXPECT_EQ(st.lost, 0);
  EXPECT_EQ(st.gaps, 0);
  EXPECT_EQ(st.received, 400);
  EXPECT_LT(st.max_step_error_s, 1e-9);
}

TEST_F(RtdeLoopback, GapsAreDetectedFromTheControllerTimestamp) {
  rtde::Client client(options_for(server->port()));
  client.start();
  wait_for_clients(*server, 1);
  publish(*server, 0, 300, 50.0, {100, 101, 102, 103, 104, 200});
  const auto got = drain(client, 294);
  ASSERT_EQ(got.size(), 294u);
  int marked = 0;
  for (std::size_t i = 0; i < got.size(); ++i) {
    if (!got[i].gap_before) continue;
    ++marked;
    const double step = got[i].timestamp - got[i - 1].timestamp;
    EXPECT_TRUE(std::abs(step - 0.012) < 1e-9 || std::abs(step - 0.004) < 1e-9) << step;  // nothing interpolated
  }
  EXPECT_EQ(marked, 2);
  const auto st = client.stats();
  EXPECT_EQ(st.lost, 6);
  EXPECT_EQ(st.gaps, 2);
}

// review of session 18: a resent package (the same controller cycle twice) was delivered shifted
// by a period and marked as a gap, so the monitor processed it as a new sample and reported a
// stream fault of "0 samples missing"
TEST_F(RtdeLoopback, AResentCycleIsCountedAndNotDelivered) {
  rtde::Client client(options_for(server->port()));
  client.start();
  wait_for_clients(*server, 1);
  FrameMaker fm;
  for (long k = 0; k < 200; ++k) {
    server->publish(fm.make(k, 20.0 + 0.002 * static_cast<double>(k)));
    if (k == 50 || k == 120) server->publish(fm.make(k, 20.0 + 0.002 * static_cast<double>(k)));  // resent
    std::this_thread::sleep_for(100us);
  }
  const auto got = drain(client, 200);
  ASSERT_EQ(got.size(), 200u);
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_DOUBLE_EQ(got[i].timestamp, 20.0 + 0.002 * static_cast<double>(i));
    EXPECT_FALSE(got[i].gap_before) << i;
  }
  RobotSample extra;
  EXPECT_FALSE(client.pop(extra, 100ms));
  const auto st = client.stats();
  EXPECT_EQ(st.received, 202);
  EXPECT_EQ(st.repeated, 2);
  EXPECT_EQ(st.gaps, 0);
}

TEST_F(RtdeLoopback, NotFoundNamesAreReportedByName) {
  auto o = options_for(server->port());
  o.outputs = {"timestamp", "actual_q", "acutal_qd", "joint_temperatures", "bogus_output"};
  rtde::Client client(o);
  try {
    client.start();
    FAIL() << "start() should have thrown";
  } catch (const rtde::RecipeError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("acutal_qd"), std::string::npos) << m;
    EXPECT_NE(m.find("bogus_output"), std::string::npos) << m;
    EXPECT_NE(m.find("NOT_FOUND"), std::string::npos) << m;
    EXPECT_EQ(m.find("joint_temperatures"), std::string::npos) << m;
  }
}

TEST(RtdeClient, FallsBackToProtocolV1) {
  twinwatch::log::set_sink(nullptr);
  rtde::ServerOptions so;
  so.port = 0;
  so.max_protocol = 1;  // an old controller
  rtde::Server server(so);
  server.start();
  rtde::Client client(options_for(server.port()));
  client.start();
  wait_for_clients(server, 1);
  EXPECT_EQ(client.stats().protocol, 1);
  EXPECT_EQ(client.stats().frequency, 500.0);  // v1 streams at the controller's full rate
  publish(server, 0, 50, 1.0);
  const auto got = drain(client, 50);
  ASSERT_EQ(got.size(), 50u);
  EXPECT_DOUBLE_EQ(got[49].timestamp, 1.0 + 0.002 * 49);
  EXPECT_EQ(got[49].q[5], 0.001 * 49 + 5);
}

// session 23: the payload the program declares (payload, payload_cog) is in the default recipe and
// asked for from controller 5.5.1 on; an older controller has no such outputs (its NOT_FOUND would
// refuse the whole recipe), so they are left out there and the samples carry no declaration
TEST(RtdeClient, TheDeclaredPayloadIsAskedForFrom551On) {
  twinwatch::log::set_sink(nullptr);
  for (const rtde::ControllerVersion v : {rtde::ControllerVersion{5, 23, 0, 0}, rtde::ControllerVersion{5, 5, 1, 0},
                                          rtde::ControllerVersion{5, 5, 0, 0}, rtde::ControllerVersion{5, 4, 3, 0}}) {
    SCOPED_TRACE(::testing::Message() << "controller " << v.major << "." << v.minor << "." << v.bugfix);
    const bool has = v.minor > 5 || (v.minor == 5 && v.bugfix >= 1);
    rtde::ServerOptions so;
    so.port = 0;
    so.version = v;
    rtde::Server server(so);
    server.start();
    rtde::Client client(options_for(server.port()));
    client.start();
    wait_for_clients(server, 1);
    const auto names = client.recipe().names;
    EXPECT_EQ(std::count(names.begin(), names.end(), "payload"), has ? 1 : 0);
    EXPECT_EQ(std::count(names.begin(), names.end(), "payload_cog"), has ? 1 : 0);
    EXPECT_EQ((client.sample_fields() & twinwatch::kFieldPayload) != 0, has);
    FrameMaker fm;
    const int mass = rtde::find_output_field("payload")->slot, cog = rtde::find_output_field("payload_cog")->slot;
    for (long k = 0; k < 20; ++k) {
      fm.f[static_cast<std::size_t>(mass)] = k < 10 ? 0.0 : 1.5;
      fm.f[static_cast<std::size_t>(cog + 2)] = k < 10 ? 0.0 : 0.045;
      server.publish(fm.make(k, 1.0 + 0.002 * static_cast<double>(k)));
      std::this_thread::sleep_for(100us);
    }
    const auto got = drain(client, 20);
    ASSERT_EQ(got.size(), 20u);
    EXPECT_EQ(got[19].has(twinwatch::kFieldPayload), has);
    if (has) {
      EXPECT_EQ(got[9].payload, 0.0);
      EXPECT_EQ(got[19].payload, 1.5);
      EXPECT_EQ(got[19].payload_cog[2], 0.045);
    } else {
      EXPECT_TRUE(std::isnan(got[19].payload));
    }
    client.stop();
    server.stop();
  }
}

TEST(RtdeClient, ReconnectsAfterTheControllerRestartsWithAGapMarker) {
  twinwatch::log::set_sink(nullptr);
  rtde::ServerOptions so;
  so.port = 0;
  auto server = std::make_unique<rtde::Server>(so);
  server->start();
  const std::uint16_t port = server->port();
  rtde::Client client(options_for(port));
  client.start();
  wait_for_clients(*server, 1);
  publish(*server, 0, 100, 500.0);
  auto before = drain(client, 100);
  ASSERT_EQ(before.size(), 100u);

  server->stop();  // the controller goes away (e-stop, restart)...
  std::this_thread::sleep_for(150ms);
  so.port = port;
  server = std::make_unique<rtde::Server>(so);  // ...and comes back, its clock restarted
  server->start();
  wait_for_clients(*server, 1);
  ASSERT_EQ(server->stats().streaming, 1) << "client did not reconnect: " << client.stats().last_error;
  publish(*server, 0, 100, 40.0);
  auto after = drain(client, 100);
  ASSERT_EQ(after.size(), 100u);
  EXPECT_TRUE(after[0].gap_before);
  for (std::size_t i = 1; i < after.size(); ++i) EXPECT_FALSE(after[i].gap_before);
  EXPECT_GT(after[0].timestamp, before.back().timestamp);  // still monotonic across the restart
  EXPECT_NEAR(after[1].timestamp - after[0].timestamp, 0.002, 1e-9);
  const auto st = client.stats();
  EXPECT_EQ(st.reconnects, 1);
  EXPECT_EQ(st.gaps, 1);
  EXPECT_GT(st.lost, 0);  // estimated from the outage
}

TEST_F(RtdeLoopback, SlowConsumerNeverBlocksTheSocket) {
  auto o = options_for(server->port());
  o.queue_capacity = 32;
  rtde::Client client(o);
  client.start();
  wait_for_clients(*server, 1);
  publish(*server, 0, 1000, 0.0);  // the consumer does not pop at all meanwhile
  const auto until = std::chrono::steady_clock::now() + 3s;
  while (client.stats().received < 1000 && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(5ms);
  const auto st = client.stats();
  EXPECT_EQ(st.received, 1000);                       // the reader kept draining the socket...
  EXPECT_EQ(server->stats().packages_skipped, 0);     // ...so the controller never had to skip
  EXPECT_EQ(st.delivered, 32);
  EXPECT_EQ(st.dropped, 1000 - 32);
  // the consumer sees the 32 oldest samples, then the next one that fits carries the gap marker
  auto got = drain(client, 32, 1000ms);
  ASSERT_EQ(got.size(), 32u);
  for (const auto& s : got) EXPECT_FALSE(s.gap_before);
  publish(*server, 1000, 1001, 0.0);
  got = drain(client, 1, 2000ms);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_TRUE(got[0].gap_before);
  // and how many of the gap's samples this computer dropped (the controller sent them): the monitor
  // says so instead of blaming the controller's timestamps
  EXPECT_EQ(got[0].dropped_before, 1000u - 32u);
  for (const auto& s : got) EXPECT_LE(s.dropped_before, 1000u);
}

TEST_F(RtdeLoopback, SeveralClientsAtOnceWithTheirOwnRates) {
  auto o1 = options_for(server->port());
  auto o2 = options_for(server->port());
  o2.frequency = 125.0;
  o2.outputs = {"timestamp", "actual_q", "actual_TCP_pose"};
  rtde::Client a(o1), b(o2);
  a.start();
  b.start();
  wait_for_clients(*server, 2);
  publish(*server, 0, 400, 0.0);
  EXPECT_EQ(drain(a, 400).size(), 400u);
  const auto gb = drain(b, 100);
  ASSERT_EQ(gb.size(), 100u);
  EXPECT_NEAR(gb[1].timestamp - gb[0].timestamp, 0.008, 1e-9);
  EXPECT_EQ(b.stats().lost, 0);  // 125 Hz steps are not gaps at 125 Hz
}

// ---- a rogue controller ---------------------------------------------------------------------

namespace {

// Minimal raw TCP server: accepts one client, answers the handshake with a real ServerSession,
// then sends whatever the test scripts.
class RogueServer {
 public:
  RogueServer() {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    int one = 1;
    ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    ::listen(fd_, 4);
    socklen_t len = sizeof a;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port = ntohs(a.sin_port);
  }
  ~RogueServer() {
    if (client_ >= 0) ::close(client_);
    ::close(fd_);
  }
  // Accepts a client and answers nothing (the test sends what it likes).
  void accept_raw() {
    if (client_ >= 0) ::close(client_);
    client_ = ::accept(fd_, nullptr, nullptr);
  }
  // Accepts and runs the handshake until START was answered.
  void accept_and_handshake() {
    if (client_ >= 0) ::close(client_);
    client_ = ::accept(fd_, nullptr, nullptr);
    session = std::make_unique<rtde::ServerSession>(rtde::ControllerVersion{5, 23, 0, 0}, 500.0);
    std::uint8_t buf[4096];
    while (!session->streaming()) {
      const ssize_t k = ::recv(client_, buf, sizeof buf, 0);
      if (k <= 0) return;
      rtde::Bytes out;
      session->on_bytes(buf, static_cast<std::size_t>(k), out);
      send(out);
    }
  }
  // Waits up to timeout_ms for bytes from the client (read and dropped); true if some came.
  bool heard_from_client(int timeout_ms) {
    pollfd p{client_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return false;
    std::uint8_t buf[4096];
    return ::recv(client_, buf, sizeof buf, 0) > 0;
  }
  void send(const rtde::Bytes& b) { ASSERT_EQ(::send(client_, b.data(), b.size(), MSG_NOSIGNAL), static_cast<ssize_t>(b.size())); }
  void send_frames(long k0, long k1) {
    FrameMaker fm;
    rtde::Bytes out;
    for (long k = k0; k < k1; ++k) session->on_cycle(fm.make(k, 0.002 * static_cast<double>(k)), out);
    send(out);
  }
  std::uint16_t port = 0;
  std::unique_ptr<rtde::ServerSession> session;

 private:
  int fd_ = -1, client_ = -1;
};

}  // namespace

// a server that is not RTDE and answers at once (an HTTP or SSH banner) fails the handshake with its
// address and the hint (audit of session 38: the message named neither)
TEST(RtdeRobustness, ANonRtdeServerIsNamedWithItsAddress) {
  twinwatch::log::set_sink(nullptr);
  RogueServer rogue;
  auto o = options_for(rogue.port);
  o.reconnect = false;
  std::thread banner([&] {
    rogue.accept_raw();
    const std::string http = "HTTP/1.0 400 Bad Request\r\nServer: x\r\n\r\n";
    rogue.send(rtde::Bytes(http.begin(), http.end()));
  });
  rtde::Client client(o);
  std::string what;
  try {
    client.start();
  } catch (const rtde::ProtocolError& e) {
    what = e.what();
  }
  banner.join();
  EXPECT_THAT(what, ::testing::HasSubstr(fmt::format("RTDE handshake with 127.0.0.1:{} failed: package size field is 18516 bytes", rogue.port)));
  EXPECT_THAT(what, ::testing::HasSubstr("is it an RTDE server?"));
}

TEST(RtdeRobustness, CorruptAndMalformedPackagesNeverLoseReceivedSamples) {
  twinwatch::log::set_sink(nullptr);
  RogueServer rogue;
  auto o = options_for(rogue.port);
  std::thread accept([&] { rogue.accept_and_handshake(); });
  rtde::Client client(o);
  client.start();
  accept.join();

  rogue.send_frames(0, 50);
  // a data package one byte short (framed correctly): skipped and counted, the stream goes on
  rogue.send(rtde::Bytes{0x00, 0x04, 'U', 0x01});
  // an unknown package type: ignored
  rogue.send(rtde::Bytes{0x00, 0x05, 'Q', 0x01, 0x02});
  // a text message from the controller is delivered, not mistaken for data
  rtde::Bytes msg;
  rtde::encode_text_message(msg, 2, {rtde::MessageLevel::Warning, "protective stop", "controller"});
  rogue.send(msg);
  rogue.send_frames(50, 100);
  auto got = drain(client, 100);
  ASSERT_EQ(got.size(), 100u);
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i].timestamp, 0.002 * static_cast<double>(i), 1e-12);
  EXPECT_EQ(client.stats().protocol_errors, 1);
  EXPECT_EQ(client.stats().text_messages, 1);

  // now a corrupt size field: the stream cannot be re-framed, so the client drops the connection,
  // reconnects and re-handshakes; the 20 samples sent before the garbage are all delivered
  rogue.send_frames(100, 120);
  rogue.send(rtde::Bytes{0xff, 0xff, 'U', 0xde, 0xad});
  rogue.accept_and_handshake();  // the client comes back on its own
  rogue.send_frames(120, 130);
  got = drain(client, 30);
  ASSERT_EQ(got.size(), 30u);
  for (std::size_t i = 0; i < 20; ++i) EXPECT_NEAR(got[i].timestamp, 0.002 * static_cast<double>(100 + i), 1e-12);
  EXPECT_TRUE(got[20].gap_before);
  const auto st = client.stats();
  EXPECT_EQ(st.reconnects, 1);
  EXPECT_EQ(st.protocol_errors, 2);
  EXPECT_NE(st.last_error.find("corrupt RTDE stream"), std::string::npos) << st.last_error;
}

// a controller that stalls, then takes the reconnection and never answers the handshake: stop()
// gives the wait up at once instead of waiting out the reply timeouts (review of session 49: a live
// monitor's --duration 8 ran 9.7 s, the reader thread joined in a 2 s reply wait). The reply
// timeout here is 10 min, so a stop() that waited for it would take the test past its ctest limit;
// the 30 s bound is not a timing figure but that limit made visible.
TEST(RtdeRobustness, StopDoesNotWaitOutAHandshakeTheControllerNeverAnswers) {
  twinwatch::log::set_sink(nullptr);
  RogueServer rogue;
  auto o = options_for(rogue.port);
  o.reply_timeout_ms = 600000;
  std::thread accept([&] { rogue.accept_and_handshake(); });
  rtde::Client client(o);
  client.start();
  accept.join();
  rogue.send_frames(0, 50);
  ASSERT_EQ(drain(client, 50).size(), 50u);
  // the controller drops the link (accept_raw closes the old connection) and the client
  // reconnects; this time the connection is taken and its first request goes unanswered
  rogue.accept_raw();
  ASSERT_TRUE(rogue.heard_from_client(5000)) << "the client did not reconnect: " << client.stats().last_error;
  std::this_thread::sleep_for(100ms);
  EXPECT_FALSE(client.finished());  // still waiting in the handshake
  const auto t0 = std::chrono::steady_clock::now();
  client.stop();
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(took, 30.0);
  EXPECT_TRUE(client.finished());
  const auto st = client.stats();
  EXPECT_EQ(st.reconnects, 0);  // the handshake never completed
  // the last error is the lost link (the old connection, closed by the test), not the stop
  EXPECT_THAT(st.last_error, ::testing::HasSubstr("closed the connection"));
}

TEST(RtdeRobustness, ServerSurvivesGarbageAndKeepsServingOthers) {
  twinwatch::log::set_sink(nullptr);
  rtde::ServerOptions so;
  so.port = 0;
  rtde::Server server(so);
  server.start();
  // a client that sends garbage with a corrupt size field
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(server.port());
  ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  const std::uint8_t garbage[] = {0x00, 0x01, 0x47, 0x45, 0x54, 0x20, 0x2f};  // size 1: impossible
  ::send(fd, garbage, sizeof garbage, MSG_NOSIGNAL);
  // the server answers with an EXCEPTION text message and closes
  std::uint8_t buf[512];
  std::size_t total = 0;
  for (;;) {
    const ssize_t k = ::recv(fd, buf + total, sizeof buf - total, 0);
    if (k <= 0) break;
    total += static_cast<std::size_t>(k);
  }
  ::close(fd);
  rtde::Framer f;
  f.feed(buf, total);
  rtde::Package p;
  ASSERT_TRUE(f.next(p));
  const auto m = rtde::decode_text_message(p, 2);
  EXPECT_EQ(m.level, rtde::MessageLevel::Exception);
  EXPECT_NE(m.message.find("size"), std::string::npos) << m.message;
  // and a well-behaved client still works
  rtde::Client client(options_for(server.port()));
  client.start();
  wait_for_clients(server, 1);
  publish(server, 0, 20, 0.0);
  EXPECT_EQ(drain(client, 20).size(), 20u);
  EXPECT_GE(server.stats().protocol_errors, 1);
}
