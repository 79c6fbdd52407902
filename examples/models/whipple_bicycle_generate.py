# SPDX-License-Identifier: BSD-3-Clause
"""Writes examples/models/whipple_bicycle.yaml: the nonlinear Whipple bicycle of Meijaard,
Papadopoulos, Ruina and Schwab (2007, Proc. R. Soc. A 463:1955) in eight generalized coordinates.

The kinetic energy, the potential energy, the front wheel's contact (holonomic) and the two
wheels' rolling without slipping (nonholonomic) are composed here with SymPy from the rigid-body
kinematics below, and written out unexpanded as model-file expressions (the model-file language
has no named sub-expressions of the coordinates, so each appears inlined). Nothing is linearized:
ukdyn differentiates these expressions itself (docs/linearize.md, "The Whipple bicycle").

    /usr/bin/python3 examples/models/whipple_bicycle_generate.py > examples/models/whipple_bicycle.yaml
"""
import sympy as sp
from sympy import Matrix, cos, sin, sqrt

# the benchmark's parameters, as the paper writes them (x forward, y right, z down)
PARAMETERS = """w: 1.02, c: 0.08, lam: pi/10, g: 9.81, v: 5, push: 0.5,
             rR: 0.3, mR: 2, IRxx: 0.0603, IRyy: 0.12,
             xB: 0.3, zB: -0.9, mB: 85, IBxx: 9.2, IByy: 11, IBzz: 2.8, IBxz: 2.4,
             xH: 0.9, zH: -0.7, mH: 4, IHxx: 0.05892, IHyy: 0.06, IHzz: 0.00708, IHxz: -0.00756,
             rF: 0.35, mF: 3, IFxx: 0.1405, IFyy: 0.28,
             sl: sin(lam), cl: cos(lam)"""
(w, c, g, rR, mR, IRxx, IRyy, xB, zB, mB, IBxx, IByy, IBzz, IBxz, xH, zH, mH, IHxx, IHyy, IHzz,
 IHxz, rF, mF, IFxx, IFyy, sl, cl) = sp.symbols(
    "w c g rR mR IRxx IRyy xB zB mB IBxx IByy IBzz IBxz xH zH mH IHxx IHyy IHzz IHxz rF mF IFxx "
    "IFyy sl cl")
NAMES = ["x", "y", "psi", "phi", "theta", "delta", "theta_R", "theta_F"]
x, y, psi, phi, th, de, thR, thF = sp.symbols(NAMES)
xd, yd, psid, phid, thd, ded, thRd, thFd = sp.symbols([n + "_dot" for n in NAMES])


def Rx(a):
    return Matrix([[1, 0, 0], [0, cos(a), -sin(a)], [0, sin(a), cos(a)]])


def Ry(a):
    return Matrix([[cos(a), 0, sin(a)], [0, 1, 0], [-sin(a), 0, cos(a)]])


def Rz(a):
    return Matrix([[cos(a), -sin(a), 0], [sin(a), cos(a), 0], [0, 0, 1]])


ex, ey, ez = Matrix([1, 0, 0]), Matrix([0, 1, 0]), Matrix([0, 0, 1])
# frames (z up, y left): yaw Y = Rz(psi), lean L = Y Rx(phi), rear frame B = L Ry(theta) (pitch),
# front frame H = B Rs(delta), Rs the rotation about the steer axis s, tilted back by lam
s = Matrix([-sl, 0, cl])
Rlam = Matrix([[cl, 0, -sl], [0, 1, 0], [sl, 0, cl]])  # Ry(-lam): e_z -> s
Rs = Rlam * Rz(de) * Rlam.T
RLB = Ry(th)
RYL = Rx(phi)
RYB = RYL * RLB
# body points from the rear wheel's centre, in B at the reference pose (the paper's z is down)
b = Matrix([xB, 0, -zB - rR])    # rear body's centre of mass
a = Matrix([w + c, 0, -rR])      # where the steer axis meets the ground
pH = Matrix([xH, 0, -zH - rR])   # front body's centre of mass
pF = Matrix([w, 0, rF - rR])     # front wheel's centre
# angular velocities in B's components
wL = RYB.T * (psid * ez) + RLB.T * (phid * ex)
wB = wL + thd * ey
wH = wB + ded * s
aF_B = Rs * ey                   # the front wheel's axle, in B
# velocities in B's components
Pd_Y = Matrix([xd * cos(psi) + yd * sin(psi), -xd * sin(psi) + yd * cos(psi), 0])
vCR = RYB.T * Pd_Y + rR * wL.cross(RLB.T * ez)
vGB = vCR + wB.cross(b)
vGH = vCR + wB.cross(a) + wH.cross(Rs * (pH - a))
vCF = vCR + wB.cross(a) + wH.cross(Rs * (pF - a))
# inertia tensors with z up: the products I_xz change sign
IB = Matrix([[IBxx, 0, -IBxz], [0, IByy, 0], [-IBxz, 0, IBzz]])
IH = Matrix([[IHxx, 0, -IHxz], [0, IHyy, 0], [-IHxz, 0, IHzz]])
wHH = Rs.T * wH


def sq(v):
    return (v.T * v)[0]


# wheels: axisymmetric, I_xx |w|^2 + (I_yy - I_xx) (w . axle)^2
T = (mR * sq(vCR) + mB * sq(vGB) + mH * sq(vGH) + mF * sq(vCF)
     + IRxx * sq(wB) + 2 * IRxx * thRd * wB[1] + IRxx * thRd**2 + (IRyy - IRxx) * (wB[1] + thRd)**2
     + (wB.T * IB * wB)[0] + (wHH.T * IH * wHH)[0]
     + IFxx * sq(wH) + 2 * IFxx * thFd * (wH.T * aF_B)[0] + IFxx * thFd**2
     + (IFyy - IFxx) * ((wH.T * aF_B)[0] + thFd)**2) / 2


def height(v):
    return (RYB * v)[2]


zCR = rR * cos(phi)
V = g * (mR * zCR + mB * (zCR + height(b)) + mH * (zCR + height(a + Rs * (pH - a)))
         + mF * (zCR + height(a + Rs * (pF - a))))
# the front wheel touches the ground: its centre's height = rF |horizontal part of the axle|
aF = RYB * aF_B
contact = zCR + height(a + Rs * (pF - a)) - rF * sqrt(aF[0]**2 + aF[1]**2)
# rolling: the wheels' material contact points are at rest (horizontal components, yaw frame)
wF = RYB * (wH + thFd * aF_B)
down_F = -rF * (ez - aF[2] * aF) / sqrt(aF[0]**2 + aF[1]**2)
vPF = RYB * vCF + wF.cross(down_F)
vPR = sp.simplify(RYB * vCR + (RYB * (wB + thRd * ey)).cross(-rR * (RYL * ez)))


def text(e):
    return str(e).replace("**", "^")


def block(e, indent=4):
    # wrap a long expression at its top-level " + " / " - " for YAML folding (>-)
    words, line, lines = text(e).split(" "), "", []
    for word in words:
        if len(line) + len(word) + 1 > 96 and line:
            lines.append(line)
            line = word
        else:
            line = (line + " " + word) if line else word
    lines.append(line)
    return "\n".join(" " * indent + l for l in lines)


print(f"""# SPDX-License-Identifier: BSD-3-Clause
# Whipple bicycle benchmark (Meijaard, Papadopoulos, Ruina, Schwab 2007): nonlinear, rolling
name: Whipple bicycle
# GENERATED by examples/models/whipple_bicycle_generate.py (SymPy) — edit that, not this.
# Four rigid bodies: the rear wheel R, the rear frame with its rider B, the front frame
# (fork and handlebar) H and the front wheel F; knife-edge wheels rolling without slipping on
# the level ground; a hinge (the steering joint) between B and H. The 25 parameters are the
# benchmark's (Table 1), in the paper's axes (x forward, y right, z down: zB, zH < 0, and its
# products of inertia IBxz, IHxz); the model itself uses z up and y left.
# Coordinates: the rear contact point (x, y), yaw psi, lean phi, pitch theta of the rear frame,
# steer delta, and the wheels' rotations theta_R, theta_F relative to their frames.
# Constraints: `front_contact` (holonomic: the front wheel touches the ground — it fixes the
# pitch), `rear_rolling` and `front_rolling` (nonholonomic, two rows each: the material points
# of the wheels at their contacts are at rest). 8 coordinates, 7 positions and 3 velocities free.
# The upright straight run at speed v (all angles 0, x' = v, theta_R' = v/rR, theta_F' = v/rF)
# is a steady motion; its lean and steer (phi, delta, phi', delta') decouple from the cyclic
# coordinates, and their four eigenvalues are those of Table 2 of the paper: self-stable for
# 4.29238253634111 < v < 6.02426201538837 m/s (tests/analysis/test_whipple_bicycle.cpp):
#   ukdyn linearize examples/models/whipple_bicycle.yaml --set v=5 --set push=0 \\
#       --independent x,y,psi,phi,delta,theta_R,theta_F \\
#       --independent-velocities phi,delta,theta_R --states phi,delta,phi_dot,delta_dot
# (push = 0: the initial state is the straight run). The run: at v = 5 m/s (inside the stable
# range) pushed sideways (lean rate `push`, 0.5 rad/s), the weave decays (eigenvalues
# -0.775 ± 4.465i, -0.323, -14.08) and the bicycle runs on upright on a new heading.
parameters: {{{PARAMETERS}}}
coordinates: [{", ".join(NAMES)}]
units: {{x: m, y: m, psi: rad, phi: rad, theta: rad, delta: rad, theta_R: rad, theta_F: rad}}
kinetic_energy: >-
{block(T)}
potential_energy: >-
{block(V)}
constraints:
  - name: front_contact
    holonomic: >-
{block(contact, 6)}
  - name: rear_rolling
    nonholonomic:
      - {text(vPR[0])}
      - {text(vPR[1])}
  - name: front_rolling
    nonholonomic:
      - >-
{block(vPF[0], 8)}
      - >-
{block(vPF[1], 8)}
initial:
  q: {{}}
  q_dot: {{x: v, theta_R: v/rR, theta_F: v/rF, phi: push}}
  project: {{keep: [x_dot, phi_dot, theta_R_dot]}}
simulate: {{t_end: 5, integrator: dopri5, rtol: 1e-10, atol: 1e-12}}
output:
  every: 0.01
  expressions:
    speed: rR*theta_R_dot
""")
