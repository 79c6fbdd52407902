// SPDX-License-Identifier: BSD-3-Clause
// No heap allocation per evaluation with the sparse engine once the workspace exists: chains of
// planar bodies closed to ground (also redundantly), state-dependent mass blocks, dense rows,
// inactive constraints, non-ideal forces, the projections, and large N.
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <ukdyn/linalg/sparse.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/alloc_counter.hpp"
#include "support/planar_revolute.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using testing::start_counting_allocations;
using testing::stop_counting_allocations;

using Pin = testing::PlanarRevolute;  // point s_i of body i on point s_j of body j (or ground)

struct Chain {
  System sys;
  VectorXd q, qd;
};

// N rods of length 1/N pinned at the origin, the last tip pinned where it is `closures` times;
// optionally every other block state-dependent, a dense acceleration row, an inactive
// constraint and viscous friction
Chain chain(Index N, int closures, bool extras) {
  const double L = 1.0 / double(N), m = L, I = m * L * L / 12.0;
  SystemBuilder b(3 * N);
  VectorXd q(3 * N), qd(3 * N);
  Eigen::Vector2d p(0.0, 0.0);
  for (Index i = 0; i < N; ++i) {
    const double phi = -1.0 + 2.0 * double(i) / double(N) + 0.1 * std::sin(double(i));
    const Eigen::Vector2d u(std::cos(phi), std::sin(phi));
    q.segment<2>(3 * i) = p + 0.5 * L * u;
    q[3 * i + 2] = phi;
    p += L * u;
    const MatrixXd Mi = Eigen::Vector3d(m, m, I).asDiagonal().toDenseMatrix();
    if (extras && i % 2 == 1) {
      b.mass_block(3 * i, 3,
                   [Mi, i](const Eigen::Ref<const VectorXd>& x, double, Eigen::Ref<MatrixXd> out) {
                     out = Mi * (1.0 + 0.01 * x[3 * i] * x[3 * i]);
                   });
    } else {
      b.mass_block(3 * i, Mi);
    }
  }
  for (Index i = 0; i < 3 * N; ++i) qd[i] = 0.2 * std::cos(1.3 * double(i));
  b.forces([N, m](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>& v, double,
                  Eigen::Ref<VectorXd> Q) {
    Q = -0.01 * v;
    for (Index i = 0; i < N; ++i) Q[3 * i + 1] -= 9.81 * m;
  });
  const auto pin = [](const std::string& name, Index i, Eigen::Vector2d si, Index j,
                      Eigen::Vector2d sj) {
    return Constraint(name, ConstraintKind::kHolonomic, 2, std::make_shared<Pin>(i, si, j, sj));
  };
  const Eigen::Vector2d back(-0.5 * L, 0.0), tip(0.5 * L, 0.0);
  b.add(pin("pin0", 0, back, -1, Eigen::Vector2d::Zero()));
  for (Index i = 1; i < N; ++i) b.add(pin("pin" + std::to_string(i), i, back, i - 1, tip));
  for (int c = 0; c < closures; ++c) b.add(pin("close" + std::to_string(c), N - 1, tip, -1, p));
  if (extras) {
    // a dense row: the sum of the angular accelerations is prescribed
    b.add(acceleration_constraint(
        "dense", 1,
        [N](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
            Eigen::Ref<MatrixXd> A, Eigen::Ref<VectorXd> rhs) {
          A.setZero();
          for (Index i = 0; i < N; ++i) A(0, 3 * i + 2) = 1.0;
          rhs[0] = 0.0;
        }));
    Constraint later = pin("later", N / 2, back, -1, Eigen::Vector2d::Zero());
    later.active_between(100.0, 101.0);
    b.add(later);
    b.add(viscous_friction({.coefficient = 0.02, .name = "drag"}));
  }
  return {b.build(), q, qd};
}

const SolverOptions kSparse{.engine = Engine::kSparse};

// allocations made by `calls` evaluations on a fresh sparse workspace (none before them)
long allocations_of(const Chain& c, int calls) {
  Workspace ws(c.sys, kSparse);
  EXPECT_TRUE(ws.is_sparse());
  start_counting_allocations();
  for (int i = 0; i < calls; ++i) forward_dynamics(c.sys, ws, c.q, c.qd, 0.01 * i);
  const long count = stop_counting_allocations();
  EXPECT_EQ(ws.status, Status::kOk) << describe_status(c.sys, ws);
  return count;
}

TEST(SparseNoAllocation, CounterSeesTheAnalysis) {
  // making the workspace (pattern, ordering, symbolic factorization) does allocate
  const Chain c = chain(16, 1, false);
  start_counting_allocations();
  { Workspace ws(c.sys, kSparse); }
  EXPECT_GT(stop_counting_allocations(), 10);
}

TEST(SparseNoAllocation, ClosedChain) { EXPECT_EQ(allocations_of(chain(16, 1, false), 5), 0); }

TEST(SparseNoAllocation, RedundantLoopDenseRowInactiveConstraintAndFriction) {
  EXPECT_EQ(allocations_of(chain(16, 3, true), 5), 0);
}

TEST(SparseNoAllocation, LargeChain) { EXPECT_EQ(allocations_of(chain(1024, 2, true), 3), 0); }

TEST(SparseNoAllocation, Projections) {
  const Chain c = chain(64, 2, true);
  Workspace ws(c.sys, kSparse);
  VectorXd q = c.q, qd = c.qd;
  for (Index i = 0; i < q.size(); ++i) q[i] += 1e-4 * std::sin(double(i));
  ProjectionOptions o;
  o.mask.assign(std::size_t(c.sys.constraint_count()), 1);
  start_counting_allocations();
  const ProjectionResult rp = project_positions(c.sys, ws, q, 0.0, o);
  const ProjectionResult rv = project_velocities(c.sys, ws, q, qd, 0.0, o);
  const long count = stop_counting_allocations();
  EXPECT_TRUE(rp.converged);
  EXPECT_TRUE(rv.converged);
  EXPECT_GE(rp.iterations, 1);
  EXPECT_EQ(count, 0);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
