# SPDX-License-Identifier: BSD-3-Clause
"""Docstrings on everything public, and stubs that name everything the compiled module has."""

import ast
import inspect
import pathlib

import ukdyn
from ukdyn import _ukdyn

STUB = pathlib.Path(ukdyn.__file__).with_name("_ukdyn.pyi")


def public(obj):
    return [n for n in dir(obj) if not n.startswith("_")]


def test_every_public_symbol_has_a_docstring():
    missing = []
    for name in ukdyn.__all__:
        obj = getattr(ukdyn, name)
        if not (inspect.getdoc(obj) or "").strip():
            missing.append(name)
        if inspect.isclass(obj):
            for member in public(obj):
                attr = getattr(obj, member)
                if callable(attr) or isinstance(attr, property):
                    if not (inspect.getdoc(attr) or "").strip():
                        missing.append(f"{name}.{member}")
    assert not missing, f"no docstring: {missing}"


def test_stubs_name_every_class_member_and_function_of_the_compiled_module():
    tree = ast.parse(STUB.read_text())
    stubbed = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            members = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
            members |= {n.target.id for n in node.body if isinstance(n, ast.AnnAssign)}
            stubbed[node.name] = members
        elif isinstance(node, ast.FunctionDef):
            stubbed[node.name] = None
    for name in dir(_ukdyn):
        if name.startswith("__"):
            continue
        obj = getattr(_ukdyn, name)
        if inspect.isclass(obj):
            assert name in stubbed, f"class {name} missing from the stub"
            missing = set(public(obj)) - stubbed[name]
            assert not missing, f"{name}: {missing} missing from the stub"
        elif callable(obj):
            assert name in stubbed, f"function {name} missing from the stub"


def test_the_readme_counts_the_examples():
    """README's count of examples/models/ is the directory's and ukdyn.examples()' (it said 23
    when there were 32: review 2026-11-27)."""
    import re
    root = pathlib.Path(__file__).resolve().parents[2]
    files = sorted(p.stem for p in (root / "examples" / "models").glob("*.yaml"))
    readme = (root / "README.md").read_text()
    said = re.search(r"`examples/models/` holds (\d+)", readme)
    assert said and int(said.group(1)) == len(files), said and said.group(0)
    assert sorted(ukdyn.examples()) == files


def test_python_md_says_from_sympy_translates_the_non_smooth_functions():
    """docs/python.md said Piecewise, sign and Heaviside raise ValueError; from_sympy translates
    them (symbolic.py)."""
    root = pathlib.Path(__file__).resolve().parents[2]
    text = (root / "docs" / "python.md").read_text()
    assert "(Piecewise, sign, Heaviside, …) raise" not in text
    import sympy as sp
    x = sp.Symbol("x")
    model = ukdyn.from_sympy([x], T=sp.Rational(1, 2) * sp.Symbol("x_dot") ** 2,
                             V=sp.Piecewise((x ** 2, x > 0), (0, True)) + sp.sign(x)
                             + sp.Heaviside(x))
    assert model is not None
