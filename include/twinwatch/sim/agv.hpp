#pragma once
/// @file agv.hpp
/// Differential-drive AGV with two DC motors [AGV §3–4]: the "real" robot stand-in and its twin are
/// two instances with different parameters. Motor model at the wheel axle (gearbox 120:1 inside):
///   U = Ra i + k w            (eq. 1-2, inductance neglected)
///   J dw/dt = k i - Tq sign(w) - B w   (eq. 4; static friction holds the wheel while |k i| <= Tq)
/// Quadrature encoders with 3840 ticks per wheel revolution; the controller estimates wheel speed
/// from encoder ticks per sample period (40 ms by default); a caster carries no torque.
#include <cstdint>
#include <random>

namespace twinwatch::sim {

struct DcMotorParams {
  double Ra = 6.16;     ///< armature resistance [Ohm]
  double k = 0.32;      ///< back-emf = torque constant [V·s/rad = N·m/A]
  double Tq = 0.021;    ///< static (Coulomb) friction torque [N·m]
  double B = 3.2e-3;    ///< viscous friction [N·m·s/rad]
  double J = 3.39e-3;   ///< rotor + wheel inertia [kg·m²]
  /// Open-loop time constant J Ra / (B Ra + k²) [s] and gain k / (B Ra + k²) [rad/s/V] (eq. 6).
  double time_constant() const { return J * Ra / (B * Ra + k * k); }
  double gain() const { return k / (B * Ra + k * k); }
  void validate(const char* which) const;
};

/// AGV Table 1 (right and left motors of the real robot).
DcMotorParams agv_table1_right();
DcMotorParams agv_table1_left();

enum class AgvFault { None, MotorVoltageZero, BlockedWheel, WheelSlip, EncoderDropout };

struct AgvParams {
  DcMotorParams right = agv_table1_right(), left = agv_table1_left();
  double wheel_radius = 0.0325;   ///< [m]
  double track = 0.15;            ///< distance between the wheels [m]
  int ticks_per_rev = 3840;       ///< quadrature, after the 120:1 gearbox
  double voltage_limit = 6.0;     ///< [V]
  double current_noise = 0.002;   ///< [A] measurement noise
  void validate() const;
};

/// Wheel speeds and body velocity estimated from the encoders.
struct AgvState {
  double t = 0.0;
  double w_right = 0.0, w_left = 0.0;   ///< wheel speed estimates [rad/s]
  double v = 0.0, w = 0.0;              ///< body linear [m/s] and angular [rad/s] speed
  double u_right = 0.0, u_left = 0.0;   ///< applied voltages [V]
  double i_right = 0.0, i_left = 0.0;   ///< measured currents [A]
  std::int32_t enc_right = 0, enc_left = 0;
};

/// The plant. step() integrates the two motors at a fine internal step and updates the encoder
/// estimates once per call (one control period).
class AgvPlant {
 public:
  explicit AgvPlant(AgvParams p, unsigned seed = 1);
  /// Applies voltages [V] (clamped to the limit) for `dt` seconds; returns the measured state.
  const AgvState& step(double u_right, double u_left, double dt);
  void set_fault(AgvFault f, int wheel = 2) { fault_ = f, fault_wheel_ = wheel; }
  const AgvParams& params() const { return p_; }
  /// True wheel speeds (evaluation only).
  double true_w_right() const { return wr_; }
  double true_w_left() const { return wl_; }

 private:
  AgvParams p_;
  AgvState s_;
  double wr_ = 0.0, wl_ = 0.0, th_r_ = 0.0, th_l_ = 0.0;
  AgvFault fault_ = AgvFault::None;
  int fault_wheel_ = 2;  // 0 right, 1 left, 2 both
  std::mt19937 rng_;
  std::normal_distribution<double> n01_{0.0, 1.0};
};

/// PI speed controller tuned by IMC for a first-order plant [AGV Table 2]:
///   Kc = tau / (g_p (tau_cl + t_d)),  Ti = tau,  Td = 0.
struct PiGains {
  double Kc = 0.0, Ti = 0.0;
};
PiGains imc_pi(double g_p, double tau, double tau_cl, double dead_time = 0.0);

/// Discrete PI (forward Euler integral, anti-windup by clamping) producing a voltage.
class PiController {
 public:
  PiController(PiGains g, double u_limit) : g_(g), lim_(u_limit) {}
  double update(double reference, double measured, double dt);
  void reset() { integral_ = 0.0; }

 private:
  PiGains g_;
  double lim_;
  double integral_ = 0.0;
};

}  // namespace twinwatch::sim
