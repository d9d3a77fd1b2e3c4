#include "twinwatch/device/rtde_client.hpp"

#include <fmt/format.h>
#include <sys/resource.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>

#include "tcp.hpp"
#include "twinwatch/core/error.hpp"
#include "twinwatch/core/log.hpp"

namespace twinwatch::device::rtde {

namespace {

using Clock = std::chrono::steady_clock;

// Where a recipe field goes in a RobotSample.
enum Target : int {
  kTimestamp,
  kQ,
  kQd,
  kTargetQ,
  kTargetQd,
  kTargetQdd,
  kCurrent,
  kTargetCurrent,
  kTargetMoment,
  kTemperature,
  kDigitalOutputs,
  kRobotMode,
  kSafetyMode,
  kPayload,
  kPayloadCog,
  kNone,
};

struct TargetInfo {
  const char* name;
  Target target;
  std::uint32_t field;
};
constexpr TargetInfo kTargets[] = {
    {"timestamp", kTimestamp, 0},
    {"actual_q", kQ, 0},
    {"actual_qd", kQd, kFieldActualQd},
    {"target_q", kTargetQ, kFieldTargetQ},
    {"target_qd", kTargetQd, kFieldTargetQd},
    {"target_qdd", kTargetQdd, kFieldTargetQdd},
    {"actual_current", kCurrent, kFieldActualCurrent},
    {"target_current", kTargetCurrent, kFieldTargetCurrent},
    {"target_moment", kTargetMoment, kFieldTargetMoment},
    {"joint_temperatures", kTemperature, kFieldTemperature},
    {"actual_digital_output_bits", kDigitalOutputs, kFieldDigitalOutputs},
    {"robot_mode", kRobotMode, kFieldRobotMode},
    {"safety_mode", kSafetyMode, kFieldSafetyMode},
    {"payload", kPayload, 0},  // kFieldPayload once payload_cog is in the recipe too (build_mapping)
    {"payload_cog", kPayloadCog, 0},
};

// Outputs a controller streams only from some version on: asked for only then, so that the default
// recipe works on every controller (an unknown name makes the whole recipe NOT_FOUND). payload and
// payload_cog: 5.5.1 ([URRTDE] RTDEReceiveInterface asks for them from there; fact sheet §10).
struct VersionGate {
  const char* name;
  ControllerVersion since;
};
constexpr VersionGate kVersionGates[] = {{"payload", {5, 5, 1, 0}}, {"payload_cog", {5, 5, 1, 0}}};

bool at_least(const ControllerVersion& v, const ControllerVersion& since) {
  if (v.major != since.major) return v.major > since.major;
  if (v.minor != since.minor) return v.minor > since.minor;
  return v.bugfix >= since.bugfix;
}

constexpr int kHistBins = 2000;  // 10 µs bins up to 20 ms
constexpr double kHistBin = 10e-6;
constexpr int kStillTryingEvery = 30;  // [s] between "still no connection" warnings while reconnecting

double cpu_seconds_this_thread() {
  rusage u{};
  ::getrusage(RUSAGE_THREAD, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

int ms_left(Clock::time_point deadline) {
  return static_cast<int>(std::max<long>(0, std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count()));
}

}  // namespace

void parse_endpoint(const std::string& endpoint, std::string& host, std::uint16_t& port) {
  tcp::parse_endpoint(endpoint, host, port, kDefaultPort);
}

const std::vector<std::string>& default_outputs() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const auto& t : kTargets) v.emplace_back(t.name);
    return v;
  }();
  return names;
}

Client::Client(ClientOptions options) : opt_(std::move(options)), queue_(std::max<std::size_t>(1, opt_.queue_capacity)) {
  if (!(opt_.frequency > 0.0) || opt_.frequency > 500.0)
    throw InvalidArgument(fmt::format("RTDE output frequency must be in (0, 500] Hz, got {}", opt_.frequency));
  if (opt_.outputs.empty()) throw InvalidArgument("RTDE output recipe is empty: give at least one output name");
  if (opt_.max_protocol != 1 && opt_.max_protocol != 2)
    throw InvalidArgument(fmt::format("RTDE protocol must be 1 or 2, got {}", opt_.max_protocol));
  std::size_t bytes = 0;
  for (const auto& n : opt_.outputs) bytes += n.size() + 1;
  if (bytes > kMaxNameListBytes)
    throw InvalidArgument(fmt::format("RTDE output recipe names take {} bytes; the controller accepts at most {}", bytes, kMaxNameListBytes));
  arrival_hist_.assign(kHistBins + 1, 0);
}

Client::~Client() { stop(); }

// ---- handshake ----------------------------------------------------------------------------

namespace {

// Reads packages until one of type `want` arrives; text messages on the way are delivered,
// stale data packages (from a previous recipe) are skipped.
class Replies {
 public:
  // (`cancel`: a client being stopped gives up the wait within 50 ms; without it a controller that
  // accepts the connection and never answers held stop() for up to a reply timeout per reply: a
  // live monitor's --duration 8 ran 9.7 s on a stalled stream)
  Replies(int fd, Framer& framer, const std::function<void(const TextMessage&)>& on_text, int protocol, const std::atomic<bool>* cancel)
      : fd_(fd), framer_(framer), on_text_(on_text), protocol_(protocol), cancel_(cancel) {}

  // Returns the payload copy of the reply.
  Bytes wait(PackageType want, int timeout_ms) {
    const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
    std::uint8_t buf[4096];
    for (;;) {
      Package p;
      while (framer_.next(p)) {
        if (p.type == static_cast<std::uint8_t>(want)) return Bytes(p.payload.begin(), p.payload.end());
        if (p.type == static_cast<std::uint8_t>(PackageType::TextMessage)) {
          try {
            const TextMessage m = decode_text_message(p, protocol_);
            if (on_text_) on_text_(m);
            log::info(fmt::format("rtde: controller says ({}): {}", level_name(m.level), m.message));
          } catch (const ProtocolError& e) {
            log::warn(fmt::format("rtde: {}", e.what()));
          }
        }
      }
      const int left = ms_left(deadline);
      if (left <= 0)
        throw tcp::ConnectError(fmt::format("no {} reply within {} ms", package_name(static_cast<std::uint8_t>(want)), timeout_ms));
      if (cancel_ && cancel_->load()) throw tcp::ConnectError("stopped during the handshake");
      if (!tcp::wait_readable(fd_, cancel_ ? std::min(left, 50) : left)) continue;
      const ssize_t k = ::recv(fd_, buf, sizeof buf, 0);
      if (k == 0) throw tcp::ConnectError("controller closed the connection during the handshake");
      if (k < 0) {
        if (errno == EINTR || errno == EAGAIN) continue;
        throw tcp::ConnectError(fmt::format("recv: {}", std::strerror(errno)));
      }
      framer_.feed(buf, static_cast<std::size_t>(k));
    }
  }
  void set_protocol(int p) { protocol_ = p; }

 private:
  int fd_;
  Framer& framer_;
  const std::function<void(const TextMessage&)>& on_text_;
  int protocol_;
  const std::atomic<bool>* cancel_;
};

void send_or_throw(int fd, const Bytes& b, int timeout_ms) {
  if (!tcp::send_all(fd, b.data(), b.size(), timeout_ms)) throw tcp::ConnectError("send failed: connection lost");
}

Package as_package(PackageType t, const Bytes& payload) { return Package{static_cast<std::uint8_t>(t), payload}; }

}  // namespace

// Runs the handshake on a fresh connection. On success `recipe_` is set and streaming has begun;
// packages that arrived after the START reply stay in `framer` for stream().
static OutputRecipe run_handshake(int fd, const ClientOptions& opt, Framer& framer,
                                  const std::function<void(const TextMessage&)>& on_text, int& protocol,
                                  ControllerVersion& version, const std::atomic<bool>* cancel) {
  framer.clear();
  Replies replies(fd, framer, on_text, 2, cancel);
  Bytes out;
  protocol = 0;
  for (int v = opt.max_protocol; v >= 1 && protocol == 0; --v) {
    out.clear();
    encode_request_protocol_version(out, static_cast<std::uint16_t>(v));
    send_or_throw(fd, out, opt.reply_timeout_ms);
    const Bytes r = replies.wait(PackageType::RequestProtocolVersion, opt.reply_timeout_ms);
    if (decode_accepted_reply(as_package(PackageType::RequestProtocolVersion, r))) protocol = v;
  }
  if (protocol == 0) throw RecipeError("the controller accepts neither RTDE protocol 2 nor 1");
  replies.set_protocol(protocol);

  out.clear();
  encode_get_urcontrol_version(out);
  send_or_throw(fd, out, opt.reply_timeout_ms);
  version = decode_urcontrol_version_reply(as_package(PackageType::GetUrcontrolVersion, replies.wait(PackageType::GetUrcontrolVersion, opt.reply_timeout_ms)));

  // outputs this controller does not have yet are left out of the recipe (said once per connection)
  std::vector<std::string> outputs;
  for (const std::string& name : opt.outputs) {
    const auto gate = std::find_if(std::begin(kVersionGates), std::end(kVersionGates), [&](const VersionGate& g) { return name == g.name; });
    if (gate != std::end(kVersionGates) && !at_least(version, gate->since)) {
      log::info(fmt::format("rtde: controller {}.{}.{} has no output '{}' (from {}.{}.{} on): not asked for", version.major, version.minor,
                            version.bugfix, name, gate->since.major, gate->since.minor, gate->since.bugfix));
      continue;
    }
    outputs.push_back(name);
  }
  if (outputs.empty())
    throw RecipeError(fmt::format("controller {}.{}.{} has none of the outputs asked for", version.major, version.minor, version.bugfix));
  out.clear();
  encode_setup_outputs(out, protocol, opt.frequency, outputs);
  send_or_throw(fd, out, opt.reply_timeout_ms);
  const SetupReply reply =
      decode_setup_reply(as_package(PackageType::SetupOutputs, replies.wait(PackageType::SetupOutputs, opt.reply_timeout_ms)), protocol);
  OutputRecipe recipe;
  try {
    recipe = OutputRecipe::from_reply(outputs, reply, protocol);
  } catch (const ProtocolError& e) {
    throw RecipeError(e.what());  // NOT_FOUND / IN_USE: retrying cannot help
  }
  if (protocol >= 2 && reply.recipe_id == 0) throw RecipeError("the controller refused the output recipe (recipe id 0)");

  out.clear();
  encode_start(out);
  send_or_throw(fd, out, opt.reply_timeout_ms);
  if (!decode_accepted_reply(as_package(PackageType::Start, replies.wait(PackageType::Start, opt.reply_timeout_ms))))
    throw tcp::ConnectError("the controller refused RTDE_CONTROL_PACKAGE_START");
  return recipe;
}

void Client::handshake(int fd) {
  int protocol = 0;
  ControllerVersion version;
  OutputRecipe recipe = run_handshake(fd, opt_, framer_, on_text_, protocol, version, &stop_);
  // Rate actually streamed: v1 always sends at the controller's full rate; CB3 (major < 5) tops
  // out at 125 Hz, e-Series at 500 Hz (fact sheet §7).
  const double max_rate = version.major >= 5 ? 500.0 : 125.0;
  const double rate = protocol >= 2 ? std::min(opt_.frequency, max_rate) : max_rate;
  std::lock_guard<std::mutex> lock(mutex_);
  recipe_ = std::move(recipe);
  values_.assign(static_cast<std::size_t>(recipe_.values), std::numeric_limits<double>::quiet_NaN());
  build_mapping();
  period_ = 1.0 / rate;
  stats_.frequency = rate;
  stats_.protocol = protocol;
  stats_.controller = version;
  stats_.connected = true;
}

void Client::build_mapping() {
  mapping_.clear();
  fields_ = kFieldStreamGap;  // the client marks its own gaps (lost samples, reconnects)
  for (std::size_t i = 0; i < recipe_.names.size(); ++i) {
    for (const auto& t : kTargets) {
      if (recipe_.names[i] != t.name) continue;
      mapping_.push_back({recipe_.value_index[i], t.target});
      fields_ |= t.field;
    }
  }
  // the declared payload is its mass and centre of mass together (a recording has both or neither)
  const auto has = [&](Target t) { return std::any_of(mapping_.begin(), mapping_.end(), [&](const Slot& m) { return m.target == t; }); };
  if (has(kPayload) && has(kPayloadCog)) fields_ |= kFieldPayload;
}

// ---- start / stop -------------------------------------------------------------------------

void Client::start() {
  if (reader_.joinable()) return;
  started_ = Clock::now();
  stop_ = false;
  finished_ = false;
  fd_ = tcp::connect(opt_.host, opt_.port, opt_.connect_timeout_ms);
  try {
    handshake(fd_);
  } catch (const tcp::ConnectError& e) {
    tcp::close(fd_);
    throw tcp::ConnectError(fmt::format("RTDE handshake with {}:{} failed: {}", opt_.host, opt_.port, e.what()));
  } catch (const RecipeError&) {
    tcp::close(fd_);
    throw;
  } catch (const ProtocolError& e) {
    // (a server that answers at once with something else, an HTTP or SSH banner, is named with its
    // address and the step it failed at)
    tcp::close(fd_);
    throw ProtocolError(fmt::format("RTDE handshake with {}:{} failed: {} (is it an RTDE server? a UR controller serves RTDE on "
                                    "port 30004)",
                                    opt_.host, opt_.port, e.what()));
  } catch (...) {
    tcp::close(fd_);
    throw;
  }
  const ClientStats st = stats();
  log::info(fmt::format("rtde: connected to {}:{} (controller {}.{}.{}, protocol v{}, {} outputs at {} Hz)", opt_.host,
                        opt_.port, st.controller.major, st.controller.minor, st.controller.bugfix, st.protocol,
                        recipe_.names.size(), st.frequency));
  // the rate asked for is not the one streamed: v1 sends at the controller's full rate, and a CB3
  // controller tops out at 125 Hz
  if (std::abs(st.frequency - opt_.frequency) > 1e-9)
    log::warn(fmt::format("rtde: {:g} Hz was asked for and the controller streams at {:g} Hz ({})", opt_.frequency, st.frequency,
                          st.protocol < 2 ? "protocol v1 has no rate of its own: it sends at the controller's full rate"
                                          : "the most this controller sends"));
  reader_ = std::thread([this] { read_loop(); });
}

void Client::stop() {
  stop_ = true;
  if (reader_.joinable()) reader_.join();
  tcp::close(fd_);
  finished_ = true;
}

OutputRecipe Client::recipe() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return recipe_;
}

std::string Client::fatal_error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return fatal_;
}

bool Client::pop(RobotSample& out, std::chrono::nanoseconds timeout) {
  if (queue_.try_pop(out)) return true;
  if (finished()) return queue_.try_pop(out);
  return queue_.wait_pop(out, timeout);
}

ClientStats Client::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  ClientStats s = stats_;
  s.wall_seconds = std::chrono::duration<double>(Clock::now() - started_).count();
  long total = 0;
  for (auto c : arrival_hist_) total += c;
  if (total > 0) s.arrival_interval_s = arrival_interval_sum_ / static_cast<double>(total);
  if (total > 0) {
    const long want = static_cast<long>(std::ceil(0.99 * static_cast<double>(total)));
    long acc = 0;
    for (std::size_t b = 0; b < arrival_hist_.size(); ++b) {
      acc += arrival_hist_[b];
      if (acc >= want) {
        s.arrival_p99_s = static_cast<double>(b + 1) * kHistBin;
        break;
      }
    }
  }
  return s;
}

// ---- reader thread ------------------------------------------------------------------------

void Client::read_loop() {
  double backoff = opt_.backoff_initial_s;
  auto warned = Clock::now();  // the last "still no connection" (a user watching the log must see it is still trying)
  while (!stop_) {
    if (fd_ >= 0) {
      stream(fd_);
      tcp::close(fd_);
      {
        std::lock_guard<std::mutex> lock(mutex_);
        stats_.connected = false;
        stats_.cpu_seconds = cpu_seconds_this_thread();
      }
      if (stop_ || !opt_.reconnect) break;
      lost_at_ = Clock::now();
      pending_gap_ = true;
      reconnected_ = true;
      backoff = opt_.backoff_initial_s;
      warned = lost_at_;
    }
    // Back off, then reconnect with the full handshake.
    const auto wake = Clock::now() + std::chrono::duration<double>(backoff);
    while (!stop_ && Clock::now() < wake) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    if (stop_) break;
    try {
      int fd = tcp::connect(opt_.host, opt_.port, opt_.connect_timeout_ms, &stop_);
      try {
        handshake(fd);
      } catch (...) {
        tcp::close(fd);
        throw;
      }
      fd_ = fd;
      std::lock_guard<std::mutex> lock(mutex_);
      ++stats_.reconnects;
      log::info(fmt::format("rtde: reconnected to {}:{}", opt_.host, opt_.port));
    } catch (const RecipeError& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      fatal_ = e.what();
      stats_.last_error = e.what();
      break;
    } catch (const std::exception& e) {
      if (stop_) break;  // (given up because of stop(): the error before it stays the last)
      std::lock_guard<std::mutex> lock(mutex_);
      stats_.last_error = e.what();
      backoff = std::min(opt_.backoff_max_s, backoff * 2.0);
      if (Clock::now() - warned >= std::chrono::seconds(kStillTryingEvery)) {
        warned = Clock::now();
        log::warn(fmt::format("rtde: still no connection to {}:{} after {:.0f} s ({}); retrying every {:.1f} s", opt_.host, opt_.port,
                              std::chrono::duration<double>(warned - lost_at_).count(), e.what(), backoff));
      }
    }
  }
  if (fd_ >= 0 && stop_) {
    Bytes out;
    encode_pause(out);
    tcp::send_all(fd_, out.data(), out.size(), 100);  // best effort: the controller also pauses on disconnect
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.connected = false;
    stats_.cpu_seconds = cpu_seconds_this_thread();
  }
  finished_.store(true, std::memory_order_release);
}

// Streams until the connection ends (or stop()). Returns to the reconnect logic.
void Client::stream(int fd) {
  std::uint8_t buf[16384];
  auto last_data = Clock::now();
  // a link is lost after stall_timeout_ms without data, or three sample periods at a slow rate: at
  // 0.5 Hz the 1 s watchdog fired between every two samples, each "gap" a reconnection (audit of
  // session 38). (period_ is the handshake's, set before this thread streams, as handle_data reads it)
  const auto stall = std::max(std::chrono::duration_cast<Clock::duration>(std::chrono::milliseconds(opt_.stall_timeout_ms)),
                              std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(3.0 * period_)));
  long packages = 0;
  for (;;) {
    // Packages the handshake already buffered come first.
    Package p;
    try {
      while (framer_.next(p)) {
        const auto now = Clock::now();
        if (p.type == static_cast<std::uint8_t>(PackageType::DataPackage)) {
          handle_data(p, now);
          last_data = now;
          if (++packages % 512 == 0) {
            std::lock_guard<std::mutex> lock(mutex_);
            stats_.cpu_seconds = cpu_seconds_this_thread();
          }
        } else if (p.type == static_cast<std::uint8_t>(PackageType::TextMessage)) {
          try {
            const TextMessage m = decode_text_message(p, recipe_.protocol);
            {
              std::lock_guard<std::mutex> lock(mutex_);
              ++stats_.text_messages;
            }
            if (on_text_) on_text_(m);
            log::info(fmt::format("rtde: controller says ({}): {}", level_name(m.level), m.message));
          } catch (const ProtocolError& e) {
            std::lock_guard<std::mutex> lock(mutex_);
            ++stats_.protocol_errors;
            stats_.last_error = e.what();
          }
        }
        // Other replies (PAUSE/START answers, a stray version reply) need no action.
      }
    } catch (const ProtocolError& e) {  // corrupt size field: the stream cannot be re-framed
      std::lock_guard<std::mutex> lock(mutex_);
      ++stats_.protocol_errors;
      stats_.last_error = fmt::format("corrupt RTDE stream from {}:{}: {}", opt_.host, opt_.port, e.what());
      log::warn(stats_.last_error + "; reconnecting");
      framer_.clear();
      return;
    }
    if (stop_) return;
    if (!tcp::wait_readable(fd, 50)) {
      if (Clock::now() - last_data > stall) {
        std::lock_guard<std::mutex> lock(mutex_);
        stats_.last_error = fmt::format("no data from {}:{} for {} ms", opt_.host, opt_.port,
                                        std::chrono::duration_cast<std::chrono::milliseconds>(stall).count());
        log::warn(stats_.last_error + "; reconnecting");
        return;
      }
      continue;
    }
    const ssize_t k = ::recv(fd, buf, sizeof buf, 0);
    if (k == 0 || (k < 0 && errno != EINTR && errno != EAGAIN)) {
      std::lock_guard<std::mutex> lock(mutex_);
      stats_.last_error = k == 0 ? fmt::format("{}:{} closed the connection", opt_.host, opt_.port)
                                 : fmt::format("recv from {}:{}: {}", opt_.host, opt_.port, std::strerror(errno));
      log::warn(stats_.last_error);
      return;
    }
    if (k > 0) framer_.feed(buf, static_cast<std::size_t>(k));
  }
}

void Client::handle_data(const Package& p, Clock::time_point arrival) {
  try {
    decode_data_package(p, recipe_, values_.data());
  } catch (const ProtocolError& e) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.protocol_errors;
    stats_.last_error = e.what();
    return;  // skipped, counted; the stream is still framed
  }
  const double period = period_;
  RobotSample s = RobotSample::empty(6);
  s.present = fields_;
  double raw_ts = std::numeric_limits<double>::quiet_NaN();
  for (const Slot& m : mapping_) {
    const double* v = values_.data() + m.value_index;
    switch (m.target) {
      case kTimestamp: raw_ts = v[0]; break;
      case kQ: s.q = Eigen::Map<const Eigen::VectorXd>(v, 6); break;
      case kQd: s.qd = Eigen::Map<const Eigen::VectorXd>(v, 6); break;
      case kTargetQ: s.target_q = Eigen::Map<const Eigen::VectorXd>(v, 6); break;
      case kTargetQd: s.target_qd = Eigen::Map<const Eigen::VectorXd>(v, 6); break;
      case kTargetQdd: s.target_qdd = Eigen::Map<const Eigen::VectorXd>(v, 6); break;
      case kCurrent: s.current = Eigen::Map<const Eigen::VectorXd>(v, 6); break;
      case kTargetCurrent: s.target_current = Eigen::Map<const Eigen::VectorXd>(v, 6); break;
      case kTargetMoment: s.target_moment = Eigen::Map<const Eigen::VectorXd>(v, 6); break;
      case kTemperature: s.temperature = Eigen::Map<const Eigen::VectorXd>(v, 6); break;
      case kDigitalOutputs: s.digital_outputs = static_cast<std::uint64_t>(v[0]); break;
      case kRobotMode: s.robot_mode = static_cast<std::int32_t>(v[0]); break;
      case kSafetyMode: s.safety_mode = static_cast<std::int32_t>(v[0]); break;
      case kPayload: s.payload = v[0]; break;
      case kPayloadCog: std::copy(v, v + 3, s.payload_cog); break;
      default: break;
    }
  }

  long lost = 0;
  bool gap = pending_gap_;
  double step_error = 0.0;
  if (std::isfinite(raw_ts)) {
    if (!have_last_) {
      ts_offset_ = 0.0;
    } else if (reconnected_) {
      const double outage = std::chrono::duration<double>(arrival - lost_at_).count();
      if (raw_ts + ts_offset_ <= last_ts_) {
        // The controller restarted: its clock began again. Continue from where we were, shifted
        // by the wall-clock outage, and estimate the loss from the same outage.
        ts_offset_ = last_ts_ + std::max(outage, period) - raw_ts;
        lost += std::max(0L, std::lround(outage / period) - 1);
      } else {
        lost += std::max(0L, std::lround((raw_ts + ts_offset_ - last_ts_) / period) - 1);
      }
    } else {
      const double step = raw_ts - last_raw_ts_;
      if (step == 0.0) {
        // the same controller cycle again (a resend): delivered twice it would count twice in
        // every filter and debounce downstream
        std::lock_guard<std::mutex> lock(mutex_);
        ++stats_.received;
        ++stats_.repeated;
        return;
      }
      if (step < 0.0) {
        // Not monotonic without a reconnect: a controller bug or a corrupted value. Keep the
        // sample, mark it, and keep time monotonic.
        ts_offset_ += last_raw_ts_ - raw_ts + period;
        gap = true;
      } else if (step > 1.5 * period) {
        gap = true;
        lost += std::max(0L, std::lround(step / period) - 1);
      } else {
        step_error = std::abs(step - period);
      }
    }
    last_raw_ts_ = raw_ts;
    s.timestamp = raw_ts + ts_offset_;
    last_ts_ = s.timestamp;
    have_last_ = true;
  } else {
    s.timestamp = std::chrono::duration<double>(arrival - started_).count();  // no timestamp in the recipe
  }
  double arrival_interval = -1.0;  // (none across a gap or a reconnection)
  if (last_arrival_.time_since_epoch().count() != 0 && !gap && !reconnected_)
    arrival_interval = std::chrono::duration<double>(arrival - last_arrival_).count();
  last_arrival_ = arrival;
  reconnected_ = false;
  if (lost > 0) gap = true;
  s.gap_before = gap;  // (a sample dropped before this one left pending_gap_ set)
  s.dropped_before = pending_dropped_;

  const bool pushed = queue_.try_push(s);
  pending_gap_ = !pushed;  // a dropped sample makes the next one a gap
  if (pushed) pending_dropped_ = 0;
  else if (pending_dropped_ < UINT32_MAX) ++pending_dropped_;
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.received;
  if (pushed) ++stats_.delivered;
  else ++stats_.dropped;
  stats_.lost += lost;
  if (gap && pushed) ++stats_.gaps;
  stats_.max_step_error_s = std::max(stats_.max_step_error_s, step_error);
  if (arrival_interval >= 0.0) {
    const double arrival_error = std::abs(arrival_interval - period);
    ++arrival_hist_[static_cast<std::size_t>(std::min<double>(kHistBins, arrival_error / kHistBin))];
    stats_.arrival_max_s = std::max(stats_.arrival_max_s, arrival_error);
    arrival_interval_sum_ += arrival_interval;
  }
}

}  // namespace twinwatch::device::rtde
