#pragma once
// Reads the scipy fixtures of tests/data/signal/ (made by make_fixtures.py): comma-separated
// numbers, '#' lines are comments.
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace twinwatch::signal::test {

inline std::vector<std::vector<double>> read_fixture(const std::string& name) {
  std::ifstream f(std::string(TWINWATCH_SOURCE_DIR) + "/tests/data/signal/" + name);
  std::vector<std::vector<double>> rows;
  if (!f) return rows;
  for (std::string line; std::getline(f, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<double> v;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) v.push_back(std::stod(c));
    rows.push_back(std::move(v));
  }
  return rows;
}

}  // namespace twinwatch::signal::test
