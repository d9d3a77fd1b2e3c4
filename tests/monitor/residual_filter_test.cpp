// The monitor's residual filter per joint: the first-order IIR (default) or Cao's FIR (eq. 29).
// The twin is identified from healthy runs only; thresholds are learned with the FIR.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "twinwatch/core/error.hpp"
#include "twinwatch/ident/physics_ident.hpp"
#include "twinwatch/monitor/monitor.hpp"
#include "twinwatch/signal/fir.hpp"
#include "monitor/simulated_run.hpp"
#include "twinwatch/sim/scenario.hpp"

namespace twinwatch::monitor {
namespace {

using test::run;
using test::scenario;

// UR3e §4.2 J5 resistance with Cao's FIR on every joint's residual (thresholds learned with it),
// and the filters applied per joint as configured
TEST(ResidualFilter, J5ResistanceIsDetectedWithCaoFirAndFiltersArePerJoint) {
  const auto exc = run("robot: ur3e\nseed: 501\nduration: 60\ntrajectory: {type: fourier, amplitude: 0.9, period: 10, harmonics: 5, seed: 3}\n");
  const auto fig = run(scenario(502, 40, 0.5));
  model::RigidBodyInertia payload;
  payload.mass = 0.5;
  payload.com = Eigen::Vector3d(0, 0, 0.04);
  ident::IdentReport rep;
  ident::TwinModel twin = ident::identify_physics("ur3e", {{&exc, {}}, {&fig, payload}}, ident::IdentOptions{}, rep);
  const auto h1 = run(scenario(503, 24, 0.5));
  const auto h2 = run(scenario(504, 16, 0.0));
  MonitorConfig settings;
  settings.residual_filter = {"fir"};
  const MonitorConfig cfg = learn_thresholds(twin, {{&h1, payload}, {&h2, {}}}, settings);
  ASSERT_EQ(cfg.residual_filter, std::vector<std::string>{"fir"});
  twin.set_payload(payload);

  // detection and attribution as with the IIR (tests/monitor/monitor_test.cpp)
  const auto rec = run(scenario(603, 16, 0.5, "  - {type: resistance, joint: 5, onset: 6, ramp: 0.2, magnitude: 0.8}\n"));
  Monitor m(twin, cfg);
  for (const auto& s : rec.samples) m.push(s);
  m.finish();
  const auto& ev = m.events();
  ASSERT_FALSE(ev.empty());
  EXPECT_GE(ev.front().t_start, 6.0);
  EXPECT_LT(ev.front().t_detected, 8.0) << ev.front().detail;
  EXPECT_EQ(ev.front().fault, FaultClass::Resistance) << ev.front().detail;
  EXPECT_EQ(ev.front().joint, 4) << ev.front().detail;
  EXPECT_NEAR(ev.front().magnitude, 0.8, 0.3) << ev.front().detail;

  // per joint: FIR on J5 only, the IIR y += a (r - y) elsewhere, both from the first residual
  MonitorConfig mixed = cfg;
  mixed.residual_filter = {"iir", "iir", "iir", "iir", "fir", "iir"};
  Monitor mm(twin, mixed);
  signal::FirFilter fir(signal::cao_torque_fir_taps());
  const double a = 1.0 - std::exp(-2.0 * M_PI * mixed.filter_cutoff_hz * mixed.nominal_period);
  VectorJ iir;
  for (size_t k = 0; k < 1500; ++k) {
    mm.push(rec.samples[k]);
    const VectorJ& r = mm.residual();
    iir = k == 0 ? r : VectorJ(iir + a * (r - iir));
    const double want5 = fir.push(r[4]);
    ASSERT_NEAR(mm.filtered_residual()[4], want5, 1e-12) << k;
    for (int j : {0, 1, 2, 3, 5}) ASSERT_NEAR(mm.filtered_residual()[j], iir[j], 1e-12) << "joint " << j + 1 << " sample " << k;
  }
}

TEST(ResidualFilter, ConfigNamesAnUnknownKindAndAWrongCount) {
  MonitorConfig c;
  c.static_level = VectorJ::Ones(6);
  c.use_dynamic = false;
  c.residual_filter = {"iir", "butter"};
  c.residual_filter.resize(6, "iir");
  try {
    c.validate(6);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("residual_filter (--filter) of J2 is 'butter', expected 'iir' or 'fir'"));
  }
  c.residual_filter = {"fir", "fir"};
  try {
    c.validate(6);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("residual_filter (--filter) has 2 entries, expected 0, 1 or 6"));
  }
}

TEST(ResidualFilter, KindSurvivesTheTwinFile) {
  MonitorConfig c;
  c.static_level = VectorJ::Ones(6);
  c.use_dynamic = false;
  c.residual_filter = {"iir", "iir", "fir", "iir", "fir", "iir"};
  EXPECT_EQ(MonitorConfig::from_json(c.to_json(), "t").residual_filter, c.residual_filter);
  c.residual_filter.clear();
  EXPECT_TRUE(MonitorConfig::from_json(c.to_json(), "t").residual_filter.empty());  // default: IIR everywhere
}

}  // namespace
}  // namespace twinwatch::monitor
