#pragma once
/// @file threshold.hpp
/// Residual thresholds learned from healthy runs.
///
/// - Static, per joint [UR3e §4.1]: thr_j = max nominal MAE_j + 3 sigma_j, where sigma_j is the
///   standard deviation of the healthy residual of joint j.
/// - Dynamic, state-dependent [Cao eq. 24-26]:
///     |r_i| < r_det_i = Psi_i u_i + upsilon_i,   u_i = [|qdd_i|, |qd_i|, exp(-rho_i |qd_i|)]
///   with Psi_i = diag(psi_i1, psi_i2, psi_i3) >= 0 and upsilon_i from the convex program
///     min alpha (+ w mean_k r_det_i(k), see mean_gap_weight)
///     s.t.  xi_i <= r_det_i(k) - |r_i(k)| <= alpha   for every healthy sample k,
///   solved as a linear program with COIN-OR CLP. rho_i, which the paper tunes by hand, is chosen
///   from a grid by the smallest alpha.
///
/// Both are evaluated in O(1) per sample without allocation; both scale with a user sensitivity
/// factor per joint (1 = as learned, < 1 more sensitive).
#include <cmath>
#include <span>
#include <string>
#include <vector>

#include "twinwatch/core/types.hpp"

namespace twinwatch::monitor {

/// Static per-joint threshold [UR3e §4.1].
struct StaticThreshold {
  VectorJ level;  ///< threshold on |residual| per joint (units of the residual)

  /// Learns max-MAE + k_sigma * sigma per joint from healthy residual runs.
  /// @param runs residual vectors of each healthy run (each sample: n_dof values)
  /// @param k_sigma multiplier of the standard deviation (3 in the paper)
  /// Throws InvalidArgument on empty input or inconsistent sizes.
  static StaticThreshold learn(const std::vector<std::vector<VectorJ>>& runs, double k_sigma = 3.0);
};

/// StaticThreshold::learn a residual at a time, for runs read and not held (learn_thresholds): add()
/// each residual of a run, end_run() after each run (a run with none is no run), then learn().
/// The same sums in the same order: the same levels.
class StaticThresholdAccumulator {
 public:
  /// Throws InvalidArgument naming the run and the sample for a residual of another size than the
  /// first, or one not finite (one NaN would make every level NaN, and a NaN threshold never trips).
  void add(const VectorJ& v);
  void end_run();
  int runs() const { return runs_; }
  /// Throws InvalidArgument without a run, or for k_sigma < 0.
  StaticThreshold learn(double k_sigma = 3.0) const;

 private:
  long n_ = -1;
  int runs_ = 0;
  size_t k_ = 0;  // residuals of the current run
  VectorJ mae_, level_, sum_, sum2_;
  double count_ = 0.0;
};

/// Options of the dynamic-threshold fit.
struct DynamicThresholdOptions {
  double margin = 0.0;        ///< xi_i: minimum distance between threshold and healthy |r| (units of r); <= 0: auto = 3 * MAD-sigma of r
  std::vector<double> rho_grid{2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0};  ///< candidate rho_i [s/rad]
  int max_samples = 20000;    ///< healthy samples used per joint (uniformly decimated above that)
  /// Weight of the mean threshold level in the LP objective (alpha + w * mean r_det). Cao's eq. 26
  /// minimises alpha alone; on a twin's healthy misfit (largest just beside a reversal, ~0 at it) that
  /// prefers a flat threshold at the misfit's peak: on the identified UR3e the J1 observer threshold
  /// came out flat at 2.06 N·m while the misfit is <= 0.65 N·m away from reversals. With w = 10 the
  /// mean level dominates and the threshold follows the misfit (1.2 N·m at speed, 2.2 at reversals):
  /// 3 N·m contacts in 20 instead of 32 ms, no new false alarm (docs/validation.md). w = 1e-3 is Cao.
  double mean_gap_weight = 10.0;
  /// Throws InvalidArgument naming the first invalid field.
  void validate() const;
};

/// Parameters of one joint's dynamic threshold [Cao eq. 24-25].
struct DynamicThresholdJoint {
  double psi_qdd = 0.0;  ///< psi_i1, multiplies |qdd|
  double psi_qd = 0.0;   ///< psi_i2, multiplies |qd|
  double psi_rev = 0.0;  ///< psi_i3, multiplies exp(-rho |qd|) (velocity reversals)
  double upsilon = 0.0;  ///< upsilon_i, constant part
  double rho = 0.0;      ///< rho_i [s/rad]
  double margin = 0.0;   ///< xi_i used in the fit
  double alpha = 0.0;    ///< optimal max gap of the fit (diagnostic)

  /// r_det for the joint state [Cao eq. 24].
  double evaluate(double qd, double qdd) const {
    const double aqd = std::abs(qd);
    // the reversal term in single precision: the monitor evaluates it twice per joint and sample
    // (current residual and observer), and the double exp was ~6 % of the loop; its 1e-7 relative
    // error is far inside the margin xi the thresholds are learned with
    const double rev = psi_rev != 0.0 ? psi_rev * static_cast<double>(std::exp(static_cast<float>(-rho * aqd))) : 0.0;
    return psi_qdd * std::abs(qdd) + psi_qd * aqd + rev + upsilon;
  }
};

/// Summary of a dynamic-threshold fit for one joint.
struct DynamicThresholdFit {
  bool ok = false;
  std::string message;
  DynamicThresholdJoint params;
};

/// Fits one joint's dynamic threshold on healthy data [Cao eq. 26].
/// @param r residual samples, @param qd [rad/s], @param qdd [rad/s²]: equal lengths, >= 10.
DynamicThresholdFit fit_dynamic_threshold(std::span<const double> r, std::span<const double> qd,
                                          std::span<const double> qdd, const DynamicThresholdOptions& options = {});

/// fit_dynamic_threshold a sample at a time, for runs read and not held (learn_thresholds): it keeps
/// what the fit uses of `total` samples (the uniform decimation to options.max_samples and the 64
/// largest |r|), so `total` must be known before the first add(). Of samples tied at the 64th largest
/// |r| the earlier are kept (std::partial_sort, which fit_dynamic_threshold used before, kept any).
class DynamicThresholdSampler {
 public:
  /// Throws InvalidArgument for invalid options or fewer than 10 samples.
  DynamicThresholdSampler(size_t total, const DynamicThresholdOptions& options = {});
  /// the next sample; throws InvalidArgument naming it when it is not finite, or past `total`
  void add(double r, double qd, double qdd);
  /// after `total` add()s (InvalidArgument otherwise)
  DynamicThresholdFit fit() const;

 private:
  struct Kept {
    size_t k;
    double r, qd, qdd;
  };
  DynamicThresholdOptions options_;
  size_t total_, count_ = 0, wanted_ = 0, next_ = 0;  // next_: the uniform decimation's next sample
  std::vector<Kept> uniform_, largest_;  // largest_: a heap, the smallest |r| on top
};

/// The load a joint reverses under, as far as the direction of its drive is in doubt.
///
/// A drive's current for a torque tau is tau / g when it drives the joint (motoring) and
/// c_gen tau / g when the load drives it (back-driven, tau qd < 0; twin_model.hpp). Within a few
/// encoder counts of a reversal the measured velocity cannot say which: its sign is no better than
/// its resolution (3 mrad/s a count on a UR3e at 500 Hz), and a loaded joint may stick-slip across
/// zero for tens of ms. There the twin's blended prediction can be off by up to (1 - c_gen) times
/// the load. Measured on the virtual UR3e (docs/validation.md, "Thresholds that grow with the load"):
/// J4 reversing under 4 N·m (a 2 kg payload) stepped its current 0.50 -> 0.33 A and back twice
/// within 30 ms while the measured velocity read 0 or one count.
///
/// This returns |tau| times how much in doubt the direction is: 1 at qd = 0, falling to 0 as |qd|
/// passes a few `width` [rad/s]: 1 - |tanh(qd / width)|. The thresholds learned on healthy runs
/// already cover the reversals they saw; the monitor widens them only by the part of this load
/// beyond the largest one learned (MonitorConfig::reversal_load_max), times the step the switch
/// puts into each residual for it (Monitor::widen_for_load).
inline double reversal_load(double tau, double qd, double width) {
  const double x = std::abs(qd) / width;
  if (x > 20.0) return 0.0;  // (1 - tanh(20) < 1e-17; most samples are far from a reversal)
  return std::abs(tau) * (1.0 - std::tanh(x));
}

/// Dynamic thresholds for all joints.
struct DynamicThreshold {
  std::vector<DynamicThresholdJoint> joints;
  /// Fills level[i] = r_det_i for the state; level must have size n_dof (no allocation).
  void evaluate(const VectorJ& qd, const VectorJ& qdd, VectorJ& level) const;
};

}  // namespace twinwatch::monitor
