#include "twinwatch/sim/trajectory.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>

#include "twinwatch/core/error.hpp"
#include "twinwatch/model/dynamics.hpp"

namespace twinwatch::sim {

namespace {

double wrap_time(double t, double period) {
  if (!(period > 0.0)) return t;
  const double r = std::fmod(t, period);
  return r < 0.0 ? r + period : r;
}

class Fourier final : public Trajectory {
 public:
  explicit Fourier(FourierCoefficients c) : c_(std::move(c)) {}
  int n_dof() const override { return static_cast<int>(c_.q0.size()); }
  double period() const override { return 2.0 * M_PI / c_.w_f; }
  void evaluate(double t, VectorJ& q, VectorJ& qd, VectorJ& qdd) const override {
    const int n = n_dof();
    q = c_.q0;
    qd.setZero(n);
    qdd.setZero(n);
    for (int l = 1; l <= c_.a.cols(); ++l) {
      const double w = l * c_.w_f, s = std::sin(w * t), co = std::cos(w * t);
      for (int j = 0; j < n; ++j) {
        const double a = c_.a(j, l - 1), b = c_.b(j, l - 1);
        q[j] += a / w * s - b / w * co;
        qd[j] += a * co + b * s;
        qdd[j] += -a * w * s + b * w * co;
      }
    }
  }
  std::optional<ClosedForm> closed_form() const override {
    // harmonic l: a/(l w_f) sin(l w_f t) - b/(l w_f) cos(l w_f t)
    const int n = n_dof(), L = static_cast<int>(c_.a.cols());
    ClosedForm f;
    f.q0 = c_.q0;
    f.s.resize(n, L);
    f.c.resize(n, L);
    for (int l = 1; l <= L; ++l) {
      const double w = l * c_.w_f;
      f.omega.push_back(w);
      f.sweep.push_back(0.0);
      f.s.col(l - 1) = c_.a.col(l - 1) / w;
      f.c.col(l - 1) = -c_.b.col(l - 1) / w;
    }
    return f;
  }

 private:
  FourierCoefficients c_;
};

class Sine final : public Trajectory {
 public:
  Sine(VectorJ q0, VectorJ A, VectorJ f, VectorJ phi) : q0_(q0), A_(A), f_(f), phi_(phi) {}
  int n_dof() const override { return static_cast<int>(q0_.size()); }
  double period() const override {
    double p = 0.0;
    for (int j = 0; j < f_.size(); ++j)
      if (f_[j] > 0) p = std::max(p, 1.0 / f_[j]);
    return p > 0 ? p : 1.0;
  }
  void evaluate(double t, VectorJ& q, VectorJ& qd, VectorJ& qdd) const override {
    const int n = n_dof();
    q.resize(n), qd.resize(n), qdd.resize(n);
    for (int j = 0; j < n; ++j) {
      const double w = 2 * M_PI * f_[j], s = std::sin(w * t + phi_[j]), c = std::cos(w * t + phi_[j]);
      q[j] = q0_[j] + A_[j] * s;
      qd[j] = A_[j] * w * c;
      qdd[j] = -A_[j] * w * w * s;
    }
  }
  std::optional<ClosedForm> closed_form() const override {
    // joint j's own component: A sin(w t + phi) = A cos(phi) sin(w t) + A sin(phi) cos(w t)
    const int n = n_dof();
    ClosedForm f;
    f.q0 = q0_;
    f.s = Eigen::MatrixXd::Zero(n, n);
    f.c = Eigen::MatrixXd::Zero(n, n);
    for (int j = 0; j < n; ++j) {
      f.omega.push_back(2 * M_PI * f_[j]);
      f.sweep.push_back(0.0);
      f.s(j, j) = A_[j] * std::cos(phi_[j]);
      f.c(j, j) = A_[j] * std::sin(phi_[j]);
    }
    return f;
  }

 private:
  VectorJ q0_, A_, f_, phi_;
};

class Chirp final : public Trajectory {
 public:
  Chirp(VectorJ q0, VectorJ A, double f0, double f1, double T) : q0_(q0), A_(A), f0_(f0), f1_(f1), T_(T) {}
  int n_dof() const override { return static_cast<int>(q0_.size()); }
  double period() const override { return T_; }
  void evaluate(double t, VectorJ& q, VectorJ& qd, VectorJ& qdd) const override {
    t = wrap_time(t, T_);
    // phase phi = 2 pi (f0 t + k t^2 / 2), k = (f1 - f0) / T; the sweep ends on a zero crossing
    // because A is faded by a raised-cosine window over the first and last 5 % of the sweep
    const double k = (f1_ - f0_) / T_;
    const double ph = 2 * M_PI * (f0_ * t + 0.5 * k * t * t);
    const double dph = 2 * M_PI * (f0_ + k * t), ddph = 2 * M_PI * k;
    const double edge = 0.05 * T_;
    double win = 1, dwin = 0, ddwin = 0;
    auto ramp = [&](double x, double sign) {  // raised cosine 0 -> 1 over [0, edge]
      const double u = M_PI * x / edge;
      win = 0.5 - 0.5 * std::cos(u);
      dwin = sign * 0.5 * std::sin(u) * M_PI / edge;
      ddwin = 0.5 * std::cos(u) * (M_PI / edge) * (M_PI / edge);
    };
    if (t < edge) ramp(t, 1.0);
    else if (t > T_ - edge) ramp(T_ - t, -1.0);
    const int n = n_dof();
    q.resize(n), qd.resize(n), qdd.resize(n);
    const double s = std::sin(ph), c = std::cos(ph);
    for (int j = 0; j < n; ++j) {
      const double A = A_[j];
      q[j] = q0_[j] + A * win * s;
      qd[j] = A * (dwin * s + win * c * dph);
      qdd[j] = A * (ddwin * s + 2 * dwin * c * dph + win * (-s * dph * dph + c * ddph));
    }
  }
  std::optional<ClosedForm> closed_form() const override {
    ClosedForm f;
    f.q0 = q0_;
    f.omega = {2 * M_PI * f0_};
    f.sweep = {2 * M_PI * (f1_ - f0_) / T_};
    f.s = A_;
    f.c = Eigen::MatrixXd::Zero(n_dof(), 1);
    f.wrap = T_;
    f.fade = 0.05 * T_;
    return f;
  }

 private:
  VectorJ q0_, A_;
  double f0_, f1_, T_;
};

// quintic blend 0 -> 1 with zero velocity and acceleration at both ends
void quintic(double s, double& p, double& v, double& a) {
  s = std::clamp(s, 0.0, 1.0);
  const double s2 = s * s, s3 = s2 * s;
  p = s3 * (10 - 15 * s + 6 * s2);
  v = 30 * s2 * (1 - 2 * s + s2);
  a = 60 * s * (1 - 3 * s + 2 * s2);
}

class Segments final : public Trajectory {
 public:
  // each segment: from, to, duration (quintic); from == to means hold; creep segments use a
  // constant-velocity profile flagged by `linear`
  struct Seg {
    VectorJ from, to;
    double T;
    bool linear;
  };
  explicit Segments(std::vector<Seg> segs) : segs_(std::move(segs)) {
    for (const auto& s : segs_) total_ += s.T;
  }
  int n_dof() const override { return static_cast<int>(segs_.front().from.size()); }
  double period() const override { return total_; }
  void evaluate(double t, VectorJ& q, VectorJ& qd, VectorJ& qdd) const override {
    t = wrap_time(t, total_);
    for (const auto& s : segs_) {
      if (t <= s.T || &s == &segs_.back()) {
        const double x = std::clamp(t / s.T, 0.0, 1.0);
        double p, v, a;
        if (s.linear) p = x, v = 1, a = 0;
        else quintic(x, p, v, a);
        q = s.from + p * (s.to - s.from);
        qd = v / s.T * (s.to - s.from);
        qdd = a / (s.T * s.T) * (s.to - s.from);
        return;
      }
      t -= s.T;
    }
  }

 private:
  std::vector<Seg> segs_;
  double total_ = 0.0;
};

// flange-position path sampled, solved by IK, then interpolated (cubic Hermite on q with
// numerically differentiated qd; qdd linear between samples)
class Sampled final : public Trajectory {
 public:
  Sampled(std::vector<VectorJ> q, double h) : q_(std::move(q)), h_(h) {
    const size_t N = q_.size();
    qd_.resize(N), qdd_.resize(N);
    for (size_t k = 0; k < N; ++k) {
      const VectorJ& qp = q_[(k + 1) % N];
      const VectorJ& qm = q_[(k + N - 1) % N];
      qd_[k] = (qp - qm) / (2 * h_);
      qdd_[k] = (qp - 2 * q_[k] + qm) / (h_ * h_);
    }
  }
  int n_dof() const override { return static_cast<int>(q_.front().size()); }
  double period() const override { return h_ * static_cast<double>(q_.size()); }
  void evaluate(double t, VectorJ& q, VectorJ& qd, VectorJ& qdd) const override {
    t = wrap_time(t, period());
    const size_t N = q_.size();
    const double x = t / h_;
    const size_t k = std::min(static_cast<size_t>(x), N - 1);
    const size_t k1 = (k + 1) % N;
    const double s = x - static_cast<double>(k);
    // cubic Hermite
    const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s, h01 = -2 * s * s * s + 3 * s * s,
                 h11 = s * s * s - s * s;
    q = h00 * q_[k] + h10 * h_ * qd_[k] + h01 * q_[k1] + h11 * h_ * qd_[k1];
    qd = (1 - s) * qd_[k] + s * qd_[k1];
    qdd = (1 - s) * qdd_[k] + s * qdd_[k1];
  }

 private:
  std::vector<VectorJ> q_, qd_, qdd_;
  double h_;
};

std::unique_ptr<Trajectory> cartesian(const model::RobotModel& m, const VectorJ& start, double period, double h,
                                      const std::function<Eigen::Vector3d(double)>& offset, const char* what,
                                      const std::function<Eigen::Matrix3d(double)>& rotation = {}) {
  model::DynamicsData d(m);
  const Eigen::Isometry3d T0 = model::forward_kinematics(m, d, start);
  const size_t N = static_cast<size_t>(std::ceil(period / h));
  const double hh = period / static_cast<double>(N);
  std::vector<VectorJ> qs;
  qs.reserve(N);
  VectorJ seed = start, q;
  for (size_t k = 0; k < N; ++k) {
    Eigen::Isometry3d T = T0;
    T.translation() += offset(hh * static_cast<double>(k));
    if (rotation) T.linear() = T0.linear() * rotation(hh * static_cast<double>(k));
    if (!inverse_kinematics(m, T, seed, q))
      throw InvalidArgument(fmt::format("{}: the path leaves the workspace at t = {:.3f} s (inverse kinematics did not converge)",
                                        what, hh * static_cast<double>(k)));
    qs.push_back(q);
    seed = q;
  }
  return std::make_unique<Sampled>(std::move(qs), hh);
}

}  // namespace

void ClosedForm::evaluate(double t, VectorJ& q, VectorJ& qd, VectorJ& qdd) const {
  const double u = wrap_time(t, std::isfinite(wrap) ? wrap : 0.0);
  double w = 1.0, dw = 0.0, ddw = 0.0;  // the fade and its derivatives in u
  if (fade > 0.0) {
    const bool rising = u < fade, falling = u > wrap - fade;
    if (rising || falling) {
      const double x = rising ? u : wrap - u, sign = rising ? 1.0 : -1.0, k = M_PI / fade;
      w = 0.5 - 0.5 * std::cos(k * x);
      dw = sign * 0.5 * k * std::sin(k * x);
      ddw = 0.5 * k * k * std::cos(k * x);
    }
  }
  const int n = n_dof();
  VectorJ y = VectorJ::Zero(n), yd = VectorJ::Zero(n), ydd = VectorJ::Zero(n);  // the sum before the fade
  for (int k = 0; k < components(); ++k) {
    const double th = omega[k] * u + 0.5 * sweep[k] * u * u, thd = omega[k] + sweep[k] * u, thdd = sweep[k];
    const double sn = std::sin(th), cs = std::cos(th);
    for (int j = 0; j < n; ++j) {
      const double S = s(j, k), C = c(j, k);
      y[j] += S * sn + C * cs;
      yd[j] += (S * cs - C * sn) * thd;
      ydd[j] += (S * cs - C * sn) * thdd - (S * sn + C * cs) * thd * thd;
    }
  }
  q = q0 + w * y;
  qd = dw * y + w * yd;
  qdd = ddw * y + 2 * dw * yd + w * ydd;
}

ClosedForm ClosedForm::slowed(double f) const {
  if (!(f > 0.0) || !std::isfinite(f)) throw InvalidArgument(fmt::format("a slow-down factor of {}, expected a finite number > 0", f));
  ClosedForm r = *this;
  for (double& w : r.omega) w /= f;
  for (double& a : r.sweep) a /= f * f;
  r.wrap *= f;  // (infinity stays)
  r.fade *= f;
  return r;
}

std::unique_ptr<Trajectory> make_fourier(const FourierCoefficients& c) {
  if (!(c.w_f > 0.0)) throw InvalidArgument(fmt::format("Fourier base pulsation w_f is {}, must be > 0", c.w_f));
  if (c.a.rows() != c.q0.size() || c.b.rows() != c.q0.size() || c.a.cols() != c.b.cols())
    throw InvalidArgument(fmt::format("Fourier coefficients a ({}x{}) and b ({}x{}) must both be n_dof ({}) x L", c.a.rows(),
                                      c.a.cols(), c.b.rows(), c.b.cols(), c.q0.size()));
  return std::make_unique<Fourier>(c);
}

FourierCoefficients random_fourier(const VectorJ& q0, double amplitude, double period, int harmonics, unsigned seed) {
  if (harmonics < 1) throw InvalidArgument(fmt::format("harmonics is {}, must be >= 1", harmonics));
  if (!(period > 0.0)) throw InvalidArgument(fmt::format("period is {}, must be > 0", period));
  FourierCoefficients c;
  c.w_f = 2 * M_PI / period;
  c.q0 = q0;
  const int n = static_cast<int>(q0.size());
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  c.a.resize(n, harmonics);
  c.b.resize(n, harmonics);
  for (int j = 0; j < n; ++j) {
    double bound = 0.0;
    for (int l = 1; l <= harmonics; ++l) {
      c.a(j, l - 1) = u(rng);
      c.b(j, l - 1) = u(rng);
      bound += (std::abs(c.a(j, l - 1)) + std::abs(c.b(j, l - 1))) / (l * c.w_f);
    }
    // scale so that |q - q0| <= amplitude for all t
    const double s = amplitude / bound;
    c.a.row(j) *= s;
    c.b.row(j) *= s;
  }
  return c;
}

std::unique_ptr<Trajectory> make_sine(const VectorJ& q0, const VectorJ& A, const VectorJ& f, const VectorJ& phi) {
  check_size("amplitude", A.size(), q0.size(), "q0");
  check_size("frequency", f.size(), q0.size(), "q0");
  check_size("phase", phi.size(), q0.size(), "q0");
  return std::make_unique<Sine>(q0, A, f, phi);
}

std::unique_ptr<Trajectory> make_chirp(const VectorJ& q0, const VectorJ& A, double f0, double f1, double sweep) {
  check_size("amplitude", A.size(), q0.size(), "q0");
  if (!(f0 > 0.0 && f1 > 0.0)) throw InvalidArgument(fmt::format("chirp frequencies are {} and {} Hz, must be > 0", f0, f1));
  if (!(sweep > 0.0)) throw InvalidArgument(fmt::format("chirp sweep is {} s, must be > 0", sweep));
  return std::make_unique<Chirp>(q0, A, f0, f1, sweep);
}

std::unique_ptr<Trajectory> make_point_to_point(const std::vector<VectorJ>& w, const std::vector<double>& T) {
  if (w.size() < 2) throw InvalidArgument(fmt::format("point-to-point has {} waypoints, expected at least 2", w.size()));
  if (T.size() != w.size())
    throw InvalidArgument(fmt::format("point-to-point has {} durations, expected {} (one per segment incl. the return)",
                                      T.size(), w.size()));
  std::vector<Segments::Seg> segs;
  for (size_t k = 0; k < w.size(); ++k) {
    if (!(T[k] > 0.0)) throw InvalidArgument(fmt::format("duration {} is {} s, must be > 0", k, T[k]));
    segs.push_back({w[k], w[(k + 1) % w.size()], T[k], false});
  }
  return std::make_unique<Segments>(std::move(segs));
}

std::unique_ptr<Trajectory> make_quasi_static(const std::vector<VectorJ>& poses, double delta, double creep, double hold) {
  if (poses.empty()) throw InvalidArgument("quasi-static trajectory has no poses");
  if (!(delta > 0.0 && creep > 0.0 && hold >= 0.0))
    throw InvalidArgument(fmt::format("quasi-static delta {}, creep speed {}, hold {}: expected > 0, > 0, >= 0", delta, creep, hold));
  std::vector<Segments::Seg> segs;
  const double move_T = 2.0, creep_T = delta / creep;
  VectorJ prev = poses.front() - VectorJ::Constant(poses.front().size(), delta);
  for (const VectorJ& p : poses) {
    const VectorJ below = p - VectorJ::Constant(p.size(), delta), above = p + VectorJ::Constant(p.size(), delta);
    segs.push_back({prev, below, move_T, false});
    segs.push_back({below, p, creep_T, true});  // approach from below at creep speed
    if (hold > 0) segs.push_back({p, p, hold, false});
    segs.push_back({p, above, move_T, false});
    segs.push_back({above, p, creep_T, true});  // approach from above
    if (hold > 0) segs.push_back({p, p, hold, false});
    prev = p;
  }
  segs.push_back({prev, poses.front() - VectorJ::Constant(prev.size(), delta), move_T, false});
  return std::make_unique<Segments>(std::move(segs));
}

std::string joint_limit_violation(const Trajectory& traj, const model::RobotModel& m, double duration, double rate) {
  check_size("trajectory joints", traj.n_dof(), m.n_dof(), "model.n_dof");
  // the controller reads the target at t = k dt (Simulator::step); one period holds every value a
  // cyclic trajectory takes, so a long run needs no more than that
  const double dt = 1.0 / rate;
  const long run_steps = std::llround(duration * rate);
  const double period = traj.period();
  const long steps = std::isfinite(period) ? std::min(run_steps, static_cast<long>(std::ceil(period * rate)) + 1) : run_steps;
  VectorJ q, qd, qdd;
  for (long k = 0; k < steps; ++k) {
    const double t = static_cast<double>(k) * dt;
    traj.evaluate(t, q, qd, qdd);
    for (int j = 0; j < m.n_dof(); ++j) {
      const model::JointLimits& l = m.joint(j).limits;
      if (!(q[j] >= l.q_min && q[j] <= l.q_max))
        return fmt::format("joint {} target position reaches {:.6g} rad at t = {:.6g} s, outside its range [{:.6g}, {:.6g}] rad ({})",
                           j + 1, q[j], t, l.q_min, l.q_max, m.name());
      if (!(std::abs(qd[j]) <= l.qd_max))
        return fmt::format("joint {} target velocity reaches {:.6g} rad/s at t = {:.6g} s, beyond its limit of {:.6g} rad/s ({})",
                           j + 1, qd[j], t, l.qd_max, m.name());
      // (a published acceleration limit, the Panda's: a scenario at 8.3 rad/s² against its 7.5 was
      // simulated; review of session 57)
      if (!(std::abs(qdd[j]) <= l.qdd_max))
        return fmt::format("joint {} target acceleration reaches {:.6g} rad/s² at t = {:.6g} s, beyond its limit of {:.6g} rad/s² ({})",
                           j + 1, qdd[j], t, l.qdd_max, m.name());
    }
  }
  return "";
}

bool inverse_kinematics(const model::RobotModel& m, const Eigen::Isometry3d& target, const VectorJ& seed, VectorJ& q) {
  model::DynamicsData d(m);
  q = seed;
  Matrix6J J;
  constexpr double kLambda = 1e-3;   // damping of the least-squares step
  constexpr double kTol = 1e-11;     // position [m] and rotation [rad] error to stop at
  for (int it = 0; it < 100; ++it) {
    const Eigen::Isometry3d T = model::forward_kinematics(m, d, q);
    Eigen::Matrix<double, 6, 1> e;
    e.head<3>() = target.translation() - T.translation();
    const Eigen::AngleAxisd dR(target.linear() * T.linear().transpose());
    e.tail<3>() = dR.axis() * dR.angle();
    if (e.norm() < kTol) return true;
    const int last = m.n_dof() - 1;
    model::point_jacobian(m, d, last, d.oMi[static_cast<size_t>(last)].inverse() * T.translation(), J);
    const Eigen::MatrixXd Jm = J;
    const Eigen::MatrixXd A = Jm * Jm.transpose() + kLambda * kLambda * Eigen::MatrixXd::Identity(6, 6);
    const Eigen::VectorXd dq = Jm.transpose() * A.ldlt().solve(Eigen::VectorXd(e));
    q += dq;
  }
  return false;
}

std::unique_ptr<Trajectory> make_figure_eight(const model::RobotModel& m, const VectorJ& start, double ax, double ay,
                                              double period, const Eigen::Vector3d& tilt, double h) {
  if (!(period > 0.0)) throw InvalidArgument(fmt::format("figure-eight period is {} s, must be > 0", period));
  // lemniscate of Gerono: x = ax sin(w t), y = ay sin(2 w t): smooth, periodic, starts at the centre
  const double w = 2 * M_PI / period;
  return cartesian(m, start, period, h,
                   [=](double t) { return Eigen::Vector3d(ax * std::sin(w * t), ay * std::sin(2 * w * t), 0.0); },
                   "figure-eight", [=](double t) {
                     const double s = std::sin(w * t);
                     return Eigen::Matrix3d(Eigen::AngleAxisd(tilt.x() * s, Eigen::Vector3d::UnitX()) *
                                            Eigen::AngleAxisd(tilt.y() * s, Eigen::Vector3d::UnitY()) *
                                            Eigen::AngleAxisd(tilt.z() * s, Eigen::Vector3d::UnitZ()));
                   });
}

std::unique_ptr<Trajectory> make_triangle(const model::RobotModel& m, const VectorJ& start, double side, double speed,
                                          double h) {
  if (!(side > 0.0 && speed > 0.0))
    throw InvalidArgument(fmt::format("triangle side {} m and speed {} m/s must be > 0", side, speed));
  // quintic edges: peak speed = 1.875 L / T
  const double Te = 1.875 * side / speed;
  const Eigen::Vector3d v0(0, 0, 0), v1(side, 0, 0), v2(side / 2, side * std::sqrt(3.0) / 2, 0);
  const Eigen::Vector3d verts[3] = {v0, v1, v2};
  return cartesian(m, start, 3 * Te, h,
                   [=](double t) {
                     const int e = std::min(static_cast<int>(t / Te), 2);
                     double p, v, a;
                     quintic((t - e * Te) / Te, p, v, a);
                     return Eigen::Vector3d(verts[e] + p * (verts[(e + 1) % 3] - verts[e]));
                   },
                   "triangle");
}

}  // namespace twinwatch::sim
