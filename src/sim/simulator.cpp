#include "twinwatch/sim/simulator.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <string>

#include "twinwatch/core/error.hpp"

namespace twinwatch::sim {

namespace {
// closed-loop bandwidth of the default joint PD [rad/s] and its damping ratio: stiff enough that a
// 1 N·m disturbance moves a wrist joint by a few mrad, slow enough for a 500 Hz loop
constexpr double kDefaultBandwidth = 2 * M_PI * 10.0;
constexpr double kDefaultDamping = 0.8;
// velocity scale of the smooth sign used by the resistance fault [rad/s]
constexpr double kResistanceVelocityScale = 0.01;
}  // namespace

const char* to_string(FaultType t) {
  switch (t) {
    case FaultType::Resistance: return "resistance";
    case FaultType::FrictionGrowth: return "friction_growth";
    case FaultType::PayloadPick: return "payload_pick";
    case FaultType::PayloadLoss: return "payload_loss";
    case FaultType::Collision: return "collision";
    case FaultType::CurrentOffset: return "current_offset";
    case FaultType::StuckCurrent: return "stuck_current";
    case FaultType::DroppedSamples: return "dropped_samples";
    case FaultType::TimestampJitter: return "timestamp_jitter";
    case FaultType::MissedPick: return "missed_pick";
  }
  return "unknown";
}

const char* to_string(StopKind k) {
  switch (k) {
    case StopKind::Pause: return "pause";
    case StopKind::Protective: return "protective";
    case StopKind::Emergency: return "emergency";
  }
  return "unknown";
}

double min_stop_hold(const StopSpec& stop) {
  switch (stop.kind) {
    case StopKind::Pause: return stop.stopping_time;
    case StopKind::Protective: return stop.stopping_time + kUnlockLead;
    case StopKind::Emergency: return stop.stopping_time + kIdleBeforeRelease + kBrakeReleaseLead;
  }
  return stop.stopping_time;
}

double FaultSpec::level(double t) const {
  if (t < onset || t >= end) return 0.0;
  if (ramp <= 0.0) return 1.0;
  return std::min(1.0, (t - onset) / ramp);
}

VectorJ collision_torque_per_newton(const model::RobotModel& m, const model::DynamicsData& d, const FaultSpec& f) {
  Matrix6J J;
  model::point_jacobian(m, d, f.link, f.point, J);
  return J.topRows<3>().transpose() * f.direction.normalized();
}

PlantTruth default_truth(const model::RobotModel& m, unsigned serial) {
  PlantTruth p;
  p.serial = serial;
  std::mt19937 rng(serial ^ 0x9e3779b9u);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = m.n_dof();
  for (int j = 0; j < n; ++j) {
    JointTruth jt;
    // joint size from the torque limit: friction, gains and noise scale with it
    const double tau_max = std::isfinite(m.joint(j).limits.torque_max) ? m.joint(j).limits.torque_max : 50.0;
    const double size = std::clamp(tau_max / 28.0, 0.3, 2.0);
    // harmonic-drive friction has a floor even on small joints (motor-side friction seen through N)
    jt.Fc = (0.35 + 0.2 * size) * (1 + 0.2 * u(rng));
    jt.Fs = jt.Fc * (1.4 + 0.2 * u(rng));
    jt.vs = 0.04 * (1 + 0.3 * u(rng));
    jt.Fv = (0.3 + 0.25 * size) * (1 + 0.2 * u(rng));
    jt.sigma0 = 3000 * size;
    jt.sigma1 = 3.0 * size;
    jt.ripple = 0.02 * size;
    jt.ripple_phase = M_PI * u(rng);
    jt.ripple1 = 0.03 * size;
    jt.ripple1_phase = M_PI * u(rng);
    jt.gear_ratio = 101;
    jt.kt = size >= 1.5 ? 0.125 : (size >= 0.9 ? 0.11 : 0.0945);
    jt.eta = 0.9;
    jt.eta_rev = 0.85;
    // DESIGN.md rule 4: sigma 0.014-0.04 A per joint, more on the base joint
    jt.current_sigma = j == 0 ? 0.03 : std::clamp(0.012 + 0.008 * size, 0.014, 0.04);
    jt.current_offset = 0.0;
    jt.torque_sigma = 0.002 * tau_max;
    p.joints.push_back(jt);
  }
  return p;
}

std::string duration_problem(double duration, double rate) {
  if (!(duration > 0.0)) return fmt::format("expected a duration > 0 s, got {}", duration);
  if (!(duration <= kMaxDuration))
    return fmt::format("expected at most {:g} s (the longest run the simulator accepts), got {}", kMaxDuration, duration);
  // at least one sample: run() records llround(duration * rate) of them (the tolerance lets a
  // duration of exactly 1 / rate through whatever its rounding)
  if (duration * rate < 1.0 - 1e-9)
    return fmt::format("expected at least one sample period ({:g} s at {:g} Hz), got {} s", 1.0 / rate, rate, duration);
  return "";
}

void SimOptions::validate(int n) const {
  if (!(rate >= kMinRate && rate <= kMaxRate))
    throw InvalidArgument(fmt::format("rate is {} Hz, must be in [{:g}, {:g}]", rate, kMinRate, kMaxRate));
  if (substeps < 1) throw InvalidArgument(fmt::format("substeps is {}, must be >= 1", substeps));
  if (rate * substeps < kMinPhysicsRate)
    throw InvalidArgument(fmt::format("physics rate is {} Hz (rate {} x substeps {}), must be >= {:g} Hz", rate * substeps,
                                      rate, substeps, kMinPhysicsRate));
  if (const std::string p = duration_problem(duration, rate); !p.empty()) throw InvalidArgument("duration: " + p);
  if (kp.size() != 0 && kp.size() != n) throw InvalidArgument(fmt::format("kp has size {}, expected {} (n_dof)", kp.size(), n));
  if (kd.size() != 0 && kd.size() != n) throw InvalidArgument(fmt::format("kd has size {}, expected {} (n_dof)", kd.size(), n));
  payload.validate("payload");
  double free_from = 0.0;  // when the last stop's resume ramp ends
  for (size_t k = 0; k < stops.size(); ++k) {
    const StopSpec& st = stops[k];
    const std::string name = fmt::format("stops[{}] ({})", k, to_string(st.kind));
    if (!(st.at >= 0.0) || !std::isfinite(st.at)) throw InvalidArgument(fmt::format("{}: at is {} s, expected >= 0", name, st.at));
    if (!(st.stopping_time > 0.0 && st.stopping_time <= kMaxStoppingTime))
      throw InvalidArgument(
          fmt::format("{}: stopping_time is {} s, expected more than 0 and at most {:g} s", name, st.stopping_time, kMaxStoppingTime));
    if (!(st.hold >= min_stop_hold(st)) || !std::isfinite(st.hold))
      throw InvalidArgument(fmt::format("{}: hold is {} s, expected at least {:g} s (the stop's deceleration{})", name, st.hold,
                                        min_stop_hold(st),
                                        st.kind == StopKind::Emergency  ? ", power-on and brake release"
                                        : st.kind == StopKind::Protective ? " and the unlock before the resume"
                                                                          : ""));
    if (st.at < free_from)
      throw InvalidArgument(fmt::format("{}: at is {} s, expected after the previous stop has resumed ({:g} s): stops in time order, "
                                        "one at a time",
                                        name, st.at, free_from));
    free_from = st.at + st.hold + st.stopping_time;
  }
}

std::uint32_t Simulator::fields() {
  return kFieldActualQd | kFieldTargetQ | kFieldTargetQd | kFieldTargetQdd | kFieldActualCurrent | kFieldTargetCurrent |
         kFieldTargetMoment | kFieldTemperature | kFieldDigitalOutputs | kFieldRobotMode | kFieldSafetyMode;
}

std::uint32_t Simulator::sample_fields() const {
  return (fields() & (opt_.streams_targets ? ~0u : ~kTargetFields)) | (opt_.streams_payload ? kFieldPayload : 0u) |
         (opt_.joint_torque_sensors ? kFieldJointTorque : 0u);
}

// armature: motor rotor inertia reflected through the gear, J_m N^2 [kg m^2]; rotor inertia grows
// with the joint size
double armature(const JointTruth& jt) {
  const double rotor = jt.kt >= 0.12 ? 2.5e-5 : (jt.kt >= 0.1 ? 1.2e-5 : 5e-6);
  return rotor * jt.gear_ratio * jt.gear_ratio;
}

namespace {

model::RobotModel perturbed(const model::RobotModel& nominal, double spread, unsigned seed) {
  model::RobotModel m = nominal;
  std::mt19937 rng(seed ^ 0x85ebca6bu);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < m.n_dof(); ++i) {
    model::RigidBodyInertia b = m.joint(i).body;
    b.mass *= 1 + spread * u(rng);
    b.com += Eigen::Vector3d(u(rng), u(rng), u(rng)) * (spread * 0.1 * std::max(b.com.norm(), 0.05));
    b.inertia_com *= 1 + spread * u(rng);
    m.set_link_inertia(i, b);
  }
  return m;
}

}  // namespace

Simulator::Simulator(const model::RobotModel& nominal, std::shared_ptr<const Trajectory> trajectory, PlantTruth truth,
                     SimOptions options, std::vector<FaultSpec> faults)
    : nominal_(nominal),
      truth_model_(perturbed(nominal, truth.inertial_perturbation, truth.serial)),
      controller_model_(nominal),
      traj_(std::move(trajectory)),
      truth_(std::move(truth)),
      opt_(std::move(options)),
      faults_(std::move(faults)),
      dtruth_(nominal),
      dctrl_(nominal),
      rng_(opt_.seed),
      torque_rng_(opt_.seed ^ 0x5eed70c5u),
      n_(nominal.n_dof()) {
  opt_.validate(n_);
  if (!traj_) throw InvalidArgument("trajectory is missing");
  if (traj_->n_dof() != n_) throw InvalidArgument(fmt::format("trajectory has {} joints, expected {}", traj_->n_dof(), n_));
  if (static_cast<int>(truth_.joints.size()) != n_)
    throw InvalidArgument(fmt::format("truth has {} joints, expected {}", truth_.joints.size(), n_));
  for (size_t k = 0; k < faults_.size(); ++k) {
    const FaultSpec& f = faults_[k];
    const bool needs_joint = f.type == FaultType::Resistance || f.type == FaultType::FrictionGrowth ||
                             f.type == FaultType::CurrentOffset || f.type == FaultType::StuckCurrent;
    if (needs_joint && (f.joint < 0 || f.joint >= n_))
      throw InvalidArgument(fmt::format("fault {} ({}): joint is {}, expected 1 to {}", k, to_string(f.type), f.joint + 1, n_));
    if (f.type == FaultType::Collision && (f.link < 0 || f.link >= n_))
      throw InvalidArgument(fmt::format("fault {} (collision): link is {}, expected 1 to {}", k, f.link + 1, n_));
    if (f.type == FaultType::Collision && !(f.duration > 0.0))
      throw InvalidArgument(fmt::format("fault {} (collision): duration is {} s, must be > 0", k, f.duration));
    // the bit is shifted into a 64-bit word: outside 0..63 the shift is undefined
    if (f.io_bit < 0 || f.io_bit > kMaxDigitalOutputBit)
      throw InvalidArgument(fmt::format("fault {} ({}): io_bit is {}, expected 0 to {}", k, to_string(f.type), f.io_bit,
                                        kMaxDigitalOutputBit));
    const double max_jitter = kMaxJitterFraction / opt_.rate;
    if (f.type == FaultType::TimestampJitter && !(f.magnitude >= 0.0 && f.magnitude <= max_jitter))
      throw InvalidArgument(fmt::format("fault {} (timestamp_jitter): magnitude is {} s, expected 0 to {:g} s", k, f.magnitude,
                                        max_jitter));
  }
  fault_applied_.assign(faults_.size(), false);
  declaration_applied_.assign(faults_.size(), false);
  if (opt_.payload.mass > 0.0) {
    truth_model_.set_payload(opt_.payload);
    if (opt_.payload_declared) controller_model_.set_payload(opt_.payload);
    payload_on_ = true;
    dout_ |= 1u;
  }
  // initial state on the trajectory
  VectorJ qdd;
  traj_->evaluate(0.0, q_, qd_, qdd);
  z_ = VectorJ::Zero(n_);
  temp_.resize(n_);
  for (int j = 0; j < n_; ++j) temp_[j] = opt_.cold_start ? truth_.ambient : truth_.joints[static_cast<size_t>(j)].T_ref;
  q_meas_prev_ = q_;
  current_held_ = VectorJ::Zero(n_);
  link_torque_ = VectorJ::Zero(n_);
  // default gains from the joint inertia at the start pose (incl. armature)
  const MatrixJ M = model::crba(controller_model_, dctrl_, q_);
  kp_.resize(n_);
  kd_.resize(n_);
  for (int j = 0; j < n_; ++j) {
    const double I = M(j, j) + armature(truth_.joints[static_cast<size_t>(j)]);
    kp_[j] = opt_.kp.size() ? opt_.kp[j] : I * kDefaultBandwidth * kDefaultBandwidth;
    kd_[j] = opt_.kd.size() ? opt_.kd[j] : 2 * kDefaultDamping * kDefaultBandwidth * I;
  }
}

Simulator::ProgramState Simulator::program_state(double t) const {
  ProgramState p;
  for (const StopSpec& st : opt_.stops) {
    const double a = st.at, ts = st.stopping_time, resume = st.at + st.hold;
    if (t < a) break;  // (in time order)
    if (t >= resume + ts) {
      p.lost += st.hold;  // a stop costs the program its hold: ts / 2 slowing down, ts / 2 speeding up
      continue;
    }
    // the time lost in this stop so far, the integral of 1 - r (exact: no sum of steps drifts)
    if (t < a + ts) {
      p.r = 1.0 - (t - a) / ts, p.rdot = -1.0 / ts;  // decelerating along the path
      p.lost += (t - a) * (t - a) / (2 * ts);
    } else if (t < resume) {
      p.r = 0.0, p.rdot = 0.0;
      p.lost += ts / 2 + (t - a - ts);
    } else {
      const double u = t - resume;
      p.r = u / ts, p.rdot = 1.0 / ts;  // the program resumes with the same ramp
      p.lost += st.hold - ts / 2 + u - u * u / (2 * ts);
    }
    if (st.kind == StopKind::Protective && t < resume - kUnlockLead) p.safety_mode = 3;  // PROTECTIVE_STOP
    if (st.kind == StopKind::Emergency) {
      const double release = resume - kBrakeReleaseLead, power_on = release - kIdleBeforeRelease;
      if (t < power_on) p.safety_mode = 7;  // ROBOT_EMERGENCY_STOP until reset
      if (t >= a + ts && t < release) {
        p.braked = true;
        p.robot_mode = t < power_on ? 3 : 5;  // POWER_OFF, then IDLE (powered, brakes on)
      }
    }
    break;
  }
  return p;
}

double Simulator::resistance(int j) const {
  double size = 0.0;
  for (const FaultSpec& f : faults_)
    if (f.joint == j && f.type == FaultType::Resistance) size += f.magnitude * f.level(t_);
  return size;
}

VectorJ Simulator::implicit_acceleration(const MatrixJ& M, const VectorJ& b, const VectorJ& qd, const VectorJ& R, double h) {
  // qdd = argmin Phi(x) = x'Mx/2 - b'x + sum_j R_j vs/h logcosh((qd_j + h x_j)/vs), whose gradient
  // M x - b + R tanh((qd + h x)/vs) is the substep's equation of motion with the resistance at the
  // velocity it ends with. Phi is convex (M positive definite, logcosh convex): Newton steps with a
  // backtracking line search converge from anywhere, where plain Newton on the saturated sign
  // would overshoot
  constexpr double vs = kResistanceVelocityScale;
  const auto logcosh = [](double a) { return std::abs(a) + std::log1p(std::exp(-2.0 * std::abs(a))) - std::log(2.0); };
  const auto phi = [&](const VectorJ& x) {
    double v = 0.5 * x.dot(M * x) - b.dot(x);
    for (int j = 0; j < n_; ++j)
      if (R[j] > 0.0) v += R[j] * vs / h * logcosh((qd[j] + h * x[j]) / vs);
    return v;
  };
  Eigen::LLT<MatrixJ> llt(M);
  VectorJ x = llt.solve(b);  // (the arm without the resistance: a start on the far side is fine too)
  for (int it = 0; it < 50; ++it) {
    VectorJ g = M * x - b;
    MatrixJ Jm = M;
    for (int j = 0; j < n_; ++j) {
      if (!(R[j] > 0.0)) continue;
      const double th = std::tanh((qd[j] + h * x[j]) / vs);
      g[j] += R[j] * th;
      Jm(j, j) += h * R[j] * (1.0 - th * th) / vs;
    }
    if (g.norm() <= 1e-10 * (1.0 + b.norm())) break;
    llt.compute(Jm);
    const VectorJ dx = llt.solve(g);
    const double f0 = phi(x), slope = g.dot(dx);
    double t = 1.0;
    while (t > 1e-12 && phi(x - t * dx) > f0 - 1e-4 * t * slope) t *= 0.5;
    x -= t * dx;
  }
  return x;
}

double Simulator::friction_torque(int j, double v, double h) {
  const JointTruth& jt = truth_.joints[static_cast<size_t>(j)];
  double wear = 1.0;
  for (const FaultSpec& f : faults_)
    if (f.joint == j && f.type == FaultType::FrictionGrowth) wear *= 1.0 + f.magnitude * f.level(t_);
  // LuGre: z' = v - sigma0 |v| / g(v) z, advanced exactly with v held over the step
  const double Fc = jt.Fc * wear, Fs = jt.Fs * wear;
  const double g = Fc + (Fs - Fc) * std::exp(-(v / jt.vs) * (v / jt.vs));
  const double a = jt.sigma0 * std::abs(v) / g;
  double& z = z_[j];
  const double z_old = z;
  if (a * h > 1e-12) {
    const double z_ss = v / a;
    z = z_ss + (z - z_ss) * std::exp(-a * h);
  } else {
    z += v * h;
  }
  const double zdot = (z - z_old) / h;
  const double Fv = jt.Fv * wear * std::exp(-jt.visc_temp_coeff * (temp_[j] - jt.T_ref));
  const double q = q_[j];
  const double ripple = jt.ripple * std::sin(jt.gear_ratio * q + jt.ripple_phase) + jt.ripple1 * std::sin(q + jt.ripple1_phase);
  return jt.sigma0 * z + jt.sigma1 * zdot + Fv * v + ripple;
}

void Simulator::apply_payload_faults(double t) {
  for (size_t k = 0; k < faults_.size(); ++k) {
    const FaultSpec& f = faults_[k];
    // the program declares what it picks: with the grip, or declare_delay after (before) it
    if (f.type == FaultType::PayloadPick && !declaration_applied_[k] && t >= f.onset + f.declare_delay) {
      controller_model_.set_payload(f.payload);
      declaration_applied_[k] = true;
    }
    if (fault_applied_[k] || t < f.onset) continue;
    if (f.type == FaultType::PayloadPick) {
      truth_model_.set_payload(f.payload);
      dout_ |= (1ull << f.io_bit);
      payload_on_ = true;
      fault_applied_[k] = true;
    } else if (f.type == FaultType::MissedPick) {
      controller_model_.set_payload(f.payload);  // declared, but nothing is gripped: the truth keeps what it had
      dout_ |= (1ull << f.io_bit);
      fault_applied_[k] = true;
    } else if (f.type == FaultType::PayloadLoss) {
      truth_model_.clear_payload();  // the controller still believes it carries it
      dout_ &= ~(1ull << f.io_bit);
      payload_on_ = false;
      fault_applied_[k] = true;
    }
  }
}

bool Simulator::step(RobotSample& s) {
  const double dt = 1.0 / opt_.rate;
  const double h = dt / opt_.substeps;
  apply_payload_faults(t_);

  // the program's time: the trajectory's clock, slowed to a halt and resumed by the stops (its rate r:
  // targets q(tau), r q'(tau), r^2 q''(tau) + r' q'(tau))
  const ProgramState ps = program_state(t_);
  VectorJ qt, qdt, qddt;
  traj_->evaluate(t_ - ps.lost, qt, qdt, qddt);
  if (ps.r != 1.0 || ps.rdot != 0.0) {
    qddt = ps.r * ps.r * qddt + ps.rdot * qdt;
    qdt *= ps.r;
  }
  // controller: PD + nominal feed-forward (with armature) on the target, from measured state
  const VectorJ q_meas = ((q_.array() / truth_.encoder_lsb).round() * truth_.encoder_lsb).matrix();
  const VectorJ qd_meas = tick_ == 0 ? qd_ : VectorJ((q_meas - q_meas_prev_) / dt);
  if (ps.braked) {
    // power off, brakes on: the drives are off, the controller's targets are where the arm stands
    qt = q_meas;
    qdt.setZero();
    qddt.setZero();
  }
  VectorJ tau_cmd = model::rnea(controller_model_, dctrl_, qt, qdt, qddt);
  if (ps.braked) tau_cmd.setZero();
  for (int j = 0; j < n_ && !ps.braked; ++j) {
    tau_cmd[j] += armature(truth_.joints[static_cast<size_t>(j)]) * qddt[j];
    tau_cmd[j] += kp_[j] * (qt[j] - q_meas[j]) + kd_[j] * (qdt[j] - qd_meas[j]);
    const double lim = nominal_.joint(j).limits.torque_max;
    if (std::isfinite(lim)) tau_cmd[j] = std::clamp(tau_cmd[j], -lim, lim);
  }

  // collision force pulses: tau_ext = J^T F at the contact point
  std::vector<std::pair<const FaultSpec*, double>> pulses;
  for (const FaultSpec& f : faults_) {
    if (f.type != FaultType::Collision || t_ < f.onset || t_ >= f.onset + f.duration) continue;
    pulses.emplace_back(&f, std::sin(M_PI * (t_ - f.onset) / f.duration));
  }

  // physics substeps (semi-implicit Euler of M qdd + h = tau - tau_f + tau_ext); the brakes hold
  // the arm where it stands
  if (ps.braked) qd_.setZero();
  //
  // A resistance's smooth sign is stiff: 100 N·m over 0.01 rad/s is a slope of 1e4 N·m s/rad, and
  // explicit Euler of it is stable only for h slope / M < 2 (M ~ 0.03 kg m² at a wrist). Past that
  // it chattered about qd = 0 with a mean near zero: from ~90 N·m on a UR3e wrist a larger resistance
  // had less effect than a small one, and 1000 N·m none (audit of session 56). The substep takes it
  // at the velocity it ends with (implicit_acceleration), which holds a joint stalled for any size
  VectorJ R(n_);
  for (int j = 0; j < n_; ++j) R[j] = resistance(j);
  const bool resisted = (R.array() > 0.0).any();
  for (int k = 0; k < opt_.substeps && !ps.braked; ++k) {
    VectorJ tau = tau_cmd;
    for (int j = 0; j < n_; ++j) tau[j] -= friction_torque(j, qd_[j], h);
    VectorJ tau_link = tau;  // what passes the gear into the link (a torque sensor's side): no contact
    if (!pulses.empty()) {
      model::forward_kinematics(truth_model_, dtruth_, q_);
      for (const auto& [f, shape] : pulses) {
        const VectorJ unit = collision_torque_per_newton(truth_model_, dtruth_, *f);
        const double scale = unit.cwiseAbs().maxCoeff();
        if (scale > 1e-9) tau += (f->magnitude * shape / scale) * unit;
      }
    }
    const VectorJ hvec = model::nonlinear_effects(truth_model_, dtruth_, q_, qd_);
    MatrixJ M = model::crba(truth_model_, dtruth_, q_);
    for (int j = 0; j < n_; ++j) M(j, j) += armature(truth_.joints[static_cast<size_t>(j)]);
    VectorJ qdd;
    if (resisted) {
      qdd = implicit_acceleration(M, tau - hvec, qd_, R, h);
      for (int j = 0; j < n_; ++j) tau_link[j] -= R[j] * std::tanh((qd_[j] + h * qdd[j]) / kResistanceVelocityScale);
    } else {
      dtruth_.llt.compute(M);
      qdd = dtruth_.llt.solve(tau - hvec);
    }
    if (opt_.joint_torque_sensors && k == opt_.substeps - 1)
      for (int j = 0; j < n_; ++j) link_torque_[j] = tau_link[j] - armature(truth_.joints[static_cast<size_t>(j)]) * qdd[j];
    qd_ += h * qdd;
    q_ += h * qd_;
  }

  // drive, thermal, measurement
  s = RobotSample::empty(n_);
  s.present = sample_fields();
  if (opt_.streams_payload) {
    // what the controller is told it carries (set_payload), not what it carries
    const model::RigidBodyInertia& declared = controller_model_.payload();
    s.payload = declared.mass;
    for (int k = 0; k < 3; ++k) s.payload_cog[k] = declared.mass > 0.0 ? declared.com[k] : 0.0;
  }
  s.q = ((q_.array() / truth_.encoder_lsb).round() * truth_.encoder_lsb).matrix();
  s.qd = (s.q - q_meas) / dt;
  if (opt_.streams_targets) {  // (else they stay NaN, as in a log without them)
    s.target_q = qt;
    s.target_qd = qdt;
    s.target_qdd = qddt;
    s.target_moment = tau_cmd;
  }
  for (int j = 0; j < n_; ++j) {
    const JointTruth& jt = truth_.joints[static_cast<size_t>(j)];
    const double kN = jt.kt * jt.gear_ratio;
    const bool motoring = tau_cmd[j] * qd_[j] >= 0.0;
    const double i_true = ps.braked ? 0.0 : (motoring ? tau_cmd[j] / (kN * jt.eta) : tau_cmd[j] * jt.eta_rev / kN);
    temp_[j] += dt * (jt.R_heat * i_true * i_true - (temp_[j] - truth_.ambient) / jt.R_th) / jt.C_th;
    double i_meas = i_true + jt.current_offset + jt.current_sigma * normal_(rng_);
    if (opt_.streams_targets) s.target_current[j] = tau_cmd[j] / (kN * jt.eta);
    for (const FaultSpec& f : faults_) {
      if (f.joint != j) continue;
      if (f.type == FaultType::CurrentOffset) i_meas += f.magnitude * f.level(t_);
      if (f.type == FaultType::StuckCurrent && f.level(t_) > 0.0 && tick_ > 0) i_meas = current_held_[j];
    }
    i_meas = std::round(i_meas / truth_.current_lsb) * truth_.current_lsb;
    current_held_[j] = i_meas;
    s.current[j] = i_meas;
    s.temperature[j] = std::round(temp_[j] * 10.0) / 10.0;
  }
  if (opt_.joint_torque_sensors) {
    // the brakes hold the arm on the motor side: the sensors carry its weight (the static torque)
    if (ps.braked) link_torque_ = model::rnea(truth_model_, dtruth_, q_, VectorJ::Zero(n_), VectorJ::Zero(n_));
    for (int j = 0; j < n_; ++j)
      s.joint_torque[j] = link_torque_[j] + truth_.joints[static_cast<size_t>(j)].torque_sigma * torque_normal_(torque_rng_);
  }
  s.digital_outputs = dout_;
  s.robot_mode = ps.robot_mode;
  s.safety_mode = ps.safety_mode;
  s.timestamp = t_ + dt;
  for (const FaultSpec& f : faults_)
    if (f.type == FaultType::TimestampJitter && f.level(t_) > 0.0)
      s.timestamp += f.magnitude * std::clamp(normal_(rng_), -kJitterClipSigmas, kJitterClipSigmas);

  check_within_limits(s);
  q_meas_prev_ = q_meas;
  ++tick_;
  t_ = static_cast<double>(tick_) * dt;  // from the tick count: no drift of summed steps

  // stream faults: drop samples
  bool deliver = true;
  for (const FaultSpec& f : faults_) {
    if (f.type != FaultType::DroppedSamples || t_ < f.onset || t_ >= f.end) continue;
    const double since = t_ - f.onset;
    const double phase = f.period > 0.0 ? std::fmod(since + 1e-9, f.period) : since + 1e-9;
    if (phase < f.magnitude * dt) deliver = false;
  }
  return deliver;
}

void Simulator::check_within_limits(const RobotSample& s) const {
  // A fault far beyond what the arm takes (a contact of 1000 N·m against J1's 54) threw it past its
  // range at 40 rad/s, and the recording was written as if a real arm could do it (audit of session
  // 56). A real controller stops the arm at its limits (a protective stop): the run is refused,
  // naming where it left them. Room is left for what a healthy run does at its limits: a target on
  // the range's edge overshoots it by a few encoder steps (kPositionLimitMargin), and a joint that a
  // resistance held seized whips back to its target when released, at 1.5-1.7x its speed limit
  // (review of session 56); a contact that throws the arm goes far beyond (12x at 1000 N·m)
  for (int j = 0; j < n_; ++j) {
    const model::JointLimits& lim = nominal_.joint(j).limits;
    const double q = s.q[j], qd = s.qd[j];
    std::string what;
    if (q < lim.q_min - kPositionLimitMargin || q > lim.q_max + kPositionLimitMargin)
      what = fmt::format("J{} at {:.4f} rad, its range {:.4f} to {:.4f} rad", j + 1, q, lim.q_min, lim.q_max);
    else if (std::abs(qd) > kSpeedLimitFactor * lim.qd_max)
      what = fmt::format("J{} at {:.2f} rad/s, beyond {:g} times its limit {:.2f} rad/s", j + 1, qd, kSpeedLimitFactor, lim.qd_max);
    if (what.empty()) continue;
    // (the faults that had begun by then: a later one, or one on another arm's joint, explains nothing)
    std::string faults;
    for (const FaultSpec& f : faults_)
      if ((f.type == FaultType::Collision || f.type == FaultType::Resistance) && f.onset <= t_)
        faults += fmt::format("{}{} of {:g} N·m from {:g} s", faults.empty() ? "" : ", ", to_string(f.type), f.magnitude, f.onset);
    throw InvalidArgument(fmt::format("the simulated arm left its limits at {:.3f} s: {} (a real controller stops the arm there, a "
                                      "protective stop); {}",
                                      s.timestamp, what,
                                      faults.empty() ? "is the trajectory within the robot's range and speeds?"
                                                     : "a fault beyond what the arm can take? the scenario's " + faults));
  }
}

void Simulator::run(const std::function<void(const RobotSample&)>& sink, const std::function<void(double)>& progress) {
  const long steps = static_cast<long>(std::llround(opt_.duration * opt_.rate));
  RobotSample s;
  const long report_every = std::max(1L, steps / 100);
  for (long k = 0; k < steps; ++k) {
    if (!step(s)) continue;
    // a state that is no number is no recording: the arm's integration diverged (a fault or a noise
    // far beyond what the arm can take, e.g. a contact of 1e6 N·m); said, never written as NaN
    if (!s.q.allFinite() || !s.qd.allFinite() || !s.current.allFinite())
      throw InvalidArgument(fmt::format("the simulation diverged at {:.3f} s (a joint's position, velocity or current is not finite): "
                                        "a fault magnitude or a noise level far beyond what the arm can take{}",
                                        s.timestamp, faults_.empty() ? std::string() : " (the scenario's faults: check their magnitudes)"));
    sink(s);
    if (progress && k % report_every == 0) progress(static_cast<double>(k) / static_cast<double>(steps));
  }
  if (progress) progress(1.0);
}

}  // namespace twinwatch::sim
