#pragma once
/// @file rtde_client.hpp
/// RTDE client for UR e-Series (and CB3) controllers: output-only, so it coexists with a ROS
/// driver or a PLC that owns the input registers (it never sends SETUP_INPUTS).
///
/// Threads and data flow:
///   socket → reader thread (framing, decoding, gap/jitter bookkeeping) → SpscQueue<RobotSample>
///   → consumer (pop()).
/// The reader thread only ever blocks on the socket. When the consumer falls behind and the queue
/// is full, the newest sample is dropped (counted in ClientStats::dropped) and the next sample that
/// does get through carries gap_before — the socket is never stalled, so the controller never has
/// to skip packages on our account.
///
/// Gaps: the controller `timestamp` (seconds since controller start, one step per control cycle)
/// is the clock. A step larger than 1.5 periods is a gap: the sample after it carries gap_before
/// and round(step·f) − 1 samples are counted as lost. Nothing is interpolated.
///
/// Reconnect: when the connection drops (EOF, error, corrupt stream, or no data for
/// `stall_timeout_ms` while streaming) the reader reconnects with back-off (initial, doubling,
/// capped) and repeats the whole handshake. The first sample afterwards carries gap_before. If the
/// controller restarted, its timestamp starts again near zero; the client then shifts all later
/// timestamps so that the stream stays monotonic, by the wall-clock length of the outage (the
/// lost count for that gap is estimated from the same wall-clock outage).
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "twinwatch/core/sample.hpp"
#include "twinwatch/core/spsc_queue.hpp"
#include "twinwatch/device/rtde_protocol.hpp"

namespace twinwatch::device::rtde {

/// "HOST[:PORT]" → host and port (30004 when absent). Throws InvalidArgument on a bad port.
void parse_endpoint(const std::string& endpoint, std::string& host, std::uint16_t& port);

/// The outputs the recording format has columns for, in recording order.
const std::vector<std::string>& default_outputs();

struct ClientOptions {
  std::string host = "127.0.0.1";
  std::uint16_t port = kDefaultPort;
  double frequency = 500.0;  ///< requested output rate [Hz] (v2; a v1 controller sends at its own rate)
  std::vector<std::string> outputs = default_outputs();
  std::size_t queue_capacity = 8192;  ///< samples buffered for a slow consumer (16 s at 500 Hz)
  int connect_timeout_ms = 1000;
  int reply_timeout_ms = 2000;  ///< per handshake reply
  int stall_timeout_ms = 1000;  ///< no data for this long (or three sample periods, if longer) while streaming = connection lost
  double backoff_initial_s = 0.1;
  double backoff_max_s = 5.0;
  bool reconnect = true;  ///< false: a lost connection ends the stream
  int max_protocol = 2;   ///< 1 forces the v1 protocol (tests, old controllers)
};

/// A recipe the controller refused (NOT_FOUND / IN_USE by name) or another error that a retry
/// cannot fix; ends the client.
class RecipeError : public ProtocolError {
 public:
  using ProtocolError::ProtocolError;
};

struct ClientStats {
  bool connected = false;
  int protocol = 0;
  ControllerVersion controller;
  double frequency = 0.0;    ///< rate the controller streams at (v1: its full rate)
  long received = 0;         ///< data packages decoded
  long delivered = 0;        ///< samples handed to the queue
  long dropped = 0;          ///< samples dropped because the queue was full (slow consumer)
  long lost = 0;             ///< samples missing from the controller's timestamp sequence
  long gaps = 0;             ///< gaps (timestamp jumps or reconnects)
  long reconnects = 0;       ///< successful handshakes after the first
  long protocol_errors = 0;  ///< malformed packages (skipped) and corrupt streams (reconnected)
  long repeated = 0;         ///< packages with the previous one's controller timestamp (resends: not delivered)
  long text_messages = 0;
  double max_step_error_s = 0.0;   ///< largest |timestamp step − period| outside gaps
  double arrival_p99_s = 0.0;      ///< 99th percentile of |arrival interval − period|
  double arrival_max_s = 0.0;
  double arrival_interval_s = 0.0; ///< mean wall-clock interval between consecutive samples (outside gaps); 0 before two
  /// Whether arrival_p99_s / arrival_max_s mean jitter: false when samples arrive at another pace
  /// than the controller's period (a virtual robot served faster or slower than real time), where
  /// |interval − period| measures the pace, not the network.
  bool arrival_jitter_valid() const {
    return frequency > 0.0 && arrival_interval_s > 0.0 && std::abs(arrival_interval_s * frequency - 1.0) <= 0.1;
  }
  double cpu_seconds = 0.0;        ///< CPU time used by the reader thread
  double wall_seconds = 0.0;       ///< since start()
  std::string last_error;
};

class Client {
 public:
  explicit Client(ClientOptions options);
  ~Client();
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  /// Connects and handshakes in the calling thread, then starts the reader thread.
  /// Throws tcp-level errors (std::runtime_error naming host:port) if the first connection fails,
  /// RecipeError for NOT_FOUND names, ProtocolError if the controller speaks neither v2 nor v1.
  void start();
  /// Sends PAUSE, closes, joins the reader. Idempotent.
  void stop();

  /// Next sample, waiting up to `timeout`. False on timeout or when the stream has ended and the
  /// queue is empty (check finished()).
  bool pop(RobotSample& out, std::chrono::nanoseconds timeout);
  /// The reader has stopped for good (stop(), a fatal error, or reconnect disabled).
  bool finished() const { return finished_.load(std::memory_order_acquire); }
  /// The fatal error that ended the stream, if any.
  std::string fatal_error() const;

  /// Called from the reader thread for every text message the controller sends.
  void on_text(std::function<void(const TextMessage&)> callback) { on_text_ = std::move(callback); }

  ClientStats stats() const;
  /// The recipe of the current connection (a copy: the reader replaces it on reconnect).
  OutputRecipe recipe() const;
  /// SampleField flags that the recipe fills.
  std::uint32_t sample_fields() const { return fields_; }
  const ClientOptions& options() const { return opt_; }

 private:
  void handshake(int fd);
  void read_loop();
  void stream(int fd);
  void handle_data(const Package& p, std::chrono::steady_clock::time_point arrival);
  void build_mapping();

  ClientOptions opt_;
  OutputRecipe recipe_;  // written by handshake(), read by the reader; copies under mutex_
  Framer framer_;
  double period_ = 0.002;  // of the stream actually delivered [s]
  std::uint32_t fields_ = 0;
  struct Slot {
    int value_index;
    int target;
  };
  std::vector<Slot> mapping_;
  std::vector<double> values_;
  SpscQueue<RobotSample> queue_;
  std::function<void(const TextMessage&)> on_text_;

  int fd_ = -1;
  std::thread reader_;
  std::atomic<bool> stop_{false}, finished_{false};
  std::chrono::steady_clock::time_point started_;

  // reader-thread state
  bool have_last_ = false, pending_gap_ = false;
  std::uint32_t pending_dropped_ = 0;  // samples dropped (queue full) since the last one delivered
  double last_raw_ts_ = 0.0, last_ts_ = 0.0, ts_offset_ = 0.0;
  std::chrono::steady_clock::time_point last_arrival_{}, lost_at_{};
  double arrival_interval_sum_ = 0.0;  // wall seconds over the counted intervals (those in arrival_hist_)
  bool reconnected_ = false;

  mutable std::mutex mutex_;  // guards stats_, fatal_
  ClientStats stats_;
  std::vector<std::uint32_t> arrival_hist_;  // 10 µs bins of |interval − period|
  std::string fatal_;
};

}  // namespace twinwatch::device::rtde
