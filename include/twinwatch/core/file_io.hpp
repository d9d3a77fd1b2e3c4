#pragma once
/// @file file_io.hpp
/// Output files that fail loudly: a full disk or a vanished directory is an error naming the path,
/// not a truncated file behind exit code 0.
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <filesystem>
#include <string>
#include <vector>

#include "twinwatch/core/error.hpp"

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
  if (!f) throw PathError(path + ": cannot open for writing: " + (errno ? std::strerror(errno) : "unknown reason"));
  f << text;
  close_written(f, path);
}

/// Throws PathError "PATH: cannot write: REASON" unless PATH could be written: an existing
/// regular file that is writable, or a new file in an existing, writable directory. Leaves nothing
/// changed, so a command that connects to a robot first can refuse a bad output path before the
/// connection (and an existing file is not replaced by an input that fails to load).
/// access(2) alone passes whatever root asks for outside a read-only mount (/proc, /sys), so the
/// path is also opened as it will be: an existing regular file for writing (not truncated, no
/// byte written), a new one (or a link's missing target) created and removed again.
inline void require_writable(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto fail = [&](const std::string& why) { throw PathError(path + ": cannot write: " + why); };
  if (path.empty()) fail("empty path");
  const fs::file_status st = fs::status(path, ec);
  if (fs::exists(st)) {
    if (fs::is_directory(st)) fail("it is a directory");
    if (::access(path.c_str(), W_OK) != 0) fail(std::strerror(errno));
    if (fs::is_regular_file(st)) {  // (a device or a FIFO is opened only when written: /dev/null, a pipe's reader)
      // O_CREAT as the writers open it (no O_TRUNC: nothing changes): a sticky directory's file of
      // another user (fs.protected_regular) or an append-only one fails here as it would there
      const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_NOCTTY | O_CLOEXEC, 0644);
      if (fd < 0) fail(std::strerror(errno));
      ::close(fd);
    }
    return;
  }
  // a link to a file that does not exist yet is written through: its target is what is created
  fs::path p(path);
  std::string via;
  for (int hop = 0; fs::is_symlink(fs::symlink_status(p, ec)); ++hop) {
    if (hop == 16) fail("too many levels of symbolic links");
    fs::path target = fs::read_symlink(p, ec);
    if (ec) fail(ec.message());
    if (target.is_relative() && p.has_parent_path()) target = p.parent_path() / target;
    p = target;
    via = " (a link to " + p.string() + ")";
  }
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec)) fail("directory " + dir.string() + " does not exist" + via);
  if (::access(dir.c_str(), W_OK) != 0) fail("directory " + dir.string() + ": " + std::strerror(errno) + via);
  const int fd = ::open(p.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOCTTY | O_CLOEXEC, 0644);
  if (fd < 0) {
    if (errno != EEXIST) fail(std::strerror(errno) + via);  // (EEXIST: a file made meanwhile: written as before)
    return;
  }
  ::close(fd);
  ::unlink(p.c_str());  // (where a file can be made but not removed, the empty file stays; the write replaces it)
}

/// Throws ParseError "PATH: cannot read: it is a directory, not a file" for a directory an input
/// names: std::ifstream opens one and reads nothing, which a parser then reports as an empty
/// document (the wrong cause).
inline void refuse_directory_input(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw ParseError(path, 0, "", "cannot read: it is a directory, not a file");
}

/// The whole content of a text file an input names. Throws ParseError naming the path for a
/// directory (refuse_directory_input), a file that cannot be opened, or a failed read.
inline std::string read_text_file(const std::string& path) {
  refuse_directory_input(path);
  errno = 0;
  std::ifstream f(path, std::ios::binary);
  if (!f)
    throw ParseError(path, 0, "", std::string("cannot open the file: ") + (errno ? std::strerror(errno) : "does it exist and is it readable?"));
  std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (f.bad()) throw ParseError(path, 0, "", "cannot read: a read failed");
  return text;
}

/// Whether two paths name the same file (the same name, or another name of one existing file:
/// ./fig.csv and fig.csv, a link, an absolute path).
inline bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  return a == b || std::filesystem::equivalent(a, b, ec);
}

/// require_writable, and OUT is none of `inputs` (the same file under another name too): an output
/// given the name of an input would destroy the input (monitor rec.csv --events rec.csv).
inline void require_output(const std::string& out, const std::vector<std::string>& inputs) {
  require_writable(out);
  for (const std::string& in : inputs)
    if (!in.empty() && same_file(out, in))
      throw PathError(out + ": cannot write: it is the input " + in + ", which it would replace");
}

/// An output file written as it comes and put in place only once complete (commit()): a regular
/// file, or a new one, is written beside its target under a temporary name (TARGET.tmpPID) and renamed
/// over it, so a failure part-way (a full disk, an input found cut or changed while it was read) leaves
/// what the target held and no part of the output; a device or a pipe (/dev/stdout) is written in
/// place (and never removed), as is a file beside which nothing can be created. Destroyed without
/// commit(), the temporary is removed. Writes are checked as close_written checks them, naming the path.
class ReplacingFile {
 public:
  explicit ReplacingFile(const std::string& path) : path_(path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);  // (through a symbolic link)
    if (!fs::exists(st) || fs::is_regular_file(st)) {
      existed_ = fs::exists(st);
      perms_ = st.permissions();
      target_ = existed_ ? fs::canonical(path, ec) : fs::path(path);
      tmp_ = target_;
      tmp_ += ".tmp" + std::to_string(static_cast<long>(::getpid()));
      errno = 0;
      f_.open(tmp_, std::ios::binary | std::ios::trunc);
      if (!f_) tmp_.clear();  // no file can be made beside it: in place
    }
    if (tmp_.empty()) {
      errno = 0;
      f_.open(path, std::ios::binary | std::ios::trunc);
      if (!f_) throw PathError(path + ": cannot open for writing: " + (errno ? std::strerror(errno) : "unknown reason"));
    }
  }
  ReplacingFile(const ReplacingFile&) = delete;
  ReplacingFile& operator=(const ReplacingFile&) = delete;
  ~ReplacingFile() {
    if (committed_ || tmp_.empty()) return;
    f_.close();
    std::error_code ec;
    std::filesystem::remove(tmp_, ec);
  }
  std::ofstream& stream() { return f_; }
  /// Closes the file (throws as close_written) and puts it in place.
  void commit() {
    close_written(f_, path_);
    committed_ = true;
    if (tmp_.empty()) return;
    std::error_code ec;
    if (existed_) std::filesystem::permissions(tmp_, perms_, ec);
    std::filesystem::rename(tmp_, target_, ec);
    if (ec) {
      std::filesystem::remove(tmp_, ec);
      throw std::runtime_error(path_ + ": cannot write: " + ec.message());
    }
  }

 private:
  std::string path_;
  std::filesystem::path target_, tmp_;  // tmp_ empty: written in place
  std::filesystem::perms perms_ = std::filesystem::perms::unknown;
  bool existed_ = false, committed_ = false;
  std::ofstream f_;
};

}  // namespace twinwatch
