#include "tcp.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstring>

#include "twinwatch/core/error.hpp"

namespace twinwatch::device::tcp {

void set_nodelay(int fd) {
  int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
}

void set_nonblocking(int fd) { ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL, 0) | O_NONBLOCK); }

void close(int& fd) {
  if (fd >= 0) ::close(fd);
  fd = -1;
}

int connect(const std::string& host, std::uint16_t port, int timeout_ms, const std::atomic<bool>* cancel) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* res = nullptr;
  const std::string service = std::to_string(port);
  if (int rc = ::getaddrinfo(host.c_str(), service.c_str(), &hints, &res); rc != 0)
    throw ConnectError(fmt::format("cannot resolve '{}': {}", host, ::gai_strerror(rc)));
  std::string last = "no address";
  for (addrinfo* a = res; a; a = a->ai_next) {
    int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) continue;
    set_nonblocking(fd);
    int rc = ::connect(fd, a->ai_addr, a->ai_addrlen);
    if (rc != 0 && errno == EINPROGRESS) {
      // (in slices of 50 ms when it can be cancelled)
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
      for (;;) {
        if (cancel && cancel->load()) {
          ::close(fd);
          ::freeaddrinfo(res);
          throw ConnectError(fmt::format("connecting to {}:{}: cancelled", host, port));
        }
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count();
        pollfd p{fd, POLLOUT, 0};
        rc = left <= 0 ? 0 : ::poll(&p, 1, static_cast<int>(cancel ? std::min<long long>(left, 50) : left));
        if (rc < 0 && errno == EINTR) continue;
        if (rc != 0 || left <= 0) break;
      }
      if (rc < 0) {
        last = std::strerror(errno);
        ::close(fd);
        continue;
      }
      if (rc == 0) {
        last = fmt::format("no answer within {} ms", timeout_ms);
        ::close(fd);
        continue;
      }
      int err = 0;
      socklen_t len = sizeof err;
      ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len);
      rc = err == 0 ? 0 : -1;
      errno = err;
    }
    if (rc == 0) {
      ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL, 0) & ~O_NONBLOCK);
      set_nodelay(fd);
      ::freeaddrinfo(res);
      return fd;
    }
    last = std::strerror(errno);
    ::close(fd);
  }
  ::freeaddrinfo(res);
  throw ConnectError(fmt::format("cannot connect to {}:{}: {}", host, port, last));
}

int listen(const std::string& bind, std::uint16_t port) {
  int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error(fmt::format("socket(): {}", std::strerror(errno)));
  int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  if (::inet_pton(AF_INET, bind.c_str(), &addr.sin_addr) != 1) {
    ::close(fd);
    throw InvalidArgument(fmt::format("bind address '{}' is not an IPv4 address (e.g. 127.0.0.1 or 0.0.0.0)", bind));
  }
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 || ::listen(fd, 16) != 0) {
    const std::string e = std::strerror(errno);
    ::close(fd);
    throw std::runtime_error(fmt::format("cannot listen on {}:{}: {}", bind, port, e));
  }
  return fd;
}

std::uint16_t local_port(int fd) {
  sockaddr_in addr{};
  socklen_t len = sizeof addr;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  return ntohs(addr.sin_port);
}

bool wait_readable(int fd, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, timeout_ms) > 0;
}

bool send_all(int fd, const std::uint8_t* data, std::size_t n, int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (n > 0) {
    const ssize_t k = ::send(fd, data, n, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (k > 0) {
      data += k;
      n -= static_cast<std::size_t>(k);
      continue;
    }
    if (k < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) return false;
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) return false;
    pollfd p{fd, POLLOUT, 0};
    ::poll(&p, 1, static_cast<int>(left));
  }
  return true;
}

void parse_endpoint(const std::string& s, std::string& host, std::uint16_t& port, std::uint16_t default_port) {
  // (an empty host resolved to nothing and failed as an unreachable robot, exit 1: it is bad usage,
  // as are a URL and an address with two ports)
  const auto bad = [&](const std::string& why) {
    return InvalidArgument(fmt::format("'{}': expected HOST[:PORT] (an IPv6 address in brackets: [::1]:30004), {}", s, why));
  };
  if (s.find("://") != std::string::npos) throw bad("not a URL");
  std::string rest;  // after the host: empty or ":PORT"
  if (!s.empty() && s[0] == '[') {
    const auto close = s.find(']');
    if (close == std::string::npos) throw bad("the '[' has no ']'");
    host = s.substr(1, close - 1);
    in6_addr a6{};
    if (inet_pton(AF_INET6, host.c_str(), &a6) != 1) throw bad(fmt::format("'{}' in brackets is not an IPv6 address", host));
    rest = s.substr(close + 1);
    if (!rest.empty() && rest[0] != ':') throw bad(fmt::format("'{}' after the ']'", rest));
  } else if (std::count(s.begin(), s.end(), ':') > 1) {
    in6_addr a6{};
    if (inet_pton(AF_INET6, s.c_str(), &a6) != 1) throw bad("more than one ':'");
    host = s;  // a bare IPv6 address, the default port
  } else {
    const auto colon = s.find(':');
    host = s.substr(0, colon);
    if (colon != std::string::npos) rest = s.substr(colon);
  }
  if (host.find_first_not_of(" \t") == std::string::npos) throw bad("the host is missing");
  if (host.find_first_of(" \t") != std::string::npos) throw bad(fmt::format("the host '{}' has a space", host));
  if (rest.empty()) {
    port = default_port;
    return;
  }
  const std::string p = rest.substr(1);
  char* end = nullptr;
  const long v = std::strtol(p.c_str(), &end, 10);
  // the whole field is the port: strtol took " 80" and "+80"
  if (p.empty() || !std::isdigit(static_cast<unsigned char>(p[0])) || *end != '\0' || v < 1 || v > 65535)
    throw InvalidArgument(fmt::format("'{}': port '{}' is not a number in 1..65535", s, p));
  port = static_cast<std::uint16_t>(v);
}

}  // namespace twinwatch::device::tcp
