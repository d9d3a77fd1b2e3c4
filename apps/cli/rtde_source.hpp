#pragma once
// Opening an RTDE stream from the command line (record --rtde, monitor --rtde): parses
// HOST[:PORT], connects, and keeps trying the first connection for `wait_s` seconds.
#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "twinwatch/device/rtde_client.hpp"

namespace twinwatch::cli {

struct RtdeSourceOptions {
  std::string endpoint;
  double frequency = 500.0;
  double wait_s = 0.0;
  int protocol = 2;
  bool reconnect = true;
  std::vector<std::string> outputs;  ///< empty: the recording columns
};

/// [s] a live stream silent this long when recording or monitoring ends was lost (the client gives up
/// on a stalled connection after 1 s and reconnects): record and monitor report that stretch
inline constexpr double kSilentAtEnd = 1.5;
/// kSilentAtEnd, or three sample periods of a slow stream (`frequency` [Hz]) if longer
inline double silent_at_end(double frequency) { return frequency > 0.0 ? std::max(kSilentAtEnd, 3.0 / frequency) : kSilentAtEnd; }

/// A started client. Throws (RecipeError, connection errors) with the controller's address.
std::unique_ptr<device::rtde::Client> open_rtde(const RtdeSourceOptions& o);

/// "controller 5.23.0.0, RTDE v2, 12 outputs at 500 Hz"
std::string describe(const device::rtde::Client& c);

}  // namespace twinwatch::cli
