#include "twinwatch/ident/agv_ident.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::ident {

namespace {
// a steady-state point needs the wheel turning (U / w is undefined at rest) [rad/s]
constexpr double kMinSpeed = 0.5;
// [1] the step response's last fifth within this of the fifth before counts as settled (a first-order
// step recorded over 5 time constants differs by 2.0 %, over 8.7 as make-tests records by 0.2 %)
constexpr double kSettled = 0.03;

// least squares y = a x + b
void line_fit(const std::vector<double>& x, const std::vector<double>& y, double& a, double& b) {
  Eigen::MatrixXd A(static_cast<Eigen::Index>(x.size()), 2);
  Eigen::VectorXd v(static_cast<Eigen::Index>(x.size()));
  for (size_t k = 0; k < x.size(); ++k) A(static_cast<Eigen::Index>(k), 0) = x[k], A(static_cast<Eigen::Index>(k), 1) = 1.0, v(static_cast<Eigen::Index>(k)) = y[k];
  const Eigen::Vector2d s = A.colPivHouseholderQr().solve(v);
  a = s(0);
  b = s(1);
}
}  // namespace

AgvMotorFit fit_agv_motor(const std::vector<AgvTestRow>& rows, const std::string& motor) {
  std::vector<double> x3, y3, w5, y5;
  std::vector<std::pair<double, double>> step;
  double step_voltage = 0.0;
  for (const auto& r : rows) {
    if (r.motor != motor) continue;
    if (r.test == "steady" && r.speed > kMinSpeed) {
      x3.push_back(r.current / r.speed);
      y3.push_back(r.voltage / r.speed);
    } else if (r.test == "step") {
      step.emplace_back(r.time, r.speed);
      step_voltage = r.voltage;
    }
  }
  if (x3.size() < 3) {
    // a test run backwards (the friction torque changes sign with the speed, so the fit of eq. 5
    // takes one direction; the forward one): said, not counted as a wheel at rest
    const auto backwards = std::count_if(rows.begin(), rows.end(), [&](const AgvTestRow& r) {
      return r.motor == motor && r.test == "steady" && r.speed < -kMinSpeed;
    });
    throw InvalidArgument(fmt::format("{} motor: {} steady-state points with the wheel turning forwards (speed > {:g} rad/s), expected at "
                                      "least 3{}",
                                      motor, x3.size(), kMinSpeed,
                                      backwards > 0 ? fmt::format("; {} steady rows turn backwards (negative speed): the fit takes the "
                                                                  "forward direction; test forwards, or negate the speed, voltage and "
                                                                  "current of a backward test",
                                                                  backwards)
                                                    : std::string()));
  }
  AgvMotorFit fit;
  fit.steady_points = static_cast<int>(x3.size());
  // eq. 3: U/w = Ra i/w + k
  line_fit(x3, y3, fit.params.Ra, fit.params.k);
  // eq. 5: k i = B w + Tq
  for (const auto& r : rows)
    if (r.motor == motor && r.test == "steady" && r.speed > kMinSpeed) w5.push_back(r.speed), y5.push_back(fit.params.k * r.current);
  line_fit(w5, y5, fit.params.B, fit.params.Tq);
  // eq. 6: tau from the step: time to 63.2 % of the final speed (mean of the last fifth)
  if (step.size() < 10) throw InvalidArgument(fmt::format("{} motor: {} step samples, expected at least 10", motor, step.size()));
  std::sort(step.begin(), step.end());
  // the step is applied one logging period before the first step row (make-tests' rows start at
  // t = dt): tau counts from there, not from t = 0 (a log whose clock started 2 s earlier gave a
  // tau of 2.17 s and J 13x too large; review, session 47)
  const double onset = step[0].first - (step[1].first - step[0].first);
  // the final value: the mean of the last fifth, which must have settled (a step cut off while the
  // wheel still accelerates gave tau 0.116 s, exit 0): the fifth before it within kSettled
  double final = 0, before = 0;
  const size_t tail = step.size() / 5;
  for (size_t k = step.size() - tail; k < step.size(); ++k) final += step[k].second;
  for (size_t k = step.size() - 2 * tail; k < step.size() - tail; ++k) before += step[k].second;
  final /= static_cast<double>(tail);
  before /= static_cast<double>(tail);
  if (!(std::abs(final - before) <= kSettled * std::abs(final)))
    throw InvalidArgument(fmt::format("{} motor: the step response has not settled: the mean speed of its last fifth ({:.4g} rad/s, from t = "
                                      "{:.3f} s) differs by {:.1f} % from the fifth before, at most {:.0f} %; record the step until the "
                                      "speed is steady (about 5 time constants)",
                                      motor, final, step[step.size() - tail].first, 100 * std::abs(final - before) / std::abs(final),
                                      100 * kSettled));
  // the steady fit takes the forward direction (eq. 5's friction sign): a step that turns the wheel
  // backwards, or against its voltage, is another test (a backward step gave J 1.455e-3 for 3.39e-3,
  // exit 0: audit of session 56)
  if (!(final > kMinSpeed) || !(step_voltage > 0.0))
    throw InvalidArgument(fmt::format("{} motor: the step response settles at {:.4g} rad/s under {:g} V, expected the wheel turning forwards "
                                      "(> {:g} rad/s) under a positive voltage, as the steady test; test forwards, or negate the speed, "
                                      "voltage and current of a backward test",
                                      motor, final, step_voltage, kMinSpeed));
  const double target = 0.632 * final;
  // the encoder speed of sample k is the mean over (t_k - dt, t_k]: read it at the mid-point,
  // interpolating linearly between the samples around the crossing
  for (size_t k = 1; k < step.size(); ++k) {
    if (step[k].second >= target) {
      const double dt = step[k].first - step[k - 1].first;
      const double t0 = step[k - 1].first - dt / 2, t1 = step[k].first - dt / 2;
      const double f = (target - step[k - 1].second) / (step[k].second - step[k - 1].second);
      fit.tau = t0 + f * (t1 - t0) - onset;
      break;
    }
  }
  if (!(fit.tau > 0.0)) throw InvalidArgument(fmt::format("{} motor: the step response never reaches 63 % of its final value", motor));
  fit.step_points = static_cast<int>(step.size());
  fit.params.J = fit.tau * (fit.params.B * fit.params.Ra + fit.params.k * fit.params.k) / fit.params.Ra;
  // a physical motor, or the tuning (IMC PI) and the twin built on it are meaningless
  try {
    fit.params.validate(motor.c_str());
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(fmt::format("{} (fitted from {} steady-state and {} step rows: they do not describe a DC motor, eq. 3-6)",
                                      e.what(), fit.steady_points, fit.step_points));
  }
  return fit;
}

}  // namespace twinwatch::ident
