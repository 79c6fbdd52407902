// SPDX-License-Identifier: BSD-3-Clause
// The fictitious-inertia formulation the quaternion bodies used before the singular mass matrix
// (Udwadia & Schutte 2010): every 4 × 4 quaternion block M_u gets + 4 J0 u uᵀ and Q gets
// − 4 J0 |u'|² u, with the system's own M, Q and constraints otherwise. It has a regular
// (positive definite) M and the same motion: an independent route to q'' for tests, and the
// "before" of bench/bench_singular_mass.cpp. The returned system calls into `sys`, which must
// outlive it.
#pragma once

#include <vector>

#include "ukdyn/core/system.hpp"

namespace ukdyn::test {

inline System with_fictitious_inertia(const System& sys, double J0) {
  // the quaternions: the state-dependent 4 × 4 blocks (multibody/multibody.hpp builds no other)
  std::vector<Index> quats;
  for (const MassBlock& b : sys.mass_blocks()) {
    if (!b.constant() && b.size == 4) quats.push_back(b.offset);
  }
  SystemBuilder sb(sys.coordinate_names());
  for (const MassBlock& b : sys.mass_blocks()) {
    if (b.constant()) {
      sb.mass_block(b.offset, b.value);
    } else if (b.size == 4) {
      const Index o = b.offset;
      sb.mass_block(o, 4,
                    [fn = b.fn, o, J0](const Eigen::Ref<const VectorXd>& q, double t,
                                       Eigen::Ref<MatrixXd> M) {
                      fn(q, t, M);
                      const Eigen::Vector4d u = q.segment<4>(o);
                      M += 4.0 * J0 * u * u.transpose();
                    });
    } else {
      sb.mass_block(b.offset, b.size, b.fn);
    }
  }
  sb.forces([&sys, quats, J0](const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t,
                              Eigen::Ref<VectorXd> Q) {
    sys.forces(q, qd, t, Q);
    for (Index o : quats) {
      Q.segment<4>(o) -= 4.0 * J0 * qd.segment<4>(o).squaredNorm() * q.segment<4>(o);
    }
  });
  for (Index k = 0; k < sys.constraint_count(); ++k) sb.add(sys.constraint(k));
  return sb.build();
}

}  // namespace ukdyn::test
