// Real-time factor of the virtual UR3e: 60 s of the nominal figure-eight at 500 Hz (2 kHz physics),
// samples consumed but not written. Goal (issue 3): 1 h in <= 30 s on one core, i.e. >= 120x.
//   build-bench/bench/sim/sim_benchmark --benchmark_repetitions=3
#include <benchmark/benchmark.h>

#include "twinwatch/sim/scenario.hpp"

namespace {

void BM_SimulateFigureEight60s(benchmark::State& st) {
  using namespace twinwatch;
  const sim::Scenario s = sim::load_scenario(std::string(TWINWATCH_SOURCE_DIR) + "/scenarios/ur3e/nominal_figure_eight.yaml");
  double checksum = 0.0;
  for (auto _ : st) {
    sim::Scenario run = s;
    run.options.duration = 60.0;
    auto simulator = sim::make_simulator(run);
    simulator->run([&](const RobotSample& x) { checksum += x.current[0]; });
  }
  benchmark::DoNotOptimize(checksum);
  st.counters["realtime_factor"] = benchmark::Counter(60.0 * static_cast<double>(st.iterations()),
                                                      benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SimulateFigureEight60s)->Unit(benchmark::kMillisecond)->MinTime(3.0);

}  // namespace

BENCHMARK_MAIN();
