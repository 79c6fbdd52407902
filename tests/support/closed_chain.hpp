// SPDX-License-Identifier: BSD-3-Clause
// The closed chains of ../shared/reproducers/2026-11-28/gen_chain.py as model-file text: N uniform
// planar rods (total length 2 m, 1 kg/m) on revolute joints, pinned at (0, 0), along a gentle
// bend (not straight), at rest under gravity; the last tip pinned to the ground where it starts
// (joint 'close'), moved by `gap` in x. With `second_gap` > 0 the tip is pinned a second time,
// at `second_gap` beyond the first pin in x (joint 'close2'): two pins that no pose satisfies.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace ukdyn::test {

inline std::string closed_chain(int n, double gap = 0.0, double second_gap = 0.0) {
  const double L = 2.0 / n, pi = std::acos(-1.0);
  auto num = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return std::string(buf);
  };
  std::string b = "bodies:\n", j = "joints:\n";
  double x = 0.0, y = 0.0;
  for (int k = 0; k < n; ++k) {
    const double a = -pi / 2 * k / std::max(n - 1, 1) * 0.5;
    const double cx = x + 0.5 * L * std::cos(a), cy = y + 0.5 * L * std::sin(a);
    b += "  - {name: l" + std::to_string(k) + ", type: planar, mass: m, inertia: m*L^2/12, " +
         "position: [" + num(cx) + ", " + num(cy) + "], angle: " + num(a) + "}\n";
    j += "  - {name: j" + std::to_string(k) + ", type: revolute, parent: " +
         (k == 0 ? std::string("ground") : "l" + std::to_string(k - 1)) + ", child: l" +
         std::to_string(k) + ", parent_point: " + (k == 0 ? "[0, 0]" : "[L/2, 0]") +
         ", child_point: [-L/2, 0]}\n";
    x += L * std::cos(a);
    y += L * std::sin(a);
  }
  auto pin = [&](const char* name, double dx) {
    return "  - {name: " + std::string(name) + ", type: revolute, parent: ground, child: l" +
           std::to_string(n - 1) + ", parent_point: [" + num(x + dx) + ", " + num(y) +
           "], child_point: [L/2, 0]}\n";
  };
  j += pin("close", gap);
  if (second_gap > 0.0) j += pin("close2", gap + second_gap);
  return "name: chain" + std::to_string(n) + "\nparameters: {L: " + num(L) + ", m: " + num(L) +
         ", g: 9.81}\n" + b + j + "forces:\n  - {type: gravity, g: [0, -g]}\n" +
         "simulate: {t_end: 1, integrator: rk4, step: 2e-3}\n";
}

}  // namespace ukdyn::test
