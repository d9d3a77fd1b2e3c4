// `twinwatch align A.csv B.csv`: time alignment of two recordings of the same motion by
// cross-correlation, with the raw vs aligned RMSE/MAE per joint of UR3e Table 2.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "twinwatch/core/error.hpp"
#include "twinwatch/device/recording.hpp"
#include "twinwatch/signal/align.hpp"
#include "verb_registry.hpp"

namespace {

using namespace twinwatch;

// the recording columns that can be aligned: RTDE name, sample member, presence flag (0: always), unit
struct SignalColumn {
  const char* name;
  VectorJ RobotSample::*member;
  std::uint32_t flag;
  const char* unit;
};
constexpr SignalColumn kColumns[] = {
    {"actual_q", &RobotSample::q, 0, "rad"},
    {"actual_qd", &RobotSample::qd, kFieldActualQd, "rad/s"},
    {"target_q", &RobotSample::target_q, kFieldTargetQ, "rad"},
    {"target_qd", &RobotSample::target_qd, kFieldTargetQd, "rad/s"},
    {"target_qdd", &RobotSample::target_qdd, kFieldTargetQdd, "rad/s^2"},
    {"actual_current", &RobotSample::current, kFieldActualCurrent, "A"},
    {"target_current", &RobotSample::target_current, kFieldTargetCurrent, "A"},
    {"target_moment", &RobotSample::target_moment, kFieldTargetMoment, "N·m"},
    {"joint_temperatures", &RobotSample::temperature, kFieldTemperature, "degC"},
};
// the two recordings must share the sample period within this fraction: the lag is found on the
// sample grid, which only means time when both grids are the same
constexpr double kPeriodTolerance = 0.01;

struct AlignCliOptions {
  std::string a, b, signal = "actual_q";
  double max_lag_ms = 2000.0;
  bool per_joint = false, no_subsample = false, json = false;
};

const SignalColumn& column_of(const std::string& name) {
  std::string names;
  for (const auto& c : kColumns) {
    if (name == c.name) return c;
    names += names.empty() ? c.name : std::string(", ") + c.name;
  }
  throw InvalidArgument(fmt::format("--signal '{}' is not a recording column group; expected one of {}", name, names));
}

std::vector<std::vector<double>> channels(const device::Recording& r, const SignalColumn& c) {
  if (c.flag != 0 && (r.present & c.flag) == 0)
    throw InvalidArgument(fmt::format("{} has no {}_* columns (choose another --signal)", r.path, c.name));
  std::vector<std::vector<double>> out(static_cast<size_t>(r.n_dof));
  for (const RobotSample& s : r.samples)
    for (int j = 0; j < r.n_dof; ++j) out[static_cast<size_t>(j)].push_back((s.*c.member)[j]);
  return out;
}

// the normalised correlation below which a joint's lag is called into doubt
constexpr double kWeakCorrelation = 0.8;
// the ratio of the two recordings' spreads of a joint's signal beyond which they are called other units
constexpr double kScaleMismatch = 5.0;

int run_align(const AlignCliOptions& o) {
  const SignalColumn& col = column_of(o.signal);
  if (!(o.max_lag_ms >= 0.0)) throw InvalidArgument(fmt::format("--max-lag-ms is {}, must be >= 0", o.max_lag_ms));
  const device::Recording ra = device::read_recording(o.a), rb = device::read_recording(o.b);
  for (const auto* r : {&ra, &rb})
    if (r->samples.size() < signal::kAlignMinSamples)
      throw InvalidArgument(fmt::format("{}: {} row(s), expected at least {} to align", r->path, r->samples.size(), signal::kAlignMinSamples));
  if (ra.n_dof != rb.n_dof) throw InvalidArgument(fmt::format("{} has {} joints, {} has {}; expected equal", o.a, ra.n_dof, o.b, rb.n_dof));
  const double T = ra.median_period;
  if (!(T > 0.0)) throw InvalidArgument(fmt::format("{}: no sample period (needs at least two rows with increasing timestamps)", o.a));
  if (!(std::abs(rb.median_period - T) <= kPeriodTolerance * T))
    throw InvalidArgument(fmt::format("{} is sampled every {:.6g} s, {} every {:.6g} s; expected the same period (within {:g} %)", o.a, T,
                                      o.b, rb.median_period, 100 * kPeriodTolerance));
  // the lag is found on the sample index: lost samples in either recording shift what follows them
  for (const auto* r : {&ra, &rb})
    if (r->gaps > 0 && !o.json)
      fmt::print(stderr, "warning: {} has {} stream gap(s); samples after a gap are compared as if none were lost\n", r->path, r->gaps);
  signal::AlignOptions opt;
  // (clipped to half the longer recording before it becomes an integer: 1e20 ms overflowed to no
  // search at all, and called a 20 ms lag "in step")
  const double longest = static_cast<double>(std::max(ra.samples.size(), rb.samples.size()));
  opt.max_lag = static_cast<int>(std::lround(std::min(o.max_lag_ms / 1000.0 / T, longest)));
  if (o.max_lag_ms > 0.0 && opt.max_lag == 0)  // (it was cut to a search of lag 0 alone, without a word)
    throw InvalidArgument(fmt::format("--max-lag-ms {:g} is less than half the sample period ({:g} ms): the search would cover lag 0 "
                                      "alone; give at least {:g}",
                                      o.max_lag_ms, 1000.0 * T, 1000.0 * T));
  opt.subsample = !o.no_subsample;
  opt.common_lag = !o.per_joint;
  const auto ca = channels(ra, col), cb = channels(rb, col);
  const auto res = signal::align_channels(ca, cb, opt);
  const double ms = 1000.0 * T;
  // no joint whose signal changes in both: there is nothing to correlate, and a "common lag 0.00
  // samples (in step)" was printed as a finding (audit, session 37)
  if (std::none_of(res.begin(), res.end(), [](const signal::Alignment& r) { return r.valid; }))
    throw InvalidArgument(fmt::format("{} is constant on every joint in {} or {}: there is nothing to align (give --signal another column)",
                                      col.name, o.a, o.b));
  bool edge = false;
  for (const auto& r : res) edge |= r.valid && r.at_window_edge;
  // joints whose signals hardly correlate at the lag found: not the same motion, or not alignable
  // (two different programs gave "late by 211.5 ms" at correlations -0.37 to 0.60, without a word)
  std::vector<int> weak;
  for (size_t k = 0; k < res.size(); ++k)
    if (res[k].valid && !(res[k].correlation >= kWeakCorrelation)) weak.push_back(static_cast<int>(k) + 1);
  if (!weak.empty() && !o.json)
    fmt::print(stderr, "warning: J{} correlate{} below {:g} at the lag found: are {} and {} recordings of the same motion? The lag "
                       "means little there\n",
               fmt::join(weak, ", J"), weak.size() == 1 ? "s" : "", kWeakCorrelation, o.a, o.b);

  // the same signal in other units (degrees for radians, mA for A): the correlation does not see a
  // scale, and the RMSE report compared 57-fold values in "rad" without a word
  std::vector<int> scaled;
  std::vector<double> ratio(res.size(), 1.0);
  const auto spread = [](const std::vector<double>& x) {
    double m = 0.0;
    for (double v : x) m += v;
    m /= static_cast<double>(x.size());
    double q = 0.0;
    for (double v : x) q += (v - m) * (v - m);
    return std::sqrt(q / static_cast<double>(x.size()));
  };
  for (size_t k = 0; k < res.size(); ++k) {
    const double sa = spread(ca[k]), sb = spread(cb[k]);
    if (!(sa > 0.0 && sb > 0.0)) continue;
    ratio[k] = sb / sa;
    if (ratio[k] > kScaleMismatch || ratio[k] < 1.0 / kScaleMismatch) scaled.push_back(static_cast<int>(k) + 1);
  }
  if (!scaled.empty() && !o.json)
    fmt::print(stderr, "warning: J{}: {}'s {} varies {:.3g} times as much as {}'s: the same signal in other units (degrees? mA?)? The "
                       "RMSE below compares them as they are\n",
               fmt::join(scaled, ", J"), o.b, col.name, ratio[static_cast<size_t>(scaled.front() - 1)], o.a);

  if (o.json) {
    nlohmann::json j;
    j["a"] = o.a;
    j["scale_mismatch_joints"] = scaled;
    j["b"] = o.b;
    j["signal"] = col.name;
    j["unit"] = col.unit;
    j["period_s"] = T;
    j["common_lag"] = opt.common_lag;
    j["window_samples"] = res.empty() ? 0 : res.front().window;
    j["peak_at_window_edge"] = edge;
    j["weak_correlation_joints"] = weak;
    for (size_t k = 0; k < res.size(); ++k) {
      const auto& r = res[k];
      j["joints"].push_back({{"joint", k + 1}, {"valid", r.valid}, {"lag_samples", r.lag}, {"lag_ms", r.lag * ms},
                             {"correlation", r.correlation}, {"raw_rmse", r.raw.rmse}, {"aligned_rmse", r.aligned.rmse},
                             {"raw_mae", r.raw.mae}, {"aligned_mae", r.aligned.mae}});
    }
    fmt::print("{}\n", j.dump());
    return 0;
  }
  fmt::print("{} against {}: {} [{}], {:g} Hz, {} rows vs {}; lag search +-{} samples ({:g} ms){}\n", o.b, o.a, col.name, col.unit, 1.0 / T,
             rb.samples.size(), ra.samples.size(), res.empty() ? 0 : res.front().window, (res.empty() ? 0 : res.front().window) * ms,
             opt.subsample ? ", parabolic sub-sample peak" : "");
  // (a lag printed as -0.00 samples was called "early": audit of session 56; below the printed
  // hundredth of a sample it is in step, and shown as 0.00)
  if (opt.common_lag && !res.empty()) {
    const double lag = std::abs(res.front().lag) < 0.005 ? 0.0 : res.front().lag;
    fmt::print("common lag {:.2f} samples = {:.1f} ms ({} is {})\n", lag, lag * ms, o.b, lag > 0 ? "late" : lag < 0 ? "early" : "in step");
  }
  const std::string u = col.unit;
  // each column at least two wider than its heading (rad/s^2 ran the headings together)
  const std::string heads[] = {"Raw RMSE [" + u + "]", "Aligned RMSE [" + u + "]", "Raw MAE [" + u + "]", "Aligned MAE [" + u + "]"};
  const size_t base[] = {18, 22, 17, 21};
  size_t w[4];
  for (int c = 0; c < 4; ++c) w[c] = std::max(base[c], heads[c].size() + 2);
  fmt::print("{:<6}{:>10}{:>8}{:>{}}{:>{}}{:>{}}{:>{}}\n", "Joint", "lag [ms]", "corr", heads[0], w[0], heads[1], w[1], heads[2], w[2],
             heads[3], w[3]);
  for (size_t k = 0; k < res.size(); ++k) {
    const auto& r = res[k];
    fmt::print("J{:<5}{:>10.1f}{:>8.4f}{:>{}.5g}{:>{}.5g}{:>{}.5g}{:>{}.5g}{}\n", k + 1, std::abs(r.lag) < 0.005 ? 0.0 : r.lag * ms, r.correlation,
               r.raw.rmse, w[0], r.aligned.rmse, w[1], r.raw.mae, w[2], r.aligned.mae, w[3], r.valid ? "" : "  (constant: no correlation of its own)");
  }
  if (edge)
    fmt::print(stderr, "warning: the correlation peak lies on the edge of the +-{:g} ms search window; the lag may be larger: widen --max-lag-ms\n",
               (res.empty() ? 0 : res.front().window) * ms);
  return 0;
}

twinwatch::cli::VerbRegistrar reg{"align", 36, [](CLI::App& app) {
  auto o = std::make_shared<AlignCliOptions>();
  auto* sub = app.add_subcommand(
      "align",
      "Time-align two recordings of the same motion by cross-correlation and compare them before and after (UR3e Table 2).\n"
      "The lag maximises the normalised cross-correlation of B against A on the sample grid (one lag for all joints\n"
      "unless --per-joint), refined below a sample by a parabola through the peak. Positive lag: B is late.\n"
      "Prints per joint the lag, the correlation, and RMSE/MAE of B against A raw and after shifting B by the lag.");
  sub->add_option("A", o->a, "Reference recording CSV")->required()->check(CLI::ExistingFile);
  sub->add_option("B", o->b, "Recording to align to A")->required()->check(CLI::ExistingFile);
  sub->add_option("--signal", o->signal, "Column group to align: actual_q, actual_qd, target_q, target_qd, target_qdd, actual_current, "
                                         "target_current, target_moment, joint_temperatures")
      ->capture_default_str();
  sub->add_option("--max-lag-ms", o->max_lag_ms, "Search window +- [ms] (clipped to half the shorter recording)")->capture_default_str();
  sub->add_flag("--per-joint", o->per_joint, "Estimate a lag per joint instead of one common lag");
  sub->add_flag("--no-subsample", o->no_subsample, "Keep the lag on the integer sample grid");
  sub->add_flag("--json", o->json,
                "Print {\"signal\", \"unit\", \"period_s\", \"joints\": [{\"joint\", \"valid\" (false: the joint's signal is constant, "
                "no lag of its own), \"lag_samples\", \"lag_ms\", \"correlation\", \"raw_rmse\", \"aligned_rmse\", \"raw_mae\", \"aligned_mae\"}, "
                "...]}");
  sub->callback([o] { twinwatch::cli::set_exit_code(run_align(*o)); });
}};

}  // namespace
