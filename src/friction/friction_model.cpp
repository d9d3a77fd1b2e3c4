#include "twinwatch/friction/friction_model.hpp"

#include <fmt/format.h>

#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::friction {

void FrictionRecord::validate(std::string_view what, long min_samples) const {
  if (!std::isfinite(dt) || dt <= 0.0)
    throw InvalidArgument(fmt::format("{}.dt is {}, must be > 0 [s]", what, dt));
  if (qd.size() != tau.size())
    throw InvalidArgument(fmt::format("{}.tau has size {}, expected {} (size of {}.qd)", what,
                                      tau.size(), qd.size(), what));
  if (size() < min_samples)
    throw InvalidArgument(
        fmt::format("{} has {} samples, expected at least {}", what, size(), min_samples));
  // non-finite values would poison every fit: name the first one
  for (std::size_t k = 0; k < qd.size(); ++k) {
    if (!std::isfinite(qd[k]))
      throw InvalidArgument(fmt::format("{}.qd[{}] is {}, must be finite", what, k, qd[k]));
    if (!std::isfinite(tau[k]))
      throw InvalidArgument(fmt::format("{}.tau[{}] is {}, must be finite", what, k, tau[k]));
  }
}

std::string_view to_string(FitStatus status) noexcept {
  switch (status) {
    case FitStatus::Converged:
      return "converged";
    case FitStatus::BudgetExhausted:
      return "budget_exhausted";
    case FitStatus::Failed:
      return "failed";
  }
  return "unknown";
}

std::string FitSummary::brief_report() const {
  return fmt::format("{}: rmse {:.4g} N·m, {} evaluations, {:.3f} s ({})", to_string(status), rmse,
                     evaluations, seconds, message);
}

std::vector<double> FrictionModel::predict(std::span<const double> qd, double dt) {
  start(dt);
  std::vector<double> out(qd.size());
  for (std::size_t k = 0; k < qd.size(); ++k) out[k] = step(qd[k]);
  return out;
}

}  // namespace twinwatch::friction
