#pragma once
/// @file error.hpp
/// Error types shared by every module (STYLE.md "Errors").
///
/// - `InvalidArgument`: bad caller input at an API boundary. The message names the quantity,
///   the index, the expected value and the actual value.
/// - `ParseError`: a malformed input file. Carries the file, the line (1-based, 0 when the whole
///   file is concerned) and the field, and formats them into what().
#include <stdexcept>
#include <string>

namespace twinwatch {

/// Bad caller input (wrong size, out-of-range value, unknown name).
class InvalidArgument : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// A path the user named that cannot be used as asked: an output in a missing or read-only directory,
/// an output that is an input, an input that does not exist or is not what it should be (an event
/// store that is not a database). Bad input like InvalidArgument (the command line exits 2); a
/// failure while writing to a good path (a full disk) stays a std::runtime_error (exit 1).
class PathError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A malformed file: CSV, URDF, JSON description, YAML scenario, twin file.
class ParseError : public std::runtime_error {
 public:
  /// @param file  path of the file as the user gave it
  /// @param line  1-based line number, 0 if unknown / whole file
  /// @param field name of the field, column or element ("" if none)
  /// @param what  what is wrong, ideally "expected X, got Y"
  ParseError(std::string file, int line, std::string field, const std::string& what);

  const std::string& file() const noexcept { return file_; }
  int line() const noexcept { return line_; }
  const std::string& field() const noexcept { return field_; }

 private:
  std::string file_;
  int line_;
  std::string field_;
};

/// Throws InvalidArgument("<what> has size <actual>, expected <expected>") when sizes differ.
/// Mirrors Pinocchio's PINOCCHIO_CHECK_ARGUMENT_SIZE: `what` names the argument and, where
/// useful, the hint, e.g. "q" and "model.n_dof".
void check_size(const char* what, long actual, long expected, const char* hint = nullptr);

}  // namespace twinwatch
