#include "twinwatch/model/regressor.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <array>
#include <cmath>
#include <random>

#include "forward_pass.hpp"
#include "vec3.hpp"
#include "twinwatch/core/error.hpp"

namespace twinwatch::model {

int friction_columns_per_joint(FrictionColumns f) {
  switch (f) {
    case FrictionColumns::None: return 0;
    case FrictionColumns::CoulombViscous: return 2;
    case FrictionColumns::CoulombViscousOffset: return 3;
  }
  return 0;
}

void regressor(const RobotModel& model, DynamicsData& d, const VectorJ& q, const VectorJ& qd, const VectorJ& qdd,
               RegressorMatrix& Y, FrictionColumns friction) {
  const int n = model.n_dof();
  check_size("q", q.size(), n, "model.n_dof");
  check_size("qd", qd.size(), n, "model.n_dof");
  check_size("qdd", qdd.size(), n, "model.n_dof");
  const int kf = friction_columns_per_joint(friction);
  // every entry is written below (the zero ones explicitly): no full setZero of the 5 KB buffer
  Y.resize(n, 10 * n + kf * n);

  // forward pass as in the RNEA: R, w, wd, a (a includes -g) of every body in its own frame
  using detail::M3;
  using detail::V3;
  M3 R[kMaxDof];
  V3 W[kMaxDof], WD[kMaxDof], A[kMaxDof];
  detail::forward_pass(model, q, &qd, &qdd, true, R, W, WD, A);
  for (int i = 0; i < n; ++i) {
    detail::store(R[i], d.R[i]);
    detail::store(W[i], d.w[i]);
    detail::store(WD[i], d.wd[i]);
    detail::store(A[i], d.a[i]);
  }

  // each link's body wrench is linear in its parameters:
  //   F = [a, [wd]x + [w]x[w]x, 0] pi,   N = [0, -[a]x, L(wd) + [w]x L(w)] pi
  // and joint j (<= i) feels  Y(j, link i) = S_j^T [F; N]  with S_j = (v, u) the unit twist of
  // joint j expressed in body i: u = z_j, v = z_j x (o_i - o_j). S_j is carried from body to body
  //   u' = R^T u,  v' = R^T (v + u x p)
  // which is O(n^2) 6-vectors instead of O(n^2) 6x10 wrench blocks. The twists are stored by
  // component (structure of arrays) so that the loops over j run two joints per SSE2 instruction
  // and write contiguous runs of Y's column-major storage.
  // Joints after i do not feel link i: their twists stay zero until they are reached, so the same
  // loop writes the zero rows below i (exact zeros for finite inputs) without a branch or a
  // memset per column.
  alignas(16) double ux[kMaxDof] = {}, uy[kMaxDof] = {}, uz[kMaxDof] = {}, vx[kMaxDof] = {}, vy[kMaxDof] = {},
                     vz[kMaxDof] = {};
  double* const Yd = Y.data();
  const Eigen::Index ld = Y.outerStride();
  for (int i = 0; i < n; ++i) {
    // carry the twists of joints 0..i-1 into body i
    if (i > 0) {
      const M3 Ri = R[i];
      const V3 p = detail::load(model.link_cache(i).p);
      for (int j = 0; j < i; ++j) {
        const double tx = vx[j] + (uy[j] * p.z - uz[j] * p.y);
        const double ty = vy[j] + (uz[j] * p.x - ux[j] * p.z);
        const double tz = vz[j] + (ux[j] * p.y - uy[j] * p.x);
        const double sx = ux[j], sy = uy[j], sz = uz[j];
        vx[j] = Ri.c0.x * tx + Ri.c0.y * ty + Ri.c0.z * tz;
        vy[j] = Ri.c1.x * tx + Ri.c1.y * ty + Ri.c1.z * tz;
        vz[j] = Ri.c2.x * tx + Ri.c2.y * ty + Ri.c2.z * tz;
        ux[j] = Ri.c0.x * sx + Ri.c0.y * sy + Ri.c0.z * sz;
        uy[j] = Ri.c1.x * sx + Ri.c1.y * sy + Ri.c1.z * sz;
        uz[j] = Ri.c2.x * sx + Ri.c2.y * sy + Ri.c2.z * sz;
      }
    }
    // joint i's own twist in body i: u = z, v = 0
    uz[i] = 1.0;

    // Y(j, link i) = v . F + u . N with F = m a + ([wd]x + [w]x[w]x) h and
    // N = h x a + I wd + w x (I w), written out per column:
    //   mass:           v . a
    //   first moment:   w (w . v) - |w|^2 v + v x wd + a x u
    //   inertia (sym):  u^T I wd + s^T I w,  s = u x w
    const V3 w = W[i], wd = WD[i], a = A[i];
    const double ww = dot(w, w);
    double* const c0 = Yd + 10 * i * ld;  // Y(j, 10 i + k) = c0[k * ld + j]
    double* const c1 = c0 + ld;
    double* const c2 = c0 + 2 * ld;
    double* const c3 = c0 + 3 * ld;
    double* const c4 = c0 + 4 * ld;
    double* const c5 = c0 + 5 * ld;
    double* const c6 = c0 + 6 * ld;
    double* const c7 = c0 + 7 * ld;
    double* const c8 = c0 + 8 * ld;
    double* const c9 = c0 + 9 * ld;
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC ivdep  // the ten columns never overlap (GCC would need > 10 run-time alias checks)
#endif
    for (int j = 0; j < n; ++j) {
      const double Ux = ux[j], Uy = uy[j], Uz = uz[j], Vx = vx[j], Vy = vy[j], Vz = vz[j];
      c0[j] = Vx * a.x + Vy * a.y + Vz * a.z;
      const double wv = w.x * Vx + w.y * Vy + w.z * Vz;
      c1[j] = w.x * wv - ww * Vx + (Vy * wd.z - Vz * wd.y) + (a.y * Uz - a.z * Uy);
      c2[j] = w.y * wv - ww * Vy + (Vz * wd.x - Vx * wd.z) + (a.z * Ux - a.x * Uz);
      c3[j] = w.z * wv - ww * Vz + (Vx * wd.y - Vy * wd.x) + (a.x * Uy - a.y * Ux);
      const double sx = Uy * w.z - Uz * w.y, sy = Uz * w.x - Ux * w.z, sz = Ux * w.y - Uy * w.x;
      c4[j] = Ux * wd.x + sx * w.x;
      c5[j] = Ux * wd.y + Uy * wd.x + sx * w.y + sy * w.x;
      c6[j] = Ux * wd.z + Uz * wd.x + sx * w.z + sz * w.x;
      c7[j] = Uy * wd.y + sy * w.y;
      c8[j] = Uy * wd.z + Uz * wd.y + sy * w.z + sz * w.y;
      c9[j] = Uz * wd.z + sz * w.z;
    }
  }

  // friction columns on the joint's own row
  if (kf > 0) {
    Y.rightCols(kf * n).setZero();
    for (int j = 0; j < n; ++j) {
      const int col = 10 * n + kf * j;
      Y(j, col) = qd[j] > 0.0 ? 1.0 : (qd[j] < 0.0 ? -1.0 : 0.0);
      Y(j, col + 1) = qd[j];
      if (kf == 3) Y(j, col + 2) = 1.0;
    }
  }
}

Eigen::VectorXd standard_parameters(const RobotModel& model, FrictionColumns friction) {
  const int n = model.n_dof();
  const int kf = friction_columns_per_joint(friction);
  Eigen::VectorXd pi = Eigen::VectorXd::Zero(10 * n + kf * n);
  for (int i = 0; i < n; ++i) {
    const detail::LinkCache& c = model.link_cache(i);
    pi(10 * i) = c.m;
    pi.segment<3>(10 * i + 1) = c.h;
    pi.segment<6>(10 * i + 4) << c.I_o(0, 0), c.I_o(0, 1), c.I_o(0, 2), c.I_o(1, 1), c.I_o(1, 2), c.I_o(2, 2);
  }
  return pi;
}

Eigen::VectorXd BaseParameters::base_values(const Eigen::VectorXd& pi) const {
  check_size("pi", pi.size(), n_standard, "BaseParameters.n_standard");
  Eigen::VectorXd beta(rank), dep(static_cast<Eigen::Index>(dependent.size()));
  for (int k = 0; k < rank; ++k) beta(k) = pi(independent[static_cast<size_t>(k)]);
  for (size_t k = 0; k < dependent.size(); ++k) dep(static_cast<Eigen::Index>(k)) = pi(dependent[k]);
  if (dep.size() > 0) beta += K_d * dep;
  return beta;
}

Eigen::MatrixXd BaseParameters::base_regressor(const RegressorMatrix& Y) const {
  check_size("Y columns", Y.cols(), n_standard, "BaseParameters.n_standard");
  Eigen::MatrixXd Yb(Y.rows(), rank);
  for (int k = 0; k < rank; ++k) Yb.col(k) = Y.col(independent[static_cast<size_t>(k)]);
  return Yb;
}

Eigen::VectorXd BaseParameters::standard_from_base(const Eigen::VectorXd& beta) const {
  check_size("beta", beta.size(), rank, "BaseParameters.rank");
  Eigen::VectorXd pi = Eigen::VectorXd::Zero(n_standard);
  for (int k = 0; k < rank; ++k) pi(independent[static_cast<size_t>(k)]) = beta(k);
  return pi;
}

void BaseParameterOptions::validate() const {
  if (n_states < 1) throw InvalidArgument(fmt::format("n_states is {}, must be >= 1", n_states));
  if (!(relative_tolerance > 0.0 && relative_tolerance < 1.0))
    throw InvalidArgument(fmt::format("relative_tolerance is {}, must be in (0, 1)", relative_tolerance));
}

BaseParameters compute_base_parameters(const RobotModel& model, FrictionColumns friction,
                                       const BaseParameterOptions& options) {
  options.validate();
  const int n = model.n_dof();
  DynamicsData d(model);
  RegressorMatrix Y;
  const int p = 10 * n + friction_columns_per_joint(friction) * n;
  // stack Y over random states spanning the joint ranges (positions), velocities and accelerations
  Eigen::MatrixXd W(static_cast<Eigen::Index>(options.n_states) * n, p);
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int s = 0; s < options.n_states; ++s) {
    VectorJ q(n), qd(n), qdd(n);
    for (int i = 0; i < n; ++i) q[i] = M_PI * u(rng), qd[i] = 2.0 * u(rng), qdd[i] = 5.0 * u(rng);
    regressor(model, d, q, qd, qdd, Y, friction);
    W.middleRows(static_cast<Eigen::Index>(s) * n, n) = Y;
  }
  // column scaling would change which columns are picked; keep raw columns so that the choice
  // favours the physically large ones (as the classic numeric procedure does)
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(W);
  const Eigen::MatrixXd R = qr.matrixR().topLeftCorner(std::min(W.rows(), W.cols()), p).template triangularView<Eigen::Upper>();
  const double r00 = std::abs(R(0, 0));
  BaseParameters b;
  b.n_standard = p;
  b.tolerance = options.relative_tolerance * r00;
  int r = 0;
  while (r < R.rows() && std::abs(R(r, r)) > b.tolerance) ++r;
  b.rank = r;
  const auto& perm = qr.colsPermutation().indices();
  for (int k = 0; k < p; ++k) (k < r ? b.independent : b.dependent).push_back(perm(k));
  // K_d = R1^-1 R2: every dependent column = independent columns times K_d
  const Eigen::MatrixXd R1 = R.topLeftCorner(r, r);
  const Eigen::MatrixXd R2 = R.block(0, r, r, p - r);
  b.K_d = R1.triangularView<Eigen::Upper>().solve(R2);
  // entries of K_d that are round-off (columns exactly dependent by structure): clean to zero
  b.K_d = b.K_d.unaryExpr([](double v) { return std::abs(v) < 1e-10 ? 0.0 : v; });
  return b;
}

}  // namespace twinwatch::model
