#pragma once
/// @file learned_ident.hpp
/// Identification of the learned reference (UR3e §3.5) from recordings of a healthy robot only
/// (DESIGN.md rule 1): method "mlp" (the network alone predicts the currents, as in the paper)
/// and method "hybrid" (the physics twin of physics_ident.hpp plus a network trained on its
/// current residual).
///
/// Both first identify the physics twin from the same recordings: the hybrid needs it, and the
/// mlp twin keeps it for the drive gains (its torque is g_j i_j) and for the monitor's diagnosis.
/// The network's qd input is Savitzky-Golay smoothed per recording before training [UR3e §3.5];
/// the twin is then evaluated sample by sample on the recorded qd (the monitor has no look-ahead).
/// The hybrid's training target is i - i_phys(q, qd, qdd, payload, T) with exactly the physics
/// prediction the twin makes online.
#include <functional>
#include <string>
#include <vector>

#include "twinwatch/ident/learned_model.hpp"
#include "twinwatch/ident/mlp.hpp"
#include "twinwatch/ident/physics_ident.hpp"
#include "twinwatch/ident/twin_model.hpp"

namespace twinwatch::ident {

struct LearnedIdentOptions {
  MlpOptions mlp;           ///< network and training (hidden, l2, seed, early stopping)
  LearnedInputs inputs;     ///< network inputs
  int sg_window = 11;       ///< Savitzky-Golay window for qd [samples], odd (0: no smoothing)
  int sg_order = 3;         ///< Savitzky-Golay polynomial order
  /// Every k-th sample goes into the network's training set. 5 (100 Hz at 500 Hz): the currents'
  /// repeatable part lies far below 50 Hz (trajectories < 2 Hz), so a 5x thinner set keeps the
  /// information and makes each full-batch L-BFGS evaluation 5x cheaper.
  int decimate = 5;
  IdentOptions physics;     ///< the physics identification underneath
  /// Throws InvalidArgument naming the first field out of range.
  void validate() const;
  /// The defaults of a method: "mlp" -> the paper's network (inputs q and qd, 15 ReLU units);
  /// "hybrid" -> inputs qd + friction_shape, 15 units, l2 1e-2 (chosen on the validation runs,
  /// see learned_ident.cpp and docs/validation.md).
  /// Throws InvalidArgument for another name.
  static LearnedIdentOptions defaults(const std::string& method);
};

struct LearnedIdentReport {
  IdentReport physics;             ///< the physics step
  MlpFitReport fit;                ///< the network's training
  std::vector<double> rmse, r2;    ///< the whole twin's current fit on all training samples, per joint
  std::vector<double> validation_rmse;  ///< the whole twin on the held-out blocks, per joint [A]
  long samples = 0;                ///< samples the network saw (fitted + held out)
};

/// Identifies a twin with a learned block. role Current: method "mlp"; Residual: "hybrid".
/// progress gets a fraction in [0, 1]. Throws InvalidArgument like identify_physics, and on
/// invalid options or recordings shorter than the smoothing window.
TwinModel identify_learned(const std::string& robot, const std::vector<TrainingRun>& runs, LearnedRole role,
                           const LearnedIdentOptions& options, LearnedIdentReport& report,
                           const std::function<void(double)>& progress = {});

}  // namespace twinwatch::ident
