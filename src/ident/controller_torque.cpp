#include "twinwatch/ident/controller_torque.hpp"

#include <cmath>
#include <exception>

#include "twinwatch/model/dynamics.hpp"

namespace twinwatch::ident {

ControllerTorqueFit controller_torque_fit(const model::RobotModel& robot, const std::vector<const device::Recording*>& recordings,
                                          size_t max_samples) {
  const int n = robot.n_dof();
  ControllerTorqueFit fit;
  fit.rms = VectorJ::Zero(n);
  constexpr std::uint32_t kNeeded = kFieldTargetQ | kFieldTargetQd | kFieldTargetQdd | kFieldTargetMoment;
  size_t total = 0;
  for (const device::Recording* r : recordings)
    if (r->n_dof == n && (r->present & kNeeded) == kNeeded) total += r->samples.size();
  if (total == 0 || max_samples == 0) return fit;
  const size_t stride = std::max<size_t>(1, total / max_samples);
  model::RobotModel m = robot;
  model::DynamicsData d(m);
  VectorJ e2 = VectorJ::Zero(n);
  double t2 = 0.0;
  double declared = -1.0;  // (the payload attached: set again only when it changes)
  Eigen::Vector3d declared_cog = Eigen::Vector3d::Zero();
  size_t k = 0;
  for (const device::Recording* r : recordings) {
    if (r->n_dof != n || (r->present & kNeeded) != kNeeded) continue;
    const bool with_payload = (r->present & kFieldPayload) != 0;
    for (const RobotSample& s : r->samples) {
      if (k++ % stride != 0) continue;
      if (!s.target_q.allFinite() || !s.target_qd.allFinite() || !s.target_qdd.allFinite() || !s.target_moment.allFinite()) continue;
      const double mass = with_payload && std::isfinite(s.payload) && s.payload > 0.0 ? s.payload : 0.0;
      const Eigen::Vector3d cog = mass > 0.0 && std::isfinite(s.payload_cog[0]) && std::isfinite(s.payload_cog[1]) && std::isfinite(s.payload_cog[2])
                                      ? Eigen::Vector3d(s.payload_cog[0], s.payload_cog[1], s.payload_cog[2])
                                      : Eigen::Vector3d::Zero();
      if (mass != declared || cog != declared_cog) {
        model::RigidBodyInertia p;
        p.mass = mass;
        p.com = cog;
        try {
          m.set_payload(p);
        } catch (const std::exception&) {
          m.clear_payload();  // (a declared payload no arm carries: compared without it)
        }
        declared = mass, declared_cog = cog;
      }
      const VectorJ& tau = model::rnea(m, d, s.target_q, s.target_qd, s.target_qdd);
      e2 += (s.target_moment - tau).cwiseAbs2();
      t2 += s.target_moment.squaredNorm();
      ++fit.samples;
    }
  }
  if (fit.samples == 0) return fit;
  if (!(t2 > 0.0)) return ControllerTorqueFit{0.0, VectorJ::Zero(n), 0};  // (a torque of zeros: no model to compare with)
  fit.rms = (e2 / static_cast<double>(fit.samples)).cwiseSqrt();
  fit.relative_rms = std::sqrt(e2.sum() / t2);
  return fit;
}

}  // namespace twinwatch::ident
