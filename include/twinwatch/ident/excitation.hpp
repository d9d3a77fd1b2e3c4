#pragma once
/// @file excitation.hpp
/// Excitation trajectory design for dynamic identification.
///
/// Each joint j follows a finite Fourier series [Cao eq. 21], [Swevers1997]:
///   q_j(t)   = q0_j + sum_{k=1..L} ( a_kj / (k w) sin(k w t) - b_kj / (k w) cos(k w t) )
///   qd_j(t)  =        sum_k ( a_kj cos(k w t) + b_kj sin(k w t) )
///   qdd_j(t) =        sum_k k w ( -a_kj sin(k w t) + b_kj cos(k w t) )
/// with base pulsation w = 2 pi f_b and period T = 1 / f_b. The boundary conditions of [Cao eq. 22]
/// (q(0) = q(T) = q0, qd = qdd = 0 at both ends) are linear in (a, b); since the series is
/// T-periodic, the conditions at t = T equal those at t = 0, and they read
///   sum_k a_kj = 0,   sum_k k b_kj = 0,   sum_k b_kj / k = 0.
/// **Construction:** these are eliminated exactly (no offset polynomial, no penalty): a_1j and
/// (b_1j, b_2j) are solved from the free coefficients a_2..a_L and b_3..b_L, so every candidate the
/// optimiser tries starts and ends at rest at q0 to round-off, and the trajectory can repeat for
/// whole cycles. Needs L >= 3 harmonics.
///
/// **Limits:** position (description limits minus a margin, intersected with q0 +- amplitude),
/// velocity (qd_max) and acceleration (qdd_max, or `default_qdd_max` where the description has
/// none), all scaled by `limit_fraction`, are enforced by projection: a candidate's joint j is
/// scaled by min(1, 1 / r_j), r_j its largest limit ratio on the optimisation grid (scaling keeps
/// the boundary conditions, which are homogeneous). The result is checked and, if needed, scaled
/// again on a dense grid, so the limits hold everywhere the dense grid looks.
///
/// **Objective:** the condition number of the observation matrix W stacked from the base regressor
/// Y_b(q, qd, qdd) (rigid body + per-joint Coulomb, viscous, offset columns, i.e. the unknowns of
/// rigid_body_ls.hpp) on `samples` points of one period [Swevers1997, HESR §III-C]. NLopt: a global
/// step (GN_CRS2_LM, controlled random search with local mutation) then a local one (LN_SBPLX).
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "twinwatch/core/types.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "twinwatch/model/regressor.hpp"
#include "twinwatch/model/robot_model.hpp"

namespace twinwatch::ident {

struct ExcitationOptions {
  int harmonics = 5;              ///< L, >= 3 (three coefficients per joint are fixed by the end conditions)
  double base_frequency = 0.1;    ///< f_b [Hz]; period 1 / f_b
  unsigned seed = 1;              ///< random start (and NLopt's own randomness)
  int samples = 100;              ///< grid points per period for cond(W)
  int check_samples = 5000;       ///< dense grid points per period for the final limit check
  VectorJ q0;                     ///< centre [rad]; empty: the middle of each joint's range (0 if unbounded)
  double amplitude = 1.0;         ///< largest excursion |q - q0| [rad] allowed besides the joint limits
  double position_margin = 0.05;  ///< [rad] kept away from q_min / q_max
  double limit_fraction = 0.9;    ///< share of qd_max / qdd_max (and of the position range) used
  double default_qdd_max = 5.0;   ///< [rad/s²] where the description publishes no acceleration limit
  int global_evaluations = 3000;  ///< NLopt GN_CRS2_LM budget (0: skip the global step)
  int local_evaluations = 3000;   ///< NLopt LN_SBPLX budget (0: skip the local step)
  model::FrictionColumns friction = model::FrictionColumns::CoulombViscousOffset;  ///< columns in W
  /// Lowest height [m] over the base's mounting plane (z = 0) the body origins after the first, the
  /// flange and the tool points may reach (excitation_lowest_point): a constraint of the search (a
  /// penalty on the design grid, kept 1 cm inside). -infinity: none. The result's `lowest`, on the
  /// dense grid, tells whether it held.
  double min_height = -std::numeric_limits<double>::infinity();
  /// Points of the tool mounted on the flange, in the flange frame [m] (a gripper's fingertips, a
  /// tool's corners): kept above min_height like the flange. A gripper 15 cm long reaches 15 cm
  /// lower than the flange the check would otherwise stop at. Each finite and within 2 m.
  std::vector<Eigen::Vector3d> tool_points;
  /// The installation's safety limits the program will run under (PolyScope: Installation > Safety >
  /// Robot Limits), model::CartesianSpeeds: the tool speed (the flange's centre and the tool points)
  /// [m/s], the elbow speed [m/s], the momentum of the links and of `carried` [kg·m/s]. +infinity: none. Each is linear in qd at a fixed pose, so they are enforced as
  /// the joint limits are, by projection: a candidate beyond one on the grid is scaled down as a whole
  /// (all joints alike) until it keeps them, and checked so on the dense grid.
  double tool_speed_max = std::numeric_limits<double>::infinity();
  double elbow_speed_max = std::numeric_limits<double>::infinity();
  double momentum_max = std::numeric_limits<double>::infinity();
  /// What the flange carries while the excitation runs (a gripper; mass and centre of mass in the
  /// flange frame): counted in the momentum only (the design's cond(W) is the arm's).
  model::RigidBodyInertia carried;
  /// Throws InvalidArgument naming the first bad field (q0 is checked against the model's joints).
  void validate(int n_dof) const;
};

/// Finite Fourier coefficients of an excitation (same layout as sim::FourierCoefficients).
struct ExcitationTrajectory {
  double w_f = 0.0;       ///< base pulsation [rad/s]
  VectorJ q0;             ///< centre = start = end position [rad]
  Eigen::MatrixXd a, b;   ///< n_dof x L
  double period() const { return 2.0 * M_PI / w_f; }
  /// q [rad], qd [rad/s], qdd [rad/s²] at time t [s].
  void evaluate(double t, VectorJ& q, VectorJ& qd, VectorJ& qdd) const;
};

/// The lowest point the arm reaches along a trajectory, in the base frame (z up from the mounting
/// surface the base stands on): over the origins of the body frames after the first, the flange and
/// the tool points. (A link between two of these points comes no lower than its ends: height is
/// linear along a segment.)
struct ExcitationLowestPoint {
  double z = std::numeric_limits<double>::infinity();  ///< [m]
  double t = 0.0;                                      ///< [s] when
  /// which: 1..n_dof-1 the origin of body (joint) body+1, n_dof the flange, n_dof+1+k tool point k
  int body = -1;
};

/// excitation_lowest_point on `samples` points of one period: what tells a trajectory that would
/// drive the arm or its tool (`tool_points`, flange frame [m]) into the table it stands on (the
/// design keeps above ExcitationOptions::min_height). Throws InvalidArgument on a bad tool point.
ExcitationLowestPoint excitation_lowest_point(const model::RobotModel& model, const ExcitationTrajectory& trajectory, int samples,
                                              const std::vector<Eigen::Vector3d>& tool_points = {});

/// A centre pose that holds the arm high: within each joint's limits (less position_margin; +-pi
/// where unbounded), the configuration that maximises the lowest point of the static pose (body
/// origins after the first, the flange and the tool points) plus a tenth of the mean height of the bodies
/// and the flange (the tie-break that stands the arm up), less a small pull to the middle of the ranges, from there (NLopt Subplex).
/// For `excite` when the middle
/// of the ranges (a UR's stretched-out zero pose, its flange 7 cm over the table) leaves the design
/// no room above min_height.
VectorJ excitation_raised_centre(const model::RobotModel& model, const ExcitationOptions& options);

struct ExcitationResult {
  ExcitationTrajectory trajectory;
  double cond_start = 0.0;        ///< cond(W) of the (projected) random start
  double cond_global = 0.0;       ///< after the global step
  double cond_final = 0.0;        ///< after the local step and the dense-grid check
  int evaluations = 0;            ///< objective evaluations
  int base_columns = 0;           ///< columns of W (base parameters incl. friction)
  VectorJ q_lo, q_hi, qd_lim, qdd_lim;  ///< the limits enforced [rad], [rad/s], [rad/s²]
  VectorJ q_min_seen, q_max_seen, qd_peak, qdd_peak;  ///< extremes on the dense grid
  ExcitationLowestPoint lowest;   ///< on the dense grid (no other collision check: the user's cell is unknown)
  /// peaks on the dense grid of model::CartesianSpeeds (tool_point: where the tool's peak is)
  model::CartesianSpeeds speed_peak;
};

/// Designs an excitation trajectory for `model`. `progress` (may be empty) gets (fraction done,
/// best cond so far). Throws InvalidArgument on bad options.
ExcitationResult design_excitation(const model::RobotModel& model, const ExcitationOptions& options,
                                   const std::function<void(double, double)>& progress = {});

/// cond(W) of a trajectory: W stacked from the base regressor on `samples` points of one period
/// (ratio of the largest to the smallest singular value; infinity if rank deficient).
double excitation_condition_number(const model::RobotModel& model, const ExcitationTrajectory& trajectory,
                                   int samples, model::FrictionColumns friction);

/// A complete scenario file (YAML) that `twinwatch simulate` runs: robot `robot`, `cycles` periods
/// of the trajectory (type fourier_series, see docs/scenarios.md). `comment` lines are prefixed
/// with '#'.
std::string excitation_scenario_yaml(const ExcitationTrajectory& trajectory, const std::string& robot, int cycles,
                                     const std::string& comment);

}  // namespace twinwatch::ident
