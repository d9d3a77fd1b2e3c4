#pragma once
/// @file numbers.hpp
/// Checked conversions for the parsers of user files.
#include <cmath>
#include <limits>
#include <optional>

namespace twinwatch {

/// The int a parsed number holds when it is a whole number within int's range, else nothing.
/// (Casting 1e20, NaN or 2.5 to int would be undefined or silently wrong; every parser that
/// reads a count, an index or a mode checks with this first and names the field itself.)
inline std::optional<int> whole_int(double x) {
  if (!(x == std::floor(x) && std::abs(x) <= std::numeric_limits<int>::max())) return std::nullopt;
  return static_cast<int>(x);
}

}  // namespace twinwatch
