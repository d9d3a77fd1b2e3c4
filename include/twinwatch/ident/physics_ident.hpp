#pragma once
/// @file physics_ident.hpp
/// Identification of the current-domain physics twin from recordings only (DESIGN.md rule 1).
///
/// Per joint, least squares of the measured current on the design row of twin_model.hpp, with
/// the drive gain and the back-driven factor c_gen fitted jointly with the rigid-body and
/// friction parameters (Levenberg-Marquardt on sufficient statistics); the drive direction of
/// each sample comes from the previous pass's torque, so every pass re-splits the samples. Velocity reversals (|qd_j| < reversal_screen) can be left out of the fit
/// [HESR §III-E]. The drive gain g_j comes out as 1 / (payload coefficient) when some recordings
/// were made with a known payload.
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "twinwatch/device/recording.hpp"
#include "twinwatch/ident/twin_model.hpp"

namespace twinwatch::ident {

/// How the back-driven factor c_gen is fitted.
enum class EfficiencyFit {
  /// Jointly with theta and the gains (Levenberg-Marquardt on per-direction statistics): recovers
  /// c_gen (J2 of the simulated UR3e: 0.765 for 0.765). The gains of joints the known payload
  /// hardly loads (UR3e J1, J5, J6 with an on-axis payload) converge to finite values that look
  /// plausible but are not (J1 31.6 N·m/A for 11.4): they are flagged !gain_identified and the
  /// monitor does not convert residuals to torque with them. The default.
  Joint,
  /// The first version: c_gen re-estimated between passes with theta fixed, which crawls from 1
  /// (J2 0.98 after two passes) and lets the unloaded joints' gains drift far out of range.
  Alternating,
};

struct IdentOptions {
  double reversal_screen = 0.0;  ///< [rad/s] leave |qd_j| below this out of the fit (0: keep all)
  EfficiencyFit efficiency_fit = EfficiencyFit::Joint;
  int efficiency_passes = 2;     ///< re-fits with the samples re-split into motoring/back-driven (alternating: and c_gen updated)
  int decimate = 1;              ///< use every k-th sample
  double temperature_ref = 35.0; ///< [°C]
  /// [rad/s] TwinModel::direction_blend of the identified twin: two velocity quanta of a 20-bit
  /// encoder differenced at 500 Hz (2 x 6e-6 rad / 2 ms = 6e-3 rad/s), rounded
  double direction_blend = 0.005;
  /// fit the low-speed friction (pre-sliding memory and Stribeck rise, twin_model.cpp): shapes on the
  /// plain fit's residual, then the whole fit again with them; false: plain Coulomb sign(qd), the twin of before
  bool low_speed_friction = true;
  /// [s] TwinModel::velocity_lag: NaN (default) estimates it from the recordings
  /// (estimate_velocity_lag); a number sets it (0: the streamed velocity read as it is, the twin of before)
  double velocity_lag = std::numeric_limits<double>::quiet_NaN();
  /// read the drive's direction on the controller's target velocity near standstill, measured on
  /// the recordings (estimate_target_direction; TwinModel::target_direction); false: the twin of before
  bool target_direction = true;
  /// [s] TwinModel::acceleration_window: the half window of the velocity smoothing the acceleration of
  /// a recording without target_qdd is differenced from (0: kAccelerationHalfWidth samples). A 1 kHz
  /// log of a noisy velocity (a Panda's dq) needs ~15 ms: differenced over 3 ms its noise enters the
  /// inertial columns of the fit and biases them towards 0 (errors in the variables)
  double acceleration_window = 0.0;
  /// The recordings' measured channel is joint torque sensors (RobotSample::current holds them in
  /// N·m: device::ColumnMap::joint_torque_as_current): no drive between the sensor and the link, so
  /// every gain and c_gen stays 1, the torque scale is the sensors' own (gains_absolute) and the
  /// twin's signal is TwinModel::Signal::JointTorque. Needs EfficiencyFit::Joint.
  bool joint_torque = false;
  void validate() const;
};

/// A recording and the payload the robot carried while it was made (mass 0: none/unknown).
struct TrainingRun {
  const device::Recording* recording = nullptr;
  model::RigidBodyInertia payload;
};

/// How late the streamed velocity (actual_qd) is against the instant of its sample, measured on
/// recordings: the least squares of  qd_k = s v(t_k - lambda) ~ s c_k - s lambda a_k  over every
/// joint and recording, with c_k the central difference of actual_q carried to t_k (the velocity at
/// the positions' instant, to O(dt^2)), a_k the joint acceleration (joint_accelerations: target_qdd
/// when streamed, else a zero-phase difference of qd) and s the velocity's scale against the
/// positions' derivative (1 for a velocity in rad/s of that joint; else the lag is not measured and
/// a note says so). A velocity the controller differences backwards over one period lags half of it
/// (1 ms at 500 Hz); a filtered one lags more, a predicted one less.
struct VelocityLag {
  double seconds = 0.0;   ///< lambda [s] (0 when not measurable: see note)
  double stderr_s = 0.0;  ///< its standard error [s], as if the samples were independent (they are not: an indication)
  double period = 0.0;    ///< the recordings' median sample period [s]
  long samples = 0;       ///< joint samples used
  bool given = false;     ///< set by IdentOptions::velocity_lag, not measured
  std::string note;       ///< why it was left at 0, when it was
};

/// estimate_velocity_lag over recordings and their joint accelerations (one per sample, as
/// joint_accelerations returns). Steps across a stream gap or longer than 1.5 median periods are
/// left out. Too little acceleration to measure it (rms below 0.05 rad/s^2 or fewer than 100
/// samples), or a lag beyond +-0.1 s (no controller's): 0, with a note.
VelocityLag estimate_velocity_lag(const std::vector<const device::Recording*>& recordings,
                                  const std::vector<std::vector<VectorJ>>& accelerations);

/// How closely each joint follows the controller's target velocity, measured on recordings that
/// stream target_qd (TwinModel::target_direction): per joint the least squares of
/// c_k - target_qd_k = lead target_qdd_k, c_k the central difference of actual_q carried to t_k (as
/// in estimate_velocity_lag), and the rms of what is left (the tracking error and the positions'
/// resolution) over the samples near standstill (|target_qd| < 0.05 rad/s; all when fewer than 100),
/// at least TwinModel::kDirectionLeadMin; the part that grows with the acceleration at least the
/// timing of the drive's switch the current shows at the crossings (physics_ident.cpp,
/// drive_switch_offsets). Empty, with a note, when a recording lacks target_qd, a
/// joint has fewer than 100 samples, or a joint's error is above kTargetDirectionWidthMax (the
/// target is not that joint's velocity).
struct TargetDirectionFit {
  TargetDirection direction;
  long samples = 0;   ///< joint samples used
  /// per joint, the target crossings whose current showed the drive's switch clearly; at 5 or more
  /// the blend is at least as wide in time as the switch's offset from the crossing at 90 % of them
  std::vector<long> switches;
  std::string note;   ///< why it is empty, when it is
  /// every recording streamed target_qdd; without it (a joint-torque twin reads none) the lead and
  /// the width's time part are 0: the direction is read on target_qd itself
  bool with_acceleration = true;
};
TargetDirectionFit estimate_target_direction(const std::vector<const device::Recording*>& recordings);

struct IdentReport {
  VelocityLag velocity_lag;         ///< TwinModel::velocity_lag, and how it was measured
  TargetDirectionFit target_direction;  ///< TwinModel::target_direction, and how it was measured
  std::vector<long> samples_used;   ///< per joint
  std::vector<double> rmse, r2;     ///< training fit per joint
  std::vector<double> generating_fraction;  ///< per joint: share of samples classed back-driven (tau qd < 0)
  std::vector<double> payload_current_rms;  ///< per joint: rms of the known payload's current [A] (joint fit only)
  std::vector<bool> c_gen_identified;       ///< per joint: c_gen fitted (false: too few back-driven samples, or pinned to its range)
  std::vector<std::string> notes;
};

/// Half width [samples] of the velocity smoothing in joint_accelerations by default
inline constexpr int kAccelerationHalfWidth = TwinModel::kAccelerationHalfWidth;
/// Joint accelerations of a recording: target_qdd when recorded, else a zero-phase smoothed
/// central difference of actual_qd (a centred mean over +-half_width samples, then central
/// differences). Returns one vector per sample.
std::vector<VectorJ> joint_accelerations(const device::Recording& rec, int half_width = kAccelerationHalfWidth);

/// joint_accelerations a sample at a time, for a recording read row by row (validate): the same
/// values, each handed over with its sample, in order, once known: at once with target_qdd, else when
/// the samples the zero-phase smoothing looks ahead to have come (4 at the smoothing's half width of
/// 3), the last ones at finish(). Holds a dozen samples.
class JointAccelerationStream {
 public:
  using Ready = std::function<void(const RobotSample&, const VectorJ&)>;
  /// `present`: the recording's fields (SampleField flags); `half_width`: as joint_accelerations'
  JointAccelerationStream(int n_dof, std::uint32_t present, int half_width = kAccelerationHalfWidth);
  void push(const RobotSample& s, const Ready& ready);
  /// the end of the recording: the samples still waiting for what came after them
  void finish(const Ready& ready);

 private:
  void smooth_up_to(size_t end);  // the smoothed velocity of samples [qs_end_, end), their windows cut at total_
  void emit(size_t end, const Ready& ready);  // accelerations of samples [next_, end)
  int n_;
  bool target_, has_qd_;
  int half_;                // the smoothing's half width [samples]
  size_t total_ = 0;        // samples pushed
  size_t base_ = 0;         // global index of buf_.front() and qs_.front()
  size_t qs_end_ = 0;       // smoothed velocities known for [0, qs_end_)
  size_t next_ = 0;         // the next sample to hand over
  std::deque<RobotSample> buf_;
  std::deque<VectorJ> qs_;
};

/// Identifies the physics twin. Throws InvalidArgument when the data cannot support it (no
/// current column, too few samples, robot/recording joint counts differ).
TwinModel identify_physics(const std::string& robot, const std::vector<TrainingRun>& runs, const IdentOptions& options,
                           IdentReport& report, const std::function<void(double)>& progress = {});

}  // namespace twinwatch::ident
