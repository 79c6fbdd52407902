// SPDX-License-Identifier: BSD-3-Clause
// Exact tracking control (control/control.hpp): closed-form error dynamics on chaotic and
// multibody systems, optimality of the weighted law against random admissible forces, the laws
// against independent methods (KKT with the requirements as constraints, closed-form weighted
// least norm, least squares), the robust term under a 20 % mass error, and the messages users
// meet. (Physical constraints with requirements, spacecraft attitude and gyroscopes:
// test_control_physical.cpp.)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>

#include <ukdyn/control/control.hpp>
#include <ukdyn/reference/reference.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/cartesian_pendulum.hpp"
#include "support/control_runs.hpp"
#include "support/error_dynamics.hpp"
#include "support/random_problem.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using test::cartesian_pendulum;  // (a plant with other coordinates, ControlErrors)
using test::record;
using test::second_order_error;  // e(t) of e'' + 2 zeta omega e' + omega² e = 0
using test::tight;
using testing::null_space;
using testing::rel_diff;
using testing::vec;

constexpr double kG = 9.81;

// sample j of an N × width field
Eigen::Map<const VectorXd> sample(const std::vector<double>& f, Index width, Index j) {
  return {f.data() + j * width, width};
}

// ---------------------------------------------------------------------------------------------
// models

// the chaotic Duffing oscillator m x'' + 0.3 x' − x + x³ = 0.5 cos(1.2 t)
System duffing(double m = 1.0) {
  return SystemBuilder({"x"})
      .mass_matrix(MatrixXd::Constant(1, 1, m))
      .forces([](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                 double t, Eigen::Ref<VectorXd> Q) {
        Q[0] = -0.3 * qd[0] + q[0] - q[0] * q[0] * q[0] + 0.5 * std::cos(1.2 * t);
      })
      .build();
}

// x − sin t
Constraint track_sine() {
  return holonomic("track", 1, [](const auto& q, const auto& t, auto& e) {
    using std::sin;
    e[0] = q[0] - sin(t);
  });
}

// A chain of point masses m_i on rigid massless links L_i from a fixed pivot, in absolute angles
// th_i from the downward vertical. mu_ij = Σ_{k >= max(i,j)} m_k;
//   M_ij = mu_ij L_i L_j cos(th_i − th_j),
//   Q_i  = −Σ_j mu_ij L_i L_j sin(th_i − th_j) th_j'² − g mu_ii L_i sin th_i,
//   V    = −g Σ_i mu_ii L_i cos th_i.
struct Chain {
  std::vector<double> m, L;
  Index n() const { return Index(m.size()); }
  double mu(Index i, Index j) const {
    double s = 0.0;
    for (Index k = std::max(i, j); k < n(); ++k) s += m[std::size_t(k)];
    return s;
  }
  MatrixXd mass(const Eigen::Ref<const VectorXd>& th) const {
    MatrixXd M(n(), n());
    for (Index i = 0; i < n(); ++i) {
      for (Index j = 0; j < n(); ++j) {
        M(i, j) = mu(i, j) * L[std::size_t(i)] * L[std::size_t(j)] * std::cos(th[i] - th[j]);
      }
    }
    return M;
  }
  VectorXd force(const Eigen::Ref<const VectorXd>& th, const Eigen::Ref<const VectorXd>& w) const {
    VectorXd Q(n());
    for (Index i = 0; i < n(); ++i) {
      Q[i] = -kG * mu(i, i) * L[std::size_t(i)] * std::sin(th[i]);
      for (Index j = 0; j < n(); ++j) {
        Q[i] -= mu(i, j) * L[std::size_t(i)] * L[std::size_t(j)] * std::sin(th[i] - th[j]) * w[j] *
                w[j];
      }
    }
    return Q;
  }
};

System chain_system(const Chain& c) {
  std::vector<std::string> names;
  for (Index i = 0; i < c.n(); ++i) names.push_back("th" + std::to_string(i + 1));
  return SystemBuilder(names)
      .mass_matrix([c](const Eigen::Ref<const VectorXd>& q, double, Eigen::Ref<MatrixXd> M) {
        M = c.mass(q);
      })
      .forces([c](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                  Eigen::Ref<VectorXd> Q) { Q = c.force(q, qd); })
      .potential_energy([c](const Eigen::Ref<const VectorXd>& q, double) {
        double V = 0.0;
        for (Index i = 0; i < c.n(); ++i)
          V -= kG * c.mu(i, i) * c.L[std::size_t(i)] * std::cos(q[i]);
        return V;
      })
      .build();
}

const Chain kTriple{{1.0, 0.8, 0.6}, {1.0, 0.9, 0.8}};

// desired joint angle of joint i: 0.4 sin((i+1) t / 2) + 0.1 i
template <class S>
S joint_path(Index i, const S& t) {
  using std::sin;
  return 0.4 * sin(double(i + 1) * t / 2.0) + 0.1 * double(i);
}

// the tip path of the end-point requirement: (0.8 + 0.3 sin t, −2.0 + 0.3 cos t), in reach of
// the triple pendulum (total length 2.7)
template <class S>
void tip_path(const S& t, S& x, S& y) {
  using std::cos;
  using std::sin;
  x = 0.8 + 0.3 * sin(t);
  y = -2.0 + 0.3 * cos(t);
}

Constraint tip_requirement() {
  const Chain c = kTriple;
  return holonomic("tip", 2, [c](const auto& q, const auto& t, auto& e) {
    using S = std::decay_t<decltype(t)>;
    using std::cos;
    using std::sin;
    S x(0.0), y(0.0);
    for (Index i = 0; i < 3; ++i) {
      x += c.L[std::size_t(i)] * sin(q[i]);
      y -= c.L[std::size_t(i)] * cos(q[i]);
    }
    S xd, yd;
    tip_path(t, xd, yd);
    e[0] = x - xd;
    e[1] = y - yd;
  });
}

// A_r and b_r of the tip requirement with e'' + 2α e' + β² e = 0, by hand (independent of AD)
void tip_acceleration_form(const Eigen::Ref<const VectorXd>& th,
                           const Eigen::Ref<const VectorXd>& w, double t, double alpha, double beta,
                           MatrixXd& A, VectorXd& b) {
  const auto& L = kTriple.L;
  A.resize(2, 3);
  b.resize(2);
  double x = 0, y = 0, xd = 0, yd = 0, xc = 0, yc = 0;  // tip, its rate, centripetal terms
  for (Index i = 0; i < 3; ++i) {
    const double l = L[std::size_t(i)], c = std::cos(th[i]), s = std::sin(th[i]);
    A(0, i) = l * c;
    A(1, i) = l * s;
    x += l * s;
    y -= l * c;
    xd += l * c * w[i];
    yd += l * s * w[i];
    xc -= l * s * w[i] * w[i];
    yc += l * c * w[i] * w[i];
  }
  const double px = 0.8 + 0.3 * std::sin(t), py = -2.0 + 0.3 * std::cos(t);
  const double vx = 0.3 * std::cos(t), vy = -0.3 * std::sin(t);
  const double ax = -0.3 * std::sin(t), ay = -0.3 * std::cos(t);
  // x'' = A th'' + xc = ax − 2α (x' − vx) − β² (x − px)
  b[0] = ax - 2 * alpha * (xd - vx) - beta * beta * (x - px) - xc;
  b[1] = ay - 2 * alpha * (yd - vy) - beta * beta * (y - py) - yc;
}

// ---------------------------------------------------------------------------------------------
// the Duffing oscillator: e(t) = (1 + t) e^{−2t}

TEST(ControlDuffing, FollowsSineWithPrescribedErrorDynamics) {
  const System sys = duffing();
  const Controller ctrl =
      ControllerBuilder(sys).require(track_sine(), ErrorDynamics::second_order(2.0, 1.0)).build();
  const ControlledTrajectory run = simulate_controlled(ctrl, sys, vec({1.0}), vec({0.0}), tight(6));
  ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
  ASSERT_GT(run.samples(), 100);
  double worst = 0.0, worst_force = 0.0;
  for (Index j = 0; j < run.samples(); ++j) {
    const double t = run.plant.t[std::size_t(j)];
    const double e = run.error[std::size_t(j)];
    // e'' + 4 e' + 4 e = 0, e(0) = 1, e'(0) = −1
    EXPECT_NEAR(e, (1.0 + t) * std::exp(-2.0 * t), 1e-8) << t;
    worst = std::max(worst, std::abs(e - (1.0 + t) * std::exp(-2.0 * t)));
    // Q_c = m x'' − Q with x'' = −sin t − 4 e' − 4 e
    const double x = run.plant.q[std::size_t(j)], xd = run.plant.qd[std::size_t(j)];
    const double ed = xd - std::cos(t);
    const double Qc =
        (-std::sin(t) - 4 * ed - 4 * e) - (-0.3 * xd + x - x * x * x + 0.5 * std::cos(1.2 * t));
    EXPECT_NEAR(run.Qc_control[std::size_t(j)], Qc, 1e-10 * (1 + std::abs(Qc))) << t;
    worst_force = std::max(worst_force, std::abs(run.Qc_control[std::size_t(j)] - Qc));
  }
  record("max_error_deviation", worst);
  record("max_force_deviation", worst_force);
  // effort and |work|: exact ODE states against composite Simpson on the samples (h = 0.05:
  // quadrature error of order h⁴ max|f''''| / 180 ≈ 1e-6 relative)
  const Index N = run.samples();
  auto simpson = [&](auto f, Index upto) {
    double s = 0.0;
    for (Index j = 0; j + 2 <= upto; j += 2) s += (f(j) + 4 * f(j + 1) + f(j + 2)) * 0.05 / 3.0;
    return s;
  };
  const Index last = (N - 1) / 2 * 2;
  const double effort = simpson(
      [&](Index j) {
        const double q = run.Qc_control[std::size_t(j)];
        return q * q;
      },
      last);
  const double work = simpson([&](Index j) { return run.control_power[std::size_t(j)]; }, last);
  EXPECT_NEAR(run.control_effort[std::size_t(last)], effort, 1e-5 * effort);
  EXPECT_NEAR(run.control_work[std::size_t(last)], work, 1e-5 * std::abs(effort));
  EXPECT_NEAR(run.control_effort.front(), 0.0, 1e-15);
  EXPECT_GE(run.control_work_abs[std::size_t(last)],
            std::abs(run.control_work[std::size_t(last)]) - 1e-12);
  // the same plant run by simulate() itself, through controlled_system()
  const Trajectory direct =
      simulate(controlled_system(ctrl, sys), vec({1.0}), vec({0.0}), tight(6));
  ASSERT_EQ(direct.samples(), run.samples());
  for (Index j = 0; j < run.samples(); ++j) {
    EXPECT_NEAR(direct.q[std::size_t(j)], run.plant.q[std::size_t(j)], 1e-9);
  }
  // the CSV columns
  const auto cols = control_csv_columns(run);
  std::vector<std::string> names;
  for (const auto& c : cols) names.push_back(c.name);
  EXPECT_EQ(names,
            (std::vector<std::string>{"error.track", "Qc_control.x", "control_power",
                                      "control_effort", "control_work_abs", "control_work"}));
  for (const auto& c : cols) EXPECT_EQ(Index(c.values.size()), N) << c.name;
}

TEST(ControlDuffing, NonholonomicRequirementHasFirstOrderErrorDynamics) {
  // psi = x' − cos t = 0 with psi' + 3 psi = 0: psi(t) = psi(0) e^{−3t}, psi(0) = −1
  const System sys = duffing();
  const Controller ctrl =
      ControllerBuilder(sys)
          .require(nonholonomic("speed", 1,
                                [](const auto&, const auto& qd, const auto& t, auto& psi) {
                                  using std::cos;
                                  psi[0] = qd[0] - cos(t);
                                }),
                   ErrorDynamics::first_order(3.0))
          .build();
  const ControlledTrajectory run = simulate_controlled(ctrl, sys, vec({0.5}), vec({0.0}), tight(4));
  ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
  double worst = 0.0;
  for (Index j = 0; j < run.samples(); ++j) {
    const double t = run.plant.t[std::size_t(j)];
    EXPECT_NEAR(run.error[std::size_t(j)], -std::exp(-3.0 * t), 1e-9) << t;
    EXPECT_NEAR(run.error[std::size_t(j)], run.plant.qd[std::size_t(j)] - std::cos(t), 1e-14);
    worst = std::max(worst, std::abs(run.error[std::size_t(j)] + std::exp(-3.0 * t)));
  }
  record("max_error_deviation", worst);
}

// ---------------------------------------------------------------------------------------------
// triple pendulum

TEST(ControlTriplePendulum, JointAnglesFollowPrescribedTrajectories) {
  const System sys = chain_system(kTriple);
  const double zeta = 0.7, omega = 3.0;
  ControllerBuilder builder(sys);
  for (Index i = 0; i < 3; ++i) {
    builder.require(
        holonomic("joint" + std::to_string(i + 1), 1,
                  [i](const auto& q, const auto& t, auto& e) { e[0] = q[i] - joint_path(i, t); }),
        ErrorDynamics::second_order(omega, zeta));
  }
  const Controller ctrl = builder.build();
  const VectorXd q0 = vec({0.3, -0.2, 0.5}), qd0 = vec({0.0, 0.4, -0.3});
  const ControlledTrajectory run = simulate_controlled(ctrl, sys, q0, qd0, tight(4));
  ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
  EXPECT_EQ(run.control.not_met, 0);
  double worst = 0.0;
  for (Index j = 0; j < run.samples(); ++j) {
    const double t = run.plant.t[std::size_t(j)];
    for (Index i = 0; i < 3; ++i) {
      // e_i(0) = th_i(0) − path_i(0), e_i'(0) = th_i'(0) − 0.2 (i+1)
      const double e0 = q0[i] - joint_path(i, 0.0), e1 = qd0[i] - 0.2 * double(i + 1);
      const double expected = second_order_error(zeta, omega, e0, e1, t);
      const double e = sample(run.error, 3, j)[i];
      EXPECT_NEAR(e, expected, 1e-8) << "joint " << i + 1 << " t = " << t;
      worst = std::max(worst, std::abs(e - expected));
    }
  }
  record("max_error_deviation", worst);
  // energy balance with the control's work: E(t) − E(0) = ∫ Qcᵀ q' dt (the integral is a state)
  EXPECT_NEAR(run.plant.stats.energy_drift, 0.0, 1e-8);
  record("energy_drift", run.plant.stats.energy_drift);
}

// One end-point requirement (2 rows) on 3 actuated joints: redundant actuation. The weighted law
// must give the least Q_cᵀ N Q_c among all forces that meet the requirement.
TEST(ControlTriplePendulum, EndPointWeightedLawIsOptimal) {
  const System sys = chain_system(kTriple);
  const double omega = 2.0;  // ζ = 1: α = β = 2
  auto N_of = [](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd) {
    MatrixXd N = MatrixXd::Zero(3, 3);
    N.diagonal() << 1.0 + q[0] * q[0], 2.0 + 0.5 * std::sin(q[1]), 3.0 + 0.1 * qd[2] * qd[2];
    N(0, 1) = N(1, 0) = 0.3 * std::cos(q[2]);
    return N;
  };
  const Controller ctrl = ControllerBuilder(sys)
                              .require(tip_requirement(), ErrorDynamics::second_order(omega))
                              .weighted([N_of](const Eigen::Ref<const VectorXd>& q,
                                               const Eigen::Ref<const VectorXd>& qd, double,
                                               Eigen::Ref<MatrixXd> N) { N = N_of(q, qd); })
                              .build();
  ControlWorkspace ws(ctrl);
  double worst_closed_form = 0.0, worst_gap = 0.0, worst_orthogonality = 0.0;
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int trial = 0; trial < 8; ++trial) {
    const VectorXd q = vec({0.4 + 0.3 * U(gen), 0.3 * U(gen), 0.5 + 0.3 * U(gen)});
    const VectorXd qd = vec({U(gen), U(gen), U(gen)});
    const double t = 2.0 * (1.0 + U(gen));
    ASSERT_EQ(compute_control(ctrl, ws, q, qd, t), ControlStatus::kOk)
        << describe_control_status(ctrl, ws);
    // independent: X = A M⁻¹, e = b − A a from the hand-written A, b and the chain's M, Q
    MatrixXd A;
    VectorXd b;
    tip_acceleration_form(q, qd, t, omega, omega, A, b);
    const MatrixXd M = kTriple.mass(q);
    const Eigen::LLT<MatrixXd> llt(M);
    const MatrixXd X = A * llt.solve(MatrixXd::Identity(3, 3));
    const VectorXd e = b - A * llt.solve(kTriple.force(q, qd));
    const MatrixXd N = N_of(q, qd);
    const VectorXd& Qc = ws.Qc_control;
    // meets the requirement
    EXPECT_NEAR((X * Qc - e).norm(), 0.0, 1e-10 * (1 + e.norm()));
    // closed form for full-rank X: Q_c = N⁻¹ Xᵀ (X N⁻¹ Xᵀ)⁻¹ e
    const MatrixXd NinvXt = N.llt().solve(X.transpose());
    const VectorXd expected = NinvXt * (X * NinvXt).ldlt().solve(e);
    EXPECT_NEAR(rel_diff(Qc, expected), 0.0, 1e-10);
    worst_closed_form = std::max(worst_closed_form, rel_diff(Qc, expected));
    // no admissible force Q_c + d (X d = 0) costs less: cost(Q_c + d) − cost(Q_c) = dᵀ N d
    const MatrixXd Z = null_space(X);
    ASSERT_EQ(Z.cols(), 1);
    const double cost = Qc.dot(N * Qc);
    for (int k = 0; k < 20; ++k) {
      const VectorXd d = Z * (3.0 * U(gen) * (1 + Qc.norm()));
      const VectorXd F = Qc + d;
      EXPECT_NEAR((X * F - e).norm(), 0.0, 1e-9 * (1 + e.norm()));  // admissible
      const double cost_F = F.dot(N * F);
      EXPECT_GE(cost_F, cost);
      EXPECT_NEAR(cost_F - cost, d.dot(N * d), 1e-9 * (1 + cost_F));
      worst_gap = std::max(worst_gap, std::abs(cost_F - cost - d.dot(N * d)) / (1 + cost_F));
      worst_orthogonality =
          std::max(worst_orthogonality, std::abs(d.dot(N * Qc)) / (d.norm() * (N * Qc).norm()));
    }
  }
  record("max_rel_diff_closed_form", worst_closed_form);
  record("max_rel_cost_gap_error", worst_gap);
  record("max_cos_d_NQc", worst_orthogonality);
  // and the tip follows the path with the prescribed error dynamics
  const VectorXd q0 = vec({0.5, 0.2, 0.6}), qd0 = vec({0.0, 0.0, 0.0});
  const ControlledTrajectory run = simulate_controlled(ctrl, sys, q0, qd0, tight(3));
  ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
  double x0 = 0, y0 = 0;
  for (Index i = 0; i < 3; ++i) {
    x0 += kTriple.L[std::size_t(i)] * std::sin(q0[i]);
    y0 -= kTriple.L[std::size_t(i)] * std::cos(q0[i]);
  }
  const double ex0 = x0 - 0.8, ey0 = y0 - (-2.0 + 0.3);  // e'(0) = 0 − path'(0) = (−0.3, 0)
  double worst = 0.0;
  for (Index j = 0; j < run.samples(); ++j) {
    const double t = run.plant.t[std::size_t(j)];
    const double ex = second_order_error(1.0, omega, ex0, -0.3, t);
    const double ey = second_order_error(1.0, omega, ey0, 0.0, t);
    EXPECT_NEAR(sample(run.error, 2, j)[0], ex, 1e-8);
    EXPECT_NEAR(sample(run.error, 2, j)[1], ey, 1e-8);
    worst = std::max({worst, std::abs(sample(run.error, 2, j)[0] - ex),
                      std::abs(sample(run.error, 2, j)[1] - ey)});
  }
  record("max_error_deviation", worst);
}

// ---------------------------------------------------------------------------------------------
// the laws against independent methods

TEST(ControlLaws, GaussEqualsKktConstraintForceOfTheRequirements) {
  const System sys = chain_system(kTriple);
  const Controller ctrl =
      ControllerBuilder(sys).require(tip_requirement(), ErrorDynamics::second_order(2.0)).build();
  ControlWorkspace ws(ctrl);
  const VectorXd q = vec({0.4, -0.3, 0.7}), qd = vec({0.5, -1.0, 0.2});
  ASSERT_EQ(compute_control(ctrl, ws, q, qd, 0.8), ControlStatus::kOk);
  // Lagrange multipliers of the requirements as constraints: M q'' = Q + Aᵀ λ, A q'' = b
  MatrixXd A;
  VectorXd b;
  tip_acceleration_form(q, qd, 0.8, 2.0, 2.0, A, b);
  KktSolver kkt(3, 2);
  VectorXd qdd(3), lambda(2);
  ASSERT_EQ(kkt.solve(kTriple.mass(q), kTriple.force(q, qd), A, b, qdd, lambda), Eigen::Success);
  EXPECT_NEAR(rel_diff(ws.Qc_control, A.transpose() * lambda), 0.0, 1e-12);
  EXPECT_NEAR(rel_diff(ws.qdd, qdd), 0.0, 1e-12);
  record("rel_diff_kkt", rel_diff(ws.Qc_control, A.transpose() * lambda));
  // and the textbook formula M^{1/2} B⁺ e with the eigendecomposition and SVD
  TextbookDecomposition tb(3, 2);
  tb.compute_mass(kTriple.mass(q));
  tb.compute_constraints(A);
  VectorXd dq(3), Qc(3), lam(2);
  const VectorXd a = kTriple.mass(q).llt().solve(kTriple.force(q, qd));
  tb.solve_ideal(b - A * a, dq, Qc, lam);
  EXPECT_NEAR(rel_diff(ws.Qc_control, Qc), 0.0, 1e-10);
  record("rel_diff_textbook", rel_diff(ws.Qc_control, Qc));
}

TEST(ControlLaws, WeightedWithInverseMassIsGaussAndWithMassIsNot) {
  const System sys = chain_system(kTriple);
  auto builder = [&] {
    return ControllerBuilder(sys).require(tip_requirement(), ErrorDynamics::second_order(2.0));
  };
  const Controller gauss = builder().build();
  const Controller inverse_mass =
      builder()
          .weighted([](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>&,
                       double, Eigen::Ref<MatrixXd> N) { N = kTriple.mass(q).inverse(); })
          .build();
  const Controller mass =
      builder()
          .weighted([](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>&,
                       double, Eigen::Ref<MatrixXd> N) { N = kTriple.mass(q); })
          .build();
  // actuating every coordinate through S = I takes the general path (cost Sᵀ M⁻¹ S)
  const Controller through_S = builder().actuation(MatrixXd::Identity(3, 3)).build();
  ControlWorkspace wg(gauss), wi(inverse_mass), wm(mass), ws(through_S);
  const VectorXd q = vec({0.2, 0.5, -0.4}), qd = vec({-0.3, 0.8, 1.1});
  const double t = 1.3;
  ASSERT_EQ(compute_control(gauss, wg, q, qd, t), ControlStatus::kOk);
  ASSERT_EQ(compute_control(inverse_mass, wi, q, qd, t), ControlStatus::kOk);
  ASSERT_EQ(compute_control(mass, wm, q, qd, t), ControlStatus::kOk);
  ASSERT_EQ(compute_control(through_S, ws, q, qd, t), ControlStatus::kOk);
  EXPECT_NEAR(rel_diff(wi.Qc_control, wg.Qc_control), 0.0, 1e-10);
  EXPECT_NEAR(rel_diff(ws.Qc_control, wg.Qc_control), 0.0, 1e-10);
  record("rel_diff_N_Minv_vs_gauss", rel_diff(wi.Qc_control, wg.Qc_control));
  record("rel_diff_S_identity_vs_gauss", rel_diff(ws.Qc_control, wg.Qc_control));
  record("rel_diff_N_M_vs_gauss", rel_diff(wm.Qc_control, wg.Qc_control));
  // N = M minimizes another cost: a different force, which still meets the requirement
  EXPECT_GT(rel_diff(wm.Qc_control, wg.Qc_control), 1e-2);
  EXPECT_NEAR((wm.req.A * wm.qdd - wm.req.b).norm(), 0.0, 1e-11);
  EXPECT_NEAR((wg.req.A * wg.qdd - wg.req.b).norm(), 0.0, 1e-11);
  // each is the least in its own cost: Gauss's M⁻¹-cost is below that of the N = M force
  const MatrixXd Minv = kTriple.mass(q).inverse(), M = kTriple.mass(q);
  EXPECT_LT(wg.Qc_control.dot(Minv * wg.Qc_control), wm.Qc_control.dot(Minv * wm.Qc_control));
  EXPECT_LT(wm.Qc_control.dot(M * wm.Qc_control), wg.Qc_control.dot(M * wg.Qc_control));
}

TEST(ControlLaws, ActuatedSubsetThatCannotMeetTheRequirementsIsReported) {
  // joints 1 and 2 must follow paths, only joint 3 is actuated: 2 rows, 1 actuator
  const System sys = chain_system(kTriple);
  ControllerBuilder builder(sys);
  for (Index i = 0; i < 2; ++i) {
    builder.require(
        holonomic("joint" + std::to_string(i + 1), 1,
                  [i](const auto& q, const auto& t, auto& e) { e[0] = q[i] - joint_path(i, t); }),
        ErrorDynamics::second_order(3.0));
  }
  const Controller ctrl = builder.actuated({"th3"}).build();
  ControlWorkspace ws(ctrl);
  const VectorXd q = vec({0.3, -0.2, 0.5}), qd = vec({0.1, 0.4, -0.3});
  ASSERT_EQ(compute_control(ctrl, ws, q, qd, 0.7), ControlStatus::kRequirementsNotMet);
  const std::string msg = describe_control_status(ctrl, ws);
  EXPECT_NE(msg.find("cannot all be met with the actuators (th3)"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'joint1'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("least squares"), std::string::npos) << msg;
  // independent least squares: u minimizes ‖X S u − e‖, X = A M⁻¹, A = [I₂ 0]
  const MatrixXd M = kTriple.mass(q);
  MatrixXd A = MatrixXd::Zero(2, 3);
  A(0, 0) = A(1, 1) = 1.0;
  VectorXd b(2);
  for (Index i = 0; i < 2; ++i) {
    const double t = 0.7, k = double(i + 1) / 2.0;
    const double path = 0.4 * std::sin(k * t) + 0.1 * double(i);
    const double rate = 0.4 * k * std::cos(k * t), acc = -0.4 * k * k * std::sin(k * t);
    b[i] = acc - 2 * 3.0 * (qd[i] - rate) - 9.0 * (q[i] - path);
  }
  const MatrixXd XS = (A * M.inverse()).col(2);
  const VectorXd e = b - A * M.llt().solve(kTriple.force(q, qd));
  const VectorXd u = XS.colPivHouseholderQr().solve(e);
  EXPECT_NEAR(ws.u[0], u[0], 1e-10 * (1 + std::abs(u[0])));
  EXPECT_NEAR(rel_diff(ws.Qc_control, vec({0.0, 0.0, u[0]})), 0.0, 1e-10);
  EXPECT_NEAR(rel_diff(ws.residual, XS * u - e), 0.0, 1e-10);
  record("rel_diff_least_squares_u", std::abs(ws.u[0] - u[0]) / std::abs(u[0]));
  EXPECT_EQ(ws.rows_not_met, 2);
  // with joint 3 required instead, the single actuator suffices
  const Controller ok = ControllerBuilder(sys)
                            .require(holonomic("joint3", 1,
                                               [](const auto& qq, const auto& t, auto& e3) {
                                                 e3[0] = qq[2] - joint_path(2, t);
                                               }),
                                     ErrorDynamics::second_order(3.0))
                            .actuated({"th3"})
                            .build();
  ControlWorkspace wo(ok);
  EXPECT_EQ(compute_control(ok, wo, q, qd, 0.7), ControlStatus::kOk);
  EXPECT_EQ(wo.Qc_control[0], 0.0);
  EXPECT_EQ(wo.Qc_control[1], 0.0);
}

// ---------------------------------------------------------------------------------------------
// model uncertainty: the plant's mass is 1, the controller believes 1.2 (a 20 % error)

TEST(ControlRobust, TwentyPercentMassErrorStaysInsideTheReportedBound) {
  const System plant = duffing(1.0), nominal = duffing(1.2);
  const double omega = 2.0;  // ζ = 1: α = β = 2
  // with the nominal force the plant's requirement residual is exactly 0.2 b_r, and a requested
  // v becomes 1.2 v: relative_bound = gain_uncertainty = 0.2
  const RobustControl robust{
      .bound = 0.0, .relative_bound = 0.2, .gain_uncertainty = 0.2, .boundary_layer = 1e-3};
  const Controller with = ControllerBuilder(nominal)
                              .require(track_sine(), ErrorDynamics::second_order(omega))
                              .robust(robust)
                              .build();
  const Controller without =
      ControllerBuilder(nominal).require(track_sine(), ErrorDynamics::second_order(omega)).build();
  SimulationOptions o;
  o.t_end = 21.0;
  o.output_every = 0.05;
  const ControlledTrajectory r = simulate_controlled(with, plant, vec({1.0}), vec({0.0}), o);
  const ControlledTrajectory n = simulate_controlled(without, plant, vec({1.0}), vec({0.0}), o);
  ASSERT_EQ(r.plant.stats.status, Status::kOk) << r.plant.stats.message;
  ASSERT_EQ(n.plant.stats.status, Status::kOk) << n.plant.stats.message;
  ASSERT_TRUE(r.robust);
  // the robust run stays inside its bound at every sample (the bound starts at
  // sqrt(V(0) / (α² + β²)), V(0) = (β² + 2α²) e² + 2α e e' + e'² = 12 − 4 + 1 with e(0) = 1,
  // e'(0) = −1)
  EXPECT_NEAR(r.error_bound.front(), std::sqrt(9.0 / 8.0), 1e-12);
  for (Index j = 0; j < r.samples(); ++j) {
    EXPECT_LE(std::abs(r.error[std::size_t(j)]), r.error_bound[std::size_t(j)])
        << r.plant.t[std::size_t(j)];
  }
  // the nominal control alone: e'' + 4.8 e' + 4.8 e = −0.2 sin t in steady state, amplitude
  // 0.2 / |4.8 − 1 + 4.8 i| = 0.032670…; it leaves the robust bound
  double nominal_peak = 0.0, bound_late = 0.0, robust_peak = 0.0;
  for (Index j = 0; j < n.samples(); ++j) {
    if (n.plant.t[std::size_t(j)] < 14.0) continue;
    nominal_peak = std::max(nominal_peak, std::abs(n.error[std::size_t(j)]));
    bound_late = std::max(bound_late, r.error_bound[std::size_t(j)]);
    robust_peak = std::max(robust_peak, std::abs(r.error[std::size_t(j)]));
  }
  EXPECT_NEAR(nominal_peak, 0.2 / std::hypot(3.8, 4.8), 2e-4);
  EXPECT_GT(nominal_peak, 3.0 * bound_late);
  record("robust_bound_late", bound_late);
  record("nominal_peak_late", nominal_peak);
  record("robust_peak_late", robust_peak);
  // the bound is the ultimate one of the largest gain seen: sqrt(κ ε / (2 γ (α² + β²))),
  // γ = 2α (1 − α / sqrt(α² + β²)) = 4 − 2√2
  const double gamma = 4.0 - 2.0 * std::sqrt(2.0);
  EXPECT_NEAR(with.robust_rate(0), gamma, 1e-14);
  EXPECT_LE(bound_late, std::sqrt(r.control.max_kappa * 1e-3 / (2 * gamma * 8.0)) * (1 + 1e-9));
  EXPECT_NEAR(with.ultimate_error_bound(0, r.control.max_kappa),
              std::sqrt(r.control.max_kappa * 1e-3 / (2 * gamma * 8.0)), 1e-15);
  // the CSV carries the bound and the robust force
  const auto cols = control_csv_columns(r);
  EXPECT_EQ(cols[1].name, "error_bound.track");
  EXPECT_EQ(cols[3].name, "Qc_robust.x");
}

// ---------------------------------------------------------------------------------------------
// errors users meet

TEST(ControlErrors, MessagesNameTheProblem) {
  const System sys = duffing();
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(no exception)");
  };
  EXPECT_NE(message([&] {
              requirement(track_sine(), ErrorDynamics::first_order(2.0));
            }).find("holonomic requirement phi(q, t) = 0 takes second-order"),
            std::string::npos);
  EXPECT_NE(message([&] {
              requirement(nonholonomic("v", 1,
                                       [](const auto&, const auto& qd, const auto&, auto& p) {
                                         p[0] = qd[0];
                                       }),
                          ErrorDynamics::second_order(2.0));
            }).find("use ErrorDynamics::first_order(k)"),
            std::string::npos);
  EXPECT_NE(message([&] { ErrorDynamics::second_order(-1.0); }).find("omega and zeta must be > 0"),
            std::string::npos);
  EXPECT_NE(message([&] { ControllerBuilder(sys).build(); }).find("no requirement"),
            std::string::npos);
  EXPECT_NE(message([&] {
              ControllerBuilder(sys).require(track_sine()).actuated({"y"}).build();
            }).find("actuated coordinate 'y' is not a coordinate of the model (x)"),
            std::string::npos);
  EXPECT_NE(
      message([&] {
        ControllerBuilder(sys).require(track_sine()).weighted(MatrixXd::Identity(2, 2)).build();
      }).find("the weight N must be n × n = 1 × 1, got 2 × 2"),
      std::string::npos);
  EXPECT_NE(
      message([&] {
        ControllerBuilder(sys).require(track_sine()).weighted(-MatrixXd::Identity(1, 1)).build();
      }).find("positive definite"),
      std::string::npos);
  EXPECT_NE(message([&] {
              ControllerBuilder(sys)
                  .require(track_sine())
                  .robust({.bound = 1.0, .boundary_layer = 0.01})
                  .build();
            }).find("'track' has alpha = 0"),
            std::string::npos);
  EXPECT_NE(message([&] {
              ControllerBuilder(sys)
                  .require(track_sine(), ErrorDynamics::second_order(1.0))
                  .robust({.bound = 1.0})
                  .build();
            }).find("boundary_layer must be > 0"),
            std::string::npos);
  // a workspace of another controller, a plant with other coordinates
  const Controller a = ControllerBuilder(sys).require(track_sine()).build();
  const Controller b = ControllerBuilder(sys).require(track_sine()).build();
  ControlWorkspace wb(b);
  EXPECT_NE(message([&] {
              compute_control(a, wb, vec({0.0}), vec({0.0}), 0.0);
            }).find("made for another controller"),
            std::string::npos);
  EXPECT_NE(message([&] {
              simulate_controlled(a, cartesian_pendulum(1, 1), vec({0, -1}), vec({0, 0}));
            }).find("have different coordinates"),
            std::string::npos);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
