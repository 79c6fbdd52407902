// SPDX-License-Identifier: BSD-3-Clause
// Singular (positive semi-definite) mass matrices (issue #13, item 3; the math reference,
// docs/theory.md section 6): M may be singular as long as [M; A] has full column rank,
// and then q'' and Qc = M q'' − Q are unique. Every expected number comes from analysis or from
// an independent formulation, never from the code under test:
//
//  1. a pendulum in redundant coordinates (x, y, theta) with M = diag(m, m, 0): the exact
//     elliptic-function solution, its period and the rod tension; dense and sparse engines;
//  3. two particles on a massless link whose massless midpoint is a coordinate: the same system
//     without the midpoint, and the centre of mass falling while the link turns uniformly;
//  5. model files whose kinetic energy omits a velocity or whose mass_matrix has a zero row;
//  6. q'' is the q'' of the regular auxiliary system M + Aᵀ G A, Q + Aᵀ G b for any G, built
//     here by hand, and of the KKT system [M Aᵀ; A 0].
// (2, the torque-free top on quaternions, and 4, motion that [M; A] leaves undetermined:
// test_singular_mass_bodies.cpp.)
//
// Tests named SingularMassReference.* check the references themselves on regular systems that
// ukdyn solves without the singular-mass support (a rotational inertia J > 0 on theta, the J = 0
// pendulum as a hand-written auxiliary system M + g AᵀA, the dumbbell without its midpoint, the
// auxiliary systems against KKT): they
// hold before and after the implementation. The SingularMass.* tests need it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Dense>
#include <boost/math/special_functions/ellint_1.hpp>
#include <boost/math/special_functions/jacobi_elliptic.hpp>

#include "ukdyn/core/autodiff.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

#include "support/singular_mass.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using Eigen::Vector2d;

using test::expect_relative;
using test::kMotionUndetermined;

// column i of a trajectory field stored N × width
VectorXd sample(const std::vector<double>& f, Index width, Index i) {
  return Trajectory::view(f, width).col(i);
}

// =============================================================================================
// 1. the pendulum in redundant coordinates (x, y, theta)
//
// A particle of mass m at (x, y) = (L sin theta, −L cos theta) (two holonomic rows), gravity
// along −y, T = ½ m (x'² + y'²) + ½ J theta'². With J = 0 (the case of issue #13) M = diag(m,
// m, 0) is singular and theta is set by the constraints alone; with J > 0 (the reference check,
// solvable today) the particle and a flywheel of inertia J on theta form a compound pendulum.
// Either way theta'' = −w² sin theta with w² = m g L / (m L² + J), so released at rest from
// theta0 (|theta0| < pi):
//   sin(theta/2) = k sn(K(k) − w t, k),  k = sin(theta0/2),  period 4 K(k) / w,
//   theta' = −2 k w cn dn / cos(theta/2)   (d/dt of the above; cos(theta/2) > 0),
//   theta'² = 2 w² (cos theta − cos theta0)   (energy).
// The rod's force on the particle, F = m p'' + m g e_y, has the component T = m g cos theta
// + m L theta'² towards the pivot and m sin theta (g − L w²) along t = (cos theta, sin theta),
// which vanishes for J = 0; Qc_theta = J theta''.
struct PendulumParams {
  double m = 1.3, L = 0.9, g = 9.81, theta0 = 2.5, J = 0.0;
};

class EllipticPendulum {
 public:
  explicit EllipticPendulum(const PendulumParams& p)
      : p_(p),
        k_(std::sin(0.5 * p.theta0)),
        K_(boost::math::ellint_1(k_)),
        w_(std::sqrt(p.m * p.g * p.L / (p.m * p.L * p.L + p.J))) {}

  double period() const { return 4.0 * K_ / w_; }
  double w() const { return w_; }
  double theta(double t) const {
    return 2.0 * std::asin(k_ * boost::math::jacobi_sn(k_, K_ - w_ * t));
  }
  double theta_dot(double t) const {
    double cn = 0.0, dn = 0.0;
    const double sn = boost::math::jacobi_elliptic(k_, K_ - w_ * t, &cn, &dn);
    return -2.0 * k_ * w_ * cn * dn / std::sqrt(1.0 - k_ * k_ * sn * sn);
  }
  // theta'' at theta
  double theta_ddot(double theta) const { return -w_ * w_ * std::sin(theta); }

  // q'' = (x'', y'', theta'') at (theta, theta')
  VectorXd qdd(double th, double thd) const {
    const double s = std::sin(th), c = std::cos(th), thdd = theta_ddot(th), L = p_.L;
    VectorXd r(3);
    r << L * (c * thdd - s * thd * thd), L * (s * thdd + c * thd * thd), thdd;
    return r;
  }
  // Qc = M q'' − Q
  VectorXd Qc(double th, double thd) const {
    const VectorXd a = qdd(th, thd);
    VectorXd r(3);
    r << p_.m * a[0], p_.m * a[1] + p_.m * p_.g, p_.J * a[2];
    return r;
  }
  // the rod's pull towards the pivot
  double tension(double th, double thd) const {
    return p_.m * p_.g * std::cos(th) + p_.m * p_.L * thd * thd;
  }

 private:
  PendulumParams p_;
  double k_, K_, w_;
};

// the pendulum as a System: dense M = diag(m, m, J), or the blocks diag(m, m) and (J) for the
// sparse engine, or (one_block) the single block diag(m, m, J)
System xytheta_pendulum(const PendulumParams& p, bool blocks = false, bool one_block = false) {
  auto rod = [L = p.L](const auto& q, const auto&, auto& phi) {
    using std::cos;
    using std::sin;
    phi[0] = q[0] - L * sin(q[2]);
    phi[1] = q[1] + L * cos(q[2]);
  };
  SystemBuilder b(std::vector<std::string>{"x", "y", "theta"});
  if (one_block) {
    b.mass_block(0, Eigen::Vector3d(p.m, p.m, p.J).asDiagonal().toDenseMatrix());
  } else if (blocks) {
    b.mass_block(0, p.m * MatrixXd::Identity(2, 2));
    b.mass_block(2, MatrixXd::Constant(1, 1, p.J));
  } else {
    b.mass_matrix(Eigen::Vector3d(p.m, p.m, p.J).asDiagonal().toDenseMatrix());
  }
  const double m = p.m, g = p.g;
  return b
      .forces([m, g](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) { Q << 0.0, -m * g, 0.0; })
      .potential_energy(
          [m, g](const Eigen::Ref<const VectorXd>& q, double) { return m * g * q[1]; })
      .add(holonomic("rod", 2, rod))
      .build();
}

// (q, q') on the constraints at (theta, theta')
void pendulum_state(const PendulumParams& p, double th, double thd, VectorXd& q, VectorXd& qd) {
  q.resize(3);
  qd.resize(3);
  q << p.L * std::sin(th), -p.L * std::cos(th), th;
  qd << p.L * std::cos(th) * thd, p.L * std::sin(th) * thd, thd;
}

// the states at which the pendulum's forward dynamics is checked
const std::vector<std::pair<double, double>> kPendulumStates = {
    {2.5, 0.0}, {0.9, -1.7}, {-0.3, 4.2}, {0.0, 5.0}, {-2.2, -2.0}};

void expect_pendulum_closed_form(const PendulumParams& p, const System& sys, Workspace& ws) {
  const EllipticPendulum ref(p);
  for (const auto& [th, thd] : kPendulumStates) {
    SCOPED_TRACE("theta = " + std::to_string(th) + ", theta' = " + std::to_string(thd));
    VectorXd q, qd;
    pendulum_state(p, th, thd, q, qd);
    ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.3), Status::kOk) << describe_status(sys, ws);
    expect_relative(ws.qdd, ref.qdd(th, thd), 1e-12, "q''");
    expect_relative(ws.Qc, ref.Qc(th, thd), 1e-12, "Qc = M q'' - Q");
    EXPECT_EQ(ws.rank, 2);
    // the rod's force on the particle, split along the rod and across it
    const Vector2d towards_pivot(-std::sin(th), std::cos(th)), across(std::cos(th), std::sin(th));
    const Vector2d F = ws.Qc.head<2>();
    const double scale = p.m * p.g + p.m * p.L * thd * thd;
    EXPECT_NEAR(F.dot(towards_pivot), ref.tension(th, thd), 1e-12 * scale);
    EXPECT_NEAR(F.dot(across), p.m * std::sin(th) * (p.g - p.L * ref.w() * ref.w()), 1e-12 * scale);
  }
}

// theta and theta' of the samples against the elliptic solution; x, y on the rod; the samples
// at the periods and half periods at the turning points
void expect_follows_elliptic(const PendulumParams& p, const Trajectory& tr, double tol) {
  const EllipticPendulum ref(p);
  ASSERT_EQ(tr.n, 3);
  ASSERT_GT(tr.samples(), 100);
  double worst = 0.0, worst_rate = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    const VectorXd q = sample(tr.q, 3, i), qd = sample(tr.qd, 3, i);
    worst = std::max(worst, std::abs(q[2] - ref.theta(t)));
    worst_rate = std::max(worst_rate, std::abs(qd[2] - ref.theta_dot(t)));
    EXPECT_NEAR(q[0], p.L * std::sin(q[2]), 1e-9) << "t = " << t;
    EXPECT_NEAR(q[1], -p.L * std::cos(q[2]), 1e-9) << "t = " << t;
    const double cycles = t / (0.5 * ref.period());
    if (std::abs(cycles - std::round(cycles)) < 1e-12) {
      // a turning point: ±theta0 at rest
      const double sign = (long(std::round(cycles)) % 2 == 0) ? 1.0 : -1.0;
      EXPECT_NEAR(q[2], sign * p.theta0, tol) << "t = " << t;
      EXPECT_NEAR(qd[2], 0.0, 10 * tol * ref.w()) << "t = " << t;
    }
  }
  EXPECT_NEAR(worst, 0.0, tol);
  EXPECT_NEAR(worst_rate, 0.0, 10 * tol * ref.w());
}

SimulationOptions pendulum_run(const PendulumParams& p, int periods) {
  const double T = EllipticPendulum(p).period();
  SimulationOptions o;
  o.t_end = periods * T;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  o.output_every = 0.01;
  for (int i = 1; i < 2 * periods; ++i) o.output_at.push_back(0.5 * i * T);
  return o;
}

Trajectory run_pendulum(const PendulumParams& p, const System& sys, int periods,
                        Engine engine = Engine::kAuto) {
  VectorXd q0, qd0;
  pendulum_state(p, p.theta0, 0.0, q0, qd0);
  SimulationOptions o = pendulum_run(p, periods);
  o.solver.engine = engine;
  return simulate(sys, q0, qd0, o);
}

TEST(SingularMassReference, EllipticPendulumIsTheCompoundPendulumWithInertiaOnTheta) {
  // the period of the example pendulum (L = 1, theta0 = pi/2): 2.367841947576 s
  EXPECT_NEAR(EllipticPendulum({.m = 1, .L = 1, .g = 9.81, .theta0 = std::numbers::pi / 2, .J = 0})
                  .period(),
              2.367841947576, 1e-11);
  const PendulumParams p{.J = 0.4};
  const EllipticPendulum ref(p);
  // the closed form satisfies its own energy integral and starts at theta0
  for (double t : {0.0, 0.37, 1.1, 2.9}) {
    EXPECT_NEAR(std::pow(ref.theta_dot(t), 2),
                2 * ref.w() * ref.w() * (std::cos(ref.theta(t)) - std::cos(p.theta0)), 1e-12);
  }
  EXPECT_NEAR(ref.theta(0.0), p.theta0, 1e-14);
  // dense and block M (the sparse engine), at single states and over three periods
  for (bool blocks : {false, true}) {
    SCOPED_TRACE(blocks ? "blocks" : "dense");
    const System sys = xytheta_pendulum(p, blocks);
    for (Engine engine : {Engine::kDense, Engine::kSparse}) {
      if (engine == Engine::kSparse && !blocks) continue;
      Workspace ws(sys, SolverOptions{.engine = engine});
      expect_pendulum_closed_form(p, sys, ws);
    }
    const Trajectory tr = run_pendulum(p, sys, 3, blocks ? Engine::kSparse : Engine::kDense);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    expect_follows_elliptic(p, tr, 1e-7);
  }
}

// the J = 0 pendulum as the regular auxiliary system of section 6, written out by hand along
// the motion: M_A(q) = diag(m, m, 0) + g A(q)ᵀ A(q), Q_A = Q + g A(q)ᵀ b(q, q'), with the same
// rod. It has the motion and the constraint force M q'' − Q = M_A q'' − Q_A of the singular
// pendulum, and runs without the singular-mass support: the J = 0 references checked today.
System auxiliary_pendulum(const PendulumParams& p, double g_aux) {
  auto rod = [L = p.L](const auto& q, const auto&, auto& phi) {
    using std::cos;
    using std::sin;
    phi[0] = q[0] - L * sin(q[2]);
    phi[1] = q[1] + L * cos(q[2]);
  };
  const double m = p.m, g = p.g, L = p.L;
  auto A_of = [L](const Eigen::Ref<const VectorXd>& q) {
    Eigen::Matrix<double, 2, 3> A;
    A << 1.0, 0.0, -L * std::cos(q[2]), 0.0, 1.0, -L * std::sin(q[2]);
    return A;
  };
  return SystemBuilder(std::vector<std::string>{"x", "y", "theta"})
      .mass_matrix(
          [m, g_aux, A_of](const Eigen::Ref<const VectorXd>& q, double, Eigen::Ref<MatrixXd> M) {
            const Eigen::Matrix<double, 2, 3> A = A_of(q);
            M = g_aux * A.transpose() * A;
            M(0, 0) += m;
            M(1, 1) += m;
          })
      .forces([m, g, L, g_aux, A_of](const Eigen::Ref<const VectorXd>& q,
                                     const Eigen::Ref<const VectorXd>& qd, double,
                                     Eigen::Ref<VectorXd> Q) {
        const Vector2d b(-L * std::sin(q[2]) * qd[2] * qd[2], L * std::cos(q[2]) * qd[2] * qd[2]);
        Q = g_aux * A_of(q).transpose() * b;
        Q[1] -= m * g;
      })
      .potential_energy(
          [m, g](const Eigen::Ref<const VectorXd>& q, double) { return m * g * q[1]; })
      .add(holonomic("rod", 2, rod))
      .build();
}

TEST(SingularMassReference, AuxiliaryFormulationOfTheMasslessThetaIsTheEllipticPendulum) {
  const PendulumParams p;  // J = 0
  for (double g_aux : {0.05 * p.m, 50.0 * p.m}) {
    SCOPED_TRACE("g = " + std::to_string(g_aux));
    const System sys = auxiliary_pendulum(p, g_aux);
    Workspace ws(sys);
    expect_pendulum_closed_form(p, sys, ws);
    const Trajectory tr = run_pendulum(p, sys, 3);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    expect_follows_elliptic(p, tr, 1e-7);
    for (Index i = 0; i < tr.samples(); i += 37) {
      const VectorXd q = sample(tr.q, 3, i), Qc = sample(tr.Qc_ideal, 3, i);
      const double T = p.m * p.g * (3 * std::cos(q[2]) - 2 * std::cos(p.theta0));
      EXPECT_NEAR(Qc.head<2>().dot(Vector2d(-std::sin(q[2]), std::cos(q[2]))), T, 1e-7 * p.m * p.g);
    }
  }
}

TEST(SingularMass, RedundantPendulumAccelerationAndTensionAreTheClosedForm) {
  const PendulumParams p;  // J = 0: M = diag(m, m, 0)
  const System sys = xytheta_pendulum(p);
  Workspace ws(sys);
  expect_pendulum_closed_form(p, sys, ws);
  // the massless coordinate takes no constraint force: Qc_theta = 0 exactly as M's row is zero
  // and Q_theta = 0
  EXPECT_NEAR(ws.Qc[2], 0.0, 1e-12 * p.m * p.g);
}

TEST(SingularMass, RedundantPendulumFollowsTheEllipticSolutionForThreePeriods) {
  const PendulumParams p;
  const Trajectory tr = run_pendulum(p, xytheta_pendulum(p), 3);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_NEAR(tr.t.back(), 3 * EllipticPendulum(p).period(), 1e-12);
  expect_follows_elliptic(p, tr, 1e-7);
  // the rod tension along the run: lambda of the rows x − L sin theta, y + L cos theta is
  // (Qc_x, Qc_y), and |Qc_xy| = T = m g (3 cos theta − 2 cos theta0)
  for (Index i = 0; i < tr.samples(); i += 37) {
    const VectorXd q = sample(tr.q, 3, i), Qc = sample(tr.Qc_ideal, 3, i);
    const double T = p.m * p.g * (3 * std::cos(q[2]) - 2 * std::cos(p.theta0));
    EXPECT_NEAR(Qc.head<2>().dot(Vector2d(-std::sin(q[2]), std::cos(q[2]))), T, 1e-7 * p.m * p.g);
    EXPECT_NEAR(Qc[2], 0.0, 1e-9 * p.m * p.g);
  }
}

// The sparse engine completes a singular block with the rows local to it (docs/singular-mass.md):
// theta's own block (0) is tied to (x, y) only by the rod rows, so that form is refused with
// the documented error and hint; diag(m, m, 0) as one block runs.
TEST(SingularMass, SparseEngineNeedsTheRowsThatDetermineASingularBlockToBeLocal) {
  const PendulumParams p;
  const System split = xytheta_pendulum(p, true);
  Workspace ws(split, SolverOptions{.engine = Engine::kSparse});
  VectorXd q, qd;
  pendulum_state(p, 0.9, -1.7, q, qd);
  ASSERT_EQ(forward_dynamics(split, ws, q, qd, 0.25), Status::kMotionUndetermined);
  const std::string msg = describe_status(split, ws);
  EXPECT_NE(msg.find("the coordinates 'theta' are not determined"), std::string::npos) << msg;
  EXPECT_NE(msg.find("use Engine::kDense"), std::string::npos) << msg;
  EXPECT_NE(msg.find("t = 0.25"), std::string::npos) << msg;
  Workspace wd(split, SolverOptions{.engine = Engine::kDense});
  EXPECT_EQ(forward_dynamics(split, wd, q, qd, 0.25), Status::kOk) << describe_status(split, wd);
}

TEST(SingularMass, RedundantPendulumIsTheSameOnTheDenseAndTheSparseEngine) {
  const PendulumParams p;
  const System dense = xytheta_pendulum(p), blocks = xytheta_pendulum(p, true, true);
  Workspace wd(dense, SolverOptions{.engine = Engine::kDense});
  Workspace wb(blocks, SolverOptions{.engine = Engine::kDense});
  Workspace ws(blocks, SolverOptions{.engine = Engine::kSparse});
  ASSERT_TRUE(ws.is_sparse());
  expect_pendulum_closed_form(p, dense, wd);
  expect_pendulum_closed_form(p, blocks, wb);
  expect_pendulum_closed_form(p, blocks, ws);
  for (const auto& [th, thd] : kPendulumStates) {
    VectorXd q, qd;
    pendulum_state(p, th, thd, q, qd);
    ASSERT_EQ(forward_dynamics(dense, wd, q, qd, 0.0), Status::kOk);
    ASSERT_EQ(forward_dynamics(blocks, ws, q, qd, 0.0), Status::kOk);
    expect_relative(ws.qdd, wd.qdd, 1e-12, "sparse q'' against dense q''");
  }
  const Trajectory tr = run_pendulum(p, blocks, 1, Engine::kSparse);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  expect_follows_elliptic(p, tr, 1e-7);
}

// =============================================================================================
// 3. two particles on a massless link with a massless midpoint coordinate
//
// p1, p2 (masses m1, m2) at distance L, gravity g along −y. Gravity is uniform, so it exerts no
// torque about the centre of mass c: c'' = −g e_y and the link turns at the constant rate w:
//   c(t) = c0 + v0 t − ½ g t² e_y,  r = p1 − p2 = L (cos phi, sin phi),  phi = phi0 + w t,
//   p1 = c + m2/(m1 + m2) r,  p2 = c − m1/(m1 + m2) r,
// with tension mu L w² (mu = m1 m2 / (m1 + m2)) pulling each particle towards the other.
// The midpoint (xm, ym) = (p1 + p2)/2 is a coordinate without mass: M = diag(m1, m1, m2, m2,
// 0, 0), two holonomic rows tie it to the particles.
struct Dumbbell {
  double m1 = 1.0, m2 = 3.0, L = 0.8, g = 9.81, phi0 = 0.4, w = 2.2;
  Vector2d c0{0.3, 1.0}, v0{0.5, 1.5};

  double total() const { return m1 + m2; }
  double phi(double t) const { return phi0 + w * t; }
  Vector2d c(double t) const { return c0 + v0 * t - 0.5 * g * t * t * Vector2d::UnitY(); }
  Vector2d cd(double t) const { return v0 - g * t * Vector2d::UnitY(); }
  Vector2d r(double t) const { return L * Vector2d(std::cos(phi(t)), std::sin(phi(t))); }
  Vector2d rd(double t) const { return L * w * Vector2d(-std::sin(phi(t)), std::cos(phi(t))); }
  // (x1, y1, x2, y2, xm, ym) and their rates at t
  VectorXd q(double t) const {
    VectorXd s(6);
    const Vector2d p1 = c(t) + m2 / total() * r(t), p2 = c(t) - m1 / total() * r(t);
    s << p1, p2, 0.5 * (p1 + p2);
    return s;
  }
  VectorXd qd(double t) const {
    VectorXd s(6);
    const Vector2d v1 = cd(t) + m2 / total() * rd(t), v2 = cd(t) - m1 / total() * rd(t);
    s << v1, v2, 0.5 * (v1 + v2);
    return s;
  }
  double tension() const { return m1 * m2 / total() * L * w * w; }
};

System dumbbell_system(const Dumbbell& d, bool midpoint) {
  auto link = [L = d.L](const auto& q, const auto&, auto& phi) {
    using S = typename std::decay_t<decltype(q)>::Scalar;
    const S dx = q[0] - q[2], dy = q[1] - q[3];
    phi[0] = (dx * dx + dy * dy - L * L) / (2 * L);
  };
  auto mid = [](const auto& q, const auto&, auto& phi) {
    phi[0] = q[4] - 0.5 * (q[0] + q[2]);
    phi[1] = q[5] - 0.5 * (q[1] + q[3]);
  };
  std::vector<std::string> names{"x1", "y1", "x2", "y2"};
  VectorXd diag(4);
  diag << d.m1, d.m1, d.m2, d.m2;
  if (midpoint) {
    names.insert(names.end(), {"xm", "ym"});
    diag.conservativeResize(6);
    diag.tail<2>().setZero();
  }
  const double m1 = d.m1, m2 = d.m2, g = d.g;
  SystemBuilder b(names);
  b.mass_matrix(MatrixXd(diag.asDiagonal()))
      .forces([m1, m2, g](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&,
                          double, Eigen::Ref<VectorXd> Q) {
        Q.setZero();
        Q[1] = -m1 * g;
        Q[3] = -m2 * g;
      })
      .potential_energy([m1, m2, g](const Eigen::Ref<const VectorXd>& q, double) {
        return m1 * g * q[1] + m2 * g * q[3];
      })
      .add(holonomic("link", 1, link));
  if (midpoint) b.add(holonomic("midpoint", 2, mid));
  return b.build();
}

// the particles' q'' and constraint force from the closed form at t
void expect_dumbbell_closed_form(const Dumbbell& d, const Eigen::Ref<const VectorXd>& qdd,
                                 const Eigen::Ref<const VectorXd>& Qc, double t) {
  const Vector2d rdd = -d.w * d.w * d.r(t), cdd(0.0, -d.g);
  VectorXd a(4);
  a << cdd + d.m2 / d.total() * rdd, cdd - d.m1 / d.total() * rdd;
  expect_relative(qdd.head<4>(), a, 1e-12, "particles' q''");
  const Vector2d e = d.r(t) / d.L;  // from p2 to p1
  VectorXd F(4);
  F << -d.tension() * e, d.tension() * e;
  expect_relative(Qc.head<4>(), F, 1e-12, "link force");
}

void expect_dumbbell_run(const Dumbbell& d, const Trajectory& tr, Index n) {
  double worst = 0.0, worst_rate = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    worst = std::max(worst, (sample(tr.q, n, i) - d.q(t).head(n)).cwiseAbs().maxCoeff());
    worst_rate =
        std::max(worst_rate, (sample(tr.qd, n, i) - d.qd(t).head(n)).cwiseAbs().maxCoeff());
  }
  EXPECT_NEAR(worst, 0.0, 1e-8);
  EXPECT_NEAR(worst_rate, 0.0, 1e-7);
}

SimulationOptions dumbbell_run() {
  SimulationOptions o;
  o.t_end = 3.0;
  o.rtol = 1e-11;
  o.atol = 1e-13;
  o.output_every = 0.02;
  return o;
}

TEST(SingularMassReference, DumbbellWithoutTheMidpointFollowsTheClosedForm) {
  const Dumbbell d;
  const System sys = dumbbell_system(d, false);
  Workspace ws(sys);
  for (double t : {0.0, 0.7, 2.1}) {
    ASSERT_EQ(forward_dynamics(sys, ws, d.q(t).head<4>(), d.qd(t).head<4>(), t), Status::kOk)
        << describe_status(sys, ws);
    expect_dumbbell_closed_form(d, ws.qdd, ws.Qc, t);
  }
  const Trajectory tr = simulate(sys, d.q(0).head<4>(), d.qd(0).head<4>(), dumbbell_run());
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  expect_dumbbell_run(d, tr, 4);
}

TEST(SingularMass, MasslessMidpointMovesWithTheLinkAndChangesNothing) {
  const Dumbbell d;
  const System with = dumbbell_system(d, true), without = dumbbell_system(d, false);
  Workspace ws(with), wr(without);
  for (double t : {0.0, 0.7, 2.1}) {
    SCOPED_TRACE("t = " + std::to_string(t));
    ASSERT_EQ(forward_dynamics(with, ws, d.q(t), d.qd(t), t), Status::kOk)
        << describe_status(with, ws);
    ASSERT_EQ(forward_dynamics(without, wr, d.q(t).head<4>(), d.qd(t).head<4>(), t), Status::kOk);
    expect_dumbbell_closed_form(d, ws.qdd, ws.Qc, t);
    // the regular formulation without the midpoint
    expect_relative(ws.qdd.head<4>(), wr.qdd, 1e-12, "q'' against the system without midpoint");
    expect_relative(ws.Qc.head<4>(), wr.Qc, 1e-12, "Qc against the system without midpoint");
    // the midpoint accelerates as the mean of the particles and takes no force
    expect_relative(ws.qdd.tail<2>(), 0.5 * (wr.qdd.head<2>() + wr.qdd.segment<2>(2)), 1e-12,
                    "midpoint q''");
    EXPECT_NEAR(ws.Qc.tail<2>().norm(), 0.0, 1e-12 * d.tension());
    EXPECT_EQ(ws.rank, 3);
  }
  const Trajectory tr = simulate(with, d.q(0), d.qd(0), dumbbell_run());
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  expect_dumbbell_run(d, tr, 6);
}

// =============================================================================================
// 5. model files: a kinetic energy without theta_dot, a mass_matrix with a zero row

std::string data_file(const std::string& name) {
  return std::string(UKDYN_TEST_DATA_DIR) + "/" + name + ".yaml";
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// the files' parameters are PendulumParams' defaults
void expect_model_pendulum(const Model& m, const PendulumParams& p) {
  ASSERT_EQ(m.system.coordinate_names(), (std::vector<std::string>{"x", "y", "theta"}));
  EXPECT_NEAR(m.q0[2], p.theta0, 1e-15);
  EXPECT_NEAR(m.qd0.norm(), 0.0, 1e-15);
  Workspace ws(m.system);
  expect_pendulum_closed_form(p, m.system, ws);
  // the file's t_end and outputs: three periods, turning points at every half period
  const double T = EllipticPendulum(p).period();
  SimulationOptions o = m.options;
  o.t_end = 3 * T;
  o.output_at.clear();
  for (int i = 1; i < 6; ++i) o.output_at.push_back(0.5 * i * T);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  expect_follows_elliptic(p, tr, 1e-7);
}

TEST(SingularMassReference, ModelFilesWithInertiaOnThetaAreTheCompoundPendulum) {
  const PendulumParams p{.J = 0.4};
  // the mass_matrix file with its parameter J = 0.4
  expect_model_pendulum(load_model(data_file("singular_pendulum_mass_matrix"), {{"J", 0.4}}), p);
  // the Lagrangian file with ½ J theta'² put back
  std::string text = read_text(data_file("singular_pendulum_lagrangian"));
  const std::string T = "kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)";
  const auto at = text.find(T);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, T.size(), T + " + 0.5*0.4*theta_dot^2");
  expect_model_pendulum(parse_model(text, "lagrangian with J"), p);
}

TEST(SingularMass, ModelFileWhoseKineticEnergyOmitsThetaDotRuns) {
  const Model m = load_model(data_file("singular_pendulum_lagrangian"));
  MatrixXd M(3, 3);
  m.system.mass_matrix(m.q0, 0.0, M);
  EXPECT_NEAR(M(2, 2), 0.0, 0.0);
  const CheckReport report = check_model(m);
  EXPECT_TRUE(report.ok()) << (report.problems.empty() ? "" : report.problems.front());
  EXPECT_EQ(report.degrees_of_freedom, 1);
  expect_model_pendulum(m, PendulumParams{});
}

TEST(SingularMass, ModelFileWithAZeroRowInTheMassMatrixRuns) {
  const Model m = load_model(data_file("singular_pendulum_mass_matrix"));
  EXPECT_EQ(m.parameters.at("J"), 0.0);
  const CheckReport report = check_model(m);
  EXPECT_TRUE(report.ok()) << (report.problems.empty() ? "" : report.problems.front());
  expect_model_pendulum(m, PendulumParams{});
}

// =============================================================================================
// 6. independence of G: the auxiliary system M_A = M + Aᵀ G A, Q_A = Q + Aᵀ G b, built by hand
// at a fixed state as an ordinary regular system, and the KKT system [M Aᵀ; A 0] [q''; −λ] =
// [Q; b]

struct Solved {
  VectorXd qdd, Qc, lambda;
};

// the regular auxiliary system with constant M_A, Q_A and the constant rows A q'' = b
Solved auxiliary(const std::vector<std::string>& names, const MatrixXd& M,
                 const Eigen::Ref<const VectorXd>& Q, const MatrixXd& A,
                 const Eigen::Ref<const VectorXd>& b, const MatrixXd& G) {
  const MatrixXd MA = M + A.transpose() * G * A;
  const VectorXd QA = Q + A.transpose() * G * b;
  const System sys =
      SystemBuilder(names)
          .mass_matrix(MA)
          .forces([QA](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                       Eigen::Ref<VectorXd> out) { out = QA; })
          .add(acceleration_constraint(
              "aux", A.rows(),
              [A, b = VectorXd(b)](const Eigen::Ref<const VectorXd>&,
                                   const Eigen::Ref<const VectorXd>&, double,
                                   Eigen::Ref<MatrixXd> Aout, Eigen::Ref<VectorXd> bout) {
                Aout = A;
                bout = b;
              }))
          .build();
  Workspace ws(sys);
  const VectorXd zero = VectorXd::Zero(M.rows());
  EXPECT_EQ(forward_dynamics(sys, ws, zero, zero, 0.0), Status::kOk) << describe_status(sys, ws);
  // the actual system's constraint force: M q'' − Q (the auxiliary's own Qc equals it too)
  return {ws.qdd, M * ws.qdd - Q, ws.lambda};
}

Solved kkt(const MatrixXd& M, const Eigen::Ref<const VectorXd>& Q, const MatrixXd& A,
           const Eigen::Ref<const VectorXd>& b) {
  const Index n = M.rows(), m = A.rows();
  MatrixXd K = MatrixXd::Zero(n + m, n + m);
  K.topLeftCorner(n, n) = M;
  K.topRightCorner(n, m) = A.transpose();
  K.bottomLeftCorner(m, n) = A;
  VectorXd rhs(n + m);
  rhs << Q, b;
  const Eigen::FullPivLU<MatrixXd> lu(K);
  EXPECT_EQ(lu.rank(), n + m) << "[M Aᵀ; A 0] is singular: [M; A] or A lacks rank";
  const VectorXd x = lu.solve(rhs);
  return {x.head(n), M * x.head(n) - Q, -x.tail(m)};
}

// one fixed state of a system with M, Q, A, b written out by hand
struct Case {
  std::string name;
  System sys;
  VectorXd q, qd;
  double t = 0.0;
  MatrixXd M, A;
  VectorXd Q, b;
  std::vector<MatrixXd> Gs;  // the G to try
};

std::vector<Case> g_cases() {
  std::vector<Case> cases;
  {
    // the pendulum at theta = 0.9, theta' = −1.7: A = [1 0 −L cos; 0 1 −L sin],
    // b = (−L sin theta'², L cos theta'²)
    const PendulumParams p;
    Case c{"pendulum", xytheta_pendulum(p)};
    const double th = 0.9, thd = -1.7, s = std::sin(th), co = std::cos(th);
    pendulum_state(p, th, thd, c.q, c.qd);
    c.M = Eigen::Vector3d(p.m, p.m, 0.0).asDiagonal();
    c.Q = Eigen::Vector3d(0.0, -p.m * p.g, 0.0);
    c.A.resize(2, 3);
    c.A << 1, 0, -p.L * co, 0, 1, -p.L * s;
    c.b = Eigen::Vector2d(-p.L * s * thd * thd, p.L * co * thd * thd);
    MatrixXd G(2, 2);
    G << 3.0, 1.0, 1.0, 0.5;
    c.Gs = {1e-2 * p.m * MatrixXd::Identity(2, 2), 1e3 * p.m * MatrixXd::Identity(2, 2), p.m * G};
    cases.push_back(c);
  }
  {
    // a coupled M of rank 2 (null space (1, −2, 0)), velocity-dependent Q, and the curve
    // a + ½ sin b − c² = 0.2: A = [1, ½ cos b, −2 c], b = ½ sin b b'² + 2 c'²;
    // A (1, −2, 0)ᵀ = 1 − cos b ≠ 0, so [M; A] has full column rank
    MatrixXd M(3, 3);
    M << 2.0, 1.0, 0.0, 1.0, 0.5, 0.0, 0.0, 0.0, 1.0;
    const System sys =
        SystemBuilder(std::vector<std::string>{"a", "b", "c"})
            .mass_matrix(M)
            .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>& qd,
                       double,
                       Eigen::Ref<VectorXd> Q) { Q << 0.3, -1.0 - 0.4 * qd[1], 0.5 + 0.2 * qd[2]; })
            .accounts_for_energy(false)
            .add(holonomic("curve", 1,
                           [](const auto& q, const auto&, auto& phi) {
                             using std::sin;
                             phi[0] = q[0] + 0.5 * sin(q[1]) - q[2] * q[2] - 0.2;
                           }))
            .build();
    Case c{"coupled", sys};
    c.q = Eigen::Vector3d(0.4, 1.3, 0.7);
    c.qd = Eigen::Vector3d(-0.8, 0.6, 1.1);
    c.M = M;
    c.Q = Eigen::Vector3d(0.3, -1.0 - 0.4 * 0.6, 0.5 + 0.2 * 1.1);
    c.A.resize(1, 3);
    c.A << 1.0, 0.5 * std::cos(1.3), -2 * 0.7;
    c.b = VectorXd::Constant(1, 0.5 * std::sin(1.3) * 0.36 + 2 * 1.21);
    c.Gs = {MatrixXd::Constant(1, 1, 1e-2), MatrixXd::Constant(1, 1, 1e3)};
    cases.push_back(c);
  }
  {
    // the dumbbell with its midpoint at t = 0.7
    const Dumbbell d;
    Case c{"dumbbell", dumbbell_system(d, true)};
    c.t = 0.7;
    c.q = d.q(c.t);
    c.qd = d.qd(c.t);
    VectorXd diag(6);
    diag << d.m1, d.m1, d.m2, d.m2, 0.0, 0.0;
    c.M = diag.asDiagonal();
    c.Q = VectorXd::Zero(6);
    c.Q[1] = -d.m1 * d.g;
    c.Q[3] = -d.m2 * d.g;
    const Vector2d r = c.q.head<2>() - c.q.segment<2>(2), rd = c.qd.head<2>() - c.qd.segment<2>(2);
    c.A = MatrixXd::Zero(3, 6);
    c.A.block<1, 2>(0, 0) = r.transpose() / d.L;
    c.A.block<1, 2>(0, 2) = -r.transpose() / d.L;
    c.A.block<2, 2>(1, 0) = -0.5 * Eigen::Matrix2d::Identity();
    c.A.block<2, 2>(1, 2) = -0.5 * Eigen::Matrix2d::Identity();
    c.A.block<2, 2>(1, 4) = Eigen::Matrix2d::Identity();
    c.b = Eigen::Vector3d(-rd.squaredNorm() / d.L, 0.0, 0.0);
    c.Gs = {1e-2 * d.m1 * MatrixXd::Identity(3, 3), 1e3 * d.m2 * MatrixXd::Identity(3, 3)};
    cases.push_back(c);
  }
  return cases;
}

TEST(SingularMassReference, AuxiliarySystemsForAnyGAgreeWithKKT) {
  for (const Case& c : g_cases()) {
    SCOPED_TRACE(c.name);
    // the hand-written A, b are the system's own (stage 2 alone, no M involved)
    Workspace ws(c.sys, SolverOptions{.engine = Engine::kDense});
    ASSERT_EQ(assemble_constraints(c.sys, ws, c.q, c.qd, c.t), Status::kOk);
    EXPECT_NEAR((ws.A - c.A).norm(), 0.0, 1e-14 * c.A.norm());
    EXPECT_NEAR((ws.b - c.b).norm(), 0.0, 1e-14 * (1.0 + c.b.norm()));
    MatrixXd M(c.M.rows(), c.M.cols());
    c.sys.mass_matrix(c.q, c.t, M);
    EXPECT_NEAR((M - c.M).norm(), 0.0, 0.0);
    VectorXd Q(c.Q.size());
    c.sys.forces(c.q, c.qd, c.t, Q);
    EXPECT_NEAR((Q - c.Q).norm(), 0.0, 1e-14 * c.Q.norm());
    // M is singular: positive semi-definite with a null space
    const Eigen::SelfAdjointEigenSolver<MatrixXd> eig(c.M);
    EXPECT_NEAR(eig.eigenvalues().minCoeff(), 0.0, 1e-14);
    const Solved ref = kkt(c.M, c.Q, c.A, c.b);
    expect_relative(c.A * ref.qdd, c.b, 1e-13, "A q'' = b");
    for (const MatrixXd& G : c.Gs) {
      const Solved aux = auxiliary(c.sys.coordinate_names(), c.M, c.Q, c.A, c.b, G);
      expect_relative(aux.qdd, ref.qdd, 1e-12, "auxiliary q'' against KKT");
      expect_relative(aux.Qc, ref.Qc, 1e-11, "auxiliary Qc against KKT");
      expect_relative(aux.lambda, ref.lambda, 1e-11, "auxiliary lambda against KKT");
    }
  }
}

TEST(SingularMass, AccelerationIsTheAuxiliarySystemsForEveryG) {
  for (const Case& c : g_cases()) {
    SCOPED_TRACE(c.name);
    Workspace ws(c.sys);
    ASSERT_EQ(forward_dynamics(c.sys, ws, c.q, c.qd, c.t), Status::kOk)
        << describe_status(c.sys, ws);
    const Solved ref = kkt(c.M, c.Q, c.A, c.b);
    expect_relative(ws.qdd, ref.qdd, 1e-12, "q'' against KKT");
    for (const MatrixXd& G : c.Gs) {
      const Solved aux = auxiliary(c.sys.coordinate_names(), c.M, c.Q, c.A, c.b, G);
      expect_relative(ws.qdd, aux.qdd, 1e-12, "q'' against the auxiliary system");
      expect_relative(ws.Qc, aux.Qc, 1e-11, "Qc = M q'' - Q against the auxiliary system");
      expect_relative(ws.lambda, aux.lambda, 1e-11, "lambda against the auxiliary system");
    }
    // residuals of the actual system
    expect_relative(ws.Qc, c.M * ws.qdd - c.Q, 1e-12, "Qc = M q'' - Q");
    EXPECT_NEAR(ws.residuals.constraint, 0.0, 1e-12 * (1.0 + c.b.norm()));
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
