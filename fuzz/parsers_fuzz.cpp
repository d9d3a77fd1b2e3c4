// libFuzzer targets for the parsers of the project's user files, one binary per parser, selected at
// compile time by TWINWATCH_FUZZ_<TARGET> (fuzz/CMakeLists.txt builds each):
//
//   recording         device::read_recording (CSV) and device::ColumnMap::load — path only: the
//                     input goes to a temporary file. An input holding a line "##map" is split
//                     there: the part after it is a column map applied to the part before.
//   scenario          sim::parse_scenario (YAML text)
//   twin_model        ident::TwinModel::from_json (JSON text; with its learned and monitor blocks)
//   description_json  model::parse_description_json (JSON text)
//   description_urdf  model::load_description_urdf — path only: the input goes to a temporary file
//   monitor_config    monitor::MonitorConfig::from_json (JSON text)
//   friction_block    friction::friction_block_from_json (JSON text)
//
// The contract checked: for any input the parser returns, or throws the error its header
// documents — twinwatch::ParseError naming the origin it was given (core/error.hpp). Any other
// exception escaping (std::out_of_range, nlohmann::json errors, YAML::Exception, std::bad_alloc,
// std::filesystem::filesystem_error, InvalidArgument where a ParseError is documented, ...) is a
// finding, as are crashes, sanitizer reports and hangs (scripts/fuzz.sh runs with -timeout).
// Findings go to fuzz/regressions/<target>/ and are replayed by ctest (fuzz.<target>_replay).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <typeinfo>

#include "twinwatch/core/error.hpp"

#if defined(TWINWATCH_FUZZ_RECORDING)
#include "twinwatch/device/recording.hpp"
#elif defined(TWINWATCH_FUZZ_SCENARIO)
#include "twinwatch/sim/scenario.hpp"
#elif defined(TWINWATCH_FUZZ_TWIN_MODEL)
#include "twinwatch/ident/twin_model.hpp"
#elif defined(TWINWATCH_FUZZ_DESCRIPTION_JSON) || defined(TWINWATCH_FUZZ_DESCRIPTION_URDF)
#include "twinwatch/model/description_io.hpp"
#elif defined(TWINWATCH_FUZZ_MONITOR_CONFIG)
#include "twinwatch/monitor/monitor.hpp"
#elif defined(TWINWATCH_FUZZ_FRICTION_BLOCK)
#include "twinwatch/friction/twin_block.hpp"
#else
#error "define one of TWINWATCH_FUZZ_<TARGET> (see fuzz/CMakeLists.txt)"
#endif

namespace {

[[noreturn]] void finding(const char* what, const std::string& detail) {
  std::fprintf(stderr, "contract broken: %s: %s\n", what, detail.c_str());
  std::abort();
}

// TWINWATCH_FUZZ_VERBOSE=1: print each input's outcome (to check that seeds parse)
const bool kVerbose = std::getenv("TWINWATCH_FUZZ_VERBOSE") != nullptr;

// runs one parse and checks the contract: it returns or throws a ParseError naming `origin` (or,
// with any_file, the file it failed on: scenarios and twin files name a robot file they load)
template <class Parse>
void expect_parse_error_only(const std::string& origin, Parse&& parse, bool any_file = false) {
  try {
    parse();
    if (kVerbose) std::fprintf(stderr, "parsed\n");
  } catch (const twinwatch::ParseError& e) {
    if (kVerbose) std::fprintf(stderr, "ParseError: %s\n", e.what());
    if (!any_file && e.file() != origin) finding("ParseError names another file", "'" + e.file() + "' instead of '" + origin + "': " + e.what());
  } catch (const std::exception& e) {
    finding("undocumented exception escaped", std::string(typeid(e).name()) + ": " + e.what());
  } catch (...) {
    finding("undocumented exception escaped", "not a std::exception");
  }
}

// a per-process temporary file for the path-only loaders, rewritten for every input and removed
// at exit
class TempFile {
 public:
  explicit TempFile(const char* suffix)
      : path_((std::filesystem::temp_directory_path() / ("twinwatch_fuzz_" + std::to_string(::getpid()) + suffix)).string()) {}
  ~TempFile() {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
  const std::string& write(const std::string& text) const {
    std::ofstream f(path_, std::ios::binary | std::ios::trunc);
    f.write(text.data(), static_cast<std::streamsize>(text.size()));
    if (!f) finding("cannot write the temporary file", path_);
    return path_;
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

void fuzz_one(const std::string& text) {
#if defined(TWINWATCH_FUZZ_RECORDING)
  namespace device = twinwatch::device;
  static const TempFile csv(".csv"), map(".map.csv");
  // the whole input as a recording, then as a column map
  expect_parse_error_only(csv.write(text), [&] { device::read_recording(csv.path()); });
  expect_parse_error_only(map.write(text), [&] { device::ColumnMap::load(map.path()); });
  // "<recording>##map\n<column map>": the recording read through the map
  const std::string::size_type cut = text.find("##map\n");
  if (cut == std::string::npos) return;
  device::ColumnMap m;
  try {
    m = device::ColumnMap::load(map.write(text.substr(cut + 6)));
  } catch (const twinwatch::ParseError&) {
    return;  // a bad map alone is checked above
  }
  expect_parse_error_only(csv.write(text.substr(0, cut)), [&] { device::read_recording(csv.path(), &m); });
#elif defined(TWINWATCH_FUZZ_SCENARIO)
  expect_parse_error_only("fuzz.yaml", [&] { twinwatch::sim::parse_scenario(text, "fuzz.yaml"); }, true);
#elif defined(TWINWATCH_FUZZ_TWIN_MODEL)
  expect_parse_error_only("twin.json", [&] { twinwatch::ident::TwinModel::from_json(text, "twin.json"); }, true);
#elif defined(TWINWATCH_FUZZ_DESCRIPTION_JSON)
  expect_parse_error_only("robot.json", [&] { twinwatch::model::parse_description_json(text, "robot.json"); });
#elif defined(TWINWATCH_FUZZ_DESCRIPTION_URDF)
  static const TempFile urdf(".urdf");
  expect_parse_error_only(urdf.write(text), [&] { twinwatch::model::load_description_urdf(urdf.path()); });
#elif defined(TWINWATCH_FUZZ_MONITOR_CONFIG)
  expect_parse_error_only("monitor.json", [&] { twinwatch::monitor::MonitorConfig::from_json(text, "monitor.json"); });
#elif defined(TWINWATCH_FUZZ_FRICTION_BLOCK)
  expect_parse_error_only("twin.json", [&] { twinwatch::friction::friction_block_from_json(text, "twin.json"); });
#endif
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz_one(std::string(reinterpret_cast<const char*>(data), size));
  return 0;
}
