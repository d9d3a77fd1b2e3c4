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
#include "twinwatch/core/sample.hpp"
#include "twinwatch/core/types.hpp"
#include "twinwatch/ident/twin_model.hpp"
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

/// The generalized-momentum observer [DeLuca2003, Haddadin2017] on the identified twin,
/// discretised for the monitor's per-sample path (one inverse-dynamics evaluation per sample).
///
/// With p = M(q) qd the continuous observer is  r' = K (p' - (tau_m - tau_f + C^T qd - g + r)),
/// i.e. r = K / (s + K) tau_ext. Over one sample period dt, with C^T qd = Mdot qd - C qd and the
/// rectangle rule for the Mdot qd integral,  p_k - p_{k-1} - (M_k - M_{k-1}) qd_k = M_{k-1} (qd_k - qd_{k-1}),
/// so the observer update is, up to evaluating M at q_k instead of q_{k-1},
///   r_k = r_{k-1} + a (tau_twin(q_k, qd_k, (qd_k - qd_{k-1}) / dt) - tau_m,k - r_{k-1}),
///   a = 1 - exp(-K dt)   (the exact zero-order-hold discretisation of the first-order lag),
/// where tau_twin is the twin's joint torque (rigid body + friction + rotor inertia) and tau_m the
/// drive torque measured through the identified drive model (g_j i_j, divided by c_gen_j when the
/// joint is back-driven). The velocity difference is the only "derivative": no second difference
/// and no acceleration filter, the observer gain alone sets the bandwidth.
///
/// Timing: a streamed velocity is the mean over the last sample period, so the difference of two is
/// the acceleration at the previous sample instant, where the drive torques of the previous and
/// the current period meet; tau_m,k is therefore the mean of the two measured drive torques.
class TwinMomentumObserver {
 public:
  /// @param n_dof joints; @param gain K [1/s], > 0 (bandwidth; 1/K is the time constant)
  /// Throws InvalidArgument when gain <= 0 or n_dof < 1.
  TwinMomentumObserver(int n_dof, double gain);

  /// Forgets the state; the next update restarts the observer (r = 0) and the twin's friction memory.
  void reset();
  /// Restarts the observer (r = 0 at the next update) and keeps the twin's friction memory, which
  /// follows the encoders whatever the observer does (a payload the twin takes: the monitor's
  /// restart_estimators keeps its own memory too)
  void restart();

  /// One sample. Allocation-free after construction.
  /// @param twin the reference model (its payload included); @param s q [rad], qd [rad/s],
  /// current [A], temperature [°C] of n_dof joints; @param dt time since the previous sample [s]
  /// @param extra_torque optional drive torque the twin does not predict, added to its prediction
  /// (the monitor's temperature compensation of the viscous friction) [N·m]; null: none
  /// @return r, the estimate of the external joint torque [N·m] (twin torque units)
  const VectorJ& update(const ident::TwinModel& twin, const RobotSample& s, double dt, const VectorJ* extra_torque = nullptr);

  /// The same sample in two steps, for an owner that evaluates the twin itself (the monitor, with
  /// its own prediction in one TwinModel::predict_pair). acceleration(): the acceleration the twin's
  /// torque is needed at for sample s, the finite difference (qd - qd_prev) / dt; null when this
  /// sample needs no twin torque (the first one, or dt <= 0). Then update_with_torque() with the
  /// twin's torque at that acceleration (ignored when acceleration() returned null).
  const VectorJ* acceleration(const RobotSample& s, double dt);
  /// `memory`: the owner's twin memory advanced to s (TwinModel::advance with the sample), whose
  /// target-read drive direction the measured torque is converted with (measured_drive_torque)
  /// `reference`: the twin's torque (with extra_torque) at the acceleration the prediction uses, where
  /// a drive's direction in doubt takes the level nearer it (measured_drive_torque; the monitor);
  /// null: the blend (update(), which the thresholds are learned with).
  const VectorJ& update_with_torque(const ident::TwinModel& twin, const RobotSample& s, double dt, const VectorJ& twin_torque,
                                    const VectorJ* extra_torque = nullptr, const ident::FrictionMemory* memory = nullptr,
                                    const VectorJ* reference = nullptr);

  /// Estimate of the external joint torque after the last update [N·m].
  const VectorJ& residual() const { return r_; }
  /// Adds `delta` [N·m] to the estimate: the twin's torque changed by delta in one step (a payload
  /// it now carries) and the estimate goes on as if it had always predicted with it, where reset()
  /// would start it from zero (blind for its start-up samples). Exact for a delta that is constant
  /// over the lag's time constant 1/K; the payload's torque changes over the motion's time scale.
  void shift(const VectorJ& delta) { r_ += delta; }
  /// Measured drive torque of the last sample [N·m].
  const VectorJ& drive_torque() const { return tau_m_; }
  double gain() const { return gain_; }

 private:
  int n_;
  double gain_;
  bool started_ = false;
  VectorJ r_, qd_prev_, tau_m_, tau_m_prev_, qdd_, tau_twin_;
  ident::FrictionMemory memory_;  // the twin's pre-sliding state on this stream (update() only)
  double dt_ = 0.0, a_ = 0.0;  // last period and its lag coefficient 1 - exp(-K dt)
};

/// Measured drive torque of a sample through the twin's drive model: tau_j = g_j i_j when the
/// joint is motoring (i_j qd_j >= 0), g_j i_j / c_gen_j when it is back-driven [N·m]. (On the
/// streamed velocity, not TwinModel::direction_velocity: carried forward, the observer's largest
/// healthy ratio on the long held-out runs rose, 0.949 -> 0.977 (J4), and no false alarm went;
/// docs/validation.md, session 26.) Where `memory` (advanced to this sample) reads a joint's
/// direction on the controller's target (TwinModel::target_direction): through the twin's blended
/// factor there (TwinModel::drive_factor), as its current is predicted.
/// With `reference` (the twin's torque at this sample), where the direction read with the target is
/// in doubt (TwinModel::drive_in_doubt): the one of the two levels' torques nearer the reference.
void measured_drive_torque(const ident::TwinModel& twin, const VectorJ& current, const VectorJ& qd, VectorJ& tau,
                           const ident::FrictionMemory* memory = nullptr, const VectorJ* reference = nullptr);

}  // namespace twinwatch::monitor
