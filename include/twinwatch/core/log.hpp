#pragma once
/// @file log.hpp
/// Library code never prints (STYLE.md): it logs through this tiny sink interface and the
/// application chooses where messages go (stderr in the CLI, nowhere in tests).
#include <functional>
#include <string_view>

namespace twinwatch::log {

enum class Level { Debug, Info, Warn, Error };

/// Signature of a log sink.
using Sink = std::function<void(Level, std::string_view)>;

/// Installs the process-wide sink (nullptr silences logging). Not for real-time threads.
void set_sink(Sink sink);
/// Minimum level that reaches the sink (default Info).
void set_level(Level level);

void write(Level level, std::string_view message);
inline void debug(std::string_view m) { write(Level::Debug, m); }
inline void info(std::string_view m) { write(Level::Info, m); }
inline void warn(std::string_view m) { write(Level::Warn, m); }
inline void error(std::string_view m) { write(Level::Error, m); }

}  // namespace twinwatch::log
