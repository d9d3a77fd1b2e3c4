#pragma once
/// @file lasso.hpp
/// Lasso regression by cyclic coordinate descent, with glmnet's conventions [Friedman2010], and
/// K-fold cross-validation like cv.glmnet. Used by the sequential identification of Cao (eq. 20).
///
/// Problem for one lambda (x_j standardised with the 1/n variance, y centred, intercept a0):
///   min_{a0, b}  1/(2n) ||y - a0 - X b||^2 + lambda sum_j pf_j |b_j|
/// Coefficients are returned on the original scale of X and y (like glmnet's coef()).
/// The lambda path has nlambda values log-spaced from lambda_max (the smallest lambda with every
/// penalised coefficient zero) down to lambda_max * eps, eps = 1e-4 when n > p, else 1e-2.
/// Each lambda starts from the previous solution (warm start). "Covariance" updates keep the
/// gradient g = X'r/n through the Gram matrix (cost p per coefficient change, independent of n);
/// "naive" updates keep the residual r (cost n per change). glmnet picks covariance for p < 500.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace twinwatch::ident {

enum class LassoAlgorithm { Auto, Covariance, Naive };

struct LassoOptions {
  int nlambda = 100;               ///< length of the lambda path (ignored when `lambda` is given)
  double lambda_min_ratio = -1.0;  ///< eps of the path; < 0: glmnet's default (1e-4 if n > p else 1e-2)
  std::vector<double> lambda;      ///< user path, strictly decreasing, > 0 (empty: computed)
  bool standardize = true;         ///< scale columns to unit (1/n) variance before fitting
  bool intercept = true;           ///< fit a0 (centre X and y)
  double tol = 1e-7;               ///< glmnet's thresh: stop when max_j xv_j (delta b_j)^2 < tol * var(y)
  long max_passes = 100000;        ///< coordinate passes over the whole path (glmnet's maxit)
  bool early_stop = true;          ///< glmnet's path exits: deviance ratio > 0.999 or gains < 1e-5 relative
  LassoAlgorithm algorithm = LassoAlgorithm::Auto;
  Eigen::VectorXd penalty_factor;  ///< pf_j >= 0 per column (0: unpenalised), empty: all 1
  /// Throws InvalidArgument naming the first field that is out of range.
  void validate() const;
};

/// A solution path.
struct LassoPath {
  Eigen::VectorXd lambda;     ///< [L] in the units of y (as glmnet reports it)
  Eigen::MatrixXd beta;       ///< [p x L] coefficients on the original scale of X
  Eigen::VectorXd a0;         ///< [L] intercepts
  Eigen::VectorXi df;         ///< [L] nonzero coefficients
  Eigen::VectorXd dev_ratio;  ///< [L] fraction of the (centred) variance of y explained
  long passes = 0;            ///< coordinate passes used
  bool converged = true;      ///< false when max_passes ran out (the path is then truncated)
  std::string message;

  /// Predictions a0 + X b at path index l; X [m x p].
  Eigen::VectorXd predict(const Eigen::Ref<const Eigen::MatrixXd>& X, int l) const;
};

/// Fits the whole lambda path. X [n x p], y [n]. Throws InvalidArgument on size mismatch,
/// non-finite data, n < 2 or invalid options.
LassoPath lasso_path(const Eigen::Ref<const Eigen::MatrixXd>& X, const Eigen::Ref<const Eigen::VectorXd>& y,
                     const LassoOptions& options);

/// How the folds' solutions are lined up with the lambdas of the path on all samples.
enum class LassoCvAlignment {
  FoldPaths,   ///< cv.glmnet's default: each fold computes its own lambda path (with the path exits),
               ///< its solutions are interpolated linearly in lambda at the full path's lambdas
  FullLambda,  ///< each fold is solved at exactly the full path's lambdas (scikit-learn's LassoCV,
               ///< and cv.glmnet when given `lambda`)
};

struct LassoCvOptions {
  LassoCvAlignment alignment = LassoCvAlignment::FoldPaths;  ///< FullLambda whenever options.lambda is given
  int nfolds = 10;             ///< K (>= 2); ignored when foldid is given
  unsigned seed = 1;           ///< fold assignment when foldid is empty: a seeded shuffle of 1..K repeated
  std::vector<int> foldid;     ///< fold of each sample, 0-based, size n (cv.glmnet's foldid - 1)
  /// Coefficients whose standardised size |b_j| sd(x_j) is below prune_ratio * sd(y) are set to
  /// zero in the chosen model (Cao: small coefficients pruned); 0 keeps all.
  double prune_ratio = 0.0;
  bool refit = false;          ///< least-squares refit on the surviving columns (relaxed Lasso)
  bool use_1se = false;        ///< choose lambda_1se instead of lambda_min
  void validate(long n) const;
};

/// Cross-validated Lasso (cv.glmnet's rules): the path is fitted on all samples, each fold is
/// fitted on the other folds over the same lambdas, the mean squared error of the held-out fold is
/// averaged over folds (weighted by fold size), lambda_min minimises it and lambda_1se is the
/// largest lambda within one standard error of the minimum.
struct LassoCvResult {
  LassoPath path;           ///< on all samples
  Eigen::VectorXd cvm;      ///< [L] mean CV squared error
  Eigen::VectorXd cvsd;     ///< [L] its standard error
  int index_min = 0, index_1se = 0;
  double lambda_min = 0.0, lambda_1se = 0.0;
  Eigen::VectorXd beta;     ///< chosen coefficients (after pruning / refit), original scale
  double a0 = 0.0;          ///< chosen intercept
  int pruned = 0;           ///< coefficients zeroed by pruning

  Eigen::VectorXd predict(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
};

/// Cross-validated Lasso for one response.
LassoCvResult cv_lasso(const Eigen::Ref<const Eigen::MatrixXd>& X, const Eigen::Ref<const Eigen::VectorXd>& y,
                       const LassoOptions& options, const LassoCvOptions& cv);

/// Cross-validated Lasso for several responses on the same design (columns of Y [n x m]), same
/// folds: the fold Gram matrices are computed once and shared (Cao eq. 20 per joint).
std::vector<LassoCvResult> cv_lasso_multi(const Eigen::Ref<const Eigen::MatrixXd>& X, const Eigen::Ref<const Eigen::MatrixXd>& Y,
                                          const LassoOptions& options, const LassoCvOptions& cv);

/// The fold assignment cv_lasso uses when foldid is empty: n values in 0..K-1, balanced, shuffled.
std::vector<int> lasso_folds(long n, int nfolds, unsigned seed);

}  // namespace twinwatch::ident
