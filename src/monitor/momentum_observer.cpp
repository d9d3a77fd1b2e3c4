#include "twinwatch/monitor/momentum_observer.hpp"

#include <fmt/format.h>

#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::monitor {

namespace {
// step for the central difference of M along qd; M is smooth (sin/cos of q), so 1e-6 rad of
// motion gives ~1e-12 relative truncation error while staying far from round-off.
constexpr double kMdotStep = 1e-6;
}  // namespace

MomentumObserver::MomentumObserver(const model::RobotModel& model, double gain)
    : model_(model), data_(model), gain_(gain) {
  if (!(gain > 0.0)) throw InvalidArgument(fmt::format("momentum observer gain is {}, must be > 0", gain));
  const int n = model.n_dof();
  p0_ = integral_ = r_ = beta_ = q_tmp_ = mdot_qd_ = c_qd_ = VectorJ::Zero(n);
}

void MomentumObserver::reset(const VectorJ& q, const VectorJ& qd) {
  check_size("q", q.size(), model_.n_dof(), "model.n_dof");
  model::crba(model_, data_, q);
  p0_ = data_.M * qd;
  integral_.setZero();
  r_.setZero();
  started_ = true;
}

const VectorJ& MomentumObserver::update(const VectorJ& q, const VectorJ& qd, const VectorJ& tau_m, double dt) {
  if (!started_) reset(q, qd);
  // Mdot qd by a central difference of M along qd
  q_tmp_ = q + kMdotStep * qd;
  model::crba(model_, data_, q_tmp_);
  mdot_qd_ = data_.M * qd;
  q_tmp_ = q - kMdotStep * qd;
  model::crba(model_, data_, q_tmp_);
  mdot_qd_ -= data_.M * qd;
  mdot_qd_ /= 2.0 * kMdotStep;
  // beta = g - C^T qd = g - (Mdot qd - C qd)
  c_qd_ = model::coriolis_torque(model_, data_, q, qd);
  beta_ = model::gravity_torque(model_, data_, q);
  beta_ -= mdot_qd_ - c_qd_;
  // integrate, then r = K (p - p0 - integral)
  integral_ += (tau_m - beta_ + r_) * dt;
  model::crba(model_, data_, q);
  r_ = gain_ * (data_.M * qd - p0_ - integral_);
  return r_;
}

void measured_drive_torque(const ident::TwinModel& twin, const VectorJ& current, const VectorJ& qd, VectorJ& tau,
                           const ident::FrictionMemory* memory, const VectorJ* reference) {
  const int n = twin.n_dof();
  const bool target = memory != nullptr && memory->direction.size() == n;
  double to_motoring = 0.0, to_back_driven = 0.0;
  for (int j = 0; j < n; ++j) {
    const ident::JointDrive& d = twin.joints[static_cast<size_t>(j)];
    // inverse of the twin's current model: i = c tau / g with c = c_gen when back-driven (the
    // torque's sign is the current's: g > 0)
    const double tau_motoring = d.gain * current[j];
    const bool kept = target && !std::isnan(memory->direction[j]);
    if (kept && reference != nullptr && twin.drive_in_doubt(j, tau_motoring, *memory, to_motoring, to_back_driven)) {
      // the drive's direction in doubt (TwinModel::drive_in_doubt): the level nearer the twin's own
      // torque, as the current residual takes the level nearer the current (resolve_drive_doubt)
      const double back_driven = tau_motoring / d.c_gen;
      tau[j] = std::abs(back_driven - (*reference)[j]) < std::abs(tau_motoring - (*reference)[j]) ? back_driven : tau_motoring;
    } else if (kept && !memory->measured) {
      // read with the target: through the twin's blended factor, as its current is predicted
      tau[j] = tau_motoring / twin.drive_factor(j, tau_motoring, qd[j], 0.0, memory);
    } else {
      // the hard switch on the measured velocity's sign (also where a stream without targets keeps
      // the measured blend only for the doubt's reading)
      tau[j] = tau_motoring * qd[j] < 0.0 ? tau_motoring / d.c_gen : tau_motoring;
    }
  }
}

TwinMomentumObserver::TwinMomentumObserver(int n_dof, double gain) : n_(n_dof), gain_(gain) {
  if (n_dof < 1) throw InvalidArgument(fmt::format("momentum observer: n_dof is {}, must be >= 1", n_dof));
  if (!(gain > 0.0)) throw InvalidArgument(fmt::format("momentum observer gain is {}, must be > 0", gain));
  r_ = qd_prev_ = tau_m_ = tau_m_prev_ = qdd_ = tau_twin_ = VectorJ::Zero(n_dof);
}

void TwinMomentumObserver::reset() {
  restart();
  memory_ = ident::FrictionMemory{};
}

void TwinMomentumObserver::restart() {
  started_ = false;
  r_.setZero();
}

const VectorJ& TwinMomentumObserver::update(const ident::TwinModel& twin, const RobotSample& s, double dt, const VectorJ* extra_torque) {
  // (the drive's direction with the acceleration the monitor reads it with: the target's when
  // streamed, else the last difference; every sample, so that the measured torque never reads a
  // direction left from an earlier one)
  const VectorJ* qdd = acceleration(s, dt);
  twin.advance(memory_, s, s.has(kFieldTargetQdd) ? s.target_qdd : qdd_);
  if (qdd != nullptr) twin.predict_torque(s.q, s.qd, *qdd, s.temperature, tau_twin_, &memory_);
  // (no reference: the blended factor where the direction is in doubt, as the thresholds are
  // learned; the monitor reads the level on the current, Monitor::push)
  return update_with_torque(twin, s, dt, tau_twin_, extra_torque, &memory_);
}

const VectorJ* TwinMomentumObserver::acceleration(const RobotSample& s, double dt) {
  if (!started_ || !(dt > 0.0)) return nullptr;
  // momentum balance over the period: tau_ext ~ M (qd_k - qd_{k-1}) / dt + h + tau_f - tau_m
  qdd_ = (s.qd - qd_prev_) / dt;
  return &qdd_;
}

const VectorJ& TwinMomentumObserver::update_with_torque(const ident::TwinModel& twin, const RobotSample& s, double dt,
                                                        const VectorJ& twin_torque, const VectorJ* extra_torque,
                                                        const ident::FrictionMemory* memory, const VectorJ* reference) {
  // measured drive torque through the identified drive model (where the drive's direction is in
  // doubt, the level nearer the reference)
  measured_drive_torque(twin, s.current, s.qd, tau_m_, memory, reference);
  if (!started_ || !(dt > 0.0)) {
    // first sample (or a non-increasing timestamp): nothing to difference yet
    qd_prev_ = s.qd;
    tau_m_prev_ = tau_m_;
    started_ = true;
    return r_;
  }
  // first-order lag with bandwidth K (exact for a held input)
  if (dt != dt_) {
    dt_ = dt;
    a_ = 1.0 - std::exp(-gain_ * dt);
  }
  const double a = a_;
  for (int j = 0; j < n_; ++j) {
    const double tau_twin = twin_torque[j] + (extra_torque != nullptr ? (*extra_torque)[j] : 0.0);
    const double tau_ext = tau_twin - 0.5 * (tau_m_[j] + tau_m_prev_[j]);
    r_[j] += a * (tau_ext - r_[j]);
  }
  qd_prev_ = s.qd;
  tau_m_prev_ = tau_m_;
  return r_;
}

}  // namespace twinwatch::monitor
