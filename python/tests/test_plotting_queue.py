# SPDX-License-Identifier: BSD-3-Clause
"""The order in which the command's two plotting processes take the figures
(ukdyn/plotting_files.py queue_order, plotting.COST): dearest first, so that the last figure
taken is a cheap one and the processes finish together."""

import matplotlib

matplotlib.use("Agg")

from ukdyn import plotting, plotting_files  # noqa: E402


def test_every_figure_has_a_cost():
    assert {stem for stem, _ in plotting.FIGURES} == set(plotting.COST)
    assert all(0.05 <= c <= 1.0 for c in plotting.COST.values())


def test_the_queue_takes_the_dearest_figures_first():
    stems = [s for s, _ in plotting.FIGURES]
    order = [stems[i] for i in plotting_files.queue_order(plotting.FIGURES, plotting.COST)]
    assert sorted(order) == sorted(stems)  # each figure once
    # control (six panels), then the three views of a spatial model's bodies; outputs last
    assert order[:2] == ["control", "bodies"] and order[-1] == "outputs"
    assert order.index("coordinates") < order.index("energy")


def test_equal_costs_keep_the_figures_order_and_unknown_ones_go_last():
    figures = [("a", None), ("b", None), ("c", None), ("d", None)]
    assert plotting_files.queue_order(figures, {"a": 1.0, "b": 2.0, "c": 1.0}) == [1, 0, 2, 3]
    assert plotting_files.queue_order(figures, {}) == [0, 1, 2, 3]
