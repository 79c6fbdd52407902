# SPDX-License-Identifier: BSD-3-Clause
"""The browser viewer (docs/viewer.md) in a real browser: headless Chromium through Selenium
(Debian's chromium, chromium-driver, python3-selenium), software-rendered WebGL (SwiftShader).

What is checked comes from analysis, not from the page: the pendulum's bob is drawn where the
perspective projection of (L sin θ, −L cos θ) falls (the camera read from the page, the
projection done here); every body of a mechanism shows in its own colour; moving the slider moves
the drawing; turning the force arrows off removes their colour. Screenshots of the gallery's
spatial examples are kept in $UKDYN_TEST_OUTPUT/viewer/ (CI's artefacts).
"""

import base64
import io
import math
import os
import pathlib
import shutil
import subprocess
import time

import numpy as np
import pytest

import ukdyn
from conftest import import_or_missing, missing_dependency

CHROMEDRIVER = "/usr/bin/chromedriver"


def _artefacts() -> pathlib.Path:
    base = os.environ.get("UKDYN_TEST_OUTPUT")
    root = pathlib.Path(base) if base else pathlib.Path(__file__).resolve().parents[2] / "build"
    path = root / "viewer"
    path.mkdir(parents=True, exist_ok=True)
    return path


@pytest.fixture(scope="module")
def browser():
    """Headless Chromium (as root in CI: --no-sandbox), 900 × 600, WebGL by SwiftShader."""
    webdriver = import_or_missing("selenium.webdriver", "python3-selenium is not installed")
    from selenium.webdriver.chrome.service import Service
    if not os.access(CHROMEDRIVER, os.X_OK) or not shutil.which("chromium"):
        missing_dependency("chromium and chromium-driver are not installed (scripts/install-deps.sh)")
    options = webdriver.ChromeOptions()
    for a in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--use-gl=swiftshader",
              "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--window-size=900,700",
              "--force-device-scale-factor=1"):
        options.add_argument(a)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    yield driver
    driver.quit()


class Page:
    """A viewer page open in the browser."""

    def __init__(self, driver, path: pathlib.Path) -> None:
        self.driver = driver
        driver.get_log("browser")  # drop what earlier pages said
        driver.get(path.resolve().as_uri())
        for _ in range(100):
            if driver.execute_script("return !!(window.ukdyn && window.ukdyn.ready)"):
                break
            time.sleep(0.05)
        assert driver.execute_script("return !!(window.ukdyn && window.ukdyn.ready)"), \
            "the viewer did not start: %s" % driver.get_log("browser")

    def errors(self):
        return [e for e in self.driver.get_log("browser") if e["level"] == "SEVERE"]

    def js(self, code, *args):
        return self.driver.execute_script(code, *args)

    def pixels(self) -> np.ndarray:
        """The canvas as an H × W × 3 array of 0..255. A canvas read back wholly black (its
        drawing buffer empty: headless Chromium's WebGL, once in a fresh-clone CI run under
        load, gave one for a page whose scene checks had all passed) is rendered and read again,
        up to three times; a page that draws nothing stays black and fails its test."""
        from PIL import Image
        for attempt in range(4):
            url = self.js("return ukdyn.snapshot()")
            image = Image.open(io.BytesIO(base64.b64decode(url.split(",", 1)[1]))).convert("RGB")
            img = np.asarray(image).astype(int)
            if img.any():
                return img
            time.sleep(0.5)
        return img

    def save(self, name: str) -> pathlib.Path:
        path = _artefacts() / name
        self.driver.save_screenshot(str(path))
        return path


def _mask(img: np.ndarray, hex_colour: str, tolerance: float = 0.06) -> np.ndarray:
    """Pixels of the colour's chromaticity (its shade under the lights may differ), saturated."""
    target = np.array([int(hex_colour[i:i + 2], 16) for i in (1, 3, 5)], float)
    total = img.sum(axis=2)
    chroma = img / np.maximum(total, 1)[..., None]
    want = target / max(target.sum(), 1)
    spread = img.max(axis=2) - img.min(axis=2)
    return (np.abs(chroma - want).max(axis=2) < tolerance) & (spread > 35)


def _project(camera, point):
    """The pixel of a world point for the page's perspective camera (computed here: the camera
    looks from `position` at `target` with the `up` vector and vertical field of view `fov`)."""
    eye, target, up = (np.array(camera[k], float) for k in ("position", "target", "up"))
    forward = target - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    d = np.array(point, float) - eye
    depth = d @ forward
    focal = camera["height"] / 2 / math.tan(math.radians(camera["fov"]) / 2)
    return (camera["width"] / 2 + focal * (d @ right) / depth,
            camera["height"] / 2 - focal * (d @ true_up) / depth)


@pytest.fixture(scope="module")
def pendulum_page(tmp_path_factory):
    """The pendulum example (its visual: bob at (x, y)), 1.2 s."""
    result = ukdyn.load("pendulum").simulate(t_end=1.2)
    path = tmp_path_factory.mktemp("viewer") / "pendulum.html"
    result.save_animation(path)
    return result, path


def test_pendulum_bob_is_drawn_where_the_projection_says(browser, pendulum_page):
    result, path = pendulum_page
    page = Page(browser, path)
    page.js("ukdyn.show('trails', false); ukdyn.show('ideal', false)")
    camera = page.js("return ukdyn.camera()")
    t_page = page.js("return ukdyn.data.t")
    L = 1.0
    for frame in (0, len(t_page) // 3, 2 * len(t_page) // 3, len(t_page) - 1):
        page.js("ukdyn.setFrame(arguments[0])", frame)
        # the angle at the frame's time, from the run (theta = atan2(x, -y))
        theta = float(np.interp(t_page[frame], result.t, result["theta"]))
        expected = _project(camera, (L * math.sin(theta), -L * math.cos(theta), 0.0))
        mask = _mask(page.pixels(), "#d62728")
        assert mask.sum() > 50, "the bob is not drawn at frame %d" % frame
        ys, xs = np.nonzero(mask)
        assert abs(xs.mean() - expected[0]) < 3 and abs(ys.mean() - expected[1]) < 3, \
            (frame, theta, (xs.mean(), ys.mean()), expected)
    assert page.errors() == []


def test_toggling_the_force_arrows_changes_the_picture(browser, pendulum_page):
    _, path = pendulum_page
    page = Page(browser, path)
    page.js("ukdyn.setFrame(10)")
    with_arrows = page.pixels()
    arrow = _mask(with_arrows, "#e6007e").sum()
    page.js("ukdyn.show('ideal', false)")
    without = page.pixels()
    assert arrow > 30  # the rod's tension, drawn at the bob
    assert _mask(without, "#e6007e").sum() < 0.05 * arrow
    assert (np.abs(with_arrows - without).sum(axis=2) > 30).sum() > 30
    page.js("ukdyn.show('ideal', true)")
    assert _mask(page.pixels(), "#e6007e").sum() == arrow
    assert page.errors() == []


def test_friction_arrows_are_the_non_ideal_colour_and_toggle(browser, tmp_path):
    """four_bar_coulomb: the rocker's Coulomb friction is a non-ideal force at C (its
    coordinates xC, yC), drawn in the non-ideal colour and turned off by its own check box,
    apart from the ideal arrows."""
    result = ukdyn.load("four_bar_coulomb").simulate(t_end=0.5)
    assert np.max(np.abs(result["Qc_nonideal.xC"])) > 0
    path = tmp_path / "four_bar_coulomb.html"
    result.save_animation(path)
    page = Page(browser, path)
    # the frame of the largest friction force
    force = np.array(page.js("return ukdyn.data.points.find((p) => p.name === 'C').nonideal"))
    page.js("ukdyn.setFrame(arguments[0])", int(np.argmax(np.hypot(force[0], force[1]))))
    both = page.pixels()
    nonideal, ideal = _mask(both, "#ff2a00").sum(), _mask(both, "#e6007e").sum()
    assert nonideal > 30 and ideal > 30, (nonideal, ideal)
    page.js("ukdyn.show('nonideal', false)")
    only_ideal = page.pixels()
    assert _mask(only_ideal, "#ff2a00").sum() < 0.05 * nonideal
    assert _mask(only_ideal, "#e6007e").sum() > 0.8 * ideal  # the ideal arrows stay
    page.save("four_bar_coulomb.png")
    assert page.errors() == []


# the body colours of the page (viewer_template.html PALETTE), in body order
PALETTE = ["#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#bcbd22", "#17becf"]


def test_command_draws_every_body_and_the_slider_moves_them(browser, cli, tmp_path):
    """ukdyn run writes animation.html by default for a model with bodies: the five bars of the
    double four-bar show in five colours (and no sixth), and the slider moves them."""
    out = tmp_path / "four_bar"
    proc = subprocess.run([cli, "run", "--example", "double_four_bar_bodies", "--t-end", "1",
                           "-o", str(out), "--no-plots"], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "animation.html" in proc.stdout
    page = Page(browser, out / "animation.html")
    first = page.pixels()
    counts = [int(_mask(first, c).sum()) for c in PALETTE]
    assert all(c > 100 for c in counts[:5]), counts
    assert all(c < 5 for c in counts[5:]), counts
    page.save("double_four_bar_bodies.png")
    frames = page.js("return ukdyn.frames")
    assert frames == 31  # 1 s at 30 frames per second, both ends
    page.js("ukdyn.setFrame(arguments[0])", frames - 1)
    last = page.pixels()
    # each body moved: its colour left some of the pixels it covered
    for c in PALETTE[:5]:
        before, after = _mask(first, c), _mask(last, c)
        assert (before & ~after).sum() > 20, c
    assert page.errors() == []


@pytest.mark.parametrize("example, flags, written", [
    ("pendulum", [], True),                   # a visual: section: on by default
    ("control_duffing", [], False),           # coordinates without visual: off by default
    ("control_duffing", ["--viewer"], True),  # asked for: the requirement's error chart
])
def test_viewer_default_and_flag(cli, tmp_path, example, flags, written):
    out = tmp_path / "run"
    proc = subprocess.run([cli, "run", "--example", example, "--t-end", "0.2", "-o", str(out),
                           "--no-plots", *flags], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert (out / "animation.html").exists() == written
    assert ("wrote %s" % (out / "animation.html") in proc.stdout) == written
    assert "warning" not in proc.stderr


def test_no_viewer_flag(cli, tmp_path):
    out = tmp_path / "none"
    proc = subprocess.run([cli, "run", "--example", "double_four_bar_bodies", "--t-end", "0.05",
                           "-o", str(out), "--no-plots", "--no-viewer"], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert not (out / "animation.html").exists()


@pytest.mark.parametrize("example, t_end", [("heavy_top", 1.0), ("rolling_disk_bodies", 1.0),
                                            ("bricard", 0.5), ("spherical_pendulum", 1.0),
                                            ("double_pendulum", 1.0), ("chaplygin_sleigh", 10.0),
                                            ("bead_on_rotating_wire", 2.0),
                                            ("control_triple_pendulum_tip", 3.0)])
def test_gallery_screenshots(browser, tmp_path, example, t_end):
    """The gallery's spatial (and two planar) examples draw without errors; screenshots kept."""
    result = ukdyn.load(example).simulate(t_end=t_end)
    path = tmp_path / (example + ".html")
    result.save_animation(path)
    assert path.stat().st_size < 2_000_000
    page = Page(browser, path)
    page.js("ukdyn.setFrame(ukdyn.frames - 1)")
    img = page.pixels()
    coloured = (img.max(axis=2) - img.min(axis=2) > 60).sum()
    assert coloured > 200, "nothing coloured drawn"
    page.save(example + ".png")
    assert page.errors() == []


def test_frame_axes_turn_with_the_angle(browser, tmp_path):
    """A visual: frame is drawn as three axes: its x axis (red) points along the angle."""
    result = ukdyn.parse(
        "coordinates: [th]\nkinetic_energy: th_dot^2/2\ninitial: {q_dot: {th: 1}}\n"
        "simulate: {t_end: 3}\noutput: {every: 0.01}\n"
        "visual: {points: {o: [0, 0], far: [1, 1]}, frames: {f: {at: [0, 0], angle: th, size: 1}}}\n",
        "frame.yaml").simulate()
    path = tmp_path / "frame.html"
    result.save_animation(path)
    page = Page(browser, path)
    camera = page.js("return ukdyn.camera()")
    t_page = page.js("return ukdyn.data.t")
    for frame in (0, len(t_page) // 2):
        page.js("ukdyn.setFrame(arguments[0])", frame)
        th = t_page[frame]  # th = t
        red = _mask(page.pixels(), "#cc0000", tolerance=0.1)
        ys, xs = np.nonzero(red)
        assert red.sum() > 20
        # the red pixels lie along the projected x axis (cos th, sin th): their mean is on it
        # (the arrow's head weighs more than its shaft, so not at the middle)
        o = np.array(_project(camera, (0.0, 0.0, 0.0)))
        tip = np.array(_project(camera, (math.cos(th), math.sin(th), 0.0))) - o
        c = np.array([xs.mean(), ys.mean()]) - o
        along = c @ tip / (tip @ tip)
        across = abs(c[0] * tip[1] - c[1] * tip[0]) / np.linalg.norm(tip)
        assert 0.3 < along < 1.0 and across < 3, (frame, th, along, across)
    assert page.errors() == []


def _chain(bodies: int) -> str:
    """A planar chain of `bodies` bars (a pendulum of many links)."""
    lines = ["name: chain of %d bars" % bodies, "parameters: {m: 1, L: 0.5, g: 9.81}", "bodies:"]
    for k in range(bodies):
        lines.append("  - {name: b%d, type: planar, mass: m, inertia: m*L^2/12, position: [%g*L, 0]}"
                     % (k, k + 0.5))
    lines.append("joints:")
    lines.append("  - {name: j0, type: revolute, parent: ground, child: b0, parent_point: [0, 0], "
                 "child_point: [-L/2, 0]}")
    for k in range(1, bodies):
        lines.append("  - {name: j%d, type: revolute, parent: b%d, child: b%d, parent_point: [L/2, 0],"
                     " child_point: [-L/2, 0]}" % (k, k - 1, k))
    lines += ["forces:", "  - {type: gravity, g: [0, -g]}",
              "simulate: {t_end: 10, integrator: dopri5, rtol: 1e-6, atol: 1e-8}", "output: {every: 0.01}"]
    return "\n".join(lines) + "\n"


def test_ten_bodies_ten_seconds_under_2_mb():
    result = ukdyn.parse(_chain(10), "chain.yaml").simulate()
    html = result.animation_html()
    assert len(html.encode()) < 2_000_000
    # 10 s at 30 frames per simulated second: 301 frames, whatever the run's sample rate
    assert '"t":[0,' in html


def test_declared_solids_and_colours():
    model = ukdyn.parse(
        "name: box\n"
        "bodies:\n"
        "  - {name: b, type: rigid, mass: 1, inertia: [1, 1, 1],\n"
        "     visual: [{shape: box, size: [1, 0.2, 0.1], color: \"#123456\"},\n"
        "              {shape: capsule, radius: 0.1, length: 1, axis: z, offset: [0, 0, 0.5]}]}\n"
        "simulate: {t_end: 0.1}\n", "box.yaml")
    result = model.simulate()
    body = result.scene["bodies"][0]
    assert body["visual"][0] == {"shape": "box", "size": [1, 0.2, 0.1], "offset": [0, 0, 0],
                                 "color": "#123456"}
    assert body["visual"][1]["axis"] == "z" and body["visual"][1]["length"] == 1


@pytest.mark.parametrize("text, line, marker, message", [
    ("bodies:\n  - {name: b, type: particle, mass: 1, visual: {shape: cone, radius: 1}}\n",
     2, "cone", "unknown shape 'cone'"),
    ("bodies:\n  - {name: b, type: particle, mass: 1, visual: {shape: box, color: red}}\n",
     2, "{shape", "a box needs size: [x, y, z]"),
    ("coordinates: [x]\nkinetic_energy: x_dot^2/2\nvisual:\n  points: {p: [x, 0]}\n"
     "  links: [[p, q]]\n", 5, "q]", "the link names 'q', which is not a point"),
    ("coordinates: [x]\nkinetic_energy: x_dot^2/2\nvisual:\n  points: {p: [x, 0]}\n"
     "  trails: [r]\n", 5, "r]", "the trail names 'r', which is not a point"),
    ("coordinates: [x]\nkinetic_energy: x_dot^2/2\nvisual:\n  points: {p: {at: [x, 0], color: teal}}\n",
     4, "teal", "unknown colour 'teal'"),
])
def test_visual_errors_are_located(text, line, marker, message):
    """Errors in visual: name the file, line and column of the entry at fault."""
    with pytest.raises(ukdyn.ModelError) as e:
        ukdyn.parse(text, "t.yaml")
    column = text.splitlines()[line - 1].index(marker) + 1
    assert str(e.value).startswith("t.yaml:%d:%d: error: " % (line, column)), str(e.value)
    assert message in str(e.value), str(e.value)


def test_unquoted_hash_colour_is_explained():
    """color: #f00 is a YAML comment: the value is empty, and the hint says to quote it."""
    with pytest.raises(ukdyn.ModelError, match=r"t\.yaml:5:21: error: .*the colour is empty "
                                               r"\(hint: color: \"#d62728\" \(quoted"):
        ukdyn.parse("coordinates: [x]\nkinetic_energy: x_dot^2/2\nvisual:\n"
                    "  points:\n    p: {at: [x, 0], color: #f00\n      }\n", "t.yaml")


def test_nothing_to_draw_is_said():
    """A model in coordinates without visual: has nothing to draw: show() says how to add it."""
    assert ukdyn.load("control_duffing").simulate(t_end=0.1).animation_html()  # its chart
    result = ukdyn.load("incline_friction").simulate(t_end=0.1)
    with pytest.raises(ValueError, match="nothing to draw: the model has no bodies and no visual:"):
        result.show()
    result.scene = None  # e.g. a Result read back from a file
    with pytest.raises(ValueError, match="this result has no scene"):
        result.save_animation("never.html")


PIN_FRICTION = """name: planar pendulum with pin friction
parameters: {m: 1, L: 1, g: 9.81}
bodies:
  - {name: bar, type: planar, mass: m, inertia: m*L^2/12, position: [L/2, 0], angle: 0}
joints:
  - {name: pin, type: revolute, parent: ground, child: bar, parent_point: [0, 0],
     child_point: [-L/2, 0], friction: {mu: 0.3, radius: 0.05}}
forces:
  - {type: gravity, g: [0, -g]}
simulate: {t_end: 1}
output: {every: 0.01}
"""


def test_pin_friction_torque_is_drawn_and_toggles(browser, tmp_path):
    """A revolute joint's friction is a torque (reaction.pin.friction_tz; its friction forces are
    0): the page has a non-ideal check box, and turning it off changes the pixels around the pin
    (at the origin) and removes the non-ideal colour."""
    result = ukdyn.parse(PIN_FRICTION, "pin.yaml").simulate()
    assert np.max(np.abs(result["reaction.pin.friction_tz"])) > 0
    assert np.max(np.abs(result["reaction.pin.friction_fx"])) == 0
    path = tmp_path / "pin.html"
    result.save_animation(path)
    page = Page(browser, path)
    assert page.js("return document.getElementById('show-nonideal').parentNode.style.display") \
        != "none"
    assert "torque" in page.js("return document.getElementById('legend').textContent")
    torque = page.js("return ukdyn.data.joints[0].nonideal_torque")
    assert torque[0] is None or not any(torque[0])  # planar: about z only
    frame = int(np.argmax(np.abs(torque[2])))
    page.js("ukdyn.setFrame(arguments[0])", frame)
    page.js("ukdyn.show('ideal', false)")
    both = page.pixels()
    page.save("pin_friction.png")
    page.js("ukdyn.show('nonideal', false)")
    without = page.pixels()
    camera = page.js("return ukdyn.camera()")
    px, py = _project(camera, (0.0, 0.0, 0.0))
    near = np.zeros(both.shape[:2], bool)
    r = 60
    near[max(0, int(py) - r):int(py) + r, max(0, int(px) - r):int(px) + r] = True
    changed = (np.abs(both - without).sum(axis=2) > 30) & near
    assert changed.sum() > 30, changed.sum()
    assert (_mask(both, "#ff2a00") & near).sum() > 30
    assert _mask(without, "#ff2a00").sum() < 5
    assert page.errors() == []


FLOOR = """name: block on rough floor
parameters: {m: 1, g: 9.81, mu: 0.3, v0: 2}
coordinates: [x, y]
kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)
potential_energy: m*g*y
constraints:
  - {name: floor, holonomic: y}
nonideal:
  - {friction: coulomb, constraint: floor, mu: mu}
initial: {q: {x: 0, y: 0}, q_dot: {x: v0, y: 0}}
simulate: {t_end: 0.5}
output: {every: 0.01}
visual:
  points:
    block: {at: [x, y], color: red, radius: 0.05}
    mark: [x + 0.1, y]
"""


def test_point_on_a_constant_coordinate_has_its_forces(browser, tmp_path):
    """A block on a rough floor (y ≡ 0): the point block: [x, y] is matched to its coordinates by
    the scene, not by its values, so the normal force (ideal, up, m g) and the friction
    (non-ideal, against the motion, μ m g) are drawn there; mark: [x + 0.1, y] has none."""
    result = ukdyn.parse(FLOOR, "floor.yaml").simulate()
    assert np.all(result["y"] == 0)
    points = {p["name"]: p for p in result.scene["points"]}
    assert points["block"]["coordinates"] == ["x", "y"]
    assert points["mark"]["coordinates"] == [None, "y"]
    assert points["mark"]["expressions"] == ["x + 0.1", "y"]
    path = tmp_path / "floor.html"
    result.save_animation(path)
    page = Page(browser, path)
    block = page.js("return ukdyn.data.points.find((p) => p.name === 'block')")
    mark = page.js("return ukdyn.data.points.find((p) => p.name === 'mark')")
    assert "ideal" not in mark and "nonideal" not in mark
    m, g, mu = 1.0, 9.81, 0.3
    assert block["ideal"][1][5] == pytest.approx(m * g, rel=1e-3)
    assert block["nonideal"][0][5] == pytest.approx(-mu * m * g, rel=1e-3)
    page.js("ukdyn.setFrame(5)")
    img = page.pixels()
    assert _mask(img, "#e6007e").sum() > 30 and _mask(img, "#ff2a00").sum() > 30
    page.save("floor.png")
    assert page.errors() == []


GAP_FAR = """name: gap oscillator far from the origin
parameters: {m: 1, k: 100, d: 0.1, v0: 1}
coordinates: [x]
kinetic_energy: 0.5*m*x_dot^2
potential_energy: if(x - d, 0.5*k*(x - d)^2, if(-x - d, 0.5*k*(x + d)^2, 0))
initial: {q: {x: 0}, q_dot: {x: v0}}
simulate: {t_end: 5, rtol: 1e-10, atol: 1e-12}
output: {every: 0.001}
visual:
  points:
    left: {at: [1000 - d, 0], color: grey, radius: 0.02}
    right: {at: [1000 + d, 0], color: grey, radius: 0.02}
    mass: {at: [1000 + x, 0], color: red, radius: 0.03}
"""


def _page_data(html: str):
    """The data of a page: the text of its <script type="application/json"> element."""
    import json
    opening = '<script type="application/json" id="ukdyn-data">'
    start = html.index(opening) + len(opening)
    return json.loads(html[start:html.index("</script>", start)])


def test_positions_are_kept_to_the_scenes_extent(cli, tmp_path):
    """A motion drawn about 1000 m from the origin (1000 + x, |x| ≲ 0.2): the page's positions
    are the CSV's to 1e-4 of the motion's range, not to 4 significant digits (999.8, 999.9)."""
    (tmp_path / "gap_far.yaml").write_text(GAP_FAR)
    out = tmp_path / "run"
    proc = subprocess.run([cli, "run", str(tmp_path / "gap_far.yaml"), "-o", str(out),
                           "--no-plots"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    import csv
    with open(out / "trajectory.csv", newline="") as f:
        rows = list(csv.reader(f))
    names, values = rows[0], np.array(rows[1:], float)
    t, x = values[:, names.index("t")], values[:, names.index("visual.mass.x")]
    span = x.max() - x.min()
    assert 0.2 < span < 0.5, span
    data = _page_data((out / "animation.html").read_text())
    mass = next(p for p in data["points"] if p["name"] == "mass")
    stored = np.array(mass["q"][0], float)
    expected = np.interp(np.array(data["t"], float), t, x)
    assert len(set(mass["q"][0])) > 100
    assert np.max(np.abs(stored - expected)) < 1e-4 * span
    left = next(p for p in data["points"] if p["name"] == "left")
    assert left["q"][0][0] == pytest.approx(999.9, abs=1e-9)


def test_nothing_to_draw_writes_no_page(cli, tmp_path):
    """--viewer for a model in coordinates without visual: (and no control): the command says
    there is nothing to draw, as Result.show() does, and writes no page (the run still succeeds)."""
    (tmp_path / "gap.yaml").write_text(GAP_FAR.split("visual:")[0])
    out = tmp_path / "run"
    proc = subprocess.run([cli, "run", str(tmp_path / "gap.yaml"), "-o", str(out), "--no-plots",
                           "--viewer", "--t-end", "0.1"], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "warning: nothing to draw: the model has no bodies and no visual: section" \
        in proc.stderr
    assert not (out / "animation.html").exists()
    assert (out / "trajectory.csv").exists()


NOT_FINITE = """name: a point that stops being finite
coordinates: [th]
kinetic_energy: th_dot^2/2
initial: {q: {th: 0}, q_dot: {th: 1}}
simulate: {t_end: 1}
output: {every: 0.01}
visual:
  points:
    o: {at: [0, 0], color: grey}
    far: {at: [-2, -1], color: grey}
    p: {at: [log(0.5 - th) + 1, 0.5], color: red, radius: 0.1}
  links: [[o, p]]
  trails: [p]
"""


def test_a_point_not_finite_is_said_and_hidden(browser, cli, tmp_path):
    """p's x is log(0.5 − t) + 1: finite until t = 0.5, then not. The command warns, naming the
    point, the first time and the expression; the page draws p where it is finite and hides it
    (not at 0) after, with no console error."""
    (tmp_path / "nan.yaml").write_text(NOT_FINITE)
    out = tmp_path / "run"
    proc = subprocess.run([cli, "run", str(tmp_path / "nan.yaml"), "-o", str(out), "--no-plots"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    import re
    match = re.search(r"warning: visual point 'p' is not finite from t = ([0-9.e+-]+) "
                      r"\(its expression x: log\(0\.5 - th\) \+ 1\)", proc.stderr)
    assert match, proc.stderr
    assert 0.5 - 1e-9 <= float(match.group(1)) <= 0.51 + 1e-9
    assert "visual point 'o'" not in proc.stderr
    page = Page(browser, out / "animation.html")
    t = np.array(page.js("return ukdyn.data.t"), float)
    camera = page.js("return ukdyn.camera()")
    before = int(np.searchsorted(t, 0.3))
    page.js("ukdyn.setFrame(arguments[0])", before)
    red = _mask(page.pixels(), "#d62728")
    assert red.sum() > 50
    ys, xs = np.nonzero(red)
    expected = _project(camera, (math.log(0.5 - t[before]) + 1, 0.5, 0.0))
    assert abs(xs.mean() - expected[0]) < 4 and abs(ys.mean() - expected[1]) < 4
    page.js("ukdyn.show('trails', false)")
    page.js("ukdyn.setFrame(arguments[0])", len(t) - 1)
    assert _mask(page.pixels(), "#d62728").sum() < 5
    assert page.errors() == []


def test_round_off_torques_draw_nothing():
    """A planar revolute joint's ideal torque about z is 0 up to round-off (1e-14 N m): no arc;
    the Bricard mechanism's hinges carry real ideal torques (a spatial revolute joint resists
    turning about two axes): arcs."""
    from ukdyn import viewer
    for example, t_end, torques in (("double_four_bar_bodies", 1.0, False), ("bricard", 0.5, True)):
        result = ukdyn.load(example).simulate(t_end=t_end)
        data = viewer.scene_data(result.scene, result.names, result._columns)
        assert all(("ideal_torque" in j) == torques for j in data["joints"]), example


def test_a_point_not_finite_warns_in_python():
    """Result.animation_html() says the same as the command, as a RuntimeWarning, and stores
    the point as null (hidden) where it is not finite."""
    result = ukdyn.parse(NOT_FINITE, "nan.yaml").simulate()
    with pytest.warns(RuntimeWarning, match=r"visual point 'p' is not finite from t = 0\.5"):
        html = result.animation_html()
    p = next(q for q in _page_data(html)["points"] if q["name"] == "p")
    t = _page_data(html)["t"]
    assert all((x is None) == (tt > 0.5 + 1e-9) for x, tt in zip(p["q"][0], t) if abs(tt - 0.5) > 0.02)


def _desired_tip(t):
    """control_triple_pendulum_tip's requirement: the tip on the circle (0.8 + 0.3 sin t,
    -2 + 0.3 cos t)."""
    return 0.8 + 0.3 * math.sin(t), -2 + 0.3 * math.cos(t)


def test_a_requirement_on_a_point_draws_its_desired_path(browser, cli, tmp_path):
    """control_triple_pendulum_tip declares no target: the requirement's rows are the point
    tip's coordinates, so the page draws the desired circle (dashed, green, with a ring where the
    tip should be now) and the tip's trail (its actual path); the chart shows each row's desired
    and actual value. The numbers come from the requirement's own formula and the CSV."""
    out = tmp_path / "tip"
    proc = subprocess.run([cli, "run", "--example", "control_triple_pendulum_tip", "--t-end", "3",
                           "-o", str(out), "--no-plots"], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    data = _page_data((out / "animation.html").read_text())
    [path] = data["desired_paths"]
    assert (path["requirement"], path["of"]) == ("tip", "tip")
    assert "tip" in data["trails"]
    t = np.array(data["t"], float)
    want = np.array([_desired_tip(s) for s in t]).T
    assert np.max(np.abs(np.array(path["q"], float) - want)) < 1e-3
    # each row's actual value is the tip's coordinate (desired + error)
    import csv
    with open(out / "trajectory.csv", newline="") as f:
        rows = list(csv.reader(f))
    names, values = rows[0], np.array(rows[1:], float)
    rows_of = {r["name"]: r for r in data["requirements"]}
    for k, axis in enumerate("xy"):
        actual = np.interp(t, values[:, 0], values[:, names.index("visual.tip." + axis)])
        desired = np.array([_desired_tip(s)[k] for s in t])
        row = rows_of["tip.%d" % k]
        assert np.max(np.abs(np.array(row["actual"], float) - actual)) < 1e-3 * (1 + abs(actual).max())
        assert np.max(np.abs(np.array(row["desired"], float) - desired)) < 1e-3
    # the tip starts 0.83 from where the requirement wants it: the ring is drawn at the desired
    # point, not at the tip
    page = Page(browser, out / "animation.html")
    page.js("ukdyn.show('trails', false)")
    camera = page.js("return ukdyn.camera()")
    page.js("ukdyn.setFrame(0)")
    img = page.pixels()
    green = _mask(img, "#00a651")
    ys, xs = np.nonzero(green)
    target = _project(camera, (*_desired_tip(0.0), 0.0))
    tip = _project(camera, (actual_x := float(values[0, names.index("visual.tip.x")]),
                            float(values[0, names.index("visual.tip.y")]), 0.0))
    assert actual_x == pytest.approx(0.8253, abs=1e-3)

    def near(p, r):
        return int(((xs - p[0]) ** 2 + (ys - p[1]) ** 2 < r * r).sum())
    assert near(target, 25) > 60, (near(target, 25), target)
    assert near(tip, 10) == 0
    # the chart of desired and actual values is shown; turning "desired" off removes the green
    assert page.js("return getComputedStyle(document.getElementById('paths')).display") == "block"
    page.js("ukdyn.show('desired', false)")
    assert _mask(page.pixels(), "#00a651").sum() < 0.05 * green.sum()
    page.save("control_triple_pendulum_tip_desired.png")
    assert page.errors() == []


ARM_WITH_TIP = """
visual:
  points:
    tip: [link2_x + L2/2*cos(link2_theta), link2_y + L2/2*sin(link2_theta)]
  trails: [tip]
"""


def test_a_requirement_of_a_bodies_model_draws_its_desired_path(tmp_path):
    """A bodies/joints model under control (tests/data/arm_circle_bodies.yaml, the arm's tip on
    a circle) with a visual point at the tip: the requirement's rows are that point's
    coordinates, and the page draws the circle (cx + R cos Wt, cy + R sin Wt). A requirement on
    joint angles (control_triple_pendulum) is no path in the scene: only the chart."""
    root = pathlib.Path(__file__).resolve().parents[2]
    text = (root / "tests" / "data" / "arm_circle_bodies.yaml").read_text() + ARM_WITH_TIP
    result = ukdyn.parse(text).simulate()
    path = tmp_path / "arm.html"
    result.save_animation(path)
    data = _page_data(path.read_text())
    [desired] = data["desired_paths"]
    assert (desired["requirement"], desired["of"]) == ("tip", "tip")
    t = np.array(data["t"], float)
    want = np.array([0.6 + 0.25 * np.cos(2 * t), 0.2 + 0.25 * np.sin(2 * t)])
    assert np.max(np.abs(np.array(desired["q"], float) - want)) < 1e-3
    page = _page_data(ukdyn.load("control_triple_pendulum").simulate(t_end=0.5).animation_html())
    assert page["desired_paths"] == []
    assert sorted(r["name"] for r in page["requirements"] if "desired" in r) == \
        ["joint1", "joint2", "joint3"]


# --- hostile names (issue #29 item 7): the page's data cannot break out of or confuse its script
HOSTILE_NAMES = [
    "</script><script>window.__pwned = 1</script>",
    "x<!--<script>y",
    "<!--",
    "</title><img src=x onerror='window.__pwned = 1'>",
    "__proto__", "constructor", "toString", "hasOwnProperty", "prototype",
    "/*UKDYN_THREE*/", "/*UKDYN_DATA*/null", "<!--UKDYN_TITLE-->",
    "\x1b]0;retitled\x07\x1b[2J\x1b[31m",
    "\u202eevil\u202c \u2066x\u2069 \u200f",
    "\u2028\u2029 & \"quoted\" 'single' `${back}` \\",
    "a" * 100_000,
]


def _swinging_page(model: str, point: str) -> str:
    """A page of a scene holding two visual points, a grey pivot at the origin and a red bob
    named `point` (linked to the pivot, with a trail), that swings on the unit circle; the model
    is named `model`. Built by viewer.build_page from a scene as viewer_scene_json writes it."""
    from ukdyn import viewer
    t = [k * 0.01 for k in range(101)]
    theta = [1.0 + math.sin(3.0 * s) for s in t]
    x, y = [math.sin(a) for a in theta], [-math.cos(a) for a in theta]
    zero = [0.0] * len(t)
    scene = {"model": model, "coordinates": ["x", "y"], "planar": True, "controlled": False,
             "bodies": [], "joints": [], "frames": [], "links": [["pivot", point]],
             "trails": [point],
             "points": [{"name": "pivot", "dimensions": 2, "radius": 0.03, "color": "#7f7f7f",
                         "coordinates": [None, None], "expressions": ["0", "0"]},
                        {"name": point, "dimensions": 2, "radius": 0.08, "color": "#d62728",
                         "coordinates": ["x", "y"], "expressions": ["x", "y"]}]}
    names = ["t", "x", "y", "visual.pivot.x", "visual.pivot.y", "visual.%s.x" % point,
             "visual.%s.y" % point]
    return viewer.build_page(scene, names, [t, x, y, zero, zero, x, y])


def _bob_centres(page: "Page"):
    """The centre of the red bob (pixels) at four frames, trails and arrows hidden."""
    page.js("ukdyn.show('trails', false)")
    n = page.js("return ukdyn.data.t.length")
    centres = []
    for frame in (0, n // 3, 2 * n // 3, n - 1):
        page.js("ukdyn.setFrame(arguments[0])", frame)
        mask = _mask(page.pixels(), "#d62728")
        assert mask.sum() > 50, "the bob is not drawn at frame %d" % frame
        ys, xs = np.nonzero(mask)
        centres.append((xs.mean(), ys.mean()))
    return np.array(centres)


@pytest.fixture(scope="module")
def plain_bob(browser, tmp_path_factory):
    """The bob's centres on the page with plain names (model "p", point "bob")."""
    path = tmp_path_factory.mktemp("hostile") / "plain.html"
    path.write_text(_swinging_page("p", "bob"), encoding="utf-8")
    return _bob_centres(Page(browser, path))


@pytest.mark.parametrize("name", HOSTILE_NAMES, ids=lambda s: repr(s[:24]))
def test_hostile_names_neither_run_nor_break_the_page(browser, plain_bob, tmp_path, name):
    """A name used as the model's and a visual point's: the page draws the same scene as with
    plain names (the bob where it is drawn then), shows the name as text, and runs no script of
    the data; the data stays inside its JSON script element (no "<" in it)."""
    html = _swinging_page(name, name)
    opening = '<script type="application/json" id="ukdyn-data">'
    start = html.index(opening) + len(opening)
    payload = html[start:html.index("</script>", start)]
    assert not set("<>&\u2028\u2029") & set(payload)
    assert _page_data(html)["model"] == name
    path = tmp_path / "hostile.html"
    path.write_text(html, encoding="utf-8")
    page = Page(browser, path)
    assert page.js("return window.__pwned === undefined")
    assert page.js("return document.getElementById('name').textContent") == name
    assert page.js("return ukdyn.data.points[1].name") == name
    np.testing.assert_allclose(_bob_centres(page), plain_bob, atol=0.5)
    assert page.errors() == []


@pytest.mark.parametrize("model_name, point", [("x<!--<script>y", "bob"), ("p", "__proto__")])
def test_hostile_names_from_a_model_file(browser, tmp_path, model_name, point):
    """The two model files of the reproducer viewer_page_breakers.sh, read, run and saved by
    Python as `ukdyn run` does: each page starts and draws its bob, without an error."""
    text = hostile_model(model_name, point)
    path = tmp_path / "page.html"
    ukdyn.parse(text).simulate(t_end=0.5).save_animation(path)
    page = Page(browser, path)
    assert page.js("return document.getElementById('name').textContent") == model_name
    page.js("ukdyn.show('trails', false); ukdyn.show('ideal', false)")
    assert _mask(page.pixels(), "#d62728").sum() > 50
    assert page.errors() == []


def hostile_model(model_name: str, point: str) -> str:
    """A pendulum model file whose model and bob are called model_name and point (the model
    files of viewer_page_breakers.sh; test_viewer_page.py runs them with the command)."""
    return f"""
name: {json_string(model_name)}
coordinates: [x, y]
kinetic_energy: 0.5*(x_dot^2 + y_dot^2)
potential_energy: 9.81*y
constraints:
  - {{name: rod, holonomic: (x^2 + y^2 - 1)/2}}
initial: {{q: {{x: 1}}}}
visual:
  points:
    pivot: {{at: [0, 0], color: grey, radius: 0.03}}
    {point}: {{at: [x, y], color: red, radius: 0.08}}
  links: [[pivot, {point}]]
  trails: [{point}]
"""


def json_string(text: str) -> str:
    """text as a double-quoted YAML (JSON) string."""
    import json
    return json.dumps(text)


def test_a_visual_section_of_frames_only_gets_its_page_by_default(cli, tmp_path):
    """`ukdyn run` writes animation.html for a model whose visual: holds only frames (u19 08: it
    wrote none, and said nothing), as for points; a model without visual: gets none."""
    model = tmp_path / "frame_only.yaml"
    model.write_text(
        "coordinates: [th]\nkinetic_energy: th_dot^2/2\ninitial: {q_dot: {th: 1}}\n"
        "simulate: {t_end: 0.5}\n"
        "visual: {frames: {f: {at: [0, 0], angle: th, size: 1}}}\n", encoding="utf-8")
    out = tmp_path / "out"
    done = subprocess.run([cli, "run", str(model), "-o", str(out), "--no-plots"],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    page = out / "animation.html"
    assert page.exists(), done.stdout + done.stderr
    assert 100_000 < page.stat().st_size < 2_000_000
    bare = tmp_path / "bare.yaml"
    bare.write_text("coordinates: [th]\nkinetic_energy: th_dot^2/2\nsimulate: {t_end: 0.5}\n",
                    encoding="utf-8")
    out2 = tmp_path / "out2"
    done = subprocess.run([cli, "run", str(bare), "-o", str(out2), "--no-plots"],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert not (out2 / "animation.html").exists()
