#pragma once
/// @file mqtt.hpp
/// Events to a plant's MQTT broker (DESIGN.md, "MQTT / event store"): the monitor's event lines and
/// its run's state, published as they happen, for a line's PLC gateway, SCADA or maintenance system.
///
/// Topics under a prefix P (default "twinwatch"):
/// - `P/events/CLASS` (CLASS: collision, resistance, payload_change, ...): each event's JSON line, the
///   same bytes `monitor --events` writes (with `--events-open` also the lines of open alerts);
///   QoS 1 by default, not retained.
/// - `P/status`: the run's state as JSON ("monitoring", then "finished", "stopped", "connection lost"
///   or "failed"), retained, so a subscriber that comes later sees it; the broker publishes the last
///   will `{"state":"lost",...}` there when the monitor's connection ends without a goodbye (the
///   process killed, the machine down, the network cut for longer than 1.5 keep-alive periods).
///
/// Delivery: publishing never blocks the monitoring loop. Messages wait in an outbox until the
/// network thread hands them to libmosquitto, and are counted until the broker acknowledges them
/// (QoS 1 and 2; QoS 0: until written). MQTT 5 is spoken (3.1.1 with a broker that has only that),
/// so that a broker that refuses a message (an access list: reason code 135) says so and the message
/// counts as refused, not delivered. A broker that cannot be reached at the start, or is lost later,
/// is retried every 1-30 s (doubling; at once after a connection that lasted 5 s) while the outbox
/// keeps what waits; at most `outbox_limit` messages wait (the oldest event lines dropped first and
/// counted; the status keeps only its newest), and at most 1000 are in the library's hands. After a
/// reconnection the newest state is published again (the broker may have published the last will
/// meanwhile).
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace twinwatch::ui {

/// Where and how to publish.
struct MqttSettings {
  std::string host;               ///< broker host name or address (required)
  int port = 0;                   ///< 0: 1883, or 8883 with TLS
  std::string topic = "twinwatch";  ///< topic prefix: no wildcard ('+', '#'), no empty level, no leading or trailing '/', no leading '$'
  int qos = 1;                    ///< 0, 1 or 2
  std::string client_id;          ///< "" : "twinwatch-HOSTNAME-PID"
  std::string username;           ///< "" : none
  std::string password;           ///< with username only (the CLI reads it from the environment, not the command line)
  std::string cafile;             ///< TLS: the CA certificate (PEM) that signed the broker's; "" : plain TCP
  int keepalive_s = 30;           ///< [s] 5 .. 3600: how soon the broker publishes the last will after a silent loss
  std::size_t outbox_limit = 10000;  ///< messages kept while the broker is away (>= 1)
  /// the last will's JSON (published by the broker on `P/status`); "" : {"state":"lost"}
  std::string will;

  /// The port that will be used (port, else 1883 / 8883 with TLS).
  int effective_port() const { return port > 0 ? port : cafile.empty() ? 1883 : 8883; }
  /// "host:port" for messages.
  std::string address() const;
  /// Throws InvalidArgument naming the first field out of range (host empty, port beyond 1..65535,
  /// a topic with a wildcard, an empty level, a control character or a leading '$', qos, keepalive,
  /// outbox_limit, a password without a user, a cafile that cannot be read, a client id that is not
  /// UTF-8 of up to 65535 bytes without control characters).
  void validate() const;
};

/// "HOST[:PORT]" (an IPv6 address in brackets: "[::1]:1883") into `s.host` and `s.port`. Throws
/// InvalidArgument naming `option` and the text for an empty host or a port that is not 1..65535.
void parse_mqtt_address(const std::string& text, MqttSettings& s, const std::string& option = "--mqtt");

/// What the publisher has done so far (a snapshot).
struct MqttCounters {
  long published = 0;   ///< messages handed to the publisher
  long delivered = 0;   ///< acknowledged by the broker (QoS 0: written to its socket)
  long dropped = 0;     ///< event lines dropped: the outbox was full, or the client library refused one
  long refused = 0;     ///< refused by the broker (MQTT 5 reason code >= 0x80, e.g. 135 not authorised)
  long superseded = 0;  ///< states replaced by a newer one before they were sent
  long waiting = 0;     ///< in the outbox or in flight
  long connects = 0;    ///< successful connections (1 + reconnections)
  bool connected = false;
};

/// Publishes to one broker from a thread of its own (libmosquitto driven by our loop).
class MqttPublisher {
 public:
  /// Starts the network thread, which connects (asynchronously: an unreachable broker does not
  /// delay the caller) and publishes the outbox. Throws InvalidArgument (settings.validate()).
  explicit MqttPublisher(MqttSettings settings);
  /// Disconnects cleanly (the broker then does not publish the will) and stops the thread; what is
  /// still waiting is given up: call drain() first to deliver it. Waits at most 3 s for the thread: one
  /// held in a host name lookup (the C library's resolver cannot be interrupted) is left to end with
  /// the process.
  ~MqttPublisher();
  MqttPublisher(const MqttPublisher&) = delete;
  MqttPublisher& operator=(const MqttPublisher&) = delete;

  /// Queues an event line for `P/events/<fault_class>`. Thread-safe, never blocks on the network.
  void publish_event(const std::string& fault_class, const std::string& json_line);
  /// Queues the run's state for `P/status` (retained); replaces a status still waiting.
  void publish_status(const std::string& json);
  /// Waits up to `timeout` until everything queued so far is delivered, or until `give_up` (polled
  /// every 100 ms; may be empty) says to stop; returns how many messages are still waiting (0: none).
  long drain(std::chrono::milliseconds timeout, const std::function<bool()>& give_up = {});
  /// Notes for the user since the last call, oldest first ("connected to ...", "cannot reach ...:
  /// Connection refused; retrying ...", "the broker refused the connection: not authorised"): the
  /// library prints nothing (STYLE.md), the application prints these.
  std::vector<std::string> take_notes();
  MqttCounters counters() const;
  const MqttSettings& settings() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace twinwatch::ui
