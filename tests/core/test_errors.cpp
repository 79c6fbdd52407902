// SPDX-License-Identifier: BSD-3-Clause
// Bad input: misuse throws std::invalid_argument with a useful message (tier 1); numerical
// failures set a status that describe_status() explains and throw_if_failed() raises (tier 3).
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include <ukdyn/core/format.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/ukdyn.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

System pendulum(MassMatrixFn mass) {
  return SystemBuilder({"x", "y"})
      .mass_matrix(std::move(mass))
      .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<VectorXd> Q) { Q << 0.0, -9.81; })
      .add(holonomic(
          "rod", 1,
          [](const auto& q, const auto&, auto& phi) { phi[0] = q[0] * q[0] + q[1] * q[1] - 1.0; }))
      .build();
}

MassMatrixFn identity_mass() {
  return [](const Eigen::Ref<const VectorXd>&, double, Eigen::Ref<MatrixXd> M) { M.setIdentity(); };
}

VectorXd state(double x, double y) {
  VectorXd v(2);
  v << x, y;
  return v;
}

// valid_utf8 keeps well-formed UTF-8 and turns each ill-formed piece into one U+FFFD (the
// "maximal subpart" rule of the Unicode standard, section 3.9)
TEST(Errors, MessagesAreValidUtf8) {
  const std::string bad = "\xEF\xBF\xBD";
  EXPECT_EQ(ukdyn::valid_utf8("plain ascii"), "plain ascii");
  EXPECT_EQ(ukdyn::valid_utf8("\xC3\xA9 \xE2\x88\x9A \xF0\x9F\x98\x80"),
            "\xC3\xA9 \xE2\x88\x9A \xF0\x9F\x98\x80");  // é √ 😀 kept
  EXPECT_EQ(ukdyn::valid_utf8("a\xC3"
                              "b"),
            "a" + bad + "b");                                               // lead without its tail
  EXPECT_EQ(ukdyn::valid_utf8("\xA9"), bad);                                // stray continuation
  EXPECT_EQ(ukdyn::valid_utf8("\xF0\x9F\x98"), bad);                        // cut short: one U+FFFD
  EXPECT_EQ(ukdyn::valid_utf8("\xC0\xAF"), bad + bad);                      // overlong '/'
  EXPECT_EQ(ukdyn::valid_utf8("\xED\xA0\x80"), bad + bad + bad);            // a surrogate
  EXPECT_EQ(ukdyn::valid_utf8("\xF4\x90\x80\x80"), bad + bad + bad + bad);  // above U+10FFFF
  EXPECT_EQ(ukdyn::valid_utf8(std::string("a\0b", 3)), std::string("a\0b", 3));
  // a ModelError built from bytes that are not UTF-8 holds and prints valid UTF-8
  const ukdyn::ModelError e("m\xFF.yaml", 3, 4, "unexpected '\xC3'", "h\x80");
  EXPECT_EQ(e.file(), "m" + bad + ".yaml");
  EXPECT_EQ(e.message(), "unexpected '" + bad + "'");
  EXPECT_EQ(e.hint(), "h" + bad);
  EXPECT_EQ(std::string(e.what()),
            "m" + bad + ".yaml:3:4: error: unexpected '" + bad + "' (hint: h" + bad + ")");
}

TEST(Errors, MassNotPositiveDefiniteIsAStatusWithAClearMessage) {
  const System sys = pendulum([](const Eigen::Ref<const VectorXd>&, double,
                                 Eigen::Ref<MatrixXd> M) { M << 1.0, 0.0, 0.0, -2.0; });
  Workspace ws(sys);
  EXPECT_EQ(forward_dynamics(sys, ws, state(1, 0), state(0, 0), 0.25),
            Status::kMassNotPositiveDefinite);
  const std::string msg = describe_status(sys, ws);
  EXPECT_TRUE(contains(msg, "mass matrix not positive definite")) << msg;
  EXPECT_TRUE(contains(msg, "t = 0.25")) << msg;
  EXPECT_THROW(throw_if_failed(sys, ws), SolveError);
  EXPECT_EQ(ws.counters.failures, 1);
}

TEST(Errors, MassNotSymmetric) {
  const System sys = pendulum([](const Eigen::Ref<const VectorXd>&, double,
                                 Eigen::Ref<MatrixXd> M) { M << 1.0, 0.5, 0.0, 1.0; });
  Workspace ws(sys);
  EXPECT_EQ(forward_dynamics(sys, ws, state(1, 0), state(0, 0), 0.0), Status::kMassNotSymmetric);
  EXPECT_TRUE(contains(describe_status(sys, ws), "not symmetric"));
}

TEST(Errors, NaNInStateNamesTheCoordinate) {
  const System sys = pendulum(identity_mass());
  Workspace ws(sys);
  EXPECT_EQ(forward_dynamics(sys, ws, state(1, 0), state(0, kNaN), 0.0), Status::kNonFiniteInput);
  const std::string msg = describe_status(sys, ws);
  EXPECT_TRUE(contains(msg, "q_dot")) << msg;
  EXPECT_TRUE(contains(msg, "coordinate 'y'")) << msg;
  EXPECT_EQ(forward_dynamics(sys, ws, state(1, 0), state(0, 0), kNaN), Status::kNonFiniteInput);
  EXPECT_STREQ(ws.failed_quantity, "t");
}

TEST(Errors, NaNFromAConstraintNamesTheConstraint) {
  const System sys =
      SystemBuilder(2)
          .mass_matrix(MatrixXd::Identity(2, 2))
          .add(holonomic("ok", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[0]; }))
          .add(holonomic("bad", 1,
                         [](const auto& q, const auto&, auto& phi) {
                           using std::sqrt;
                           phi[0] = sqrt(q[1]);  // derivative is Inf at 0, NaN below
                         }))
          .build();
  Workspace ws(sys);
  EXPECT_EQ(forward_dynamics(sys, ws, state(0, -1), state(0, 0), 0.0), Status::kNonFiniteInput);
  const std::string msg = describe_status(sys, ws);
  EXPECT_TRUE(contains(msg, "constraint 'bad'")) << msg;
  EXPECT_EQ(ws.failed_index, 1);
}

TEST(Errors, NaNInForceOrC) {
  const System sys =
      SystemBuilder(2)
          .mass_matrix(MatrixXd::Identity(2, 2))
          .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double t,
                     Eigen::Ref<VectorXd> Q) { Q << (t > 1 ? kNaN : 0.0), 0.0; })
          .add(
              NonIdealForce("broken",
                            [](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&,
                               double t, const IdealForceInfo&, Eigen::Ref<VectorXd> C) {
                              if (t < 0) C[0] = kNaN;
                            }))
          .build();
  Workspace ws(sys);
  EXPECT_EQ(forward_dynamics(sys, ws, state(0, 0), state(0, 0), 2.0), Status::kNonFiniteInput);
  EXPECT_STREQ(ws.failed_quantity, "Q");
  EXPECT_EQ(forward_dynamics(sys, ws, state(0, 0), state(0, 0), -1.0), Status::kNonFiniteInput);
  EXPECT_TRUE(contains(describe_status(sys, ws), "non-ideal force 'broken'"));
  EXPECT_EQ(forward_dynamics(sys, ws, state(0, 0), state(0, 0), 0.0), Status::kOk);
}

// the acceleration constraint x'' = rhs on (x, y)
auto row(double rhs) {
  return [rhs](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
               Eigen::Ref<MatrixXd> A, Eigen::Ref<VectorXd> b) {
    A << 1.0, 0.0;
    b << rhs;
  };
}

TEST(Errors, InconsistentConstraintsAreFoundWithoutResidualsOnBothEngines) {
  // x'' = 0 and x'' = 1 at once, residuals off (as the simulation runs): the consistency test
  // still runs because the rank (1) is below the active rows (2); a full-rank A skips it
  const System sys = SystemBuilder(2)
                         .mass_block(0, MatrixXd::Identity(1, 1))
                         .mass_block(1, MatrixXd::Identity(1, 1))
                         .add(acceleration_constraint("zero", 1, row(0.0)))
                         .add(acceleration_constraint("one", 1, row(1.0)))
                         .build();
  for (const Engine engine : {Engine::kDense, Engine::kSparse}) {
    Workspace ws(sys, SolverOptions{.engine = engine, .compute_residuals = false});
    EXPECT_EQ(forward_dynamics(sys, ws, state(0, 0), state(0, 0), 0.0),
              Status::kInconsistentConstraints);
    EXPECT_NEAR(ws.residuals.constraint, std::sqrt(0.5), 1e-14);
    // one of them alone: full row rank, no test and no residual unless asked
    ws.activity_override = {1, 0};
    EXPECT_EQ(forward_dynamics(sys, ws, state(0, 0), state(0, 0), 0.0), Status::kOk);
    EXPECT_EQ(ws.rank, 1);
    EXPECT_TRUE(std::isnan(ws.residuals.constraint));
    EXPECT_NEAR(ws.qdd[0], 0.0, 1e-15);
  }
  Workspace asked(sys, SolverOptions{.compute_residuals = true});
  asked.activity_override = {0, 1};
  EXPECT_EQ(forward_dynamics(sys, asked, state(0, 0), state(0, 0), 0.0), Status::kOk);
  EXPECT_NEAR(asked.qdd[0], 1.0, 1e-15);
  EXPECT_NEAR(asked.residuals.constraint, 0.0, 1e-15);
}

TEST(Errors, InconsistentConstraintsAreReportedNotLeastSquared) {
  // x'' = 0 and x'' = 1 at once
  const System sys = SystemBuilder(2)
                         .mass_matrix(MatrixXd::Identity(2, 2))
                         .add(acceleration_constraint("zero", 1, row(0.0)))
                         .add(acceleration_constraint("one", 1, row(1.0)))
                         .build();
  Workspace ws(sys);
  EXPECT_EQ(forward_dynamics(sys, ws, state(0, 0), state(0, 0), 0.0),
            Status::kInconsistentConstraints);
  EXPECT_NEAR(ws.residuals.constraint, std::sqrt(0.5), 1e-14);  // least squares x'' = 1/2
  EXPECT_EQ(ws.rank, 1);
  const std::string msg = describe_status(sys, ws);
  EXPECT_TRUE(contains(msg, "inconsistent constraints")) << msg;
  EXPECT_TRUE(contains(msg, "rank(A) = 1 of 2 active rows")) << msg;
  try {
    throw_if_failed(sys, ws);
    FAIL();
  } catch (const SolveError& e) {
    EXPECT_EQ(e.status(), Status::kInconsistentConstraints);
  }
}

TEST(Errors, MisuseThrowsInvalidArgumentNamingTheProblem) {
  const System sys = pendulum(identity_mass());
  const System other = pendulum(identity_mass());
  Workspace ws(sys);
  try {
    forward_dynamics(sys, ws, VectorXd::Zero(3), VectorXd::Zero(2), 0.0);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_TRUE(contains(e.what(), "q has 3 entries, expected n = 2")) << e.what();
  }
  try {
    forward_dynamics(other, ws, VectorXd::Zero(2), VectorXd::Zero(2), 0.0);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_TRUE(contains(e.what(), "another system")) << e.what();
  }
  EXPECT_THROW(Workspace(sys, SolverOptions{.rank_threshold = 0.0}), std::invalid_argument);
  EXPECT_THROW(Workspace(sys, SolverOptions{.consistency_tolerance = -1.0}), std::invalid_argument);
}

TEST(Errors, BuilderRejectsIncompleteOrDuplicateDescriptions) {
  EXPECT_THROW(SystemBuilder(0), std::invalid_argument);
  EXPECT_THROW(SystemBuilder({"x", "x"}), std::invalid_argument);
  try {
    SystemBuilder(2).build();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_TRUE(contains(e.what(), "no mass matrix")) << e.what();
  }
  EXPECT_THROW(SystemBuilder(2).mass_matrix(MatrixXd::Identity(3, 3)), std::invalid_argument);
  auto c = holonomic("c", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[0]; });
  EXPECT_THROW(SystemBuilder(2).mass_matrix(MatrixXd::Identity(2, 2)).add(c).add(c).build(),
               std::invalid_argument);
  EXPECT_THROW(holonomic("", 1, [](const auto&, const auto&, auto&) {}), std::invalid_argument);
  EXPECT_THROW(holonomic("z", 0, [](const auto&, const auto&, auto&) {}), std::invalid_argument);
  EXPECT_THROW(c.active_between(2.0, 1.0), std::invalid_argument);
  const System sys = pendulum(identity_mass());
  try {
    sys.constraint_index("rdo");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_TRUE(contains(e.what(), "no constraint named 'rdo'; the constraints are 'rod'"))
        << e.what();
  }
}

TEST(Errors, RecoversAfterAFailure) {
  const System sys = pendulum(identity_mass());
  Workspace ws(sys);
  EXPECT_EQ(forward_dynamics(sys, ws, state(kNaN, 0), state(0, 0), 0.0), Status::kNonFiniteInput);
  EXPECT_EQ(forward_dynamics(sys, ws, state(1, 0), state(0, 0), 0.0), Status::kOk);
  EXPECT_EQ(describe_status(sys, ws), "ok");
  EXPECT_NEAR(ws.Qc.norm(), 0.0, 1e-15);  // horizontal at rest: no tension
  EXPECT_EQ(ws.counters.evaluations, 2);
  EXPECT_EQ(ws.counters.failures, 1);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
