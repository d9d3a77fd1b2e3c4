#pragma once
/// @file agv_ident.hpp
/// DC-motor identification of the AGV paper [AGV §4.1]:
/// - steady state, eq. 3:  U / w = Ra (i / w) + k      -> Ra (slope), k (intercept)
/// - steady state, eq. 5:  k i = B w + Tq              -> B (slope), Tq (intercept)
/// - step response, eq. 6: tau = J Ra / (B Ra + k^2)   -> J = tau (B Ra + k^2) / Ra
///
/// Test CSV layout (one file, both motors), header required:
///   motor,test,voltage_V,current_A,speed_rad_s,time_s
/// motor = right|left; test = steady (one row per applied voltage, time_s ignored) or step (the
/// speed response to a voltage step applied at time_s = 0, one row per sample).
#include <string>
#include <vector>

#include "twinwatch/device/agv_tests.hpp"
#include "twinwatch/model/dc_motor.hpp"

namespace twinwatch::ident {

using device::AgvTestRow;

struct AgvMotorFit {
  model::DcMotorParams params;
  double tau = 0.0;  ///< measured time constant [s]
  int steady_points = 0, step_points = 0;
};

/// Fits one motor ("right" or "left") from the rows. Throws InvalidArgument when there are fewer
/// than 3 steady-state points with w > 0, no usable step response, or the fitted parameters are not
/// a physical motor (DcMotorParams::validate: Ra, k, J > 0; B, Tq >= 0).
AgvMotorFit fit_agv_motor(const std::vector<AgvTestRow>& rows, const std::string& motor);

}  // namespace twinwatch::ident
