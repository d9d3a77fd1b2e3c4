#pragma once
/// @file rtde_server.hpp
/// The virtual controller's RTDE side: it answers any RTDE client exactly as a UR e-Series
/// controller does (fact sheet ../shared/reference/rtde-protocol.md §10) and streams whatever
/// frames its owner publishes — in `twinwatch serve-robot`, the simulator at 500 Hz.
///
/// Behaviour (each choice where the fact sheet is silent is marked "ours"):
///  - protocol v2 and v1 accepted, anything else refused (accepted = 0); clients that ignore the
///    reply (ur_rtde) work because v2 is the default;
///  - 'v' answers the configured controller version (default 5.23.0.0);
///  - SETUP_OUTPUTS: one type per name in order, NOT_FOUND for unknown names, a trailing comma
///    ignored; recipe ids count 1, 2, ... per connection; a failed setup answers recipe id 0 (ours)
///    and installs nothing; 0 < frequency ≤ base rate, 0 means the base rate (as URCL assumes);
///    a setup while streaming is refused with a text message (ours);
///  - SETUP_INPUTS: known input names get types and a recipe id, unknown ones NOT_FOUND; input
///    data packages are checked and otherwise ignored (the virtual robot takes no commands);
///  - START without an output recipe → accepted = 0; START / PAUSE / START works;
///  - malformed payloads of known types and unknown package types are answered with an ERROR
///    text message and the connection carries on; a corrupt size field closes it (a TCP stream
///    cannot be resynchronised);
///  - a client that does not read fast enough gets the newest data only: packages that do not fit
///    the socket buffer are skipped, as the real controller does (fact sheet §7).
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "twinwatch/device/rtde_protocol.hpp"

namespace twinwatch::device::rtde {

/// One client connection's protocol state, without the socket (unit-tested and fuzzed directly).
class ServerSession {
 public:
  /// @param max_protocol 2, or 1 to behave like an old controller that refuses v2.
  ServerSession(ControllerVersion version, double base_frequency, int max_protocol = 2);

  /// Feeds received bytes; appends replies to `out`. Throws ProtocolError when the stream is
  /// corrupt and the connection must close.
  void on_bytes(const std::uint8_t* data, std::size_t n, Bytes& out);
  /// One controller cycle: appends a data package to `out` if streaming and due at this rate.
  bool on_cycle(const double* frame, Bytes& out);

  bool streaming() const { return streaming_; }
  int protocol() const { return protocol_; }
  long errors() const { return errors_; }
  const std::vector<TextMessage>& messages_received() const { return messages_; }
  const ServerRecipe* output_recipe() const { return has_recipe_ ? &recipe_ : nullptr; }
  double frequency() const { return frequency_; }

 private:
  void handle(const Package& p, Bytes& out);
  void error_text(Bytes& out, const std::string& what);

  ControllerVersion version_;
  double base_frequency_;
  int max_protocol_;
  int protocol_ = 2;  // until negotiated: ur_rtde never waits for the reply (fact sheet §4)
  Framer framer_;
  bool streaming_ = false, has_recipe_ = false;
  ServerRecipe recipe_;
  double frequency_ = 0.0, phase_ = 0.0;
  std::uint8_t next_output_id_ = 1, next_input_id_ = 1;
  std::vector<std::vector<const FieldInfo*>> input_recipes_;  // index = id - 1
  long errors_ = 0;
  std::vector<TextMessage> messages_;
};

struct ServerOptions {
  std::string bind = "127.0.0.1";  ///< "0.0.0.0" to serve other machines
  std::uint16_t port = kDefaultPort;  ///< 0: an ephemeral port (tests)
  ControllerVersion version{5, 23, 0, 0};
  double base_frequency = 500.0;  ///< e-Series control rate [Hz]
  int max_protocol = 2;           ///< 1: refuse v2 like an old controller (tests of v1 fallback)
};

struct ServerStats {
  int clients = 0;           ///< connected now
  int streaming = 0;         ///< of which started (START accepted)
  long connections = 0;      ///< accepted since start
  long packages_sent = 0;    ///< data packages
  long packages_skipped = 0; ///< data packages not sent because a client's socket was full
  long protocol_errors = 0;
  long cycles = 0;
};

/// TCP server: an accept thread, a reader thread per client, and publish() from the owner's
/// control loop. Thread-safe.
class Server {
 public:
  explicit Server(ServerOptions options);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// Binds and starts accepting. Throws std::runtime_error naming the address if it cannot.
  void start();
  /// Closes every connection and the listening socket; joins all threads. Idempotent.
  void stop();
  std::uint16_t port() const { return port_; }

  /// One controller cycle: `frame` holds frame_scalars() values (see output_fields()); every
  /// streaming client whose rate is due gets a data package. Never blocks on a slow client.
  void publish(const double* frame);
  /// Sends a text message to every connected client.
  void broadcast(const TextMessage& m);
  ServerStats stats() const;

 private:
  struct Connection;
  void accept_loop();
  void client_loop(std::shared_ptr<Connection> c);
  void reap();

  ServerOptions opt_;
  int listen_fd_ = -1;
  std::uint16_t port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread accept_thread_;
  mutable std::mutex mutex_;  // guards conns_ and stats_
  std::vector<std::shared_ptr<Connection>> conns_;
  ServerStats stats_;
};

}  // namespace twinwatch::device::rtde
