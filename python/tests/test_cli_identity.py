# SPDX-License-Identifier: BSD-3-Clause
"""A model run from Python gives bit-identical results to `ukdyn run` on the same file.

The command writes every number in the shortest form that reads back bit for bit (io/trajectory_files.hpp), so
parsing its trajectory.csv gives back the doubles it computed; they must equal the arrays of
Model.simulate() exactly, column by column and in the same order.

Every model must match exactly: the expression compiler visits the operands of sums and
products in an order of its own (not GiNaC's, which depends on addresses), so two processes
compute the same bits (also checked for the command alone by the cli.reproducible_* tests)."""

import subprocess

import numpy as np
import pytest

import ukdyn


def read_csv(path):
    with open(path, encoding="utf-8") as f:
        names = f.readline().rstrip("\n").split(",")
        rows = [[float(x) for x in line.rstrip("\n").split(",")] for line in f if line.strip()]
    return names, np.array(rows).T


def run_cli(cli, out_dir, *args):
    proc = subprocess.run([cli, "run", *args, "-o", str(out_dir), "--no-plots"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return read_csv(out_dir / "trajectory.csv")


def assert_identical(result, names, values):
    assert result.names == names
    different = [n for k, n in enumerate(names)
                 if not np.array_equal(result[n], values[k], equal_nan=True)]
    assert not different, f"not bit-identical: {different}"


@pytest.mark.parametrize("example", [
    "pendulum", "block_slide_stick", "incline_friction", "four_bar_friction", "control_duffing",
    "control_spacecraft", "double_four_bar_bodies", "heavy_top"])
def test_example_runs_bit_identical_to_the_command(cli, out_dir, example):
    if example not in ukdyn.examples():
        pytest.skip(f"no example {example}")
    names, values = run_cli(cli, out_dir, "--example", example, "--t-end", "1")
    result = ukdyn.load(example).simulate(t_end=1.0)
    assert_identical(result, names, values)


def test_file_with_overrides_runs_bit_identical_to_the_command(cli, out_dir, examples_dir):
    path = examples_dir / "incline_friction.yaml"
    names, values = run_cli(cli, out_dir, str(path), "--set", "mu=0.35", "--set", "alpha=0.6",
                            "--t-end", "1.5")
    result = ukdyn.load(path, mu=0.35, alpha=0.6).simulate(t_end=1.5)
    assert_identical(result, names, values)


def test_result_to_csv_writes_what_the_command_writes(cli, out_dir):
    names, values = run_cli(cli, out_dir, "--example", "pendulum", "--t-end", "0.5")
    result = ukdyn.load("pendulum").simulate(t_end=0.5)
    result.to_csv(str(out_dir / "python.csv"))
    assert (out_dir / "python.csv").read_text() == (out_dir / "trajectory.csv").read_text()
