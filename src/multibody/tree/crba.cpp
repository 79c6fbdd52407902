// SPDX-License-Identifier: BSD-3-Clause
// M(q) of a tree by the composite-rigid-body algorithm (Featherstone 2008, algorithm 6.2).
#include <type_traits>

#include "multibody/tree/spatial.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree {

void mass_matrix(const Tree& tree, const Eigen::Ref<const VectorXd>& q, TreeData& d,
                 Eigen::Ref<MatrixXd> M) {
  const char* who = "ukdyn::tree::mass_matrix";
  detail::check_sizes(who, tree, d, q.size());
  detail::check_sizes(who, tree, d, M.rows());
  detail::check_sizes(who, tree, d, M.cols());
  forward_kinematics(tree, q, d);
  detail::mass_matrix_from_kinematics(tree, d, M);
}

void detail::mass_matrix_from_kinematics(const Tree& tree, TreeData& d, Eigen::Ref<MatrixXd> M) {
  // composite inertias, leaves first: Ic_λ += X_iᵀ Ic_i X_i
  for (Index i = 0; i < tree.link_count(); ++i) d.Ic[std::size_t(i)] = tree.spatial_inertia(i);
  for (Index i = tree.link_count(); i-- > 0;) {
    const Index p = tree.parent(i);
    if (p < 0) continue;
    const std::size_t k = std::size_t(i);
    d.Ic[std::size_t(p)] += detail::inertia_to_parent(d.E[k], d.r[k], d.Ic[k]);
  }
  // M_ii = S_iᵀ Ic_i S_i; up the branch M_ij = (X…ᵀ Ic_i S_i)ᵀ S_j; other branches stay zero
  M.setZero();
  // F = Ic_i S_i carried up the branch (a Vector6d for a 1-DOF joint, no dynamic sizes)
  const auto branch = [&](Index i, auto& F) {
    const Index oi = tree.offset(i);
    const int ni = tree.dofs(i);
    constexpr bool one = std::is_same_v<std::decay_t<decltype(F)>, Vector6d>;
    if constexpr (one) {
      M(oi, oi) = d.S[std::size_t(i)].col(0).dot(F);
    } else {
      M.block(oi, oi, ni, ni).noalias() = d.S[std::size_t(i)].transpose() * F;
    }
    for (Index j = i; tree.parent(j) >= 0;) {
      detail::forces_to_parent(d.E[std::size_t(j)], d.r[std::size_t(j)], F);
      j = tree.parent(j);
      const int nj = tree.dofs(j);
      if (nj == 0) continue;
      const Index oj = tree.offset(j);
      if constexpr (one) {
        if (nj == 1) {
          M(oi, oj) = M(oj, oi) = F.dot(d.S[std::size_t(j)].col(0));
          continue;
        }
        if (nj == 7) {
          // a floating base: a fixed-size 1 × 7 row (every link of a floating robot gets here)
          const Eigen::Matrix<double, 1, 7> row =
              F.transpose() * detail::floating_subspace(d.S[std::size_t(j)]);
          M.block<1, 7>(oi, oj) = row;
          M.block<7, 1>(oj, oi) = row.transpose();
          continue;
        }
      }
      M.block(oi, oj, ni, nj).noalias() = F.transpose() * d.S[std::size_t(j)];
      M.block(oj, oi, nj, ni) = M.block(oi, oj, ni, nj).transpose();
    }
  };
  for (Index i = 0; i < tree.link_count(); ++i) {
    const int ni = tree.dofs(i);
    if (ni == 1) {
      // (S_i = e_k: F is column k of Ic_i, the same bits as the product)
      const int k = detail::subspace_pick(tree, i);
      Vector6d F = k >= 0 ? Vector6d(d.Ic[std::size_t(i)].col(k))
                          : Vector6d(d.Ic[std::size_t(i)] * d.S[std::size_t(i)].col(0));
      branch(i, F);
    } else if (ni > 1) {
      TreeData::S6 F = d.Ic[std::size_t(i)] * d.S[std::size_t(i)];
      branch(i, F);
    }
  }
}

}  // namespace ukdyn::tree
