// SPDX-License-Identifier: BSD-3-Clause
// The core library without ukdyn::reference (issue #15 item 1): the textbook formula is not in
// it, and asking for it says which library to link, instead of failing to link or running
// another algorithm. This program is the one test that does not link ukdyn::reference.
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include <ukdyn/ukdyn.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

TEST(WithoutReference, TextbookAlgorithmNamesTheLibraryToLink) {
  const gallery::Example ex = gallery::pendulum(1.0, 1.0, 9.81);
  const System& sys = ex.system;
  SolverOptions o;
  o.engine = Engine::kDense;
  o.algorithm = Algorithm::kTextbook;
  try {
    Workspace ws(sys, o);
    FAIL() << "a workspace for the textbook algorithm was made without ukdyn::reference";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("Algorithm::kTextbook is in the reference library"), std::string::npos)
        << what;
    EXPECT_NE(what.find("ukdyn::reference"), std::string::npos) << what;
  }
  // the default algorithm is unaffected: released horizontally at rest, q'' = (0, −g)
  o.algorithm = Algorithm::kDefault;
  Workspace ws(sys, o);
  ASSERT_EQ(forward_dynamics(sys, ws, ex.q0, ex.qd0, 0.0), Status::kOk);
  EXPECT_NEAR(ws.qdd[0], 0.0, 1e-12);
  EXPECT_NEAR(ws.qdd[1], -9.81, 1e-12);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
