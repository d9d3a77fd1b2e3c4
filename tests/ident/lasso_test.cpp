// Lasso against R's glmnet (fixture made by tests/data/ident/make_lasso_fixture.R), the KKT
// optimality conditions at every lambda, recovery of a sparse truth, and input validation.
#include "twinwatch/ident/lasso.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "twinwatch/core/error.hpp"

namespace twinwatch::ident {
namespace {

using ::testing::HasSubstr;

// glmnet ran with thresh = 1e-14; ours runs with the same, so paths agree far below these
constexpr double kLambdaRelTol = 1e-9;  // the path is closed-form from lambda_max
constexpr double kCoefTol = 1e-6;       // coefficients, relative to max(1, |b|)
constexpr double kCvRelTol = 1e-6;      // CV errors
constexpr double kInterceptTol = 1e-5;  // a0 = ym - xm'b sums the coefficient errors times the means
constexpr double kTightTol = 1e-14;
// p > n: the end of the path is ill-conditioned (many near-equivalent supports), so two solvers
// that both meet thresh = 1e-14 differ more in the coefficients (measured up to 1.4e-5)
constexpr double kWideFactor = 100.0;
constexpr double kKktSolverTol = 1e-20;

struct Case {
  std::string tag;
  bool standardize = true, intercept = true;
  std::map<std::string, Eigen::MatrixXd> m;
};

std::vector<Case> load_fixture() {
  const std::string path = std::string(TWINWATCH_SOURCE_DIR) + "/tests/data/ident/lasso_glmnet_fixture.txt";
  std::ifstream f(path);
  EXPECT_TRUE(f.good()) << path;
  std::vector<Case> cases;
  std::string line;
  while (std::getline(f, line)) {
    std::istringstream ss(line);
    std::string name;
    ss >> name;
    if (name.empty()) continue;
    if (name == "case") {
      Case c;
      int n, p, st, ic;
      ss >> c.tag >> n >> p >> st >> ic;
      c.standardize = st != 0;
      c.intercept = ic != 0;
      cases.push_back(c);
      continue;
    }
    long r, k;
    ss >> r >> k;
    Eigen::MatrixXd m(r, k);
    for (long i = 0; i < r; ++i) {
      std::getline(f, line);
      std::istringstream row(line);
      for (long j = 0; j < k; ++j) row >> m(i, j);
    }
    cases.back().m[name] = m;
  }
  return cases;
}

LassoOptions options_of(const Case& c) {
  LassoOptions o;
  o.nlambda = 30;
  o.standardize = c.standardize;
  o.intercept = c.intercept;
  o.tol = kTightTol;
  return o;
}

TEST(Lasso, PathMatchesGlmnet) {
  const auto cases = load_fixture();
  ASSERT_EQ(cases.size(), 4u);
  for (const Case& c : cases) {
    for (LassoAlgorithm alg : {LassoAlgorithm::Covariance, LassoAlgorithm::Naive}) {
      SCOPED_TRACE(c.tag + (alg == LassoAlgorithm::Naive ? " naive" : " covariance"));
      LassoOptions o = options_of(c);
      o.algorithm = alg;
      const LassoPath path = lasso_path(c.m.at("x"), c.m.at("y").col(0), o);
      const Eigen::MatrixXd& lam = c.m.at("lambda");
      const double f = c.tag == "wide" ? kWideFactor : 1.0;
      // glmnet's early exits give the same path length
      ASSERT_EQ(path.lambda.size(), lam.rows());
      for (long l = 0; l < lam.rows(); ++l) {
        EXPECT_NEAR(path.lambda(l), lam(l, 0), kLambdaRelTol * lam(l, 0)) << "lambda " << l;
        EXPECT_NEAR(path.a0(l), c.m.at("a0")(l, 0), f * kInterceptTol * std::max(1.0, std::abs(c.m.at("a0")(l, 0)))) << "a0 " << l;
        for (long j = 0; j < path.beta.rows(); ++j) {
          const double ref = c.m.at("beta")(j, l);
          EXPECT_NEAR(path.beta(j, l), ref, f * kCoefTol * std::max(1.0, std::abs(ref))) << "beta " << j << " at lambda " << l;
        }
      }
    }
  }
}

// cv.glmnet's default (each fold its own path, interpolated) and with lambda given (FullLambda)
TEST(Lasso, CrossValidationMatchesCvGlmnet) {
  for (const Case& c : load_fixture()) {
    for (LassoCvAlignment al : {LassoCvAlignment::FoldPaths, LassoCvAlignment::FullLambda}) {
      const std::string sfx = al == LassoCvAlignment::FoldPaths ? "" : "_full";
      SCOPED_TRACE(c.tag + sfx);
      LassoCvOptions cv;
      cv.alignment = al;
      const Eigen::MatrixXd& fid = c.m.at("foldid");
      for (long i = 0; i < fid.rows(); ++i) cv.foldid.push_back(static_cast<int>(fid(i, 0)));
      const LassoCvResult r = cv_lasso(c.m.at("x"), c.m.at("y").col(0), options_of(c), cv);
      const Eigen::MatrixXd& cvm = c.m.at("cvm" + sfx);
      const double f = c.tag == "wide" ? kWideFactor : 1.0;
      ASSERT_EQ(r.cvm.size(), cvm.rows());
      for (long l = 0; l < cvm.rows(); ++l) {
        EXPECT_NEAR(r.cvm(l), cvm(l, 0), f * kCvRelTol * cvm(l, 0)) << "cvm " << l;
        EXPECT_NEAR(r.cvsd(l), c.m.at("cvsd" + sfx)(l, 0), f * kCvRelTol * cvm(l, 0)) << "cvsd " << l;
      }
      EXPECT_NEAR(r.lambda_min, c.m.at("lambda_min_1se" + sfx)(0, 0), kLambdaRelTol * r.lambda_min);
      EXPECT_NEAR(r.lambda_1se, c.m.at("lambda_min_1se" + sfx)(1, 0), kLambdaRelTol * r.lambda_1se);
      // the chosen model is the path's solution at lambda_min
      EXPECT_EQ(r.beta, r.path.beta.col(r.index_min));
    }
  }
}

// random design with correlated columns of different scales; seed printed by SCOPED_TRACE
void random_problem(unsigned seed, long n, long p, Eigen::MatrixXd& X, Eigen::VectorXd& y, Eigen::VectorXd& truth) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> N01;
  std::uniform_real_distribution<double> U(0.2, 4.0);
  X.resize(n, p);
  for (long i = 0; i < n; ++i) {
    double prev = 0.0;
    for (long j = 0; j < p; ++j) X(i, j) = prev = 0.6 * prev + N01(rng);
  }
  for (long j = 0; j < p; ++j) X.col(j) = X.col(j) * U(rng) + Eigen::VectorXd::Constant(n, U(rng) - 2.0);
  truth = Eigen::VectorXd::Zero(p);
  for (long j = 0; j < p; j += 7) truth(j) = (j % 2 ? 1.0 : -1.0) * (0.5 + 0.1 * static_cast<double>(j % 5));
  y = X * truth;
  for (long i = 0; i < n; ++i) y(i) += 3.0 + 0.5 * N01(rng);
}

// KKT of 1/(2n)||y - a0 - X~ c||^2 + lambda |c|_1 (X~ standardised): g_j = x~_j'r/n equals
// lambda sign(c_j) where c_j != 0 and |g_j| <= lambda where c_j = 0; unpenalised columns g_j = 0
void expect_kkt(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const LassoPath& path, const Eigen::VectorXd& pf) {
  const long n = X.rows(), p = X.cols();
  const Eigen::RowVectorXd xm = X.colwise().mean();
  Eigen::MatrixXd Xc = X.rowwise() - xm;
  const Eigen::VectorXd xs = (Xc.colwise().squaredNorm() / static_cast<double>(n)).cwiseSqrt();
  const double pf_scale = static_cast<double>(p) / pf.sum();
  const double ysd = std::sqrt((y.array() - y.mean()).square().mean());
  for (long l = 0; l < path.lambda.size(); ++l) {
    const Eigen::VectorXd r = y - path.predict(X, static_cast<int>(l));
    EXPECT_NEAR(r.mean(), 0.0, 1e-9) << "intercept at lambda " << l;
    const double lam = path.lambda(l);
    for (long j = 0; j < p; ++j) {
      const double g = Xc.col(j).dot(r) / static_cast<double>(n) / xs(j);
      const double pen = lam * pf(j) * pf_scale;
      const double b = path.beta(j, l);
      // the solver stops when max xv (delta c)^2 < kKktSolverTol: coefficients within 1e-10 (in
      // units of sd(y)), so the gradient is within a small multiple of that
      const double tol = 1e-8 * ysd;
      if (b != 0.0)
        EXPECT_NEAR(g, std::copysign(pen, b), tol) << "active column " << j << " at lambda " << l;
      else
        EXPECT_LE(std::abs(g), pen + tol) << "inactive column " << j << " at lambda " << l;
    }
  }
}

TEST(Lasso, KktConditionsHoldAtEveryLambda) {
  for (unsigned seed : {11u, 12u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Eigen::MatrixXd X;
    Eigen::VectorXd y, truth;
    random_problem(seed, 300, 40, X, y, truth);
    for (LassoAlgorithm alg : {LassoAlgorithm::Covariance, LassoAlgorithm::Naive}) {
      LassoOptions o;
      o.tol = kKktSolverTol;
      o.nlambda = 50;
      o.early_stop = false;
      o.algorithm = alg;
      Eigen::VectorXd pf = Eigen::VectorXd::Ones(40);
      pf(5) = 0.0;   // unpenalised
      pf(9) = 2.5;   // penalised more
      o.penalty_factor = pf;
      const LassoPath path = lasso_path(X, y, o);
      ASSERT_TRUE(path.converged) << path.message;
      ASSERT_EQ(path.lambda.size(), 50);
      // lambda_max: all penalised coefficients zero there, and only there
      EXPECT_EQ(path.df(0), 1);
      EXPECT_GT(path.df(1), 1);
      expect_kkt(X, y, path, pf);
    }
  }
}

TEST(Lasso, CovarianceAndNaiveUpdatesAgree) {
  Eigen::MatrixXd X;
  Eigen::VectorXd y, truth;
  random_problem(21, 200, 30, X, y, truth);
  LassoOptions o;
  o.tol = kTightTol;
  o.algorithm = LassoAlgorithm::Covariance;
  const LassoPath a = lasso_path(X, y, o);
  o.algorithm = LassoAlgorithm::Naive;
  const LassoPath b = lasso_path(X, y, o);
  ASSERT_EQ(a.lambda.size(), b.lambda.size());
  EXPECT_LT((a.beta - b.beta).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT((a.a0 - b.a0).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(Lasso, RecoversASparseTruthFromNoisyData) {
  Eigen::MatrixXd X;
  Eigen::VectorXd y, truth;
  random_problem(31, 3000, 50, X, y, truth);
  LassoCvOptions cv;
  cv.use_1se = true;
  cv.seed = 5;
  const LassoCvResult r = cv_lasso(X, y, LassoOptions{}, cv);
  for (long j = 0; j < 50; ++j) {
    if (truth(j) != 0.0) {
      // selected with the right sign, shrunk towards zero (the Lasso bias) but not far
      EXPECT_GT(r.beta(j) * truth(j), 0.0) << "column " << j;
      EXPECT_LT(std::abs(r.beta(j)), std::abs(truth(j)) + 0.02) << "column " << j;
      EXPECT_NEAR(r.beta(j), truth(j), 0.1) << "column " << j;
    }
  }
  // with a refit on the pruned support the estimate is unbiased
  cv.prune_ratio = 0.01;
  cv.refit = true;
  const LassoCvResult rr = cv_lasso(X, y, LassoOptions{}, cv);
  for (long j = 0; j < 50; ++j) {
    if (truth(j) != 0.0) EXPECT_NEAR(rr.beta(j), truth(j), 0.02) << "column " << j;
    else EXPECT_EQ(rr.beta(j), 0.0) << "column " << j << " should be pruned";
  }
  EXPECT_NEAR(rr.a0, 3.0, 0.1);
  // the prediction of the chosen model beats the noise-free truth only by chance
  const double rmse = std::sqrt((rr.predict(X) - y).squaredNorm() / 3000.0);
  EXPECT_NEAR(rmse, 0.5, 0.03);
}

TEST(Lasso, SeveralResponsesGiveTheSameAsOneAtATime) {
  Eigen::MatrixXd X;
  Eigen::VectorXd y1, y2, truth;
  random_problem(41, 400, 20, X, y1, truth);
  y2 = X.col(3) * 2.0 - X.col(11) + Eigen::VectorXd::LinSpaced(400, 0.0, 1.0);
  Eigen::MatrixXd Y(400, 2);
  Y << y1, y2;
  LassoCvOptions cv;
  cv.nfolds = 5;
  const auto both = cv_lasso_multi(X, Y, LassoOptions{}, cv);
  ASSERT_EQ(both.size(), 2u);
  for (int r = 0; r < 2; ++r) {
    const LassoCvResult one = cv_lasso(X, Y.col(r), LassoOptions{}, cv);
    EXPECT_EQ(one.index_min, both[static_cast<size_t>(r)].index_min);
    EXPECT_LT((one.cvm - both[static_cast<size_t>(r)].cvm).cwiseAbs().maxCoeff(), 1e-12 * one.cvm.maxCoeff());
    EXPECT_LT((one.beta - both[static_cast<size_t>(r)].beta).cwiseAbs().maxCoeff(), 1e-10);
  }
}

TEST(Lasso, ReportsWhenThePassBudgetRunsOut) {
  Eigen::MatrixXd X;
  Eigen::VectorXd y, truth;
  random_problem(51, 100, 10, X, y, truth);
  LassoOptions o;
  o.max_passes = 3;
  const LassoPath p = lasso_path(X, y, o);
  EXPECT_FALSE(p.converged);
  EXPECT_THAT(p.message, HasSubstr("max_passes"));
  EXPECT_LT(p.lambda.size(), 100);
}

TEST(Lasso, FoldsAreBalancedAndSeeded) {
  const auto a = lasso_folds(103, 10, 7), b = lasso_folds(103, 10, 7), c = lasso_folds(103, 10, 8);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  std::vector<int> count(10, 0);
  for (int f : a) ++count[static_cast<size_t>(f)];
  for (int k = 0; k < 10; ++k) EXPECT_TRUE(count[static_cast<size_t>(k)] == 10 || count[static_cast<size_t>(k)] == 11);
}

// --- validation errors -------------------------------------------------------------------------

void expect_error(const LassoOptions& o, const std::string& what) {
  Eigen::MatrixXd X = Eigen::MatrixXd::Random(20, 3);
  Eigen::VectorXd y = Eigen::VectorXd::Random(20);
  try {
    lasso_path(X, y, o);
    ADD_FAILURE() << "expected InvalidArgument with '" << what << "'";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr(what));
  }
}

TEST(LassoValidation, NlambdaMustBePositive) {
  LassoOptions o;
  o.nlambda = 0;
  expect_error(o, "nlambda is 0, must be >= 1");
}
TEST(LassoValidation, LambdaMinRatioInUnitInterval) {
  LassoOptions o;
  o.lambda_min_ratio = 1.5;
  expect_error(o, "lambda_min_ratio is 1.5, must be in (0, 1)");
}
TEST(LassoValidation, UserLambdaMustDecrease) {
  LassoOptions o;
  o.lambda = {1.0, 2.0};
  expect_error(o, "lambda[1] is 2, must be < lambda[0] = 1");
}
TEST(LassoValidation, UserLambdaMustBePositive) {
  LassoOptions o;
  o.lambda = {-1.0};
  expect_error(o, "lambda[0] is -1, must be > 0");
}
TEST(LassoValidation, TolMustBePositive) {
  LassoOptions o;
  o.tol = 0.0;
  expect_error(o, "tol is 0, must be > 0");
}
TEST(LassoValidation, MaxPassesMustBePositive) {
  LassoOptions o;
  o.max_passes = 0;
  expect_error(o, "max_passes is 0, must be >= 1");
}
TEST(LassoValidation, PenaltyFactorNonNegative) {
  LassoOptions o;
  o.penalty_factor = Eigen::Vector3d(1, -1, 1);
  expect_error(o, "penalty_factor[1] is -1, must be >= 0");
}
TEST(LassoValidation, PenaltyFactorNotAllZero) {
  LassoOptions o;
  o.penalty_factor = Eigen::Vector3d::Zero();
  expect_error(o, "penalty_factor is all zero");
}
TEST(LassoValidation, PenaltyFactorSize) {
  LassoOptions o;
  o.penalty_factor = Eigen::Vector2d(1, 1);
  expect_error(o, "penalty_factor has size 2, expected 3");
}
TEST(LassoValidation, RowsOfXAndY) {
  try {
    lasso_path(Eigen::MatrixXd::Random(20, 3), Eigen::VectorXd::Random(19), LassoOptions{});
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("X has 20 rows, y has 19"));
  }
}
TEST(LassoValidation, NonFiniteData) {
  Eigen::MatrixXd X = Eigen::MatrixXd::Random(20, 3);
  X(4, 2) = std::nan("");
  try {
    lasso_path(X, Eigen::VectorXd::Random(20), LassoOptions{});
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("column 2 of X has a non-finite value"));
  }
}

void expect_cv_error(const LassoCvOptions& cv, const std::string& what) {
  try {
    cv_lasso(Eigen::MatrixXd::Random(20, 3), Eigen::VectorXd::Random(20), LassoOptions{}, cv);
    ADD_FAILURE() << "expected InvalidArgument with '" << what << "'";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr(what));
  }
}
TEST(LassoValidation, NfoldsAtLeastTwo) {
  LassoCvOptions cv;
  cv.nfolds = 1;
  expect_cv_error(cv, "nfolds is 1, must be >= 2");
}
TEST(LassoValidation, NfoldsAtMostN) {
  LassoCvOptions cv;
  cv.nfolds = 21;
  expect_cv_error(cv, "nfolds is 21, must be <= the number of samples 20");
}
TEST(LassoValidation, FoldidSize) {
  LassoCvOptions cv;
  cv.foldid = {0, 1};
  expect_cv_error(cv, "foldid has size 2, expected 20");
}
TEST(LassoValidation, FoldidNegative) {
  LassoCvOptions cv;
  cv.foldid.assign(20, 0);
  cv.foldid[1] = 1;
  cv.foldid[3] = -2;
  expect_cv_error(cv, "foldid[3] is -2, must be >= 0");
}
TEST(LassoValidation, FoldidWithoutGaps) {
  LassoCvOptions cv;
  cv.foldid.assign(20, 0);
  cv.foldid[1] = 2;
  expect_cv_error(cv, "fold 1 is empty");
}
TEST(LassoValidation, PruneRatio) {
  LassoCvOptions cv;
  cv.prune_ratio = -0.1;
  expect_cv_error(cv, "prune_ratio is -0.1, must be in [0, 1)");
}

}  // namespace
}  // namespace twinwatch::ident
