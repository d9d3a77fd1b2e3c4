// The whole HESR protocol on one simulated joint (measured torque with a rigid body in it): the
// tables are consistent with each other and with what they claim to measure.
#include "twinwatch/friction/protocol.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::friction {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

constexpr unsigned kSeed = 1;

TEST(HesrProtocol, TablesOfASimulatedJointAreConsistent) {
  const ProtocolRecords r = simulated_protocol_records(simulated_study_joints()[2], kSeed);
  ProtocolOptions o;
  o.trials = 20;  // the CLI default is 200; the statistics only need to be sane here
  o.smoothing_windows = {9};
  const ProtocolResult p = run_hesr_protocol(r, o);
  ASSERT_EQ(p.study.models.size(), 6u);
  // Table III: a larger threshold keeps fewer samples; every fit has full rank on sweep data
  ASSERT_EQ(p.screening.size(), 3u);
  EXPECT_GT(p.screening[0].samples, p.screening[1].samples);
  EXPECT_GT(p.screening[1].samples, p.screening[2].samples);
  for (const ScreeningRow& s : p.screening) {
    EXPECT_EQ(s.rank, 6);
    EXPECT_LE(s.rmse_retained, s.rmse_all * 1.5);
  }
  // the nominal row of Tables IV and V is the study's ParFam-H
  const ModelStudy& ph = p.study.model("ParFam-H");
  EXPECT_DOUBLE_EQ(p.smoothing.front().reversal_rmse, ph.reversal_rmse);
  EXPECT_DOUBLE_EQ(p.uncertainty.front().fourier_mean, ph.fourier_rmse);
  ASSERT_EQ(p.smoothing.size(), 2u);
  EXPECT_TRUE(std::isfinite(p.smoothing[1].reversal_rmse));
  // Table V: added noise of level x RMS(tau_f) raises the RMSE about in quadrature: for the 5 %
  // level, sqrt(rmse^2 + (0.05 rms)^2) within the trials' spread
  ASSERT_EQ(p.uncertainty.size(), 4u);
  double rms = 0.0;
  const FrictionRecord res = p.rigid.residual(r.fourier);
  for (double t : res.tau) rms += t * t;
  rms = std::sqrt(rms / static_cast<double>(res.tau.size()));
  const UncertaintyRow& severe = p.uncertainty.back();
  EXPECT_NEAR(severe.level, 0.05, 1e-12);
  EXPECT_NEAR(severe.fourier_mean, std::hypot(ph.fourier_rmse, 0.05 * rms), 0.05 * ph.fourier_rmse + 3 * severe.fourier_std);
  EXPECT_GT(severe.fourier_std, p.uncertainty[1].fourier_std);
  for (const UncertaintyRow& u : p.uncertainty) {
    EXPECT_GE(u.first_share, 0.0);
    EXPECT_LE(u.first_share, 1.0);
  }
}

TEST(HesrProtocol, InvalidOptionsAreNamed) {
  ProtocolOptions o;
  o.trials = 0;
  EXPECT_THAT([&] { o.validate(); }, ThrowsMessage<InvalidArgument>(HasSubstr("protocol trials is 0")));
  o = {};
  o.smoothing_windows = {5, 8};
  EXPECT_THAT([&] { o.validate(); }, ThrowsMessage<InvalidArgument>(HasSubstr("smoothing_windows[1] is 8")));
  o = {};
  o.screening_thresholds = {-0.05};
  EXPECT_THAT([&] { o.validate(); }, ThrowsMessage<InvalidArgument>(HasSubstr("screening_thresholds[0] is -0.05")));
  o = {};
  o.uncertainty_levels = {0.01, std::nan("")};
  EXPECT_THAT([&] { o.validate(); }, ThrowsMessage<InvalidArgument>(HasSubstr("uncertainty_levels[1] is nan")));
}

}  // namespace
}  // namespace twinwatch::friction
