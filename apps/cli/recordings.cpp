#include "recordings.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "twinwatch/core/data_dir.hpp"
#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"
#include "twinwatch/core/log.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/monitor/monitor.hpp"
#include "twinwatch/monitor/trend.hpp"

namespace twinwatch::cli {

ident::TwinModel load_twin(const std::string& path) {
  ident::TwinModel twin = ident::TwinModel::load(path);
  if (!twin.monitor_json.empty()) monitor::MonitorConfig::from_twin(twin);
  return twin;
}

model::RigidBodyInertia payload_for(const ident::TwinModel& twin, const std::string& twin_path, double mass,
                                    const std::vector<double>& com) {
  // not given: the payload the twin file holds ("payload", 0 kg as identify writes it; a user may
  // set it), checked as --payload-mass would be
  if (std::isnan(mass)) {
    if (com.size() == 3) throw InvalidArgument("--payload-com is given without --payload-mass (a centre of mass needs a mass)");
    const model::RigidBodyInertia& p = twin.payload();
    if (p.mass > twin.robot().payload_limit())
      throw InvalidArgument(fmt::format("{}: field 'payload.mass': expected at most {:g} kg ({}), got {:g} kg", twin_path,
                                        twin.robot().payload_limit(), twin.robot().payload_limit_text(), p.mass));
    if (p.mass > 0.0 && p.com.norm() > model::kPayloadComMax)
      throw InvalidArgument(fmt::format("{}: field 'payload.com': expected a centre of mass within {:g} m of the flange, got one {:.3g} m away "
                                        "(in mm? give metres)",
                                        twin_path, model::kPayloadComMax, p.com.norm()));
    if (p.mass > 0.0 && !twin.gains_known())
      throw InvalidArgument(fmt::format("{}: field 'payload.mass' is {:g} kg, but the twin was identified without a known payload that fixes "
                                        "its gains: a payload in kg cannot be added to it (set it to 0)",
                                        twin_path, p.mass));
    return p;
  }
  if (!(mass >= 0.0 && std::isfinite(mass))) throw InvalidArgument(fmt::format("--payload-mass must be a finite mass >= 0 kg, got {}", mass));
  // beyond what the arm may carry: a typo (5 for 0.5 kg), which every residual would then carry
  if (mass > twin.robot().payload_limit())
    throw InvalidArgument(fmt::format("--payload-mass {:g}: expected at most {:g} kg ({})", mass, twin.robot().payload_limit(),
                                      twin.robot().payload_limit_text()));
  model::RigidBodyInertia p;
  p.mass = mass;
  if (com.size() == 3) {
    if (!(mass > 0.0)) throw InvalidArgument("--payload-com is given without --payload-mass (a centre of mass needs a mass)");
    for (double c : com)
      if (!std::isfinite(c)) throw InvalidArgument(fmt::format("--payload-com {} {} {}: expected three finite numbers [m]", com[0], com[1], com[2]));
    p.com = Eigen::Vector3d(com[0], com[1], com[2]);
    // metres from the flange is most likely millimetres, as identify's --known-payload and the monitor say
    if (p.com.norm() > model::kPayloadComMax)
      throw InvalidArgument(fmt::format("--payload-com {:g} {:g} {:g}: expected a centre of mass within {:g} m of the flange, got one "
                                        "{:.3g} m away (in mm? give metres)",
                                        com[0], com[1], com[2], model::kPayloadComMax, p.com.norm()));
  }
  if (mass > 0.0 && !twin.gains_known())
    throw InvalidArgument(fmt::format(
        "{} was identified without a known payload that fixes its gains (none, or the same in every recording): its "
        "current-to-torque gains are relative, so a payload in kg cannot be "
        "added to it (--payload-mass {:g}). Run without --payload-mass and --payload-com, on recordings made with the payload "
        "the twin was identified with, or identify the twin again with a known payload ('twinwatch identify ... "
        "--known-payload REC.csv=MASS,CX,CY,CZ')",
        twin_path, mass));
  return p;
}

namespace {
// /proc/meminfo's `key` [bytes]; NaN where it cannot be read
double meminfo(const std::string& key) {
  std::ifstream f("/proc/meminfo");
  std::string name, unit;
  double kb = 0.0;
  while (f >> name >> kb) {
    std::getline(f, unit);
    if (name == key + ":") return kb * 1024.0;
  }
  return std::numeric_limits<double>::quiet_NaN();
}
}  // namespace

void check_held_size(const std::vector<std::string>& files, const std::string& verb) {
  double bytes = 0.0, samples = 0.0;
  for (const std::string& path : files) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    std::ifstream f(path);
    std::string line;
    if (ec || !f || !std::getline(f, line)) continue;  // (not a file to size: the reading says what it is)
    const double header = static_cast<double>(line.size() + 1);
    double rows = 0.0, row_bytes = 0.0;
    while (rows < 100 && std::getline(f, line)) {
      rows += 1.0;
      row_bytes += static_cast<double>(line.size() + 1);
    }
    bytes += static_cast<double>(size);
    if (rows > 0.0) samples += (static_cast<double>(size) - header) / (row_bytes / rows);
  }
  const double need = samples * kHeldBytesPerSample, total = meminfo("MemTotal"), free = meminfo("MemAvailable");
  const auto gb = [](double b) { return fmt::format("{:.1f} GB", b / 1e9); };
  const std::string what = fmt::format("{} holds its recordings whole: {} file(s), {} of CSV, about {:.2g} samples, need about {} of memory",
                                       verb, files.size(), gb(bytes), samples, gb(need));
  const std::string advice = "identify from shorter runs (an excitation run of minutes: 'twinwatch excite'), or cut them ('head -n 300001 "
                             "rec.csv > part.csv' keeps 10 minutes at 500 Hz); monitor, report, validate and thresholds read long "
                             "recordings without holding them";
  if (std::isfinite(total) && need > total)
    throw InvalidArgument(fmt::format("{}, more than this machine's {}: it would be stopped part-way. {}", what, gb(total), advice));
  if (std::isfinite(free) && need > free)
    log::warn(fmt::format("{}, more than the {} free now: the system may stop it part-way. {}", what, gb(free), advice));
}

void require_distinct(const std::vector<std::string>& files, const std::string& what) {
  for (size_t a = 0; a < files.size(); ++a)
    for (size_t b = a + 1; b < files.size(); ++b)
      if (same_file(files[a], files[b]))
        throw InvalidArgument(fmt::format("{}: '{}' and '{}' are the same file; a recording given twice would count twice", what,
                                          files[a], files[b]));
}

std::vector<device::Recording> driven_only(std::vector<device::Recording> recs, bool quiet) {
  std::vector<device::Recording> out;
  for (device::Recording& r : recs) {
    // (a recording driven throughout, the usual case, is moved through: no copy of its samples)
    if (std::all_of(r.samples.begin(), r.samples.end(), [](const RobotSample& x) { return x.driven(); })) {
      out.push_back(std::move(r));
      continue;
    }
    std::string note;
    std::vector<device::Recording> segs = device::driven_segments(r, kMinDrivenStretch, &note);
    if (segs.empty())
      throw InvalidArgument(fmt::format("{}: the controller does not drive the arm for {:g} s or more at a time in this recording "
                                        "(robot_mode RUNNING and safety_mode NORMAL or REDUCED): nothing in it shows the driven arm a "
                                        "twin models",
                                        r.path, kMinDrivenStretch));
    if (!note.empty() && !quiet) fmt::print(stderr, "note: {}\n", note);
    for (auto& g : segs) out.push_back(std::move(g));
  }
  return out;
}

std::vector<std::unique_ptr<device::FileSamples>> scan_training_runs(const std::string& path, const device::ColumnMap* map,
                                                                     const model::RobotModel& robot, const std::string& verb,
                                                                     const std::string& user, const std::string& what,
                                                                     std::size_t* implausible, bool quiet) {
  TrainingCheck check(path, robot, what, map && map->joint_torque_as_current);
  device::DrivenStretches driven(kMinDrivenStretch);
  // implausible temperatures: of the whole recording, and of the driven stretches kept so far
  std::size_t all = 0, kept = 0, open = 0;
  const device::RecordingScan scan = scan_recording(path, map, robot, verb, user, [&](const RobotSample& s) {
    check.add(s);
    const std::size_t bad = monitor::implausible_temperatures(s);
    all += bad;
    const std::size_t before = driven.stretches().size();
    driven.see(s);
    if (s.driven()) {
      open += bad;
      return;
    }
    if (driven.stretches().size() > before) kept += open;  // (the stretch just closed is used)
    open = 0;
  });
  {
    const std::size_t before = driven.stretches().size();
    driven.finish();
    if (driven.stretches().size() > before) kept += open;
  }
  check.finish();  // (after the units check: currents in mA are said as such, not as a corrupted word)
  if (driven.used().empty())
    throw InvalidArgument(fmt::format("{}: the controller does not drive the arm for {:g} s or more at a time in this recording "
                                      "(robot_mode RUNNING and safety_mode NORMAL or REDUCED): nothing in it shows the driven arm a "
                                      "twin models",
                                      path, kMinDrivenStretch));
  if (const std::string note = driven.note(path, scan.timing.median_period); !note.empty() && !quiet) fmt::print(stderr, "note: {}\n", note);
  if (implausible) *implausible = driven.whole() ? all : kept;
  return device::FileSamples::of(path, map, scan, driven);
}

void require_driven(const device::Recording& rec, const std::string& user) {
  for (size_t k = 0; k < rec.samples.size(); ++k) {
    const RobotSample& s = rec.samples[k];
    if (s.driven()) continue;
    throw InvalidArgument(fmt::format("{}: at t = {:.3f} s (sample {}) the controller does not drive the arm (robot_mode {}, safety_mode "
                                      "{}; expected RUNNING 7 and NORMAL 1 or REDUCED 2): {} fits whole recordings, so cut the stop out "
                                      "(identify, thresholds and validate leave such stretches out themselves)",
                                      rec.path, s.timestamp - rec.samples.front().timestamp, k + 1, s.robot_mode, s.safety_mode, user));
  }
}

UnitsCheck::UnitsCheck(const std::string& path, int n_dof, std::uint32_t present, const model::RobotModel& robot, bool torque)
    : path_(path), robot_(robot), present_(present), torque_(torque), n_(std::min(n_dof, robot.n_dof())), agree_(path, n_dof) {
  // (report read a 7-joint log into a 6-joint twin and said "q has size 7, expected 6 (model.n_dof)")
  if (n_dof != robot.n_dof())
    throw InvalidArgument(fmt::format("{} has {} joints, the robot ({}) {}{}", path, n_dof, robot.name(), robot.n_dof(),
                                      // (the joints a description has, and where the robot is chosen)
                                      fmt::format(" ({}): give the arm's description with --robot (a built-in name, e.g. panda, or a "
                                                  ".json/.urdf file), or, for a twin's verbs, a twin of that arm",
                                                  [&] {
                                                    std::string names;
                                                    for (int j = 0; j < robot.n_dof(); ++j)
                                                      names += (j ? ", " : "") + robot.joint(j).name;
                                                    return names;
                                                  }())));
  currents_.resize(static_cast<size_t>(n_dof));
}

void UnitsCheck::check_period(double median_period) const { check_sample_period(path_, median_period); }

void check_sample_period(const std::string& path_, double median_period) {
  // (a sample index scaled by 1e-6 for 1e-3 was written into a twin, exit 0; review, session 47)
  if (median_period > 0.0 && median_period < kUnitsMinPeriod)
    throw InvalidArgument(fmt::format("{}: the samples are {:g} s apart (median), expected a controller's 0.001-0.1 s: is the time "
                                      "column in microseconds, or scaled wrongly? Scale it to seconds with a column map "
                                      "('TIME_COLUMN,timestamp,0.000001' for microseconds, docs/recordings.md)",
                                      path_, median_period));
  if (median_period > kUnitsMaxPeriod)
    throw InvalidArgument(fmt::format("{}: the samples are {:g} s apart (median), expected a controller's 0.001-0.1 s: is the time "
                                      "column in milliseconds? Scale it to seconds with a column map ('TIME_COLUMN,timestamp,0.001', "
                                      "docs/recordings.md)",
                                      path_, median_period));
}

void UnitsCheck::add(const RobotSample& s) {
  if (samples_ == 0) t0_ = s.timestamp;
  ++samples_;
  for (int j = 0; j < n_; ++j) {
    const model::JointLimits& l = robot_.joint(j).limits;
    const double t = s.timestamp - t0_;
    if (s.q[j] < l.q_min - kUnitsPositionMargin || s.q[j] > l.q_max + kUnitsPositionMargin) {
      // degrees only where degrees would fit the range (a Kinova's 0.43 rad against a Panda's range
      // read "are the positions in degrees?", which scaling would make worse; review, session 47)
      const double as_radians = s.q[j] * kDegree;
      const bool degrees = as_radians >= l.q_min - kUnitsPositionMargin && as_radians <= l.q_max + kUnitsPositionMargin;
      throw InvalidArgument(fmt::format("{}: J{} is at {:.4g} rad at t = {:.3f} s (sample {}), beyond the {}'s range {:.3g} to {:.3g} "
                                        "rad: {}",
                                        path_, j + 1, s.q[j], t, samples_, robot_.name(), l.q_min, l.q_max,
                                        // (a value a joint can have in radians may be another arm's: a Kinova log read
                                        // with the Panda's model was asked only about degrees; audit of session 56)
                                        degrees ? fmt::format("are the positions in degrees? Scale them with a column map "
                                                              "('COLUMN,actual_q_{},0.017453292519943295', docs/recordings.md){}",
                                                              j,
                                                              std::abs(s.q[j]) <= 2.0 * M_PI + kUnitsPositionMargin
                                                                  ? fmt::format("; or, in radians, is it a recording of another arm than the {}?",
                                                                                robot_.name())
                                                                  : std::string())
                                                : fmt::format("is it a recording of another arm than the {}, or are the joints in another "
                                                              "order or with another zero? (in degrees it would be {:.4g} rad, beyond the "
                                                              "range too; give the arm's description with --robot, or, for a twin's verbs, a twin of that arm)",
                                                              robot_.name(), as_radians)));
    }
    if (std::abs(s.qd[j]) > kUnitsSpeedFactor * l.qd_max)
      throw InvalidArgument(fmt::format("{}: J{} moves at {:.4g} rad/s at t = {:.3f} s (sample {}), more than {:g} times the {}'s limit "
                                        "{:.3g} rad/s: are the speeds in degrees/s? Scale them with a column map "
                                        "('COLUMN,actual_qd_{},0.017453292519943295', docs/recordings.md)",
                                        path_, j + 1, s.qd[j], t, samples_, kUnitsSpeedFactor, robot_.name(), l.qd_max, j));
  }
  // (single precision: the percentile below only tells A from mA, and a day of 500 Hz samples then
  // holds 24 bytes each)
  if ((present_ & kFieldActualCurrent) && s.has(kFieldActualCurrent))
    for (size_t j = 0; j < currents_.size(); ++j)
      if (std::isfinite(s.current[static_cast<Eigen::Index>(j)]))
        currents_[j].push_back(static_cast<float>(std::abs(s.current[static_cast<Eigen::Index>(j)])));
  if (present_ & kFieldActualQd) agree_.add(s);
}

void UnitsCheck::finish() {
  agree_.finish();
  // currents in mA: judged on each joint's 99th percentile of |i|, which a glitch of a few samples
  // (a sensor fault the monitor is there to report) does not move
  for (size_t j = 0; j < currents_.size(); ++j) {
    std::vector<float>& a = currents_[j];
    if (a.empty()) continue;
    const auto at = a.begin() + static_cast<std::ptrdiff_t>(0.99 * static_cast<double>(a.size() - 1));
    std::nth_element(a.begin(), at, a.end());
    if (torque_) {
      // joint torque sensors: twice the joint's torque limit (1000 N·m where the description has none)
      const bool limited = static_cast<int>(j) < robot_.n_dof() && std::isfinite(robot_.joint(static_cast<int>(j)).limits.torque_max);
      const double lim = limited ? 2.0 * robot_.joint(static_cast<int>(j)).limits.torque_max : kTrainingCurrentMax;
      if (*at > lim)
        throw InvalidArgument(fmt::format("{}: J{}'s joint torque is above {:.4g} N·m in 1 % of the samples, more than {}: are the "
                                          "torques in N·mm? Scale them with a column map ('COLUMN,actual_joint_torque_{},0.001', "
                                          "docs/recordings.md)",
                                          path_, j + 1, *at,
                                          limited ? fmt::format("twice the {}'s limit ({:g} N·m)", robot_.name(), lim / 2.0)
                                                  : fmt::format("the {:g} N·m twinwatch takes where the description gives no limit", lim),
                                          j));
      continue;
    }
    if (*at > kUnitsCurrentMax)
      throw InvalidArgument(fmt::format("{}: J{}'s current is above {:.4g} A in 1 % of the samples, more than the {:g} A twinwatch takes "
                                        "for a joint current: are the currents in mA? Scale them with a column map "
                                        "('COLUMN,actual_current_{},0.001', docs/recordings.md)",
                                        path_, j + 1, *at, kUnitsCurrentMax, j));
  }
  currents_.clear();
}

void warn_if_another_arm(const std::string& path, const model::RobotModel& robot, const ident::ArmVerdict& v, const std::string& user) {
  const double j2 = robot.n_dof() >= 2 ? v.own.rms[1] : v.own.rms[0];
  const bool live = path.rfind("rtde://", 0) == 0;  // (a stream's first seconds, not a file)
  if (v.other_arm())
    fmt::print(stderr,
               "WARNING: {} is not {} of a {} (the arm it is read for): the controller's own torque (target_moment) along its "
               "targets is reproduced by the {}'s model (relative rms {:.2f}) and not by the {}'s ({:.2f}; J2 off by {:.1f} N·m rms): {} "
               "reads it with a model of another arm{}\n",
               path, live ? "the stream" : "a recording", robot.name(), v.better, v.theirs.relative_rms, robot.name(), v.own.relative_rms,
               j2, user, live ? fmt::format(": its residuals are that model's error, not faults (identify a twin of this {})", v.better)
                              : fmt::format(" (this arm's: --robot {})", v.better));
  else if (v.poor())
    fmt::print(stderr,
               "WARNING: {}: the {}'s model reproduces the controller's own torque (target_moment) only to {:.2f} relative rms (J2 off by "
               "{:.1f} N·m rms; its own arm's model does to 0.05-0.17): is it another arm, or does the arm carry a payload its program does "
               "not declare?\n",
               path, robot.name(), v.own.relative_rms, j2);
}

namespace {
// the checks of a recording's header, before its first row (check_headers, scan_recording)
device::RecordingReader open_checked(const std::string& path, const device::ColumnMap* map, const model::RobotModel& robot,
                                     const std::string& verb, const std::string& user) {
  device::require_rereadable(path, verb);
  device::RecordingReader reader(path, map);
  device::require_fields(reader, kFieldActualQd | kFieldActualCurrent, user);
  UnitsCheck(path, reader.n_dof(), reader.present(), robot, map && map->joint_torque_as_current);  // (its joint count)
  return reader;
}
}  // namespace

void check_headers(const std::vector<std::string>& files, const device::ColumnMap* map, const model::RobotModel& robot,
                   const std::string& verb, const std::string& user) {
  for (const std::string& f : files) open_checked(f, map, robot, verb, user);
}

device::RecordingScan scan_recording(const std::string& path, const device::ColumnMap* map, const model::RobotModel& robot,
                                     const std::string& verb, const std::string& user,
                                     const std::function<void(const RobotSample&)>& each) {
  device::RecordingReader reader = open_checked(path, map, robot, verb, user);
  UnitsCheck units(path, reader.n_dof(), reader.present(), robot, map && map->joint_torque_as_current);
  // is it the twin's arm? (its controller's torque against the arm's model and the other built-in
  // arms', every 25th sample: 20 a second at 500 Hz; ident::ArmCheck)
  std::optional<ident::ArmCheck> arm;
  if (reader.n_dof() == robot.n_dof()) arm.emplace(robot, 25);
  const device::RecordingScan scan = device::scan_rows(reader, [&](const RobotSample& s) {
    units.add(s);
    if (arm) arm->add(s);
    if (each) each(s);
  });
  units.check_period(scan.timing.median_period);
  units.finish();
  if (arm) warn_if_another_arm(path, robot, arm->verdict(), user);
  return scan;
}

StreamScan scan_stream(const std::vector<std::string>& files, const device::ColumnMap* map, const model::RobotModel& robot,
                       const std::string& verb, const std::string& user, const std::function<void(const std::string&)>& before_each) {
  StreamScan out;
  for (size_t i = 0; i < files.size(); ++i) {
    const std::string& f = files[i];
    double first = std::numeric_limits<double>::quiet_NaN(), last = first;
    if (before_each) before_each(f);
    out.scans.push_back(scan_recording(f, map, robot, verb, user, [&](const RobotSample& s) {
      if (std::isnan(first)) first = s.timestamp;
      last = s.timestamp;
    }));
    const device::RecordingScan& scan = out.scans.back();
    if (i > 0) {
      const std::string& before = files[i - 1];
      const device::RecordingScan& head = out.scans.front();
      if (scan.n_dof != head.n_dof || scan.present != head.present)
        throw InvalidArgument(fmt::format("{}: its header's columns are not those of {}{}: the files read as one stream must be "
                                          "parts of one recording, with the same columns",
                                          f, files.front(),
                                          scan.n_dof != head.n_dof ? fmt::format(" ({} joints against {})", scan.n_dof, head.n_dof)
                                                                   : std::string()));
      if (!(first > out.last_t.back()))
        throw InvalidArgument(fmt::format("{}: it starts at t = {:.3f} s, not after {} ends (t = {:.3f} s): the files are read as one "
                                          "stream in the order given; give them in the order they were recorded",
                                          f, first, before, out.last_t.back()));
      const double p0 = head.timing.median_period, p = scan.timing.median_period;
      if (p0 > 0.0 && p > 0.0 && std::abs(p / p0 - 1.0) > 0.05)
        log::warn(fmt::format("{} runs at {:.0f} Hz, {} at {:.0f} Hz: the monitor filters them all at the first one's rate", f, 1.0 / p,
                              files.front(), 1.0 / p0));
    }
    out.first_t.push_back(first);
    out.last_t.push_back(last);
    out.gap_factor = std::max(out.gap_factor, scan.timing.gap_factor);
  }
  return out;
}

size_t StreamScan::file_at(double t) const {
  size_t i = 0;
  while (i + 1 < first_t.size() && first_t[i + 1] <= t) ++i;
  return i;
}

long StreamScan::replay(const std::vector<std::string>& files, const device::ColumnMap* map, const std::function<void(RobotSample&)>& each,
                        Cut* cut) const {
  double previous = std::numeric_limits<double>::quiet_NaN();
  long total = 0;
  if (cut) *cut = Cut{};
  for (size_t i = 0; i < files.size() && i < scans.size(); ++i) {
    // the rows the first pass read and checked (a file still being written has more by now)
    device::RecordingReader again(files[i], map);
    bool first_row = true;
    const long k = device::replay_rows(again, scans[i], [&](RobotSample& s) {
      // (the step from the file before: a gap as the first file's timing measures one)
      if (first_row && !std::isnan(previous) && scans.front().timing.is_gap(s.timestamp - previous)) s.gap_before = true;
      first_row = false;
      previous = s.timestamp;
      each(s);
    });
    total += k;
    if (k < scans[i].rows) {
      if (cut) *cut = Cut{static_cast<long>(i), k};
      break;
    }
  }
  return total;
}

PositionSpeedCheck::PositionSpeedCheck(std::string path, int n_dof) : path_(std::move(path)), joints_(static_cast<size_t>(std::max(n_dof, 0))) {}

namespace {
// the ratios (position change / speed integral) a unit makes, and what each says: positions in
// degrees, speeds in degrees/s, a speed counted the other way round, and either unit with the other
// sign (the review of session 57 found -57.3 and -1/57.3 passing)
struct Signature {
  double ratio;
  const char* advice;  // what the message asks and the map line that fixes it ({0}: the joint's index)
};
constexpr Signature kSignatures[kAgreeSignatures] = {
    {1.0 / kDegree,
     "are the positions in degrees and the speeds in rad/s? Scale the positions with a column map "
     "('COLUMN,actual_q_{0},0.017453292519943295', docs/recordings.md)"},
    {kDegree,
     "are the speeds in degrees/s and the positions in radians? Scale the speeds with a column map "
     "('COLUMN,actual_qd_{0},0.017453292519943295', docs/recordings.md)"},
    {-1.0,
     "the speed has the other sign than the position's change. Does the logger count the speed the other way round? Negate it "
     "with a column map ('COLUMN,actual_qd_{0},-1', docs/recordings.md)"},
    {-1.0 / kDegree,
     "are the positions in degrees, and the speed counted the other way round? Scale the positions and negate the speed with "
     "a column map ('COLUMN,actual_q_{0},0.017453292519943295' and 'COLUMN,actual_qd_{0},-1', docs/recordings.md)"},
    {-kDegree,
     "are the speeds in degrees/s and counted the other way round? Scale and negate them with a column map "
     "('COLUMN,actual_qd_{0},-0.017453292519943295', docs/recordings.md)"},
};
}  // namespace

void PositionSpeedCheck::add(const RobotSample& s) {
  const int n = std::min(static_cast<int>(joints_.size()), s.n_dof());
  bool finite = std::isfinite(s.timestamp);
  for (int j = 0; j < n; ++j) finite = finite && std::isfinite(s.q[j]) && std::isfinite(s.qd[j]);
  if (!has_prev_) t0_ = s.timestamp;
  const double dt = s.timestamp - prev_t_;
  // (a lost sample or two is no reason to start anew: the trapezoid spans the step, and a logger
  // that loses 5 % of its samples cut every stretch short of the travel the check needs, in the
  // verbs that read the whole file with its gaps marked; review of session 57)
  if (!finite || !has_prev_ || !(dt > 0.0) || dt > kAgreeMaxStep) {
    // a new stretch from this sample (a long silence, a step back in time or a value that is not a
    // number says nothing about the units)
    close_stretch();
    stretch_start_ = s.timestamp - t0_;
  } else {
    for (int j = 0; j < n; ++j) {
      Joint& a = joints_[static_cast<size_t>(j)];
      a.moved += s.q[j] - prev_q_[j];
      a.integral += 0.5 * (s.qd[j] + prev_qd_[j]) * dt;
    }
    stretch_len_ += dt;
    if (stretch_len_ >= kAgreeStretch) {
      close_stretch();
      stretch_start_ = s.timestamp - t0_;
    }
  }
  has_prev_ = finite;
  if (finite) prev_q_ = s.q, prev_qd_ = s.qd, prev_t_ = s.timestamp;
}

void PositionSpeedCheck::close_stretch() {
  for (Joint& a : joints_) {
    if (std::abs(a.moved) >= kAgreeMinTravel && std::abs(a.integral) >= kAgreeMinTravel) {
      const double ratio = a.moved / a.integral;
      ++a.stretches;
      for (int b = 0; b < kAgreeSignatures; ++b)
        if (const double r = ratio / kSignatures[b].ratio; r >= 1.0 / kAgreeBand && r <= kAgreeBand) {
          if (a.in_band[b]++ == 0) a.first_t[b] = stretch_start_;
          a.log_sum[b] += std::log(std::abs(ratio));
        }
    }
    a.moved = a.integral = 0.0;
  }
  stretch_len_ = 0.0;
}

void PositionSpeedCheck::finish() const {
  for (size_t j = 0; j < joints_.size(); ++j) {
    const Joint& a = joints_[j];
    if (a.stretches < kAgreeMinStretches) continue;
    for (int b = 0; b < kAgreeSignatures; ++b) {
      if (static_cast<double>(a.in_band[b]) < kAgreeShare * static_cast<double>(a.stretches)) continue;
      const Signature& sig = kSignatures[b];
      const double typical = std::copysign(std::exp(a.log_sum[b] / static_cast<double>(a.in_band[b])), sig.ratio);
      throw InvalidArgument(fmt::format("{}: J{}'s position changes {:.3g} times what its speed integrates to, in {} of the {} stretches "
                                        "of {:g} s in which both move (the first from t = {:.3f} s): {}",
                                        path_, j + 1, typical, a.in_band[b], a.stretches, kAgreeStretch, a.first_t[b],
                                        fmt::format(fmt::runtime(sig.advice), j)));
    }
  }
}

void check_units(const device::Recording& rec, const model::RobotModel& robot, bool torque) {
  UnitsCheck check(rec.path, rec.n_dof, rec.present, robot, torque);
  check.check_period(rec.median_period);
  for (const RobotSample& s : rec.samples) check.add(s);
  check.finish();
}

void check_training_recording(const device::Recording& rec, const model::RobotModel& robot, const std::string& what, bool torque) {
  check_units(rec, robot, torque);
  TrainingCheck check(rec.path, robot, what, torque);
  for (const RobotSample& s : rec.samples) check.add(s);
  check.finish();
}

void TrainingCheck::add(const RobotSample& s) {
  if (failure_.empty()) failure_ = check(s);
  ++k_;
}

void TrainingCheck::finish() const {
  if (!failure_.empty()) throw InvalidArgument(failure_);
}

TrainingCheck::TrainingCheck(std::string path, const model::RobotModel& robot, std::string what, bool torque)
    : path_(std::move(path)), what_(std::move(what)), robot_(&robot), torque_(torque) {}

std::string TrainingCheck::check(const RobotSample& s) {
  const size_t k = k_;
  if (k == 0) first_ = s.timestamp;
  const double limit = robot_->payload_limit();
  const double t = s.timestamp - first_;
  // a corrupted word (1.7e308 A) among healthy samples: the monitor skips such a sample as a
  // sensor fault; a learner would fit it
  for (int j = 0; j < s.n_dof(); ++j)
    if (s.has(kFieldActualCurrent) && !(std::abs(s.current[j]) <= kTrainingCurrentMax))
      return fmt::format("{0}: column '{1}_{2}' is {3:g} {7} at t = {4:.3f} s (sample {5}), no reading a joint's {8} gives (above "
                         "{6:g} {7}); {9} learns from healthy runs: leave this stretch out of the recording",
                         path_, torque_ ? "actual_joint_torque" : "actual_current", j, s.current[j], t, k + 1, kTrainingCurrentMax,
                         torque_ ? "N·m" : "A", torque_ ? "torque sensor" : "drive", what_);
  if (!s.has(kFieldPayload)) return {};
  const Eigen::Vector3d c(s.payload_cog[0], s.payload_cog[1], s.payload_cog[2]);
  if (!std::isfinite(s.payload) || !c.allFinite())
    return fmt::format("{}: the payload declared at t = {:.3f} s (sample {}) is not a finite mass and centre of mass; {} needs the "
                       "payload each healthy run carried",
                       path_, t, k + 1, what_);
  if (s.payload > limit)
    return fmt::format("{}: column 'payload' declares {:g} kg at t = {:.3f} s (sample {}), more than {:g} kg ({}){}; {} would learn "
                       "from a run whose payload the monitor cannot take",
                       path_, s.payload, t, k + 1, limit, robot_->payload_limit_text(),
                       s.payload / 1000.0 <= limit ? ": is it in grams? Scale it with a column map ('COLUMN,payload,0.001', docs/recordings.md)" : "",
                       what_);
  if (s.payload > 0.0 && c.norm() > model::kPayloadComMax)
    return fmt::format("{}: columns 'payload_cog_0..2' declare a centre of mass ({:g}, {:g}, {:g}) {:.3g} m from the flange at t = "
                       "{:.3f} s (sample {}), more than {:g} m: is it in mm? Scale it with a column map ('COLUMN,payload_cog_0,0.001', "
                       "docs/recordings.md); {} would learn from a run whose payload the monitor cannot take",
                       path_, c.x(), c.y(), c.z(), c.norm(), t, k + 1, model::kPayloadComMax, what_);
  return {};
}

std::string magnitude_text(double value, const std::string& units) {
  const bool whole = std::isfinite(value) && std::abs(value) >= 1.0 && std::abs(value) < 1e15 && value == std::round(value);
  return (whole ? fmt::format("{:.0f}", value) : fmt::format("{:.3g}", value)) + (units.empty() ? "" : " " + units);
}

std::string robot_reference(const std::string& name_or_path) {
  std::string tip;
  const std::string file = model::robot_file(name_or_path, &tip);
  if (file.empty()) return name_or_path;  // a built-in robot
  std::error_code ec;
  const std::filesystem::path a = std::filesystem::absolute(file, ec);
  return (ec ? file : a.lexically_normal().string()) + (tip.empty() ? "" : "#" + tip);
}

std::string column_map_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(path, ec) || path.find('/') != std::string::npos) return path;
  // a bare name: one of the maps twinwatch ships (data/column_maps, or an installed share/twinwatch)
  const fs::path dir = data_directory("column_maps");
  for (const fs::path& f : {dir / path, dir / (path + ".csv")})
    if (fs::is_regular_file(f, ec)) return f.string();
  const std::vector<std::string> names = data_names("column_maps", ".csv");
  throw InvalidArgument(fmt::format("--column-map {}: no such file, and no map of that name among those twinwatch ships ({}: {})", path,
                                    dir.string(), names.empty() ? std::string("none") : fmt::format("{}", fmt::join(names, ", "))));
}

std::optional<device::ColumnMap> load_column_map(const std::string& path) {
  if (path.empty()) return std::nullopt;
  return device::ColumnMap::load(column_map_file(path));
}

std::optional<device::ColumnMap> load_column_map(const std::string& path, const ident::TwinModel& twin) {
  std::optional<device::ColumnMap> map = load_column_map(path);
  if (twin.measures_torque()) {
    if (!map) map.emplace();
    map->joint_torque_as_current = true;
  }
  return map;
}

ColumnMaps::ColumnMaps(const std::vector<std::string>& values, const std::vector<std::string>& recordings, bool joint_torque) {
  std::string all_value;
  std::vector<std::string> own_value;  // the value that gave own_[k]
  std::error_code ec;
  const auto is_recording = [&](const std::string& name) {
    for (const std::string& r : recordings)
      if (same_file(r, name)) return true;
    return false;
  };
  // a map's errors name the --column-map value it came from
  // (a bad map's content is a ParseError naming the map file and line)
  const auto load = [](const std::string& value, const std::string& map, std::string& file) {
    try {
      file = column_map_file(map);
    } catch (const InvalidArgument& e) {
      if (value == map) throw;
      const std::string why = e.what(), prefix = "--column-map " + map + ": ";
      throw InvalidArgument(fmt::format("--column-map '{}': {}", value, why.rfind(prefix, 0) == 0 ? why.substr(prefix.size()) : why));
    }
    std::error_code missing;
    if (!std::filesystem::is_regular_file(file, missing))
      throw InvalidArgument(fmt::format("--column-map '{}': no map file '{}'", value, file));
    return device::ColumnMap::load(file);
  };
  for (const std::string& v : values) {
    if (v.empty()) throw InvalidArgument("--column-map '': expected MAP or REC=MAP, got an empty value");
    // REC=MAP: the first '=' whose left part names one of the recordings (a recording's name may
    // hold a '=' too); a value that names an existing file is a MAP
    const bool a_file = std::filesystem::exists(v, ec);
    size_t eq = std::string::npos;
    if (!a_file)
      for (size_t at = v.find('='); at != std::string::npos && eq == std::string::npos; at = v.find('=', at + 1))
        if (is_recording(v.substr(0, at))) eq = at;
    if (eq == std::string::npos) {
      if (v.find('=') != std::string::npos && !a_file)
        throw InvalidArgument(fmt::format("--column-map '{}': no map file of that name, and {} ({}); REC=MAP gives one of them its own "
                                          "map",
                                          v, v.front() == '=' ? std::string("no recording is named before '='")
                                                              : "'" + v.substr(0, v.find('=')) + "' before '=' is none of the recordings",
                                          fmt::join(recordings, ", ")));
      if (!all_value.empty())
        throw InvalidArgument(fmt::format("--column-map '{}' and '{}': two maps for every recording; give one, or REC=MAP for each "
                                          "recording that needs its own",
                                          all_value, v));
      std::string file;
      all_ = load(v, v, file);
      all_value = v;
      files_.push_back(file);
      continue;
    }
    const std::string rec = v.substr(0, eq), map = v.substr(eq + 1);
    if (map.empty()) throw InvalidArgument(fmt::format("--column-map '{}': expected REC=MAP, the map after '=' is missing", v));
    for (size_t k = 0; k < own_.size(); ++k)
      if (same_file(own_[k].first, rec))
        throw InvalidArgument(fmt::format("--column-map '{}' and '{}': two maps for {}; give one", own_value[k], v, rec));
    std::string file;
    own_.emplace_back(rec, load(v, map, file));
    own_value.push_back(v);
    files_.push_back(file);
  }
  if (joint_torque) {
    if (!all_) all_.emplace();
    all_->joint_torque_as_current = true;
    for (auto& own : own_) own.second.joint_torque_as_current = true;
  }
}

const device::ColumnMap* ColumnMaps::of(const std::string& recording) const {
  for (const auto& [rec, map] : own_)
    if (same_file(rec, recording)) return &map;
  return all_ ? &*all_ : nullptr;
}

}  // namespace twinwatch::cli
