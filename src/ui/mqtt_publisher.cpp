// MqttPublisher: the monitor's events to an MQTT broker, from a thread of its own.
//
// libmosquitto (Debian's libmosquitto-dev) speaks the protocol (MQTT 5, falling back to 3.1.1 for a
// broker that has only that). The connection, its retries and the delivery accounting are ours: the
// library's own loop thread (mosquitto_loop_start) never connects after a first mosquitto_connect_async
// that failed (measured with 2.0.11: a broker that was down when the monitor started would never get
// an event). A QoS 1/2 message the library accepted is its to keep: it queues it even while
// disconnected and sends it again after a reconnection (measured: a review's noconn.c, session 53), so
// ours is an outbox in front of it, for the order, its limit and the newest state only.
//
// The thread drives the library with mosquitto_loop(), so every library callback runs on it; the
// caller's thread only touches the outbox under the mutex.
#include <fmt/format.h>
#include <mosquitto.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <fstream>
#include <map>
#include <set>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <thread>

#include "twinwatch/core/error.hpp"
#include "twinwatch/ui/mqtt.hpp"

namespace twinwatch::ui {

namespace {

// the library's global state, once per process (mosquitto_lib_init is not thread-safe)
void init_library() {
  static std::once_flag once;
  std::call_once(once, [] { mosquitto_lib_init(); });
}

// reconnection back-off: 1 s, doubling to 30 s (a broker restart takes seconds; a plant's network
// outage minutes, and 30 s keeps a retry from flooding its log)
constexpr std::chrono::milliseconds kRetryFirst{1000};
constexpr std::chrono::milliseconds kRetryMax{30000};
// a connection not acknowledged (CONNACK) within this is given up and retried: a host that drops
// SYNs would otherwise hold the attempt for the kernel's TCP timeout (minutes). Shorter than the
// monitor's 10 s wait at its end, so that an address that never answers is said before it
constexpr std::chrono::milliseconds kConnectTimeout{5000};
// a connection that lasted less than this and was lost is retried after the back-off, not at once:
// two clients with one id take each other's session at the broker in turn (a review measured 70,600
// connections in 15 s with immediate retries)
constexpr std::chrono::milliseconds kStableLink{5000};
// messages handed to the library and not yet acknowledged at most (the rest wait in the outbox,
// under its limit): a broker that takes the connection but acknowledges nothing must not grow the
// library's queue without bound
constexpr std::size_t kMaxInFlight = 1000;
// how long the destructor waits for the network thread (a host name lookup the C library does not
// interrupt can hold it: then the thread is left to end with the process)
constexpr std::chrono::milliseconds kStopWait{3000};
// one turn of the network loop waits at most this for the socket: how soon a queued message leaves
// and how soon the thread sees a stop
constexpr int kLoopWaitMs = 20;

bool has_control_character(const std::string& t) {
  return std::any_of(t.begin(), t.end(), [](char ch) { return (static_cast<unsigned char>(ch) < 0x20) || ch == 0x7f; });
}

bool valid_topic_prefix(const std::string& t, std::string& why) {
  if (t.empty()) return why = "it is empty", false;
  if (t.front() == '$') return why = "it starts with '$', which brokers keep for their own topics ($SYS) and refuse to clients", false;
  if (has_control_character(t)) return why = "it holds a control character", false;
  if (t.find_first_of("+#") != std::string::npos) return why = "it holds a wildcard ('+' or '#'), which only a subscription may", false;
  if (t.front() == '/' || t.back() == '/') return why = "it starts or ends with '/' (an empty level)", false;
  if (t.find("//") != std::string::npos) return why = "it has an empty level ('//')", false;
  if (mosquitto_validate_utf8(t.c_str(), static_cast<int>(t.size())) != MOSQ_ERR_SUCCESS) return why = "it is not valid UTF-8", false;
  if (t.size() > 60000) return why = "it is longer than MQTT allows", false;
  return true;
}

// the library's words without their full stop (they go inside our sentences)
std::string without_full_stop(std::string r) {
  while (!r.empty() && r.back() == '.') r.pop_back();
  return r;
}

// the library's words for a failure
std::string reason(int rc, int err) {
  if (rc == MOSQ_ERR_KEEPALIVE) return "no answer within the keep-alive";  // (the library says "Unknown error")
  return without_full_stop(rc == MOSQ_ERR_ERRNO ? std::strerror(err) : mosquitto_strerror(rc));
}

std::string default_client_id() {
  char host[128] = {0};
  if (gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  // (MQTT 3.1.1 brokers must accept 1-23 characters; longer ids are accepted by mosquitto and others)
  return fmt::format("twinwatch-{}-{}", host[0] ? host : "host", static_cast<long>(getpid()));
}

}  // namespace

std::string MqttSettings::address() const {
  return host.find(':') != std::string::npos ? fmt::format("[{}]:{}", host, effective_port()) : fmt::format("{}:{}", host, effective_port());
}

void MqttSettings::validate() const {
  if (host.empty()) throw InvalidArgument("MQTT broker: the host is empty");
  if (port < 0 || port > 65535) throw InvalidArgument(fmt::format("MQTT broker port is {}, must be 1..65535", port));
  if (std::string why; !valid_topic_prefix(topic, why)) throw InvalidArgument(fmt::format("MQTT topic prefix '{}': {}", topic, why));
  if (qos < 0 || qos > 2) throw InvalidArgument(fmt::format("MQTT QoS is {}, must be 0, 1 or 2", qos));
  if (keepalive_s < 5 || keepalive_s > 3600) throw InvalidArgument(fmt::format("MQTT keep-alive is {} s, must be 5..3600", keepalive_s));
  if (outbox_limit < 1) throw InvalidArgument("MQTT outbox limit is 0, must be >= 1");
  if (!password.empty() && username.empty()) throw InvalidArgument("MQTT password given without a user name");
  if (!cafile.empty() && !std::ifstream(cafile)) throw InvalidArgument(fmt::format("MQTT CA file '{}': cannot be read", cafile));
  // (the library refuses such an id only when the client is made, as "Out of memory")
  if (!client_id.empty() && (client_id.size() > 65535 || has_control_character(client_id) ||
                             mosquitto_validate_utf8(client_id.c_str(), static_cast<int>(client_id.size())) != MOSQ_ERR_SUCCESS))
    throw InvalidArgument(fmt::format("MQTT client id '{}': expected up to 65535 bytes of UTF-8 without control characters",
                                      client_id.size() > 80 ? client_id.substr(0, 80) + "..." : client_id));
}

void parse_mqtt_address(const std::string& text, MqttSettings& s, const std::string& option) {
  std::string host = text, port;
  if (!text.empty() && text.front() == '[') {  // [IPv6]:port
    const auto close = text.find(']');
    if (close == std::string::npos)
      throw InvalidArgument(fmt::format("{} '{}': an address in brackets needs its ']' (e.g. [::1]:1883)", option, text));
    host = text.substr(1, close - 1);
    if (close + 1 < text.size()) {
      if (text[close + 1] != ':') throw InvalidArgument(fmt::format("{} '{}': expected ':PORT' after ']'", option, text));
      port = text.substr(close + 2);
      if (port.empty()) throw InvalidArgument(fmt::format("{} '{}': the port after ':' is empty", option, text));
    }
  } else if (const auto c = text.rfind(':'); c != std::string::npos) {
    if (text.find(':') != c)
      throw InvalidArgument(fmt::format("{} '{}': an IPv6 address goes in brackets, e.g. [{}]:1883", option, text, text));
    host = text.substr(0, c);
    port = text.substr(c + 1);
    if (port.empty()) throw InvalidArgument(fmt::format("{} '{}': the port after ':' is empty", option, text));
  }
  if (host.empty()) throw InvalidArgument(fmt::format("{} '{}': the broker's host is empty (HOST[:PORT])", option, text));
  s.host = host;
  if (!port.empty()) {
    const bool digits = port.size() <= 5 && std::all_of(port.begin(), port.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
    const int p = digits ? std::stoi(port) : -1;
    if (p < 1 || p > 65535) throw InvalidArgument(fmt::format("{} '{}': the port must be a whole number from 1 to 65535, got '{}'", option, text, port));
    s.port = p;
  }
}

struct MqttPublisher::Impl {
  struct Message {
    std::string topic, payload;
    int qos = 1;
    bool retain = false;
    bool status = false;  // the run's state: only the newest one waits
    bool again = false;   // the state sent again after a reconnection (not counted as published)
  };
  enum class Link { Down, Connecting, Up };

  MqttSettings s;
  std::string status_topic, will;
  mosquitto* m = nullptr;
  int protocol = MQTT_PROTOCOL_V5;

  mutable std::mutex mu;
  std::condition_variable cv;        // the thread: work queued or a stop; drain(): a delivery
  std::deque<Message> outbox;        // not yet handed to the library
  std::map<int, Message> inflight;   // handed over (by message id), not yet acknowledged
  std::set<int> acked_early;         // acknowledged inside mosquitto_publish, before hand_over saw the id
  bool handing = false;              // hand_over is inside mosquitto_publish
  std::vector<std::string> notes;
  MqttCounters c;
  std::string last_status;           // the newest state published: sent again after a reconnection
  bool stop = false;
  bool finished = false;             // the thread has ended
  Link link = Link::Down;            // (the thread's; the callbacks run inside its mosquitto_loop)
  bool ever_connected = false;
  std::chrono::steady_clock::time_point up_since;
  int quick_losses = 0;              // connections lost within kStableLink of being made, in a row
  std::string last_failure;          // the last failure said, so that a retry does not repeat it
  std::set<int> refusals_said;       // the broker's reason codes for refused messages, said once each
  std::thread thread;

  void note(std::string text) {  // (mu held)
    notes.push_back(std::move(text));
    if (notes.size() > 100) notes.erase(notes.begin());  // (nobody reading: keep the newest)
  }

  // --- library callbacks (on the thread, inside mosquitto_loop) -------------------------------
  static void on_connect(mosquitto*, void* self, int rc, int /*flags*/, const mosquitto_property*) {
    auto* p = static_cast<Impl*>(self);
    std::lock_guard lk(p->mu);
    if (rc == 0) {
      p->link = Link::Up;
      p->up_since = std::chrono::steady_clock::now();
      ++p->c.connects;
      p->c.connected = true;
      const bool again = p->ever_connected;
      if (!again || p->quick_losses == 0)
        p->note(again ? fmt::format("reconnected to {}; {} message(s) waiting are sent now", p->s.address(), p->waiting())
                      : fmt::format("connected to {}; events go to {}/events/CLASS, the run's state to {}", p->s.address(), p->s.topic,
                                    p->status_topic));
      p->ever_connected = true;
      p->last_failure.clear();
      // the broker may have published the last will while the link was down (a silence longer than
      // the keep-alive): the run's state again, unless a newer one waits anyway
      if (again && !p->last_status.empty() &&
          std::none_of(p->outbox.begin(), p->outbox.end(), [](const Message& x) { return x.status; }))
        p->outbox.push_back({p->status_topic, p->last_status, std::max(1, p->s.qos), true, true, true});
      p->cv.notify_all();
      return;
    }
    // a broker with MQTT 3.1.1 only (3.1.1's "unacceptable protocol version", or 5's 132): speak that
    if (p->protocol == MQTT_PROTOCOL_V5 && (rc == 1 || rc == 132)) {
      p->protocol = MQTT_PROTOCOL_V311;
      mosquitto_int_option(p->m, MOSQ_OPT_PROTOCOL_VERSION, MQTT_PROTOCOL_V311);
      p->note(fmt::format("the broker at {} speaks MQTT 3.1.1, not 5: publishing with 3.1.1, under which a broker that refuses a "
                          "message (an ACL) cannot say so",
                          p->s.address()));
      p->link = Link::Down;
      return;
    }
    // a refusal by the broker (CONNACK): credentials, a client id it rejects, ...
    std::string said = without_full_stop(p->protocol == MQTT_PROTOCOL_V5 ? mosquitto_reason_string(rc) : mosquitto_connack_string(rc));
    if (said.rfind("Connection Refused: ", 0) == 0) said.erase(0, 20);
    std::string why = fmt::format("the broker at {} refused the connection: {}", p->s.address(), said);
    // (3.1.1: 4 bad user name or password, 5 not authorised; 5: 134, 135)
    if (rc == 4 || rc == 5 || rc == 134 || rc == 135) why += " (check the user name and password)";
    if (why != p->last_failure) p->note(why + "; retrying, events are kept until it takes them");
    p->last_failure = why;
    p->link = Link::Down;
    p->cv.notify_all();
  }
  static void on_disconnect(mosquitto*, void* self, int rc, const mosquitto_property*) {
    auto* p = static_cast<Impl*>(self);
    std::lock_guard lk(p->mu);
    if (p->link == Link::Up && rc != 0 && !p->stop) p->lost(reason(rc, errno));
    p->link = Link::Down;
    p->c.connected = false;
  }
  static void on_publish(mosquitto*, void* self, int mid, int reason_code, const mosquitto_property*) {
    auto* p = static_cast<Impl*>(self);
    std::lock_guard lk(p->mu);
    const auto it = p->inflight.find(mid);
    if (it == p->inflight.end()) {
      if (p->handing) p->acked_early.insert(mid);  // (inside mosquitto_publish: hand_over counts it)
    } else {
      p->settle(it->second, reason_code);
      p->inflight.erase(it);
    }
    p->cv.notify_all();
  }

  // a message the broker answered: taken, or refused (MQTT 5 reason codes 0x80 and up: an ACL's "not
  // authorised", a topic it will not take). Under 3.1.1 a broker acknowledges a message it drops.
  void settle(const Message& msg, int reason_code) {  // (mu held)
    if (reason_code < 0x80) {
      if (!msg.again) ++c.delivered;
      return;
    }
    ++c.refused;
    if (refusals_said.insert(reason_code).second) {
      note(fmt::format("the broker at {} refused a message to {}: {}{}", s.address(), msg.topic,
                       without_full_stop(mosquitto_reason_string(reason_code)),
                       reason_code == 135 ? " (does its access list let this client publish under this topic?)" : ""));
    }
  }

  // a connection that was up is lost (mu held): said, unless connections keep being lost at once
  void lost(const std::string& why) {
    const bool quick = std::chrono::steady_clock::now() - up_since < kStableLink;
    quick_losses = quick ? quick_losses + 1 : 0;
    if (quick_losses == 3)
      note(fmt::format("the broker at {} ended the connection within {} s of each of the last 3 connections ({}): is another client "
                       "connected with the id '{}' (--mqtt-client-id)? retrying every {}-{} s",
                       s.address(), kStableLink.count() / 1000, why, s.client_id, kRetryFirst.count() / 1000, kRetryMax.count() / 1000));
    else if (quick_losses < 3)
      note(fmt::format("lost the broker at {} ({}); reconnecting, events are kept until it takes them", s.address(), why));
    last_failure.clear();
    link = Link::Down;
    c.connected = false;
  }

  // a connection that could not be made (rc, errno from the library's call)
  void unreachable(int rc, int err) {  // (mu held)
    // (the library says only "A TLS error occurred": what usually causes it)
    const std::string hint =
        rc == MOSQ_ERR_TLS ? fmt::format(" (does the broker's certificate check against {} and name the host '{}'? does the port "
                                         "speak TLS?)",
                                         s.cafile, s.host)
                           : std::string();
    failed(fmt::format("cannot reach the broker at {}: {}{}", s.address(), reason(rc, err), hint));
  }

  // a failure to connect: said once per distinct cause (a retry does not repeat it)
  void failed(const std::string& why) {  // (mu held)
    if (why != last_failure)
      note(fmt::format("{}; retrying every {}-{} s, events are kept until it takes them", why, kRetryFirst.count() / 1000,
                       kRetryMax.count() / 1000));
    last_failure = why;
    link = Link::Down;
    c.connected = false;
  }

  // hands the outbox to the library while it is connected (called with mu held; released around the
  // library's call, which writes to the socket at once and may call on_publish from inside it)
  void hand_over(std::unique_lock<std::mutex>& lk) {
    while (!outbox.empty() && link == Link::Up && !stop && inflight.size() < kMaxInFlight) {
      Message msg = std::move(outbox.front());
      outbox.pop_front();
      handing = true;
      lk.unlock();
      int mid = 0;
      const int rc = mosquitto_publish(m, &mid, msg.topic.c_str(), static_cast<int>(msg.payload.size()), msg.payload.data(), msg.qos, msg.retain);
      lk.lock();
      handing = false;
      const bool link_error = rc == MOSQ_ERR_NO_CONN || rc == MOSQ_ERR_CONN_LOST || rc == MOSQ_ERR_ERRNO;
      if (rc == MOSQ_ERR_SUCCESS || (link_error && msg.qos > 0 && mid != 0)) {
        // the library has it: QoS 0 was written (on_publish maybe inside the call), QoS 1/2 is queued
        // and sent again after a reconnection if the link failed under it
        if (acked_early.erase(mid) > 0) {
          if (!msg.again) ++c.delivered;
          cv.notify_all();
        } else {
          inflight.emplace(mid, std::move(msg));
        }
        if (link_error) return;  // (the loop sees the loss)
        continue;
      }
      if (link_error) {  // QoS 0 the library did not keep: it waits again, first in line
        outbox.push_front(std::move(msg));
        return;
      }
      // a message the library refuses (too large for the broker, ...): dropped, said
      note(fmt::format("a message to {} was refused by the client library: {}; dropped", msg.topic, reason(rc, errno)));
      ++c.dropped;
    }
  }

  void run() {
    auto retry = kRetryFirst;
    auto next_attempt = std::chrono::steady_clock::now();
    auto connect_started = next_attempt;
    std::unique_lock lk(mu);
    // after a turn that ended the link: when to try again (at once after a connection that lasted, as
    // a broker's restart ends one; growing waits while attempts fail or links are lost at once)
    auto schedule = [&](bool lasted) {
      const auto now = std::chrono::steady_clock::now();
      if (lasted) {
        retry = kRetryFirst;
        next_attempt = now;
      } else {
        next_attempt = now + retry;
        retry = std::min(kRetryMax, retry * 2);
      }
    };
    while (!stop) {
      const auto now = std::chrono::steady_clock::now();
      if (link == Link::Down) {
        if (now < next_attempt) {
          cv.wait_until(lk, next_attempt, [&] { return stop; });
          continue;
        }
        // (re)connect: the library's socket connect is non-blocking; the CONNACK comes in the loop.
        // (A host name is looked up here, blocking: the C library's resolver)
        lk.unlock();
        const int rc = mosquitto_connect_async(m, s.host.c_str(), s.effective_port(), s.keepalive_s);
        const int err = errno;
        lk.lock();
        if (stop) break;
        if (rc != MOSQ_ERR_SUCCESS) {
          unreachable(rc, err);
          schedule(false);
          continue;
        }
        link = Link::Connecting;
        connect_started = now;
      }
      if (link == Link::Connecting && now - connect_started > kConnectTimeout) {
        lk.unlock();
        mosquitto_disconnect(m);
        lk.lock();
        failed(fmt::format("the broker at {} did not answer within {} s", s.address(), kConnectTimeout.count() / 1000));
        schedule(false);
        continue;
      }
      if (link == Link::Up) hand_over(lk);
      // one turn of the network loop (reads, writes, keep-alive, the callbacks)
      const Link before = link;
      const auto up_at = up_since;
      lk.unlock();
      const int rc = mosquitto_loop(m, kLoopWaitMs, 1);
      const int err = errno;
      lk.lock();
      if (stop) break;
      if (rc != MOSQ_ERR_SUCCESS && link != Link::Down) {
        if (link == Link::Up) {
          lost(reason(rc, err));
        } else {
          unreachable(rc, err);
        }
      }
      if (link == Link::Down && before != Link::Down)
        schedule(before == Link::Up && std::chrono::steady_clock::now() - up_at >= kStableLink);
    }
    // a clean goodbye: the broker then keeps the status the run last published instead of the will
    if (link == Link::Up) {
      lk.unlock();
      mosquitto_disconnect(m);
      for (int i = 0; i < 10 && mosquitto_loop(m, kLoopWaitMs, 1) == MOSQ_ERR_SUCCESS; ++i) {
      }
      lk.lock();
    }
    finished = true;
    cv.notify_all();
  }

  long waiting() const { return static_cast<long>(outbox.size() + inflight.size()); }  // (mu held)

  void enqueue(Message msg) {
    std::lock_guard lk(mu);
    ++c.published;
    if (msg.status) {  // only the newest state matters; it goes after the events it follows
      last_status = msg.payload;
      auto old = std::find_if(outbox.begin(), outbox.end(), [](const Message& x) { return x.status; });
      if (old != outbox.end()) {
        if (!old->again) ++c.superseded;
        outbox.erase(old);
      }
    }
    if (outbox.size() >= s.outbox_limit) {
      // full (the broker away for long): the oldest event line goes
      auto victim = std::find_if(outbox.begin(), outbox.end(), [](const Message& x) { return !x.status; });
      if (victim != outbox.end()) {
        outbox.erase(victim);
        ++c.dropped;
        if (c.dropped == 1 || c.dropped % 1000 == 0)
          note(fmt::format("the outbox holds {} messages and the broker at {} does not take them: {} oldest event line(s) dropped",
                           s.outbox_limit, s.address(), c.dropped));
      }
    }
    outbox.push_back(std::move(msg));
    cv.notify_all();
  }
};

MqttPublisher::MqttPublisher(MqttSettings settings) : impl_(std::make_unique<Impl>()) {
  settings.validate();
  init_library();
  Impl& p = *impl_;
  p.s = std::move(settings);
  if (p.s.client_id.empty()) p.s.client_id = default_client_id();
  p.status_topic = p.s.topic + "/status";
  p.will = p.s.will.empty() ? std::string(R"({"state":"lost"})") : p.s.will;
  p.m = mosquitto_new(p.s.client_id.c_str(), true, &p);
  if (!p.m)
    throw std::runtime_error(fmt::format("MQTT: cannot create a client with the id '{}' ({})", p.s.client_id, std::strerror(errno)));
  auto check = [&](int rc, const char* what) {
    if (rc != MOSQ_ERR_SUCCESS) {
      const int err = errno;
      mosquitto_destroy(p.m);
      throw InvalidArgument(fmt::format("MQTT {}: {}", what, reason(rc, err)));
    }
  };
  check(mosquitto_int_option(p.m, MOSQ_OPT_PROTOCOL_VERSION, MQTT_PROTOCOL_V5), "protocol version");
  check(mosquitto_will_set(p.m, p.status_topic.c_str(), static_cast<int>(p.will.size()), p.will.data(), std::max(1, p.s.qos), true),
        "last will");
  if (!p.s.username.empty())
    check(mosquitto_username_pw_set(p.m, p.s.username.c_str(), p.s.password.empty() ? nullptr : p.s.password.c_str()), "user name");
  if (!p.s.cafile.empty()) check(mosquitto_tls_set(p.m, p.s.cafile.c_str(), nullptr, nullptr, nullptr, nullptr), "TLS CA file");
  mosquitto_connect_v5_callback_set(p.m, &Impl::on_connect);
  mosquitto_disconnect_v5_callback_set(p.m, &Impl::on_disconnect);
  mosquitto_publish_v5_callback_set(p.m, &Impl::on_publish);
  p.thread = std::thread([&p] { p.run(); });
}

MqttPublisher::~MqttPublisher() {
  std::unique_lock lk(impl_->mu);
  impl_->stop = true;
  impl_->cv.notify_all();
  if (!impl_->cv.wait_for(lk, kStopWait, [&] { return impl_->finished; })) {
    // the thread is held in a host name lookup: it is left to end with the process, and what it uses
    // with it (destroying them under it would crash it)
    lk.unlock();
    impl_->thread.detach();
    (void)impl_.release();
    return;
  }
  lk.unlock();
  impl_->thread.join();
  mosquitto_destroy(impl_->m);
}

void MqttPublisher::publish_event(const std::string& fault_class, const std::string& json_line) {
  impl_->enqueue({impl_->s.topic + "/events/" + fault_class, json_line, impl_->s.qos, false, false, false});
}

void MqttPublisher::publish_status(const std::string& json) {
  // (at least QoS 1: the state is what a control room's screen shows, and it is retained)
  impl_->enqueue({impl_->status_topic, json, std::max(1, impl_->s.qos), true, true, false});
}

long MqttPublisher::drain(std::chrono::milliseconds timeout, const std::function<bool()>& give_up) {
  std::unique_lock lk(impl_->mu);
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (impl_->waiting() > 0 && std::chrono::steady_clock::now() < until) {
    if (give_up && give_up()) break;
    impl_->cv.wait_until(lk, std::min(until, std::chrono::steady_clock::now() + std::chrono::milliseconds(100)),
                         [&] { return impl_->waiting() == 0; });
  }
  return impl_->waiting();
}

std::vector<std::string> MqttPublisher::take_notes() {
  std::lock_guard lk(impl_->mu);
  std::vector<std::string> out;
  out.swap(impl_->notes);
  return out;
}

MqttCounters MqttPublisher::counters() const {
  std::lock_guard lk(impl_->mu);
  MqttCounters c = impl_->c;
  c.waiting = impl_->waiting();
  return c;
}

const MqttSettings& MqttPublisher::settings() const { return impl_->s; }

}  // namespace twinwatch::ui
