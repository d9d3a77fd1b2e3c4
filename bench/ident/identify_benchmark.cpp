// The whole identification of 10 minutes of 500 Hz data (issue 5: <= 20 s on this machine):
// read the recordings from CSV and identify the physics twin, as `twinwatch identify` does.
//
// The recordings are made once, outside the timed region, by the virtual UR3e: 5 min of Fourier
// excitation without payload and 5 min of figure-eight with a known 0.5 kg payload (the pair the
// README's quickstart uses), 300 000 samples in all.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "twinwatch/device/recording.hpp"
#include "twinwatch/ident/physics_ident.hpp"
#include "twinwatch/sim/scenario.hpp"

namespace {

using namespace twinwatch;

constexpr double kMinutesPerRun = 5.0;  // two runs -> 10 minutes of data

std::string simulate_to_csv(const std::string& scenario, double duration, const std::string& out) {
  sim::Scenario s = sim::load_scenario(std::string(TWINWATCH_SOURCE_DIR) + "/scenarios/ur3e/" + scenario + ".yaml");
  s.options.duration = duration;
  device::RecordingWriter w(out, 6, sim::Simulator::fields());
  sim::make_simulator(s)->run([&](const RobotSample& x) { w.write(x); });
  w.close();
  return out;
}

struct Data {
  std::string excitation, figure8;
  Data() {
    const auto dir = std::filesystem::temp_directory_path();
    excitation = simulate_to_csv("excitation", 60 * kMinutesPerRun, (dir / "twinwatch_bench_exc.csv").string());
    figure8 = simulate_to_csv("nominal_figure_eight", 60 * kMinutesPerRun, (dir / "twinwatch_bench_fig8.csv").string());
  }
  ~Data() {
    std::remove(excitation.c_str());
    std::remove(figure8.c_str());
  }
};

const Data& data() {
  static const Data d;
  return d;
}

void BM_IdentifyPhysics10Minutes(benchmark::State& state) {
  const Data& d = data();
  model::RigidBodyInertia payload;
  payload.mass = 0.5;
  payload.com = Eigen::Vector3d(0, 0, 0.04);
  long samples = 0;
  for (auto _ : state) {
    // read: the CLI's path, CSV parse included
    const device::Recording exc = device::read_recording(d.excitation);
    const device::Recording fig = device::read_recording(d.figure8);
    samples = static_cast<long>(exc.samples.size() + fig.samples.size());
    ident::IdentReport report;
    ident::TwinModel twin = ident::identify_physics("ur3e", {{&exc, {}}, {&fig, payload}}, ident::IdentOptions{}, report);
    benchmark::DoNotOptimize(twin.beta.data());
  }
  state.counters["samples"] = static_cast<double>(samples);
  state.counters["data_minutes"] = 2 * kMinutesPerRun;
}
BENCHMARK(BM_IdentifyPhysics10Minutes)->Unit(benchmark::kSecond)->Iterations(2)->UseRealTime();

// the CSV parse alone, to show where the time goes
void BM_ReadRecordings10Minutes(benchmark::State& state) {
  const Data& d = data();
  for (auto _ : state) {
    const device::Recording exc = device::read_recording(d.excitation);
    const device::Recording fig = device::read_recording(d.figure8);
    benchmark::DoNotOptimize(exc.samples.data());
    benchmark::DoNotOptimize(fig.samples.data());
  }
}
BENCHMARK(BM_ReadRecordings10Minutes)->Unit(benchmark::kSecond)->Iterations(2)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
