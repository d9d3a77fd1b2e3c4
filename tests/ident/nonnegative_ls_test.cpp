// Nonnegative least squares with free columns: the active-set solution against the exhaustive
// one (every subset of held coefficients solved, the best feasible kept), on random problems.
#include "twinwatch/ident/nonnegative_ls.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <limits>
#include <random>

#include "twinwatch/core/error.hpp"

namespace twinwatch::ident {
namespace {

// the minimum of |A x - b|² over x_i >= 0 (i bounded), by trying every set of bounded
// coefficients held at zero: the optimum is the unconstrained fit on one of those faces
double exhaustive_min(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, const std::vector<bool>& bounded) {
  const auto n = A.cols();
  double best = std::numeric_limits<double>::infinity();
  for (long mask = 0; mask < (1L << n); ++mask) {
    std::vector<Eigen::Index> keep;
    bool ok = true;
    for (Eigen::Index i = 0; i < n; ++i) {
      const bool held = (mask >> i) & 1;
      if (held && !bounded[static_cast<size_t>(i)]) ok = false;
      if (!held) keep.push_back(i);
    }
    if (!ok) continue;
    Eigen::MatrixXd Ak(A.rows(), static_cast<Eigen::Index>(keep.size()));
    for (size_t c = 0; c < keep.size(); ++c) Ak.col(static_cast<Eigen::Index>(c)) = A.col(keep[c]);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
    if (!keep.empty()) {
      const Eigen::VectorXd xk = Ak.colPivHouseholderQr().solve(b);
      for (size_t c = 0; c < keep.size(); ++c) x(keep[c]) = xk(static_cast<Eigen::Index>(c));
    }
    bool feasible = true;
    for (Eigen::Index i = 0; i < n; ++i) feasible &= !bounded[static_cast<size_t>(i)] || x(i) >= -1e-12;
    if (feasible) best = std::min(best, (A * x - b).squaredNorm());
  }
  return best;
}

TEST(NonnegativeLs, MatchesTheExhaustiveOptimumOnRandomProblemsWithFreeColumns) {
  std::mt19937 rng(7);
  std::normal_distribution<double> N(0.0, 1.0);
  int held_somewhere = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 1 + trial % 5, m = 3 + trial % 17;
    Eigen::MatrixXd A(m, n);
    for (int r = 0; r < m; ++r)
      for (int c = 0; c < n; ++c) A(r, c) = N(rng) * (c + 1.0) * (trial % 3 == 0 ? 1e3 : 1.0);  // columns of other units
    if (trial % 4 == 1 && n >= 2) A.col(1) = A.col(0) * 0.999 + 0.001 * A.col(1);  // nearly collinear
    Eigen::VectorXd b(m);
    for (int r = 0; r < m; ++r) b(r) = N(rng);
    std::vector<bool> bounded(static_cast<size_t>(n), true);
    if (trial % 2 == 0) bounded[static_cast<size_t>(n - 1)] = false;  // an offset left free
    const Eigen::VectorXd x = nonnegative_ls_normal(A.transpose() * A, A.transpose() * b, bounded);
    for (int i = 0; i < n; ++i) {
      if (bounded[static_cast<size_t>(i)]) {
        EXPECT_GE(x(i), 0.0) << "trial " << trial;
        if (x(i) == 0.0) ++held_somewhere;
      }
    }
    const double ref = exhaustive_min(A, b, bounded);
    EXPECT_LE((A * x - b).squaredNorm(), ref * (1.0 + 1e-9) + 1e-12) << "trial " << trial;
  }
  EXPECT_GT(held_somewhere, 100);  // the bounds were active often: the test exercises them
}

TEST(NonnegativeLs, ReturnsTheFreeSolutionWhenItIsFeasibleAndZeroForAnEmptyColumn) {
  Eigen::MatrixXd A(4, 3);
  A << 1, 0, 0, 1, 1, 0, 1, 2, 0, 1, 3, 0;
  const Eigen::Vector4d b(1.0, 3.0, 5.0, 7.0);  // 1 + 2 t, exactly
  const Eigen::VectorXd x = nonnegative_ls(A, b);
  EXPECT_NEAR(x(0), 1.0, 1e-12);
  EXPECT_NEAR(x(1), 2.0, 1e-12);
  EXPECT_EQ(x(2), 0.0);
  // friction that would push the motion along: the Coulomb level is held, the viscous one refits
  Eigen::MatrixXd F(4, 2);
  F << 1, 0.5, 1, 1.0, -1, -0.5, -1, -1.0;
  const Eigen::Vector4d tau(-0.2 + 1.0, -0.2 + 2.0, 0.2 - 1.0, 0.2 - 2.0);  // Fc = -0.2, Fv = 2
  const Eigen::VectorXd f = nonnegative_ls(F, tau);
  EXPECT_EQ(f(0), 0.0);
  // with Fc held at 0: Fv = sum(v tau) / sum(v²)
  EXPECT_NEAR(f(1), (0.5 * 0.8 + 1.0 * 1.8 + 0.5 * 0.8 + 1.0 * 1.8) / 2.5, 1e-12);
}

TEST(NonnegativeLs, RefusesMismatchedSizesAndNonFiniteInput) {
  const Eigen::MatrixXd G = Eigen::MatrixXd::Identity(2, 2);
  EXPECT_THROW(nonnegative_ls_normal(G, Eigen::VectorXd::Zero(3), {true, true}), InvalidArgument);
  EXPECT_THROW(nonnegative_ls_normal(G, Eigen::VectorXd::Zero(2), {true}), InvalidArgument);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(2);
  g(1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(nonnegative_ls_normal(G, g, {true, true}), InvalidArgument);
  EXPECT_THROW(nonnegative_ls(Eigen::MatrixXd::Zero(3, 2), Eigen::VectorXd::Zero(2)), InvalidArgument);
}

}  // namespace
}  // namespace twinwatch::ident
