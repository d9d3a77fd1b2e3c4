// RTDE benchmarks (issue #4 goals):
//   BM_DecodeDataPackage/30      ≥ 2 million data packages per second for a 30-field recipe
//   BM_LoopbackLatency500Hz      server send → client pop, p99 ≤ 1 ms at 500 Hz
//                                (and the client's reader thread < 5 % of one core)
// Run: build-bench/bench/device/rtde_benchmark --benchmark_repetitions=3
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "twinwatch/core/log.hpp"
#include "twinwatch/device/rtde_client.hpp"
#include "twinwatch/device/rtde_server.hpp"

namespace rtde = twinwatch::device::rtde;

namespace {

// The first n output fields of the controller's table: with n = 30 that is timestamp, 21 VECTOR6D,
// joint_mode, 3 INT32 and 4 UINT32 — 137 scalars, 1105 payload bytes: a heavy recipe.
std::vector<std::string> first_fields(int n) {
  std::vector<std::string> names;
  for (const auto& f : rtde::output_fields()) {
    if (static_cast<int>(names.size()) == n) break;
    names.push_back(f.name);
  }
  return names;
}

void BM_DecodeDataPackage(benchmark::State& state) {
  const auto names = first_fields(static_cast<int>(state.range(0)));
  rtde::ServerRecipe sr;
  sr.id = 1;
  std::vector<std::string> types;
  for (const auto& n : names) {
    sr.fields.push_back(rtde::find_output_field(n));
    types.emplace_back(rtde::type_name(sr.fields.back()->type));
  }
  std::vector<double> frame(static_cast<std::size_t>(rtde::frame_scalars()));
  for (std::size_t i = 0; i < frame.size(); ++i) frame[i] = 0.37 * static_cast<double>(i);
  rtde::Bytes bytes;
  rtde::encode_data_package(bytes, 2, sr, frame.data());
  const auto recipe = rtde::OutputRecipe::from_reply(names, {1, types}, 2);
  // through the framer as the client does: cut the package, then decode it
  rtde::Framer framer;
  std::vector<double> values(static_cast<std::size_t>(recipe.values));
  for (auto _ : state) {
    framer.feed(bytes.data(), bytes.size());
    rtde::Package p;
    framer.next(p);
    rtde::decode_data_package(p, recipe, values.data());
    benchmark::DoNotOptimize(values.data());
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["payload_bytes"] = static_cast<double>(recipe.payload_size);
  state.counters["scalars"] = recipe.values;
}
BENCHMARK(BM_DecodeDataPackage)->Arg(30)->Arg(12);

// 500 Hz for 5 s over loopback: the virtual controller publishes (stamping the send time in an
// output double register), the client's consumer pops; latency = pop time − send time.
void BM_LoopbackLatency500Hz(benchmark::State& state) {
  twinwatch::log::set_sink(nullptr);
  for (auto _ : state) {
    rtde::ServerOptions so;
    so.port = 0;
    rtde::Server server(so);
    server.start();
    rtde::ClientOptions co;
    co.port = server.port();
    co.outputs = rtde::default_outputs();
    co.outputs.push_back("output_double_register_0");
    rtde::Client client(co);
    client.start();
    while (server.stats().streaming < 1) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const int stamp = rtde::find_output_field("output_double_register_0")->slot;
    const int ts = rtde::find_output_field("timestamp")->slot;
    const int stamp_index = client.recipe().value_index[static_cast<std::size_t>(client.recipe().index_of("output_double_register_0"))];
    (void)stamp_index;
    std::vector<double> frame(static_cast<std::size_t>(rtde::frame_scalars()), 0.0);
    const long n = 2500;
    std::vector<double> latency;
    latency.reserve(n);
    // The consumer: pops and measures against the send time kept per timestamp.
    std::vector<std::chrono::steady_clock::time_point> sent(static_cast<std::size_t>(n));
    std::atomic<long> published{0};
    std::thread consumer([&] {
      twinwatch::RobotSample s;
      long got = 0;
      while (got < n) {
        if (!client.pop(s, std::chrono::milliseconds(100))) {
          if (published.load() >= n) break;
          continue;
        }
        const auto now = std::chrono::steady_clock::now();
        const long k = std::lround(s.timestamp / 0.002);
        if (k >= 0 && k < n) latency.push_back(std::chrono::duration<double>(now - sent[static_cast<std::size_t>(k)]).count());
        ++got;
      }
    });
    const auto t0 = std::chrono::steady_clock::now();
    for (long k = 0; k < n; ++k) {
      std::this_thread::sleep_until(t0 + std::chrono::microseconds(2000 * k));
      frame[static_cast<std::size_t>(ts)] = 0.002 * static_cast<double>(k);
      frame[static_cast<std::size_t>(stamp)] = static_cast<double>(k);
      sent[static_cast<std::size_t>(k)] = std::chrono::steady_clock::now();
      server.publish(frame.data());
      published = k + 1;
    }
    consumer.join();
    const auto st = client.stats();
    client.stop();
    server.stop();
    std::sort(latency.begin(), latency.end());
    auto pct = [&](double p) { return latency.empty() ? -1.0 : latency[static_cast<std::size_t>(p * static_cast<double>(latency.size() - 1))]; };
    state.counters["received"] = static_cast<double>(latency.size());
    state.counters["p50_us"] = 1e6 * pct(0.50);
    state.counters["p99_us"] = 1e6 * pct(0.99);
    state.counters["max_us"] = 1e6 * pct(1.0);
    state.counters["client_cpu_pct"] = 100.0 * st.cpu_seconds / st.wall_seconds;
    state.counters["lost"] = static_cast<double>(st.lost);
  }
}
BENCHMARK(BM_LoopbackLatency500Hz)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
