# SPDX-License-Identifier: BSD-3-Clause
"""What a user meets first (issue #33 items 4 and 5): `dir(ukdyn)` is the API and the package's
submodules, not the helpers __init__.py imports (Any, Optional, os, json, annotations); and
Result.show() in a notebook shows the viewer without IPython's red "Consider using
IPython.display.IFrame instead" warning (the tour notebook's last cell)."""

import html
import re
import types
import warnings

import pytest

import ukdyn


def test_dir_lists_the_api_and_the_submodules_only():
    public = {n for n in dir(ukdyn) if not n.startswith("_")}
    modules = {n for n in public if isinstance(getattr(ukdyn, n), types.ModuleType)}
    # every submodule is one of the package's own
    assert all(getattr(ukdyn, n).__name__ == "ukdyn." + n for n in modules), sorted(modules)
    assert public - modules == set(ukdyn.__all__), sorted((public - modules) ^ set(ukdyn.__all__))
    for helper in ("Any", "Optional", "os", "json", "annotations"):
        assert helper not in public


def test_show_holds_the_page_and_does_not_warn():
    pytest.importorskip("IPython")
    result = ukdyn.load("heavy_top").simulate(t_end=0.2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # IPython's UserWarning would raise here
        shown = result.show(height=300)
    text = shown.data
    m = re.fullmatch(r'<div class="ukdyn-viewer"><iframe srcdoc="([^"]*)" '
                     r'style="width:100%;height:300px;border:1px solid #ccc" '
                     r'sandbox="allow-scripts"></iframe></div>', text)
    assert m, text[:200]
    # the iframe holds exactly the page save_animation writes (escaped for the attribute)
    assert html.unescape(m.group(1)) == result.animation_html()
