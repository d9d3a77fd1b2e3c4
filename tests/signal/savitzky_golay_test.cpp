#include "twinwatch/signal/savitzky_golay.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "twinwatch/core/error.hpp"
#include "error_text.hpp"

namespace twinwatch::signal {
namespace {

std::vector<double> parse(const std::string& line, size_t skip) {
  std::vector<double> v;
  std::stringstream ss(line);
  size_t k = 0;
  for (std::string c; std::getline(ss, c, ',');)
    if (k++ >= skip) v.push_back(std::stod(c));
  return v;
}

// against scipy.signal.savgol_filter (mode interp), fixture made by tests/data/signal/make_fixtures.py
TEST(SavitzkyGolay, MatchesScipyIncludingEdgesAndDerivatives) {
  std::ifstream f(std::string(TWINWATCH_SOURCE_DIR) + "/tests/data/signal/savgol_scipy.csv");
  ASSERT_TRUE(f);
  std::string line;
  std::getline(f, line);  // comment
  std::getline(f, line);
  const std::vector<double> x = parse(line, 0);
  int cases = 0;
  while (std::getline(f, line)) {
    const auto head = parse(line, 0);
    SavitzkyGolay sg{static_cast<int>(head[0]), static_cast<int>(head[1]), static_cast<int>(head[2]), 0.002};
    const std::vector<double> want(head.begin() + 3, head.end());
    const auto got = sg.apply(x);
    ASSERT_EQ(got.size(), want.size());
    double scale = 0;
    for (double w : want) scale = std::max(scale, std::abs(w));
    for (size_t k = 0; k < got.size(); ++k)
      ASSERT_NEAR(got[k], want[k], 1e-9 * scale) << "window " << sg.window << " order " << sg.order << " deriv " << sg.deriv << " k " << k;
    ++cases;
  }
  EXPECT_EQ(cases, 5);
}

TEST(SavitzkyGolay, DifferentiatesAPolynomialExactly) {
  std::vector<double> x;
  for (int k = 0; k < 50; ++k) x.push_back(0.5 * std::pow(k * 0.01, 3) - 2 * k * 0.01);
  const auto d1 = SavitzkyGolay{9, 3, 1, 0.01}.apply(x);
  for (int k = 0; k < 50; ++k) EXPECT_NEAR(d1[static_cast<size_t>(k)], 1.5 * std::pow(k * 0.01, 2) - 2, 1e-9);
}

std::string error_of(const SavitzkyGolay& sg, const std::vector<double>& x) {
  return twinwatch::test::error_text<InvalidArgument>([&] { sg.apply(x); });
}

TEST(SavitzkyGolay, ValidationNamesTheParameter) {
  const std::vector<double> x(20, 0.0);
  EXPECT_THAT(error_of({10, 3, 0, 1}, x), ::testing::HasSubstr("window is 10, must be odd"));
  EXPECT_THAT(error_of({5, 5, 0, 1}, x), ::testing::HasSubstr("order is 5"));
  EXPECT_THAT(error_of({5, 2, 3, 1}, x), ::testing::HasSubstr("deriv is 3"));
  EXPECT_THAT(error_of({5, 2, 0, 0}, x), ::testing::HasSubstr("delta is 0"));
  EXPECT_THAT(error_of({31, 2, 0, 1}, x), ::testing::HasSubstr("input has 20 samples"));
}

TEST(CentralDifference, ExactOnALineAndNamedErrors) {
  const std::vector<double> x{1, 3, 5, 7};
  for (double d : central_difference(x, 0.5)) EXPECT_DOUBLE_EQ(d, 4.0);
  EXPECT_THROW(central_difference(std::vector<double>{1}, 0.1), InvalidArgument);
}

}  // namespace
}  // namespace twinwatch::signal
