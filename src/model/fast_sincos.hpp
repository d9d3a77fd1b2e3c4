#pragma once
// sin and cos of a joint angle at once, for the dynamics kernels.
//
// Why not std::sin/std::cos: in the RNEA of a 6-joint arm libm's sincos took a third of the time
// (perf, docs/benchmarks.md). Joint angles are small (|q| < a few turns), so a Cody–Waite
// reduction to [-pi/4, pi/4] with pi/2 split in three parts and fdlibm's minimax polynomials give results within ~2 ulp of libm at a fraction of the cost. Angles beyond
// kFastRange fall back to libm.
#include <Eigen/Core>
#include <cmath>

namespace twinwatch::model::detail {

inline void fast_sincos(double x, double& s, double& c) {
  // beyond this the 3-part reduction loses bits; joint angles never get there
  constexpr double kFastRange = 1e5;
  if (!(std::abs(x) < kFastRange)) {
    s = std::sin(x);
    c = std::cos(x);
    return;
  }
  constexpr double kTwoOverPi = 0.63661977236758134308;
  // pi/2 = P1 + P2 + P3 (Cody–Waite; P1, P2 have trailing zero bits so k * Pi is exact)
  constexpr double P1 = 1.5707963267341256e+00;
  constexpr double P2 = 6.0771005065061922e-11;
  constexpr double P3 = 2.0222662487959506e-21;
  const double k = std::floor(x * kTwoOverPi + 0.5);
  const double r = ((x - k * P1) - k * P2) - k * P3;
  const double r2 = r * r;
  // minimax polynomials of fdlibm's __kernel_sin / __kernel_cos (|r| <= pi/4, error < 1 ulp
  // of the polynomial); two short independent Horner chains
  constexpr double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                   S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                   S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
  constexpr double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                   C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                   C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
  const double r4 = r2 * r2;
  const double sr = r + r * r2 * (S1 + r2 * (S2 + r2 * S3) + r4 * r2 * (S4 + r2 * (S5 + r2 * S6)));
  const double hz = 0.5 * r2;
  const double w = 1.0 - hz;
  const double cpoly = r4 * (C1 + r2 * (C2 + r2 * C3) + r4 * r2 * (C4 + r2 * (C5 + r2 * C6)));
  // fdlibm's compensation: cos = w + (((1 - w) - hz) + cpoly)
  const double cr = w + (((1.0 - w) - hz) + cpoly);
  // quadrant
  const long q = static_cast<long>(k) & 3;
  switch (q) {
    case 0: s = sr; c = cr; break;
    case 1: s = cr; c = -sr; break;
    case 2: s = -sr; c = -cr; break;
    default: s = -cr; c = sr; break;
  }
}

// parent_R_body = R0 * Rz(theta), written column by column (Rz only mixes columns 0 and 1);
// shared by the RNEA, CRBA, kinematics and the regressor.
inline void rotate_about_z(const Eigen::Matrix3d& R0, double theta, Eigen::Matrix3d& R) {
  double s, c;
  fast_sincos(theta, s, c);
  R.col(0) = c * R0.col(0) + s * R0.col(1);
  R.col(1) = c * R0.col(1) - s * R0.col(0);
  R.col(2) = R0.col(2);
}

}  // namespace twinwatch::model::detail
