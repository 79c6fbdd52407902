// SPDX-License-Identifier: BSD-3-Clause
// The lowest point of a thin disk towards a plane, shared by the bodies' and the trees' contact
// kinematics (multibody/contacts.cpp, multibody/tree/contact_kinematics.cpp).
#pragma once

#include <Eigen/Core>

namespace ukdyn::mb::detail {

/// The offset ρ from a disk's centre to its point nearest a plane, and its rate ρ': with the
/// plane's unit normal n (rate n'), the disk's unit axis a (rate a') and radius r,
///   m = n − (n·a) a,   ρ = −r m/|m|,   ρ' = −r (m' − (e·m') e)/|m|,  e = m/|m|,
/// m' = n' − (n·a)' a − (n·a) a'. Undefined where the disk lies flat (|m| = 0: the callers refuse
/// it). Cost O(1).
inline void disk_lowest_point(const Eigen::Vector3d& n, const Eigen::Vector3d& n1,
                              const Eigen::Vector3d& a, const Eigen::Vector3d& a1, double r,
                              Eigen::Vector3d& rho, Eigen::Vector3d& rho1) {
  const double s = n.dot(a), s1 = n1.dot(a) + n.dot(a1);
  const Eigen::Vector3d m = n - s * a, m1 = n1 - s1 * a - s * a1;
  const double len = m.norm();
  const Eigen::Vector3d e = m / len;
  rho = -r * e;
  rho1 = -r * (m1 - e.dot(m1) * e) / len;
}

}  // namespace ukdyn::mb::detail
