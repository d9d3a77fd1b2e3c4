#pragma once
/// @file types.hpp
/// Fixed-capacity vector and matrix types used on every hot path.
///
/// Robots here have at most kMaxDof joints (UR: 6, Panda and Gen3: 7). The types below have a
/// run-time size but a compile-time maximum, so Eigen stores them inline: no heap allocation in
/// the RNEA, the simulator step or the monitor step.
#include <Eigen/Core>

namespace twinwatch {

/// Largest number of joints a serial chain may have.
inline constexpr int kMaxDof = 7;

/// Joint-space vector (size n_dof ≤ kMaxDof), stored inline.
using VectorJ = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxDof, 1>;
/// Joint-space square matrix (n_dof × n_dof), stored inline.
using MatrixJ = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kMaxDof, kMaxDof>;
/// 6 × n_dof matrix (geometric Jacobian: rows 0-2 linear, rows 3-5 angular), stored inline.
using Matrix6J = Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::ColMajor, 6, kMaxDof>;

}  // namespace twinwatch
