#include "twinwatch/core/error.hpp"

#include <fmt/format.h>

namespace twinwatch {

namespace {
std::string format_parse_error(const std::string& file, int line, const std::string& field,
                               const std::string& what) {
  std::string where = file;
  if (line > 0) where += fmt::format(":{}", line);
  if (!field.empty()) where += fmt::format(": field '{}'", field);
  return fmt::format("{}: {}", where, what);
}
}  // namespace

ParseError::ParseError(std::string file, int line, std::string field, const std::string& what)
    : std::runtime_error(format_parse_error(file, line, field, what)),
      file_(std::move(file)),
      line_(line),
      field_(std::move(field)) {}

void check_size(const char* what, long actual, long expected, const char* hint) {
  if (actual == expected) return;
  if (hint != nullptr)
    throw InvalidArgument(fmt::format("{} has size {}, expected {} ({})", what, actual, expected, hint));
  throw InvalidArgument(fmt::format("{} has size {}, expected {}", what, actual, expected));
}

}  // namespace twinwatch
