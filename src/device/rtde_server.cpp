#include "twinwatch/device/rtde_server.hpp"

#include <fmt/format.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>

#include "tcp.hpp"
#include "twinwatch/core/log.hpp"

namespace twinwatch::device::rtde {

// ---- session ------------------------------------------------------------------------------

ServerSession::ServerSession(ControllerVersion version, double base_frequency, int max_protocol)
    : version_(version), base_frequency_(base_frequency), max_protocol_(max_protocol) {}

void ServerSession::on_bytes(const std::uint8_t* data, std::size_t n, Bytes& out) {
  framer_.feed(data, n);
  Package p;
  while (framer_.next(p)) handle(p, out);  // a corrupt size field throws out of here
}

void ServerSession::error_text(Bytes& out, const std::string& what) {
  ++errors_;
  encode_text_message(out, protocol_, {MessageLevel::Error, what, "twinwatch virtual controller"});
}

void ServerSession::handle(const Package& p, Bytes& out) {
  try {
    switch (static_cast<PackageType>(p.type)) {
      case PackageType::RequestProtocolVersion: {
        const std::uint16_t v = decode_request_protocol_version(p);
        const bool ok = v >= 1 && v <= max_protocol_;
        if (ok) protocol_ = v;
        encode_protocol_version_reply(out, ok);
        return;
      }
      case PackageType::GetUrcontrolVersion:
        if (!p.payload.empty()) throw ProtocolError(fmt::format("RTDE_GET_URCONTROL_VERSION: expected an empty payload, got {} bytes", p.payload.size()));
        encode_urcontrol_version_reply(out, version_);
        return;
      case PackageType::SetupOutputs: {
        const SetupRequest req = decode_setup_outputs(p, protocol_);
        if (streaming_) {
          error_text(out, "RTDE_CONTROL_PACKAGE_SETUP_OUTPUTS while streaming: send PAUSE first");
          encode_setup_reply(out, PackageType::SetupOutputs, protocol_, 0, {});
          return;
        }
        std::vector<std::string> types;
        std::vector<const FieldInfo*> fields;
        bool all = !req.names.empty();
        for (const auto& name : req.names) {
          const FieldInfo* f = find_output_field(name);
          types.emplace_back(f ? type_name(f->type) : "NOT_FOUND");
          fields.push_back(f);
          all = all && f;
        }
        double freq = req.frequency;
        if (protocol_ >= 2 && !(freq >= 0.0 && freq <= base_frequency_)) {
          error_text(out, fmt::format("output frequency {} Hz outside 0..{} Hz", freq, base_frequency_));
          all = false;
        }
        if (protocol_ < 2 || freq == 0.0) freq = base_frequency_;
        if (!all) {
          encode_setup_reply(out, PackageType::SetupOutputs, protocol_, 0, types);
          return;
        }
        recipe_.id = next_output_id_++;
        recipe_.fields = std::move(fields);
        recipe_.payload_size = (protocol_ >= 2 ? 1 : 0);
        for (const FieldInfo* f : recipe_.fields) recipe_.payload_size += wire_size(f->type);
        has_recipe_ = true;
        frequency_ = freq;
        phase_ = 1.0 - frequency_ / base_frequency_;  // the first cycle after START sends, then every base/f
        encode_setup_reply(out, PackageType::SetupOutputs, protocol_, recipe_.id, types);
        return;
      }
      case PackageType::SetupInputs: {
        const SetupRequest req = decode_setup_inputs(p);
        std::vector<std::string> types;
        std::vector<const FieldInfo*> fields;
        bool all = !req.names.empty();
        for (const auto& name : req.names) {
          const FieldInfo* f = find_input_field(name);
          types.emplace_back(f ? type_name(f->type) : "NOT_FOUND");
          fields.push_back(f);
          all = all && f;
        }
        std::uint8_t id = 0;
        if (all && next_input_id_ < 255) {
          id = next_input_id_++;
          input_recipes_.push_back(std::move(fields));
        }
        encode_setup_reply(out, PackageType::SetupInputs, protocol_, id, types);
        return;
      }
      case PackageType::Start:
        if (!p.payload.empty()) throw ProtocolError(fmt::format("RTDE_CONTROL_PACKAGE_START: expected an empty payload, got {} bytes", p.payload.size()));
        streaming_ = has_recipe_;
        if (!has_recipe_) error_text(out, "RTDE_CONTROL_PACKAGE_START before any successful SETUP_OUTPUTS");
        encode_accepted_reply(out, PackageType::Start, has_recipe_);
        return;
      case PackageType::Pause:
        if (!p.payload.empty()) throw ProtocolError(fmt::format("RTDE_CONTROL_PACKAGE_PAUSE: expected an empty payload, got {} bytes", p.payload.size()));
        streaming_ = false;
        encode_accepted_reply(out, PackageType::Pause, true);
        return;
      case PackageType::TextMessage:
        messages_.push_back(decode_text_message(p, protocol_));
        if (messages_.size() > 1000) messages_.erase(messages_.begin());
        return;
      case PackageType::DataPackage: {  // input registers from the client
        if (p.payload.empty()) throw ProtocolError("RTDE_DATA_PACKAGE: empty payload, expected an input recipe id");
        const std::uint8_t id = p.payload[0];
        if (id == 0 || id > input_recipes_.size())
          throw ProtocolError(fmt::format("RTDE_DATA_PACKAGE: input recipe id {} was never set up", id));
        std::size_t size = 1;
        for (const FieldInfo* f : input_recipes_[id - 1u]) size += static_cast<std::size_t>(wire_size(f->type));
        if (p.payload.size() != size)
          throw ProtocolError(fmt::format("RTDE_DATA_PACKAGE: input recipe {} needs {} payload bytes, got {}", id, size, p.payload.size()));
        return;  // the virtual robot takes no commands: inputs are accepted and ignored
      }
    }
    error_text(out, fmt::format("{} ({} payload bytes) is not an RTDE request; ignored", package_name(p.type), p.payload.size()));
  } catch (const ProtocolError& e) {
    error_text(out, e.what());
    // a malformed request still gets its (negative) answer, so a waiting client does not hang
    switch (static_cast<PackageType>(p.type)) {
      case PackageType::RequestProtocolVersion: encode_protocol_version_reply(out, false); break;
      case PackageType::SetupOutputs:
      case PackageType::SetupInputs: encode_setup_reply(out, static_cast<PackageType>(p.type), protocol_, 0, {}); break;
      case PackageType::Start:
      case PackageType::Pause: encode_accepted_reply(out, static_cast<PackageType>(p.type), false); break;
      default: break;
    }
  }
}

bool ServerSession::on_cycle(const double* frame, Bytes& out) {
  if (!streaming_) return false;
  // a rate accumulator instead of "every k-th": exact for rates that do not divide the base rate
  phase_ += frequency_ / base_frequency_;
  if (phase_ < 1.0 - 1e-9) return false;
  phase_ -= 1.0;
  if (phase_ > 1.0) phase_ = 0.0;
  encode_data_package(out, protocol_, recipe_, frame);
  return true;
}

// ---- server -------------------------------------------------------------------------------

struct Server::Connection {
  int fd = -1;
  std::string peer;
  std::mutex mutex;  // guards session, pending and fd writes
  ServerSession session;
  Bytes pending;     // bytes the socket did not take yet
  std::thread thread;
  std::atomic<bool> done{false};
  std::atomic<bool> streaming{false};  // mirror of session.streaming() for stats() (no lock order issue)
  Connection(int f, std::string p, const ServerOptions& o) : fd(f), peer(std::move(p)), session(o.version, o.base_frequency, o.max_protocol) {}

  // Control replies must arrive: queue and wait for the socket (up to 1 s). Caller holds mutex.
  bool send_reliable(const Bytes& b) {
    pending.insert(pending.end(), b.begin(), b.end());
    const bool ok = tcp::send_all(fd, pending.data(), pending.size(), 1000);
    pending.clear();
    return ok;
  }
  // Data: never wait. If older bytes are still pending, try to flush them and skip this package
  // unless they all went out. Caller holds mutex. Returns false if the package was skipped.
  bool send_data(const std::uint8_t* d, std::size_t n, bool& broken) {
    if (!pending.empty()) {
      const ssize_t k = ::send(fd, pending.data(), pending.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      if (k < 0 && errno != EAGAIN && errno != EWOULDBLOCK) broken = true;
      if (k > 0) pending.erase(pending.begin(), pending.begin() + k);
      if (!pending.empty()) return false;
    }
    const ssize_t k = ::send(fd, d, n, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (k < 0) {
      if (errno != EAGAIN && errno != EWOULDBLOCK) broken = true;
      return false;
    }
    if (static_cast<std::size_t>(k) < n) pending.assign(d + k, d + n);  // finish it later: the stream stays framed
    return true;
  }
};

Server::Server(ServerOptions options) : opt_(std::move(options)) {}

Server::~Server() { stop(); }

void Server::start() {
  if (listen_fd_ >= 0) return;
  listen_fd_ = tcp::listen(opt_.bind, opt_.port);
  port_ = tcp::local_port(listen_fd_);
  stop_ = false;
  accept_thread_ = std::thread([this] { accept_loop(); });
}

void Server::stop() {
  if (listen_fd_ < 0 && !accept_thread_.joinable()) return;
  stop_ = true;
  if (accept_thread_.joinable()) accept_thread_.join();
  tcp::close(listen_fd_);
  std::vector<std::shared_ptr<Connection>> conns;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    conns.swap(conns_);
    stats_.clients = 0;
  }
  for (auto& c : conns) {
    ::shutdown(c->fd, SHUT_RDWR);
    if (c->thread.joinable()) c->thread.join();
    tcp::close(c->fd);
  }
}

void Server::accept_loop() {
  while (!stop_) {
    reap();
    if (!tcp::wait_readable(listen_fd_, 50)) continue;
    sockaddr_storage addr{};
    socklen_t len = sizeof addr;
    const int fd = ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len, SOCK_CLOEXEC);
    if (fd < 0) continue;
    tcp::set_nodelay(fd);
    tcp::set_nonblocking(fd);
    auto c = std::make_shared<Connection>(fd, fmt::format("client {}", fd), opt_);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      conns_.push_back(c);
      ++stats_.connections;
      stats_.clients = static_cast<int>(conns_.size());
    }
    log::info(fmt::format("rtde server: {} connected", c->peer));
    c->thread = std::thread([this, c] { client_loop(c); });
  }
}

void Server::reap() {
  std::vector<std::shared_ptr<Connection>> dead;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto it = conns_.begin(); it != conns_.end();) {
      if ((*it)->done) {
        dead.push_back(*it);
        it = conns_.erase(it);
      } else {
        ++it;
      }
    }
    stats_.clients = static_cast<int>(conns_.size());
  }
  for (auto& c : dead) {
    if (c->thread.joinable()) c->thread.join();
    tcp::close(c->fd);
  }
}

void Server::client_loop(std::shared_ptr<Connection> c) {
  std::uint8_t buf[4096];
  Bytes out;
  while (!stop_) {
    if (!tcp::wait_readable(c->fd, 50)) continue;
    const ssize_t k = ::recv(c->fd, buf, sizeof buf, 0);
    if (k == 0) break;  // client closed
    if (k < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) continue;
      break;
    }
    std::lock_guard<std::mutex> lock(c->mutex);
    out.clear();
    const long errors_before = c->session.errors();
    bool close = false;
    try {
      c->session.on_bytes(buf, static_cast<std::size_t>(k), out);
    } catch (const ProtocolError& e) {
      log::warn(fmt::format("rtde server: {}: {}; closing the connection", c->peer, e.what()));
      encode_text_message(out, c->session.protocol(), {MessageLevel::Exception, e.what(), "twinwatch virtual controller"});
      close = true;
    }
    c->streaming = c->session.streaming();
    const long new_errors = c->session.errors() - errors_before + (close ? 1 : 0);
    if (new_errors > 0) {
      std::lock_guard<std::mutex> slock(mutex_);
      stats_.protocol_errors += new_errors;
    }
    if (!out.empty() && !c->send_reliable(out)) close = true;
    if (close) break;
  }
  ::shutdown(c->fd, SHUT_RDWR);
  log::info(fmt::format("rtde server: {} disconnected", c->peer));
  c->done = true;
}

void Server::publish(const double* frame) {
  thread_local Bytes out;
  std::vector<std::shared_ptr<Connection>> conns;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    conns = conns_;
    ++stats_.cycles;
  }
  long sent = 0, skipped = 0;
  for (auto& c : conns) {
    if (c->done) continue;
    std::lock_guard<std::mutex> lock(c->mutex);
    out.clear();
    if (!c->session.on_cycle(frame, out)) continue;
    bool broken = false;
    if (c->send_data(out.data(), out.size(), broken)) ++sent;
    else ++skipped;
    if (broken) ::shutdown(c->fd, SHUT_RDWR);  // its reader thread sees the hang-up and cleans up
  }
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.packages_sent += sent;
  stats_.packages_skipped += skipped;
}

void Server::broadcast(const TextMessage& m) {
  std::vector<std::shared_ptr<Connection>> conns;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    conns = conns_;
  }
  for (auto& c : conns) {
    std::lock_guard<std::mutex> lock(c->mutex);
    Bytes out;
    encode_text_message(out, c->session.protocol(), m);
    c->send_reliable(out);
  }
}

ServerStats Server::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  ServerStats s = stats_;
  s.streaming = 0;
  for (const auto& c : conns_) s.streaming += c->streaming && !c->done ? 1 : 0;
  return s;
}

}  // namespace twinwatch::device::rtde
