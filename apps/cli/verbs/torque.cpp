// `twinwatch identify-torque` and `twinwatch validate-torque`: rigid-body + friction least squares
// in the torque domain (joint torque sensors or a current-derived torque), and its validation on
// held-out data next to a published model.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "twinwatch/core/file_io.hpp"
#include "twinwatch/core/error.hpp"
#include "twinwatch/device/recording.hpp"
#include "twinwatch/ident/rigid_body_ls.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "recordings.hpp"
#include "verb_registry.hpp"

namespace {

using namespace twinwatch;

// "FROM:TO" as fractions of a recording's duration
std::pair<double, double> parse_segment(const std::string& s) {
  const auto c = s.find(':');
  double a = 0.0, b = 1.0;
  auto number = [&](const std::string& x, double& v) {
    if (x.empty()) return true;  // open end keeps the default
    try {
      size_t used = 0;
      v = std::stod(x, &used);
      return used == x.size();
    } catch (const std::exception&) {
      return false;
    }
  };
  if (c == std::string::npos || !number(s.substr(0, c), a) || !number(s.substr(c + 1), b))
    throw InvalidArgument(fmt::format("--segment '{}': expected FROM:TO as fractions of the duration, e.g. 0:0.65", s));
  if (!(a >= 0.0 && b <= 1.0 && a < b))
    throw InvalidArgument(fmt::format("--segment '{}': expected 0 <= FROM < TO <= 1", s));
  return {a, b};
}

// published sigmoid friction per joint (Gaz 2019 Table I form):
//   tau_f = phi1 / (1 + exp(-phi2 (qd + phi3))) - phi1 / (1 + exp(-phi2 phi3))
struct Sigmoid {
  double phi1, phi2, phi3;
};
std::vector<Sigmoid> load_sigmoid_table(const std::string& path, int n) {
  std::ifstream f(path);
  if (!f) throw ParseError(path, 0, "", "cannot open the friction table");
  std::vector<Sigmoid> out(static_cast<size_t>(n), Sigmoid{0, 0, 0});
  std::vector<bool> seen(static_cast<size_t>(n), false);
  std::string line;
  int ln = 0;
  bool header = false;
  while (std::getline(f, line)) {
    ++ln;
    if (line.empty() || line[0] == '#') continue;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!header) {  // first non-comment line: the column names (the columns are read by position)
      header = true;
      // names may carry units after the parameter's name (joint,phi1_Nm,phi2_s_per_rad,phi3_rad_per_s)
      std::vector<std::string> names;
      std::stringstream hs(line);
      for (std::string h; std::getline(hs, h, ',');) names.push_back(h);
      const char* want[4] = {"joint", "phi1", "phi2", "phi3"};
      bool ok = names.size() == 4;
      for (size_t i = 0; ok && i < 4; ++i) ok = names[i].rfind(want[i], 0) == 0 && (names[i].size() == std::strlen(want[i]) || names[i][std::strlen(want[i])] == '_');
      if (!ok)
        throw ParseError(path, ln, "", fmt::format("expected the header 'joint,phi1,phi2,phi3' (each name may end in _UNITS), got '{}'", line));
      continue;
    }
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cells.push_back(c);
    if (cells.size() != 4) throw ParseError(path, ln, "", fmt::format("expected 4 cells 'joint,phi1,phi2,phi3', got {}", cells.size()));
    double v[4];
    const char* names[4] = {"joint", "phi1", "phi2", "phi3"};
    for (int i = 0; i < 4; ++i) {
      try {
        size_t used = 0;
        v[i] = std::stod(cells[static_cast<size_t>(i)], &used);
        if (used != cells[static_cast<size_t>(i)].size() || !std::isfinite(v[i])) throw std::invalid_argument("junk");
      } catch (const std::exception&) {
        throw ParseError(path, ln, names[i], fmt::format("expected a finite number, got '{}'", cells[static_cast<size_t>(i)]));
      }
    }
    const int j = static_cast<int>(v[0]);
    if (j < 1 || j > n || v[0] != j) throw ParseError(path, ln, "joint", fmt::format("expected 1 to {}, got {}", n, cells[0]));
    if (seen[static_cast<size_t>(j - 1)])  // (the later row silently won)
      throw ParseError(path, ln, "joint", fmt::format("joint {} has a row already: expected one row per joint", j));
    out[static_cast<size_t>(j - 1)] = {v[1], v[2], v[3]};
    seen[static_cast<size_t>(j - 1)] = true;
  }
  for (int j = 0; j < n; ++j)
    if (!seen[static_cast<size_t>(j)]) throw ParseError(path, 0, "joint", fmt::format("no row for joint {}", j + 1));
  return out;
}

double sigmoid_friction(const Sigmoid& s, double qd) {
  return s.phi1 / (1.0 + std::exp(-s.phi2 * (qd + s.phi3))) - s.phi1 / (1.0 + std::exp(-s.phi2 * s.phi3));
}

struct IdentOpts {
  std::vector<std::string> recordings, reverse;
  std::string robot = "ur3e", output, column_map, segment = "0:1", signal = "joint_torque";
  double screen = 0.1;
  bool ols = false, no_refit = false, json = false, quiet = false;
  int half_window = 15, order = 2, decimate = 1;
};

int run_identify(const IdentOpts& o) {
  // (before the fit: the model file is no input, and a recording counts once)
  cli::require_distinct(o.recordings, "RECORDINGS");
  {
    std::vector<std::string> inputs = o.recordings;
    for (const auto& p : o.reverse) inputs.push_back(p.substr(p.find('=') == std::string::npos ? 0 : p.find('=') + 1));
    inputs.push_back(o.robot);
    inputs.push_back(o.column_map);
    require_output(o.output, inputs);
  }
  const model::RobotModel m = model::load_robot(o.robot);
  const auto map = cli::load_column_map(o.column_map);
  std::vector<device::Recording> recs, revs;
  recs.reserve(o.recordings.size());
  for (const auto& f : o.recordings) {
    recs.push_back(device::read_recording(f, map ? &*map : nullptr));
    cli::check_units(recs.back(), m);
    cli::require_driven(recs.back(), "identify-torque");
    // is it the arm's recording? (the controller's torque against its model and the other built-in arms')
    ident::ArmCheck arm(m, std::max<size_t>(1, recs.back().samples.size() / 20000));
    for (const RobotSample& s : recs.back().samples) arm.add(s);
    cli::warn_if_another_arm(f, m, arm.verdict(), "identify-torque");
  }
  // FWD=REV pairs: REV is FWD's trajectory played backwards
  std::vector<std::pair<std::string, std::string>> pairs;
  for (const auto& p : o.reverse) {
    const auto eq = p.find('=');
    if (eq == std::string::npos) throw InvalidArgument(fmt::format("--reverse '{}': expected FWD.csv=REV.csv", p));
    pairs.emplace_back(p.substr(0, eq), p.substr(eq + 1));
  }
  revs.reserve(pairs.size());
  const auto [from, to] = parse_segment(o.segment);
  std::vector<ident::Segment> segs;
  for (const auto& r : recs) segs.push_back({&r, from, to, nullptr});
  for (const auto& [fw, rv] : pairs) {
    auto it = std::find_if(segs.begin(), segs.end(), [&](const ident::Segment& s) { return s.recording->path == fw; });
    if (it == segs.end()) throw InvalidArgument(fmt::format("--reverse names '{}', which is not one of the recordings", fw));
    revs.push_back(device::read_recording(rv, map ? &*map : nullptr));
    cli::check_units(revs.back(), m);
    cli::require_driven(revs.back(), "identify-torque");
    it->reverse = &revs.back();
  }
  ident::RigidBodyLsOptions io;
  io.signal = ident::torque_signal_from_string(o.signal);
  io.reversal_screen = o.screen;
  io.weighted = !o.ols;
  io.refit_friction = !o.no_refit;
  io.derivative_half_window = o.half_window;
  io.derivative_order = o.order;
  io.decimate = o.decimate;
  const bool bar = !o.quiet && !o.json && isatty(STDERR_FILENO);
  const ident::RigidBodyModel r = ident::identify_rigid_body(m, o.robot, segs, io, [&](double f) {
    if (bar) std::fprintf(stderr, "\r  identifying %3.0f %%%s", 100 * f, f >= 1.0 ? "\n" : "");
  });
  write_text_file(o.output, r.to_json() + '\n');
  if (o.json) {
    fmt::print("{}\n", r.to_json());
    return 0;
  }
  if (o.quiet) return 0;
  fmt::print("torque model for {} ({}, {}, reversal screen {} rad/s{}) from {} recording(s), segment {} -> {}\n", m.name(),
             o.signal, o.ols ? "OLS" : "weighted LS", o.screen, r.averaged ? ", forward/reverse averaged" : "", recs.size(),
             o.segment, o.output);
  fmt::print("{} base parameters, cond {:.4g} (column-scaled)\n", r.beta.size(), r.cond);
  fmt::print("{:<6} {:>8} {:>8} {:>9} {:>20} {:>20} {:>20}\n", "joint", "rows rb", "rows f", "sigma N·m", "Fc N·m (std %)",
             "Fv N·m·s/rad (std %)", "offset N·m (std %)");
  auto pct = [](double v, double s) { return std::abs(v) > 0 ? 100.0 * s / std::abs(v) : INFINITY; };
  // a coefficient held at its bound has no spread of its own
  auto cell = [&](int j, int c) {
    if (c < 2 && r.friction_held(j, c)) return fmt::format("{:.4f} (held)", r.friction(j, c));
    return fmt::format("{:.4f} ({:.1f})", r.friction(j, c), pct(r.friction(j, c), r.friction_std(j, c)));
  };
  for (int j = 0; j < m.n_dof(); ++j) {
    const size_t J = static_cast<size_t>(j);
    fmt::print("J{:<5} {:>8} {:>8} {:>9.4f} {:>20} {:>20} {:>20}\n", j + 1, r.rows_rigid[J], r.rows_friction[J], r.sigma[J],
               cell(j, 0), cell(j, 1), cell(j, 2));
  }
  for (int j = 0; j < m.n_dof(); ++j) {
    for (int c = 0; c < 2; ++c) {
      if (r.friction_held(j, c))
        fmt::print("note: J{}: {} friction held at 0: the fit would make it negative (friction pushing the motion along), "
                   "which no joint does: the column was taking up something else (too narrow a speed range, or model error)\n",
                   j + 1, c == 0 ? "Coulomb" : "viscous");
    }
  }
  int well = 0;
  for (Eigen::Index i = 0; i < r.beta.size(); ++i) well += pct(r.beta(i), r.beta_std(i)) < 10.0 ? 1 : 0;
  fmt::print("base parameters with relative std < 10 %: {} of {} (all values and std in {})\n", well, r.beta.size(), o.output);
  return 0;
}

struct ValidateOpts {
  std::string model, recording, column_map, segment = "0:1", published, friction_table;
  bool json = false;
};

int run_validate(const ValidateOpts& o) {
  std::ifstream f(o.model);
  if (!f) throw InvalidArgument(fmt::format("{}: cannot open the model", o.model));
  std::stringstream ss;
  ss << f.rdbuf();
  const ident::RigidBodyModel rb = ident::RigidBodyModel::from_json(ss.str(), o.model);
  const model::RobotModel m = model::load_robot(rb.robot);
  if (rb.friction.rows() != m.n_dof())
    throw ParseError(o.model, 0, "friction", fmt::format("expected {} rows (one per joint of {}), got {}", m.n_dof(), rb.robot, rb.friction.rows()));
  const auto map = cli::load_column_map(o.column_map);
  const device::Recording rec = device::read_recording(o.recording, map ? &*map : nullptr);
  if (rec.n_dof != m.n_dof())
    throw InvalidArgument(fmt::format("{} has {} joints, the model's robot {}", o.recording, rec.n_dof, m.n_dof()));
  cli::check_units(rec, m);
  const auto [from, to] = parse_segment(o.segment);
  const ident::TorqueData d =
      ident::torque_data({&rec, from, to, nullptr}, rb.signal, rb.derivative_half_window, rb.derivative_order);
  // (a segment of one sample scored R² 0.0000 on every joint, a number R² does not have there: audit
  // of session 56; validate's own minimum)
  constexpr size_t kMinSamples = 10;
  if (d.t.size() < kMinSamples)
    throw InvalidArgument(fmt::format("{}: --segment {} holds {} sample(s), expected at least {} to score", o.recording, o.segment, d.t.size(),
                                      kMinSamples));
  model::DynamicsData dd(m);
  const auto ours = ident::torque_metrics(d, [&](size_t k) { return rb.predict(m, dd, d.q[k], d.qd[k], d.qdd[k]); });
  // the published model: RNEA with the description's parameters (+ a published friction table)
  std::optional<std::vector<signal::FitMetrics>> pub;
  if (!o.published.empty()) {
    const model::RobotModel pm = model::load_robot(o.published);
    if (pm.n_dof() != m.n_dof()) throw InvalidArgument(fmt::format("--published {} has {} joints, expected {}", o.published, pm.n_dof(), m.n_dof()));
    std::vector<Sigmoid> fr;
    if (!o.friction_table.empty()) fr = load_sigmoid_table(o.friction_table, pm.n_dof());
    model::DynamicsData pd(pm);
    pub = ident::torque_metrics(d, [&](size_t k) {
      VectorJ tau = model::rnea(pm, pd, d.q[k], d.qd[k], d.qdd[k]);
      for (size_t j = 0; j < fr.size(); ++j) tau[static_cast<Eigen::Index>(j)] += sigmoid_friction(fr[j], d.qd[k][static_cast<Eigen::Index>(j)]);
      return tau;
    });
  }
  const double span = d.t.back() - d.t.front();
  if (o.json) {
    nlohmann::json j{{"recording", o.recording}, {"segment", o.segment}, {"samples", d.t.size()}, {"seconds", span}, {"signal", to_string(rb.signal)}};
    auto put = [](const std::vector<signal::FitMetrics>& ms) {
      nlohmann::json a = nlohmann::json::array();
      for (const auto& x : ms) a.push_back({{"rmse", x.rmse}, {"d_tau_pct", x.rel_err_pct}, {"r2", x.r2}, {"max_abs", x.max_abs}});
      return a;
    };
    j["identified"] = put(ours);
    if (pub) j["published"] = put(*pub);
    j["units"] = {{"seconds", "s"}, {"rmse", "N·m"}, {"max_abs", "N·m"}, {"r2", "1"},
                  {"d_tau_pct", "% (norm of the error / norm of the measured torque)"}};
    fmt::print("{}\n", j.dump(2));
    return 0;
  }
  fmt::print("{}: segment {} ({} samples, {:.2f} s), signal {}\n", o.recording, o.segment, d.t.size(), span, to_string(rb.signal));
  // (the published model without --friction-table has no friction at all: J7 d_tau 100.53 % read
  // as the published model's error, without a word; audit of session 56)
  if (pub && o.friction_table.empty())
    fmt::print("note: the published model here is {}'s rigid body alone, without friction (give its table with --friction-table)\n",
               o.published);
  fmt::print("{:<6} {:>14} {:>12} {:>10}", "joint", "RMSE N·m", "d_tau %", "R²");
  if (pub) fmt::print(" | {:>14} {:>12} {:>10}", "published RMSE", "d_tau %", "R²");
  fmt::print("\n");
  auto row = [&](const std::string& name, const signal::FitMetrics& a, const signal::FitMetrics* b) {
    fmt::print("{:<6} {:>14.4f} {:>12.2f} {:>10.4f}", name, a.rmse, a.rel_err_pct, a.r2);
    if (b) fmt::print(" | {:>14.4f} {:>12.2f} {:>10.4f}", b->rmse, b->rel_err_pct, b->r2);
    fmt::print("\n");
  };
  for (size_t j = 0; j < ours.size(); ++j) row(fmt::format("J{}", j + 1), ours[j], pub ? &(*pub)[j] : nullptr);
  return 0;
}

twinwatch::cli::VerbRegistrar reg{"identify-torque", 41, [](CLI::App& app) {
  auto o = std::make_shared<IdentOpts>();
  auto* sub = app.add_subcommand("identify-torque", "Identify a rigid-body + friction model in the torque domain (least squares)");
  sub->footer(twinwatch::cli::with_exit_status(
      "tau_j = Y_b,j(q, qd, qdd) beta + Fc_j sign(qd_j) + Fv_j qd_j + offset_j on the base parameters, for robots\n"
      "with joint torque sensors (Panda, Kinova) or a current-derived torque. qdd is the zero-phase local-polynomial\n"
      "derivative of qd on the recorded time axis; rows with |qd_j| below --screen are left out of the rigid-body\n"
      "fit only (HESR III-E); weighted LS with per-joint residual variances (or --ols); parameter standard\n"
      "deviations. Foreign logs load through --column-map (docs/recordings.md)."));
  sub->add_option("RECORDINGS", o->recordings, "Recording CSV file(s)")->required()->check(CLI::ExistingFile);
  sub->add_option("--robot", o->robot, "Robot description (built-in name or .json/.urdf file; a file is stored in the model by its absolute path)")
      ->capture_default_str()
      ->transform([](std::string s) { return cli::robot_reference(s); });
  sub->add_option("-o,--output", o->output, "Model JSON to write")->required();
  sub->add_option("--column-map", o->column_map, "Column map for foreign CSV logs (file column -> RTDE name, scale)");
  sub->add_option("--signal", o->signal, "Torque signal: joint_torque, current_as_torque or target_moment")->capture_default_str();
  sub->add_option("--segment", o->segment, "Part of each recording to use, FROM:TO as fractions of its duration")->capture_default_str();
  sub->add_option("--reverse", o->reverse, "FWD.csv=REV.csv: REV is FWD played backwards; average them (HESR III-C)");
  sub->add_option("--screen", o->screen, "Reversal screen [rad/s] for the rigid-body fit (0: off)")->capture_default_str()->check(twinwatch::cli::nonnegative_number());
  sub->add_option("--half-window", o->half_window, "Half window [samples] of the qd smoothing / qdd derivative")->capture_default_str()->check(twinwatch::cli::whole_number(1, 100000));
  sub->add_option("--order", o->order, "Polynomial order of that local fit")->capture_default_str()->check(twinwatch::cli::whole_number(1, 10));
  sub->add_option("--decimate", o->decimate, "Use every k-th sample")->capture_default_str()->check(twinwatch::cli::whole_number(1, 1000000));
  sub->add_flag("--ols", o->ols, "Ordinary least squares instead of weighted");
  sub->add_flag("--no-refit", o->no_refit, "Keep the friction from the screened joint fit (no re-fit on all rows; that fit does not hold Coulomb and viscous >= 0)");
  sub->add_flag("--json", o->json, "Print the model JSON");
  sub->add_flag("-q,--quiet", o->quiet, "Print nothing on success but the JSON that --json asks for");
  sub->callback([o] { twinwatch::cli::set_exit_code(run_identify(*o)); });
}};

twinwatch::cli::VerbRegistrar reg2{"validate-torque", 42, [](CLI::App& app) {
  auto o = std::make_shared<ValidateOpts>();
  auto* sub = app.add_subcommand("validate-torque", "Torque RMSE and d_tau % of an identify-torque model, next to a published model");
  sub->footer(twinwatch::cli::with_exit_status(
      "Per-joint torque RMSE and d_tau % (100 |tau - tau_hat| / |tau|) on a recording (segment), optionally next\n"
      "to a published model: RNEA with a robot description's own parameters plus a published sigmoid friction\n"
      "table (CSV joint,phi1,phi2,phi3; Gaz 2019 Table I form)."));
  sub->add_option("RECORDING", o->recording, "Recording CSV")->required()->check(CLI::ExistingFile);
  sub->add_option("--model", o->model, "Model JSON from identify-torque")->required()->check(CLI::ExistingFile);
  sub->add_option("--column-map", o->column_map, "Column map for a foreign CSV log");
  sub->add_option("--segment", o->segment, "Part of the recording, FROM:TO as fractions of its duration")->capture_default_str();
  sub->add_option("--published", o->published, "Robot description whose own parameters are the published model");
  auto* friction_table = sub->add_option("--friction-table", o->friction_table, "Published sigmoid friction CSV for --published");
  sub->add_flag("--json", o->json, "Print the metrics as JSON");
  sub->callback([=] {
    twinwatch::cli::refuse_unless({friction_table}, !o->published.empty(), "with --published (the published model's friction)");
    twinwatch::cli::set_exit_code(run_validate(*o));
  });
}};

}  // namespace
