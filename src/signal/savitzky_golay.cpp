#include "twinwatch/signal/savitzky_golay.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::signal {

namespace {
double factorial(int k) {
  double f = 1;
  for (int i = 2; i <= k; ++i) f *= i;
  return f;
}
}  // namespace

void SavitzkyGolay::validate() const {
  if (window < 1 || window % 2 == 0) throw InvalidArgument(fmt::format("window is {}, must be odd and >= 1", window));
  if (order < 0 || order >= window) throw InvalidArgument(fmt::format("order is {}, must be in [0, window - 1] = [0, {}]", order, window - 1));
  if (deriv < 0 || deriv > order) throw InvalidArgument(fmt::format("deriv is {}, must be in [0, order] = [0, {}]", deriv, order));
  if (!(delta > 0)) throw InvalidArgument(fmt::format("delta is {}, must be > 0", delta));
}

std::vector<double> SavitzkyGolay::apply(std::span<const double> x) const {
  validate();
  const int N = static_cast<int>(x.size());
  if (N < window) throw InvalidArgument(fmt::format("input has {} samples, expected at least the window ({})", N, window));
  const int h = window / 2;
  // least-squares polynomial on offsets -h..h: coefficients c = pinv(V) y, V(k, p) = k^p;
  // the deriv-th derivative at offset s is sum_p c_p p!/(p-d)! s^(p-d) / delta^d
  Eigen::MatrixXd V(window, order + 1);
  for (int k = 0; k < window; ++k)
    for (int p = 0; p <= order; ++p) V(k, p) = std::pow(static_cast<double>(k - h), p);
  const Eigen::MatrixXd P = V.completeOrthogonalDecomposition().pseudoInverse();  // (order+1) x window
  const double scale = 1.0 / std::pow(delta, deriv);
  auto eval_row = [&](double s) {  // weights giving the derivative at offset s from the window centre
    Eigen::RowVectorXd r = Eigen::RowVectorXd::Zero(window);
    for (int p = deriv; p <= order; ++p)
      r += P.row(p) * (factorial(p) / factorial(p - deriv) * std::pow(s, p - deriv));
    return Eigen::RowVectorXd(r * scale);
  };
  const Eigen::RowVectorXd centre = eval_row(0.0);
  std::vector<double> y(static_cast<size_t>(N));
  const Eigen::Map<const Eigen::VectorXd> xv(x.data(), N);
  for (int k = h; k < N - h; ++k) y[static_cast<size_t>(k)] = centre.dot(xv.segment(k - h, window));
  // edges (scipy mode='interp'): evaluate the first/last window's polynomial
  for (int k = 0; k < h; ++k) {
    y[static_cast<size_t>(k)] = eval_row(k - h).dot(xv.segment(0, window));
    y[static_cast<size_t>(N - 1 - k)] = eval_row(h - k).dot(xv.segment(N - window, window));
  }
  return y;
}

std::vector<double> central_difference(std::span<const double> x, double dt) {
  if (x.size() < 2) throw InvalidArgument(fmt::format("central difference: {} samples, expected at least 2", x.size()));
  if (!(dt > 0)) throw InvalidArgument(fmt::format("central difference: dt is {}, must be > 0", dt));
  const size_t N = x.size();
  std::vector<double> d(N);
  d[0] = (x[1] - x[0]) / dt;
  d[N - 1] = (x[N - 1] - x[N - 2]) / dt;
  for (size_t k = 1; k + 1 < N; ++k) d[k] = (x[k + 1] - x[k - 1]) / (2 * dt);
  return d;
}

}  // namespace twinwatch::signal
