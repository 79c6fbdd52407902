#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""The browser viewer of a ukdyn run: one self-contained HTML page (docs/viewer.md).

The page of Python's ``Result.show()`` / ``Result.save_animation()``. ``ukdyn run --viewer``
writes the same page itself, without Python (app/viewer_page.hpp, app/viewer_data.cpp): it
follows these functions rule for rule (decimation, rounding, the data's keys in this order, the
JSON in json.dumps's form, the template filled in one pass), so that for the same trajectory the
two pages are the same bytes (python/tests/test_viewer_page.py); a change here is made there too.

usage: viewer.py TRAJECTORY.csv SCENE.json OUTPUT.html

The scene (modelfile/visual.hpp, ``viewer_scene_json``) says what to draw: bodies (kind, mass,
principal inertias, declared solids), joints (parent, child and their points), the points,
links and trails of a ``visual:`` section; a robot's links (their joints), URDF visuals, mesh
files (base64, each once) and loops. The trajectory's columns say where: a planar body's
``<b>.x, <b>.y, <b>.theta``; a rigid body's ``<b>.x, <b>.y, <b>.z, <b>.u0 … <b>.u3``; a point's
``visual.<p>.x, .y (, .z)``; a joint's reaction ``reaction.<j>.fx, fy (, fz)`` (ideal) and
``reaction.<j>.friction_fx …`` (non-ideal), drawn at the joint's point on its child, and its
torque ``reaction.<j>.tx …``, ``reaction.<j>.friction_tx …`` (a revolute joint's friction); the control
force ``Qc_control.<c>``; the energy ``energy``. The samples are decimated to the display rate
(``fps`` frames per simulated second) and rounded to what a screen shows: positions to 1e-4 of
the scene's extent, angles and quaternions to 1e-4, forces to ``digits`` significant digits;
and the page holds three.js itself (and the loader of each mesh format it embeds): it opens
from disk, without a server or network.

Pure Python (no NumPy needed): the command runs it with whatever /usr/bin/python3 has.
"""
import csv
import errno
import json
import math
import os
import re
import stat
import sys
import tempfile

# where three.js is found when it is not beside this file (Debian's libjs-three); without it
# (a pip or venv install), the copy the extension _ukdyn embedded from there at build time
DEBIAN_THREE = "/usr/share/javascript/three"
THREE_FILES = ("three.min.js", "OrbitControls.js")
# the mesh loaders of a robot's URDF visuals, put in a page whose data holds meshes of the format
MESH_LOADERS = (("stl", "STLLoader.js"), ("obj", "OBJLoader.js"), ("dae", "ColladaLoader.js"))
TEMPLATE = "viewer_template.html"
# the page's script, put in order in place of the template's /*UKDYN_SCRIPT*/ (no file over ~900
# lines; app/embed_viewer.cmake does the same)
SCRIPTS = ("viewer_template.js", "viewer_panels.js")

# the kinds of contact event the page marks as impacts (an impact closing a contact at rest too)
IMPACT_KINDS = ("impact", "rest")

# the frames per simulated second, the most frames a page holds, the significant digits
FPS = 30.0
MAX_FRAMES = 3000
DIGITS = 4


def _embedded_script(name):
    """Debian's three.js file `name` as the extension _ukdyn embedded it at build time (a str),
    or None: built without libjs-three, or run as a script, without the package."""
    try:
        from ukdyn import _ukdyn
    except ImportError:
        return None
    data = _ukdyn._viewer_script(name)
    return None if data is None else data.decode("utf-8")


def _asset(name, here):
    """The text of an asset: beside this file, else in Debian's libjs-three, else (three.js's
    files) the copy of it embedded in the extension."""
    places = [os.path.join(here, name), os.path.join(here, "_viewer", name)]
    if name == "three.min.js":
        places.append(os.path.join(DEBIAN_THREE, name))
    elif name == "OrbitControls.js":
        places.append(os.path.join(DEBIAN_THREE, "examples", "js", "controls", name))
    elif name.endswith("Loader.js"):
        places.append(os.path.join(DEBIAN_THREE, "examples", "js", "loaders", name))
    for p in places:
        if os.path.exists(p):
            with open(p, encoding="utf-8") as f:
                return f.read()
    text = _embedded_script(name) if name != TEMPLATE else None
    if text is not None:
        return text
    raise FileNotFoundError(
        "viewer: %s not found (looked in %s and the module; install Debian's libjs-three)"
        % (name, ", ".join(places)))


def _frames(t, fps, max_frames):
    """The indices of the samples shown: about fps per simulated second (every sample when they
    are sparser), at most max_frames, always the first and the last."""
    n = len(t)
    if n == 0:
        return []
    span = t[-1] - t[0]
    wanted = min(max_frames, max(2, int(math.ceil(span * fps)) + 1)) if span > 0 else 1
    if wanted >= n:
        return list(range(n))
    out, k = [], 0
    for i in range(wanted):
        target = t[0] + span * i / (wanted - 1)
        while k + 1 < n and t[k + 1] <= target:
            k += 1
        if not out or out[-1] != k:
            out.append(k)
    if out[-1] != n - 1:
        out.append(n - 1)
    return out


def _round(v, digits):
    """v with `digits` significant digits, as a short JSON number (null when not finite)."""
    if v is None or not math.isfinite(v):
        return None
    if v == 0:
        return 0
    r = float("%.*g" % (digits, v))
    return int(r) if r.is_integer() and abs(r) < 1e15 else r


def _fixed(v, decimals):
    """v rounded to `decimals` decimal places (negative: to tens, hundreds …), as a short JSON
    number (null when not finite)."""
    if v is None or not math.isfinite(v):
        return None
    r = round(v, decimals)
    return int(r) if r.is_integer() and abs(r) < 1e15 else r


def _position_decimals(axes):
    """The decimal places that keep positions to 1e-4 of the scene's extent (the largest spread
    of the positions along x, y or z, over every position shown; their largest magnitude when
    nothing moves): a motion about 1000 m away is as sharp as one about the origin, not 4
    significant digits. axes: the values along each axis."""
    extent, largest = 0.0, 0.0
    for values in axes:
        finite = [v for v in values if v is not None and math.isfinite(v)]
        if finite:
            extent = max(extent, max(finite) - min(finite))
            largest = max(largest, max(abs(v) for v in finite))
    extent = extent if extent > 0 else (largest or 1.0)
    return 4 - int(math.floor(math.log10(extent)))


class _Packer:
    """Columns of the decimated samples as compact JSON arrays, rounded."""

    def __init__(self, names, columns, keep, digits):
        self.index = {}
        for k, name in enumerate(names):
            self.index.setdefault(name, k)
        self.columns, self.keep, self.digits = columns, keep, digits

    def has(self, name):
        return name in self.index

    def raw(self, name):
        column = self.columns[self.index[name]]
        return [float(column[i]) for i in self.keep]

    def pack(self, name, digits=None):
        d = self.digits if digits is None else digits
        return [_round(v, d) for v in self.raw(name)]

    def pack_fixed(self, name, decimals):
        return [_fixed(v, decimals) for v in self.raw(name)]


def _scale(values):
    """The magnitude drawn a quarter of the scene long: the 90th percentile of the vectors'
    finite magnitudes over the run (a peak, an impact, does not shrink every other frame's
    arrows to nothing; the viewer caps what is longer); 1 when there is none."""
    norms = sorted(math.sqrt(sum(c * c for c in v if c is not None and math.isfinite(c)))
                   for v in values)
    norms = [n for n in norms if n > 0]
    if not norms:
        return 1.0
    return norms[min(len(norms) - 1, int(0.9 * len(norms)))]


def scene_data(scene, names, columns, fps=FPS, max_frames=MAX_FRAMES, digits=DIGITS,
               contact_events=None, unit_system=None):
    """The page's data: the scene with each body's, joint's and point's decimated samples.

    scene: the dict of viewer_scene_json; names, columns: the trajectory's columns (any
    sequences of floats, e.g. a Result's arrays or the CSV's lists); contact_events: the run's
    contact events (summary.json's ``contact_events``: dicts with ``t``, ``contact``, ``kind``),
    whose impacts the page marks at the contacts of ``visual: contacts:``; unit_system: the
    model's units (summary.json's ``unit_system``), which label the page's time, energy and
    forces; None or SI: the page's SI labels.
    """
    t_all = [float(v) for v in columns[names.index("t")]] if "t" in names else []
    keep = _frames(t_all, fps, max_frames)
    p = _Packer(names, columns, keep, digits)
    data = {
        "model": scene.get("model", ""),
        "planar": bool(scene.get("planar", True)),
        "t": p.pack("t", 7) if keep else [],
        "energy": p.pack("energy", 6) if p.has("energy") else None,
        "bodies": [], "joints": [], "points": [], "links": scene.get("links", []),
        "trails": scene.get("trails", []), "frames": [], "requirements": [],
        # each coordinate's unit, where known (the page labels forces by them)
        "units": {c: u for c, u in zip(scene.get("coordinates", []),
                                       scene.get("coordinate_units", [])) if u},
    }
    # positions to 1e-4 of the scene's extent, angles and quaternions to 1e-4
    along = {"x": [], "y": [], "z": []}
    for b in scene.get("bodies", []):
        for a in along:
            along[a].append(b["name"] + "." + a)
    for pt in scene.get("points", []) + scene.get("frames", []):
        for a in ("x", "y", "z")[: pt.get("dimensions", 2)]:
            along[a].append("visual.%s.%s" % (pt["name"], a))
    positions = [[v for c in cols if p.has(c) for v in p.raw(c)] for cols in along.values()]
    decimals = _position_decimals(positions) if keep else 4

    def position(column):
        return p.pack_fixed(column, decimals)

    def angle(column):
        return p.pack_fixed(column, 4)

    # bodies: planar (x, y, theta), rigid (x, y, z, u0..u3), particle (x, y, z)
    for b in scene.get("bodies", []):
        name, kind = b["name"], b["kind"]
        keys = {"planar": ("x", "y", "theta"), "rigid": ("x", "y", "z", "u0", "u1", "u2", "u3"),
                "particle": ("x", "y", "z")}[kind]
        body = dict(b)
        body["q"] = [(position if k in ("x", "y", "z") else angle)(name + "." + k) for k in keys]
        control = ["Qc_control.%s.%s" % (name, k) for k in ("x", "y", "z")]
        if any(p.has(c) for c in control):
            body["control"] = [p.pack(c) if p.has(c) else None for c in control]
        # the control torque: a planar body's about z (Qc_control.<b>.theta); a rigid body's
        # from the generalized forces on its quaternion (_quaternion_torque)
        theta = "Qc_control.%s.theta" % name
        quaternion = ["Qc_control.%s.u%d" % (name, k) for k in range(4)]
        if kind == "planar" and p.has(theta):
            body["control_torque"] = [None, None, p.pack(theta)]
        elif kind == "rigid" and all(p.has(c) for c in quaternion):
            torque = _quaternion_torque([p.raw("%s.u%d" % (name, k)) for k in range(4)],
                                        [p.raw(c) for c in quaternion])
            body["control_torque"] = [[_round(v, digits) for v in c] for c in torque]
        data["bodies"].append(body)
    # joints: the reaction force at the child's point, ideal and non-ideal (friction), and the
    # reaction torque, ideal and non-ideal (a revolute joint's friction torque)
    for j in scene.get("joints", []):
        joint = dict(j)
        base = "reaction.%s." % j["name"]
        for key, prefix in (("ideal", ""), ("nonideal", "friction_")):
            for suffix, parts in (("", ("fx", "fy", "fz")), ("_torque", ("tx", "ty", "tz"))):
                cols = [base + prefix + c for c in parts]
                if any(p.has(c) for c in cols):
                    joint[key + suffix] = [p.pack(c) if p.has(c) else None for c in cols]
        data["joints"].append(joint)
    # points of a visual: section; a point whose components are each exactly a coordinate
    # (the scene says which: `bob: [x, y]`) carries the generalized constraint (and control)
    # forces of those coordinates
    for pt in scene.get("points", []):
        point = dict(pt)
        axes = ("x", "y", "z")[: pt.get("dimensions", 2)]
        cols = ["visual.%s.%s" % (pt["name"], a) for a in axes]
        point["q"] = [position(c) for c in cols]
        same = list(pt.get("coordinates") or [None] * len(cols))
        if same and all(same):
            for key, prefix in (("ideal", "Qc_ideal."), ("nonideal", "Qc_nonideal."),
                                ("control", "Qc_control.")):
                if all(p.has(prefix + q) for q in same):
                    point[key] = [p.pack(prefix + q) for q in same]
        data["points"].append(point)
    # frames of a visual: section: origin, and angle about z or quaternion
    for fr in scene.get("frames", []):
        frame = dict(fr)
        axes = ("x", "y", "z")[: fr.get("dimensions", 2)]
        frame["q"] = [position("visual.%s.%s" % (fr["name"], a)) for a in axes]
        parts = ("qw", "qx", "qy", "qz") if fr.get("quaternion") else ("angle",)
        frame["r"] = [angle("visual.%s.%s" % (fr["name"], c)) for c in parts]
        data["frames"].append(frame)
    # a robot's links (robot: or a .urdf, docs/robots.md): each link's joint with its
    # coordinates' samples (angles, displacements, a floating base's position and quaternion,
    # to 1e-4); the page computes the frames (forward kinematics) and draws the links between
    # them and the joint axes
    if scene.get("robot"):
        robot = dict(scene["robot"])
        robot["links"] = []
        for link in scene["robot"].get("links", []):
            link = dict(link)
            link["q"] = [p.pack_fixed(c, 4) for c in link.get("coordinates", [])]
            robot["links"].append(link)
        data["robot"] = robot
    # contacts of visual: contacts: (docs/contact.md): the contact point, the direction its
    # force pushes (normalized by the page), the force's magnitude (the multiplier
    # lambda.<name>: the normal force when the gap is a distance), and the impacts (their time
    # and contact; the page finds the place at that time)
    if scene.get("contacts"):
        data["contacts"] = []
        for c in scene["contacts"]:
            contact = dict(c)
            base = "visual.contact.%s." % c["name"]
            axes = ("x", "y", "z")[: c.get("dimensions", 2)]
            contact["q"] = [position(base + a) for a in axes]
            contact["n"] = [angle(base + "n" + a) for a in axes]
            # the whole multiplier (lambda_total: with the share of the non-ideal forces)
            total = "lambda_total." + c["name"]
            contact["force"] = p.pack(total if p.has(total) else "lambda." + c["name"])
            if c.get("friction"):
                contact["friction_force"] = _friction_force(p, c["friction"])
            data["contacts"].append(contact)
        drawn = set(c["name"] for c in scene["contacts"])
        data["impacts"] = [{"t": _round(float(e["t"]), 7), "contact": e["contact"]}
                           for e in contact_events or []
                           if e.get("kind") in IMPACT_KINDS and e.get("contact") in drawn]
    # the control's requirements: the error of each row (actual minus desired), over time, and
    # where the requirement says what is desired (desired_<row>), the desired and the actual
    # value (actual = desired + error); a requirement whose rows are, in some order, the
    # coordinates of a point or a body of the scene gets its desired path drawn in the scene
    rows = _requirement_rows(names)
    actual = {}  # each row's actual value (desired + error) at the samples shown
    for row, error, desired in rows:
        entry = {"name": row, "error": p.pack(error)}
        if desired:
            actual[row] = [d + e for d, e in zip(p.raw(desired), p.raw(error))]
            entry["desired"] = p.pack(desired)
            entry["actual"] = [_round(v, digits) for v in actual[row]]
        data["requirements"].append(entry)
    data["desired_paths"] = _desired_paths(scene, p, rows, actual, decimals)
    for path in data["desired_paths"]:
        if path["of"] not in data["trails"]:
            data["trails"] = data["trails"] + [path["of"]]
    # a kind of force that is zero throughout (no friction, no control) draws no arrows; nor
    # does a torque that is round-off (a planar revolute joint's ideal torque about z, 1e-14 N m):
    # at most 1e-9 of the largest joint force times the scene's extent
    kinds = ("ideal", "nonideal", "control", "ideal_torque", "nonideal_torque", "control_torque")
    largest_force = max([abs(v) for j in data["joints"] for key in ("ideal", "nonideal")
                         for c in j.get(key) or [] if c for v in c if v is not None] or [0.0])
    extent = 10.0 ** (4 - decimals)  # the scene's extent, to its power of ten
    for item in data["joints"] + data["points"] + data["bodies"]:
        for key in kinds:
            if key not in item:
                continue
            floor = 1e-9 * largest_force * extent if key.endswith("_torque") else 0.0
            if not any(abs(v) > floor for c in item[key] if c for v in c if v is not None):
                del item[key]
    # the scales of the force (and torque) arrows: the largest of each kind over the run
    for key in kinds:
        vectors = []
        for item in data["joints"] + data["points"] + data["bodies"]:
            if item.get(key):
                comps = [c for c in item[key] if c is not None]
                vectors.extend(zip(*comps))
        data.setdefault("force_scale", {})[key] = _scale(vectors)
    if "contacts" in data:
        data["force_scale"]["contact"] = _scale([[v] for c in data["contacts"]
                                                 for v in c["force"]])
    # the model's units when not SI, last as app/viewer.cpp adds them (the page's labels:
    # docs/model-format.md, "Units")
    if unit_system and unit_system.get("energy", "J") != "J":
        data["unit_system"] = {k: unit_system[k] for k in ("length", "time", "force", "energy")
                               if k in unit_system}
    return data


def _quaternion_torque(u, Q):
    """The torque (world axes) of the generalized forces Q = (Q0, Qx, Qy, Qz) on a unit
    quaternion u = (w, x, y, z), per sample: tau = 1/2 E(u) Q with E(u) = [-v | w I + [v]x]
    (omega = 2 E(u) u', so tau . omega = Q . u' for every motion; Q's part along u does no
    work). app/viewer_data.cpp's quaternion_torque, operation for operation."""
    out = [[], [], []]
    for w, x, y, z, q0, qx, qy, qz in zip(*u, *Q):
        out[0].append(0.5 * (w * qx - x * q0 + (y * qz - z * qy)))
        out[1].append(0.5 * (w * qy - y * q0 + (z * qx - x * qz)))
        out[2].append(0.5 * (w * qz - z * q0 + (x * qy - y * qx)))
    return out


def _friction_force(p, friction):
    """The friction force at a contact in the scene's axes, per frame shown: F = map Q_f, Q_f
    each sliding coordinate's generalized friction force (the sum of its columns, one each: the
    run's visual.contact.<name>.Qf.<coordinate>, the stick constraint's whole multiplier while
    the contact holds and Qc_nonideal.<coordinate> while it slides; the scene's ``friction``,
    src/modelfile/visual.cpp). The page draws its part across the normal."""
    sums = []
    for columns in friction["columns"]:
        total = None
        for column in columns:
            values = p.raw(column)
            total = values if total is None else [a + b for a, b in zip(total, values)]
        sums.append(total)
    out = []
    for row in friction["map"]:
        comp = []
        for i in range(len(sums[0])):
            f = 0.0
            for j, weight in enumerate(row):
                f += weight * sums[j][i]
            comp.append(_round(f, p.digits))
        out.append(comp)
    return out


def _requirement_rows(names):
    """(row, error column, desired column or None) of each requirement row: error.<row> and
    desired_<row> with the row's dots written as underscores (error.tip.0, desired_tip_0)."""
    present = set(names)
    out = []
    for name in names:
        if name.startswith("error."):
            row = name[len("error."):]
            desired = "desired_" + row.replace(".", "_")
            out.append((row, name, desired if desired in present else None))
    return out


def _desired_paths(scene, p, rows, actual, decimals):
    """The requirements whose desired value is a path in the scene: a requirement whose rows
    (error.<name>.0, .1 (, .2), each with its desired value) are, in some order, the positions
    x, y (, z) of a visual point or of a body's centre: the actual value of each row (desired +
    error) equals that coordinate at every sample shown, to 1e-9 of the scene's extent (the same
    expression evaluated twice; `actual` maps each row to those values). Returns, for each, the
    point or body ("of") and the desired
    position along x, y (, z) at each sample ("q")."""
    groups = {}
    for row, error, desired in rows:
        base, _, k = row.rpartition(".")
        if base and k.isdigit() and desired:
            groups.setdefault(base, []).append((int(k), row, desired))
    candidates = [("visual.%s." % pt["name"], pt["name"], pt.get("dimensions", 2))
                  for pt in scene.get("points", [])]
    candidates += [(b["name"] + ".", b["name"], 2 if b["kind"] == "planar" else 3)
                   for b in scene.get("bodies", [])]
    tolerance = 1e-9 * 10.0 ** (4 - decimals)
    out = []
    for base, parts in groups.items():
        parts.sort()
        if len(parts) not in (2, 3) or [k for k, _, _ in parts] != list(range(len(parts))):
            continue
        values_of = [actual[row] for _, row, _ in parts]
        for prefix, name, dimensions in candidates:
            axes = [prefix + a for a in ("x", "y", "z")[:dimensions]]
            if dimensions != len(parts) or not all(p.has(c) for c in axes):
                continue
            # which row is which axis: each axis the one row that equals it throughout
            order = []
            for c in axes:
                along = p.raw(c)
                match = [r for r, values in enumerate(values_of)
                         if r not in order and all(math.isfinite(a) and abs(a - v) <= tolerance
                                                   for a, v in zip(values, along))]
                if not match:
                    break
                order.append(match[0])
            if len(order) == dimensions:
                out.append({"requirement": base, "of": name,
                            "q": [p.pack_fixed(parts[r][2], decimals) for r in order]})
                break
    return out


def _point_columns(scene):
    return ["visual.%s.%s" % (pt["name"], a) for pt in scene.get("points", [])
            for a in ("x", "y", "z")[: pt.get("dimensions", 2)]]


def nonfinite_warnings(scene, first):
    """The warnings for the visual points that are not finite (NaN or infinite: log of a
    negative number, …), which the page hides while so: first maps a point's column to the
    first time it is not finite."""
    out = []
    for pt in scene.get("points", []):
        axes = ("x", "y", "z")[: pt.get("dimensions", 2)]
        bad = [(first[c], a, k) for k, a in enumerate(axes)
               for c in ["visual.%s.%s" % (pt["name"], a)] if c in first]
        if not bad:
            continue
        t, axis, k = min(bad)
        expressions = pt.get("expressions") or []
        what = "%s: %s" % (axis, expressions[k]) if k < len(expressions) else axis
        out.append("warning: visual point '%s' is not finite from t = %.9g (its expression %s); "
                   "the viewer hides it while so" % (pt["name"], t, what))
    return out


def read_contact_events(summary_path):
    """The contact events of a run's summary.json (a list; empty when the file is missing, not
    JSON, or has none)."""
    try:
        with open(summary_path, encoding="utf-8") as f:
            summary = json.load(f)
    except (OSError, ValueError):
        return []
    events = summary.get("contact_events") if isinstance(summary, dict) else None
    return [e for e in events if isinstance(e, dict)] if isinstance(events, list) else []


def read_unit_system(summary_path):
    """The model's units of a run's summary.json (``unit_system``: a dict), or None."""
    try:
        with open(summary_path, encoding="utf-8") as f:
            summary = json.load(f)
    except (OSError, ValueError):
        return None
    system = summary.get("unit_system") if isinstance(summary, dict) else None
    return system if isinstance(system, dict) else None


def _three_text(scene, here):
    """three.js and OrbitControls, then the loader of each mesh format the robot's visuals embed
    (in MESH_LOADERS' order), joined by newlines (app/viewer.cpp's viewer_three_text)."""
    files = list(THREE_FILES)
    robot = scene.get("robot")
    visuals = robot.get("visuals", []) if isinstance(robot, dict) else []
    for fmt, loader in MESH_LOADERS:
        if any("file" in v and v.get("format") == fmt for v in visuals):
            files.append(loader)
    return "\n".join(_asset(n, here) for n in files)


def build_page(scene, names, columns, title=None, **options):
    """The HTML page (a str) of a run: its scene (dict) and its columns (see scene_data)."""
    here = os.path.dirname(os.path.abspath(__file__))
    data = scene_data(scene, names, columns, **options)
    template = page_template(here)
    three = _three_text(scene, here)
    payload = _json_for_html(data)
    # no "</script" inside three.js's script element
    three = three.replace("</script", "<\\/script")
    title = title or ("ukdyn: " + str(data["model"]))
    # one pass over the template: what is put in (a name in the title or the data) is never
    # searched for a placeholder
    parts = {"<!--UKDYN_TITLE-->": _escape(title), "/*UKDYN_THREE*/": three,
             "/*UKDYN_DATA*/null": payload}
    return re.sub("|".join(re.escape(k) for k in parts), lambda m: parts[m.group(0)], template)


def page_template(here):
    """The page's template: viewer_template.html with the script files (SCRIPTS, concatenated)
    in place of its /*UKDYN_SCRIPT*/, as app/embed_viewer.cmake embeds it in the command."""
    template = _asset(TEMPLATE, here)
    return template.replace("/*UKDYN_SCRIPT*/", "".join(_asset(n, here) for n in SCRIPTS), 1)


def _json_for_html(data):
    """`data` as JSON text that an HTML parser cannot take for anything but the text of its
    <script type="application/json"> element: every <, > and & (only ever inside strings) and
    U+2028/U+2029 written as \\u escapes, so that no name (</script>, <!--, <script>) can end
    the element or change how it is parsed; the page reads it with JSON.parse."""
    # (ensure_ascii: every character beyond ASCII, U+2028/9 among them, is a \\u escape)
    text = json.dumps(data, separators=(",", ":"), allow_nan=False, ensure_ascii=True)
    for c in "<>&":
        text = text.replace(c, "\\u%04x" % ord(c))
    return text


def _escape(text):
    return (text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;"))


def _umask():
    """The process's umask (read from /proc where it can be, without changing it)."""
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_replacing(path, write):
    """Writes `path` whole or not at all, safe in a directory that others can write: a path
    that exists and is not a regular file (a symbolic link, a FIFO, a directory) is refused with
    OSError before anything is written; write(f) fills a binary file object opened on a
    temporary of unpredictable name beside `path` (tempfile.mkstemp: O_EXCL, O_NOFOLLOW),
    which is then renamed over `path`, with the mode that open() would have given it. (The same
    function is in ukdyn/plotting.py, which is run on its own as a script.)"""
    path = os.fspath(path)
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        mode = None
    if mode is not None and not stat.S_ISREG(mode):
        raise OSError(errno.EEXIST, "exists and is not a regular file (a symbolic link, a FIFO "
                      "or a directory): not written over", path)
    directory, name = os.path.split(os.path.abspath(path))
    fd, temporary = tempfile.mkstemp(prefix="." + name + ".", suffix=".tmp", dir=directory)
    try:
        with os.fdopen(fd, "wb") as f:
            os.fchmod(f.fileno(), 0o666 & ~_umask())
            write(f)
        os.replace(temporary, path)
    except BaseException:
        try:
            os.remove(temporary)
        except OSError:
            pass
        raise


def write_page(path, page):
    """Writes the page (a str) to `path` whole or not at all (write_replacing)."""
    write_replacing(path, lambda f: f.write(page.encode("utf-8")))


def read_csv(path, fps=FPS, max_frames=MAX_FRAMES, watch=(), first_nonfinite=None):
    """The CSV's column names and the columns (lists of floats) of the rows shown only: those
    _frames() picks, found in two passes over the file, so that memory stays O(frames × columns)
    however long the run (ukdyn run streams any number of rows to trajectory.csv).
    first_nonfinite (a dict), when given, gets the first time each column named in `watch` is
    not finite, over every row."""
    # pass 1: the number of rows, the first and the last time (and where watched columns fail)
    n, t0, t1 = 0, None, None
    with open(path, newline="") as f:
        header = next(csv.reader([f.readline()]))
        watched = [(header.index(c), c) for c in watch if c in header]
        for line in f:
            if not line.strip():
                continue
            t1 = float(line.split(",", 1)[0])
            if t0 is None:
                t0 = t1
            n += 1
            if watched:
                fields = line.split(",")
                for k, c in watched:
                    if c not in first_nonfinite and not math.isfinite(float(fields[k])):
                        first_nonfinite[c] = t1
    data = [[] for _ in header]
    if n == 0:
        return header, data
    span = t1 - t0
    wanted = min(max_frames, max(2, int(math.ceil(span * fps)) + 1)) if span > 0 else 1
    # pass 2: row j is shown when a target time lies in [t_j, t_(j+1)) (as _frames), or is last
    def keep(row):
        for j, value in enumerate(row):
            data[j].append(float(value))
    k, previous = 0, None
    with open(path, newline="") as f:
        rows = csv.reader(f)
        next(rows)
        for row in rows:
            if not row:
                continue
            t = float(row[0])
            if previous is not None:
                shown = wanted >= n
                while k < wanted and t0 + span * k / max(wanted - 1, 1) < t:
                    shown, k = True, k + 1
                if shown:
                    keep(previous)
            previous = row
    keep(previous)
    return header, data


def main(argv):
    if len(argv) != 4:
        sys.stderr.write("usage: viewer.py TRAJECTORY.csv SCENE.json OUTPUT.html\n")
        return 2
    with open(argv[2], encoding="utf-8") as f:
        scene = json.load(f)
    # already decimated: build_page keeps every row
    first = {}
    names, columns = read_csv(argv[1], watch=_point_columns(scene), first_nonfinite=first)
    for line in nonfinite_warnings(scene, first):
        sys.stderr.write(line + "\n")
    # the impacts: from summary.json beside the trajectory, as the command reads them
    summary = os.path.join(os.path.dirname(os.path.abspath(argv[1])), "summary.json")
    events = read_contact_events(summary)
    write_page(argv[3], build_page(scene, names, columns, contact_events=events,
                                   unit_system=read_unit_system(summary)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
