#include "twinwatch/ident/sequential_ident.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <ctime>
#include <random>

#include "twinwatch/core/error.hpp"
#include "twinwatch/ident/nonnegative_ls.hpp"
#include "twinwatch/model/description_io.hpp"

namespace twinwatch::ident {

namespace {

// target_qd of a held pose is exactly zero; a measured qd at rest is encoder noise
constexpr double kStillTarget = 1e-9;   // [rad/s]
constexpr double kStillMeasured = 5e-3; // [rad/s]
// the approach direction of a hold is the mean velocity over this window before it [s]
constexpr double kApproachWindow = 0.05;
// a gravity regressor column is unused by a joint when its values over all poses stay below this
constexpr double kColumnUnused = 1e-9;
// the Lasso folds are whole blocks of this length [s] (neighbouring samples are correlated, a
// random split would leak them between training and test and pick too small a lambda)
constexpr double kFoldBlock = 1.0;
// random configurations that reveal the independent gravity columns of each joint, the seed of
// their draw, and the relative pivot below which a column counts as dependent
constexpr int kGravityProbes = 200;
constexpr unsigned kGravitySeed = 7;
constexpr double kGravityRank = 1e-9;

std::string now_iso() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

void require_current(const device::Recording& rec, const char* role) {
  if (!(rec.present & kFieldActualCurrent))
    throw InvalidArgument(fmt::format("{} ({} recording): no actual_current_* columns, the current-domain twin needs motor currents",
                                      rec.path, role));
}

const VectorJ& velocity_of(const device::Recording& rec, const RobotSample& s) {
  return (rec.present & kFieldTargetQd) ? s.target_qd : s.qd;
}
const VectorJ& position_of(const device::Recording& rec, const RobotSample& s) {
  return (rec.present & kFieldTargetQ) ? s.target_q : s.q;
}

}  // namespace

void SequentialOptions::validate(int n_dof) const {
  library.validate(n_dof);
  if (!(min_hold > 0.0)) throw InvalidArgument(fmt::format("SequentialOptions.min_hold is {} s, must be > 0", min_hold));
  if (!(pose_tolerance > 0.0)) throw InvalidArgument(fmt::format("SequentialOptions.pose_tolerance is {} rad, must be > 0", pose_tolerance));
  if (!(sine_min_speed >= 0.0)) throw InvalidArgument(fmt::format("SequentialOptions.sine_min_speed is {} rad/s, must be >= 0", sine_min_speed));
  if (!(sine_q_tolerance > 0.0)) throw InvalidArgument(fmt::format("SequentialOptions.sine_q_tolerance is {} rad, must be > 0", sine_q_tolerance));
  if (!(sine_qd_tolerance > 0.0))
    throw InvalidArgument(fmt::format("SequentialOptions.sine_qd_tolerance is {} rad/s, must be > 0", sine_qd_tolerance));
  if (decimate < 1) throw InvalidArgument(fmt::format("SequentialOptions.decimate is {}, must be >= 1", decimate));
  if (nfolds < 2) throw InvalidArgument(fmt::format("SequentialOptions.nfolds is {}, must be >= 2", nfolds));
  if (nlambda < 1) throw InvalidArgument(fmt::format("SequentialOptions.nlambda is {}, must be >= 1", nlambda));
  if (!(prune_ratio >= 0.0 && prune_ratio < 1.0))
    throw InvalidArgument(fmt::format("SequentialOptions.prune_ratio is {}, must be in [0, 1)", prune_ratio));
}

std::vector<GravitySample> paired_holds(const device::Recording& rec, const SequentialOptions& o) {
  const size_t N = rec.samples.size();
  const bool target = rec.present & kFieldTargetQd;
  const double still = target ? kStillTarget : kStillMeasured;
  auto stationary = [&](size_t k) { return velocity_of(rec, rec.samples[k]).cwiseAbs().maxCoeff() <= still; };
  struct Hold {
    VectorJ q, qt, current, approach;  // measured and commanded (target) pose
  };
  std::vector<Hold> holds;
  // stationary segments of at least min_hold: mean q and current over their second half
  // (the first half lets the controller settle), approach velocity just before them
  size_t k = 0;
  while (k < N) {
    if (!stationary(k)) {
      ++k;
      continue;
    }
    size_t e = k;
    while (e < N && stationary(e)) ++e;
    const double len = rec.samples[e - 1].timestamp - rec.samples[k].timestamp;
    if (len >= o.min_hold && k > 0) {
      Hold h;
      const size_t a = k + (e - k) / 2;
      h.q = h.qt = VectorJ::Zero(rec.n_dof);
      h.current = VectorJ::Zero(rec.n_dof);
      for (size_t m = a; m < e; ++m) {
        h.q += rec.samples[m].q;
        h.qt += position_of(rec, rec.samples[m]);
        h.current += rec.samples[m].current;
      }
      h.q /= static_cast<double>(e - a);
      h.qt /= static_cast<double>(e - a);
      h.current /= static_cast<double>(e - a);
      h.approach = VectorJ::Zero(rec.n_dof);
      const double t0 = rec.samples[k].timestamp;
      for (size_t m = k; m-- > 0 && t0 - rec.samples[m].timestamp <= kApproachWindow;) h.approach += velocity_of(rec, rec.samples[m]);
      holds.push_back(h);
    }
    k = e;
  }
  // consecutive holds at the same pose reached from opposite directions (Cao eq. 12-14):
  // i_1 + i_2 = 2 G(phi) when qd is small and qdd = 0. The pose is compared on the commanded
  // position when recorded: friction holds the measured one a little short of it on each side
  // (about 1.5e-3 rad on the UR3e wrist), which the average cancels too
  std::vector<GravitySample> out;
  for (size_t i = 0; i + 1 < holds.size();) {
    const Hold &a = holds[i], &b = holds[i + 1];
    if ((a.qt - b.qt).cwiseAbs().maxCoeff() < o.pose_tolerance && a.approach.dot(b.approach) < 0.0) {
      out.push_back({(a.q + b.q) / 2, (a.current + b.current) / 2});
      i += 2;
    } else {
      ++i;
    }
  }
  return out;
}

std::vector<std::pair<double, double>> sine_pairs(const device::Recording& rec, int j, const SequentialOptions& o) {
  const long N = static_cast<long>(rec.samples.size());
  std::vector<long> turns;
  for (long k = 1; k < N; ++k) {
    const double a = velocity_of(rec, rec.samples[static_cast<size_t>(k - 1)])[j], b = velocity_of(rec, rec.samples[static_cast<size_t>(k)])[j];
    if ((a > 0 && b <= 0) || (a < 0 && b >= 0)) turns.push_back(k);
  }
  std::vector<std::pair<double, double>> out;
  for (size_t t = 0; t < turns.size(); ++t) {
    const long k0 = turns[t];
    const long lo = t > 0 ? turns[t - 1] : 0, hi = t + 1 < turns.size() ? turns[t + 1] : N;
    // mirrored samples about the turning point: same q and qdd, opposite qd (Cao eq. 12, 15)
    for (long m = 0; k0 - 1 - m > lo && k0 + m < hi; ++m) {
      const RobotSample& a = rec.samples[static_cast<size_t>(k0 - 1 - m)];
      const RobotSample& b = rec.samples[static_cast<size_t>(k0 + m)];
      const VectorJ& va = velocity_of(rec, a);
      const VectorJ& vb = velocity_of(rec, b);
      if (std::abs(va[j]) < o.sine_min_speed) continue;
      if ((position_of(rec, a) - position_of(rec, b)).cwiseAbs().maxCoeff() > o.sine_q_tolerance) continue;
      const VectorJ tol = (o.sine_qd_tolerance + 0.02 * va.cwiseAbs().array()).matrix();
      if (((va + vb).cwiseAbs() - tol).maxCoeff() > 0.0) continue;
      out.emplace_back((a.qd[j] - b.qd[j]) / 2, (a.current[j] - b.current[j]) / 2);
    }
  }
  return out;
}

SineFriction fit_sine_friction(const std::vector<std::pair<double, double>>& pairs) {
  const auto N = static_cast<Eigen::Index>(pairs.size());
  Eigen::MatrixXd A(N, 2);
  Eigen::VectorXd b(N);
  for (Eigen::Index k = 0; k < N; ++k) {
    const auto& [qd, di] = pairs[static_cast<size_t>(k)];
    A(k, 0) = qd > 0 ? 1.0 : (qd < 0 ? -1.0 : 0.0);
    A(k, 1) = qd;
    b(k) = di;
  }
  SineFriction f;
  if (N == 0) return f;
  // with mirrored pairs the free fit is consistent on a healthy joint, but a sine too slow or too
  // short to separate the two columns can give them opposite signs, and the twin would then
  // predict friction that drives the joint at some speeds
  f.orientation = A.col(0).dot(b) >= 0.0 ? 1.0 : -1.0;
  const Eigen::VectorXd x = f.orientation * nonnegative_ls(f.orientation * A, b);
  const Eigen::Vector2d free = A.colPivHouseholderQr().solve(b);
  f.coulomb = x(0);
  f.viscous = x(1);
  f.free_coulomb = free(0);
  f.free_viscous = free(1);
  f.coulomb_held = f.orientation * free(0) < 0.0 && x(0) == 0.0;
  f.viscous_held = f.orientation * free(1) < 0.0 && x(1) == 0.0;
  f.rmse = std::sqrt((A * x - b).squaredNorm() / static_cast<double>(N));
  return f;
}

TwinModel identify_sequential(const std::string& robot, const std::vector<const device::Recording*>& quasi_static,
                              const std::vector<const device::Recording*>& sine, const std::vector<TrainingRun>& general,
                              const SequentialOptions& o, SequentialReport& report, const std::function<void(double)>& progress) {
  const model::RobotModel rm = model::load_robot(robot);
  const int n = rm.n_dof();
  o.validate(n);
  if (quasi_static.empty())
    throw InvalidArgument("sequential identification needs a quasi-static recording (bidirectional poses, Cao eq. 13-14): --quasi-static FILE");
  if (sine.empty()) throw InvalidArgument("sequential identification needs a sine recording (symmetric motion, Cao eq. 15): --sine FILE");
  if (general.empty())
    throw InvalidArgument("sequential identification needs at least one general recording for the Lasso stage (Cao eq. 20)");
  auto check_joints = [&](const device::Recording& r, const char* role) {
    if (r.n_dof != n) throw InvalidArgument(fmt::format("{} ({} recording): {} joints, but robot '{}' has {}", r.path, role, r.n_dof, robot, n));
    require_current(r, role);
  };
  for (const auto* r : quasi_static) check_joints(*r, "quasi-static");
  for (const auto* r : sine) check_joints(*r, "sine");
  for (const auto& r : general) check_joints(*r.recording, "general");

  report = SequentialReport{};
  TwinModel twin(robot, rm);
  twin.method = "sequential";
  twin.created = now_iso();
  SequentialModel seq;
  seq.library = o.library;
  // (a recording cut into its driven stretches is named once)
  const auto once = [](std::vector<std::string>& v, const std::string& p) {
    if (std::find(v.begin(), v.end(), p) == v.end()) v.push_back(p);
  };
  for (const auto* r : quasi_static) once(seq.quasi_static, r->path), once(twin.recordings, r->path);
  for (const auto* r : sine) once(seq.sine, r->path), once(twin.recordings, r->path);
  for (const auto& r : general) once(seq.general, r.recording->path), once(twin.recordings, r.recording->path);
  for (const auto* r : quasi_static) for (const RobotSample& s : r->samples) twin.envelope.include(s.q, s.qd);
  for (const auto* r : sine) for (const RobotSample& s : r->samples) twin.envelope.include(s.q, s.qd);
  for (const auto& r : general) for (const RobotSample& s : r.recording->samples) twin.envelope.include(s.q, s.qd);
  seq.joints.assign(static_cast<size_t>(n), SequentialJoint{});
  twin.joints.assign(static_cast<size_t>(n), JointDrive{});
  const VectorJ zero = VectorJ::Zero(n);
  model::RegressorMatrix Y;
  VectorJ tau_p;

  // 1. gravity from paired quasi-static holds, per joint least squares on the base columns of
  //    the gravity regressor (min-norm where a joint's columns are dependent)
  std::vector<GravitySample> gs;
  for (const auto* r : quasi_static) {
    const auto s = paired_holds(*r, o);
    if (s.empty())
      throw InvalidArgument(fmt::format("{} (quasi-static recording): no pose held for >= {} s and reached from both directions "
                                        "(expected pairs of holds at the same pose, approached from below and from above)",
                                        r->path, o.min_hold));
    gs.insert(gs.end(), s.begin(), s.end());
  }
  report.poses = static_cast<int>(gs.size());
  // per joint, a minimal set of gravity columns: the independent columns of row j of
  // Yg = Y(q, 0, 0) over random configurations of the robot description (column-pivoted QR);
  // the full-dynamics base set would leave more unknowns than poses and fit noise
  std::vector<std::vector<int>> joint_cols(static_cast<size_t>(n));
  {
    std::mt19937 rng(kGravitySeed);
    std::uniform_real_distribution<double> U(-M_PI, M_PI);
    std::vector<Eigen::MatrixXd> rows(static_cast<size_t>(n), Eigen::MatrixXd(kGravityProbes, 10 * n));
    VectorJ q(n);
    for (int r = 0; r < kGravityProbes; ++r) {
      for (int j = 0; j < n; ++j) q[j] = U(rng);
      twin.regress(q, zero, zero, Y, tau_p);
      for (int j = 0; j < n; ++j) rows[static_cast<size_t>(j)].row(r) = Y.row(j).head(10 * n);
    }
    std::vector<int> all;
    for (int j = 0; j < n; ++j) {
      Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(rows[static_cast<size_t>(j)]);
      qr.setThreshold(kGravityRank);
      for (Eigen::Index k = 0; k < qr.rank(); ++k) joint_cols[static_cast<size_t>(j)].push_back(qr.colsPermutation().indices()(k));
      all.insert(all.end(), joint_cols[static_cast<size_t>(j)].begin(), joint_cols[static_cast<size_t>(j)].end());
    }
    std::sort(all.begin(), all.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());
    seq.gravity_columns = all;
  }
  const int ng = static_cast<int>(seq.gravity_columns.size());
  Eigen::MatrixXd G(static_cast<long>(gs.size()) * n, ng);
  for (size_t s = 0; s < gs.size(); ++s) {
    twin.regress(gs[s].q, zero, zero, Y, tau_p);
    for (int j = 0; j < n; ++j)
      for (int c = 0; c < ng; ++c) G(static_cast<long>(s) * n + j, c) = Y(j, seq.gravity_columns[static_cast<size_t>(c)]);
  }
  report.gravity_rmse.assign(static_cast<size_t>(n), 0.0);
  for (int j = 0; j < n; ++j) {
    Eigen::MatrixXd Gj(static_cast<long>(gs.size()), ng);
    Eigen::VectorXd ij(static_cast<long>(gs.size()));
    for (size_t s = 0; s < gs.size(); ++s) {
      Gj.row(static_cast<long>(s)) = G.row(static_cast<long>(s) * n + j);
      ij(static_cast<long>(s)) = gs[s].current[j];
    }
    std::vector<int> used;
    for (int c = 0; c < ng; ++c) {
      const auto& jc = joint_cols[static_cast<size_t>(j)];
      if (std::find(jc.begin(), jc.end(), seq.gravity_columns[static_cast<size_t>(c)]) != jc.end() &&
          Gj.col(c).cwiseAbs().maxCoeff() > kColumnUnused)
        used.push_back(c);
    }
    if (static_cast<long>(used.size()) > Gj.rows())
      report.notes.push_back(fmt::format("joint {}: {} gravity columns but only {} quasi-static poses: min-norm fit", j + 1, used.size(), Gj.rows()));
    Eigen::VectorXd th = Eigen::VectorXd::Zero(ng);
    if (!used.empty()) {
      Eigen::MatrixXd A(Gj.rows(), static_cast<long>(used.size()));
      for (size_t u = 0; u < used.size(); ++u) A.col(static_cast<long>(u)) = Gj.col(used[u]);
      // column scaling before the rank-revealing solve
      const Eigen::VectorXd sc = A.colwise().norm().transpose();
      const Eigen::MatrixXd As = A * sc.cwiseInverse().asDiagonal();
      const Eigen::VectorXd x = As.completeOrthogonalDecomposition().solve(ij);
      for (size_t u = 0; u < used.size(); ++u) th(used[u]) = x(static_cast<long>(u)) / sc(static_cast<long>(u));
    }
    seq.joints[static_cast<size_t>(j)].gravity = th;
    report.gravity_rmse[static_cast<size_t>(j)] = std::sqrt((Gj * th - ij).squaredNorm() / static_cast<double>(gs.size()));
  }
  if (progress) progress(0.05);

  // 2. friction from mirrored sine samples, per joint: (i1 - i2) / 2 = Fc sign(qd) + Fv qd
  report.friction_pairs.assign(static_cast<size_t>(n), 0);
  report.friction_rmse.assign(static_cast<size_t>(n), 0.0);
  for (int j = 0; j < n; ++j) {
    std::vector<std::pair<double, double>> pr;
    for (const auto* r : sine) {
      const auto s = sine_pairs(*r, j, o);
      pr.insert(pr.end(), s.begin(), s.end());
    }
    bool both = false;
    for (const auto& p : pr) both |= p.first * pr.front().first < 0;
    if (pr.size() < 10 || !both)
      throw InvalidArgument(fmt::format("{} (sine recording): {} mirrored sample pairs for joint {} (at least 10 in both directions "
                                        "expected): every joint must follow a sine with common turning points, faster than {} rad/s",
                                        sine.front()->path, pr.size(), j + 1, o.sine_min_speed));
    const SineFriction f = fit_sine_friction(pr);
    const char* const unit[2] = {"A", "A·s/rad"};
    const char* const name[2] = {"Coulomb", "viscous"};
    const bool held[2] = {f.coulomb_held, f.viscous_held};
    const double free[2] = {f.free_coulomb, f.free_viscous};
    for (int c = 0; c < 2; ++c) {
      if (held[c])
        report.notes.push_back(fmt::format("J{}: {} friction held at 0 (the sine pairs alone give {:.4g} {}, against the sign of the "
                                           "joint's friction as a whole): record a sine with a wider speed range on this joint",
                                           j + 1, name[c], free[c], unit[c]));
    }
    if (f.orientation < 0.0)
      report.notes.push_back(fmt::format("J{}: the friction current has the opposite sign of the velocity (Coulomb {:.4g} A): the "
                                         "current channel counts the other way, or the recording is not the joint's",
                                         j + 1, f.coulomb));
    seq.joints[static_cast<size_t>(j)].coulomb = f.coulomb;
    seq.joints[static_cast<size_t>(j)].viscous = f.viscous;
    report.friction_pairs[static_cast<size_t>(j)] = static_cast<long>(pr.size());
    report.friction_rmse[static_cast<size_t>(j)] = f.rmse;
  }
  if (progress) progress(0.1);

  // 3. remaining current over the general recordings: y_j = i_j - gravity_j - friction_j, Lasso on
  //    the candidates A ⊗ B (+ the known payload's torque, unpenalised, when a run carried one)
  bool any_payload = false;
  for (const auto& r : general) any_payload |= r.payload.mass > 0.0;
  const int pc = o.library.size(n);
  const int p = pc + (any_payload ? 1 : 0);
  long N = 0;
  for (const auto& r : general) N += (static_cast<long>(r.recording->samples.size()) + o.decimate - 1) / o.decimate;
  if (N < 10L * o.nfolds)
    throw InvalidArgument(fmt::format("sequential identification: {} samples in the general recordings, expected at least {}", N, 10 * o.nfolds));
  Eigen::MatrixXd X(N, p);
  Eigen::MatrixXd Yr(N, n), I(N, n), Base(N, n), TauP;
  if (any_payload) TauP.setZero(N, n);
  std::vector<long> block(static_cast<size_t>(N));
  Eigen::VectorXd grow(pc);
  long row = 0, block_base = 0;
  for (const auto& r : general) {
    const device::Recording& rec = *r.recording;
    const auto qdd = joint_accelerations(rec);
    const double t0 = rec.samples.empty() ? 0.0 : rec.samples.front().timestamp;
    long last_block = 0;
    for (size_t k = 0; k < rec.samples.size(); k += static_cast<size_t>(o.decimate), ++row) {
      const RobotSample& s = rec.samples[k];
      seq.library.row(s.q, s.qd, qdd[k], grow);
      X.row(row).head(pc) = grow.transpose();
      twin.set_payload({});
      twin.regress(s.q, zero, zero, Y, tau_p);
      VectorJ i0(n);
      for (int j = 0; j < n; ++j) {
        const SequentialJoint& m = seq.joints[static_cast<size_t>(j)];
        double g = 0.0;
        for (int c = 0; c < ng; ++c) g += Y(j, seq.gravity_columns[static_cast<size_t>(c)]) * m.gravity(c);
        i0[j] = g + m.coulomb * (s.qd[j] > 0 ? 1.0 : (s.qd[j] < 0 ? -1.0 : 0.0)) + m.viscous * s.qd[j];
      }
      if (any_payload) {
        twin.set_payload(r.payload);
        twin.regress(s.q, s.qd, qdd[k], Y, tau_p);
        TauP.row(row) = tau_p.transpose();
      }
      for (int j = 0; j < n; ++j) {
        I(row, j) = s.current[j];
        Base(row, j) = i0[j];
        Yr(row, j) = s.current[j] - i0[j];
      }
      last_block = static_cast<long>((s.timestamp - t0) / kFoldBlock);
      block[static_cast<size_t>(row)] = block_base + last_block;
    }
    block_base += last_block + 1;
  }
  twin.set_payload({});
  if (progress) progress(0.3);
  // folds of whole blocks, blocks assigned to folds by a seeded shuffle
  if (block_base < o.nfolds)
    throw InvalidArgument(fmt::format("sequential identification: the general recordings span {} s, expected at least {} s for {} folds of "
                                      "{} s blocks", block_base * kFoldBlock, o.nfolds * kFoldBlock, o.nfolds, kFoldBlock));
  const std::vector<int> block_fold = lasso_folds(block_base, o.nfolds, o.seed);
  LassoCvOptions cv;
  cv.foldid.resize(static_cast<size_t>(N));
  for (long r = 0; r < N; ++r) cv.foldid[static_cast<size_t>(r)] = block_fold[static_cast<size_t>(block[static_cast<size_t>(r)])];
  cv.prune_ratio = o.prune_ratio;
  cv.use_1se = o.use_1se;
  LassoOptions lo;
  lo.nlambda = o.nlambda;
  lo.algorithm = LassoAlgorithm::Covariance;  // p in the hundreds, n in the tens of thousands
  std::vector<LassoCvResult> fits;
  if (any_payload) {
    // joint j's own payload torque as one unpenalised column (its coefficient is 1 / gain_j):
    // the design differs per joint, so one Lasso per joint (the payload torques of all joints
    // together are too collinear along one payload run to be told apart)
    lo.penalty_factor = Eigen::VectorXd::Ones(p);
    lo.penalty_factor(pc) = 0.0;
    for (int j = 0; j < n; ++j) {
      X.col(pc) = TauP.col(j);
      fits.push_back(cv_lasso(X, Yr.col(j), lo, cv));
      if (progress) progress(0.3 + 0.65 * (j + 1) / n);
    }
  } else {
    fits = cv_lasso_multi(X, Yr, lo, cv);
  }
  if (progress) progress(0.95);

  report.lasso_samples = N;
  report.candidates = pc;
  report.nonzero.assign(static_cast<size_t>(n), 0);
  report.rmse.assign(static_cast<size_t>(n), 0.0);
  report.r2.assign(static_cast<size_t>(n), 0.0);
  report.cv_rmse.assign(static_cast<size_t>(n), 0.0);
  for (int j = 0; j < n; ++j) {
    const LassoCvResult& f = fits[static_cast<size_t>(j)];
    SequentialJoint& m = seq.joints[static_cast<size_t>(j)];
    m.intercept = f.a0;
    for (int k = 0; k < pc; ++k)
      if (f.beta(k) != 0.0) m.lasso_index.push_back(k), m.lasso_value.push_back(f.beta(k));
    if (any_payload) {
      m.payload = Eigen::VectorXd::Zero(n);
      m.payload(j) = f.beta(pc);
    }
    const int pick = o.use_1se ? f.index_1se : f.index_min;
    m.lambda = f.path.lambda(pick);
    m.cv_rmse = std::sqrt(f.cvm(pick));
    if (!f.path.converged) report.notes.push_back(fmt::format("joint {}: {}", j + 1, f.path.message));
    // full-model fit on the general recordings
    if (any_payload) X.col(pc) = TauP.col(j);
    const Eigen::VectorXd pred = Base.col(j) + f.predict(X);
    const double sse = (pred - I.col(j)).squaredNorm();
    const double sst = (I.col(j).array() - I.col(j).mean()).square().sum();
    m.rmse = std::sqrt(sse / static_cast<double>(N));
    m.r2 = sst > 0 ? 1.0 - sse / sst : 0.0;
    report.nonzero[static_cast<size_t>(j)] = static_cast<int>(m.lasso_index.size());
    report.rmse[static_cast<size_t>(j)] = m.rmse;
    report.r2[static_cast<size_t>(j)] = m.r2;
    report.cv_rmse[static_cast<size_t>(j)] = m.cv_rmse;
    twin.joints[static_cast<size_t>(j)].rmse = m.rmse;
    twin.joints[static_cast<size_t>(j)].r2 = m.r2;
  }
  twin.sequential = std::move(seq);
  report.notes.push_back("sequential twin: current domain with per-joint coefficients, no current-to-torque gains identified "
                         "(torque outputs are in amperes)");
  if (progress) progress(1.0);
  return twin;
}

}  // namespace twinwatch::ident
