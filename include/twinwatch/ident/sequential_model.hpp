#pragma once
/// @file sequential_model.hpp
/// The model that Cao's sequential identification builds (Cao §III, eq. 11-20), in the current
/// domain: per joint j
///   i_j = sum_c Yg_jc(q) theta_jc                         gravity   (eq. 11, Yg = Y(q, 0, 0))
///       + Fc_j sign(qd_j) + Fv_j qd_j                     friction  (eq. 15, Coulomb + viscous)
///       + a0_j + sum_k p_jk g_k(q, qd, qdd)               remaining inertial/Coriolis (eq. 17-20)
///       + h_j tau_payload_j(q, qd, qdd)                   known payload (only when trained with one)
/// with the candidates g = A ⊗ B (eq. 17), A = [qdd_i ; qd_i qd_k (i <= k)] over the motion
/// joints, B = w(q_c1) ⊗ w(q_c2) ⊗ ..., w(q) = [1, sin q, cos q, ..., sin m q, cos m q] over the
/// configuration joints (m = 2, Cao Appendix 1). Every coefficient is per joint and in amperes, so
/// the unknown current-to-torque gains are absorbed (no torque scale is identified).
#include <Eigen/Core>
#include <string>
#include <vector>

#include "twinwatch/core/types.hpp"

namespace twinwatch::ident {

/// The candidate library A ⊗ B of Cao eq. 17 (joints 0-based).
struct CandidateLibrary {
  std::vector<int> motion_joints;  ///< joints whose qdd and qd products form A (empty: all)
  std::vector<int> config_joints;  ///< joints whose w(q) form B
  int harmonics = 2;               ///< m of w(q)

  /// Throws InvalidArgument naming the field (joint out of 0..n_dof-1, repeated, m < 1, too large).
  void validate(int n_dof) const;
  int size_a(int n_dof) const;
  int size_b() const;
  int size(int n_dof) const { return size_a(n_dof) * size_b(); }
  /// Candidate values g(q, qd, qdd) [size(n_dof)], index a * size_b() + b. Allocation-free.
  void row(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, Eigen::Ref<Eigen::VectorXd> g) const;
  /// Readable name of candidate k, e.g. "qdd2*sin(q2)*cos(2q3)" (joints 1-based).
  std::string name(int n_dof, int k) const;
};

/// One joint of the sequential model (current domain, amperes).
struct SequentialJoint {
  Eigen::VectorXd gravity;           ///< theta_jc per gravity column [A per regressor unit]
  double coulomb = 0.0;              ///< Fc_j [A]
  double viscous = 0.0;              ///< Fv_j [A·s/rad]
  double intercept = 0.0;            ///< a0_j [A]
  std::vector<int> lasso_index;      ///< nonzero candidates of the remaining-torque Lasso
  std::vector<double> lasso_value;   ///< their coefficients p_jk
  Eigen::VectorXd payload;           ///< h_jl [A/(N·m)] per joint l, identified: l = j only (empty: no payload term)
  double lambda = 0.0;               ///< chosen Lasso lambda
  double cv_rmse = 0.0;              ///< 10-fold CV RMSE of the remaining-current Lasso at lambda [A]
  double rmse = 0.0, r2 = 0.0;       ///< full-model fit on the training recordings [A]
};

struct SequentialModel {
  CandidateLibrary library;
  std::vector<int> gravity_columns;  ///< standard-regressor columns of Yg used by the gravity term
  std::vector<SequentialJoint> joints;
  std::vector<std::string> quasi_static, sine, general;  ///< recordings of each stage

  /// Predicted current [A] from the state, the gravity regressor Yg [n x 10n] at (q, 0, 0) and
  /// the payload torque [N·m] (zero vector when none). Allocation-free after the first call.
  void predict(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const Eigen::Ref<const Eigen::MatrixXd>& Yg,
               const VectorJ& tau_payload, VectorJ& current) const;
  /// True when a payload term was identified (some training recording had a known payload).
  bool has_payload() const { return !joints.empty() && joints.front().payload.size() > 0; }

  mutable Eigen::VectorXd g_;  ///< workspace: candidate row
};

}  // namespace twinwatch::ident
