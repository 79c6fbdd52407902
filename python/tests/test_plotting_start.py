# SPDX-License-Identifier: BSD-3-Clause
"""The command's plot script started before the simulation (app/run.cpp start_plots,
plotting.py --wait): its imports overlap the run; it draws when told "go" (the run's files are
written) and leaves without drawing at the end of its input (the run failed), leaving no
temporary directory behind."""

import os
import stat
import subprocess

import pytest

from test_plotting import FREE  # (a free slider, 0.2 s: two figures)
from ukdyn import plotting

#: contradicting constraints: the run cannot start (exit 3), after the plot script was started
CONTRADICTING = """
name: contradicting
coordinates: [x, y]
kinetic_energy: 0.5*(x_dot^2+y_dot^2)
constraints:
  - {name: at0, holonomic: x}
  - {name: at1, holonomic: x - 1}
"""

SCRIPT = os.path.join(os.path.dirname(os.path.abspath(plotting.__file__)), "plotting.py")


@pytest.fixture()
def free_run(cli, out_dir):
    model = out_dir / "free.yaml"
    model.write_text(FREE)
    done = subprocess.run([cli, "run", str(model), "-o", str(out_dir / "run"), "--no-plots"],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return out_dir / "run"


def pngs(directory):
    return sorted(f for f in os.listdir(directory) if f.endswith(".png"))


@pytest.mark.parametrize("told, drawn", [("go\n", ["coordinates.png", "energy.png"]),
                                         ("", []), ("stop\n", [])])
def test_the_waiting_script_draws_only_when_told_go(free_run, told, drawn):
    done = subprocess.run(["/usr/bin/python3", SCRIPT, "--wait", str(free_run / "trajectory.csv"),
                           str(free_run), "png"], input=told, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    assert pngs(free_run) == drawn


def wrapper(tmp_path):
    """A python that notes, as it starts, its arguments and whether the run's summary.json
    exists yet (written after the simulation), then is /usr/bin/python3."""
    path = tmp_path / "python"
    path.write_text('#!/bin/sh\n'
                    'if [ -e "$4/summary.json" ]; then w=after; else w=before; fi\n'
                    'echo "$2 $w" >> "%s"\n'
                    'exec /usr/bin/python3 "$@"\n' % (tmp_path / "started"))
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    return path


def test_the_command_starts_the_plot_script_in_waiting_mode(cli, tmp_path):
    """The command starts the script with --wait, before the run (which takes 200 000 steps, a
    few tenths of a second, so that the script's start is usually seen before summary.json: but
    a loaded machine may schedule the script's shell only after the run, so the test does not
    ask which it saw), and the script draws once told go."""
    model = tmp_path / "free.yaml"
    model.write_text(FREE)
    env = dict(os.environ, UKDYN_PYTHON=str(wrapper(tmp_path)), TMPDIR=str(tmp_path))
    done = subprocess.run([cli, "run", str(model), "-o", str(tmp_path / "run"), "--max-step",
                           "1e-6", "--output-every", "0.05"],
                          capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "started").read_text() in ("--wait before\n", "--wait after\n")
    assert pngs(tmp_path / "run") == ["coordinates.png", "energy.png"]
    assert not [f for f in os.listdir(tmp_path) if f.startswith("ukdyn-plot-")]


def test_a_run_that_cannot_start_draws_nothing_and_leaves_nothing(cli, tmp_path):
    model = tmp_path / "c.yaml"
    model.write_text(CONTRADICTING)
    env = dict(os.environ, UKDYN_PYTHON=str(wrapper(tmp_path)), TMPDIR=str(tmp_path))
    done = subprocess.run([cli, "run", str(model), "-o", str(tmp_path / "run")],
                          capture_output=True, text=True, env=env)
    assert done.returncode == 3, done.stderr
    assert "contradict each other" in done.stderr
    assert "plotting.py" not in done.stderr and "Traceback" not in done.stderr
    assert (tmp_path / "started").read_text() == "--wait before\n"  # (it was started)
    run = tmp_path / "run"
    assert not os.path.exists(run) or pngs(run) == []
    assert not [f for f in os.listdir(tmp_path) if f.startswith("ukdyn-plot-")]


@pytest.mark.parametrize("missing", ["numpy", "matplotlib"])
def test_a_python_without_the_plotting_modules_gets_one_warning_not_a_traceback(cli, tmp_path,
                                                                                missing):
    """A python whose plotting modules are missing (here: Debian's /usr/bin/python3 with a
    sitecustomize that hides NumPy, and with it matplotlib, or matplotlib alone): the run's files
    are written, the command warns in one line (exit 0: a documented warning, `ukdyn --help`'s exit
    codes, docs/simulation.md, the plots' paragraph) and no traceback is printed."""
    hide = tmp_path / "hide"
    hide.mkdir()
    (hide / "sitecustomize.py").write_text(
        "import sys\n"
        "class Hide:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] in (%r, 'matplotlib'):\n"
        "            raise ImportError('hidden: ' + name)\n"
        "sys.meta_path.insert(0, Hide())\n" % missing)
    python = tmp_path / "python-without"
    python.write_text('#!/bin/sh\nPYTHONPATH="%s" exec /usr/bin/python3 "$@"\n' % hide)
    python.chmod(python.stat().st_mode | stat.S_IXUSR)
    model = tmp_path / "free.yaml"
    model.write_text(FREE)
    env = dict(os.environ, UKDYN_PYTHON=str(python), TMPDIR=str(tmp_path))
    done = subprocess.run([cli, "run", str(model), "-o", str(tmp_path / "run")],
                          capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    assert ("warning: %s has no matplotlib: no plots" % python) in done.stderr
    assert {"summary.json", "trajectory.csv"} <= set(os.listdir(tmp_path / "run"))
    assert pngs(tmp_path / "run") == []
    assert not [f for f in os.listdir(tmp_path) if f.startswith("ukdyn-plot-")]
