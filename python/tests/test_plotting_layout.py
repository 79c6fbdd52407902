# SPDX-License-Identifier: BSD-3-Clause
"""The plots' fixed layout (ukdyn/plotting_layout.py, in place of matplotlib's constrained
layout): every panel with its labels and legend, and the title, inside the canvas, none running
into another, and the canvas used (no wide empty margin) — the boxes measured on the drawn
figure, never its pixels."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402

import ukdyn  # noqa: E402
from ukdyn import plotting, plotting_layout  # noqa: E402

#: the widest empty margin accepted between the boxes and the canvas' edge (pixels at 110 dpi:
#: the layout's pad and slack are 5 pt, 7.6 px)
MARGIN = 14.0


@pytest.fixture(scope="module")
def runs():
    return {name: ukdyn.load(name).simulate(t_end=t_end) for name, t_end in (
        ("pendulum", 0.5), ("slider_crank", 0.2), ("heavy_top", 0.1),
        ("control_triple_pendulum_tip", 0.5), ("double_four_bar_bodies_redundant", 0.2))}


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def boxes(fig):
    """The drawn figure's boxes: each panel's tight box (labels, ticks, legend), then the
    title's; and the canvas."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    out = [ax.get_tightbbox(renderer) for ax in fig.axes]
    if fig._suptitle is not None:
        out.append(fig._suptitle.get_window_extent(renderer))
    return out, fig.bbox


@pytest.mark.parametrize("style", ["screen", "paper"])
def test_every_label_inside_the_canvas_and_apart(runs, style):
    checked = 0
    for name, result in runs.items():
        for stem, fig in result.figures(style=style).items():
            assert isinstance(fig.get_layout_engine(), plotting_layout.FixedLayout), stem
            found, canvas = boxes(fig)
            where = "%s %s %s" % (name, stem, style)
            for b in found:
                assert b.x0 >= canvas.x0 - 0.5 and b.x1 <= canvas.x1 + 0.5, where
                assert b.y0 >= canvas.y0 - 0.5 and b.y1 <= canvas.y1 + 0.5, where
            for i, a in enumerate(found):
                for b in found[i + 1:]:
                    overlap = (min(a.x1, b.x1) - max(a.x0, b.x0),
                               min(a.y1, b.y1) - max(a.y0, b.y0))
                    assert min(overlap) <= 0.5, (where, a, b)
            # the canvas is used: the boxes reach within MARGIN of every edge
            assert min(b.x0 for b in found) - canvas.x0 <= MARGIN, where
            assert canvas.x1 - max(b.x1 for b in found) <= MARGIN, where
            assert min(b.y0 for b in found) - canvas.y0 <= MARGIN, where
            assert canvas.y1 - max(b.y1 for b in found) <= MARGIN, where
            checked += 1
            plt.close(fig)
    assert checked >= 25


def test_a_title_wider_than_the_canvas_is_broken_into_lines(runs):
    """The double four-bar's joint reactions title (its model name, the figure's, "no torque")
    is longer than 9 in: broken at spaces, every word kept, inside the canvas."""
    fig = runs["double_four_bar_bodies_redundant"].figures()["joint_reactions"]
    words = fig._suptitle.get_text().split()
    found, canvas = boxes(fig)
    title = fig._suptitle.get_text()
    assert "\n" in title and title.split() == words
    assert found[-1].width <= canvas.width


def test_written_figures_are_laid_out_once(runs, tmp_path, monkeypatch):
    """write_figures lays each figure out once (plotting_layout.settle) and saves it without a
    layout engine, so that savefig draws it once: the panels where the engine puts them."""
    calls = []
    execute = plotting_layout.FixedLayout.execute
    monkeypatch.setattr(plotting_layout.FixedLayout, "execute",
                        lambda self, fig: calls.append(fig) or execute(self, fig))
    written = plotting.write_figures(runs["pendulum"], runs["pendulum"].plot_metadata, tmp_path,
                                     close=False)
    assert len(written) == 5 and len(calls) == 5 and len(set(map(id, calls))) == 5
    for fig in calls:
        assert fig.get_layout_engine() is None


def test_a_draw_lays_out_each_axis_twice_not_for_empty_titles(runs, monkeypatch):
    """plotting.untitled: a panel without a title of its own is drawn without matplotlib's
    search for its titles' place, which laid out the x axis of each upper panel of a shared time
    axis (its tick labels hidden) three more times in every draw — a third of a figure's CPU.
    Counted: matplotlib's tick updates in one draw of each figure after its layout, two per axis
    (the axis itself, its label's place); four to six per axis without untitled. The titles are
    empty and where they were, at the panels' top; the bodies figure's views have titles, set at
    the same place (y = 1.0) so that their place is not searched for either."""
    import matplotlib.axis
    updates = []
    update = matplotlib.axis.Axis._update_ticks
    monkeypatch.setattr(matplotlib.axis.Axis, "_update_ticks",
                        lambda self: updates.append(self) or update(self))
    checked = 0
    for name in ("slider_crank", "control_triple_pendulum_tip", "heavy_top"):
        for stem, fig in runs[name].figures().items():
            plotting_layout.settle(fig)
            del updates[:]
            fig.canvas.draw()
            axes = 2 * len(fig.axes)
            assert axes * 2 - 2 <= len(updates) <= axes * 2, (name, stem, len(updates))
            for ax in fig.axes:
                title = ("%s–%s view" % (ax.get_xlabel()[0], ax.get_ylabel()[0])
                         if stem == "bodies" else "")
                assert ax.get_title() == title, (name, stem)
                assert ax.title.get_position()[1] == 1.0
            checked += 1
            plt.close(fig)
    assert checked >= 16


def test_linear_axes_have_at_most_tick_bins_intervals(runs):
    """plotting.few_ticks: every linear axis of the plots has between 2 and TICK_BINS + 1 major
    ticks in its view (matplotlib's default fitted eight or nine on a panel's y axis: each tick
    five objects laid out and drawn); a log axis keeps its decades."""
    from matplotlib.ticker import LogLocator, MaxNLocator
    checked = logs = 0
    for name in ("slider_crank", "heavy_top", "control_triple_pendulum_tip"):
        for stem, fig in runs[name].figures().items():
            fig.canvas.draw()
            for ax in fig.axes:
                for axis, (low, high) in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
                    locator = axis.get_major_locator()
                    if isinstance(locator, LogLocator):
                        logs += 1
                        continue
                    assert isinstance(locator, MaxNLocator), (name, stem)
                    low, high = min(low, high), max(low, high)
                    inside = [v for v in axis.get_majorticklocs()
                              if low - 1e-9 * (high - low) <= v <= high + 1e-9 * (high - low)]
                    assert 2 <= len(inside) <= plotting.TICK_BINS + 1, (name, stem, inside)
                    checked += 1
            plt.close(fig)
    assert checked >= 40 and logs >= 2


def test_one_layout_round_when_the_ticks_do_not_change(runs, monkeypatch):
    """FixedLayout measures a second time only when placing the panels changed their ticks or
    views (plotting_layout._ticks): the plots' linear axes (few_ticks) keep theirs, so one round;
    the bodies' equal-aspect views always take two. One round places the panels within a pixel
    of where a second would (plotting.LEGEND_GAP: a legend beside a panel keeps its distance
    when the panel is resized)."""
    rounds = []
    place = plotting_layout._place
    monkeypatch.setattr(plotting_layout, "_place",
                        lambda fig, *a: rounds.append(fig) or place(fig, *a))
    counted = {}
    for name in ("slider_crank", "heavy_top"):
        for stem, fig in runs[name].figures().items():
            del rounds[:]
            plotting_layout.settle(fig)
            counted[name, stem] = len(rounds)
            before = [ax.bbox.extents.copy() for ax in fig.axes]
            place(fig, [ax for ax in fig.axes], fig._get_renderer())  # a further round
            for a, ax in zip(before, fig.axes):
                assert abs(a - ax.bbox.extents).max() < 1.0, (name, stem, a, ax.bbox.extents)
            plt.close(fig)
    for key, n in counted.items():  # (a log axis's decades may thin out on a shorter axis)
        assert n in ({2} if key[1] == "bodies" else {1, 2} if key[1] == "violation" else {1}), \
            (key, n)
    assert len(counted) >= 12
