# SPDX-License-Identifier: BSD-3-Clause
"""The plots (ukdyn/plotting.py, the one implementation behind `ukdyn run` and Result): the
figures' objects are inspected — panels, axis labels and their units, line counts, titles —
never their pixels."""

import os
import subprocess

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import ukdyn  # noqa: E402
from ukdyn import plotting  # noqa: E402

FREE = """
name: free spinning slider
coordinates: [s, phi]
units: {s: m, phi: rad}
parameters: {m: 2, J: 0.5}
kinetic_energy: 0.5*m*s_dot^2 + 0.5*J*phi_dot^2
initial: {q: {s: 0, phi: 0}, q_dot: {s: 1, phi: 3}}
simulate: {t_end: 0.2}
"""


def data_lines(ax):
    """The lines of an Axes that have a legend entry (not the start dots, bounds' mirrors)."""
    return [line for line in ax.get_lines() if not line.get_label().startswith("_")]


def ylabels(fig):
    return [ax.get_ylabel() for ax in fig.axes]


@pytest.fixture(scope="module")
def pendulum():
    return ukdyn.load("pendulum").simulate(t_end=0.5)


@pytest.fixture(scope="module")
def top():
    return ukdyn.load("heavy_top").simulate(t_end=0.1)


@pytest.fixture(scope="module")
def crank():
    return ukdyn.load("slider_crank").simulate(t_end=0.1)


@pytest.fixture(scope="module")
def tip():
    return ukdyn.load("control_triple_pendulum_tip").simulate(t_end=0.5)


@pytest.fixture(scope="module")
def free():
    return ukdyn.parse(FREE).simulate()


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def test_units_come_from_the_file_and_the_bodies(pendulum, top):
    assert ukdyn.load("pendulum").units == {"x": "m", "y": "m", "theta": "rad", "r": "m"}
    units = ukdyn.load("heavy_top").units
    assert {units[c] for c in units if c[-2:] in (".x", ".y", ".z")} == {"m"}
    assert units["tilt"] == "rad"  # an output expression's, from the file
    assert [units[c] for c in units if ".u" in c] == ["1"] * 4
    assert set(ukdyn.load("slider_crank").units.values()) == {"m", "rad"}
    # a model that says nothing: no unit, never a guessed one
    assert set(ukdyn.load("incline_friction").units.values()) == {""}
    assert pendulum.model_name == "pendulum"


def test_units_errors_are_located():
    with pytest.raises(ukdyn.ModelError,
                       match=r"<string>:4:9: error: units: 'q' is neither a coordinate nor an "
                             r"output expression \(hint: the coordinates are s, phi\)"):
        ukdyn.parse(FREE.replace("units: {s: m,", "units: {q: m,"))
    with pytest.raises(ukdyn.ModelError, match=r":4:12: error: the unit of 's' must be a short"):
        ukdyn.parse(FREE.replace("{s: m,", "{s: [m],"))
    with pytest.raises(ukdyn.ModelError, match=r":4:8: error: units must map coordinates \(or"):
        ukdyn.parse(FREE.replace("units: {s: m, phi: rad}", "units: [m, rad]"))


def test_output_expressions_have_the_units_the_file_gives(pendulum, top):
    assert pendulum.units == {"x": "m", "y": "m", "theta": "rad", "r": "m"}
    fig = pendulum.figures()["outputs"]
    assert ylabels(fig) == ["value [rad]", "value [m]"]
    assert [[line.get_label() for line in data_lines(ax)] for ax in fig.axes] == [["theta"], ["r"]]
    text = FREE + "output: {expressions: {turns: phi/(2*pi), e: 0.5*m*s_dot^2}}\n"
    model = ukdyn.parse(text.replace("phi: rad}", "phi: rad, e: J}"))
    assert model.units == {"s": "m", "phi": "rad", "turns": "", "e": "J"}
    fig = model.simulate().figures()["outputs"]
    assert ylabels(fig) == ["value (no unit given)", "value [J]"]
    with pytest.raises(ukdyn.ModelError, match=r"the coordinates are s, phi, the output "
                                               r"expressions turns, e"):
        ukdyn.parse(text.replace("phi: rad}", "phi: rad, E: J}"))


def test_coordinates_are_grouped_by_unit(top, free):
    fig = top.figures()["coordinates"]
    assert ylabels(fig) == ["position [m]", "quaternion components [1]"]
    assert [len(data_lines(ax)) for ax in fig.axes] == [3, 4]
    assert "heavy top" in fig._suptitle.get_text().lower() or top.model_name in \
        fig._suptitle.get_text()
    assert fig.axes[-1].get_xlabel() == "t [s]"
    fig = free.figures()["coordinates"]
    assert ylabels(fig) == ["position [m]", "angle [rad]"]
    assert fig._suptitle.get_text() == "free spinning slider: coordinates"


def test_unconstrained_model_has_no_constraint_figures(free):
    figs = free.figures()
    assert set(figs) == {"coordinates", "energy"}


def test_no_empty_panels(pendulum, top, crank, tip, free):
    for result in (pendulum, top, crank, tip, free):
        for stem, fig in result.figures().items():
            for ax in fig.axes:
                assert data_lines(ax), (result.model_name, stem, ax.get_ylabel())
            assert result.model_name in fig._suptitle.get_text()
        plt.close("all")


def test_constraint_forces_and_violation(pendulum):
    figs = pendulum.figures()
    forces = figs["constraint_forces"]
    assert ylabels(forces) == ["ideal constraint force [N]"]
    assert [line.get_label() for line in data_lines(forces.axes[0])] == ["x", "y"]
    violation = figs["violation"]
    for ax in violation.axes:
        assert ax.get_yscale() == "log"
        for line in data_lines(ax):
            y = np.asarray(line.get_ydata(), dtype=float)
            assert np.all(np.isnan(y) | (y > 0))  # exact zeros are not drawn at a floor
    assert ylabels(violation)[0] == "max |position violation|"
    assert "running maximum" in violation._suptitle.get_text()
    # each line is that constraint's running maximum of |violation|: it never falls, and it is
    # the largest |sample| so far, checked against the trajectory's own column
    table = pendulum
    for line in data_lines(violation.axes[0]):
        y = np.asarray(line.get_ydata(), dtype=float)
        drawn = ~np.isnan(y)
        assert drawn.sum() > 10
        assert np.all(np.diff(y[drawn]) >= 0)
        expected = np.maximum.accumulate(np.abs(np.asarray(table["violation." + line.get_label()])))
        np.testing.assert_array_equal(y[drawn], expected[drawn])
        assert line.get_drawstyle() == "steps-post"
    # one Axes (Result.plot_*): the same drawing code
    ax = pendulum.plot_forces()
    assert ax.get_ylabel() == "generalized constraint force [N]"
    assert pendulum.plot("x", "y").get_ylabel() == "[m]"
    assert pendulum.plot("x_dot").get_ylabel() == "[m/s]"


def test_energy_labels(pendulum):
    fig = pendulum.figures()["energy"]
    assert ylabels(fig) == ["energy [J]", "balance residual [J]"]
    labels = [line.get_label() for ax in fig.axes for line in data_lines(ax)]
    assert not any("_" in label for label in labels)


def test_line_styles_are_distinct_for_many_lines():
    styles = {tuple(sorted((k, str(v)) for k, v in plotting.line_style(i).items()))
              for i in range(300)}
    assert len(styles) == 300


def test_spatial_bodies_three_views(top):
    fig = top.figures()["bodies"]
    assert len(fig.axes) == 3
    assert [(ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes] == [
        ("x [m]", "y [m]"), ("x [m]", "z [m]"), ("y [m]", "z [m]")]
    legend = fig.axes[-1].get_legend()
    assert "start" in [t.get_text() for t in legend.get_texts()]


def test_planar_bodies_one_view(crank):
    fig = crank.figures()["bodies"]
    assert len(fig.axes) == 1
    ax = fig.axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("x [m]", "y [m]")
    assert ax.get_aspect() == 1.0
    assert "start" in [t.get_text() for t in ax.get_legend().get_texts()]
    coords = crank.figures()["coordinates"]
    assert ylabels(coords) == ["position [m]", "angle [rad]"]


def test_control_desired_against_actual(tip):
    fig = tip.figures()["control"]
    assert ylabels(fig) == ["tracking error", "requirement\n(desired, actual)",
                            "control force [N·m]", "power [W]", "work [J]", "effort [N²·m²·s]"]
    panel = fig.axes[1]
    lines = {line.get_label(): np.asarray(line.get_ydata()) for line in data_lines(panel)}
    assert sorted(lines) == ["tip.0 actual", "tip.0 desired", "tip.1 actual", "tip.1 desired"]
    # actual: the tip's position from the coordinates (L1, L2, L3 = 1, 0.9, 0.8)
    L = (1.0, 0.9, 0.8)
    x = sum(Li * np.sin(tip[c]) for Li, c in zip(L, "abc"))
    y = -sum(Li * np.cos(tip[c]) for Li, c in zip(L, "abc"))
    np.testing.assert_allclose(lines["tip.0 actual"], x, rtol=0, atol=1e-9)
    np.testing.assert_allclose(lines["tip.1 actual"], y, rtol=0, atol=1e-9)
    np.testing.assert_allclose(lines["tip.0 desired"], 0.8 + 0.3 * np.sin(tip.t), rtol=0,
                               atol=1e-12)
    assert len(data_lines(fig.axes[0])) == 2 and len(data_lines(fig.axes[2])) == 3


def test_save_plots_formats(free, tmp_path):
    written = free.save_plots(tmp_path, formats="svg")
    assert sorted(os.path.basename(p) for p in written) == ["coordinates.svg", "energy.svg"]
    assert all(os.path.getsize(p) > 0 for p in written)
    with pytest.raises(ValueError,
                       match="unknown plot format 'gif': the formats are png, pdf, svg"):
        free.save_plots(tmp_path, formats=["png", "gif"])


def test_save_plots_creates_the_directory(free, tmp_path):
    """A missing directory (nested too) is created, as by ``ukdyn run -o`` (it was a
    FileNotFoundError on the temporary file)."""
    written = free.save_plots(tmp_path / "missing" / "dir", formats="svg")
    assert sorted(os.path.relpath(p, tmp_path) for p in written) == [
        os.path.join("missing", "dir", "coordinates.svg"), os.path.join("missing", "dir", "energy.svg")]


def test_command_writes_the_formats_asked_for(cli, out_dir):
    model = out_dir / "free.yaml"
    model.write_text(FREE)
    run = subprocess.run([cli, "run", str(model), "-o", str(out_dir / "run"),
                          "--plot-format", "pdf,svg"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    files = set(os.listdir(out_dir / "run")) - {".ukdyn.lock"}
    assert files == {"trajectory.csv", "summary.json", "coordinates.pdf", "energy.pdf",
                     "coordinates.svg", "energy.svg"}
    assert "wrote %s" % (out_dir / "run" / "coordinates.svg") in run.stdout
    # the script's figures from the CSV and summary.json: units and the model's name
    table = plotting.read_csv(str(out_dir / "run" / "trajectory.csv"))
    meta = plotting.read_summary(str(out_dir / "run" / "summary.json"))
    # (and the time's, t, and the model's unit system: SI here)
    assert meta == {"model": "free spinning slider", "units": {"s": "m", "phi": "rad", "t": "s"},
                    "unit_system": plotting._data.SI_UNITS}
    fig = plotting.coordinates_figure(table, meta)
    assert ylabels(fig) == ["position [m]", "angle [rad]"]
    assert fig._suptitle.get_text() == "free spinning slider: coordinates"


def test_command_refuses_an_unknown_plot_format(cli, out_dir):
    run = subprocess.run([cli, "run", "--example", "pendulum", "--t-end", "0.3", "-o",
                          str(out_dir), "--plot-format", "png,gif"],
                         capture_output=True, text=True)
    assert run.returncode == 2
    assert "--plot-format gif: the plot formats are png, pdf and svg" in run.stderr
    assert not os.path.exists(out_dir / "trajectory.csv")


def test_running_max_skips_nan_and_rises():
    got = plotting.running_max([0.0, -2e-12, np.nan, 1e-13, -5e-12, 0.0])
    np.testing.assert_array_equal(got, [0.0, 2e-12, 2e-12, 2e-12, 5e-12, 5e-12])
    assert plotting.running_max([]).size == 0


def test_paper_style_is_a_single_column_in_8_points(pendulum):
    """``style="paper"``: every figure 3.5 in wide, its text at 8 pt or less (ticks 7, legends 6),
    legends inside the panels; the screen style is unchanged afterwards (9 in, rc restored)."""
    default_size = matplotlib.rcParams["font.size"]
    figs = pendulum.figures(style="paper")
    assert set(figs) >= {"coordinates", "violation", "energy"}
    for stem, fig in figs.items():
        width, height = fig.get_size_inches()
        assert width == pytest.approx(3.5, abs=1e-12), stem
        assert 1.0 < height < 6.0, stem
        for ax in fig.axes:
            assert ax.yaxis.label.get_fontsize() == pytest.approx(8.0), stem
            assert all(t.get_fontsize() == pytest.approx(7.0) for t in ax.get_xticklabels())
            legend = ax.get_legend()
            if legend is not None:  # inside the panel: anchored to the Axes' own box
                assert legend.get_bbox_to_anchor().bounds == ax.bbox.bounds, stem
                assert all(t.get_fontsize() == pytest.approx(6.0) for t in legend.get_texts())
    plt.close("all")
    assert matplotlib.rcParams["font.size"] == default_size
    screen = pendulum.figures()["coordinates"]
    assert screen.get_size_inches()[0] == pytest.approx(9.0, abs=1e-12)
    plt.close("all")
    with pytest.raises(ValueError, match="unknown plot style 'papr': the styles are screen, paper"):
        pendulum.save_plots("unused", style="papr")
    assert not os.path.exists("unused")


def test_paper_style_writes_vector_files(pendulum, tmp_path):
    """save_plots(style="paper") writes PDF by default: a vector file (its text as fonts, Type 42,
    not as pixels), and no PNG."""
    written = pendulum.save_plots(tmp_path, style="paper")
    assert sorted(os.path.basename(p) for p in written) == [
        "constraint_forces.pdf", "coordinates.pdf", "energy.pdf", "outputs.pdf", "violation.pdf"]
    pdf = (tmp_path / "coordinates.pdf").read_bytes()
    assert pdf.startswith(b"%PDF") and b"/FontFile2" in pdf and b"/Subtype /Image" not in pdf


def test_command_plot_style_paper(cli, out_dir):
    run = subprocess.run([cli, "run", "--example", "pendulum", "--t-end", "0.3", "-o",
                          str(out_dir / "paper"), "--plot-style", "paper"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    files = set(os.listdir(out_dir / "paper")) - {".ukdyn.lock"}
    assert {"coordinates.pdf", "violation.pdf", "energy.pdf"} <= files
    assert not any(f.endswith(".png") for f in files)
    bad = subprocess.run([cli, "run", "--example", "pendulum", "--t-end", "0.3", "-o",
                          str(out_dir / "bad"), "--plot-style", "papr"],
                         capture_output=True, text=True)
    assert bad.returncode == 2
    assert "--plot-style papr: the plot styles are screen and paper (did you mean 'paper'?)" \
        in bad.stderr
    assert not os.path.exists(out_dir / "bad" / "trajectory.csv")


# the repro's ball in mm, g and ms (docs/model-format.md, "Units"): every label in them, never in
# s, J or N (4.41e3 g·mm²/ms² is 4.41 J); an SI model's labels are the tests' above
BALL_MM = """
name: ball mm g ms
parameters: {m: 500, r: 100, g: 9.81e-3, h0: 1000, e: 0.7}
bodies:
  - {name: ball, type: rigid, mass: m, inertia: 0.4*m*r^2, position: [0, 0, h0],
     velocity: [0.5, 0, 0]}
forces:
  - {type: gravity, g: [0, 0, -g]}
contacts:
  - {name: floor, body: ball, shape: sphere, radius: r, restitution: e}
units: {length: mm, mass: g, time: ms}
simulate: {t_end: 500}
"""


def test_labels_follow_the_models_units():
    model = ukdyn.parse(BALL_MM)
    assert model.unit_system == {
        "length": "mm", "mass": "g", "time": "ms", "velocity": "mm/ms", "force": "g·mm/ms²",
        "energy": "g·mm²/ms²", "power": "g·mm²/ms³"}
    assert model.units["ball.x"] == "mm" and model.units["ball.u0"] == "1"
    r = model.simulate()
    units = r.column_units()
    assert units["t"] == "ms"
    assert units["ball.x"] == "mm" and units["ball.x_dot"] == "mm/ms"
    assert units["ball.z_ddot"] == "mm/ms²" and units["ball.u0_dot"] == "1/ms"
    assert units["energy"] == "g·mm²/ms²" and units["work_impact"] == "g·mm²/ms²"
    figures = r.figures()
    energy = figures["energy"]
    assert ylabels(energy) == ["energy [g·mm²/ms²]", "balance residual [g·mm²/ms²]"]
    assert energy.axes[-1].get_xlabel() == "t [ms]"
    coords = figures["coordinates"]
    assert ylabels(coords)[0] == "position [mm]" and coords.axes[-1].get_xlabel() == "t [ms]"
    assert r.plot("ball.x_dot").get_ylabel() == "[mm/ms]"
    assert [(ax.get_xlabel(), ax.get_ylabel()) for ax in figures["bodies"].axes][0] == (
        "x [mm]", "y [mm]")
    page = r._repr_html_()
    assert "t = 0 &hellip; 500 ms" in page
    # nowhere an SI label
    for fig in figures.values():
        if fig is None:
            continue
        for ax in fig.axes:
            for text in (ax.get_xlabel(), ax.get_ylabel()):
                assert "[J]" not in text and "[N]" not in text and "[s]" not in text, text
                assert "/s]" not in text and "N·m" not in text, text
