#include "verb_registry.hpp"

#include <cctype>
#include <charconv>

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <limits>
#include <cstdlib>
#include <vector>

#include "twinwatch/core/error.hpp"

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
std::atomic<int> g_signal{0};  // the signal that stopped the verb (0: none)
}  // namespace

namespace {
// SIGHUP: the terminal went away (a closed window, a dropped SSH session). The stop is the same
// orderly one, and what would be printed to that terminal goes to /dev/null from then on: a write
// to a vanished terminal fails (EIO), and the summary's failure must not cost the files their last
// events. Only the descriptors that were terminals at the start are redirected (a log file keeps
// its summary); the handler itself only calls dup2, which is async-signal-safe.
int g_dev_null = -1;
bool g_stdout_tty = false, g_stderr_tty = false;
// A second signal while the first one's orderly stop runs (a store locked for its last 10 s, a
// slow disk): the user insists, and the process ends at once, as the signal ends a process that
// does not catch it (signal and raise are async-signal-safe).
void stop_now(int sig) {
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}
}  // namespace

void install_interrupt_handler() {
  struct sigaction sa {};
  sa.sa_handler = [](int sig) {
    if (g_interrupted.load()) stop_now(sig);
    g_signal = sig;  // (before the flag: a verb that sees the flag reads the signal)
    g_interrupted = true;
  };
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  if (g_dev_null < 0) g_dev_null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
  g_stdout_tty = ::isatty(STDOUT_FILENO) != 0;
  g_stderr_tty = ::isatty(STDERR_FILENO) != 0;
  struct sigaction hup {};
  hup.sa_handler = [](int sig) {
    if (g_interrupted.load()) stop_now(sig);
    g_signal = sig;  // (before the flag: a verb that sees the flag reads the signal)
    g_interrupted = true;
    if (g_dev_null >= 0 && g_stdout_tty) ::dup2(g_dev_null, STDOUT_FILENO);
    if (g_dev_null >= 0 && g_stderr_tty) ::dup2(g_dev_null, STDERR_FILENO);
  };
  sigemptyset(&hup.sa_mask);
  sigaction(SIGHUP, &hup, nullptr);
}
bool interrupted() { return g_interrupted.load(); }
int interrupt_signal() { return g_signal.load(); }

VerbRegistrar::VerbRegistrar(std::string name, int order, VerbSetup setup) {
  registry().push_back({std::move(name), order, std::move(setup)});
}

void set_exit_code(int code) { g_exit_code = code; }
int exit_code() { return g_exit_code; }

namespace {
// a number the option's text is, in full and finite; else "" and false
bool read_number(const std::string& text, double& v) {
  char* end = nullptr;
  v = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size() && std::isfinite(v);
}
CLI::Validator bound_check(const char* name, const char* expected, bool (*ok)(double)) {
  return CLI::Validator(
      [expected, ok](std::string& text) -> std::string {
        double v = 0.0;
        if (read_number(text, v) && ok(v)) return {};
        return std::string("expected ") + expected + ", got '" + text + "'";
      },
      name);
}
}  // namespace

const CLI::Validator& positive_number() {
  static const CLI::Validator v = bound_check("POSITIVE", "a finite number > 0", [](double x) { return x > 0.0; });
  return v;
}
const CLI::Validator& nonnegative_number() {
  static const CLI::Validator v = bound_check("NONNEGATIVE", "a finite number >= 0", [](double x) { return x >= 0.0; });
  return v;
}

CLI::Validator number_in(double lo, double hi, const char* unit) {
  return CLI::Validator(
      [lo, hi, unit](std::string& text) -> std::string {
        double v = 0.0;
        if (read_number(text, v) && v >= lo && v <= hi) return {};
        return fmt::format("expected a number from {:g} to {:g} {}, got '{}'", lo, hi, unit, text);
      },
      fmt::format("{:g}..{:g} {}", lo, hi, unit));
}

CLI::Validator whole_number(long lo, long hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        double v = 0.0;
        if (read_number(text, v) && v == std::floor(v) && v >= static_cast<double>(lo) && v <= static_cast<double>(hi)) return {};
        return fmt::format("expected a whole number from {} to {}, got '{}'", lo, hi, text);
      },
      fmt::format("INT {}..{}", lo, hi));
}

std::string with_option_names(std::string message, std::initializer_list<std::pair<std::string_view, std::string_view>> fields) {
  for (const auto& [field, option] : fields) {
    if (message.rfind(field, 0) != 0) continue;
    const char next = message.size() > field.size() ? message[field.size()] : ' ';
    if (std::isalnum(static_cast<unsigned char>(next)) || next == '_') continue;
    return std::string(option) + message.substr(field.size());
  }
  return message;
}

CLI::Option* add_tool_point_option(CLI::App* sub, std::vector<double>& values, const std::string& help) {
  // (each value a number: '--tool-point 0 0 -o x.script' took '-o' as the third and said only
  // "Could not convert: --tool-point = 0,0,-o"; audit of session 56)
  const CLI::Validator number(
      [](std::string& v) {
        double x = 0.0;
        const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), x);
        return ec == std::errc() && end == v.data() + v.size()
                   ? std::string()
                   : fmt::format("expected three numbers X Y Z [m] an occurrence, got '{}'{}", v,
                                 !v.empty() && v[0] == '-' ? " (an option where a number was due: are numbers missing?)" : "");
      },
      "X Y Z");
  return sub->add_option("--tool-point", values, help)
      ->type_size(-3)  // three numbers an occurrence, any number of occurrences
      ->allow_extra_args(false)
      ->check(number);
}

std::vector<Eigen::Vector3d> tool_points(const std::vector<double>& values) {
  std::vector<Eigen::Vector3d> points;
  for (size_t k = 0; k + 2 < values.size(); k += 3) points.emplace_back(values[k], values[k + 1], values[k + 2]);
  return points;
}

void add_safety_limit_options(CLI::App* sub, SafetyLimitOptions& o, const std::string& purpose) {
  sub->add_option("--tool-speed-limit", o.tool_speed,
                  purpose + " the installation's tool speed limit [m/s] (Safety > Robot Limits), at the flange's centre and the "
                            "--tool-point points, less --speed-tolerance")
      ->check(positive_number());
  sub->add_option("--elbow-speed-limit", o.elbow_speed,
                  purpose + " the installation's elbow speed limit [m/s] (the faster end of the elbow's housing), less --speed-tolerance")
      ->check(positive_number());
  sub->add_option("--momentum-limit", o.momentum,
                  purpose + " the installation's momentum limit [kg·m/s] (the links', the tool's (--tool-mass) and any payload's), "
                            "less --momentum-tolerance")
      ->check(positive_number());
  sub->add_option("--speed-tolerance", o.speed_tolerance,
                  "What the safety system keeps a speed below its limit by [m/s] (UR e-Series: 0.05, the speed limit's accuracy); "
                  "0: the limit as entered")
      ->capture_default_str()
      ->check(nonnegative_number());
  sub->add_option("--momentum-tolerance", o.momentum_tolerance,
                  "The same for the momentum [kg·m/s] (UR e-Series: 3)")
      ->capture_default_str()
      ->check(nonnegative_number());
  sub->add_option("--tool-mass", o.tool_mass, "The gripper or tool on the flange [kg], counted in the momentum (default: none)")
      ->check(nonnegative_number());
  sub->add_option("--tool-cog", o.tool_cog, "Its centre of mass in the flange frame [m] (3 numbers; default 0 0 0)")->expected(3);
}

std::string OperationalLimit::text(const char* unit) const {
  if (tolerance == 0.0) return fmt::format("{:g} {} (the {} as entered)", entered, unit, option);
  return fmt::format("{:g} {} (the {} {:g} less the safety system's {:g} {} tolerance)", value(), unit, option, entered, tolerance, unit);
}

std::vector<OperationalLimit> operational_limits(const SafetyLimitOptions& o) {
  std::vector<OperationalLimit> out{{"--tool-speed-limit", o.tool_speed, o.speed_tolerance},
                                    {"--elbow-speed-limit", o.elbow_speed, o.speed_tolerance},
                                    {"--momentum-limit", o.momentum, o.momentum_tolerance}};
  for (OperationalLimit& l : out) {
    if (!l.given()) {
      l.entered = std::numeric_limits<double>::infinity(), l.tolerance = 0.0;
      continue;
    }
    if (!(l.value() > 0.0))
      throw InvalidArgument(fmt::format("{} {:g}: the safety system keeps a motion {:g} {} below it ({}), which leaves nothing to move "
                                        "at; give a larger limit, or a smaller tolerance if your controller's is smaller",
                                        l.option, l.entered, l.tolerance, l.option == std::string("--momentum-limit") ? "kg·m/s" : "m/s",
                                        l.option == std::string("--momentum-limit") ? "--momentum-tolerance" : "--speed-tolerance"));
  }
  return out;
}

std::string slow_down_remedy(const sim::ProgramMotion& motion, const model::RobotModel& robot, double given, double qdd_cap,
                             const std::function<std::string(double)>& violation_at) {
  const double k = sim::slow_down_for_joint_limits(motion, robot, qdd_cap);
  // (the review of session 57 found these said as nothing: the message just stopped)
  if (!std::isfinite(k)) return "; a joint leaves its range, which no --slow-down changes (the same path at any speed)";
  if (k <= 1.0) return "";
  // (rounded up to the hundredth the option is written with, and a thousandth above the peak: the
  // servo period's samples of the slower motion fall elsewhere)
  double slower = std::ceil(given * k * 1.001 * 100.0) / 100.0;
  while (slower <= 100.0 && !violation_at(slower).empty()) slower = std::ceil(slower * 1.01 * 100.0) / 100.0;
  if (slower > 100.0) return fmt::format("; no --slow-down up to 100 fits it (it needs {:.4g} or more)", slower);
  return fmt::format("; --slow-down {:.2f} keeps every joint within its speed and acceleration limits (the same path, {:.2f} times "
                     "slower than now)",
                     slower, slower / given);
}

model::RigidBodyInertia carried_on_flange(const SafetyLimitOptions& o, const model::RobotModel& robot, const model::RigidBodyInertia& payload) {
  if (!o.tool_cog.empty() && o.tool_mass == 0.0) throw InvalidArgument("--tool-cog applies only with --tool-mass (the tool's mass [kg])");
  model::RigidBodyInertia tool;
  tool.mass = o.tool_mass;
  if (!o.tool_cog.empty()) tool.com = Eigen::Vector3d(o.tool_cog[0], o.tool_cog[1], o.tool_cog[2]);
  if (!(std::isfinite(o.tool_mass) && o.tool_mass <= 1000.0))
    throw InvalidArgument(fmt::format("--tool-mass: expected a mass from 0 to 1000 kg, got {}", o.tool_mass));
  if (!tool.com.allFinite() || tool.com.norm() > 2.0)
    throw InvalidArgument(fmt::format("--tool-cog: expected a point within 2 m of the flange [m], got ({:g}, {:g}, {:g})", tool.com.x(),
                                      tool.com.y(), tool.com.z()));
  const model::RigidBodyInertia carried = tool.mass > 0.0 ? payload + tool : payload;
  if (carried.mass > robot.payload_limit())
    throw InvalidArgument(payload.mass > 0.0
                              ? fmt::format("--tool-mass {:g} kg and the scenario's {:g} kg payload: the flange would carry {:g} kg, beyond {} "
                                            "({:g} kg)",
                                            o.tool_mass, payload.mass, carried.mass, robot.payload_limit_text(), robot.payload_limit())
                              : fmt::format("--tool-mass {:g} kg: beyond {} ({:g} kg)", o.tool_mass, robot.payload_limit_text(),
                                            robot.payload_limit()));
  return carried;
}

void refuse_unless(std::initializer_list<const CLI::Option*> options, bool applies, std::string_view where) {
  if (applies) return;
  std::string given;
  int n = 0;
  for (const CLI::Option* o : options) {
    if (o->count() == 0) continue;
    given += (given.empty() ? "" : ", ") + o->get_name();
    ++n;
  }
  if (n > 0) throw InvalidArgument(fmt::format("{} appl{} only {}", given, n == 1 ? "ies" : "y", where));
}

namespace {
// CLI11 (2.1) reads an empty text as 0 for a number ("--duration ''" ran a run of 0 s, reported as
// "got 0") and a whole number beyond 64 bits as the largest one ("--seed 99999999999999999999" was
// reported as 9223372036854775807). Every number option of every verb gets this check, which runs
// on the text before CLI11 converts it; the option's own checks (bounds) come before it.
CLI::Validator number_text(bool whole) {
  return CLI::Validator(
      [whole](std::string& text) -> std::string {
        if (text.empty()) return fmt::format("expected {}, got '' (an empty value)", whole ? "a whole number" : "a number");
        if (!whole) return {};  // (CLI11 refuses what strtod does not read in full)
        errno = 0;
        char* end = nullptr;
        (void)std::strtoll(text.c_str(), &end, 0);
        if (errno == ERANGE && end == text.c_str() + text.size())
          return fmt::format("expected a whole number, got '{}', beyond the range of a 64-bit integer", text);
        return {};
      },
      "");  // (no description: --help stays as it was)
}

// A file option given an empty value (an unset shell variable: --column-map "$MAP") was taken as not
// given: report shaded no labels and read the log unmapped without a word (audit, session 37).
// (--db '' is meaningful, "no event store", and is not among these.)
CLI::Validator file_name_given() {
  return CLI::Validator(
      [](std::string& text) -> std::string { return text.empty() ? "expected a file name, got '' (an empty value)" : std::string(); }, "");
}
constexpr const char* kFileOptions[] = {"--column-map", "--labels", "--robot"};

void guard_options(CLI::App& app) {
  for (CLI::Option* opt : app.get_options({})) {
    const std::string type = opt->get_type_name();
    const std::string base = type.substr(0, type.find(':'));
    if (base == "INT" || base == "UINT") opt->check(number_text(true));
    else if (base == "FLOAT") opt->check(number_text(false));
    for (const char* name : kFileOptions)
      if (opt->check_lname(name + 2)) opt->check(file_name_given());
  }
  for (CLI::App* sub : app.get_subcommands({})) guard_options(*sub);
}
}  // namespace

void register_all_verbs(CLI::App& app) {
  auto& r = registry();
  std::stable_sort(r.begin(), r.end(), [](const Entry& a, const Entry& b) {
    return a.order != b.order ? a.order < b.order : a.name < b.name;
  });
  for (auto& e : r) e.setup(app);
  guard_options(app);
}

}  // namespace twinwatch::cli
