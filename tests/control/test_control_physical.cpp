// SPDX-License-Identifier: BSD-3-Clause
// Exact tracking control (control/control.hpp) of physical plants: a pendulum whose rod is a
// physical constraint while a requirement tracks its abscissa (with non-ideal plant forces and the
// energy balance), spacecraft attitude tracking on a unit quaternion, and the synchronization of
// two chaotic gyroscopes; the control's integrals (effort, work) against closed forms under
// every integrator. (The Duffing oscillator, the triple pendulum, the laws against
// independent methods, the robust term and the messages: test_control.cpp.)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <ukdyn/control/control.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/reference/reference.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/cartesian_pendulum.hpp"
#include "support/control_runs.hpp"
#include "support/error_dynamics.hpp"
#include "support/random_problem.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using test::cartesian_pendulum;
using test::record;
using test::second_order_error;  // e(t) of e'' + 2 zeta omega e' + omega² e = 0
using test::tight;
using testing::rel_diff;
using testing::vec;

constexpr double kG = 9.81;

// sample j of an N × width field
Eigen::Map<const VectorXd> sample(const std::vector<double>& f, Index width, Index j) {
  return {f.data() + j * width, width};
}

// ---------------------------------------------------------------------------------------------
// models

// x − 0.3 sin t
Constraint track_x() {
  return holonomic("x_track", 1, [](const auto& q, const auto& t, auto& e) {
    using std::sin;
    e[0] = q[0] - 0.3 * sin(t);
  });
}

// ---------------------------------------------------------------------------------------------
// physical constraints and requirements together

TEST(ControlPhysical, PendulumRodAndTrackedAbscissa) {
  const double m = 1.3, L = 1.0, omega = 3.0;
  const System sys = cartesian_pendulum(m, L);
  const Controller ctrl =
      ControllerBuilder(sys).require(track_x(), ErrorDynamics::second_order(omega)).build();
  ControlWorkspace ws(ctrl);
  const double th = 0.35, w = -0.7, t = 0.4;
  const VectorXd q = vec({L * std::sin(th), -L * std::cos(th)});
  const VectorXd qd = vec({L * std::cos(th) * w, L * std::sin(th) * w});
  ASSERT_EQ(compute_control(ctrl, ws, q, qd, t), ControlStatus::kOk);
  // the Gauss control loads no physical constraint: A_p M⁻¹ Q_c = 0 (M = m I: Q_c ⊥ the rod)
  EXPECT_NEAR(q.dot(ws.Qc_control), 0.0, 1e-12 * ws.Qc_control.norm());
  // so the rod's reaction is that of the uncontrolled pendulum, m (g cos θ + L θ'²) inward
  const double tension = m * (kG * std::cos(th) + L * w * w);
  EXPECT_NEAR(rel_diff(ws.Qc_physical, -tension * q / L), 0.0, 1e-12);
  // and reaction + control = the constraint force with rod and requirement stacked (KKT)
  MatrixXd A(2, 2);
  VectorXd b(2);
  A << q[0] / L, q[1] / L, 1.0, 0.0;
  const double e = q[0] - 0.3 * std::sin(t), ed = qd[0] - 0.3 * std::cos(t);
  b << -qd.squaredNorm() / L, -0.3 * std::sin(t) - 2 * omega * ed - omega * omega * e;
  KktSolver kkt(2, 2);
  VectorXd qdd(2), lambda(2);
  ASSERT_EQ(kkt.solve(m * MatrixXd::Identity(2, 2), vec({0.0, -m * kG}), A, b, qdd, lambda),
            Eigen::Success);
  EXPECT_NEAR(rel_diff(ws.Qc_physical + ws.Qc_control, A.transpose() * lambda), 0.0, 1e-12);
  record("rel_diff_stacked_kkt", rel_diff(ws.Qc_physical + ws.Qc_control, A.transpose() * lambda));
  EXPECT_NEAR(rel_diff(ws.qdd, qdd), 0.0, 1e-12);

  // only x actuated: the rod now reacts to the control too, and the motion is still right
  const Controller act = ControllerBuilder(sys)
                             .require(track_x(), ErrorDynamics::second_order(omega))
                             .actuated({"x"})
                             .build();
  ControlWorkspace wa(act);
  ASSERT_EQ(compute_control(act, wa, q, qd, t), ControlStatus::kOk);
  EXPECT_EQ(wa.Qc_control[1], 0.0);
  EXPECT_NEAR(rel_diff(wa.qdd, qdd), 0.0, 1e-11);  // both constraints hold: the same q''
  // the reaction: KKT of the rod alone with Q + Q_c
  KktSolver rod(2, 1);
  VectorXd qdd_rod(2), lambda_rod(1);
  ASSERT_EQ(rod.solve(m * MatrixXd::Identity(2, 2), vec({wa.Qc_control[0], -m * kG}), A.topRows(1),
                      b.head(1), qdd_rod, lambda_rod),
            Eigen::Success);
  EXPECT_NEAR(rel_diff(wa.Qc_physical, A.topRows(1).transpose() * lambda_rod), 0.0, 1e-11);
  EXPECT_GT(rel_diff(wa.Qc_physical, ws.Qc_physical), 1e-3);

  // simulated: the rod holds, the abscissa error follows e'' + 6 e' + 9 e = 0
  const double th0 = 0.2;
  const VectorXd q0 = vec({L * std::sin(th0), -L * std::cos(th0)}), qd0 = vec({0.0, 0.0});
  const ControlledTrajectory run = simulate_controlled(ctrl, sys, q0, qd0, tight(4));
  ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
  double worst = 0.0;
  for (Index j = 0; j < run.samples(); ++j) {
    const double tj = run.plant.t[std::size_t(j)];
    const double expected = second_order_error(1.0, omega, q0[0], -0.3, tj);
    EXPECT_NEAR(run.error[std::size_t(j)], expected, 1e-8) << tj;
    EXPECT_NEAR(run.plant.position_violation[std::size_t(j)], 0.0, 1e-11);
    worst = std::max(worst, std::abs(run.error[std::size_t(j)] - expected));
  }
  EXPECT_NEAR(run.plant.stats.energy_drift, 0.0, 1e-8);  // E − E0 = ∫ Q_cᵀ q' dt
  record("max_error_deviation", worst);
  record("energy_drift", run.plant.stats.energy_drift);
}

TEST(ControlPhysical, NonIdealPlantForcesAndEnergyBalance) {
  // the rod pendulum with viscous damping C = −c q' (a non-ideal force of the plant): the Gauss
  // control still gives the prescribed error (C does not read the reaction), and
  // E(t) − E(0) = W_nonideal(t) + W_control(t)
  const double m = 1.0, L = 1.0, omega = 3.0;
  const System sys =
      SystemBuilder({"x", "y"})
          .mass_matrix(m * MatrixXd::Identity(2, 2))
          .forces([m](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                      Eigen::Ref<VectorXd> Q) { Q << 0.0, -m * kG; })
          .potential_energy(
              [m](const Eigen::Ref<const VectorXd>& q, double) { return m * kG * q[1]; })
          .add(holonomic("rod", 1,
                         [L](const auto& q, const auto&, auto& phi) {
                           phi[0] = (q[0] * q[0] + q[1] * q[1] - L * L) / (2 * L);
                         }))
          .add(viscous_friction({.coefficient = 0.4}))
          .build();
  const Controller ctrl =
      ControllerBuilder(sys).require(track_x(), ErrorDynamics::second_order(omega)).build();
  const VectorXd q0 = vec({L * std::sin(0.2), -L * std::cos(0.2)}), qd0 = vec({0.0, 0.0});
  const ControlledTrajectory run = simulate_controlled(ctrl, sys, q0, qd0, tight(4));
  ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
  double worst = 0.0;
  for (Index j = 0; j < run.samples(); ++j) {
    const double t = run.plant.t[std::size_t(j)];
    const double expected = second_order_error(1.0, omega, q0[0], -0.3, t);
    EXPECT_NEAR(run.error[std::size_t(j)], expected, 1e-8) << t;
    worst = std::max(worst, std::abs(run.error[std::size_t(j)] - expected));
  }
  record("max_error_deviation", worst);
  EXPECT_LT(run.plant.work_nonideal.back(), -1e-3);  // the damper dissipates
  EXPECT_NEAR(run.plant.stats.energy_drift, 0.0, 1e-8);
  record("energy_drift", run.plant.stats.energy_drift);
}

// ---------------------------------------------------------------------------------------------
// spacecraft attitude tracking with a unit quaternion u = (u0, u1, u2, u3) in generalized
// coordinates (docs/control.md): body rates [0; ω] = 2 E(u) u', T = 2 u'ᵀ Eᵀ J̄ E u' with
// J̄ = diag(J0, J1, J2, J3) (J0 > 0 arbitrary: it only weighs u'ᵀu, zero on the constraint), so
//   M = 4 Eᵀ J̄ E,  Q = −8 E(u')ᵀ diag(0, J1, J2, J3) E(u) u' − 4 J0 |u'|² u + 2 Eᵀ [0; τ],
// and the unit norm (uᵀu − 1)/2 = 0 is a physical constraint.

Eigen::Matrix4d E_of(const Eigen::Vector4d& u) {
  Eigen::Matrix4d E;
  E << u[0], u[1], u[2], u[3],   //
      -u[1], u[0], u[3], -u[2],  //
      -u[2], -u[3], u[0], u[1],  //
      -u[3], u[2], -u[1], u[0];
  return E;
}

const Eigen::Vector4d kJbar(1.0, 1.0, 2.0, 3.0);  // J0, J1, J2, J3

System spacecraft() {
  return SystemBuilder({"u0", "u1", "u2", "u3"})
      .mass_matrix([](const Eigen::Ref<const VectorXd>& u, double, Eigen::Ref<MatrixXd> M) {
        const Eigen::Matrix4d E = E_of(u);
        M = 4.0 * E.transpose() * kJbar.asDiagonal() * E;
      })
      .forces([](const Eigen::Ref<const VectorXd>& u, const Eigen::Ref<const VectorXd>& ud, double,
                 Eigen::Ref<VectorXd> Q) {
        const Eigen::Vector4d J(0.0, kJbar[1], kJbar[2], kJbar[3]);
        Q = -8.0 * E_of(ud).transpose() * J.asDiagonal() * E_of(u) * ud -
            4.0 * kJbar[0] * ud.squaredNorm() * u;
      })
      .add(holonomic("unit", 1,
                     [](const auto& u, const auto&, auto& phi) {
                       phi[0] = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2] + u[3] * u[3] - 1.0) / 2.0;
                     }))
      .build();
}

// desired attitude: angle 0.4 t + 0.2 sin t about n = (1, 2, 2)/3
template <class S>
void desired_attitude(const S& t, S d[4]) {
  using std::cos;
  using std::sin;
  const S half = (0.4 * t + 0.2 * sin(t)) / 2.0;
  d[0] = cos(half);
  d[1] = sin(half) / 3.0;
  d[2] = 2.0 * sin(half) / 3.0;
  d[3] = 2.0 * sin(half) / 3.0;
}

// the vector part of conj(q_d) ⊗ u: d0 u_v − u0 d − d × u_v
Constraint attitude_requirement() {
  return holonomic("attitude", 3, [](const auto& u, const auto& t, auto& e) {
    using S = std::decay_t<decltype(t)>;
    S d[4];
    desired_attitude(t, d);
    e[0] = d[0] * u[1] - u[0] * d[1] - (d[2] * u[3] - d[3] * u[2]);
    e[1] = d[0] * u[2] - u[0] * d[2] - (d[3] * u[1] - d[1] * u[3]);
    e[2] = d[0] * u[3] - u[0] * d[3] - (d[1] * u[2] - d[2] * u[1]);
  });
}

Eigen::Vector4d quat_mul(const Eigen::Vector4d& a, const Eigen::Vector4d& b) {
  const Eigen::Vector3d av = a.tail<3>(), bv = b.tail<3>();
  Eigen::Vector4d c;
  c[0] = a[0] * b[0] - av.dot(bv);
  c.tail<3>() = a[0] * bv + b[0] * av + av.cross(bv);
  return c;
}

Eigen::Vector4d conj(const Eigen::Vector4d& a) { return {a[0], -a[1], -a[2], -a[3]}; }

TEST(ControlSpacecraft, TorqueFreeQuaternionModelConservesAngularMomentum) {
  // the model itself: H = R(u) J ω (inertial) and T are constant without torque
  const System sys = spacecraft();
  const Eigen::Vector4d u0(std::cos(0.25), 0.0, 0.0, std::sin(0.25));
  const Eigen::Vector4d ud0 = 0.5 * quat_mul(u0, Eigen::Vector4d(0.0, 0.3, -0.5, 0.8));
  SimulationOptions o = tight(3.0, 0.5);
  const Trajectory tr = simulate(sys, u0, ud0, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  auto momentum = [&](Index j) {
    const Eigen::Vector4d u = sample(tr.q, 4, j), ud = sample(tr.qd, 4, j);
    const Eigen::Vector3d w = (2.0 * E_of(u) * ud).tail<3>();
    const Eigen::Vector3d Jw = kJbar.tail<3>().asDiagonal() * w;
    // R(u) v = u ⊗ (0, v) ⊗ u*
    return Eigen::Vector3d(
        quat_mul(quat_mul(u, Eigen::Vector4d(0, Jw[0], Jw[1], Jw[2])), conj(u)).tail<3>());
  };
  const Eigen::Vector3d H0 = momentum(0);
  double worst = 0.0;
  for (Index j = 1; j < tr.samples(); ++j) {
    EXPECT_NEAR((momentum(j) - H0).norm(), 0.0, 1e-8 * H0.norm()) << tr.t[std::size_t(j)];
    worst = std::max(worst, (momentum(j) - H0).norm() / H0.norm());
  }
  record("max_rel_momentum_drift", worst);
  EXPECT_NEAR(tr.stats.energy_drift, 0.0, 1e-9);
}

TEST(ControlSpacecraft, AttitudeErrorDecaysAsPrescribedAndNormHolds) {
  const System sys = spacecraft();
  const double omega = 2.0;
  const Controller ctrl = ControllerBuilder(sys)
                              .require(attitude_requirement(), ErrorDynamics::second_order(omega))
                              .build();
  // start 0.5 rad about z, tumbling at ω = (0.1, −0.2, 0.3)
  const Eigen::Vector4d u0(std::cos(0.25), 0.0, 0.0, std::sin(0.25));
  const Eigen::Vector4d ud0 = 0.5 * quat_mul(u0, Eigen::Vector4d(0.0, 0.1, -0.2, 0.3));
  // e(0) and e'(0) by hand: vec(conj(q_d) ⊗ u) and its rate, q_d' = (θ'/2)(−sin, n cos)(θ/2)
  const Eigen::Vector4d d0(1.0, 0.0, 0.0, 0.0);
  const double theta_rate = 0.4 + 0.2;  // θ'(0)
  const Eigen::Vector4d dd0 = 0.5 * theta_rate * Eigen::Vector4d(0.0, 1.0 / 3, 2.0 / 3, 2.0 / 3);
  const Eigen::Vector3d e0 = quat_mul(conj(d0), u0).tail<3>();
  const Eigen::Vector3d e1 = (quat_mul(conj(dd0), u0) + quat_mul(conj(d0), ud0)).tail<3>();
  const ControlledTrajectory run = simulate_controlled(ctrl, sys, u0, ud0, tight(5));
  ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
  EXPECT_EQ(run.control.not_met, 0);
  double worst = 0.0;
  for (Index j = 0; j < run.samples(); ++j) {
    const double t = run.plant.t[std::size_t(j)];
    for (Index i = 0; i < 3; ++i) {
      const double expected = second_order_error(1.0, omega, e0[i], e1[i], t);
      EXPECT_NEAR(sample(run.error, 3, j)[i], expected, 1e-8) << i << " t = " << t;
      worst = std::max(worst, std::abs(sample(run.error, 3, j)[i] - expected));
    }
    // the unit norm holds
    EXPECT_NEAR(sample(run.plant.q, 4, j).norm(), 1.0, 1e-11);
    // the Gauss control is a pure body torque: Q_c = 2 Eᵀ [0; τ]
    const Eigen::Vector4d Qc = sample(run.Qc_control, 4, j);
    const Eigen::Vector4d u = sample(run.plant.q, 4, j);
    EXPECT_NEAR((E_of(u) * Qc)[0], 0.0, 1e-10 * (1 + Qc.norm()));
  }
  record("max_error_deviation", worst);
  // at the end the attitude is that desired, to the decayed error
  const Eigen::Vector4d uT = sample(run.plant.q, 4, run.samples() - 1);
  Eigen::Vector4d dT;
  double d[4];
  desired_attitude(5.0, d);
  dT << d[0], d[1], d[2], d[3];
  EXPECT_NEAR(std::abs(quat_mul(conj(dT), uT)[0]), 1.0, 1e-4);
}

// ---------------------------------------------------------------------------------------------
// synchronization of two chaotic gyroscopes (symmetric gyro with linear-plus-cubic damping):
//   th'' + a² (1 − cos th)² / sin³ th − b sin th + c1 th' + c2 th'³ = f sin th sin(w t),
// written with (1 − cos th)² / sin³ th = sin(th/2) / (2 cos³(th/2)) (regular at th = 0)

double gyro_force(double th, double w, double t) {
  const double a2 = 100.0, b = 1.0, c1 = 0.5, c2 = 0.05, f = 35.5, om = 2.0;
  const double h = 0.5 * th;
  return -a2 * std::sin(h) / (2.0 * std::pow(std::cos(h), 3)) + b * std::sin(th) - c1 * w -
         c2 * w * w * w + f * std::sin(th) * std::sin(om * t);
}

TEST(ControlGyroscopes, SlaveSynchronizesWithPrescribedErrorDynamics) {
  const System pair =
      SystemBuilder({"master", "slave"})
          .mass_matrix(MatrixXd::Identity(2, 2))
          .forces([](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                     double t, Eigen::Ref<VectorXd> Q) {
            Q << gyro_force(q[0], qd[0], t), gyro_force(q[1], qd[1], t);
          })
          .build();
  const double zeta = 0.8, omega = 4.0;
  const Controller ctrl =
      ControllerBuilder(pair)
          .require(
              holonomic("sync", 1, [](const auto& q, const auto&, auto& e) { e[0] = q[1] - q[0]; }),
              ErrorDynamics::second_order(omega, zeta))
          .actuated({"slave"})
          .build();
  const VectorXd q0 = vec({1.0, -0.3}), qd0 = vec({-0.5, 0.8});
  const ControlledTrajectory run = simulate_controlled(ctrl, pair, q0, qd0, tight(6));
  ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
  EXPECT_EQ(run.control.not_met, 0);
  // the master runs free: compare with it simulated alone
  const System master =
      SystemBuilder({"master"})
          .mass_matrix(MatrixXd::Identity(1, 1))
          .forces([](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                     double t, Eigen::Ref<VectorXd> Q) { Q[0] = gyro_force(q[0], qd[0], t); })
          .build();
  const Trajectory alone = simulate(master, vec({1.0}), vec({-0.5}), tight(6));
  ASSERT_EQ(alone.samples(), run.samples());
  double worst = 0.0, master_dev = 0.0;
  for (Index j = 0; j < run.samples(); ++j) {
    const double t = run.plant.t[std::size_t(j)];
    const double expected = second_order_error(zeta, omega, -1.3, 1.3, t);
    EXPECT_NEAR(run.error[std::size_t(j)], expected, 1e-8) << t;
    worst = std::max(worst, std::abs(run.error[std::size_t(j)] - expected));
    EXPECT_EQ(sample(run.Qc_control, 2, j)[0], 0.0);
    EXPECT_NEAR(sample(run.plant.q, 2, j)[0], alone.q[std::size_t(j)], 1e-6) << t;
    master_dev =
        std::max(master_dev, std::abs(sample(run.plant.q, 2, j)[0] - alone.q[std::size_t(j)]));
  }
  record("max_master_deviation", master_dev);
  record("max_error_deviation", worst);
}

// The plant's kinetic energy at each sample of a controlled run is ½ q'ᵀ M(q) q' of the plant
// alone (not the augmented run's, which holds ½ z'ᵀz' of the control's integrals besides), also
// where the sample takes M from the run's own evaluation of diag(M, I) at that state: a planar
// two-link arm, M(q) in closed form (M_11 = a + 2 b cos q2, M_12 = d + b cos q2, M_22 = d).
TEST(ControlPhysical, SampleKineticEnergyIsThePlantsAtEverySample) {
  const double a = 2.5, b = 0.6, d = 0.4;
  const auto mass = [a, b, d](double q2, Eigen::Ref<MatrixXd> M) {
    const double c = std::cos(q2);
    M(0, 0) = a + 2.0 * b * c;
    M(0, 1) = M(1, 0) = d + b * c;
    M(1, 1) = d;
  };
  SystemBuilder builder({"q1", "q2"});
  builder.mass_matrix([mass](const Eigen::Ref<const VectorXd>& q, double, Eigen::Ref<MatrixXd> M) {
    mass(q[1], M);
  });
  // the Coriolis and centrifugal terms of that M (no gravity): Q = b sin q2 (2 q1' q2' + q2'²,
  // −q1'²)
  builder.forces([b](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                     double, Eigen::Ref<VectorXd> Q) {
    const double s = b * std::sin(q[1]);
    Q[0] = s * (2.0 * qd[0] * qd[1] + qd[1] * qd[1]);
    Q[1] = -s * qd[0] * qd[0];
  });
  const System arm = builder.build();
  const Controller ctrl = ControllerBuilder(arm)
                              .require(holonomic("shoulder", 1,
                                                 [](const auto& q, const auto& t, auto& e) {
                                                   using std::sin;
                                                   e[0] = q[0] - 0.4 * sin(2.0 * t);
                                                 }),
                                       ErrorDynamics::second_order(8.0))
                              .build();
  const ControlledTrajectory run =
      simulate_controlled(ctrl, arm, vec({0.3, 0.8}), vec({0.0, 1.5}), tight(2.0));
  ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
  ASSERT_GT(run.samples(), 30);
  MatrixXd M(2, 2);
  double worst = 0.0;
  for (Index j = 0; j < run.samples(); ++j) {
    const VectorXd q = Eigen::Map<const VectorXd>(run.plant.q.data() + 2 * j, 2);
    const VectorXd qd = Eigen::Map<const VectorXd>(run.plant.qd.data() + 2 * j, 2);
    mass(q[1], M);
    const double T = 0.5 * qd.dot(M * qd);
    const double got = run.plant.kinetic_energy[std::size_t(j)];
    EXPECT_NEAR(got, T, 1e-14 * T) << run.plant.t[std::size_t(j)];
    worst = std::max(worst, std::abs(got - T) / T);
  }
  record("max_rel_diff_kinetic_energy", worst);
}

// ---------------------------------------------------------------------------------------------
// the control's integrals: quadratures beside the plant (simulate_controlled), every integrator

// A free unit mass x'' = Qc held at x_d = 0 from x(0) = 1 with e'' + 4 e' + 4 e = 0:
//   e = (1 + 2t) e^{−2t},  e' = −4t e^{−2t},  Qc = e'' = (8t − 4) e^{−2t}, so
//   effort   ∫ Qc² dt     = 2 − e^{−4T} (16T² − 8T + 2),
//   work     ∫ Qc e' dt   = e'(T)² / 2 = 8T² e^{−4T},
//   |work|   ∫ |Qc e'| dt = 4 e^{−2} − 8T² e^{−4T}  (T > 1/2: ½ e'² rises to 2 e^{−2} at t = 1/2).
TEST(ControlIntegrals, EffortAndWorkAreTheClosedFormsUnderEveryIntegrator) {
  const System mass =
      SystemBuilder({"x"})
          .mass_matrix(MatrixXd::Identity(1, 1))
          .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) { Q.setZero(); })
          .build();
  const Controller ctrl =
      ControllerBuilder(mass)
          .require(holonomic("hold", 1, [](const auto& q, const auto&, auto& e) { e[0] = q[0]; }),
                   ErrorDynamics::second_order(2.0, 1.0))
          .build();
  const double T = 2.0, decay = std::exp(-4.0 * T);
  const double effort = 2.0 - decay * (16 * T * T - 8 * T + 2), work = 8 * T * T * decay,
               work_abs = 4 * std::exp(-2.0) - 8 * T * T * decay;
  for (const Integrator method :
       {Integrator::kRK4, Integrator::kDopri5, Integrator::kRKF78, Integrator::kBDF}) {
    SimulationOptions o = tight(T, 0.25);
    o.integrator = method;
    o.step = 1e-3;  // (rk4: a local error of order h⁵ per step)
    const ControlledTrajectory run = simulate_controlled(ctrl, mass, vec({1.0}), vec({0.0}), o);
    ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
    ASSERT_EQ(run.plant.n, 1);  // (the integrals are no coordinates of the run)
    const std::size_t last = std::size_t(run.samples() - 1);
    ASSERT_DOUBLE_EQ(run.plant.t[last], T);
    const double tol = method == Integrator::kBDF ? 1e-6 : 1e-9;
    EXPECT_NEAR(run.control_effort[last], effort, tol * effort) << to_string(method);
    EXPECT_NEAR(run.control_work[last], work, tol * effort) << to_string(method);
    EXPECT_NEAR(run.plant.work_control[last], work, tol * effort) << to_string(method);
    EXPECT_NEAR(run.control_work_abs[last], work_abs, tol * effort) << to_string(method);
    EXPECT_NEAR(run.error[last], (1 + 2 * T) * std::exp(-2.0 * T), 1e-8) << to_string(method);
    // the plant's energy balance with the control's work: T(t) − T(0) = W_control(t)
    EXPECT_NEAR(run.plant.kinetic_energy[last], 0.5 * 16 * T * T * decay, tol * effort);
    EXPECT_NEAR(run.plant.kinetic_energy[last], run.control_work[last], tol * effort);
  }
}

// ---------------------------------------------------------------------------------------------
// a mass matrix that is not positive definite (defect 03 of session 17): control factorizes the
// model's completion M_A (control/laws.cpp; docs/singular-mass.md, "Limits")

TEST(ControlSingularMass, AModelWhoseMIsSingularIsControlledOnItsCompletion) {
  // M = diag(m, 0), y tied to x: [M; A] has full rank, and the Gauss law, fully actuated, runs
  // on M_A = M + A_pᵀ G A_p (it stopped with "the nominal model failed: ok", then with "M is not
  // positive definite"). x = sin t + e, e'' + 20 e' + 100 e = 0 from e(0) = 0, e'(0) = −1:
  // e = −t exp(−10 t); y = x; the control's F_x + F_y = m x'' (its split between x and y is the
  // tie's to take: F + μ (−1, 1) moves nothing)
  Model m = parse_model(
      "parameters: {m: 2}\n"
      "coordinates: [x, y]\n"
      "kinetic_energy: 0.5*m*x_dot^2\n"
      "potential_energy: 0\n"
      "constraints:\n"
      "  - {name: tie, holonomic: y - x}\n"
      "control:\n"
      "  requirements:\n"
      "    - {name: track, holonomic: x - sin(t), dynamics: {omega: 10, zeta: 1}}\n"
      "simulate: {t_end: 0.5, integrator: dopri5, rtol: 1e-11, atol: 1e-13}\n"
      "output: {every: 0.1}\n");
  const ControlledTrajectory r =
      simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(r.plant.stats.status, Status::kOk) << r.plant.stats.message;
  EXPECT_EQ(r.control.not_met, 0) << r.control.not_met_message;
  const Trajectory& tr = r.plant;
  ASSERT_EQ(tr.samples(), 6);
  for (std::size_t i = 0; i < 6; ++i) {
    const double t = tr.t[i], E = std::exp(-10.0 * t);
    const double x = std::sin(t) - t * E, x2 = -std::sin(t) + (20.0 - 100.0 * t) * E;
    EXPECT_NEAR(tr.q[2 * i], x, 1e-9) << "t = " << t;
    EXPECT_NEAR(tr.q[2 * i + 1], x, 1e-9) << "t = " << t;
    EXPECT_NEAR(r.Qc_control[2 * i] + r.Qc_control[2 * i + 1], 2.0 * x2, 1e-7) << "t = " << t;
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
