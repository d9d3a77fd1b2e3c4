#include "twinwatch/device/agv_tests.hpp"

#include <fmt/format.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "twinwatch/core/error.hpp"

namespace twinwatch::device {

std::vector<AgvTestRow> read_agv_tests(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw ParseError(path, 0, "", "cannot open the test file");
  std::string line;
  if (!std::getline(f, line) || line.rfind("motor,test,voltage_V,current_A,speed_rad_s,time_s", 0) != 0)
    throw ParseError(path, 1, "", "expected the header 'motor,test,voltage_V,current_A,speed_rad_s,time_s'");
  const char* cols[] = {"motor", "test", "voltage_V", "current_A", "speed_rad_s", "time_s"};
  std::vector<AgvTestRow> rows;
  int ln = 1;
  while (std::getline(f, line)) {
    ++ln;
    if (line.empty()) continue;
    std::vector<std::string> c;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) c.push_back(cell);
    if (c.size() != 6) throw ParseError(path, ln, "", fmt::format("expected 6 cells, got {}", c.size()));
    AgvTestRow r;
    r.motor = c[0];
    r.test = c[1];
    if (r.motor != "right" && r.motor != "left") throw ParseError(path, ln, "motor", fmt::format("expected right or left, got '{}'", r.motor));
    if (r.test != "steady" && r.test != "step") throw ParseError(path, ln, "test", fmt::format("expected steady or step, got '{}'", r.test));
    double* dst[] = {&r.voltage, &r.current, &r.speed, &r.time};
    for (int k = 0; k < 4; ++k) {
      try {
        size_t used = 0;
        *dst[k] = std::stod(c[static_cast<size_t>(k + 2)], &used);
        if (used != c[static_cast<size_t>(k + 2)].size()) throw std::invalid_argument("trailing");
      } catch (const std::exception&) {
        throw ParseError(path, ln, cols[k + 2], fmt::format("expected a number, got '{}'", c[static_cast<size_t>(k + 2)]));
      }
    }
    rows.push_back(r);
  }
  return rows;
}

void write_agv_tests(const std::string& path, const std::vector<AgvTestRow>& rows) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open for writing");
  f << "motor,test,voltage_V,current_A,speed_rad_s,time_s\n";
  for (const auto& r : rows) f << fmt::format("{},{},{:.6g},{:.6g},{:.6g},{:.6g}\n", r.motor, r.test, r.voltage, r.current, r.speed, r.time);
}

}  // namespace twinwatch::device
