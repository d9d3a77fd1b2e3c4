#include "twinwatch/core/log.hpp"

#include <mutex>

namespace twinwatch::log {

namespace {
std::mutex g_mutex;
Sink g_sink;
Level g_level = Level::Info;
}  // namespace

void set_sink(Sink sink) {
  std::lock_guard lock(g_mutex);
  g_sink = std::move(sink);
}

void set_level(Level level) {
  std::lock_guard lock(g_mutex);
  g_level = level;
}

void write(Level level, std::string_view message) {
  std::lock_guard lock(g_mutex);
  if (g_sink && level >= g_level) g_sink(level, message);
}

}  // namespace twinwatch::log
