// Dynamics kernels of twinwatch side by side with Orocos KDL on the UR3e, in one binary and run.
//   cmake -B build-bench -DBUILD_BENCHMARKS=ON && cmake --build build-bench --target dynamics_benchmark
//   build-bench/bench/model/dynamics_benchmark --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// Each iteration uses the next of 1024 pre-drawn random states, so branch prediction and caches
// see varying inputs as they would in a real loop. "/baseline" is twinwatch before the issue-2
// rewrite (dynamics_baseline.hpp), kept to measure the rewrite against in the same run.
#include <benchmark/benchmark.h>

#include <kdl/chaindynparam.hpp>
#include <kdl/chainfdsolver_recursive_newton_euler.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <random>
#include <vector>

#include "dynamics_baseline.hpp"
#include "kdl_chain.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "twinwatch/model/regressor.hpp"

namespace {

using namespace twinwatch;

constexpr int kStates = 1024;

struct States {
  std::vector<VectorJ> q, qd, qdd;
  std::vector<KDL::JntArray> kq, kqd, kqdd;
  States() {
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int s = 0; s < kStates; ++s) {
      VectorJ a(6), b(6), c(6);
      KDL::JntArray ka(6), kb(6), kc(6);
      for (int i = 0; i < 6; ++i) {
        a[i] = 3 * u(rng), b[i] = 2 * u(rng), c[i] = 5 * u(rng);
        ka(i) = a[i], kb(i) = b[i], kc(i) = c[i];
      }
      q.push_back(a), qd.push_back(b), qdd.push_back(c);
      kq.push_back(ka), kqd.push_back(kb), kqdd.push_back(kc);
    }
  }
};

const States& states() {
  static const States s;
  return s;
}
const model::RobotModel& ur3e() {
  static const model::RobotModel m = model::load_robot("ur3e");
  return m;
}

void BM_Rnea_twinwatch(benchmark::State& st) {
  model::DynamicsData d(ur3e());
  const auto& s = states();
  int k = 0;
  for (auto _ : st) {
    benchmark::DoNotOptimize(model::rnea(ur3e(), d, s.q[k], s.qd[k], s.qdd[k]).data());
    k = (k + 1) & (kStates - 1);
  }
}
// two accelerations of one state: rnea_pair against two rnea calls (the monitor's current residual
// and its momentum observer, docs/benchmarks.md issue 7)
void BM_RneaTwoAccelerations_pair(benchmark::State& st) {
  model::DynamicsData d(ur3e());
  const auto& s = states();
  VectorJ tau2(6);
  int k = 0;
  for (auto _ : st) {
    const int k2 = (k + 1) & (kStates - 1);
    benchmark::DoNotOptimize(model::rnea_pair(ur3e(), d, s.q[k], s.qd[k], s.qdd[k], s.qdd[k2], tau2).data());
    benchmark::DoNotOptimize(tau2.data());
    k = k2;
  }
}
void BM_RneaTwoAccelerations_two(benchmark::State& st) {
  model::DynamicsData d(ur3e());
  const auto& s = states();
  VectorJ tau(6);
  int k = 0;
  for (auto _ : st) {
    const int k2 = (k + 1) & (kStates - 1);
    tau = model::rnea(ur3e(), d, s.q[k], s.qd[k], s.qdd[k]);
    benchmark::DoNotOptimize(tau.data());
    benchmark::DoNotOptimize(model::rnea(ur3e(), d, s.q[k], s.qd[k], s.qdd[k2]).data());
    k = k2;
  }
}
void BM_Rnea_baseline(benchmark::State& st) {
  model::DynamicsData d(ur3e());
  const auto& s = states();
  int k = 0;
  for (auto _ : st) {
    benchmark::DoNotOptimize(model::baseline::rnea(ur3e(), d, s.q[k], s.qd[k], s.qdd[k]).data());
    k = (k + 1) & (kStates - 1);
  }
}
void BM_Rnea_kdl(benchmark::State& st) {
  const KDL::Chain chain = testing_support::to_kdl_chain(ur3e());
  KDL::ChainIdSolver_RNE id(chain, KDL::Vector(0, 0, -9.81));
  KDL::JntArray tau(6);
  KDL::Wrenches f(chain.getNrOfSegments(), KDL::Wrench::Zero());
  const auto& s = states();
  int k = 0;
  for (auto _ : st) {
    id.CartToJnt(s.kq[k], s.kqd[k], s.kqdd[k], f, tau);
    benchmark::DoNotOptimize(tau.data.data());
    k = (k + 1) & (kStates - 1);
  }
}
void BM_MassMatrix_twinwatch(benchmark::State& st) {
  model::DynamicsData d(ur3e());
  const auto& s = states();
  int k = 0;
  for (auto _ : st) {
    benchmark::DoNotOptimize(model::crba(ur3e(), d, s.q[k]).data());
    k = (k + 1) & (kStates - 1);
  }
}
void BM_MassMatrix_kdl(benchmark::State& st) {
  const KDL::Chain chain = testing_support::to_kdl_chain(ur3e());
  KDL::ChainDynParam dyn(chain, KDL::Vector(0, 0, -9.81));
  KDL::JntSpaceInertiaMatrix M(6);
  const auto& s = states();
  int k = 0;
  for (auto _ : st) {
    dyn.JntToMass(s.kq[k], M);
    benchmark::DoNotOptimize(M.data.data());
    k = (k + 1) & (kStates - 1);
  }
}
void BM_ForwardDynamics_twinwatch(benchmark::State& st) {
  model::DynamicsData d(ur3e());
  const auto& s = states();
  int k = 0;
  for (auto _ : st) {
    benchmark::DoNotOptimize(model::forward_dynamics(ur3e(), d, s.q[k], s.qd[k], s.qdd[k]).data());
    k = (k + 1) & (kStates - 1);
  }
}
// KDL 1.5's ChainFdSolver_RNE: CRBA-like mass matrix by ChainDynParam + RNE bias + LDL solve
void BM_ForwardDynamics_kdl(benchmark::State& st) {
  const KDL::Chain chain = testing_support::to_kdl_chain(ur3e());
  KDL::ChainFdSolver_RNE fd(chain, KDL::Vector(0, 0, -9.81));
  KDL::JntArray qdd(6);
  KDL::Wrenches f(chain.getNrOfSegments(), KDL::Wrench::Zero());
  const auto& s = states();
  int k = 0;
  for (auto _ : st) {
    fd.CartToJnt(s.kq[k], s.kqd[k], s.kqdd[k], f, qdd);
    benchmark::DoNotOptimize(qdd.data.data());
    k = (k + 1) & (kStates - 1);
  }
}
void BM_Regressor_twinwatch(benchmark::State& st) {
  model::DynamicsData d(ur3e());
  model::RegressorMatrix Y;
  const auto& s = states();
  int k = 0;
  for (auto _ : st) {
    model::regressor(ur3e(), d, s.q[k], s.qd[k], s.qdd[k], Y);
    benchmark::DoNotOptimize(Y.data());
    k = (k + 1) & (kStates - 1);
  }
}
void BM_Regressor_baseline(benchmark::State& st) {
  model::DynamicsData d(ur3e());
  model::RegressorMatrix Y;
  const auto& s = states();
  int k = 0;
  for (auto _ : st) {
    model::baseline::regressor(ur3e(), d, s.q[k], s.qd[k], s.qdd[k], Y);
    benchmark::DoNotOptimize(Y.data());
    k = (k + 1) & (kStates - 1);
  }
}

BENCHMARK(BM_Rnea_twinwatch)->Name("BM_Rnea/twinwatch");
BENCHMARK(BM_Rnea_baseline)->Name("BM_Rnea/baseline");
BENCHMARK(BM_Rnea_kdl)->Name("BM_Rnea/kdl");
BENCHMARK(BM_RneaTwoAccelerations_pair)->Name("BM_RneaTwoAccelerations/rnea_pair");
BENCHMARK(BM_RneaTwoAccelerations_two)->Name("BM_RneaTwoAccelerations/two_rnea");
BENCHMARK(BM_MassMatrix_twinwatch)->Name("BM_MassMatrix/twinwatch");
BENCHMARK(BM_MassMatrix_kdl)->Name("BM_MassMatrix/kdl");
BENCHMARK(BM_ForwardDynamics_twinwatch)->Name("BM_ForwardDynamics/twinwatch");
BENCHMARK(BM_ForwardDynamics_kdl)->Name("BM_ForwardDynamics/kdl");
BENCHMARK(BM_Regressor_twinwatch)->Name("BM_Regressor/twinwatch");
BENCHMARK(BM_Regressor_baseline)->Name("BM_Regressor/baseline");

}  // namespace

BENCHMARK_MAIN();
