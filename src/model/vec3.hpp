#pragma once
// Plain 3-vectors and 3x3 rotations for the recursive kernels (RNEA, regressor).
//
// Why not Eigen::Vector3d there: with Eigen 3-vectors (one SSE2 packet plus one scalar each)
// and the recursion state read back through DynamicsData, the RNEA took 27 % more time, although
// it executed slightly fewer instructions (docs/benchmarks.md, issue 2, step 2). These structs
// stay in registers and compile to straight scalar code with short dependency chains.
#include <Eigen/Core>

namespace twinwatch::model::detail {

struct V3 {
  double x, y, z;
};

inline V3 load(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
inline void store(const V3& v, Eigen::Vector3d& out) {
  double* o = out.data();
  o[0] = v.x, o[1] = v.y, o[2] = v.z;
}

inline V3 operator+(const V3& a, const V3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(double s, const V3& a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(const V3& a, const V3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

/// 3x3 matrix by columns (c0, c1, c2), as Eigen stores it.
struct M3 {
  V3 c0, c1, c2;
};

inline M3 load(const Eigen::Matrix3d& m) {
  return {{m(0, 0), m(1, 0), m(2, 0)}, {m(0, 1), m(1, 1), m(2, 1)}, {m(0, 2), m(1, 2), m(2, 2)}};
}
inline void store(const M3& m, Eigen::Matrix3d& out) {
  double* o = out.data();  // column-major
  o[0] = m.c0.x, o[1] = m.c0.y, o[2] = m.c0.z, o[3] = m.c1.x, o[4] = m.c1.y, o[5] = m.c1.z;
  o[6] = m.c2.x, o[7] = m.c2.y, o[8] = m.c2.z;
}
/// M x
inline V3 mul(const M3& m, const V3& v) {
  return {m.c0.x * v.x + m.c1.x * v.y + m.c2.x * v.z, m.c0.y * v.x + m.c1.y * v.y + m.c2.y * v.z,
          m.c0.z * v.x + m.c1.z * v.y + m.c2.z * v.z};
}
/// M^T x
inline V3 mul_t(const M3& m, const V3& v) { return {dot(m.c0, v), dot(m.c1, v), dot(m.c2, v)}; }

/// parent_R_body = R0 Rz(theta) from s = sin(theta), c = cos(theta): Rz only mixes columns 0 and 1.
inline M3 rotate_about_z(const M3& R0, double s, double c) {
  return {c * R0.c0 + s * R0.c1, c * R0.c1 - s * R0.c0, R0.c2};
}

/// Symmetric 3x3 matrix [xx xy xz; xy yy yz; xz yz zz] (inertia tensors).
struct S3 {
  double xx, xy, xz, yy, yz, zz;
};
inline S3 load_sym(const Eigen::Matrix3d& m) { return {m(0, 0), m(0, 1), m(0, 2), m(1, 1), m(1, 2), m(2, 2)}; }
inline V3 mul(const S3& I, const V3& v) {
  return {I.xx * v.x + I.xy * v.y + I.xz * v.z, I.xy * v.x + I.yy * v.y + I.yz * v.z,
          I.xz * v.x + I.yz * v.y + I.zz * v.z};
}

}  // namespace twinwatch::model::detail
