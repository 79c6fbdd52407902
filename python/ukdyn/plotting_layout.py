# SPDX-License-Identifier: BSD-3-Clause
"""The plots' layout (part of ukdyn/plotting.py; imports nothing of ukdyn: the command runs it as
a script beside plotting.py): :class:`FixedLayout`, a matplotlib layout engine that places a
figure's grid of panels from what sticks out of each panel — tick labels, axis labels,
titles, a legend beside it — measured, placed, and measured and placed again; :func:`settle`
does it once before the figure is saved and takes the engine away, so that savefig draws the
figure once. matplotlib's constrained layout, in its place before, ran in both of the draws that
savefig makes with a layout engine, measuring every panel twice in each (about half of each
savefig of the plots; bench/RESULTS.md, "Plotting time of `ukdyn run`").

The result is like the constrained layout's: every label inside the canvas, the panels of a column
as wide as each other and aligned, the rows as high as each other (or in the grid's height
ratios), the figure's title above them. What it does not do: colour bars, nested grids, figure
legends (the plots have none)."""

import numpy as np
from matplotlib.layout_engine import LayoutEngine
from matplotlib.transforms import Bbox

#: the space around the panels and between them, beyond what sticks out of them (inches; the
#: constrained layout's default pads, 3 pt)
PAD = 3.0 / 72.0

#: the space kept free beyond each measurement (inches): a panel's tick labels are measured at
#: its first size and may change a little at the final one (a new tick, a wider label)
SLACK = 2.0 / 72.0


class FixedLayout(LayoutEngine):
    """Places the panels of a figure made on one grid (plt.subplots, fig.add_gridspec): margins
    measured from each panel's tight box (``get_tightbbox``, for layout only) at its present
    position, then the columns and rows share what is left; two rounds. Cost: two tight boxes
    per panel, the second cheap (the ticks exist by then); the constrained layout made four per
    saved file."""

    _adjust_compatible = False
    _colorbar_gridspec = False

    def execute(self, fig):
        """Positions every panel of `fig` (and its title); panels not on a grid are left where
        they are. A second round, which measures the panels at nearly their final size, only
        when the first one's placing changed what sticks out: a panel's ticks or view (a tick
        more on a longer axis with matplotlib's default locator, the limits of an equal-aspect
        panel), and so its labels. The plots' linear axes have ticks that do not depend on the
        panel's size (plotting.few_ticks), so most of their figures are laid out in one
        round: a quarter of the layout's CPU less."""
        panels = [ax for ax in fig.axes if ax.get_visible() and ax.get_in_layout()
                  and ax.get_subplotspec() is not None]
        if not panels:
            return
        renderer = fig._get_renderer()
        measured = _place(fig, panels, renderer)
        if measured is None or measured != _ticks(panels):
            _place(fig, panels, renderer)


def _ticks(panels):
    """What the margins of `panels` measured depend on besides the labels' text: each axis'
    major tick locations (its locator asked at the panel's present size: cheap, no text laid
    out) and view limits, and the panels' aspects (an equal aspect changes the limits with
    the size)."""
    out = []
    for ax in panels:
        if ax.get_aspect() != "auto":
            return None  # (never equal to a measurement: always the second round)
        for axis in (ax.xaxis, ax.yaxis):
            out.append((tuple(axis.get_view_interval()), tuple(axis.get_majorticklocs())))
    return out


def _place(fig, panels, renderer):
    """One round of FixedLayout: measures each panel where it is, then moves it; returns
    :func:`_ticks` as they were measured."""
    grid = panels[0].get_subplotspec().get_topmost_subplotspec().get_gridspec()
    rows, cols = grid.get_geometry()
    dpi = fig.dpi
    width, height = fig.get_size_inches() * dpi  # (pixels)
    pad, slack = PAD * dpi, SLACK * dpi
    # what sticks out of each panel, by the grid's edges it touches (pixels)
    left, right = np.zeros(cols), np.zeros(cols)
    top, bottom = np.zeros(rows), np.zeros(rows)
    spans = []
    for ax in panels:
        spec = ax.get_subplotspec().get_topmost_subplotspec()
        r, c = spec.rowspan, spec.colspan
        spans.append((ax, r, c))
        tight = ax.get_tightbbox(renderer, for_layout_only=True)
        if tight is None:
            continue
        x0, y0, x1, y1 = ax.bbox.extents  # (after get_tightbbox, which applies the aspect)
        left[c.start] = max(left[c.start], x0 - tight.x0 + slack)
        right[c.stop - 1] = max(right[c.stop - 1], tight.x1 - x1 + slack)
        top[r.start] = max(top[r.start], tight.y1 - y1 + slack)
        bottom[r.stop - 1] = max(bottom[r.stop - 1], y0 - tight.y0 + slack)
    measured = _ticks(panels)
    title = fig._suptitle
    above = pad
    if title is not None and title.get_visible() and title.get_text():
        title.set_y(1.0 - pad / height)
        title.set_verticalalignment("top")
        _wrap(title, renderer, width - 2 * pad)
        above += title.get_window_extent(renderer).height + pad
    xs = _cuts(width, pad, pad, left, right, grid.get_width_ratios(), pad)
    # rows from the top: the grid's row 0 is the top one
    ys = _cuts(height, above, pad, top, bottom, grid.get_height_ratios(), pad)
    for ax, r, c in spans:
        x0, x1 = xs[c.start][0], xs[c.stop - 1][1]
        y1, y0 = height - ys[r.start][0], height - ys[r.stop - 1][1]
        ax._set_position(Bbox.from_extents(x0 / width, y0 / height, x1 / width, y1 / height))
    return measured


def _wrap(text, renderer, room):
    """Breaks a line of `text` wider than `room` (pixels) at the last spaces that fit (a long
    model name with a long figure title), as few lines as it takes."""
    if text.get_window_extent(renderer).width <= room:
        return
    lines = []
    for line in text.get_text().split("\n"):
        words, current = line.split(" "), ""
        for word in words:
            trial = word if not current else current + " " + word
            text.set_text(trial)
            if current and text.get_window_extent(renderer).width > room:
                lines.append(current)
                trial = word
            current = trial
        lines.append(current)
    text.set_text("\n".join(lines))


def _cuts(length, before, after, lead, trail, ratios, gap):
    """The [start, end] of each cell along a length (pixels): `before` and `after` at the ends,
    cell k preceded by lead[k] and followed by trail[k], `gap` between cells, the rest shared
    in the `ratios` (equal when None). A cell never gets less than a pixel."""
    n = len(lead)
    ratios = np.ones(n) if ratios is None else np.asarray(ratios, dtype=float)
    free = length - before - after - lead.sum() - trail.sum() - (n - 1) * gap
    sizes = max(1.0, free) * ratios / ratios.sum()
    out, at = [], before
    for k in range(n):
        start = at + lead[k]
        out.append((start, start + sizes[k]))
        at = start + sizes[k] + trail[k] + gap
    return out


def settle(fig):
    """Lays out `fig` now, once, when its engine is a :class:`FixedLayout`, and takes the engine
    away: savefig then draws the figure once (with a layout engine, matplotlib's savefig draws it
    twice, laying it out each time)."""
    if isinstance(fig.get_layout_engine(), FixedLayout):
        fig.get_layout_engine().execute(fig)
        fig.set_layout_engine(None)
