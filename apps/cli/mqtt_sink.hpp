#pragma once
// monitor's and serve's --mqtt: the events and the run's state to an MQTT broker (ui::MqttPublisher;
// topics and delivery in include/twinwatch/ui/mqtt.hpp, for users in docs/events.md).
#include <CLI/CLI.hpp>

#include <chrono>

#include <functional>
#include <memory>
#include <set>
#include <string>

namespace twinwatch::ui {
class MqttPublisher;
}

namespace twinwatch::cli {

/// What the command line says of the broker.
struct MqttCliOptions {
  std::string address;  ///< --mqtt HOST[:PORT] ("": no MQTT)
  std::string topic = "twinwatch", user, cafile, client_id;
  int qos = 1;
  int keepalive = 30;  ///< [s]
  double status_every = 10.0;  ///< [s] of wall-clock time between the run's states while it runs (0: at the start and end only)
};

/// Adds --mqtt, --mqtt-topic, --mqtt-qos, --mqtt-user, --mqtt-cafile, --mqtt-client-id to `sub`;
/// returns the check to run in the verb's callback (the --mqtt-* options need --mqtt; a build
/// without MQTT refuses --mqtt).
std::function<void()> add_mqtt_options(CLI::App* sub, MqttCliOptions& o);

/// The run's events and state on the broker, for monitor's loop. Does nothing when --mqtt is not given.
class MqttSink {
 public:
  /// Starts the publisher (it connects in the background: an unreachable broker is a note, not a
  /// stop) and publishes the state "monitoring". The password comes from $TWINWATCH_MQTT_PASSWORD
  /// (the command line is visible to every user of the machine). Throws InvalidArgument for
  /// settings out of range.
  MqttSink(const MqttCliOptions& o, const std::string& source, const std::string& twin, const std::string& program, long run);
  ~MqttSink();
  bool active() const { return pub_ != nullptr; }
  /// An event's JSON line (as --events writes it) to TOPIC/events/CLASS. A closed event is published
  /// once: the same alert closed again (an error that unwinds the run closes what it finds open)
  /// is not published twice.
  void event(const std::string& fault_class, const std::string& json_line, bool closed = false, double t_detected = 0.0);
  /// Prints what the publisher has to say (connected, lost, refused) on stderr as warnings or
  /// notes; call it from the loop now and then (about once a second) and at the end.
  void say(bool quiet);
  /// While the run goes on: the state "monitoring" with its counts (`samples` watched, `events` so
  /// far, `open_alerts` now, the live stream's counters or ""), retained on TOPIC/status, when
  /// status_every seconds of wall-clock time have passed since the last; call it often (each second of
  /// samples, and while a live stream is silent). A control room sees the counts move, or stop.
  void tick(long samples, long events, long open_alerts, const std::string& stream);
  /// What the broker did not get by the end.
  struct Undelivered {
    long waiting = 0;  ///< not taken within the wait
    long refused = 0;  ///< refused by the broker (MQTT 5: an access list, ...)
    long dropped = 0;  ///< dropped: the outbox was full, or the client library refused one
    bool gave_up = false;  ///< the wait was given up (Ctrl-C)
    long total() const { return waiting + refused + dropped; }
    /// "3 message(s) not delivered: 2 not taken within 10 s, 1 refused by the broker"
    std::string describe(int wait_ms) const;
  };
  /// The final state ("finished", "stopped", "connection lost", "failed") with the counts, then waits
  /// up to `wait_ms` for the broker to take what waits, or until `give_up` (Ctrl-C; may be empty).
  Undelivered finish(const std::string& state, long samples, long events, int wait_ms, bool quiet,
                     const std::function<bool()>& give_up = {});
  /// "HOST:PORT" for messages.
  std::string address() const;

 private:
  // (a deleter of its own: a build without MQTT has no MqttPublisher to destroy)
  std::unique_ptr<ui::MqttPublisher, void (*)(ui::MqttPublisher*)> pub_;
  std::string source_, twin_, program_, started_at_;
  long run_ = 0;
  std::set<double> closed_;  // the raise times of the closed events published
  std::string status_json(const std::string& state, long samples, long events, long open_alerts = -1, const std::string& stream = "") const;
  double status_every_ = 0.0;
  std::chrono::steady_clock::time_point last_status_;
};

}  // namespace twinwatch::cli
