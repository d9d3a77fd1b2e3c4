#pragma once
/// @file data_dir.hpp
/// Where twinwatch reads the data it ships: the built-in robot descriptions, the scenario library
/// (`twinwatch demo`), the column maps of the real recordings.
#include <string>
#include <vector>

namespace twinwatch {

/// The directory of one kind of shipped data, the first of these that has it:
///   1. $TWINWATCH_DATA_DIR/<kind> (set: used even when it lacks the kind, so that a typo is an
///      error naming it rather than a silent fall-back);
///   2. an installed tree ('cmake --install build --prefix P'): P/share/twinwatch/<kind>, found
///      from the running program at P/bin/twinwatch;
///   3. the source tree the program was built from: data/robots, data/column_maps, scenarios.
/// @param kind "robots", "column_maps" or "scenarios"; another kind throws std::invalid_argument.
std::string data_directory(const std::string& kind);

/// The names (without the extension, sorted) of the files in data_directory(kind) whose name ends
/// in `extension` (e.g. ".json"); none when the directory cannot be read.
std::vector<std::string> data_names(const std::string& kind, const std::string& extension);

}  // namespace twinwatch
