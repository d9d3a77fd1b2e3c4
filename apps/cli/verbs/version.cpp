// `twinwatch version`: the version and the libraries it was built with.
#include <fmt/format.h>

#include <Eigen/Core>

#include "twinwatch/version.hpp"
#include "verb_registry.hpp"

namespace {
twinwatch::cli::VerbRegistrar reg{"version", 99, [](CLI::App& app) {
  auto* sub = app.add_subcommand("version", "Print the version and the library versions it was built with");
  sub->callback([] {
    fmt::print("twinwatch {}\nEigen {}.{}.{}\n", twinwatch::kVersion, EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION,
               EIGEN_MINOR_VERSION);
  });
}};
}  // namespace
