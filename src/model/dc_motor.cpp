#include "twinwatch/model/dc_motor.hpp"

#include <fmt/format.h>

#include "twinwatch/core/error.hpp"

namespace twinwatch::model {

void DcMotorParams::validate(const char* which) const {
  auto pos = [&](double v, const char* name) {
    if (!(v > 0.0)) throw InvalidArgument(fmt::format("{} motor: {} is {}, must be > 0", which, name, v));
  };
  pos(Ra, "Ra");
  pos(k, "k");
  pos(J, "J");
  if (!(Tq >= 0.0)) throw InvalidArgument(fmt::format("{} motor: Tq is {}, must be >= 0", which, Tq));
  if (!(B >= 0.0)) throw InvalidArgument(fmt::format("{} motor: B is {}, must be >= 0", which, B));
}

DcMotorParams agv_table1_right() { return {6.16, 0.32, 0.021, 3.2e-3, 3.39e-3}; }
DcMotorParams agv_table1_left() { return {6.41, 0.30, 0.021, 2.6e-3, 3.42e-3}; }

}  // namespace twinwatch::model
