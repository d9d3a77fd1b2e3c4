// `twinwatch agv make-tests|identify|demo`: the AGV digital twin [AGV].
#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <thread>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"
#include "twinwatch/device/agv_link.hpp"
#include "twinwatch/device/agv_tests.hpp"
#include "twinwatch/ident/agv_ident.hpp"
#include "twinwatch/monitor/agv_monitor.hpp"
#include "twinwatch/sim/agv.hpp"
#include "verb_registry.hpp"

namespace {

using namespace twinwatch;

constexpr double kPeriod = 0.04;   // the robots' sampling period [s] [AGV §4.1.2]
constexpr double kTauCl = 0.2;     // desired closed-loop time [s] [AGV §4.2]
constexpr double kWheelSpeed = 4;  // [rad/s] as in the paper's tests

void print_fit(const char* name, const ident::AgvMotorFit& f, const model::DcMotorParams& table) {
  fmt::print("{:<6} Ra {:6.3f} Ω ({:5.2f})  k {:6.4f} V·s/rad ({:5.3f})  Tq {:7.4f} N·m ({:5.3f})  B {:9.3e} N·m·s/rad ({:8.2e})  "
             "J {:9.3e} kg·m² ({:8.2e})  tau {:5.3f} s\n",
             name, f.params.Ra, table.Ra, f.params.k, table.k, f.params.Tq, table.Tq, f.params.B, table.B, f.params.J, table.J, f.tau);
}

// the fit and the IMC PI it gives (AGV Table 2), with the units a script needs to read them
nlohmann::json fit_json(const ident::AgvMotorFit& f) {
  const auto g = sim::imc_pi(f.params.gain(), f.params.time_constant(), kTauCl);
  return {{"Ra", f.params.Ra}, {"k", f.params.k}, {"Tq", f.params.Tq}, {"B", f.params.B}, {"J", f.params.J}, {"tau", f.tau},
          {"pi", {{"Kc", g.Kc}, {"Ti", g.Ti}, {"tau_cl", kTauCl}}}};
}

const nlohmann::json& fit_units() {
  static const nlohmann::json u = {{"Ra", "Ω"}, {"k", "V·s/rad"}, {"Tq", "N·m"}, {"B", "N·m·s/rad"}, {"J", "kg·m²"}, {"tau", "s"},
                                   {"pi", {{"Kc", "V·s/rad"}, {"Ti", "s"}, {"tau_cl", "s"}}}};
  return u;
}

// one robot process: waits for a command, steps its PI loops and plant once, answers with its state
[[noreturn]] void robot_process(device::UdpSocket& sock, std::uint16_t monitor_port, device::AgvRole role,
                                const sim::AgvParams& plant_params, const sim::AgvParams& model_params, unsigned seed, int timeout_ms) {
  sim::AgvPlant plant(plant_params, seed);
  const auto gr = sim::imc_pi(model_params.right.gain(), model_params.right.time_constant(), kTauCl);
  const auto gl = sim::imc_pi(model_params.left.gain(), model_params.left.time_constant(), kTauCl);
  sim::PiController pr(gr, plant_params.voltage_limit), pl(gl, plant_params.voltage_limit);
  std::uint8_t buf[256], out[device::kAgvStateSize];
  sim::AgvState s;
  for (;;) {
    const long n = sock.receive(buf, sizeof buf, timeout_ms);
    if (n < 0) _exit(2);  // the monitor went away
    device::AgvCommandDatagram c;
    if (device::decode(buf, static_cast<size_t>(n), c) != device::DecodeStatus::Ok) continue;
    // a command for the other robot is not this one's (a quit meant for the twin stopped the real robot)
    if (c.target != role && c.target != device::AgvRole::Both) continue;
    if (c.flags & device::kAgvQuit) _exit(0);
    plant.set_fault((c.flags & device::kAgvForceZeroVoltage) ? sim::AgvFault::MotorVoltageZero : sim::AgvFault::None);
    const double ur = (c.flags & device::kAgvStop) ? 0.0 : pr.update(c.w_right_ref, s.w_right, kPeriod);
    const double ul = (c.flags & device::kAgvStop) ? 0.0 : pl.update(c.w_left_ref, s.w_left, kPeriod);
    if (c.flags & device::kAgvStop) pr.reset(), pl.reset();
    s = plant.step(ur, ul, kPeriod);
    device::AgvStateDatagram d;
    d.role = role;
    d.seq = c.seq;
    d.t = c.seq * kPeriod;
    d.v = s.v;
    d.w = s.w;
    d.w_right = static_cast<float>(s.w_right);
    d.w_left = static_cast<float>(s.w_left);
    d.u_right = static_cast<float>(s.u_right);
    d.u_left = static_cast<float>(s.u_left);
    d.enc_right = s.enc_right;
    d.enc_left = s.enc_left;
    device::encode(d, out);
    sock.send_to(monitor_port, out, sizeof out);
  }
}

struct DemoOptions {
  double speed = 10.0;
  bool json = false;
  unsigned seed = 7;
  std::string tests;  // the motor tests the twin is identified from ("": simulated with --seed)
};

// [--speed] the demo's time factor: below, the robots' 40 ms periods take minutes; above, a period
// is shorter than a loaded machine's scheduling (and 1e-300 overflowed the period's microseconds)
constexpr double kMinSpeed = 0.05, kMaxSpeed = 1000.0;

int run_demo(const DemoOptions& o) {
  if (!(o.speed >= kMinSpeed && o.speed <= kMaxSpeed))
    throw InvalidArgument(fmt::format("--speed must be a factor from {:g} to {:g}, got {}", kMinSpeed, kMaxSpeed, o.speed));
  // the "real" robot is AGV Table 1; the twin is what identification of that robot's tests gives
  // (the tests --tests names, e.g. make-tests' file, else simulated with the seed)
  sim::AgvParams real;
  const auto tests = o.tests.empty() ? sim::simulate_agv_tests(real, o.seed) : device::read_agv_tests(o.tests);
  sim::AgvParams twin = real;
  const auto fit = [&](const char* motor) {
    try {
      return ident::fit_agv_motor(tests, motor).params;
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(o.tests.empty() ? std::string(e.what()) : fmt::format("{}: {}", o.tests, e.what()));
    }
  };
  twin.right = fit("right");
  twin.left = fit("left");
  twin.current_noise = real.current_noise;

  device::UdpSocket mon, real_sock, twin_sock;
  // a robot waits this long for the next command before it takes the monitor for gone
  const int robot_timeout_ms = std::max(5000, static_cast<int>(std::ceil(3000.0 * kPeriod / o.speed)));
  std::fflush(stdout);  // (the children must not print the parent's buffer again)
  const pid_t pr = fork();
  if (pr == 0) robot_process(real_sock, mon.port(), device::AgvRole::Real, real, twin, o.seed + 1, robot_timeout_ms);
  const pid_t pt = fork();
  if (pt == 0) robot_process(twin_sock, mon.port(), device::AgvRole::Twin, twin, twin, o.seed + 2, robot_timeout_ms);

  monitor::AgvMonitor monitor;
  struct Phase {
    double duration, wr, wl;
    std::uint8_t flags_real, flags_twin;
  };
  struct Test {
    const char* name;
    std::vector<Phase> phases;
  };
  const std::vector<Test> schedule = {
      {"straight_4rad_s", {{3.0, kWheelSpeed, kWheelSpeed, 0, 0}, {1.5, 0, 0, 0, 0}}},
      {"rotate_in_place_4rad_s", {{3.0, kWheelSpeed, -kWheelSpeed, 0, 0}, {1.5, 0, 0, 0, 0}}},
      {"sudden_stop", {{2.0, kWheelSpeed, -kWheelSpeed, 0, 0}, {1.5, 0, 0, device::kAgvStop, device::kAgvStop}}},
      // AGV Fig. 16: the twin's motor voltage forced to 0 during a rotation, then both are told to stop
      {"forced_divergence",
       {{3.0, kWheelSpeed, -kWheelSpeed, 0, device::kAgvForceZeroVoltage}, {1.5, 0, 0, device::kAgvStop, device::kAgvStop}}},
  };
  nlohmann::json out;
  out["tests"] = nlohmann::json::array();
  std::uint32_t seq = 0;
  std::uint8_t buf[256];
  bool all_pass = true;
  const auto wall = std::chrono::microseconds(static_cast<long>(1e6 * kPeriod / o.speed));
  if (!o.json) fmt::print("{:<24} {:>7} {:>18}  {}\n", "test", "alerts", "alert duration s", "expected");
  for (const Test& test : schedule) {
    const double t0 = seq * kPeriod;
    const size_t before = monitor.alerts().size();
    for (const Phase& ph : test.phases) {
      const int steps = static_cast<int>(std::lround(ph.duration / kPeriod));
      for (int k = 0; k < steps; ++k, ++seq) {
        const auto next = std::chrono::steady_clock::now() + wall;
        std::uint8_t cmd[device::kAgvCommandSize];
        device::AgvCommandDatagram c;
        c.seq = seq;
        c.t = seq * kPeriod;
        c.w_right_ref = static_cast<float>(ph.wr);
        c.w_left_ref = static_cast<float>(ph.wl);
        c.target = device::AgvRole::Real;
        c.flags = ph.flags_real;
        device::encode(c, cmd);
        mon.send_to(real_sock.port(), cmd, sizeof cmd);
        c.target = device::AgvRole::Twin;
        c.flags = ph.flags_twin;
        device::encode(c, cmd);
        mon.send_to(twin_sock.port(), cmd, sizeof cmd);
        // collect both answers until two periods have passed (a lost datagram is counted). Only a
        // state counts as an answer: 150 junk datagrams had taken the place of 150 states, which
        // were then counted as lost and moved the alert (review, session 47)
        const auto give_up = std::chrono::steady_clock::now() + 2 * wall;
        for (int got = 0; got < 2;) {
          const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(give_up - std::chrono::steady_clock::now()).count();
          const long n = mon.receive(buf, sizeof buf, static_cast<int>(std::max<long long>(1, left)));
          if (n < 0) break;
          device::AgvStateDatagram state;
          if (device::decode(buf, static_cast<size_t>(n), state) == device::DecodeStatus::Ok) {
            monitor.push(state);
            ++got;
          } else {
            monitor.push_bytes(buf, static_cast<size_t>(n));  // (counted as malformed)
          }
        }
        std::this_thread::sleep_until(next);
      }
    }
    // the test's alerts end with it; the pairing goes on (a state answered late still pairs)
    monitor.close_alerts(seq * kPeriod);
    int alerts = 0;
    double duration = 0.0;
    nlohmann::json spans = nlohmann::json::array();
    std::string spans_text;
    for (size_t a = before; a < monitor.alerts().size(); ++a) {
      const monitor::AgvAlert& al = monitor.alerts()[a];
      if (al.start < t0) continue;
      ++alerts, duration += al.duration();
      const char* channel = al.channel == 'v' ? "linear speed" : "angular speed";
      spans.push_back({{"channel", channel}, {"start_s", al.start - t0}, {"end_s", al.end - t0}, {"duration_s", al.duration()}});
      spans_text += fmt::format("{}{} {:.2f}-{:.2f} s", spans_text.empty() ? "" : ", ", channel, al.start - t0, al.end - t0);
    }
    const int expected = std::string(test.name) == "forced_divergence" ? 1 : 0;
    const bool pass = alerts == expected;
    all_pass = all_pass && pass;
    out["tests"].push_back({{"name", test.name},
                            {"alerts", alerts},
                            {"alert_duration_s", duration},
                            {"expected_alerts", expected},
                            {"pass", pass},
                            {"alert_spans", spans}});
    if (!o.json)
      fmt::print("{:<24} {:>7} {:>18.2f}  {}{}{}\n", test.name, alerts, duration,
                 expected ? "one alert lasting the divergence (~3 s)" : "no alert", pass ? "" : "  FAIL",
                 spans_text.empty() ? "" : fmt::format("  [{} after the test's start]", spans_text));
  }
  std::uint8_t quit[device::kAgvCommandSize];
  device::AgvCommandDatagram q;
  q.flags = device::kAgvQuit;
  device::encode(q, quit);
  mon.send_to(real_sock.port(), quit, sizeof quit);
  mon.send_to(twin_sock.port(), quit, sizeof quit);
  // the robots' ends: 0 after the quit; 2 a robot that timed out waiting, anything else a crash
  const auto ended = [](pid_t p) {
    int st = 0;
    if (waitpid(p, &st, 0) != p) return std::string("not waited for");
    if (WIFEXITED(st)) return WEXITSTATUS(st) == 0 ? std::string() : fmt::format("exited with status {}", WEXITSTATUS(st));
    return WIFSIGNALED(st) ? fmt::format("killed by signal {}", WTERMSIG(st)) : std::string("ended abnormally");
  };
  const std::string real_end = ended(pr), twin_end = ended(pt);
  // states still on their way (answers to the last commands) are read before the count is made
  for (long n; (n = mon.receive(buf, sizeof buf, 50)) >= 0;) monitor.push_bytes(buf, static_cast<size_t>(n));
  monitor.finish(seq * kPeriod);
  if (seq > 0) monitor.account_for_sent(0, seq - 1);  // a lost tail shows as no gap
  const auto& c = monitor.counters();
  out["datagrams"] = {{"sent_per_side", seq}, {"received", c.received}, {"paired", c.paired},   {"lost", c.lost},
                      {"duplicated", c.duplicated}, {"reordered", c.reordered}, {"malformed", c.malformed}, {"unpaired", c.unpaired},
                      {"stray", c.stray}, {"resyncs", c.resyncs}};
  out["robots"] = {{"real", real_end.empty() ? "quit" : real_end}, {"twin", twin_end.empty() ? "quit" : twin_end}};
  const bool robots_ok = real_end.empty() && twin_end.empty();
  out["pass"] = all_pass && robots_ok;
  if (o.json) fmt::print("{}\n", out.dump());
  else {
    fmt::print("datagrams: {} commands sent to each side, {} states received, {} paired, {} lost, {} duplicated, {} reordered, {} malformed, "
               "{} unpaired (partner never came){}\n",
               seq, c.received, c.paired, c.lost, c.duplicated, c.reordered, c.malformed, c.unpaired,
               c.stray + c.resyncs > 0 ? fmt::format(", {} stray (a sequence number far from the robot's), {} resync(s)", c.stray, c.resyncs)
                                       : std::string());
    if (!robots_ok)
      fmt::print("robots: the real stand-in {}, the twin {}\n", real_end.empty() ? "quit" : real_end, twin_end.empty() ? "quit" : twin_end);
    if (!all_pass) fmt::print("FAIL: a test did not raise what it expects\n");
  }
  // a test that missed its expectation, or a robot that stopped answering, is a failed run (status 1)
  return all_pass && robots_ok ? 0 : 1;
}

twinwatch::cli::VerbRegistrar reg{"agv", 50, [](CLI::App& app) {
  auto* agv = app.add_subcommand("agv", "AGV digital twin: motor tests, identification, the three-process twin demo");
  agv->require_subcommand(1);

  auto mk = std::make_shared<std::pair<std::string, unsigned>>("agv_tests.csv", 1u);
  auto* make = agv->add_subcommand("make-tests", "Simulate the motor tests of AGV §4.1 on the real-robot stand-in (Table 1 motors)");
  make->add_option("-o,--output", mk->first, "Test CSV to write")->capture_default_str();
  // (beyond 32 bits it said CLI11's "Could not convert", or "beyond a 64-bit integer": audit of session 56)
  make->add_option("--seed", mk->second, "Noise seed (0 to 4294967295)")->capture_default_str()->check(twinwatch::cli::whole_number(0, 4294967295L));
  make->callback([mk] {
    require_writable(mk->first);  // (a directory or a missing folder: exit 2, named)
    device::write_agv_tests(mk->first, sim::simulate_agv_tests(sim::AgvParams{}, mk->second));
    fmt::print("wrote {}\n", mk->first);
  });

  auto idf = std::make_shared<std::pair<std::string, bool>>("", false);
  auto* ident_cmd = agv->add_subcommand("identify", "Fit Ra, k (eq. 3), B, Tq (eq. 5) and J (eq. 6) per motor from a test CSV");
  ident_cmd->add_option("TESTS", idf->first,
                        "Test CSV with the header motor,test,voltage_V,current_A,speed_rad_s,time_s: motor 'right' or 'left'; test "
                        "'steady' (a constant voltage held until the speed is steady: one row per voltage, time_s unused; rows with the "
                        "wheel below 0.5 rad/s are left out) or 'step' (a voltage step from rest, one row per logging period from the "
                        "first period after the step at one voltage, the wheel turning forwards, until the speed has settled; time_s from any "
                        "origin). Units: V, A, rad/s, s; a current beyond 50 A, a speed beyond 200 rad/s or step rows more than 0.5 s apart "
                        "are refused as another unit (mA, degrees/s or rpm, ms)")
      ->required()
      ->check(CLI::ExistingFile);
  ident_cmd->add_flag("--json", idf->second, "Print {\"right\": {Ra, k, Tq, B, J, tau, pi: {Kc, Ti, tau_cl}}, \"left\": {...}, \"units\": {...}}");
  ident_cmd->callback([idf] {
    const auto rows = device::read_agv_tests(idf->first);
    // the fit's complaints (too few points, a non-physical result) concern this file
    const auto fit = [&](const char* motor) {
      try {
        return ident::fit_agv_motor(rows, motor);
      } catch (const InvalidArgument& e) {
        throw InvalidArgument(fmt::format("{}: {}", idf->first, e.what()));
      }
    };
    const auto r = fit("right"), l = fit("left");
    if (idf->second) {
      fmt::print("{}\n", nlohmann::json{{"right", fit_json(r)}, {"left", fit_json(l)}, {"units", fit_units()}}.dump());
      return;
    }
    fmt::print("identified motor parameters (AGV Table 1 in brackets)\n");
    print_fit("right", r, model::agv_table1_right());
    print_fit("left", l, model::agv_table1_left());
    for (const auto& [name, f] : {std::pair{"right", r}, std::pair{"left", l}}) {
      const auto steady = std::count_if(rows.begin(), rows.end(), [&](const device::AgvTestRow& x) { return x.motor == name && x.test == "steady"; });
      fmt::print("{:<6} from {} of {} steady-state rows (the others with the wheel below 0.5 rad/s) and {} step rows\n", name, f.steady_points,
                 steady, f.step_points);
    }
    for (const auto& [name, f] : {std::pair{"right", r}, std::pair{"left", l}}) {
      const auto g = sim::imc_pi(f.params.gain(), f.params.time_constant(), kTauCl);
      fmt::print("{:<6} IMC PI (AGV Table 2, tau_cl {:.0f} ms): Kc {:.3f} V·s/rad, Ti {:.3f} s\n", name, 1000 * kTauCl, g.Kc, g.Ti);
    }
  });

  auto d = std::make_shared<DemoOptions>();
  auto* demo = agv->add_subcommand("demo", "Real stand-in, twin and monitor as three processes on loopback; the paper's four tests");
  demo->add_option("--speed", d->speed, fmt::format("Time factor (10 = ten times faster than real time; {:g} to {:g})", kMinSpeed, kMaxSpeed))
      ->capture_default_str();
  demo->add_option("--seed", d->seed, "Noise seed (of the simulated motor tests, unless --tests, and of the robots; 0 to 4294967295)")
      ->capture_default_str()
      ->check(twinwatch::cli::whole_number(0, 4294967295L));
  demo->add_option("--tests", d->tests, "Identify the twin from this test CSV ('agv make-tests', or your motors' tests) instead of simulated ones")
      ->check(CLI::ExistingFile);
  demo->add_flag("--json", d->json,
                 "Print {\"tests\": [{\"name\", \"alerts\", \"alert_duration_s\", \"expected_alerts\", \"pass\", \"alert_spans\": [{\"channel\", "
                 "\"start_s\", \"end_s\", \"duration_s\"}] (s after the test's start)}, ...], \"datagrams\": {\"sent_per_side\", \"received\", "
                 "\"paired\", \"lost\", \"duplicated\", \"reordered\", \"malformed\", \"unpaired\", \"stray\", \"resyncs\"}, \"robots\": "
                 "{\"real\", \"twin\"}, \"pass\"}");
  demo->callback([d] { twinwatch::cli::set_exit_code(run_demo(*d)); });
}};

}  // namespace
