#pragma once
/// @file mlp.hpp
/// A small fully connected network (multilayer perceptron) for the learned reference model of
/// UR3e §3.5: inputs and outputs z-scored with the training statistics (stored in the model),
/// ReLU hidden layers (one of 15 units by default, as in the paper), linear outputs, L2 weight
/// regularisation.
///
/// Training is full-batch L-BFGS [Liu1989] (NLopt's LD_LBFGS) on
///   L(theta) = 1/(2 N m) sum_k ||f(x_k; theta) - y_k||^2 + (l2 / 2) sum_l ||W_l||_F^2
/// (z-scored x and y, N samples, m outputs; biases are not penalised), with early stopping on a
/// held-out block: the parameters kept are those with the lowest held-out loss seen. Why L-BFGS:
/// the data sets are small (10^4-10^5 samples, a few hundred weights), so the exact full-batch
/// gradient is cheap; the result depends only on the seed of the initial weights (no shuffling,
/// no learning rate to tune), so the same seed gives bit-identical weights; and quasi-Newton
/// steps reach a much lower loss than first-order steps in the same number of gradient
/// evaluations on networks this small (the reason scikit-learn recommends 'lbfgs' for them).
///
/// Per-sample prediction (predict) allocates nothing: it works in a workspace sized once.
/// The workspace makes predict non-reentrant: use one Mlp per thread.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace twinwatch::ident {

struct MlpOptions {
  std::vector<int> hidden = {15};  ///< units per hidden layer (UR3e §3.5: one layer of 15)
  double l2 = 1e-4;                ///< L2 penalty on the weights (z-scored units)
  std::uint64_t seed = 1;          ///< seed of the initial weights
  int max_evaluations = 3000;      ///< cap on loss/gradient evaluations of L-BFGS
  double validation_fraction = 0.2;  ///< held-out block at the end of every segment, in [0, 0.5)
  int patience = 200;              ///< evaluations without a better held-out loss before stopping
  double ftol_rel = 1e-12;         ///< L-BFGS stops when the loss changes less than this (relative)
  int lbfgs_memory = 10;           ///< number of stored correction pairs
  /// Throws InvalidArgument naming the first field out of range.
  void validate() const;
};

/// How a fit ended.
enum class MlpStop { Converged, EarlyStopped, MaxEvaluations, Roundoff, Failure };
const char* to_string(MlpStop s);

struct MlpFitReport {
  MlpStop stop = MlpStop::Failure;
  int evaluations = 0;           ///< loss/gradient evaluations
  int best_evaluation = 0;       ///< evaluation whose parameters were kept
  double train_loss = 0.0;       ///< data term of L on the fitted samples, kept parameters (z units)
  double validation_loss = 0.0; ///< same on the held-out block (NaN when there is none)
  long train_samples = 0, validation_samples = 0;
};

class Mlp {
 public:
  Mlp() = default;
  /// Network with n_in inputs and n_out outputs, weights drawn from the seed (He-uniform for the
  /// ReLU layers, Glorot-uniform for the linear output), identity normalisation.
  /// Throws InvalidArgument on n_in, n_out < 1 or invalid options.
  Mlp(int n_in, int n_out, const MlpOptions& options);

  int n_inputs() const { return n_in_; }
  int n_outputs() const { return n_out_; }
  const std::vector<int>& hidden() const { return hidden_; }
  /// Training options (fit uses them; l2 and seed are also the public fields below).
  const MlpOptions& options() const { return options_; }
  /// Throws InvalidArgument when o is invalid or changes the layer widths.
  void set_options(const MlpOptions& o);
  int n_parameters() const;

  /// Fits the network to the columns of X (n_in x N) and Y (n_out x N), raw units. The z-scoring
  /// statistics come from the fitted (not held-out) columns. segment_ends lists the end column
  /// (exclusive) of each contiguous recording, so the held-out block is the last
  /// validation_fraction of every segment (time series: a random hold-out would sit next to
  /// almost identical training samples); empty means one segment. progress gets a fraction in [0, 1].
  /// Throws InvalidArgument on size mismatches, non-finite data or too few samples.
  MlpFitReport fit(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Y, const std::vector<Eigen::Index>& segment_ends = {},
                   const std::function<void(double)>& progress = {});

  /// One sample, raw units: x (n_in) -> y (n_out). Allocation-free; sizes are asserted.
  void predict(const double* x, double* y) const;
  /// Columns of X (n_in x N) -> n_out x N. Throws InvalidArgument on a size mismatch.
  Eigen::MatrixXd predict(const Eigen::MatrixXd& X) const;

  /// Flat parameter vector: per layer W (column-major, out x in) then b.
  Eigen::VectorXd parameters() const;
  /// Throws InvalidArgument when theta has the wrong size.
  void set_parameters(const Eigen::VectorXd& theta);

  /// The training objective L and (when gradient is not null) its gradient at theta, on already
  /// z-scored data Xz (n_in x N), Yz (n_out x N); without_penalty: the data term only. Exposed for
  /// the finite-difference test.
  double loss(const Eigen::VectorXd& theta, const Eigen::MatrixXd& Xz, const Eigen::MatrixXd& Yz, Eigen::VectorXd* gradient,
              bool with_penalty = true) const;

  Eigen::VectorXd x_mean, x_std, y_mean, y_std;  ///< z-score statistics (raw units)
  double l2 = 0.0;                               ///< penalty used by loss()
  std::uint64_t seed = 0;                        ///< seed the initial weights came from

  /// JSON text / back. from_json throws ParseError naming origin and the field (prefix + key).
  std::string to_json() const;
  static Mlp from_json(const std::string& text, const std::string& origin, const std::string& prefix);

 private:
  void allocate_workspace();
  int n_in_ = 0, n_out_ = 0;
  std::vector<int> hidden_;
  MlpOptions options_;
  std::vector<Eigen::MatrixXd> W_;
  std::vector<Eigen::VectorXd> b_;
  mutable std::vector<Eigen::VectorXd> a_;  // per-sample activations (workspace)
};

}  // namespace twinwatch::ident
