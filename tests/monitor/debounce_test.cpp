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

}  // namespace
}  // namespace twinwatch::monitor
