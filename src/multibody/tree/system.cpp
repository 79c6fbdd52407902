// SPDX-License-Identifier: BSD-3-Clause
// A tree as ukdyn's unconstrained system: M from the CRBA, Q = τ − D q' − h from the RNEA.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "multibody/internal.hpp"
#include "multibody/tree/kinematics_cache.hpp"
#include "multibody/tree/mimic.hpp"
#include "multibody/tree/spatial.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree {

namespace {

// the per-workspace buffers of the tree's callables
struct TreeScratch final : CallableScratch {
  explicit TreeScratch(std::shared_ptr<const Tree> t)
      : tree(std::move(t)),
        kinematics(*tree),
        h(tree->coordinate_count()),
        tau(tree->coordinate_count()),
        M(tree->coordinate_count(), tree->coordinate_count()),
        Q(tree->coordinate_count()) {}
  std::shared_ptr<const Tree> tree;  // the system's tree (for shared_kinematics)
  // the forward kinematics at the last q: M, Q and V of one evaluation (and the frame
  // constraints evaluated with this workspace, detail::shared_kinematics) share it
  detail::KinematicsCache kinematics;
  VectorXd h;    // (n) bias forces, filled by Q
  VectorXd tau;  // (n) the input τ, filled by Q and P_ext
  // the last M and Q at the kinematics of version `version` (an evaluation that shares this
  // scratch at the same state, a controller's model evaluated with its plant, copies them),
  // filled by M and Q
  MatrixXd M;  // (n × n) M(q)
  VectorXd Q;  // (n) Q(q, q', t_Q), q' = kinematics.qd_v (the RNEA's, which marks it)
  double t_Q = 0.0;
  std::uint64_t version = 0;  // kinematics.version of M and Q
  bool M_valid = false, Q_valid = false;
  // M is kept only once two callers (two workspaces sharing this scratch: a controller's model
  // and its plant) have asked for it, told apart by their output buffers: a workspace of its own
  // asks at each state once and would only pay for the copy (n² doubles, 3 % of the humanoid's
  // evaluation)
  const double* M_out = nullptr;  // the output buffer of the last M
  bool keep_M = false;
};

TreeScratch& scratch_of(CallableScratch* s) { return *static_cast<TreeScratch*>(s); }

// forward kinematics at q into the scratch's data, once per state: M and Q of one evaluation
// (and V of a sample, and the frame constraints sharing the scratch) share it. The same q, bit
// for bit, gives the same kinematics, so the results are those of running it in each callable.
// M and Q kept are dropped when the kinematics changed (here or by a constraint sharing them).
void kinematics_at(const Tree& tree, const Eigen::Ref<const VectorXd>& q, TreeScratch& ts) {
  ts.kinematics.at(tree, q);
  if (ts.version != ts.kinematics.version) {
    ts.M_valid = ts.Q_valid = false;
    ts.version = ts.kinematics.version;
  }
}

// each coordinate's parent in the tree of coordinates: the one before it in its joint, else the
// last coordinate of the nearest ancestor link that moves (-1 at a root)
std::vector<Index> coordinate_parents(const Tree& tree) {
  std::vector<Index> parent(std::size_t(tree.coordinate_count()), -1);
  for (Index i = 0; i < tree.link_count(); ++i) {
    const Index o = tree.offset(i);
    if (tree.dofs(i) == 0) continue;
    Index a = tree.parent(i);
    while (a >= 0 && tree.dofs(a) == 0) a = tree.parent(a);
    parent[std::size_t(o)] = a < 0 ? -1 : tree.offset(a) + tree.dofs(a) - 1;
    for (Index k = 1; k < tree.dofs(i); ++k) parent[std::size_t(o + k)] = o + k - 1;
  }
  return parent;
}

}  // namespace

System make_system(const Tree& tree, JointTorqueFn tau, FrictionRegularization friction) {
  return system_builder(tree, std::move(tau), friction).build();
}

SystemBuilder system_builder(const Tree& tree_in, JointTorqueFn tau,
                             FrictionRegularization friction) {
  for (const double eps : {friction.angular, friction.linear}) {
    if (!(std::isfinite(eps) && eps > 0.0)) {
      throw std::invalid_argument(
          "ukdyn::tree::system_builder: the joint friction's regularization must be a finite "
          "number > 0, got " +
          format_number(eps) + " (FrictionRegularization: angular, linear)");
    }
  }
  const auto tree = std::make_shared<const Tree>(tree_in);
  const Index n = tree->coordinate_count();
  // D, the joints' viscous damping (n)
  VectorXd D = VectorXd::Zero(n);
  for (Index i = 0; i < tree->link_count(); ++i) {
    if (tree->dofs(i) == 1) D[tree->offset(i)] = tree->link(i).joint.damping;
  }
  const bool damped = D.any();
  // each floating link's quaternion block of M, 4 E(u)ᵀ J E(u), is singular along u; it is
  // completed with c u uᵀ and Q with c u b of its unit-norm row (u·u'' = b = −u'·u'), c = tr/3 of
  // the block at the neutral pose: M + c AᵀA, Q + c Aᵀ b has the same constrained q'' and Qc as
  // M, Q (Qc ∈ range Aᵀ; docs/robots.md), and the engine factorizes a regular M once per
  // evaluation instead of completing a singular one
  struct Completion {
    Index offset;  // the quaternion's first coordinate
    double c;      // the completion's scale (kg·m²)
  };
  std::vector<Completion> completions;
  if (!tree->floating_links().empty()) {
    TreeData d0(*tree);
    MatrixXd M0(n, n);
    mass_matrix(*tree, tree->neutral(), d0, M0);
    for (Index i : tree->floating_links()) {
      const Index o = tree->offset(i) + 3;
      const double c = M0.block<4, 4>(o, o).trace() / 3.0;
      completions.push_back({o, c > 0.0 ? c : 1.0});
    }
  }
  SystemBuilder sb(tree->coordinate_names());
  // M's sparsity follows the tree (M_ij = 0 unless the link of i is an ancestor of that of j
  // or the other way, the completion c u uᵀ inside one link's block): the engine factorizes it
  // along the branches (SystemBuilder::mass_tree) when it branches
  // (a single chain, an arm's, has a dense M and gains nothing: the dense Cholesky's kernels are
  // then the faster, 3 % on the 7-DOF arm's evaluation)
  std::vector<Index> parent = coordinate_parents(*tree);
  bool chain = true;
  for (std::size_t k = 0; k < parent.size(); ++k) chain = chain && parent[k] == Index(k) - 1;
  if (!chain) sb.mass_tree(std::move(parent));
  sb.scratch(
      [tree]() -> std::unique_ptr<CallableScratch> { return std::make_unique<TreeScratch>(tree); });
  sb.mass_matrix([tree, completions](const Eigen::Ref<const VectorXd>& q, double,
                                     CallableScratch* s, Eigen::Ref<MatrixXd> M) {
    TreeScratch& ts = scratch_of(s);
    kinematics_at(*tree, q, ts);
    if (M.data() != ts.M_out) {
      ts.keep_M = ts.keep_M || ts.M_out != nullptr;
      ts.M_out = M.data();
    }
    // (the M of this q, bit for bit, is the one kept)
    if (ts.M_valid) {
      M = ts.M;
      return;
    }
    detail::mass_matrix_from_kinematics(*tree, ts.kinematics.data, M);
    // M_uu += c u uᵀ
    for (const Completion& k : completions) {
      const Eigen::Vector4d u = q.segment<4>(k.offset);
      M.block<4, 4>(k.offset, k.offset).noalias() += k.c * u * u.transpose();
    }
    if (ts.keep_M) {
      ts.M = M;
      ts.M_valid = true;
    }
  });
  // Q = τ − D q' − h(q, q') (+ c u b per floating link)
  sb.forces([tree, D, tau, completions](const Eigen::Ref<const VectorXd>& q,
                                        const Eigen::Ref<const VectorXd>& qd, double t,
                                        CallableScratch* s, Eigen::Ref<VectorXd> Q) {
    TreeScratch& ts = scratch_of(s);
    kinematics_at(*tree, q, ts);
    // (the Q of this q, q' and t, bit for bit, is the one kept — only without an input τ: a
    // user's τ may depend on more than q, q' and t, e.g. a sweep's parameters or its own state)
    if (!tau && ts.Q_valid && t == ts.t_Q &&
        std::memcmp(qd.data(), ts.kinematics.qd_v.data(),
                    sizeof(double) * std::size_t(qd.size())) == 0) {
      Q = ts.Q;
      return;
    }
    detail::rnea_from_kinematics(*tree, qd, nullptr, ts.kinematics.data, ts.h,
                                 ts.kinematics.keep_c ? &ts.kinematics.c : nullptr);
    // data.v and c are the velocities and velocity products at q' (a frame requirement's J' q'
    // pass sharing these kinematics adds them), and qd_v the q' of the Q kept once complete
    ts.Q_valid = false;
    ts.kinematics.mark_velocities(qd);
    Q = -ts.h - D.cwiseProduct(qd);
    if (tau) {
      tau(q, qd, t, ts.tau);
      Q += ts.tau;
    }
    // Q_u −= c u (u'·u')
    for (const Completion& k : completions) {
      Q.segment<4>(k.offset) -=
          (k.c * qd.segment<4>(k.offset).squaredNorm()) * q.segment<4>(k.offset);
    }
    ts.Q = Q;
    ts.t_Q = t;
    ts.Q_valid = true;
  });
  // V = −Σ m_i g · p_W(com_i)
  sb.potential_energy([tree](const Eigen::Ref<const VectorXd>& q, double, CallableScratch* s) {
    TreeScratch& ts = scratch_of(s);
    kinematics_at(*tree, q, ts);
    const TreeData& d = ts.kinematics.data;
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
  // eps²), eps = friction.linear on a prismatic joint, friction.angular on a rotating one
  for (Index i = 0; i < tree->link_count(); ++i) {
    const double F = tree->link(i).joint.friction;
    if (tree->dofs(i) != 1 || !(F > 0.0)) continue;
    const Index j = tree->offset(i);
    const double eps =
        tree->link(i).joint.kind == JointKind::kPrismatic ? friction.linear : friction.angular;
    sb.add(NonIdealForce(
        tree->link(i).joint.name + ".friction",
        [F, j, eps](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>& qd, double,
                    const IdealForceInfo&, Eigen::Ref<VectorXd> C) {
          const double w = qd[j];
          C[j] = -F * w / std::sqrt(w * w + eps * eps);
        }));
  }
  // the floating joints' unit quaternions, as a rigid body's (multibody.hpp)
  for (Index i : tree->floating_links()) {
    sb.add(Constraint(tree->link(i).name + ".unit", ConstraintKind::kHolonomic, 1,
                      std::make_shared<mb::detail::UnitQuaternionModel>(tree->offset(i) + 3)));
  }
  // URDF's mimics: q_j = m q_ref + o, one row each
  detail::add_mimic_constraints(*tree, sb);
  return sb;
}

bool detail::same_kinematics(const Tree& a, const Tree& b) {
  if (&a == &b) return true;
  if (a.link_count() != b.link_count() || a.coordinate_count() != b.coordinate_count()) {
    return false;
  }
  for (Index i = 0; i < a.link_count(); ++i) {
    const Joint &ja = a.link(i).joint, &jb = b.link(i).joint;
    if (a.parent(i) != b.parent(i) || a.offset(i) != b.offset(i) || a.dofs(i) != b.dofs(i) ||
        ja.kind != jb.kind || ja.p_PJ != jb.p_PJ || ja.axis != jb.axis ||
        a.joint_rotation(i) != b.joint_rotation(i)) {
      return false;
    }
  }
  return true;
}

detail::KinematicsCache* detail::shared_kinematics(CallableScratch* shared, const Tree& tree) {
  auto* ts = dynamic_cast<TreeScratch*>(shared);
  if (ts == nullptr || !same_kinematics(*ts->tree, tree)) return nullptr;
  return &ts->kinematics;
}

}  // namespace ukdyn::tree
