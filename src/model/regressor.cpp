#include "twinwatch/model/regressor.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <array>
#include <cmath>
#include <random>

#include "fast_sincos.hpp"
#include "twinwatch/core/error.hpp"

namespace twinwatch::model {

namespace {

using detail::rotate_about_z;


}  // namespace

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

  // forward pass as in the RNEA: w, wd, a (a includes -g) of every body in its own frame
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d w_prev = Eigen::Vector3d::Zero(), wd_prev = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_prev = -model.gravity();
  for (int i = 0; i < n; ++i) {
    const detail::LinkCache& c = model.link_cache(i);
    rotate_about_z(c.R0, q[i] + c.q_offset, d.R[i]);
    const Eigen::Matrix3d& R = d.R[i];
    const Eigen::Vector3d w_in = R.transpose() * w_prev;
    d.w[i] = w_in + qd[i] * z;
    d.wd[i] = R.transpose() * wd_prev + w_in.cross(qd[i] * z) + qdd[i] * z;
    d.a[i] = R.transpose() * (a_prev + wd_prev.cross(c.p) + w_prev.cross(w_prev.cross(c.p)));
    w_prev = d.w[i];
    wd_prev = d.wd[i];
    a_prev = d.a[i];
  }

  // each link's body wrench is linear in its parameters:
  //   F = [a, [wd]x + [w]x[w]x, 0] pi,   N = [0, -[a]x, L(wd) + [w]x L(w)] pi
  // and joint j (<= i) feels  Y(j, link i) = S_j^T [F; N]  with S_j = (v, u) the unit twist of
  // joint j expressed in body i: u = z_j, v = z_j x (o_i - o_j). S_j is carried from body to body
  //   u' = R^T u,  v' = R^T (v + u x p)
  // which is O(n^2) 6-vectors instead of O(n^2) 6x10 wrench blocks.
  std::array<Eigen::Vector3d, kMaxDof> u, v;
  for (int i = 0; i < n; ++i) {
    if (i > 0) {
      const Eigen::Matrix3d& R = d.R[i];
      const Eigen::Vector3d& p = model.link_cache(i).p;
      for (int j = 0; j < i; ++j) {
        v[j] = R.transpose() * (v[j] + u[j].cross(p));
        u[j] = R.transpose() * u[j];
      }
    }
    u[i] = z;
    v[i].setZero();
    const Eigen::Vector3d w = d.w[i];
    const Eigen::Vector3d wd = d.wd[i];
    const Eigen::Vector3d a = d.a[i];
    const double ww = w.squaredNorm();
    double* col = &Y(0, 10 * i);  // column-major: Y(j, 10 i + c) = col[c * ld + j]
    const Eigen::Index ld = Y.outerStride();
    for (int j = 0; j <= i; ++j) {
      // Y(j, link i) = v . F + u . N with F = m a + ([wd]x + [w]x[w]x) h and
      // N = h x a + I wd + w x (I w), written out so that nothing spills:
      //   mass:           v . a
      //   first moment:   w (w . v) - |w|^2 v + v x wd + a x u
      //   inertia (sym):  u^T I wd + s^T I w,  s = u x w
      const Eigen::Vector3d& vj = v[j];
      const Eigen::Vector3d& uj = u[j];
      col[j] = vj.dot(a);
      const Eigen::Vector3d hp = w * w.dot(vj) - ww * vj + vj.cross(wd) + a.cross(uj);
      col[1 * ld + j] = hp.x();
      col[2 * ld + j] = hp.y();
      col[3 * ld + j] = hp.z();
      const Eigen::Vector3d sj = uj.cross(w);
      col[4 * ld + j] = uj.x() * wd.x() + sj.x() * w.x();
      col[5 * ld + j] = uj.x() * wd.y() + uj.y() * wd.x() + sj.x() * w.y() + sj.y() * w.x();
      col[6 * ld + j] = uj.x() * wd.z() + uj.z() * wd.x() + sj.x() * w.z() + sj.z() * w.x();
      col[7 * ld + j] = uj.y() * wd.y() + sj.y() * w.y();
      col[8 * ld + j] = uj.y() * wd.z() + uj.z() * wd.y() + sj.y() * w.z() + sj.z() * w.y();
      col[9 * ld + j] = uj.z() * wd.z() + sj.z() * w.z();
    }
    // joints after i do not feel link i
    for (int c = 0; c < 10; ++c)
      for (int j = i + 1; j < n; ++j) col[c * ld + j] = 0.0;
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
