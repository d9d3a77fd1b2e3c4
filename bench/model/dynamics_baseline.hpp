#pragma once
// The kernels as they were before the issue-2 rewrite (commit 4af293c), kept verbatim as the
// benchmark baseline: Eigen 3-vectors through DynamicsData, one scalar sincos per joint (with its
// quadrant switch), the regressor's twist loop over j one joint at a time. Benchmark only.
#include <array>
#include <cmath>

#include "twinwatch/core/error.hpp"

#include "twinwatch/model/dynamics.hpp"
#include "twinwatch/model/regressor.hpp"

namespace twinwatch::model::baseline {

inline void fast_sincos(double x, double& s, double& c) {
  // beyond this the 3-part reduction loses bits; joint angles never get there
  constexpr double kFastRange = 1e5;
  if (!(std::abs(x) < kFastRange)) {
    s = std::sin(x);
    c = std::cos(x);
    return;
  }
  constexpr double kTwoOverPi = 0.63661977236758134308;
  // pi/2 = P1 + P2 + P3 (Cody–Waite; P1, P2 have trailing zero bits so k * Pi is exact)
  constexpr double P1 = 1.5707963267341256e+00;
  constexpr double P2 = 6.0771005065061922e-11;
  constexpr double P3 = 2.0222662487959506e-21;
  const double k = std::floor(x * kTwoOverPi + 0.5);
  const double r = ((x - k * P1) - k * P2) - k * P3;
  const double r2 = r * r;
  // minimax polynomials of fdlibm's __kernel_sin / __kernel_cos (|r| <= pi/4, error < 1 ulp
  // of the polynomial); two short independent Horner chains
  constexpr double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                   S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                   S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
  constexpr double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                   C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                   C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
  const double r4 = r2 * r2;
  const double sr = r + r * r2 * (S1 + r2 * (S2 + r2 * S3) + r4 * r2 * (S4 + r2 * (S5 + r2 * S6)));
  const double hz = 0.5 * r2;
  const double w = 1.0 - hz;
  const double cpoly = r4 * (C1 + r2 * (C2 + r2 * C3) + r4 * r2 * (C4 + r2 * (C5 + r2 * C6)));
  // fdlibm's compensation: cos = w + (((1 - w) - hz) + cpoly)
  const double cr = w + (((1.0 - w) - hz) + cpoly);
  // quadrant
  const long q = static_cast<long>(k) & 3;
  switch (q) {
    case 0: s = sr; c = cr; break;
    case 1: s = cr; c = -sr; break;
    case 2: s = -sr; c = -cr; break;
    default: s = -cr; c = sr; break;
  }
}

// parent_R_body = R0 * Rz(theta), written column by column (Rz only mixes columns 0 and 1)
inline void rotate_about_z(const Eigen::Matrix3d& R0, double theta, Eigen::Matrix3d& R) {
  double s, c;
  fast_sincos(theta, s, c);
  R.col(0) = c * R0.col(0) + s * R0.col(1);
  R.col(1) = c * R0.col(1) - s * R0.col(0);
  R.col(2) = R0.col(2);
}

inline void rnea_impl(const RobotModel& model, DynamicsData& d, const VectorJ& q, const VectorJ* qd, const VectorJ* qdd,
                 bool with_gravity) {
  const int n = model.n_dof();
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();

  // forward pass: velocities and accelerations of every body, in its own frame
  //   w_i  = R_i^T w_{i-1} + qd_i z
  //   wd_i = R_i^T wd_{i-1} + (R_i^T w_{i-1}) x (qd_i z) + qdd_i z
  //   a_i  = R_i^T (a_{i-1} + wd_{i-1} x p_i + w_{i-1} x (w_{i-1} x p_i)),  a_{-1} = -g
  Eigen::Vector3d w_prev = Eigen::Vector3d::Zero();
  Eigen::Vector3d wd_prev = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_prev = with_gravity ? Eigen::Vector3d(-model.gravity()) : Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const detail::LinkCache& c = model.link_cache(i);
    Eigen::Matrix3d& R = d.R[i];
    rotate_about_z(c.R0, q[i] + c.q_offset, R);
    const double qdi = qd ? (*qd)[i] : 0.0;
    const double qddi = qdd ? (*qdd)[i] : 0.0;
    const Eigen::Vector3d w_in = R.transpose() * w_prev;
    d.w[i] = w_in + qdi * z;
    d.wd[i] = R.transpose() * wd_prev + w_in.cross(qdi * z) + qddi * z;
    d.a[i] = R.transpose() * (a_prev + wd_prev.cross(c.p) + w_prev.cross(w_prev.cross(c.p)));
    w_prev = d.w[i];
    wd_prev = d.wd[i];
    a_prev = d.a[i];
  }

  // backward pass: body wrenches about the body origin, accumulated towards the base
  //   F_i = m a_i + wd_i x h + w_i x (w_i x h)
  //   N_i = I_o wd_i + w_i x (I_o w_i) + h x a_i
  //   f_i = F_i + R_{i+1} f_{i+1};  n_i = N_i + R_{i+1} n_{i+1} + p_{i+1} x (R_{i+1} f_{i+1})
  //   tau_i = z . n_i
  d.tau.resize(n);
  Eigen::Vector3d f_child = Eigen::Vector3d::Zero();
  Eigen::Vector3d n_child = Eigen::Vector3d::Zero();
  for (int i = n - 1; i >= 0; --i) {
    const detail::LinkCache& c = model.link_cache(i);
    const Eigen::Vector3d& w = d.w[i];
    const Eigen::Vector3d& wd = d.wd[i];
    const Eigen::Vector3d& a = d.a[i];
    const Eigen::Vector3d Iw = c.I_o * w;
    d.f[i] = c.m * a + wd.cross(c.h) + w.cross(w.cross(c.h)) + f_child;
    d.n[i] = c.I_o * wd + w.cross(Iw) + c.h.cross(a) + n_child;
    d.tau[i] = d.n[i].z();
    if (i > 0) {
      // express this body's wrench in the parent frame, moment about the parent origin
      f_child = d.R[i] * d.f[i];
      n_child = d.R[i] * d.n[i] + c.p.cross(f_child);
    }
  }
}

// the public rnea() of 4af293c: size checks, then the recursion
inline const VectorJ& rnea(const RobotModel& model, DynamicsData& d, const VectorJ& q, const VectorJ& qd,
                           const VectorJ& qdd) {
  check_size("q", q.size(), model.n_dof(), "model.n_dof");
  check_size("qd", qd.size(), model.n_dof(), "model.n_dof");
  check_size("qdd", qdd.size(), model.n_dof(), "model.n_dof");
  rnea_impl(model, d, q, &qd, &qdd, true);
  return d.tau;
}

// regressor() of 4af293c without the friction columns (the benchmark uses none)
inline void regressor(const RobotModel& model, DynamicsData& d, const VectorJ& q, const VectorJ& qd,
                      const VectorJ& qdd, RegressorMatrix& Y) {
  const int n = model.n_dof();
  check_size("q", q.size(), n, "model.n_dof");
  check_size("qd", qd.size(), n, "model.n_dof");
  check_size("qdd", qdd.size(), n, "model.n_dof");
  // every entry is written below (the zero ones explicitly): no full setZero of the 5 KB buffer
  Y.resize(n, 10 * n);

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
}

}  // namespace twinwatch::model::baseline
