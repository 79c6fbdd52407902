# SPDX-License-Identifier: BSD-3-Clause
"""Shared fixtures of the Python tests (run by CTest as python.pytest; see python/CMakeLists.txt).

Environment (set by CTest): PYTHONPATH (the built package), UKDYN_CLI (the ukdyn command),
UKDYN_EXAMPLES_DIR (examples/models), UKDYN_TEST_OUTPUT (a scratch directory).
"""

import os
import pathlib
import shutil
import signal
import subprocess
import sys
import time

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def examples_dir() -> pathlib.Path:
    """examples/models of the source tree."""
    return pathlib.Path(os.environ.get("UKDYN_EXAMPLES_DIR", ROOT / "examples" / "models"))


@pytest.fixture(scope="session")
def testdata_dir() -> pathlib.Path:
    """app/testdata: the command's malformed and inconsistent models."""
    return ROOT / "app" / "testdata"


@pytest.fixture(scope="session")
def cli() -> str:
    """The ukdyn command (UKDYN_CLI, or build/app/ukdyn)."""
    path = os.environ.get("UKDYN_CLI") or str(ROOT / "build" / "app" / "ukdyn")
    if not os.access(path, os.X_OK):
        pytest.skip(f"the ukdyn command is not built ({path})")
    return path


@pytest.fixture()
def out_dir(tmp_path: pathlib.Path) -> pathlib.Path:
    """A fresh scratch directory."""
    return tmp_path


def missing_dependency(reason: str) -> None:
    """A test whose Debian package is missing: skipped on a developer's machine, failed under CI
    (CI=true), whose set-up (scripts/install-deps.sh) installs every dependency — a skip there
    would hide a missing install step."""
    if os.environ.get("CI") == "true":
        pytest.fail(reason + " (CI=true: scripts/install-deps.sh should have installed it)")
    pytest.skip(reason)


def import_or_missing(module: str, reason: str):
    """The module, or missing_dependency(reason)."""
    import importlib
    try:
        return importlib.import_module(module)
    except ImportError:
        missing_dependency(reason)


def interrupt_python(argv, delay: float):
    """Runs Python with `argv`, waits for its line "started", sends SIGINT `delay` s later →
    (return code, the rest of stdout, stderr, the monotonic time of the SIGINT)."""
    child = subprocess.Popen(
        [sys.executable] + list(argv), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        # SIGINT at its default in the child (the test runner may ignore it), so that Python
        # installs its own handler there, as in an interactive session
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        assert child.stdout.readline().strip() == "started", child.stderr.read()
        time.sleep(delay)  # the run is well under way
        sent = time.monotonic()
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=120)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    return child.returncode, out, err, sent
