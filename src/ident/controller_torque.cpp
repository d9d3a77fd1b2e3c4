#include "twinwatch/ident/controller_torque.hpp"

#include <cmath>
#include <exception>

#include "twinwatch/model/description_io.hpp"

namespace twinwatch::ident {

namespace {
constexpr std::uint32_t kNeeded = kFieldTargetQ | kFieldTargetQd | kFieldTargetMoment;  // (and target_qdd, or the step before)
// (measured: the arm's own model 0.05-0.17 relative rms, another's 0.6-2.2)
constexpr double kOwnFit = 0.3, kFactor = 3.0;
// a step longer than this is no step to difference the target velocity over (a gap)
constexpr double kLongestStep = 0.05;
}  // namespace

ControllerTorqueAccumulator::ControllerTorqueAccumulator(const model::RobotModel& robot, size_t stride)
    : model_(robot), data_(model_), stride_(std::max<size_t>(1, stride)), e2_(VectorJ::Zero(robot.n_dof())) {}

void ControllerTorqueAccumulator::add(const RobotSample& s) {
  // only where the controller drives the arm (RUNNING, NORMAL): stopped, powered off or braking, its
  // torque is no model's along targets
  const bool usable = (s.present & kNeeded) == kNeeded && s.n_dof() == model_.n_dof() && s.robot_mode == 7 && s.safety_mode == 1 &&
                      s.target_q.allFinite() && s.target_qd.allFinite() && s.target_moment.allFinite();
  const bool streamed = (s.present & kFieldTargetQdd) != 0;
  // without target_qdd: the middle of the step from the previous sample (this class's comment)
  const double dt = s.timestamp - previous_t_;
  const bool differenced = usable && !streamed && previous_ok_ && !s.gap_before && dt > 0.0 && dt <= kLongestStep;
  if (usable && !streamed) {
    if (differenced) {
      q_ = 0.5 * (s.target_q + previous_q_);
      qd_ = 0.5 * (s.target_qd + previous_qd_);
      qdd_ = (s.target_qd - previous_qd_) / dt;
      moment_ = 0.5 * (s.target_moment + previous_moment_);
    }
    previous_q_ = s.target_q, previous_qd_ = s.target_qd, previous_moment_ = s.target_moment, previous_t_ = s.timestamp;
  }
  previous_ok_ = usable && !streamed;
  if (!(differenced || (usable && streamed && s.target_qdd.allFinite()))) return;
  if (seen_++ % stride_ != 0) return;
  const bool with_payload = (s.present & kFieldPayload) != 0;
  const double mass = with_payload && std::isfinite(s.payload) && s.payload > 0.0 ? s.payload : 0.0;
  const Eigen::Vector3d cog = mass > 0.0 && std::isfinite(s.payload_cog[0]) && std::isfinite(s.payload_cog[1]) && std::isfinite(s.payload_cog[2])
                                  ? Eigen::Vector3d(s.payload_cog[0], s.payload_cog[1], s.payload_cog[2])
                                  : Eigen::Vector3d::Zero();
  if (mass != declared_ || cog != declared_cog_) {
    model::RigidBodyInertia p;
    p.mass = mass;
    p.com = cog;
    try {
      model_.set_payload(p);
    } catch (const std::exception&) {
      model_.clear_payload();  // (a declared payload no arm carries: compared without it)
    }
    declared_ = mass, declared_cog_ = cog;
  }
  const VectorJ& tau = streamed ? model::rnea(model_, data_, s.target_q, s.target_qd, s.target_qdd) : model::rnea(model_, data_, q_, qd_, qdd_);
  const VectorJ& measured = streamed ? s.target_moment : moment_;
  e2_ += (measured - tau).cwiseAbs2();
  t2_ += measured.squaredNorm();
  ++samples_;
}

ControllerTorqueFit ControllerTorqueAccumulator::fit() const {
  ControllerTorqueFit f;
  f.rms = VectorJ::Zero(model_.n_dof());
  if (samples_ == 0 || !(t2_ > 0.0)) return f;  // (a torque of zeros: no model to compare with)
  f.samples = samples_;
  f.rms = (e2_ / static_cast<double>(samples_)).cwiseSqrt();
  f.relative_rms = std::sqrt(e2_.sum() / t2_);
  return f;
}

ArmCheck::ArmCheck(const model::RobotModel& robot, size_t stride) {
  fits_.emplace_back(robot, stride);
  for (const std::string& name : model::builtin_robot_names())
    if (name != robot.name())
      if (const model::RobotModel m = model::load_robot(name); m.n_dof() == robot.n_dof()) fits_.emplace_back(m, stride);
}

void ArmCheck::add(const RobotSample& s) {
  for (ControllerTorqueAccumulator& f : fits_) f.add(s);
}

ArmVerdict ArmCheck::verdict() const {
  ArmVerdict v;
  v.own = fits_.front().fit();
  if (v.own.samples == 0) return v;
  double best = v.own.relative_rms;
  for (size_t k = 1; k < fits_.size(); ++k)
    if (const ControllerTorqueFit f = fits_[k].fit(); f.samples > 0 && f.relative_rms < best) best = f.relative_rms, v.better = fits_[k].robot().name(), v.theirs = f;
  if (!(best < kOwnFit && v.own.relative_rms > kFactor * best)) v.better.clear(), v.theirs = {};
  return v;
}

}  // namespace twinwatch::ident
