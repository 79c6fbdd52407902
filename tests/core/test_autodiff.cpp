// SPDX-License-Identifier: BSD-3-Clause
// Automatically derived A and b against hand-derived ones.
#include <cmath>

#include <gtest/gtest.h>

#include <ukdyn/core/autodiff.hpp>

#include "support/random_problem.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

struct Derived {
  MatrixXd A;
  VectorXd b, position, velocity;
};

// A, b and the violations of constraint c at (q, q', t)
Derived derive(const Constraint& c, const Eigen::Ref<const VectorXd>& q,
               const Eigen::Ref<const VectorXd>& qd, double t) {
  const Index n = q.size();
  auto scratch = c.model().make_scratch(n);
  Derived d{MatrixXd(c.rows(), n), VectorXd(c.rows()), VectorXd(c.rows()), VectorXd(c.rows())};
  c.model().acceleration_form(q, qd, t, scratch.get(), d.A, d.b);
  c.model().violation(q, qd, t, scratch.get(), d.position, d.velocity);
  return d;
}

using testing::vec;

constexpr double kTol = 1e-13;

TEST(AutoDiff, PendulumInCartesianCoordinates) {
  const double L = 1.3;
  const auto c = holonomic("rod", 1, [L](const auto& q, const auto&, auto& phi) {
    phi[0] = q[0] * q[0] + q[1] * q[1] - L * L;
  });
  const VectorXd q = vec({0.7, -0.9}), qd = vec({1.1, 0.4});
  const auto d = derive(c, q, qd, 0.3);
  // A = [2x, 2y], b = −2(x'² + y'²)
  EXPECT_NEAR(d.A(0, 0), 2 * q[0], kTol);
  EXPECT_NEAR(d.A(0, 1), 2 * q[1], kTol);
  EXPECT_NEAR(d.b[0], -2 * qd.squaredNorm(), kTol);
  EXPECT_NEAR(d.position[0], q.squaredNorm() - L * L, kTol);
  EXPECT_NEAR(d.velocity[0], 2 * q.dot(qd), kTol);
  EXPECT_EQ(c.kind(), ConstraintKind::kHolonomic);
}

TEST(AutoDiff, BeadOnUniformlyRotatingWire) {
  const double W = 2.5;  // the wire through the origin at angle W t: −x sin(Wt) + y cos(Wt) = 0
  const auto c = holonomic("wire", 1, [W](const auto& q, const auto& t, auto& phi) {
    using std::cos;
    using std::sin;
    phi[0] = -q[0] * sin(W * t) + q[1] * cos(W * t);
  });
  const VectorXd q = vec({0.8, 0.3}), qd = vec({-0.2, 1.7});
  const double t = 0.41, s = std::sin(W * t), co = std::cos(W * t);
  const auto d = derive(c, q, qd, t);
  // A = [−sin Wt, cos Wt];  b = 2W(x' cos Wt + y' sin Wt) − W²(x sin Wt − y cos Wt)
  EXPECT_NEAR(d.A(0, 0), -s, kTol);
  EXPECT_NEAR(d.A(0, 1), co, kTol);
  EXPECT_NEAR(d.b[0], 2 * W * (qd[0] * co + qd[1] * s) - W * W * (q[0] * s - q[1] * co), kTol);
  // d phi/dt along the motion = A q' + dphi/dt
  EXPECT_NEAR(d.velocity[0], -qd[0] * s + qd[1] * co - W * (q[0] * co + q[1] * s), kTol);
}

TEST(AutoDiff, PendulumOfTimeVaryingLength) {
  const double L0 = 1.0, eps = 0.2, w = 3.0;  // L(t) = L0 + eps sin(w t)
  const auto c = holonomic("rod", 1, [=](const auto& q, const auto& t, auto& phi) {
    using std::sin;
    using S = std::decay_t<decltype(t)>;
    const S L = L0 + eps * sin(w * t);
    phi[0] = q[0] * q[0] + q[1] * q[1] - L * L;
  });
  const VectorXd q = vec({0.5, -0.95}), qd = vec({0.9, -0.3});
  const double t = 1.7;
  const double L = L0 + eps * std::sin(w * t), Ld = eps * w * std::cos(w * t),
               Ldd = -eps * w * w * std::sin(w * t);
  const auto d = derive(c, q, qd, t);
  // b = −2(x'² + y'²) + 2(L'² + L L'')
  EXPECT_NEAR(d.A(0, 0), 2 * q[0], kTol);
  EXPECT_NEAR(d.A(0, 1), 2 * q[1], kTol);
  EXPECT_NEAR(d.b[0], -2 * qd.squaredNorm() + 2 * (Ld * Ld + L * Ldd), kTol);
  EXPECT_NEAR(d.position[0], q.squaredNorm() - L * L, kTol);
}

TEST(AutoDiff, KnifeEdgeIsLinearInVelocity) {
  const auto c =
      nonholonomic("knife", 1, [](const auto& q, const auto& qd, const auto&, auto& psi) {
        using std::cos;
        using std::sin;
        psi[0] = qd[0] * sin(q[2]) - qd[1] * cos(q[2]);
      });
  const VectorXd q = vec({0.3, -1.2, 0.77}), qd = vec({0.6, 0.25, -1.4});
  const double s = std::sin(q[2]), co = std::cos(q[2]);
  const auto d = derive(c, q, qd, 0.0);
  // A = [sin θ, −cos θ, 0];  b = −(x' cos θ + y' sin θ) θ'
  EXPECT_NEAR(d.A(0, 0), s, kTol);
  EXPECT_NEAR(d.A(0, 1), -co, kTol);
  EXPECT_NEAR(d.A(0, 2), 0.0, kTol);
  EXPECT_NEAR(d.b[0], -(qd[0] * co + qd[1] * s) * qd[2], kTol);
  EXPECT_NEAR(d.velocity[0], qd[0] * s - qd[1] * co, kTol);
  EXPECT_NEAR(d.position[0], 0.0, kTol);
  EXPECT_EQ(c.kind(), ConstraintKind::kNonholonomic);
}

TEST(AutoDiff, VelocityQuadraticConstraint) {
  const double cc = 0.7;  // x'² + y'² − c² z'² = 0
  const auto c = nonholonomic("cone", 1, [cc](const auto&, const auto& qd, const auto&, auto& psi) {
    psi[0] = qd[0] * qd[0] + qd[1] * qd[1] - cc * cc * qd[2] * qd[2];
  });
  const VectorXd q = vec({1.0, 2.0, 3.0}), qd = vec({0.3, -0.4, 0.9});
  const auto d = derive(c, q, qd, 0.0);
  // A = [2x', 2y', −2c² z'];  b = 0
  EXPECT_NEAR(d.A(0, 0), 2 * qd[0], kTol);
  EXPECT_NEAR(d.A(0, 1), 2 * qd[1], kTol);
  EXPECT_NEAR(d.A(0, 2), -2 * cc * cc * qd[2], kTol);
  EXPECT_NEAR(d.b[0], 0.0, kTol);
}

TEST(AutoDiff, NonholonomicWithExplicitTimeAndPosition) {
  // psi = x' − t y:  A = [1, 0], b = −(dpsi/dq q' + dpsi/dt) = t y' + y
  const auto c = nonholonomic(
      "drive", 1,
      [](const auto& q, const auto& qd, const auto& t, auto& psi) { psi[0] = qd[0] - t * q[1]; });
  const VectorXd q = vec({0.1, 0.8}), qd = vec({-0.5, 1.9});
  const double t = 2.2;
  const auto d = derive(c, q, qd, t);
  EXPECT_NEAR(d.A(0, 0), 1.0, kTol);
  EXPECT_NEAR(d.A(0, 1), 0.0, kTol);
  EXPECT_NEAR(d.b[0], t * qd[1] + q[1], kTol);
}

TEST(AutoDiff, HolonomicAcrossSeveralJacobianChunks) {
  // n = 9 spans three chunks: phi = Σ (j+1) q_j² + t² q_0
  const Index n = 9;
  const auto c = holonomic("sum", 1, [n](const auto& q, const auto& t, auto& phi) {
    using S = std::decay_t<decltype(t)>;
    S s = t * t * q[0];
    for (Index j = 0; j < n; ++j) s += double(j + 1) * q[j] * q[j];
    phi[0] = s;
  });
  VectorXd q(n), qd(n);
  for (Index j = 0; j < n; ++j) {
    q[j] = 0.1 * double(j) - 0.3;
    qd[j] = 0.2 - 0.05 * double(j * j);
  }
  const double t = 0.9;
  const auto d = derive(c, q, qd, t);
  // A_j = 2 (j+1) q_j + [j = 0] t²;  b = −(Σ 2 (j+1) q_j'² + 2 q_0 + 4 t q_0')
  double b = 2 * q[0] + 4 * t * qd[0];
  for (Index j = 0; j < n; ++j) {
    EXPECT_NEAR(d.A(0, j), 2.0 * double(j + 1) * q[j] + (j == 0 ? t * t : 0.0), kTol) << j;
    b += 2.0 * double(j + 1) * qd[j] * qd[j];
  }
  EXPECT_NEAR(d.b[0], -b, kTol);
}

TEST(AutoDiff, NonholonomicAcrossSeveralChunksWithTwoRows) {
  // n = 7, so n + 1 = 8 directions fill exactly two chunks
  // psi_0 = Σ (j+1) q_j q_j'² + t q_0',  psi_1 = q_1 q_2'
  const Index n = 7;
  const auto c =
      nonholonomic("pair", 2, [n](const auto& q, const auto& qd, const auto& t, auto& psi) {
        using S = std::decay_t<decltype(t)>;
        S s = t * qd[0];
        for (Index j = 0; j < n; ++j) s += double(j + 1) * q[j] * qd[j] * qd[j];
        psi[0] = s;
        psi[1] = q[1] * qd[2];
      });
  VectorXd q(n), qd(n);
  for (Index j = 0; j < n; ++j) {
    q[j] = 0.3 + 0.1 * double(j);
    qd[j] = -0.4 + 0.15 * double(j);
  }
  const double t = 1.3;
  const auto d = derive(c, q, qd, t);
  double b0 = qd[0];  // dpsi_0/dt
  for (Index j = 0; j < n; ++j) {
    EXPECT_NEAR(d.A(0, j), 2.0 * double(j + 1) * q[j] * qd[j] + (j == 0 ? t : 0.0), kTol) << j;
    EXPECT_NEAR(d.A(1, j), j == 2 ? q[1] : 0.0, kTol) << j;
    b0 += double(j + 1) * qd[j] * qd[j] * qd[j];
  }
  EXPECT_NEAR(d.b[0], -b0, kTol);
  EXPECT_NEAR(d.b[1], -qd[1] * qd[2], kTol);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
