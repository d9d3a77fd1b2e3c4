#pragma once
/// @file agv_link.hpp
/// The AGV twin link [AGV §4.3, Fig. 12]: fixed-layout little-endian UDP datagrams, version 1.
/// Specified in docs/agv.md. State (robot -> monitor, 60 bytes):
///   0 magic "TWAS" | 4 version u8 = 1 | 5 role u8 (0 real, 1 twin) | 6..7 reserved | 8 seq u32 |
///   12 t_sender f64 [s] | 20 v f64 [m/s] | 28 w f64 [rad/s] | 36 w_right f32 | 40 w_left f32 [rad/s] |
///   44 u_right f32 | 48 u_left f32 [V] | 52 enc_right i32 | 56 enc_left i32
/// Command (monitor -> robot, 32 bytes):
///   0 magic "TWAC" | 4 version u8 = 1 | 5 target u8 (0 real, 1 twin, 2 both) | 6 flags u8
///   (bit0 stop, bit1 force motor voltage to 0, bit2 quit) | 7 reserved | 8 seq u32 |
///   12 t_sender f64 | 20 w_right_ref f32 | 24 w_left_ref f32 [rad/s] | 28 reserved u32
#include <cstddef>
#include <cstdint>
#include <string>

namespace twinwatch::device {

inline constexpr std::uint8_t kAgvLinkVersion = 1;
inline constexpr std::size_t kAgvStateSize = 60;
inline constexpr std::size_t kAgvCommandSize = 32;

enum class AgvRole : std::uint8_t { Real = 0, Twin = 1, Both = 2 };

struct AgvStateDatagram {
  AgvRole role = AgvRole::Real;
  std::uint32_t seq = 0;
  double t = 0.0, v = 0.0, w = 0.0;
  float w_right = 0, w_left = 0, u_right = 0, u_left = 0;
  std::int32_t enc_right = 0, enc_left = 0;
};

enum AgvCommandFlag : std::uint8_t { kAgvStop = 1, kAgvForceZeroVoltage = 2, kAgvQuit = 4 };

struct AgvCommandDatagram {
  AgvRole target = AgvRole::Both;
  std::uint8_t flags = 0;
  std::uint32_t seq = 0;
  double t = 0.0;
  float w_right_ref = 0, w_left_ref = 0;
};

enum class DecodeStatus { Ok, TooShort, TooLong, WrongMagic, WrongVersion, BadField };
const char* to_string(DecodeStatus s);

void encode(const AgvStateDatagram& d, std::uint8_t* out);    ///< writes kAgvStateSize bytes
void encode(const AgvCommandDatagram& d, std::uint8_t* out);  ///< writes kAgvCommandSize bytes
DecodeStatus decode(const std::uint8_t* data, std::size_t n, AgvStateDatagram& out);
DecodeStatus decode(const std::uint8_t* data, std::size_t n, AgvCommandDatagram& out);

/// A UDP socket bound to 127.0.0.1 (loopback only). Throws std::runtime_error on socket errors.
class UdpSocket {
 public:
  explicit UdpSocket(std::uint16_t port = 0);  ///< 0: an ephemeral port
  ~UdpSocket();
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;
  std::uint16_t port() const { return port_; }
  void send_to(std::uint16_t port, const std::uint8_t* data, std::size_t n);
  /// Receives one datagram, waiting at most timeout_ms (0: poll). Returns its size, or -1 if none.
  long receive(std::uint8_t* buf, std::size_t cap, int timeout_ms);

 private:
  int fd_ = -1;
  std::uint16_t port_ = 0;
};

}  // namespace twinwatch::device
