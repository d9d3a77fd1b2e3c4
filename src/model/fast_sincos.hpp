#pragma once
// sin and cos of a joint angle at once, for the dynamics kernels.
//
// Why not std::sin/std::cos: in the RNEA of a 6-joint arm libm's sincos took a third of the time
// (perf, docs/benchmarks.md). Joint angles are small (|q| < a few turns), so a Cody–Waite
// reduction to [-pi/4, pi/4] with pi/2 split in three parts and fdlibm's minimax polynomials give
// results within ~2 ulp of libm at a fraction of the cost. Angles beyond kFastRange fall back to
// libm. The kernels call fast_sincos_n once for all joints: the branch-free kernel lets GCC
// process two angles per SSE2 instruction.
#include <Eigen/Core>
#include <bit>
#include <cmath>
#include <cstdint>

namespace twinwatch::model::detail {

// beyond this the 3-part reduction loses bits; joint angles never get there
inline constexpr double kFastRange = 1e5;

// kernel shared by the scalar and the batched entry points: x must satisfy |x| < kFastRange.
// Branch-free (the quadrant is applied with bit masks), so a loop over joints vectorises with
// plain SSE2 (two angles per instruction) without any ISA flag.
inline void fast_sincos_kernel(double x, double& s, double& c) {
  constexpr double kTwoOverPi = 0.63661977236758134308;
  // adding 1.5 * 2^52 rounds to the nearest integer (default rounding mode) and leaves it in
  // the low mantissa bits: k without floor() (SSE4.1) and the quadrant from the same bits
  constexpr double kRoundShift = 6755399441055744.0;
  // pi/2 = P1 + P2 + P3 (Cody–Waite; P1, P2 have trailing zero bits so k * Pi is exact)
  constexpr double P1 = 1.5707963267341256e+00;
  constexpr double P2 = 6.0771005065061922e-11;
  constexpr double P3 = 2.0222662487959506e-21;
  const double t = x * kTwoOverPi + kRoundShift;
  const double k = t - kRoundShift;
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
  // quadrant q = k mod 4:  (s, c) = (sr, cr), (cr, -sr), (-sr, -cr), (-cr, sr)
  const std::uint64_t q = std::bit_cast<std::uint64_t>(t);
  const std::uint64_t swap = 0 - (q & 1);         // all ones in quadrants 1 and 3
  const std::uint64_t s_sign = (q & 2) << 62;      // sin negative in quadrants 2 and 3
  const std::uint64_t c_sign = ((q + 1) & 2) << 62;  // cos negative in quadrants 1 and 2
  const std::uint64_t sb = std::bit_cast<std::uint64_t>(sr), cb = std::bit_cast<std::uint64_t>(cr);
  s = std::bit_cast<double>(((cb & swap) | (sb & ~swap)) ^ s_sign);
  c = std::bit_cast<double>(((sb & swap) | (cb & ~swap)) ^ c_sign);
}

inline void fast_sincos(double x, double& s, double& c) {
  if (!(std::abs(x) < kFastRange)) {
    s = std::sin(x);
    c = std::cos(x);
    return;
  }
  fast_sincos_kernel(x, s, c);
}

// s[i], c[i] = sin, cos of x[i] for i < n, identical to fast_sincos element by element; the
// loop has no branch so the compiler processes two angles per SSE2 instruction.
inline void fast_sincos_n(const double* x, int n, double* s, double* c) {
  bool in_range = true;
  for (int i = 0; i < n; ++i) in_range &= std::abs(x[i]) < kFastRange;
  if (!in_range) {
    for (int i = 0; i < n; ++i) fast_sincos(x[i], s[i], c[i]);
    return;
  }
  for (int i = 0; i < n; ++i) fast_sincos_kernel(x[i], s[i], c[i]);
}

// parent_R_body = R0 * Rz(theta) from s = sin(theta), c = cos(theta), written column by column
// (Rz only mixes columns 0 and 1); used by the CRBA and the kinematics (the RNEA and the
// regressor use the vec3.hpp version).
inline void rotate_about_z(const Eigen::Matrix3d& R0, double s, double c, Eigen::Matrix3d& R) {
  R.col(0) = c * R0.col(0) + s * R0.col(1);
  R.col(1) = c * R0.col(1) - s * R0.col(0);
  R.col(2) = R0.col(2);
}

}  // namespace twinwatch::model::detail
