#include "twinwatch/signal/butterworth.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>

#include "signal/fixture_csv.hpp"
#include "twinwatch/core/error.hpp"
#include "error_text.hpp"

namespace twinwatch::signal {
namespace {

// coefficients and outputs agree with scipy to rounding; the cascade has a few dozen operations
constexpr double kRelTol = 1e-11;  // measured: <= 1e-13 (design) and 3e-14 (filtfilt)

// |H(e^{i w})| of the cascade, evaluated directly from the section coefficients
double magnitude(const std::vector<Sos>& sos, double f, double fs) {
  const std::complex<double> z1 = std::polar(1.0, -2.0 * M_PI * f / fs);  // z^-1
  std::complex<double> H = 1.0;
  for (const Sos& c : sos) H *= (c[0] + c[1] * z1 + c[2] * z1 * z1) / (c[3] + c[4] * z1 + c[5] * z1 * z1);
  return std::abs(H);
}

// the bilinear-transformed Butterworth with prewarping, in closed form:
//   |H|^2 = 1 / (1 + (tan(pi f / fs) / tan(pi fc / fs))^(2N))
double analytic_magnitude(int N, double fc, double f, double fs) {
  return 1.0 / std::sqrt(1.0 + std::pow(std::tan(M_PI * f / fs) / std::tan(M_PI * fc / fs), 2 * N));
}

TEST(Butterworth, DesignAndInitialConditionsMatchScipy) {
  const auto rows = test::read_fixture("butter_sos_scipy.csv");
  ASSERT_EQ(rows.size(), 10u);
  for (const auto& r : rows) {
    const int N = static_cast<int>(r[0]);
    const auto sos = butterworth_lowpass(N, r[1], r[2]);
    const size_t ns = static_cast<size_t>((N + 1) / 2);
    ASSERT_EQ(sos.size(), ns) << "order " << N;
    ASSERT_EQ(r.size(), 3 + 6 * ns + 2 * ns) << "order " << N;
    for (size_t s = 0; s < ns; ++s)
      for (size_t c = 0; c < 6; ++c) {
        const double want = r[3 + 6 * s + c];
        EXPECT_NEAR(sos[s][c], want, kRelTol * std::abs(want) + 1e-14)
            << "order " << N << " cutoff " << r[1] << " fs " << r[2] << " section " << s << " coefficient " << c;
      }
    const auto zi = sosfilt_zi(sos);
    for (size_t i = 0; i < 2 * ns; ++i) {
      const double want = r[3 + 6 * ns + i];
      EXPECT_NEAR(zi[i], want, kRelTol * std::abs(want) + 1e-12) << "order " << N << " zi " << i;
    }
  }
}

TEST(Butterworth, FiltfiltMatchesScipyIncludingShortSignals) {
  const auto rows = test::read_fixture("sosfiltfilt_scipy.csv");
  ASSERT_EQ(rows.size(), 9u);
  const std::vector<double>& x = rows[0];
  for (size_t k = 1; k < rows.size(); ++k) {
    const auto& r = rows[k];
    const size_t used = static_cast<size_t>(r[3]);
    const ButterworthLowpass lp{static_cast<int>(r[0]), r[1], r[2]};
    const auto y = lp.apply(std::span<const double>(x.data(), used));
    ASSERT_EQ(y.size() + 4, r.size());
    for (size_t i = 0; i < used; ++i)
      ASSERT_NEAR(y[i], r[4 + i], kRelTol * 3.0) << "order " << lp.order << " cutoff " << lp.cutoff_hz << " n " << used << " sample " << i;
  }
}

// independent of scipy: the response of the sections equals the closed form, -3 dB at the cutoff
TEST(Butterworth, ResponseIsTheClosedFormButterworthOnRandomDesigns) {
  const unsigned seed = 20261123;
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> order(1, 12);
  std::uniform_real_distribution<double> u(0.002, 0.45);
  for (int trial = 0; trial < 200; ++trial) {
    const double fs = 500.0;
    const int N = order(rng);
    const double fc = u(rng) * fs;
    const auto sos = butterworth_lowpass(N, fc, fs);
    EXPECT_NEAR(magnitude(sos, 0.0, fs), 1.0, 1e-9) << "seed " << seed << " trial " << trial;
    EXPECT_NEAR(magnitude(sos, fc, fs), 1.0 / std::sqrt(2.0), 1e-9) << "seed " << seed << " trial " << trial;
    for (double f : {0.3 * fc, 0.9 * fc, std::min(1.5 * fc, 0.49 * fs), 0.49 * fs})
      EXPECT_NEAR(magnitude(sos, f, fs), analytic_magnitude(N, fc, f, fs), 1e-9)
          << "seed " << seed << " trial " << trial << " order " << N << " fc " << fc << " f " << f;
  }
}

// zero phase: a passband sinusoid comes out with amplitude |H|^2 and no lag; a constant is kept
TEST(Butterworth, FiltfiltHasZeroPhaseAndKeepsConstants) {
  const double fs = 500.0, f = 3.0, fc = 8.0;
  std::vector<double> x(2000);
  for (size_t k = 0; k < x.size(); ++k) x[k] = std::sin(2 * M_PI * f * static_cast<double>(k) / fs);
  const ButterworthLowpass lp{4, fc, fs};
  const auto y = lp.apply(x);
  const double gain = std::pow(analytic_magnitude(4, fc, f, fs), 2);
  // away from the ends (the padding transient decays within a few hundred samples)
  for (size_t k = 500; k < 1500; ++k) ASSERT_NEAR(y[k], gain * x[k], 1e-6) << k;
  const std::vector<double> c(100, 2.5);
  for (double v : lp.apply(c)) EXPECT_NEAR(v, 2.5, 1e-12);
}

TEST(Butterworth, CausalSosfiltStartsInSteadyStateWithScaledZi) {
  const auto sos = butterworth_lowpass(5, 20.0, 500.0);
  auto zi = sosfilt_zi(sos);
  for (double& v : zi) v *= -1.5;
  const std::vector<double> c(50, -1.5);
  for (double v : sosfilt(sos, c, zi)) EXPECT_NEAR(v, -1.5, 1e-12);
}

std::string error_of(const std::function<void()>& f) {
  return twinwatch::test::error_text<InvalidArgument>([&] { f(); });
}

TEST(Butterworth, ValidationNamesTheValueAndTheLimit) {
  EXPECT_THAT(error_of([] { butterworth_lowpass(0, 10, 500); }), ::testing::HasSubstr("order is 0, must be in [1, 20]"));
  EXPECT_THAT(error_of([] { butterworth_lowpass(21, 10, 500); }), ::testing::HasSubstr("order is 21, must be in [1, 20]"));
  EXPECT_THAT(error_of([] { butterworth_lowpass(4, 0, 500); }), ::testing::HasSubstr("cutoff_hz is 0, must be in (0, fs_hz / 2) = (0, 250)"));
  EXPECT_THAT(error_of([] { butterworth_lowpass(4, 250, 500); }), ::testing::HasSubstr("cutoff_hz is 250, must be in (0, fs_hz / 2)"));
  EXPECT_THAT(error_of([] { butterworth_lowpass(4, 10, -1); }), ::testing::HasSubstr("fs_hz is -1, must be > 0"));
  EXPECT_THAT(error_of([] { ButterworthLowpass{2, 600, 500}.validate(); }), ::testing::HasSubstr("cutoff_hz is 600"));
  EXPECT_THAT(error_of([] { ButterworthLowpass{-3, 6, 500}.validate(); }), ::testing::HasSubstr("order is -3"));
  // scipy's rule: more samples than padlen = 3 (2 sections + 1) = 15 for order 4
  const std::vector<double> x(15, 1.0);
  EXPECT_THAT(error_of([&] { ButterworthLowpass{4, 10, 500}.apply(x); }),
              ::testing::HasSubstr("input has 15 samples, must be more than padlen = 15"));
  EXPECT_THAT(error_of([&] { sosfiltfilt({}, x); }), ::testing::HasSubstr("no sections"));
  EXPECT_THAT(error_of([&] { sosfiltfilt(butterworth_lowpass(2, 10, 500), x, 20); }),
              ::testing::HasSubstr("input has 15 samples, must be more than padlen = 20"));
  std::vector<double> zi(3);
  const auto sos = butterworth_lowpass(4, 10, 500);
  EXPECT_THAT(error_of([&] { sosfilt(sos, x, zi); }), ::testing::HasSubstr("zi has 3 values, expected 2 per section = 4"));
}

TEST(Butterworth, PadlenFollowsScipyForOddAndEvenOrders) {
  EXPECT_EQ(sosfiltfilt_padlen(butterworth_lowpass(4, 10, 500)), 15);
  EXPECT_EQ(sosfiltfilt_padlen(butterworth_lowpass(3, 10, 500)), 12);  // one first-order section
  EXPECT_EQ(sosfiltfilt_padlen(butterworth_lowpass(1, 10, 500)), 6);
}

}  // namespace
}  // namespace twinwatch::signal
