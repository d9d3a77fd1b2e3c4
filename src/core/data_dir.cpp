#include "twinwatch/core/data_dir.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace twinwatch {

namespace fs = std::filesystem;

std::string data_directory(const std::string& kind) {
  const char* in_source = nullptr;
  if (kind == "robots") in_source = "data/robots";
  else if (kind == "column_maps") in_source = "data/column_maps";
  else if (kind == "scenarios") in_source = "scenarios";
  else throw std::invalid_argument("data_directory: unknown kind '" + kind + "' (robots, column_maps, scenarios)");
  if (const char* env = std::getenv("TWINWATCH_DATA_DIR"); env != nullptr && *env != '\0') return (fs::path(env) / kind).string();
  // installed: <prefix>/bin/twinwatch next to <prefix>/share/twinwatch (Linux names the running
  // program in /proc; a build-tree program has no share/ beside it and reads the source tree)
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path installed = exe.parent_path().parent_path() / "share" / "twinwatch" / kind;
    if (fs::is_directory(installed, ec)) return installed.string();
  }
  return (fs::path(TWINWATCH_SOURCE_DIR) / in_source).string();
}

std::vector<std::string> data_names(const std::string& kind, const std::string& extension) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(data_directory(kind), ec))
    if (e.path().extension() == extension) names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace twinwatch
