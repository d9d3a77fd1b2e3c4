// AGV twin monitor: decode + pair + IIR + debounce per datagram. Goal (issue 8): >= 100,000
// datagrams per second.   build-bench/bench/monitor/agv_monitor_benchmark
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <vector>

#include "twinwatch/monitor/agv_monitor.hpp"

namespace {

using namespace twinwatch;

void BM_AgvMonitorDatagrams(benchmark::State& st) {
  // a pre-encoded stream: real and twin alternate, with a divergence now and then
  std::vector<std::array<std::uint8_t, device::kAgvStateSize>> stream;
  for (std::uint32_t seq = 0; seq < 4096; ++seq)
    for (int r = 0; r < 2; ++r) {
      device::AgvStateDatagram d;
      d.role = r ? device::AgvRole::Twin : device::AgvRole::Real;
      d.seq = seq;
      d.t = seq * 0.04;
      d.w = (r == 0 && (seq / 200) % 2) ? 1.7 : 0.0;
      d.v = 0.1 * std::sin(seq * 0.01);
      std::array<std::uint8_t, device::kAgvStateSize> b{};
      device::encode(d, b.data());
      stream.push_back(b);
    }
  monitor::AgvMonitor m;
  size_t k = 0;
  std::uint32_t base = 0;
  for (auto _ : st) {
    if (k == stream.size()) {
      // continue the sequence numbers so that pairing keeps working
      k = 0;
      base += 4096;
      st.PauseTiming();
      for (auto& b : stream) {
        device::AgvStateDatagram d;
        device::decode(b.data(), b.size(), d);
        d.seq += 4096;
        device::encode(d, b.data());
      }
      st.ResumeTiming();
    }
    m.push_bytes(stream[k].data(), stream[k].size());
    ++k;
  }
  benchmark::DoNotOptimize(m.counters().paired);
  st.counters["datagrams_per_s"] = benchmark::Counter(static_cast<double>(st.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_AgvMonitorDatagrams);

}  // namespace

BENCHMARK_MAIN();
