// Per-sample prediction of the network and of a twin with a learned block allocates nothing: the
// monitor calls it 500 times a second (STYLE.md: hot loops allocate nothing). Own executable,
// because it interposes malloc (as tests/model/dynamics_invariants_test.cpp does): every heap
// allocation — operator new, Eigen's aligned_malloc, std containers — is counted while counting.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <random>

#include "twinwatch/ident/mlp.hpp"
#include "twinwatch/ident/twin_model.hpp"
#include "twinwatch/model/description_io.hpp"

#include "malloc_counter.hpp"  // counts heap allocations (one TU per test binary)

namespace twinwatch::ident {
namespace {

TEST(LearnedAllocation, CounterSeesAnAllocation) {
  g_allocations = 0;
  g_counting = true;
  void* probe = std::malloc(16);
  g_counting = false;
  std::free(probe);
  ASSERT_EQ(g_allocations.load(), 1);
}

TEST(LearnedAllocation, NetworkPredictAllocatesNothing) {
  MlpOptions o;
  o.hidden = {15, 8};
  Mlp net(12, 6, o);
  double x[12], y[6];
  for (int i = 0; i < 12; ++i) x[i] = 0.1 * i - 0.4;
  net.predict(x, y);  // warm
  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < 100; ++k) net.predict(x, y);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0);
}

// a hybrid twin (physics + residual network) and an mlp twin, through predict and predict_current
TEST(LearnedAllocation, TwinPredictWithALearnedBlockAllocatesNothing) {
  const model::RobotModel rm = model::load_robot("ur3e");
  TwinModel twin("ur3e", rm);
  const model::BaseParameters base = model::compute_base_parameters(rm);
  twin.base_columns = base.independent;
  twin.beta = Eigen::VectorXd::Constant(base.rank, 0.01);
  twin.joints.assign(6, JointDrive{});
  LearnedModel lm;
  lm.inputs.qdd = lm.inputs.temperature = lm.inputs.friction_shape = true;
  lm.net = Mlp(lm.inputs.count(6), 6, MlpOptions{});
  twin.learned = lm;
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  VectorJ q(6), qd(6), qdd(6), T(6), tau, i;
  for (int j = 0; j < 6; ++j) q[j] = u(rng), qd[j] = u(rng), qdd[j] = u(rng), T[j] = 30 + u(rng);
  for (LearnedRole role : {LearnedRole::Residual, LearnedRole::Current}) {
    twin.learned->role = role;
    twin.predict(q, qd, qdd, T, tau, i);  // warm (syncs the fitted model once)
    g_allocations = 0;
    g_counting = true;
    for (int k = 0; k < 100; ++k) {
      twin.predict(q, qd, qdd, T, tau, i);
      twin.predict_current(q, qd, qdd, T, i);
    }
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0) << (role == LearnedRole::Residual ? "hybrid" : "mlp");
  }
}

}  // namespace
}  // namespace twinwatch::ident
