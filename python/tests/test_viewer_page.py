# SPDX-License-Identifier: BSD-3-Clause
"""The command writes the viewer page itself (issue #33 item 2): the page of ``ukdyn run`` is
the page that Python's viewer (python/ukdyn/viewer.py) writes from the same trajectory, byte for
byte; its data is Result.save_animation()'s; no Python process is needed; hostile names stay
data; a page that cannot be written makes the exit code 1. (The pages are drawn in headless
Chromium by test_viewer.py.)"""

import json
import os
import pathlib
import subprocess

import pytest

import ukdyn
from test_viewer import hostile_model
from ukdyn import viewer

OPENING = '<script type="application/json" id="ukdyn-data">'


def _page_data(html: str):
    start = html.index(OPENING) + len(OPENING)
    return json.loads(html[start:html.index("</script>", start)])


def _run(cli, args, out, env=None):
    proc = subprocess.run([cli, "run", *args, "-o", str(out), "--no-plots", "--viewer"],
                          capture_output=True, text=True, timeout=180, env=env)
    return proc


def _python_page(model_path: pathlib.Path, csv: pathlib.Path) -> str:
    """viewer.py's page of the command's trajectory.csv, with the model's scene."""
    scene = json.loads(ukdyn.load(model_path)._scene_json)
    names, columns = viewer.read_csv(csv)
    events = viewer.read_contact_events(csv.parent / "summary.json")
    return viewer.build_page(scene, names, columns, contact_events=events)


@pytest.mark.parametrize("example, t_end", [
    ("pendulum", "3"),                      # visual points carrying Qc_ideal
    ("double_four_bar_bodies", "1"),        # planar bodies, joints' reactions
    ("heavy_top", "2"),                     # a rigid body (quaternion)
    ("slider_crank_coulomb", "1"),          # Coulomb friction: the non-ideal reactions
    ("control_triple_pendulum_tip", "3"),   # requirements, a desired path
    ("bouncing_ball", "2"),                 # a contact: its force and impacts
    ("ladder_leaves_wall", "0.8"),          # two contacts, one released
])
def test_the_commands_page_is_pythons_byte_for_byte(cli, examples_dir, tmp_path, example, t_end):
    out = tmp_path / "run"
    proc = _run(cli, ["--example", example, "--t-end", t_end], out)
    assert proc.returncode == 0, proc.stderr
    page = (out / "animation.html").read_text(encoding="utf-8")
    expected = _python_page(examples_dir / (example + ".yaml"), out / "trajectory.csv")
    assert len(page) > 100000  # three.js is in it
    if page != expected:  # the first difference, readably
        a, b = _page_data(page), _page_data(expected)
        assert a == b
        assert page == expected


def test_the_commands_data_is_save_animations(cli, examples_dir, tmp_path):
    """The same run made by Python (Model.simulate, Result.save_animation): the same data."""
    out = tmp_path / "run"
    proc = _run(cli, ["--example", "double_four_bar_bodies", "--t-end", "1"], out)
    assert proc.returncode == 0, proc.stderr
    model = ukdyn.load(examples_dir / "double_four_bar_bodies.yaml")
    model.simulate(t_end=1.0).save_animation(tmp_path / "python.html")
    ours = _page_data((out / "animation.html").read_text(encoding="utf-8"))
    theirs = _page_data((tmp_path / "python.html").read_text(encoding="utf-8"))
    assert len(ours["t"]) == 31
    assert ours == theirs


def test_the_commands_impacts_are_save_animations(cli, examples_dir, tmp_path):
    """A run with contacts made by Python (Result.save_animation, its stats' contact events):
    the same contacts and impacts as the command's page (from its summary.json)."""
    out = tmp_path / "run"
    proc = _run(cli, ["--example", "bouncing_ball"], out)
    assert proc.returncode == 0, proc.stderr
    ukdyn.load(examples_dir / "bouncing_ball.yaml").simulate().save_animation(
        tmp_path / "python.html")
    ours = _page_data((out / "animation.html").read_text(encoding="utf-8"))
    theirs = _page_data((tmp_path / "python.html").read_text(encoding="utf-8"))
    assert len(ours["impacts"]) > 10
    assert ours["impacts"] == theirs["impacts"]
    assert ours["contacts"] == theirs["contacts"]


def test_three_js_without_libjs_three(monkeypatch, tmp_path):
    """A pip or venv install on a machine without Debian's libjs-three: save_animation falls back
    to the copy of it the extension embedded at build time, and the page is the one made with
    libjs-three, byte for byte: three.js is Debian's file, and so is each loader."""
    debian = pathlib.Path(viewer.DEBIAN_THREE)
    result = ukdyn.load("pendulum").simulate(t_end=0.5)
    result.save_animation(tmp_path / "debian.html")
    monkeypatch.setattr(viewer, "DEBIAN_THREE", str(tmp_path / "no-libjs-three"))
    result.save_animation(tmp_path / "embedded.html")
    page = (tmp_path / "embedded.html").read_bytes()
    three = (debian / "three.min.js").read_bytes().replace(b"</script", b"<\\/script")
    assert len(three) > 100000
    assert three in page
    assert page == (tmp_path / "debian.html").read_bytes()
    # each file as embedded is the Debian file's bytes
    from ukdyn import _ukdyn
    for name, folder in [("three.min.js", ""), ("OrbitControls.js", "examples/js/controls"),
                         ("STLLoader.js", "examples/js/loaders"),
                         ("OBJLoader.js", "examples/js/loaders"),
                         ("ColladaLoader.js", "examples/js/loaders")]:
        assert _ukdyn._viewer_script(name) == (debian / folder / name).read_bytes(), name
    assert _ukdyn._viewer_script("GLTFLoader.js") is None
    # without the embedded copy either, the error names the file
    monkeypatch.setattr(viewer, "_embedded_script", lambda name: None)
    with pytest.raises(FileNotFoundError, match="three.min.js not found"):
        result.save_animation(tmp_path / "none.html")


def test_no_python_is_run(cli, tmp_path):
    """With no python3 to be found (UKDYN_PYTHON names none, PATH is empty) the page is still
    written, and the same."""
    env = dict(os.environ, UKDYN_PYTHON=str(tmp_path / "no-python"), PATH="")
    out = tmp_path / "run"
    proc = _run(cli, ["--example", "pendulum", "--t-end", "1"], out, env)
    assert proc.returncode == 0, proc.stderr
    assert "python" not in proc.stderr
    page = (out / "animation.html").read_text(encoding="utf-8")
    proc = _run(cli, ["--example", "pendulum", "--t-end", "1"], tmp_path / "again")
    assert page == (tmp_path / "again" / "animation.html").read_text(encoding="utf-8")


@pytest.mark.parametrize("model_name, point", [
    ("x<!--<script>y", "bob"), ("</script><script>window.__pwned=1</script>", "__proto__"),
    ("/*UKDYN_DATA*/null \u2028 & é", "constructor")])
def test_hostile_names_stay_data(cli, tmp_path, model_name, point):
    """A model's and a point's names reach the command's page only as JSON strings: no <, >, &
    or U+2028 in the data element, the title escaped, the names read back as given."""
    path = tmp_path / "hostile.yaml"
    path.write_text(hostile_model(model_name, point), encoding="utf-8")
    out = tmp_path / "run"
    proc = _run(cli, [str(path), "--t-end", "0.5"], out)
    assert proc.returncode == 0, proc.stderr
    html = (out / "animation.html").read_text(encoding="utf-8")
    start = html.index(OPENING) + len(OPENING)
    payload = html[start:html.index("</script>", start)]
    assert not set("<>&\u2028\u2029") & set(payload)
    data = _page_data(html)
    assert data["model"] == model_name
    assert [p["name"] for p in data["points"]] == ["pivot", point]
    assert html.count(OPENING) == 1
    title = html[html.index("<title>") + 7:html.index("</title>")]
    assert "<" not in title and title.startswith("ukdyn: ")
    assert html == _python_page(path, out / "trajectory.csv")


def _limit_file_size():
    """In the child: files end at 200 kB (write fails with EFBIG, SIGXFSZ ignored)."""
    import resource
    import signal
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (200000, 200000))


def test_a_page_that_cannot_be_written_is_exit_1(cli, tmp_path):
    """A page that cannot be written whole (files limited to 200 kB, less than three.js) is a
    missing output: the command says so and exits 1, leaves no page and no temporary, and keeps
    the other files."""
    out = tmp_path / "run"
    proc = subprocess.run([cli, "run", "--example", "pendulum", "--t-end", "0.5", "-o", str(out),
                           "--no-plots", "--viewer"], capture_output=True, text=True,
                          timeout=180, preexec_fn=_limit_file_size)
    assert proc.returncode == 1, proc.stderr
    assert "error: the viewer's page: " in proc.stderr
    assert "File too large: no animation.html" in proc.stderr
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".ukdyn")) == \
        ["summary.json", "trajectory.csv"]
