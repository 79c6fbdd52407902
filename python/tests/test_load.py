# SPDX-License-Identifier: BSD-3-Clause
"""Loading models: files, built-in examples, overrides, and the errors of bad input."""

import re
import subprocess

import numpy as np
import pytest

import ukdyn


def test_examples_are_the_model_files(examples_dir):
    names = sorted(p.stem for p in examples_dir.glob("*.yaml"))
    assert ukdyn.examples() == names
    assert "pendulum" in names
    assert ukdyn.example_text("pendulum") == (examples_dir / "pendulum.yaml").read_text()


def test_example_and_file_give_the_same_model(examples_dir):
    a = ukdyn.load("pendulum")
    b = ukdyn.load(examples_dir / "pendulum.yaml")
    c = ukdyn.load(str(examples_dir / "pendulum.yaml"))
    assert a.file == "examples/models/pendulum.yaml"
    assert b.file == c.file == str(examples_dir / "pendulum.yaml")
    for m in (a, b, c):
        assert m.name == "pendulum"
        assert m.coordinates == ["x", "y"]
        assert m.constraints == ["rod"]
        assert m.parameters == {"L": 1.0, "g": 9.81, "m": 1.0}
        assert m.output_names == ["theta", "r"]
        assert m.options["t_end"] == 2.367841947576
        assert m.options["integrator"] == "dopri5"
        assert m.controller is None
    np.testing.assert_array_equal(a.q0, [1.0, 0.0])


def test_overrides_replace_parameters_and_enter_the_initial_state():
    m = ukdyn.load("pendulum", L=2.0, m=3)
    assert m.parameters == {"L": 2.0, "g": 9.81, "m": 3.0}
    np.testing.assert_array_equal(m.q0, [2.0, 0.0])  # initial: q: {x: L}


def test_overrides_re_evaluate_the_derived_parameters_after_them():
    text = ("parameters: {m: 3, L: 2, I: m*L^2/12, Ip: I + m*(L/2)^2}\n"
            "coordinates: [th]\nkinetic_energy: 0.5*Ip*th_dot^2\n")
    assert ukdyn.parse(text).parameters == pytest.approx({"m": 3, "L": 2, "I": 1, "Ip": 4},
                                                         rel=1e-15)
    # m = 2: I = 2/3, Ip = 8/3; an override of I itself wins over its expression
    assert ukdyn.parse(text, m=2).parameters == pytest.approx(
        {"m": 2, "L": 2, "I": 2 / 3, "Ip": 8 / 3}, rel=1e-15)
    assert ukdyn.parse(text, I=5).parameters == pytest.approx(
        {"m": 3, "L": 2, "I": 5, "Ip": 8}, rel=1e-15)


def test_unknown_example_lists_the_examples():
    with pytest.raises(ValueError) as err:
        ukdyn.load("pendullum")
    assert "no model file or example called 'pendullum'" in str(err.value)
    for name in ukdyn.examples():
        assert name in str(err.value)


@pytest.mark.parametrize("typo", ["pendlum", "pendullum", "Pendulum"])
def test_unknown_example_suggests_the_nearest(typo):
    """A typo of an example's name: the nearest is suggested, as `ukdyn run --example` does
    (app/suggest.cpp's rule, one or two edits here), by load and example_text alike."""
    with pytest.raises(ValueError, match=r"^no model file or example called '%s' \(did you mean "
                       r"'pendulum'\?\); the examples are " % typo):
        ukdyn.load(typo)
    with pytest.raises(ValueError, match=r"^no example called '%s' \(did you mean 'pendulum'\?\)"
                       % typo):
        ukdyn.example_text(typo)


def test_unknown_example_far_from_all_suggests_none():
    with pytest.raises(ValueError) as err:
        ukdyn.load("zzzzzzzzzzzz")
    assert str(err.value).startswith("no model file or example called 'zzzzzzzzzzzz'; the examples")


def test_missing_file_is_a_model_error(out_dir):
    with pytest.raises(ukdyn.ModelError) as err:
        ukdyn.load(out_dir / "nosuch.yaml")
    assert err.value.file == str(out_dir / "nosuch.yaml")


def test_model_error_carries_the_cpp_message_and_its_parts(testdata_dir, cli, out_dir):
    path = testdata_dir / "malformed.yaml"
    with pytest.raises(ukdyn.ModelError) as err:
        ukdyn.load(path)
    e = err.value
    assert isinstance(e, RuntimeError)
    assert e.file == str(path)
    assert e.line == 6  # potential_energy: m*g*z
    assert e.column > 0
    assert "unknown name 'z'" in e.message
    assert str(e) == f"{e.file}:{e.line}:{e.column}: error: {e.message}" + (
        f" (hint: {e.hint})" if e.hint else "")
    # the command prints the same what() text
    run = subprocess.run([cli, "run", str(path), "-o", str(out_dir), "--no-plots"],
                         capture_output=True, text=True)
    assert run.returncode == 3
    assert str(e) in run.stderr


def test_unknown_override_is_a_model_error_naming_the_parameters():
    with pytest.raises(ukdyn.ModelError) as err:
        ukdyn.load("pendulum", nosuch=1.0)
    assert "the model has no parameter 'nosuch'" in str(err.value)
    assert err.value.line == 0
    # (named as the keyword argument, not as the command's --set)
    assert err.value.message.startswith("load(nosuch): the model has no parameter 'nosuch'")
    assert "--set" not in str(err.value)


def test_an_override_out_of_range_is_named_as_the_keyword_argument():
    """ukdyn.load(..., e=1.5) of a contact whose restitution is e: the ModelError is located at
    the restitution's value and names the keyword argument (the command names ``--set e=1.5``)."""
    text = ("parameters: {e: 0.5}\ncoordinates: [z]\nkinetic_energy: 0.5*z_dot^2\n"
            "potential_energy: 9.81*z\nconstraints:\n"
            "  - {name: floor, holonomic: z, unilateral: true, restitution: e}\n"
            "initial: {q: {z: 1}}\n")
    with pytest.raises(ukdyn.ModelError) as err:
        ukdyn.parse(text, "ball.yaml", e=1.5)
    assert (err.value.file, err.value.line) == ("ball.yaml", 6)
    assert "parse(e=1.5): " in str(err.value) and "--set" not in str(err.value)
    assert err.value.message.startswith("parse(e=1.5): ")
    assert "got 1.5" in err.value.message


def test_override_that_is_not_a_number_is_a_value_error():
    with pytest.raises(ValueError, match="nosuch='abc' is not a number"):
        ukdyn.load("pendulum", nosuch="abc")


def test_parse_reports_positions_in_the_text():
    text = "coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\npotential_energy: k*x^2\n"
    with pytest.raises(ukdyn.ModelError) as err:
        ukdyn.parse(text, "spring.yaml")
    assert err.value.file == "spring.yaml"
    assert err.value.line == 3
    assert "unknown name 'k'" in err.value.message
    m = ukdyn.parse(text.replace("k*", "4*"), "spring.yaml")
    assert m.file == "spring.yaml" and m.coordinates == ["x"]


def test_a_character_outside_ascii_is_quoted_whole():
    # CI's fuzzer: "Omeéa" in an expression gave a message holding half of 'é', which Python
    # could not decode (UnicodeDecodeError instead of ModelError)
    text = "coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\npotential_energy: 2*Ome\u00e9a*x^2\n"
    with pytest.raises(ukdyn.ModelError) as err:
        ukdyn.parse(text, "spring.yaml")
    assert (err.value.line, err.value.column) == (3, 24)
    assert err.value.message.endswith("unexpected character '\u00e9'")


def test_unknown_key_is_a_model_error():
    with pytest.raises(ukdyn.ModelError, match="kinetic_enrgy"):
        ukdyn.parse("coordinates: [x]\nkinetic_enrgy: 0.5*x_dot^2\n")


def test_bad_settings_are_value_errors():
    m = ukdyn.load("pendulum")
    with pytest.raises(ValueError, match="unknown setting 't_ned'"):
        m.simulate(t_ned=1.0)
    with pytest.raises(ValueError, match="rk9"):
        m.simulate(integrator="rk9")
    with pytest.raises(ValueError):
        m.simulate(t_end=-1.0)
    with pytest.raises(ValueError, match="q0 must have 2 entries"):
        m.simulate(q0=[1.0, 0.0, 0.0])


def test_inconsistent_initial_state_is_a_value_error_unless_projected(testdata_dir):
    m = ukdyn.load(testdata_dir / "inconsistent_pendulum.yaml")
    with pytest.raises(ValueError, match="rod"):
        m.simulate(t_end=0.1)
    r = m.simulate(t_end=0.1, project_initial=True)
    # projected onto the circle of radius L = 1 (least M-norm change: along the radius)
    assert r["x"][0] == pytest.approx(1.0, abs=1e-12)
    assert r["y"][0] == pytest.approx(0.0, abs=1e-12)


def test_check_reports_rank_and_redundancy(testdata_dir):
    rep = ukdyn.load(testdata_dir / "redundant_pendulum.yaml").check()
    assert rep["ok"]
    assert rep["coordinates"] == 2
    assert rep["rank"] == 1
    assert rep["degrees_of_freedom"] == 1
    assert rep["redundant"] == ["rod_copy"]
    bad = ukdyn.load(testdata_dir / "inconsistent_pendulum.yaml").check()
    assert not bad["ok"] and bad["initial_violations"]


def test_initial_state_override_at_the_equilibrium_stays_at_rest():
    r = ukdyn.load("pendulum").simulate(t_end=0.5, q0=[0.0, -1.0], qd0=[0.0, 0.0])
    np.testing.assert_allclose(r.x, 0.0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(r.y, -1.0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(r["lambda.rod"], -9.81, rtol=1e-13)  # tension m g, inward


def test_multibody_model_reports_its_joint_reactions():
    if "double_four_bar_bodies" not in ukdyn.examples():
        pytest.skip("no multibody example")
    m = ukdyn.load("double_four_bar_bodies")
    assert m.is_multibody
    r = m.simulate(t_end=0.2)
    assert r.ok and any(name.startswith("reaction.") for name in r.names)


def test_directory_is_named_as_a_directory(out_dir):
    # the same message as `ukdyn run DIR` (load_model): not "a model is a mapping of keys"
    with pytest.raises(ukdyn.ModelError, match="is a directory, not a model file"):
        ukdyn.load(str(out_dir))


def test_duplicate_key_is_a_model_error_at_the_second_copy():
    with pytest.raises(ukdyn.ModelError) as err:
        ukdyn.parse("coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\nkinetic_energy: x_dot^2\n",
                    "m.yaml")
    assert "m.yaml:3:1: error: the key 'kinetic_energy' is given twice" in str(err.value)
    assert "first at line 2" in str(err.value)
