# SPDX-License-Identifier: BSD-3-Clause
"""Models from SymPy expressions (docs/python.md, "SymPy").

:func:`from_sympy` translates SymPy expressions into the model-file expression language
(docs/model-format.md) and reads the resulting model text with the C++ reader, so GiNaC
differentiates them exactly (M from T, Q from Lagrange's equations, A and b from the
constraints) and they run in C++ at the speed of a model file. :func:`sympy_to_yaml` returns
that text (save it to get a model file for ``ukdyn run``).

Coordinates are SymPy symbols (``x, y = sympy.symbols("x y")``); their velocities are the
symbols ``x_dot`` (:func:`velocities` makes them); time is the symbol ``t``. Coordinates written
as functions of time (``sympy.Function("x")(t)``, ``sympy.physics.mechanics.dynamicsymbols``)
are accepted too: ``x(t)`` becomes ``x`` and ``x(t).diff(t)`` becomes ``x_dot``. Parameters are
symbols given values in ``parameters={m: 1.0}``; they stay symbols in the model, so they can be
overridden (``from_sympy(..., m=2.0)``).

Functions the language has: sin cos tan asin acos atan atan2 sinh cosh tanh exp log sqrt Abs,
powers, pi and E, and the non-smooth sign, Heaviside (½ at 0, or its H0), Min, Max (of any number
of arguments) and Piecewise, whose conditions are comparisons (<, <=, >, >=) joined by And, Or
and Not: ``Piecewise((a, x > 1), (b, True))`` becomes ``if(x - 1, a, b)`` (docs/model-format.md;
their switches are located as integrator events). Anything else (an Eq condition, a Piecewise
without a last ``True`` piece, other functions) raises ValueError naming it.
"""

from __future__ import annotations

import json
import math
import re
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Union

__all__ = ["from_sympy", "sympy_to_yaml", "velocities", "to_expression"]

_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
# the language's functions, by SymPy class name
_FUNCTIONS = {"sin": "sin", "cos": "cos", "tan": "tan", "asin": "asin", "acos": "acos",
              "atan": "atan", "sinh": "sinh", "cosh": "cosh", "tanh": "tanh", "exp": "exp",
              "log": "log", "Abs": "abs", "atan2": "atan2", "sign": "sign"}
_ADD, _MUL, _POW, _ATOM = 1, 2, 3, 4


def _sympy() -> Any:
    try:
        import sympy
    except ImportError as e:  # pragma: no cover - python3-sympy is a dependency
        raise ImportError("ukdyn.from_sympy needs SymPy (Debian: python3-sympy)") from e
    return sympy


def velocities(*coordinates: Any) -> List[Any]:
    """The velocity symbols ``x_dot`` of coordinate symbols (``velocities(x, y)`` or
    ``velocities([x, y])``)."""
    sp = _sympy()
    if len(coordinates) == 1 and isinstance(coordinates[0], (list, tuple)):
        coordinates = tuple(coordinates[0])
    return [sp.Symbol(_name(c) + "_dot") for c in coordinates]


def _name(c: Any) -> str:
    """The name of a coordinate given as a symbol, a string or a function of time."""
    sp = _sympy()
    if isinstance(c, str):
        name = c
    elif isinstance(c, sp.Symbol):
        name = c.name
    elif isinstance(c, sp.core.function.AppliedUndef):
        name = c.func.__name__
    else:
        raise ValueError(f"from_sympy: a coordinate must be a SymPy symbol, a function of t or a "
                         f"name (got {c!r})")
    if not _IDENT.match(name):
        raise ValueError(f"from_sympy: '{name}' is not a valid name (letters, digits, _)")
    return name


def _number(value: float) -> str:
    if not math.isfinite(value):
        raise ValueError(f"from_sympy: the number {value} is not finite")
    text = repr(float(value))
    return text[:-2] if text.endswith(".0") else text


def to_expression(expr: Any, time: Any = None) -> str:
    """The model-file text of a SymPy expression (or a number).

    Raises ValueError naming a function or object the language does not have.
    """
    sp = _sympy()
    t_sym = time if time is not None else sp.Symbol("t")

    def wrap(text: str, own: int, needed: int) -> str:
        return f"({text})" if own < needed else text

    def go(e: Any, needed: int) -> str:
        # numbers
        if isinstance(e, bool):
            raise ValueError(f"from_sympy: {e!r} is not an expression")
        if isinstance(e, (int, float)):
            e = sp.sympify(e)
        if e is sp.pi:
            return "pi"
        if e is sp.E:
            return "exp(1)"
        if e.is_Integer:
            v = int(e)
            return wrap(str(v), _ATOM if v >= 0 else _ADD, needed)
        if e.is_Rational:
            p, q = int(e.p), int(e.q)
            return wrap(f"{p}/{q}", _MUL if p >= 0 else _ADD, needed + (1 if needed == _MUL else 0))
        if e.is_Float:
            text = _number(float(e))
            return wrap(text, _ATOM if not text.startswith("-") else _ADD, needed)
        if e.is_Number:
            raise ValueError(f"from_sympy: the number {e} is not real and finite")
        if isinstance(e, sp.Symbol):
            if not _IDENT.match(e.name):
                raise ValueError(f"from_sympy: '{e.name}' is not a valid name (letters, digits, _)")
            return e.name
        # functions of time: x(t) -> x, d/dt x(t) -> x_dot
        if isinstance(e, sp.core.function.AppliedUndef):
            if e.args != (t_sym,):
                raise ValueError(f"from_sympy: {e} must be a function of t alone")
            return _name(e)
        if isinstance(e, sp.Derivative):
            f = e.expr
            if (isinstance(f, sp.core.function.AppliedUndef) and f.args == (t_sym,)
                    and e.variable_count == ((t_sym, 1),)):
                return _name(f) + "_dot"
            raise ValueError(f"from_sympy: only first time derivatives of coordinates may appear "
                             f"(got {e}); write second derivatives with the equations of motion")
        if isinstance(e, sp.Add):
            terms = list(e.as_ordered_terms())
            out = go(terms[0], _ADD)
            for term in terms[1:]:
                coeff, rest = term.as_coeff_Mul()
                if coeff.is_negative:
                    out += " - " + go(-term, _MUL)
                else:
                    out += " + " + go(term, _MUL)
            return wrap(out, _ADD, needed)
        if isinstance(e, sp.Mul):
            coeff, rest = e.as_coeff_Mul()
            if coeff.is_negative:
                return wrap("-" + go(-e, _MUL), _ADD, needed)
            num: List[str] = []
            den: List[str] = []
            for f in e.as_ordered_factors():
                if f.is_Rational and not f.is_Integer:
                    if f.p != 1:
                        num.append(str(int(f.p)))
                    den.append(str(int(f.q)))
                elif isinstance(f, sp.Pow) and f.exp.is_Rational and f.exp.is_negative:
                    den.append(go(f.base if f.exp == -1 else
                                  sp.Pow(f.base, -f.exp, evaluate=False), _POW))
                else:
                    num.append(go(f, _MUL + 1 if len(e.args) > 1 else _MUL))
            text = "*".join(num) if num else "1"
            if den:
                text += "/" + (den[0] if len(den) == 1 else "(" + "*".join(den) + ")")
            return wrap(text, _MUL, needed)
        if isinstance(e, sp.Pow):
            base, ex = e.base, e.exp
            if ex == sp.Rational(1, 2):
                return f"sqrt({go(base, 0)})"
            if ex.is_Rational and ex.is_negative:
                inverse = base if ex == -1 else sp.Pow(base, -ex, evaluate=False)
                return wrap("1/" + go(inverse, _POW), _MUL, needed + 1)
            b = go(base, _ATOM)
            if ex.is_Integer and ex >= 0:
                x = str(int(ex))
            elif isinstance(ex, sp.Symbol):
                x = ex.name
            else:
                x = "(" + go(ex, 0) + ")"
            return wrap(f"{b}^{x}", _POW, needed)
        if isinstance(e, sp.Heaviside):
            h0 = e.args[1] if len(e.args) > 1 else sp.Rational(1, 2)
            x = go(e.args[0], 0)
            if h0 == sp.Rational(1, 2):
                return f"heaviside({x})"
            # another value at 0: picked there (if(x, 1, 0) is the value at x > 0, x < 0)
            return f"if({x}, 1, if(-({x}), 0, {go(h0, 0)}))"
        if isinstance(e, (sp.Min, sp.Max)):
            fn = "min" if isinstance(e, sp.Min) else "max"
            args = [go(a, 0) for a in e.args]
            out = args[-1]
            for a in reversed(args[:-1]):
                out = f"{fn}({a}, {out})"
            return out
        if isinstance(e, sp.Piecewise):
            return piecewise(list(e.args), e)
        if isinstance(e, sp.Function):
            name = type(e).__name__
            if name in _FUNCTIONS:
                args = ", ".join(go(a, 0) for a in e.args)
                return f"{_FUNCTIONS[name]}({args})"
            raise ValueError(f"from_sympy: the model language has no function '{name}' (in {e}); "
                             "it has sin cos tan asin acos atan atan2 sinh cosh tanh exp log "
                             "sqrt abs sign Heaviside Min Max Piecewise")
        raise ValueError(f"from_sympy: cannot translate {e!r} ({type(e).__name__}) into the model "
                         "language")

    def condition(c: Any, yes: str, no: str, whole: Any) -> str:
        # the text that is `yes` where c holds and `no` elsewhere: if(g, a, b) is a where g > 0
        if c is sp.true or c == True:  # noqa: E712 (SymPy's true)
            return yes
        if c is sp.false or c == False:  # noqa: E712
            return no
        if isinstance(c, (sp.StrictGreaterThan, sp.StrictLessThan)):
            g = c.lhs - c.rhs if isinstance(c, sp.StrictGreaterThan) else c.rhs - c.lhs
            return f"if({go(g, 0)}, {yes}, {no})"
        if isinstance(c, (sp.GreaterThan, sp.LessThan)):
            # a >= b holds where b - a > 0 does not
            g = c.rhs - c.lhs if isinstance(c, sp.GreaterThan) else c.lhs - c.rhs
            return f"if({go(g, 0)}, {no}, {yes})"
        if isinstance(c, sp.Not):
            return condition(c.args[0], no, yes, whole)
        if isinstance(c, sp.And):
            out = yes
            for a in reversed(c.args):
                out = condition(a, out, no, whole)
            return out
        if isinstance(c, sp.Or):
            out = no
            for a in reversed(c.args):
                out = condition(a, yes, out, whole)
            return out
        raise ValueError(f"from_sympy: the condition {c} (in {whole}) is not a comparison "
                         "<, <=, >, >= (or And, Or, Not of them); the model language's if(c, a, b) "
                         "takes a where c > 0")

    def piecewise(pieces: List[Any], whole: Any) -> str:
        # (e1, c1), (e2, c2), …, (en, True): if(c1, e1, if(c2, e2, … en))
        if not pieces or not (pieces[-1][1] is sp.true or pieces[-1][1] == True):  # noqa: E712
            raise ValueError(f"from_sympy: {whole} is undefined where no condition holds; end it "
                             "with an otherwise piece (expr, True)")
        out = go(pieces[-1][0], 0)
        for value, c in reversed(pieces[:-1]):
            out = condition(c, go(value, 0), out, whole)
        return out

    return go(sp.sympify(expr), 0)


# --- the YAML text -----------------------------------------------------------------------------

class _Expr(str):
    """A translated expression (emitted quoted)."""


def _scalar(v: Any) -> str:
    if isinstance(v, _Expr):
        return json.dumps(str(v))
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return _number(v)
    if isinstance(v, str):
        return v if _IDENT.match(v) else json.dumps(v)
    raise ValueError(f"from_sympy: cannot write {v!r}")


def _flow(v: Any) -> str:
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_scalar(k)}: {_flow(x)}" for k, x in v.items()) + "}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_flow(x) for x in v) + "]"
    return _scalar(v)


def _block(v: Dict[str, Any], indent: int = 0) -> List[str]:
    pad = " " * indent
    lines: List[str] = []
    for key, value in v.items():
        if isinstance(value, dict) and any(isinstance(x, (dict, list)) for x in value.values()):
            lines.append(f"{pad}{_scalar(key)}:")
            lines += _block(value, indent + 2)
        elif isinstance(value, list) and value and all(isinstance(x, dict) for x in value):
            lines.append(f"{pad}{_scalar(key)}:")
            for item in value:
                lines.append(f"{pad}  - {_flow(item)}")
        else:
            lines.append(f"{pad}{_scalar(key)}: {_flow(value)}")
    return lines


def _key(k: Any) -> str:
    return _name(k) if not isinstance(k, str) else k


def sympy_to_yaml(coordinates: Sequence[Any], *, T: Any = None, V: Any = None, M: Any = None,
                  Q: Any = None, constraints: Any = None, nonideal: Any = None,
                  parameters: Optional[Mapping[Any, float]] = None,
                  initial: Optional[Mapping[str, Any]] = None,
                  simulate: Optional[Mapping[str, Any]] = None,
                  output: Optional[Mapping[str, Any]] = None,
                  requirements: Any = None, control: Optional[Mapping[str, Any]] = None,
                  name: Optional[str] = None, t: Any = None,
                  units: Optional[Mapping[Any, str]] = None,
                  visual: Optional[Mapping[str, Any]] = None,
                  tables: Optional[Mapping[str, Any]] = None) -> str:
    """The model-file text of a model given by SymPy expressions (arguments as
    :func:`from_sympy`)."""
    sp = _sympy()
    ex = lambda e: _Expr(to_expression(e, t))  # noqa: E731
    doc: Dict[str, Any] = {}
    if name is not None:
        doc["name"] = str(name)
    if parameters:
        doc["parameters"] = {_key(k): float(v) for k, v in parameters.items()}
    coords = [_name(c) for c in coordinates]
    doc["coordinates"] = coords
    n = len(coords)
    if (T is None) == (M is None):
        raise ValueError("from_sympy: give exactly one of T (kinetic energy) and M (mass matrix)")
    if T is not None:
        doc["kinetic_energy"] = ex(T)
    else:
        rows = [[ex(M[i, j]) for j in range(n)] for i in range(n)] if hasattr(M, "shape") \
            else [[ex(x) for x in row] for row in M]
        doc["mass_matrix"] = rows
    if V is not None:
        doc["potential_energy"] = ex(V)
    if Q is not None:
        items = list(Q) if not hasattr(Q, "shape") else [Q[i] for i in range(n)]
        doc["forces"] = [ex(x) for x in items]

    velocity_names = {c + "_dot" for c in coords}

    def has_velocity(e: Any) -> bool:
        e = sp.sympify(e)
        names = {s.name for s in e.free_symbols}
        return bool(names & velocity_names) or bool(e.atoms(sp.Derivative))

    def constraint_entry(cname: str, spec: Any, kinds: Sequence[str]) -> Dict[str, Any]:
        if isinstance(spec, dict):
            entry: Dict[str, Any] = {"name": cname}
            for k, v in spec.items():
                if k in kinds:
                    entry[k] = [ex(x) for x in v] if isinstance(v, (list, tuple)) else ex(v)
                elif k == "A":
                    entry[k] = [[ex(x) for x in row] for row in v]
                elif k == "b":
                    entry[k] = [ex(x) for x in v]
                else:
                    entry[k] = v
            return entry
        exprs = list(spec) if isinstance(spec, (list, tuple)) else [spec]
        kind = "nonholonomic" if any(has_velocity(e) for e in exprs) else "holonomic"
        value = [ex(x) for x in exprs] if isinstance(spec, (list, tuple)) else ex(spec)
        return {"name": cname, kind: value}

    def entries(specs: Any, kinds: Sequence[str]) -> List[Dict[str, Any]]:
        if isinstance(specs, dict):
            return [constraint_entry(str(k), v, kinds) for k, v in specs.items()]
        out = []
        for s in specs:
            s = dict(s)
            out.append(constraint_entry(str(s.pop("name")), s, kinds))
        return out

    if constraints:
        doc["constraints"] = entries(constraints, ("holonomic", "nonholonomic"))
    if nonideal:
        forces = []
        for f in nonideal:
            f = dict(f)
            if "C" in f:
                f["C"] = [ex(x) for x in f["C"]]
            if "surface_velocity" in f:
                f["surface_velocity"] = [ex(x) for x in f["surface_velocity"]]
            for key in ("mu", "mu_static", "c", "coefficient", "regularization_velocity"):
                if key in f and not isinstance(f[key], (int, float)):
                    f[key] = ex(f[key])
            if "coordinates" in f:
                f["coordinates"] = [_key(c) for c in f["coordinates"]]
            forces.append(f)
        doc["nonideal"] = forces
    if initial:
        init: Dict[str, Any] = {}
        for part in ("q", "q_dot"):
            if part in initial:
                init[part] = {_key(k): (float(v) if isinstance(v, (int, float)) else ex(v))
                              for k, v in initial[part].items()}
        if "project" in initial:
            init["project"] = bool(initial["project"])
        unknown = set(initial) - {"q", "q_dot", "project"}
        if unknown:
            raise ValueError(f"from_sympy: unknown initial keys {sorted(unknown)} "
                             "(known: q, q_dot, project)")
        doc["initial"] = init
    if simulate:
        doc["simulate"] = {str(k): (float(v) if isinstance(v, (int, float)) and not
                                    isinstance(v, bool) else v) for k, v in simulate.items()}
    if output:
        out_doc: Dict[str, Any] = {}
        for k, v in output.items():
            if k == "expressions":
                out_doc[k] = {str(nm): ex(e) for nm, e in v.items()}
            else:
                out_doc[k] = v
        doc["output"] = out_doc
    if requirements or control:
        ctrl: Dict[str, Any] = {}
        if requirements:
            ctrl["requirements"] = entries(requirements, ("holonomic", "nonholonomic"))
        for k, v in (control or {}).items():
            if k == "N":
                ctrl[k] = [[ex(x) for x in row] for row in
                           (v.tolist() if hasattr(v, "tolist") else v)]
            elif k == "actuated":
                ctrl[k] = [_key(c) for c in v]
            else:
                ctrl[k] = {_key(a): b for a, b in v.items()} if isinstance(v, dict) else v
        doc["control"] = ctrl

    # any SymPy object left in a setting (a parameter symbol as a requirement's omega, an
    # expression as a gain) is written as an expression of the model language: the reader then
    # accepts it or names it at file:line:column, instead of a traceback from here
    def settle(v: Any) -> Any:
        if isinstance(v, dict):
            return {k: settle(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return [settle(x) for x in v]
        if isinstance(v, sp.Basic) and not isinstance(v, _Expr):
            number = float(v) if v.is_number and v.is_real else None
            return number if number is not None else ex(v)
        return v

    # units: (base units and each coordinate's or output's unit), visual: (points, links,
    # frames: expressions in the coordinates) and tables: (measured data), as in the model file
    if units:
        doc["units"] = {_key(k): str(v) for k, v in units.items()}
    if visual:
        doc["visual"] = dict(visual)
    if tables:
        doc["tables"] = {str(k): v for k, v in tables.items()}
    doc = settle(doc)
    return "# written by ukdyn.sympy_to_yaml\n" + "\n".join(_block(doc)) + "\n"


def from_sympy(coordinates: Sequence[Any], *, T: Any = None, V: Any = None, M: Any = None,
               Q: Any = None, constraints: Any = None, nonideal: Any = None,
               parameters: Optional[Mapping[Any, float]] = None,
               initial: Optional[Mapping[str, Any]] = None,
               simulate: Optional[Mapping[str, Any]] = None,
               output: Optional[Mapping[str, Any]] = None, requirements: Any = None,
               control: Optional[Mapping[str, Any]] = None, name: Optional[str] = None,
               t: Any = None, units: Optional[Mapping[Any, str]] = None,
               visual: Optional[Mapping[str, Any]] = None,
               tables: Optional[Mapping[str, Any]] = None, **overrides: float) -> Any:
    """A :class:`ukdyn.Model` from SymPy expressions (the keys of docs/model-format.md).

    Args:
        coordinates: the coordinates q (symbols, names, or functions of t).
        T: the kinetic energy T(q, q', t) (velocities: the symbols ``x_dot``, or
            derivatives of functions of t); M is then ∂²T/∂q'∂q' and Q comes from Lagrange's
            equations with L = T − V.
        V: the potential energy V(q, t).
        M: the mass matrix (n × n: a SymPy Matrix or nested lists), instead of T.
        Q: the generalized forces (n): beside T the non-conservative part, with M all of it.
        constraints: ``{name: expr}`` (a list of exprs for several rows; holonomic unless the
            expression holds a velocity) or a list of dicts ``{"name", "holonomic" |
            "nonholonomic" | "A"+"b", "active": [t0, t1], "stabilization": {...}}``.
        nonideal: a list of dicts as in the model file: ``{"friction": "coulomb", "constraint":
            name, "mu": mu}``, ``{"friction": "viscous", "c": c}``, ``{"C": [exprs]}`` (the
            symbols ``N_<constraint>`` and ``lambda_<constraint>`` read the ideal reaction).
        parameters: ``{symbol or name: value}``.
        initial: ``{"q": {x: value}, "q_dot": {...}, "project": bool}``.
        simulate: the ``simulate:`` settings (t_end, integrator, rtol, ...).
        output: ``{"every": dt, "at": [...], "expressions": {name: expr}}``.
        requirements: tracking requirements, written like constraints, each with
            ``"dynamics": {"omega": w, "zeta": z}`` or ``{"alpha", "beta"}`` (holonomic) or
            ``{"rate": k}`` (nonholonomic): the ``control: requirements:`` section.
        control: the rest of the ``control:`` section: ``law`` ('gauss', 'weighted'), ``N``,
            ``actuated``, ``nominal`` (parameter overrides of the controller's model),
            ``robust`` ({bound, boundary_layer, ...}).
        name: the model's name.
        t: the time symbol, when it is not ``sympy.Symbol("t")``.
        units: the ``units:`` section: base units ``{"length": "mm", "mass": "g", "time":
            "ms"}`` (the model's numbers are then in them) and labels of coordinates or outputs
            ``{x: "mm"}`` (docs/model-format.md, "Units").
        visual: the ``visual:`` section, its expressions SymPy ones: ``{"points": {"p": [x,
            0]}, "links": [["o", "p"]]}`` — what :meth:`Result.save_animation` draws
            (docs/viewer.md).
        tables: the ``tables:`` section (measured data: ``{name: {"x": ..., "data": ...}}``,
            docs/model-format.md, "Tables").
        overrides: parameter overrides, as :func:`ukdyn.load`.

    Returns the Model, read by the C++ model reader from :func:`sympy_to_yaml`'s text (its
    ``file`` is ``"<sympy>"``). Raises ValueError for what cannot be translated and
    :class:`ukdyn.ModelError` for what the reader refuses (unknown names, a T that is not
    quadratic in the velocities, ...), pointing into that text.
    """
    from . import parse
    text = sympy_to_yaml(coordinates, T=T, V=V, M=M, Q=Q, constraints=constraints,
                         nonideal=nonideal, parameters=parameters, initial=initial,
                         simulate=simulate, output=output, requirements=requirements,
                         control=control, name=name, t=t, units=units, visual=visual,
                         tables=tables)
    return parse(text, "<sympy>", **overrides)
