#pragma once
/// @file closed_loop.hpp
/// The closed-loop application of HESR §V-G on a simulated joint: a commercial-style
/// velocity-command interface (inner PI velocity loop, no torque command), the model torque fed
/// forward through that interface, and the torque-error adaptive PD of HESR eq. 19-20:
///
///   tau_d   = I qdd_d + f_hat(qd_d)            (rigid body + the residual-torque model)
///   qd_ff   : kv qd_ff + ki int qd_ff dt = tau_d   (the velocity offset that makes the inner PI
///             loop deliver tau_d while the joint follows qd_d; the inner loop's inverse)
///   e_tau   = LP(tau_d) - LP(tau_meas)         (tau_meas: noisy current-based torque; both low-passed
///                                               by the same filter so that e_tau = 0 when the joint
///                                               follows qd_d with an exact model)
///   qd_comp = K_p(|qd_d|) e_tau + K_d(|qd_d|) de_tau/dt                          (eq. 19)
///   K_{p,d}(|qd_d|) = K^min + (K^max - K^min) exp(-lambda |qd_d|)                   (eq. 20)
///   qd_cmd  = qd_d + qd_ff + qd_comp
///
/// Why qd_ff: with a time-aligned e_tau and an exact model, e_tau = I (qdd_d - qdd) + f(qd_d) - f(qd)
/// carries only the tracking error, so eq. 19 alone is feedback and cannot feed the model forward
/// (with it alone even the true friction tracks no better than no compensation; `inverse_feedforward`
/// false reproduces that). The trial starts from rest with a 1 s ramp-in (not scored).
///
/// The plant: I qdd = u - tau_f, tau_f from a generalized Maxwell-slip truth (maxwell_slip.hpp),
/// u = kv (qd_cmd - qd) + ki int (qd_cmd - qd) dt, integrated on substeps. Evaluation code:
/// it reads the truth by construction (it *is* the simulated robot).
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "twinwatch/friction/friction_model.hpp"
#include "twinwatch/friction/maxwell_slip.hpp"
#include "twinwatch/friction/study.hpp"
#include "twinwatch/friction/synthetic_joint.hpp"

namespace twinwatch::friction {

/// Gains of eq. 20 (units: K_p [rad/s per N·m], K_d [rad per N·m], lambda [s/rad]).
struct AdaptivePdGains {
  double kp_min = 0.005, kp_max = 0.05;
  double kd_min = 0.0, kd_max = 0.0005;
  double lambda = 4.0;
  /// K_p(|qd_d|) and K_d(|qd_d|) of eq. 20.
  double kp(double qd_d) const noexcept;
  double kd(double qd_d) const noexcept;
  /// Throws InvalidArgument naming the field: negative or non-finite gains, min > max, lambda < 0.
  void validate() const;
};

struct ClosedLoopOptions {
  double inertia = 0.45;        ///< the plant's I [kg·m^2] (the simulated joint), > 0
  /// The twin's I [kg·m^2], identified from the joint's recordings (fit_rigid_body), > 0: the
  /// rigid-body part of tau_d and what the recorded residual torque subtracts. The controller never
  /// sees the plant's `inertia`.
  double model_inertia = 0.45;
  double kv = 25.0;             ///< inner velocity-loop proportional gain [N·m·s/rad], > 0
  double ki = 150.0;            ///< inner velocity-loop integral gain [N·m/rad], >= 0
  double dt = 0.005;            ///< command period [s] (200 Hz), > 0
  int substeps = 20;            ///< plant/inner-loop steps per command period, >= 1
  double torque_noise = 0.1;    ///< sigma of tau_meas [N·m], >= 0
  double derivative_filter = 0.02;  ///< time constant of the de_tau/dt filter [s], > 0
  /// Time constant of the first-order low-pass that smooths the current-based torque estimate
  /// before it enters e_tau [s], >= 0 (0: raw). HESR §V-G: the current-derived torque is noisy;
  /// a controller cannot use it unfiltered.
  double torque_filter = 0.1;
  /// Low-pass tau_d with the same filter as tau_meas before e_tau (true: time-aligned; false: the
  /// filter's lag alone makes e_tau = tau_d - LP(tau_d) != 0 on a perfectly tracked trajectory).
  bool matched_filter = true;
  /// Feed tau_d forward through the inverse of the inner PI loop (qd_ff); false: eq. 19 alone.
  bool inverse_feedforward = true;
  double reversal_window = 0.1; ///< +-window around desired-velocity zero crossings [s], > 0
  double segment = 1.0;         ///< segment length of the segment-wise RMSE [s], > 0
  AdaptivePdGains gains;
  unsigned seed = 1;            ///< seeds the torque noise
  /// Also return what the joint's own sensors recorded (ClosedLoopRun::measured): identification
  /// data gathered under this feedback. Off by default; the run itself is the same either way.
  bool record_measurements = false;
  /// Throws InvalidArgument naming the first field out of range.
  void validate() const;
};

/// One closed-loop run.
struct ClosedLoopRun {
  std::string compensation;       ///< "None", "Baseline", or the model's name
  std::vector<double> q_d, q;     ///< desired and actual position [rad] per command period
  double rmse = 0.0;              ///< tracking RMSE of q_d - q [rad] (Table X)
  double segment_average = 0.0;   ///< mean of the per-segment RMSEs [rad] (Table XI)
  double reversal_rmse = 0.0;     ///< RMSE within +-window of desired-velocity zero crossings [rad] (Table XI)
  int reversals = 0;
  /// RMSE of the model's f_hat(qd_d) against the truth friction along the desired trajectory
  /// [N·m] (evaluation only: explains the tracking figures); NaN without a model.
  double feedforward_rmse = 0.0;
  /// The same within |qd_d| < 0.1 rad/s, where eq. 20's gains are highest [N·m]; NaN without a model.
  double feedforward_rmse_slow = 0.0;
  /// With record_measurements: the residual-torque record of the whole run, ramp-in included, as the
  /// joint's sensors give it (20-bit encoder, the torque noise of the options): per command period
  /// the mean velocity from encoder increments and the mean motor torque less I times the period's
  /// velocity change (encoder central differences; I: the twin's model_inertia). Empty otherwise.
  FrictionRecord measured;
};

/// Runs the joint along the desired velocity profile (q_d(0) = q(0) = 0 after a 1 s ramp-in from
/// rest that is not scored; the held command of each period is its mean desired velocity, tau_d is
/// taken at its midpoint and compared with the mean motor torque it produced). `model` predicts the
/// residual torque along qd_d for tau_d; null means "Baseline" (tau_d = I qdd_d). With
/// `feedforward` false the command is qd_d alone ("None"). `plant_start` is the plant friction's
/// state when the ramp-in begins (null: relaxed elements, a fresh joint; else a copy of the state
/// another motion of the same joint left, e.g. training_end_state(): the trial continues it, at
/// rest, the inner loop's integrator holding the torque the elements hold; with ki = 0 nothing holds
/// it and the elements spring back). Throws InvalidArgument on bad options or a plant_start of
/// another joint (other Maxwell-slip parameters).
ClosedLoopRun run_closed_loop(const MaxwellSlipParams& truth, const VelocityProfile& desired, FrictionModel* model,
                              const ClosedLoopOptions& options = {}, bool feedforward = true,
                              const MaxwellSlipFriction* plant_start = nullptr);

/// Closed-loop options for a simulated study joint: the plant's inertia (simulated_rigid_body()),
/// the twin's `model_inertia` as identified (e.g. identified_inertia()), an inner velocity loop of
/// 55 rad/s bandwidth (kv = 55 I, the robot's own loop tuned on its own inertia,
/// ki = 6 kv), eq. 20 gains from the torque loop's stability alone (K_p^max = 0.5/kv: a gain margin
/// of 2 on the sampled unfiltered loop qd_comp = K_p e_tau, unstable at kv K_p = 1; K_p^min =
/// K_p^max/10, K_d 0 .. K_p^max/130 s, lambda 4 s/rad), the joint's torque noise.
/// Throws InvalidArgument when model_inertia is not finite and > 0.
ClosedLoopOptions closed_loop_options_for(const SimulatedJoint& joint, double model_inertia);

/// The joint's inertia as the twin identifies it: fit_rigid_body (HESR's 0.1 rad/s reversal
/// screening) on the joint's protocol records (simulated_protocol_records: sweep, Fourier, chirp
/// of `seed`), never the simulator's value.
double identified_inertia(const SimulatedJoint& joint, unsigned seed,
                          TrainingExcitation training = TrainingExcitation::Sweep);

/// Result of tune_in_loop().
struct LoopTuning {
  std::shared_ptr<FrictionModel> model;  ///< the tuned copy (the input model is not changed)
  double rmse_before = 0.0;              ///< tracking RMSE of the training trials with the fitted parameters [rad]
  double rmse_after = 0.0;               ///< the same with the tuned parameters [rad]
  int parameters = 0;                    ///< parameters tuned
  long evaluations = 0;                  ///< objective evaluations, the fitted parameters' included (each one trial per trajectory)
};

/// Tunes a fitted model's parameters on the loop's own tracking error (a diagnosis, not HESR's
/// protocol): derivative-free local search (NLopt BOBYQA) from the fitted parameters, each
/// evaluation one closed-loop trial of every `training` trajectory (the joint's encoder against the
/// desired path, what a robot's trial run gives; the noise of `options.seed`, the same for every
/// trial); the objective is the RMS over the trajectories of their tracking RMSE. LuGre:
/// sigma0, Fs, vs, Fc (x e^[-1,1]), sigma1, sigma2 (x e^[-1,1] when nonzero), offset (+-0.5 N·m);
/// ParFam-H / ParFam-V: every active coefficient (x [0.5, 1.5]) and alpha, beta (x e^[-1,1]).
/// Throws InvalidArgument for another model type, an unfitted model, no trajectory or evaluations < 1.
LoopTuning tune_in_loop(const FrictionModel& model, const MaxwellSlipParams& truth, std::span<const VelocityProfile> training,
                        const ClosedLoopOptions& options, const MaxwellSlipFriction* plant_start, int evaluations);

/// The closed-loop desired trajectory: 10 s, five harmonics of 0.1 Hz, peak 1.0 rad/s,
/// coefficients from seed + 100 (not the study's validation trajectory).
VelocityProfile closed_loop_profile(unsigned seed);

/// The truth itself as a FrictionModel (an oracle reference for the closed loop: what a perfect
/// residual-torque model would give). fit() does nothing; equation() names the truth.
class MaxwellSlipOracle final : public FrictionModel {
 public:
  explicit MaxwellSlipOracle(MaxwellSlipParams truth);
  std::string_view name() const noexcept override { return "True friction"; }
  FitSummary fit(const FrictionRecord& record) override;
  bool fitted() const noexcept override { return true; }
  void start(double dt) override;
  double step(double qd) noexcept override;
  std::string equation() const override { return "generalized Maxwell-slip truth"; }

 private:
  MaxwellSlipFriction gms_;
  double dt_ = 0.005;
};

}  // namespace twinwatch::friction
