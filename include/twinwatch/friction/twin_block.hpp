#pragma once
/// @file twin_block.hpp
/// The optional friction block of the twin file: the identified symbolic residual-torque
/// equation of each joint (HESR Table VII), stored so that the twin can re-load it into the
/// compiled evaluator (parfam.hpp) without identifying again.
///
/// JSON (the value of the twin file's "friction_models" key):
///   [{"joint": 1, "model": "ParFam-H", "dim": 3, "functions": ["tanh", ...], "theta": [...],
///     "denominator_floor": 0.05, "alpha": 10.2, "beta": 95.0, "input_min": [...], "input_max": [...],
///     "equation": "tau_f = ..."}, ...]
/// theta follows the layout of ParFamExpression; alpha and beta are present when dim is 3; the
/// input guard (input_min/max, dim values each) is optional.
#include <string>
#include <vector>

#include "twinwatch/friction/parfam.hpp"

namespace twinwatch::friction {

/// One joint's stored equation.
struct JointFrictionEquation {
  int joint = 1;                  ///< 1-based joint number
  ParFamExpression expression;    ///< physical units
  HysteresisParams hysteresis;    ///< used when expression.dim == 3
  /// A fitted ParFamModel that evaluates the stored equation (compiled evaluator).
  ParFamModel model() const { return ParFamModel::restore(expression, hysteresis); }
};

/// The equation of a fitted ParFam model for joint `joint` (1-based). Throws InvalidArgument
/// when the model is not fitted.
JointFrictionEquation friction_equation_of(const ParFamModel& model, int joint);

/// JSON text of the block (an array).
std::string friction_block_to_json(const std::vector<JointFrictionEquation>& equations);

/// Parses the block. Throws ParseError naming `origin` and the field ("friction_models[1].theta")
/// with what was expected: not an array, a missing field, an unknown function name, a theta of
/// the wrong size, a non-finite number, alpha/beta missing or not > 0 for dim 3.
std::vector<JointFrictionEquation> friction_block_from_json(const std::string& text, const std::string& origin);

}  // namespace twinwatch::friction
