// twinwatch: command-line entry point. Verbs live in apps/cli/verbs/ and register themselves.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
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
  app.footer(twinwatch::cli::kExitStatusHelp);
  app.set_version_flag("-V,--version", std::string("twinwatch ") + twinwatch::kVersion);
  app.require_subcommand(1);
  app.fallthrough();

  twinwatch::log::set_sink([](twinwatch::log::Level level, std::string_view msg) {
    static const char* names[] = {"debug", "info", "warning", "error"};
    std::fprintf(stderr, "[%s] %.*s\n", names[static_cast<int>(level)], static_cast<int>(msg.size()), msg.data());
  });
  twinwatch::cli::register_all_verbs(app);
  // an unknown verb is named (CLI11 said only "A subcommand is required"); no verb at all still
  // gets CLI11's usage
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.empty() || a[0] == '-') continue;
    std::vector<std::string> verbs;
    for (const CLI::App* v : app.get_subcommands({})) verbs.push_back(v->get_name());
    if (std::find(verbs.begin(), verbs.end(), a) == verbs.end()) {
      std::string list;
      for (const auto& v : verbs) list += (list.empty() ? "" : ", ") + v;
      std::fprintf(stderr, "error: '%s' is not a twinwatch command; the commands are: %s ('twinwatch --help' says what each does)\n",
                   a.c_str(), list.c_str());
      return 2;
    }
    break;  // the verb: its own options follow
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; every usage error exits 2 like bad input (CLI11's own codes,
    // 105-114 by kind, told a script nothing it could act on)
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const twinwatch::ParseError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const twinwatch::InvalidArgument& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const twinwatch::PathError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  // what the verb printed must have reached its file: '> /dev/full' (a full disk) exited 0 with the
  // output lost (review, session 47)
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    std::fprintf(stderr, "error: the output could not be written (standard output: %s)\n", errno != 0 ? std::strerror(errno) : "write error");
    return 1;
  }
  return twinwatch::cli::exit_code();
}
