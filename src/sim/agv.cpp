#include "twinwatch/sim/agv.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::sim {

namespace {
// internal integration step of the motor ODE [s]: 20x below the fastest time constant (~0.17 s)
constexpr double kInternalStep = 0.0005;
// wheel speed below which static friction can hold the wheel [rad/s]
constexpr double kStickSpeed = 1e-3;
}  // namespace

void AgvParams::validate() const {
  right.validate("right");
  left.validate("left");
  if (!(wheel_radius > 0.0)) throw InvalidArgument(fmt::format("wheel_radius is {}, must be > 0", wheel_radius));
  if (!(track > 0.0)) throw InvalidArgument(fmt::format("track is {}, must be > 0", track));
  if (ticks_per_rev < 1) throw InvalidArgument(fmt::format("ticks_per_rev is {}, must be >= 1", ticks_per_rev));
  if (!(voltage_limit > 0.0)) throw InvalidArgument(fmt::format("voltage_limit is {}, must be > 0", voltage_limit));
}

AgvPlant::AgvPlant(AgvParams p, unsigned seed) : p_(p), rng_(seed) { p_.validate(); }

const AgvState& AgvPlant::step(double ur, double ul, double dt) {
  ur = std::clamp(ur, -p_.voltage_limit, p_.voltage_limit);
  ul = std::clamp(ul, -p_.voltage_limit, p_.voltage_limit);
  if (fault_ == AgvFault::MotorVoltageZero) {
    if (fault_wheel_ != 1) ur = 0.0;
    if (fault_wheel_ != 0) ul = 0.0;
  }
  const int enc_r0 = s_.enc_right, enc_l0 = s_.enc_left;
  double ir = 0.0, il = 0.0;
  // integrate J dw/dt = k i - Tq sign(w) - B w with i = (U - k w) / Ra
  auto motor = [&](const DcMotorParams& m, double u, double& w, double& th, double& i, bool blocked, double h) {
    i = (u - m.k * w) / m.Ra;
    if (blocked) {
      w = 0.0;
      i = u / m.Ra;
      return;
    }
    const double drive = m.k * i;
    if (std::abs(w) < kStickSpeed && std::abs(drive) <= m.Tq) {
      w = 0.0;  // static friction holds the wheel
      return;
    }
    const double sgn = std::abs(w) < kStickSpeed ? (drive > 0 ? 1.0 : -1.0) : (w > 0 ? 1.0 : -1.0);
    const double w_new = w + h * (drive - m.Tq * sgn - m.B * w) / m.J;
    // friction cannot reverse the motion: crossing zero with a drive below Tq means it sticks
    w = (w_new * w < 0.0 && std::abs(drive) <= m.Tq) ? 0.0 : w_new;
    th += h * w;
  };
  const int steps = std::max(1, static_cast<int>(std::ceil(dt / kInternalStep)));
  const double h = dt / steps;
  const bool block_r = fault_ == AgvFault::BlockedWheel && fault_wheel_ != 1;
  const bool block_l = fault_ == AgvFault::BlockedWheel && fault_wheel_ != 0;
  for (int k = 0; k < steps; ++k) {
    motor(p_.right, ur, wr_, th_r_, ir, block_r, h);
    motor(p_.left, ul, wl_, th_l_, il, block_l, h);
  }
  s_.t += dt;
  // encoders (wheel slip: the wheel turns but the encoder counts a fraction; dropout: no ticks)
  const double tick = 2.0 * M_PI / p_.ticks_per_rev;
  double th_r_seen = th_r_, th_l_seen = th_l_;
  if (fault_ == AgvFault::WheelSlip) {
    if (fault_wheel_ != 1) th_r_seen *= 0.5;
    if (fault_wheel_ != 0) th_l_seen *= 0.5;
  }
  if (fault_ != AgvFault::EncoderDropout || fault_wheel_ == 1) s_.enc_right = static_cast<std::int32_t>(std::floor(th_r_seen / tick));
  if (fault_ != AgvFault::EncoderDropout || fault_wheel_ == 0) s_.enc_left = static_cast<std::int32_t>(std::floor(th_l_seen / tick));
  s_.w_right = (s_.enc_right - enc_r0) * tick / dt;
  s_.w_left = (s_.enc_left - enc_l0) * tick / dt;
  s_.v = p_.wheel_radius * (s_.w_right + s_.w_left) / 2.0;
  s_.w = p_.wheel_radius * (s_.w_right - s_.w_left) / p_.track;
  s_.u_right = ur;
  s_.u_left = ul;
  s_.i_right = ir + p_.current_noise * n01_(rng_);
  s_.i_left = il + p_.current_noise * n01_(rng_);
  return s_;
}

PiGains imc_pi(double g_p, double tau, double tau_cl, double dead_time) {
  if (!(g_p > 0.0)) throw InvalidArgument(fmt::format("plant gain g_p is {}, must be > 0", g_p));
  if (!(tau > 0.0)) throw InvalidArgument(fmt::format("open-loop time constant is {} s, must be > 0", tau));
  if (!(tau_cl > 0.0)) throw InvalidArgument(fmt::format("closed-loop time is {} s, must be > 0", tau_cl));
  if (!(dead_time >= 0.0)) throw InvalidArgument(fmt::format("dead time is {} s, must be >= 0", dead_time));
  return {tau / (g_p * (tau_cl + dead_time)), tau};
}

double PiController::update(double ref, double meas, double dt) {
  const double e = ref - meas;
  const double candidate = integral_ + e * dt;
  const double u = g_.Kc * (e + candidate / g_.Ti);
  // anti-windup: only integrate while the output is not saturated
  if (std::abs(u) < lim_) integral_ = candidate;
  return std::clamp(g_.Kc * (e + integral_ / g_.Ti), -lim_, lim_);
}

std::vector<device::AgvTestRow> simulate_agv_tests(const AgvParams& params, unsigned seed) {
  // settling and measuring time of a steady-state point, the 40 ms sampling, the 5 ms step log [s]
  constexpr double kSettle = 2.0, kMeasure = 1.0, kPeriod = 0.04, kStepPeriod = 0.005;
  std::vector<device::AgvTestRow> rows;
  for (int m = 0; m < 2; ++m) {
    const std::string name = m == 0 ? "right" : "left";
    // steady state: fifteen voltages, robot in the air, mean of the 40 ms readings after settling
    for (int k = 1; k <= 15; ++k) {
      AgvPlant plant(params, seed + 31 * static_cast<unsigned>(k) + 7 * static_cast<unsigned>(m));
      const double U = 6.0 * k / 15.0;
      double w = 0, i = 0;
      int n = 0;
      for (double t = 0; t < kSettle + kMeasure; t += kPeriod) {
        const auto& s = plant.step(m == 0 ? U : 0.0, m == 1 ? U : 0.0, kPeriod);
        if (t >= kSettle) w += m == 0 ? s.w_right : s.w_left, i += m == 0 ? s.i_right : s.i_left, ++n;
      }
      rows.push_back({name, "steady", U, i / n, w / n, 0.0});
    }
    // step: 6 V from rest, encoder speed over each 5 ms sample
    AgvPlant plant(params, seed + 1000 + static_cast<unsigned>(m));
    for (double t = kStepPeriod; t <= 1.5; t += kStepPeriod) {
      const auto& s = plant.step(m == 0 ? 6.0 : 0.0, m == 1 ? 6.0 : 0.0, kStepPeriod);
      rows.push_back({name, "step", 6.0, m == 0 ? s.i_right : s.i_left, m == 0 ? s.w_right : s.w_left, t});
    }
  }
  return rows;
}

}  // namespace twinwatch::sim
