# SPDX-License-Identifier: BSD-3-Clause
"""Self-describing runs (issue #16 item 4): summary.json's provenance, trajectory.h5 with every
column of trajectory.csv, ``ukdyn run --from-summary`` making a run again, Result.to_hdf5."""

import hashlib
import json
import shutil
import subprocess

import numpy as np
import pytest

import ukdyn


def read_csv(path):
    with open(path, encoding="utf-8") as f:
        names = f.readline().rstrip("\n").split(",")
        rows = [[float(x) for x in line.rstrip("\n").split(",")] for line in f if line.strip()]
    return names, np.array(rows).T


def run(cli, *args):
    return subprocess.run([cli, "run", *args, "--no-plots"], capture_output=True, text=True)


def same_bits(a, b):
    return np.array_equal(np.asarray(a).view(np.uint64), np.asarray(b).view(np.uint64))


def test_summary_records_the_model_parameters_and_build(cli, out_dir):
    proc = run(cli, "--example", "pendulum", "--set", "L=0.5", "--t-end", "0.5",
               "-o", str(out_dir / "a"))
    assert proc.returncode == 0, proc.stderr
    made = json.loads((out_dir / "a" / "summary.json").read_text())["provenance"]
    assert made["example"] == "pendulum" and made["model_file"] is None
    text = ukdyn.example_text("pendulum").encode()
    assert made["model_sha256"] == hashlib.sha256(text).hexdigest()
    assert made["ukdyn_version"] == ukdyn.__version__
    assert made["ukdyn_commit"]
    assert made["parameters"]["L"] == 0.5 and made["overridden"] == ["L"]
    assert set(made["parameters"]) == {"L", "g", "m"}
    assert made["arguments"][1:3] == ["run", "--example"]


def test_hdf5_has_every_csv_column_bit_for_bit(cli, out_dir):
    # a controlled model: its control columns go to both files
    proc = run(cli, "--example", "control_duffing", "--t-end", "0.5", "--format", "csv,hdf5",
               "-o", str(out_dir / "c"))
    assert proc.returncode == 0, proc.stderr
    names, values = read_csv(out_dir / "c" / "trajectory.csv")
    result, summary = ukdyn.read_hdf5(out_dir / "c" / "trajectory.h5")
    assert result.names == names
    assert any(n.startswith("error.") for n in names)
    for k, n in enumerate(names):
        assert same_bits(result[n], values[k]), n
    on_disk = json.loads((out_dir / "c" / "summary.json").read_text())
    # the same summary but for the wall time of writing it
    assert summary["steps"] == on_disk["steps"] and summary["control"] == on_disk["control"]
    assert summary["control"]["evaluations"] > 0
    assert summary["provenance"]["model_sha256"] == on_disk["provenance"]["model_sha256"]


def test_hdf5_alone_writes_no_csv(cli, out_dir):
    proc = run(cli, "--example", "pendulum", "--t-end", "0.2", "--format", "hdf5",
               "-o", str(out_dir / "h"))
    assert proc.returncode == 0, proc.stderr
    assert (out_dir / "h" / "trajectory.h5").exists()
    assert not (out_dir / "h" / "trajectory.csv").exists()
    proc = run(cli, "--example", "pendulum", "--format", "xml", "-o", str(out_dir / "x"))
    assert proc.returncode == 2 and "the formats are csv and hdf5" in proc.stderr


def test_from_summary_makes_the_same_run_again(cli, out_dir, examples_dir):
    model = out_dir / "model.yaml"
    shutil.copy(examples_dir / "block_slide_stick.yaml", model)
    proc = run(cli, str(model), "--set", "mu=0.3", "--t-end", "1.5", "--integrator", "rk4",
               "--step", "0.002", "-o", str(out_dir / "first"))
    assert proc.returncode == 0, proc.stderr
    summary = out_dir / "first" / "summary.json"
    again = run(cli, "--from-summary", str(summary), "-o", str(out_dir / "again"))
    assert again.returncode == 0, again.stderr
    first = (out_dir / "first" / "trajectory.csv").read_bytes()
    assert (out_dir / "again" / "trajectory.csv").read_bytes() == first
    made = json.loads((out_dir / "again" / "summary.json").read_text())
    assert made["options"]["integrator"] == "rk4" and made["options"]["t_end"] == 1.5
    assert made["provenance"]["parameters"]["mu"] == 0.3
    assert made["provenance"]["overridden"] == ["mu"]
    # flags given with it apply on top
    other = run(cli, "--from-summary", str(summary), "--t-end", "0.5", "-o", str(out_dir / "o"))
    assert other.returncode == 0, other.stderr
    assert json.loads((out_dir / "o" / "summary.json").read_text())["t_reached"] == 0.5
    # a model changed since refuses, naming both hashes
    model.write_text(model.read_text() + "\n# edited\n")
    changed = run(cli, "--from-summary", str(summary), "-o", str(out_dir / "changed"))
    assert changed.returncode == 2
    assert "has changed since that run" in changed.stderr
    # not a summary; a model given as well
    bad = run(cli, "--from-summary", str(model), "-o", str(out_dir / "bad"))
    assert bad.returncode == 2 and "not a JSON summary" in bad.stderr
    both = run(cli, str(model), "--from-summary", str(summary), "-o", str(out_dir / "both"))
    assert both.returncode == 2 and "give no model file" in both.stderr


def test_result_to_hdf5_round_trips(out_dir):
    result = ukdyn.load("pendulum").simulate(t_end=0.3)
    path = out_dir / "r.h5"
    result.to_hdf5(path)
    back, summary = ukdyn.read_hdf5(path)
    assert back.names == result.names
    for n in result.names:
        assert same_bits(back[n], result[n]), n
    assert summary["steps"] == result.stats["steps"]
    assert summary["provenance"]["written_by"] == "Result.to_hdf5"
    assert back.coordinates == result.coordinates
