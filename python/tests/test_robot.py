# SPDX-License-Identifier: BSD-3-Clause
"""Robots from URDF (docs/robots.md): ukdyn.load of a .urdf and of a model file naming one."""

import pathlib

import numpy as np
import pytest

import ukdyn

DATA = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data"
PANDA = DATA / "panda_arm.urdf"


def test_a_urdf_loads_as_a_robot_whose_joints_are_its_coordinates():
    m = ukdyn.load(str(PANDA))
    assert m.coordinates == [f"panda_joint{i}" for i in range(1, 8)]
    r = m.simulate(t_end=0.1)
    q = np.asarray(r["panda_joint2"])
    # from rest at the neutral pose, gravity swings joint 2: q2'' = Q2/M22 at t = 0, so over
    # 0.1 s it moves, and the summary notes joint 4's limit (the neutral pose is outside it)
    assert q[0] == pytest.approx(0.0, abs=0.0)
    assert abs(q[-1]) > 1e-3
    assert any("panda_joint4" in note for note in r.stats["notes"])


def test_a_model_file_names_a_urdf_next_to_it(tmp_path):
    (tmp_path / "arm.urdf").write_text(PANDA.read_text())
    (tmp_path / "arm.yaml").write_text(
        "robot: {urdf: arm.urdf, gravity: [0, 0, 0], torques: {panda_joint1: 2}}\n"
        "initial: {q: {panda_joint4: -1.5}}\n")
    m = ukdyn.load(tmp_path / "arm.yaml")
    r = m.simulate(t_end=0.05)
    q1 = np.asarray(r["panda_joint1"])
    # no gravity and a constant torque on joint 1 from rest: q1 grows, the others barely
    assert q1[-1] > 0.0


def test_a_missing_urdf_is_a_model_error_at_its_line(tmp_path):
    (tmp_path / "arm.yaml").write_text("name: arm\nrobot: {urdf: nothere.urdf}\n")
    with pytest.raises(ukdyn.ModelError, match=r"arm.yaml:2:.*nothere.urdf: no such file"):
        ukdyn.load(tmp_path / "arm.yaml")
