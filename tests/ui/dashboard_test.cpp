#include "twinwatch/ui/dashboard.hpp"

#include <arpa/inet.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "twinwatch/core/error.hpp"

namespace twinwatch::ui {
namespace {

using nlohmann::json;

DashboardSetup two_joints(double window = 120.0) {
  DashboardSetup s;
  s.title = "twin.json";
  s.source = "rec.csv";
  s.n_dof = 2;
  s.window_s = window;
  s.points_per_s = 50.0;
  return s;
}

// one 500 Hz sample: residual r on both joints, threshold thr, current i
void push(DashboardFeed& f, double t, std::array<double, 2> r, double thr = 1.0, double i = 0.5) {
  const std::array<double, 2> th{thr, thr}, cur{i, -i}, pred{i + 0.01, -i}, obs{0.1, 0.2}, obs_th{1.0, 1.0};
  DashboardSignals s;
  s.t = t;
  s.measured = cur.data();
  s.predicted = pred.data();
  s.residual = r.data();
  s.threshold = th.data();
  s.observer = obs.data();
  s.observer_threshold = obs_th.data();
  s.total_current = 2 * std::abs(i);
  f.push(s);
}

TEST(DashboardFeed, APointPerIntervalKeepsTheSampleClosestToItsThreshold) {
  DashboardFeed f(two_joints());
  // 1 s at 500 Hz; a one-sample pulse of 5 A on J2 at t = 0.503 s (inside the 0.50-0.52 s interval)
  for (int k = 0; k < 500; ++k) {
    const double t = 0.002 * k;
    push(f, t, {0.1 * std::sin(t), k == 251 ? -5.0 : 0.05});
  }
  f.status("finished", "{}");  // the last interval too
  const json d = json::parse(f.json_since(0));
  const auto& t = d["points"]["t"];
  // 50 points a second: one per 20 ms of controller time
  ASSERT_EQ(t.size(), 50u);
  // the interval holding the pulse draws it at its peak (sign kept), not at the interval's last sample
  size_t hit = 0;
  for (size_t k = 0; k < t.size(); ++k)
    if (d["points"]["residual"][1][k].get<double>() == -5.0) hit = k;
  EXPECT_NEAR(t[hit].get<double>(), 0.518, 1e-9);  // (its last sample's time)
  EXPECT_EQ(d["points"]["threshold"][1][hit].get<double>(), 1.0);
  // the neighbours do not carry it
  EXPECT_EQ(d["points"]["residual"][1][hit - 1].get<double>(), 0.05);
  EXPECT_EQ(d["points"]["residual"][1][hit + 1].get<double>(), 0.05);
  EXPECT_EQ(d["points"]["measured"][1][0].get<double>(), -0.5);
  EXPECT_EQ(d["points"]["total_current"][0].get<double>(), 1.0);
  EXPECT_TRUE(d["reset"].get<bool>());
  EXPECT_EQ(d["status"]["state"], "finished");
}

TEST(DashboardFeed, TheWindowKeepsItsSecondsAndNoMore) {
  DashboardFeed f(two_joints(10.0));
  for (int k = 0; k < 500 * 60; ++k) push(f, 0.002 * k, {0.0, 0.0});
  const json d = json::parse(f.json_since(0));
  const auto& t = d["points"]["t"];
  ASSERT_FALSE(t.empty());
  const double last = t.back().get<double>(), first = t.front().get<double>();
  EXPECT_GE(first, last - 10.0);
  EXPECT_LE(t.size(), 501u);
  EXPECT_GE(t.size(), 499u);
}

TEST(DashboardFeed, ACursorGetsWhatIsNewAndAnAlertIsReplacedWhenItCloses) {
  DashboardFeed f(two_joints());
  for (int k = 0; k < 100; ++k) push(f, 0.002 * k, {0.0, 0.0});
  f.event(R"({"class":"unknown","t_detected":0.1,"detail":"raised"})", true, 0.1);
  const json a = json::parse(f.json_since(0));
  ASSERT_EQ(a["active"].size(), 1u);
  EXPECT_TRUE(a["events"].empty());
  const std::uint64_t c = a["cursor"].get<std::uint64_t>();
  EXPECT_EQ(c, f.cursor());
  const size_t seen = a["points"]["t"].size();
  // a re-diagnosis replaces the open alert; its close moves it to the events
  for (int k = 100; k < 200; ++k) push(f, 0.002 * k, {0.0, 0.0});
  f.event(R"({"class":"collision","t_detected":0.1,"detail":"re-diagnosed"})", true, 0.1);
  const json b = json::parse(f.json_since(c));
  ASSERT_EQ(b["active"].size(), 1u);
  EXPECT_EQ(b["active"][0]["detail"], "re-diagnosed");
  EXPECT_FALSE(b["reset"].get<bool>());
  EXPECT_FALSE(b["whole"].get<bool>());
  // only the points after the cursor: about 100 samples, 10 points
  EXPECT_GE(b["points"]["t"].size(), 9u);
  EXPECT_LE(b["points"]["t"].size(), 11u);
  EXPECT_GT(b["points"]["t"][0].get<double>(), a["points"]["t"][seen - 1].get<double>());
  f.event(R"({"class":"collision","t_detected":0.1,"detail":"closed"})", false, 0.1);
  f.note(0.3, "a note with \"quotes\"");
  const json e = json::parse(f.json_since(b["cursor"].get<std::uint64_t>()));
  EXPECT_TRUE(e["active"].empty());
  ASSERT_EQ(e["events"].size(), 1u);
  EXPECT_EQ(e["events"][0]["detail"], "closed");
  ASSERT_EQ(e["notes"].size(), 1u);
  EXPECT_EQ(e["notes"][0]["text"], "a note with \"quotes\"");
  // nothing new: nothing again
  const json g = json::parse(f.json_since(e["cursor"].get<std::uint64_t>()));
  EXPECT_TRUE(g["events"].empty());
  EXPECT_TRUE(g["notes"].empty());
  // a cursor from the future (the page outlived a restart): the whole state
  const json h = json::parse(f.json_since(1u << 30));
  EXPECT_TRUE(h["whole"].get<bool>());
  EXPECT_EQ(h["events"].size(), 1u);
}

// an alert the monitor withdraws (monitor::Monitor::on_withdraw: a pause, a pick declared late) leaves
// the open alerts and is no event (before session 53 it stayed on the page as active for good)
TEST(DashboardFeed, AWithdrawnAlertLeavesTheOpenOnesAndIsNoEvent) {
  DashboardFeed f(two_joints());
  for (int k = 0; k < 100; ++k) push(f, 0.002 * k, {0.0, 0.0});
  f.event(R"({"class":"unknown","t_detected":0.1,"detail":"raised"})", true, 0.1);
  f.event(R"({"class":"collision","t_detected":0.15,"detail":"another"})", true, 0.15);
  const json a = json::parse(f.json_since(0));
  ASSERT_EQ(a["active"].size(), 2u);
  f.event(R"({"class":"payload_change","t_detected":0.1,"detail":"withdrawn","withdrawn":true})", false, 0.1, true);
  const json b = json::parse(f.json_since(a["cursor"].get<std::uint64_t>()));
  ASSERT_EQ(b["active"].size(), 1u);
  EXPECT_EQ(b["active"][0]["detail"], "another");
  EXPECT_TRUE(b["events"].empty());
  EXPECT_TRUE(json::parse(f.json_since(0))["events"].empty());
}

TEST(DashboardFeed, TimeGoingBackStartsAPointOfItsOwn) {
  DashboardFeed f(two_joints());
  push(f, 10.000, {0.3, 0.0});
  push(f, 10.002, {0.2, 0.0});
  push(f, 5.000, {0.1, 0.0});  // another file, earlier
  f.status("finished", "{}");
  const json d = json::parse(f.json_since(0));
  ASSERT_EQ(d["points"]["t"].size(), 2u);
  EXPECT_EQ(d["points"]["residual"][0][0].get<double>(), 0.3);
  EXPECT_EQ(d["points"]["residual"][0][1].get<double>(), 0.1);
}

TEST(DashboardFeed, MissingSignalsAreNullNotZero) {
  DashboardFeed f(two_joints());
  DashboardSignals s;
  s.t = 1.0;
  const std::array<double, 2> cur{NAN, 0.4};
  s.measured = cur.data();
  f.push(s);
  f.status("finished", "not json");
  const json d = json::parse(f.json_since(0));
  EXPECT_TRUE(d["points"]["measured"][0][0].is_null());
  EXPECT_EQ(d["points"]["measured"][1][0].get<double>(), 0.4);
  EXPECT_TRUE(d["points"]["predicted"][0][0].is_null());
  EXPECT_TRUE(d["points"]["residual"][1][0].is_null());
  EXPECT_TRUE(d["points"]["observer"][1][0].is_null());
  EXPECT_TRUE(d["status"]["counters"].is_object());
}

TEST(DashboardFeed, SetupOutOfRangeIsNamed) {
  DashboardSetup s = two_joints();
  s.n_dof = 0;
  EXPECT_THAT([&] { DashboardFeed f(s); }, testing::ThrowsMessage<InvalidArgument>(testing::HasSubstr("n_dof is 0, expected 1 to 7")));
  s = two_joints(0.0);
  EXPECT_THAT([&] { DashboardFeed f(s); }, testing::ThrowsMessage<InvalidArgument>(testing::HasSubstr("window_s is 0")));
  s = two_joints();
  s.points_per_s = -1;
  EXPECT_THAT([&] { DashboardFeed f(s); }, testing::ThrowsMessage<InvalidArgument>(testing::HasSubstr("points_per_s is -1")));
}

// ---- the server, spoken to as a browser or a script would -------------------------------------

// sends `request` bytes to 127.0.0.1:port and reads until the server closes
std::string talk(unsigned short port, const std::string& request) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return "connect failed";
  }
  timeval tv{5, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  size_t sent = 0;
  while (sent < request.size()) {
    const ssize_t n = ::send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) break;
    sent += static_cast<size_t>(n);
  }
  std::string out;
  char buf[4096];
  for (ssize_t n; (n = ::recv(fd, buf, sizeof buf, 0)) > 0;) out.append(buf, static_cast<size_t>(n));
  ::close(fd);
  return out;
}

std::string get(unsigned short port, const std::string& target) {
  return talk(port, "GET " + target + " HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n");
}

std::string body_of(const std::string& response) {
  const size_t at = response.find("\r\n\r\n");
  return at == std::string::npos ? std::string() : response.substr(at + 4);
}

TEST(DashboardServer, ServesThePageAndTheStateAndSaysWhatIsWrongWithARequest) {
  DashboardFeed feed(two_joints());
  for (int k = 0; k < 1000; ++k) push(feed, 0.002 * k, {0.0, 0.1});
  feed.event(R"({"class":"collision","t_detected":1.0,"detail":"contact on link 3"})", false, 1.0);
  DashboardServer server(feed, "127.0.0.1", 0);
  ASSERT_GT(server.port(), 0);

  // the page: HTML, whole, with no external URL (a plant network has no internet)
  const std::string page = get(server.port(), "/");
  EXPECT_THAT(page, testing::StartsWith("HTTP/1.1 200"));
  EXPECT_THAT(page, testing::HasSubstr("Content-Type: text/html; charset=utf-8"));
  EXPECT_EQ(body_of(page), dashboard_page());
  EXPECT_THAT(dashboard_page(), testing::HasSubstr("/api/state?since="));
  EXPECT_THAT(dashboard_page(), testing::Not(testing::HasSubstr("http://")));
  EXPECT_THAT(dashboard_page(), testing::Not(testing::HasSubstr("https://")));
  EXPECT_THAT(dashboard_page(), testing::Not(testing::HasSubstr("@TWINWATCH")));  // (the build filled it in)

  // the state: what the feed holds, as JSON
  const std::string state = get(server.port(), "/api/state?since=0");
  EXPECT_THAT(state, testing::HasSubstr("Content-Type: application/json"));
  const json d = json::parse(body_of(state));
  EXPECT_EQ(d["setup"]["n_dof"], 2);
  // the twin's channel, which the page's labels take (a twin of joint torque sensors: "joint torque", N·m)
  EXPECT_EQ(d["setup"]["channel"], "current");
  EXPECT_EQ(d["setup"]["channel_unit"], "A");
  EXPECT_THAT(dashboard_page(), testing::HasSubstr("st.channel_unit"));
  EXPECT_EQ(d["events"][0]["detail"], "contact on link 3");
  EXPECT_EQ(d["points"]["t"].size(), 100u);
  EXPECT_EQ(d["cursor"].get<std::uint64_t>(), feed.cursor());

  // HEAD: the headers alone
  const std::string head = talk(server.port(), "HEAD / HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
  EXPECT_THAT(head, testing::StartsWith("HTTP/1.1 200"));
  EXPECT_THAT(head, testing::HasSubstr("Content-Length: " + std::to_string(dashboard_page().size())));
  EXPECT_EQ(body_of(head), "");

  // what is not served is said
  EXPECT_THAT(get(server.port(), "/api/state?since=abc"),
              testing::AllOf(testing::StartsWith("HTTP/1.1 400"), testing::HasSubstr("since must be a whole number >= 0")));
  EXPECT_THAT(get(server.port(), "/api/state?since=-1"), testing::StartsWith("HTTP/1.1 400"));
  EXPECT_THAT(get(server.port(), "/nope"), testing::AllOf(testing::StartsWith("HTTP/1.1 404"), testing::HasSubstr("/nope is not served")));
  const std::string post = talk(server.port(), "POST /api/state HTTP/1.1\r\nHost: x\r\nContent-Length: 2\r\nConnection: close\r\n\r\n{}");
  EXPECT_THAT(post, testing::AllOf(testing::StartsWith("HTTP/1.1 405"), testing::HasSubstr("Allow: GET, HEAD")));
  // bytes that are no HTTP: a 400, and the server goes on answering
  EXPECT_THAT(talk(server.port(), std::string("\x16\x03\x01\x02\x00 garbage\r\n\r\n", 20)), testing::StartsWith("HTTP/1.1 400"));
  EXPECT_THAT(talk(server.port(), "GET / HTTP/1.1\r\nHost: x\r\nX-Big: " + std::string(64 * 1024, 'a') + "\r\n\r\n"),
              testing::StartsWith("HTTP/1.1 400"));
  EXPECT_THAT(get(server.port(), "/api/state?since=0"), testing::StartsWith("HTTP/1.1 200"));

  // keep-alive: two requests on one connection, both answered
  const std::string two = talk(server.port(),
                                   "GET /api/state?since=0 HTTP/1.1\r\nHost: x\r\n\r\n"
                                   "GET /nope HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
  EXPECT_THAT(two, testing::HasSubstr("HTTP/1.1 200"));
  EXPECT_THAT(two, testing::HasSubstr("HTTP/1.1 404"));
  EXPECT_GE(server.requests(), 10);
  server.stop();
  server.stop();  // (idempotent)
  EXPECT_EQ(get(server.port(), "/"), "connect failed");
}

TEST(DashboardServer, AnAddressThatCannotBeListenedOnIsNamed) {
  DashboardFeed feed(two_joints());
  DashboardServer first(feed, "127.0.0.1", 0);
  EXPECT_THAT([&] { DashboardServer second(feed, "127.0.0.1", first.port()); },
              testing::ThrowsMessage<PathError>(testing::AllOf(testing::HasSubstr("cannot listen on 127.0.0.1:" + std::to_string(first.port())),
                                                                testing::HasSubstr("choose another with --listen"))));
  EXPECT_THAT([&] { DashboardServer third(feed, "no-such-host.invalid", 0); },
              testing::ThrowsMessage<PathError>(testing::HasSubstr("cannot listen on no-such-host.invalid:0")));
}

}  // namespace
}  // namespace twinwatch::ui
