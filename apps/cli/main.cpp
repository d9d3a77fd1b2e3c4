// twinwatch: command-line entry point. Verbs live in apps/cli/verbs/ and register themselves.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/log.hpp"
#include "twinwatch/version.hpp"
#include "verb_registry.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "twinwatch — a digital twin for sensorless condition monitoring of robots.\n"
      "It predicts what a healthy robot draws from what its controller already streams and turns\n"
      "the difference into diagnoses. Run 'twinwatch VERB --help' for each verb."};
  app.set_version_flag("-V,--version", std::string("twinwatch ") + twinwatch::kVersion);
  app.require_subcommand(1);
  app.fallthrough();
  bool verbose = false;
  app.add_flag("-v,--verbose", verbose, "Log debug messages to stderr");

  twinwatch::log::set_sink([](twinwatch::log::Level level, std::string_view msg) {
    static const char* names[] = {"debug", "info", "warning", "error"};
    std::fprintf(stderr, "[%s] %.*s\n", names[static_cast<int>(level)], static_cast<int>(msg.size()), msg.data());
  });
  twinwatch::cli::register_all_verbs(app);
  // verbs run inside parse(), so the log level must be set before it
  for (int i = 1; i < argc; ++i) {
    const std::string_view a = argv[i];
    if (a == "-v" || a == "--verbose") twinwatch::log::set_level(twinwatch::log::Level::Debug);
    if (!a.empty() && a[0] != '-') break;  // the verb: its own options follow
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const twinwatch::ParseError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const twinwatch::InvalidArgument& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return twinwatch::cli::exit_code();
}
