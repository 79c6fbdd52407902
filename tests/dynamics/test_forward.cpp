// SPDX-License-Identifier: BSD-3-Clause
// forward_dynamics: closed-form cases, cross-checks against independent methods (KKT, textbook
// formula), the properties of the fundamental equation, redundancy and rank changes.
#include <cmath>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <ukdyn/reference/reference.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/random_problem.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using testing::make_system;
using testing::null_space;
using testing::random_problem;
using testing::rel_diff;

constexpr double kG = 9.81;

using testing::vec;

// a particle of mass m in d dimensions under gravity −g along the last axis
SystemBuilder particle(Index d, double m) {
  std::vector<std::string> names = {"x", "y", "z"};
  names.resize(std::size_t(d));
  SystemBuilder b(names);
  b.mass_matrix(m * MatrixXd::Identity(d, d))
      .forces([m, d](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) {
        Q.setZero();
        Q[d - 1] = -m * kG;
      });
  return b;
}

// ---------------------------------------------------------------------------------------------
// closed form

TEST(ClosedForm, PendulumRodTension) {
  const double m = 2.0, L = 1.5;
  const System sys = particle(2, m)
                         .add(holonomic("rod", 1,
                                        [L](const auto& q, const auto&, auto& phi) {
                                          phi[0] = q[0] * q[0] + q[1] * q[1] - L * L;
                                        }))
                         .build();
  Workspace ws(sys);
  for (double theta : {-2.5, -0.4, 0.0, 0.9, 1.57, 3.0}) {
    for (double w : {0.0, 0.8, -2.3}) {
      const VectorXd q = vec({L * std::sin(theta), -L * std::cos(theta)});
      const VectorXd qd = vec({L * std::cos(theta) * w, L * std::sin(theta) * w});
      ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
      // tension m (g cos θ + L θ'²), pulling toward the pivot
      const double T = m * (kG * std::cos(theta) + L * w * w);
      EXPECT_NEAR(ws.Qc.dot(-q / L), T, 1e-12 * (1 + std::abs(T))) << theta << " " << w;
      EXPECT_NEAR(ws.Qc.dot(vec({-q[1], q[0]})), 0.0, 1e-12);
      // θ'' = −(g/L) sin θ, and the centripetal acceleration L θ'²
      const double theta_dd = (ws.qdd[0] * std::cos(theta) + ws.qdd[1] * std::sin(theta)) / L;
      EXPECT_NEAR(theta_dd, -kG / L * std::sin(theta), 1e-12);
      EXPECT_NEAR(ws.qdd.dot(-q / L), L * w * w, 1e-12);
      EXPECT_NEAR(ws.lambda[0] * 2 * L, -T, 1e-11 * (1 + std::abs(T)));
    }
  }
}

TEST(ClosedForm, ConicalPendulumTension) {
  const double m = 0.7, L = 1.2;
  const System sys = particle(3, m)
                         .add(holonomic("rod", 1,
                                        [L](const auto& q, const auto&, auto& phi) {
                                          phi[0] = q.squaredNorm() - L * L;
                                        }))
                         .build();
  Workspace ws(sys);
  for (double alpha : {0.2, 0.7, 1.3}) {
    // steady rotation at w² = g / (L cos α) about the vertical
    const double w = std::sqrt(kG / (L * std::cos(alpha))), phi = 0.4, r = L * std::sin(alpha);
    const VectorXd q = vec({r * std::cos(phi), r * std::sin(phi), -L * std::cos(alpha)});
    const VectorXd qd = vec({-w * r * std::sin(phi), w * r * std::cos(phi), 0.0});
    ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
    EXPECT_NEAR(ws.Qc.norm(), m * kG / std::cos(alpha), 1e-12 * m * kG / std::cos(alpha));
    // the acceleration is centripetal, −w² (x, y, 0)
    EXPECT_NEAR(rel_diff(ws.qdd, vec({-w * w * q[0], -w * w * q[1], 0.0})), 0.0, 1e-12);
  }
}

TEST(ClosedForm, BlockSlidingDownInclineWithCoulombFriction) {
  const double m = 3.0, alpha = 0.5, mu = 0.3;
  // the plane y = −x tan α, so down-slope is t = (cos α, −sin α)
  const System sys = particle(2, m)
                         .add(holonomic("plane", 1,
                                        [alpha](const auto& q, const auto&, auto& phi) {
                                          phi[0] = q[1] + q[0] * std::tan(alpha);
                                        }))
                         .add(coulomb_friction({.constraint = "plane", .mu = mu}))
                         .build();
  Workspace ws(sys);
  const VectorXd tangent = vec({std::cos(alpha), -std::sin(alpha)});
  const VectorXd normal = vec({std::sin(alpha), std::cos(alpha)});
  for (double speed : {0.5, 2.0, 10.0}) {
    const VectorXd q = vec({1.0, -std::tan(alpha)}), qd = speed * tangent;
    ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
    // a = g (sin α − μ cos α) down the slope, none across it
    EXPECT_NEAR(ws.qdd.dot(tangent), kG * (std::sin(alpha) - mu * std::cos(alpha)), 1e-12);
    EXPECT_NEAR(ws.qdd.dot(normal), 0.0, 1e-12);
    // N = m g cos α (ideal), friction μ N up the slope (non-ideal)
    EXPECT_NEAR(ws.Qc_ideal.dot(normal), m * kG * std::cos(alpha), 1e-11);
    EXPECT_NEAR(ws.Qc_nonideal.dot(tangent), -mu * m * kG * std::cos(alpha), 1e-11);
    EXPECT_NEAR(ws.Qc_nonideal.dot(normal), 0.0, 1e-11);
    EXPECT_NEAR(ws.shares.col(0).norm(), m * kG * std::cos(alpha), 1e-11);
  }
}

TEST(ClosedForm, BeadOnRotatingWireTransverseForce) {
  // horizontal plane, wire at angle W t: the bead feels 2 m W r' across the wire and
  // r'' = W² r along it
  const double m = 0.5, W = 1.7, t = 0.3, r = 0.8, rd = -0.6;
  const System sys = SystemBuilder({"x", "y"})
                         .mass_matrix(m * MatrixXd::Identity(2, 2))
                         .add(holonomic("wire", 1,
                                        [W](const auto& q, const auto& tt, auto& phi) {
                                          using std::cos;
                                          using std::sin;
                                          phi[0] = -q[0] * sin(W * tt) + q[1] * cos(W * tt);
                                        }))
                         .build();
  Workspace ws(sys);
  const VectorXd u = vec({std::cos(W * t), std::sin(W * t)}), n = vec({-u[1], u[0]});
  const VectorXd q = r * u, qd = rd * u + r * W * n;
  ASSERT_EQ(forward_dynamics(sys, ws, q, qd, t), Status::kOk);
  EXPECT_NEAR(ws.Qc.dot(n), 2 * m * W * rd, 1e-12);
  EXPECT_NEAR(ws.Qc.dot(u), 0.0, 1e-12);
  // radial acceleration r'' − r W² = 0
  EXPECT_NEAR(ws.qdd.dot(u), -r * W * W + W * W * r, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// independent methods

TEST(CrossCheck, AgreesWithKktSolveWhenFullRank) {
  for (auto [n, m] : {std::pair<Index, Index>{3, 1}, {6, 3}, {12, 6}, {30, 20}, {60, 40}}) {
    const auto p = random_problem(n, m, m, 100u + unsigned(n), false);
    const System sys = make_system(p);
    Workspace ws(sys);
    ASSERT_EQ(forward_dynamics(sys, ws, VectorXd::Zero(n), VectorXd::Zero(n), 0.0), Status::kOk);
    KktSolver kkt(n, m);
    VectorXd qdd(n), lambda(m);
    ASSERT_EQ(kkt.solve(p.M, p.Q, p.A, p.b, qdd, lambda), Eigen::Success);
    EXPECT_NEAR(rel_diff(ws.qdd, qdd), 0.0, 1e-12) << n;
    EXPECT_NEAR(rel_diff(ws.lambda, lambda), 0.0, 1e-12) << n;
    EXPECT_NEAR(rel_diff(ws.Qc_ideal, p.A.transpose() * lambda), 0.0, 1e-12) << n;
    EXPECT_EQ(ws.rank, m);
  }
}

using testing::Case;
class DefaultVsTextbook : public ::testing::TestWithParam<Case> {};

TEST_P(DefaultVsTextbook, AgreeOnRandomSystems) {
  const auto [n, m, r] = GetParam();
  const auto p = random_problem(n, m, r, 200u + unsigned(n + 7 * m + r), true);
  const System sys = make_system(p);
  Workspace fast(sys), slow(sys, SolverOptions{.algorithm = Algorithm::kTextbook});
  const VectorXd z = VectorXd::Zero(n);
  ASSERT_EQ(forward_dynamics(sys, fast, z, z, 0.0), Status::kOk);
  ASSERT_EQ(forward_dynamics(sys, slow, z, z, 0.0), Status::kOk);
  EXPECT_EQ(fast.rank, r);
  EXPECT_EQ(slow.rank, r);
  EXPECT_NEAR(rel_diff(fast.qdd, slow.qdd), 0.0, 1e-9);
  EXPECT_NEAR(rel_diff(fast.Qc_ideal, slow.Qc_ideal), 0.0, 1e-9);
  EXPECT_NEAR(rel_diff(fast.Qc_nonideal, slow.Qc_nonideal), 0.0, 1e-9);
  EXPECT_NEAR(rel_diff(fast.lambda, slow.lambda), 0.0, 1e-9);
  EXPECT_NEAR(rel_diff(fast.lambda_nonideal, slow.lambda_nonideal), 0.0, 1e-9);
}

// Without constraints the textbook formula is a = M⁻¹ Q: it crashed (Eigen's SVD of the empty
// B = A M^{-1/2}; `ukdyn run --algorithm textbook` on an oscillator).
TEST(DefaultVsTextbook, NoConstraintsIsMInverseQ) {
  SystemBuilder b({"x", "y"});
  Eigen::Matrix2d M;
  M << 2.0, 0.5, 0.5, 1.0;
  b.mass_matrix(M).forces([](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>&,
                             double, Eigen::Ref<VectorXd> Q) { Q << -3.0 * q[0], 1.0; });
  const System sys = b.build();
  Workspace slow(sys, SolverOptions{.algorithm = Algorithm::kTextbook});
  const VectorXd q = (VectorXd(2) << 1.0, 0.0).finished(), qd = VectorXd::Zero(2);
  ASSERT_EQ(forward_dynamics(sys, slow, q, qd, 0.0), Status::kOk);
  // [2 0.5; 0.5 1] a = [-3; 1]: M⁻¹ = [1 -0.5; -0.5 2] / 1.75, a = [-2; 2]
  EXPECT_NEAR(slow.qdd[0], (-3.0 * 1.0 - 0.5 * 1.0) / 1.75, 1e-13);
  EXPECT_NEAR(slow.qdd[1], (2.0 * 1.0 + 0.5 * 3.0) / 1.75, 1e-13);
  EXPECT_NEAR(slow.Qc.norm(), 0.0, 1e-15);
  EXPECT_EQ(slow.rank, 0);
}

INSTANTIATE_TEST_SUITE_P(Sizes, DefaultVsTextbook,
                         ::testing::Values(Case{6, 3, 3}, Case{6, 3, 2}, Case{12, 6, 6},
                                           Case{12, 6, 4}, Case{30, 20, 20}, Case{30, 20, 11},
                                           Case{60, 40, 40}, Case{60, 40, 33}, Case{120, 80, 80},
                                           Case{120, 80, 61}, Case{20, 30, 18}),
                         testing::CaseName());

// ---------------------------------------------------------------------------------------------
// properties of the fundamental equation, with non-ideal C

class Properties : public ::testing::TestWithParam<Case> {
 protected:
  void SetUp() override {
    const auto [n, m, r] = GetParam();
    p = random_problem(n, m, r, 300u + unsigned(n * m + r), true);
    sys = std::make_unique<System>(make_system(p));
    ws = std::make_unique<Workspace>(*sys);
    ASSERT_EQ(forward_dynamics(*sys, *ws, VectorXd::Zero(n), VectorXd::Zero(n), 0.0), Status::kOk);
    N = null_space(p.A);
  }
  testing::RandomProblem p;
  std::unique_ptr<System> sys;
  std::unique_ptr<Workspace> ws;
  MatrixXd N;  // null-space basis of A
};

TEST_P(Properties, ConstraintsAreSatisfied) {
  EXPECT_NEAR(rel_diff(p.A * ws->qdd, p.b, 1.0), 0.0, 1e-12);
  EXPECT_NEAR(ws->residuals.constraint, 0.0, 1e-11 * (1 + p.b.norm()));
}

TEST_P(Properties, GaussPrincipleRandomFeasiblePerturbationsNeverLowerTheGaussian) {
  // G(x) = (M x − Q − C)ᵀ M⁻¹ (M x − Q − C); for A v = 0, G(q'' + v) − G(q'') = vᵀ M v >= 0
  const Eigen::LLT<MatrixXd> llt(p.M);
  auto gaussian = [&](const Eigen::Ref<const VectorXd>& x) {
    const VectorXd r = p.M * x - p.Q - p.C;
    return r.dot(llt.solve(r));
  };
  std::mt19937 gen(5);
  const double g0 = gaussian(ws->qdd);
  for (int trial = 0; trial < 20; ++trial) {
    const VectorXd v = N * testing::gaussian(N.cols(), 1, gen) * (trial % 2 ? 1e-3 : 1.0);
    const double dv = v.dot(p.M * v);
    EXPECT_NEAR(gaussian(ws->qdd + v) - g0, dv, 1e-9 * (g0 + dv));
    EXPECT_GE(gaussian(ws->qdd + v), g0);
  }
  EXPECT_NEAR(ws->residuals.gauss, 0.0, 1e-11 * (1 + p.Q.norm() + p.C.norm()));
}

TEST_P(Properties, VirtualWorkOfConstraintForceIsPrescribedByC) {
  // vᵀ Qc = vᵀ C for every v with A v = 0; with no such v (rank A = n), C does no work at all
  // and the non-ideal force vanishes
  if (N.cols() == 0) {
    EXPECT_NEAR(ws->Qc_nonideal.norm(), 0.0, 1e-12 * p.C.norm());
    return;
  }
  const VectorXd lhs = N.transpose() * ws->Qc, rhs = N.transpose() * p.C;
  EXPECT_NEAR(rel_diff(lhs, rhs, 1.0), 0.0, 1e-11);
  EXPECT_NEAR(ws->residuals.virtual_work, 0.0, 1e-11 * (1 + p.C.norm() + ws->Qc.norm()));
}

TEST_P(Properties, IdealAndNonIdealPartsAreMOrthogonal) {
  // u = M⁻¹ Qc_ideal, w = M⁻¹ Qc_nonideal: uᵀ M w = Qc_idealᵀ M⁻¹ Qc_nonideal = 0
  const Eigen::LLT<MatrixXd> llt(p.M);
  const VectorXd u = llt.solve(ws->Qc_ideal), w = llt.solve(ws->Qc_nonideal);
  const double scale = std::sqrt(u.dot(p.M * u) * w.dot(p.M * w));
  EXPECT_NEAR(u.dot(p.M * w), 0.0, 1e-12 * scale);
  // and q'' = a + u + w
  EXPECT_NEAR(rel_diff(ws->qdd, llt.solve(p.Q) + u + w), 0.0, 1e-12);
}

TEST_P(Properties, TotalForceIsCPlusConstraintMultipliers) {
  EXPECT_NEAR(rel_diff(ws->Qc, p.C + p.A.transpose() * (ws->lambda + ws->lambda_nonideal)), 0.0,
              1e-11);
  EXPECT_NEAR(rel_diff(p.M * ws->qdd, p.Q + ws->Qc), 0.0, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Sizes, Properties,
                         ::testing::Values(Case{4, 2, 2}, Case{6, 3, 3}, Case{6, 3, 1},
                                           Case{10, 7, 5}, Case{30, 20, 20}, Case{30, 20, 9},
                                           Case{8, 8, 8}, Case{8, 12, 6}),
                         testing::CaseName());

// ---------------------------------------------------------------------------------------------
// redundancy and rank changes

TEST(Redundancy, DuplicatedAndCombinedRowsLeaveMotionAndForceUnchanged) {
  const Index n = 12, m = 5;
  const auto p = random_problem(n, m, m, 77u, true);
  // A' = [A; A_0; 2 A_1 − 3 A_2; A], b' likewise
  testing::RandomProblem q = p;
  q.A.resize(2 * m + 2, n);
  q.b.resize(2 * m + 2);
  q.A << p.A, p.A.row(0), 2 * p.A.row(1) - 3 * p.A.row(2), p.A;
  q.b << p.b, p.b[0], 2 * p.b[1] - 3 * p.b[2], p.b;
  const System s1 = make_system(p), s2 = make_system(q);
  Workspace w1(s1), w2(s2);
  const VectorXd z = VectorXd::Zero(n);
  ASSERT_EQ(forward_dynamics(s1, w1, z, z, 0.0), Status::kOk);
  ASSERT_EQ(forward_dynamics(s2, w2, z, z, 0.0), Status::kOk);
  EXPECT_EQ(w2.rank, m);
  EXPECT_NEAR(rel_diff(w2.qdd, w1.qdd), 0.0, 1e-12);
  EXPECT_NEAR(rel_diff(w2.Qc, w1.Qc), 0.0, 1e-12);
  EXPECT_NEAR(rel_diff(w2.Qc_ideal, w1.Qc_ideal), 0.0, 1e-12);
  EXPECT_NEAR(rel_diff(w2.Qc_nonideal, w1.Qc_nonideal), 0.0, 1e-12);
  EXPECT_EQ(w2.counters.rank_deficient, 1);
  // the minimum-norm multipliers split a duplicated row's force equally
  EXPECT_NEAR(w2.lambda[3], w2.lambda[m + 2 + 3], 1e-12 * (1 + std::abs(w2.lambda[3])));
}

TEST(Redundancy, RankChangesWithConfiguration) {
  // y = 0 and y = x²: independent except at x = 0, where both normals are (0, 1)
  const System sys =
      particle(2, 1.0)
          .add(holonomic("line", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[1]; }))
          .add(
              holonomic("parabola", 1,
                        [](const auto& q, const auto&, auto& phi) { phi[0] = q[1] - q[0] * q[0]; }))
          .build();
  Workspace ws(sys);
  // at the origin at rest: rank 1, the particle is held against gravity, q'' = 0
  ASSERT_EQ(forward_dynamics(sys, ws, vec({0.0, 0.0}), vec({0.0, 0.0}), 0.0), Status::kOk);
  EXPECT_EQ(ws.rank, 1);
  EXPECT_NEAR(ws.qdd.norm(), 0.0, 1e-13);
  EXPECT_NEAR(ws.Qc[1], kG, 1e-12);
  // shares: each constraint carries half of the weight
  EXPECT_NEAR(ws.lambda[0], ws.lambda[1], 1e-12);
  // moving through the origin is impossible: the constraints are inconsistent there
  EXPECT_EQ(forward_dynamics(sys, ws, vec({0.0, 0.0}), vec({1.0, 0.0}), 0.0),
            Status::kInconsistentConstraints);
  EXPECT_NEAR(ws.residuals.constraint, 2.0 / std::sqrt(2.0), 1e-9);
  // away from the origin the two normals differ: rank 2, the particle is held fixed
  ASSERT_EQ(forward_dynamics(sys, ws, vec({0.5, 0.0}), vec({0.0, 0.0}), 0.0), Status::kOk);
  EXPECT_EQ(ws.rank, 2);
  EXPECT_NEAR(ws.qdd.norm(), 0.0, 1e-14);
  EXPECT_NEAR(ws.Qc[1], kG, 1e-12);
}

TEST(Redundancy, ConstraintActiveOnIntervalOnly) {
  // a particle on the line y = 0 for t in [1, 2] only
  Constraint line =
      holonomic("line", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[1]; });
  line.active_between(1.0, 2.0);
  const System sys = particle(2, 2.0).add(line).build();
  Workspace ws(sys);
  const VectorXd q = vec({0.3, 0.0}), qd = vec({1.0, 0.0});
  for (double t : {0.5, 1.0, 1.5, 2.0, 2.5}) {
    ASSERT_EQ(forward_dynamics(sys, ws, q, qd, t), Status::kOk);
    const bool on = t >= 1.0 && t <= 2.0;
    EXPECT_EQ(ws.rank, on ? 1 : 0) << t;
    EXPECT_EQ(ws.active_rows, on ? 1 : 0) << t;
    EXPECT_NEAR(ws.qdd[1], on ? 0.0 : -kG, 1e-14) << t;
    EXPECT_NEAR(ws.Qc[1], on ? 2.0 * kG : 0.0, 1e-13) << t;
  }
}

// ---------------------------------------------------------------------------------------------
// constant and state-dependent mass matrices give the same answer

TEST(MassMatrix, CallableAndConstantAgree) {
  const auto p = random_problem(7, 3, 3, 9u, true);
  const System s1 = make_system(p);
  SystemBuilder b(7);
  b.mass_matrix(
       [M = p.M](const Eigen::Ref<const VectorXd>&, double, Eigen::Ref<MatrixXd> out) { out = M; })
      .forces([Q = p.Q](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&,
                        double, Eigen::Ref<VectorXd> out) { out = Q; })
      .add(s1.constraint(0));
  b.add(NonIdealForce(
      "C", [C = p.C](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     const IdealForceInfo&, Eigen::Ref<VectorXd> out) { out = C; }));
  const System s2 = b.build();
  EXPECT_TRUE(s1.mass_is_constant());
  EXPECT_FALSE(s2.mass_is_constant());
  Workspace w1(s1), w2(s2);
  const VectorXd z = VectorXd::Zero(7);
  for (int i = 0; i < 3; ++i) {
    ASSERT_EQ(forward_dynamics(s1, w1, z, z, 0.1 * i), Status::kOk);
    ASSERT_EQ(forward_dynamics(s2, w2, z, z, 0.1 * i), Status::kOk);
    EXPECT_NEAR(rel_diff(w1.qdd, w2.qdd), 0.0, 1e-15);
  }
}

// ---------------------------------------------------------------------------------------------
// block-diagonal M and constraints with local columns (the inputs of the sparse engine) give the
// same motion through the dense engine as the same system written densely

// a rod between particles i and j of a planar chain (fixed point (fx, fy) when j < 0):
// phi = (|p_i − p_j|² − L²)/2, A_i = (p_i − p_j)ᵀ, A_j = −A_i, b = −|v_i − v_j|²
class LocalRod final : public ConstraintModel {
 public:
  LocalRod(Index i, Index j, double L) : i_(i), j_(j), L_(L) {
    if (j >= 0) cols_ = {2 * j, 2 * j + 1};
    cols_.insert(cols_.end(), {2 * i, 2 * i + 1});
    if (j > i) std::swap_ranges(cols_.begin(), cols_.begin() + 2, cols_.begin() + 2);
  }
  const std::vector<Index>& columns() const override { return cols_; }
  void acceleration_form_local(const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double, ConstraintScratch*,
                               Eigen::Ref<MatrixXd> A, Eigen::Ref<VectorXd> b) const override {
    const double dx = q[2 * i_] - (j_ >= 0 ? q[2 * j_] : 0.0);
    const double dy = q[2 * i_ + 1] - (j_ >= 0 ? q[2 * j_ + 1] : 0.0);
    const double vx = qd[2 * i_] - (j_ >= 0 ? qd[2 * j_] : 0.0);
    const double vy = qd[2 * i_ + 1] - (j_ >= 0 ? qd[2 * j_ + 1] : 0.0);
    // column order of cols_: the lower particle first
    const Index own = (j_ >= 0 && j_ < i_) ? 2 : 0, other = 2 - own;
    A(0, own) = dx;
    A(0, own + 1) = dy;
    if (j_ >= 0) {
      A(0, other) = -dx;
      A(0, other + 1) = -dy;
    }
    b[0] = -(vx * vx + vy * vy);
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>&, double,
                 ConstraintScratch*, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    const double dx = q[2 * i_] - (j_ >= 0 ? q[2 * j_] : 0.0);
    const double dy = q[2 * i_ + 1] - (j_ >= 0 ? q[2 * j_ + 1] : 0.0);
    position[0] = 0.5 * (dx * dx + dy * dy - L_ * L_);
    velocity[0] = 0.0;
  }

 private:
  Index i_, j_;
  double L_;
  std::vector<Index> cols_;
};

TEST(BlockDiagonalAndLocal, SameMotionAsTheDenseDescription) {
  // three particles of masses 1, 2, 3 hanging in a chain from the origin, the last one also
  // tied back to particle 0 (a closed loop) — and a state-dependent block for particle 1
  const std::vector<double> mass = {1.0, 2.0, 3.0};
  const auto block_fn = [](const Eigen::Ref<const VectorXd>& q, double, Eigen::Ref<MatrixXd> Mk) {
    Mk << 2.0 + q[2] * q[2], 0.5, 0.5, 2.0;
  };
  SystemBuilder blocks(6), dense(6);
  blocks.mass_block(4, 3.0 * MatrixXd::Identity(2, 2))
      .mass_block(2, 2, block_fn)
      .mass_block(0, 1.0 * MatrixXd::Identity(2, 2));
  dense.mass_matrix([&](const Eigen::Ref<const VectorXd>& q, double t, Eigen::Ref<MatrixXd> M) {
    M.setZero();
    M.block(0, 0, 2, 2).setIdentity();
    block_fn(q, t, M.block(2, 2, 2, 2));
    M.block(4, 4, 2, 2) = 3.0 * MatrixXd::Identity(2, 2);
  });
  const auto Q = [&](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> F) {
    F << 0.1, -9.81 * mass[0], 0.0, -9.81 * mass[1], -0.3, -9.81 * mass[2];
  };
  blocks.forces(Q);
  dense.forces(Q);
  const struct { Index i, j; } rods[] = {{0, -1}, {1, 0}, {2, 1}, {0, 2}};
  for (const auto& r : rods) {
    const std::string name = "rod" + std::to_string(r.i) + std::to_string(r.j);
    blocks.add(
        Constraint(name, ConstraintKind::kHolonomic, 1, std::make_shared<LocalRod>(r.i, r.j, 1.0)));
    const Index i = r.i, j = r.j;
    dense.add(holonomic(name, 1, [i, j](const auto& q, const auto&, auto& phi) {
      if (j >= 0) {
        phi[0] = 0.5 * ((q[2 * i] - q[2 * j]) * (q[2 * i] - q[2 * j]) +
                        (q[2 * i + 1] - q[2 * j + 1]) * (q[2 * i + 1] - q[2 * j + 1]) - 1.0);
      } else {
        phi[0] = 0.5 * (q[2 * i] * q[2 * i] + q[2 * i + 1] * q[2 * i + 1] - 1.0);
      }
    }));
  }
  const System a = blocks.build(), b = dense.build();
  EXPECT_TRUE(a.mass_is_block_diagonal());
  EXPECT_FALSE(a.mass_is_constant());
  ASSERT_EQ(a.mass_blocks().size(), 3u);
  EXPECT_EQ(a.mass_blocks()[1].offset, 2);  // sorted by offset
  const VectorXd q = vec({0.3, -0.95, 0.9, -1.6, 0.2, -1.9});
  const VectorXd qd = vec({0.4, -0.2, 1.1, 0.3, -0.5, 0.7});
  // the dense engine on both (it fills the workspace's M, A and b), then kAuto's choice for the
  // blocks (the sparse engine: three blocks, m <= n)
  SolverOptions dense_engine;
  dense_engine.engine = Engine::kDense;
  Workspace wa(a, dense_engine), wb(b, dense_engine), wauto(a);
  ASSERT_EQ(forward_dynamics(a, wa, q, qd, 0.0), Status::kOk);
  ASSERT_EQ(forward_dynamics(b, wb, q, qd, 0.0), Status::kOk);
  ASSERT_EQ(forward_dynamics(a, wauto, q, qd, 0.0), Status::kOk);
  ASSERT_EQ(wa.M.rows(), wb.M.rows());
  EXPECT_NEAR((wa.M - wb.M).norm(), 0.0, 1e-15);
  EXPECT_NEAR((wa.A - wb.A).norm(), 0.0, 1e-14);  // the scatter of the local columns
  EXPECT_NEAR((wa.b - wb.b).norm(), 0.0, 1e-14);
  for (const Workspace* w : {&wa, &wauto}) {
    EXPECT_NEAR((w->qdd - wb.qdd).norm(), 0.0, 1e-12 * wb.qdd.norm());
    EXPECT_NEAR((w->Qc - wb.Qc).norm(), 0.0, 1e-12 * wb.Qc.norm());
  }
}

TEST(BlockDiagonalAndLocal, BuilderRefusesBlocksThatDoNotTileAndBadColumns) {
  const auto error_of = [](const SystemBuilder& b) -> std::string {
    try {
      b.build();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  SystemBuilder gap(4);
  gap.mass_block(0, MatrixXd::Identity(2, 2)).mass_block(3, MatrixXd::Identity(1, 1));
  EXPECT_NE(error_of(gap).find("coordinates 2 to 2 have no mass block"), std::string::npos)
      << error_of(gap);
  SystemBuilder overlap(3);
  overlap.mass_block(0, MatrixXd::Identity(2, 2)).mass_block(1, MatrixXd::Identity(2, 2));
  EXPECT_NE(error_of(overlap).find("overlaps"), std::string::npos);
  SystemBuilder both(2);
  both.mass_block(0, MatrixXd::Identity(2, 2)).mass_matrix(MatrixXd::Identity(2, 2));
  EXPECT_NE(error_of(both).find("not both"), std::string::npos);
  SystemBuilder out_of_range(2);
  out_of_range.mass_matrix(MatrixXd::Identity(2, 2))
      .add(Constraint("rod", ConstraintKind::kHolonomic, 1,
                      std::make_shared<LocalRod>(1, 0, 1.0)));  // columns 0..3 of 2
  EXPECT_NE(error_of(out_of_range).find("constraint 'rod': columns() must be strictly increasing"),
            std::string::npos)
      << error_of(out_of_range);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
