#pragma once
/// @file study.hpp
/// The HESR evaluation protocol (§V) for one joint: every model (LuGre, Stribeck, RBFNN,
/// RBFNN-H, ParFam-V, ParFam-H) fitted on the same residual-torque training record, then
///
/// - offline RMSE on an untrained Fourier trajectory                         (HESR Table VIII)
/// - RMSE inside +-0.1 s windows around the velocity reversals of that trajectory (Table IX)
/// - chirp 0.1-1.0 Hz split at 0.6 Hz: in- vs out-of-distribution RMSE          (§V-F)
/// - per-sample evaluation time of the deployed model                           (Table VI)
///
/// plus simulated joints for it (generalized Maxwell-slip truth, synthetic_joint.hpp).
/// RBFNN-H gets the (alpha, beta) identified by ParFam-H ("the same hysteresis features").
#include <memory>
#include <string>
#include <vector>

#include "twinwatch/friction/friction_model.hpp"
#include "twinwatch/friction/maxwell_slip.hpp"
#include "twinwatch/friction/parfam.hpp"
#include "twinwatch/friction/rbf_network.hpp"
#include "twinwatch/friction/stribeck.hpp"
#include "twinwatch/friction/synthetic_joint.hpp"

namespace twinwatch::friction {

/// The records of one joint.
struct FrictionStudyData {
  std::string joint;                    ///< label
  FrictionRecord train;                 ///< identification record (HESR: 0.25 Hz sine sweep)
  FrictionRecord fourier;               ///< untrained validation trajectory
  FrictionRecord chirp;                 ///< 0.1-1.0 Hz chirp; may be empty (no chirp columns then)
  std::vector<double> chirp_frequency;  ///< instantaneous chirp frequency per sample [Hz]
};

/// The ParFam options the study uses: the library's HESR family with three changes measured on the
/// simulated joints (docs/validation.md, "Acceptance of issue 6"):
/// - h in the displacement clock (hysteresis.hpp): the pre-sliding memory of a harmonic drive is
///   undone by motion, not by waiting;
/// - Stage 1 compares the loops after removing the viscous slope of tau_f (remove_viscous), so
///   that a saturating, sign-like h can match (beta no longer drifts to the grid's lower edge);
/// - two tanh units instead of {sin, cos, exp, tanh} (still degree 1, the same rational-free outer
///   layer), gamma = 1e-6: saturating odd primitives, one takes the Stribeck drop in qd and one
///   shapes the pre-sliding curve in h; sin/cos/exp units fit the sweep and extrapolate worse.
ParFamOptions study_parfam_options();

struct FrictionStudyOptions {
  double reversal_window = 0.1;      ///< half-width of a reversal window [s], > 0
  double reversal_threshold = 0.05;  ///< a reversal is a sign change of qd after |qd| exceeded this [rad/s], >= 0
  double chirp_split = 0.6;          ///< in-distribution below, out-of-distribution from this frequency [Hz], > 0
  int timing_repeats = 5;            ///< evaluation passes timed per model (the fastest counts), >= 1
  ParFamOptions parfam = study_parfam_options();  ///< for ParFam-H; ParFam-V the same with input = Velocity
  /// gamma of ParFam-V: the library's 1e-5, not the study's 1e-3 (at 1e-3 the velocity-only
  /// expression loses its Coulomb term: offline RMSE 2.02 instead of 0.96 N·m on J1), >= 0
  double parfam_v_l1 = 1e-5;
  ParametricFitOptions parametric;   ///< LuGre and Stribeck
  RbfOptions rbf;                    ///< RBFNN; RBFNN-H the same with input = Hysteresis
  /// Throws InvalidArgument naming the first field out of range (also of the model options).
  void validate() const;
};

/// The numbers of one model on one joint.
struct ModelStudy {
  std::string name;
  FitSummary fit;
  std::string equation;
  double fourier_rmse = 0.0;    ///< [N·m]
  double reversal_rmse = 0.0;   ///< [N·m], samples within +-window of the Fourier record's reversals
  double chirp_id_rmse = 0.0;   ///< [N·m], chirp samples below the split frequency
  double chirp_ood_rmse = 0.0;  ///< [N·m], chirp samples from the split frequency on
  double eval_ns = 0.0;         ///< deployed evaluation (state update + model) per sample [ns]
  std::vector<double> fourier_prediction;  ///< the model's prediction of the Fourier record [N·m]
  std::shared_ptr<FrictionModel> model;    ///< the fitted model (null when the fit failed)
};

/// The study of one joint.
struct JointStudy {
  std::string joint;
  std::vector<ModelStudy> models;  ///< in HESR Table VIII order
  int reversals = 0;               ///< reversals found in the Fourier record
  long reversal_samples = 0;       ///< samples inside their windows
  FrictionRecord train;            ///< the residual-torque training record
  FrictionRecord fourier;          ///< the validation record the predictions are scored on
  std::vector<char> reversal_mask; ///< its +-window reversal samples
  /// The model called `name`; throws InvalidArgument when there is none.
  const ModelStudy& model(std::string_view name) const;
};

/// Mask of the samples within +-window [s] of a velocity reversal of qd (sampled every dt), and the
/// number of reversals. A reversal is a sign change of qd after |qd| exceeded `threshold`.
std::vector<char> reversal_window_mask(std::span<const double> qd, double dt, double window, double threshold,
                                       int* reversals = nullptr);

/// Runs the protocol on one joint. Throws InvalidArgument on bad records/options (chirp_frequency
/// must match the chirp record's size). An empty chirp record leaves the chirp RMSEs NaN.
JointStudy run_friction_study(const FrictionStudyData& data, const FrictionStudyOptions& options = {});

/// Three simulated harmonic-drive-like joints (generalized Maxwell-slip truth with four elements,
/// Stribeck peak, viscous friction and frictional lag; see study.cpp for the values and why).
struct SimulatedJoint {
  std::string name;
  MaxwellSlipParams truth;
  double torque_noise = 0.1;  ///< [N·m]
};
std::vector<SimulatedJoint> simulated_study_joints();

/// The training excitation of a simulated joint.
enum class TrainingExcitation {
  Sweep,    ///< HESR: 0.25 Hz sine at 1.2 rad/s for 20 s
  Fourier,  ///< richer: four harmonics of 0.25 Hz (0.25-1.0 Hz, the chirp's range), peak 1.2 rad/s, 20 s
  /// not HESR's protocol (a diagnosis): 12 s of the sweep, then 8 s of slow constant-velocity crawls
  /// (sweep_and_crawls_profile), as in classical Stribeck-curve identification
  Crawls,
};

/// The training profile of `training` (20 s; `seed` only for Fourier).
VelocityProfile training_profile(TrainingExcitation training, unsigned seed);

/// The HESR protocol's records for a simulated joint: training 0.25 Hz / 1.2 rad/s sine for 20 s
/// (or `training`), a 20 s five-harmonic Fourier trajectory (base 0.1 Hz, peak 1.2 rad/s,
/// coefficients from `seed`), a 20 s 0.1-1.0 Hz chirp at 1.2 rad/s; 200 Hz, 20-bit encoder, the
/// joint's torque noise, each record with its own noise seed.
FrictionStudyData simulated_study_data(const SimulatedJoint& joint, unsigned seed,
                                       TrainingExcitation training = TrainingExcitation::Sweep);

/// The joint's truth friction as the training record of simulated_study_data left it (the sweep
/// ends at rest with its elements stressed in the last direction of motion; the crawls and the
/// Fourier excitation end moving, so a trial that starts from this state at rest follows an instant
/// stop). Evaluation only: a closed-loop trial that follows the training motion on the same joint
/// starts from this state, so that the two records appended form one continuous experiment.
MaxwellSlipFriction training_end_state(const SimulatedJoint& joint, unsigned seed,
                                       TrainingExcitation training = TrainingExcitation::Sweep);

}  // namespace twinwatch::friction
