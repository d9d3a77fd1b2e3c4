#include "verb_registry.hpp"

#include <algorithm>
#include <atomic>
#include <csignal>
#include <vector>

namespace twinwatch::cli {

namespace {
struct Entry {
  std::string name;
  int order;
  VerbSetup setup;
};
std::vector<Entry>& registry() {
  static std::vector<Entry> entries;  // function-local: safe against static init order
  return entries;
}
int g_exit_code = 0;
std::atomic<bool> g_interrupted{false};
}  // namespace

void install_interrupt_handler() {
  struct sigaction sa {};
  sa.sa_handler = [](int) { g_interrupted = true; };
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}
bool interrupted() { return g_interrupted.load(); }

VerbRegistrar::VerbRegistrar(std::string name, int order, VerbSetup setup) {
  registry().push_back({std::move(name), order, std::move(setup)});
}

void set_exit_code(int code) { g_exit_code = code; }
int exit_code() { return g_exit_code; }

void register_all_verbs(CLI::App& app) {
  auto& r = registry();
  std::stable_sort(r.begin(), r.end(), [](const Entry& a, const Entry& b) {
    return a.order != b.order ? a.order < b.order : a.name < b.name;
  });
  for (auto& e : r) e.setup(app);
}

}  // namespace twinwatch::cli
