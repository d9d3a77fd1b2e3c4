#pragma once
/// @file dc_motor.hpp
/// A DC motor seen at its output axle (gearbox inside), inductance neglected [AGV eq. 1-6]:
///   U = Ra i + k w,   J dw/dt = k i - Tq sign(w) - B w
namespace twinwatch::model {

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

}  // namespace twinwatch::model
