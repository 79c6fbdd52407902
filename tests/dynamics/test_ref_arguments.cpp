// SPDX-License-Identifier: BSD-3-Clause
// The public entry points and the callables take their read-only vectors as
// Eigen::Ref<const VectorXd> (issue #15, item 5): a segment of a larger vector, an Eigen::Map over
// a std::array and a fixed-size Eigen::Vector<double, N> pass without a copy, and every result is
// bitwise the one from plain VectorXd arguments. The segment sits between NaNs, so an entry point
// that read past it would give NaN. Every view starts where a VectorXd's data would (Eigen's
// alignment): Eigen's vectorized reductions (dot, norm, sum) start with the entries before the
// first aligned one, so a view at another address may round them differently in the last bit.
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <ukdyn/ukdyn.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// the same values as v (size N) held three other ways
template <int N>
struct Views {
  // the segment's offset: one alignment unit of doubles
  static constexpr int kOffset = EIGEN_MAX_ALIGN_BYTES / int(sizeof(double));
  explicit Views(const VectorXd& v) : padded(VectorXd::Constant(N + 2 * kOffset, kNaN)), fixed(v) {
    for (int i = 0; i < N; ++i) {
      padded[kOffset + i] = v[i];
      array[std::size_t(i)] = v[i];
    }
  }
  VectorXd padded;  // v at [kOffset, kOffset + N), NaN around it
  alignas(EIGEN_MAX_ALIGN_BYTES) std::array<double, N> array{};  // v
  alignas(EIGEN_MAX_ALIGN_BYTES) Eigen::Vector<double, N> fixed;

  auto segment() const { return padded.segment(kOffset, N); }
  Eigen::Map<const VectorXd> map() const { return Eigen::Map<const VectorXd>(array.data(), N); }
};

// a and b hold the same bits
::testing::AssertionResult bitwise_equal(const Eigen::Ref<const MatrixXd>& a,
                                         const Eigen::Ref<const MatrixXd>& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) {
    return ::testing::AssertionFailure() << "sizes differ";
  }
  for (Index j = 0; j < a.cols(); ++j) {
    for (Index i = 0; i < a.rows(); ++i) {
      const double x = a(i, j), y = b(i, j);
      if (std::memcmp(&x, &y, sizeof(double)) != 0) {
        return ::testing::AssertionFailure()
               << "entry (" << i << ", " << j << "): " << a(i, j) << " vs " << b(i, j);
      }
    }
  }
  return ::testing::AssertionSuccess();
}

::testing::AssertionResult bitwise_equal(const std::vector<double>& a,
                                         const std::vector<double>& b) {
  return bitwise_equal(Eigen::Map<const VectorXd>(a.data(), Index(a.size())),
                       Eigen::Map<const VectorXd>(b.data(), Index(b.size())));
}

// forward dynamics, the violations, the system's callables and a short simulation at (q, q', t)
// with arguments of type Q and QD, bitwise against the same calls with VectorXd arguments
template <class Q, class QD>
void expect_same_as_vectorxd(const System& sys, const VectorXd& q, const VectorXd& qd, double t,
                             const Q& q_view, const QD& qd_view) {
  const Index n = sys.coordinate_count();
  // forward_dynamics: q'', the constraint forces and the multipliers
  Workspace ws_plain(sys), ws_view(sys);
  ASSERT_EQ(forward_dynamics(sys, ws_plain, q, qd, t), Status::kOk);
  ASSERT_EQ(forward_dynamics(sys, ws_view, q_view, qd_view, t), Status::kOk);
  EXPECT_TRUE(bitwise_equal(ws_view.qdd, ws_plain.qdd));
  EXPECT_TRUE(bitwise_equal(ws_view.Qc_ideal, ws_plain.Qc_ideal));
  EXPECT_TRUE(bitwise_equal(ws_view.Qc_nonideal, ws_plain.Qc_nonideal));
  EXPECT_TRUE(bitwise_equal(ws_view.lambda, ws_plain.lambda));
  // measure_violations (dynamics/projection.hpp)
  const Violations v_plain = measure_violations(sys, ws_plain, q, qd, t);
  const Violations v_view = measure_violations(sys, ws_view, q_view, qd_view, t);
  EXPECT_TRUE(v_plain.finite);
  EXPECT_EQ(0, std::memcmp(&v_view.position, &v_plain.position, sizeof(double)));
  EXPECT_EQ(0, std::memcmp(&v_view.velocity, &v_plain.velocity, sizeof(double)));
  // the system's callables: M, Q, V
  MatrixXd M_plain(n, n), M_view(n, n);
  sys.mass_matrix(q, t, M_plain);
  sys.mass_matrix(q_view, t, M_view);
  EXPECT_TRUE(bitwise_equal(M_view, M_plain));
  VectorXd Q_plain(n), Q_view(n);
  sys.forces(q, qd, t, Q_plain);
  sys.forces(q_view, qd_view, t, Q_view);
  EXPECT_TRUE(bitwise_equal(Q_view, Q_plain));
  const double V_plain = sys.potential_energy(q, t), V_view = sys.potential_energy(q_view, t);
  EXPECT_EQ(0, std::memcmp(&V_view, &V_plain, sizeof(double)));
  // simulate from that state (projected onto the constraints first): every sample
  SimulationOptions o{
      .t_start = t, .t_end = t + 0.05, .integrator = Integrator::kRK4, .step = 1e-2};
  // (the state is off the constraints: simulate projects it first, through the views)
  o.project_initial = true;
  const Trajectory tr_plain = simulate(sys, q, qd, o);
  const Trajectory tr_view = simulate(sys, q_view, qd_view, o);
  ASSERT_EQ(tr_view.stats.status, tr_plain.stats.status);
  EXPECT_EQ(tr_plain.stats.status, Status::kOk) << tr_plain.stats.message;
  EXPECT_TRUE(bitwise_equal(tr_view.t, tr_plain.t));
  EXPECT_TRUE(bitwise_equal(tr_view.q, tr_plain.q));
  EXPECT_TRUE(bitwise_equal(tr_view.qd, tr_plain.qd));
  EXPECT_TRUE(bitwise_equal(tr_view.lambda, tr_plain.lambda));
}

// every kind of argument for one example at its initial state (stepped a little off it, so
// that the violations are not all zero)
template <int N>
void expect_every_kind_same(const gallery::Example& ex) {
  ASSERT_EQ(ex.system.coordinate_count(), N) << ex.name;
  const VectorXd q = ex.q0 + VectorXd::LinSpaced(N, 1e-3, 2e-3);
  const VectorXd qd = ex.qd0 + VectorXd::LinSpaced(N, 0.1, 0.2);
  const Views<N> vq(q), vqd(qd);
  {
    SCOPED_TRACE(ex.name + ": segments");
    expect_same_as_vectorxd(ex.system, q, qd, 0.1, vq.segment(), vqd.segment());
  }
  {
    SCOPED_TRACE(ex.name + ": maps over std::array");
    expect_same_as_vectorxd(ex.system, q, qd, 0.1, vq.map(), vqd.map());
  }
  {
    SCOPED_TRACE(ex.name + ": fixed-size vectors");
    expect_same_as_vectorxd(ex.system, q, qd, 0.1, vq.fixed, vqd.fixed);
  }
  {
    SCOPED_TRACE(ex.name + ": mixed");
    expect_same_as_vectorxd(ex.system, q, qd, 0.1, vq.map(), vqd.segment());
  }
}

TEST(RefArguments, PendulumHolonomic) { expect_every_kind_same<2>(gallery::pendulum()); }

TEST(RefArguments, BeadOnRotatingWireRheonomic) {
  expect_every_kind_same<2>(gallery::bead_on_rotating_wire());
}

TEST(RefArguments, BlockOnInclineCoulombFriction) {
  expect_every_kind_same<2>(gallery::block_on_incline());
}

TEST(RefArguments, ChaplyginSleighNonholonomic) {
  const gallery::Example ex = gallery::chaplygin_sleigh();
  ASSERT_EQ(ex.system.coordinate_count(), 3);
  expect_every_kind_same<3>(ex);
}

TEST(RefArguments, ReportedCoordinateOfASharedProblem) {
  const gallery::Example ex = gallery::shared_P2();
  ASSERT_EQ(ex.q0.size(), 4);
  const Views<4> v(ex.q0);
  const double plain = gallery::reported_coordinate("shared_P2", ex.q0);
  for (const double x : {gallery::reported_coordinate("shared_P2", v.segment()),
                         gallery::reported_coordinate("shared_P2", v.map()),
                         gallery::reported_coordinate("shared_P2", v.fixed)}) {
    EXPECT_EQ(0, std::memcmp(&x, &plain, sizeof(double)));
  }
}

TEST(RefArguments, MultibodyReports) {
  // a planar pendulum body on a revolute joint: x, y, theta
  mb::Multibody b;
  const mb::BodyId rod = b.add_planar_body("rod", 2.0, 0.5, Eigen::Vector3d(0.3, -0.4, 0.2),
                                           Eigen::Vector3d(0.1, 0.2, 0.3));
  b.add_joint(mb::revolute("pin", mb::kGround, mb::Frame{}, rod,
                           mb::Frame::at(Eigen::Vector3d(-0.3, 0.4, 0.0))));
  b.set_gravity(Eigen::Vector3d(0, -9.81, 0));
  const mb::MultibodyModel m = b.build();
  ASSERT_EQ(m.system.coordinate_count(), 3);
  const VectorXd q = m.q0, qd = m.qd0 + VectorXd::Constant(3, 0.05);
  const Views<3> vq(q), vqd(qd);
  const double E = mb::total_energy(m, q, qd, 0.0);
  const mb::Pose P = mb::body_pose(m, q, rod);
  // (not a structured binding: clang 14 does not let a lambda capture one)
  const auto momentum = mb::momentum(m, q, qd);
  const auto& p = momentum.first;
  const auto& L = momentum.second;
  auto check = [&](const auto& qv, const auto& qdv) {
    const double Ev = mb::total_energy(m, qv, qdv, 0.0);
    EXPECT_EQ(0, std::memcmp(&Ev, &E, sizeof(double)));
    const mb::Pose Pv = mb::body_pose(m, qv, rod);
    EXPECT_TRUE(bitwise_equal(Pv.p_WB, P.p_WB));
    EXPECT_TRUE(bitwise_equal(Pv.R_WB.coeffs(), P.R_WB.coeffs()));
    const auto [pv, Lv] = mb::momentum(m, qv, qdv);
    EXPECT_TRUE(bitwise_equal(pv, p));
    EXPECT_TRUE(bitwise_equal(Lv, L));
  };
  check(vq.segment(), vqd.segment());
  check(vq.map(), vqd.map());
  check(vq.fixed, vqd.fixed);
}

TEST(RefArguments, CallablesReceiveTheCallersMemory) {
  // with a segment, M and Q see the caller's own storage (no copy was made on the way)
  VectorXd padded = VectorXd::Constant(6, kNaN);
  padded.segment(2, 2) << 0.6, -0.8;
  const double* seen_by_M = nullptr;
  const double* seen_by_Q = nullptr;
  const System sys =
      SystemBuilder(2)
          .mass_matrix([&](const Eigen::Ref<const VectorXd>& q, double, Eigen::Ref<MatrixXd> M) {
            seen_by_M = q.data();
            M.setIdentity();
          })
          .forces([&](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>&,
                      double, Eigen::Ref<VectorXd> Q) {
            seen_by_Q = q.data();
            Q << 0.0, -9.81;
          })
          .build();
  Workspace ws(sys);
  const Eigen::Vector2d qd(0.0, 0.0);
  ASSERT_EQ(forward_dynamics(sys, ws, padded.segment(2, 2), qd, 0.0), Status::kOk);
  EXPECT_EQ(seen_by_M, padded.data() + 2);
  EXPECT_EQ(seen_by_Q, padded.data() + 2);
  EXPECT_DOUBLE_EQ(ws.qdd[1], -9.81);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
