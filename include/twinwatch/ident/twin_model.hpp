#pragma once
/// @file twin_model.hpp
/// The reference ("healthy twin") model that twinwatch identify writes and the monitor runs.
///
/// Physics model [UR3e §3.2, eq. 3; HESR §III]: shared rigid-body base parameters beta, and per
/// joint j a drive gain g_j = kt N eta [N·m/A], friction and a direction-dependent efficiency:
///   tau_j = Y_b,j(q, qd, qdd) beta + tau_payload_j(q, qd, qdd)             (rigid body)
///         + Fc_j sign(qd_j) + Fv_j qd_j + off_j + Ia_j qdd_j                (friction, rotor inertia)
///         + Ft_j qd_j (T_j - T_ref)                                         (viscous vs temperature)
///   i_j   = tau_j / g_j            when the drive is motoring (tau_j v_j >= 0)
///         = c_gen_j tau_j / g_j    when it is back-driven
/// with v_j = qd_j + velocity_lag qdd_j the joint's velocity at the sample's instant
/// (direction_velocity): a streamed velocity that lags the positions (a backward difference of the
/// encoder lags half a period) is carried forward by its identified lag.
/// The gains are absolute (N·m/A) when the training data included a known payload; otherwise the
/// common scale of beta and g is arbitrary (fixed so that prod g_j = 1) and only currents are
/// meaningful (gains_known() is false).
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "twinwatch/core/sample.hpp"
#include "twinwatch/ident/sequential_model.hpp"
#include "twinwatch/ident/learned_model.hpp"
#include "twinwatch/model/regressor.hpp"

namespace twinwatch::ident {

/// The motion a twin was identified on: per joint the range of actual_q and the largest |actual_qd|
/// over its training recordings. Beyond it the twin extrapolates, and a residual there can be model
/// error rather than a fault (monitor::EnvelopeWatch). Empty for a twin written before it was
/// recorded (session 17).
struct MotionEnvelope {
  VectorJ q_min, q_max;  ///< [rad]
  VectorJ qd_max;        ///< [rad/s] largest |qd|
  bool empty() const { return qd_max.size() == 0; }
  /// Widens the envelope to take in one sample (the first sets its size).
  void include(const VectorJ& q, const VectorJ& qd);
};

/// Friction columns of a joint, in this order.
enum FrictionColumn : int { kCoulomb = 0, kViscous, kOffset, kArmature, kViscousTemperature, kFrictionColumns };

/// Format version of the twin file that TwinModel::to_json writes (docs/twin-file.md). In version 2
/// every field the writer always writes is required; version-1 files (written before 2026-11-24)
/// are read with the values the program assumed for the fields the earliest of them lack, and one
/// warning names them.
inline constexpr int kTwinFormatVersion = 2;

struct JointDrive {
  double gain = 1.0;             ///< g_j [N·m/A] (arbitrary common scale when !gains_known)
  double c_gen = 1.0;            ///< current factor when back-driven
  /// false when the recordings did not fix g_j (the known payload hardly loads the joint): g_j
  /// still scales the predicted current, but torque from it is not trustworthy
  bool gain_identified = true;
  Eigen::Matrix<double, kFrictionColumns, 1> friction = Eigen::Matrix<double, kFrictionColumns, 1>::Zero();  ///< [N·m, N·m·s/rad, N·m, kg·m², N·m·s/rad/°C]
  double rmse = 0.0, r2 = 0.0;   ///< current fit on the training data
  /// Low-speed friction (twin_model.cpp, "Low-speed friction"): pre-sliding memory and Stribeck
  /// rise, shapes chosen on the plain fit's residual, levels fitted with everything else (physics_ident.cpp);
  /// all zero = plain Coulomb sign(qd).
  double presliding_alpha = 0.0;   ///< [1/rad] 1 / pre-sliding distance of the memory state h (0: no memory)
  double presliding = 0.0;         ///< [N·m] coefficient of (h - sign(qd)): the friction held at rest
  double stribeck_velocity = 0.0;  ///< [rad/s] v_s of the Stribeck term (0: none)
  double stribeck = 0.0;           ///< [N·m] Fs - Fc: the extra friction at |qd| << v_s
};

/// Per-stream memory of a twin: the pre-sliding state h_j of each joint, driven by the measured
/// joint displacement (twin_model.cpp), and, when the twin reads the drive's direction on the
/// controller's target (TwinModel::target_direction) and the stream carries it, that direction at
/// the sample it was last advanced to (advance() with a sample). One per robot stream; a new
/// recording starts a new one.
struct FrictionMemory {
  VectorJ h;        ///< [-] in [-1, 1]
  VectorJ q_prev;   ///< [rad] last position seen
  bool primed = false;
  /// per joint the drive's direction where it is read with the target (TwinModel::target_drive_direction),
  /// as the argument x of its blend (tanh x: +1 forward, -1 backward); on a stream without targets
  /// the measured velocity's own argument, kept only where it is in doubt (|x| <= kDoubtArgument);
  /// NaN (or empty): read on the measured velocity alone (TwinModel::direction_velocity at
  /// direction_blend)
  VectorJ direction;
  /// tanh of direction per joint, evaluated once where advance() reads it, for the prediction's
  /// current and the observer's measured torque at the same sample (one tanh per joint, not two);
  /// read only while its size is direction's (a copy that sets direction alone leaves it empty)
  VectorJ direction_tanh;
  /// per joint 1 where the direction is read with the target and the target does not rest (a
  /// target at zero velocity without acceleration: TwinModel::kTargetRestVelocity,
  /// kTargetRestAcceleration), or, on a stream without targets, where the measured velocity's blend
  /// is in doubt (a log cannot tell a rest from a crawl: its joints are in doubt at both); else 0:
  /// where TwinModel::drive_in_doubt may hold
  VectorJ crossing;
  /// true where direction comes from the measured velocity (a stream without targets): outside the
  /// monitor's reading of the doubt the observer keeps its hard switch on the velocity's sign there
  /// (monitor::measured_drive_torque), as before session 33
  bool measured = false;
};

/// The drive's direction read on the controller's target velocity where the measured one cannot tell
/// it. The drive's current factor switches when the joint's velocity crosses zero; the streamed
/// velocity is a difference of encoder counts, 0 for as long as the joint moves less than a count a
/// period (on a UR, 3 mrad/s): at a slow reversal under load (J2 of a figure-eight run at a third of
/// its speed, 0.11 rad/s²) 60 ms in which the twin's blend sits halfway between the motoring and
/// back-driven levels, half the drive's step (0.14 A) in the residual on each side of the crossing.
/// The target velocity has no counts: the joint follows it within its tracking error.
/// Measured on recordings that stream target_qd (ident::estimate_target_direction).
struct TargetDirection {
  VectorJ lead;   ///< [s] per joint: the joint's velocity at its sample's instant ~ target_qd + lead target_qdd
  /// per joint, the rms of the joint's velocity about that near standstill, sqrt(width^2 +
  /// (width_time target_qdd)^2): the blend's width. A joint reversing fast sticks and breaks away
  /// for a few ms behind its target, an error that grows with the deceleration; at a slow reversal
  /// it follows within the positions' resolution
  VectorJ width;       ///< [rad/s]
  VectorJ width_time;  ///< [s]
  bool empty() const { return width.size() == 0; }
  /// joint j's blend width at target acceleration qdd [rad/s]
  double width_at(int j, double qdd) const {
    const double a = width_time[j] * qdd;  // (sqrt, not std::hypot: a third of the cost, per joint and sample)
    return std::sqrt(width[j] * width[j] + a * a);
  }
};

/// Pre-sliding state after a measured displacement dq [rad]: the Dahl law in the displacement
/// clock, dh/ds = alpha (sign(dq) - h), stepped exactly (friction/hysteresis.hpp,
/// HysteresisDrive::Displacement, with tanh(beta qd) -> sign: the twin drives it with encoder
/// increments, not with a velocity). Standing still (dq = 0) keeps h.
inline double presliding_step(double h, double dq, double alpha) {
  if (dq == 0.0 || !(alpha > 0.0)) return h;
  const double s = dq > 0.0 ? 1.0 : -1.0;
  if (h == s) return s;  // sliding on: the state has reached s exactly (most samples at speed; no exp)
  // single-precision exp: 1e-7 relative on a factor in (0, 1), far below the state's meaning, and
  // half the cost of the double one on the per-sample path (twice per sample in the monitor)
  return s + (h - s) * static_cast<double>(std::exp(static_cast<float>(-alpha * std::abs(dq))));
}
/// Stribeck shape sign(qd) exp(-(qd/vs)^2) (0 when vs <= 0).
inline double stribeck_shape(double qd, double vs) {
  if (!(vs > 0.0) || qd == 0.0) return 0.0;
  const double x2 = (qd / vs) * (qd / vs);
  if (x2 > 40.0) return 0.0;  // exp(-40) = 4e-18: below a double's resolution of any level it scales
  return (qd > 0.0 ? 1.0 : -1.0) * static_cast<double>(std::exp(static_cast<float>(-x2)));  // float: see presliding_step
}

class TwinModel {
 public:
  TwinModel() = default;
  /// @param robot the robot description the regressor uses (built-in name or path)
  TwinModel(std::string robot, const model::RobotModel& model);

  const model::RobotModel& robot() const { return *robot_; }
  const std::string& robot_name() const { return robot_name_; }
  int n_dof() const { return robot_ ? robot_->n_dof() : 0; }

  std::vector<int> base_columns;   ///< standard-regressor columns of the base parameters
  Eigen::VectorXd beta;            ///< base parameters (torque units when gains_known)
  std::vector<JointDrive> joints;
  bool gains_absolute = false;     ///< true when a known payload fixed the torque scale
  /// What the twin predicts and the monitor compares (the twin file's "signal"):
  /// - Current: the motor currents (actual_current [A]) through the drive gains and factors above;
  /// - JointTorque: joint torque sensors (actual_joint_torque [N·m], a Panda's or a Kinova's), read
  ///   where the current is (device::ColumnMap::joint_torque_as_current). There is no drive between
  ///   the sensor and the link: every gain and c_gen is 1 and gains_absolute is true (identify
  ///   --signal joint_torque), so the "current" the twin predicts is the torque in N·m.
  enum class Signal { Current, JointTorque };
  Signal signal = Signal::Current;
  bool measures_torque() const { return signal == Signal::JointTorque; }
  /// [s] half window of the velocity smoothing the acceleration of a stream without target_qdd is
  /// differenced from, in identification and validation (ident::joint_accelerations; identify
  /// --acceleration-window); 0: the default 3 samples. The twin file's "acceleration_window"
  double acceleration_window = 0.0;
  static constexpr double kAccelerationWindowMax = 0.1;
  /// Half width [samples] of that smoothing without a window: 3 (6 ms at 500 Hz)
  static constexpr int kAccelerationHalfWidth = 3;
  /// That half window in samples of `period` [s] (kAccelerationHalfWidth when 0 or the period is
  /// unknown), at least 1
  int acceleration_half_width(double period) const {
    if (!(acceleration_window > 0.0) || !(period > 0.0)) return kAccelerationHalfWidth;
    return std::max(1, static_cast<int>(std::lround(acceleration_window / period)));
  }
  /// The unit of the measured channel and of its residuals and thresholds: "A", or "N·m"
  const char* channel_unit() const { return measures_torque() ? "N·m" : "A"; }
  /// What the measured channel is called in what the tools say: "current", or "torque"
  const char* channel_name() const { return measures_torque() ? "torque" : "current"; }
  /// The twin file's "signal" (and the column names of what is compared): "current", or "joint_torque"
  const char* signal_name() const { return measures_torque() ? "joint_torque" : "current"; }
  double temperature_ref = 35.0;        ///< [°C] reference of the temperature column
  /// [rad/s] width of the smooth motoring/back-driven switch of the current factor (0: hard switch
  /// at qd = 0); about the resolution of the measured velocity (twin_model.cpp, direction_factor)
  double direction_blend = 0.0;
  /// [s] how far the streamed velocity (actual_qd) lags the instant of its sample, identified from
  /// the recordings (ident::estimate_velocity_lag): the drive's direction is read on
  /// direction_velocity(), the velocity carried forward by this lag. Near a reversal under load the
  /// drive's current factor switches when the joint's velocity crosses zero; a velocity read half a
  /// sample late put the switch a sample late in the prediction (a step of |1 - c_gen| tau / g in
  /// the residual). 0: the streamed velocity as it is (a twin from before)
  double velocity_lag = 0.0;
  /// The joint's velocity at its sample's instant, qd + velocity_lag qdd [rad/s]: what the drive's
  /// motoring/back-driven switch is read on. A lead below kDirectionLeadMin is none: a joint at rest
  /// or crawling has no acceleration the lead could time, and there the target acceleration's noise
  /// (0.05 rad/s², 0.05 mrad/s of lead) would decide the hard switch of a streamed velocity of 0
  /// (the observer's torque at a loaded stop read back-driven: 2.7 N·m on J3, a false contact).
  double direction_velocity(double qd, double qdd) const {
    const double lead = velocity_lag * qdd;
    return std::abs(lead) >= kDirectionLeadMin ? qd + lead : qd;
  }
  /// [rad/s] the smallest lead direction_velocity applies: a sixth of one encoder count of velocity
  /// on a UR at 500 Hz (2 pi / 2^20 rad / 2 ms = 3 mrad/s), i.e. 0.5 rad/s² at the 1 ms lag
  static constexpr double kDirectionLeadMin = 5e-4;
  /// [s] the largest |velocity_lag| a twin takes (file, identify, estimate_velocity_lag): a streamed
  /// velocity a tenth of a second late is no controller's (a 500 Hz backward difference lags 1 ms)
  static constexpr double kVelocityLagMax = 0.1;
  /// Read on the controller's target velocity where it agrees with the measured one (empty: never;
  /// a twin from before session 31, or recordings without target_qd)
  TargetDirection target_direction;
  /// Where joint j's drive direction is read with the controller's target at sample s: the stream
  /// carries target_qd, and the target's velocity at the sample's instant, v_t = target_qd + lead
  /// target_qdd, agrees with the measured one within the measured velocity's resolution
  /// (direction_blend) and three of the joint's static tracking errors (TargetDirection::width: a
  /// joint that sticks at a reversal while its target moves on reads 0 counts against it). Then
  /// true, and x the direction as the argument of the blend, the evidence of both added (their log
  /// odds): x = v_t / w + v_m / direction_blend, w = TargetDirection::width_at(j, target_qdd),
  /// v_m = direction_velocity(qd, qdd). The target times
  /// the crossing where the encoder reads 0; a count the encoder does read says which way the joint
  /// went (at a slow loaded reversal the joint turned 7 ms before its target, and its first count
  /// back came a sample before the target's crossing). Else false: direction_velocity() alone.
  /// (Where the two disagree the arm does not follow its target, e.g. stopped by an obstacle, and
  /// the measured velocity is what the drive sees.)
  bool target_drive_direction(const RobotSample& s, const VectorJ& qdd, int j, double& x) const {
    if (target_direction.empty() || !s.has(kFieldTargetQd)) return false;
    const double blend = std::max(direction_blend, kDirectionLeadMin);
    // a joint moving at 20 blend widths or more: its measured velocity alone saturates the blend, and
    // a target that agrees with it only adds to that (most samples end here, without the divisions)
    if (!(std::abs(s.qd[j]) < 20.0 * blend)) return false;
    const double a = s.has(kFieldTargetQdd) ? s.target_qdd[j] : 0.0;
    const double vt = s.target_qd[j] + target_direction.lead[j] * a;
    if (!(std::abs(vt - s.qd[j]) <= blend + 3.0 * target_direction.width[j])) return false;  // (false for NaN too)
    x = vt / target_direction.width_at(j, a) + direction_velocity(s.qd[j], qdd[j]) / blend;
    return std::isfinite(x);
  }
  /// Rms tracking error above which a joint's direction is not read on its target: 0.05 rad/s is
  /// 15 encoder counts a period on a UR, a target the joint does not follow near standstill
  static constexpr double kTargetDirectionWidthMax = 0.05;
  std::string method = "physics";
  std::vector<std::string> recordings;  ///< files that built it
  MotionEnvelope envelope;              ///< the motion of those files (empty: not recorded, an older twin)
  std::string created;                  ///< ISO time
  std::string monitor_json;             ///< the monitor's learned thresholds (opaque JSON, "" if none)
  /// Cao's sequential model (method "sequential"): when set, predict() uses it for the current
  /// and reports torque as gain * current (see sequential_model.hpp).
  std::optional<SequentialModel> sequential;
  /// Learned block (UR3e §3.5), absent for the physics method. Role Current (method "mlp"): the
  /// network's output is the predicted current and the torque is g_j i_j (/ c_gen_j when
  /// back-driven), meaningful only when gains_known(). Role Residual (method "hybrid"): the output
  /// is added to the physics current, and g_j times it (/ c_gen_j) to the torque.
  std::optional<LearnedModel> learned;
  /// Optional friction block "friction_models": per-joint symbolic residual-torque equations
  /// (HESR Table VII; JSON array of friction/twin_block.hpp, opaque here, "" if none).
  std::string friction_json;
  /// The file the twin was read from (from_json's `origin`; "" for a twin built in memory): the
  /// readers of its opaque blocks (the monitor's thresholds) name it in their errors.
  std::string origin;

  /// Payload the robot carries now (flange frame); enters through the identified gains.
  void set_payload(const model::RigidBodyInertia& p) { payload_ = p; }
  const model::RigidBodyInertia& payload() const { return payload_; }

  /// True when the current-to-torque gains are absolute (a known payload was in the training data).
  bool gains_known() const { return gains_absolute; }
  /// The gain [N·m/A] that converts joint j's current to torque: its own when the recordings fixed it
  /// (gain_identified) and it is plausible for a harmonic-drive joint (kTrustedGainMin to Max), else
  /// the median of the joints' that are (a joint no payload loads may fit e.g. 3080); 1 when none
  /// is, and for a joint-torque twin (its sensors read N·m). What the monitor sizes faults with.
  double trusted_gain(int j) const;
  /// Whether any joint's gain is trusted (else trusted_gain is 1 for the untrusted ones: no median).
  bool any_trusted_gain() const;
  /// Whether joint j's torque is sized through the median of the trusted gains, not its own: a twin
  /// with absolute gains, some trusted, and j's not among them (identify's table and thresholds
  /// mark such a joint).
  bool gain_from_median(int j) const;
  /// plausible current-to-torque gains kt N eta of a harmonic-drive arm joint [N·m/A] (kt 0.05-0.3,
  /// N 50-160, eta 0.7-0.95)
  static constexpr double kTrustedGainMin = 2.0, kTrustedGainMax = 40.0;
  /// True when the prediction changes with the payload (set_payload): the physics and hybrid twins,
  /// and a sequential one identified with payload columns; not a network that predicts the current
  /// alone (method "mlp"), which never saw a payload as an input.
  bool predicts_payload() const;

  /// Predicted joint torque [N·m] (incl. friction) and current [A] for one state; temperature
  /// may be NaN (then T_ref is used). Torque is in arbitrary units unless gains_known().
  /// `memory`: the stream's pre-sliding state, already advanced to this sample (advance()); without
  /// it the state is taken at its steady value sign(qd) (the friction of a joint in steady motion,
  /// and none held at rest).
  void predict(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature, VectorJ& torque,
               VectorJ& current, const FrictionMemory* memory = nullptr) const;
  /// Only the torque (skips the drive's current factor: the momentum observer's per-sample call).
  void predict_torque(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature, VectorJ& torque,
                      const FrictionMemory* memory = nullptr) const;
  /// predict() at acceleration qdd, and in the same call the torque at a second acceleration qdd2
  /// of the same state (the monitor's current residual and its momentum observer). For the physics
  /// twin the second torque costs about half a prediction (model::rnea_pair); sequential and learned
  /// twins evaluate it by a second predict_torque().
  void predict_pair(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& qdd2, const VectorJ& temperature,
                    VectorJ& torque, VectorJ& current, VectorJ& torque2, const FrictionMemory* memory = nullptr) const;
  /// Only the current.
  void predict_current(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature,
                       VectorJ& current, const FrictionMemory* memory = nullptr) const;

  /// Advances the pre-sliding memory to the measured position q of the next sample (O(n), no
  /// allocation once primed). Call once per sample, before predict().
  void advance(FrictionMemory& memory, const VectorJ& q) const;
  /// advance() to the sample's positions, and the drive's direction at it where it is read with the
  /// target (target_drive_direction; qdd the acceleration the prediction uses) into the memory, read
  /// by predict() and monitor::measured_drive_torque. Allocation-free once primed.
  void advance(FrictionMemory& memory, const RobotSample& s, const VectorJ& qdd) const;
  /// The current factor of joint j's drive for torque tau: 1 motoring, c_gen back-driven, blended
  /// across the direction's uncertainty (the memory's direction read with the target where it has
  /// one, else direction_velocity(qd, qdd) at direction_blend).
  double drive_factor(int j, double tau, double qd, double qdd, const FrictionMemory* memory) const;
  /// Whether joint j's drive direction is in doubt at this sample for torque tau: the joint's
  /// target does not rest (memory.crossing, from advance()) and the blend read with it
  /// (drive_factor) weighs the back-driven level between kDriveDoubt and 1 - kDriveDoubt. The drive
  /// itself switches hard when the joint's velocity crosses zero, at an instant the twin cannot place
  /// closer than the blend's width; there the blended prediction sits between the two levels. Then
  /// true, with the current's two levels as offsets from the blended prediction: to_motoring =
  /// (1 - f) tau / g and to_back_driven = (c_gen - f) tau / g. False also where the twin predicts
  /// without the factor (sequential, a network predicting the current itself) or has no step
  /// (c_gen 1), and at a joint resting on its target (a held joint's current sits anywhere between
  /// the levels, where static friction leaves it). On a stream without targets (or with a twin that
  /// has no TargetDirection) the blend is the measured velocity's (direction_blend), in doubt within
  /// about two encoder counts of zero, resting or not: measured on the slow, stop and payload-at-rest
  /// sets without targets (docs/validation.md, session 33), 37 false contacts at slow reversals went,
  /// and none came at rests.
  bool drive_in_doubt(int j, double tau, const FrictionMemory& memory, double& to_motoring, double& to_back_driven) const;
  /// the back-driven weight of the blend inside which the direction is in doubt (drive_in_doubt):
  /// |x| < 1.47 of the blend's argument, about 1.5 widths of the direction's uncertainty either side
  static constexpr double kDriveDoubt = 0.05;
  /// the blend's argument |x| within which the weight is in [kDriveDoubt, 1 - kDriveDoubt]:
  /// atanh(1 - 2 kDriveDoubt)
  static constexpr double kDoubtArgument = 1.4722194895832204;
  /// A joint's target rests below this velocity [rad/s] and acceleration [rad/s²] (a controller's
  /// target at rest is exactly zero; a crawl the slow sets command is 1 mrad/s, their slowest
  /// reversal 0.045 rad/s²)
  static constexpr double kTargetRestVelocity = 1e-6;
  static constexpr double kTargetRestAcceleration = 1e-3;

  /// Friction design row of joint j (kFrictionColumns values).
  void friction_row(int j, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature,
                    Eigen::Ref<Eigen::Matrix<double, kFrictionColumns, 1>> row) const;

  /// Regressor and payload torque for a state (workspace internal).
  void regress(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, model::RegressorMatrix& Y, VectorJ& tau_payload) const;

  /// JSON text of the whole model (format version kTwinFormatVersion).
  std::string to_json() const;
  /// Reads a twin file's text; `origin` names the file in errors. Every field the writer always
  /// writes is required (version 2), each value is checked for its type and range, and a key the
  /// format does not have, or the same key twice in an object, is an error. A version-1 file gets
  /// the defaults of the fields its writer may have lacked, and one log warning names them. The
  /// opaque monitor block is checked by monitor::MonitorConfig::from_twin.
  /// Throws ParseError(origin, 0, JSON path, "expected X, got Y").
  static TwinModel from_json(const std::string& text, const std::string& origin);
  /// Writes to_json() to `path`. A regular file is replaced only once the new text is completely
  /// on disk (written beside it, then renamed over it), so a failed write leaves the old file as
  /// it was. Throws std::runtime_error naming the path and the system's reason, or the field when
  /// the text would not load back (from_json), before writing anything.
  void save(const std::string& path) const;
  /// from_json of the file at `path`; ParseError when it cannot be read.
  static TwinModel load(const std::string& path);

 private:
  std::string robot_name_;
  std::shared_ptr<model::RobotModel> robot_;
  model::RigidBodyInertia payload_;
  mutable std::shared_ptr<model::DynamicsData> data_;
  mutable model::RegressorMatrix Y_;
  // The rigid-body prediction runs as RNEA on a copy of the robot whose link parameters are the
  // fitted base parameters mapped to standard ones (non-base columns zero): Y·pi_std = Y_b·beta
  // exactly, at the cost of one RNEA (≈ 0.6 µs) instead of the full regressor plus a 36-term
  // product (≈ 1.8 µs). Re-synced whenever beta, base_columns or the payload change.
  void sync_fitted() const;
  // rigid body + friction torque of the physics model
  // (qdd2, torque2 not null: also the torque at the acceleration qdd2)
  void physics_torque(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature, VectorJ& torque,
                      const FrictionMemory* memory, const VectorJ* qdd2 = nullptr, VectorJ* torque2 = nullptr) const;
  // the drive's current of a physics torque
  void drive_current(const VectorJ& qd, const VectorJ& qdd, const VectorJ& torque, VectorJ& current, const FrictionMemory* memory) const;
  void predict_sequential(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, VectorJ& torque, VectorJ& current) const;
  // adds (hybrid) or substitutes (mlp) the learned block's output
  void apply_learned(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature, VectorJ& torque,
                     VectorJ& current, const FrictionMemory* memory) const;
  mutable std::optional<model::RobotModel> fitted_;  // by value: copies of a twin never share it
  mutable std::optional<model::DynamicsData> fitted_data_;
  mutable Eigen::VectorXd fitted_beta_;
  mutable std::vector<int> fitted_columns_;
  mutable model::RigidBodyInertia fitted_payload_;
};

}  // namespace twinwatch::ident
