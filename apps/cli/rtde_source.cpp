#include "rtde_source.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "twinwatch/core/error.hpp"
#include "twinwatch/device/recording.hpp"
#include "verb_registry.hpp"

namespace twinwatch::cli {

namespace rtde = device::rtde;

std::unique_ptr<rtde::Client> open_rtde(const RtdeSourceOptions& o) {
  rtde::ClientOptions co;
  rtde::parse_endpoint(o.endpoint, co.host, co.port);
  co.frequency = o.frequency;
  co.max_protocol = o.protocol;
  co.reconnect = o.reconnect;
  if (!o.outputs.empty()) co.outputs = o.outputs;
  auto client = std::make_unique<rtde::Client>(co);
  // The first connection: retry for up to wait_s (a robot that is still booting).
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.wait_s);
  for (;;) {
    try {
      client->start();
      return client;
    } catch (const rtde::RecipeError&) {
      throw;  // NOT_FOUND names: retrying cannot help
    } catch (const std::exception&) {
      if (std::chrono::steady_clock::now() >= until || interrupted()) throw;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  }
}

double outage_limit(double frequency) { return frequency > 0.0 ? std::max(kSilentAtEnd, 3.0 / frequency) : kSilentAtEnd; }

EndSilence end_silence(SteadyTime stopped, SteadyTime end, SteadyTime last_sample, bool end_asked, double frequency) {
  const bool cut_short = !interrupted() && end_asked && stopped + std::chrono::milliseconds(100) < end;
  const double seconds = std::chrono::duration<double>((cut_short ? end : stopped) - last_sample).count();
  const double limit = cut_short ? 0.1 : outage_limit(frequency);
  return {seconds, seconds > limit};
}

std::string describe(const rtde::Client& c) {
  const rtde::ClientStats st = c.stats();
  return fmt::format("controller {}.{}.{}.{}, RTDE v{}, {} outputs at {:g} Hz", st.controller.major, st.controller.minor,
                     st.controller.bugfix, st.controller.build, st.protocol, c.recipe().names.size(), st.frequency);
}

void check_split_every(double seconds) {
  if (!device::SplitRecordingWriter::valid_interval(seconds))
    throw InvalidArgument(fmt::format("--split-every must be a finite time >= 1 s of controller time, got {}", seconds));
}

}  // namespace twinwatch::cli
