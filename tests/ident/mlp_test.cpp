// The learned reference's network (UR3e §3.5): gradient against finite differences, learning a
// known smooth function, determinism for a seed, z-score invariance, early stopping, file round
// trip, and one test per validation error.
#include "twinwatch/ident/mlp.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <random>

#include "twinwatch/core/error.hpp"
#include "error_text.hpp"

namespace twinwatch::ident {
namespace {

using ::testing::HasSubstr;

// central differences of a smooth (away from ReLU kinks) function of ~100 parameters: truncation
// O(h^2) ~ 1e-12, rounding O(eps / h) ~ 1e-10 relative to the loss
constexpr double kFdStep = 1e-6;
constexpr double kFdTol = 1e-6;

Eigen::MatrixXd uniform(int rows, int cols, std::mt19937& rng, double a) {
  std::uniform_real_distribution<double> u(-a, a);
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index r = 0; r < m.rows(); ++r) m(r, c) = u(rng);
  return m;
}

// y1 = sin(x1) cos(x2), y2 = 0.5 x3^2 - 0.3 x1 x2 on [-2, 2]^3: smooth, nonlinear, coupled
Eigen::MatrixXd target(const Eigen::MatrixXd& X) {
  Eigen::MatrixXd Y(2, X.cols());
  for (Eigen::Index k = 0; k < X.cols(); ++k) {
    Y(0, k) = std::sin(X(0, k)) * std::cos(X(1, k));
    Y(1, k) = 0.5 * X(2, k) * X(2, k) - 0.3 * X(0, k) * X(1, k);
  }
  return Y;
}

template <typename F>
std::string message_of(F f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no exception)";
}

TEST(Mlp, GradientMatchesFiniteDifferences) {
  const unsigned seed = 11;
  std::mt19937 rng(seed);
  MlpOptions o;
  o.hidden = {6, 4};  // two hidden layers: the backward pass through a ReLU layer is exercised
  o.l2 = 0.03;
  Mlp net(3, 2, o);
  const Eigen::MatrixXd X = uniform(3, 40, rng, 1.5), Y = uniform(2, 40, rng, 1.0);
  Eigen::VectorXd theta = net.parameters() + 0.1 * uniform(net.n_parameters(), 1, rng, 1.0);
  for (Eigen::Index i = 0; i < theta.size(); ++i) theta(i) += 0.05;  // biases off zero, units active
  Eigen::VectorXd g;
  net.loss(theta, X, Y, &g);
  ASSERT_EQ(g.size(), net.n_parameters());
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    Eigen::VectorXd tp = theta, tm = theta;
    tp(i) += kFdStep;
    tm(i) -= kFdStep;
    const double fd = (net.loss(tp, X, Y, nullptr) - net.loss(tm, X, Y, nullptr)) / (2 * kFdStep);
    EXPECT_NEAR(g(i), fd, kFdTol * std::max(1.0, std::abs(fd))) << "parameter " << i << ", seed " << seed;
  }
}

TEST(Mlp, LossWithoutPenaltyIsTheMeanSquaredErrorOverTwo) {
  std::mt19937 rng(3);
  MlpOptions o;
  o.l2 = 0.5;
  Mlp net(3, 2, o);
  const Eigen::MatrixXd X = uniform(3, 25, rng, 1.0), Y = uniform(2, 25, rng, 1.0);
  // independent evaluation through the per-sample path (identity z-scores)
  double sse = 0.0;
  for (Eigen::Index k = 0; k < X.cols(); ++k) {
    double y[2];
    net.predict(X.col(k).data(), y);
    sse += (Eigen::Vector2d(y[0], y[1]) - Y.col(k)).squaredNorm();
  }
  EXPECT_NEAR(net.loss(net.parameters(), X, Y, nullptr, false), sse / (2.0 * 25 * 2), 1e-14);
  EXPECT_GT(net.loss(net.parameters(), X, Y, nullptr, true), net.loss(net.parameters(), X, Y, nullptr, false));
}

// a known smooth function from 2000 samples, checked on 2000 fresh ones: RMSE below 0.05 and
// R^2 above 0.99 on both outputs (standard deviations 0.44 and 0.72)
TEST(Mlp, LearnsAKnownSmoothFunction) {
  const unsigned seed = 5;
  std::mt19937 rng(seed);
  const Eigen::MatrixXd X = uniform(3, 2000, rng, 2.0), Xt = uniform(3, 2000, rng, 2.0);
  MlpOptions o;
  o.hidden = {15};
  o.l2 = 1e-6;
  o.max_evaluations = 4000;
  Mlp net(3, 2, o);
  const MlpFitReport r = net.fit(X, target(X));
  const Eigen::MatrixXd E = net.predict(Xt) - target(Xt);
  for (int i = 0; i < 2; ++i) {
    const double rmse = std::sqrt(E.row(i).squaredNorm() / static_cast<double>(E.cols()));
    const Eigen::RowVectorXd y = target(Xt).row(i);
    const double r2 = 1.0 - E.row(i).squaredNorm() / (y.array() - y.mean()).square().sum();
    EXPECT_LT(rmse, 0.05) << "output " << i << ", seed " << seed << ", " << to_string(r.stop) << " after " << r.evaluations;
    EXPECT_GT(r2, 0.99) << "output " << i << ", seed " << seed;
  }
  EXPECT_EQ(r.train_samples, 1600);
  EXPECT_EQ(r.validation_samples, 400);
}

TEST(Mlp, SameSeedGivesBitIdenticalWeights) {
  std::mt19937 rng(8);
  const Eigen::MatrixXd X = uniform(3, 500, rng, 2.0);
  const Eigen::MatrixXd Y = target(X);
  MlpOptions o;
  o.max_evaluations = 300;
  o.seed = 42;
  Mlp a(3, 2, o), b(3, 2, o);
  a.fit(X, Y);
  b.fit(X, Y);
  const Eigen::VectorXd pa = a.parameters(), pb = b.parameters();
  ASSERT_EQ(pa.size(), pb.size());
  for (Eigen::Index i = 0; i < pa.size(); ++i) EXPECT_EQ(pa(i), pb(i)) << "parameter " << i;  // exact, not near
  o.seed = 43;
  Mlp c(3, 2, o);
  c.fit(X, Y);
  EXPECT_GT((c.parameters() - pa).norm(), 1e-3);
}

// z-scoring with the training statistics makes the fit blind to the units of inputs and outputs
// (up to rounding, which a long L-BFGS run amplifies into another local minimum: short run)
TEST(Mlp, PredictionsDoNotDependOnTheUnitsOfTheData) {
  std::mt19937 rng(9);
  const Eigen::MatrixXd X = uniform(3, 400, rng, 2.0), Xt = uniform(3, 50, rng, 2.0);
  const Eigen::MatrixXd Y = target(X);
  MlpOptions o;
  o.max_evaluations = 30;
  Mlp a(3, 2, o), b(3, 2, o);
  a.fit(X, Y);
  const Eigen::Vector3d sx(1000.0, 0.001, 3.0), ox(5.0, -2.0, 0.0);
  const Eigen::Vector2d sy(0.01, 50.0), oy(1.0, -3.0);
  b.fit((sx.asDiagonal() * X).colwise() + ox, (sy.asDiagonal() * Y).colwise() + oy);
  const Eigen::MatrixXd pa = a.predict(Xt);
  const Eigen::MatrixXd pb = (sy.cwiseInverse().asDiagonal() * (b.predict((sx.asDiagonal() * Xt).colwise() + ox).colwise() - oy));
  EXPECT_LT((pa - pb).cwiseAbs().maxCoeff(), 1e-6);
}

// noisy data and a wide network with no penalty overfit; the fit must stop `patience`
// evaluations after the best held-out loss and keep that evaluation's parameters
TEST(Mlp, EarlyStoppingKeepsTheBestHeldOutEvaluation) {
  std::mt19937 rng(12);
  const Eigen::MatrixXd X = uniform(3, 300, rng, 2.0);
  Eigen::MatrixXd Y = target(X) + 0.3 * uniform(2, 300, rng, 1.0);
  MlpOptions o;
  o.hidden = {60};
  o.l2 = 0.0;
  o.patience = 30;
  o.max_evaluations = 5000;
  Mlp net(3, 2, o);
  const MlpFitReport r = net.fit(X, Y);
  ASSERT_EQ(r.stop, MlpStop::EarlyStopped);
  EXPECT_EQ(r.evaluations, r.best_evaluation + o.patience);
  EXPECT_GT(r.validation_loss, r.train_loss);  // overfitting shows on the held-out block
}

TEST(Mlp, SegmentsHoldOutTheEndOfEachRecording) {
  std::mt19937 rng(13);
  const Eigen::MatrixXd X = uniform(3, 300, rng, 2.0);
  MlpOptions o;
  o.max_evaluations = 5;
  o.validation_fraction = 0.25;
  Mlp net(3, 2, o);
  const MlpFitReport r = net.fit(X, target(X), {100, 300});  // 25 + 50 held out
  EXPECT_EQ(r.validation_samples, 75);
  EXPECT_EQ(r.train_samples, 225);
}

TEST(Mlp, JsonRoundTripIsExact) {
  std::mt19937 rng(14);
  const Eigen::MatrixXd X = uniform(3, 300, rng, 2.0);
  MlpOptions o;
  o.hidden = {7, 5};
  o.max_evaluations = 50;
  Mlp net(3, 2, o);
  net.fit(X, target(X));
  const Mlp back = Mlp::from_json(net.to_json(), "net.json", "");
  const Eigen::MatrixXd d = net.predict(X) - back.predict(X);
  EXPECT_EQ(d.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(back.seed, o.seed);
  EXPECT_EQ(back.hidden(), o.hidden);
}

TEST(Mlp, BatchAndPerSamplePredictionsAgree) {
  std::mt19937 rng(15);
  Mlp net(3, 2, MlpOptions{});
  net.x_mean = Eigen::Vector3d(0.1, -0.2, 0.3);
  net.x_std = Eigen::Vector3d(2.0, 0.5, 1.5);
  net.y_mean = Eigen::Vector2d(1.0, -1.0);
  net.y_std = Eigen::Vector2d(0.2, 3.0);
  const Eigen::MatrixXd X = uniform(3, 20, rng, 2.0);
  const Eigen::MatrixXd P = net.predict(X);
  for (Eigen::Index k = 0; k < X.cols(); ++k) {
    double y[2];
    net.predict(X.col(k).data(), y);
    EXPECT_NEAR(y[0], P(0, k), 1e-12);
    EXPECT_NEAR(y[1], P(1, k), 1e-12);
  }
}

// ---- validation errors, one per field ----
TEST(MlpOptions, RejectsNoHiddenLayer) {
  MlpOptions o;
  o.hidden.clear();
  EXPECT_THAT(message_of([&] { o.validate(); }), HasSubstr("hidden is empty"));
}
TEST(MlpOptions, RejectsAZeroWidthLayer) {
  MlpOptions o;
  o.hidden = {15, 0};
  EXPECT_THAT(message_of([&] { o.validate(); }), HasSubstr("hidden[1] is 0, must be >= 1"));
}
TEST(MlpOptions, RejectsANegativePenalty) {
  MlpOptions o;
  o.l2 = -1e-3;
  EXPECT_THAT(message_of([&] { o.validate(); }), HasSubstr("l2 is -0.001"));
}
TEST(MlpOptions, RejectsZeroEvaluations) {
  MlpOptions o;
  o.max_evaluations = 0;
  EXPECT_THAT(message_of([&] { o.validate(); }), HasSubstr("max_evaluations is 0, must be >= 1"));
}
TEST(MlpOptions, RejectsAHeldOutFractionOfAHalf) {
  MlpOptions o;
  o.validation_fraction = 0.5;
  EXPECT_THAT(message_of([&] { o.validate(); }), HasSubstr("validation_fraction is 0.5, must be in [0, 0.5)"));
}
TEST(MlpOptions, RejectsZeroPatience) {
  MlpOptions o;
  o.patience = 0;
  EXPECT_THAT(message_of([&] { o.validate(); }), HasSubstr("patience is 0"));
}
TEST(MlpOptions, RejectsANegativeTolerance) {
  MlpOptions o;
  o.ftol_rel = -1.0;
  EXPECT_THAT(message_of([&] { o.validate(); }), HasSubstr("ftol_rel is -1"));
}
TEST(MlpOptions, RejectsNoLbfgsMemory) {
  MlpOptions o;
  o.lbfgs_memory = 0;
  EXPECT_THAT(message_of([&] { o.validate(); }), HasSubstr("lbfgs_memory is 0"));
}
TEST(Mlp, RejectsZeroInputs) { EXPECT_THAT(message_of([] { Mlp(0, 2, MlpOptions{}); }), HasSubstr("input count is 0")); }
TEST(Mlp, RejectsZeroOutputs) { EXPECT_THAT(message_of([] { Mlp(2, 0, MlpOptions{}); }), HasSubstr("output count is 0")); }
TEST(Mlp, RejectsTargetsWithTheWrongRowCount) {
  Mlp net(3, 2, MlpOptions{});
  EXPECT_THAT(message_of([&] { net.fit(Eigen::MatrixXd::Zero(3, 50), Eigen::MatrixXd::Zero(3, 50)); }),
              HasSubstr("Y (rows) has size 3, expected 2"));
}
TEST(Mlp, RejectsInputsWithTheWrongRowCount) {
  Mlp net(3, 2, MlpOptions{});
  EXPECT_THAT(message_of([&] { net.fit(Eigen::MatrixXd::Zero(4, 50), Eigen::MatrixXd::Zero(2, 50)); }),
              HasSubstr("X (rows) has size 4, expected 3"));
}
TEST(Mlp, RejectsUnequalSampleCounts) {
  Mlp net(3, 2, MlpOptions{});
  EXPECT_THAT(message_of([&] { net.fit(Eigen::MatrixXd::Zero(3, 50), Eigen::MatrixXd::Zero(2, 49)); }),
              HasSubstr("Y (columns) has size 49, expected 50"));
}
TEST(Mlp, RejectsNaNInputs) {
  Mlp net(3, 2, MlpOptions{});
  Eigen::MatrixXd X = Eigen::MatrixXd::Ones(3, 50);
  X(1, 7) = std::nan("");
  EXPECT_THAT(message_of([&] { net.fit(X, Eigen::MatrixXd::Zero(2, 50)); }), HasSubstr("X contain NaN"));
}
TEST(Mlp, RejectsNaNTargets) {
  Mlp net(3, 2, MlpOptions{});
  Eigen::MatrixXd Y = Eigen::MatrixXd::Ones(2, 50);
  Y(0, 3) = std::nan("");
  EXPECT_THAT(message_of([&] { net.fit(Eigen::MatrixXd::Zero(3, 50), Y); }), HasSubstr("Y contain NaN"));
}
TEST(Mlp, RejectsDecreasingSegmentEnds) {
  Mlp net(3, 2, MlpOptions{});
  EXPECT_THAT(message_of([&] { net.fit(Eigen::MatrixXd::Zero(3, 50), Eigen::MatrixXd::Zero(2, 50), {30, 20, 50}); }),
              HasSubstr("segment_ends[1] is 20, must be in (30, 50]"));
}
TEST(Mlp, RejectsSegmentsThatDoNotCoverTheData) {
  Mlp net(3, 2, MlpOptions{});
  EXPECT_THAT(message_of([&] { net.fit(Eigen::MatrixXd::Zero(3, 50), Eigen::MatrixXd::Zero(2, 50), {20, 40}); }),
              HasSubstr("segment_ends ends at 40, expected X.cols() = 50"));
}
TEST(Mlp, RejectsTooFewSamples) {
  Mlp net(3, 2, MlpOptions{});
  EXPECT_THAT(message_of([&] { net.fit(Eigen::MatrixXd::Zero(3, 8), Eigen::MatrixXd::Zero(2, 8)); }),
              HasSubstr("has 7 samples to fit, expected at least 10"));
}
TEST(Mlp, RejectsAParameterVectorOfTheWrongSize) {
  Mlp net(3, 2, MlpOptions{});
  EXPECT_THAT(message_of([&] { net.set_parameters(Eigen::VectorXd::Zero(5)); }), HasSubstr("has size 5, expected 92"));
}
TEST(MlpFile, NamesAMissingField) {
  Mlp net(3, 2, MlpOptions{});
  nlohmann::json j = nlohmann::json::parse(net.to_json());
  j.erase("x_std");
  EXPECT_THAT(message_of([&] { Mlp::from_json(j.dump(), "t.json", "learned.network."); }),
              HasSubstr("t.json: field 'learned.network.x_std': missing required field"));
}
TEST(MlpFile, NamesAnUnknownKey) {
  Mlp net(3, 2, MlpOptions{});
  std::string text = net.to_json();
  text.replace(text.find("\"x_std\""), 7, "\"x_sdd\"");
  EXPECT_THAT(message_of([&] { Mlp::from_json(text, "t.json", "learned.network."); }),
              HasSubstr("t.json: field 'learned.network.x_sdd': unknown key, expected one of: inputs, outputs, hidden, activation, l2, seed, x_mean, x_std"));
}
TEST(MlpFile, NamesALayerOfTheWrongShape) {
  Mlp net(3, 2, MlpOptions{});
  nlohmann::json j = nlohmann::json::parse(net.to_json());
  j["layers"][0]["rows"] = 7;
  EXPECT_THAT(message_of([&] { Mlp::from_json(j.dump(), "t.json", "network."); }), HasSubstr("t.json: field 'network.layers[0].rows': expected"));
  j = nlohmann::json::parse(net.to_json());
  j["activation"] = "tanh";
  EXPECT_THAT(message_of([&] { Mlp::from_json(j.dump(), "t.json", "network."); }),
              HasSubstr("t.json: field 'network.activation': expected \"relu\", got \"tanh\""));
}
TEST(MlpFile, NamesAVectorOfTheWrongLength) {
  EXPECT_THAT(message_of([] {
                Mlp::from_json(R"({"inputs": 2, "outputs": 1, "hidden": [3], "activation": "relu", "l2": 0, "seed": 0, "x_mean": [0], "x_std": [1, 1], "y_mean": [0],
                                  "y_std": [1], "layers": []})", "t.json", "");
              }),
              HasSubstr("expected an array of 2 numbers, got 1"));
}
TEST(MlpFile, NamesAWrongLayerCount) {
  EXPECT_THAT(message_of([] {
                Mlp::from_json(R"({"inputs": 2, "outputs": 1, "hidden": [3], "activation": "relu", "l2": 0, "seed": 0, "x_mean": [0, 0], "x_std": [1, 1], "y_mean": [0],
                                  "y_std": [1], "layers": []})", "t.json", "");
              }),
              HasSubstr("expected 2 layers (hidden + output), got 0"));
}
TEST(MlpFile, NamesANonPositiveScale) {
  EXPECT_THAT(message_of([] {
                Mlp::from_json(R"({"inputs": 2, "outputs": 1, "hidden": [3], "activation": "relu", "l2": 0, "seed": 0, "x_mean": [0, 0], "x_std": [1, 0], "y_mean": [0],
                                  "y_std": [1], "layers": []})", "t.json", "");
              }),
              HasSubstr("x_std[1]"));
}

// found by fuzzing the twin file (fuzz/regressions/twin_model): get<int>() of 1e20 was undefined,
// and a hidden width of 2e9 tried to allocate 190 GB before the weights were checked
TEST(Mlp, FromJsonRejectsHugeSizesBeforeAllocating) {
  const auto error_of = [](const std::string& text) {
    return twinwatch::test::error_text<ParseError>([&] { Mlp::from_json(text, "net.json", "network."); });
  };
  const std::string tail = R"(, "activation": "relu", "l2": 0, "seed": 0, "x_mean": [0], "x_std": [1], "y_mean": [0], "y_std": [1],
                                "layers": [{"rows": 1, "cols": 1, "W": [1], "b": [0]}, {"rows": 1, "cols": 1, "W": [1], "b": [0]}]})";
  EXPECT_EQ(error_of(R"({"inputs": 1, "outputs": 1, "hidden": [1])" + tail), "no error");
  EXPECT_THAT(error_of(R"({"inputs": 1e20, "outputs": 1, "hidden": [1])" + tail),
              HasSubstr("net.json: field 'network.inputs': expected a whole number, got 1e+20"));
  EXPECT_THAT(error_of(R"({"inputs": 1, "outputs": 1, "hidden": [2000000000])" + tail),
              HasSubstr("field 'network.layers[0].W': expected an array of 2000000000 numbers (2000000000 x 1), got 1"));
}

}  // namespace
}  // namespace twinwatch::ident
