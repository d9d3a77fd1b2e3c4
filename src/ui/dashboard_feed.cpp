#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <mutex>
#include <vector>
#include <nlohmann/json.hpp>

#include "twinwatch/core/error.hpp"
#include "twinwatch/ui/dashboard.hpp"

namespace twinwatch::ui {

namespace {
constexpr int kMaxJoints = 7;
// events and notes kept for a page that connects late; older ones are in the event store
constexpr size_t kKeepEvents = 500, kKeepNotes = 200;
// [intervals] a sample within this of an interval's start is in it (rounding of k * period)
constexpr double kBoundaryTolerance = 1e-6;
}  // namespace

void DashboardSetup::validate() const {
  if (n_dof < 1 || n_dof > kMaxJoints) throw InvalidArgument(fmt::format("dashboard: n_dof is {}, expected 1 to {}", n_dof, kMaxJoints));
  if (!(window_s > 0.0) || !std::isfinite(window_s))
    throw InvalidArgument(fmt::format("dashboard: window_s is {}, must be > 0 s", window_s));
  if (!(points_per_s > 0.0) || !std::isfinite(points_per_s))
    throw InvalidArgument(fmt::format("dashboard: points_per_s is {}, must be > 0", points_per_s));
  if (window_s * points_per_s > 1e6)
    throw InvalidArgument(fmt::format("dashboard: window_s x points_per_s is {:g} points, at most 1e6 are kept", window_s * points_per_s));
}

namespace {
struct Point {
  std::uint64_t seq = 0;
  double t = 0.0, total = 0.0;
  // per joint; ratio*: the |value| / threshold the interval's pick was made on
  std::array<double, kMaxJoints> measured{}, predicted{}, residual{}, threshold{}, observer{}, observer_threshold{};
  std::array<double, kMaxJoints> ratio{}, observer_ratio{};
};
struct Tagged {
  std::uint64_t seq;
  double t;
  std::string json;
};
}  // namespace

struct DashboardFeed::State {
  std::mutex m;
  std::uint64_t seq = 0;
  Point pending;  // the interval being gathered
  bool have_pending = false;
  double interval = 0.0;  // the pending point's interval index
  std::deque<Point> points;
  std::vector<Tagged> active;  // open alerts (key in t)
  std::deque<Tagged> events, notes;
  std::string state = "starting", counters = "{}";

  // the interval's point into the window
  void flush(const DashboardSetup& setup) {
    if (!have_pending) return;
    pending.seq = ++seq;
    points.push_back(pending);
    have_pending = false;
    // the window: by time, and by count (a clock that jumps ahead must not leave the deque growing)
    const double oldest = points.back().t - setup.window_s;
    const size_t max_points = static_cast<size_t>(std::ceil(setup.window_s * setup.points_per_s)) + 1;
    while (points.size() > 1 && (points.front().t < oldest || points.size() > max_points)) points.pop_front();
  }
};

DashboardFeed::DashboardFeed(DashboardSetup setup) : setup_(std::move(setup)), st_(std::make_unique<State>()) { setup_.validate(); }
DashboardFeed::~DashboardFeed() = default;

void DashboardFeed::push(const DashboardSignals& s) {
  const int n = setup_.n_dof;
  State& st = *st_;
  const std::lock_guard lock(st.m);
  // a new interval when this one is over, or when time went back
  // (the interval's index on a grid of 1/points_per_s; the tolerance keeps a sample that lands on
  // a boundary up to rounding, 0.002 * 10 against 0.02, in one interval)
  const double index = std::floor(s.t * setup_.points_per_s + kBoundaryTolerance);
  if (st.have_pending && (index != st.interval || s.t < st.pending.t)) st.flush(setup_);
  Point& p = st.pending;
  const bool first = !st.have_pending;
  if (first) {
    st.interval = index;
    st.have_pending = true;
  }
  p.t = s.t;
  p.total = s.total_current;
  const auto ratio = [](double v, double thr) { return thr > 0.0 && std::isfinite(v) ? std::abs(v) / thr : std::abs(v); };
  // a signal and its threshold: the interval's sample with the largest |value| / threshold
  using Joints = std::array<double, kMaxJoints>;
  const auto keep_peak = [&](const double* value, const double* thr, size_t k, Joints& best, Joints& v, Joints& th) {
    if (value && thr) {
      const double r = ratio(value[k], thr[k]);
      if (first || !(r <= best[k])) best[k] = r, v[k] = value[k], th[k] = thr[k];
    } else if (first) {
      v[k] = th[k] = NAN;
    }
  };
  for (int j = 0; j < n; ++j) {
    const auto k = static_cast<size_t>(j);
    p.measured[k] = s.measured ? s.measured[j] : NAN;
    p.predicted[k] = s.predicted ? s.predicted[j] : NAN;
    keep_peak(s.residual, s.threshold, k, p.ratio, p.residual, p.threshold);
    keep_peak(s.observer, s.observer_threshold, k, p.observer_ratio, p.observer, p.observer_threshold);
  }
}

void DashboardFeed::event(const std::string& json, bool open, double key, bool withdrawn) {
  State& st = *st_;
  const std::lock_guard lock(st.m);
  st.flush(setup_);  // the signals up to the event are on the page with it
  const std::uint64_t seq = ++st.seq;
  // an alert is named by its raise time while open: a re-diagnosis replaces it, its close removes it
  const auto same = [key](const Tagged& a) { return a.t == key; };
  st.active.erase(std::remove_if(st.active.begin(), st.active.end(), same), st.active.end());
  if (open) {
    st.active.push_back({seq, key, json});
    return;
  }
  if (withdrawn) return;  // (no event of its own: it leaves the open alerts, and nothing else)
  st.events.push_back({seq, key, json});
  if (st.events.size() > kKeepEvents) st.events.pop_front();
}

void DashboardFeed::note(double t, const std::string& text) {
  State& st = *st_;
  const std::lock_guard lock(st.m);
  st.notes.push_back({++st.seq, t, nlohmann::json(text).dump()});
  if (st.notes.size() > kKeepNotes) st.notes.pop_front();
}

void DashboardFeed::status(const std::string& state, const std::string& counters_json) {
  State& st = *st_;
  const std::lock_guard lock(st.m);
  if (state != "monitoring") st.flush(setup_);  // the last interval (at the end)
  st.state = state;
  st.counters = counters_json;
}

std::uint64_t DashboardFeed::cursor() const {
  const std::lock_guard lock(st_->m);
  return st_->seq;
}

std::string DashboardFeed::json_since(std::uint64_t since) const {
  // what is new is copied under the lock and written out after it: the monitoring loop waits for
  // the copy (a page's first load, the whole window: 6000 points, a memcpy), not for the JSON
  State& st = *st_;
  std::vector<Point> points;
  std::vector<Tagged> active, events, notes;
  std::uint64_t cursor = 0;
  std::string state, counters;
  bool reset = false;
  {
    const std::lock_guard lock(st.m);
    // a cursor beyond the newest (a page left open while the program restarted): everything
    if (since > st.seq) since = 0;
    cursor = st.seq;
    state = st.state;
    counters = st.counters;
    // the points newer than the cursor; a cursor older than the window's start gets the window
    // (every retained point new: the page takes it in place of its own)
    const auto first = std::upper_bound(st.points.begin(), st.points.end(), since, [](std::uint64_t c, const Point& p) { return c < p.seq; });
    reset = since == 0 || first == st.points.begin();
    points.assign(first, st.points.end());
    active = st.active;
    for (const Tagged& e : st.events)
      if (e.seq > since) events.push_back(e);
    for (const Tagged& x : st.notes)
      if (x.seq > since) notes.push_back(x);
  }
  using nlohmann::json;
  const int n = setup_.n_dof;
  json out;
  out["cursor"] = cursor;
  out["whole"] = since == 0;  // everything kept: the page replaces what it holds
  out["reset"] = reset;
  out["setup"] = {{"title", setup_.title},   {"source", setup_.source},     {"n_dof", n},
                  {"window_s", setup_.window_s}, {"points_per_s", setup_.points_per_s}, {"live", setup_.live},
                  {"channel", setup_.channel},   {"channel_unit", setup_.channel_unit}};
  out["status"] = {{"state", state}, {"counters", json::parse(counters, nullptr, false)}};
  if (out["status"]["counters"].is_discarded()) out["status"]["counters"] = json::object();
  // the points column-wise (a number array per signal and joint)
  const auto finite_or_null = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  json t = json::array(), total = json::array();
  std::array<json, 6> per;  // measured, predicted, residual, threshold, observer, observer_threshold
  for (json& a : per) {
    a = json::array();
    for (int j = 0; j < n; ++j) a.push_back(json::array());
  }
  for (const Point& pt : points) {
    t.push_back(pt.t);
    total.push_back(finite_or_null(pt.total));
    const std::array<const std::array<double, kMaxJoints>*, 6> src = {&pt.measured, &pt.predicted, &pt.residual,
                                                                      &pt.threshold, &pt.observer, &pt.observer_threshold};
    for (size_t k = 0; k < per.size(); ++k)
      for (int j = 0; j < n; ++j) per[k][static_cast<size_t>(j)].push_back(finite_or_null((*src[k])[static_cast<size_t>(j)]));
  }
  out["points"] = {{"t", std::move(t)},           {"total_current", std::move(total)}, {"measured", std::move(per[0])},
                   {"predicted", std::move(per[1])}, {"residual", std::move(per[2])},     {"threshold", std::move(per[3])},
                   {"observer", std::move(per[4])},  {"observer_threshold", std::move(per[5])}};
  // open alerts: always all of them (the page replaces its list); events and notes: the new ones
  out["active"] = json::array();
  for (const Tagged& x : active) out["active"].push_back(json::parse(x.json, nullptr, false));
  out["events"] = json::array();
  for (const Tagged& e : events) out["events"].push_back(json::parse(e.json, nullptr, false));
  out["notes"] = json::array();
  for (const Tagged& x : notes) out["notes"].push_back({{"t", x.t}, {"text", json::parse(x.json, nullptr, false)}});
  return out.dump();
}

}  // namespace twinwatch::ui
