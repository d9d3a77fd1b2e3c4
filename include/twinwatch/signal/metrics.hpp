#pragma once
/// @file metrics.hpp
/// Fit metrics of a prediction against a measurement (UR3e Table 3; robot-identification
/// benchmarks' relative torque error).
#include <limits>
#include <span>

namespace twinwatch::signal {

struct FitMetrics {
  double rmse = 0.0;       ///< sqrt(mean (y - yhat)^2)
  double mae = 0.0;        ///< mean |y - yhat|
  double r2 = 0.0;         ///< 1 - SS_res / SS_tot (SS_tot about the mean of y)
  double nrmse_pct = 0.0;  ///< 100 * rmse / (max y - min y)   (range-normalised)
  double rel_err_pct = 0.0;  ///< d_tau: 100 * ||y - yhat||_2 / ||y||_2
  double max_abs = 0.0;    ///< max |y - yhat|
  /// max y - min y: 0 for a measured signal that never changes, where r2, nrmse_pct (and rel_err_pct
  /// when it is 0 throughout) are undefined and read 0 (a caller reporting them says so)
  double range = 0.0;
  long n = 0;
};

/// fit_metrics a pair at a time, holding six sums: a report streams a day's recording through one per
/// joint instead of holding its currents. NaN pairs are skipped.
class FitAccumulator {
 public:
  void add(double measured, double predicted);
  long count() const { return n_; }
  /// the metrics of the pairs added; throws InvalidArgument when none was valid (non-NaN)
  FitMetrics metrics() const;

 private:
  double sum_ = 0.0, sum2_ = 0.0, sse_ = 0.0, sae_ = 0.0, lo_ = std::numeric_limits<double>::infinity(), hi_ = -lo_, max_abs_ = 0.0;
  long n_ = 0;
};

/// Metrics of `predicted` against `measured` (equal lengths >= 1; throws InvalidArgument otherwise).
/// NaN pairs are skipped.
FitMetrics fit_metrics(std::span<const double> measured, std::span<const double> predicted);

}  // namespace twinwatch::signal
