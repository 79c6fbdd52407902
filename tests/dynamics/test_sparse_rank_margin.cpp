// SPDX-License-Identifier: BSD-3-Clause
// The sparse engine's rank margin (SparseDecomposition::rank_margin, issue #29 item 5): the
// integrators read Workspace::rank_margin to project their stages near a singular configuration
// (docs/simulation.md), and the sparse engine reported NaN. Now it reports min over the kept rows
// of (d_k / G_kk)^{1/2}, the sine of the angle between a row of W = A L⁻ᵀ and the rows eliminated
// before it. Checked on two body models that lose rank at a dead centre, against
//  * the theory: with unit rows, d_k / G_kk = 1 / [(G_{1:k})⁻¹]_kk >= λ_min(G_{1:k}) >=
//    λ_min(G) (Cauchy interlacing), so the margin is at least σ_min of the row-normalized W,
//    computed here by an SVD (an independent method); and it falls linearly with the distance to
//    the dead centre, as σ_min does;
//  * the dense engine's margin (σ_r / σ_1 of W itself, estimated by its pivoted QR): the same up
//    to a constant factor bounded by the spread of the rows' norms ρ = max‖w_i‖ / min‖w_i‖
//    (the dense one compares rows of different scales, this one each row with its own norm),
//    and both fall in the same proportion towards the dead centre.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/SVD>

#include <ukdyn/dynamics/forward.hpp>
#include <ukdyn/dynamics/workspace.hpp>
#include <ukdyn/modelfile/model.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

// An isosceles slider-crank (crank and rod of length 1, no drive): at crank angle th the slider
// is at x = 2 cos th. At th = π/2 the slider reaches the ground pin and the rod may also fold
// back about it: the rank of the 8 joint rows drops to 7 (a dead centre where two motions meet).
// Coordinates crank (x, y, θ), rod (x, y, θ), slider (x, y, θ).
const char* const kSliderCrank = R"(name: isosceles slider-crank
bodies:
  - {name: crank, type: planar, mass: 1, inertia: 1/12, position: [0, 0.5], angle: pi/2}
  - {name: rod, type: planar, mass: 2, inertia: 2/12, position: [0, 0.5], angle: -pi/2}
  - {name: slider, type: planar, mass: 0.5, inertia: 0.01, position: [0, 0]}
joints:
  - {name: pin, type: revolute, parent: ground, child: crank, parent_point: [0, 0],
     child_point: [-0.5, 0]}
  - {name: crank_rod, type: revolute, parent: crank, child: rod, parent_point: [0.5, 0],
     child_point: [-0.5, 0]}
  - {name: rod_slider, type: revolute, parent: rod, child: slider, parent_point: [0.5, 0]}
  - {name: slide, type: prismatic, parent: ground, child: slider}
forces:
  - {type: gravity, g: [0, -9.81]}
)";

VectorXd slider_crank_q(double th) {
  VectorXd q(9);
  q << 0.5 * std::cos(th), 0.5 * std::sin(th), th,  // crank
      1.5 * std::cos(th), 0.5 * std::sin(th), -th,  // rod, from the crank tip to the slider
      2.0 * std::cos(th), 0.0, 0.0;                 // slider
  return q;
}

// the double four-bar of the examples (bodies): cranks at th from the vertical, singular at π/2
VectorXd double_four_bar_q(double th) {
  VectorXd q(15);
  for (int k = 0; k < 3; ++k) {
    q.segment(3 * k, 3) << k + 0.5 * std::sin(th), 0.5 * std::cos(th), M_PI / 2 - th;
  }
  for (int k = 0; k < 2; ++k) {
    q.segment(9 + 3 * k, 3) << k + 0.5 + std::sin(th), std::cos(th), 0.0;
  }
  return q;
}

struct Margins {
  double sparse = 0.0, dense = 0.0;
  double sigma_min = 0.0;  // σ_min of the row-normalized W
  double spread = 0.0;     // ρ = max‖w_i‖ / min‖w_i‖
};

// both engines' margins at q (at rest), and σ_min of the row-normalized W by an SVD
Margins margins(const Model& m, const VectorXd& q) {
  SolverOptions so, d;
  so.engine = Engine::kSparse;
  d.engine = Engine::kDense;
  Workspace ws(m.system, so), wd(m.system, d);
  const VectorXd qd = VectorXd::Zero(q.size());
  EXPECT_EQ(forward_dynamics(m.system, ws, q, qd, 0.0), Status::kOk);
  EXPECT_EQ(forward_dynamics(m.system, wd, q, qd, 0.0), Status::kOk);
  EXPECT_TRUE(ws.is_sparse());
  EXPECT_FALSE(wd.is_sparse());
  EXPECT_EQ(ws.rank, wd.rank);
  // W = A L⁻ᵀ from the dense workspace's M and A, rows scaled to unit norm
  const Eigen::LLT<MatrixXd> llt(wd.M);
  MatrixXd W = llt.matrixL().solve(wd.A.transpose()).transpose();
  const VectorXd norms = W.rowwise().norm();
  for (Index i = 0; i < W.rows(); ++i) W.row(i) /= norms[i];
  const Eigen::JacobiSVD<MatrixXd> svd(W);
  return {ws.rank_margin, wd.rank_margin, svd.singularValues()[W.rows() - 1],
          norms.maxCoeff() / norms.minCoeff()};
}

// The margin is at least σ_min of the normalized W, of its order (within 4×: the pivots of a
// fixed order over unit rows), comparable to the dense engine's (from a third of it to 3ρ times
// it), and falls linearly with the distance d to the dead centre: d = 1e-3 → 1e-4 divides it by
// 10, as it divides the dense engine's.
void expect_margins(const Model& m, VectorXd (*q_at)(double)) {
  const double dead = M_PI / 2;
  const Margins far = margins(m, q_at(0.3)), near = margins(m, q_at(dead - 1e-3)),
                nearer = margins(m, q_at(dead - 1e-4));
  for (const Margins& x : {far, near, nearer}) {
    EXPECT_GE(x.sparse, x.sigma_min * (1.0 - 1e-9)) << x.sigma_min;
    EXPECT_LE(x.sparse, 4.0 * x.sigma_min) << x.sigma_min;
    EXPECT_GE(x.sparse / x.dense, 1.0 / 3.0) << x.sparse << " " << x.dense;
    EXPECT_LE(x.sparse / x.dense, 3.0 * x.spread) << x.sparse << " " << x.dense;
  }
  // the two engines' margins in the same proportion near the dead centre
  EXPECT_NEAR((near.sparse / near.dense) / (nearer.sparse / nearer.dense), 1.0, 0.05);
  // far from the dead centre: clear of the integrators' 1e-2 (no projected stages there)
  EXPECT_GT(far.sparse, 0.05);
  EXPECT_LE(far.sparse, 1.0);
  // near it: below 1e-2, and linear in the distance
  EXPECT_LT(near.sparse, 1e-2);
  EXPECT_GT(near.sparse, 1e-5);
  EXPECT_NEAR(near.sparse / nearer.sparse, 10.0, 0.5);
}

TEST(SparseRankMargin, SliderCrankNearAndFarFromItsDeadCentre) {
  const Model m = parse_model(kSliderCrank, "isosceles_slider_crank.yaml");
  ASSERT_EQ(m.system.coordinate_count(), 9);
  expect_margins(m, slider_crank_q);
}

TEST(SparseRankMargin, DoubleFourBarBodiesNearAndFarFromItsDeadCentre) {
  const Model m = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/double_four_bar_bodies.yaml");
  ASSERT_EQ(m.system.coordinate_count(), 15);
  expect_margins(m, double_four_bar_q);
}

// 1 without constraint rows, as the dense engine's; exactly redundant rows are dropped and do not
// count (the redundant double four-bar away from its dead centre: the margin of the kept rows)
TEST(SparseRankMargin, OneWithoutRowsAndKeptRowsOnlyWhenRedundant) {
  const Model free = parse_model(
      "name: free body\nbodies:\n  - {name: b, type: planar, mass: 1, inertia: 1, "
      "position: [0, 0]}\n",
      "free.yaml");
  SolverOptions so;
  so.engine = Engine::kSparse;
  Workspace ws(free.system, so);
  ASSERT_EQ(forward_dynamics(free.system, ws, free.q0, free.qd0, 0.0), Status::kOk);
  EXPECT_EQ(ws.rank_margin, 1.0);
  const Model red =
      load_model(std::string(UKDYN_EXAMPLES_DIR) + "/double_four_bar_bodies_redundant.yaml");
  Workspace wr(red.system, so);
  ASSERT_EQ(forward_dynamics(red.system, wr, red.q0, red.qd0, 0.0), Status::kOk);
  EXPECT_LT(wr.rank, red.system.constraint_rows());
  EXPECT_GT(wr.rank_margin, 0.05);
  EXPECT_LE(wr.rank_margin, 1.0);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
