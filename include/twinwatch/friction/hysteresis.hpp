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
///
/// Memory clock. Eq. 10 relaxes h in TIME (HysteresisDrive::Time, the paper's form). The
/// pre-sliding memory of a harmonic drive relaxes with DISPLACEMENT instead (a bristle/asperity
/// deflection is undone by moving, not by waiting: Dahl, LuGre's z, Maxwell-slip elements). With
/// HysteresisDrive::Displacement, eq. 10 is the same law written in the travelled-distance clock
/// s, ds = |qd| dt:
///
///   dh/ds = -alpha * h + alpha * tanh(beta * qd)      i.e.   hd = alpha |qd| (tanh(beta qd) - h)
///
/// -- eq. 10 with the relaxation rate alpha |qd| instead of alpha (alpha in [1/rad]: 1/alpha is the
/// pre-sliding distance), which is the Dahl model [Dahl1968] with exponent 1 (a Bouc-Wen state with n = 1,
/// A = beta_BW = gamma_BW). It is rate independent: the h-q loop is the same at any speed, and h
/// does not move while the joint stands still. It is discretised exactly for qd held over a step,
///
///   h_k  = T_k + (h_{k-1} - T_k) exp(-alpha |qd_k| dt),   T_k = tanh(beta qd_k)
///   hd_k = alpha |qd_k| (T_k - h_k),
///
/// because alpha |qd| dt is far above 1 at speed (1/alpha is a few mrad, a 200 Hz sample moves
/// several mrad) and Euler would oscillate there; the exact step keeps |h_k| <= 1 for any dt
/// (h_k is a convex combination of h_{k-1} and T_k), so eq. 12's bound holds unconditionally.
#include <cmath>
#include <span>
#include <vector>

namespace twinwatch::friction {

/// The clock in which h relaxes (see the file comment).
enum class HysteresisDrive {
  Time,         ///< HESR eq. 10-11 as printed: hd = -alpha h + alpha tanh(beta qd), alpha [1/s]
  Displacement, ///< eq. 10 in the displacement clock: hd = alpha |qd| (tanh(beta qd) - h), alpha [1/rad]
};

/// "time" / "displacement".
const char* to_string(HysteresisDrive d) noexcept;

/// Parameters of the hysteresis state (HESR eq. 10).
struct HysteresisParams {
  double alpha = 10.0;  ///< relaxation rate [1/s] (Time) or [1/rad] (Displacement), > 0
  double beta = 100.0;  ///< transition sharpness of tanh(beta*qd) [s/rad], > 0
  HysteresisDrive drive = HysteresisDrive::Time;

  /// Throws InvalidArgument naming the field when alpha or beta is not a finite positive number.
  void validate() const;
  /// True when the recursion at sample time dt [s] is stable: Time: 0 < 1 - alpha*dt < 1 (eq. 11);
  /// Displacement: always (exact exponential step), for dt > 0.
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
    if (params_.drive == HysteresisDrive::Time) {
      h_ = decay_ * h_ + alpha_dt_ * drive;
      return {h_, params_.alpha * (drive - h_)};
    }
    // displacement clock: exact step of dh/ds = alpha (T - h) over ds = |qd| dt
    const double rate = params_.alpha * std::abs(qd);
    h_ = drive + (h_ - drive) * std::exp(-rate * dt_);
    return {h_, rate * (drive - h_)};
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
