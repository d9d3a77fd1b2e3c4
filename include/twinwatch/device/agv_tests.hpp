#pragma once
/// @file agv_tests.hpp
/// The AGV motor-test file [AGV §4.1], one CSV for both motors, header required:
///   motor,test,voltage_V,current_A,speed_rad_s,time_s
/// motor = right|left; test = steady (one row per applied voltage, time_s ignored) or step (the
/// speed response to a voltage step applied at time_s = 0, one row per sample).
#include <string>
#include <vector>

namespace twinwatch::device {

struct AgvTestRow {
  std::string motor, test;
  double voltage = 0.0, current = 0.0, speed = 0.0, time = 0.0;
};

/// Reads the test CSV (LF or CRLF line ends, an optional UTF-8 byte-order mark); errors (ParseError)
/// name the file, line and column. Every number must be finite and within +-1e6; time_s >= 0.
std::vector<AgvTestRow> read_agv_tests(const std::string& path);
/// Writes the test CSV. Throws std::runtime_error naming the path when it cannot be opened or written
/// (a full disk included).
void write_agv_tests(const std::string& path, const std::vector<AgvTestRow>& rows);

}  // namespace twinwatch::device
