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

#include <vector>

#include "twinwatch/device/agv_tests.hpp"
#include "twinwatch/model/dc_motor.hpp"

namespace twinwatch::sim {

using model::DcMotorParams;
using model::agv_table1_right;
using model::agv_table1_left;

enum class AgvFault { None, MotorVoltageZero, BlockedWheel, WheelSlip, EncoderDropout };

struct AgvParams {
  DcMotorParams right = model::agv_table1_right(), left = model::agv_table1_left();
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

/// Simulated motor tests on a plant [AGV §4.1]: fifteen steady-state voltages in (0, 6] V (robot
/// in the air, mean of the 40 ms readings after settling) and a 6 V step logged every 5 ms, with
/// the plant's measurement noise (speed from the encoders, current with noise).
std::vector<device::AgvTestRow> simulate_agv_tests(const AgvParams& params, unsigned seed);

}  // namespace twinwatch::sim
