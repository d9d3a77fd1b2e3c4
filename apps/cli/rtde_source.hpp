#pragma once
// Opening an RTDE stream from the command line (record --rtde, monitor --rtde): parses
// HOST[:PORT], connects, and keeps trying the first connection for `wait_s` seconds.
#include <chrono>
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
/// on a stalled connection after 1 s and reconnects): record and monitor report that stretch. A
/// slow stream's limit is three sample periods if that is longer.
inline constexpr double kSilentAtEnd = 1.5;

/// A steady-clock instant in seconds as double (the verbs' ends are `now + duration<double>`).
using SteadyTime = std::chrono::time_point<std::chrono::steady_clock, std::chrono::duration<double>>;

/// The silence at the end of a live run (record, monitor --rtde), stopped at `stopped`, its last
/// sample received at `last_sample`. A run that ended before `end` without an operator's stop
/// (--no-reconnect, the robot gone) misses everything up to `end` where `end` was asked for
/// (`end_asked`); otherwise the silence runs to the stop. `lost`: long enough to be an outage (0.1 s
/// when cut short, else kSilentAtEnd or three periods at `frequency` [Hz]).
struct EndSilence {
  double seconds = 0.0;
  bool lost = false;
};
/// How long a live stream may be silent before it is an outage: kSilentAtEnd, or three periods at
/// `frequency` [Hz] if longer.
double outage_limit(double frequency);
EndSilence end_silence(SteadyTime stopped, SteadyTime end, SteadyTime last_sample, bool end_asked, double frequency);

/// A started client. Throws (RecipeError, connection errors) with the controller's address.
std::unique_ptr<device::rtde::Client> open_rtde(const RtdeSourceOptions& o);

/// --split-every (record, monitor --record): 0 or a finite time >= 1 s of controller time, else
/// InvalidArgument naming the option (checked before connecting)
void check_split_every(double seconds);

/// "controller 5.23.0.0, RTDE v2, 12 outputs at 500 Hz"
std::string describe(const device::rtde::Client& c);

}  // namespace twinwatch::cli
