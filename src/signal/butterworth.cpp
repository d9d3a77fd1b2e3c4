#include "twinwatch/signal/butterworth.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <complex>
#include <numeric>
#include <stdexcept>

#include "twinwatch/core/error.hpp"

namespace twinwatch::signal {

namespace {

using Complex = std::complex<double>;

bool is_real(Complex c) { return c.imag() == 0.0; }

// index of the element closest to the unit circle (scipy zpk2sos idx_worst, digital case);
// the first one wins a tie, as np.argmin
size_t idx_worst(const std::vector<Complex>& v, bool real_only = false) {
  size_t best = v.size();
  double dist = 0.0;
  for (size_t i = 0; i < v.size(); ++i) {
    if (real_only && !is_real(v[i])) continue;
    const double d = std::abs(1.0 - std::abs(v[i]));
    if (best == v.size() || d < dist) {
      best = i;
      dist = d;
    }
  }
  return best;
}

// index of the element of `from` nearest to `to`, restricted to real (kind 1), complex (kind 2)
// or any (kind 0) elements (scipy _nearest_real_complex_idx); v.size() when there is none
size_t nearest_idx(const std::vector<Complex>& from, Complex to, int kind) {
  size_t best = from.size();
  double dist = 0.0;
  for (size_t i = 0; i < from.size(); ++i) {
    if ((kind == 1 && !is_real(from[i])) || (kind == 2 && is_real(from[i]))) continue;
    const double d = std::abs(from[i] - to);
    if (best == from.size() || d < dist) {
      best = i;
      dist = d;
    }
  }
  return best;
}

Complex take(std::vector<Complex>& v, size_t i) {
  // the pairing always finds a partner for a Butterworth low-pass
  if (i >= v.size()) throw std::logic_error("butterworth_lowpass: pole/zero pairing found no partner");
  const Complex c = v[i];
  v.erase(v.begin() + static_cast<long>(i));
  return c;
}

// coefficients of prod (1 - r z^-1) over up to two roots, real parts (roots come in conjugate or
// real pairs), right-aligned into [c0 c1 c2] like scipy _single_zpksos
std::array<double, 3> poly2(std::initializer_list<Complex> roots) {
  std::array<Complex, 3> c{1.0, 0.0, 0.0};
  size_t deg = 0;
  for (Complex r : roots) {
    // multiply by (1 - r x): c_new[k] = c[k] - r c[k-1]
    for (size_t k = deg + 1; k > 0; --k) c[k] -= r * c[k - 1];
    ++deg;
  }
  std::array<double, 3> out{0.0, 0.0, 0.0};
  for (size_t k = 0; k <= deg; ++k) out[2 - deg + k] = c[k].real();
  return out;
}

Sos section(std::initializer_list<Complex> zeros, std::initializer_list<Complex> poles) {
  const auto b = poly2(zeros);
  const auto a = poly2(poles);
  return {b[0], b[1], b[2], a[0], a[1], a[2]};
}

void check_design(int order, double cutoff_hz, double fs_hz) {
  if (order < 1 || order > kMaxButterworthOrder)
    throw InvalidArgument(fmt::format("Butterworth order is {}, must be in [1, {}]", order, kMaxButterworthOrder));
  if (!(fs_hz > 0.0) || !std::isfinite(fs_hz)) throw InvalidArgument(fmt::format("Butterworth fs_hz is {}, must be > 0", fs_hz));
  if (!(cutoff_hz > 0.0) || !(cutoff_hz < 0.5 * fs_hz))
    throw InvalidArgument(
        fmt::format("Butterworth cutoff_hz is {}, must be in (0, fs_hz / 2) = (0, {}) (below the Nyquist frequency)", cutoff_hz, 0.5 * fs_hz));
}

}  // namespace

std::vector<Sos> butterworth_lowpass(int order, double cutoff_hz, double fs_hz) {
  check_design(order, cutoff_hz, fs_hz);
  const int N = order;
  // analog prototype poles p = -exp(i pi m / (2N)), m = -N+1, -N+3, ..., N-1 (scipy buttap);
  // keep one of each conjugate pair (imag > 0, m < 0) and the real pole -1 of odd orders
  // prewarp: wo = 2 fs' tan(pi Wn / fs'), fs' = 2, Wn = cutoff / Nyquist (scipy iirfilter)
  const double Wn = 2.0 * cutoff_hz / fs_hz;
  constexpr double kFs = 2.0;
  const double wo = 2.0 * kFs * std::tan(M_PI * Wn / kFs);
  // bilinear transform z = (2 fs' + s) / (2 fs' - s); zeros at z = -1 for the N zeros at infinity;
  // gain k = wo^N / real(prod(2 fs' - s_p))
  const double fs2 = 2.0 * kFs;
  std::vector<Complex> pc, pr;
  Complex den = 1.0;
  for (int m = -N + 1; m <= N - 1; m += 2) {
    const Complex s = m == 0 ? Complex(-wo, 0.0) : -std::exp(Complex(0.0, M_PI * m / (2.0 * N))) * wo;
    den *= fs2 - s;
    const Complex zp = m == 0 ? Complex((fs2 - wo) / (fs2 + wo), 0.0) : (fs2 + s) / (fs2 - s);
    if (m < 0) pc.push_back(zp);
    else if (m == 0) pr.push_back(zp);
  }
  const double k = std::pow(wo, N) / den.real();
  std::vector<Complex> z(static_cast<size_t>(N), Complex(-1.0, 0.0));
  // an odd count gets a pole and a zero at the origin so every section is second order
  if (N % 2 == 1) {
    pr.push_back(0.0);
    z.push_back(0.0);
  }
  // scipy _cplxreal order: conjugate representatives by real part then |imag|, then reals by value
  std::sort(pc.begin(), pc.end(), [](Complex a, Complex b) {
    return a.real() != b.real() ? a.real() < b.real() : std::abs(a.imag()) < std::abs(b.imag());
  });
  std::sort(pr.begin(), pr.end(), [](Complex a, Complex b) { return a.real() < b.real(); });
  std::sort(z.begin(), z.end(), [](Complex a, Complex b) { return a.real() < b.real(); });
  std::vector<Complex> p = pc;
  p.insert(p.end(), pr.begin(), pr.end());

  // scipy zpk2sos pairing 'nearest': the pole closest to the unit circle goes into the last
  // section, paired with its nearest zero; repeat towards the first section
  const size_t n_sections = static_cast<size_t>((N + 1) / 2);
  std::vector<Sos> sos(n_sections);
  for (size_t si = n_sections; si-- > 0;) {
    const Complex p1 = take(p, idx_worst(p));
    const long real_p = std::count_if(p.begin(), p.end(), is_real);
    const long real_z = std::count_if(z.begin(), z.end(), is_real);
    if (is_real(p1) && real_p == 0) {
      // last remaining real pole
      const Complex z1 = take(z, nearest_idx(z, p1, 1));
      sos[si] = section({z1, 0.0}, {p1, 0.0});
    } else if (p.size() + 1 == z.size() && !is_real(p1) && real_p == 1 && real_z == 1) {
      // one real pole and one real zero left: the complex pole must take a complex zero
      const Complex z1 = take(z, nearest_idx(z, p1, 2));
      sos[si] = section({z1, std::conj(z1)}, {p1, std::conj(p1)});
    } else {
      const Complex p2 = is_real(p1) ? take(p, idx_worst(p, true)) : std::conj(p1);
      const Complex z1 = take(z, nearest_idx(z, p1, 0));
      if (!is_real(z1)) {
        sos[si] = section({z1, std::conj(z1)}, {p1, p2});
      } else {
        const Complex z2 = take(z, nearest_idx(z, p1, 1));
        sos[si] = section({z1, z2}, {p1, p2});
      }
    }
  }
  assert(p.empty() && z.empty());
  // the gain goes into the first section
  for (size_t c = 0; c < 3; ++c) sos[0][c] *= k;
  return sos;
}

std::vector<double> sosfilt(std::span<const Sos> sos, std::span<const double> x, std::span<double> zi) {
  if (!zi.empty() && zi.size() != 2 * sos.size())
    throw InvalidArgument(fmt::format("sosfilt: zi has {} values, expected 2 per section = {}", zi.size(), 2 * sos.size()));
  std::vector<double> state(2 * sos.size(), 0.0);
  if (!zi.empty()) std::copy(zi.begin(), zi.end(), state.begin());
  std::vector<double> y(x.size());
  // transposed direct form II per section (scipy _sosfilt):
  //   y = b0 x + s0;  s0 = b1 x - a1 y + s1;  s1 = b2 x - a2 y
  for (size_t n = 0; n < x.size(); ++n) {
    double cur = x[n];
    for (size_t s = 0; s < sos.size(); ++s) {
      const Sos& c = sos[s];
      double* st = &state[2 * s];
      const double out = c[0] * cur + st[0];
      st[0] = c[1] * cur - c[4] * out + st[1];
      st[1] = c[2] * cur - c[5] * out;
      cur = out;
    }
    y[n] = cur;
  }
  if (!zi.empty()) std::copy(state.begin(), state.end(), zi.begin());
  return y;
}

std::vector<double> sosfilt_zi(std::span<const Sos> sos) {
  std::vector<double> zi(2 * sos.size());
  double scale = 1.0;
  for (size_t s = 0; s < sos.size(); ++s) {
    const Sos& c = sos[s];
    const double b0 = c[0] / c[3], b1 = c[1] / c[3], b2 = c[2] / c[3], a1 = c[4] / c[3], a2 = c[5] / c[3];
    // lfilter_zi: solve (I - companion(a)^T) zi = b[1:] - a[1:] b0, i.e.
    //   [1 + a1  -1] [zi0]   [b1 - a1 b0]
    //   [a2       1] [zi1] = [b2 - a2 b0]
    const double r0 = b1 - a1 * b0, r1 = b2 - a2 * b0;
    const double det = (1.0 + a1) + a2;
    const double z0 = (r0 + r1) / det;
    zi[2 * s] = scale * z0;
    zi[2 * s + 1] = scale * (r1 - a2 * z0);
    // the next section sees this section's DC gain H(1) = sum(b) / sum(a)
    scale *= (b0 + b1 + b2) / (1.0 + a1 + a2);
  }
  return zi;
}

int sosfiltfilt_padlen(std::span<const Sos> sos) {
  const long b2_zero = std::count_if(sos.begin(), sos.end(), [](const Sos& c) { return c[2] == 0.0; });
  const long a2_zero = std::count_if(sos.begin(), sos.end(), [](const Sos& c) { return c[5] == 0.0; });
  const long ntaps = 2 * static_cast<long>(sos.size()) + 1 - std::min(b2_zero, a2_zero);
  return static_cast<int>(3 * ntaps);
}

std::vector<double> sosfiltfilt(std::span<const Sos> sos, std::span<const double> x, int padlen) {
  if (sos.empty()) throw InvalidArgument("sosfiltfilt: no sections given");
  const int edge = padlen < 0 ? sosfiltfilt_padlen(sos) : padlen;
  const size_t n = x.size();
  if (n <= static_cast<size_t>(edge))
    throw InvalidArgument(fmt::format("sosfiltfilt: input has {} samples, must be more than padlen = {}{}", n, edge,
                                      padlen < 0 ? fmt::format(" (3 x (2 x {} sections + 1 - first-order sections))", sos.size()) : ""));
  // odd extension: 2 x[0] - x[edge..1] before, 2 x[n-1] - x[n-2..n-1-edge] after
  const size_t e = static_cast<size_t>(edge);
  std::vector<double> ext(n + 2 * e);
  for (size_t i = 0; i < e; ++i) {
    ext[i] = 2.0 * x[0] - x[e - i];
    ext[n + e + i] = 2.0 * x[n - 1] - x[n - 2 - i];
  }
  std::copy(x.begin(), x.end(), ext.begin() + static_cast<long>(e));
  // forward pass from the steady state of the first extended value
  const std::vector<double> zi = sosfilt_zi(sos);
  std::vector<double> state(zi.size());
  for (size_t i = 0; i < zi.size(); ++i) state[i] = zi[i] * ext.front();
  std::vector<double> y = sosfilt(sos, ext, state);
  // backward pass from the steady state of the last forward output
  std::reverse(y.begin(), y.end());
  for (size_t i = 0; i < zi.size(); ++i) state[i] = zi[i] * y.front();
  y = sosfilt(sos, y, state);
  std::reverse(y.begin(), y.end());
  return {y.begin() + static_cast<long>(e), y.end() - static_cast<long>(e)};
}

void ButterworthLowpass::validate() const {
  if (order < 1 || order > kMaxButterworthOrder) throw InvalidArgument(fmt::format("order is {}, must be in [1, {}]", order, kMaxButterworthOrder));
  if (!(fs_hz > 0.0) || !std::isfinite(fs_hz)) throw InvalidArgument(fmt::format("fs_hz is {}, must be > 0", fs_hz));
  if (!(cutoff_hz > 0.0) || !(cutoff_hz < 0.5 * fs_hz))
    throw InvalidArgument(fmt::format("cutoff_hz is {}, must be in (0, fs_hz / 2) = (0, {})", cutoff_hz, 0.5 * fs_hz));
}

std::vector<Sos> ButterworthLowpass::sections() const {
  validate();
  return butterworth_lowpass(order, cutoff_hz, fs_hz);
}

std::vector<double> ButterworthLowpass::apply(std::span<const double> x) const { return sosfiltfilt(sections(), x); }

}  // namespace twinwatch::signal
