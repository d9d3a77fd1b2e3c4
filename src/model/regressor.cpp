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


inline Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return S;
}

// I_o x written as L(x) [Ixx Ixy Ixz Iyy Iyz Izz]^T
inline Eigen::Matrix<double, 3, 6> inertia_map(const Eigen::Vector3d& x) {
  Eigen::Matrix<double, 3, 6> L;
  L << x(0), x(1), x(2), 0, 0, 0, 0, x(0), 0, x(1), x(2), 0, 0, 0, x(0), 0, x(1), x(2);
  return L;
}

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
  Y.setZero(n, 10 * n + kf * n);

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
    const Eigen::Vector3d& w = d.w[i];
    const Eigen::Vector3d& wd = d.wd[i];
    const Eigen::Vector3d& a = d.a[i];
    const Eigen::Matrix3d Sw = skew(w);
    // the wrench map's blocks, using its sparsity (column 0 has no moment, columns 4-9 no force):
    //   F = m a + A1 h,  N = -[a]x h + B6 I
    const Eigen::Matrix3d A1 = skew(wd) + Sw * Sw;
    const Eigen::Matrix<double, 3, 6> B6 = inertia_map(wd) + Sw * inertia_map(w);
    const Eigen::Matrix3d A1t = A1.transpose();
    const Eigen::Matrix<double, 6, 3> B6t = B6.transpose();
    for (int j = 0; j <= i; ++j) {
      // Y(j, link i) = v . F + u . N, column block by column block
      const Eigen::Vector3d& vj = v[j];
      const Eigen::Vector3d& uj = u[j];
      Y(j, 10 * i) = vj.dot(a);
      const Eigen::Vector3d h_part = A1t * vj + a.cross(uj);  // A1^T v - [a]x^T u = A1^T v + a x u
      Y(j, 10 * i + 1) = h_part.x();
      Y(j, 10 * i + 2) = h_part.y();
      Y(j, 10 * i + 3) = h_part.z();
      const Eigen::Matrix<double, 6, 1> i_part = B6t * uj;
      for (int c = 0; c < 6; ++c) Y(j, 10 * i + 4 + c) = i_part(c);
    }
  }

  // friction columns on the joint's own row
  if (kf > 0) {
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
