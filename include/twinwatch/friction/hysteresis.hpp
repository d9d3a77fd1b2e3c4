#pragma once
/// @file hysteresis.hpp
/// The HESR hysteresis state h, a measurement-derived memory coordinate reconstructed from the
/// joint velocity alone [HESR §IV-A]:
///
///   hd = -alpha * h + alpha * tanh(beta * qd)                                   (HESR eq. 10)
///
/// discretised by explicit Euler at the sample time dt:
///
///   h_k  = (1 - alpha*dt) * h_{k-1} + alpha*dt * tanh(beta * qd_k)
///   hd_k = -alpha * h_k + alpha * tanh(beta * qd_k)                              (HESR eq. 11)
///
/// The update is O(1) per sample, allocates nothing and never throws once constructed.
/// Stability: 0 < 1 - alpha*dt < 1 keeps the recursion non-oscillatory, and then |h_k| <= 1 for
/// every k whenever |h_0| <= 1 (HESR eq. 12: V = h^2/2 decreases outside [-1, 1]).
#include <span>
#include <vector>

namespace twinwatch::friction {

/// Parameters of the hysteresis state (HESR eq. 10).
struct HysteresisParams {
  double alpha = 10.0;  ///< relaxation rate (inverse memory time constant) [1/s], > 0
  double beta = 100.0;  ///< transition sharpness of tanh(beta*qd) [s/rad], > 0

  /// Throws InvalidArgument naming the field when alpha or beta is not a finite positive number.
  void validate() const;
  /// True when the Euler recursion (eq. 11) at sample time dt [s] satisfies 0 < 1 - alpha*dt < 1.
  bool stable(double dt) const noexcept;
};

/// One sample of the hysteresis features.
struct HysteresisSample {
  double h = 0.0;   ///< hysteresis state [-]
  double hd = 0.0;  ///< its time derivative [1/s]
};

/// The recursive hysteresis state (HESR eq. 11). Real-time safe: step() is O(1), no allocation.
class HysteresisState {
 public:
  /// @param params alpha, beta (validated)
  /// @param dt     sample time [s], > 0
  /// @param h0     initial state, |h0| <= 1
  /// Throws InvalidArgument on invalid params, dt <= 0, |h0| > 1, or when 1 - alpha*dt is
  /// outside (0, 1) (the stability condition of eq. 11).
  HysteresisState(HysteresisParams params, double dt, double h0 = 0.0);

  /// Advances by one sample with the measured velocity qd_k [rad/s]; returns (h_k, hd_k).
  HysteresisSample step(double qd) noexcept {
    const double drive = fast_tanh(params_.beta * qd);
    h_ = decay_ * h_ + alpha_dt_ * drive;
    return {h_, params_.alpha * (drive - h_)};
  }

  /// Resets the state to h0 (clamped to [-1, 1]).
  void reset(double h0 = 0.0) noexcept;
  double h() const noexcept { return h_; }
  const HysteresisParams& params() const noexcept { return params_; }
  double dt() const noexcept { return dt_; }

  /// tanh that saturates cheaply for |x| > 20 (std::tanh is exact to 1 ulp there anyway).
  static double fast_tanh(double x) noexcept;

 private:
  HysteresisParams params_;
  double dt_;
  double decay_;     ///< 1 - alpha*dt
  double alpha_dt_;  ///< alpha*dt
  double h_ = 0.0;
};

/// Batch features of a whole record (h_0 = 0 before the first sample).
struct HysteresisFeatures {
  std::vector<double> h;   ///< [-], size n
  std::vector<double> hd;  ///< [1/s], size n
};

/// Runs eq. 11 over the velocity record qd [rad/s] sampled every dt [s].
/// Throws as HysteresisState's constructor.
HysteresisFeatures hysteresis_features(std::span<const double> qd, double dt,
                                       const HysteresisParams& params);

}  // namespace twinwatch::friction
