// SPDX-License-Identifier: BSD-3-Clause
// The forward kinematics of a tree kept at the last q, per workspace: a tree system's M, Q and V
// share one, and so do the frame constraints and requirements on the same tree evaluated with
// that workspace (a closure of the system itself, or a controller's requirements evaluated with
// its model's workspace): one forward kinematics per state instead of one per user.
#pragma once

#include <cstdint>
#include <cstring>

#include "ukdyn/core/system.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree::detail {

/// Forward kinematics at the last q. The users of `data` may also write its scratch fields (v,
/// a, f, Ic: each pass that reads them writes them first); only the kinematics (R_WL, p_WL, E,
/// r, S) are kept between users. A user that keeps results of the kinematics (M, Q, Jacobians)
/// remembers `version` and drops them when it changed.
struct KinematicsCache {
  /// Sizes the buffers for `tree`. Allocates (once).
  explicit KinematicsCache(const Tree& tree)
      : data(tree),
        q(tree.coordinate_count()),
        qd_v(tree.coordinate_count()),
        c(std::size_t(tree.link_count()), Vector6d::Zero()) {}

  TreeData data;              ///< the passes' links; the kinematics are those of q when valid
  VectorXd q;                 ///< (n) the q of data's kinematics
  bool valid = false;         ///< data holds the kinematics of q
  std::uint64_t version = 0;  ///< incremented by every forward kinematics run here
  /// The link velocities data.v: every link's, at the kinematics of v_version (0: none) and
  /// q' = qd_v, as an RNEA leaves them (mark_velocities). A pass that writes data.v at another
  /// q' clears them (clear_velocities); one at the same q' writes the same bits.
  VectorXd qd_v;                ///< (n) the q' of data.v
  std::uint64_t v_version = 0;  ///< the version of data.v's kinematics; 0: data.v unknown
  /// (links) the velocity products c_i + v_i × S_i q'_i the same RNEA left (its argument c):
  /// valid with data.v when c_valid, so a J' q' pass at this state adds them instead of
  /// recomputing them
  TreeData::Aligned<Vector6d> c;
  bool keep_c = false;   ///< a frame constraint or requirement shares this cache: the RNEA fills c
  bool c_valid = false;  ///< c is the RNEA's of data.v (set by mark_velocities from keep_c)

  /// Whether data.v holds every link's velocity at the current kinematics and q' = qd (bit for
  /// bit). Cost O(n).
  bool velocities_at(const Eigen::Ref<const VectorXd>& qd) const {
    return valid && v_version == version && qd.size() == qd_v.size() &&
           std::memcmp(qd.data(), qd_v.data(), sizeof(double) * std::size_t(qd.size())) == 0;
  }
  /// Records that a pass over every link (the RNEA) just wrote data.v (and c when keep_c) at
  /// the current kinematics and q' = qd. Cost O(n).
  void mark_velocities(const Eigen::Ref<const VectorXd>& qd) {
    qd_v = qd;
    v_version = version;
    c_valid = keep_c;
  }
  /// Records that data.v was written at another q' (or on some links only). Cost O(1).
  void clear_velocities() { v_version = 0; }

  /// forward_kinematics(tree, q_in, data) unless data already holds it (q_in equal to q bit for
  /// bit, which gives the same kinematics bit for bit). Cost O(n) when kept, O(links) otherwise.
  /// @throws std::invalid_argument from forward_kinematics on a q of the wrong size.
  void at(const Tree& tree, const Eigen::Ref<const VectorXd>& q_in) {
    if (valid && q_in.size() == q.size() &&
        std::memcmp(q_in.data(), q.data(), sizeof(double) * std::size_t(q.size())) == 0) {
      return;
    }
    valid = false;  // (forward_kinematics throws on a q of the wrong size)
    ++version;
    forward_kinematics(tree, q_in, data);
    q = q_in;
    valid = true;
  }
};

/// True when the forward kinematics, frame Jacobians and bias accelerations of `a` and `b` are
/// the same functions of q: the same links, parents, joints (kind, origin, axis). Masses may
/// differ (a controller's nominal model and its requirements' tree). Cost O(links).
bool same_kinematics(const Tree& a, const Tree& b);

/// The kinematics cache of a tree System's callables' scratch (`shared`, from
/// System::make_scratch of make_system(t)) when t has the same kinematics as `tree`; null for
/// any other scratch or none. Cost O(links).
KinematicsCache* shared_kinematics(CallableScratch* shared, const Tree& tree);

}  // namespace ukdyn::tree::detail
