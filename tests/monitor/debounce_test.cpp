#include "twinwatch/monitor/debounce.hpp"

#include <gtest/gtest.h>

namespace twinwatch::monitor {
namespace {

TEST(Debouncer, RaisesAfterNConsecutiveAndResetsOnABreak) {
  Debouncer d(3, 2);
  using C = Debouncer::Change;
  EXPECT_EQ(d.update(true, 0.0), C::None);
  EXPECT_EQ(d.update(true, 0.1), C::None);
  EXPECT_EQ(d.update(false, 0.2), C::None);  // counter back to 0
  EXPECT_EQ(d.update(true, 0.3), C::None);
  EXPECT_EQ(d.update(true, 0.4), C::None);
  EXPECT_EQ(d.update(true, 0.5), C::Raised);
  EXPECT_DOUBLE_EQ(d.start(), 0.3) << "the alert starts at the first exceedance of the run";
  EXPECT_EQ(d.update(true, 0.6), C::None);
  EXPECT_EQ(d.update(false, 0.7), C::None);
  EXPECT_EQ(d.update(true, 0.8), C::None);   // a single exceedance keeps it active
  EXPECT_EQ(d.update(false, 0.9), C::None);
  EXPECT_EQ(d.update(false, 1.0), C::Cleared);
  EXPECT_DOUBLE_EQ(d.end(), 1.0);
  EXPECT_FALSE(d.active());
}

TEST(Debouncer, IsolatedSpikesNeverRaise) {
  Debouncer d(3, 5);
  for (int k = 0; k < 1000; ++k) EXPECT_NE(d.update(k % 3 == 0, k * 0.002), Debouncer::Change::Raised);
}

// The margin of a debounced decision: the largest v that raise_after consecutive ratios all exceeded
// (max over windows of the window's min), i.e. the sensitivity below which the debouncer raises.
TEST(DebouncedPeak, IsTheLargestMinimumOverEveryRunOfRaiseAfterSamples) {
  const double ratios[] = {0.5, 0.9, 0.8, 0.2, 1.2, 0.1};
  DebouncedPeak one(1), two(2), three(3);
  for (double r : ratios) {
    one.update(r);
    two.update(r);
    three.update(r);
  }
  EXPECT_DOUBLE_EQ(one.peak(), 1.2);    // a single sample raises
  EXPECT_DOUBLE_EQ(two.peak(), 0.8);    // 0.9, 0.8
  EXPECT_DOUBLE_EQ(three.peak(), 0.5);  // 0.5, 0.9, 0.8
  DebouncedPeak early(3);
  early.update(2.0);
  early.update(2.0);
  EXPECT_DOUBLE_EQ(early.peak(), 0.0) << "fewer than raise_after samples are no run";
  // the same decisions through a Debouncer at a threshold just below / above the peak
  for (const double s : {0.79, 0.81}) {
    Debouncer d(2, 5);
    bool raised = false;
    for (int k = 0; k < 6; ++k) raised |= d.update(ratios[k] > s, 0.002 * k) == Debouncer::Change::Raised;
    EXPECT_EQ(raised, s < two.peak()) << "sensitivity " << s;
  }
}

}  // namespace
}  // namespace twinwatch::monitor
