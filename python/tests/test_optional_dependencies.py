# SPDX-License-Identifier: BSD-3-Clause
"""Every third-party module that ukdyn imports only inside the functions that use it has a pip
extra (pyproject.toml) and is recommended or suggested by the Debian package
(cmake/packaging.cmake), so that neither install leaves a documented function without what it
needs (issue #33 item 6: xarray, for Result.to_xarray and ukdyn.to_dataset, had neither)."""

import ast
import pathlib
import re
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]

# the module -> (its pip extra, its Debian package)
OPTIONAL = {
    "matplotlib": ("plots", "python3-matplotlib"),
    "pandas": ("dataframes", "python3-pandas"),
    "sympy": ("sympy", "python3-sympy"),
    "xarray": ("xarray", "python3-xarray"),
}
# imported only where the caller already has them: Jupyter's display (Result.show in a
# notebook) and the Dask client a caller passes to sweep(client=...)
THE_CALLERS = {"IPython", "distributed"}
STANDARD = set(getattr(sys, "stdlib_module_names", ())) | {"ukdyn", "numpy"}


def _lazy_imports():
    """The top-level names of the modules imported inside functions of python/ukdyn/*.py."""
    names = set()
    for path in (ROOT / "python" / "ukdyn").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import) and node.col_offset > 0:
                names.update(a.name.split(".")[0] for a in node.names)
            elif isinstance(node, ast.ImportFrom) and node.col_offset > 0 and node.level == 0:
                names.add(node.module.split(".")[0])
    return names - STANDARD


def test_every_optional_import_is_known():
    if not STANDARD - {"ukdyn", "numpy"}:
        pytest.skip("sys.stdlib_module_names needs Python 3.10")
    found = _lazy_imports()
    assert {"matplotlib", "pandas", "sympy", "xarray"} <= found
    assert found - set(OPTIONAL) - THE_CALLERS == set()


def test_every_optional_import_has_an_extra_and_a_debian_package():
    tomllib = pytest.importorskip("tomllib")
    with open(ROOT / "pyproject.toml", "rb") as f:
        extras = tomllib.load(f)["project"]["optional-dependencies"]
    packaging = (ROOT / "cmake" / "packaging.cmake").read_text()
    recommends = re.search(r'CPACK_DEBIAN_PACKAGE_RECOMMENDS\s+"([^"]*)"', packaging).group(1)
    suggests = re.search(r'CPACK_DEBIAN_PACKAGE_SUGGESTS\s+"([^"]*)"', packaging).group(1)
    debian = {p.strip() for p in (recommends + "," + suggests).replace("\\\n", "").split(",")}
    for module, (extra, package) in OPTIONAL.items():
        assert any(re.match(re.escape(module) + r"\b", r) for r in extras.get(extra, [])), module
        assert package in debian, module
    # the data-frame and data-set modules are recommended (installed by default), not suggested
    assert {"python3-pandas", "python3-xarray", "python3-matplotlib"} <= {
        p.strip() for p in recommends.split(",")}
