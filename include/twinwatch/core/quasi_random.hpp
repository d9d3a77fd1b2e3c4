#pragma once
/// @file quasi_random.hpp
/// Deterministic quasi-random points (Halton): they fill a box evenly, so an average over them
/// converges faster than over pseudo-random ones and is the same on every run.

namespace twinwatch {

/// Halton radical inverse of i in `base` (a prime), in [0, 1): point i of a Halton sequence takes
/// one coordinate per base (2, 3, 5, 7, 11, ...).
inline double radical_inverse(int i, int base) {
  double f = 1.0, r = 0.0;
  for (int k = i; k > 0; k /= base) {
    f /= base;
    r += f * (k % base);
  }
  return r;
}

}  // namespace twinwatch
