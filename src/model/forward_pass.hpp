#pragma once
// The forward (outward) pass of the recursive Newton-Euler algorithm [Luh1980], shared by the
// RNEA and the regressor. Private header of twinwatch_model.
#include "fast_sincos.hpp"
#include "twinwatch/model/robot_model.hpp"
#include "vec3.hpp"

namespace twinwatch::model::detail {

/// sn[i], cs[i] = sin, cos of q_i + q_offset_i for every joint, two per SSE2 instruction.
inline void joint_sincos(const RobotModel& model, const VectorJ& q, double* sn, double* cs) {
  const int n = model.n_dof();
  double th[kMaxDof];
  for (int i = 0; i < n; ++i) th[i] = q[i] + model.link_cache(i).q_offset;
  fast_sincos_n(th, n, sn, cs);
}

/// Motion of every body in its own frame: R[i] = parent_R_body, W = w [rad/s], WD = wd [rad/s²],
/// A = a of the body origin including -g [m/s²]. qd / qdd may be null (taken as zero);
/// with_gravity = false starts from a_{-1} = 0 instead of -g.
///   w_i  = R_i^T w_{i-1} + qd_i z
///   wd_i = R_i^T wd_{i-1} + (R_i^T w_{i-1}) x (qd_i z) + qdd_i z
///   a_i  = R_i^T (a_{i-1} + wd_{i-1} x p_i + w_{i-1} x (w_{i-1} x p_i)),  a_{-1} = -g
/// Every joint turns about its own z axis, so the joint terms (qd z, qdd z, w x qd z) touch one or
/// two components only; they are written out instead of multiplying full vectors by e_z.
/// kAboutX: every placement is Rx(alpha) (RobotModel::placements_about_x()); then
///   R = Rx(alpha) Rz(q) = [c, -s, 0; ca s, ca c, -sa; sa s, sa c, ca]
///   R^T x = Rz^T (Rx^T x),  Rx^T x = (x0, ca x1 + sa x2, -sa x1 + ca x2)   (12 flops, not 15)
template <bool kAboutX>
inline void forward_pass_t(const RobotModel& model, const VectorJ& q, const VectorJ* qd, const VectorJ* qdd,
                           bool with_gravity, M3* R, V3* W, V3* WD, V3* A) {
  const int n = model.n_dof();
  double sn[kMaxDof], cs[kMaxDof];
  joint_sincos(model, q, sn, cs);

  // outward recursion, state in registers
  const Eigen::Vector3d& g = model.gravity();
  V3 w_prev{0, 0, 0}, wd_prev{0, 0, 0};
  V3 a_prev = with_gravity ? V3{-g.x(), -g.y(), -g.z()} : V3{0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const LinkCache& c = model.link_cache(i);
    const double qdi = qd ? (*qd)[i] : 0.0;
    const double qddi = qdd ? (*qdd)[i] : 0.0;
    const V3 p = load(c.p);
    const V3 t = a_prev + cross(wd_prev, p) + cross(w_prev, cross(w_prev, p));
    M3 Ri;
    V3 w, wd, a;
    if constexpr (kAboutX) {
      const double s = sn[i], co = cs[i], ca = c.cos_alpha, sa = c.sin_alpha;
      Ri = {{co, ca * s, sa * s}, {-s, ca * co, sa * co}, {0.0, -sa, ca}};
      const auto rot_t = [&](const V3& x) {
        const double y1 = ca * x.y + sa * x.z;
        return V3{co * x.x + s * y1, co * y1 - s * x.x, ca * x.z - sa * x.y};
      };
      w = rot_t(w_prev);
      wd = rot_t(wd_prev);
      a = rot_t(t);
    } else {
      Ri = rotate_about_z(load(c.R0), sn[i], cs[i]);
      w = mul_t(Ri, w_prev);
      wd = mul_t(Ri, wd_prev);
      a = mul_t(Ri, t);
    }
    // (R^T w_{i-1}) x (qd z) = qd (w_y, -w_x, 0), taken before w gets its own qd z
    wd.x += qdi * w.y;
    wd.y -= qdi * w.x;
    wd.z += qddi;
    w.z += qdi;
    R[i] = Ri;
    W[i] = w;
    WD[i] = wd;
    A[i] = a;
    w_prev = w;
    wd_prev = wd;
    a_prev = a;
  }
}

/// forward_pass_t with the cheaper rotation when the model allows it.
inline void forward_pass(const RobotModel& model, const VectorJ& q, const VectorJ* qd, const VectorJ* qdd,
                         bool with_gravity, M3* R, V3* W, V3* WD, V3* A) {
  if (model.placements_about_x())
    forward_pass_t<true>(model, q, qd, qdd, with_gravity, R, W, WD, A);
  else
    forward_pass_t<false>(model, q, qd, qdd, with_gravity, R, W, WD, A);
}

}  // namespace twinwatch::model::detail
