// `twinwatch friction-study REC... | --simulated [--json]`: the HESR evaluation protocol (§V) on
// recordings or on the built-in simulated joints, printed as the paper's tables.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <iterator>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <utility>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"
#include "twinwatch/device/recording.hpp"
#include "twinwatch/friction/closed_loop.hpp"
#include "twinwatch/friction/protocol.hpp"
#include "twinwatch/friction/synthetic_joint.hpp"
#include "twinwatch/friction/twin_block.hpp"
#include "twinwatch/ident/twin_model.hpp"
#include "recordings.hpp"
#include "verb_registry.hpp"

namespace {

using namespace twinwatch;
using namespace twinwatch::friction;

struct StudyOptions {
  std::vector<std::string> recordings;
  bool simulated = false, closed_loop = false;
  std::vector<int> joints;  // 1-based
  std::vector<std::string> column_maps;
  std::string torque = "current", save_twin;
  double gain = 1.0;
  bool gain_given = false;  // --gain on the command line (its default 1 leaves currents in A)
  double split = 0.5;
  int decimate = 1;
  int trials = 200;
  int hops = -1;
  double input_guard = 0.1;
  int reversal_weight = 1;
  bool rich_training = false;
  bool crawl_training = false;
  int loop_training = 0;  // closed-loop identification rounds (--loop-training)
  int loop_tuning = 0;    // closed-loop trials to tune LuGre's and ParFam-H's parameters (--loop-tuning)
  int tuning_trajectories = 1;  // training trajectories per tuning trial (--tuning-trajectories)
  std::string memory = "displacement";
  int remove_viscous = -1;  // < 0: the study's (on); 0 off, 1 on
  std::string predictions;  // CSV of the validation record and every model's prediction
  std::string functions;  // empty: the library's operator set
  double l1 = -1.0;       // < 0: the study's gamma
  int starts = -1;        // < 0: the library's
  int odd = -1;           // < 0: the study's; 0 off, 1 on (ParFam odd symmetry)
  double fixed_alpha = 0.0, fixed_beta = 0.0;  // > 0 both: Stage 1 skipped
  unsigned seed = 1;
  double screening = 0.1;
  bool json = false, quiet = false;
  double pd_scale = 1.0;       // multiplies the eq. 20 gains of the closed loop
  bool literal_eq19 = false;   // closed loop without the inner-loop inverse feed-forward
  double truth_lag_scale = 1.0;  // --closed-loop diagnosis: multiplies the truth's frictional-lag time
};

// joint j of a recording as a JointRecord (every k-th sample), torque = gain * current or target_moment
JointRecord joint_record(const device::Recording& rec, int j, const StudyOptions& o) {
  const bool moment = o.torque == "moment";
  const std::uint32_t need = moment ? kFieldTargetMoment : kFieldActualCurrent;
  if (!(rec.present & need))
    throw InvalidArgument(fmt::format("{}: no {} columns (--torque {}), expected the joint torque source", rec.path,
                                      moment ? "target_moment_*" : "actual_current_*", o.torque));
  if (!(rec.present & kFieldActualQd))
    throw InvalidArgument(fmt::format("{}: no actual_qd_* columns, expected the measured joint velocity", rec.path));
  if (rec.gaps > 0)
    throw InvalidArgument(fmt::format("{}: {} timestamp gap(s), expected a uniformly sampled record", rec.path, rec.gaps));
  JointRecord r;
  r.dt = rec.median_period * o.decimate;
  for (std::size_t k = 0; k < rec.samples.size(); k += static_cast<std::size_t>(o.decimate)) {
    const RobotSample& s = rec.samples[k];
    r.q.push_back(s.q[j]);
    r.qd.push_back(s.qd[j]);
    r.tau.push_back(moment ? s.target_moment[j] : o.gain * s.current[j]);
  }
  r.validate(fmt::format("{} joint {}", rec.path, j + 1));
  return r;
}

JointRecord slice(const JointRecord& r, long a, long b) {
  JointRecord s;
  s.dt = r.dt;
  s.q.assign(r.q.begin() + a, r.q.begin() + b);
  s.qd.assign(r.qd.begin() + a, r.qd.begin() + b);
  s.tau.assign(r.tau.begin() + a, r.tau.begin() + b);
  return s;
}

// The mean of friction x speed over the samples faster than the median speed (a friction model's
// power taken from the motion there: > 0), and that median; none for no samples or predictions of
// another length
struct SpeedPower {
  double median_speed, mean;
};
std::optional<SpeedPower> power_above_median_speed(const std::vector<double>& qd, const std::vector<double>& friction) {
  if (qd.empty() || friction.size() != qd.size()) return std::nullopt;
  std::vector<double> speeds;
  for (const double v : qd) speeds.push_back(std::abs(v));
  std::vector<double> sorted = speeds;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
  const double median = sorted[sorted.size() / 2];
  double power = 0.0;
  long n = 0;
  for (size_t k = 0; k < qd.size(); ++k)
    if (speeds[k] > median) power += friction[k] * qd[k], ++n;
  if (n == 0) return std::nullopt;
  return SpeedPower{median, power / static_cast<double>(n)};
}

// (n_dof: the recordings' joint count)
std::vector<ProtocolRecords> recorded_joints(const StudyOptions& o, int& n_dof) {
  // (TRAIN given again as VALIDATION was called an "untrained validation record")
  cli::require_distinct(o.recordings, "RECORDINGS");
  if (o.recordings.size() > 3)
    throw InvalidArgument(fmt::format("{} recordings given, expected 1 to 3 (TRAIN [VALIDATION [CHIRP]])", o.recordings.size()));
  const cli::ColumnMaps maps(o.column_maps, o.recordings);
  std::vector<device::Recording> recs;
  for (const auto& f : o.recordings) recs.push_back(device::read_recording(f, maps.of(f)));
  for (const auto& r : recs) cli::require_driven(r, "friction-study");
  // the units checks that need no arm (the study takes none): a time column in milliseconds made a
  // 1 s sample period and fitted it, exit 0 (audit of session 56)
  for (const auto& r : recs) {
    cli::check_sample_period(r.path, r.median_period);
    // (and positions in degrees beside speeds in rad/s, or the other way round, or of the other sign,
    // told by the positions' change against the speeds' integral: the range check the other verbs
    // make needs the arm's description, which the study takes none of; audit of session 56)
    cli::PositionSpeedCheck agree(r.path, r.n_dof);
    for (size_t k = 0; k < r.samples.size(); ++k) {
      for (int j = 0; j < r.n_dof; ++j)
        if (std::abs(r.samples[k].qd[j]) > cli::kUnitsAnyJointSpeedMax)
          throw InvalidArgument(fmt::format("{}: J{} moves at {:.4g} rad/s at t = {:.3f} s (sample {}), faster than any arm joint turns "
                                            "({:g} rad/s): are the speeds in degrees/s, or is another column mapped to actual_qd_{}? Scale "
                                            "them with a column map ('COLUMN,actual_qd_{},0.017453292519943295', docs/recordings.md)",
                                            r.path, j + 1, r.samples[k].qd[j], r.samples[k].timestamp - r.samples.front().timestamp,
                                            k + 1, cli::kUnitsAnyJointSpeedMax, j, j));
      agree.add(r.samples[k]);
    }
    agree.finish();
  }
  for (const auto& r : recs)
    if (r.n_dof != recs[0].n_dof)
      throw InvalidArgument(fmt::format("{} has {} joints, {} has {}", r.path, r.n_dof, recs[0].path, recs[0].n_dof));
  n_dof = recs[0].n_dof;
  // the joints: given, or every joint that moves in the training record
  std::vector<int> joints;
  const auto peak_speed = [&](int j) {
    double peak = 0.0;
    for (const RobotSample& s : recs[0].samples) peak = std::max(peak, std::abs(s.qd[j]));
    return peak;
  };
  for (int j : o.joints) {
    if (j < 1 || j > recs[0].n_dof)
      throw InvalidArgument(fmt::format("--joint {} is out of range, expected 1..{}", j, recs[0].n_dof));
    // (it said "the rigid-body fit keeps 0 samples", naming no joint)
    if (const double peak = peak_speed(j - 1); !(peak > 2.0 * o.screening))
      throw InvalidArgument(fmt::format("--joint {}: J{} moves at most {:.3g} rad/s in {}, not faster than {:g} rad/s (twice --screening): "
                                        "the study needs a joint that moves (its friction away from the reversals)",
                                        j, j, peak, recs[0].path, 2.0 * o.screening));
    joints.push_back(j - 1);
  }
  if (joints.empty())
    for (int j = 0; j < recs[0].n_dof; ++j)
      if (peak_speed(j) > 2.0 * o.screening) joints.push_back(j);
  if (joints.empty())
    throw InvalidArgument(fmt::format("{}: no joint moves faster than {} rad/s; name one with --joint", recs[0].path,
                                      2.0 * o.screening));
  std::vector<ProtocolRecords> out;
  for (int j : joints) {
    ProtocolRecords p;
    p.joint = fmt::format("J{}", j + 1);
    const JointRecord first = joint_record(recs[0], j, o);
    if (recs.size() == 1) {
      // one recording: the first `split` of it trains, the rest validates
      const auto cut = static_cast<long>(std::lround(o.split * static_cast<double>(first.size())));
      p.train = slice(first, 0, cut);
      p.fourier = slice(first, cut, first.size());
    } else {
      p.train = first;
      p.fourier = joint_record(recs[1], j, o);
    }
    if (recs.size() == 3) p.chirp = joint_record(recs[2], j, o);
    out.push_back(std::move(p));
  }
  return out;
}

// the ParFam options the command line sets (for ParFam-H, ParFam-V and the smoothing re-fits)
void apply_parfam_options(ParFamOptions& p, const StudyOptions& o) {
  if (o.hops >= 0) p.hops = o.hops;
  if (o.starts >= 0) p.starts = o.starts;
  if (o.l1 >= 0.0) p.l1 = o.l1;
  p.input_guard = o.input_guard;
  p.reversal_weight = o.reversal_weight;
  if (o.memory == "time")
    p.prior.drive = HysteresisDrive::Time;
  else if (o.memory == "displacement")
    p.prior.drive = HysteresisDrive::Displacement;
  else
    throw InvalidArgument(fmt::format("--memory is '{}', expected 'time' or 'displacement'", o.memory));
  if (o.remove_viscous > 1)
    throw InvalidArgument(fmt::format("--prior-remove-viscous is {}, expected 0 or 1", o.remove_viscous));
  if (o.remove_viscous >= 0) p.prior.remove_viscous = o.remove_viscous == 1;
  if (o.fixed_alpha > 0.0 || o.fixed_beta > 0.0) {
    p.hysteresis = HysteresisParams{o.fixed_alpha, o.fixed_beta, p.prior.drive};
    p.hysteresis->validate();
  }
  if (o.odd > 1) throw InvalidArgument(fmt::format("--odd is {}, expected 0 or 1", o.odd));
  if (o.odd >= 0) p.odd = o.odd == 1;
  if (!o.functions.empty()) {
    p.functions.clear();
    std::size_t a = 0;
    while (a <= o.functions.size()) {
      const std::size_t b = std::min(o.functions.find(',', a), o.functions.size());
      const std::string f = o.functions.substr(a, b - a);
      const auto op = unary_op_from_string(f);
      if (!op) throw InvalidArgument(fmt::format("--functions has '{}', expected a comma list of sin, cos, exp, tanh, stribeck", f));
      p.functions.push_back(*op);
      a = b + 1;
    }
  }
}

std::string num(double v, int prec = 4) { return std::isfinite(v) ? fmt::format("{:.{}f}", v, prec) : "n/a"; }
// mean ± spread over trials; "n/a" when there was nothing to score (no reversal window in the record:
// "nan ± 0.0000" read as a measured spread of 0)
std::string pm(double mean, double spread) {
  return std::isfinite(mean) ? fmt::format("{:.4f} ± {:.4f}", mean, spread) : "n/a";
}

nlohmann::json jnum(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

// the unit of every torque the offline tables give: a recording's currents without --gain are
// studied as they are (gain 1), in A, which the tables used to label N·m
std::string torque_unit(const StudyOptions& o) {
  return !o.recordings.empty() && o.torque == "current" && !o.gain_given ? "A" : "N·m";
}

void print_tables(const std::vector<ProtocolResult>& res, const StudyOptions& o) {
  const std::string u = torque_unit(o);
  const std::vector<std::string> names = {"LuGre", "Stribeck", "RBFNN", "RBFNN-H", "ParFam-V", "ParFam-H"};
  const auto table = [&](const char* title, auto get, int prec) {
    fmt::print("\n{}\n{:<10}", title, "Model");
    for (const auto& r : res) fmt::print("{:>12}", r.study.joint);
    fmt::print("\n");
    for (const auto& n : names) {
      fmt::print("{:<10}", n);
      for (const auto& r : res) fmt::print("{:>12}", num(get(r.study.model(n)), prec));
      fmt::print("\n");
    }
  };
  fmt::print("HESR friction study ({} joint(s){})\n", res.size(), o.simulated ? ", simulated Maxwell-slip joints" : "");
  for (const auto& r : res) {
    fmt::print("{}: {} (screening {} rad/s, {} retained samples, rank {}/{})\n", r.study.joint, r.rigid.equation(),
               r.rigid.options.reversal_threshold, r.rigid.samples, r.rigid.rank, r.rigid.columns);
    fmt::print("{}: {} reversals in the validation record, {} samples in their +-0.1 s windows\n", r.study.joint,
               r.study.reversals, r.study.reversal_samples);
  }
  table(fmt::format("Table VIII: offline residual-torque RMSE on the untrained validation record [{}]", u).c_str(),
        [](const ModelStudy& m) { return m.fourier_rmse; }, 4);
  table(fmt::format("Table IX: RMSE within +-0.1 s velocity-reversal windows [{}]", u).c_str(),
        [](const ModelStudy& m) { return m.reversal_rmse; }, 4);
  table(fmt::format("Chirp: in-distribution RMSE (below the split frequency) [{}]", u).c_str(),
        [](const ModelStudy& m) { return m.chirp_id_rmse; }, 4);
  table(fmt::format("Chirp: out-of-distribution RMSE (from the split frequency on) [{}]", u).c_str(),
        [](const ModelStudy& m) { return m.chirp_ood_rmse; }, 4);
  table("Chirp: OOD / ID RMSE ratio", [](const ModelStudy& m) { return m.chirp_ood_rmse / m.chirp_id_rmse; }, 2);
  for (const auto& r : res) {
    fmt::print("\nTable III ({}): reversal-screening threshold sensitivity of the rigid-body fit\n", r.study.joint);
    fmt::print("{:>8} {:>9} {:>6} {:>10} {:>10} {:>10}\n", "Th.", "Samples", "Rank", "All", "Ret.", "log10 k");
    for (const auto& s : r.screening)
      fmt::print("{:>8.2f} {:>9} {:>6} {:>10.4f} {:>10.4f} {:>10.3f}\n", s.threshold, s.samples, s.rank, s.rmse_all,
                 s.rmse_retained, s.log10_condition);
  }
  for (const auto& r : res) {
    fmt::print("\nTable IV ({}): smoothing-window sensitivity of ParFam-H (window 1 = nominal)\n", r.study.joint);
    fmt::print("{:>8} {:>14} {:>14} {:>12}\n", "Window", "Offline RMSE", "Reversal RMSE", "Rev. samples");
    for (const auto& s : r.smoothing)
      fmt::print("{:>8} {:>14} {:>14} {:>12}\n", s.window, num(s.fourier_rmse), num(s.reversal_rmse), s.reversal_samples);
  }
  for (const auto& r : res) {
    fmt::print("\nTable V ({}): measurement-uncertainty sensitivity of ParFam-H, {} trials per level\n", r.study.joint,
               o.trials);
    fmt::print("{:>8} {:>22} {:>22} {:>12}\n", "Level", "Offline RMSE", "Reversal RMSE", "ranked 1st");
    for (const auto& u : r.uncertainty)
      fmt::print("{:>7.0f}% {:>22} {:>22} {:>11.0f}%\n", 100 * u.level,
                 pm(u.fourier_mean, u.fourier_std), pm(u.reversal_mean, u.reversal_std), 100 * u.first_share);
  }
  table("Table VI: evaluation time per sample (state update + model) [ns]",
        [](const ModelStudy& m) { return m.eval_ns; }, 1);
  table("Identification time [s]", [](const ModelStudy& m) { return m.fit.seconds; }, 2);
  fmt::print("\nFits\n");
  for (const auto& r : res)
    for (const auto& m : r.study.models) fmt::print("{} {}: {}\n", r.study.joint, m.name, m.fit.brief_report());
  fmt::print("\nTable VII: identified equations\n");
  for (const auto& r : res)
    for (const char* n : {"ParFam-H", "ParFam-V"}) fmt::print("{} {}: {}\n", r.study.joint, n, r.study.model(n).equation);
}

nlohmann::json to_json(const std::vector<ProtocolResult>& res) {
  nlohmann::json out;
  for (const auto& r : res) {
    nlohmann::json j;
    j["joint"] = r.study.joint;
    j["rigid_body"] = {{"equation", r.rigid.equation()}, {"samples", r.rigid.samples}, {"rank", r.rigid.rank},
                       {"inertia", r.rigid.inertia}, {"gravity_sin", r.rigid.gravity_sin},
                       {"gravity_cos", r.rigid.gravity_cos}, {"offset", r.rigid.offset}};
    j["reversals"] = r.study.reversals;
    j["reversal_samples"] = r.study.reversal_samples;
    for (const auto& m : r.study.models)
      j["models"].push_back({{"name", m.name}, {"fit_status", std::string(to_string(m.fit.status))},
                             {"fit_seconds", m.fit.seconds}, {"equation", m.equation},
                             {"fourier_rmse", jnum(m.fourier_rmse)}, {"reversal_rmse", jnum(m.reversal_rmse)},
                             {"chirp_id_rmse", jnum(m.chirp_id_rmse)}, {"chirp_ood_rmse", jnum(m.chirp_ood_rmse)},
                             {"eval_ns", m.eval_ns}});
    for (const auto& s : r.screening)
      j["screening"].push_back({{"threshold", s.threshold}, {"samples", s.samples}, {"rank", s.rank},
                                {"rmse_all", s.rmse_all}, {"rmse_retained", s.rmse_retained},
                                {"log10_condition", jnum(s.log10_condition)}});
    for (const auto& s : r.smoothing)
      j["smoothing"].push_back({{"window", s.window}, {"fourier_rmse", jnum(s.fourier_rmse)},
                                {"reversal_rmse", jnum(s.reversal_rmse)}, {"reversal_samples", s.reversal_samples}});
    for (const auto& u : r.uncertainty)
      j["uncertainty"].push_back({{"level", u.level}, {"fourier_mean", u.fourier_mean}, {"fourier_std", u.fourier_std},
                                  {"reversal_mean", u.reversal_mean}, {"reversal_std", u.reversal_std},
                                  {"first_share", u.first_share}});
    out["joints"].push_back(j);
  }
  return out;
}

// the simulated joints' training excitation (--rich-training, --crawl-training; HESR's sweep by default)
TrainingExcitation training_of(const StudyOptions& o) {
  if (o.rich_training && o.crawl_training) throw InvalidArgument("--rich-training and --crawl-training exclude each other");
  return o.rich_training ? TrainingExcitation::Fourier : o.crawl_training ? TrainingExcitation::Crawls : TrainingExcitation::Sweep;
}

// HESR §V-G on the simulated joints: models fitted on each joint's residual-torque training record,
// then the eq. 19-20 feed-forward with each of them on a 10 s untrained Fourier trajectory
int run_closed_loop_study(const StudyOptions& o) {
  if (!o.recordings.empty())
    throw InvalidArgument("--closed-loop runs on the simulated joints; give no recordings");
  if (!std::isfinite(o.pd_scale) || o.pd_scale < 0.0)
    throw InvalidArgument(fmt::format("--pd-scale is {}, must be >= 0", o.pd_scale));
  if (!std::isfinite(o.truth_lag_scale) || o.truth_lag_scale < 0.0)
    throw InvalidArgument(fmt::format("--truth-lag-scale is {}, must be >= 0", o.truth_lag_scale));
  const std::vector<std::string> comps = {"None", "Baseline", "LuGre", "RBFNN-H", "ParFam-H", "True friction"};
  struct JointRuns {
    std::string joint;
    std::vector<ClosedLoopRun> runs;
    std::string parfam_equation;  // ParFam-H as fitted on the joint's training record
  };
  std::vector<JointRuns> all;
  const auto t0 = std::chrono::steady_clock::now();
  const auto say = [&](const std::string& msg) {
    if (o.quiet) return;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    fmt::print(stderr, "[{:6.1f} s] {}\n", s, msg);
  };
  for (SimulatedJoint j : simulated_study_joints()) {
    if (!o.joints.empty() && std::find(o.joints.begin(), o.joints.end(), j.name[1] - '0') == o.joints.end()) continue;
    // a diagnosis only: the same truth (records and plant) with its frictional lag scaled
    j.truth.lag_time *= o.truth_lag_scale;
    say(fmt::format("{}: fitting the residual-torque models on the 20 s {}", j.name,
                    o.crawl_training ? "sweep and crawls" : "sweep"));
    FrictionStudyOptions so;
    apply_parfam_options(so.parfam, o);
    const FrictionStudyData data = simulated_study_data(j, o.seed, training_of(o));
    const JointStudy study = run_friction_study(data, so);
    // the controller's rigid body as the twin identifies it from the joint's recordings
    const double inertia = identified_inertia(j, o.seed, training_of(o));
    say(fmt::format("{}: identified inertia {:.4f} kg·m^2 (rigid-body fit on the sweep, Fourier and chirp records)", j.name, inertia));
    ClosedLoopOptions co = closed_loop_options_for(j, inertia);
    co.seed = o.seed;
    co.gains.kp_min *= o.pd_scale;
    co.gains.kp_max *= o.pd_scale;
    co.gains.kd_min *= o.pd_scale;
    co.gains.kd_max *= o.pd_scale;
    co.inverse_feedforward = !o.literal_eq19;
    const VelocityProfile desired = closed_loop_profile(o.seed);
    JointRuns jr{j.name, {}, study.model("ParFam-H").equation};
    say(fmt::format("{}: closed loop, {} compensations", j.name, comps.size()));
    jr.runs.push_back(run_closed_loop(j.truth, desired, nullptr, co, false));
    jr.runs.push_back(run_closed_loop(j.truth, desired, nullptr, co, true));
    // --loop-training: the trial continues the training motion on the same joint: its plant starts in
    // the state the sweep left (at rest, elements stressed), so that the appended record is one
    // continuous experiment for the refit's stateful models. From relaxed elements instead, the
    // record's first ~0.1 s (a break-away from zero) contradicts the state the models carry over from
    // the sweep by up to the Coulomb level, and those samples dominated the least-squares refit.
    const std::optional<MaxwellSlipFriction> after_training =
        o.loop_training > 0 ? std::optional(training_end_state(j, o.seed, training_of(o))) : std::nullopt;
    // --loop-tuning: the training trajectories of the tuning trials (never the scored one)
    std::vector<VelocityProfile> tuning;
    for (int k = 0; o.loop_tuning > 0 && k < o.tuning_trajectories; ++k)
      tuning.push_back(closed_loop_profile(o.seed + 1000u + 100u * static_cast<unsigned>(k)));
    for (const char* name : {"LuGre", "RBFNN-H", "ParFam-H"}) {
      std::shared_ptr<FrictionModel> model = study.model(name).model;
      if (!model) throw InvalidArgument(fmt::format("{}: the {} fit failed: {}", j.name, name, study.model(name).fit.brief_report()));
      // identification in the loop (--loop-training N): run the model's own feed-forward on a
      // training trajectory of the loop (another seed than the scored one), append what the joint's
      // sensors recorded to the training record, refit; N rounds, the same for every model
      for (int round = 0; round < o.loop_training; ++round) {
        ClosedLoopOptions lo = co;
        lo.record_measurements = true;
        lo.seed = co.seed + 500u + static_cast<unsigned>(round);
        const ClosedLoopRun trial = run_closed_loop(j.truth, closed_loop_profile(o.seed + 1000u + static_cast<unsigned>(round)),
                                                    model.get(), lo, true, &*after_training);
        FrictionStudyData d2 = data;
        d2.train.qd.insert(d2.train.qd.end(), trial.measured.qd.begin(), trial.measured.qd.end());
        d2.train.tau.insert(d2.train.tau.end(), trial.measured.tau.begin(), trial.measured.tau.end());
        const JointStudy again = run_friction_study(d2, so);
        say(fmt::format("{}: {} in-loop round {}: training tracking {:.2f} mrad, refitted on {} + {} samples", j.name, name, round + 1,
                        1e3 * trial.rmse, data.train.size(), trial.measured.size()));
        model = again.model(name).model;
        if (!model) throw InvalidArgument(fmt::format("{}: the in-loop refit of {} failed: {}", j.name, name, again.model(name).fit.brief_report()));
      }
      // parameters tuned on the loop's tracking error of the training trajectory (--loop-tuning N)
      if (o.loop_tuning > 0 && std::string_view(name) != "RBFNN-H") {
        ClosedLoopOptions lo = co;
        lo.seed = co.seed + 500u;
        const LoopTuning t = tune_in_loop(*model, j.truth, tuning, lo, nullptr, o.loop_tuning);
        say(fmt::format("{}: {} tuned in the loop: {} parameters, {} evaluations of {} trial(s), training tracking {:.2f} -> {:.2f} mrad",
                        j.name, name, t.parameters, t.evaluations, tuning.size(), 1e3 * t.rmse_before, 1e3 * t.rmse_after));
        model = t.model;
      }
      jr.runs.push_back(run_closed_loop(j.truth, desired, model.get(), co, true));
    }
    MaxwellSlipOracle oracle(j.truth);
    jr.runs.push_back(run_closed_loop(j.truth, desired, &oracle, co, true));
    all.push_back(std::move(jr));
  }
  if (o.json) {
    nlohmann::json out;
    for (const auto& jr : all) {
      nlohmann::json j;
      j["joint"] = jr.joint;
      for (const auto& r : jr.runs)
        j["runs"].push_back({{"compensation", r.compensation}, {"rmse", r.rmse}, {"segment_average", r.segment_average},
                             {"reversal_rmse", r.reversal_rmse}, {"reversals", r.reversals},
                             {"feedforward_rmse", jnum(r.feedforward_rmse)},
                             {"feedforward_rmse_slow", jnum(r.feedforward_rmse_slow)}});
      out["joints"].push_back(j);
    }
    fmt::print("{}\n", out.dump());
    return 0;
  }
  fmt::print("HESR closed loop (§V-G): velocity-command joint, {}adaptive PD on the torque error (eq. 19-20),\n"
             "10 s untrained Fourier trajectory; tracking error q_d - q [rad]\n",
             o.literal_eq19 ? "" : "tau_d fed forward through the inner loop's inverse + ");
  fmt::print("\nTable X: tracking RMSE [rad]\n{:<14}", "Compensation");
  for (const auto& jr : all) fmt::print("{:>11}", jr.joint);
  fmt::print("\n");
  for (std::size_t c = 0; c < comps.size(); ++c) {
    fmt::print("{:<14}", comps[c]);
    for (const auto& jr : all) fmt::print("{:>11.5f}", jr.runs[c].rmse);
    fmt::print("\n");
  }
  fmt::print("\nTable XI: segment-wise (1 s) and reversal-event (+-0.1 s) RMSE [rad]\n{:<14}{:>11}", "Compensation",
             "Seg. avg.");
  for (const auto& jr : all) fmt::print("{:>11}", "Rev. " + jr.joint);
  fmt::print("\n");
  for (std::size_t c = 0; c < comps.size(); ++c) {
    double seg = 0.0;
    for (const auto& jr : all) seg += jr.runs[c].segment_average / static_cast<double>(all.size());
    fmt::print("{:<14}{:>11.5f}", comps[c], seg);
    for (const auto& jr : all) fmt::print("{:>11.5f}", jr.runs[c].reversal_rmse);
    fmt::print("\n");
  }
  fmt::print("\nFeed-forward model error along the desired trajectory, RMSE of f_hat(qd_d) - tau_f,true(qd_d) [N·m]:"
             " all / |qd_d| < 0.1 rad/s\n{:<14}", "Compensation");
  for (const auto& jr : all) fmt::print("{:>16}", jr.joint);
  fmt::print("\n");
  for (std::size_t c = 0; c < comps.size(); ++c) {
    if (!std::isfinite(all.empty() ? 0.0 : all[0].runs[c].feedforward_rmse)) continue;
    fmt::print("{:<14}", comps[c]);
    for (const auto& jr : all)
      fmt::print("{:>16}", fmt::format("{:.4f} / {:.4f}", jr.runs[c].feedforward_rmse, jr.runs[c].feedforward_rmse_slow));
    fmt::print("\n");
  }
  fmt::print("(None: qd_cmd = qd_d; Baseline: tau_d = I qdd_d, the rigid body only; True friction: the simulator's "
             "Maxwell-slip truth as the model, an oracle reference; gains x{})\n", o.pd_scale);
  fmt::print("\nParFam-H as fitted on the training record\n");
  for (const auto& jr : all) fmt::print("{} {}\n", jr.joint, jr.parfam_equation);
  return 0;
}

int run(const StudyOptions& o) {
  if (o.closed_loop) return run_closed_loop_study(o);
  // the twin's friction block is in N·m: equations fitted to currents times the default gain 1
  // would be stored in A, ten times off on a UR3e joint, without a word
  if (!o.save_twin.empty() && o.torque == "current" && !o.gain_given && !o.recordings.empty())
    throw InvalidArgument(fmt::format("--save-twin {}: the study's torque is actual_current x --gain, and no --gain was given (the "
                                      "default 1 leaves it in A); give the joint's N·m/A (the twin's gains) or --torque moment",
                                      o.save_twin));
  if (o.simulated == !o.recordings.empty())
    throw InvalidArgument("give either recordings (TRAIN [VALIDATION [CHIRP]]) or --simulated, not both and not neither");
  if (o.simulated && !o.column_maps.empty()) throw InvalidArgument("--column-map applies to recordings, not to --simulated");
  if (o.torque != "current" && o.torque != "moment")
    throw InvalidArgument(fmt::format("--torque is '{}', expected 'current' or 'moment'", o.torque));
  if (!(o.split > 0.0 && o.split < 1.0)) throw InvalidArgument(fmt::format("--split is {}, must be in (0, 1)", o.split));
  if (o.decimate < 1) throw InvalidArgument(fmt::format("--decimate is {}, must be >= 1", o.decimate));
  // (before the protocol's minutes, and never over a recording or a column map)
  if (!o.predictions.empty()) {
    std::vector<std::string> inputs = o.recordings;
    inputs.insert(inputs.end(), o.column_maps.begin(), o.column_maps.end());
    inputs.push_back(o.save_twin);
    require_output(o.predictions, inputs);
  }
  std::vector<ProtocolRecords> joints;
  int recorded_dof = 0;
  if (o.simulated) {
    for (const SimulatedJoint& j : simulated_study_joints()) {
      if (!o.joints.empty() && std::find(o.joints.begin(), o.joints.end(), j.name[1] - '0') == o.joints.end()) continue;
      joints.push_back(simulated_protocol_records(j, o.seed, training_of(o)));
    }
  } else {
    joints = recorded_joints(o, recorded_dof);
  }
  ProtocolOptions po;
  po.trials = o.trials;
  po.seed = o.seed;
  po.rigid.reversal_threshold = o.screening;
  apply_parfam_options(po.study.parfam, o);
  const auto t0 = std::chrono::steady_clock::now();
  if (!o.quiet)
    po.progress = [t0](std::string_view msg) {
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      fmt::print(stderr, "[{:6.1f} s] {}\n", s, msg);
    };
  std::optional<ident::TwinModel> twin;
  if (!o.save_twin.empty()) {
    twin = cli::load_twin(o.save_twin);  // fail early on a bad twin file, or one that cannot be written
    require_writable(o.save_twin);       // (it was found after the study's minutes, exit 1)
    // another arm's friction in the twin: the study's own simulated joints, or a recording with
    // another joint count (a Kinova's J5 was stored in a UR3e twin, exit 0; audit of session 56)
    if (o.simulated)
      throw InvalidArgument(fmt::format("--save-twin {}: --simulated studies the study's own simulated joints, not the {}'s: their "
                                        "friction is no model of the robot; give recordings of the robot",
                                        o.save_twin, twin->robot_name()));
    if (recorded_dof != twin->n_dof())
      throw InvalidArgument(fmt::format("--save-twin {}: the recordings have {} joints, the twin's robot ({}) {}: recordings of another "
                                        "arm",
                                        o.save_twin, recorded_dof, twin->robot_name(), twin->n_dof()));
  }
  std::vector<ProtocolResult> res;
  for (const auto& j : joints) res.push_back(run_hesr_protocol(j, po));
  if (!o.predictions.empty()) {
    // built whole, then written checked: a full disk names the file (it was "cannot write to file")
    fmt::memory_buffer buf;
    auto w = std::back_inserter(buf);
    fmt::format_to(w, "joint,t,qd,tau,reversal");
    for (const auto& m : res.at(0).study.models) fmt::format_to(w, ",{}", m.name);
    fmt::format_to(w, "\n");
    for (const auto& r : res) {
      // the training record (label "<joint>-train", no predictions) for re-fits outside twinwatch
      const FrictionRecord& tr = r.study.train;
      for (std::size_t k = 0; k < tr.qd.size(); ++k) {
        fmt::format_to(w, "{}-train,{:.4f},{:.6g},{:.6g},0", r.study.joint, static_cast<double>(k) * tr.dt, tr.qd[k], tr.tau[k]);
        for (std::size_t m = 0; m < r.study.models.size(); ++m) fmt::format_to(w, ",");
        fmt::format_to(w, "\n");
      }
      const FrictionRecord& v = r.study.fourier;
      for (std::size_t k = 0; k < v.qd.size(); ++k) {
        fmt::format_to(w, "{},{:.4f},{:.6g},{:.6g},{}", r.study.joint, static_cast<double>(k) * v.dt, v.qd[k], v.tau[k],
                   static_cast<int>(r.study.reversal_mask[k]));
        for (const auto& m : r.study.models)
          fmt::format_to(w, ",{:.6g}", k < m.fourier_prediction.size() ? m.fourier_prediction[k] : 0.0);
        fmt::format_to(w, "\n");
      }
    }
    write_text_file(o.predictions, fmt::to_string(buf));
  }
  std::string refused;  // why --save-twin stores nothing (said after the tables, exit 1)
  if (twin) {
    // the friction block: ParFam-H of every studied joint, re-loadable into the compiled evaluator
    std::vector<JointFrictionEquation> eqs;
    for (const auto& r : res) {
      const int joint = std::stoi(r.study.joint.substr(1));
      if (joint > twin->n_dof())
        throw InvalidArgument(fmt::format("--save-twin {}: joint {} is beyond the twin's {} joints", o.save_twin, joint,
                                          twin->n_dof()));
      const auto* m = dynamic_cast<const ParFamModel*>(r.study.model("ParFam-H").model.get());
      if (!m) throw InvalidArgument(fmt::format("{}: ParFam-H was not fitted, nothing to store", r.study.joint));
      // an equation that predicts the validation record worse than zero friction would is not a
      // friction model of the joint: the Kinova run stored one at 29303313.7 rms, said only as
      // "stored 1 friction equation(s)" (review, session 47)
      const ModelStudy& ms = r.study.model("ParFam-H");
      double tau_rms = 0.0;
      for (const double x : r.study.fourier.tau) tau_rms += x * x;
      tau_rms = r.study.fourier.tau.empty() ? 0.0 : std::sqrt(tau_rms / static_cast<double>(r.study.fourier.tau.size()));
      if (!(ms.fourier_rmse <= tau_rms) && refused.empty())
        refused = (fmt::format("--save-twin {}: not written: {}'s ParFam-H errs {:.4g} {} rms on the validation record, more "
                                             "than the record's own {:.4g} (zero friction would predict it better); no equation of "
                                             "this study is stored",
                                             o.save_twin, r.study.joint, ms.fourier_rmse, torque_unit(o), tau_rms));
      // friction takes energy from the motion: an equation that, at the record's faster half of
      // speeds, pushes the joint along (the Kinova's J5 fitted -15.32 qd + ..., which a UR3e twin
      // took, audit of session 56) is no friction model, whatever its rms
      if (refused.empty())
        if (const auto p = power_above_median_speed(r.study.fourier.qd, ms.fourier_prediction); p && p->mean < 0.0)
          refused = fmt::format("--save-twin {}: not written: {}'s ParFam-H pushes the joint along its motion above the record's median "
                                "speed {:.3g} rad/s (its friction times the speed averages {:.3g} {}·rad/s, where friction takes "
                                "energy from the motion: > 0); no equation of this study is stored",
                                o.save_twin, r.study.joint, p->median_speed, p->mean, torque_unit(o));
      eqs.push_back(friction_equation_of(*m, joint));
    }
    if (refused.empty()) {
      twin->friction_json = friction_block_to_json(eqs);
      twin->save(o.save_twin);
      if (!o.quiet) fmt::print(stderr, "stored {} friction equation(s) in {}\n", eqs.size(), o.save_twin);
    }
  }
  if (o.json) {
    nlohmann::json j = to_json(res);
    j["torque_units"] = torque_unit(o);
    fmt::print("{}\n", j.dump());
  } else {
    if (torque_unit(o) == "A" && !o.quiet)
      fmt::print(stderr, "note: --torque current without --gain: the currents are studied as they are, and every torque below is in A "
                         "(give --gain, the drive's N·m/A, for N·m)\n");
    print_tables(res, o);
  }
  if (!refused.empty()) {
    std::fflush(stdout);  // (the tables first)
    throw std::runtime_error(refused);
  }
  return 0;
}

twinwatch::cli::VerbRegistrar reg{"friction-study", 34, [](CLI::App& app) {
  auto o = std::make_shared<StudyOptions>();
  auto* sub = app.add_subcommand(
      "friction-study",
      "HESR friction study: fit LuGre, Stribeck, RBFNN, RBFNN-H, ParFam-V and ParFam-H to one joint's residual torque "
      "and print HESR Tables III-IX and the chirp split");
  sub->footer(twinwatch::cli::with_exit_status(
      "Input: 1 to 3 recordings TRAIN [VALIDATION [CHIRP]] (RTDE column names, or any CSV through --column-map) with\n"
      "actual_q_*, actual_qd_* and the torque source: actual_current_* times --gain (N·m/A; 1 when the column is\n"
      "already a current-based torque in N·m) or target_moment_* (--torque moment). With one recording its first\n"
      "--split fraction trains and the rest validates; without a chirp the chirp rows read n/a (a chirp's frequency\n"
      "is estimated from its velocity reversals). Each joint is decoupled from its rigid body by least squares on\n"
      "[qdd, sin q, cos q, 1] (single-joint gravity; exact when the other joints stand still) with |qd| < --screening\n"
      "left out of that fit only, and [sign(qd), qd] as nuisance columns. --simulated runs the built-in Maxwell-slip\n"
      "joints J1-J3 instead (20 s sweep, Fourier and chirp records at 200 Hz)."));
  sub->add_option("RECORDINGS", o->recordings, "TRAIN [VALIDATION [CHIRP]] recordings")->check(CLI::ExistingFile);
  sub->add_flag("--simulated", o->simulated, "Run on the built-in simulated joints J1-J3");
  sub->add_flag("--closed-loop", o->closed_loop,
                "HESR §V-G instead: velocity-command simulated joints with the eq. 19-20 feed-forward of each model "
                "(Tables X-XI)");
  sub->add_option("--pd-scale", o->pd_scale,
                  "--closed-loop: multiply the eq. 20 PD gains (K_p, K_d min and max) by this factor, >= 0 "
                  "(0: the model feed-forward alone)")
      ->capture_default_str();
  sub->add_option("--truth-lag-scale", o->truth_lag_scale,
                  "--closed-loop diagnosis: multiply the simulated truth's frictional-lag time (training records and "
                  "plant alike) by this factor, >= 0 (0: no lag); not a model or loop setting")
      ->capture_default_str();
  sub->add_flag("--literal-eq19", o->literal_eq19,
                "--closed-loop: the model enters only through e_tau of eq. 19 (no inner-loop inverse feed-forward of "
                "tau_d); with a time-aligned e_tau even the true friction then cannot beat no feed-forward");
  sub->add_option("--joint", o->joints, "Joint(s) to study, 1-based (default: every joint that moves)");
  sub->add_option("--column-map", o->column_maps,
                  "CSV map 'file_column,rtde_name[,scale]' for foreign logs (docs/recordings.md), or the name of one twinwatch ships. "
                  "MAP: every recording without one of its own; REC=MAP: that recording alone (repeat for each)")->type_name("[REC=]MAP");
  sub->add_option("--torque", o->torque, "Torque source: current (x --gain) or moment")->capture_default_str();
  CLI::Option* gain = sub->add_option("--gain", o->gain, "Current-to-torque gain [N·m/A]")->capture_default_str()->check(twinwatch::cli::positive_number());
  sub->add_option("--split", o->split, "Training share of a single recording")->capture_default_str();
  sub->add_option("--decimate", o->decimate, "Use every k-th sample (e.g. 5: 1 kHz -> 200 Hz)")->capture_default_str()->check(twinwatch::cli::whole_number(1, 1000000));
  sub->add_option("--screening", o->screening, "Reversal screening of the rigid-body fit [rad/s]")->capture_default_str()->check(twinwatch::cli::nonnegative_number());
  sub->add_option("--trials", o->trials, "Monte Carlo trials per uncertainty level (Table V)")->capture_default_str()->check(twinwatch::cli::whole_number(1, 100000));
  sub->add_option("--hops", o->hops, "ParFam basin-hopping steps per start (default: the library's)");
  sub->add_option("--input-guard", o->input_guard,
                  "ParFam input guard: inputs clamped to the training range widened by this fraction (< 0: off)")
      ->capture_default_str();
  sub->add_option("--reversal-weight", o->reversal_weight,
                  "ParFam: samples within +-0.1 s of a training reversal count this many times (1: plain mse)")
      ->capture_default_str()
      ->check(twinwatch::cli::whole_number(1, 1000));
  sub->add_flag("--rich-training", o->rich_training,
                "--simulated, --closed-loop: train on four harmonics of 0.25 Hz (0.25-1.0 Hz) instead of HESR's 0.25 Hz sweep");
  sub->add_flag("--crawl-training", o->crawl_training,
                "--simulated, --closed-loop diagnosis (not HESR's protocol): train on 12 s of the sweep and 8 s of slow "
                "constant-velocity crawls (+-0.02 ... 0.1 rad/s, 1 s each), which show the steady Stribeck curve the sweep "
                "crosses in tens of ms");
  sub->add_option("--loop-tuning", o->loop_tuning,
                  "--closed-loop: tune LuGre's and ParFam-H's parameters on the loop's tracking error of 10 s training "
                  "trajectories (not the scored one; --tuning-trajectories), at most N objective evaluations each (BOBYQA from "
                  "the fitted values; RBFNN-H is not tuned); after --loop-training when both are given (a diagnosis, not HESR's "
                  "protocol)")
      ->check(CLI::Range(0, 100000));
  sub->add_option("--tuning-trajectories", o->tuning_trajectories,
                  "--loop-tuning: 10 s training trajectories per trial (each another seed than the scored one); the tuning "
                  "minimises the RMS of their tracking RMSEs")
      ->check(CLI::Range(1, 20))
      ->capture_default_str();
  sub->add_option("--loop-training", o->loop_training,
                  "--closed-loop: identification in the loop, N rounds: each model's own feed-forward runs a 10 s training "
                  "trajectory of the loop (another seed than the scored one), starting at rest in the state the training motion "
                  "left; what the joint's sensors recorded (encoder, noisy motor torque) is appended to the training record "
                  "and the model refitted; the same for every model (a diagnosis, not HESR's protocol)")
      ->check(CLI::Range(0, 10));
  sub->add_option("--memory", o->memory,
                  "Clock of the hysteresis state h: 'time' (HESR eq. 10 as printed, h relaxes in time with 1/alpha) "
                  "or 'displacement' (eq. 10 in the travelled-distance clock, hd = alpha |qd| (tanh(beta qd) - h): "
                  "rate-independent pre-sliding memory, Dahl-like)")
      ->capture_default_str();
  sub->add_option("--predictions", o->predictions,
                  "Write CSV joint,t,qd,tau,reversal,<model>... of the validation record (residual torque) and every "
                  "model's prediction, for plots; before each joint's validation rows, its training record as joint '<J>-train' "
                  "without predictions");
  sub->add_option("--functions", o->functions,
                  "ParFam operator set, a comma list of sin, cos, exp, tanh, stribeck (sgn(u) (1 - exp(-u^2))), one unit "
                  "each (default: the study's; HESR's library is sin,cos,exp,tanh)");
  sub->add_option("--odd", o->odd,
                  "ParFam odd symmetry f(-x) = -f(x) (no constant, no unit offsets), 1 or 0 (default: the study's)");
  sub->add_option("--prior-remove-viscous", o->remove_viscous,
                  "Stage 1: remove the viscous slope of tau_f before the loop descriptors, 1 or 0 (default: the study's, 1)");
  auto* alpha = sub->add_option("--alpha", o->fixed_alpha, "Fix the hysteresis alpha (with --beta; skips Stage 1, Stage 3 still refines)")
                    ->check(twinwatch::cli::positive_number());
  auto* beta = sub->add_option("--beta", o->fixed_beta, "Fix the hysteresis beta (with --alpha)")->check(twinwatch::cli::positive_number());
  alpha->needs(beta);
  beta->needs(alpha);
  sub->add_option("--l1", o->l1, "ParFam L1 weight gamma of eq. 15 on unit-RMS data (default: the study's, 1e-6)");
  sub->add_option("--starts", o->starts, "ParFam basin-hopping random starts (default: the library's)");
  sub->add_option("--seed", o->seed, "Seed of the simulated records and the Monte Carlo draws")->capture_default_str();
  sub->add_option("--save-twin", o->save_twin,
                  "Store each joint's ParFam-H equation in this existing twin file (friction_models block)")
      ->check(CLI::ExistingFile);
  sub->add_flag("--json", o->json, "Print the tables as one JSON object {\"joints\": [...]}");
  sub->add_flag("-q,--quiet", o->quiet, "No progress messages on stderr");
  // what the closed loop does not use: refused with it, not ignored
  const std::vector<const CLI::Option*> offline = {sub->get_option("--torque"),     gain,
                                                              sub->get_option("--split"),      sub->get_option("--decimate"),
                                                              sub->get_option("--screening"),  sub->get_option("--trials"),
                                                              sub->get_option("--predictions"), sub->get_option("--save-twin")};
  // what only recordings use (the simulated joints' torque is their own, in N·m)
  const std::vector<const CLI::Option*> recorded_only = {sub->get_option("--torque"), gain, sub->get_option("--split"),
                                                         sub->get_option("--column-map")};
  // the closed loop's own options mean nothing to the offline study: refused there, not ignored
  const std::vector<const CLI::Option*> loop_only = {sub->get_option("--pd-scale"),        sub->get_option("--truth-lag-scale"),
                                                     sub->get_option("--literal-eq19"),    sub->get_option("--loop-training"),
                                                     sub->get_option("--loop-tuning"),     sub->get_option("--tuning-trajectories")};
  sub->callback([o, gain, offline, recorded_only, loop_only, sub] {
    o->gain_given = gain->count() > 0;
    for (const CLI::Option* opt : offline)
      twinwatch::cli::refuse_unless({opt}, !o->closed_loop, "to the offline study (recordings or --simulated), not --closed-loop");
    for (const CLI::Option* opt : recorded_only)
      twinwatch::cli::refuse_unless({opt}, !o->recordings.empty(), "to recordings (the simulated joints' torque is in N·m already)");
    for (const CLI::Option* opt : loop_only) twinwatch::cli::refuse_unless({opt}, o->closed_loop, "with --closed-loop");
    // the simulated joints' training record: a recording is its own
    for (const char* name : {"--rich-training", "--crawl-training"})
      twinwatch::cli::refuse_unless({sub->get_option(name)}, o->recordings.empty(), "to the simulated joints (--simulated, --closed-loop)");
    if (o->rich_training && o->crawl_training) throw twinwatch::InvalidArgument("--rich-training and --crawl-training exclude each other");
    // a gain scales currents: with --torque moment it did nothing
    twinwatch::cli::refuse_unless({gain}, o->torque == "current", "with --torque current (it scales currents to N·m)");
    for (size_t a = 0; a < o->joints.size(); ++a)
      for (size_t b = a + 1; b < o->joints.size(); ++b)
        if (o->joints[a] == o->joints[b])
          throw twinwatch::InvalidArgument(fmt::format("--joint {} is given twice: each joint is studied once", o->joints[a]));
    // the library's defaults are what an option not given means; a value given must be one
    if (sub->get_option("--hops")->count() > 0 && o->hops < 0)
      throw twinwatch::InvalidArgument(fmt::format("--hops is {}, expected a count >= 0", o->hops));
    if (sub->get_option("--starts")->count() > 0 && o->starts < 1)
      throw twinwatch::InvalidArgument(fmt::format("--starts is {}, expected a count >= 1", o->starts));
    if (sub->get_option("--l1")->count() > 0 && !(o->l1 >= 0.0 && std::isfinite(o->l1)))
      throw twinwatch::InvalidArgument(fmt::format("--l1 is {}, expected a finite weight >= 0", o->l1));
    if (sub->get_option("--functions")->count() > 0 && o->functions.empty())
      throw twinwatch::InvalidArgument("--functions is empty, expected a comma list of sin, cos, exp, tanh, stribeck");
    // the simulated joints are J1-J3 (a recording's are its own: recorded_joints checks them)
    if (o->recordings.empty())
      for (int j : o->joints)
        if (j < 1 || j > 3) throw twinwatch::InvalidArgument(fmt::format("--joint {}: the simulated joints are 1, 2 and 3", j));
    twinwatch::cli::set_exit_code(run(*o));
  });
}};

}  // namespace
