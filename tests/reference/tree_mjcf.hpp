// SPDX-License-Identifier: BSD-3-Clause
// A kinematic tree (multibody/tree.hpp) written as exact MJCF for MuJoCo 2.2.2, for the
// reference tests (tests/reference/test_tree_mujoco.cpp) and the benchmarks against MuJoCo
// (bench/bench_tree_step.cpp): every joint kind (a floating one as a freejoint), each inertia as
// diaginertia + quat from Eigen's eigensolver at full precision (MuJoCo's own URDF import
// re-diagonalizes with an iterative solver and agrees to 1e-8 only), the joints' damping, no
// joint limits and no geoms (nothing collides, no limit constraint acts).
#pragma once

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree::reference {

/// The MJCF text of `tree`; `option` is put inside <mujoco> before <worldbody> (e.g.
/// "<option integrator='RK4' timestep='0.001'/>").
inline std::string tree_mjcf(const Tree& tree, const std::string& option = "") {
  std::ostringstream out;
  out.precision(17);
  out << "<mujoco model='" << tree.name() << "'>\n<compiler angle='radian'/>\n"
      << option << "\n<worldbody>\n";
  std::vector<Index> open;  // the bodies still open, as tree link indices
  for (Index i = 0; i < tree.link_count(); ++i) {
    while (!open.empty() && open.back() != tree.parent(i)) {
      out << "</body>\n";
      open.pop_back();
    }
    const Link& l = tree.link(i);
    const Joint& j = l.joint;
    out << "<body name='" << l.name << "' pos='" << j.p_PJ.transpose() << "' quat='" << j.R_PJ.w()
        << ' ' << j.R_PJ.x() << ' ' << j.R_PJ.y() << ' ' << j.R_PJ.z() << "'>\n";
    open.push_back(i);
    if (l.inertial.mass > 0) {
      const Eigen::SelfAdjointEigenSolver<Matrix3d> eig(l.inertial.I_com);
      Matrix3d V = eig.eigenvectors();
      if (V.determinant() < 0) V.col(2) *= -1;
      const Eigen::Quaterniond qi(V);
      out << "<inertial pos='" << l.inertial.com.transpose() << "' quat='" << qi.w() << ' '
          << qi.x() << ' ' << qi.y() << ' ' << qi.z() << "' mass='" << l.inertial.mass
          << "' diaginertia='" << eig.eigenvalues().transpose() << "'/>\n";
    }
    if (j.kind == JointKind::kFloating) {
      out << "<freejoint name='" << j.name << "'/>\n";
    } else if (j.kind != JointKind::kFixed) {
      out << "<joint name='" << j.name << "' type='"
          << (j.kind == JointKind::kPrismatic ? "slide" : "hinge") << "' axis='"
          << j.axis.transpose() << "' damping='" << j.damping << "'/>\n";
    }
  }
  for (std::size_t k = 0; k < open.size(); ++k) out << "</body>\n";
  out << "</worldbody>\n</mujoco>\n";
  return out.str();
}

/// tree_mjcf written to a file in the temporary directory; returns its path.
inline std::string write_tree_mjcf(const Tree& tree, const std::string& option = "") {
  const auto path = std::filesystem::temp_directory_path() / ("ukdyn_tree_" + tree.name() + ".xml");
  std::ofstream(path) << tree_mjcf(tree, option);
  return path.string();
}

}  // namespace ukdyn::tree::reference
