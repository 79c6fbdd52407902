// SPDX-License-Identifier: BSD-3-Clause
// A block on a rough incline pulled off it along the normal (docs/contact.md, "Friction at
// contacts"): mass m on the plane through the origin at angle alpha (gap n = x sin alpha +
// y cos alpha), gravity along −y, launched down the slope at v0 and pulled along the normal by
// F = k t, so that it slides with friction mu N, N = m g cos alpha − k t, until it lifts off at
// t* = m g cos alpha / k. The model file without its simulate: and output: sections, for
// tests/simulation/test_contact_friction.cpp and tests/contact/incline_mujoco.hpp.
#pragma once

namespace ukdyn::incline {

inline constexpr const char* kModel = R"(
parameters: {m: 2, g: 9.81, alpha: 0.5, mu: 0.3, k: 4, v0: 1}
coordinates: [x, y]
mass_matrix: [[m, 0], [0, m]]
forces: [k*t*sin(alpha), k*t*cos(alpha) - m*g]
constraints:
  - {name: plane, holonomic: x*sin(alpha) + y*cos(alpha), unilateral: true}
nonideal:
  - {friction: coulomb, constraint: plane, mu: mu}
initial:
  q: {x: 0, y: 0}
  q_dot: {x: v0*cos(alpha), y: -v0*sin(alpha)}
)";

}  // namespace ukdyn::incline
