#pragma once
/// @file rbf_network.hpp
/// Gaussian radial-basis-function networks, the neural baselines of [HESR] §V-D:
/// RBFNN on the velocity qd alone and RBFNN-H on the augmented input [qd, h, hd] of HESR eq. 11.
/// Both share one architecture and one training procedure; only the input differs (as in the
/// paper).
///
///   tau_f(x) = w_0 + sum_j w_j exp(-|xs - c_j|^2 / (2 s^2)),   xs = (x - mean) / std
///
/// Training [Broomhead1988]: inputs standardised per column, M centres by k-means++ with Lloyd
/// iterations (seeded), output weights by ridge least squares. The common width s is chosen on a
/// held-out set (every k-th block of consecutive samples, the paper's train/test split) by a
/// global search (NLopt DIRECT-L) polished locally (Nelder-Mead), then the weights are re-fitted
/// on all samples.
#include <optional>
#include <vector>

#include "twinwatch/friction/friction_model.hpp"
#include "twinwatch/friction/hysteresis.hpp"

namespace twinwatch::friction {

/// Which input the network sees.
enum class RbfInput {
  Velocity,    ///< x = [qd]          (RBFNN)
  Hysteresis,  ///< x = [qd, h, hd]   (RBFNN-H)
};

struct RbfOptions {
  RbfInput input = RbfInput::Velocity;
  HysteresisParams hysteresis;  ///< alpha, beta of h when input is Hysteresis
  int centers = 40;             ///< hidden neurons M, >= 1
  double ridge = 1e-8;          ///< Tikhonov weight relative to the mean diagonal of Phi^T Phi, >= 0
  double spread_min = 0.02;     ///< width search interval, in standardised input units, > 0
  double spread_max = 5.0;      ///< > spread_min
  int spread_evaluations = 40;  ///< DIRECT-L evaluations for the width, >= 4
  double holdout_block = 1.0;   ///< length of a train/test block [s], > 0
  int holdout_every = 5;        ///< every k-th block is held out, >= 2
  int kmeans_iterations = 30;   ///< Lloyd iterations, >= 0
  unsigned seed = 1;            ///< seeds k-means++
  /// Throws InvalidArgument naming the first field out of range.
  void validate() const;
};

/// RBFNN / RBFNN-H.
class RbfNetwork final : public FrictionModel {
 public:
  explicit RbfNetwork(RbfOptions options = {});

  std::string_view name() const noexcept override;
  /// Needs at least `centers` + 1 samples; throws InvalidArgument otherwise.
  FitSummary fit(const FrictionRecord& record) override;
  bool fitted() const noexcept override { return !weights_.empty(); }
  void start(double dt) override;
  double step(double qd) noexcept override;
  /// The network in closed form (centres and weights), one term per neuron.
  std::string equation() const override;

  const RbfOptions& options() const noexcept { return options_; }
  /// Selected width s (standardised units).
  double spread() const noexcept { return spread_; }
  /// Input dimension (1 or 3).
  int input_dim() const noexcept { return options_.input == RbfInput::Velocity ? 1 : 3; }

 private:
  RbfOptions options_;
  std::vector<double> mean_, inv_std_;  ///< per input column
  std::vector<double> centers_;         ///< M x d, row major, standardised
  std::vector<double> weights_;         ///< w_0, w_1..w_M
  double spread_ = 1.0;
  double inv_two_s2_ = 0.5;
  std::optional<HysteresisState> state_;
};

}  // namespace twinwatch::friction
