#pragma once
/// @file reference.hpp
/// What the monitor needs from a reference ("healthy twin") model. The identification module's
/// twin model implements it; tests implement it with the nominal rigid-body model.
#include "twinwatch/core/types.hpp"

namespace twinwatch::model {
class RobotModel;
}

namespace twinwatch::monitor {

/// A healthy-robot reference: predicts motor current and joint torque from the joint state.
/// Implementations must not allocate in predict() (the monitor calls it at 500 Hz per robot).
class ReferenceModel {
 public:
  virtual ~ReferenceModel() = default;

  virtual int n_dof() const = 0;

  /// Predicted healthy motor current [A] and joint torque [N·m] (incl. friction) for the state.
  /// @param q [rad], qd [rad/s], qdd [rad/s²], temperature [°C] (NaN if unknown): size n_dof
  virtual void predict(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const VectorJ& temperature,
                       VectorJ& current, VectorJ& torque) = 0;

  /// Joint torque [N·m] that a measured motor current corresponds to (drive model).
  virtual void current_to_torque(const VectorJ& current, const VectorJ& qd, VectorJ& torque) const = 0;

  /// Predicted friction torque [N·m] for the state (the momentum observer subtracts it).
  virtual void friction_torque(const VectorJ& qd, const VectorJ& temperature, VectorJ& tau_f) const = 0;

  /// The rigid-body model behind the prediction, or nullptr (e.g. a pure MLP reference).
  /// Used by the momentum observer and the fault-signature diagnosis.
  virtual const model::RobotModel* rigid_body() const = 0;
};

}  // namespace twinwatch::monitor
