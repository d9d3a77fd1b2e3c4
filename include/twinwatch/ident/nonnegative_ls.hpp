#pragma once
/// @file nonnegative_ls.hpp
/// Linear least squares with some coefficients held >= 0 (friction levels that may not push the
/// motion along), by the active-set method of Lawson and Hanson [Lawson1974, ch. 23], extended
/// to leave chosen coefficients free (an offset).
///
/// Written here rather than taken from a library: Eigen 3.4 as packaged has no NNLS, and the
/// problems are tiny (2–4 columns, solved per joint or per diagnosis window), so a dependency
/// would cost more than the 60 lines. The method works on the normal equations G = AᵀA, g = Aᵀb,
/// which is what the identification accumulates; with every constraint inactive it returns the
/// unconstrained solution of G x = g.
#include <Eigen/Core>
#include <vector>

namespace twinwatch::ident {

/// The solution of min |A x - b|² with x_i >= 0 for every i where bounded[i], given as the normal
/// equations (G = AᵀA, g = Aᵀb; G symmetric positive semi-definite). `bounded` has G.rows()
/// entries. A column with no weight (G_ii = 0) gets 0. Throws InvalidArgument on mismatched sizes
/// or non-finite input.
Eigen::VectorXd nonnegative_ls_normal(const Eigen::MatrixXd& G, const Eigen::VectorXd& g,
                                      const std::vector<bool>& bounded);

/// The same from the rows: min |A x - b|² with every x_i >= 0.
Eigen::VectorXd nonnegative_ls(const Eigen::MatrixXd& A, const Eigen::VectorXd& b);

}  // namespace twinwatch::ident
