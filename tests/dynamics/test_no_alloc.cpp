// SPDX-License-Identifier: BSD-3-Clause
// No heap allocation per evaluation once the workspace exists, for every kind of constraint,
// non-ideal forces, rank-deficient and large systems.
#include <array>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <ukdyn/ukdyn.hpp>

#include "support/alloc_counter.hpp"
#include "support/random_problem.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using testing::start_counting_allocations;
using testing::stop_counting_allocations;

// allocations made by `calls` evaluations on a fresh workspace (none before them)
long allocations_of(const System& sys, const Eigen::Ref<const VectorXd>& q,
                    const Eigen::Ref<const VectorXd>& qd, int calls,
                    const SolverOptions& options = {}) {
  Workspace ws(sys, options);
  start_counting_allocations();
  for (int i = 0; i < calls; ++i) forward_dynamics(sys, ws, q, qd, 0.01 * i);
  const long count = stop_counting_allocations();
  EXPECT_EQ(ws.status, Status::kOk) << describe_status(sys, ws);
  return count;
}

TEST(NoAllocation, CounterSeesAllocations) {
  start_counting_allocations();
  VectorXd v = VectorXd::Constant(100, 1.0);
  asm volatile("" : : "r"(v.data()) : "memory");  // keep the allocation
  const long count = stop_counting_allocations();
  EXPECT_EQ(count, 1);  // Eigen's buffer, through malloc
  EXPECT_DOUBLE_EQ(v.sum(), 100.0);
}

TEST(NoAllocation, TextbookAlgorithmAllocatesSoTheCounterSeesEigen) {
  const auto p = testing::random_problem(6, 3, 3, 1u, true);
  const System sys = make_system(p);
  const VectorXd z = VectorXd::Zero(6);
  EXPECT_GT(allocations_of(sys, z, z, 3, SolverOptions{.algorithm = Algorithm::kTextbook}), 3);
}

TEST(NoAllocation, AutomaticallyDifferentiatedConstraintsAndFriction) {
  // a sleigh-like system (x, y, th, z) with a holonomic, a time-dependent holonomic, a knife
  // edge and a velocity-quadratic constraint, Coulomb and viscous friction, state-dependent M
  const System sys =
      SystemBuilder({"x", "y", "th", "z", "w"})
          .mass_matrix([](const Eigen::Ref<const VectorXd>& q, double, Eigen::Ref<MatrixXd> M) {
            M.setIdentity();
            M(2, 2) = 1.0 + 0.1 * q[0] * q[0];
          })
          .forces([](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                     double t, Eigen::Ref<VectorXd> Q) {
            Q = -0.1 * qd;
            Q[3] -= 9.81;
            Q[0] += std::sin(t) * q[1];
          })
          .add(holonomic(
              "floor", 1,
              [](const auto& q, const auto&, auto& phi) { phi[0] = q[3] - 0.1 * q[0] * q[0]; }))
          .add(holonomic("clock", 1,
                         [](const auto& q, const auto& t, auto& phi) {
                           using std::sin;
                           phi[0] = q[4] - sin(t) * q[1];
                         }))
          .add(nonholonomic("knife", 1,
                            [](const auto& q, const auto& qd, const auto&, auto& psi) {
                              using std::cos;
                              using std::sin;
                              psi[0] = qd[0] * sin(q[2]) - qd[1] * cos(q[2]);
                            }))
          .add(coulomb_friction({.constraint = "floor", .mu = 0.2, .coordinates = {0, 1}}))
          .add(viscous_friction({.coefficient = 0.3, .coordinates = {2}}))
          .build();
  VectorXd q(5), qd(5);
  q << 0.3, -0.2, 0.4, 0.009, 0.0;
  qd << 0.5, 0.2, -0.1, 0.03, 0.0;
  EXPECT_EQ(allocations_of(sys, q, qd, 10), 0);
  // the same state as views (a segment of a longer vector, a Map over a std::array) and as
  // fixed-size vectors: the entry points and the callables take Eigen::Ref, nothing is copied
  VectorXd padded = VectorXd::Zero(9);
  padded.segment(2, 5) = q;
  std::array<double, 5> qd_values{};
  Eigen::Map<VectorXd>(qd_values.data(), 5) = qd;
  EXPECT_EQ(allocations_of(sys, padded.segment(2, 5),
                           Eigen::Map<const VectorXd>(qd_values.data(), 5), 10),
            0);
  const Eigen::Vector<double, 5> q_fixed = q, qd_fixed = qd;
  EXPECT_EQ(allocations_of(sys, q_fixed, qd_fixed, 10), 0);
}

TEST(NoAllocation, FrictionFixedPointAcceleratedNearPainlevesCriticalMu) {
  // Painlevé's rod (tests/simulation/test_contact_friction.cpp) at mu = 1.3 = 0.975 mu_c: the
  // plain rounds contract slowly, so apply_nonideal extrapolates (Anderson) from its second round
  const double m = 1.0, g = 9.81;
  MatrixXd M(4, 4);
  M << 2, 0, 1, 0, 0, 2, 0, 1, 1, 0, 2, 0, 0, 1, 0, 2;
  M *= m / 6.0;
  const System sys =
      SystemBuilder({"xA", "yA", "xB", "yB"})
          .mass_matrix(M)
          .forces([m, g](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&,
                         double, Eigen::Ref<VectorXd> Q) {
            Q.setZero();
            Q[1] = Q[3] = -m * g / 2;
          })
          .add(holonomic("rod", 1,
                         [](const auto& q, const auto&, auto& phi) {
                           const auto dx = q[0] - q[2], dy = q[1] - q[3];
                           phi[0] = (dx * dx + dy * dy - 4.0) / 4.0;
                         }))
          .add(holonomic("floor", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[1]; }))
          .add(coulomb_friction({.constraint = "floor", .mu = 1.3, .coordinates = {0}}))
          .build();
  const double th = std::atan(2.0);
  VectorXd q(4), qd(4);
  q << 0.0, 0.0, 2.0 * std::cos(th), 2.0 * std::sin(th);
  qd << -1.0, 0.0, -1.0, 0.0;
  EXPECT_EQ(allocations_of(sys, q, qd, 10), 0);
  Workspace ws(sys);
  ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
  EXPECT_EQ(ws.counters.nonideal_unsettled, 0);
  EXPECT_GE(ws.counters.nonideal_rounds, 3);
  EXPECT_LE(ws.counters.nonideal_rounds, 4);
  const double N = m * g / (1.6 - 1.2 * 1.3);
  EXPECT_NEAR(ws.lambda[1] + ws.lambda_nonideal[1], N, 1e-9 * N);
}

using testing::Case;
class NoAllocationRandom : public ::testing::TestWithParam<Case> {};

TEST_P(NoAllocationRandom, DefaultAlgorithm) {
  const auto [n, m, r] = GetParam();
  const auto p = testing::random_problem(n, m, r, 42u, true);
  const System sys = make_system(p);
  const VectorXd z = VectorXd::Zero(n);
  EXPECT_EQ(allocations_of(sys, z, z, 5), 0);
}

INSTANTIATE_TEST_SUITE_P(Sizes, NoAllocationRandom,
                         ::testing::Values(Case{6, 3, 3}, Case{6, 3, 2}, Case{30, 20, 20},
                                           Case{30, 20, 12}, Case{120, 80, 80}, Case{120, 80, 40},
                                           Case{10, 15, 8}),
                         testing::CaseName());

// singular mass matrices (the auxiliary M + Aᵀ G A): the pendulum in (x, y, theta) with
// M = diag(m, m, 0) on the dense engine, and a chain of rigid bodies whose quaternion blocks are
// singular on the sparse engine
TEST(NoAllocation, SingularMassMatrices) {
  {
    MatrixXd M = MatrixXd::Zero(3, 3);
    M(0, 0) = M(1, 1) = 2.0;
    const System sys =
        SystemBuilder({"x", "y", "th"})
            .mass_matrix(M)
            .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                       Eigen::Ref<VectorXd> Q) { Q << 0.0, -19.62, 0.0; })
            .add(holonomic("cx", 1,
                           [](const auto& q, const auto&, auto& phi) {
                             using std::sin;
                             phi[0] = q[0] - sin(q[2]);
                           }))
            .add(holonomic("cy", 1,
                           [](const auto& q, const auto&, auto& phi) {
                             using std::cos;
                             phi[0] = q[1] + cos(q[2]);
                           }))
            .build();
    VectorXd q(3), qd(3);
    q << std::sin(0.7), -std::cos(0.7), 0.7;
    qd << std::cos(0.7) * 1.5, std::sin(0.7) * 1.5, 1.5;
    EXPECT_EQ(allocations_of(sys, q, qd, 3), 0);
    Workspace ws(sys);
    ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
    EXPECT_TRUE(ws.mass_singular);
  }
  {
    mb::Multibody b;
    b.set_gravity({0, 0, -9.81});
    mb::BodyId prev = mb::kGround;
    for (int i = 0; i < 12; ++i) {
      const Eigen::Quaterniond u(Eigen::AngleAxisd(0.1 * i, Eigen::Vector3d::UnitX()));
      const mb::BodyId id =
          b.add_rigid_body("b" + std::to_string(i), 1.0, {0.1, 0.1, 0.02},
                           u * Eigen::Vector3d(0, 0, -0.5), u, Eigen::Vector3d::Zero(), {0, 0, 1});
      b.add_joint(mb::spherical("s" + std::to_string(i), prev, {0, 0, 0}, id, {0, 0, 0.5}));
      prev = id;
    }
    const mb::MultibodyModel m = b.build();
    SolverOptions o;
    o.engine = Engine::kSparse;
    EXPECT_EQ(allocations_of(m.system, m.q0, m.qd0, 3, o), 0);
    Workspace ws(m.system, o);
    ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, m.qd0, 0.0), Status::kOk);
    EXPECT_TRUE(ws.mass_singular);
  }
}

// multibody models (multibody/multibody.hpp): quaternion blocks, closed-form and AD-based joint
// rows, rolling, a drive and pin friction — on the dense engine and, for a long chain, the sparse
// one
TEST(NoAllocation, MultibodyModels) {
  using mb::BodyId;
  using mb::Frame;
  const BodyId kGround = mb::kGround;
  using Eigen::Quaterniond;
  using Eigen::Vector3d;
  const auto about = [](double angle, const Vector3d& axis) {
    return Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
  };
  {  // a heavy top on a spherical joint
    mb::Multibody b;
    const BodyId top = b.add_rigid_body("top", 1.0, {0.02, 0.02, 0.01}, {0.05, 0.0, 0.2},
                                        about(0.25, Vector3d::UnitY()), {0, 0.1, 0}, {0.3, 0, 20});
    b.add_joint(mb::spherical("tip", kGround, {0, 0, 0}, top, {0, 0, -0.2062}));
    b.set_gravity({0, 0, -9.81});
    const mb::MultibodyModel m = b.build();
    EXPECT_EQ(allocations_of(m.system, m.q0, m.qd0, 3), 0);
  }
  {  // a rolling disk
    mb::Multibody b;
    const double R = 0.3;
    const BodyId disk =
        b.add_rigid_body("disk", 1.0, {R * R / 4, R * R / 4, R * R / 2}, {0, 0, R * std::cos(0.3)},
                         about(1.2707963, Vector3d::UnitY()), {0.5, 0, 0});
    b.add_joint(mb::rolling_disk("roll", disk, R));
    b.set_gravity({0, 0, -9.81});
    const mb::MultibodyModel m = b.build();
    EXPECT_EQ(allocations_of(m.system, m.q0, m.qd0, 3), 0);
  }
  // the allocations of one evaluation of a spatial contact's stick rows (2 × n)
  const auto stick_rows_allocations = [](const mb::MultibodyModel& m, const char* name) {
    const Index stick = m.system.constraint_index(name);
    Workspace ws(m.system);
    MatrixXd A = MatrixXd::Zero(2, m.system.coordinate_count());
    VectorXd bb = VectorXd::Zero(2);
    start_counting_allocations();
    m.system.constraint(stick).model().acceleration_form(
        m.q0, m.qd0, 0.0, ws.scratch[std::size_t(stick)].get(), A, bb);
    return stop_counting_allocations();
  };
  {  // Coulomb friction at a sphere's contact point, sliding (ContactKinematics)
    mb::Multibody b;
    const double r = 0.1;
    const BodyId ball = b.add_rigid_body("ball", 1.0, {0.004, 0.004, 0.004}, {0, 0, r},
                                         Quaterniond::Identity(), {1, 0.5, 0}, {0, 2, 0});
    b.add_joint(mb::contact("floor", kGround, Frame{}, ball, Vector3d::Zero(), r));
    b.add_contact_friction("floor", 0.3);
    b.set_gravity({0, 0, -9.81});
    const mb::MultibodyModel m = b.build();
    EXPECT_EQ(allocations_of(m.system, m.q0, m.qd0, 3), 0);
    // and its stick constraint's rows (evaluated by a projection's assembly)
    EXPECT_EQ(stick_rows_allocations(m, "stick.coulomb.floor"), 0);
  }
  {  // Coulomb friction between moving bodies (relative ContactKinematics): a sphere on a
     // plane of a turning deck, a disk's rim point on it, a sphere on a sphere of the deck
    mb::Multibody b;
    const double r = 0.1;
    const BodyId deck = b.add_rigid_body("deck", 5.0, {1, 2, 3}, {0, 0, 0},
                                         about(0.2, Vector3d::UnitX()), {0.1, 0, 0}, {0.3, 0, 0.5});
    const BodyId ball = b.add_rigid_body("ball", 1.0, {0.004, 0.004, 0.004}, {0, 0, 1},
                                         Quaterniond::Identity(), {1, 0.5, 0}, {0, 2, 0});
    const BodyId coin = b.add_rigid_body("coin", 1.0, {0.004, 0.008, 0.004}, {1, 0, 1},
                                         about(1.2, Vector3d::UnitX()), {0.5, 0, 0}, {0, 3, 0});
    b.add_joint(mb::contact("top", deck, Frame{}, ball, Vector3d::Zero(), r));
    b.add_joint(mb::contact_disk("rim", deck, Frame{}, coin, Frame{}, r));
    b.add_joint(mb::contact_spheres("dome", deck, {0, 0, 0.5}, 0.3, ball, Vector3d::Zero(), r));
    for (const char* c : {"top", "rim", "dome"}) b.add_contact_friction(c, 0.3);
    b.set_gravity({0, 0, -9.81});
    const mb::MultibodyModel m = b.build();
    EXPECT_EQ(allocations_of(m.system, m.q0, m.qd0, 3), 0);
    for (const char* c : {"stick.coulomb.top", "stick.coulomb.rim", "stick.coulomb.dome"})
      EXPECT_EQ(stick_rows_allocations(m, c), 0) << c;
  }
  {  // a driven crank with pin friction, and a long planar chain closed to ground (sparse)
    mb::Multibody b;
    b.set_gravity({0, -9.81, 0});
    const BodyId crank = b.add_planar_body("crank", 1.0, 0.1, {0.5, 0, 0}, {0, 0.5, 1.0});
    mb::Joint pin =
        mb::revolute("pin", kGround, Frame::planar(0, 0), crank, Frame::planar(-0.5, 0));
    pin.drive = [](double t) { return Vector3d(t, 1.0, 0.0); };
    pin.friction.mu = 0.2;
    pin.friction.radius = 0.01;
    b.add_joint(pin);
    const mb::MultibodyModel m = b.build();
    EXPECT_EQ(allocations_of(m.system, m.q0, m.qd0, 3), 0);
  }
  {
    mb::Multibody b;
    b.set_gravity({0, -9.81, 0});
    const int N = 40;
    const double L = 2.0 / N;
    BodyId prev = kGround;
    for (int i = 0; i < N; ++i) {
      const BodyId link =
          b.add_planar_body("link" + std::to_string(i), L, L * L * L / 12, {(i + 0.5) * L, 0, 0});
      b.add_joint(mb::revolute("pin" + std::to_string(i), prev,
                               Frame::planar(prev == kGround ? 0.0 : L / 2, 0), link,
                               Frame::planar(-L / 2, 0)));
      prev = link;
    }
    b.add_joint(
        mb::revolute("close", kGround, Frame::planar(2.0, 0), prev, Frame::planar(L / 2, 0)));
    const mb::MultibodyModel m = b.build();
    EXPECT_EQ(allocations_of(m.system, m.q0, m.qd0, 3, SolverOptions{.engine = Engine::kSparse}),
              0);
  }
}

// The steps of a run allocate nothing: only the samples do. Two RK4 runs of a double pendulum
// with the same samples (t_start and t_end) and 500 against 1000 steps make the same number of
// allocations (before, every step of the fixed-step loop allocated its std::function).
TEST(NoAllocation, SimulationStepsOfFixedStepMethods) {
  using mb::BodyId;
  using mb::Frame;
  mb::Multibody b;
  b.set_gravity({0, -9.81, 0});
  const BodyId l0 = b.add_planar_body("l0", 1.0, 1e-3, {1, 0, 0});
  const BodyId l1 = b.add_planar_body("l1", 1.0, 1e-3, {2, 0, 0});
  b.add_joint(mb::revolute("p0", mb::kGround, Frame::planar(0, 0), l0, Frame::planar(-1, 0)));
  b.add_joint(mb::revolute("p1", l0, Frame::planar(0, 0), l1, Frame::planar(-1, 0)));
  const mb::MultibodyModel m = b.build();
  const auto allocations_of_run = [&](double t_end, Integrator method) {
    SimulationOptions o;
    o.integrator = method;
    o.step = 1e-3;
    o.t_end = t_end;
    o.output_every = 0.0;  // samples at t_start and t_end only
    start_counting_allocations();
    const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
    const long count = stop_counting_allocations();
    EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    EXPECT_EQ(tr.t.size(), 2U);
    return count;
  };
  allocations_of_run(0.1, Integrator::kRK4);  // (the first run also makes what is made once)
  for (const Integrator method : {Integrator::kRK4, Integrator::kRK5}) {
    const long short_run = allocations_of_run(0.5, method);
    const long long_run = allocations_of_run(1.0, method);
    EXPECT_GT(short_run, 0);  // the run's setup, so the counter saw it
    EXPECT_EQ(long_run, short_run) << int(method);
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
