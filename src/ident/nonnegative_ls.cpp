/// @file nonnegative_ls.cpp
/// Lawson–Hanson active set on the normal equations (see the header).
#include "twinwatch/ident/nonnegative_ls.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::ident {

namespace {

// the least-squares solution restricted to the columns in `P` (zero elsewhere), on the
// diagonally scaled subsystem; the complete orthogonal decomposition gives the minimum-norm
// solution when the chosen columns are collinear
Eigen::VectorXd solve_on(const Eigen::MatrixXd& G, const Eigen::VectorXd& g, const Eigen::VectorXd& scale,
                         const std::vector<Eigen::Index>& P) {
  const auto m = static_cast<Eigen::Index>(P.size());
  Eigen::MatrixXd Gp(m, m);
  Eigen::VectorXd gp(m);
  for (Eigen::Index a = 0; a < m; ++a) {
    gp(a) = g(P[static_cast<size_t>(a)]) / scale(P[static_cast<size_t>(a)]);
    for (Eigen::Index c = 0; c < m; ++c)
      Gp(a, c) = G(P[static_cast<size_t>(a)], P[static_cast<size_t>(c)]) /
                 (scale(P[static_cast<size_t>(a)]) * scale(P[static_cast<size_t>(c)]));
  }
  const Eigen::VectorXd zp = Gp.completeOrthogonalDecomposition().solve(gp);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(G.rows());
  for (Eigen::Index a = 0; a < m; ++a) z(P[static_cast<size_t>(a)]) = zp(a) / scale(P[static_cast<size_t>(a)]);
  return z;
}

}  // namespace

Eigen::VectorXd nonnegative_ls_normal(const Eigen::MatrixXd& G, const Eigen::VectorXd& g, const std::vector<bool>& bounded) {
  const Eigen::Index n = G.rows();
  if (G.cols() != n || g.size() != n || static_cast<Eigen::Index>(bounded.size()) != n)
    throw InvalidArgument(fmt::format("nonnegative least squares: normal matrix {}x{}, right side {}, {} bound flags "
                                      "(expected one size)",
                                      G.rows(), G.cols(), g.size(), bounded.size()));
  if (!G.allFinite() || !g.allFinite()) throw InvalidArgument("nonnegative least squares: non-finite normal equations");
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  // columns with weight take part; the scale makes the gradient test independent of column units
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(n);
  std::vector<bool> usable(static_cast<size_t>(n), false);
  for (Eigen::Index i = 0; i < n; ++i) {
    if (G(i, i) > 0.0) {
      scale(i) = std::sqrt(G(i, i));
      usable[static_cast<size_t>(i)] = true;
    }
  }
  std::vector<bool> passive(static_cast<size_t>(n), false);
  std::vector<Eigen::Index> P;
  auto rebuild = [&] {
    P.clear();
    for (Eigen::Index i = 0; i < n; ++i)
      if (passive[static_cast<size_t>(i)]) P.push_back(i);
  };
  for (Eigen::Index i = 0; i < n; ++i) passive[static_cast<size_t>(i)] = usable[static_cast<size_t>(i)] && !bounded[static_cast<size_t>(i)];
  rebuild();
  if (!P.empty()) x = solve_on(G, g, scale, P);

  double gmax = 0.0;
  for (Eigen::Index i = 0; i < n; ++i)
    if (usable[static_cast<size_t>(i)]) gmax = std::max(gmax, std::abs(g(i)) / scale(i));
  const double tol = 1e-12 * gmax;
  // each outer step adds one coefficient and the objective strictly falls, so the active set
  // never repeats; the bound is a guard against round-off cycling
  for (Eigen::Index outer = 0; outer < 3 * n + 10; ++outer) {
    const Eigen::VectorXd w = g - G * x;  // minus the gradient of |Ax - b|² / 2
    Eigen::Index add = -1;
    double best = tol;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (passive[static_cast<size_t>(i)] || !usable[static_cast<size_t>(i)] || !bounded[static_cast<size_t>(i)]) continue;
      if (w(i) / scale(i) > best) {
        best = w(i) / scale(i);
        add = i;
      }
    }
    if (add < 0) break;  // KKT: every held coefficient would raise the misfit if let go
    passive[static_cast<size_t>(add)] = true;
    rebuild();
    for (Eigen::Index inner = 0; inner <= n; ++inner) {
      const Eigen::VectorXd z = solve_on(G, g, scale, P);
      double alpha = 1.0;
      bool feasible = true;
      for (const Eigen::Index i : P) {
        if (!bounded[static_cast<size_t>(i)] || z(i) > 0.0) continue;
        feasible = false;
        const double d = x(i) - z(i);
        alpha = std::min(alpha, d > 0.0 ? x(i) / d : 0.0);
      }
      if (feasible) {
        x = z;
        break;
      }
      x += alpha * (z - x);
      for (const Eigen::Index i : P) {
        if (bounded[static_cast<size_t>(i)] && x(i) <= 0.0) {
          x(i) = 0.0;
          passive[static_cast<size_t>(i)] = false;
        }
      }
      rebuild();
      if (!passive[static_cast<size_t>(add)] && inner == 0 && alpha == 0.0) {
        // the column just let go cannot move off its bound (round-off at a degenerate KKT point)
        return x;
      }
    }
  }
  return x;
}

Eigen::VectorXd nonnegative_ls(const Eigen::MatrixXd& A, const Eigen::VectorXd& b) {
  if (A.rows() != b.size())
    throw InvalidArgument(fmt::format("nonnegative least squares: {} rows against a right side of {}", A.rows(), b.size()));
  const Eigen::MatrixXd G = A.transpose() * A;
  const Eigen::VectorXd g = A.transpose() * b;
  return nonnegative_ls_normal(G, g, std::vector<bool>(static_cast<size_t>(A.cols()), true));
}

}  // namespace twinwatch::ident
