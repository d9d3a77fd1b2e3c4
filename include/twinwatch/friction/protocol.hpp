#pragma once
/// @file protocol.hpp
/// The whole HESR evaluation protocol (§V) for one joint, from measured torque to the paper's
/// tables:
///
///   1. rigid-body decoupling with reversal screening (decoupling.hpp), residual records;
///   2. the model comparison of study.hpp (Tables VIII, IX, the chirp split, Table VI);
///   3. reversal-screening threshold sensitivity of the rigid-body fit           (Table III);
///   4. smoothing-window sensitivity of ParFam-H (moving average of qd and tau on every
///      record, decoupling and ParFam-H re-fitted)                                  (Table IV);
///   5. Monte Carlo measurement uncertainty tau_f^mc = (1 + s) tau_f + eps (eq. 17), s and eps
///      zero-mean Gaussian with sigma = level and level x RMS(tau_f), applied to the validation
///      residual; every fitted model is re-scored on each trial                     (Table V).
///
/// Inputs are measured records only (the twin never reads a simulator's truth).
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "twinwatch/friction/decoupling.hpp"
#include "twinwatch/friction/study.hpp"

namespace twinwatch::friction {

/// The measured records of one joint.
struct ProtocolRecords {
  std::string joint;
  JointRecord train;    ///< identification record (residual-torque sweep)
  JointRecord fourier;  ///< untrained validation trajectory
  JointRecord chirp;    ///< variable-frequency chirp; may be empty
  std::vector<double> chirp_frequency;  ///< per chirp sample [Hz]; empty: estimated from the reversals
};

struct ProtocolOptions {
  FrictionStudyOptions study;                           ///< the model comparison
  RigidBodyFitOptions rigid;                            ///< nominal decoupling (HESR: screening 0.1 rad/s)
  std::vector<double> screening_thresholds{0.05, 0.10, 0.15};  ///< Table III [rad/s], each >= 0
  std::vector<int> smoothing_windows{5, 9, 13};         ///< Table IV [samples], odd >= 1
  std::vector<double> uncertainty_levels{0.01, 0.03, 0.05};  ///< Table V scale/additive level, each >= 0
  int trials = 200;                                     ///< Monte Carlo trials per level, >= 1
  unsigned seed = 1;                                    ///< seeds the Monte Carlo draws
  std::function<void(std::string_view)> progress;       ///< optional progress messages
  /// Throws InvalidArgument naming the first field out of range.
  void validate() const;
};

/// Table III row: the rigid-body fit at one screening threshold.
struct ScreeningRow {
  double threshold = 0.0;  ///< [rad/s]
  long samples = 0;        ///< retained
  int rank = 0;
  double rmse_all = 0.0, rmse_retained = 0.0;  ///< [N·m]
  double log10_condition = 0.0;
};

/// Table IV row: ParFam-H after smoothing every record with a moving average.
struct SmoothingRow {
  int window = 1;
  double fourier_rmse = 0.0, reversal_rmse = 0.0;  ///< [N·m]
  long reversal_samples = 0;
};

/// Table V row: ParFam-H under measurement uncertainty, mean and standard deviation over trials.
struct UncertaintyRow {
  double level = 0.0;
  double fourier_mean = 0.0, fourier_std = 0.0;    ///< [N·m]
  double reversal_mean = 0.0, reversal_std = 0.0;  ///< [N·m]
  double first_share = 0.0;  ///< share of trials in which ParFam-H has the lowest reversal RMSE of all models
};

struct ProtocolResult {
  RigidBodyFit rigid;  ///< the nominal decoupling
  JointStudy study;
  std::vector<ScreeningRow> screening;
  std::vector<SmoothingRow> smoothing;      ///< first row: nominal (no smoothing, window 1)
  std::vector<UncertaintyRow> uncertainty;  ///< first row: nominal (level 0)
};

/// Instantaneous frequency of a chirp from its velocity reversals: between consecutive reversals
/// k_i < k_{i+1}, f = 1 / (2 (k_{i+1} - k_i) dt) at the midpoint of the interval, linear between
/// midpoints, held before the first and after the last.
/// Throws InvalidArgument when fewer than two reversals (threshold [rad/s]) are found.
std::vector<double> frequency_from_reversals(std::span<const double> qd, double dt, double threshold);

/// Runs the protocol. Throws InvalidArgument on bad records or options.
ProtocolResult run_hesr_protocol(const ProtocolRecords& records, const ProtocolOptions& options = {});

/// The rigid body the simulator gives a study joint (simulator truth: for the plant and the
/// records, never for the twin, which identifies it with fit_rigid_body): a vertical base axis J1
/// sees no gravity, the shoulder J2 the largest gravity torque.
struct SimulatedRigidBody {
  double inertia;      ///< I [kg·m^2]
  double gravity_sin;  ///< g_s [N·m]
  double gravity_cos;  ///< g_c [N·m]
  double offset;       ///< c [N·m]
};
SimulatedRigidBody simulated_rigid_body(const SimulatedJoint& joint);

/// The simulated study joints with a rigid body added to the measured torque (what a current-based
/// pipeline sees): tau = I qdd + g_s sin(q) + g_c cos(q) + c + tau_f + noise, with the records of
/// simulated_study_data() (or the richer training excitation), the rigid body of simulated_rigid_body().
ProtocolRecords simulated_protocol_records(const SimulatedJoint& joint, unsigned seed,
                                           TrainingExcitation training = TrainingExcitation::Sweep);

}  // namespace twinwatch::friction
