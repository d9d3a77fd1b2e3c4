#include "twinwatch/signal/fir.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <random>

#include "signal/fixture_csv.hpp"
#include "twinwatch/core/error.hpp"

#include "malloc_counter.hpp"  // counts heap allocations (one TU per test binary)
#include "error_text.hpp"

namespace twinwatch::signal {
namespace {

constexpr double kFs = 500.0;  // RTDE rate [Hz]

TEST(FirDesign, KaiserLowpassMatchesScipyFirwin) {
  const auto rows = test::read_fixture("firwin_kaiser_scipy.csv");
  ASSERT_EQ(rows.size(), 6u);
  for (const auto& r : rows) {
    const int n = static_cast<int>(r[0]);
    const auto h = fir_lowpass_kaiser(n, r[1], r[2], r[3]);
    ASSERT_EQ(h.size() + 4, r.size());
    for (size_t k = 0; k < h.size(); ++k)
      EXPECT_NEAR(h[k], r[4 + k], 1e-12) << "numtaps " << n << " cutoff " << r[1] << " beta " << r[2] << " tap " << k;
  }
}

TEST(FirDesign, KaiserWindowOfBetaZeroIsRectangularAndIsSymmetric) {
  for (double w : kaiser_window(7, 0.0)) EXPECT_DOUBLE_EQ(w, 1.0);
  const auto w = kaiser_window(8, 6.0);
  for (size_t k = 0; k < w.size(); ++k) EXPECT_DOUBLE_EQ(w[k], w[w.size() - 1 - k]);
  EXPECT_NEAR(w[0], 1.0 / std::cyl_bessel_i(0.0, 6.0), 1e-15);
}

// Cao eq. (29) at the UR's 500 Hz: unit DC gain, a zero at Nyquist, -3 dB at 42.8 Hz, first null at
// 104 Hz and >= 20 dB attenuation from 92 Hz up (side lobe peak 0.093 = -20.6 dB); the magnitude is
// the closed form of a symmetric even-length FIR
TEST(CaoFir, FrequencyResponse) {
  const auto h = cao_torque_fir_taps();
  ASSERT_EQ(h.size(), 6u);
  EXPECT_NEAR(fir_magnitude(h, 0.0, kFs), 1.0, 1e-12);
  EXPECT_NEAR(fir_magnitude(h, 0.5 * kFs, kFs), 0.0, 1e-12);
  for (double f = 0.0; f <= 250.0; f += 1.0) {
    const double w = 2 * M_PI * f / kFs;
    const double closed = std::abs(2 * (h[0] * std::cos(2.5 * w) + h[1] * std::cos(1.5 * w) + h[2] * std::cos(0.5 * w)));
    ASSERT_NEAR(fir_magnitude(h, f, kFs), closed, 1e-12) << f;
    if (f >= 92.0) {
      EXPECT_LT(fir_magnitude(h, f, kFs), 0.1) << "stop band at " << f << " Hz";  // -20 dB
    }
  }
  double side = 0.0;
  for (double f = 105.0; f <= 250.0; f += 0.1) side = std::max(side, fir_magnitude(h, f, kFs));
  EXPECT_NEAR(side, 0.093, 0.0005);
  EXPECT_LT(fir_magnitude(h, 104.1, kFs), 1e-3);
  // the -3 dB point by bisection
  double lo = 1.0, hi = 200.0;
  for (int i = 0; i < 60; ++i) (fir_magnitude(h, 0.5 * (lo + hi), kFs) > 1 / std::sqrt(2.0) ? lo : hi) = 0.5 * (lo + hi);
  EXPECT_NEAR(lo, 42.8, 0.05);
  // the paper's 10 Hz is the -3 dB point at about fs = 117 Hz
  EXPECT_NEAR(fir_magnitude(h, 10.0, 116.8), 1 / std::sqrt(2.0), 2e-3);
}

// the claim in fir.hpp: no firwin(6, fc, ('kaiser', beta)) reproduces the printed taps
TEST(CaoFir, PrintedTapsAreNotAKaiserWindowedSinc) {
  const auto cao = cao_torque_fir_taps();
  double best = 1.0;
  for (double c = 0.005; c < 0.995; c += 0.005)
    for (double beta = 0.0; beta <= 10.0; beta += 0.05) {
      const auto h = fir_lowpass_kaiser(6, c * 50.0, beta, 100.0);
      double err = 0.0;
      for (size_t k = 0; k < 6; ++k) err = std::max(err, std::abs(h[k] - cao[k]));
      best = std::min(best, err);
    }
  EXPECT_GT(best, 0.006);  // the printed taps have 4 decimals: a match would be within 5e-5
  EXPECT_LT(best, 0.0075);
}

// linear phase: a ramp comes out delayed by exactly (taps - 1) / 2 = 2.5 samples, and a sinusoid
// with gain |H| and the same delay
TEST(CaoFir, GroupDelayIsTwoAndAHalfSamples) {
  FirFilter f(cao_torque_fir_taps());
  EXPECT_DOUBLE_EQ(f.group_delay(), 2.5);
  for (int k = 0; k < 40; ++k) {
    const double y = f.push(0.01 * k);
    if (k >= 5) {
      ASSERT_NEAR(y, 0.01 * (k - 2.5), 1e-12) << k;
    }
  }
  FirFilter g(cao_torque_fir_taps());
  const double fhz = 20.0, w = 2 * M_PI * fhz / kFs, gain = fir_magnitude(cao_torque_fir_taps(), fhz, kFs);
  for (int k = 0; k < 100; ++k) {
    const double y = g.push(std::sin(w * k));
    if (k >= 5) {
      ASSERT_NEAR(y, gain * std::sin(w * (k - 2.5)), 1e-12) << k;
    }
  }
}

// the streaming filter equals the direct convolution of the input preceded by its first value
TEST(FirFilter, StreamingEqualsConvolutionOnRandomInput) {
  const unsigned seed = 4242;
  std::mt19937 rng(seed);
  std::normal_distribution<double> nd(0.0, 1.0);
  for (int numtaps : {1, 2, 6, 17}) {
    std::vector<double> h(static_cast<size_t>(numtaps)), x(300);
    for (double& v : h) v = nd(rng);
    for (double& v : x) v = nd(rng);
    FirFilter f(h);
    for (size_t n = 0; n < x.size(); ++n) {
      double want = 0.0;
      for (size_t k = 0; k < h.size(); ++k) want += h[k] * (n >= k ? x[n - k] : x[0]);
      ASSERT_NEAR(f.push(x[n]), want, 1e-12) << "seed " << seed << " taps " << numtaps << " n " << n;
    }
    // reset: starts again from the next sample
    f.reset();
    double s = 0.0;
    for (double v : h) s += v;
    EXPECT_NEAR(f.push(3.0), 3.0 * s, 1e-12);
  }
}

TEST(FirFilter, PushAllocatesNothing) {
  FirFilter f(fir_lowpass_kaiser(31, 10.0, 8.6, kFs));
  double acc = 0.0;
  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < 1000; ++k) acc += f.push(std::sin(0.01 * k));
  f.reset();
  acc += f.push(1.0);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
  EXPECT_TRUE(std::isfinite(acc));
}

std::string error_of(const std::function<void()>& fn) {
  return twinwatch::test::error_text<InvalidArgument>([&] { fn(); });
}

TEST(FirDesign, ValidationNamesTheValueAndTheLimit) {
  EXPECT_THAT(error_of([] { fir_lowpass_kaiser(0, 10, 2, 500); }), ::testing::HasSubstr("numtaps is 0, must be >= 1"));
  EXPECT_THAT(error_of([] { fir_lowpass_kaiser(6, 250, 2, 500); }), ::testing::HasSubstr("cutoff_hz is 250, must be in (0, fs_hz / 2) = (0, 250)"));
  EXPECT_THAT(error_of([] { fir_lowpass_kaiser(6, 10, -1, 500); }), ::testing::HasSubstr("beta is -1, must be >= 0"));
  EXPECT_THAT(error_of([] { fir_lowpass_kaiser(6, 10, 2, 0); }), ::testing::HasSubstr("fs_hz is 0, must be > 0"));
  EXPECT_THAT(error_of([] { kaiser_window(0, 1); }), ::testing::HasSubstr("length is 0"));
  EXPECT_THAT(error_of([] { FirFilter f(std::vector<double>{}); }), ::testing::HasSubstr("no taps"));
  EXPECT_THAT(error_of([] { FirFilter f(std::vector<double>{0.5, NAN}); }), ::testing::HasSubstr("tap 1 is nan, must be finite"));
}

}  // namespace
}  // namespace twinwatch::signal
