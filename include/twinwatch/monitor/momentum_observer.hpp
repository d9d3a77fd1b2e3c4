#pragma once
/// @file momentum_observer.hpp
/// Generalized-momentum residual [DeLuca2003, Haddadin2017]: an estimate of the external joint
/// torque that needs no joint acceleration.
///
///   p = M(q) qd
///   r(t) = K_O ( p(t) - p(0) - integral_0^t ( tau_m + C^T(q, qd) qd - g(q) + r ) ds )
///
/// with tau_m the joint torque the drives deliver (from current, minus predicted friction).
/// In the Laplace domain r = K_O / (s + K_O) tau_ext: a first-order low-pass of the external
/// torque with bandwidth K_O [1/s]. C^T qd is obtained from  Mdot = C + C^T  as
///   C^T qd = Mdot qd - C qd,  Mdot qd = (M(q + e qd) - M(q - e qd)) / (2 e) qd.
#include "twinwatch/core/types.hpp"
#include "twinwatch/model/dynamics.hpp"

namespace twinwatch::monitor {

class MomentumObserver {
 public:
  /// @param gain K_O per joint [1/s], > 0 (e.g. 50: 20 ms time constant)
  MomentumObserver(const model::RobotModel& model, double gain);

  /// Restarts the observer at the given state (r = 0).
  void reset(const VectorJ& q, const VectorJ& qd);

  /// One step of length dt [s] with joint torque tau_m [N·m] (drive torque minus friction).
  /// Allocation-free. @return the residual r [N·m], an estimate of the external torque.
  const VectorJ& update(const VectorJ& q, const VectorJ& qd, const VectorJ& tau_m, double dt);

  const VectorJ& residual() const { return r_; }
  double gain() const { return gain_; }

 private:
  const model::RobotModel& model_;
  model::DynamicsData data_;
  double gain_;
  bool started_ = false;
  VectorJ p0_, integral_, r_, beta_, q_tmp_, mdot_qd_, c_qd_;
};

}  // namespace twinwatch::monitor
