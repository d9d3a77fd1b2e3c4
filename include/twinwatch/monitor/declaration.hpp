#pragma once
// A payload the controller declares (the stream's kFieldPayload, RTDE payload / payload_cog) as the
// monitor takes it, shared by the monitor (Monitor::take_declared_payload) and the learning that must
// predict what it predicts (learn_thresholds, learn_trend_temperature, and validate's prediction).
#include <algorithm>

#include <string>
#include <vector>

#include "twinwatch/ident/twin_model.hpp"
#include "twinwatch/monitor/monitor.hpp"

namespace twinwatch::monitor {

// samples the observer runs before its threshold may raise an alert (its start-up transient; the
// threshold learning skips as many)
constexpr int kObserverSettle = 50;
// decisions wait this long after the controller declares a new payload (take_declared_payload) [s]:
// the tracking error a position loop carried for a payload it did not know unwinds in about 4 of
// its time constants. On the virtual UR3e (10 Hz loop, damping 0.8: 20 ms) a 1.5 kg part dropped
// undeclared, then a declared pick, still raised a 4 ms "contact" 34 ms after the declaration with a
// 30 ms wait, none with 40-80 ms; a real controller's slower loop would need a longer wait
constexpr double kDeclarationSettle = 0.05;
// a declared centre of mass farther than this from the flange is no part a UR arm carries (its
// reach is 0.5-1.3 m): most likely a value in mm. It is not taken (it made the monitor blind: a
// declared centre of mass of 40 "m" hid a part lost and a 10 N·m contact, session 23 review) [m]
constexpr double kDeclaredCogMax = model::kPayloadComMax;

/// A payload the controller declares is a number the twin can read: a finite mass >= 0 at a finite
/// centre of mass (the recording reader refuses other rows; a live stream's odd value is not taken).
bool declaration_readable(const RobotSample& s);
/// Why the twin does not predict with a readable declaration, or "" when it does (the monitor says
/// the reason; the learning keeps the run's payload).
std::string declaration_refusal(const ident::TwinModel& twin, const RobotSample& s);
/// The payload the twin predicts with for a declaration it takes. The declaration has no shape
/// (payload_inertia is not read): the twin's own when it is the same part, else a point mass.
model::RigidBodyInertia declared_inertia(const RobotSample& s, const model::RigidBodyInertia& had);
/// The same part: mass and (for a part) centre of mass.
bool same_payload(const model::RigidBodyInertia& a, const model::RigidBodyInertia& b);

// The payload the monitor predicts a healthy run with, sample by sample: the run's own (HealthyRun::
// payload), then, where the stream carries what the program declares (kFieldPayload) and the monitor
// follows declarations (MonitorConfig::follow_payload), each declaration the twin takes, from its
// sample on (Monitor::take_declared_payload). Learned with the run's payload alone, the thresholds
// were learned on another prediction than the monitor's: healthy runs from a controller declaring
// 0.5 kg, learned without --payload-mass, gave J2/J3 dynamic thresholds of 0.46/0.48 A where the
// declared payload gives 0.08/0.07 A (session 33), blind to a 5 N·m contact. Where the payload
// changes, the residual filter and the observer start again and decisions wait, as in the monitor
// (the current residual's kDeclarationSettle, the observer's start-up kObserverSettle samples); those
// samples teach no threshold. (A declaration that leaves the twin's payload as it was changes
// nothing here; the monitor restarts its estimators there too, which costs it only the wait.)
class PayloadTimeline {
 public:
  /// `period`: the recording's sampling period where it has none of its own (the settling waits)
  PayloadTimeline(const ident::TwinModel& twin, const HealthyRun& h, bool follow, double period);
  /// The same for a run read row by row and not held (validate): see() each sample in order (a
  /// sample without kFieldPayload declares nothing), then finish(). `twin` must outlive see()
  PayloadTimeline(const ident::TwinModel& twin, const model::RigidBodyInertia& payload, bool follow);
  void see(size_t k, const RobotSample& s);
  /// after the last see(): `samples` seen, `period` their sampling period (the settling waits)
  void finish(size_t samples, double period);
  /// Sets the run's first payload on t; advance() then follows it.
  void start(ident::TwinModel& t) {
    next_ = 1;
    t.set_payload(steps_.front().payload);
  }
  /// Sets the payload from sample k on (k in order); true where it changes there.
  bool advance(size_t k, ident::TwinModel& t) {
    if (next_ >= steps_.size() || steps_[next_].from != k) return false;
    t.set_payload(steps_[next_++].payload);
    return true;
  }
  /// A sample the monitor decides on the current residual at (not settling after a change).
  bool judged(size_t k) const { return judged_[k] != 0; }
  /// judged() for a run read once, without finish(): sample k and every one before it seen, `period`
  /// as finish() takes it (a change's settling looks back only: the same answer)
  bool judged_seen(size_t k, double period) const;
  /// A sample the monitor decides on the observer at (its start-up after a change too).
  bool judged_observer(size_t k) const { return judged_observer_[k] != 0; }
  /// The payloads in order (step 0 from sample 0: the run's own, or what it declares from its start)
  size_t steps() const { return steps_.size(); }
  size_t step_from(size_t i) const { return steps_[i].from; }
  double step_time(size_t i) const { return steps_[i].t; }  ///< the timestamp of step_from's sample [s]
  const model::RigidBodyInertia& step_payload(size_t i) const { return steps_[i].payload; }
  double heaviest() const {
    double m = 0.0;
    for (const auto& p : steps_) m = std::max(m, p.payload.mass);
    return m;
  }

 private:
  struct Step {
    size_t from = 0;
    model::RigidBodyInertia payload;
    double t = 0.0;
  };
  const ident::TwinModel* twin_;
  bool follow_;
  bool seen_any_ = false;       // a declaration read yet
  double last_mass_ = 0.0;      // the declaration read last (Monitor::same_declaration)
  double last_cog_[3] = {0.0, 0.0, 0.0};
  std::vector<Step> steps_;
  std::vector<char> judged_, judged_observer_;
  size_t next_ = 1;
};

}  // namespace twinwatch::monitor
