// SPDX-License-Identifier: BSD-3-Clause
// URDF's <mimic>: a joint that follows another, q_j = multiplier · q_ref + offset, as a holonomic
// constraint of the tree's system (mimic.cpp).
#pragma once

#include <vector>

#include "ukdyn/core/system.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree::detail {

// The mimic relations of a tree being built (its links ordered, offsets known), checked: the
// joint mimicked exists, is not the joint itself, both have one coordinate, the multiplier and
// offset are finite, and no cycle of mimics (j1 follows j2 follows j1) — chains are allowed.
// @throws std::invalid_argument naming the joint. Cost O(links) (hashing the names).
std::vector<Mimic> mimic_relations(const Tree& tree);

// Sets each mimic joint's q from its reference's (chains in order): q_j = m q_ref + o. Cost
// O(mimics).
void meet_mimics(const Tree& tree, Eigen::Ref<VectorXd> q);

// Adds one holonomic constraint "<joint>.mimic" per mimic to `builder`: the row
// phi = q_j − m q_ref − o, A = e_jᵀ − m e_refᵀ, b = 0 (on two columns). Cost O(mimics).
void add_mimic_constraints(const Tree& tree, SystemBuilder& builder);

}  // namespace ukdyn::tree::detail
