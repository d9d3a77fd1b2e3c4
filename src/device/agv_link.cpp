#include "twinwatch/device/agv_link.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace twinwatch::device {

namespace {
// explicit little-endian (de)serialisation, independent of the host's byte order
template <typename T>
void put(std::uint8_t* p, T v) {
  std::uint8_t b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  for (size_t i = 0; i < sizeof(T); ++i) p[i] = b[i];  // x86/ARM hosts here are little-endian
}
template <typename T>
T get(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}
constexpr char kStateMagic[4] = {'T', 'W', 'A', 'S'};
constexpr char kCommandMagic[4] = {'T', 'W', 'A', 'C'};
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the AGV link codec assumes a little-endian host");
}  // namespace

const char* to_string(DecodeStatus s) {
  switch (s) {
    case DecodeStatus::Ok: return "ok";
    case DecodeStatus::TooShort: return "datagram too short";
    case DecodeStatus::TooLong: return "datagram too long";
    case DecodeStatus::WrongMagic: return "wrong magic";
    case DecodeStatus::WrongVersion: return "unsupported version";
    case DecodeStatus::BadField: return "field out of range";
  }
  return "unknown";
}

void encode(const AgvStateDatagram& d, std::uint8_t* o) {
  std::memcpy(o, kStateMagic, 4);
  o[4] = kAgvLinkVersion;
  o[5] = static_cast<std::uint8_t>(d.role);
  o[6] = o[7] = 0;
  put(o + 8, d.seq);
  put(o + 12, d.t);
  put(o + 20, d.v);
  put(o + 28, d.w);
  put(o + 36, d.w_right);
  put(o + 40, d.w_left);
  put(o + 44, d.u_right);
  put(o + 48, d.u_left);
  put(o + 52, d.enc_right);
  put(o + 56, d.enc_left);
}

void encode(const AgvCommandDatagram& d, std::uint8_t* o) {
  std::memcpy(o, kCommandMagic, 4);
  o[4] = kAgvLinkVersion;
  o[5] = static_cast<std::uint8_t>(d.target);
  o[6] = d.flags;
  o[7] = 0;
  put(o + 8, d.seq);
  put(o + 12, d.t);
  put(o + 20, d.w_right_ref);
  put(o + 24, d.w_left_ref);
  put(o + 28, std::uint32_t{0});
}

DecodeStatus decode(const std::uint8_t* p, std::size_t n, AgvStateDatagram& d) {
  if (n < kAgvStateSize) return DecodeStatus::TooShort;
  if (n > kAgvStateSize) return DecodeStatus::TooLong;
  if (std::memcmp(p, kStateMagic, 4) != 0) return DecodeStatus::WrongMagic;
  if (p[4] != kAgvLinkVersion) return DecodeStatus::WrongVersion;
  if (p[5] > 1) return DecodeStatus::BadField;
  d.role = static_cast<AgvRole>(p[5]);
  d.seq = get<std::uint32_t>(p + 8);
  d.t = get<double>(p + 12);
  d.v = get<double>(p + 20);
  d.w = get<double>(p + 28);
  d.w_right = get<float>(p + 36);
  d.w_left = get<float>(p + 40);
  d.u_right = get<float>(p + 44);
  d.u_left = get<float>(p + 48);
  d.enc_right = get<std::int32_t>(p + 52);
  d.enc_left = get<std::int32_t>(p + 56);
  if (!std::isfinite(d.t) || !std::isfinite(d.v) || !std::isfinite(d.w)) return DecodeStatus::BadField;
  return DecodeStatus::Ok;
}

DecodeStatus decode(const std::uint8_t* p, std::size_t n, AgvCommandDatagram& d) {
  if (n < kAgvCommandSize) return DecodeStatus::TooShort;
  if (n > kAgvCommandSize) return DecodeStatus::TooLong;
  if (std::memcmp(p, kCommandMagic, 4) != 0) return DecodeStatus::WrongMagic;
  if (p[4] != kAgvLinkVersion) return DecodeStatus::WrongVersion;
  if (p[5] > 2 || (p[6] & ~7u) != 0) return DecodeStatus::BadField;
  d.target = static_cast<AgvRole>(p[5]);
  d.flags = p[6];
  d.seq = get<std::uint32_t>(p + 8);
  d.t = get<double>(p + 12);
  d.w_right_ref = get<float>(p + 20);
  d.w_left_ref = get<float>(p + 24);
  if (!std::isfinite(d.w_right_ref) || !std::isfinite(d.w_left_ref)) return DecodeStatus::BadField;
  return DecodeStatus::Ok;
}

UdpSocket::UdpSocket(std::uint16_t port) {
  fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("udp socket: ") + std::strerror(errno));
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    const std::string m = std::strerror(errno);
    ::close(fd_);
    throw std::runtime_error("udp bind 127.0.0.1:" + std::to_string(port) + ": " + m);
  }
  socklen_t len = sizeof a;
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
  port_ = ntohs(a.sin_port);
}

UdpSocket::~UdpSocket() {
  if (fd_ >= 0) ::close(fd_);
}

void UdpSocket::send_to(std::uint16_t port, const std::uint8_t* data, std::size_t n) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::sendto(fd_, data, n, 0, reinterpret_cast<sockaddr*>(&a), sizeof a);  // UDP: loss is the monitor's business
}

long UdpSocket::receive(std::uint8_t* buf, std::size_t cap, int timeout_ms) {
  pollfd p{fd_, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0) return -1;
  const ssize_t n = ::recv(fd_, buf, cap, 0);
  return n < 0 ? -1 : static_cast<long>(n);
}

}  // namespace twinwatch::device
