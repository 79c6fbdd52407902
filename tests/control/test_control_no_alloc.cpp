// SPDX-License-Identifier: BSD-3-Clause
// No heap allocation per control evaluation once the control workspace exists: both laws, a
// state-dependent M and N, actuated subsets, physical constraints, nonholonomic requirements,
// requirements that cannot be met, the robust term, and the controlled plant's forward dynamics.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <ukdyn/control/control.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/alloc_counter.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using testing::start_counting_allocations;
using testing::stop_counting_allocations;

// allocations made by `calls` evaluations on a fresh control workspace (none before them)
long allocations_of(const Controller& ctrl, const Eigen::Ref<const VectorXd>& q,
                    const Eigen::Ref<const VectorXd>& qd, int calls,
                    ControlStatus expected = ControlStatus::kOk) {
  ControlWorkspace ws(ctrl);
  start_counting_allocations();
  for (int i = 0; i < calls; ++i) compute_control(ctrl, ws, q, qd, 0.01 * i);
  const long count = stop_counting_allocations();
  EXPECT_EQ(ws.status, expected) << describe_control_status(ctrl, ws);
  return count;
}

// a triple pendulum in absolute angles with a state-dependent M; callables that do not allocate
System chain() {
  const double m[3] = {1.0, 0.8, 0.6}, L[3] = {1.0, 0.9, 0.8};
  Eigen::Matrix3d mu;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      mu(i, j) = 0.0;
      for (int k = std::max(i, j); k < 3; ++k) mu(i, j) += m[k];
      mu(i, j) *= L[i] * L[j];
    }
  }
  const Eigen::Vector3d mgL(9.81 * (m[0] + m[1] + m[2]) * L[0], 9.81 * (m[1] + m[2]) * L[1],
                            9.81 * m[2] * L[2]);
  return SystemBuilder({"th1", "th2", "th3"})
      .mass_matrix([mu](const Eigen::Ref<const VectorXd>& q, double, Eigen::Ref<MatrixXd> M) {
        for (Index i = 0; i < 3; ++i) {
          for (Index j = 0; j < 3; ++j) M(i, j) = mu(i, j) * std::cos(q[i] - q[j]);
        }
      })
      .forces([mu, mgL](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                        double, Eigen::Ref<VectorXd> Q) {
        for (Index i = 0; i < 3; ++i) {
          Q[i] = -mgL[i] * std::sin(q[i]);
          for (Index j = 0; j < 3; ++j) Q[i] -= mu(i, j) * std::sin(q[i] - q[j]) * qd[j] * qd[j];
        }
      })
      .build();
}

Constraint joint(Index i) {
  return holonomic("joint" + std::to_string(i + 1), 1, [i](const auto& q, const auto& t, auto& e) {
    using std::sin;
    e[0] = q[i] - 0.4 * sin(t);
  });
}

Constraint tip() {
  return holonomic("tip", 2, [](const auto& q, const auto& t, auto& e) {
    using std::cos;
    using std::sin;
    e[0] = sin(q[0]) + 0.9 * sin(q[1]) + 0.8 * sin(q[2]) - 0.8 - 0.3 * sin(t);
    e[1] = -cos(q[0]) - 0.9 * cos(q[1]) - 0.8 * cos(q[2]) + 2.0 - 0.3 * cos(t);
  });
}

const VectorXd& q3() {
  static const VectorXd q = (VectorXd(3) << 0.3, -0.2, 0.5).finished();
  return q;
}
const VectorXd& qd3() {
  static const VectorXd qd = (VectorXd(3) << 0.1, 0.4, -0.3).finished();
  return qd;
}

TEST(ControlNoAllocation, CounterSeesAllocations) {
  start_counting_allocations();
  VectorXd v = VectorXd::Constant(100, 1.0);
  asm volatile("" : : "r"(v.data()) : "memory");
  EXPECT_EQ(stop_counting_allocations(), 1);
  EXPECT_DOUBLE_EQ(v.sum(), 100.0);
}

TEST(ControlNoAllocation, GaussStateDependentMass) {
  const Controller c =
      ControllerBuilder(chain()).require(tip(), ErrorDynamics::second_order(2.0)).build();
  EXPECT_EQ(allocations_of(c, q3(), qd3(), 10), 0);
}

TEST(ControlNoAllocation, WeightedStateDependentAndConstant) {
  const Controller c =
      ControllerBuilder(chain())
          .require(tip(), ErrorDynamics::second_order(2.0))
          .weighted([](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>&,
                       double, Eigen::Ref<MatrixXd> N) {
            N.setZero();
            N(0, 0) = 1.0 + q[0] * q[0];
            N(1, 1) = 2.0;
            N(2, 2) = 3.0 + std::sin(q[1]);
          })
          .build();
  EXPECT_EQ(allocations_of(c, q3(), qd3(), 10), 0);
  const Controller k = ControllerBuilder(chain())
                           .require(tip(), ErrorDynamics::second_order(2.0))
                           .weighted(Eigen::Vector3d(1.0, 2.0, 3.0).asDiagonal().toDenseMatrix())
                           .build();
  EXPECT_EQ(allocations_of(k, q3(), qd3(), 10), 0);
}

TEST(ControlNoAllocation, ActuatedSubsetsAndInfeasibleRequirements) {
  const Controller gauss = ControllerBuilder(chain())
                               .require(joint(2), ErrorDynamics::second_order(3.0))
                               .actuated({"th3"})
                               .build();
  EXPECT_EQ(allocations_of(gauss, q3(), qd3(), 10), 0);
  const Controller weighted = ControllerBuilder(chain())
                                  .require(tip(), ErrorDynamics::second_order(2.0))
                                  .weighted(MatrixXd::Identity(3, 3))
                                  .actuated({"th2", "th3"})
                                  .build();
  EXPECT_EQ(allocations_of(weighted, q3(), qd3(), 10), 0);
  MatrixXd S(3, 2);
  S << 1, 0, 1, 1, 0, 1;
  const Controller matrix = ControllerBuilder(chain())
                                .require(tip(), ErrorDynamics::second_order(2.0))
                                .actuation(S)
                                .build();
  EXPECT_EQ(allocations_of(matrix, q3(), qd3(), 10), 0);
  const Controller infeasible = ControllerBuilder(chain())
                                    .require(joint(0), ErrorDynamics::second_order(3.0))
                                    .require(joint(1), ErrorDynamics::second_order(3.0))
                                    .actuated({"th3"})
                                    .build();
  EXPECT_EQ(allocations_of(infeasible, q3(), qd3(), 10, ControlStatus::kRequirementsNotMet), 0);
}

TEST(ControlNoAllocation, PhysicalConstraintsNonholonomicAndRobust) {
  const System pendulum =
      SystemBuilder({"x", "y"})
          .mass_matrix(MatrixXd::Identity(2, 2))
          .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) {
            Q[0] = 0.0;
            Q[1] = -9.81;
          })
          .add(holonomic("rod", 1,
                         [](const auto& q, const auto&, auto& phi) {
                           phi[0] = (q[0] * q[0] + q[1] * q[1] - 1.0) / 2.0;
                         }))
          .add(viscous_friction({.coefficient = 0.1}))
          .build();
  const Constraint x_speed =
      nonholonomic("x_speed", 1, [](const auto&, const auto& qd, const auto& t, auto& psi) {
        using std::cos;
        psi[0] = qd[0] - 0.3 * cos(t);
      });
  VectorXd q(2), qd(2);
  q << std::sin(0.3), -std::cos(0.3);
  qd << std::cos(0.3) * 0.5, std::sin(0.3) * 0.5;
  const Controller gauss =
      ControllerBuilder(pendulum).require(x_speed, ErrorDynamics::first_order(2.0)).build();
  EXPECT_EQ(allocations_of(gauss, q, qd, 10), 0);
  const Controller actuated =
      ControllerBuilder(pendulum)
          .require(x_speed, ErrorDynamics::first_order(2.0))
          .actuated({"x"})
          .robust({.relative_bound = 0.2, .gain_uncertainty = 0.2, .boundary_layer = 1e-3})
          .build();
  EXPECT_EQ(allocations_of(actuated, q, qd, 10), 0);
  const Controller robust = ControllerBuilder(chain())
                                .require(tip(), ErrorDynamics::second_order(2.0))
                                .robust({.bound = 0.1,
                                         .relative_bound = 0.2,
                                         .gain_uncertainty = 0.1,
                                         .boundary_layer = 1e-2})
                                .build();
  EXPECT_EQ(allocations_of(robust, q3(), qd3(), 10), 0);
}

TEST(ControlNoAllocation, ControlledPlantForwardDynamics) {
  const System plant = chain();
  const Controller c =
      ControllerBuilder(plant).require(tip(), ErrorDynamics::second_order(2.0)).build();
  const System controlled = controlled_system(c, plant);
  Workspace ws(controlled);
  const VectorXd q = q3(), qd = qd3();  // made before counting
  start_counting_allocations();
  for (int i = 0; i < 10; ++i) forward_dynamics(controlled, ws, q, qd, 0.01 * i);
  const long count = stop_counting_allocations();
  EXPECT_EQ(ws.status, Status::kOk) << describe_status(controlled, ws);
  EXPECT_EQ(count, 0);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
