# SPDX-License-Identifier: BSD-3-Clause
"""ukdyn.sweep (docs/ensembles.md): a small pendulum over L against its closed form, failing samples
recorded, the same numbers bit for bit on 1 and 2 threads, on a Dask LocalCluster of two worker
processes and from the command line (``ukdyn sweep``), grids as xarray Datasets."""

import math
import pathlib
import subprocess

import numpy as np
import pandas as pd
import pytest

import ukdyn
from conftest import import_or_missing, interrupt_python

ROOT = pathlib.Path(__file__).resolve().parents[2]
PENDULUM = str(ROOT / "tests" / "data" / "ensemble_pendulum.yaml")


def assert_same_frames(a: pd.DataFrame, b: pd.DataFrame) -> None:
    """Every column equal bit for bit (NaN where the other has NaN)."""
    assert list(a.columns) == list(b.columns)
    assert len(a) == len(b)
    for name in a.columns:
        x, y = a[name].to_numpy(), b[name].to_numpy()
        if x.dtype.kind == "f":
            assert np.array_equal(x, y, equal_nan=True), name
            assert np.array_equal(x.view(np.int64), y.view(np.int64)), name
        else:
            assert list(x) == list(y), name


def test_small_pendulum_over_length():
    # theta(t) = theta0 cos(sqrt(g/L) t) to a phase error of omega t theta0^2 / 16
    frame = ukdyn.sweep(PENDULUM, grid={"L": [0.5, 1.0, 2.0]}, at=[0.3, 0.7], workers=2)
    assert list(frame["L"]) == [0.5, 1.0, 2.0]
    assert list(frame["status"]) == ["ok"] * 3
    theta0 = 0.01
    for _, row in frame.iterrows():
        w = math.sqrt(9.81 / row["L"])
        for t in (0.3, 0.7):
            tol = 1.5 * theta0 ** 3 * (w * t / 16 + 0.01)
            assert row[f"theta@{t:g}"] == pytest.approx(theta0 * math.cos(w * t), abs=tol)
    assert frame["t_reached"].tolist() == [1.0] * 3


def test_failing_samples_are_recorded():
    frame = ukdyn.sweep(PENDULUM, grid={"L": [0.0, 1.0]}, workers=2)
    assert list(frame["status"]) == ["refused", "ok"]
    assert "ensemble_pendulum.yaml" in frame["message"].iloc[0]
    assert list(frame["ok"]) == [False, True]
    assert math.isnan(frame["x@end"].iloc[0])


def test_random_draws_same_on_one_and_two_threads():
    kw = dict(random={"theta0": "uniform(0.01,0.2)", "L": ("loguniform", 0.5, 2.0)}, n=6, seed=7,
              at=[0.5], t_end=0.5)
    one = ukdyn.sweep(PENDULUM, workers=1, **kw)
    two = ukdyn.sweep(PENDULUM, workers=2, **kw)
    assert_same_frames(one, two)
    assert (one["theta0"] > 0.01).all() and (one["theta0"] < 0.2).all()
    # a sample is `Model.simulate` of the model read with its parameters (and `at` as output_at)
    row = one.iloc[3]
    model = ukdyn.load(PENDULUM, theta0=row["theta0"], L=row["L"])
    result = model.simulate(t_end=0.5, output_at=[0.5])
    assert result["theta"][-1] == row["theta@0.5"]


def test_grid_as_dataset():
    ds = ukdyn.sweep(PENDULUM, grid={"L": "0.5:1.5:3", "theta0": [0.01, 0.02]}, at=[0.2],
                     t_end=0.2, dataset=True)
    assert dict(ds.sizes) == {"L": 3, "theta0": 2}
    assert ds["theta@0.2"].sel(L=1.0, theta0=0.02).item() == pytest.approx(
        0.02 * math.cos(math.sqrt(9.81) * 0.2), abs=1e-6)


def test_sweep_frames_and_datasets_carry_the_units():
    """The units of pendulum.yaml (x, y, r: m; theta: rad) reach the frame's attrs["units"] and
    each variable of the Dataset, as a Result's (test_results_units.py): a swept velocity per s,
    t_end and t_reached in s, energy_exchanged in J, a recorded value in its column's unit; a
    parameter (g) and the counts have none (issue #33 item 5)."""
    frame = ukdyn.sweep("pendulum", grid={"g": [9.81, 1.62], "y_dot": [0.0, 0.5],
                                          "t_end": [0.2, 0.3]},
                        at=[0.2], outputs=["theta", "r"], workers=2)
    assert list(frame["status"]) == ["ok"] * 8
    assert frame.attrs["units"] == {
        "y_dot": "m/s", "t_end": "s", "t_reached": "s", "energy_exchanged": "J",
        "x@0.2": "m", "y@0.2": "m", "x_dot@0.2": "m/s", "y_dot@0.2": "m/s", "theta@0.2": "rad",
        "r@0.2": "m"}
    xr = import_or_missing("xarray", "xarray is not installed (python3-xarray)")
    ds = ukdyn.to_dataset(frame)
    assert isinstance(ds, xr.Dataset)
    assert dict(ds.sizes) == {"g": 2, "y_dot": 2, "t_end": 2}
    assert ds["x@0.2"].attrs["units"] == "m" and ds["theta@0.2"].attrs["units"] == "rad"
    assert ds["x_dot@0.2"].attrs["units"] == "m/s" and ds["t_reached"].attrs["units"] == "s"
    assert ds["y_dot"].attrs["units"] == "m/s" and ds["t_end"].attrs["units"] == "s"
    assert "units" not in ds["g"].attrs and "units" not in ds["steps"].attrs
    assert "units" not in ds["status"].attrs
    assert ds.attrs["model"] == "examples/models/pendulum.yaml"
    # the rod's length stays 1 m: r is in m and equals 1 to the run's tolerance
    np.testing.assert_allclose(ds["r@0.2"].values, 1.0, rtol=0, atol=1e-8)


def test_dask_local_cluster_equals_threads():
    distributed = import_or_missing("distributed", "python3-distributed is not installed")
    kw = dict(grid={"L": [0.5, 1.0, 0.0]}, random={"theta0": "normal(0.05,0.01)"}, n=3, seed=3,
              at=[0.25], t_end=0.25)
    threaded = ukdyn.sweep(PENDULUM, workers=2, **kw)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=50) as cluster, \
            distributed.Client(cluster) as client:
        on_dask = ukdyn.sweep(PENDULUM, client=client, chunk_size=2, **kw)
    assert_same_frames(threaded, on_dask)
    assert list(on_dask["status"]).count("refused") == 3  # L = 0


def test_command_line_writes_the_same_table(cli, out_dir):
    subprocess.run([cli, "sweep", PENDULUM, "--grid", "L=0.5:1.5:3", "--random",
                    "theta0~uniform(0.01,0.1)", "--samples", "2", "--seed", "5", "--at", "0.25",
                    "--t-end", "0.25", "--jobs", "2", "-o", str(out_dir), "--no-plots"],
                   check=True, capture_output=True)
    from_cli = pd.read_csv(out_dir / "ensemble.csv", keep_default_na=False,
                           na_values=["nan"], float_precision="round_trip")
    from_python = ukdyn.sweep(PENDULUM, grid={"L": "0.5:1.5:3"},
                              random={"theta0": "uniform(0.01,0.1)"}, n=2, seed=5, at=[0.25],
                              t_end=0.25, workers=2)
    for name in ("L", "theta0", "steps", "theta@0.25", "x_dot@0.25", "energy_balance"):
        assert np.array_equal(from_cli[name].to_numpy(dtype=float),
                              from_python[name].to_numpy(dtype=float)), name


def test_a_contact_model_sweep_counts_its_events_and_rest_time(cli, out_dir):
    """The bouncing ball over e: K + 1 impacts (K the first with e^K < 1e-6, the rest
    criterion's, the last impact a rest) and the rest at t0 + 2 t0 e (1 - e^K)/(1 - e), the same
    on 1 and 2 threads and in ukdyn sweep's ensemble.csv; a model without contacts has no such
    columns."""
    kw = dict(grid={"e": [0.3, 0.5, 0.7]}, t_end=4.0)
    one = ukdyn.sweep("bouncing_ball", workers=1, **kw)
    two = ukdyn.sweep("bouncing_ball", workers=2, **kw)
    assert_same_frames(one, two)
    t0 = math.sqrt(2 / 9.81)
    for _, row in one.iterrows():
        e = row["e"]
        K = next(k for k in range(100) if e ** k < 1e-6)
        assert row["impacts"] == K + 1
        assert (row["releases"], row["sticks"], row["slips"]) == (0, 0, 0)
        assert row["rest_time"] == pytest.approx(t0 + 2 * t0 * e * (1 - e ** K) / (1 - e),
                                                 abs=1e-8)
    subprocess.run([cli, "sweep", "--example", "bouncing_ball", "--grid", "e=0.3:0.7:3",
                    "--t-end", "4", "--jobs", "2", "-o", str(out_dir), "--no-plots"],
                   check=True, capture_output=True)
    from_cli = pd.read_csv(out_dir / "ensemble.csv", keep_default_na=False,
                           na_values=["nan"], float_precision="round_trip")
    for name in ("impacts", "releases", "sticks", "slips", "rest_time"):
        assert np.array_equal(from_cli[name].to_numpy(dtype=float),
                              one[name].to_numpy(dtype=float)), name
    assert "impacts" not in ukdyn.sweep(PENDULUM, grid={"L": [1.0]}, t_end=0.1).columns


def test_command_line_sigint_keeps_the_finished_samples(cli, out_dir):
    # two short samples, then two long ones (the interrupt tests' pendulum over 5e4 s) on one
    # thread: SIGINT stops the third at its next step; the fourth is not run
    import signal
    import time
    long_model = str(ROOT / "tests" / "data" / "interrupt_pendulum.yaml")
    proc = subprocess.Popen([cli, "sweep", long_model, "--grid", "t_end=0.5,1,5e4,5e4",
                             "--jobs", "1", "-o", str(out_dir), "--no-plots"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    # (the first two samples take milliseconds; give the third time to start)
    time.sleep(1.5)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=max(1, deadline - time.monotonic()))
    assert proc.returncode == 130, out + err
    assert "interrupted by SIGINT" in err
    frame = pd.read_csv(out_dir / "ensemble.csv", keep_default_na=False, na_values=["nan"])
    assert list(frame["status"]) == ["ok", "ok", "interrupted", "not run"]
    assert list(frame["t_reached"][:2]) == [0.5, 1.0]
    assert 0 < frame["t_reached"][2] < 5e4


def test_ctrl_c_raises_interrupted_with_the_finished_samples():
    import os
    import signal
    import threading
    long_model = str(ROOT / "tests" / "data" / "interrupt_pendulum.yaml")
    timer = threading.Timer(1.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(ukdyn.Interrupted) as caught:
            ukdyn.sweep(long_model, grid={"t_end": [0.5, 1.0, 5e4, 5e4]}, workers=1)
    finally:
        timer.cancel()
    frame = caught.value.result
    assert list(frame["status"]) == ["ok", "ok", "interrupted", "not run"]
    assert 0 < frame["t_reached"].iloc[2] < 5e4


@pytest.mark.parametrize("kw, message", [
    (dict(n=-1), "sweep: n=-1: must be a whole number >= 1"),
    (dict(n=2.5), "sweep: n=2.5: must be a whole number >= 1"),
    (dict(n=3, seed=-1), "sweep: seed=-1: must be a whole number >= 0"),
    (dict(n=3, workers=-1), "sweep: workers=-1: must be a whole number >= 0"),
    (dict(n=3, workers=1.5), "sweep: workers=1.5: must be a whole number >= 0"),
])
def test_sweep_refuses_bad_counts_by_name(kw, message):
    """A negative or fractional n or seed: a ValueError naming it (not pybind11's TypeError, not
    truncated to 2)."""
    with pytest.raises(ValueError) as err:
        ukdyn.sweep(PENDULUM, random={"theta0": "uniform(0.01,0.1)"}, **kw)
    assert str(err.value) == message


def test_sweep_refuses_absurd_workers():
    with pytest.raises(ValueError, match=r"sweep: workers=5000: at most 1024 threads"):
        ukdyn.sweep(PENDULUM, random={"theta0": "uniform(0.01,0.1)"}, n=3, workers=5000)


def test_sweep_random_errors_say_what_was_given():
    """The law's numbers as given (not the stand-in 0,1), the form of a short tuple, and no C++
    function names (review 2026-11-27)."""
    with pytest.raises(ValueError) as err:
        ukdyn.sweep(PENDULUM, random={"mu": ("beta", 1, 2)}, n=2)
    assert str(err.value).startswith("sweep: 'mu~beta(1, 2)': unknown law 'beta'")
    with pytest.raises(ValueError) as err:
        ukdyn.sweep(PENDULUM, random={"mu": ("uniform", 1)}, n=2)
    assert str(err.value).startswith("sweep: random['mu'] = ('uniform', 1): give a law and its "
                                     "two numbers, ('uniform', A, B)")
    with pytest.raises(ValueError) as err:
        ukdyn.sweep(PENDULUM, random={"L": ("uniform", 2, 1)}, n=2)
    assert str(err.value) == "sweep: L~uniform(2, 1): the upper bound is below the lower one"
    with pytest.raises(ValueError) as err:
        ukdyn.sweep(PENDULUM, grid={"nosuch": [1, 2]})
    assert str(err.value).startswith("sweep: 'nosuch' is not a parameter, coordinate")
    assert "ukdyn::" not in str(err.value)


# a sweep in a child process that reports, as JSON, what Ctrl-C (SIGINT, sent by the parent once
# the sweep has started) left it with
SWEEP_CHILD = r"""
import json, sys, time, ukdyn
import pandas  # (imported here: its import is not part of the reaction)
model, workers = sys.argv[1], int(sys.argv[2])
print("started", flush=True)
try:
    ukdyn.sweep(model, grid={"t_end": [0.5, 1.0] + [5e4] * 4}, workers=workers)
    print(json.dumps({"finished": True}))
except ukdyn.Interrupted as e:
    print(json.dumps({"caught_at": time.monotonic(), "status": list(e.result["status"]),
                      "t_reached": [float(v) for v in e.result["t_reached"]]}))
"""


@pytest.mark.parametrize("workers, statuses", [
    (2, ["ok", "ok", "interrupted", "interrupted", "not run", "not run"]),
    (4, ["ok", "ok"] + ["interrupted"] * 4),
])
def test_ctrl_c_stops_a_sweep_on_several_threads(workers, statuses):
    """Ctrl-C with two or more workers (issue #29; reproducer py_sweep_ctrl_c.py): the signal is
    looked at on the calling (main) thread, where CPython runs handlers, and stops the samples
    under way at their next step. Two short samples, then four of 5e4 s that no thread finishes
    before the SIGINT at 1.5 s: each thread ran a short one and took a long one."""
    import json
    long_model = str(ROOT / "tests" / "data" / "interrupt_pendulum.yaml")
    returncode, out, err, sent = interrupt_python(["-c", SWEEP_CHILD, long_model, str(workers)],
                                                  1.5)
    assert returncode == 0, err
    report = json.loads(out.splitlines()[-1])
    # within a fraction of a second (20 ms checks plus a step; generous for a loaded machine)
    print(f"workers={workers}: Interrupted {(report['caught_at'] - sent) * 1e3:.0f} ms after SIGINT")
    assert 0.0 < report["caught_at"] - sent < 2.0
    assert report["status"] == statuses
    assert report["t_reached"][:2] == [0.5, 1.0]
    for t, status in zip(report["t_reached"], report["status"]):
        if status == "interrupted":
            assert 0 < t < 5e4


def test_ctrl_c_during_a_dask_sweep_raises_interrupted_with_the_finished_chunks():
    """Ctrl-C while a sweep waits for its Dask chunks (issue #29; reproducer py_dask_ctrl_c.py):
    ukdyn.Interrupted with the whole table, the finished chunks' rows as they ran and the others
    "not run" with the same figures as a threaded sweep's samples not run (no pandas
    IntCastingNaNError). Chunks of one sample: two short ones, then four long ones on two
    workers (a Dask LocalCluster of two processes); SIGINT at 3 s."""
    import os
    import signal
    import threading
    distributed = import_or_missing("distributed", "python3-distributed is not installed")
    long_model = str(ROOT / "tests" / "data" / "interrupt_pendulum.yaml")
    grid = {"t_end": [0.5, 1.0] + [5e4] * 4}
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=50) as cluster, \
            distributed.Client(cluster) as client:
        client.run(lambda: __import__("ukdyn"))  # (the workers ready: the short chunks take ms)
        timer = threading.Timer(3.0, lambda: os.kill(os.getpid(), signal.SIGINT))
        timer.start()
        try:
            with pytest.raises(ukdyn.Interrupted) as caught:
                ukdyn.sweep(long_model, grid=grid, client=client, chunk_size=1)
        finally:
            timer.cancel()
        # the workers' long samples are abandoned with the cluster
    frame = caught.value.result
    assert list(frame["status"]) == ["ok", "ok"] + ["not run"] * 4
    assert list(frame["t_end"]) == grid["t_end"]
    assert list(frame["sample"]) == list(range(6))
    assert list(frame["t_reached"][:2]) == [0.5, 1.0]
    # the rows not run: as a threaded sweep's samples after a stop (integer columns stay integers)
    rest = frame.iloc[2:]
    assert list(rest["status_code"]) == [-2] * 4 and frame["status_code"].dtype == np.int64
    assert list(rest["steps"]) == [0] * 4 and list(rest["evaluations"]) == [0] * 4
    assert not rest["ok"].any() and rest["t_reached"].isna().all()
    assert set(rest["message"]) == {"not run: the ensemble was stopped before this sample"}
