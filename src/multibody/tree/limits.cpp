// SPDX-License-Identifier: BSD-3-Clause
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

void check_samples(const char* who, Index coordinates, const std::vector<double>& t,
                   const std::vector<double>& values) {
  const std::size_t n = std::size_t(coordinates);
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

LimitWatch::LimitWatch(const Tree& tree) : n_(tree.coordinate_count()) {
  for (Index i = 0; i < tree.link_count(); ++i) {
    const Joint& j = tree.link(i).joint;
    if (tree.dofs(i) != 1) continue;
    offset_.push_back(tree.offset(i));
    const bool prismatic = j.kind == JointKind::kPrismatic;
    lower_.push_back({j.name, "lower", j.lower, 0.0, 0.0, 0.0, prismatic});
    upper_.push_back({j.name, "upper", j.upper, 0.0, 0.0, 0.0, prismatic});
    // URDF's effort 0 is "not given" in many files (urdfdom's default): no limit then
    const bool limited = j.effort > 0.0 && !std::isinf(j.effort);
    effort_.push_back({j.name, "effort", limited ? j.effort : INFINITY, 0.0, 0.0, 0.0, prismatic});
    // (likewise a velocity of 0)
    const bool fast = j.velocity > 0.0 && !std::isinf(j.velocity);
    velocity_.push_back(
        {j.name, "velocity", fast ? j.velocity : INFINITY, 0.0, 0.0, 0.0, prismatic});
  }
}

void LimitWatch::observe(const std::vector<double>& t, const std::vector<double>& q,
                         const std::vector<double>& tau, const std::vector<double>& qd) {
  const char* who = "ukdyn::tree::LimitWatch::observe";
  check_samples(who, n_, t, q);
  if (!tau.empty()) check_samples(who, n_, t, tau);
  if (!qd.empty()) check_samples(who, n_, t, qd);
  const std::size_t n = std::size_t(n_);
  for (std::size_t k = 0; k < offset_.size(); ++k) {
    const std::size_t o = std::size_t(offset_[k]);
    // q < lower by lower − q; q > upper by q − upper; |τ| > effort by |τ| − effort
    // (infinite limits never pass)
    for (std::size_t s = 0; s < t.size(); ++s) {
      note(lower_[k], lower_[k].bound - q[s * n + o], t[s]);
      note(upper_[k], q[s * n + o] - upper_[k].bound, t[s]);
      if (!tau.empty()) note(effort_[k], std::abs(tau[s * n + o]) - effort_[k].bound, t[s]);
      if (!qd.empty()) note(velocity_[k], std::abs(qd[s * n + o]) - velocity_[k].bound, t[s]);
    }
  }
}

std::vector<LimitExcess> LimitWatch::excesses() const {
  std::vector<LimitExcess> out;
  for (std::size_t k = 0; k < offset_.size(); ++k) {
    if (lower_[k].excess > 0.0) out.push_back(lower_[k]);
    if (upper_[k].excess > 0.0) out.push_back(upper_[k]);
  }
  for (const auto* list : {&velocity_, &effort_}) {
    for (const LimitExcess& e : *list) {
      if (e.excess > 0.0) out.push_back(e);
    }
  }
  return out;
}

std::vector<LimitExcess> check_joint_limits(const Tree& tree, const std::vector<double>& t,
                                            const std::vector<double>& q) {
  LimitWatch watch(tree);
  watch.observe(t, q, {});
  return watch.excesses();
}

std::vector<LimitExcess> check_effort_limits(const Tree& tree, const std::vector<double>& t,
                                             const std::vector<double>& tau) {
  // the efforts only (the zero positions' excesses, if any, are dropped)
  LimitWatch watch(tree);
  watch.observe(t, std::vector<double>(tau.size(), 0.0), tau);
  std::vector<LimitExcess> out;
  for (const LimitExcess& e : watch.excesses()) {
    if (e.limit == "effort") out.push_back(e);
  }
  return out;
}

std::string describe(const LimitExcess& e, const UnitSystem& units) {
  // the excess's unit: a force or torque for an effort, a rate for a velocity, a length or
  // angle for a position
  const bool effort = e.limit == "effort";
  const std::string unit = effort ? (e.prismatic ? units.force() : units.torque())
                           : e.limit == "velocity"
                               ? units.rate(e.prismatic ? units.length : "rad")
                               : (e.prismatic ? units.length : std::string("rad"));
  return "joint '" + e.joint + "' exceeds its " + e.limit + " limit " + format_number(e.bound) +
         " by " + format_number(e.excess, 4) + " " + unit +
         " (first at t = " + format_number(e.first_time, 6) + " " + units.time +
         ", worst at t = " + format_number(e.worst_time, 6) + " " + units.time + ")";
}

}  // namespace ukdyn::tree
