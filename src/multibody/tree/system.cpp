// SPDX-License-Identifier: BSD-3-Clause
// A tree as ukdyn's unconstrained system: M from the CRBA, Q = τ − D q' − h from the RNEA.
#include <cmath>
#include <memory>
#include <utility>

#include "multibody/internal.hpp"
#include "multibody/tree/spatial.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree {

namespace {

// the per-workspace buffers of the tree's callables
struct TreeScratch final : CallableScratch {
  explicit TreeScratch(const Tree& tree)
      : data(tree), h(tree.coordinate_count()), tau(tree.coordinate_count()) {}
  TreeData data;  // the passes' links
  VectorXd h;     // (n) bias forces, filled by Q
  VectorXd tau;   // (n) the input τ, filled by Q and P_ext
};

TreeScratch& scratch_of(CallableScratch* s) { return *static_cast<TreeScratch*>(s); }

}  // namespace

System make_system(const Tree& tree, JointTorqueFn tau) {
  return system_builder(tree, std::move(tau)).build();
}

SystemBuilder system_builder(const Tree& tree_in, JointTorqueFn tau) {
  const auto tree = std::make_shared<const Tree>(tree_in);
  const Index n = tree->coordinate_count();
  // D, the joints' viscous damping (n)
  VectorXd D = VectorXd::Zero(n);
  for (Index i = 0; i < tree->link_count(); ++i) {
    if (tree->dofs(i) == 1) D[tree->offset(i)] = tree->link(i).joint.damping;
  }
  const bool damped = D.any();
  SystemBuilder sb(tree->coordinate_names());
  sb.scratch([tree]() -> std::unique_ptr<CallableScratch> {
    return std::make_unique<TreeScratch>(*tree);
  });
  sb.mass_matrix([tree](const Eigen::Ref<const VectorXd>& q, double, CallableScratch* s,
                        Eigen::Ref<MatrixXd> M) { mass_matrix(*tree, q, scratch_of(s).data, M); });
  // Q = τ − D q' − h(q, q')
  sb.forces([tree, D, tau](const Eigen::Ref<const VectorXd>& q,
                           const Eigen::Ref<const VectorXd>& qd, double t, CallableScratch* s,
                           Eigen::Ref<VectorXd> Q) {
    TreeScratch& ts = scratch_of(s);
    bias_forces(*tree, q, qd, ts.data, ts.h);
    Q = -ts.h - D.cwiseProduct(qd);
    if (tau) {
      tau(q, qd, t, ts.tau);
      Q += ts.tau;
    }
  });
  // V = −Σ m_i g · p_W(com_i)
  sb.potential_energy([tree](const Eigen::Ref<const VectorXd>& q, double, CallableScratch* s) {
    TreeData& d = scratch_of(s).data;
    forward_kinematics(*tree, q, d);
    double V = 0.0;
    for (Index i = 0; i < tree->link_count(); ++i) {
      const Inertial& in = tree->link(i).inertial;
      V -= in.mass * tree->gravity().dot(world_point(d, i, in.com));
    }
    return V;
  });
  // P_ext = q'ᵀ (τ − D q') (the velocity terms do no work: Ṁ − 2C is skew)
  if (tau || damped) {
    sb.external_power([D, tau](const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double t, CallableScratch* s) {
      double P = -qd.dot(D.cwiseProduct(qd));
      if (tau) {
        TreeScratch& ts = scratch_of(s);
        tau(q, qd, t, ts.tau);
        P += qd.dot(ts.tau);
      }
      return P;
    });
  }
  // URDF's friction: a Coulomb torque (force) of that magnitude against the joint's rate,
  // regularized as the bodies' joint friction is (mb::JointFriction): C_j = −F q'_j / sqrt(q'_j² +
  // eps²), eps = kJointFrictionRegularization
  for (Index i = 0; i < tree->link_count(); ++i) {
    const double F = tree->link(i).joint.friction;
    if (tree->dofs(i) != 1 || !(F > 0.0)) continue;
    const Index j = tree->offset(i);
    sb.add(NonIdealForce(
        tree->link(i).joint.name + ".friction",
        [F, j](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>& qd, double,
               const IdealForceInfo&, Eigen::Ref<VectorXd> C) {
          const double w = qd[j], eps = kJointFrictionRegularization;
          C[j] = -F * w / std::sqrt(w * w + eps * eps);
        }));
  }
  // the floating joints' unit quaternions, as a rigid body's (multibody.hpp)
  for (Index i : tree->floating_links()) {
    sb.add(Constraint(tree->link(i).name + ".unit", ConstraintKind::kHolonomic, 1,
                      std::make_shared<mb::detail::UnitQuaternionModel>(tree->offset(i) + 3)));
  }
  return sb;
}

}  // namespace ukdyn::tree
