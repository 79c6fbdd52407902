// SPDX-License-Identifier: BSD-3-Clause
// Redundant constraints in a simulation (issue #13, item 1): off the constraint manifold an
// inconsistency that the state's own violation explains takes the least-squares q''; a genuine
// one is still an error naming the constraints. The IFToMM A04 Bricard mechanism
// (examples/models/bricard.yaml) runs on default settings and follows its 1-DOF reduced
// dynamics, solved here without ukdyn.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/ukdyn.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr double kG = 9.81;

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

Model load_example(const std::string& name) {
  return load_model(std::string(UKDYN_EXAMPLES_DIR) + "/" + name + ".yaml");
}

// ---------------------------------------------------------------------------------------------
// a genuine inconsistency

// a pendulum (particle on a rod of length 1) with a second, acceleration-form copy of the rod's
// row whose b is off by `gap` from t = 0.5 on: contradictory constraints, which no violation of
// the state explains
System contradictory_pendulum(double gap) {
  auto rod = [](const auto& q, const auto&, auto& phi) {
    phi[0] = 0.5 * (q[0] * q[0] + q[1] * q[1] - 1.0);
  };
  auto rod_again = [gap](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, Eigen::Ref<MatrixXd> A, Eigen::Ref<VectorXd> b) {
    A << q[0], q[1];
    b << -qd.squaredNorm() + (t > 0.5 ? gap : 0.0);
  };
  return SystemBuilder(std::vector<std::string>{"x", "y"})
      .mass_matrix(MatrixXd::Identity(2, 2))
      .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<VectorXd> Q) { Q << 0.0, -kG; })
      .add(holonomic("rod", 1, rod))
      .add(acceleration_constraint("rod_again", 1, rod_again))
      .build();
}

TEST(Redundancy, ContradictoryConstraintsStillFailInsideSimulateNamingThem) {
  const System sys = contradictory_pendulum(1.0);
  VectorXd q0(2), qd0(2);
  q0 << 1.0, 0.0;
  qd0 << 0.0, 0.0;
  const Trajectory tr = simulate(sys, q0, qd0, {.t_end = 2.0});
  EXPECT_EQ(tr.stats.status, Status::kInconsistentConstraints);
  EXPECT_NEAR(tr.stats.t_reached, 0.5, 0.02);
  EXPECT_TRUE(contains(tr.stats.message, "inconsistent constraints")) << tr.stats.message;
  EXPECT_TRUE(contains(tr.stats.message,
                       "the constraints that cannot all hold: 'rod', "
                       "'rod_again'"))
      << tr.stats.message;
  // consistent until then: nothing was least-squared
  EXPECT_EQ(tr.stats.least_squares, 0);
  // the same rows with consistent right-hand sides run to the end
  const Trajectory ok = simulate(contradictory_pendulum(0.0), q0, qd0, {.t_end = 2.0});
  EXPECT_EQ(ok.stats.status, Status::kOk) << ok.stats.message;
}

TEST(Redundancy, ForwardDynamicsOnAUsersStateStaysStrict) {
  // the Bricard mechanism at rest: consistent (rank 34 of 35 rows); with velocities off the
  // constraints the redundant row's b disagrees, and forward_dynamics says so (only a
  // simulation's stage states are forgiven)
  const Model m = load_example("bricard");
  Workspace ws(m.system);
  ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, m.qd0, 0.0), Status::kOk)
      << describe_status(m.system, ws);
  EXPECT_EQ(ws.rank, 34);
  EXPECT_EQ(ws.active_rows, 35);
  VectorXd qd = VectorXd::Zero(m.system.coordinate_count());
  for (Index i = 0; i < qd.size(); ++i) qd[i] = 0.1 * std::sin(1.0 + 3.0 * double(i));
  EXPECT_EQ(forward_dynamics(m.system, ws, m.q0, qd, 0.0), Status::kInconsistentConstraints);
  EXPECT_TRUE(contains(describe_status(m.system, ws), "the constraints that cannot all hold: "))
      << describe_status(m.system, ws);
}

// ---------------------------------------------------------------------------------------------
// the Bricard mechanism's 1-DOF reduced dynamics, independent of ukdyn
//
// Joints j = 0..5 at the cube corners V_j with axes a_j (initial, world); rod k = 1..5 spans
// V_{k-1} → V_k and turns by R_k = R_{k-1} Rot(a_{k-1}, θ_{k-1}) (all frames start aligned with
// the world, so the axes in the parent's frame are the initial ones). The chain's end must meet
// the ground joint at V_5 with its axis along a_5: five equations f(θ_0..θ_4) = 0 of rank 4. For
// a given θ_1 (the second joint's angle, which has no turning point along this motion, unlike
// θ_0 at −π/6) Gauss–Newton solves the other four; the tangent θ' (θ_1' = 1) solves
// J_r t = −J_1; then T = ½ μ(θ_1) θ_1'², V(θ_1) and Lagrange's equation
// μ θ_1'' + ½ μ' θ_1'² + V' = 0, integrated with RK4 (μ' by central differences).
class BricardReference {
 public:
  BricardReference() {
    V_ = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(1, 1, 0),
          Vector3d(1, 1, 1), Vector3d(0, 1, 1), Vector3d(0, 0, 1)};
    a_ = {Vector3d::UnitY(), Vector3d::UnitZ(), Vector3d::UnitX(),
          Vector3d::UnitY(), Vector3d::UnitZ(), Vector3d::UnitX()};
    const double a = 0.1, L = 1.0, Jt = (L * L + a * a) / 12.0, Ja = a * a / 6.0;
    for (int k = 1; k <= 5; ++k) {
      const Vector3d d = V_[k] - V_[k - 1];
      J_[k] = Matrix3d::Identity() * Jt;
      for (int i = 0; i < 3; ++i) {
        if (std::abs(d[i]) > 0.5) J_[k](i, i) = Ja;
      }
    }
    theta_.setZero();
  }

  // closure solved for θ_1 (warm start from the last solution)
  void solve(double theta1) {
    theta_[kFree] = theta1;
    for (int it = 0; it < 30; ++it) {
      pose();
      const Eigen::Matrix<double, 5, 1> f = residual();
      if (f.norm() < 1e-15) return;
      const Eigen::Matrix<double, 5, 5> J = jacobian();
      const Eigen::Matrix<double, 4, 1> d = others(J).colPivHouseholderQr().solve(-f);
      add_others(d);
      if (d.norm() < 1e-16) break;
    }
    pose();
  }

  // μ(θ_1), dV/dθ_1 and V at the solved pose
  void coefficients(double& mu, double& dV, double& V) {
    const Eigen::Matrix<double, 5, 5> J = jacobian();
    Eigen::Matrix<double, 5, 1> rate = Eigen::Matrix<double, 5, 1>::Zero();
    const Eigen::Matrix<double, 4, 1> t = others(J).colPivHouseholderQr().solve(-J.col(kFree));
    std::swap(theta_, rate);
    theta_[kFree] = 1.0;
    add_others(t);
    std::swap(theta_, rate);
    mu = dV = V = 0.0;
    for (int k = 1; k <= 5; ++k) {
      const Vector3d c = 0.5 * (p_[k - 1] + p_[k]);
      Vector3d v = Vector3d::Zero(), w = Vector3d::Zero();
      for (int j = 0; j < k; ++j) {
        w += rate[j] * axis_[j];
        v += rate[j] * axis_[j].cross(c - p_[j]);
      }
      mu += v.squaredNorm() + w.dot(R_[k] * J_[k] * R_[k].transpose() * w);
      dV += kG * v.y();
      V += kG * c.y();
    }
    largest_rate_ = std::max(largest_rate_, rate.cwiseAbs().maxCoeff());
  }

  // θ_1'' at (θ_1, θ_1'); energy() then gives E there
  double acceleration(double th, double thd) {
    constexpr double h = 1e-5;
    double mu_p, mu_m, mu, dV, V, unused;
    const Eigen::Matrix<double, 5, 1> start = theta_;
    solve(th + h);
    coefficients(mu_p, unused, unused);
    solve(th - h);
    coefficients(mu_m, unused, unused);
    theta_ = start;
    solve(th);
    coefficients(mu, dV, V);
    energy_ = 0.5 * mu * thd * thd + V;
    return -(0.5 * (mu_p - mu_m) / (2 * h) * thd * thd + dV) / mu;
  }

  double energy() const { return energy_; }
  double theta0() const { return theta_[0]; }
  double largest_rate() const { return largest_rate_; }
  // joint j4's world position (the far end of rod 3) at the last solved pose
  const Vector3d& corner() const { return p_[3]; }

 private:
  static constexpr int kFree = 1;
  // the columns of J of the four dependent angles, and adding their increments
  static Eigen::Matrix<double, 5, 4> others(const Eigen::Matrix<double, 5, 5>& J) {
    Eigen::Matrix<double, 5, 4> Jo;
    Jo << J.col(0), J.rightCols<3>();
    return Jo;
  }
  void add_others(const Eigen::Matrix<double, 4, 1>& d) {
    theta_[0] += d[0];
    theta_.tail<3>() += d.tail<3>();
  }
  static Matrix3d rot(const Vector3d& axis, double angle) {
    return Eigen::AngleAxisd(angle, axis).toRotationMatrix();
  }
  // R_k, world axes w_j = R_j a_j, joint points p_j (p_5: the chain's end)
  void pose() {
    R_[0] = Matrix3d::Identity();
    p_[0] = V_[0];
    for (int k = 1; k <= 5; ++k) {
      R_[k] = R_[k - 1] * rot(a_[k - 1], theta_[k - 1]);
      axis_[k - 1] = R_[k - 1] * a_[k - 1];
      p_[k] = p_[k - 1] + R_[k] * (V_[k] - V_[k - 1]);
    }
  }
  Eigen::Matrix<double, 5, 1> residual() const {
    Eigen::Matrix<double, 5, 1> f;
    const Vector3d end_axis = R_[5] * a_[5];
    f << p_[5] - V_[5], end_axis.y(), end_axis.z();
    return f;
  }
  Eigen::Matrix<double, 5, 5> jacobian() const {
    Eigen::Matrix<double, 5, 5> J;
    const Vector3d end_axis = R_[5] * a_[5];
    for (int j = 0; j < 5; ++j) {
      const Vector3d dp = axis_[j].cross(p_[5] - p_[j]), da = axis_[j].cross(end_axis);
      J.col(j) << dp, da.y(), da.z();
    }
    return J;
  }

  std::array<Vector3d, 6> V_, a_, axis_, p_;
  std::array<Matrix3d, 6> R_, J_;
  Eigen::Matrix<double, 5, 1> theta_;
  double energy_ = 0.0, largest_rate_ = 0.0;
};

// θ_0(t) at t = 0, dt, …, t_end (RK4 in θ_1 with `substeps` steps per sample), the largest
// energy change of the reduced model and the largest dependent joint rate per unit θ_1'
std::vector<double> reference_angle(double t_end, double dt, int substeps, double& energy_change,
                                    double& largest_rate) {
  BricardReference ref;
  std::vector<double> out = {0.0};
  double th = 0.0, thd = 0.0;
  ref.acceleration(th, thd);
  const double E0 = ref.energy();
  energy_change = 0.0;
  const double h = dt / substeps;
  const int samples = int(std::lround(t_end / dt));
  for (int i = 0; i < samples; ++i) {
    for (int s = 0; s < substeps; ++s) {
      const double k1 = ref.acceleration(th, thd), l1 = thd;
      const double k2 = ref.acceleration(th + 0.5 * h * l1, thd + 0.5 * h * k1),
                   l2 = thd + 0.5 * h * k1;
      const double k3 = ref.acceleration(th + 0.5 * h * l2, thd + 0.5 * h * k2),
                   l3 = thd + 0.5 * h * k2;
      const double k4 = ref.acceleration(th + h * l3, thd + h * k3), l4 = thd + h * k3;
      th += h / 6 * (l1 + 2 * l2 + 2 * l3 + l4);
      thd += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    ref.acceleration(th, thd);
    energy_change = std::max(energy_change, std::abs(ref.energy() - E0));
    out.push_back(ref.theta0());
  }
  largest_rate = ref.largest_rate();
  return out;
}

constexpr double kReferenceSpan = 1.0;

TEST(Redundancy, BricardRunsOnDefaultsConservesEnergyAndFollowsItsReducedDynamics) {
  const Model m = load_example("bricard");
  ASSERT_EQ(m.options.integrator, Integrator::kDopri5);  // the defaults
  ASSERT_EQ(m.options.rtol, SimulationOptions{}.rtol);
  ASSERT_EQ(m.options.drift, DriftControl::kProjection);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_NEAR(tr.t.back(), 10.0, 1e-12);
  // the stage states took the least-squares acceleration, and said so
  EXPECT_GT(tr.stats.least_squares, 0);
  // energy (29.43 J at rest) kept to 1e-7 of its magnitude; the loop closed to 1e-10 m
  const double E0 = tr.energy.front();
  double dE = 0.0;
  for (double E : tr.energy) dE = std::max(dE, std::abs(E - E0));
  EXPECT_NEAR(dE / std::abs(E0), 0.0, 1e-7);
  EXPECT_NEAR(tr.stats.energy_drift, 0.0, 1e-7);
  EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-10);
  // θ_0 = the angle of rod 1 about y: u = (cos θ/2, 0, sin θ/2, 0)
  double energy_change = 0.0, largest_rate = 0.0;
  // (over the first second: θ_1, the reduced model's coordinate, turns later in the motion)
  const std::vector<double> ref =
      reference_angle(kReferenceSpan, 0.01, 10, energy_change, largest_rate);
  ASSERT_LE(ref.size(), tr.t.size());
  EXPECT_NEAR(energy_change / std::abs(E0), 0.0, 1e-9);  // the reference's own accuracy
  const Index n = tr.n, u0 = m.system.coordinate_index("rod1.u0"),
              u2 = m.system.coordinate_index("rod1.u2");
  double worst = 0.0, range = 0.0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const double* q = tr.q.data() + i * std::size_t(n);
    const double theta = 2.0 * std::atan2(q[u2], q[u0]);
    worst = std::max(worst, std::abs(theta - ref[i]));
    range = std::max(range, std::abs(ref[i]));
  }
  EXPECT_GT(range, 0.3);  // it moves
  EXPECT_NEAR(worst, 0.0, 1e-8) << "largest |θ_0 − reference| over the first second";
  std::printf(
      "[ Bricard ] steps %ld, evaluations %ld (least squares %ld), energy %.3g (rel), "
      "closure %.3g m, |θ_0 − reference| %.3g rad (range %.3g), reference energy %.3g, "
      "largest joint rate ratio %.3g\n",
      tr.stats.steps, tr.stats.evaluations, tr.stats.least_squares, dE / std::abs(E0),
      tr.stats.max_position_violation, worst, range, energy_change / std::abs(E0), largest_rate);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
