# SPDX-License-Identifier: BSD-3-Clause
"""LQR on the linearization of a constrained system, run in the nonlinear model, against ukdyn's
exact tracking controller on the same task (issue #32 item 4; docs/linearize.md, "From linear to
nonlinear: LQR").

The plant: a pendulum on a cart in Cartesian coordinates — the cart's x and the bob's (px, py),
one holonomic row (the rod: (px − x)² + py² = l²) — balanced upright. Two actuators: a force u1
on the cart (along x) and a horizontal force u2 on the bob (along px). The task: from the
pendulum tilted by th0 at rest, bring it upright over the cart and the cart back to x = 0.

1. ``Model.linearize`` at the upright state with the inputs ``x`` and ``px`` (generalized
   forces): A (4 × 4) and B (4 × 2) in the manifold's coordinates (x, px and their rates; py
   is the dependent one);
2. LQR: P from the continuous algebraic Riccati equation AᵀP + PA − PBR⁻¹BᵀP + Q = 0 (SciPy's
   ``solve_continuous_are``), K = R⁻¹BᵀP;
3. the nonlinear model with the forces u = −K x written into its ``forces:``, simulated by ukdyn
   (the rod kept exactly by the fundamental equation);
4. the same plant under ukdyn's exact tracking controller (``control:``): the requirements
   ``home`` (x = 0) and ``upright`` (px − x = 0) with critically damped error dynamics, the same
   two actuators;
5. a plot of both: the two task errors and the size of the control force.

Run: ``PYTHONPATH=build/python /usr/bin/python3 python/examples/lqr_cart_pendulum.py out/``
"""

import os
import sys
from dataclasses import dataclass
from typing import Dict

import numpy as np

import ukdyn

PARAMETERS = dict(M=1.0, m=0.3, l=0.6, g=9.81, th0=0.3)
T_END = 6.0
OMEGA_HOME, OMEGA_UPRIGHT = 2.0, 4.0  # the tracking controller's error dynamics (zeta = 1)

PLANT = """
name: cart pendulum (Cartesian)
parameters: {{M: {M}, m: {m}, l: {l}, g: {g}, th0: {th0}}}
coordinates: [x, px, py]
kinetic_energy: 0.5*M*x_dot^2 + 0.5*m*(px_dot^2 + py_dot^2)
potential_energy: m*g*py
{forces}
constraints:
  - {{name: rod, holonomic: (px - x)^2 + py^2 - l^2}}
initial:
  q: {{x: 0, px: l*sin(th0), py: l*cos(th0)}}
simulate: {{t_end: {t_end}, rtol: 1e-10, atol: 1e-12}}
output: {{every: 0.01}}
{control}
"""


def plant_text(forces: str = "", control: str = "") -> str:
    return PLANT.format(**PARAMETERS, t_end=T_END, forces=forces, control=control)


@dataclass
class Design:
    """The linear model, the Riccati solution and the gain."""
    lm: ukdyn.LinearModel
    P: np.ndarray
    K: np.ndarray
    Q: np.ndarray
    R: np.ndarray

    def closed_loop_eigenvalues(self) -> np.ndarray:
        return np.linalg.eigvals(self.lm.A - self.lm.B @ self.K)


def design(Q=None, R=None) -> Design:
    """LQR on the linearization about the upright state (x = px = 0, py = l, at rest)."""
    from scipy.linalg import solve_continuous_are

    model = ukdyn.parse(plant_text())
    l = PARAMETERS["l"]
    lm = model.linearize(q=[0, 0, l], q_dot=[0, 0, 0], inputs=["x", "px"])
    n, k = lm.B.shape
    Q = np.diag([10.0, 10.0, 1.0, 1.0]) if Q is None else np.asarray(Q)
    R = np.eye(k) if R is None else np.asarray(R)
    P = solve_continuous_are(lm.A, lm.B, Q, R)
    K = np.linalg.solve(R, lm.B.T @ P)
    return Design(lm, P, K, Q, R)


def lqr_forces(d: Design) -> str:
    """``forces:`` of the closed loop: u = −K (x − x0) on the inputs' coordinates."""
    rows = []
    for i in range(d.K.shape[0]):
        terms = " + ".join(f"({d.K[i, j]:.17g})*({s} - ({d.lm.x0[j]:.17g}))"
                           for j, s in enumerate(d.lm.states))
        rows.append(f"-({terms})")
    by_coordinate = dict(zip(d.lm.inputs, rows))
    return "forces: [" + ", ".join(by_coordinate.get(c, "0") for c in ("x", "px", "py")) + "]"


TRACKING = f"""control:
  requirements:
    - {{name: home, holonomic: x, dynamics: {{omega: {OMEGA_HOME}, zeta: 1}}}}
    - {{name: upright, holonomic: px - x, dynamics: {{omega: {OMEGA_UPRIGHT}, zeta: 1}}}}
  actuated: [x, px]
"""


def run_lqr(d: Design):
    """The nonlinear closed loop under u = −K x: the Result and u (N × 2) at its samples."""
    res = ukdyn.parse(plant_text(forces=lqr_forces(d))).simulate()
    x = np.column_stack([res[s] for s in d.lm.states]) - d.lm.x0
    return res, -(x @ d.K.T)


def run_tracking():
    """The plant under the exact tracking controller: the Result and Q_c (N × 2, x and px)."""
    res = ukdyn.parse(plant_text(control=TRACKING)).simulate()
    return res, np.column_stack([res["Qc_control.x"], res["Qc_control.px"]])


def compare(d: Design) -> Dict[str, Dict[str, float]]:
    """Task errors and effort of both controllers: the largest |x| and |px − x| after 3 s, the
    peak force and ∫|u|² dt (trapezoid on the samples)."""
    out = {}
    for name, (res, u) in (("lqr", run_lqr(d)), ("tracking", run_tracking())):
        t = np.asarray(res.t)
        late = t >= 3.0
        u2 = (u**2).sum(axis=1)
        out[name] = dict(
            home_error_after_3s=float(np.abs(res["x"][late]).max()),
            upright_error_after_3s=float(np.abs(res["px"][late] - res["x"][late]).max()),
            peak_force=float(np.sqrt(u2).max()),
            effort=float(np.sum(0.5 * (u2[1:] + u2[:-1]) * np.diff(t))),
        )
    return out


def plot(d: Design, path: str):
    """The two controllers' task errors (x, px − x) and force size against time."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(8, 7.5), sharex=True)
    for name, (res, u), style in (("LQR (linearization)", run_lqr(d), "-"),
                                  ("exact tracking (ukdyn control)", run_tracking(), "--")):
        t = res.t
        axes[0].plot(t, res["x"], style, label=name)
        axes[1].plot(t, res["px"] - res["x"], style, label=name)
        axes[2].plot(t, np.hypot(u[:, 0], u[:, 1]), style, label=name)
    axes[0].set_ylabel("cart x [m]")
    axes[1].set_ylabel("bob offset px − x [m]")
    axes[2].set_ylabel("|u| [N]")
    axes[2].set_xlabel("t [s]")
    for ax in axes:
        ax.axhline(0, color="k", linewidth=0.5)
        ax.legend(fontsize=8)
    axes[0].set_title("pendulum on a cart, balanced from th0 = "
                      f"{PARAMETERS['th0']} rad: LQR vs exact tracking")
    fig.tight_layout()
    fig.savefig(path)
    return fig


def main(outdir: str = "."):
    os.makedirs(outdir, exist_ok=True)
    d = design()
    print("states", d.lm.states, "inputs", d.lm.inputs)
    print("K =", d.K)
    print("closed-loop eigenvalues", np.sort_complex(d.closed_loop_eigenvalues()))
    for name, c in compare(d).items():
        print(name, c)
    plot(d, os.path.join(outdir, "lqr_vs_tracking.png"))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
