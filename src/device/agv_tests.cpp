#include "twinwatch/device/agv_tests.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"

namespace twinwatch::device {

namespace {
constexpr const char* kHeader = "motor,test,voltage_V,current_A,speed_rad_s,time_s";
constexpr const char* kUtf8Bom = "\xEF\xBB\xBF";
// largest magnitude a cell may hold [V, A, rad/s, s]: far above any bench test (AGV §4.1 stays within
// 6 V, 1 A, 16 rad/s and 1.5 s), and small enough that the least-squares sums of squares stay finite
// (a -1e300 cell turned the fitted gain into NaN)
constexpr double kMaxMagnitude = 1e6;
// an AGV wheel drive's plausible ranges (AGV §4.1: 6 V, 1 A, 16 rad/s, 5 ms logging): beyond them a
// column is in another unit, which the fit takes as a physically wrong motor with exit 0 (mA: Ra
// 0.006 Ohm, Tq 21 N·m; ms: tau 174 s; degrees/s: k 0.0056 V s/rad; audit of session 56)
constexpr double kMaxCurrent = 50.0;     // [A]
constexpr double kMaxSpeed = 200.0;      // [rad/s] at the wheel (1900 rpm: 20 m/s on a 0.1 m wheel)
constexpr double kMaxStepPeriod = 0.5;   // [s] between a step test's rows
constexpr double kStepVoltageTolerance = 0.05;  // [1] a step's rows within this of its first row's voltage

// a line without the '\r' of a CRLF file (as the recording reader accepts them)
void strip_cr(std::string& line) {
  if (!line.empty() && line.back() == '\r') line.pop_back();
}
}  // namespace

std::vector<AgvTestRow> read_agv_tests(const std::string& path) {
  refuse_directory_input(path);
  std::ifstream f(path);
  if (!f) throw ParseError(path, 0, "", "cannot open the test file");
  std::string line;
  if (!std::getline(f, line)) throw ParseError(path, 1, "", fmt::format("expected the header '{}', got an empty file", kHeader));
  strip_cr(line);
  if (line.rfind(kUtf8Bom, 0) == 0) line.erase(0, std::string(kUtf8Bom).size());  // as a spreadsheet may write it
  if (line != kHeader) throw ParseError(path, 1, "", fmt::format("expected the header '{}', got '{}'", kHeader, line));
  const char* cols[] = {"motor", "test", "voltage_V", "current_A", "speed_rad_s", "time_s"};
  std::vector<AgvTestRow> rows;
  std::map<std::pair<std::string, double>, int> step_line;  // (motor, time) of each step row -> its line
  std::map<std::string, std::pair<double, int>> step_voltage;  // motor -> its step's voltage, and the line of its first step row
  int ln = 1;
  while (std::getline(f, line)) {
    ++ln;
    strip_cr(line);
    if (line.empty()) continue;
    std::vector<std::string> c;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) c.push_back(cell);
    // (getline drops a last empty cell: a trailing comma is a seventh cell, not nothing)
    if (!line.empty() && line.back() == ',') c.push_back("");
    if (c.size() != 6)
      throw ParseError(path, ln, "", fmt::format("expected 6 cells ({}), got {}", kHeader, c.size()));
    // blanks around a cell are a spreadsheet's, read as the number they surround (" 0.5" was read and
    // "0.5 " refused)
    for (std::string& x : c) {
      const size_t a = x.find_first_not_of(" \t"), b = x.find_last_not_of(" \t");
      x = a == std::string::npos ? std::string() : x.substr(a, b - a + 1);
    }
    AgvTestRow r;
    r.motor = c[0];
    r.test = c[1];
    if (r.motor != "right" && r.motor != "left") throw ParseError(path, ln, "motor", fmt::format("expected right or left, got '{}'", r.motor));
    if (r.test != "steady" && r.test != "step") throw ParseError(path, ln, "test", fmt::format("expected steady or step, got '{}'", r.test));
    double* dst[] = {&r.voltage, &r.current, &r.speed, &r.time};
    for (int k = 0; k < 4; ++k) {
      const std::string& text = c[static_cast<size_t>(k + 2)];
      const char* col = cols[k + 2];
      try {
        size_t used = 0;
        *dst[k] = std::stod(text, &used);
        if (used != text.size()) throw std::invalid_argument("trailing");
      } catch (const std::exception&) {
        throw ParseError(path, ln, col, fmt::format("expected a number, got '{}'", text));
      }
      // (std::stod reads "nan" and "inf" as numbers)
      if (!std::isfinite(*dst[k])) throw ParseError(path, ln, col, fmt::format("expected a finite number, got '{}'", text));
      if (std::abs(*dst[k]) > kMaxMagnitude)
        throw ParseError(path, ln, col, fmt::format("expected a number within +-{:g}, got '{}'", kMaxMagnitude, text));
    }
    // (time_s is read from any origin, as the help says: a log's clock may be negative)
    if (std::abs(r.current) > kMaxCurrent)
      throw ParseError(path, ln, "current_A", fmt::format("expected a wheel drive's current within ±{:g} A, got '{}' (in mA? give A)", kMaxCurrent, c[3]));
    if (std::abs(r.speed) > kMaxSpeed)
      throw ParseError(path, ln, "speed_rad_s",
                       fmt::format("expected a wheel's speed within ±{:g} rad/s, got '{}' (in degrees/s or rpm? give rad/s)", kMaxSpeed, c[4]));
    // a motor's step test has one speed per instant: a second row at a time is a second test, or the
    // file's rows written twice, which the fit (sorted by time) would interleave into one response
    if (r.test == "step") {
      // a step is one voltage held: another one in a row is another test (the fit read the speed alone)
      const auto [first, was_new] = step_voltage.try_emplace(r.motor, std::pair{r.voltage, ln});
      // (a measured voltage varies by a few per cent: 6.01 V after 6 V is the same step; review of session 56)
      if (!was_new && std::abs(r.voltage - first->second.first) > kStepVoltageTolerance * std::abs(first->second.first))
        throw ParseError(path, ln, "voltage_V",
                         fmt::format("the {} motor's step test holds one voltage (within 5 %): this row has {}, its first step row "
                                     "(line {}) {:g} V",
                                     r.motor, c[2], first->second.second, first->second.first));
      const auto [at, fresh] = step_line.try_emplace({r.motor, r.time}, ln);
      if (!fresh)
        throw ParseError(path, ln, "time_s",
                         fmt::format("the {} motor's step test has a row at {} s already (line {}): expected one step test per motor, "
                                     "one row per time (are the file's rows repeated?)",
                                     r.motor, c[5], at->second));
    }
    rows.push_back(r);
  }
  if (rows.empty()) throw ParseError(path, 2, "", "no data rows after the header");
  // a step test's logging period: a time column in ms made tau 174 s, exit 0
  for (const auto& [motor, first] : step_voltage) {
    std::vector<double> t;
    for (const auto& [key, line] : step_line)
      if (key.first == motor) t.push_back(key.second);  // (the map keeps them sorted)
    std::vector<double> dt;
    for (size_t k = 1; k < t.size(); ++k) dt.push_back(t[k] - t[k - 1]);
    if (dt.empty()) continue;
    std::nth_element(dt.begin(), dt.begin() + static_cast<long>(dt.size() / 2), dt.end());
    if (dt[dt.size() / 2] > kMaxStepPeriod)
      throw ParseError(path, first.second, "time_s",
                       fmt::format("the {} motor's step rows are {:g} s apart (median), expected a logger's period of at most {:g} s (in ms? "
                                   "give s)",
                                   motor, dt[dt.size() / 2], kMaxStepPeriod));
  }
  return rows;
}

void write_agv_tests(const std::string& path, const std::vector<AgvTestRow>& rows) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open for writing");
  f << kHeader << '\n';
  for (const auto& r : rows) f << fmt::format("{},{},{:.6g},{:.6g},{:.6g},{:.6g}\n", r.motor, r.test, r.voltage, r.current, r.speed, r.time);
  // a full disk shows only when the buffer goes out
  f.close();
  if (!f) throw std::runtime_error(path + ": write error (disk full?)");
}

}  // namespace twinwatch::device
