#pragma once
/// @file synthetic_joint.hpp
/// Residual-torque records of a simulated joint whose truth friction is a generalized
/// Maxwell-slip model (maxwell_slip.hpp), for the HESR evaluation protocol (§V): the joint
/// follows a velocity profile exactly; the record holds what a current-based pipeline would
/// measure: a velocity differentiated from a quantised encoder position and the friction torque
/// with Gaussian noise (HESR eq. 9: the rigid-body part is assumed already removed).
#include <functional>
#include <string>
#include <vector>

#include "twinwatch/friction/friction_model.hpp"
#include "twinwatch/friction/maxwell_slip.hpp"

namespace twinwatch::friction {

/// A joint-velocity profile.
struct VelocityProfile {
  std::string name;
  double duration = 20.0;                 ///< [s], > 0
  std::function<double(double)> qd;       ///< qd(t) [rad/s]
  std::function<double(double)> frequency;  ///< instantaneous frequency [Hz] (chirp), may be empty
};

/// qd = v sin(2 pi f t): the HESR residual-torque training sweep (0.25 Hz, 1.2 rad/s).
VelocityProfile sine_profile(double f, double v_amp, double duration);

/// Finite Fourier series qd = sum_{l=1..L} a_l sin(2 pi l f_b t) + b_l cos(2 pi l f_b t), the
/// coefficients drawn uniformly in [-1, 1] from `seed` and scaled so that max |qd| = v_amp
/// (the untrained validation trajectory, HESR Table VIII).
VelocityProfile fourier_profile(int harmonics, double f_base, double v_amp, double duration, unsigned seed);

/// The sweep qd = v sin(2 pi f t) for the first `sweep_time` (a whole number of periods, ending at
/// rest), then one plateau per entry of `crawls` [rad/s], each held for `crawl_time` [s] and entered
/// by a raised-cosine blend over its first `blend` [s] from the previous plateau (from 0 for the
/// first): slow constant-velocity sliding in both directions, which the sweep crosses in tens of ms.
VelocityProfile sweep_and_crawls_profile(double f, double v_amp, double sweep_time, const std::vector<double>& crawls,
                                         double crawl_time, double blend);

/// Linear chirp qd = v sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T))), T = duration (HESR §V-F).
VelocityProfile chirp_profile(double f0, double f1, double v_amp, double duration);

struct SyntheticJointOptions {
  double dt = 0.005;             ///< record sample time [s] (200 Hz), > 0
  int substeps = 10;             ///< truth integration steps per sample, >= 1
  double encoder_lsb = 5.99e-6;  ///< position quantisation [rad] (2 pi / 2^20), >= 0 (0: exact)
  double torque_noise = 0.05;    ///< Gaussian torque noise sigma [N·m], >= 0
  unsigned seed = 1;             ///< seeds the noise
  /// Throws InvalidArgument naming the first field out of range.
  void validate() const;
};

/// A simulated record and its noise-free truth.
struct SyntheticRecord {
  FrictionRecord record;           ///< measured qd (central difference of the quantised position), noisy tau_f
  std::vector<double> true_tau;    ///< truth friction at the sample instants [N·m]
  std::vector<double> true_qd;     ///< true velocity at the sample instants [rad/s]
  std::vector<double> q;           ///< measured (quantised encoder) position [rad], q(0) = 0
  std::vector<double> true_q;      ///< true position [rad]
  std::vector<double> true_qdd;    ///< true acceleration at the sample instants [rad/s^2] (central difference of qd(t), 1e-5 s)
  std::vector<double> frequency;   ///< profile frequency at the samples [Hz] (empty if the profile has none)
};

/// Runs the truth along the profile from relaxed elements at t = 0 (position by Simpson's rule on
/// the substeps). Throws InvalidArgument on bad options/profile (duration, missing qd).
SyntheticRecord simulate_joint(const MaxwellSlipParams& truth, const VelocityProfile& profile,
                               const SyntheticJointOptions& options = {});

/// The same from the truth's current state, advanced in place: a second call continues where the
/// first left off (one joint, two motions in a row). Evaluation only, like the truth itself.
SyntheticRecord simulate_joint(MaxwellSlipFriction& truth_state, const VelocityProfile& profile,
                               const SyntheticJointOptions& options = {});

}  // namespace twinwatch::friction
