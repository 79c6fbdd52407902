# SPDX-License-Identifier: BSD-3-Clause
"""Every code block of README.md and docs/*.md is run (issue #33 item 4): a ``sh`` block as a
bash script with the built ``ukdyn`` first on PATH, a ``python`` block with the built module, a
``yaml`` block (a model file) by ``ukdyn check``; a ``cpp`` block must be, line by line and in
order, up to whitespace and comments, in a source of examples/ that the suite builds and runs; a
``text`` block is output, not code, and one marked ``<!-- output -->`` must be, line by line,
what the block before it prints; a block after ``<!-- file: NAME -->`` is saved as NAME (and
checked when a model file) for the blocks after it. A block that cannot run alone (a part of a
file, a placeholder name, a build or an install) is marked by the comment
``<!-- fragment: NAME -->`` on the line before it and listed by that name in FRAGMENTS below,
with why; an unlisted fragment, a listed one that is gone, or a block of another language fails.
The blocks run in one scratch directory per document, in order, with examples/ and tests/data/
beside them (a block may use what an earlier one wrote)."""

import os
import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
DOCUMENTS = ["README.md"] + sorted(str(p.relative_to(ROOT)) for p in (ROOT / "docs").glob("*.md"))

# (document, name): why the block does not run alone
FRAGMENTS = {
    ("README.md", "setup"): "installs packages and builds everything (minutes): scripts/setup.sh",
    ("README.md", "simulation"): "C++ statements without a program around them",
    ("README.md", "build-install"): "the build, the whole suite, an install and the package",
    ("README.md", "contributing"): "the build, the suite, fuzzing and CI (an hour)",
    ("docs/ensembles.md", "dask-cluster"): "starts a Dask scheduler and workers on other nodes",
    ("docs/ensembles.md", "dask-client"): "needs that cluster",
    ("docs/install.md", "install"): "installs into /opt (tested by package.consumer)",
    ("docs/install.md", "consumer-cmake"): "a consumer's CMakeLists.txt (tests/consumer, package.consumer)",
    ("docs/install.md", "consumer-build"): "builds that consumer (package.consumer)",
    ("docs/install.md", "static-cmake"): "two lines of a consumer's CMakeLists.txt",
    ("docs/install.md", "deb"): "builds and installs the .deb (package.deb)",
    ("docs/install.md", "venv"): "a pip install of the source tree (a build, minutes)",
    ("docs/contact.md", "constraint"): "the constraints: entry alone",
    ("docs/contact.md", "cpp"): "C++ statements without a program around them",
    ("docs/contact.md", "visual"): "the visual: section alone",
    ("docs/contact.md", "contacts"): "the contacts: section alone",
    ("docs/linearize.md", "python"): "cart.yaml, model and guess stand for the reader's",
    ("docs/linearize.md", "bicycle-sweep"): "bike and straight_run stand for the block before",
    ("docs/model-format.md", "tables"): "the tables: section alone",
    ("docs/model-format.md", "keys"): "every key at once, with [...] for lists",
    ("docs/model-format.md", "control"): "the control: section alone",
    ("docs/model-format.md", "bodies"): "every kind of body, joint and force at once",
    ("docs/multibody.md", "cpp"): "C++ statements without a program around them",
    ("docs/python.md", "venv"): "a pip install of the source tree (a build, minutes)",
    ("docs/python.md", "interrupt"): "model.yaml stands for the reader's; runs until Ctrl-C",
    ("docs/reliability.md", "rerun"): "re-runs every reproducer (10 minutes)",
    ("docs/robots.md", "cpp"): "C++ statements without a program around them",
    ("docs/robots.md", "held-arm"): "a model of links (thigh, shin) that panda_arm.urdf lacks",
    ("docs/robots.md", "pose"): "the control: section alone",
    ("docs/viewer.md", "bodies"): "the bodies: section alone",
    ("docs/viewer.md", "points"): "the visual: section alone",
    ("docs/viewer.md", "frames"): "the visual: section alone",
}

FENCE = re.compile(r"^(\s*)(`{3,}|~{3,})\s*([^`\s]*)\s*$")
MARK = re.compile(r"^<!--\s*fragment:\s*([\w.-]+)\s*-->$")
FILE = re.compile(r"^<!--\s*file:\s*([\w.-]+)\s*-->$")
OUTPUT = "<!-- output -->"


def blocks(document):
    """(line, language, text, mark) of each fenced block, in order; mark: the fragment's name,
    OUTPUT, ("file", NAME) for a block to be saved as NAME, or None."""
    lines = (ROOT / document).read_text(encoding="utf-8").splitlines()
    out, i = [], 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, fence, language = m.group(1), m.group(2), m.group(3)
        before = next((lines[k].strip() for k in range(i - 1, -1, -1) if lines[k].strip()), "")
        mark, file = MARK.match(before), FILE.match(before)
        j = i + 1
        while j < len(lines) and lines[j].strip() != fence:
            j += 1
        text = "\n".join(line[len(indent):] if line.startswith(indent) else line
                         for line in lines[i + 1:j])
        out.append((i + 1, language, text + "\n",
                    mark.group(1) if mark else ("file", file.group(1)) if file
                    else OUTPUT if before == OUTPUT else None))
        i = j + 1
    return out


def _plain(code):
    """C++ without comments and whitespace."""
    code = re.sub(r"//[^\n]*", "", code)
    return re.sub(r"\s+", "", code)


def _shown_in(block, source):
    """Whether each line of the C++ block is, without comments and whitespace, in the source,
    in the block's order (the source may hold more: includes, printing)."""
    text, at = _plain(source), 0
    for line in block.splitlines():
        piece = _plain(line)
        if not piece:
            continue
        at = text.find(piece, at)
        if at < 0:
            return False
        at += len(piece)
    return True


def test_every_block_is_of_a_known_language_and_every_fragment_is_listed():
    marked, unknown = set(), []
    for document in DOCUMENTS:
        for line, language, _, fragment in blocks(document):
            if fragment == OUTPUT:
                assert language == "text", f"{document}:{line}: an output block is ```text"
            elif isinstance(fragment, tuple):
                pass
            elif fragment:
                marked.add((document, fragment))
            elif language not in ("sh", "bash", "python", "yaml", "cpp", "text"):
                unknown.append(f"{document}:{line}: ```{language}")
    assert not unknown, "blocks of no known language (mark them ```text or as a fragment): " \
        + ", ".join(unknown)
    assert marked - set(FRAGMENTS) == set(), "fragments not listed in FRAGMENTS"
    assert set(FRAGMENTS) - marked == set(), "listed fragments that the docs no longer mark"


@pytest.fixture(scope="module")
def environment(cli, tmp_path_factory):
    """PATH with the built ukdyn first, the built module on PYTHONPATH, matplotlib off-screen;
    the command's plots skipped (a python it cannot find: a warning, exit 0) — they take seconds
    each, and test_plotting.py tests them."""
    env = dict(os.environ)
    env["PATH"] = str(pathlib.Path(cli).resolve().parent) + os.pathsep + env.get("PATH", "")
    env["PYTHONPATH"] = os.pathsep.join(p for p in sys.path if p)
    env["MPLBACKEND"] = "Agg"
    env["UKDYN_PYTHON"] = "/nonexistent/python3"
    return env


def _scratch(tmp_path_factory, document):
    work = tmp_path_factory.mktemp(pathlib.Path(document).stem)
    (work / "examples").symlink_to(ROOT / "examples")
    (work / "tests").mkdir()
    (work / "tests" / "data").symlink_to(ROOT / "tests" / "data")
    return work


@pytest.mark.parametrize("document", DOCUMENTS)
def test_the_blocks_of_a_document_run(document, environment, tmp_path_factory):
    work = _scratch(tmp_path_factory, document)
    failures = []
    printed = ""  # what the last block run printed
    for line, language, text, fragment in blocks(document):
        where = f"{document}:{line}"
        if fragment == OUTPUT:
            # an output the docs show is what the block before it prints, line by line
            said = " ".join(printed.split())
            for shown in text.splitlines():
                if shown.strip() and " ".join(shown.split()) not in said:
                    failures.append(f"{where}: the block before it does not print {shown!r}")
            continue
        saved = fragment[1] if isinstance(fragment, tuple) else None
        if (fragment and not saved) or language == "text":
            continue
        if language in ("sh", "bash"):
            command = ["bash", "-euo", "pipefail", "-c", text]
        elif language == "python":
            command = [sys.executable, "-c", text]
        elif saved:
            # a file the reader saves (<!-- file: NAME -->); a model file is checked
            (work / saved).write_text(text, encoding="utf-8")
            if language != "yaml":
                continue
            command = ["ukdyn", "check", saved]
        elif language == "yaml":
            path = work / f"block_{line}.yaml"
            path.write_text(text, encoding="utf-8")
            command = ["ukdyn", "check", str(path)]
        elif language == "cpp":
            sources = [p.read_text(encoding="utf-8") for p in (ROOT / "examples").rglob("*.cpp")]
            if not any(_shown_in(text, s) for s in sources):
                failures.append(f"{where}: the C++ block is in no source of examples/")
            continue
        else:
            continue
        proc = subprocess.run(command, cwd=work, env=environment, capture_output=True,
                              text=True, timeout=120)
        printed = proc.stdout + proc.stderr
        if proc.returncode != 0:
            failures.append(f"{where} (```{language}, exit {proc.returncode}):\n"
                            f"{proc.stdout[-1500:]}{proc.stderr[-1500:]}")
    assert not failures, "\n\n".join(failures)
