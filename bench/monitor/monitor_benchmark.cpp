// Throughput and per-sample latency of the full monitoring loop (twin prediction, residual, IIR,
// dynamic threshold, debounce; diagnosis only when an alert is raised) on a recorded healthy
// UR3e figure-eight. Goal (issue 7): >= 1,000,000 samples/s on one core, p99 <= 10 us.
//   build-bench/bench/monitor/monitor_benchmark
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdint>

#include "twinwatch/ident/physics_ident.hpp"
#include "twinwatch/monitor/monitor.hpp"
#include "twinwatch/sim/scenario.hpp"

namespace {

using namespace twinwatch;

struct Setup {
  ident::TwinModel twin;
  monitor::MonitorConfig cfg;
  device::Recording rec;
  Setup() {
    auto simulate = [](const std::string& yaml) {
      device::Recording r;
      r.n_dof = 6;
      r.present = sim::Simulator::fields();
      sim::make_simulator(sim::parse_scenario(yaml, "bench"))->run([&](const RobotSample& x) { r.samples.push_back(x); });
      return r;
    };
    const auto exc = simulate("robot: ur3e\nseed: 1\nduration: 40\ntrajectory: {type: fourier, amplitude: 0.9, period: 10, harmonics: 5, seed: 3}\n");
    rec = simulate("robot: ur3e\nseed: 2\nduration: 20\ntrajectory: {type: figure_eight, size: [0.12, 0.08], period: 8, tilt: [0.3, 0.4, 0.5]}\n");
    ident::IdentReport rep;
    twin = ident::identify_physics("ur3e", {{&exc, {}}}, ident::IdentOptions{}, rep);
    cfg = monitor::learn_thresholds(twin, {{&exc, {}}});
  }
};
const Setup& setup() {
  static const Setup s;
  return s;
}

// one healthy replay after another, a fresh monitor per replay (made outside the timing); observer
// 1: the momentum observer on the sample path with its alerts (as evaluate runs it), 0: without it
// (observer_level cleared: the current residual alone, as before issue 7's observer); 2: as 1 with
// every reversal beyond the learned loads (reversal_load_max 0: the thresholds widen at each one,
// the worst case of Monitor::widen_for_load); 3: as 1 without the widening (a twin file from before
// session 25), for its cost in the same binary
struct Replayer {
  const Setup& s;
  const monitor::MonitorConfig cfg;
  monitor::Monitor mon;
  size_t k = 0, events = 0, replays = 0;  // alerts raised on the healthy replays (each runs a diagnosis)
  static monitor::MonitorConfig config(const Setup& s, std::int64_t observer) {
    monitor::MonitorConfig c = s.cfg;
    if (observer == 0) c.observer_level.resize(0);
    c.observer_alerts = observer >= 1;
    if (observer == 2) c.reversal_load_max = VectorJ::Zero(s.twin.n_dof());
    if (observer == 3) c.reversal_load_max.resize(0);
    return c;
  }
  Replayer(const Setup& setup, std::int64_t observer) : s(setup), cfg(config(setup, observer)), mon(setup.twin, cfg) {}
  void push() { mon.push(s.rec.samples[k]); }
  void next(benchmark::State& st) {
    if (++k < s.rec.samples.size()) return;
    k = 0;
    st.PauseTiming();
    events += mon.events().size();
    ++replays;
    mon = monitor::Monitor(s.twin, cfg);
    st.ResumeTiming();
  }
  void count(benchmark::State& st) const {
    st.counters["samples_per_s"] = benchmark::Counter(static_cast<double>(st.iterations()), benchmark::Counter::kIsRate);
    st.counters["events_per_replay"] = replays ? static_cast<double>(events) / static_cast<double>(replays) : 0.0;
  }
};

// per-sample latency (p50, p99, max) and throughput; range(0): observer on (1) or off (0)
void BM_MonitorLoop(benchmark::State& st) {
  Replayer r(setup(), st.range(0));
  std::vector<double> lat;
  lat.reserve(1 << 20);
  for (auto _ : st) {
    const auto t0 = std::chrono::steady_clock::now();
    r.push();
    lat.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    r.next(st);
  }
  std::sort(lat.begin(), lat.end());
  r.count(st);
  st.counters["p50_us"] = lat[lat.size() / 2];
  st.counters["p99_us"] = lat[lat.size() * 99 / 100];
  st.counters["max_us"] = lat.back();
}
BENCHMARK(BM_MonitorLoop)->Arg(0)->Arg(1)->MinTime(2.0);

// Throughput alone: the same loop without the two clock reads and the latency record per sample
// (about 50-70 ns of BM_MonitorLoop's per-sample time is its own latency measurement). range(0) as
// for BM_MonitorLoop.
void BM_MonitorThroughput(benchmark::State& st) {
  Replayer r(setup(), st.range(0));
  for (auto _ : st) {
    r.push();
    r.next(st);
  }
  benchmark::DoNotOptimize(r.mon.observer_residual().data());
  r.count(st);
}
BENCHMARK(BM_MonitorThroughput)->Arg(0)->Arg(1)->Arg(2)->Arg(3)->MinTime(2.0);

// the twin prediction alone (the regressor dominates), with its friction memory
void BM_TwinPredict(benchmark::State& st) {
  const Setup& s = setup();
  VectorJ tau, i;
  ident::FrictionMemory memory;
  size_t k = 0;
  for (auto _ : st) {
    const auto& x = s.rec.samples[k];
    s.twin.advance(memory, x.q);
    s.twin.predict(x.q, x.qd, x.target_qdd, x.temperature, tau, i, &memory);
    benchmark::DoNotOptimize(i.data());
    k = (k + 1) % s.rec.samples.size();
  }
}
BENCHMARK(BM_TwinPredict);

}  // namespace

BENCHMARK_MAIN();
