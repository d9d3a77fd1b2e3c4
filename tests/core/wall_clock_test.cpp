#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <ctime>
#include <random>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/wall_clock.hpp"

namespace twinwatch {
namespace {

// 2026-12-03T19:02:11Z, from the C library's own calendar (timegm), not from ours
double reference_unix(int y, int mo, int d, int h, int mi, int s) {
  std::tm tm{};
  tm.tm_year = y - 1900;
  tm.tm_mon = mo - 1;
  tm.tm_mday = d;
  tm.tm_hour = h;
  tm.tm_min = mi;
  tm.tm_sec = s;
  return static_cast<double>(timegm(&tm));
}

TEST(WallClock, IsoTextAgreesWithTheCLibrarysCalendar) {
  EXPECT_EQ(iso_utc(0.0), "1970-01-01T00:00:00.000Z");
  EXPECT_EQ(iso_utc(reference_unix(2026, 12, 3, 19, 2, 11) + 0.2344), "2026-12-03T19:02:11.234Z");
  // the millisecond rounds up into the next second, minute, day and year
  EXPECT_EQ(iso_utc(reference_unix(2026, 12, 31, 23, 59, 59) + 0.9996), "2027-01-01T00:00:00.000Z");
  EXPECT_EQ(iso_utc(reference_unix(2024, 2, 29, 12, 0, 0)), "2024-02-29T12:00:00.000Z");
}

TEST(WallClock, ParsesWhatItWritesAndEveryZoneForm) {
  const double t = reference_unix(2026, 12, 3, 8, 0, 0);
  EXPECT_DOUBLE_EQ(parse_iso_time("2026-12-03T08:00:00Z", "x"), t);
  EXPECT_DOUBLE_EQ(parse_iso_time("2026-12-03 08:00:00z", "x"), t);
  EXPECT_DOUBLE_EQ(parse_iso_time("2026-12-03T09:00:00+01:00", "x"), t);
  EXPECT_DOUBLE_EQ(parse_iso_time("2026-12-03T03:00:00-0500", "x"), t);
  EXPECT_DOUBLE_EQ(parse_iso_time("2026-12-03T13:30:00+05:30", "x"), t);
  EXPECT_NEAR(parse_iso_time("2026-12-03T08:00:00.250Z", "x"), t + 0.25, 1e-9);
  EXPECT_NEAR(parse_iso_time("2026-12-03T08:00:00,5Z", "x"), t + 0.5, 1e-9);
  // a leap day, the calendar's edges
  EXPECT_DOUBLE_EQ(parse_iso_time("2024-02-29T00:00:00Z", "x"), reference_unix(2024, 2, 29, 0, 0, 0));
  EXPECT_DOUBLE_EQ(parse_iso_time("2000-03-01T00:00:00Z", "x"), reference_unix(2000, 3, 1, 0, 0, 0));
  EXPECT_DOUBLE_EQ(parse_iso_time("1969-12-31T23:59:59Z", "x"), -1.0);
  // round trip over random times of this century, to the millisecond
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> when(0.0, 4.1e9);
  for (int k = 0; k < 2000; ++k) {
    const double u = std::round(when(rng) * 1000.0) / 1000.0;
    ASSERT_NEAR(parse_iso_time(iso_utc(u), "x"), u, 5e-4) << iso_utc(u);
  }
}

TEST(WallClock, RefusesTextItCannotPlaceNamingWhatAndWhy) {
  const auto message = [](const std::string& text) {
    try {
      parse_iso_time(text, "--started-at");
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  using ::testing::HasSubstr;
  EXPECT_THAT(message("2026-12-03T08:00:00"), HasSubstr("--started-at '2026-12-03T08:00:00': it has no zone"));
  EXPECT_THAT(message("2026-02-29T08:00:00Z"), HasSubstr("day 29 is not 1 to 28"));
  EXPECT_THAT(message("2026-13-01T08:00:00Z"), HasSubstr("month 13 is not 1 to 12"));
  EXPECT_THAT(message("2026-12-03T24:00:00Z"), HasSubstr("hour 24 is not 0 to 23"));
  EXPECT_THAT(message("2026-12-03T08:60:00Z"), HasSubstr("minute 60"));
  EXPECT_THAT(message("2026-12-03T08:00:60Z"), HasSubstr("leap second"));
  EXPECT_THAT(message("2026-12-03T08:00:00+15:00"), HasSubstr("beyond"));
  EXPECT_THAT(message("2026-12-03T08:00:00Z junk"), HasSubstr("' junk' after the zone"));
  EXPECT_THAT(message("2026-12-03T08:00:00.Z"), HasSubstr("no digits"));
  EXPECT_THAT(message("26-12-03T08:00:00Z"), HasSubstr("the year needs 4 digits"));
  EXPECT_THAT(message("yesterday"), HasSubstr("expected an ISO 8601 time with its zone"));
  EXPECT_THAT(message(""), HasSubstr("year"));
}

// A stream whose samples arrive with a random delay on top of a true offset: the clock's offset
// never comes out later than the true one plus the least delay of its window, never earlier than
// the true one, follows a drift, and starts afresh at a controller restart
TEST(WallClock, StreamOffsetIsTheLeastDelayedSampleAndFollowsDriftAndRestarts) {
  StreamWallClock clock(10.0, 30.0);
  EXPECT_TRUE(std::isnan(clock.offset()));
  const double boot = 1.7e9;  // Unix time of the controller's boot
  std::mt19937_64 rng(3);
  std::exponential_distribution<double> delay(1.0 / 0.004);  // 4 ms mean, a queue's backlog at times
  const double drift = 50e-6;  // the controller's clock 50 ppm slow
  bool first = true;
  for (int k = 0; k < 500 * 600; ++k) {  // 10 min at 500 Hz
    const double t = 42.0 + 0.002 * k;
    const double true_offset = boot + drift * (t - 42.0);
    const double d = delay(rng) + (k % 5000 == 17 ? 12.0 : 0.0);  // now and then a 12 s backlog
    const bool fresh = clock.sample(t, true_offset + t + d) == StreamWallClock::Change::started;
    EXPECT_EQ(fresh, first) << k;
    first = false;
    ASSERT_GE(clock.offset(), boot + drift * (t - 42.0) - 20.0 * drift - 1e-6) << k;  // (two windows of drift; a double at 1.7e9 resolves 0.24 µs)
    if (k > 500 * 20) {
      ASSERT_LT(std::abs(clock.offset() - true_offset), 0.001) << k;
    }
  }
  // the controller restarted: its clock counts from 0 again
  EXPECT_EQ(clock.sample(0.002, boot + 2000.0), StreamWallClock::Change::started);
  EXPECT_NEAR(clock.offset(), boot + 2000.0 - 0.002, 1e-6);
}


// A replay served at 8 times real time (serve-robot --speed 8): its least-delay offset would put
// events seconds away from when they were seen, so the clock goes off pace (offset NaN) within
// four blocks of 2 controller seconds, reads the pace, and reads the offset afresh once the stream
// is back at real time. A monitor that stalls a second now and then and catches up stays in pace.
TEST(WallClock, AStreamFasterThanRealTimeHasNoWallClockUntilItIsBackInPace) {
  StreamWallClock clock(10.0, 30.0);
  std::mt19937_64 rng(5);
  std::exponential_distribution<double> delay(1.0 / 0.004);
  const double boot = 1.7e9;
  double wall = 100.0, t = 42.0;  // (this machine's clock less boot: 0.002 added to 1.7e9 rounds up 5 % of a µs each time)
  int off_at = -1;
  for (int k = 0; k < 500 * 40; ++k) {  // 40 controller seconds at 8x: 5 s of this machine's
    t += 0.002;
    wall += 0.002 / 8.0;
    const StreamWallClock::Change c = clock.sample(t, boot + wall + delay(rng));
    if (c == StreamWallClock::Change::off_pace) off_at = k;
    EXPECT_NE(c, StreamWallClock::Change::on_pace) << k;
  }
  ASSERT_GE(off_at, 0);
  EXPECT_LE(off_at, 500 * 10) << "off pace after four blocks (8 s) and the one it started in";
  EXPECT_TRUE(clock.off_pace());
  EXPECT_TRUE(std::isnan(clock.offset()));
  EXPECT_NEAR(clock.pace(), 8.0, 0.08);
  // back at real time: in pace again, and the offset is now − t
  int on_at = -1;
  for (int k = 0; k < 500 * 20; ++k) {
    t += 0.002;
    wall += 0.002;
    if (clock.sample(t, boot + wall + delay(rng)) == StreamWallClock::Change::on_pace) on_at = k;
  }
  ASSERT_GE(on_at, 0);
  EXPECT_LE(on_at, 500 * 10);
  EXPECT_FALSE(clock.off_pace());
  EXPECT_NEAR(clock.offset(), boot + wall - t, 0.001);
  EXPECT_NEAR(clock.pace(), 1.0, 0.005);
  // a monitor that stalls for 1 s every 15 s and then reads its backlog at 3 times real time
  const double in_step = boot + wall - t;
  for (int k = 0; k < 500 * 120; ++k) {
    t += 0.002;
    wall += 0.002;
    // (stamped u s into the 15: read at 1 + u/3 while the backlog lasts, until u = 1.5)
    const double u = std::fmod(t, 15.0), behind = u < 1.5 ? 1.0 - 2.0 * u / 3.0 : 0.0;
    const StreamWallClock::Change c = clock.sample(t, boot + wall + behind + delay(rng));
    EXPECT_EQ(c, StreamWallClock::Change::none) << k;
  }
  EXPECT_NEAR(clock.offset(), in_step, 0.001);
  // a replay slower than real time (0.5x) goes off pace too
  for (int k = 0; k < 500 * 12; ++k) {
    t += 0.002;
    wall += 0.004;
    clock.sample(t, boot + wall + delay(rng));
  }
  EXPECT_TRUE(clock.off_pace());
  EXPECT_NEAR(clock.pace(), 0.5, 0.01);
}

}  // namespace
}  // namespace twinwatch
