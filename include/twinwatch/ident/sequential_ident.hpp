#pragma once
/// @file sequential_ident.hpp
/// Sequential identification of Cao §III from recordings only (DESIGN.md rule 1), in the current
/// domain (the UR3e streams motor currents, not torques):
///  1. gravity from bidirectional quasi-static poses (eq. 12-14): each pose is reached once from
///     below and once from above; the mean of the two held currents cancels the Coulomb friction,
///     i_g(phi) = (i_up + i_down) / 2, and least squares on the gravity regressor (eq. 11);
///  2. friction from a symmetric sine (eq. 15): samples mirrored about a turning point have the
///     same q and qdd and opposite qd, so (i(t1) - i(t2)) / 2 = Fc sign(qd) + Fv qd;
///  3. the rest of the current over general recordings by Lasso (eq. 20) on the Kronecker
///     candidate library A ⊗ B (eq. 17-19) with 10-fold CV and pruning of small coefficients.
/// See docs/validation.md "Sequential identification (Cao)".
#include <functional>
#include <string>
#include <vector>

#include "twinwatch/device/recording.hpp"
#include "twinwatch/ident/lasso.hpp"
#include "twinwatch/ident/physics_ident.hpp"
#include "twinwatch/ident/twin_model.hpp"

namespace twinwatch::ident {

struct SequentialOptions {
  CandidateLibrary library{{}, {1, 2}, 2};  ///< A over all joints, B over J2, J3, m = 2
  double min_hold = 0.3;        ///< [s] shortest stationary segment that counts as a quasi-static pose
  double pose_tolerance = 5e-3; ///< [rad] two holds are the same pose when max |q_a - q_b| (commanded q when recorded) is below this
  double sine_min_speed = 0.02; ///< [rad/s] sine pairs slower than this are left out (sign of qd unsure)
  double sine_q_tolerance = 2e-3;   ///< [rad] mirrored samples must agree in q to this
  double sine_qd_tolerance = 0.02;  ///< [rad/s] ... and have opposite qd to this (+2 % of |qd|)
  int decimate = 2;             ///< use every k-th sample of the general recordings for the Lasso
  int nfolds = 10;              ///< Lasso CV folds
  int nlambda = 100;
  unsigned seed = 1;            ///< fold assignment
  double prune_ratio = 1e-3;    ///< prune |p_k| sd(g_k) < prune_ratio sd(y)
  bool use_1se = false;         ///< lambda_1se instead of lambda_min
  void validate(int n_dof) const;
};

struct SequentialReport {
  int poses = 0;                      ///< gravity samples (paired holds)
  std::vector<long> friction_pairs;   ///< per joint
  long lasso_samples = 0;
  int candidates = 0;
  std::vector<int> nonzero;           ///< per joint, after pruning
  std::vector<double> gravity_rmse;   ///< per joint, fit of the paired-hold gravity currents [A]
  std::vector<double> friction_rmse;  ///< per joint, fit of the half differences [A]
  std::vector<double> rmse, r2;       ///< full model on the general recordings
  std::vector<double> cv_rmse;        ///< Lasso stage, at the chosen lambda
  std::vector<std::string> notes;
};

/// Identifies the sequential twin. `quasi_static` and `sine` are the recordings of steps 1 and 2,
/// `general` (with their payloads) those of step 3. Throws InvalidArgument naming the recording
/// and what is missing (no current column, no paired holds, no sine pairs for a joint, ...).
TwinModel identify_sequential(const std::string& robot, const std::vector<const device::Recording*>& quasi_static,
                              const std::vector<const device::Recording*>& sine, const std::vector<TrainingRun>& general,
                              const SequentialOptions& options, SequentialReport& report,
                              const std::function<void(double)>& progress = {});

/// Gravity samples of step 1: (q, mean current) of each pose reached from both sides.
struct GravitySample {
  VectorJ q, current;
};
std::vector<GravitySample> paired_holds(const device::Recording& rec, const SequentialOptions& options);

/// Friction samples of step 2 for joint j: (qd_j at t1, (i_j(t1) - i_j(t2)) / 2).
std::vector<std::pair<double, double>> sine_pairs(const device::Recording& rec, int j, const SequentialOptions& options);

/// Step 2's fit of (i1 - i2) / 2 = Fc sign(qd) + Fv qd over those samples, with Fc and Fv of one
/// sign (friction opposes motion). The sign is the friction's as a whole (the Coulomb-only fit):
/// the fit is in current, whose direction a channel may count either way.
struct SineFriction {
  double coulomb = 0.0;     ///< [A]
  double viscous = 0.0;     ///< [A·s/rad]
  double rmse = 0.0;        ///< [A] of the fit over the samples
  double orientation = 1;   ///< +1: friction current has the sign of qd; -1: the channel counts the other way
  double free_coulomb = 0.0, free_viscous = 0.0;  ///< the unconstrained fit, for the notes
  bool coulomb_held = false, viscous_held = false;  ///< held at 0 against the free fit's sign
};
SineFriction fit_sine_friction(const std::vector<std::pair<double, double>>& pairs);

}  // namespace twinwatch::ident
