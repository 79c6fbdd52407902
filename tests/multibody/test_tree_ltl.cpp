// SPDX-License-Identifier: BSD-3-Clause
// A tree's M factorized along its branches (linalg/tree_ltl.cpp, FundamentalDecomposition with
// a mass tree, SystemBuilder::mass_tree): the factor reproduces M with no fill-in, and every
// product of the fundamental equation equals the dense Cholesky path's to 1e-12 on the Panda
// and on the floating-base humanoid; bad trees are refused with their coordinate named.
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "linalg/tree_ltl.hpp"
#include "ukdyn/core/autodiff.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/linalg/decomposition.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree {
namespace UKDYN_TEST_FILE {

const std::string kPanda = std::string(UKDYN_TEST_DATA_DIR) + "/panda_arm.urdf";
const std::string kHumanoid = std::string(UKDYN_EXAMPLES_DIR) + "/../robots/humanoid.urdf";

// ‖x − y‖ / ‖y‖ (‖x‖ when y = 0)
double relative(const VectorXd& x, const VectorXd& y) {
  const double s = y.norm();
  return s > 0.0 ? (x - y).norm() / s : x.norm();
}

// a random state of the tree (unit quaternions for floating links; u' ⊥ u)
void random_state(const Tree& tree, int seed, VectorXd& q, VectorXd& qd) {
  std::srand(unsigned(seed));
  const Index n = tree.coordinate_count();
  q = VectorXd::Random(n);
  qd = VectorXd::Random(n);
  for (Index i : tree.floating_links()) {
    const Index o = tree.offset(i) + 3;
    q.segment<4>(o).normalize();
    const Eigen::Vector4d u = q.segment<4>(o);
    qd.segment<4>(o) -= u * u.dot(qd.segment<4>(o));
  }
}

// whether a is j or an ancestor of j in the coordinate tree
bool on_branch(const std::vector<Index>& parent, Index a, Index j) {
  for (; j >= 0; j = parent[std::size_t(j)]) {
    if (j == a) return true;
  }
  return false;
}

// the system's mass tree, or the chain 0 ← 1 ← … ← n−1 of an unbranched tree (whose system
// leaves it to the dense Cholesky)
std::vector<Index> mass_tree_of(const System& sys) {
  std::vector<Index> parent = sys.mass_tree();
  if (parent.empty()) {
    for (Index k = 0; k < sys.coordinate_count(); ++k) parent.push_back(k - 1);
  }
  return parent;
}

// the tree's factor against M and against the dense decomposition of the same M and A
void check_decomposition(const std::string& file) {
  const Tree tree = load_urdf(file);
  const System sys = make_system(tree);
  const Index n = sys.coordinate_count(), m = 5;
  const std::vector<Index> parent = mass_tree_of(sys);
  Workspace ws(sys);  // (the system's M callable needs the workspace's scratch)
  MatrixXd M(n, n);
  FundamentalDecomposition dense(n, m), sparse(n, m);
  sparse.set_mass_tree(parent);
  for (int seed = 1; seed <= 5; ++seed) {
    VectorXd q, qd;
    random_state(tree, seed, q, qd);
    sys.mass_matrix(q, 0.0, ws.callables.get(), M);
    // M lies in the tree's pattern: M_ij = 0 off the branches
    for (Index i = 0; i < n; ++i) {
      for (Index j = 0; j < i; ++j) {
        if (!on_branch(parent, j, i)) {
          EXPECT_EQ(M(i, j), 0.0) << i << ", " << j;
        }
      }
    }
    ASSERT_EQ(dense.compute_mass(M).info(), Eigen::Success);
    ASSERT_EQ(sparse.compute_mass(M).info(), Eigen::Success);
    // M = Lᵀ L from the lower triangle, and L_ij = 0 off the branches (no fill-in)
    const MatrixXd L = sparse.matrix_llt().triangularView<Eigen::Lower>();
    EXPECT_LE((L.transpose() * L - M).norm(), 1e-13 * M.norm());
    for (Index i = 0; i < n; ++i) {
      for (Index j = 0; j < i; ++j) {
        if (!on_branch(parent, j, i)) {
          EXPECT_EQ(L(i, j), 0.0) << i << ", " << j;
        }
      }
    }
    // M⁻¹ f
    const VectorXd f = VectorXd::Random(n);
    VectorXd x_dense(n), x_tree(n);
    dense.solve_mass(f, x_dense);
    sparse.solve_mass(f, x_tree);
    EXPECT_LE(relative(x_tree, x_dense), 1e-12);
    EXPECT_LE((M * x_tree - f).norm(), 1e-13 * M.norm() * x_tree.norm());  // backward error
    // A of rank 4 (its last row the sum of two others): the ideal and non-ideal parts
    MatrixXd A = MatrixXd::Random(m, n);
    A.row(4) = A.row(0) + A.row(2);
    dense.compute_constraints(A);
    sparse.compute_constraints(A);
    EXPECT_EQ(dense.rank(), 4);
    EXPECT_EQ(sparse.rank(), 4);
    const VectorXd e = A * VectorXd::Random(n), C = VectorXd::Random(n);
    VectorXd d1(n), Q1(n), l1(m), d2(n), Q2(n), l2(m);
    dense.solve_ideal(e, d1, Q1, l1);
    sparse.solve_ideal(e, d2, Q2, l2);
    EXPECT_LE(relative(d2, d1), 1e-12);
    EXPECT_LE(relative(Q2, Q1), 1e-12);
    EXPECT_LE(relative(l2, l1), 1e-12);
    EXPECT_LE(relative(A * d2, e), 1e-12);  // A (q'' − a) = e
    dense.project_nonideal(C, d1, Q1, l1);
    sparse.project_nonideal(C, d2, Q2, l2);
    EXPECT_LE(relative(d2, d1), 1e-12);
    EXPECT_LE(relative(Q2, Q1), 1e-12);
    EXPECT_LE(relative(l2, l1), 1e-12);
    // W = A F⁻ᵀ: the same singular values for both factors (F = L resp. Lᵀ)
    MatrixXd W1 = A.transpose(), W2 = A.transpose();
    dense.solve_factor(W1);
    sparse.solve_factor(W2);
    const VectorXd s1 = Eigen::JacobiSVD<MatrixXd>(W1).singularValues();
    const VectorXd s2 = Eigen::JacobiSVD<MatrixXd>(W2).singularValues();
    EXPECT_LE(relative(s2.head(4), s1.head(4)), 1e-12);
  }
}

TEST(TreeLtl, FactorAndProductsEqualTheDenseCholeskyOnThePanda) { check_decomposition(kPanda); }

TEST(TreeLtl, FactorAndProductsEqualTheDenseCholeskyOnTheHumanoid) {
  check_decomposition(kHumanoid);
}

// the coordinate tree of a floating base and a branch: the base's 7 coordinates a chain, each
// limb's first joint below the base's last coordinate
// The LTL as Featherstone's algorithm 6.3 walks it, along the lower triangle (the factorization
// before the packed rows): the reference for the packed one, which must give the same bits.
bool walked_ltl(MatrixXd& H, const std::vector<Index>& parent) {
  const Index n = H.rows();
  for (Index k = n - 1; k >= 0; --k) {
    if (!(H(k, k) > 0.0)) return false;
    const double d = std::sqrt(H(k, k)), r = 1.0 / d;
    H(k, k) = d;
    for (Index i = parent[std::size_t(k)]; i >= 0; i = parent[std::size_t(i)]) H(k, i) *= r;
    for (Index i = parent[std::size_t(k)]; i >= 0; i = parent[std::size_t(i)]) {
      const double a = H(k, i);
      for (Index j = i; j >= 0; j = parent[std::size_t(j)]) H(i, j) -= a * H(k, j);
    }
  }
  return true;
}

// the packed factorization (rows of L packed in the upper triangle) against the walk, bit for
// bit, on the humanoid's M (a deep branched tree: base, legs, arms) and the Panda's (a chain),
// and a random tree; a matrix that is not positive definite refused by both
TEST(TreeLtl, PackedRowsGiveTheBitsOfTheWalk) {
  std::vector<std::pair<MatrixXd, std::vector<Index>>> cases;
  for (const std::string& file : {kHumanoid, kPanda}) {
    const Tree tree = load_urdf(file);
    const System sys = make_system(tree);
    Workspace ws(sys);
    VectorXd q, qd;
    random_state(tree, 7, q, qd);
    MatrixXd M(sys.coordinate_count(), sys.coordinate_count());
    sys.mass_matrix(q, 0.0, ws.callables.get(), M);
    cases.emplace_back(M, mass_tree_of(sys));
  }
  // a random tree of 40 coordinates and an M in its pattern: Bᵀ B + I, B in the pattern of L
  std::srand(3u);
  std::vector<Index> parent{-1};
  for (Index k = 1; k < 40; ++k) parent.push_back(std::rand() % 4 == 0 ? -1 : std::rand() % k);
  MatrixXd B = MatrixXd::Zero(40, 40);
  for (Index k = 0; k < 40; ++k) {
    for (Index j = k; j >= 0; j = parent[std::size_t(j)]) B(k, j) = VectorXd::Random(1)[0];
  }
  cases.emplace_back(B.transpose() * B + MatrixXd::Identity(40, 40), parent);
  for (auto& [M, tree_parent] : cases) {
    const Index n = M.rows();
    MatrixXd packed = M, walked = M;
    VectorXd inv(n);
    ASSERT_TRUE(detail::tree_ltl_in_place(packed.data(), tree_parent.data(), inv.data(), n));
    ASSERT_TRUE(walked_ltl(walked, tree_parent));
    const MatrixXd Lp = packed.triangularView<Eigen::Lower>(),
                   Lw = walked.triangularView<Eigen::Lower>();
    EXPECT_EQ(Lp, Lw);
    EXPECT_EQ(inv, Lw.diagonal().cwiseInverse());
    EXPECT_LE((Lp.transpose() * Lp - M).norm(), 1e-13 * M.norm());
    // the solves and the product on the packed rows: the bits of the walks along Lw
    const VectorXd x = VectorXd::LinSpaced(n, -1.0, 2.0);
    VectorXd lt = x, l = x, mult(n), lt_ref = x, l_ref = x, mult_ref(n);
    detail::tree_lt_solve(packed.data(), tree_parent.data(), inv.data(), lt.data(), n);
    detail::tree_l_solve(packed.data(), tree_parent.data(), inv.data(), l.data(), n);
    detail::tree_lt_multiply(packed.data(), tree_parent.data(), x.data(), mult.data(), n);
    // (a reference, not the structured binding itself: clang 14 cannot capture one)
    const auto& parents = tree_parent;
    const auto up = [&](Index j) { return parents[std::size_t(j)]; };
    for (Index k = n - 1; k >= 0; --k) {
      lt_ref[k] *= inv[k];
      for (Index j = up(k); j >= 0; j = up(j)) lt_ref[j] -= Lw(k, j) * lt_ref[k];
    }
    for (Index k = 0; k < n; ++k) {
      for (Index j = up(k); j >= 0; j = up(j)) l_ref[k] -= Lw(k, j) * l_ref[j];
      l_ref[k] *= inv[k];
    }
    for (Index k = 0; k < n; ++k) mult_ref[k] = Lw(k, k) * x[k];
    for (Index k = 0; k < n; ++k) {
      for (Index j = up(k); j >= 0; j = up(j)) mult_ref[j] += Lw(k, j) * x[k];
    }
    EXPECT_EQ(lt, lt_ref);
    EXPECT_EQ(l, l_ref);
    EXPECT_EQ(mult, mult_ref);
    EXPECT_LE((Lp.transpose() * lt - x).norm(), 1e-12 * x.norm());
    // and a pivot that is not positive: refused
    MatrixXd bad = M;
    bad(n / 2, n / 2) = -1.0;
    MatrixXd bad_walked = bad;
    EXPECT_FALSE(detail::tree_ltl_in_place(bad.data(), tree_parent.data(), inv.data(), n));
    EXPECT_FALSE(walked_ltl(bad_walked, tree_parent));
  }
}

TEST(TreeLtl, CoordinateTreeFollowsTheLinks) {
  const Tree tree = load_urdf(kHumanoid);
  const System sys = make_system(tree);
  const std::vector<Index>& parent = sys.mass_tree();
  ASSERT_EQ(Index(parent.size()), tree.coordinate_count());
  EXPECT_EQ(parent[0], -1);
  for (Index k = 1; k < 7; ++k) EXPECT_EQ(parent[std::size_t(k)], k - 1);
  Index below_base = 0;
  for (std::size_t k = 7; k < parent.size(); ++k) below_base += parent[k] == 6;
  EXPECT_GE(below_base, 3);  // legs, arms and torso start at the pelvis
  // the arm is a chain: its M is dense, left to the dense Cholesky
  EXPECT_TRUE(make_system(load_urdf(kPanda)).mass_tree().empty());
}

// forward dynamics with the tree's factor against the same system factorized densely
void check_forward(const std::string& file, bool closure) {
  const Tree tree = load_urdf(file);
  SystemBuilder sb = system_builder(tree);
  if (closure) {
    const Index tool = tree.link_index("panda_tool"), l3 = tree.link_index("panda_link3");
    sb.add(
        distance_constraint(tree, "rod", {tool, Vector3d::Zero()}, {l3, Vector3d(0.1, 0, 0)}, 0.5));
  }
  sb.mass_tree(mass_tree_of(sb.build()));  // (the arm's chain given explicitly)
  const System with_tree = sb.build();
  const System dense = sb.mass_tree({}).build();
  ASSERT_FALSE(with_tree.mass_tree().empty());
  ASSERT_TRUE(dense.mass_tree().empty());
  SolverOptions o;
  o.engine = Engine::kDense;
  Workspace w1(with_tree, o), w2(dense, o);
  for (int seed = 11; seed <= 14; ++seed) {
    VectorXd q, qd;
    random_state(tree, seed, q, qd);
    ASSERT_EQ(forward_dynamics(with_tree, w1, q, qd, 0.0), Status::kOk);
    ASSERT_EQ(forward_dynamics(dense, w2, q, qd, 0.0), Status::kOk);
    EXPECT_LE(relative(w1.qdd, w2.qdd), 1e-12);
    EXPECT_LE(relative(w1.a, w2.a), 1e-12);
    // the forces against the problem's force scale ‖Q‖ + ‖Qc‖ (the humanoid's quaternion rows,
    // whose M is completed by the tree's system, carry a force of rounding size only), the
    // multipliers as their forces Aᵀ lambda
    const double force = w2.Q.norm() + w2.Qc_ideal.norm();
    EXPECT_LE((w1.Qc_ideal - w2.Qc_ideal).norm(), 1e-12 * force);
    EXPECT_LE((w1.lambda - w2.lambda).norm() * w2.A.norm(), 1e-12 * force);
    EXPECT_GT(w1.qdd.norm(), 0.1);
    if (w1.rows() > 0) {
      // the constraints hold: A q'' = b
      EXPECT_NEAR((w1.A * w1.qdd - w1.b).norm(), 0.0, 1e-10 * (1.0 + w1.b.norm()));
    }
    // the rod pulls (the humanoid's quaternion rows carry no force: it may round to 0 exactly)
    if (closure) {
      EXPECT_GT(w1.Qc_ideal.norm(), 1e-3 * force);
    }
  }
}

TEST(TreeLtl, ForwardDynamicsEqualsTheDensePathOnThePanda) { check_forward(kPanda, false); }

TEST(TreeLtl, ForwardDynamicsEqualsTheDensePathWithALoopClosure) { check_forward(kPanda, true); }

TEST(TreeLtl, ForwardDynamicsEqualsTheDensePathOnTheHumanoid) { check_forward(kHumanoid, false); }

// a singular M (a massless second coordinate) with a mass tree: the engine completes it with
// the constraint densely. q'' = (Q_0 / m, b) with the constraint q''_1 = b (q_1 = t² / 2 · 3)
TEST(TreeLtl, SingularMassFallsBackToTheDenseCompletion) {
  MatrixXd M(2, 2);
  M << 2.0, 0.0, 0.0, 0.0;
  const System sys =
      SystemBuilder(2)
          .mass_matrix(
              [M](const Eigen::Ref<const VectorXd>&, double, Eigen::Ref<MatrixXd> out) { out = M; })
          .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) { Q << 5.0, 0.0; })
          .mass_tree({-1, 0})
          .add(holonomic("drive", 1,
                         [](const auto& q, const auto& t, auto& e) { e[0] = q[1] - 1.5 * t * t; }))
          .build();
  SolverOptions o;
  o.engine = Engine::kDense;
  Workspace ws(sys, o);
  const VectorXd q = VectorXd::Zero(2), qd = VectorXd::Zero(2);
  ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
  EXPECT_NEAR(ws.qdd[0], 2.5, 1e-12);
  EXPECT_NEAR(ws.qdd[1], 3.0, 1e-12);
  ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.1), Status::kOk);
  EXPECT_NEAR(ws.qdd[0], 2.5, 1e-12);
  EXPECT_NEAR(ws.qdd[1], 3.0, 1e-12);
}

// the dense engine checks a mass tree's M over its pattern (the diagonal and each coordinate's
// pairs with its ancestors, the entries the factorization reads): an asymmetric pair or a NaN
// there is reported as for a dense M; the scale of the symmetry test is the largest entry
TEST(TreeLtl, MassChecksReadTheTreesPattern) {
  // coordinates 0 ← 1, 0 ← 2 (1 and 2 on different branches: M_12 = 0)
  const auto run = [](const MatrixXd& M) {
    const System sys =
        SystemBuilder(3)
            .mass_matrix([M](const Eigen::Ref<const VectorXd>&, double, Eigen::Ref<MatrixXd> out) {
              out = M;
            })
            .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                       Eigen::Ref<VectorXd> Q) { Q << 1.0, 2.0, 3.0; })
            .mass_tree({-1, 0, 0})
            .build();
    SolverOptions o;
    o.engine = Engine::kDense;
    Workspace ws(sys, o);
    const Status s = forward_dynamics(sys, ws, VectorXd::Zero(3), VectorXd::Zero(3), 0.0);
    return std::make_pair(s, std::string(ws.failed_quantity) + " ");
  };
  MatrixXd M(3, 3);
  M << 4.0, 1.0, 2.0, 1.0, 3.0, 0.0, 2.0, 0.0, 5.0;
  {
    const auto [s, what] = run(M);
    EXPECT_EQ(s, Status::kOk) << what;
  }
  // q'' = M⁻¹ Q, against Eigen's LLT
  {
    const System sys =
        SystemBuilder(3)
            .mass_matrix(M)
            .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                       Eigen::Ref<VectorXd> Q) { Q << 1.0, 2.0, 3.0; })
            .mass_tree({-1, 0, 0})
            .build();
    SolverOptions o;
    o.engine = Engine::kDense;
    Workspace ws(sys, o);
    ASSERT_EQ(forward_dynamics(sys, ws, VectorXd::Zero(3), VectorXd::Zero(3), 0.0), Status::kOk);
    const VectorXd expected = M.llt().solve(Vector3d(1.0, 2.0, 3.0));
    EXPECT_LT((ws.qdd - expected).norm(), 1e-15 * expected.norm());
  }
  // an asymmetric pair on a branch (M_20 against M_02): 1e-11 of the largest entry, 5
  MatrixXd A = M;
  A(2, 0) += 5e-11;
  EXPECT_EQ(run(A).first, Status::kMassNotSymmetric) << run(A).second;
  // below the tolerance (1e-12 · 5)
  A = M;
  A(2, 0) += 4e-12;
  EXPECT_EQ(run(A).first, Status::kOk) << run(A).second;
  // a NaN on the diagonal and above it on a branch
  for (const auto& [i, j] : {std::pair<Index, Index>{1, 1}, {0, 2}}) {
    A = M;
    A(i, j) = std::numeric_limits<double>::quiet_NaN();
    const auto [s, what] = run(A);
    EXPECT_EQ(s, Status::kNonFiniteInput) << i << j;
    EXPECT_EQ(what.substr(0, 2), "M ") << what;
  }
}

TEST(TreeLtl, BadTreesAreRefusedNamingTheCoordinate) {
  FundamentalDecomposition d(3, 1);
  try {
    d.set_mass_tree({-1, 0});
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("3 coordinates (or none), got 2"), std::string::npos)
        << e.what();
  }
  try {
    d.set_mass_tree({-1, 2, 0});
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("parent of coordinate 1 is 2"), std::string::npos)
        << e.what();
  }
  try {
    (void)SystemBuilder(2).mass_matrix(MatrixXd::Identity(2, 2)).mass_tree({-1, 1}).build();
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("mass_tree gives coordinate 1 the parent 1"),
              std::string::npos)
        << e.what();
  }
  try {
    (void)SystemBuilder(2).mass_matrix(MatrixXd::Identity(2, 2)).mass_tree({-1}).build();
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("mass_tree gives 1 parents, the system has 2"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn::tree
