#pragma once
/// @file diagnosis.hpp
/// Fault isolation beyond [UR3e] Table 5: the residual torque over a window is fitted to fault
/// signatures derived from the rigid-body model, and the best hypothesis is reported with its size.
///
/// Signatures (r = measured - predicted joint torque, window samples k):
/// - Resistance on joint j:  r_k = e_j (c sign(qd_jk) + v qd_jk)           (2 unknowns, one joint)
/// - Payload change:         r_k = J_n(q_k)^T W(dm, dh; w, wd, a of link n)  (4 unknowns: dm, dm*c)
///   the wrench a point-like payload change exerts on the last link (inertia terms neglected);
/// - Contact on link l:      r_k = J_l(q_k, p_l)^T F_k                        (3 unknowns per sample)
///   with p_l the middle of link l; joints after l see nothing, which is what isolates the link.
///   With the momentum observer's estimate (the `reference` argument), the link is a Bayesian model
///   choice on the pulse's joint impulse: the contact point integrated over the link's equivalent
///   inertia box, the force under a scale-free Gaussian prior (diagnosis.cpp, link_evidence);
/// - Sensor fault on joint j: one channel frozen (identical values) or offset while the others agree.
/// The explained fraction of ||r||² decides; ties go to the simpler hypothesis.
#include <limits>
#include <string>
#include <vector>

#include "twinwatch/core/types.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "twinwatch/monitor/event.hpp"

namespace twinwatch::monitor {

/// One sample of the diagnosis window.
struct DiagnosisSample {
  double t = 0.0;
  VectorJ q, qd, qdd;
  VectorJ r_tau;       ///< residual torque [N·m]: the current residual times the drive gain
  /// the measured drive torque, a back-driven joint's through its c_gen (the observer's reading),
  /// less the twin's [N·m]: what sizes a payload change (empty: r_tau). r_tau reads a back-driven
  /// joint's torque c_gen (0.77) low and a payload change 10-15 % small; the hypotheses are still
  /// scored on r_tau, whose shape the rules were tuned on
  VectorJ r_drive;
  VectorJ current;     ///< measured current [A] (for frozen-channel checks)
  VectorJ tau_ext;     ///< momentum-observer estimate of the external torque [N·m] (empty: none)
  VectorJ tau_ext_level;  ///< the observer's healthy bound (its threshold) at this sample [N·m]
  VectorJ presliding;  ///< the twin's pre-sliding state h at this sample (ident::FrictionMemory::h)
  /// the drive's direction read with the target at this sample (ident::FrictionMemory::direction)
  VectorJ direction;
  std::uint64_t digital_outputs = 0;
  bool gap_before = false;
};

/// One hypothesis and how well it explains the window.
struct Hypothesis {
  FaultClass fault = FaultClass::Unknown;
  int joint = -1;
  int link = -1;
  double magnitude = 0.0;
  std::string units;
  double explained = 0.0;  ///< fraction of sum ||r||² explained, [0, 1]
  std::string detail;
  /// Contacts: other links that explain the joint torques as well as `link` (best first), e.g. a
  /// force through the contact link's own joint axis leaves that joint untouched; empty otherwise.
  std::vector<int> other_links;
  ContactImpulse contact;  ///< contacts isolated on the observer's estimate: what the link choice read
  /// Contacts whose link was chosen on the observer's impulse: the named link's posterior
  /// probability among the links (the "% likely" of the detail); 1 where no link was chosen
  double link_share = 1.0;
  /// the share of the window's residual energy beyond the noise expected in it (the reference's
  /// variance per joint) that the signature explains, net of the noise its own fit absorbs (a
  /// contact's per-sample force), [0, 1]; NaN where no reference gives the noise
  double beyond_noise = std::numeric_limits<double>::quiet_NaN();
};

struct DiagnosisOptions {
  double collision_max_duration = 0.25;  ///< [s] exceedances shorter than this read as a pulse
  int frozen_samples = 25;               ///< identical consecutive current values that mark a stuck channel
  /// [s] when the alert was raised (NaN: any time): a frozen channel explains it only when frozen at
  /// its raise. A persistent alert looked at again later must not take another stretch's freeze in
  /// its window for its cause (the Kinova log: a J5 alert raised at 0.05 s became "J1 frozen" when
  /// J1 froze at 1.55 s, which the monitor reported as an event of its own; audit of session 55)
  double raised_at = std::numeric_limits<double>::quiet_NaN();
  double min_explained = 0.35;           ///< below this the class is Unknown
  /// centre of mass of a payload change, in the last link frame [m]: the declared payload's (a
  /// short window cannot resolve a free COM; the mass alone is fitted)
  Eigen::Vector3d payload_com = Eigen::Vector3d::Zero();
  /// per joint, the friction torque a joint at rest can hold [N·m] (the twin's Coulomb level plus
  /// its Stribeck rise): a contact torque below it does not move the joint and does not show in its
  /// current. Empty (or 0 for a joint): unknown, and a joint at rest tells the contact isolation
  /// nothing.
  VectorJ static_friction;
  /// The measured channel reads a resting joint's load as well as a moving one's: joint torque
  /// sensors, which sit between the gear and the link, so friction holds nothing back from them
  /// (ident::TwinModel::Signal::JointTorque). A joint at rest then weighs in the contact isolation as
  /// a moving one does, and static_friction is not used.
  bool rest_visible = false;
  /// The measured channel's name and unit in what the diagnosis says ("current", "A"; "torque", "N·m")
  std::string channel = "current";
  std::string channel_unit = "A";
  void validate() const;
};

/// Fits the signatures to a window. Allocates (runs once per alert, off the per-sample path).
/// @param alert_duration how long the threshold was exceeded [s] (shape: pulse vs persistent)
/// @param alert_joint joint whose threshold tripped first
/// @return hypotheses sorted best first (never empty: the last resort is Unknown)
std::vector<Hypothesis> diagnose(const model::RobotModel& model, const std::vector<DiagnosisSample>& window,
                                 double alert_duration, int alert_joint, const DiagnosisOptions& options = {},
                                 const std::vector<DiagnosisSample>* reference = nullptr);

/// The payload-change signature alone, fitted on `window` (a point mass at `com`, last link frame
/// [m]): magnitude [kg], from the drive torque (r_drive), and the share of sum ||r_tau||² it
/// explains. What `diagnose` scores as its payload hypothesis; the monitor's check after a gripper
/// output change reads it on samples that raised no alert. A joint slower than `min_speed` [rad/s]
/// at a sample is left out of the fit there (0: none).
Hypothesis fit_payload_change(const model::RobotModel& model, const std::vector<DiagnosisSample>& window, const Eigen::Vector3d& com,
                              double min_speed = 0.0);

/// Posterior probability of each link (uniform prior over the links) for a contact of joint
/// impulse `impulse` [N·m·s] whose rows have sd `sigma` [N·m·s], at configuration q: the Bayesian
/// model choice the diagnosis names the contact link with (diagnosis.cpp, link_evidence; the
/// contact point uniform in the link's equivalent inertia box, or, with `cube_half` > 0 [m], in a
/// cube of that half extent around the link's centre of mass along its body axes: a test
/// generator's own distribution). Allocates. `evaluate --link-ceiling` runs it on the simulator's
/// true impulse.
std::vector<double> contact_link_posterior(const model::RobotModel& model, const VectorJ& q, const VectorJ& impulse,
                                           const VectorJ& sigma, double cube_half = 0.0);

/// Cross-correlation matrix between residuals (rows) and joint velocities (columns) over a
/// window, as printed in [UR3e] Table 5 (Pearson coefficients at lag 0), a sample at a time: a report
/// streams a day's recording through it instead of holding the samples. Welford's running means and
/// co-moments (one pass, no loss of digits where a mean stands far above the spread, as a current
/// offset does). Allocation-free after construction.
class ResidualVelocityCorrelation {
 public:
  explicit ResidualVelocityCorrelation(int n_dof);
  /// throws InvalidArgument for a vector of another size than n_dof
  void add(const VectorJ& residual, const VectorJ& qd);
  long count() const { return k_; }
  /// C(i, j): residual i against velocity j; 0 where either does not vary. Throws InvalidArgument
  /// before any sample
  MatrixJ matrix() const;

 private:
  long k_ = 0;
  VectorJ mr_, mv_, vr_, vv_;
  MatrixJ cov_;
};

}  // namespace twinwatch::monitor
