# SPDX-License-Identifier: BSD-3-Clause
"""Models from SymPy expressions: the translation, and the same numbers as the model file."""

import math

import numpy as np
import pytest
import sympy as sp

import ukdyn
from ukdyn.symbolic import to_expression

x, y, t = sp.symbols("x y t")
m, g, L, mu, alpha, v0 = sp.symbols("m g L mu alpha v0")
xd, yd = ukdyn.velocities(x, y)

PENDULUM = dict(
    T=m * (xd**2 + yd**2) / 2, V=m * g * y,
    constraints={"rod": (x**2 + y**2 - L**2) / (2 * L)},
    parameters={m: 1, L: 1, g: 9.81},
    initial={"q": {x: L, y: 0}, "q_dot": {x: 0, y: 0}},
    simulate={"t_end": 2.367841947576, "integrator": "dopri5", "rtol": 1e-10, "atol": 1e-12},
    output={"every": 0.01, "expressions": {"theta": sp.atan2(x, -y), "r": sp.sqrt(x**2 + y**2)}},
    name="pendulum")


def assert_same(a, b, tol):
    assert a.names == b.names
    for name in a.names:
        np.testing.assert_allclose(a[name], b[name], rtol=0, atol=tol, err_msg=name)


def test_sympy_pendulum_is_the_model_file_bit_for_bit():
    model = ukdyn.from_sympy([x, y], **PENDULUM)
    assert model.file == "<sympy>"
    a, b = model.simulate(), ukdyn.load("pendulum").simulate()
    # the file also draws itself (visual:, docs/viewer.md): its visual.* columns come last
    assert a.names == [n for n in b.names if not n.startswith("visual.")]
    assert b.names[len(a.names):] == ["visual.pivot.x", "visual.pivot.y", "visual.bob.x",
                                      "visual.bob.y"]
    for name in a.names:
        np.testing.assert_allclose(a[name], b[name], rtol=0, atol=1e-12, err_msg=name)
    # the same expressions give the same GiNaC forms and tapes: identical doubles
    assert all(np.array_equal(a[n], b[n]) for n in a.names)


def test_sympy_pendulum_with_functions_of_time_and_overrides():
    X, Y = sp.Function("x")(t), sp.Function("y")(t)
    model = ukdyn.from_sympy(
        [X, Y], T=m * (X.diff(t)**2 + Y.diff(t)**2) / 2, V=m * g * Y,
        constraints={"rod": (X**2 + Y**2 - L**2) / (2 * L)}, parameters={m: 1, L: 1, g: 9.81},
        initial={"q": {"x": L, "y": 0}}, L=2.0)
    b = ukdyn.load("pendulum", L=2.0)
    a_run = model.simulate(t_end=0.5, rtol=1e-10, atol=1e-12)
    b_run = b.simulate(t_end=0.5, output_every=0.01)
    for name in ["x", "y", "x_dot", "y_dot", "lambda.rod", "energy"]:
        np.testing.assert_allclose(a_run[name], b_run[name], rtol=0, atol=1e-12, err_msg=name)


def test_mass_matrix_and_forces_form_gives_the_lagrangian_numbers():
    lagr = ukdyn.from_sympy([x, y], **PENDULUM)
    direct = dict(PENDULUM)
    del direct["T"], direct["V"]
    direct.update(M=sp.Matrix([[m, 0], [0, m]]), Q=[0, -m * g])
    eom = ukdyn.from_sympy([x, y], **direct)
    a, b = lagr.simulate(t_end=1.0), eom.simulate(t_end=1.0)
    for name in ["x", "y", "x_dot", "y_dot", "x_ddot", "y_ddot", "lambda.rod"]:
        np.testing.assert_allclose(a[name], b[name], rtol=0, atol=1e-12, err_msg=name)


def test_sympy_incline_with_coulomb_friction_matches_the_file():
    a = ukdyn.from_sympy(
        [x, y], T=m * (xd**2 + yd**2) / 2, V=m * g * y,
        constraints={"plane": y + x * sp.tan(alpha)},
        nonideal=[{"friction": "coulomb", "constraint": "plane", "mu": mu}],
        parameters={m: 1, g: 9.81, alpha: 0.5, mu: 0.2, v0: 1},
        initial={"q": {x: 0, y: 0}, "q_dot": {x: v0 * sp.cos(alpha), y: -v0 * sp.sin(alpha)}},
        simulate={"t_end": 2, "integrator": "dopri5", "rtol": 1e-10, "atol": 1e-12,
                  "drift": "projection"},
        output={"every": 0.01})
    b = ukdyn.load("incline_friction")
    ra, rb = a.simulate(), b.simulate()
    for name in ra.names:
        np.testing.assert_allclose(ra[name], rb[name], rtol=0, atol=1e-12, err_msg=name)


def test_sympy_requirement_becomes_a_control_section_like_the_duffing_file():
    c, F, w = sp.symbols("c F w")
    model = ukdyn.from_sympy(
        [x], T=m * ukdyn.velocities(x)[0]**2 / 2,
        Q=[-c * ukdyn.velocities(x)[0] + x - x**3 + F * sp.cos(w * t)],
        requirements=[{"name": "track", "holonomic": x - sp.sin(t),
                       "dynamics": {"omega": 2, "zeta": 1}}],
        control={"law": "gauss"}, parameters={m: 1, c: 0.3, F: 0.5, w: 1.2},
        initial={"q": {x: 1}, "q_dot": {x: 0}},
        simulate={"t_end": 10, "integrator": "dopri5", "rtol": 1e-11, "atol": 1e-13},
        output={"every": 0.02, "expressions": {"e_closed_form": (1 + t) * sp.exp(-2 * t)}})
    assert model.controller is not None and model.controller.row_names == ["track"]
    a, b = model.simulate(), ukdyn.load("control_duffing").simulate()
    assert a.names == b.names
    for name in a.names:  # 10 s of a chaotic plant under control: 1e-10; the integral of
        # |power|, whose kinks shorten the steps, to 1e-7 relative (docs/control.md, section 5)
        rtol = 1e-7 if name == "control_work_abs" else 0
        np.testing.assert_allclose(a[name], b[name], rtol=rtol, atol=1e-10, err_msg=name)


def test_sympy_objects_in_settings_are_written_as_expressions():
    # (reproducers, 2026-11-25) a parameter symbol as a requirement's omega raised "from_sympy:
    # cannot write wn"; it is a parameter of the model like any other, and gives the numbers of
    # the same model with the number written in
    c, F, w, wn = sp.symbols("c F w wn")

    def duffing(omega, extra):
        return ukdyn.from_sympy(
            [x], T=m * ukdyn.velocities(x)[0]**2 / 2,
            Q=[-c * ukdyn.velocities(x)[0] + x - x**3 + F * sp.cos(w * t)],
            requirements=[{"name": "track", "holonomic": x - sp.sin(t),
                           "dynamics": {"omega": omega, "zeta": sp.Integer(1)}}],
            control={"law": "gauss"}, parameters={m: 1, c: 0.3, F: 0.5, w: 1.2, **extra},
            initial={"q": {x: 1}, "q_dot": {x: 0}},
            simulate={"t_end": 2, "integrator": "dopri5", "rtol": 1e-11, "atol": 1e-13},
            output={"every": 0.1})

    a, b = duffing(wn, {wn: 2}).simulate(), duffing(2, {}).simulate()
    assert a.names == b.names
    # e = x - sin t follows e'' + 2 ωn e' + ωn² e = 0 from e(0) = 1, e'(0) = -1: (1 + t) e^(-2t)
    e = np.asarray(a["x"]) - np.sin(a.t)
    np.testing.assert_allclose(e, (1 + a.t) * np.exp(-2 * a.t), rtol=0, atol=1e-8)
    np.testing.assert_allclose(a["x"], b["x"], rtol=0, atol=1e-12)
    # a number SymPy holds (Integer, Float, Rational) is written as that number
    assert "zeta: 1" in ukdyn.sympy_to_yaml(
        [x], T=m * ukdyn.velocities(x)[0]**2 / 2, parameters={m: 1},
        requirements=[{"name": "r", "holonomic": x, "dynamics": {"omega": wn, "zeta": sp.Integer(1)}}],
        control={"law": "gauss"})


@pytest.mark.parametrize("expr", [
    x**2 - 3 * x * y / 7 + sp.Rational(1, 3),
    -x**-2 * y + sp.sqrt(1 + x**2) / (x * y + 2),
    sp.exp(-x / 2) * sp.cos(2 * y) - sp.Abs(x - y) ** sp.Rational(3, 2),
    sp.atan2(y, x) + sp.asin(x / 3) - sp.log(2 + y**2) * sp.tanh(x),
    (x - y)**3 / (x + 1)**2 - sp.pi * sp.E**x + 2.5e-3 * x,
    -(x + y) * (x - 2 * y)**-1 + 1 / sp.sqrt(x**2 + 4),
])
def test_translated_expressions_evaluate_like_sympy(expr):
    """Each expression, translated and read back by the C++ reader as an output expression, has
    the values that SymPy computes (a check of the translation, independent of ukdyn)."""
    text = ("coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2 + y_dot^2)\n"
            f"initial: {{q: {{x: 0.7, y: -0.4}}, q_dot: {{x: 0.3, y: 0.2}}}}\n"
            f"simulate: {{t_end: 0.5}}\noutput: {{every: 0.1, expressions: "
            f"{{f: \"{to_expression(expr)}\"}}}}\n")
    r = ukdyn.parse(text).simulate()
    f = sp.lambdify((x, y), expr, "math")
    expected = [f(a, b) for a, b in zip(r.x, r.y)]
    np.testing.assert_allclose(r.f, expected, rtol=1e-13, atol=1e-15)


def test_translation_text():
    assert to_expression(x**2 + 2 * x * y) == "x^2 + 2*x*y"
    assert to_expression(m * xd**2 / 2) == "m*x_dot^2/2"
    assert to_expression(1 / (2 * L)) == "1/(2*L)"
    assert to_expression(-x**2) == "-x^2"
    assert to_expression(x**(y**2)) == "x^(y^2)"
    assert to_expression(sp.sqrt(x)) == "sqrt(x)"


def test_unsupported_function_is_a_value_error():
    with pytest.raises(ValueError, match="no function 'floor'"):
        to_expression(sp.floor(x))
    with pytest.raises(ValueError, match="is not a comparison"):
        ukdyn.from_sympy([x], T=xd**2 / 2, V=sp.Piecewise((x, sp.Eq(x, 0)), (0, True)))
    with pytest.raises(ValueError, match="otherwise piece"):
        to_expression(sp.Piecewise((x, x > 0)))


@pytest.mark.parametrize("expr", [
    sp.sign(x - y) * x + sp.Abs(y),
    sp.Heaviside(x - 0.5) + 2 * sp.Heaviside(y, 0),
    sp.Min(x, y, 0.1) - sp.Max(x**2, y, -1),
    sp.Piecewise((x**2, x > 0.5), (y, x <= 0.4), (x + y, True)),
    sp.Piecewise((1, sp.And(x > 0.2, y >= -0.3)), (2, sp.Or(y < -0.35, sp.Not(x < 0.8))),
                 (3, True)),
])
def test_non_smooth_functions_evaluate_like_sympy(expr):
    """sign, Heaviside, Min, Max and Piecewise become sign, heaviside, min, max and nested if:
    read back as output expressions along a motion that crosses their switches, they have the
    values SymPy computes."""
    text = ("coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2 + y_dot^2)\n"
            f"initial: {{q: {{x: 0.1, y: -0.5}}, q_dot: {{x: 1.3, y: 0.45}}}}\n"
            f"simulate: {{t_end: 1}}\noutput: {{every: 0.0625, expressions: "
            f"{{f: \"{to_expression(expr)}\"}}}}\n")
    r = ukdyn.parse(text).simulate()
    expected = [float(expr.subs({x: a, y: b})) for a, b in zip(r.x, r.y)]
    np.testing.assert_allclose(r.f, expected, rtol=1e-13, atol=1e-15)


def test_sympy_bang_bang_with_piecewise_is_the_model_file():
    """x'' = -sign(x) from SymPy (the force as a Piecewise and as sign) is the YAML model: the
    same switch events, the same numbers, and the closed form (period 4 for amplitude 1/2)."""
    yaml = ukdyn.parse("coordinates: [x]\nmass_matrix: [[1]]\nforces: [-sign(x)]\n"
                       "initial: {q: {x: 0.5}}\n")
    settings = dict(t_end=4.0, integrator="rkf78", rtol=1e-10, atol=1e-12)
    ref = yaml.simulate(**settings)
    for force in (-sp.sign(x), sp.Piecewise((-1, x > 0), (1, x < 0), (0, True))):
        model = ukdyn.from_sympy([x], M=sp.Matrix([[1]]), Q=[force], initial={"q": {x: 0.5}})
        r = model.simulate(**settings)
        assert r.stats["switch_events"] == ref.stats["switch_events"] == 2
        np.testing.assert_allclose(r.x, ref.x, rtol=0, atol=1e-12)
        assert r.x[-1] == pytest.approx(0.5, abs=1e-8)
        assert r.x_dot[-1] == pytest.approx(0.0, abs=1e-8)
    # stepped across, the switches cost rkf78 its accuracy: the energy balance says so
    with pytest.warns(Warning, match="energy balance"):
        off = yaml.simulate(switch_events=False, **settings)
    assert off.stats["switch_events"] == 0
    assert abs(off.x[-1] - 0.5) > 1e-6


def test_unknown_symbol_is_a_model_error_pointing_into_the_generated_text():
    k = sp.Symbol("k")
    with pytest.raises(ukdyn.ModelError) as err:
        ukdyn.from_sympy([x], T=xd**2 / 2, V=k * x**2)
    assert err.value.file == "<sympy>"
    assert "unknown name 'k'" in err.value.message
    text = ukdyn.sympy_to_yaml([x], T=xd**2 / 2, V=k * x**2)
    assert "potential_energy" in text.splitlines()[err.value.line - 1]


def test_nonholonomic_constraint_is_recognised_by_its_velocities():
    text = ukdyn.sympy_to_yaml([x, y], T=(xd**2 + yd**2) / 2,
                               constraints={"knife": xd * sp.sin(t) - yd * sp.cos(t),
                                            "circle": x**2 + y**2 - 1})
    assert '{name: knife, nonholonomic: ' in text
    assert '{name: circle, holonomic: ' in text
