// Lasso with 10-fold CV and 100 lambdas on one 20000 x 225 design (issue 5), side by side with
// R's cv.glmnet and scikit-learn's LassoCV: bench/ident/lasso_peers.sh runs all three on the same
// data file and folds. This program writes the data, times ours and writes our selection.
//   lasso_benchmark --write-data=DIR          X.f64 (column-major), y.f64, foldid.i32, meta.txt
//   lasso_benchmark --data=DIR [--result=FILE] [benchmark flags]
// Baseline kept in the same run: naive (residual) updates instead of covariance updates.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "twinwatch/ident/lasso.hpp"

namespace {

using twinwatch::ident::LassoAlgorithm;

constexpr long kN = 20000;     // samples (issue 5)
constexpr long kP = 225;       // candidates: |A| = 9 (3 joints) x |B| = 25 (2 joints, m = 2)
constexpr int kFolds = 10;
constexpr unsigned kSeed = 20261123;

std::string g_data, g_result;
Eigen::MatrixXd g_X;
Eigen::VectorXd g_y;
std::vector<int> g_foldid;

// a design like the Kronecker library: correlated columns of different scales and means, a
// sparse truth of 20 terms and noise
void make_data() {
  std::mt19937 rng(kSeed);
  std::normal_distribution<double> N01;
  std::uniform_real_distribution<double> U(0.1, 3.0);
  g_X.resize(kN, kP);
  Eigen::VectorXd z(kP);
  for (long i = 0; i < kN; ++i) {
    double prev = 0.0;
    for (long j = 0; j < kP; ++j) g_X(i, j) = prev = 0.7 * prev + N01(rng);
  }
  for (long j = 0; j < kP; ++j) g_X.col(j) = g_X.col(j) * U(rng) + Eigen::VectorXd::Constant(kN, U(rng) - 1.5);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(kP);
  for (int k = 0; k < 20; ++k) b((k * 37 + 5) % kP) = (k % 2 ? 1.0 : -1.0) * (0.05 + 0.1 * (k % 7));
  g_y = g_X * b;
  for (long i = 0; i < kN; ++i) g_y(i) += 1.0 + 0.5 * N01(rng);
  g_foldid = twinwatch::ident::lasso_folds(kN, kFolds, kSeed);
}

template <class T>
void write_bin(const std::string& path, const T* p, size_t count) {
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(p), static_cast<std::streamsize>(count * sizeof(T)));
  if (!f) throw std::runtime_error("cannot write " + path);
}
template <class T>
void read_bin(const std::string& path, T* p, size_t count) {
  std::ifstream f(path, std::ios::binary);
  f.read(reinterpret_cast<char*>(p), static_cast<std::streamsize>(count * sizeof(T)));
  if (!f) throw std::runtime_error("cannot read " + path + " (run with --write-data first)");
}

void load_data() {
  g_X.resize(kN, kP);
  g_y.resize(kN);
  g_foldid.resize(kN);
  read_bin(g_data + "/X.f64", g_X.data(), static_cast<size_t>(kN * kP));
  read_bin(g_data + "/y.f64", g_y.data(), static_cast<size_t>(kN));
  read_bin(g_data + "/foldid.i32", g_foldid.data(), static_cast<size_t>(kN));
}

twinwatch::ident::LassoCvResult run(LassoAlgorithm alg) {
  twinwatch::ident::LassoOptions o;  // nlambda 100, eps 1e-4 (n > p), tol 1e-7: glmnet's defaults
  o.algorithm = alg;
  twinwatch::ident::LassoCvOptions cv;
  cv.foldid = g_foldid;
  return twinwatch::ident::cv_lasso(g_X, g_y, o, cv);
}

void BM_CvLasso_Covariance(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(run(LassoAlgorithm::Covariance).lambda_min);
}
BENCHMARK(BM_CvLasso_Covariance)->Unit(benchmark::kMillisecond)->MinTime(2.0)->UseRealTime();

void BM_CvLasso_NaiveBaseline(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(run(LassoAlgorithm::Naive).lambda_min);
}
BENCHMARK(BM_CvLasso_NaiveBaseline)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  std::vector<char*> rest{argv[0]};
  std::string write_dir;
  for (int i = 1; i < argc; ++i) {
    if (!std::strncmp(argv[i], "--write-data=", 13)) write_dir = argv[i] + 13;
    else if (!std::strncmp(argv[i], "--data=", 7)) g_data = argv[i] + 7;
    else if (!std::strncmp(argv[i], "--result=", 9)) g_result = argv[i] + 9;
    else rest.push_back(argv[i]);
  }
  if (!write_dir.empty()) {
    make_data();
    write_bin(write_dir + "/X.f64", g_X.data(), static_cast<size_t>(kN * kP));
    write_bin(write_dir + "/y.f64", g_y.data(), static_cast<size_t>(kN));
    write_bin(write_dir + "/foldid.i32", g_foldid.data(), static_cast<size_t>(kN));
    std::ofstream(write_dir + "/meta.txt") << kN << " " << kP << " " << kFolds << "\n";
    std::printf("wrote %ld x %ld design, y and %d folds to %s\n", kN, kP, kFolds, write_dir.c_str());
    return 0;
  }
  if (g_data.empty()) {
    make_data();
  } else {
    load_data();
  }
  if (!g_result.empty()) {
    // our selection, for the agreement check: lambda_min, lambda_1se, coefficients at lambda_min
    const auto r = run(LassoAlgorithm::Covariance);
    std::ofstream f(g_result);
    f.precision(17);
    f << "lambda_min " << r.lambda_min << "\nlambda_1se " << r.lambda_1se << "\nnlambda " << r.path.lambda.size() << "\ncoef";
    f << " " << r.a0;
    for (long j = 0; j < r.beta.size(); ++j) f << " " << r.beta(j);
    f << "\n";
  }
  int ac = static_cast<int>(rest.size());
  benchmark::Initialize(&ac, rest.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
