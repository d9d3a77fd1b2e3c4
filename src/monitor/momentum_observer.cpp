#include "twinwatch/monitor/momentum_observer.hpp"

#include <fmt/format.h>

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

}  // namespace twinwatch::monitor
