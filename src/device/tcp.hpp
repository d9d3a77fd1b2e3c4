#pragma once
// Small POSIX TCP helpers shared by the RTDE client and server (device-internal).
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace twinwatch::device::tcp {

/// Connecting failed (refused, unreachable, timed out, unknown host). Retryable.
class ConnectError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Connects with a timeout; returns a blocking socket with TCP_NODELAY set. With `cancel`, the wait
/// is given up (ConnectError "cancelled") within 50 ms of *cancel turning true: a client being
/// stopped does not wait out the timeout on an address that does not answer.
int connect(const std::string& host, std::uint16_t port, int timeout_ms, const std::atomic<bool>* cancel = nullptr);
/// Binds and listens (SO_REUSEADDR, so a restarted server gets its port back); port 0 picks one.
/// Throws std::runtime_error naming the address on failure (e.g. port in use).
int listen(const std::string& bind, std::uint16_t port);
std::uint16_t local_port(int fd);
void set_nonblocking(int fd);
void set_nodelay(int fd);
/// Waits until fd is readable (POLLIN) for at most timeout_ms. True if readable or hung up.
bool wait_readable(int fd, int timeout_ms);
/// Writes all bytes, waiting for the socket to drain up to timeout_ms in total. False on error
/// or timeout (the caller closes the connection).
bool send_all(int fd, const std::uint8_t* data, std::size_t n, int timeout_ms);
void close(int& fd);
/// "HOST[:PORT]" → host, port (default_port when absent). Throws InvalidArgument on a bad port.
void parse_endpoint(const std::string& s, std::string& host, std::uint16_t& port, std::uint16_t default_port);

}  // namespace twinwatch::device::tcp
