// No heap allocation per evaluation of a tree's system once the workspace exists.
#include <string>

#include <gtest/gtest.h>

#include "support/alloc_counter.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree {
namespace UKDYN_TEST_FILE {

const std::string kPanda = std::string(UKDYN_TEST_DATA_DIR) + "/panda_arm.urdf";

TEST(Tree, EvaluationsDoNotAllocate) {
  const System sys = make_system(load_urdf(kPanda));
  Workspace ws(sys);
  VectorXd q(7), qd(7);
  q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  qd << 0.5, -1.0, 0.7, 0.2, -0.9, 1.1, 0.3;
  forward_dynamics(sys, ws, q, qd, 0.0);
  testing::start_counting_allocations();
  for (int i = 0; i < 10; ++i) forward_dynamics(sys, ws, q, qd, 0.01 * i);
  EXPECT_EQ(testing::stop_counting_allocations(), 0);
  EXPECT_EQ(ws.status, Status::kOk);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn::tree
