// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/models.hpp
/// Model files of the linearization tests (tests/analysis/), each with the closed-form result it
/// is checked against.
#pragma once

namespace ukdyn::test {

/// A pendulum (point mass m at length l, angle th from the upright) on a cart of mass M, in
/// generalized coordinates (x, th); F0 is a constant force on the cart (0: the upright is an
/// equilibrium). Linearized at the upright (Ogata; Åström & Murray, §2.1, massless rod):
///   x'' = −(m g / M) th + F / M,   th'' = (M + m) g th / (M l) − F / (M l).
inline const char* kCartPendulum = R"(
name: cart pendulum
parameters: {M: 2, m: 0.5, l: 0.8, g: 9.81, F0: 0}
coordinates: [x, th]
kinetic_energy: 0.5*(M + m)*x_dot^2 + m*l*cos(th)*x_dot*th_dot + 0.5*m*l^2*th_dot^2
potential_energy: m*g*l*cos(th)
forces: [F0, 0]
)";

/// The same in Cartesian coordinates of the cart (xc, yc) and the bob (xb, yb): a rail
/// yc = 0 and a rod |bob − cart| = l, two holonomic rows.
inline const char* kCartPendulumCartesian = R"(
name: cart pendulum, Cartesian
parameters: {M: 2, m: 0.5, l: 0.8, g: 9.81}
coordinates: [xc, yc, xb, yb]
kinetic_energy: 0.5*M*(xc_dot^2 + yc_dot^2) + 0.5*m*(xb_dot^2 + yb_dot^2)
potential_energy: M*g*yc + m*g*yb
constraints:
  - {name: rail, holonomic: yc}
  - {name: rod, holonomic: ((xb - xc)^2 + (yb - yc)^2 - l^2)/(2*l)}
)";

/// A pendulum with a cubic damper: th'' = −(g/l) sin th − c th'³ / (m l²).
inline const char* kCubicPendulum = R"(
name: pendulum with a cubic damper
parameters: {m: 1.5, l: 0.7, g: 9.81, c: 0.3}
coordinates: [th]
kinetic_energy: 0.5*m*l^2*th_dot^2
potential_energy: -m*g*l*cos(th)
forces: [-c*th_dot^3]
)";

/// A parallelogram four-bar hanging under gravity: cranks (uniform rods, mass mc, length L) at
/// (0, 0) and (d, 0), angles t1, t3 from the downward vertical; the coupler (uniform rod, mass
/// mk, length d) at angle t2. Two holonomic loop rows. On its one-DOF motion t1 = t3, t2 = 0,
///   T = ½ (2 mc L²/3 + mk L²) t1'²,  V = −(mc + mk) g L cos t1,
/// so small oscillations have ω² = g (mc + mk) / (L (2 mc/3 + mk)).
inline const char* kParallelogram = R"(
name: parallelogram four-bar
parameters: {mc: 1, mk: 2, L: 0.5, d: 1, g: 9.81}
coordinates: [t1, t2, t3]
kinetic_energy: >-
  0.5*(mc*L^2/3)*(t1_dot^2 + t3_dot^2)
  + 0.5*mk*((L*t1_dot*cos(t1) - d/2*t2_dot*sin(t2))^2 + (L*t1_dot*sin(t1) + d/2*t2_dot*cos(t2))^2)
  + 0.5*(mk*d^2/12)*t2_dot^2
potential_energy: -mc*g*L/2*(cos(t1) + cos(t3)) + mk*g*(-L*cos(t1) + d/2*sin(t2))
constraints:
  - {name: loop_x, holonomic: L*sin(t1) + d*cos(t2) - d - L*sin(t3)}
  - {name: loop_y, holonomic: -L*cos(t1) + d*sin(t2) + L*cos(t3)}
)";

/// A heavy symmetric top on a fixed tip in Cardan angles R = Rx(a) Ry(b) Rz(c): transverse
/// inertia I1 = Ic + m l² about the tip, I3 about the axis. The upright spin a = b = 0,
/// c' = ω is a steady motion; linearized, I1 a'' + I3 ω b' − m g l a = 0 and
/// I1 b'' − I3 ω a' − m g l b = 0, so λ = i (±I3 ω ± √(I3² ω² − 4 I1 m g l)) / (2 I1): stable
/// ("sleeping") for ω² > 4 m g l I1 / I3².
inline const char* kCardanTop = R"(
name: heavy symmetric top, Cardan angles
parameters: {m: 1, l: 0.5, Ic: 0.05, I3: 0.08, g: 9.81}
coordinates: [a, b, c]
kinetic_energy: 0.5*(Ic + m*l^2)*(a_dot^2*cos(b)^2 + b_dot^2) + 0.5*I3*(a_dot*sin(b) + c_dot)^2
potential_energy: m*g*l*cos(a)*cos(b)
)";

}  // namespace ukdyn::test
