// SPDX-License-Identifier: BSD-3-Clause
// URDF's <mimic joint="ref" multiplier="m" offset="o"/> on joint j: the holonomic constraint
// q_j − m q_ref − o = 0 between two joint coordinates, named "<j>.mimic". Its multiplier λ is
// the coupling torque (force) on j, and −m λ acts on ref: a gear (m the ratio) or a linkage
// that URDF writes as a tree.
#include "multibody/tree/mimic.hpp"

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "ukdyn/core/format.hpp"

namespace ukdyn::tree::detail {

namespace {

// phi = q_j − m q_ref − o on columns {j, ref} (sorted): A = [1, −m] (or [−m, 1]), b = 0
class MimicModel final : public ConstraintModel {
 public:
  explicit MimicModel(const Mimic& m) : mimic_(m), first_is_j_(m.coordinate < m.reference) {
    cols_ = first_is_j_ ? std::vector<Index>{m.coordinate, m.reference}
                        : std::vector<Index>{m.reference, m.coordinate};
  }
  const std::vector<Index>& columns() const override { return cols_; }
  void acceleration_form_local(const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&,
                               double, ConstraintScratch*, Eigen::Ref<MatrixXd> A,
                               Eigen::Ref<VectorXd> b) const override {
    A(0, first_is_j_ ? 0 : 1) = 1.0;
    A(0, first_is_j_ ? 1 : 0) = -mimic_.multiplier;
    b[0] = 0.0;
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                 ConstraintScratch*, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    position[0] = q[mimic_.coordinate] - mimic_.multiplier * q[mimic_.reference] - mimic_.offset;
    velocity[0] = qd[mimic_.coordinate] - mimic_.multiplier * qd[mimic_.reference];
  }

 private:
  Mimic mimic_;
  bool first_is_j_;
  std::vector<Index> cols_;
};

}  // namespace

std::vector<Mimic> mimic_relations(const Tree& tree) {
  const std::string who = "ukdyn::tree::Tree: ";
  std::unordered_map<std::string, Index> by_joint;  // joint name → link
  for (Index i = 0; i < tree.link_count(); ++i) by_joint.emplace(tree.link(i).joint.name, i);
  std::vector<Mimic> out;
  std::vector<Index> follows(std::size_t(tree.link_count()), -1);  // link → the link it mimics
  for (Index i = 0; i < tree.link_count(); ++i) {
    const Joint& j = tree.link(i).joint;
    if (j.mimic.empty()) continue;
    const std::string where = who + "joint '" + j.name + "' mimics '" + j.mimic + "': ";
    if (j.mimic == j.name) throw std::invalid_argument(where + "a joint cannot mimic itself");
    const auto it = by_joint.find(j.mimic);
    if (it == by_joint.end()) {
      throw std::invalid_argument(where + "no joint '" + j.mimic + "' in '" + tree.name() + "'");
    }
    const Index r = it->second;
    for (const Index k : {i, r}) {
      if (tree.dofs(k) != 1) {
        throw std::invalid_argument(
            where + "joint '" + tree.link(k).joint.name + "' is " +
            joint_kind_name(tree.link(k).joint.kind) +
            " (a mimic relates two joints of one coordinate: revolute, continuous, prismatic)");
      }
    }
    if (!std::isfinite(j.mimic_multiplier) || !std::isfinite(j.mimic_offset)) {
      throw std::invalid_argument(where + "its multiplier and offset must be finite, got " +
                                  format_number(j.mimic_multiplier) + " and " +
                                  format_number(j.mimic_offset));
    }
    follows[std::size_t(i)] = r;
    out.push_back({i, tree.offset(i), tree.offset(r), j.mimic_multiplier, j.mimic_offset});
  }
  // no cycle of mimics: each walk along `follows` ends at a joint that mimics none (colours:
  // 0 unseen, 1 on the current walk, 2 known to end), O(links) in all
  std::vector<char> colour(follows.size(), 0);
  for (std::size_t s = 0; s < follows.size(); ++s) {
    std::size_t k = s;
    while (follows[k] >= 0 && colour[k] == 0) {
      colour[k] = 1;
      k = std::size_t(follows[k]);
    }
    if (follows[k] >= 0 && colour[k] == 1) {
      // k is on a cycle: name its joints
      std::string names = "'" + tree.link(Index(k)).joint.name + "'";
      for (std::size_t c = std::size_t(follows[k]); c != k; c = std::size_t(follows[c])) {
        names += " → '" + tree.link(Index(c)).joint.name + "'";
      }
      throw std::invalid_argument(who + "joint '" + tree.link(Index(k)).joint.name +
                                  "': a cycle of mimics " + names + " → '" +
                                  tree.link(Index(k)).joint.name +
                                  "' (each joint follows the next; one of them must follow none)");
    }
    for (k = s; follows[k] >= 0 && colour[k] == 1; k = std::size_t(follows[k])) colour[k] = 2;
  }
  return out;
}

void meet_mimics(const Tree& tree, Eigen::Ref<VectorXd> q) {
  const std::vector<Mimic>& mimics = tree.mimics();
  if (mimics.empty()) return;
  // in dependency order: a mimic whose reference is itself a mimic waits for it
  std::unordered_map<Index, std::size_t> by_coordinate;
  for (std::size_t k = 0; k < mimics.size(); ++k) by_coordinate.emplace(mimics[k].coordinate, k);
  std::vector<char> done(mimics.size(), 0);
  std::vector<std::size_t> stack;
  for (std::size_t s = 0; s < mimics.size(); ++s) {
    // walk up to the first reference that is set, then set the walk's joints in reverse
    for (std::size_t k = s;;) {
      if (done[k]) break;
      stack.push_back(k);
      const auto up = by_coordinate.find(mimics[k].reference);
      if (up == by_coordinate.end()) break;
      k = up->second;
    }
    while (!stack.empty()) {
      const Mimic& m = mimics[stack.back()];
      q[m.coordinate] = m.multiplier * q[m.reference] + m.offset;
      done[stack.back()] = 1;
      stack.pop_back();
    }
  }
}

void add_mimic_constraints(const Tree& tree, SystemBuilder& builder) {
  for (const Mimic& m : tree.mimics()) {
    builder.add(Constraint(tree.link(m.link).joint.name + ".mimic", ConstraintKind::kHolonomic, 1,
                           std::make_shared<MimicModel>(m)));
  }
}

}  // namespace ukdyn::tree::detail
