// SPDX-License-Identifier: BSD-3-Clause
/// @file gallery/gallery.hpp
/// Built-in example systems with known answers: closed-form solutions, published benchmark
/// values, or the shared benchmark problems of bench/data/. Each example is a ready
/// System with a consistent initial state and a suggested duration, so that a user can check
/// ukdyn (or their own build of it) against numbers that do not come from ukdyn.
///
/// Every holonomic and nonholonomic constraint is written once as a generic callable
/// (holonomic / nonholonomic of core/autodiff.hpp). Where the impressed forces are conservative the
/// system carries its potential energy, so simulations report the total energy E = T + V.
/// Holonomic constraints are written with a unit gradient at the solution where possible
/// (distance constraints as (|d|² − L²) / (2 L)), so that their violation is a length in metres.
///
/// @code
///   auto ex = ukdyn::gallery::make("pendulum");
///   auto traj = ukdyn::simulate(ex.system, ex.q0, ex.qd0, {.t_end = ex.t_end});
/// @endcode
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/core/system.hpp"
#include "ukdyn/core/types.hpp"

/// Built-in example systems with known answers (this file).
namespace ukdyn::gallery {

/// Standard gravity used by every example unless a parameter says otherwise (m/s²).
inline constexpr double kGravity = 9.81;

/// An example: its description, a consistent initial state and a suggested duration.
struct Example {
  std::string name;         ///< the name make() knows it by
  std::string description;  ///< one paragraph: model, coordinates, constraints, reference facts
  System system;            ///< the constrained system
  VectorXd q0;              ///< initial coordinates (n), consistent with every constraint at t = 0
  VectorXd qd0;             ///< initial velocities (n), consistent with every constraint at t = 0
  double t_end = 1.0;       ///< suggested duration (s), from t = 0
};

/// Names of every example, in a fixed order. Cost O(number of examples).
std::vector<std::string> names();

/// The example called `name` with its default parameters.
/// @throws std::invalid_argument naming the unknown name and listing the known ones.
Example make(const std::string& name);

/// "pendulum": a particle of mass m on a massless rod of length L about the origin, under
/// gravity g along −y, in Cartesian coordinates q = (x, y).
/// Constraint "rod" (holonomic): (x² + y² − L²) / (2 L) = 0.
/// Initial state: released horizontally at rest, q0 = (L, 0), q'0 = 0. V = m g y (zero at the
/// pivot's height, so E = 0 throughout).
/// Reference facts, with theta the angle from the downward vertical:
///  - period 4 sqrt(L/g) K(sin(pi/4)) = 2.367841947576 s for L = 1, g = 9.81 (K the complete
///    elliptic integral of the first kind, parameter m = 1/2); the particle is back at (L, 0)
///    at rest after one period and at (−L, 0) after half of it;
///  - rod tension m g cos theta + m L theta'² = 3 m g cos theta = −3 m g y / L, directed to the
///    pivot (zero at release, 3 m g at the bottom);
///  - at release q'' = (0, −g).
Example pendulum(double m = 1.0, double L = 1.0, double g = kGravity);

/// "bead_on_rotating_wire": a bead of mass m, q = (x, y), in a horizontal plane (no gravity in
/// the plane), on a straight wire through the origin that turns at the constant rate Omega.
/// Constraint "wire" (holonomic, rheonomic): −x sin(Omega t) + y cos(Omega t) = 0.
/// Initial state: r = r0 on the wire along +x, radial speed rd0: q0 = (r0, 0),
/// q'0 = (rd0, r0 Omega).
/// Reference facts, with r the distance along the wire, u = (cos Omega t, sin Omega t) and
/// n = (−sin Omega t, cos Omega t):
///  - r(t) = r0 cosh(Omega t) + (rd0 / Omega) sinh(Omega t)   (r'' = Omega² r);
///  - the wire's force is 2 m Omega r' along n (Coriolis) and nothing along u;
///  - the wire does work (the constraint depends on t): the kinetic energy is not conserved,
///    dT/dt = 2 m Omega² r r'. No potential energy.
Example bead_on_rotating_wire(double m = 1.0, double Omega = 1.0, double r0 = 1.0,
                              double rd0 = 0.5);

/// "block_on_incline": a block of mass m, q = (x, y), on a rough incline through the origin
/// rising at angle alpha (the line −x sin alpha + y cos alpha = 0), gravity g along −y,
/// launched up the slope at speed v0 from the origin.
/// Constraint "incline" (holonomic): −x sin alpha + y cos alpha = 0 (distance from the plane).
/// Non-ideal force "coulomb.incline": Coulomb sliding friction of coefficient mu with the normal
/// force taken from the incline's ideal reaction (coulomb_friction, core/nonideal.hpp;
/// regularization velocity 1e-9 m/s). V = m g y. Reference facts (while sliding up, s the distance
/// along the slope):
///  - deceleration g (sin alpha + mu cos alpha), normal force m g cos alpha, friction
///    mu m g cos alpha down the slope;
///  - the block stops at t_stop = v0 / (g (sin alpha + mu cos alpha)) after
///    s_stop = v0² / (2 g (sin alpha + mu cos alpha)); with mu > tan alpha it then sticks
///    (simulate() switches the contact to its stick constraint, see coulomb_friction; one
///    forward_dynamics call models sliding only);
///  - defaults (alpha = 0.3, mu = 0.5 > tan alpha = 0.309, v0 = 2 m/s): deceleration
///    7.584978... m/s², t_stop = 0.263679052689 s and s_stop = 0.263679052689 m (equal because
///    v0 = 2 m/s).
/// @throws std::invalid_argument unless 0 <= alpha < pi/2, mu >= 0, m > 0.
Example block_on_incline(double alpha = 0.3, double mu = 0.5, double v0 = 2.0, double m = 1.0,
                         double g = kGravity);

/// "chaplygin_sleigh": a rigid body of mass m and moment of inertia I about its centre of mass
/// G, on a horizontal plane, resting on a knife edge at the contact point P = G − a u, i.e. a
/// behind G along the body axis u = (cos theta, sin theta). Coordinates q = (x, y, theta): G and
/// the heading. With n = (−sin theta, cos theta) the knife edge forbids P to move along n.
/// Constraint "knife_edge" (nonholonomic): v_P · n = −x' sin theta + y' cos theta − a theta' = 0.
/// Reference facts, with v = v_P · u = (x', y') · u and w = theta':
///  - v is the speed of the contact point P (whose velocity is v u: P moves along the body axis
///    only) and also the component of G's velocity along the axis; G's speed is sqrt(v² + a² w²);
///  - v' = a w², w' = −m a v w / (I + m a²) (Newton along u and n, Euler about G with the knife
///    force F n at P);
///  - the kinetic energy (m v² + (I + m a²) w²) / 2 is conserved, so with
///    V² = v0² + (I + m a²) w0² / m and k = m a / (I + m a²): v' = k (V² − v²) and
///    v(t) = V tanh(k V t + atanh(v0 / V)) and w² = v' / a = (k / a) (V² − v²);
///    for the defaults (m = a = I = 1, w0 = 0.2, v0 = 0.1): V = 0.3, k = 1/2 and
///    v(t) = 0.3 tanh(0.15 t + atanh(1/3)); v → 0.3 and w → 0 as t → ∞.
/// Initial state: G at the origin, theta = 0, q'0 = (v0, a w0, w0).
Example chaplygin_sleigh(double m = 1.0, double a = 1.0, double I = 1.0, double w0 = 0.2,
                         double v0 = 0.1);

/// "double_four_bar": the IFToMM multibody benchmark A02 (double four-bar mechanism). Five
/// uniform thin rods of 1 m and 1 kg: three cranks pivoted at (0,0), (1,0), (2,0), initially
/// vertical, and two couplers joining the crank tips, initially horizontal at y = 1; gravity
/// 9.81 m/s² along −y; the crank tips start at 1 m/s along +x.
/// Natural coordinates: the three crank tips, q = (x1, y1, x2, y2, x3, y3) (6).
/// Constraints (holonomic, each a distance in metres): "crank1", "crank2", "crank3" (tip i at
/// 1 m from its pivot) and "coupler1", "coupler2" (consecutive tips 1 m apart); 5 rows, 1
/// degree of freedom. The middle crank is redundant in the parallelogram; when the cranks are
/// horizontal every row constrains x only and the rank of A drops from 5 to 3 (singular
/// configurations, which the mechanism passes twice per revolution). There the ideal
/// constraints also admit other motions (tip 1 on the pivot of crank 2 lets the loop beyond it
/// turn freely), so an integrator that steps onto the singular pose can leave the parallelogram
/// branch; the reference below is the parallelogram motion.
/// Mass matrix (constant): a crank with a fixed pivot puts m/3 I on its tip; a coupler between
/// two moving points has m/6 [2I I; I 2I]. Gravity: half of each rod's weight on each moving
/// end. V = m g (y1 + 3/2 y2 + y3).
/// Reference facts: the mechanism moves as a parallelogram, every crank at the same angle
/// theta from the vertical with 3 theta'' = 3.5 g sin theta; the tip of the left crank at
/// t = 10 s is (0.32845811, 0.94451854) (IFToMM benchmark solution).
Example double_four_bar();

/// "shared_P1": benchmark problem P1 of bench/data (double pendulum, two 1 m links
/// with 1 kg at each tip, I_com = 1e-9 kg m², pivot at the origin, released at rest with both
/// links along +x; T = 10 s), in natural coordinates q = (x1, y1, x2, y2), the two tips.
/// Constraint "links" (holonomic, 2 rows, metres): |r1| = 1, |r2 − r1| = 1.
/// Mass matrix (constant): each link between points i, j with centre of mass at fraction
/// c = com_x / L contributes m [(1−c)², (1−c)c; (1−c)c, c²] ⊗ I₂ + (I_com / L²) [1 −1; −1 1] ⊗ I₂,
/// which reproduces m v_G²/2 + I_com w²/2 exactly on the constraint manifold. Gravity on the
/// centres of mass; V measured from V_eq = −29.43 J (so E(0) = 29.43 J).
/// Reference: phi of link 1 at T = −2.1392711 rad (reported_coordinate). The 1e-9 inertias are
/// kept: the reference was computed with them (dropping them moves phi_link1(10 s) by 1.3e-7 rad,
/// by an independent integration of the closed-form double-pendulum equations).
Example shared_P1();

/// "shared_P2": benchmark problem P2 of bench/data (crank-rocker four-bar: crank
/// 0.3 m, coupler 1.0 m, rocker 0.8 m, ground 1.0 m, uniform thin rods of 1 kg/m; ground
/// pivots A = (0,0), D = (1,0); crank released at rest at 150° on the open branch; T = 10 s), in
/// natural coordinates q = (xB, yB, xC, yC): B the crank tip (crank–coupler hinge), C the
/// coupler tip, shared with the rocker tip (the loop closure).
/// Constraint "links" (holonomic, 3 rows, metres): |B − A| = 0.3, |C − B| = 1, |C − D| = 0.8.
/// Mass matrix and gravity as for shared_P1; V measured from V_eq = 3.1660572656184334 J.
/// Reference: phi of the crank at T = 3.1507615 rad (reported_coordinate).
Example shared_P2();

/// The problem's reported coordinate (radians) from natural coordinates q:
///  - "shared_P1": phi of link 1, atan2(y1, x1), on the branch [−3 pi/2, pi/2) (the motion can
///    only reach [−7 pi/6, pi/6], so the value is continuous along it; phi(0) = 0);
///  - "shared_P2": phi of the crank, atan2(yB, xB), on the branch [5 pi/12, 5 pi/12 + 2 pi) (the
///    energy of the start confines the crank to [150°, 359.6°]; phi(0) = 150° = 2.618 rad).
/// @throws std::invalid_argument for any other name or a q of the wrong size. Cost O(1).
double reported_coordinate(const std::string& name, const Eigen::Ref<const VectorXd>& q);

/// The loop-closure violation of the problem (metres), as a joint-coordinate simulator measures
/// it from body poses: every link is placed from its proximal point along the direction of
/// its natural coordinates with its exact length (crank tip B' = A + 0.3 e(phi_crank), coupler
/// tip B' + 1.0 e(phi_coupler), rocker tip D + 0.8 e(phi_rocker), e(phi) = (cos phi, sin phi)),
/// and the violation is the distance between the coupler tip and the rocker tip. It vanishes
/// exactly when the three distance constraints hold, and is of the order of their violation.
/// "shared_P1" has no loop: 0. @throws std::invalid_argument for any other name or a q of
/// the wrong size. Cost O(1).
double closure_violation(const std::string& name, const Eigen::Ref<const VectorXd>& q);

/// Facts of a shared benchmark problem (bench/data/README.md, problems.json).
struct SharedProblem {
  std::string id;          ///< "P1", "P2"
  std::string coord_name;  ///< "phi_link1", "phi_crank"
  double T = 10.0;         ///< duration (s)
  double V_eq = 0.0;       ///< potential energy of the stable equilibrium (J), the datum of V
  double reference_coordinate = 0.0;  ///< reported coordinate at T (rad), accuracy-1e-10 run
};

/// The facts of "shared_P1" or "shared_P2". @throws std::invalid_argument for other names.
SharedProblem shared_problem(const std::string& name);

}  // namespace ukdyn::gallery
