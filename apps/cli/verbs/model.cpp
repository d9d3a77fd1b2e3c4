// `twinwatch model show|list`: inspect robot descriptions.
#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "twinwatch/core/error.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "verb_registry.hpp"

namespace {

using twinwatch::model::RobotModel;

std::string fmt_gain(double v, const char* unit) {
  return std::isnan(v) ? std::string("unknown — identify") : fmt::format("{:g} {}", v, unit);
}

// the flange's position at q = 0 (what the text prints, to check a description's kinematics)
Eigen::Vector3d flange_at_zero(const RobotModel& m) {
  twinwatch::model::DynamicsData d(m);
  return twinwatch::model::forward_kinematics(m, d, twinwatch::VectorJ::Zero(m.n_dof())).translation();
}

nlohmann::json to_json(const RobotModel& m) {
  nlohmann::json j;
  j["name"] = m.name();
  j["source"] = m.description().source;
  j["n_dof"] = m.n_dof();
  double total = 0.0;
  for (int i = 0; i < m.n_dof(); ++i) {
    const auto& jt = m.joint(i);
    total += jt.body.mass;
    auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
    j["joints"].push_back({{"name", jt.name},
                           {"mass", jt.body.mass},
                           {"com", {jt.body.com.x(), jt.body.com.y(), jt.body.com.z()}},
                           {"q_min", num(jt.limits.q_min)},
                           {"q_max", num(jt.limits.q_max)},
                           {"qd_max", num(jt.limits.qd_max)},
                           {"qdd_max", num(jt.limits.qdd_max)},  // null: not published
                           {"torque_max", num(jt.limits.torque_max)},
                           {"gear_ratio", num(jt.drive.gear_ratio)},
                           {"torque_constant", num(jt.drive.torque_constant)},
                           {"efficiency", jt.drive.efficiency},
                           {"efficiency_reverse", jt.drive.efficiency_reverse},
                           {"current_limit", num(jt.drive.current_limit)}});  // null: none given
  }
  j["moving_mass"] = total;
  j["gravity"] = {m.gravity().x(), m.gravity().y(), m.gravity().z()};
  const Eigen::Vector3d f = flange_at_zero(m);
  j["flange_at_zero"] = {f.x(), f.y(), f.z()};
  const double rated = m.description().rated_payload;
  j["rated_payload"] = std::isfinite(rated) ? nlohmann::json(rated) : nlohmann::json(nullptr);  // null: not given
  j["payload_limit"] = m.payload_limit();
  j["units"] = {{"mass", "kg"},          {"com", "m (the joint's own frame)"}, {"q_min", "rad"},         {"q_max", "rad"},
                {"qd_max", "rad/s"},     {"qdd_max", "rad/s²"},                {"torque_max", "N·m"},     {"torque_constant", "N·m/A"},
                {"moving_mass", "kg"},   {"rated_payload", "kg"},              {"payload_limit", "kg"},
                {"efficiency", "1 (motor to joint)"}, {"efficiency_reverse", "1 (joint to motor, back-driven)"},
                {"current_limit", "A"},  {"gravity", "m/s² (base frame)"},     {"flange_at_zero", "m (base frame, at q = 0)"}};
  return j;
}

void print_summary(const RobotModel& m) {
  fmt::print("robot {} ({} joints) from {}\n", m.name(), m.n_dof(), m.description().source);
  fmt::print("{:<3} {:<14} {:>8} {:>26} {:>18} {:>9} {:>9} {:>11}  {}\n", "#", "joint", "mass kg", "COM (joint frame) m",
             "q range rad", "qd rad/s", "tau N·m", "qdd rad/s²", "drive N / kt");
  double total = 0.0;
  for (int i = 0; i < m.n_dof(); ++i) {
    const auto& j = m.joint(i);
    total += j.body.mass;
    // a drive the description leaves out is identified from recordings (the twin's gain N·kt·eta)
    const bool no_drive = std::isnan(j.drive.gear_ratio) && std::isnan(j.drive.torque_constant);
    // efficiencies and a current limit only where the description gives them (defaults: 1, 1, none)
    std::string extra;
    if (j.drive.efficiency != 1.0 || j.drive.efficiency_reverse != j.drive.efficiency)
      extra += fmt::format(", efficiency {:g} (back-driven {:g})", j.drive.efficiency, j.drive.efficiency_reverse);
    if (std::isfinite(j.drive.current_limit)) extra += fmt::format(", current limit {:g} A", j.drive.current_limit);
    fmt::print("{:<3} {:<14} {:>8.4f} {:>26} {:>18} {:>9.3f} {:>9.1f} {:>11}  {}{}\n", i + 1, j.name, j.body.mass,
               fmt::format("[{:.4f} {:.4f} {:.4f}]", j.body.com.x(), j.body.com.y(), j.body.com.z()),
               fmt::format("[{:.2f}, {:.2f}]", j.limits.q_min, j.limits.q_max), j.limits.qd_max, j.limits.torque_max,
               std::isfinite(j.limits.qdd_max) ? fmt::format("{:.1f}", j.limits.qdd_max) : std::string("-"),
               no_drive ? std::string("not given: identified from recordings")
                        : fmt::format("{} / {}", fmt_gain(j.drive.gear_ratio, ""), fmt_gain(j.drive.torque_constant, "N·m/A")),
               extra);
  }
  fmt::print("moving mass {:.4f} kg; gravity [{:g} {:g} {:g}] m/s²\n", total, m.gravity().x(), m.gravity().y(),
             m.gravity().z());
  // what --payload-mass, --known-payload and a scenario's payload are checked against
  fmt::print("payloads up to {:g} kg ({})\n", m.payload_limit(), m.payload_limit_text());
  // the model keeps each body in its joint's frame (origin on the axis, z along it); a DH file gives
  // it in DH frame i, a URDF in its link frame: the same point, other coordinates
  fmt::print("centres of mass in each joint's own frame (origin on its axis, z along it), which the model uses; a DH "
             "description gives them in DH frame i, a URDF in its link frame (docs/robot-description.md)\n");
  const Eigen::Vector3d f = flange_at_zero(m);
  fmt::print("flange at q = 0: [{:.5f} {:.5f} {:.5f}] m\n", f.x(), f.y(), f.z());
}

twinwatch::cli::VerbRegistrar reg{"model", 10, [](CLI::App& app) {
  auto* model = app.add_subcommand("model", "Inspect robot descriptions (built-in names or .json/.urdf files)");
  model->require_subcommand(1);

  auto robot = std::make_shared<std::string>();
  auto as_json = std::make_shared<bool>(false);
  auto* show = model->add_subcommand("show", "Print a readable summary: links, masses, limits, drives");
  show->add_option("ROBOT", *robot, "Built-in robot name (see 'twinwatch model list') or a .json/.urdf file")->required();
  show->add_flag("--json", *as_json, "Print the summary as one JSON object");
  show->callback([robot, as_json] {
    const RobotModel m = twinwatch::model::load_robot(*robot);
    if (*as_json)
      fmt::print("{}\n", to_json(m).dump(2));
    else
      print_summary(m);
  });

  auto* list = model->add_subcommand("list", "List the built-in robots");
  list->callback([] {
    const auto names = twinwatch::model::builtin_robot_names();
    // (a missing data directory printed nothing, exit 0: audit of session 56)
    if (names.empty())
      throw twinwatch::PathError(fmt::format("{}: no robot descriptions (*.json) there: is twinwatch installed whole, or does "
                                             "TWINWATCH_DATA_DIR name the wrong directory?",
                                             twinwatch::model::robots_directory()));
    for (const auto& n : names) fmt::print("{}\n", n);
  });
}};

}  // namespace
