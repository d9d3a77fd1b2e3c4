// monitor's and serve's --mqtt (mqtt_sink.hpp).
#include "mqtt_sink.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/wall_clock.hpp"
#include "verb_registry.hpp"
#include "twinwatch/ui/mqtt.hpp"

namespace twinwatch::cli {

namespace {
// the password's environment variable: an argument would be visible to every user of the machine (ps)
constexpr const char* kPasswordVariable = "TWINWATCH_MQTT_PASSWORD";

#ifdef TWINWATCH_HAVE_MQTT
// the settings the options give (the password is the constructor's to add)
ui::MqttSettings settings_of(const MqttCliOptions& o) {
  ui::MqttSettings s;
  ui::parse_mqtt_address(o.address, s);
  s.topic = o.topic;
  s.qos = o.qos;
  s.username = o.user;
  s.cafile = o.cafile;
  s.client_id = o.client_id;
  s.keepalive_s = o.keepalive;
  return s;
}

double unix_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}
#endif

}  // namespace

std::function<void()> add_mqtt_options(CLI::App* sub, MqttCliOptions& o) {
  sub->add_option("--mqtt", o.address,
                                  "Publish the events and the run's state to the MQTT broker at HOST[:PORT] (default port 1883, 8883 with "
                                  "--mqtt-cafile): each event's JSON line (as --events writes it; with --events-open the open alerts' "
                                  "lines too) to TOPIC/events/CLASS, the run's state (monitoring, finished, stopped, connection lost, "
                                  "failed) retained on TOPIC/status, where the broker puts {\"state\":\"lost\"} if this process "
                                  "vanishes. A broker that is away is retried in the background; events wait for it (docs/events.md)");
  auto* topic = sub->add_option("--mqtt-topic", o.topic, "With --mqtt: the topic prefix, e.g. plant/cell3/ur3e (one per robot)")
                    ->capture_default_str();
  auto* qos = sub->add_option("--mqtt-qos", o.qos, "With --mqtt: the quality of service of the events (0, 1 or 2)")
                  ->check(whole_number(0, 2))
                  ->capture_default_str();
  auto* user = sub->add_option("--mqtt-user", o.user,
                               fmt::format("With --mqtt: log in as this user; the password is read from ${}", kPasswordVariable));
  auto* cafile = sub->add_option("--mqtt-cafile", o.cafile,
                                 "With --mqtt: connect over TLS, checking the broker's certificate against this CA certificate (PEM)")
                     ->check(CLI::ExistingFile);
  auto* client_id = sub->add_option("--mqtt-client-id", o.client_id,
                                    "With --mqtt: the client id (default twinwatch-HOSTNAME-PID); two clients with one id take "
                                    "each other's connection at the broker");
  auto* keepalive = sub->add_option("--mqtt-keepalive", o.keepalive,
                                    "With --mqtt: the keep-alive [s]; the broker publishes the last will after 1.5 of them without a "
                                    "word from this process")
                        ->check(whole_number(5, 3600))
                        ->capture_default_str();
  auto* status_every = sub->add_option("--mqtt-status-every", o.status_every,
                                       "With --mqtt: publish the run's state with its counts (samples, events, open alerts, the "
                                       "stream's) every SECONDS of wall-clock time while it runs; 0: at its start and end only")
                           ->check(CLI::Range(0.0, 86400.0))
                           ->capture_default_str();
  return [=, &o] {
    refuse_unless({topic, qos, user, cafile, client_id, keepalive, status_every}, !o.address.empty(), "with --mqtt");
#ifndef TWINWATCH_HAVE_MQTT
    if (!o.address.empty())
      throw InvalidArgument("--mqtt: this twinwatch was built without MQTT (BUILD_MQTT=OFF or libmosquitto-dev missing at configure "
                            "time); build it again after 'apt-get install libmosquitto-dev'");
#else
    if (!o.address.empty()) {  // the settings' own checks, said with the option's name, before any work
      const ui::MqttSettings s = settings_of(o);
      try {
        s.validate();
      } catch (const InvalidArgument& e) {
        throw InvalidArgument(with_option_names(e.what(), {{"MQTT topic prefix", "--mqtt-topic"}, {"MQTT client id", "--mqtt-client-id"}}));
      }
    }
#endif
  };
}

#ifdef TWINWATCH_HAVE_MQTT

namespace {
void destroy_publisher(ui::MqttPublisher* p) { delete p; }
}  // namespace

MqttSink::MqttSink(const MqttCliOptions& o, const std::string& source, const std::string& twin, const std::string& program, long run)
    : pub_(nullptr, &destroy_publisher),
      source_(source), twin_(twin), program_(program), started_at_(iso_utc(unix_now())), run_(run) {
  if (o.address.empty()) return;
  ui::MqttSettings s = settings_of(o);
  if (const char* pw = std::getenv(kPasswordVariable); pw && *pw) {
    if (o.user.empty())
      throw InvalidArgument(fmt::format("${} is set but --mqtt-user is not: give the user the password belongs to", kPasswordVariable));
    s.password = pw;
  }
  // the will names the run, so that a subscriber knows which monitor was lost
  s.will = nlohmann::ordered_json{{"state", "lost"}, {"source", source_}, {"twin", twin_}, {"started_at", started_at_}}.dump();
  pub_.reset(new ui::MqttPublisher(std::move(s)));
  pub_->publish_status(status_json("monitoring", 0, 0));
  status_every_ = o.status_every;
  last_status_ = std::chrono::steady_clock::now();
}

void MqttSink::tick(long samples, long events, long open_alerts, const std::string& stream) {
  if (!pub_ || !(status_every_ > 0.0)) return;
  const auto now = std::chrono::steady_clock::now();
  if (std::chrono::duration<double>(now - last_status_).count() < status_every_) return;
  last_status_ = now;
  pub_->publish_status(status_json("monitoring", samples, events, open_alerts, stream));
}

MqttSink::~MqttSink() = default;

std::string MqttSink::status_json(const std::string& state, long samples, long events, long open_alerts, const std::string& stream) const {
  nlohmann::ordered_json j{{"state", state}, {"source", source_}, {"twin", twin_}, {"started_at", started_at_}};
  if (!program_.empty()) j["program"] = program_;
  if (run_ > 0) j["run"] = run_;  // the event store's run ('twinwatch events --run N')
  if (state != "monitoring") {
    j["ended_at"] = iso_utc(unix_now());
    j["samples"] = samples;
    j["events"] = events;
  } else if (open_alerts >= 0) {  // (a state while the run goes on, status_every)
    j["updated_at"] = iso_utc(unix_now());
    j["samples"] = samples;
    j["events"] = events;
    j["open_alerts"] = open_alerts;
    if (!stream.empty()) j["stream"] = stream;
  }
  return j.dump();
}

void MqttSink::event(const std::string& fault_class, const std::string& json_line, bool closed, double t_detected) {
  if (!pub_) return;
  if (closed && !closed_.insert(t_detected).second) return;  // (closed again by an error's unwinding)
  pub_->publish_event(fault_class, json_line);
}

void MqttSink::say(bool quiet) {
  if (!pub_) return;
  for (const std::string& n : pub_->take_notes()) {
    const bool trouble = n.rfind("connected", 0) != 0 && n.rfind("reconnected", 0) != 0;
    if (trouble)
      fmt::print(stderr, "warning: mqtt: {}\n", n);
    else if (!quiet)
      fmt::print(stderr, "mqtt: {}\n", n);
  }
}

std::string MqttSink::Undelivered::describe(int wait_ms) const {
  std::vector<std::string> parts;
  if (waiting > 0)
    parts.push_back(gave_up ? fmt::format("{} not taken when the wait was given up", waiting)
                            : fmt::format("{} not taken within {:g} s", waiting, wait_ms / 1000.0));
  if (refused > 0) parts.push_back(fmt::format("{} refused by the broker", refused));
  if (dropped > 0) parts.push_back(fmt::format("{} dropped (the outbox was full, or the client library refused them)", dropped));
  return fmt::format("{} message(s) not delivered: {}", total(), fmt::join(parts, ", "));
}

MqttSink::Undelivered MqttSink::finish(const std::string& state, long samples, long events, int wait_ms, bool quiet,
                                       const std::function<bool()>& give_up) {
  if (!pub_) return {};
  pub_->publish_status(status_json(state, samples, events));
  // (a broker that answers takes it within milliseconds: only a longer wait is said)
  constexpr int kSilentWaitMs = 500;
  long left = pub_->drain(std::chrono::milliseconds(std::min(wait_ms, kSilentWaitMs)), give_up);
  if (left > 0 && wait_ms > kSilentWaitMs && !(give_up && give_up())) {
    if (!quiet)
      fmt::print(stderr, "mqtt: waiting up to {:g} s for the broker at {} to take {} message(s) (Ctrl-C gives up)\n", wait_ms / 1000.0,
                 address(), left);
    left = pub_->drain(std::chrono::milliseconds(wait_ms - kSilentWaitMs), give_up);
  }
  say(quiet);
  const ui::MqttCounters c = pub_->counters();
  return {left, c.refused, c.dropped, left > 0 && give_up && give_up()};
}

std::string MqttSink::address() const { return pub_ ? pub_->settings().address() : std::string(); }

#else  // built without MQTT: add_mqtt_options refuses --mqtt, so the sink is never active

namespace {
void destroy_publisher(ui::MqttPublisher*) {}
}  // namespace

MqttSink::MqttSink(const MqttCliOptions&, const std::string&, const std::string&, const std::string&, long) : pub_(nullptr, &destroy_publisher) {}
MqttSink::~MqttSink() = default;
std::string MqttSink::status_json(const std::string&, long, long, long, const std::string&) const { return {}; }
void MqttSink::tick(long, long, long, const std::string&) {}
void MqttSink::event(const std::string&, const std::string&, bool, double) {}
void MqttSink::say(bool) {}
MqttSink::Undelivered MqttSink::finish(const std::string&, long, long, int, bool, const std::function<bool()>&) { return {}; }
std::string MqttSink::Undelivered::describe(int) const { return {}; }
std::string MqttSink::address() const { return {}; }

#endif

}  // namespace twinwatch::cli
