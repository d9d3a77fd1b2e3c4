#pragma once
/// @file regressor.hpp
/// The inertial-parameter regressor and base parameters.
///
///   tau = Y(q, qd, qdd) * pi
///
/// pi stacks, for every link i, the 10 standard parameters of robot_model.hpp
/// [m, m cx, m cy, m cz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz] (inertia about the body origin, body axes),
/// optionally followed by friction parameters per joint j (column order 10 n + k j + ...):
///   CoulombViscous:        [Fc_j, Fv_j]          tau_f = Fc sign(qd) + Fv qd
///   CoulombViscousOffset:  [Fc_j, Fv_j, off_j]   tau_f = Fc sign(qd) + Fv qd + off
///
/// Base parameters [Gautier1990, Khalil2002]: the columns of Y stacked over random states are
/// reduced by QR with column pivoting; the r independent columns span Y and every dependent
/// column is a fixed combination of them, so
///   Y pi = Y_b beta,  beta = pi_indep + K_d pi_dep.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "twinwatch/core/types.hpp"
#include "twinwatch/model/dynamics.hpp"

namespace twinwatch::model {

enum class FrictionColumns { None, CoulombViscous, CoulombViscousOffset };

/// Friction parameters per joint for a column layout (0, 2 or 3).
int friction_columns_per_joint(FrictionColumns f);

/// n_dof × (10 n_dof + friction) regressor, stored inline (no heap).
using RegressorMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kMaxDof, 13 * kMaxDof>;

/// Computes Y(q, qd, qdd) into Y (resized to n × (10 n + k n)). Allocation-free.
/// Uses the forward pass of rnea() (data.w, data.wd, data.a, data.R are overwritten).
/// @param q [rad], qd [rad/s], qdd [rad/s²]: size n_dof. Throws InvalidArgument on a size mismatch.
void regressor(const RobotModel& model, DynamicsData& data, const VectorJ& q, const VectorJ& qd, const VectorJ& qdd,
               RegressorMatrix& Y, FrictionColumns friction = FrictionColumns::None);

/// The standard parameters pi of the model (10 per link, payload merged on the last link), with
/// zero friction parameters appended for the chosen layout.
Eigen::VectorXd standard_parameters(const RobotModel& model, FrictionColumns friction = FrictionColumns::None);

/// The base-parameter structure of a model.
struct BaseParameters {
  int n_standard = 0;             ///< columns of Y
  int rank = 0;                   ///< number of base parameters
  std::vector<int> independent;   ///< standard-column indices of the base columns, in base order
  std::vector<int> dependent;     ///< the other columns (incl. columns that are identically zero)
  Eigen::MatrixXd K_d;            ///< rank × dependent.size(): beta = pi_indep + K_d pi_dep
  double tolerance = 0.0;         ///< rank threshold used on |R_kk|

  /// beta for a full standard parameter vector (size n_standard).
  Eigen::VectorXd base_values(const Eigen::VectorXd& pi) const;
  /// The base regressor Y_b = Y(:, independent) (n × rank).
  Eigen::MatrixXd base_regressor(const RegressorMatrix& Y) const;
  /// A standard-parameter vector that reproduces beta (dependent parameters zero). It is
  /// usually not physical but gives exactly Y pi = Y_b beta, so RNEA can evaluate a fitted model.
  Eigen::VectorXd standard_from_base(const Eigen::VectorXd& beta) const;
};

/// Options of the numeric base-parameter computation.
struct BaseParameterOptions {
  int n_states = 200;          ///< random states stacked (each gives n rows)
  std::uint64_t seed = 12345;  ///< random states are reproducible
  double relative_tolerance = 1e-8;  ///< rank: |R_kk| > tol * |R_00|
  void validate() const;
};

/// Numeric base parameters by QR with column pivoting on random states.
BaseParameters compute_base_parameters(const RobotModel& model, FrictionColumns friction = FrictionColumns::None,
                                       const BaseParameterOptions& options = {});

}  // namespace twinwatch::model
