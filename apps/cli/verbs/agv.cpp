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
                                const sim::AgvParams& plant_params, const sim::AgvParams& model_params, unsigned seed) {
  sim::AgvPlant plant(plant_params, seed);
  const auto gr = sim::imc_pi(model_params.right.gain(), model_params.right.time_constant(), kTauCl);
  const auto gl = sim::imc_pi(model_params.left.gain(), model_params.left.time_constant(), kTauCl);
  sim::PiController pr(gr, plant_params.voltage_limit), pl(gl, plant_params.voltage_limit);
  std::uint8_t buf[256], out[device::kAgvStateSize];
  sim::AgvState s;
  for (;;) {
    const long n = sock.receive(buf, sizeof buf, 5000);
    if (n < 0) _exit(2);  // the monitor went away
    device::AgvCommandDatagram c;
    if (device::decode(buf, static_cast<size_t>(n), c) != device::DecodeStatus::Ok) continue;
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
};

int run_demo(const DemoOptions& o) {
  if (!(o.speed > 0.0 && std::isfinite(o.speed))) throw InvalidArgument(fmt::format("--speed must be a finite factor > 0, got {}", o.speed));
  // the "real" robot is AGV Table 1; the twin is what identification of that robot's tests gives
  sim::AgvParams real;
  const auto tests = sim::simulate_agv_tests(real, o.seed);
  sim::AgvParams twin = real;
  twin.right = ident::fit_agv_motor(tests, "right").params;
  twin.left = ident::fit_agv_motor(tests, "left").params;
  twin.current_noise = real.current_noise;

  device::UdpSocket mon, real_sock, twin_sock;
  const pid_t pr = fork();
  if (pr == 0) robot_process(real_sock, mon.port(), device::AgvRole::Real, real, twin, o.seed + 1);
  const pid_t pt = fork();
  if (pt == 0) robot_process(twin_sock, mon.port(), device::AgvRole::Twin, twin, twin, o.seed + 2);

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
        // collect both answers (or give up after the period: a lost datagram is counted)
        for (int got = 0; got < 2;) {
          const long n = mon.receive(buf, sizeof buf, std::max(1, static_cast<int>(2000 * kPeriod / o.speed)));
          if (n < 0) break;
          monitor.push_bytes(buf, static_cast<size_t>(n));
          ++got;
        }
        std::this_thread::sleep_until(next);
      }
    }
    monitor.finish(seq * kPeriod);
    int alerts = 0;
    double duration = 0.0;
    for (size_t a = before; a < monitor.alerts().size(); ++a)
      if (monitor.alerts()[a].start >= t0) ++alerts, duration += monitor.alerts()[a].duration();
    const bool expect_alert = std::string(test.name) == "forced_divergence";
    if (std::getenv("TW_AGV_DEBUG"))
      for (size_t a = before; a < monitor.alerts().size(); ++a)
        fmt::print(stderr, "alert {} {:.2f}..{:.2f}\n", monitor.alerts()[a].channel, monitor.alerts()[a].start, monitor.alerts()[a].end);
    out["tests"].push_back({{"name", test.name}, {"alerts", alerts}, {"alert_duration_s", duration}});
    if (!o.json)
      fmt::print("{:<24} {:>7} {:>18.2f}  {}\n", test.name, alerts, duration,
                 expect_alert ? "one alert lasting the divergence (~3 s)" : "no alert");
  }
  std::uint8_t quit[device::kAgvCommandSize];
  device::AgvCommandDatagram q;
  q.flags = device::kAgvQuit;
  device::encode(q, quit);
  mon.send_to(real_sock.port(), quit, sizeof quit);
  mon.send_to(twin_sock.port(), quit, sizeof quit);
  int st = 0;
  waitpid(pr, &st, 0);
  waitpid(pt, &st, 0);
  if (seq > 0) monitor.account_for_sent(0, seq - 1);  // a lost tail shows as no gap
  const auto& c = monitor.counters();
  out["datagrams"] = {{"sent_per_side", seq}, {"received", c.received}, {"paired", c.paired}, {"lost", c.lost}, {"duplicated", c.duplicated},
                      {"reordered", c.reordered}, {"malformed", c.malformed}, {"unpaired", c.unpaired}};
  if (o.json) fmt::print("{}\n", out.dump());
  else fmt::print("datagrams: {} commands sent to each side, {} states received, {} paired, {} lost, {} duplicated, {} reordered, {} malformed, {} unpaired (partner never came)\n",
                  seq, c.received, c.paired, c.lost, c.duplicated, c.reordered, c.malformed, c.unpaired);
  return 0;
}

twinwatch::cli::VerbRegistrar reg{"agv", 50, [](CLI::App& app) {
  auto* agv = app.add_subcommand("agv", "AGV digital twin: motor tests, identification, the three-process twin demo");
  agv->require_subcommand(1);

  auto mk = std::make_shared<std::pair<std::string, unsigned>>("agv_tests.csv", 1u);
  auto* make = agv->add_subcommand("make-tests", "Simulate the motor tests of AGV §4.1 on the real-robot stand-in (Table 1 motors)");
  make->add_option("-o,--output", mk->first, "Test CSV to write")->capture_default_str();
  make->add_option("--seed", mk->second, "Noise seed")->capture_default_str();
  make->callback([mk] {
    require_writable(mk->first);  // (a directory or a missing folder: exit 2, named)
    device::write_agv_tests(mk->first, sim::simulate_agv_tests(sim::AgvParams{}, mk->second));
    fmt::print("wrote {}\n", mk->first);
  });

  auto idf = std::make_shared<std::pair<std::string, bool>>("", false);
  auto* ident_cmd = agv->add_subcommand("identify", "Fit Ra, k (eq. 3), B, Tq (eq. 5) and J (eq. 6) per motor from a test CSV");
  ident_cmd->add_option("TESTS", idf->first, "Test CSV: motor,test,voltage_V,current_A,speed_rad_s,time_s")->required()->check(CLI::ExistingFile);
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
      const auto g = sim::imc_pi(f.params.gain(), f.params.time_constant(), kTauCl);
      fmt::print("{:<6} IMC PI (AGV Table 2, tau_cl {:.0f} ms): Kc {:.3f} V·s/rad, Ti {:.3f} s\n", name, 1000 * kTauCl, g.Kc, g.Ti);
    }
  });

  auto d = std::make_shared<DemoOptions>();
  auto* demo = agv->add_subcommand("demo", "Real stand-in, twin and monitor as three processes on loopback; the paper's four tests");
  demo->add_option("--speed", d->speed, "Time factor (10 = ten times faster than real time)")->capture_default_str();
  demo->add_option("--seed", d->seed, "Noise seed")->capture_default_str();
  demo->add_flag("--json", d->json, "Print {\"tests\": [{\"name\", \"alerts\", \"alert_duration_s\"}, ...]}");
  demo->callback([d] { twinwatch::cli::set_exit_code(run_demo(*d)); });
}};

}  // namespace
