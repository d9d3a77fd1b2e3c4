#include "twinwatch/model/dynamics.hpp"

#include "fast_sincos.hpp"
#include "forward_pass.hpp"
#include "vec3.hpp"
#include <fmt/format.h>

#include <limits>

#include "twinwatch/core/error.hpp"

namespace twinwatch::model {

namespace {

using detail::rotate_about_z;

inline void check_q(const RobotModel& model, const VectorJ& q) { check_size("q", q.size(), model.n_dof(), "model.n_dof"); }

// core recursion shared by rnea / gravity / coriolis: null qd / qdd and with_gravity = false
// switch the velocity, acceleration and gravity terms off. The recursion state is kept in plain
// locals (vec3.hpp); the workspace only receives copies.
// (The backward pass rotates with the full R even for DH placements: the Rx(alpha) form saved
// 2 % of the instructions there and nothing measurable in time.)
// kPair (rnea_pair): also tau2 at the acceleration qdd2. tau is linear in qdd, tau(qdd2) = tau(qdd)
// + M(q) (qdd2 - qdd), and M(q) dqdd is a Newton-Euler pass with qd = 0 and no gravity over the
// same rotations:
//   dwd_i = R_i^T dwd_{i-1} + dqdd_i z,   da_i = R_i^T (da_{i-1} + dwd_{i-1} x p_i)
//   df_i  = m da_i + dwd_i x h + R_{i+1} df_{i+1}
//   dn_i  = I_o dwd_i + h x da_i + R_{i+1} dn_{i+1} + p_{i+1} x (R_{i+1} df_{i+1})
// reusing the sines, cosines, rotations and every velocity term, so the second torque costs about
// half an RNEA (docs/benchmarks.md, issue 7: the monitor's current residual and its observer).
template <bool kPair>
void rnea_impl(const RobotModel& model, DynamicsData& d, const VectorJ& q, const VectorJ* qd, const VectorJ* qdd,
               bool with_gravity, const VectorJ* qdd2 = nullptr, VectorJ* tau2 = nullptr) {
  using detail::V3;
  using detail::M3;
  const int n = model.n_dof();

  // forward pass: R, w, wd, a of every body in its own frame (forward_pass.hpp)
  M3 R[kMaxDof];
  V3 W[kMaxDof], WD[kMaxDof], A[kMaxDof];
  detail::forward_pass(model, q, qd, qdd, with_gravity, R, W, WD, A);
  [[maybe_unused]] V3 DWD[kMaxDof], DA[kMaxDof];  // the acceleration step's motion (kPair)
  if constexpr (kPair) {
    V3 dwd_prev{0, 0, 0}, da_prev{0, 0, 0};
    for (int i = 0; i < n; ++i) {
      V3 dwd = detail::mul_t(R[i], dwd_prev);
      dwd.z += (*qdd2)[i] - (*qdd)[i];
      da_prev = detail::mul_t(R[i], da_prev + cross(dwd_prev, detail::load(model.link_cache(i).p)));
      DA[i] = da_prev;
      DWD[i] = dwd_prev = dwd;
    }
    tau2->resize(n);
  }

  // backward pass: body wrenches about the body origin, accumulated towards the base
  //   F_i = m a_i + wd_i x h + w_i x (w_i x h)
  //   N_i = I_o wd_i + w_i x (I_o w_i) + h x a_i
  //   f_i = F_i + R_{i+1} f_{i+1};  n_i = N_i + R_{i+1} n_{i+1} + p_{i+1} x (R_{i+1} f_{i+1})
  //   tau_i = z . n_i
  d.tau.resize(n);
  V3 f_child{0, 0, 0}, n_child{0, 0, 0}, df_child{0, 0, 0}, dn_child{0, 0, 0};
  for (int i = n - 1; i >= 0; --i) {
    const detail::LinkCache& c = model.link_cache(i);
    const V3 w = W[i], wd = WD[i], a = A[i];
    const V3 h = detail::load(c.h);
    const detail::S3 I = detail::load_sym(c.I_o);
    const V3 f = c.m * a + cross(wd, h) + cross(w, cross(w, h)) + f_child;
    const V3 nn = mul(I, wd) + cross(w, mul(I, w)) + cross(h, a) + n_child;
    d.tau[i] = nn.z;
    [[maybe_unused]] V3 df{0, 0, 0}, dn{0, 0, 0};
    if constexpr (kPair) {
      df = c.m * DA[i] + cross(DWD[i], h) + df_child;
      dn = mul(I, DWD[i]) + cross(h, DA[i]) + dn_child;
      (*tau2)[i] = nn.z + dn.z;
    }
    // the workspace keeps every body's motion and wrench (documented in DynamicsData); the paired
    // pass returns torques only (its one caller, the monitor's twin, reads nothing else), which
    // saves the 6 x 3-12 stores per body
    if constexpr (!kPair) {
      detail::store(R[i], d.R[i]);
      detail::store(w, d.w[i]);
      detail::store(wd, d.wd[i]);
      detail::store(a, d.a[i]);
      detail::store(f, d.f[i]);
      detail::store(nn, d.n[i]);
    }
    if (i > 0) {
      // express this body's wrench in the parent frame, moment about the parent origin
      const V3 p = detail::load(c.p);
      f_child = mul(R[i], f);
      n_child = mul(R[i], nn) + cross(p, f_child);
      if constexpr (kPair) {
        df_child = mul(R[i], df);
        dn_child = mul(R[i], dn) + cross(p, df_child);
      }
    }
  }
}

}  // namespace

DynamicsData::DynamicsData(const RobotModel& model) : n_dof(model.n_dof()) {
  for (int i = 0; i < kMaxDof; ++i) {
    R[i].setIdentity();
    w[i].setZero();
    wd[i].setZero();
    a[i].setZero();
    f[i].setZero();
    n[i].setZero();
    mc[i] = 0.0;
    hc[i].setZero();
    Ic[i].setZero();
    oMi[i].setIdentity();
  }
  oMf.setIdentity();
  tau = VectorJ::Zero(n_dof);
  qdd = VectorJ::Zero(n_dof);
  M = MatrixJ::Zero(n_dof, n_dof);
  llt.compute(MatrixJ::Identity(n_dof, n_dof));
}

const Eigen::Isometry3d& forward_kinematics(const RobotModel& model, DynamicsData& d, const VectorJ& q) {
  check_q(model, q);
  double sn[kMaxDof], cs[kMaxDof];
  detail::joint_sincos(model, q, sn, cs);
  Eigen::Isometry3d parent = Eigen::Isometry3d::Identity();
  for (int i = 0; i < model.n_dof(); ++i) {
    const detail::LinkCache& c = model.link_cache(i);
    rotate_about_z(c.R0, sn[i], cs[i], d.R[i]);
    Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
    local.linear() = d.R[i];
    local.translation() = c.p;
    d.oMi[i] = parent * local;
    parent = d.oMi[i];
  }
  d.oMf = parent * model.description().flange;
  return d.oMf;
}

void point_jacobian(const RobotModel& model, const DynamicsData& d, int link, const Eigen::Vector3d& point,
                    Matrix6J& J) {
  const int n = model.n_dof();
  if (link < 0 || link >= n) throw InvalidArgument("link index " + std::to_string(link) + " is out of range, expected 0 to " + std::to_string(n - 1));
  J.setZero(6, n);
  const Eigen::Vector3d p = d.oMi[link] * point;
  // column j: [z_j x (p - o_j); z_j] for every joint j up to the link
  for (int j = 0; j <= link; ++j) {
    const Eigen::Vector3d zj = d.oMi[j].linear().col(2);
    const Eigen::Vector3d oj = d.oMi[j].translation();
    J.block<3, 1>(0, j) = zj.cross(p - oj);
    J.block<3, 1>(3, j) = zj;
  }
}

CartesianSpeeds cartesian_speeds(const RobotModel& model, DynamicsData& d, const VectorJ& q, const VectorJ& qd,
                                 const std::vector<Eigen::Vector3d>& tool_points, const RigidBodyInertia& payload) {
  const int n = model.n_dof();
  check_size("qd", qd.size(), n, "model.n_dof");
  forward_kinematics(model, d, q);
  // the velocity of a point p (base frame) on body b: sum over joints j <= b of qd_j z_j x (p - o_j)
  auto velocity = [&](int b, const Eigen::Vector3d& p) {
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    for (int j = 0; j <= b; ++j) v += qd[j] * d.oMi[j].linear().col(2).cross(p - d.oMi[j].translation());
    return v;
  };
  CartesianSpeeds c;
  const int last = n - 1;
  c.tool = velocity(last, d.oMf.translation()).norm();
  for (size_t k = 0; k < tool_points.size(); ++k)
    if (const double v = velocity(last, d.oMf * tool_points[k]).norm(); v > c.tool) c.tool = v, c.tool_point = static_cast<int>(k);
  if (n >= 3) {
    const Eigen::Vector2d& span = model.description().elbow_housing;
    const Eigen::Vector3d o = d.oMi[2].translation(), z = d.oMi[2].linear().col(2);
    c.elbow = std::max(velocity(2, o + span[0] * z).norm(), velocity(2, o + span[1] * z).norm());
  } else {
    c.elbow = std::numeric_limits<double>::quiet_NaN();
  }
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int b = 0; b < n; ++b)
    if (const RigidBodyInertia& body = model.joint(b).body; body.mass != 0.0) p += body.mass * velocity(b, d.oMi[b] * body.com);
  if (payload.mass > 0.0) p += payload.mass * velocity(last, d.oMf * payload.com);
  c.momentum = p.norm();
  return c;
}

const VectorJ& rnea(const RobotModel& model, DynamicsData& d, const VectorJ& q, const VectorJ& qd, const VectorJ& qdd) {
  check_q(model, q);
  check_size("qd", qd.size(), model.n_dof(), "model.n_dof");
  check_size("qdd", qdd.size(), model.n_dof(), "model.n_dof");
  rnea_impl<false>(model, d, q, &qd, &qdd, true);
  return d.tau;
}

const VectorJ& rnea_pair(const RobotModel& model, DynamicsData& d, const VectorJ& q, const VectorJ& qd, const VectorJ& qdd,
                         const VectorJ& qdd2, VectorJ& tau2) {
  check_q(model, q);
  check_size("qd", qd.size(), model.n_dof(), "model.n_dof");
  check_size("qdd", qdd.size(), model.n_dof(), "model.n_dof");
  check_size("qdd2", qdd2.size(), model.n_dof(), "model.n_dof");
  rnea_impl<true>(model, d, q, &qd, &qdd, true, &qdd2, &tau2);
  return d.tau;
}

const VectorJ& gravity_torque(const RobotModel& model, DynamicsData& d, const VectorJ& q) {
  check_q(model, q);
  rnea_impl<false>(model, d, q, nullptr, nullptr, true);
  return d.tau;
}

const VectorJ& nonlinear_effects(const RobotModel& model, DynamicsData& d, const VectorJ& q, const VectorJ& qd) {
  check_q(model, q);
  check_size("qd", qd.size(), model.n_dof(), "model.n_dof");
  rnea_impl<false>(model, d, q, &qd, nullptr, true);
  return d.tau;
}

const VectorJ& coriolis_torque(const RobotModel& model, DynamicsData& d, const VectorJ& q, const VectorJ& qd) {
  check_q(model, q);
  check_size("qd", qd.size(), model.n_dof(), "model.n_dof");
  rnea_impl<false>(model, d, q, &qd, nullptr, false);
  return d.tau;
}

const MatrixJ& crba(const RobotModel& model, DynamicsData& d, const VectorJ& q) {
  check_q(model, q);
  const int n = model.n_dof();
  // rotations at q (all sin, cos at once)
  double sn[kMaxDof], cs[kMaxDof];
  detail::joint_sincos(model, q, sn, cs);
  for (int i = 0; i < n; ++i) {
    const detail::LinkCache& c = model.link_cache(i);
    rotate_about_z(c.R0, sn[i], cs[i], d.R[i]);
    d.mc[i] = c.m;
    d.hc[i] = c.h;
    d.Ic[i] = c.I_o;
  }
  // composite bodies from the tip: move child composite (m, h, I_o) into the parent frame
  //   h' = R h + m p
  //   I' = R I R^T - m [p]x[p]x - [p]x[Rh]x - [Rh]x[p]x
  for (int i = n - 1; i > 0; --i) {
    const Eigen::Matrix3d& R = d.R[i];
    const Eigen::Vector3d& p = model.link_cache(i).p;
    const double m = d.mc[i];
    const Eigen::Vector3d Rh = R * d.hc[i];
    const Eigen::Matrix3d RIRt = R * d.Ic[i] * R.transpose();
    // -m [p]x^2 = m (p.p 1 - p p^T);  -([p]x[r]x + [r]x[p]x) = 2 (p.r) 1 - p r^T - r p^T
    const double pp = p.squaredNorm();
    const double pr = p.dot(Rh);
    Eigen::Matrix3d shift = -m * (p * p.transpose()) - p * Rh.transpose() - Rh * p.transpose();
    shift.diagonal().array() += m * pp + 2.0 * pr;
    d.mc[i - 1] += m;
    d.hc[i - 1] += Rh + m * p;
    d.Ic[i - 1] += RIRt + shift;
  }
  // column i: the wrench composite i needs for a unit acceleration of joint i,
  //   f = z x h_c,  n = I_c z, carried towards the base; M(k, i) = z . n_k
  d.M.resize(n, n);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d f = Eigen::Vector3d::UnitZ().cross(d.hc[i]);
    Eigen::Vector3d m = d.Ic[i].col(2);
    d.M(i, i) = m.z();
    for (int k = i; k > 0; --k) {
      f = d.R[k] * f;
      m = d.R[k] * m + model.link_cache(k).p.cross(f);
      d.M(k - 1, i) = m.z();
      d.M(i, k - 1) = m.z();
    }
  }
  return d.M;
}

const VectorJ& forward_dynamics(const RobotModel& model, DynamicsData& d, const VectorJ& q, const VectorJ& qd,
                                const VectorJ& tau) {
  check_size("tau", tau.size(), model.n_dof(), "model.n_dof");
  // h = C qd + g, then solve M qdd = tau - h by Cholesky
  nonlinear_effects(model, d, q, qd);
  d.qdd = tau - d.tau;
  crba(model, d, q);
  d.llt.compute(d.M);
  d.llt.solveInPlace(d.qdd);
  return d.qdd;
}

double kinetic_energy(const RobotModel& model, DynamicsData& d, const VectorJ& q, const VectorJ& qd) {
  check_size("qd", qd.size(), model.n_dof(), "model.n_dof");
  crba(model, d, q);
  return 0.5 * qd.dot(d.M * qd);
}

double potential_energy(const RobotModel& model, DynamicsData& d, const VectorJ& q) {
  forward_kinematics(model, d, q);
  double V = 0.0;
  for (int i = 0; i < model.n_dof(); ++i) {
    const detail::LinkCache& c = model.link_cache(i);
    // world first moment = m o_i + R h
    const Eigen::Vector3d mc_world = c.m * d.oMi[i].translation() + d.oMi[i].linear() * c.h;
    V -= model.gravity().dot(mc_world);
  }
  return V;
}

}  // namespace twinwatch::model
