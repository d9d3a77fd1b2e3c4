#include "twinwatch/ident/sequential_model.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>

#include "twinwatch/core/error.hpp"

namespace twinwatch::ident {

namespace {
// bounds that keep a candidate row on the stack and the design matrix within memory
constexpr int kMaxHarmonics = 10;
constexpr int kMaxCandidates = 20000;
}  // namespace

void CandidateLibrary::validate(int n_dof) const {
  auto check = [&](const std::vector<int>& v, const char* field) {
    for (size_t i = 0; i < v.size(); ++i) {
      if (v[i] < 0 || v[i] >= n_dof)
        throw InvalidArgument(fmt::format("CandidateLibrary.{}[{}] is joint {}, must be in 1..{}", field, i, v[i] + 1, n_dof));
      for (size_t k = 0; k < i; ++k)
        if (v[k] == v[i]) throw InvalidArgument(fmt::format("CandidateLibrary.{}: joint {} appears twice", field, v[i] + 1));
    }
  };
  check(motion_joints, "motion_joints");
  check(config_joints, "config_joints");
  if (harmonics < 1 || harmonics > kMaxHarmonics)
    throw InvalidArgument(fmt::format("CandidateLibrary.harmonics is {}, must be in 1..{}", harmonics, kMaxHarmonics));
  const double sz = static_cast<double>(size_a(n_dof)) * std::pow(2.0 * harmonics + 1.0, static_cast<double>(config_joints.size()));
  if (sz > kMaxCandidates)
    throw InvalidArgument(fmt::format("CandidateLibrary has {} candidates (|A| {} x |B| (2m+1)^{}), at most {} are supported: "
                                      "use fewer configuration joints or harmonics",
                                      sz, size_a(n_dof), config_joints.size(), kMaxCandidates));
}

int CandidateLibrary::size_a(int n_dof) const {
  const int k = motion_joints.empty() ? n_dof : static_cast<int>(motion_joints.size());
  return k + k * (k + 1) / 2;  // (n^2 + 3n) / 2 of Cao eq. 17
}

int CandidateLibrary::size_b() const {
  int s = 1;
  for (size_t i = 0; i < config_joints.size(); ++i) s *= 2 * harmonics + 1;
  return s;
}

void CandidateLibrary::row(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, Eigen::Ref<Eigen::VectorXd> g) const {
  const int n = static_cast<int>(q.size());
  const int na = size_a(n), sb = size_b(), nw = 2 * harmonics + 1;
  assert(g.size() == na * sb);
  // A = [qdd_i ; qd_i qd_k (i <= k)] over the motion joints
  std::array<double, kMaxDof + kMaxDof * (kMaxDof + 1) / 2> A{};
  const int k = motion_joints.empty() ? n : static_cast<int>(motion_joints.size());
  auto joint = [&](int i) { return motion_joints.empty() ? i : motion_joints[static_cast<size_t>(i)]; };
  int a = 0;
  for (int i = 0; i < k; ++i) A[static_cast<size_t>(a++)] = qdd[joint(i)];
  for (int i = 0; i < k; ++i)
    for (int m = i; m < k; ++m) A[static_cast<size_t>(a++)] = qd[joint(i)] * qd[joint(m)];
  // w(q_c) = [1, sin q, cos q, ..., sin m q, cos m q] per configuration joint
  std::array<double, kMaxDof * (2 * kMaxHarmonics + 1)> w{};
  for (size_t c = 0; c < config_joints.size(); ++c) {
    const double x = q[config_joints[c]];
    double* wc = &w[c * static_cast<size_t>(nw)];
    wc[0] = 1.0;
    for (int h = 1; h <= harmonics; ++h) {
      wc[2 * h - 1] = std::sin(h * x);
      wc[2 * h] = std::cos(h * x);
    }
  }
  // B = w(q_c1) ⊗ w(q_c2) ⊗ ... (last joint varies fastest), written into the last block of g
  auto B = g.tail(sb);
  for (int b = 0; b < sb; ++b) {
    double v = 1.0;
    int rest = b;
    for (int c = static_cast<int>(config_joints.size()) - 1; c >= 0; --c) {
      v *= w[static_cast<size_t>(c * nw + rest % nw)];
      rest /= nw;
    }
    B(b) = v;
  }
  // g = A ⊗ B
  for (int i = 0; i < na - 1; ++i) g.segment(i * sb, sb) = A[static_cast<size_t>(i)] * B;
  B *= A[static_cast<size_t>(na - 1)];
}

std::string CandidateLibrary::name(int n_dof, int idx) const {
  const int sb = size_b(), nw = 2 * harmonics + 1;
  const int k = motion_joints.empty() ? n_dof : static_cast<int>(motion_joints.size());
  auto joint = [&](int i) { return 1 + (motion_joints.empty() ? i : motion_joints[static_cast<size_t>(i)]); };
  int a = idx / sb, b = idx % sb;
  std::string s;
  if (a < k) {
    s = fmt::format("qdd{}", joint(a));
  } else {
    a -= k;
    for (int i = 0; i < k; ++i)
      for (int m = i; m < k; ++m)
        if (a-- == 0) s = fmt::format("qd{}*qd{}", joint(i), joint(m));
  }
  std::vector<std::string> parts(config_joints.size());
  for (int c = static_cast<int>(config_joints.size()) - 1; c >= 0; --c) {
    const int d = b % nw;
    b /= nw;
    const int h = (d + 1) / 2, jn = config_joints[static_cast<size_t>(c)] + 1;
    if (d == 0) continue;
    const std::string arg = h == 1 ? fmt::format("q{}", jn) : fmt::format("{}q{}", h, jn);
    parts[static_cast<size_t>(c)] = fmt::format("{}({})", d % 2 ? "sin" : "cos", arg);
  }
  for (const auto& p : parts)
    if (!p.empty()) s += "*" + p;
  return s;
}

void SequentialModel::predict(const VectorJ& q, const VectorJ& qd, const VectorJ& qdd, const Eigen::Ref<const Eigen::MatrixXd>& Yg,
                              const VectorJ& tau_payload, VectorJ& current) const {
  const int n = static_cast<int>(q.size());
  const int p = library.size(n);
  if (g_.size() != p) g_.resize(p);
  library.row(q, qd, qdd, g_);
  current.resize(n);
  for (int j = 0; j < n; ++j) {
    const SequentialJoint& m = joints[static_cast<size_t>(j)];
    // gravity (eq. 11), friction (eq. 15), remaining torque (eq. 19), payload
    double i = m.intercept;
    for (size_t c = 0; c < gravity_columns.size(); ++c) i += Yg(j, gravity_columns[c]) * m.gravity(static_cast<Eigen::Index>(c));
    i += m.coulomb * (qd[j] > 0 ? 1.0 : (qd[j] < 0 ? -1.0 : 0.0)) + m.viscous * qd[j];
    for (size_t k = 0; k < m.lasso_index.size(); ++k) i += m.lasso_value[k] * g_(m.lasso_index[k]);
    for (Eigen::Index l = 0; l < m.payload.size(); ++l) i += m.payload(l) * tau_payload[l];
    current[j] = i;
  }
}

}  // namespace twinwatch::ident
