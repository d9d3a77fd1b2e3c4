#include "twinwatch/ident/mlp.hpp"

#include <fmt/format.h>
#include <nlopt.h>

#include <cassert>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/json_fields.hpp"

#include "json_numbers.hpp"

namespace twinwatch::ident {

namespace {
// an input or output whose training standard deviation is below this is constant: it is centred
// but not scaled (dividing by ~0 would blow up any later variation)
constexpr double kStdFloor = 1e-12;
// fewest fitted samples per parameter-free sanity bound: below this the fit is meaningless
constexpr long kMinSamples = 10;

// uniform in [-1, 1) from the raw 64-bit engine output: fixed arithmetic, so the initial weights
// (and everything after them) are the same on every standard library, not only on this one
double uniform_pm1(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-52 - 1.0; }

nlohmann::json to_array(const Eigen::VectorXd& v) {
  nlohmann::json a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v(i));
  return a;
}

// everything the NLopt callback needs
struct FitContext {
  const Mlp* net = nullptr;
  const Eigen::MatrixXd* Xt = nullptr;  // z-scored fitted columns
  const Eigen::MatrixXd* Yt = nullptr;
  const Eigen::MatrixXd* Xv = nullptr;  // z-scored held-out columns (may be empty)
  const Eigen::MatrixXd* Yv = nullptr;
  nlopt_opt opt = nullptr;
  int patience = 0, max_evaluations = 1;
  int evaluations = 0, best_evaluation = 0, stall = 0;
  double best_validation = std::numeric_limits<double>::infinity();
  double best_train = std::numeric_limits<double>::infinity();
  bool early_stopped = false;
  Eigen::VectorXd best;
  Eigen::VectorXd grad;
  const std::function<void(double)>* progress = nullptr;
};

double objective(unsigned n, const double* x, double* grad, void* data) {
  auto& c = *static_cast<FitContext*>(data);
  const Eigen::Map<const Eigen::VectorXd> theta(x, n);
  const double L = c.net->loss(theta, *c.Xt, *c.Yt, grad ? &c.grad : nullptr);
  if (grad) Eigen::Map<Eigen::VectorXd>(grad, n) = c.grad;
  ++c.evaluations;
  // early stopping: keep the parameters with the lowest held-out loss seen so far
  if (c.Xv->cols() > 0) {
    const double v = c.net->loss(theta, *c.Xv, *c.Yv, nullptr, false);
    if (v < c.best_validation) {
      c.best_validation = v;
      c.best = theta;
      c.best_evaluation = c.evaluations;
      c.stall = 0;
    } else if (++c.stall >= c.patience) {
      c.early_stopped = true;
      nlopt_force_stop(c.opt);
    }
  } else if (L < c.best_train) {
    c.best_train = L;
    c.best = theta;
    c.best_evaluation = c.evaluations;
  }
  if (c.progress && *c.progress && c.evaluations % 25 == 0)
    (*c.progress)(std::min(1.0, static_cast<double>(c.evaluations) / c.max_evaluations));
  return L;
}

// column statistics: mean and standard deviation (population), floored
void column_stats(const Eigen::MatrixXd& A, Eigen::VectorXd& mean, Eigen::VectorXd& sd) {
  const double N = static_cast<double>(A.cols());
  mean = A.rowwise().sum() / N;
  sd = ((A.colwise() - mean).array().square().rowwise().sum() / N).sqrt().matrix();
  for (Eigen::Index i = 0; i < sd.size(); ++i)
    if (!(sd(i) > kStdFloor)) sd(i) = 1.0;
}
}  // namespace

const char* to_string(MlpStop s) {
  switch (s) {
    case MlpStop::Converged: return "converged";
    case MlpStop::EarlyStopped: return "early-stopped";
    case MlpStop::MaxEvaluations: return "max-evaluations";
    case MlpStop::Roundoff: return "roundoff-limited";
    case MlpStop::Failure: return "failure";
  }
  return "unknown";
}

void MlpOptions::validate() const {
  if (hidden.empty()) throw InvalidArgument("hidden is empty, expected at least one hidden layer width");
  for (size_t l = 0; l < hidden.size(); ++l)
    if (hidden[l] < 1) throw InvalidArgument(fmt::format("hidden[{}] is {}, must be >= 1", l, hidden[l]));
  if (!(l2 >= 0.0) || !std::isfinite(l2)) throw InvalidArgument(fmt::format("l2 is {}, must be a finite number >= 0", l2));
  if (max_evaluations < 1) throw InvalidArgument(fmt::format("max_evaluations is {}, must be >= 1", max_evaluations));
  if (!(validation_fraction >= 0.0 && validation_fraction < 0.5))
    throw InvalidArgument(fmt::format("validation_fraction is {}, must be in [0, 0.5)", validation_fraction));
  if (patience < 1) throw InvalidArgument(fmt::format("patience is {}, must be >= 1", patience));
  if (!(ftol_rel >= 0.0)) throw InvalidArgument(fmt::format("ftol_rel is {}, must be >= 0", ftol_rel));
  if (lbfgs_memory < 1) throw InvalidArgument(fmt::format("lbfgs_memory is {}, must be >= 1", lbfgs_memory));
}

Mlp::Mlp(int n_in, int n_out, const MlpOptions& o) : n_in_(n_in), n_out_(n_out), hidden_(o.hidden), options_(o) {
  o.validate();
  if (n_in < 1) throw InvalidArgument(fmt::format("MLP input count is {}, must be >= 1", n_in));
  if (n_out < 1) throw InvalidArgument(fmt::format("MLP output count is {}, must be >= 1", n_out));
  l2 = o.l2;
  seed = o.seed;
  x_mean = Eigen::VectorXd::Zero(n_in);
  x_std = Eigen::VectorXd::Ones(n_in);
  y_mean = Eigen::VectorXd::Zero(n_out);
  y_std = Eigen::VectorXd::Ones(n_out);
  // initial weights: He-uniform limit sqrt(6 / fan_in) before ReLU [He2015], Glorot-uniform
  // sqrt(6 / (fan_in + fan_out)) for the linear output [Glorot2010]; biases zero
  std::mt19937_64 rng(o.seed);
  int fan_in = n_in;
  const int L = static_cast<int>(hidden_.size()) + 1;
  for (int l = 0; l < L; ++l) {
    const bool last = l == L - 1;
    const int fan_out = last ? n_out : hidden_[static_cast<size_t>(l)];
    const double limit = last ? std::sqrt(6.0 / (fan_in + fan_out)) : std::sqrt(6.0 / fan_in);
    Eigen::MatrixXd W(fan_out, fan_in);
    for (Eigen::Index c = 0; c < W.cols(); ++c)
      for (Eigen::Index r = 0; r < W.rows(); ++r) W(r, c) = limit * uniform_pm1(rng);
    W_.push_back(W);
    b_.push_back(Eigen::VectorXd::Zero(fan_out));
    fan_in = fan_out;
  }
  allocate_workspace();
}

void Mlp::set_options(const MlpOptions& o) {
  o.validate();
  if (o.hidden != hidden_)
    throw InvalidArgument(fmt::format("options.hidden has {} layer(s) of other widths than this network's; build a new Mlp to change them",
                                      o.hidden.size()));
  options_ = o;
  l2 = o.l2;
  seed = o.seed;
}

void Mlp::allocate_workspace() {
  a_.clear();
  a_.push_back(Eigen::VectorXd::Zero(n_in_));
  for (const auto& b : b_) a_.push_back(Eigen::VectorXd::Zero(b.size()));
}

int Mlp::n_parameters() const {
  int p = 0;
  for (size_t l = 0; l < W_.size(); ++l) p += static_cast<int>(W_[l].size() + b_[l].size());
  return p;
}

Eigen::VectorXd Mlp::parameters() const {
  Eigen::VectorXd theta(n_parameters());
  Eigen::Index o = 0;
  for (size_t l = 0; l < W_.size(); ++l) {
    theta.segment(o, W_[l].size()) = Eigen::Map<const Eigen::VectorXd>(W_[l].data(), W_[l].size());
    o += W_[l].size();
    theta.segment(o, b_[l].size()) = b_[l];
    o += b_[l].size();
  }
  return theta;
}

void Mlp::set_parameters(const Eigen::VectorXd& theta) {
  check_size("MLP parameter vector", theta.size(), n_parameters(), "n_parameters()");
  Eigen::Index o = 0;
  for (size_t l = 0; l < W_.size(); ++l) {
    W_[l] = Eigen::Map<const Eigen::MatrixXd>(theta.data() + o, W_[l].rows(), W_[l].cols());
    o += W_[l].size();
    b_[l] = theta.segment(o, b_[l].size());
    o += b_[l].size();
  }
}

double Mlp::loss(const Eigen::VectorXd& theta, const Eigen::MatrixXd& Xz, const Eigen::MatrixXd& Yz, Eigen::VectorXd* gradient,
                 bool with_penalty) const {
  assert(theta.size() == n_parameters());
  assert(Xz.rows() == n_in_ && Yz.rows() == n_out_ && Xz.cols() == Yz.cols());
  const size_t L = W_.size();
  const double N = static_cast<double>(Xz.cols());
  // views of the layers inside theta
  std::vector<Eigen::Map<const Eigen::MatrixXd>> W;
  std::vector<Eigen::Map<const Eigen::VectorXd>> b;
  Eigen::Index o = 0;
  for (size_t l = 0; l < L; ++l) {
    W.emplace_back(theta.data() + o, W_[l].rows(), W_[l].cols());
    o += W_[l].size();
    b.emplace_back(theta.data() + o, b_[l].size());
    o += b_[l].size();
  }
  // forward: A_0 = X, A_l = relu(W_l A_{l-1} + b_l), output linear
  std::vector<Eigen::MatrixXd> A(L + 1);
  A[0] = Xz;
  for (size_t l = 0; l < L; ++l) {
    A[l + 1].noalias() = W[l] * A[l];
    A[l + 1].colwise() += b[l];
    if (l + 1 < L) A[l + 1] = A[l + 1].cwiseMax(0.0);
  }
  // data term 1/(2 N m) ||Yhat - Y||^2 plus (l2 / 2) sum ||W||^2
  Eigen::MatrixXd D = A[L] - Yz;
  const double scale = 1.0 / (N * static_cast<double>(n_out_));
  double value = 0.5 * scale * D.squaredNorm();
  if (with_penalty)
    for (size_t l = 0; l < L; ++l) value += 0.5 * l2 * W[l].squaredNorm();
  if (!gradient) return value;
  // backward: D_L = (Yhat - Y) / (N m); dW_l = D_l A_{l-1}^T + l2 W_l; db_l = D_l 1;
  // D_{l-1} = (W_l^T D_l) .* [A_{l-1} > 0]
  gradient->resize(theta.size());
  D *= scale;
  Eigen::Index end = theta.size();
  for (size_t l = L; l-- > 0;) {
    end -= b_[l].size();
    gradient->segment(end, b_[l].size()) = D.rowwise().sum();
    end -= W_[l].size();
    Eigen::Map<Eigen::MatrixXd> gW(gradient->data() + end, W_[l].rows(), W_[l].cols());
    gW.noalias() = D * A[l].transpose();
    gW += l2 * W[l];
    if (l > 0) {
      Eigen::MatrixXd Dp = W[l].transpose() * D;
      D = (A[l].array() > 0.0).select(Dp, 0.0);
    }
  }
  return value;
}

MlpFitReport Mlp::fit(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Y, const std::vector<Eigen::Index>& segment_ends,
                      const std::function<void(double)>& progress) {
  check_size("MLP training inputs X (rows)", X.rows(), n_in_, "n_inputs()");
  check_size("MLP training targets Y (rows)", Y.rows(), n_out_, "n_outputs()");
  check_size("MLP training targets Y (columns)", Y.cols(), X.cols(), "X.cols()");
  if (!X.allFinite()) throw InvalidArgument("MLP training inputs X contain NaN or infinite values");
  if (!Y.allFinite()) throw InvalidArgument("MLP training targets Y contain NaN or infinite values");
  const Eigen::Index N = X.cols();
  std::vector<Eigen::Index> ends = segment_ends.empty() ? std::vector<Eigen::Index>{N} : segment_ends;
  for (size_t s = 0; s < ends.size(); ++s) {
    const Eigen::Index begin = s == 0 ? 0 : ends[s - 1];
    if (ends[s] <= begin || ends[s] > N)
      throw InvalidArgument(fmt::format("segment_ends[{}] is {}, must be in ({}, {}] (increasing, at most X.cols())", s, ends[s], begin, N));
  }
  if (ends.back() != N) throw InvalidArgument(fmt::format("segment_ends ends at {}, expected X.cols() = {}", ends.back(), N));
  // held-out block: the last validation_fraction of every segment
  std::vector<Eigen::Index> fit_idx, val_idx;
  for (size_t s = 0; s < ends.size(); ++s) {
    const Eigen::Index begin = s == 0 ? 0 : ends[s - 1];
    const Eigen::Index len = ends[s] - begin;
    const Eigen::Index nv = static_cast<Eigen::Index>(std::floor(options_.validation_fraction * static_cast<double>(len)));
    for (Eigen::Index k = begin; k < ends[s] - nv; ++k) fit_idx.push_back(k);
    for (Eigen::Index k = ends[s] - nv; k < ends[s]; ++k) val_idx.push_back(k);
  }
  if (static_cast<long>(fit_idx.size()) < kMinSamples)
    throw InvalidArgument(fmt::format("MLP training has {} samples to fit, expected at least {}", fit_idx.size(), kMinSamples));
  Eigen::MatrixXd Xt = X(Eigen::all, fit_idx), Yt = Y(Eigen::all, fit_idx);
  Eigen::MatrixXd Xv = X(Eigen::all, val_idx), Yv = Y(Eigen::all, val_idx);
  // z-scores from the fitted columns only
  column_stats(Xt, x_mean, x_std);
  column_stats(Yt, y_mean, y_std);
  auto z = [](Eigen::MatrixXd& A, const Eigen::VectorXd& m, const Eigen::VectorXd& s) {
    A = ((A.colwise() - m).array().colwise() / s.array()).matrix();
  };
  z(Xt, x_mean, x_std);
  z(Yt, y_mean, y_std);
  z(Xv, x_mean, x_std);
  z(Yv, y_mean, y_std);

  // full-batch L-BFGS from the seeded initial weights
  const int p = n_parameters();
  FitContext c;
  c.net = this;
  c.Xt = &Xt;
  c.Yt = &Yt;
  c.Xv = &Xv;
  c.Yv = &Yv;
  c.patience = options_.patience;
  c.max_evaluations = options_.max_evaluations;
  c.progress = &progress;
  c.best = parameters();
  nlopt_opt opt = nlopt_create(NLOPT_LD_LBFGS, static_cast<unsigned>(p));
  c.opt = opt;
  nlopt_set_min_objective(opt, objective, &c);
  nlopt_set_maxeval(opt, options_.max_evaluations);
  nlopt_set_ftol_rel(opt, options_.ftol_rel);
  nlopt_set_vector_storage(opt, static_cast<unsigned>(options_.lbfgs_memory));
  std::vector<double> x(c.best.data(), c.best.data() + p);
  double fmin = 0.0;
  const nlopt_result res = nlopt_optimize(opt, x.data(), &fmin);
  nlopt_destroy(opt);

  MlpFitReport r;
  if (c.early_stopped) r.stop = MlpStop::EarlyStopped;
  else if (res == NLOPT_MAXEVAL_REACHED) r.stop = MlpStop::MaxEvaluations;
  else if (res == NLOPT_ROUNDOFF_LIMITED) r.stop = MlpStop::Roundoff;
  else if (res > 0) r.stop = MlpStop::Converged;
  else r.stop = MlpStop::Failure;
  if (c.evaluations == 0) throw InvalidArgument(fmt::format("MLP training: L-BFGS did not start (NLopt code {})", static_cast<int>(res)));
  set_parameters(c.best);
  r.evaluations = c.evaluations;
  r.best_evaluation = c.best_evaluation;
  r.train_samples = static_cast<long>(fit_idx.size());
  r.validation_samples = static_cast<long>(val_idx.size());
  r.train_loss = loss(c.best, Xt, Yt, nullptr, false);
  r.validation_loss = Xv.cols() > 0 ? loss(c.best, Xv, Yv, nullptr, false) : std::numeric_limits<double>::quiet_NaN();
  if (progress) progress(1.0);
  return r;
}

void Mlp::predict(const double* x, double* y) const {
  assert(!W_.empty());
  const size_t L = W_.size();
  // z-score, layers, un-z-score; every product writes into the preallocated workspace
  a_[0] = (Eigen::Map<const Eigen::VectorXd>(x, n_in_) - x_mean).cwiseQuotient(x_std);
  for (size_t l = 0; l < L; ++l) {
    a_[l + 1].noalias() = W_[l] * a_[l];
    a_[l + 1] += b_[l];
    if (l + 1 < L) a_[l + 1] = a_[l + 1].cwiseMax(0.0);
  }
  Eigen::Map<Eigen::VectorXd>(y, n_out_) = y_mean + y_std.cwiseProduct(a_[L]);
}

Eigen::MatrixXd Mlp::predict(const Eigen::MatrixXd& X) const {
  check_size("MLP inputs X (rows)", X.rows(), n_in_, "n_inputs()");
  Eigen::MatrixXd A = ((X.colwise() - x_mean).array().colwise() / x_std.array()).matrix();
  for (size_t l = 0; l < W_.size(); ++l) {
    Eigen::MatrixXd Z = W_[l] * A;
    Z.colwise() += b_[l];
    A = l + 1 < W_.size() ? Eigen::MatrixXd(Z.cwiseMax(0.0)) : Z;
  }
  return (y_std.asDiagonal() * A).colwise() + y_mean;
}

std::string Mlp::to_json() const {
  nlohmann::json j;
  j["inputs"] = n_in_;
  j["outputs"] = n_out_;
  j["hidden"] = hidden_;
  j["activation"] = "relu";
  j["l2"] = l2;
  j["seed"] = seed;
  j["x_mean"] = to_array(x_mean);
  j["x_std"] = to_array(x_std);
  j["y_mean"] = to_array(y_mean);
  j["y_std"] = to_array(y_std);
  for (size_t l = 0; l < W_.size(); ++l) {
    nlohmann::json layer;
    layer["rows"] = W_[l].rows();
    layer["cols"] = W_[l].cols();
    // row-major, so a reader sees one output unit per line of numbers
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Wr = W_[l];
    layer["W"] = to_array(Eigen::Map<const Eigen::VectorXd>(Wr.data(), Wr.size()));
    layer["b"] = to_array(b_[l]);
    j["layers"].push_back(layer);
  }
  return j.dump();
}

Mlp Mlp::from_json(const std::string& text, const std::string& origin, const std::string& prefix) {
  // `prefix` ends with '.' (or is empty): the JSON path of this object is prefix without it
  const std::string path = prefix.empty() ? prefix : prefix.substr(0, prefix.size() - 1);
  const nlohmann::json j = parse_json(text, origin, path);
  auto vec = [&](const JsonFields& o, const char* key, long n) {
    const nlohmann::json& a = o.need(key);
    if (!a.is_array() || static_cast<long>(a.size()) != n)
      o.fail(key, fmt::format("expected an array of {} numbers, got {}", n, a.is_array() ? std::to_string(a.size()) : a.type_name()));
    Eigen::VectorXd v(n);
    for (long i = 0; i < n; ++i) v(i) = json_number(a[static_cast<size_t>(i)], origin, json_element(o.field(key), static_cast<size_t>(i)));
    return v;
  };
  try {
    const JsonFields net(j, origin, path);
    net.only({"inputs", "outputs", "hidden", "activation", "l2", "seed", "x_mean", "x_std", "y_mean", "y_std", "layers"});
    if (const std::string a = net.text("activation"); a != "relu") net.fail("activation", fmt::format("expected \"relu\", got \"{}\"", a));
    MlpOptions o;
    const int n_in = json_whole(net.need("inputs"), origin, prefix + "inputs");
    const int n_out = json_whole(net.need("outputs"), origin, prefix + "outputs");
    o.hidden = json_wholes(net.need("hidden"), origin, prefix + "hidden");
    try {
      o.validate();
      if (n_in < 1 || n_out < 1) throw InvalidArgument(fmt::format("inputs {} and outputs {} must be >= 1", n_in, n_out));
    } catch (const InvalidArgument& e) {
      throw ParseError(origin, 0, prefix + "hidden", e.what());
    }
    const double l2 = net.nonnegative("l2");
    const nlohmann::json& seed = net.need("seed");
    if (!seed.is_number_unsigned() && !(seed.is_number_integer() && seed.get<std::int64_t>() >= 0))
      net.fail("seed", fmt::format("expected a whole number >= 0, got {}", json_brief(seed)));
    const Eigen::VectorXd x_mean = vec(net, "x_mean", n_in), x_std = vec(net, "x_std", n_in);
    const Eigen::VectorXd y_mean = vec(net, "y_mean", n_out), y_std = vec(net, "y_std", n_out);
    for (Eigen::Index i = 0; i < n_in; ++i)
      if (!(x_std(i) > 0)) throw ParseError(origin, 0, fmt::format("{}x_std[{}]", prefix, i), fmt::format("must be > 0, got {}", x_std(i)));
    // the weights the widths call for must be in the file, checked before allocating them (a width
    // of 2e9 would otherwise allocate terabytes): layer l is width_l+1 x width_l
    std::vector<long> widths{n_in};
    widths.insert(widths.end(), o.hidden.begin(), o.hidden.end());
    widths.push_back(n_out);
    const nlohmann::json& layers_in = net.need("layers");
    if (!layers_in.is_array() || layers_in.size() != widths.size() - 1)
      net.fail("layers", fmt::format("expected {} layers (hidden + output), got {}", widths.size() - 1, layers_in.is_array() ? layers_in.size() : 0));
    std::vector<JsonFields> layer;
    for (size_t l = 0; l + 1 < widths.size(); ++l) {
      layer.emplace_back(layers_in[l], origin, json_element(net.field("layers"), l));
      const JsonFields& L = layer.back();
      L.only({"rows", "cols", "W", "b"});
      const nlohmann::json& w = L.need("W");
      const long expected = widths[l + 1] * widths[l];
      if (!w.is_array() || static_cast<long>(w.size()) != expected)
        L.fail("W", fmt::format("expected an array of {} numbers ({} x {}), got {}", expected, widths[l + 1], widths[l],
                                w.is_array() ? std::to_string(w.size()) : w.type_name()));
      if (const int r = json_whole(L.need("rows"), origin, L.field("rows")); r != widths[l + 1])
        L.fail("rows", fmt::format("expected {} (the width of layer {}), got {}", widths[l + 1], l + 1, r));
      if (const int c = json_whole(L.need("cols"), origin, L.field("cols")); c != widths[l])
        L.fail("cols", fmt::format("expected {} (the width of its input), got {}", widths[l], c));
    }
    Mlp m(n_in, n_out, o);
    m.l2 = l2;
    m.seed = seed.get<std::uint64_t>();
    m.x_mean = x_mean;
    m.x_std = x_std;
    m.y_mean = y_mean;
    m.y_std = y_std;
    for (size_t l = 0; l < m.W_.size(); ++l) {  // (layers_in's count and W sizes are checked above)
      const Eigen::Index rows = m.W_[l].rows(), cols = m.W_[l].cols();
      const Eigen::VectorXd w = vec(layer[l], "W", rows * cols);
      m.W_[l] = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(w.data(), rows, cols);
      m.b_[l] = vec(layer[l], "b", rows);
    }
    return m;
  } catch (const nlohmann::json::exception& e) {  // (every field is type-checked above: a safety net for the fuzzer's contract)
    throw ParseError(origin, 0, path, fmt::format("wrong type: {}", e.what()));
  }
}

}  // namespace twinwatch::ident
