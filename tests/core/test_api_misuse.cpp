// SPDX-License-Identifier: BSD-3-Clause
// Misuse of the C++ API (issue #14, item 8; reliability report D14): every entry point given a
// workspace of another system, a moved-from workspace, vectors of the wrong size, a NaN state
// or a NaN t either throws std::invalid_argument naming the function and the problem, or
// returns a failing Status that describe_status turns into a message naming the quantity and
// the coordinate — never a crash, never "converged", never the previous call's results.
// The cases are those of the reproducer bad-input/scripts/cpp_misuse.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <utility>

#include "ukdyn/ukdyn.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// the exception's text, or "" when f does not throw E
template <class E, class F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

// every entry of v is NaN (and v is not empty)
bool all_nan(const Eigen::Ref<const VectorXd>& v) {
  if (v.size() == 0) return false;
  for (Index i = 0; i < v.size(); ++i) {
    if (!std::isnan(v[i])) return false;
  }
  return true;
}

#define EXPECT_INVALID(call, text)                                            \
  do {                                                                        \
    const std::string m_ = message_of<std::invalid_argument>([&] { call; });  \
    EXPECT_NE(m_.find(text), std::string::npos) << "message: '" << m_ << "'"; \
  } while (0)

class ApiMisuse : public ::testing::Test {
 protected:
  gallery::Example pend = gallery::make("pendulum");  // coordinates x, y; constraint 'rod'
  const System& sys = pend.system;
};

// --- workspaces --------------------------------------------------------------------------------

TEST_F(ApiMisuse, WorkspaceOfAnotherSystemIsRefused) {
  const auto dp = gallery::make("double_four_bar");
  Workspace ws(dp.system);
  EXPECT_INVALID(forward_dynamics(sys, ws, pend.q0, pend.qd0, 0.0),
                 "ukdyn::forward_dynamics: the workspace was made for another system");
  // another System object of the same shape is another system too
  const auto twin = gallery::make("pendulum");
  Workspace tw(twin.system);
  EXPECT_INVALID(forward_dynamics(sys, tw, pend.q0, pend.qd0, 0.0),
                 "the workspace was made for another system");
}

TEST_F(ApiMisuse, MovedFromWorkspaceIsEmptyAndRefusedByEveryEntryPoint) {
  Workspace ws(sys);
  Workspace taken(std::move(ws));
  // NOLINTBEGIN(bugprone-use-after-move): the point of the test
  EXPECT_EQ(ws.system_id(), 0u);
  EXPECT_EQ(ws.coordinate_count(), 0);
  EXPECT_EQ(ws.rows(), 0);
  const char* empty = "the workspace is empty (moved from";
  VectorXd q = pend.q0, qd = pend.qd0;
  EXPECT_INVALID(forward_dynamics(sys, ws, q, qd, 0.0), "ukdyn::forward_dynamics: ");
  EXPECT_INVALID(forward_dynamics(sys, ws, q, qd, 0.0), empty);
  EXPECT_INVALID(evaluate_unconstrained(sys, ws, q, qd, 0.0), empty);
  EXPECT_INVALID(assemble_constraints(sys, ws, q, qd, 0.0), empty);
  EXPECT_INVALID(solve_ideal(sys, ws), empty);
  EXPECT_INVALID(apply_nonideal(sys, ws, q, qd, 0.0), empty);
  EXPECT_INVALID(check_result(sys, ws), empty);
  EXPECT_INVALID(evaluate_violations(sys, ws, q, qd, 0.0), empty);
  EXPECT_INVALID(project_positions(sys, ws, q, 0.0), "ukdyn::project_positions: ");
  EXPECT_INVALID(project_positions(sys, ws, q, 0.0), empty);
  EXPECT_INVALID(project_velocities(sys, ws, q, qd, 0.0), empty);
  EXPECT_INVALID(position_violation(sys, ws, 0), "ukdyn::position_violation: ");
  EXPECT_INVALID(velocity_violation(sys, ws, 0), empty);
  // the workspace it went to works: q'' of the pendulum released at rest from (L, 0) is
  // (0, −g) (the rod carries no force at rest when horizontal)
  ASSERT_EQ(forward_dynamics(sys, taken, q, qd, 0.0), Status::kOk);
  EXPECT_NEAR(taken.qdd[0], 0.0, 1e-12);
  EXPECT_NEAR(taken.qdd[1], -9.81, 1e-12);
  // a workspace moved back into it works again
  ws = std::move(taken);
  EXPECT_EQ(ws.system_id(), sys.id());
  EXPECT_EQ(taken.system_id(), 0u);
  ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
  EXPECT_NEAR(ws.qdd[1], -9.81, 1e-12);
  EXPECT_INVALID(forward_dynamics(sys, taken, q, qd, 0.0), empty);
  // NOLINTEND(bugprone-use-after-move)
}

TEST_F(ApiMisuse, MovedFromControlWorkspaceIsRefused) {
  const Controller ctrl =
      ControllerBuilder(sys)
          .require(holonomic("height", 1,
                             [](const auto& q, const auto&, auto& e) { e[0] = q[1] + 0.5; }),
                   ErrorDynamics::second_order(2.0, 1.0))
          .build();
  ControlWorkspace cws(ctrl);
  ControlWorkspace taken(std::move(cws));
  // NOLINTNEXTLINE(bugprone-use-after-move)
  EXPECT_EQ(cws.controller_id(), 0u);
  // NOLINTNEXTLINE(bugprone-use-after-move)
  EXPECT_INVALID(compute_control(ctrl, cws, pend.q0, pend.qd0, 0.0),
                 "ukdyn::compute_control: the control workspace is empty (moved from)");
  EXPECT_NO_THROW(compute_control(ctrl, taken, pend.q0, pend.qd0, 0.0));
}

// --- sizes ---------------------------------------------------------------------------------------

TEST_F(ApiMisuse, WrongSizesNameTheFunctionAndTheSizes) {
  Workspace ws(sys);
  VectorXd q5 = VectorXd::Zero(5), empty;
  EXPECT_INVALID(forward_dynamics(sys, ws, q5, pend.qd0, 0.0),
                 "ukdyn::forward_dynamics: q has 5 entries, expected n = 2");
  EXPECT_INVALID(forward_dynamics(sys, ws, empty, empty, 0.0),
                 "ukdyn::forward_dynamics: q has 0 entries, expected n = 2");
  EXPECT_INVALID(forward_dynamics(sys, ws, pend.q0, q5, 0.0),
                 "ukdyn::forward_dynamics: q_dot has 5 entries, expected n = 2");
  EXPECT_INVALID(evaluate_unconstrained(sys, ws, q5, pend.qd0, 0.0),
                 "ukdyn::evaluate_unconstrained: q has 5 entries, expected n = 2");
  EXPECT_INVALID(assemble_constraints(sys, ws, pend.q0, empty, 0.0),
                 "ukdyn::assemble_constraints: q_dot has 0 entries, expected n = 2");
  EXPECT_INVALID(apply_nonideal(sys, ws, q5, pend.qd0, 0.0),
                 "ukdyn::apply_nonideal: q has 5 entries");
  EXPECT_INVALID(evaluate_violations(sys, ws, q5, pend.qd0, 0.0),
                 "ukdyn::evaluate_violations: q has 5 entries");
  EXPECT_INVALID(project_positions(sys, ws, q5, 0.0),
                 "ukdyn::project_positions: q has 5 entries, expected n = 2");
  VectorXd q = pend.q0;
  EXPECT_INVALID(project_velocities(sys, ws, q, q5, 0.0),
                 "ukdyn::project_velocities: q_dot has 5 entries, expected n = 2");
  SimulationOptions o;
  o.t_end = 1.0;
  VectorXd q1(1);
  q1 << 1.0;
  EXPECT_INVALID(simulate(sys, q1, q1, o),
                 "ukdyn::simulate: q0 and qd0 need n = 2 entries, got 1 and 1");
  // a NaN initial state (it used to end with status "non-finite input", no message, no sample)
  VectorXd qnan = pend.q0;
  qnan[1] = kNaN;
  EXPECT_INVALID(simulate(sys, qnan, pend.qd0, o),
                 "ukdyn::simulate: q0 is not finite at coordinate 'y'");
  EXPECT_INVALID(simulate(sys, pend.q0, qnan, o),
                 "ukdyn::simulate: qd0 is not finite at coordinate 'y'");
  EXPECT_INVALID(SystemBuilder({"x", "y"}).mass_matrix(Eigen::Matrix3d::Identity()).build(),
                 "ukdyn::SystemBuilder::mass_matrix: expected a 2x2 matrix, got 3x3");
}

TEST_F(ApiMisuse, BadSolverOptionsNameTheSetting) {
  SolverOptions so;
  so.rank_threshold = 2;
  EXPECT_INVALID(Workspace(sys, so), "SolverOptions::rank_threshold must lie in (0, 1), got 2");
  SolverOptions nan;
  nan.consistency_tolerance = kNaN;
  EXPECT_INVALID(Workspace(sys, nan), "SolverOptions::consistency_tolerance must be > 0");
}

// --- non-finite inputs -----------------------------------------------------------------------

TEST_F(ApiMisuse, NaNStateNamesTheCoordinateAndLeavesNoStaleResults) {
  Workspace ws(sys);
  // a good evaluation first: its q'' must not survive the failed one
  ASSERT_EQ(forward_dynamics(sys, ws, pend.q0, pend.qd0, 0.0), Status::kOk);
  ASSERT_NEAR(ws.qdd[1], -9.81, 1e-12);
  VectorXd q = pend.q0;
  q[0] = kNaN;
  EXPECT_EQ(forward_dynamics(sys, ws, q, pend.qd0, 0.0), Status::kNonFiniteInput);
  EXPECT_NE(describe_status(sys, ws).find("in q (coordinate 'x')"), std::string::npos)
      << describe_status(sys, ws);
  EXPECT_TRUE(all_nan(ws.qdd));
  EXPECT_TRUE(all_nan(ws.Qc));
  EXPECT_TRUE(all_nan(ws.lambda));
  const std::string m = message_of<SolveError>([&] { throw_if_failed(sys, ws); });
  EXPECT_NE(m.find("non-finite input"), std::string::npos) << m;
  // q' and t
  VectorXd qd = pend.qd0;
  qd[1] = kNaN;
  EXPECT_EQ(forward_dynamics(sys, ws, pend.q0, qd, 0.0), Status::kNonFiniteInput);
  EXPECT_NE(describe_status(sys, ws).find("in q_dot (coordinate 'y')"), std::string::npos)
      << describe_status(sys, ws);
  ASSERT_EQ(forward_dynamics(sys, ws, pend.q0, pend.qd0, 0.0), Status::kOk);
  EXPECT_EQ(forward_dynamics(sys, ws, pend.q0, pend.qd0, kNaN), Status::kNonFiniteInput);
  EXPECT_NE(describe_status(sys, ws).find("in t"), std::string::npos) << describe_status(sys, ws);
  EXPECT_TRUE(all_nan(ws.qdd));
}

TEST_F(ApiMisuse, NaNMassMatrixIsANonFiniteInput) {
  Eigen::Matrix2d M;
  M << kNaN, 0, 0, 1;
  const System s = SystemBuilder({"x", "y"}).mass_matrix(M).build();
  Workspace ws(s);
  const VectorXd z = VectorXd::Zero(2);
  EXPECT_EQ(forward_dynamics(s, ws, z, z, 0.0), Status::kNonFiniteInput);
  EXPECT_NE(describe_status(s, ws).find("in M"), std::string::npos) << describe_status(s, ws);
  EXPECT_TRUE(all_nan(ws.qdd));
}

TEST_F(ApiMisuse, ProjectionOfANaNStateIsNotConverged) {
  Workspace ws(sys);
  VectorXd q = pend.q0;
  q[0] = kNaN;
  const ProjectionResult r = project_positions(sys, ws, q, 0.0);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_TRUE(std::isnan(r.violation));
  EXPECT_EQ(r.status, Status::kNonFiniteInput);
  EXPECT_EQ(ws.status, Status::kNonFiniteInput);
  EXPECT_NE(describe_status(sys, ws).find("non-finite input (NaN or Inf) at t = 0 in q "
                                          "(coordinate 'x')"),
            std::string::npos)
      << describe_status(sys, ws);
  EXPECT_TRUE(std::isnan(q[0]));  // left as given
  EXPECT_EQ(q[1], pend.q0[1]);
  // velocities: a NaN q' names its coordinate
  VectorXd qd = pend.qd0;
  qd[1] = std::numeric_limits<double>::infinity();
  const ProjectionResult rv = project_velocities(sys, ws, pend.q0, qd, 0.0);
  EXPECT_FALSE(rv.converged);
  EXPECT_EQ(rv.status, Status::kNonFiniteInput);
  EXPECT_NE(describe_status(sys, ws).find("in q_dot (coordinate 'y')"), std::string::npos)
      << describe_status(sys, ws);
  // NaN t
  VectorXd q0 = pend.q0;
  const ProjectionResult rt = project_positions(sys, ws, q0, kNaN);
  EXPECT_FALSE(rt.converged);
  EXPECT_EQ(rt.status, Status::kNonFiniteInput);
  EXPECT_NE(describe_status(sys, ws).find("in t"), std::string::npos);
  // and a finite state still projects: (2L, 0) onto the circle of radius L
  VectorXd far = 2.0 * pend.q0;
  const ProjectionResult ok = project_positions(sys, ws, far, 0.0);
  EXPECT_TRUE(ok.converged);
  EXPECT_EQ(ok.status, Status::kOk);
  EXPECT_NEAR(far.norm(), pend.q0.norm(), 1e-12);
}

TEST_F(ApiMisuse, ProjectionOfANaNConstraintValueNamesTheConstraint) {
  // phi = sqrt(x) − 1 is NaN for x < 0: a finite q whose violation is not finite
  const System s = SystemBuilder({"x"})
                       .mass_matrix(Eigen::Matrix<double, 1, 1>::Identity())
                       .add(holonomic("root", 1,
                                      [](const auto& q, const auto&, auto& phi) {
                                        using std::sqrt;
                                        phi[0] = sqrt(q[0]) - 1.0;
                                      }))
                       .build();
  Workspace ws(s);
  VectorXd q(1);
  q << -4.0;
  const ProjectionResult r = project_positions(s, ws, q, 0.0);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.status, Status::kNonFiniteInput);
  EXPECT_NE(describe_status(s, ws).find("in phi of constraint 'root'"), std::string::npos)
      << describe_status(s, ws);
}

// --- the rest of the reproducer's cases: documented errors ------------------------------------

TEST_F(ApiMisuse, UnknownGalleryNameAndMissingFilesAreNamed) {
  EXPECT_INVALID(gallery::make("nope"), "nope");
  const std::string m = message_of<std::exception>([] { load_model("/nonexistent.yaml"); });
  EXPECT_NE(m.find("/nonexistent.yaml"), std::string::npos) << m;
  SimulationOptions o;
  o.t_end = 0.1;
  const Trajectory tr = simulate(sys, pend.q0, pend.qd0, o);
  const auto dir = std::filesystem::temp_directory_path();
  const std::string csv = message_of<std::runtime_error>([&] { write_csv(tr, dir.string()); });
  EXPECT_NE(csv.find(dir.string()), std::string::npos) << csv;
  const std::string h5 =
      message_of<std::runtime_error>([&] { write_hdf5(tr, "/nonexistent-dir/x.h5"); });
  EXPECT_NE(h5.find("/nonexistent-dir/x.h5"), std::string::npos) << h5;
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
