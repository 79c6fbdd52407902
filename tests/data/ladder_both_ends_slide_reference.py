# SPDX-License-Identifier: BSD-3-Clause
# The reference of tests/simulation/test_ladder_at_rest.cpp's LadderBothEndsSlide tests (u24 03):
# a uniform ladder (mass m, half-length l, I = m l^2 / 3 about its centre) at angle th to the
# floor, its foot A on a rough floor, its top B against a rough vertical wall (mu at both), both
# sliding (A away from the wall, B down), its centre at (l cos th, l sin th). Unknowns th'', N_f,
# N_w; the floor's friction -mu N_f along x at A, the wall's +mu N_w along y at B:
#   m x''    = N_w - mu N_f,   x'' = -l (sin th th'' + cos th th'^2)
#   m y''    = N_f + mu N_w - m g,   y'' = l (cos th th'' - sin th th'^2)
#   I th''   = -(moment about the centre, counterclockwise) (th is the body angle's complement)
#            = -l (cos th - mu sin th) N_f + l (sin th + mu cos th) N_w
# integrated (scipy DOP853, rtol 1e-13, atol 1e-15; and Radau as a check) until N_w = 0: the
# wall releases. Run: /usr/bin/python3 tests/data/ladder_both_ends_slide_reference.py
import numpy as np
from scipy.integrate import solve_ivp

m, l, g, mu, th0, w0 = 10.0, 1.5, 9.81, 0.8, 0.8, -2.0
I = m * l * l / 3


def reactions(th, w):
    """th'', N_f, N_w at the angle th and rate w, both ends sliding."""
    s, c = np.sin(th), np.cos(th)
    A = np.array([[-m * l * s, mu, -1.0],
                  [m * l * c, -1.0, -mu],
                  [I, l * (c - mu * s), -l * (mu * c + s)]])
    b = np.array([m * l * c * w * w, -m * g + m * l * s * w * w, 0.0])
    return np.linalg.solve(A, b)


def wall(t, y):
    return reactions(y[0], y[1])[2]


wall.terminal, wall.direction = True, -1
# the numbers test_ladder_at_rest.cpp asserts (LadderBothEndsSlide: t_r, th_r, w_r, N_f)
quoted = {"t_r": 0.0383016607841, "th": 0.7227208743929, "w": -2.0422005006514,
          "N_f": 37.89150684489}
for method, rtol, atol in (("DOP853", 1e-13, 1e-15), ("Radau", 1e-12, 1e-14)):
    sol = solve_ivp(lambda t, y: [y[1], reactions(y[0], y[1])[0]], [0.0, 1.0], [th0, w0],
                    method=method, rtol=rtol, atol=atol, events=wall)
    t_r = sol.t_events[0][0]
    th, w = sol.y_events[0][0]
    thdd, N_f, N_w = reactions(th, w)
    print(f"{method}: t_r = {t_r:.13f} s, th = {th:.13f}, th' = {w:.13f} rad/s, "
          f"N_f = {N_f:.11f} N, N_w = {N_w:.3g} N")
    print(f"  centre x = {l * np.cos(th):.13f}, y = {l * np.sin(th):.13f} m, "
          f"x' = {-l * np.sin(th) * w:.13f}, y' = {l * np.cos(th) * w:.13f} m/s")
    # both methods reproduce the quoted numbers (they agree to 3e-13 s, 4e-13 rad), far inside the
    # test's tolerances (1e-9 s, 1e-8 rad, 1e-5 N), and the wall's force vanishes
    for name, value, tol in (("t_r", t_r, 1e-12), ("th", th, 1e-12), ("w", w, 1e-12),
                             ("N_f", N_f, 1e-10)):
        assert abs(value - quoted[name]) <= tol, (method, name, value)
    assert abs(N_w) < 1e-9, (method, N_w)
print("the quoted reference holds under both methods")
