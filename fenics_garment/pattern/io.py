"""Read and write sewing patterns: fenics-garment's own format (TOML or JSON), and dispatch.

:func:`read_pattern` reads by suffix: ``.toml`` ours, ``.json`` ours unless it is a
GarmentCode specification (a top-level ``"pattern"`` holding ``"panels"``, :mod:`.garmentcode`),
``.dxf`` a DXF-AAMA / ASTM D6673 file (:mod:`.dxf`); every reader validates
(:mod:`.validate`) and returns outlines counter-clockwise. :func:`write_pattern` writes ours.

Our format
----------
The same structure in TOML and JSON (in JSON ``panel`` and ``seam`` are lists of objects).
Lengths are in the file's ``units``, angles in degrees, fractions unitless. Unknown keys are
refused (a misspelt key is an error, not a silently ignored line)::

    name = "tee"                 # optional; default: the file name
    units = "mm"                 # required: "mm", "cm" or "m"

    [[panel]]
    name = "front"               # required, unique
    fabric = "cotton"            # optional: the scene's [garment] fabric (one fabric per garment: a
                                 # panel naming another is refused)
    grain = [0, 1]               # required: the warp direction in the panel's plane
    start = [0, 0]               # where the outline starts (or `from` on the first edge)
    edges = [                    # the outline, one edge to the next; the last closes it
      { to = [500, 0], name = "hem" },                          # curve = "line" (default)
      { to = [500, 600], name = "side_left" },
      { to = [0, 600], curve = "arc", through = [250, 650] },   # arc through a point
      { to = [0, 0], curve = "bezier", controls = [[-20, 300]] },  # 1 or 2 control points
    ]
    # other curves: { to = [x, y], curve = "arc", radius = r, large = false, ccw = true }
    #   (SVG flags: large: sweeps > 180°; ccw: turns left, bulging to the right of the
    #   chord, outwards on a counter-clockwise outline; defaults false and true)
    #   { to = [x, y], curve = "polyline", points = [[x, y], ...] } (the points between)
    # `to` may be left out on the last edge (it closes to the start); `from` on any edge
    # states where it starts (it must be where the previous edge ends).
    placement = { translation = [0, 1000, 150], rotation = [0, 0, 0] }   # optional
    #   rotation: intrinsic X-Y-Z Euler angles (R = Rx Ry Rz, GarmentCode's), the plane
    #   point (x, y, 0) goes to R (x, y, 0) + translation
    wrap = { axis = "torso", azimuth = -90, top = 1450 }   # optional, model.Wrap:
    #   the automatic wrap: axis torso, arm_left, arm_right, leg_left, leg_right or none;
    #   azimuth: degrees from the body's left (+x) counter-clockwise seen from above (front
    #   −90, back 90); top: the height of the panel's top, or a landmark name ("neck_base")
    darts = [["dart_in", "dart_out"]]    # pairs of this panel's edges sewn together, or
    # darts = [{ a = 3, b = 4, reversed = true, name = "waist_dart" }]

    [[seam]]
    name = "side_left"           # optional: the seam's tag in the mesh
    a = { panel = "front", edge = "side_left" }       # edge: name or index (from 0)
    b = { panel = "back", edge = 1, from = 0, to = 1 } # from/to: arc-length fractions
    reversed = true              # default: a's `from` meets b's `to` (side-by-side panels)
    kind = "seam"                # or "dart" (default "seam"; panel `darts` are "dart")

A range with ``from > to`` runs against its edge: it is read as ``to … from`` with
``reversed`` flipped, so that the same points meet.

A DXF pattern with seams
------------------------
DXF-AAMA has no seams; a companion file in our format names the DXF and adds them::

    units = "mm"                 # the units of this file's numbers (placements)
    source = "shirt.dxf"         # relative to this file
    dxf_units = "cm"             # optional: overrides the DXF's own unit declaration
    [[panel]]                    # optional, per DXF piece: no `edges`, `start`
    name = "FRONT"               # the piece name of the DXF
    edge_names = ["hem", "side_left", "", "neck"]   # names for the DXF's edges, in order
    fabric = "cotton"            # and `grain` (overrides the DXF's), `placement`, `wrap`,
                                 # `darts`
    [[seam]]
    a = { panel = "FRONT", edge = "side_left" }
    b = { panel = "BACK", edge = 3 }

A DXF piece's edges are numbered as :mod:`.dxf` says: counter-clockwise from the turn point
nearest the lower-left corner of the piece's bounding box.

TOML writing: ``tomli_w`` is not a dependency; the writer here emits the small subset this
format needs (tables, arrays of tables, inline tables, arrays, strings, numbers, booleans) and
is checked by reading its output back with :mod:`tomllib`.
"""

from __future__ import annotations

import json
import math
import re
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from fenics_garment import bounded

from .model import (
    UNITS,
    Arc,
    Bezier,
    Edge,
    EdgeRange,
    Line,
    Panel,
    Pattern,
    PatternError,
    Placement,
    Polyline,
    Seam,
    Wrap,
    arc_from_radius,
    euler_xyz,
    rotation_xyz,
)
from .validate import checked, normalised_range

TOP_KEYS = {"name", "units", "source", "dxf_units", "panel", "seam"}
PANEL_KEYS = {"name", "fabric", "grain", "start", "edges", "placement", "wrap", "darts"}
COMPANION_PANEL_KEYS = {"name", "fabric", "grain", "placement", "wrap", "darts", "edge_names"}
EDGE_KEYS = {"to", "from", "name", "curve"}
CURVE_KEYS = {
    "line": set(),
    "arc": {"through", "radius", "large", "ccw"},
    "bezier": {"controls"},
    "polyline": {"points"},
}
PLACEMENT_KEYS = {"translation", "rotation"}
WRAP_KEYS = {"axis", "azimuth", "top"}
SEAM_KEYS = {"a", "b", "reversed", "name", "kind"}
RANGE_KEYS = {"panel", "edge", "from", "to"}
DART_KEYS = {"a", "b", "reversed", "name"}


# ---------------------------------------------------------------------------------- reading


def read_pattern(path: str | Path, *, seam_tolerance: float = 0.02) -> Pattern:
    """Read a pattern file by its suffix (module docstring), validated, outlines CCW."""
    path = Path(path)
    _check_file(path)
    suffix = path.suffix.lower()
    if suffix == ".dxf":
        from .dxf import read_dxf

        return read_dxf(path, seam_tolerance=seam_tolerance)
    if suffix not in (".json", ".toml"):
        raise PatternError(f"{path}: unknown pattern file type {suffix!r} (.toml, .json, .dxf)")
    data = load_data(path)
    if suffix == ".json" and is_garmentcode(data):
        from .garmentcode import pattern_from_spec

        return pattern_from_spec(data, source=str(path), seam_tolerance=seam_tolerance)
    return pattern_from_data(data, source=str(path), seam_tolerance=seam_tolerance)


def _check_file(path: Path) -> None:
    """PatternError unless ``path`` is a regular file of at most
    :data:`~fenics_garment.bounded.MAX_PATTERN_BYTES` (a FIFO would block, a device never end)."""
    try:
        bounded.check_regular(path, bounded.MAX_PATTERN_BYTES, "pattern")
    except bounded.BoundError as e:
        raise PatternError(str(e)) from None
    except OSError as e:
        raise PatternError(f"{bounded.cut_path(path)}: cannot read: {_one_line(e)}") from None


def load_data(path: Path) -> Any:
    """The parsed TOML or JSON of a file; a syntax error becomes a one-line PatternError."""
    try:
        raw = bounded.read_bytes(path, bounded.MAX_PATTERN_BYTES, "pattern")
        parse = tomllib.loads if path.suffix.lower() == ".toml" else json.loads
        data = parse(raw.decode("utf-8"))
        bounded.check_depth(data, str(path))
        return data
    except bounded.BoundError as e:
        raise PatternError(str(e)) from None
    except RecursionError:
        raise PatternError(f"{path}: nested deeper than {bounded.MAX_DEPTH} levels") from None
    except (tomllib.TOMLDecodeError, json.JSONDecodeError, UnicodeDecodeError) as e:
        raise PatternError(f"{path}: not valid {path.suffix[1:].upper()}: {_one_line(e)}") from None
    except OSError as e:
        raise PatternError(f"{path}: cannot read: {_one_line(e)}") from None


def is_garmentcode(data: Any) -> bool:
    """Whether parsed JSON is a GarmentCode specification (``{"pattern": {"panels": …}}``)."""
    return (
        isinstance(data, dict)
        and isinstance(data.get("pattern"), dict)
        and "panels" in data["pattern"]
    )


def _one_line(e: object) -> str:
    return " ".join(str(e).split())


def _keys(d: Any, allowed: set[str], where: str) -> dict:
    if not isinstance(d, dict):
        raise PatternError(f"{where}: expected a table, got {d!r}")
    bad = sorted(set(d) - allowed)
    if bad:
        raise PatternError(f"{where}: unknown key {bad[0]!r} (known: {sorted(allowed)})")
    return d


def _number(v: Any, where: str, what: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise PatternError(f"{where}: {what} must be a finite number, got {v!r}")
    return float(v)


def _vector(v: Any, n: int, where: str, what: str) -> np.ndarray:
    if not isinstance(v, (list, tuple)) or len(v) != n:
        raise PatternError(f"{where}: {what} must be a list of {n} numbers, got {v!r}")
    return np.array([_number(x, where, what) for x in v])


def _bool(v: Any, where: str, what: str) -> bool:
    if not isinstance(v, bool):
        raise PatternError(f"{where}: {what} must be true or false, got {v!r}")
    return v


def _string(v: Any, where: str, what: str) -> str:
    if not isinstance(v, str):
        raise PatternError(f"{where}: {what} must be a string, got {v!r}")
    return v


def _units(data: dict, key: str, where: str) -> float:
    u = data.get(key)
    if u is None:
        raise PatternError(f"{where}: `{key}` is required ({' | '.join(UNITS)})")
    if u not in UNITS:
        raise PatternError(f"{where}: unknown unit {u!r} in `{key}` (known: {list(UNITS)})")
    return UNITS[u]


def _curve(e: dict, kind: str, p0, p1, where: str, scale: float):
    extra = sorted(set(e) - EDGE_KEYS - CURVE_KEYS[kind])
    if extra:
        raise PatternError(f"{where}: key {extra[0]!r} does not belong to a {kind} edge")
    if kind == "line":
        return Line(p0, p1)
    if kind == "arc":
        if ("through" in e) == ("radius" in e):
            raise PatternError(f"{where}: an arc needs either `through` or `radius`")
        if "through" in e:
            if "large" in e or "ccw" in e:
                raise PatternError(f"{where}: `large` and `ccw` go with `radius`, not `through`")
            arc = Arc(p0, p1, _vector(e["through"], 2, where, "through") * scale)
        else:
            r = _number(e["radius"], where, "radius") * scale
            chord = float(np.linalg.norm(p1 - p0))
            if r < chord / 2 * (1 - 1e-9):
                raise PatternError(
                    f"{where}: radius {e['radius']} is less than half the chord "
                    f"({chord / 2 / scale:.6g})"
                )
            large = _bool(e.get("large", False), where, "large")
            ccw = _bool(e.get("ccw", True), where, "ccw")
            arc = arc_from_radius(p0, p1, r, large=large, ccw=ccw)
        arc.circle  # noqa: B018 - a degenerate arc raises here, with the edge named
        return arc
    if kind == "bezier":
        c = e.get("controls")
        if not isinstance(c, list) or len(c) not in (1, 2):
            raise PatternError(f"{where}: `controls` must be a list of 1 or 2 points")
        return Bezier(p0, p1, tuple(_vector(x, 2, where, "a control point") * scale for x in c))
    pts = e.get("points", [])
    if not isinstance(pts, list):
        raise PatternError(f"{where}: `points` must be a list of points")
    inner = [_vector(x, 2, where, "a point") * scale for x in pts]
    return Polyline(np.array([p0, *inner, p1]))


def _outline(tbl: dict, where: str, scale: float) -> tuple[Edge, ...]:
    specs = tbl.get("edges")
    if not isinstance(specs, list) or not specs:
        raise PatternError(f"{where}: `edges` must be a non-empty list of edges")
    cur = _vector(tbl["start"], 2, where, "start") * scale if "start" in tbl else None
    first = None
    edges = []
    for i, e in enumerate(specs):
        name = e.get("name", "") if isinstance(e, dict) else ""
        ew = f"{where}, edge {i}" + (f" {name!r}" if name else "")
        _keys(e, EDGE_KEYS | set().union(*CURVE_KEYS.values()), ew)
        name = _string(name, ew, "name")
        if "from" in e:
            p0 = _vector(e["from"], 2, ew, "from") * scale
            if i == 0 and cur is not None and not np.allclose(p0, cur, rtol=0, atol=1e-12):
                raise PatternError(f"{ew}: `from` differs from the panel's `start`")
        elif cur is None:
            raise PatternError(f"{ew}: the first edge needs `from` (or the panel `start`)")
        else:
            p0 = cur
        if first is None:
            first = p0
        if "to" in e:
            p1 = _vector(e["to"], 2, ew, "to") * scale
        elif i == len(specs) - 1:
            p1 = first
        else:
            raise PatternError(f"{ew}: `to` is required (only the last edge may leave it out)")
        kind = e.get("curve", "line")
        if kind not in CURVE_KEYS:
            raise PatternError(f"{ew}: unknown curve {kind!r} (known: {list(CURVE_KEYS)})")
        try:
            curve = _curve(e, kind, p0, p1, ew, scale)
        except PatternError as err:
            if str(err).startswith(ew):
                raise
            raise PatternError(f"{ew}: {err}") from None
        edges.append(Edge(curve, name))
        cur = p1
    return tuple(edges)


def _placement(v: Any, where: str, scale: float) -> Placement:
    w = f"{where}, placement"
    _keys(v, PLACEMENT_KEYS, w)
    t = _vector(v["translation"], 3, w, "translation") * scale if "translation" in v else None
    r = rotation_xyz(_vector(v["rotation"], 3, w, "rotation")) if "rotation" in v else None
    return Placement(np.zeros(3) if t is None else t, np.eye(3) if r is None else r)


def _wrap(v: Any, where: str, scale: float) -> Wrap:
    w = f"{where}, wrap"
    _keys(v, WRAP_KEYS, w)
    top = v.get("top")
    if top is not None and not isinstance(top, str):
        top = _number(top, w, "top") * scale
    azimuth = _number(v["azimuth"], w, "azimuth") if "azimuth" in v else None
    try:
        return Wrap(_string(v.get("axis", "torso"), w, "axis"), azimuth, top)
    except PatternError as err:
        raise PatternError(f"{w}: {err}") from None


def _edge_of(panel: Panel, key: Any, where: str) -> int:
    if isinstance(key, bool) or not isinstance(key, (int, str)):
        raise PatternError(f"{where}: an edge is a name or an index, got {key!r}")
    try:
        return panel.edge_index(key)
    except PatternError as err:
        raise PatternError(f"{where}: {err}") from None


def _darts(panel: Panel, v: Any, where: str) -> list[Seam]:
    if not isinstance(v, list):
        raise PatternError(f"{where}: `darts` must be a list")
    out = []
    for k, d in enumerate(v):
        w = f"{where}, dart {k}"
        if isinstance(d, list):
            if len(d) != 2:
                raise PatternError(f"{w}: a dart is a pair of edges, got {d!r}")
            d = {"a": d[0], "b": d[1]}
        _keys(d, DART_KEYS, w)
        if "a" not in d or "b" not in d:
            raise PatternError(f"{w}: a dart needs edges `a` and `b`")
        ia, ib = _edge_of(panel, d["a"], w), _edge_of(panel, d["b"], w)
        rev = _bool(d.get("reversed", True), w, "reversed")
        name = _string(d.get("name", ""), w, "name")
        out.append(Seam(EdgeRange(panel.name, ia), EdgeRange(panel.name, ib), rev, name, "dart"))
    return out


def _range(v: Any, panels: dict[str, Panel], where: str) -> EdgeRange:
    _keys(v, RANGE_KEYS, where)
    if "panel" not in v or "edge" not in v:
        raise PatternError(f"{where}: a seam side needs `panel` and `edge`")
    name = v["panel"]
    if name not in panels:
        raise PatternError(
            f"{where}: no panel {name!r} (edge {v['edge']!r}; panels: {list(panels)})"
        )
    i = _edge_of(panels[name], v["edge"], where)
    f0 = _number(v.get("from", 0.0), where, "from")
    f1 = _number(v.get("to", 1.0), where, "to")
    return EdgeRange(name, i, f0, f1)


def _seam(v: Any, k: int, panels: dict[str, Panel], where: str) -> Seam:
    label = v.get("name") if isinstance(v, dict) else None
    w = f"{where}: seam {k}" + (f" {label!r}" if label else "")
    _keys(v, SEAM_KEYS, w)
    if "a" not in v or "b" not in v:
        raise PatternError(f"{w}: a seam needs sides `a` and `b`")
    a, sa = normalised_range(_range(v["a"], panels, f"{w} side a"))
    b, sb = normalised_range(_range(v["b"], panels, f"{w} side b"))
    rev = _bool(v.get("reversed", True), w, "reversed") ^ sa ^ sb
    kind = v.get("kind", "seam")
    if kind not in ("seam", "dart"):
        raise PatternError(f"{w}: unknown kind {kind!r} (seam, dart)")
    return Seam(a, b, rev, _string(v.get("name", ""), w, "name"), kind)


def _table_list(data: dict, key: str, where: str) -> list:
    v = data.get(key, [])
    if not isinstance(v, list):
        raise PatternError(f"{where}: `{key}` must be a list of tables ([[{key}]])")
    return v


def pattern_from_data(
    data: Any, *, source: str = "", seam_tolerance: float = 0.02, validate: bool = True
) -> Pattern:
    """Build a :class:`Pattern` from parsed TOML/JSON of our format (module docstring);
    ``source`` names the file in messages and places a companion's DXF."""
    where = source or "pattern"
    _keys(data, TOP_KEYS, where)
    scale = _units(data, "units", where)
    name = _string(data.get("name", Path(source).stem if source else "pattern"), where, "name")
    tables = _table_list(data, "panel", where)
    if "source" in data:
        panels, seams = _companion_panels(data, tables, where, scale)
    else:
        if "dxf_units" in data:
            raise PatternError(f"{where}: `dxf_units` goes with `source = <file.dxf>`")
        panels, seams = {}, []
        for k, t in enumerate(tables):
            pname = t.get("name") if isinstance(t, dict) else None
            if not isinstance(pname, str) or not pname:
                raise PatternError(f"{where}: panel {k} needs a `name`")
            w = f"{where}: panel {pname!r}"
            _keys(t, PANEL_KEYS - {"edge_names"}, w)
            if pname in panels:
                raise PatternError(f"{w}: two panels have this name")
            if "grain" not in t:
                raise PatternError(f"{w}: `grain = [dx, dy]` is required (the warp direction)")
            edges = _outline(t, w, scale)
            panels[pname] = _panel(t, pname, edges, t["grain"], w, scale)
            seams += _darts(panels[pname], t.get("darts", []), w)
    for k, v in enumerate(_table_list(data, "seam", where)):
        seams.append(_seam(v, k, panels, where))
    pattern = Pattern(name, panels, tuple(seams), source)
    return checked(pattern, seam_tolerance=seam_tolerance) if validate else pattern


def _panel(t: dict, name: str, edges, grain, where: str, scale: float) -> Panel:
    g = _vector(grain, 2, where, "grain")
    if np.linalg.norm(g) == 0:
        raise PatternError(f"{where}: the grain line has no direction")
    fabric = _string(t["fabric"], where, "fabric") if "fabric" in t else None
    placement = _placement(t["placement"], where, scale) if "placement" in t else None
    wrap = _wrap(t["wrap"], where, scale) if "wrap" in t else None
    return Panel(name, edges, g, fabric, placement, wrap)


def _companion_panels(data: dict, tables: list, where: str, scale: float):
    from .dxf import read_dxf_pieces

    dxf = Path(_string(data["source"], where, "source"))
    if not dxf.is_absolute():
        dxf = Path(where).parent / dxf
    units = data.get("dxf_units")
    if units is not None:
        _units(data, "dxf_units", where)
    pieces = {p.name: p for p in read_dxf_pieces(dxf, units=units)}
    extra: dict[str, dict] = {}
    for k, t in enumerate(tables):
        pname = t.get("name") if isinstance(t, dict) else None
        if not isinstance(pname, str) or not pname:
            raise PatternError(f"{where}: panel {k} needs a `name`")
        w = f"{where}: panel {pname!r}"
        bad = sorted(set(t) - COMPANION_PANEL_KEYS)
        if bad:
            raise PatternError(
                f"{w}: key {bad[0]!r} cannot be given for a DXF piece (known: "
                f"{sorted(COMPANION_PANEL_KEYS)})"
            )
        if pname not in pieces:
            raise PatternError(f"{w}: {dxf} has no such piece (pieces: {list(pieces)})")
        extra[pname] = t
    panels, seams = {}, []
    for pname, piece in pieces.items():
        t = extra.get(pname, {})
        w = f"{where}: panel {pname!r}"
        edges = piece.edges
        if "edge_names" in t:
            names = t["edge_names"]
            if not isinstance(names, list) or len(names) != len(edges):
                raise PatternError(
                    f"{w}: `edge_names` must list {len(edges)} names, one per DXF edge"
                )
            names = [_string(n, w, "an edge name") for n in names]
            edges = tuple(Edge(e.curve, n) for e, n in zip(edges, names, strict=True))
        grain = t.get("grain", None if piece.grain is None else list(piece.grain))
        if grain is None:
            raise PatternError(f"{w}: {dxf} has no grain line (layer 7) and no `grain` is given")
        panels[pname] = _panel(t, pname, edges, grain, w, scale)
        seams += _darts(panels[pname], t.get("darts", []), w)
    return panels, seams


# ---------------------------------------------------------------------------------- writing


def _num(x: float, scale: float) -> float:
    """A length in file units, rounded 1e-13 m (so 700.0, not 699.9999999999999)."""
    return round(float(x) / scale, 13 + round(math.log10(scale)))


def _pt_out(p, scale: float) -> list[float]:
    return [_num(v, scale) for v in np.asarray(p).reshape(-1)]


def _edge_ref(panel: Panel, i: int) -> int | str:
    name = panel.edges[i].name
    if name and sum(e.name == name for e in panel.edges) == 1:
        return name
    return i


def _curve_data(c, scale: float) -> dict:
    if isinstance(c, Line):
        return {}
    if isinstance(c, Arc):
        return {"curve": "arc", "through": _pt_out(c.through, scale)}
    if isinstance(c, Bezier):
        return {"curve": "bezier", "controls": [_pt_out(p, scale) for p in c.controls]}
    return {"curve": "polyline", "points": [_pt_out(p, scale) for p in c.points[1:-1]]}


def placement_data(pl: Placement, scale: float) -> dict:
    return {
        "translation": _pt_out(pl.translation, scale),
        "rotation": [round(float(v), 12) for v in euler_xyz(pl.rotation)],
    }


def wrap_data(wrap: Wrap, scale: float) -> dict:
    out: dict[str, Any] = {"axis": wrap.axis}
    if wrap.azimuth is not None:
        out["azimuth"] = float(wrap.azimuth)
    if wrap.top is not None:
        out["top"] = wrap.top if isinstance(wrap.top, str) else _num(wrap.top, scale)
    return out


def seam_data(pattern: Pattern, s: Seam, edge_map=None) -> dict:
    """A seam as a [[seam]] table; ``edge_map(panel, i)`` renumbers edges (DXF companion)."""
    out: dict[str, Any] = {}
    if s.name:
        out["name"] = s.name
    if s.kind != "seam":
        out["kind"] = s.kind
    out["reversed"] = bool(s.reversed)
    for side, r in (("a", s.a), ("b", s.b)):
        p = pattern.panels[r.panel]
        ref = _edge_ref(p, int(r.edge))
        if edge_map is not None and not isinstance(ref, str):
            ref = edge_map(r.panel, int(r.edge))
        d: dict[str, Any] = {"panel": r.panel, "edge": ref}
        if r.f0 != 0.0 or r.f1 != 1.0:
            d["from"], d["to"] = float(r.f0), float(r.f1)
        out[side] = d
    return out


def pattern_data(pattern: Pattern, units: str = "mm") -> dict:
    """The pattern as the nested dicts and lists of our format (``units`` for lengths)."""
    if units not in UNITS:
        raise PatternError(f"unknown unit {units!r} (known: {list(UNITS)})")
    scale = UNITS[units]
    panels = []
    for p in pattern.panels.values():
        t: dict[str, Any] = {"name": p.name}
        if p.fabric is not None:
            t["fabric"] = p.fabric
        t["grain"] = [float(v) for v in p.grain]
        t["start"] = _pt_out(p.edges[0].curve.start, scale)
        if p.placement is not None:
            t["placement"] = placement_data(p.placement, scale)
        if p.wrap is not None:
            t["wrap"] = wrap_data(p.wrap, scale)
        edges = []
        prev = p.edges[0].curve.start
        for e in p.edges:
            d: dict[str, Any] = {}
            if not np.array_equal(e.curve.start, prev):
                d["from"] = _pt_out(e.curve.start, scale)
            d["to"] = _pt_out(e.curve.end, scale)
            if e.name:
                d["name"] = e.name
            d.update(_curve_data(e.curve, scale))
            edges.append(d)
            prev = e.curve.end
        t["edges"] = edges
        panels.append(t)
    out: dict[str, Any] = {"name": pattern.name, "units": units, "panel": panels}
    if pattern.seams:
        out["seam"] = [seam_data(pattern, s) for s in pattern.seams]
    return out


_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise PatternError(f"cannot write the number {v!r}")
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        if not v:
            return "{}"
        return "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise PatternError(f"cannot write {v!r} as TOML")


def _toml_key(k: str) -> str:
    return k if _BARE.match(k) else json.dumps(k, ensure_ascii=False)


def to_toml(data: dict, header: str = "") -> str:
    """Our format's dicts as TOML: scalars first, then ``[[panel]]``/``[[seam]]`` tables;
    lists of tables inside a table (``edges``) one inline table a line."""
    lines = [f"# {h}" for h in header.splitlines()]
    tables = {k: v for k, v in data.items() if isinstance(v, list) and v and isinstance(v[0], dict)}
    for k, v in data.items():
        if k not in tables:
            lines.append(f"{_toml_key(k)} = {_toml_value(v)}")
    for k, items in tables.items():
        for item in items:
            lines += ["", f"[[{_toml_key(k)}]]"]
            for kk, vv in item.items():
                if isinstance(vv, list) and vv and all(isinstance(x, dict) for x in vv):
                    lines.append(f"{_toml_key(kk)} = [")
                    lines += [f"  {_toml_value(x)}," for x in vv]
                    lines.append("]")
                else:
                    lines.append(f"{_toml_key(kk)} = {_toml_value(vv)}")
    return "\n".join(lines) + "\n"


def to_json(data: Any, depth: int = 0) -> str:
    """JSON for people: the top object, its lists of objects (panels, seams) and their items
    one entry a line, lists of objects (edges) one compact object a line, the rest compact."""
    pad, inner = "  " * depth, "  " * (depth + 1)
    if isinstance(data, dict) and depth <= 2 and any(isinstance(v, list) for v in data.values()):
        items = [f"{inner}{json.dumps(k)}: {to_json(v, depth + 1)}" for k, v in data.items()]
        return "{\n" + ",\n".join(items) + f"\n{pad}}}"
    if isinstance(data, list) and data and all(isinstance(x, dict) for x in data):
        return "[\n" + ",\n".join(inner + to_json(x, depth + 1) for x in data) + f"\n{pad}]"
    return json.dumps(data, ensure_ascii=False, allow_nan=False)


def write_data(data: dict, path: str | Path, header: str = "") -> None:
    """Write our format's dicts to ``path`` as TOML or JSON by its suffix."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".toml":
        text = to_toml(data, header)
    elif suffix == ".json":
        text = to_json(data) + "\n"
    else:
        raise PatternError(f"{path}: write .toml or .json (a DXF: dxf.write_dxf)")
    path.write_text(text, encoding="utf-8")


def write_pattern(pattern: Pattern, path: str | Path, *, units: str = "mm") -> None:
    """Write the pattern in our format, TOML or JSON by the suffix, lengths in ``units``;
    reading it back gives the same geometry to 1e-12 m (lengths are rounded to 1e-13 m,
    Euler angles to 1e-12°, so that the file shows 700.0 rather than 699.9999999999999)."""
    write_data(
        pattern_data(pattern, units),
        path,
        header="fenics-garment sewing pattern (format: fenics_garment/pattern/io.py)",
    )


def describe(pattern: Pattern) -> list[str]:
    """A pattern as lines for a user: each panel (size, area, grain, fabric, edges with their
    lengths) and each seam and dart (the two sides' lengths and their difference)."""
    lines = [f"pattern {pattern.name!r}: {len(pattern.panels)} panel(s), {len(pattern.seams)} "
             f"seam(s) and dart(s){f' ({pattern.source})' if pattern.source else ''}"]  # fmt: skip
    for p in pattern.panels.values():
        pts = p.outline(0.005)
        w, h = np.ptp(pts, axis=0) * 1e3
        g = np.degrees(np.arctan2(p.grain[1], p.grain[0]))
        lines.append(f"  panel {p.name}: {w:.0f} × {h:.0f} mm, {p.area * 1e2:.2f} dm², grain "
                     f"{g:.0f}°, fabric {p.fabric or '(the scene’s)'}")  # fmt: skip
        edges = ", ".join(
            f"{i}:{e.name or '-'} {e.length * 1e3:.1f}" for i, e in enumerate(p.edges)
        )
        lines.append(f"    edges [mm]: {edges}")
    for i, s in enumerate(pattern.seams):
        la, lb = pattern.range_length(s.a), pattern.range_length(s.b)
        d = 100 * (la - lb) / max(la, lb)

        def side(r) -> str:
            e = pattern.panel(r.panel).edges[pattern.panel(r.panel).edge_index(r.edge)]
            part = "" if (r.f0, r.f1) == (0.0, 1.0) else f" [{r.f0:g}…{r.f1:g}]"
            return f"{r.panel}.{e.name or r.edge}{part}"

        lines.append(f"  {s.kind} {pattern.seam_name(i)}: {side(s.a)} {la * 1e3:.1f} mm ↔ "
                     f"{side(s.b)} {lb * 1e3:.1f} mm ({d:+.1f} %)")  # fmt: skip
    return lines
