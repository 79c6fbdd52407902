// SPDX-License-Identifier: BSD-3-Clause
// find_constraint_conflict (dynamics/constraint_conflict.cpp) on large closed chains: the sparse
// engine's form (its rank-revealing LDLᵀ of G, linear in the chain's length; issue #29 item 4)
// against the closed form and against the dense engine's QR of A.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include <ukdyn/dynamics/projection.hpp>
#include <ukdyn/dynamics/workspace.hpp>
#include <ukdyn/modelfile/model.hpp>

#include "support/closed_chain.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

// The tip of the last rod pinned twice, to ground points d apart in x ('close' where the tip is,
// 'close2' d beyond it): the two pins' x rows of A are the same row, their violations 0 and −d.
// No correction removes the difference: (I − A A⁺) phi on them is (d/2, −d/2), of norm d/√2,
// carried by both pins and by nothing else (the y rows agree; every other joint is closed).
void expect_double_pin(const Model& m, Workspace& ws, double d) {
  const ConstraintConflict c = find_constraint_conflict(m.system, ws, m.q0, m.qd0, 0.0, 1e-10);
  ASSERT_TRUE(c.found);
  EXPECT_FALSE(c.velocity_level);
  EXPECT_NEAR(c.residual, d / std::sqrt(2.0), 1e-9 * d);
  ASSERT_EQ(c.names.size(), 2u);
  EXPECT_EQ(c.names[0], "close");
  EXPECT_EQ(c.names[1], "close2");
}

TEST(ConstraintConflict, ChainOf512PinnedTwiceWithTheSparseEngine) {
  const double d = 1e-3;
  const Model m = parse_model(test::closed_chain(512, 0.0, d), "chain512.yaml");
  Workspace ws(m.system);  // Engine::kAuto: sparse (n = 1536)
  ASSERT_TRUE(ws.is_sparse());
  expect_double_pin(m, ws, d);
}

// the same diagnosis from both engines (the dense one: a QR of A), and none on the chain pinned
// once
TEST(ConstraintConflict, SparseAndDenseEnginesAgreeOnAChainOf64) {
  for (const double d : {1e-3, 0.0}) {
    const Model m = parse_model(test::closed_chain(64, 0.0, d), "chain64.yaml");
    SolverOptions dense;
    dense.engine = Engine::kDense;
    Workspace wd(m.system, dense);
    SolverOptions sparse;
    sparse.engine = Engine::kSparse;
    Workspace wsp(m.system, sparse);
    if (d > 0) {
      expect_double_pin(m, wsp, d);
      expect_double_pin(m, wd, d);
      continue;
    }
    for (Workspace* ws : {&wd, &wsp}) {
      const ConstraintConflict c = find_constraint_conflict(m.system, *ws, m.q0, m.qd0, 0.0, 1e-10);
      EXPECT_FALSE(c.found) << c.residual;
      EXPECT_TRUE(c.names.empty());
    }
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
