# SPDX-License-Identifier: BSD-3-Clause
"""The Result object: columns, pandas view, files and plots."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import ukdyn  # noqa: E402


@pytest.fixture(scope="module")
def result():
    return ukdyn.load("incline_friction").simulate(t_end=0.5)


def test_columns_are_float64_arrays_in_csv_order(result):
    assert result.names[:3] == ["t", "x", "y"]
    assert result.names[-2:] == ["s", "s_error"]
    assert len(result) == 51
    for name in result:
        assert result[name].dtype == np.float64 and result[name].shape == (51,)
    assert result["x"] is result["x"]  # no copy on access
    assert result.q.shape == (51, 2) and result.q_dot.shape == (51, 2)
    assert set(result.group("Qc_ideal")) == {"x", "y"}
    assert result.coordinates == ["x", "y"]
    assert result.ok and result.status == "ok" and result.message == ""
    assert result.stats["steps"] > 0


def test_unknown_column_suggests_close_names(result):
    with pytest.raises(KeyError, match="did you mean 's_error'"):
        result["s_eror"]
    with pytest.raises(AttributeError):
        result.nosuch


def test_dataframe_view(result):
    df = result.to_dataframe()
    assert list(df.columns) == result.names
    np.testing.assert_array_equal(df["x"].to_numpy(), result.x)
    assert result.to_dataframe(index="t").index.name == "t"


def test_plots_draw_every_series(result):
    import matplotlib.pyplot as plt
    ax = result.plot()
    assert [line.get_label() for line in ax.get_lines()] == ["x", "y"]
    assert len(result.plot_forces().get_lines()) == 4  # ideal and non-ideal, two coordinates
    assert len(result.plot_violation().get_lines()) >= 1
    assert len(result.plot_energy().get_lines()) == 3
    fig = result.plot_all()
    assert len(fig.axes) == 4
    plt.close("all")


def test_failed_run_raises_with_the_partial_result():
    text = """
coordinates: [x]
kinetic_energy: 0.5*x_dot^2
constraints:
  - {name: still, nonholonomic: x_dot}
  - {name: moving, nonholonomic: x_dot - t, active: [0.5, 1]}
simulate: {t_end: 1}
"""
    model = ukdyn.parse(text)
    with pytest.raises(ukdyn.SolveError) as err:
        model.simulate()
    partial = err.value.result
    assert partial is not None and not partial.ok
    assert err.value.status == partial.status != "ok"
    assert 0 < partial.t[-1] <= 0.5 + 1e-9  # the samples before the second constraint acts
    again = model.simulate(check=False)
    assert not again.ok and again.message == str(err.value)
