// The monitor's per-sample loop (twin prediction, residual, filter, thresholds, the momentum
// observer and its threshold, ring buffer, debounce) allocates nothing once constructed (STYLE.md:
// hot loops allocate nothing; bench/monitor measures its speed). Own executable, because it
// interposes malloc (tests/malloc_counter.hpp).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>

#include "twinwatch/ident/twin_model.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/monitor/monitor.hpp"

#include "malloc_counter.hpp"  // counts heap allocations (one TU per test binary)

namespace twinwatch::monitor {
namespace {

TEST(MonitorAllocation, CounterSeesAnAllocation) {
  g_allocations = 0;
  g_counting = true;
  void* probe = std::malloc(16);
  g_counting = false;
  std::free(probe);
  ASSERT_EQ(g_allocations.load(), 1);
}

TEST(MonitorAllocation, PushWithTheMomentumObserverAllocatesNothing) {
  const model::RobotModel rm = model::load_robot("ur3e");
  ident::TwinModel twin("ur3e", rm);
  const model::BaseParameters base = model::compute_base_parameters(rm);
  twin.base_columns = base.independent;
  twin.beta = Eigen::VectorXd::Constant(base.rank, 0.01);
  twin.joints.assign(6, ident::JointDrive{});
  for (auto& j : twin.joints) j.gain = 10.0, j.c_gen = 0.8;
  twin.gains_absolute = true;
  MonitorConfig cfg;
  cfg.static_level = VectorJ::Constant(6, 1e9);  // never raises: the per-sample path only
  cfg.use_dynamic = true;
  for (int j = 0; j < 6; ++j) cfg.dynamic.push_back({0.01, 0.1, 0.2, 1e9, 5.0, 0.0, 0.0});
  cfg.observer_level = VectorJ::Constant(6, 1e9);
  cfg.observer_dynamic = cfg.dynamic;
  cfg.observer_alerts = true;
  cfg.trend.enabled = false;  // the wear trend works per cycle window, not per sample
  Monitor mon(twin, cfg);
  RobotSample s = RobotSample::empty(6);
  auto fill = [&](int k) {
    const double t = 0.002 * k;
    s.timestamp = t;
    for (int j = 0; j < 6; ++j) {
      const double w = 1.0 + 0.3 * j;
      s.q[j] = 0.5 * std::sin(w * t);
      s.qd[j] = 0.5 * w * std::cos(w * t);
      s.target_qdd[j] = -0.5 * w * w * std::sin(w * t);
      s.current[j] = 0.1 * std::sin(3.0 * t + j);
      s.temperature[j] = 35.0;
    }
  };
  for (int k = 0; k < 200; ++k) fill(k), mon.push(s);  // warm (observer settled, ring full of zeros)
  ASSERT_TRUE(mon.events().empty());
  g_allocations = 0;
  g_counting = true;
  for (int k = 200; k < 2200; ++k) fill(k), mon.push(s);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_TRUE(mon.events().empty());
  EXPECT_NE(mon.observer_residual().norm(), 0.0);  // the observer ran
}

}  // namespace
}  // namespace twinwatch::monitor
