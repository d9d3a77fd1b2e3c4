#pragma once
/// @file file_io.hpp
/// Output files that fail loudly: a full disk or a vanished directory is an error naming the path,
/// not a truncated file behind exit code 0.
#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>

namespace twinwatch {

/// Throws std::runtime_error "PATH: cannot write: REASON" unless the stream is still good. The
/// reason is errno's only when the failing call is the caller's last one (errno is not reset by
/// successful calls, so a stale value would name the wrong cause).
inline void check_written(const std::ofstream& f, const std::string& path, bool errno_is_fresh = false) {
  if (f.good()) return;
  throw std::runtime_error(path + ": cannot write: " +
                           (errno_is_fresh && errno ? std::string(std::strerror(errno)) : std::string("a write failed (disk full?)")));
}

/// Flushes and closes the stream; throws as check_written when any write or the close failed.
inline void close_written(std::ofstream& f, const std::string& path) {
  if (!f.is_open()) return;
  check_written(f, path);
  errno = 0;
  f.flush();
  check_written(f, path, true);
  f.close();
  check_written(f, path, true);
}

/// Writes (truncates) a whole text file, checked.
inline void write_text_file(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  errno = 0;
  if (!f) throw std::runtime_error(path + ": cannot open for writing: " + (errno ? std::strerror(errno) : "unknown reason"));
  f << text;
  close_written(f, path);
}

}  // namespace twinwatch
