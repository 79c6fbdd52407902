// URDF's joint and effort limits checked over a run's samples: which joint left its limit,
// when first, and by how much at worst (reported, never clipped).
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "ukdyn/core/format.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree {

namespace {

void check_samples(const char* who, const Tree& tree, const std::vector<double>& t,
                   const std::vector<double>& values) {
  const std::size_t n = std::size_t(tree.coordinate_count());
  if (values.size() != t.size() * n) {
    throw std::invalid_argument(std::string(who) + ": expected " + std::to_string(t.size()) +
                                " samples of " + std::to_string(n) + " values (" +
                                std::to_string(t.size() * n) + "), got " +
                                std::to_string(values.size()));
  }
}

// the excess of `value` beyond `bound` on one side (> 0 outside), accumulated into `e`
void note(LimitExcess& e, double excess, double t) {
  if (!(excess > 0.0)) return;
  if (e.excess == 0.0) e.first_time = t;
  if (excess > e.excess) {
    e.excess = excess;
    e.worst_time = t;
  }
}

}  // namespace

std::vector<LimitExcess> check_joint_limits(const Tree& tree, const std::vector<double>& t,
                                            const std::vector<double>& q) {
  check_samples("ukdyn::tree::check_joint_limits", tree, t, q);
  const std::size_t n = std::size_t(tree.coordinate_count());
  std::vector<LimitExcess> out;
  for (Index i = 0; i < tree.link_count(); ++i) {
    const Joint& j = tree.link(i).joint;
    if (tree.dofs(i) != 1) continue;
    const std::size_t o = std::size_t(tree.offset(i));
    LimitExcess lo{j.name, "lower", j.lower}, hi{j.name, "upper", j.upper};
    // q < lower by lower − q; q > upper by q − upper (infinite limits never pass)
    for (std::size_t s = 0; s < t.size(); ++s) {
      note(lo, j.lower - q[s * n + o], t[s]);
      note(hi, q[s * n + o] - j.upper, t[s]);
    }
    if (lo.excess > 0.0) out.push_back(lo);
    if (hi.excess > 0.0) out.push_back(hi);
  }
  return out;
}

std::vector<LimitExcess> check_effort_limits(const Tree& tree, const std::vector<double>& t,
                                             const std::vector<double>& tau) {
  check_samples("ukdyn::tree::check_effort_limits", tree, t, tau);
  const std::size_t n = std::size_t(tree.coordinate_count());
  std::vector<LimitExcess> out;
  for (Index i = 0; i < tree.link_count(); ++i) {
    const Joint& j = tree.link(i).joint;
    // URDF's effort 0 is "not given" in many files (urdfdom's default): no limit then
    if (tree.dofs(i) != 1 || !(j.effort > 0.0) || std::isinf(j.effort)) continue;
    const std::size_t o = std::size_t(tree.offset(i));
    LimitExcess e{j.name, "effort", j.effort};
    for (std::size_t s = 0; s < t.size(); ++s) note(e, std::abs(tau[s * n + o]) - j.effort, t[s]);
    if (e.excess > 0.0) out.push_back(e);
  }
  return out;
}

std::string describe(const LimitExcess& e) {
  const bool effort = e.limit == "effort";
  return "joint '" + e.joint + "' exceeds its " + e.limit + " limit " + format_number(e.bound) +
         " by " + format_number(e.excess) + (effort ? " (N·m or N)" : " (rad or m)") +
         " (first at t = " + format_number(e.first_time) +
         " s, worst at t = " + format_number(e.worst_time) + " s)";
}

}  // namespace ukdyn::tree
