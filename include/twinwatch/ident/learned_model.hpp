#pragma once
/// @file learned_model.hpp
/// The learned block of a twin (UR3e §3.5): an MLP on per-joint features of the state, used either
/// alone (method "mlp", as in the paper: the network predicts the motor currents) or as a
/// correction on top of the physics model (method "hybrid": the network predicts the physics
/// model's current residual i - i_phys, which the twin adds).
///
/// Inputs are built per state from (q, qd, qdd, T), all joints of one kind before the next, in
/// the order of LearnedInputs' fields. The network sees the state only (no history), so the
/// twin stays a function of (q, qd, qdd, payload, T) that the monitor evaluates sample by sample.
#include <Eigen/Core>
#include <string>

#include "twinwatch/core/types.hpp"
#include "twinwatch/ident/mlp.hpp"

namespace twinwatch::ident {

/// Which per-joint features feed the network.
struct LearnedInputs {
  bool q = true;             ///< joint position [rad] (gravity, configuration-dependent inertia)
  bool qd = true;            ///< joint velocity [rad/s] (SG-smoothed when training, UR3e §3.5)
  bool qdd = false;          ///< joint acceleration [rad/s²] (inertia, rotor and drive lag)
  bool temperature = false;  ///< joint temperature [°C] (NaN: the twin's reference)
  /// Friction-shape features per joint: tanh(qd / v_scale) (a smooth direction sign) and
  /// exp(-(qd / v_scale)²) tanh(qd / v_scale) (a Stribeck-like bump at low speed). A ReLU network
  /// on z-scored qd needs many units to make a step this narrow; these give it directly.
  bool friction_shape = false;
  double v_scale = 0.02;     ///< [rad/s] width of the friction-shape features
  /// Number of network inputs for n joints.
  int count(int n) const;
  /// Throws InvalidArgument when no feature is selected or v_scale <= 0.
  void validate() const;
  /// Feature names joined by '+', e.g. "q+qd+friction_shape" / parsed back (InvalidArgument on an
  /// unknown name).
  std::string to_string() const;
  static LearnedInputs parse(const std::string& text);
  /// Fills x (count(n) values) for one state; T may be NaN (then T_ref). Allocation-free.
  void build(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& T, double T_ref, double* x) const;
};

/// What the network's outputs mean.
enum class LearnedRole {
  Current,   ///< method "mlp": the predicted motor current [A] itself
  Residual,  ///< method "hybrid": a correction added to the physics model's current [A]
};

struct LearnedModel {
  LearnedRole role = LearnedRole::Residual;
  LearnedInputs inputs;
  Mlp net;                     ///< n_inputs = inputs.count(n_dof), n_outputs = n_dof
  double temperature_ref = 35.0;  ///< [°C] used for a NaN temperature input
  int sg_window = 11, sg_order = 3;  ///< Savitzky-Golay smoothing of qd used in training (recorded)
  std::vector<double> validation_rmse;  ///< per joint, on the held-out blocks [A]

  /// The network's outputs for one state, raw units [A] (n_dof values into out). Allocation-free.
  void evaluate(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& T, VectorJ& out) const;

  /// JSON text of the block / back (ParseError naming "learned.<field>").
  std::string to_json() const;
  static LearnedModel from_json(const std::string& text, const std::string& origin, int n_dof);

 private:
  mutable Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 8 * kMaxDof, 1> x_;  // input workspace
};

}  // namespace twinwatch::ident
