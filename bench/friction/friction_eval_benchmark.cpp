// Per-sample evaluation of every residual-torque model of the HESR study (HESR Table VI), side by
// side in the same run, and the identification time of ParFam-H on 20 s of 200 Hz data.
// Goals (issue 6): ParFam-H evaluation <= 0.2 us per sample, identification <= 30 s.
//   build-bench/bench/friction/friction_eval_benchmark
#include <benchmark/benchmark.h>

#include <memory>

#include "twinwatch/friction/study.hpp"

namespace {

using namespace twinwatch::friction;

struct Setup {
  FrictionStudyData data;
  JointStudy study;
  Setup() : data(simulated_study_data(simulated_study_joints()[1], 1)), study(run_friction_study(data)) {}
};
const Setup& setup() {
  static const Setup s;
  return s;
}

// one pass of step() over the 4001-sample Fourier record (hysteresis/bristle state update + model)
void BM_Step(benchmark::State& state, const char* name) {
  const Setup& s = setup();
  FrictionModel& m = *s.study.model(name).model;
  const std::vector<double>& qd = s.data.fourier.qd;
  for (auto _ : state) {
    m.start(s.data.fourier.dt);
    double acc = 0.0;
    for (double v : qd) acc += m.step(v);
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(qd.size()));
}
BENCHMARK_CAPTURE(BM_Step, LuGre, "LuGre");
BENCHMARK_CAPTURE(BM_Step, Stribeck, "Stribeck");
BENCHMARK_CAPTURE(BM_Step, RBFNN, "RBFNN");
BENCHMARK_CAPTURE(BM_Step, RBFNN_H, "RBFNN-H");
BENCHMARK_CAPTURE(BM_Step, ParFam_V, "ParFam-V");
BENCHMARK_CAPTURE(BM_Step, ParFam_H, "ParFam-H");

// the hysteresis state alone over the Fourier record: HESR's time clock (Euler, eq. 11) vs the
// displacement clock (one exp per sample more)
void BM_HysteresisState(benchmark::State& state, HysteresisDrive drive) {
  const Setup& s = setup();
  const std::vector<double>& qd = s.data.fourier.qd;
  HysteresisState h(HysteresisParams{drive == HysteresisDrive::Time ? 20.0 : 600.0, 30.0, drive}, s.data.fourier.dt);
  for (auto _ : state) {
    h.reset();
    double acc = 0.0;
    for (double v : qd) acc += h.step(v).hd;
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(qd.size()));
}
BENCHMARK_CAPTURE(BM_HysteresisState, Time, HysteresisDrive::Time);
BENCHMARK_CAPTURE(BM_HysteresisState, Displacement, HysteresisDrive::Displacement);

// the three stages of ParFam-H on the 20 s, 200 Hz sweep of J2, with the study's options
// (displacement clock, viscous-free Stage 1, two tanh units, gamma 1e-6) and with the library's
// (HESR as printed: time clock, sin/cos/exp/tanh, gamma 1e-5)
void BM_IdentifyParFamH(benchmark::State& state, bool study) {
  const Setup& s = setup();
  for (auto _ : state) {
    ParFamModel m(study ? study_parfam_options() : ParFamOptions{});
    benchmark::DoNotOptimize(m.fit(s.data.train));
  }
}
BENCHMARK_CAPTURE(BM_IdentifyParFamH, Study, true)->Unit(benchmark::kSecond)->Iterations(3);
BENCHMARK_CAPTURE(BM_IdentifyParFamH, TimeClock, false)->Unit(benchmark::kSecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
