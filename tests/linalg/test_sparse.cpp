// SPDX-License-Identifier: BSD-3-Clause
// The sparse engine (linalg/sparse.hpp) against the dense one (linalg/decomposition.hpp) on the
// same System: random block-diagonal systems with random local constraints (duplicated, linearly
// combined and rank-deficient rows, dense rows, inactive constraints, non-ideal forces), planar
// chains closed back to ground (also closed twice), inconsistent constraints, projection,
// simulation, and the choice of engine.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <ukdyn/core/autodiff.hpp>
#include <ukdyn/core/nonideal.hpp>
#include <ukdyn/core/system.hpp>
#include <ukdyn/dynamics/forward.hpp>
#include <ukdyn/dynamics/projection.hpp>
#include <ukdyn/dynamics/workspace.hpp>
#include <ukdyn/linalg/sparse.hpp>
#include <ukdyn/simulation/simulate.hpp>

#include "support/planar_revolute.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using testing::PlanarRevolute;

// ‖x − y‖ / max(‖y‖, floor): relative difference with a floor for vectors that should be ~0
double rel(const Eigen::Ref<const MatrixXd>& x, const Eigen::Ref<const MatrixXd>& y,
           double floor = 1e-300) {
  return (x - y).norm() / std::max(y.norm(), floor);
}

Constraint revolute(const std::string& name, Index i, Eigen::Vector2d si, Index j,
                    Eigen::Vector2d sj) {
  return Constraint(name, ConstraintKind::kHolonomic, 2,
                    std::make_shared<PlanarRevolute>(i, si, j, sj));
}

// N uniform rods (1 kg/m) of total length 2 m hanging from the ground point (0, 0) at absolute
// angles phi, under gravity; `closures` extra joints tie the last tip to the ground point where
// it is (consistent by construction; two or more make the loop redundant)
struct Chain {
  System sys;
  VectorXd q, qd;
};

Chain closed_chain(const std::vector<double>& phi, int closures, bool with_friction = false) {
  const Index N = Index(phi.size());
  const double L = 2.0 / double(N), m = L, I = m * L * L / 12.0;
  SystemBuilder b(3 * N);
  VectorXd q(3 * N), qd = VectorXd::Zero(3 * N);
  Eigen::Vector2d p(0.0, 0.0);
  for (Index i = 0; i < N; ++i) {
    const Eigen::Vector2d u(std::cos(phi[std::size_t(i)]), std::sin(phi[std::size_t(i)]));
    q.segment<2>(3 * i) = p + 0.5 * L * u;
    q[3 * i + 2] = phi[std::size_t(i)];
    qd.segment<2>(3 * i) = Eigen::Vector2d(0.0, 0.0);
    p += L * u;
    b.mass_block(3 * i, Eigen::Vector3d(m, m, I).asDiagonal().toDenseMatrix());
  }
  b.forces([N, m](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                  Eigen::Ref<VectorXd> Q) {
    Q.setZero();
    for (Index i = 0; i < N; ++i) Q[3 * i + 1] = -9.81 * m;
  });
  b.potential_energy([N, m](const Eigen::Ref<const VectorXd>& x, double) {
    double V = 0.0;
    for (Index i = 0; i < N; ++i) V += 9.81 * m * x[3 * i + 1];
    return V;
  });
  const Eigen::Vector2d back(-0.5 * L, 0.0), tip(0.5 * L, 0.0);
  b.add(revolute("pin0", 0, back, -1, Eigen::Vector2d(0.0, 0.0)));
  for (Index i = 1; i < N; ++i) b.add(revolute("pin" + std::to_string(i), i, back, i - 1, tip));
  for (int c = 0; c < closures; ++c)
    b.add(revolute("close" + std::to_string(c), N - 1, tip, -1, p));
  if (with_friction) b.add(viscous_friction({.coefficient = 0.05}));
  return {b.build(), q, qd};
}

// a rod of length d between the centres of mass of bodies i and j (local columns of both):
// phi = (|p_i − p_j|² − d²)/2, A = [Δᵀ 0 −Δᵀ 0], b = −|v_i − v_j|²
class Rung final : public ConstraintModel {
 public:
  Rung(Index i, Index j, double d) : i_(i), j_(j), d_(d) {
    for (Index c = 0; c < 3; ++c) cols_.push_back(3 * i + c);
    for (Index c = 0; c < 3; ++c) cols_.push_back(3 * j + c);
  }
  const std::vector<Index>& columns() const override { return cols_; }
  void acceleration_form_local(const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double, ConstraintScratch*,
                               Eigen::Ref<MatrixXd> A, Eigen::Ref<VectorXd> b) const override {
    const Eigen::Vector2d D = q.segment<2>(3 * i_) - q.segment<2>(3 * j_);
    const Eigen::Vector2d V = qd.segment<2>(3 * i_) - qd.segment<2>(3 * j_);
    A.setZero();
    A.block(0, 0, 1, 2) = D.transpose();
    A.block(0, 3, 1, 2) = -D.transpose();
    b[0] = -V.squaredNorm();
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                 ConstraintScratch*, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    const Eigen::Vector2d D = q.segment<2>(3 * i_) - q.segment<2>(3 * j_);
    position[0] = 0.5 * (D.squaredNorm() - d_ * d_);
    velocity[0] = D.dot(qd.segment<2>(3 * i_) - qd.segment<2>(3 * j_));
  }

 private:
  Index i_, j_;
  double d_;
  std::vector<Index> cols_;
};

// two copies of a closed chain side by side (0.5 m apart), body i of one tied to body i of the
// other by a rung: parallelograms, whose loops make one row redundant (a self-stress along the
// whole ladder)
Chain ladder(const std::vector<double>& phi) {
  const Index H = Index(phi.size()), N = 2 * H;
  const double L = 2.0 / double(H), m = L, I = m * L * L / 12.0, d = 0.5;
  SystemBuilder b(3 * N);
  VectorXd q(3 * N);
  Eigen::Vector2d p(0.0, 0.0);
  for (Index i = 0; i < H; ++i) {
    const Eigen::Vector2d u(std::cos(phi[std::size_t(i)]), std::sin(phi[std::size_t(i)]));
    for (Index side = 0; side < 2; ++side) {
      q.segment<2>(3 * (i + side * H)) = p + 0.5 * L * u + Eigen::Vector2d(d * double(side), 0.0);
      q[3 * (i + side * H) + 2] = phi[std::size_t(i)];
    }
    p += L * u;
  }
  for (Index k = 0; k < N; ++k) {
    b.mass_block(3 * k, Eigen::Vector3d(m, m, I).asDiagonal().toDenseMatrix());
  }
  b.forces([N, m](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                  Eigen::Ref<VectorXd> Q) {
    Q.setZero();
    for (Index i = 0; i < N; ++i) Q[3 * i + 1] = -9.81 * m;
  });
  const Eigen::Vector2d back(-0.5 * L, 0.0), tip(0.5 * L, 0.0);
  for (Index side = 0; side < 2; ++side) {
    const Index o = side * H;
    const std::string s = side ? "b" : "a";
    const Eigen::Vector2d shift(d * double(side), 0.0);
    b.add(revolute(s + "pin0", o, back, -1, shift));
    for (Index i = 1; i < H; ++i)
      b.add(revolute(s + "pin" + std::to_string(i), o + i, back, o + i - 1, tip));
    b.add(revolute(s + "close", o + H - 1, tip, -1, p + shift));
  }
  for (Index i = 1; i < H; ++i) {
    b.add(Constraint("rung" + std::to_string(i), ConstraintKind::kHolonomic, 1,
                     std::make_shared<Rung>(i, H + i, d)));
  }
  return {b.build(), q, VectorXd::Zero(3 * N)};
}

// ---------------------------------------------------------------------------------------------
// a linear local constraint A_local q''(cols) = b with fixed A_local (rows × cols)
class LocalLinear final : public ConstraintModel {
 public:
  LocalLinear(std::vector<Index> cols, MatrixXd A, VectorXd b)
      : cols_(std::move(cols)), A_(std::move(A)), b_(std::move(b)) {}
  const std::vector<Index>& columns() const override { return cols_; }
  void acceleration_form_local(const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&,
                               double, ConstraintScratch*, Eigen::Ref<MatrixXd> A,
                               Eigen::Ref<VectorXd> b) const override {
    A = A_;
    b = b_;
  }

 private:
  std::vector<Index> cols_;
  MatrixXd A_;
  VectorXd b_;
};

// a random block-diagonal system: blocks of sizes 1–6 (some state-dependent), random local
// constraints on 1–3 bodies, then redundancy: a duplicated constraint, a linear combination of
// two constraints on the union of their columns, a rank-deficient constraint, a dense row
// (acceleration_constraint), an inactive constraint; consistent b = A x0; a non-ideal force
struct RandomSparse {
  std::shared_ptr<const System> system;
  VectorXd q, qd;
  Index redundant = 0;  // rows that are linear combinations of others
  const System& sys() const { return *system; }
};

RandomSparse random_sparse(unsigned seed, Index bodies, Index constraints, bool redundancy,
                           bool inconsistent = false) {
  std::mt19937 gen(seed);
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<int> size_of(1, 6), rows_of(1, 3), bodies_of(1, 3);
  std::vector<Index> off, size;
  Index n = 0;
  for (Index k = 0; k < bodies; ++k) {
    off.push_back(n);
    size.push_back(size_of(gen));
    n += size.back();
  }
  const auto gaussian = [&](Index r, Index c) {
    MatrixXd X(r, c);
    for (Index j = 0; j < c; ++j) {
      for (Index i = 0; i < r; ++i) X(i, j) = normal(gen);
    }
    return X;
  };
  VectorXd x0 = gaussian(n, 1);
  SystemBuilder b(n);
  for (Index k = 0; k < bodies; ++k) {
    const MatrixXd R = gaussian(size[std::size_t(k)], size[std::size_t(k)]);
    const MatrixXd Mk = R * R.transpose() / double(size[std::size_t(k)]) +
                        MatrixXd::Identity(size[std::size_t(k)], size[std::size_t(k)]);
    if (k % 3 == 1) {
      // state-dependent: M_k (1 + 0.1 q_first²)
      const Index first = off[std::size_t(k)];
      b.mass_block(
          first, size[std::size_t(k)],
          [Mk, first](const Eigen::Ref<const VectorXd>& q, double, Eigen::Ref<MatrixXd> out) {
            out = Mk * (1.0 + 0.1 * q[first] * q[first]);
          });
    } else {
      b.mass_block(off[std::size_t(k)], Mk);
    }
  }
  const VectorXd Q = gaussian(n, 1);
  b.forces([Q](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
               Eigen::Ref<VectorXd> out) { out = Q; });
  struct Made {
    std::vector<Index> cols;
    MatrixXd A;
  };
  std::vector<Made> made;
  std::uniform_int_distribution<Index> body(0, bodies - 1);
  const auto add = [&](const std::string& name, std::vector<Index> cols, MatrixXd A) {
    VectorXd x(Index(cols.size()));
    for (std::size_t j = 0; j < cols.size(); ++j) x[Index(j)] = x0[cols[j]];
    VectorXd rhs = A * x;
    b.add(Constraint(name, ConstraintKind::kAcceleration, A.rows(),
                     std::make_shared<LocalLinear>(cols, A, rhs)));
    made.push_back({std::move(cols), std::move(A)});
  };
  for (Index c = 0; c < constraints; ++c) {
    std::vector<Index> bs;
    for (int t = bodies_of(gen); t > 0; --t) bs.push_back(body(gen));
    std::sort(bs.begin(), bs.end());
    bs.erase(std::unique(bs.begin(), bs.end()), bs.end());
    std::vector<Index> cols;
    for (Index k : bs) {
      // some of the body's coordinates (at least one)
      for (Index i = 0; i < size[std::size_t(k)]; ++i) {
        if (i == 0 || normal(gen) > -0.5) cols.push_back(off[std::size_t(k)] + i);
      }
    }
    add("c" + std::to_string(c), cols, gaussian(rows_of(gen), Index(cols.size())));
  }
  RandomSparse made_up;
  if (redundancy) {
    // a duplicate of constraint 0
    add("dup", made[0].cols, made[0].A);
    made_up.redundant += made[0].A.rows();
    // 0.7 × (row 0 of c1) − 1.3 × (row 0 of c2), on the union of their columns
    std::vector<Index> cols = made[1].cols;
    cols.insert(cols.end(), made[2].cols.begin(), made[2].cols.end());
    std::sort(cols.begin(), cols.end());
    cols.erase(std::unique(cols.begin(), cols.end()), cols.end());
    MatrixXd A = MatrixXd::Zero(1, Index(cols.size()));
    for (int w = 1; w <= 2; ++w) {
      const double f = w == 1 ? 0.7 : -1.3;
      for (std::size_t j = 0; j < made[std::size_t(w)].cols.size(); ++j) {
        const Index at =
            Index(std::lower_bound(cols.begin(), cols.end(), made[std::size_t(w)].cols[j]) -
                  cols.begin());
        A(0, at) += f * made[std::size_t(w)].A(0, Index(j));
      }
    }
    add("combination", cols, A);
    made_up.redundant += 1;
    // three rows of rank one on one body's coordinates
    const Index k = body(gen);
    std::vector<Index> own;
    for (Index i = 0; i < size[std::size_t(k)]; ++i) own.push_back(off[std::size_t(k)] + i);
    add("rank1", own, gaussian(3, 1) * gaussian(1, Index(own.size())));
    made_up.redundant += 2;
  }
  // a dense row, and a constraint that is never active
  {
    const MatrixXd A = gaussian(1, n);
    const VectorXd rhs = A * x0 + VectorXd::Constant(1, inconsistent ? 0.0 : 0.0);
    b.add(acceleration_constraint(
        "dense", 1,
        [A, rhs](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<MatrixXd> Aout, Eigen::Ref<VectorXd> bout) {
          Aout = A;
          bout = rhs;
        }));
  }
  {
    const Index k = body(gen);
    Constraint c("inactive", ConstraintKind::kAcceleration, 1,
                 std::make_shared<LocalLinear>(std::vector<Index>{off[std::size_t(k)]},
                                               MatrixXd::Ones(1, 1), VectorXd::Ones(1)));
    c.active_between(10.0, 11.0);
    b.add(c);
  }
  if (inconsistent) {
    // constraint 0 again with another right-hand side
    VectorXd x(Index(made[0].cols.size()));
    for (std::size_t j = 0; j < made[0].cols.size(); ++j) x[Index(j)] = x0[made[0].cols[j]];
    b.add(
        Constraint("conflict", ConstraintKind::kAcceleration, made[0].A.rows(),
                   std::make_shared<LocalLinear>(
                       made[0].cols, made[0].A, made[0].A * x + VectorXd::Ones(made[0].A.rows()))));
  }
  const VectorXd C = gaussian(n, 1);
  b.add(NonIdealForce(
      "C", [C](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
               const IdealForceInfo&, Eigen::Ref<VectorXd> out) { out = C; }));
  made_up.system = std::make_shared<const System>(b.build());
  made_up.q = gaussian(n, 1);
  made_up.qd = gaussian(n, 1);
  return made_up;
}

SolverOptions dense_options() { return SolverOptions{.engine = Engine::kDense}; }
SolverOptions sparse_options() { return SolverOptions{.engine = Engine::kSparse}; }

// largest relative difference of q'', Qc, lambda seen by expect_same since the last report
double g_worst = 0.0;
void report_worst(const char* what) {
  std::printf(
      "    [%s] largest relative difference sparse vs dense (q'', Qc, Qc_ideal, lambda): "
      "%.1e\n",
      what, g_worst);
  g_worst = 0.0;
}

// every result of one evaluation, sparse against dense
void expect_same(const System& sys, const Eigen::Ref<const VectorXd>& q,
                 const Eigen::Ref<const VectorXd>& qd, double tol, Status expected = Status::kOk) {
  Workspace wd(sys, dense_options()), ws(sys, sparse_options());
  ASSERT_FALSE(wd.is_sparse());
  ASSERT_TRUE(ws.is_sparse());
  EXPECT_EQ(forward_dynamics(sys, wd, q, qd, 0.0), expected) << describe_status(sys, wd);
  EXPECT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), expected) << describe_status(sys, ws);
  EXPECT_EQ(ws.rank, wd.rank);
  EXPECT_EQ(ws.active_rows, wd.active_rows);
  EXPECT_NEAR(rel(ws.qdd, wd.qdd), 0.0, tol);
  EXPECT_NEAR(rel(ws.Qc, wd.Qc), 0.0, tol);
  EXPECT_NEAR(rel(ws.Qc_ideal, wd.Qc_ideal), 0.0, tol);
  EXPECT_NEAR(rel(ws.Qc_nonideal, wd.Qc_nonideal, wd.Qc.norm()), 0.0, tol);
  EXPECT_NEAR(rel(ws.lambda, wd.lambda), 0.0, tol);
  EXPECT_NEAR(rel(ws.lambda_nonideal, wd.lambda_nonideal, wd.lambda.norm()), 0.0, tol);
  EXPECT_NEAR(rel(ws.e, wd.e), 0.0, tol);
  g_worst = std::max({g_worst, rel(ws.qdd, wd.qdd), rel(ws.Qc, wd.Qc),
                      rel(ws.Qc_ideal, wd.Qc_ideal), rel(ws.lambda, wd.lambda)});
  if (sys.nonideal_count() > 0) {
    EXPECT_NEAR(rel(ws.shares, wd.shares), 0.0, tol);
  }
  const double scale = wd.Qc.norm() + wd.Q.norm();
  EXPECT_NEAR(ws.residuals.constraint, wd.residuals.constraint,
              expected == Status::kOk ? 1e-9 * scale : 1e-8 * wd.residuals.constraint);
  EXPECT_NEAR(ws.residuals.gauss, 0.0, 1e-9 * scale);
  EXPECT_NEAR(ws.residuals.virtual_work, 0.0, 1e-9 * scale);
  // the sparse A is the dense one
  MatrixXd A_sparse = MatrixXd(ws.sparse->matrix_A());
  EXPECT_NEAR((A_sparse - wd.A).norm(), 0.0, 1e-15 * wd.A.norm());
  // and no dense matrices were made
  EXPECT_EQ(ws.M.size(), 0);
  EXPECT_EQ(ws.A.size(), 0);
  EXPECT_EQ(ws.decomposition.coordinate_count(), 0);
}

TEST(SparseEngine, RandomBlockSystemsEqualDense) {
  for (unsigned seed = 1; seed <= 12; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const RandomSparse p = random_sparse(seed, 6 + seed, 4 + seed / 2, false);
    expect_same(p.sys(), p.q, p.qd, 1e-10);
  }
  report_worst("random, independent");
}

TEST(SparseEngine, RedundantRowsGiveTheDenseMinimumNormAnswer) {
  for (unsigned seed = 1; seed <= 12; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const RandomSparse p = random_sparse(100 + seed, 8 + seed, 5 + seed / 2, true);
    Workspace ws(p.sys(), sparse_options());
    ASSERT_EQ(forward_dynamics(p.sys(), ws, p.q, p.qd, 0.0), Status::kOk)
        << describe_status(p.sys(), ws);
    // the rank drop counts the redundant rows (when the random rows are independent otherwise)
    EXPECT_LE(ws.rank, ws.active_rows - p.redundant);
    expect_same(p.sys(), p.q, p.qd, 1e-10);
  }
  report_worst("random, redundant");
}

TEST(SparseEngine, InconsistentConstraintsAreReportedLikeDense) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const RandomSparse p = random_sparse(200 + seed, 8, 5, true, true);
    expect_same(p.sys(), p.q, p.qd, 1e-9, Status::kInconsistentConstraints);
    Workspace ws(p.sys(), sparse_options());
    forward_dynamics(p.sys(), ws, p.q, p.qd, 0.0);
    EXPECT_NE(describe_status(p.sys(), ws).find("A q'' = b has no solution"), std::string::npos)
        << describe_status(p.sys(), ws);
  }
  report_worst("inconsistent");
}

std::vector<double> wavy_angles(Index N, double amplitude) {
  std::vector<double> phi;
  for (Index i = 0; i < N; ++i) {
    phi.push_back(-0.8 + 1.6 * double(i) / double(std::max<Index>(N - 1, 1)) +
                  amplitude * std::sin(1.7 * double(i)));
  }
  return phi;
}

TEST(SparseEngine, ClosedChainsEqualDense) {
  for (Index N : {3, 8, 20, 64}) {
    for (int closures : {1, 2, 3}) {
      SCOPED_TRACE("N = " + std::to_string(N) + ", closures " + std::to_string(closures));
      Chain c = closed_chain(wavy_angles(N, 0.3), closures, true);
      for (Index i = 0; i < c.qd.size(); ++i) c.qd[i] = 0.3 * std::sin(0.9 * double(i));
      expect_same(c.sys, c.q, c.qd, 1e-10);
      Workspace ws(c.sys, sparse_options());
      ASSERT_EQ(forward_dynamics(c.sys, ws, c.q, c.qd, 0.0), Status::kOk);
      EXPECT_EQ(ws.rank, 2 * N + 2);  // a closure more than one is redundant
    }
  }
  report_worst("closed chains");
}

TEST(SparseEngine, LaddersRedundantAlongLongLoopsEqualDense) {
  for (Index H : {4, 16, 64}) {
    SCOPED_TRACE("H = " + std::to_string(H));
    const Chain c = ladder(wavy_angles(H, 0.2));
    expect_same(c.sys, c.q, c.qd, 1e-10);
    Workspace ws(c.sys, sparse_options());
    ASSERT_EQ(forward_dynamics(c.sys, ws, c.q, c.qd, 0.0), Status::kOk);
    EXPECT_EQ(ws.rank, c.sys.constraint_rows() - 1);
  }
  report_worst("ladders");
  // long loops (N = 1024 bodies): the self-stress is still found (the dense engine's rank, and
  // a minimum-norm answer that satisfies the constraints)
  const Chain big = ladder(wavy_angles(512, 0.2));
  Workspace ws(big.sys, sparse_options());
  ASSERT_EQ(forward_dynamics(big.sys, ws, big.q, big.qd, 0.0), Status::kOk);
  EXPECT_EQ(ws.rank, big.sys.constraint_rows() - 1);
  EXPECT_NEAR(ws.residuals.constraint, 0.0, 1e-12 * ws.Qc.norm());
}

TEST(SparseEngine, SharesOfARedundantLoopSumToTheIdealForce) {
  Chain c = closed_chain(wavy_angles(10, 0.2), 2, true);
  Workspace ws(c.sys, sparse_options());
  ASSERT_EQ(forward_dynamics(c.sys, ws, c.q, c.qd, 0.0), Status::kOk);
  EXPECT_NEAR(rel(ws.shares.rowwise().sum(), ws.Qc_ideal), 0.0, 1e-12);
  // the two identical closures carry the same (minimum-norm) multipliers
  const Index a = c.sys.constraint_index("close0"), b = c.sys.constraint_index("close1");
  EXPECT_NEAR(rel(ws.lambda_of(c.sys, a), ws.lambda_of(c.sys, b)), 0.0, 1e-10);
}

TEST(SparseEngine, ProjectionEqualsDense) {
  Chain c = closed_chain(wavy_angles(12, 0.25), 2);
  // perturb the consistent state
  VectorXd q = c.q, qd = c.qd;
  for (Index i = 0; i < q.size(); ++i) {
    q[i] += 1e-3 * std::sin(2.3 * double(i));
    qd[i] += 1e-2 * std::cos(1.1 * double(i));
  }
  VectorXd qs = q, qds = qd;
  Workspace wd(c.sys, dense_options()), ws(c.sys, sparse_options());
  const ProjectionResult pd = project_positions(c.sys, wd, q, 0.0);
  const ProjectionResult ps = project_positions(c.sys, ws, qs, 0.0);
  EXPECT_TRUE(pd.converged);
  EXPECT_TRUE(ps.converged);
  EXPECT_EQ(pd.iterations, ps.iterations);
  EXPECT_NEAR(rel(qs, q), 0.0, 1e-12);
  const ProjectionResult vd = project_velocities(c.sys, wd, q, qd, 0.0);
  const ProjectionResult vs = project_velocities(c.sys, ws, qs, qds, 0.0);
  EXPECT_TRUE(vd.converged);
  EXPECT_TRUE(vs.converged);
  EXPECT_NEAR(rel(qds, qd), 0.0, 1e-10);
}

TEST(SparseEngine, SimulationEqualsDense) {
  Chain c = closed_chain(wavy_angles(10, 0.3), 2, true);
  SimulationOptions o;
  o.integrator = Integrator::kRK4;
  o.step = 1e-3;
  o.t_end = 0.3;
  o.output_every = 0.1;
  o.solver.engine = Engine::kDense;
  const Trajectory td = simulate(c.sys, c.q, c.qd, o);
  o.solver.engine = Engine::kSparse;
  const Trajectory ts = simulate(c.sys, c.q, c.qd, o);
  ASSERT_EQ(td.stats.status, Status::kOk) << td.stats.message;
  ASSERT_EQ(ts.stats.status, Status::kOk) << ts.stats.message;
  ASSERT_EQ(td.q.size(), ts.q.size());
  const Eigen::Map<const VectorXd> qd_(td.q.data(), Index(td.q.size()));
  const Eigen::Map<const VectorXd> qs_(ts.q.data(), Index(ts.q.size()));
  EXPECT_NEAR(rel(qs_, qd_), 0.0, 1e-10);
  const Eigen::Map<const VectorXd> ld(td.lambda.data(), Index(td.lambda.size()));
  const Eigen::Map<const VectorXd> ls(ts.lambda.data(), Index(ts.lambda.size()));
  EXPECT_NEAR(rel(ls, ld), 0.0, 1e-9);
  EXPECT_NEAR(ts.energy.back(), td.energy.back(), 1e-9 * std::abs(td.energy.back()));
  EXPECT_LT(ts.stats.max_position_violation, 1e-11);
  EXPECT_EQ(ts.stats.projections, td.stats.projections);
}

TEST(SparseEngine, CoulombStickSlipEqualsDense) {
  // a block of 3 particles (one mass block each) on a rough floor y = 0, pulled by a force that
  // grows in time: it sticks, then slips; the floor is a local constraint, the stick constraint
  // (made by coulomb_friction) dense
  SystemBuilder b({"x", "y", "u", "v", "w", "z"});
  b.mass_block(0, MatrixXd::Identity(2, 2))
      .mass_block(2, 2.0 * MatrixXd::Identity(2, 2))
      .mass_block(4, 3.0 * MatrixXd::Identity(2, 2));
  b.forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double t,
              Eigen::Ref<VectorXd> Q) { Q << 6.0 * t, -9.81, 0.0, -2 * 9.81, 0.0, -3 * 9.81; });
  b.add(Constraint("floor", ConstraintKind::kHolonomic, 1,
                   std::make_shared<LocalLinear>(std::vector<Index>{1}, MatrixXd::Ones(1, 1),
                                                 VectorXd::Zero(1))));
  // the others hang on rigid links (local rows)
  b.add(Constraint("link", ConstraintKind::kAcceleration, 2,
                   std::make_shared<LocalLinear>(std::vector<Index>{2, 3, 4, 5},
                                                 MatrixXd::Identity(2, 4), VectorXd::Zero(2))));
  b.add(coulomb_friction({.constraint = "floor", .mu = 0.3, .coordinates = {0}}));
  const System sys = b.build();
  VectorXd q = VectorXd::Zero(6), qd = VectorXd::Zero(6);
  SimulationOptions o;
  o.integrator = Integrator::kRK4;
  o.step = 1e-3;
  o.t_end = 1.0;
  o.output_every = 0.25;
  o.solver.engine = Engine::kDense;
  const Trajectory td = simulate(sys, q, qd, o);
  o.solver.engine = Engine::kSparse;
  const Trajectory ts = simulate(sys, q, qd, o);
  ASSERT_EQ(td.stats.status, Status::kOk) << td.stats.message;
  ASSERT_EQ(ts.stats.status, Status::kOk) << ts.stats.message;
  EXPECT_EQ(ts.stats.events, td.stats.events);
  EXPECT_GE(ts.stats.events, 1);
  const Eigen::Map<const VectorXd> qd_(td.q.data(), Index(td.q.size()));
  const Eigen::Map<const VectorXd> qs_(ts.q.data(), Index(ts.q.size()));
  EXPECT_NEAR(rel(qs_, qd_), 0.0, 1e-9);
}

TEST(SparseEngine, ChoiceOfEngine) {
  const Chain small = closed_chain(wavy_angles(4, 0.1), 1);      // n = 12, m = 10
  const Chain redundant = closed_chain(wavy_angles(4, 0.1), 3);  // n = 12, m = 14 > n
  const Chain large = closed_chain(wavy_angles(40, 0.1), 1);     // n = 120
  const Chain at = closed_chain(wavy_angles(8, 0.1), 1);         // n = 24, the default threshold
  EXPECT_TRUE(Workspace(at.sys).is_sparse());
  // below the threshold: sparse for two or more bodies with m <= n (measured cheaper, issue #29
  // item 5); dense for more rows than coordinates and for a single body
  EXPECT_TRUE(Workspace(closed_chain(wavy_angles(7, 0.1), 1).sys).is_sparse());
  EXPECT_TRUE(Workspace(small.sys).is_sparse());
  EXPECT_FALSE(Workspace(redundant.sys).is_sparse());
  EXPECT_FALSE(Workspace(closed_chain(wavy_angles(1, 0.1), 0).sys).is_sparse());
  EXPECT_TRUE(Workspace(large.sys).is_sparse());
  EXPECT_FALSE(Workspace(large.sys, dense_options()).is_sparse());
  EXPECT_TRUE(Workspace(redundant.sys, sparse_options()).is_sparse());
  EXPECT_TRUE(Workspace(redundant.sys, SolverOptions{.sparse_threshold = 12}).is_sparse());
  EXPECT_FALSE(Workspace(redundant.sys, SolverOptions{.sparse_threshold = 13}).is_sparse());
  // the textbook algorithm is dense
  EXPECT_FALSE(Workspace(large.sys, SolverOptions{.algorithm = Algorithm::kTextbook}).is_sparse());
  const auto error_of = [](const System& sys, const SolverOptions& o) -> std::string {
    try {
      Workspace ws(sys, o);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  // more than kAutoMaxDenseRows rows without columns(): dense
  const auto with_dense_rows = [](Index rows) {
    SystemBuilder b(30);
    for (Index i = 0; i < 10; ++i) b.mass_block(3 * i, MatrixXd::Identity(3, 3));
    b.add(acceleration_constraint(
        "rows", rows,
        [](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
           Eigen::Ref<MatrixXd> A, Eigen::Ref<VectorXd> rhs) {
          A.setIdentity();
          rhs.setZero();
        }));
    return b.build();
  };
  EXPECT_TRUE(Workspace(with_dense_rows(kAutoMaxDenseRows)).is_sparse());
  EXPECT_FALSE(Workspace(with_dense_rows(kAutoMaxDenseRows + 1)).is_sparse());
  const System dense_mass = SystemBuilder(40).mass_matrix(MatrixXd::Identity(40, 40)).build();
  EXPECT_FALSE(Workspace(dense_mass).is_sparse());  // a dense M stays dense
  EXPECT_NE(error_of(dense_mass, sparse_options()).find("Engine::kSparse needs a block-diagonal"),
            std::string::npos);
  EXPECT_NE(error_of(large.sys,
                     SolverOptions{.algorithm = Algorithm::kTextbook, .engine = Engine::kSparse})
                .find("Algorithm::kDefault only"),
            std::string::npos);
  EXPECT_NE(error_of(large.sys, SolverOptions{.sparse_rank_threshold = 0.0})
                .find("sparse_rank_threshold must lie in (0, 1)"),
            std::string::npos);
  EXPECT_NE(error_of(large.sys, SolverOptions{.sparse_threshold = -1})
                .find("sparse_threshold must be >= 0"),
            std::string::npos);
}

TEST(SparseEngine, MassNotPositiveDefiniteAndNaNAreReported) {
  SystemBuilder b(4);
  b.mass_block(0, MatrixXd::Identity(2, 2))
      .mass_block(2, 2, [](const Eigen::Ref<const VectorXd>& q, double, Eigen::Ref<MatrixXd> M) {
        M << q[0], 0.0, 0.0, 1.0;
      });
  const System sys = b.build();
  Workspace ws(sys, sparse_options());
  VectorXd q = VectorXd::Zero(4), qd = VectorXd::Zero(4);
  q[0] = -1.0;  // indefinite
  EXPECT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kMassNotPositiveDefinite);
  q[0] = 0.0;  // singular, and no constraint determines coordinate 2
  EXPECT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kMotionUndetermined);
  EXPECT_NE(describe_status(sys, ws).find("the coordinates 'q2'"), std::string::npos)
      << describe_status(sys, ws);
  q[0] = 1.0;
  EXPECT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
  q[0] = std::nan("");
  EXPECT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kNonFiniteInput);
}

TEST(SparseDecomposition, PatternIsLinearInTheNumberOfBodies) {
  // nnz(A) and nnz(L_G) per body stay bounded as the chain grows (no fill from the ordering)
  double per_body_small = 0.0;
  for (Index N : {16, 256, 1024}) {
    const Chain c = closed_chain(wavy_angles(N, 0.1), 1);
    const SparseDecomposition d(c.sys);
    const double per_body = double(d.nonzeros() + d.factor_nonzeros()) / double(N);
    if (N == 16) per_body_small = per_body;
    EXPECT_LE(per_body, 1.2 * per_body_small) << "N = " << N;
  }
}

// P1's body formulation: two point masses (inertia 1e-9 kg m² about them) on massless 1 m rods,
// a double pendulum at the angles th0, th1, with a second copy of the first pin when `duplicate`.
// The second row of each pin is nearly dependent on the first in the metric of M (its pivot of
// G is ~1e-9 G_kk): suspicious. The first pin's rows are coupled to nothing before them, so its
// pivot's roundoff is a few eps G_kk and it needs no recheck; the second pin's pivot comes after
// those ill-conditioned rows and is rechecked in the space of W.
System point_mass_pendulum(bool duplicate) {
  SystemBuilder b(6);
  for (Index i = 0; i < 2; ++i) {
    b.mass_block(3 * i, Eigen::Vector3d(1.0, 1.0, 1e-9).asDiagonal().toDenseMatrix());
  }
  b.forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
              Eigen::Ref<VectorXd> Q) {
    Q.setZero();
    Q[1] = Q[4] = -9.81;
  });
  const Eigen::Vector2d rod(-1.0, 0.0), origin(0.0, 0.0);
  b.add(revolute("pin0", 0, rod, -1, origin));
  b.add(revolute("pin1", 1, rod, 0, origin));
  if (duplicate) b.add(revolute("pin0 again", 0, rod, -1, origin));
  return b.build();
}

TEST(SparseDecomposition, PivotsWithASmallKnownRoundoffAreNotRechecked) {
  const double th0 = 0.7, th1 = -0.4;
  VectorXd q(6), qd(6);
  q << std::cos(th0), std::sin(th0), th0, std::cos(th0) + std::cos(th1),
      std::sin(th0) + std::sin(th1), th1;
  // both bodies turning about the ground pin at 0.3 rad/s as one
  qd << -0.3 * std::sin(th0), 0.3 * std::cos(th0), 0.3, -0.3 * (std::sin(th0) + std::sin(th1)),
      0.3 * (std::cos(th0) + std::cos(th1)), 0.3;
  {
    const System sys = point_mass_pendulum(false);
    Workspace ws(sys, sparse_options());
    ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk) << describe_status(sys, ws);
    EXPECT_EQ(ws.rank, 4);
    // one recheck (the second pin's) where every suspicious pivot had one before
    EXPECT_EQ(ws.sparse->rechecked_pivots(), 1);
    // κ(G) ≈ 1e9 (the pivots 1e-9 G_kk): the engines' multipliers agree to about eps κ(G)
    expect_same(sys, q, qd, 1e-6);
  }
  {
    // a duplicated first pin is still found dependent: its pivots are roundoff, far below the
    // margin that would spare them the threshold test
    const System sys = point_mass_pendulum(true);
    Workspace ws(sys, sparse_options());
    ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk) << describe_status(sys, ws);
    EXPECT_EQ(ws.active_rows, 6);
    EXPECT_EQ(ws.rank, 4);
    expect_same(sys, q, qd, 1e-6);
  }
  report_worst("point masses on rods");
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
