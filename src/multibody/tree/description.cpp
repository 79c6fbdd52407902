// SPDX-License-Identifier: BSD-3-Clause
// The description of a kinematic tree: checks, link order, coordinate offsets, spatial inertias.
#include <cmath>
#include <stdexcept>
#include <unordered_map>

#include <Eigen/Eigenvalues>

#include "multibody/tree/mimic.hpp"
#include "multibody/tree/spatial.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree {

const char* joint_kind_name(JointKind k) {
  switch (k) {
    case JointKind::kFixed:
      return "fixed";
    case JointKind::kRevolute:
      return "revolute";
    case JointKind::kContinuous:
      return "continuous";
    case JointKind::kPrismatic:
      return "prismatic";
    case JointKind::kFloating:
      return "floating";
  }
  return "?";
}

int joint_coordinates(JointKind k) {
  switch (k) {
    case JointKind::kFixed:
      return 0;
    case JointKind::kFloating:
      return 7;
    default:
      return 1;
  }
}

namespace {

const std::string kWho = "ukdyn::tree::Tree: ";

void check_link(const Link& l) {
  const std::string where = kWho + "link '" + l.name + "' (joint '" + l.joint.name + "'): ";
  const Joint& j = l.joint;
  if (j.kind != JointKind::kFixed && j.kind != JointKind::kFloating) {
    if (!j.axis.allFinite() || j.axis.norm() < 1e-12) {
      throw std::invalid_argument(where + "the joint axis is zero or not finite");
    }
  }
  if (!j.p_PJ.allFinite() || !j.R_PJ.coeffs().allFinite()) {
    throw std::invalid_argument(where + "the joint origin is not finite");
  }
  if (!(j.friction >= 0.0)) {
    throw std::invalid_argument(where + "friction must be >= 0, got " + format_number(j.friction));
  }
  if (!(j.damping >= 0.0)) {
    throw std::invalid_argument(where + "damping must be >= 0, got " + format_number(j.damping));
  }
  const Inertial& in = l.inertial;
  if (!(in.mass >= 0.0) || !std::isfinite(in.mass)) {
    throw std::invalid_argument(where + "mass must be finite and >= 0, got " +
                                format_number(in.mass));
  }
  if (!in.com.allFinite() || !in.I_com.allFinite()) {
    throw std::invalid_argument(where + "the inertial is not finite");
  }
  const double scale = std::max(1.0, in.I_com.cwiseAbs().maxCoeff());
  if ((in.I_com - in.I_com.transpose()).cwiseAbs().maxCoeff() > 1e-12 * scale) {
    throw std::invalid_argument(where + "the inertia tensor is not symmetric");
  }
  const Eigen::SelfAdjointEigenSolver<Matrix3d> eig(in.I_com);
  const Vector3d e = eig.eigenvalues();  // ascending
  // a rigid body's principal moments are >= 0 and obey the triangle inequality
  if (e[0] < -1e-12 * scale || e[0] + e[1] < e[2] * (1 - 1e-9) - 1e-12 * scale) {
    throw std::invalid_argument(where +
                                "the inertia tensor is not positive semi-definite or violates "
                                "the triangle inequality (principal moments " +
                                format_number(e[0]) + ", " + format_number(e[1]) + ", " +
                                format_number(e[2]) + ")");
  }
}

}  // namespace

Tree::Tree(std::string name, std::vector<Link> links, Vector3d gravity)
    : name_(std::move(name)), gravity_(gravity) {
  if (!gravity_.allFinite()) throw std::invalid_argument(kWho + "gravity is not finite");
  // names unique, parents known
  std::unordered_map<std::string, std::size_t> by_name, joints;
  for (std::size_t i = 0; i < links.size(); ++i) {
    const Link& l = links[i];
    if (l.name.empty()) throw std::invalid_argument(kWho + "a link has an empty name");
    if (l.joint.name.empty()) {
      throw std::invalid_argument(kWho + "link '" + l.name + "': its joint has an empty name");
    }
    if (!by_name.emplace(l.name, i).second) {
      throw std::invalid_argument(kWho + "two links are called '" + l.name + "'");
    }
    if (!joints.emplace(l.joint.name, i).second) {
      throw std::invalid_argument(kWho + "two joints are called '" + l.joint.name + "'");
    }
    check_link(l);
    if (l.joint.kind == JointKind::kFloating && !l.parent.empty()) {
      throw std::invalid_argument(kWho + "joint '" + l.joint.name +
                                  "': a floating joint must attach a root link to the world, "
                                  "not to '" +
                                  l.parent + "'");
    }
  }
  for (const Link& l : links) {
    if (l.joint.kind == JointKind::kFloating &&
        (l.joint.p_PJ.norm() != 0.0 ||
         !l.joint.R_PJ.coeffs().isApprox(Eigen::Quaterniond::Identity().coeffs(), 0.0))) {
      throw std::invalid_argument(kWho + "joint '" + l.joint.name +
                                  "': a floating joint's origin must be the identity (its "
                                  "coordinates are the link's pose in the world)");
    }
    if (!l.parent.empty() && !by_name.count(l.parent)) {
      throw std::invalid_argument(kWho + "link '" + l.name + "': unknown parent link '" + l.parent +
                                  "'");
    }
  }
  // order: depth first from the roots, parents before children; a cycle leaves links unplaced
  std::vector<std::vector<std::size_t>> children(links.size());
  std::vector<std::size_t> order, stack;
  for (std::size_t i = links.size(); i-- > 0;) {
    if (links[i].parent.empty()) {
      stack.push_back(i);
    } else {
      children[by_name[links[i].parent]].push_back(i);
    }
  }
  while (!stack.empty()) {
    const std::size_t i = stack.back();
    stack.pop_back();
    order.push_back(i);
    for (auto c = children[i].rbegin(); c != children[i].rend(); ++c) stack.push_back(*c);
  }
  if (order.size() != links.size()) {
    std::vector<bool> placed(links.size(), false);
    for (std::size_t i : order) placed[i] = true;
    for (std::size_t i = 0; i < links.size(); ++i) {
      if (!placed[i]) {
        throw std::invalid_argument(kWho + "not a tree: link '" + links[i].name +
                                    "' is on a cycle of parents (no path to the world)");
      }
    }
  }
  std::vector<Index> new_index(links.size());
  for (std::size_t k = 0; k < order.size(); ++k) new_index[order[k]] = Index(k);
  for (std::size_t k = 0; k < order.size(); ++k) {
    Link l = std::move(links[order[k]]);
    if (l.joint.kind != JointKind::kFixed && l.joint.kind != JointKind::kFloating) {
      l.joint.axis.normalize();
    }
    l.joint.R_PJ.normalize();
    parent_.push_back(l.parent.empty() ? -1 : new_index[by_name[l.parent]]);
    offset_.push_back(n_);
    if (l.joint.kind == JointKind::kFloating) {
      floating_.push_back(Index(k));
      for (const char* s : {".x", ".y", ".z", ".u0", ".u1", ".u2", ".u3"}) {
        names_.push_back(l.name + s);
      }
    } else if (l.joint.kind != JointKind::kFixed) {
      names_.push_back(l.joint.name);
    }
    n_ += joint_coordinates(l.joint.kind);
    dofs_.push_back(joint_coordinates(l.joint.kind));
    R_PJ_.push_back(l.joint.R_PJ.toRotationMatrix());
    inertia_.push_back(detail::spatial_inertia(l.inertial.mass, l.inertial.com, l.inertial.I_com));
    links_.push_back(std::move(l));
  }
  if (n_ == 0) throw std::invalid_argument(kWho + "'" + name_ + "' has no moving joint");
  // every moving joint must carry mass (and, for a rotation, inertia) in its subtree: the
  // subtree masses in one reverse pass (children follow their parents), O(links)
  // (the subtree's mass only: a subtree with mass can still leave M singular, a point mass on a
  // revolute axis; the engines then report M not positive definite)
  subtree_mass_.assign(links_.size(), 0.0);
  for (Index i = link_count(); i-- > 0;) {
    subtree_mass_[std::size_t(i)] += links_[std::size_t(i)].inertial.mass;
    if (parent_[std::size_t(i)] >= 0) {
      subtree_mass_[std::size_t(parent_[std::size_t(i)])] += subtree_mass_[std::size_t(i)];
    }
  }
  for (Index i = link_count(); i-- > 0;) {
    const JointKind k = links_[std::size_t(i)].joint.kind;
    if (k != JointKind::kFixed && !(subtree_mass_[std::size_t(i)] > 0.0)) {
      throw std::invalid_argument(kWho + "joint '" + links_[std::size_t(i)].joint.name +
                                  "' moves no mass (link '" + links_[std::size_t(i)].name +
                                  "' and its subtree are massless): M would be singular");
    }
  }
  mimics_ = detail::mimic_relations(*this);
}

Index Tree::link_index(std::string_view name) const {
  for (std::size_t i = 0; i < links_.size(); ++i) {
    if (links_[i].name == name) return Index(i);
  }
  throw std::invalid_argument("ukdyn::tree::Tree::link_index: no link '" + std::string(name) +
                              "' in '" + name_ + "'");
}

std::vector<bool> Tree::angle_coordinates() const {
  std::vector<bool> angles(std::size_t(n_), false);
  for (Index i = 0; i < link_count(); ++i) {
    const JointKind kind = link(i).joint.kind;
    for (int k = 0; k < dofs(i); ++k) {
      // (a floating base's quaternion components are weighed as lengths)
      angles[std::size_t(offset(i) + k)] =
          kind == JointKind::kRevolute || kind == JointKind::kContinuous;
    }
  }
  return angles;
}

VectorXd Tree::neutral() const {
  VectorXd q = VectorXd::Zero(n_);
  for (Index i : floating_) q[offset(i) + 3] = 1.0;
  detail::meet_mimics(*this, q);
  return q;
}

TreeData::TreeData(const Tree& tree)
    : R_WL(std::size_t(tree.link_count())),
      p_WL(std::size_t(tree.link_count())),
      E(std::size_t(tree.link_count())),
      r(std::size_t(tree.link_count())),
      S(std::size_t(tree.link_count())),
      v(std::size_t(tree.link_count())),
      a(std::size_t(tree.link_count())),
      f(std::size_t(tree.link_count())),
      Ic(std::size_t(tree.link_count())),
      tree_size(tree.link_count()) {
  for (Index i = 0; i < tree.link_count(); ++i) {
    S[std::size_t(i)].setZero(6, tree.dofs(i));
    dofs.push_back(tree.dofs(i));
  }
}

}  // namespace ukdyn::tree
