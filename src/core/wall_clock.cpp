#include "twinwatch/core/wall_clock.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <ctime>

#include "twinwatch/core/error.hpp"

namespace twinwatch {

std::string iso_utc(double unix_s) {
  const double ms_total = std::round(unix_s * 1000.0);
  const auto secs = static_cast<std::time_t>(std::floor(ms_total / 1000.0));
  const int ms = static_cast<int>(ms_total - 1000.0 * static_cast<double>(secs));
  std::tm tm{};
  gmtime_r(&secs, &tm);
  return fmt::format("{:04d}-{:02d}-{:02d}T{:02d}:{:02d}:{:02d}.{:03d}Z", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday, tm.tm_hour,
                     tm.tm_min, tm.tm_sec, ms);
}

namespace {
// days from 1970-01-01 to y-m-d in the proleptic Gregorian calendar (H. Hinnant's days_from_civil)
long days_from_civil(long y, unsigned m, unsigned d) {
  y -= m <= 2;
  const long era = (y >= 0 ? y : y - 399) / 400;
  const auto yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<long>(doe) - 719468;
}

bool leap(long y) { return (y % 4 == 0 && y % 100 != 0) || y % 400 == 0; }
}  // namespace

double parse_iso_time(const std::string& text, const std::string& what) {
  const auto bad = [&](const std::string& why) {
    return InvalidArgument(fmt::format("{} '{}': {}; expected an ISO 8601 time with its zone, e.g. 2026-12-03T08:00:00Z or "
                                       "2026-12-03T09:00:00.250+01:00",
                                       what, text, why));
  };
  size_t k = 0;
  const auto digits = [&](size_t n, const char* field) {
    long v = 0;
    for (size_t i = 0; i < n; ++i, ++k) {
      if (k >= text.size() || !std::isdigit(static_cast<unsigned char>(text[k])))
        throw bad(fmt::format("the {} needs {} digits", field, n));
      v = 10 * v + (text[k] - '0');
    }
    return v;
  };
  const auto expect = [&](const char* chars, const char* after) {
    if (k >= text.size() || std::string_view(chars).find(text[k]) == std::string_view::npos)
      throw bad(fmt::format("expected '{}' after the {}", std::string_view(chars).substr(0, 1), after));
    ++k;
  };
  const long year = digits(4, "year");
  expect("-", "year");
  const long month = digits(2, "month");
  expect("-", "month");
  const long day = digits(2, "day");
  expect("Tt ", "date");
  const long hour = digits(2, "hour");
  expect(":", "hour");
  const long minute = digits(2, "minute");
  expect(":", "minute");
  const long second = digits(2, "second");
  double fraction = 0.0;
  if (k < text.size() && (text[k] == '.' || text[k] == ',')) {
    ++k;
    double scale = 0.1;
    const size_t begin = k;
    while (k < text.size() && std::isdigit(static_cast<unsigned char>(text[k]))) {
      fraction += scale * (text[k] - '0');
      scale /= 10.0;
      ++k;
    }
    if (k == begin) throw bad("the fraction of a second has no digits");
  }
  static constexpr int kDays[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  if (month < 1 || month > 12) throw bad(fmt::format("month {} is not 1 to 12", month));
  const long month_days = kDays[month - 1] + (month == 2 && leap(year) ? 1 : 0);
  if (day < 1 || day > month_days) throw bad(fmt::format("day {} is not 1 to {}", day, month_days));
  if (hour > 23) throw bad(fmt::format("hour {} is not 0 to 23", hour));
  if (minute > 59) throw bad(fmt::format("minute {} is not 0 to 59", minute));
  if (second > 59) throw bad(fmt::format("second {} is not 0 to 59 (a leap second cannot be placed)", second));
  long zone_s = 0;
  if (k >= text.size()) throw bad("it has no zone (Z for UTC, or +HH:MM)");
  if (text[k] == 'Z' || text[k] == 'z') {
    ++k;
  } else if (text[k] == '+' || text[k] == '-') {
    const long sign = text[k] == '-' ? -1 : 1;
    ++k;
    const long zh = digits(2, "zone's hours");
    if (k < text.size() && text[k] == ':') ++k;
    const long zm = digits(2, "zone's minutes");
    if (zh > 14 || zm > 59) throw bad(fmt::format("zone {}{:02d}:{:02d} is beyond ±14:00", sign < 0 ? '-' : '+', zh, zm));
    zone_s = sign * (3600 * zh + 60 * zm);
  } else {
    throw bad(fmt::format("'{}' where the zone (Z, +HH:MM or -HH:MM) should be", text.substr(k)));
  }
  if (k != text.size()) throw bad(fmt::format("'{}' after the zone", text.substr(k)));
  const double days = static_cast<double>(days_from_civil(year, static_cast<unsigned>(month), static_cast<unsigned>(day)));
  return days * 86400.0 + static_cast<double>(3600 * hour + 60 * minute + second - zone_s) + fraction;
}

void StreamWallClock::restart(double t, double d) {
  offset_ = d;
  window_min_ = d;
  window_start_ = t;
  block_start_ = t;
  block_min_ = d;
  block_min_t_ = t;
  ended_ = 0;
  fast_ = slow_ = steady_ = 0;
}

StreamWallClock::Change StreamWallClock::sample(double t, double now) {
  const double d = now - t;
  if (!std::isfinite(d)) return Change::none;
  // (off pace, now − t moves by design: a jump is no restart then; a clock that went back is one)
  if (!std::isfinite(offset_) || (!off_pace_ && std::abs(d - offset_) > jump_s_) || t < block_start_) {
    restart(t, d);
    off_pace_ = false;
    return Change::started;
  }
  // within a window the best so far; at its end the window's own best (which may be later: drift)
  offset_ = std::min(offset_, d);
  window_min_ = std::min(window_min_, d);
  if (t - window_start_ >= window_s_) {
    offset_ = window_min_;
    window_min_ = std::numeric_limits<double>::infinity();
    window_start_ = t;
  }
  if (d < block_min_) block_min_ = d, block_min_t_ = t;
  if (t - block_start_ < kBlockS) return Change::none;
  // a block ended: its least delay against the one before it. Over Δt controller seconds this
  // machine's clock ran Δt + Δ(now − t): a pace of Δt / (Δt + Δ(now − t))
  const int k = std::min(ended_, kPaceSteps);
  if (ended_ > kPaceSteps)
    for (int i = 0; i < kPaceSteps; ++i) ended_min_[i] = ended_min_[i + 1], ended_t_[i] = ended_t_[i + 1];
  ended_min_[k] = block_min_;
  ended_t_[k] = block_min_t_;
  ++ended_;
  block_start_ = t;
  block_min_ = std::numeric_limits<double>::infinity();
  if (k == 0) return Change::none;
  const double dt = ended_t_[k] - ended_t_[k - 1], wall = dt + ended_min_[k] - ended_min_[k - 1];
  const double step_pace = wall > 0.0 ? dt / wall : std::numeric_limits<double>::infinity();
  if (step_pace > 1.0 + kPaceTolerance) ++fast_, slow_ = steady_ = 0;
  else if (step_pace < 1.0 - kPaceTolerance) ++slow_, fast_ = steady_ = 0;
  else ++steady_, fast_ = slow_ = 0;
  if (k == kPaceSteps) {
    const double span = ended_t_[k] - ended_t_[0], span_wall = span + ended_min_[k] - ended_min_[0];
    pace_ = span_wall > 0.0 ? span / span_wall : std::numeric_limits<double>::infinity();
  }
  if (!off_pace_ && (fast_ >= kPaceSteps || slow_ >= kPaceSteps)) {
    off_pace_ = true;
    return Change::off_pace;
  }
  if (off_pace_ && steady_ >= kPaceSteps) {
    restart(t, d);
    off_pace_ = false;
    return Change::on_pace;
  }
  return Change::none;
}

}  // namespace twinwatch
