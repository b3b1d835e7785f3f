"""Read GarmentCode / GarmentCodeData sewing-pattern specifications (JSON).

GarmentCode (Korosteleva & Sorkine-Hornung, SIGGRAPH Asia 2023; GarmentCodeData, ECCV 2024;
MIT licence) writes a pattern as ``*_specification.json``. This reader follows what its own
code writes and reads (maria-korosteleva/GarmentCode, read for this module):
``pygarment/garmentcode/panel.py`` ``Panel.assembly`` and ``edge.py`` ``*.assembly`` (the
writer), ``pygarment/garmentcode/connector.py`` ``StitchingRule.assembly`` (the stitches),
``pygarment/pattern/utils.py`` ``rel_to_abs_2d`` (edge-relative coordinates) and
``pygarment/meshgen/boxmeshgen.py`` (the simulator's reader: curves and stitch orientation).
Nothing of it is copied::

    {"pattern": {
        "panels": {"<name>": {
            "translation": [x, y, z], "rotation": [rx, ry, rz],      # degrees
            "vertices": [[x, y], ...],
            "edges": [{"endpoints": [i, j], "curvature": ..., "label": "..."}, ...]}},
        "stitches": [[{"panel": "<name>", "edge": k}, {"panel": ..., "edge": ...}], ...]},
     "properties": {"units_in_meter": 100, "curvature_coords": "relative", ...}}

* **Units**: lengths (vertices, translations, circle radii) are in 1 / ``units_in_meter`` m
  (100: cm, GarmentCode's own; missing: 100, as GarmentCode then leaves them unscaled).
* **Edge-relative coordinates** (quadratic and cubic control points): a point (u, v) of an
  edge from A to B is A + u (B − A) + v (B − A)⊥ with (B − A)⊥ = (−(B − A)_y, (B − A)_x), the
  edge vector turned +90°, *not* normalised: u runs along the edge as a fraction, v > 0 lies
  to the left of A → B, v < 0 to the right (``rel_to_abs_2d``). Checked on GarmentCode's own
  shirt: the back neckline's control (0.15, −0.1) then dips below its chord, into the panel.
* **Curvature**: absent: a line; legacy ``[u, v]``: a quadratic Bézier control point
  (absolute panel coordinates instead when ``properties.curvature_coords == "absolute"``);
  ``{"type": "quadratic", "params": [[u, v]]}``; ``{"type": "cubic", "params": [[u, v],
  [u, v]]}``; ``{"type": "circle", "params": [radius, large_arc, right]}``: SVG's arc flags,
  ``right`` = the arc's middle lies right of A → B (``CircleEdge.as_radius_flag``:
  ``control_y < 0``), which the simulator passes as SVG's sweep flag, i.e. the arc turns
  counter-clockwise (y up) — :func:`~.model.arc_from_radius` (``ccw = right``). A radius
  below half the chord is raised to it, as SVG does.
* **Placement**: ``rotation`` are intrinsic X-Y-Z Euler angles in degrees (the writer's
  ``Rotation.as_euler("XYZ")``: R = Rx Ry Rz); a panel point (x, y) is at R (x, y, 0) + t.
  GarmentCode's simulator reads them as R = Rz Ry Rx (``pattern/rotation.py``), which is the
  same matrix for the usual single-axis rotations; we follow the writer.
* **Orientation**: GarmentCode draws each panel counter-clockwise *seen from outside the
  body* (its shirt, hoodie, dress and jumpsuit: every front panel, normal +z towards the
  viewer, is counter-clockwise, every back panel, normal +z into the body, clockwise). A
  clockwise panel is therefore mirrored here, x ↦ −x, with its rotation R ↦ R diag(−1, 1, −1)
  (a half turn about the local y axis): every 3D point stays where GarmentCode puts it, the
  edges keep their indices and directions (so the stitches need no remapping), the outline
  becomes counter-clockwise and local +z points out of the body, the right side of the
  fabric (:mod:`.model`).
* **Grain**: GarmentCode panels have none: the grain is the panel's local +y, which
  GarmentCode lays vertically (upwards) on the body in its placement (the rotated local +y).
  A mirrored panel keeps it (the mirror is about the y axis).
* **Stitches**: ``[side_1, side_2]`` joins the two whole edges; GarmentCode's simulator
  connects the end of side 1's edge to the start of side 2's (``boxmeshgen.Seam.swap`` is
  True, "connects right side to the right side of fabric", and ``_swap_stitch_ranges``
  reverses side 1's vertices), i.e. ``reversed = True``; a third element ``"right_wrong"``
  keeps them running the same way (``reversed = False``). A stitch within one panel is a
  ``"dart"``. Gathered edges (a ruffle sewn to a shorter edge) are refused by the seam-length
  check unless ``seam_tolerance`` is raised.
* **Frame**: GarmentCode's body stands y up and faces +z (its left at +x); ours stands z up
  and faces −y: placements are turned by :data:`GC_TO_OURS`. A panel laid along a limb
  (grain more than :data:`MAX_WRAP_TILT_DEG` from vertical: a sleeve) is not wrapped around
  the torso (``Wrap(axis="none")``); the sewing closes it round the arm.
* Edge ``label`` becomes the edge's name; seams get generated names (``seam_<k>``, k the
  stitch's index in the file).
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from .model import (
    Bezier,
    Edge,
    EdgeRange,
    Line,
    Panel,
    Pattern,
    PatternError,
    Placement,
    Seam,
    Wrap,
    arc_from_radius,
    rotation_xyz,
    transform_curve,
)
from .validate import signed_area, validate

MIRROR_X = np.diag([-1.0, 1.0])
#: a half turn about the local y axis: R ↦ R @ HALF_TURN_Y keeps R (x, y, 0) for x ↦ −x
HALF_TURN_Y = np.diag([-1.0, 1.0, -1.0])


def rel_to_abs(a: np.ndarray, b: np.ndarray, uv) -> np.ndarray:
    """Edge-relative (u, v) to panel coordinates (module docstring)."""
    d = b - a
    u, v = np.asarray(uv, float).reshape(2)
    return a + u * d + v * np.array([-d[1], d[0]])


def _as_point(v: Any, where: str) -> np.ndarray:
    try:
        p = np.asarray(v, dtype=float).reshape(2)
    except (TypeError, ValueError):
        raise PatternError(f"{where}: expected a point [x, y], got {v!r}") from None
    if not np.all(np.isfinite(p)):
        raise PatternError(f"{where}: expected a finite point, got {v!r}")
    return p


def _curve(edge: dict, a: np.ndarray, b: np.ndarray, scale: float, absolute: bool, where: str):
    if "curvature" not in edge or edge["curvature"] is None:
        return Line(a, b)
    c = edge["curvature"]
    if isinstance(c, list):  # legacy quadratic
        p = _as_point(c, where) * scale if absolute else rel_to_abs(a, b, _as_point(c, where))
        return Bezier(a, b, (p,))
    if not isinstance(c, dict) or "type" not in c:
        raise PatternError(f"{where}: unknown curvature {c!r}")
    kind, params = c["type"], c.get("params")
    if kind in ("quadratic", "cubic"):
        n = 1 if kind == "quadratic" else 2
        if not isinstance(params, list) or len(params) != n:
            raise PatternError(f"{where}: a {kind} curvature needs {n} control point(s)")
        pts = [_as_point(q, where) for q in params]
        ctrl = [q * scale if absolute else rel_to_abs(a, b, q) for q in pts]
        return Bezier(a, b, tuple(ctrl))
    if kind == "circle":
        if not isinstance(params, list) or len(params) != 3:
            raise PatternError(f"{where}: a circle curvature is [radius, large_arc, right]")
        radius, large, right = params
        arc = arc_from_radius(a, b, float(radius) * scale, large=bool(large), ccw=bool(right))
        return arc
    raise PatternError(f"{where}: unknown curvature type {kind!r} (quadratic, cubic, circle)")


def _panel(name: str, spec: Any, scale: float, absolute: bool, where: str) -> Panel:
    w = f"{where}: panel {name!r}"
    if not isinstance(spec, dict) or "vertices" not in spec or "edges" not in spec:
        raise PatternError(f"{w}: a panel needs `vertices` and `edges`")
    try:
        verts = np.asarray(spec["vertices"], dtype=float).reshape(-1, 2) * scale
    except (TypeError, ValueError):
        raise PatternError(f"{w}: `vertices` must be a list of [x, y]") from None
    if not isinstance(spec["edges"], list):
        raise PatternError(f"{w}: `edges` must be a list")
    edges = []
    for i, e in enumerate(spec["edges"]):
        label = e.get("label", "") if isinstance(e, dict) else ""
        label = label if isinstance(label, str) else str(label)
        ew = f"{w}, edge {i}" + (f" {label!r}" if label else "")
        ends = e.get("endpoints") if isinstance(e, dict) else None
        if not isinstance(ends, list) or len(ends) != 2:
            raise PatternError(f"{ew}: `endpoints` must be two vertex indices")
        for v in ends:
            if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v < len(verts):
                raise PatternError(f"{ew}: no vertex {v!r} (the panel has {len(verts)})")
        a, b = verts[ends[0]], verts[ends[1]]
        try:
            curve = _curve(e, a, b, scale, absolute, ew)
        except PatternError as err:
            if str(err).startswith(ew):
                raise
            raise PatternError(f"{ew}: {err}") from None
        except (TypeError, ValueError) as err:
            raise PatternError(f"{ew}: bad curvature {e.get('curvature')!r} ({err})") from None
        edges.append(Edge(curve, label))
    try:
        t = np.asarray(spec.get("translation", [0, 0, 0]), dtype=float).reshape(3) * scale
        r = rotation_xyz(spec.get("rotation", [0, 0, 0]))
    except (TypeError, ValueError):
        raise PatternError(f"{w}: `translation` and `rotation` must be 3 numbers each") from None
    return Panel(name, tuple(edges), np.array([0.0, 1.0]), None, Placement(t, r))


def _mirrored(panel: Panel) -> Panel:
    """The panel mirrored x ↦ −x, its rotation composed with a half turn about local y
    (module docstring: same 3D points, counter-clockwise outline, +z flipped)."""
    edges = tuple(Edge(transform_curve(e.curve, MIRROR_X), e.name) for e in panel.edges)
    pl = panel.placement
    placement = None if pl is None else Placement(pl.translation, pl.rotation @ HALF_TURN_Y)
    grain = MIRROR_X @ panel.grain
    return Panel(panel.name, edges, grain, panel.fabric, placement)


def _seam(k: int, stitch: Any, panels: dict[str, Panel], where: str) -> Seam:
    w = f"{where}: stitch {k}"
    if not isinstance(stitch, list) or len(stitch) < 2:
        raise PatternError(f"{w}: a stitch is [{{panel, edge}}, {{panel, edge}}, ...]")
    sides = []
    for side in stitch[:2]:
        if not isinstance(side, dict) or "panel" not in side or "edge" not in side:
            raise PatternError(f"{w}: a stitch side is {{'panel': ..., 'edge': ...}}, got {side!r}")
        name, edge = side["panel"], side["edge"]
        if name not in panels:
            raise PatternError(f"{w}: no panel {name!r} (edge {edge!r}; panels: {list(panels)})")
        n = len(panels[name].edges)
        if isinstance(edge, bool) or not isinstance(edge, int) or not 0 <= edge < n:
            raise PatternError(f"{w}: panel {name!r} has no edge {edge!r} (it has {n} edges)")
        sides.append(EdgeRange(name, edge))
    right_wrong = "right_wrong" in stitch[2:]
    kind = "dart" if sides[0].panel == sides[1].panel else "seam"
    return Seam(sides[0], sides[1], not right_wrong, "", kind)


def pattern_from_spec(
    spec: Any, *, source: str = "", name: str | None = None, seam_tolerance: float = 0.02
) -> Pattern:
    """A :class:`Pattern` from a parsed GarmentCode specification (module docstring),
    validated, every outline counter-clockwise."""
    where = source or "GarmentCode pattern"
    if not isinstance(spec, dict) or not isinstance(spec.get("pattern"), dict):
        raise PatternError(f"{where}: not a GarmentCode specification (no `pattern`)")
    props = spec.get("properties") or {}
    units_in_meter = props.get("units_in_meter", 100)
    if (
        isinstance(units_in_meter, bool)
        or not isinstance(units_in_meter, (int, float))
        or not (units_in_meter > 0)
    ):
        raise PatternError(f"{where}: bad properties.units_in_meter {units_in_meter!r}")
    scale = 1.0 / float(units_in_meter)
    absolute = props.get("curvature_coords", "relative") == "absolute"
    panel_specs = spec["pattern"].get("panels")
    if not isinstance(panel_specs, dict) or not panel_specs:
        raise PatternError(f"{where}: `pattern.panels` must name at least one panel")
    panels = {n: _panel(n, p, scale, absolute, where) for n, p in panel_specs.items()}
    stitches = spec["pattern"].get("stitches", [])
    if not isinstance(stitches, list):
        raise PatternError(f"{where}: `pattern.stitches` must be a list")
    seams = tuple(_seam(k, s, panels, where) for k, s in enumerate(stitches))
    if name is None:
        stem = Path(source).stem if source else "garmentcode"
        name = stem.removesuffix("_specification")
    raw = Pattern(name, panels, seams, source)
    # validate as written (clockwise allowed), then mirror the clockwise panels
    validate(raw, seam_tolerance=seam_tolerance, allow_clockwise=True)
    mirrored = {n: _mirrored(p) if signed_area(p) < 0 else p for n, p in panels.items()}
    return Pattern(name, {n: _to_our_frame(p) for n, p in mirrored.items()}, seams, source)


#: GarmentCode's body frame (y up, facing +z, its left at +x: SMPL's) to ours (z up, facing −y,
#: its left at +x): a quarter turn about x, (x, y, z) ↦ (x, −z, y)
GC_TO_OURS = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
#: a placed panel whose grain (local +y, GarmentCode's vertical) leans more than this from
#: the vertical (a sleeve along an arm) is not wrapped around the torso: it stays as placed
#: and the sewing closes it round its limb
MAX_WRAP_TILT_DEG = 30.0


def _to_our_frame(panel: Panel) -> Panel:
    pl = panel.placement
    if pl is None:
        return panel
    placement = Placement(GC_TO_OURS @ pl.translation, GC_TO_OURS @ pl.rotation)
    up = placement.rotation @ np.array([0.0, 1.0, 0.0])
    tilt = np.degrees(np.arccos(np.clip(up[2], -1.0, 1.0)))
    wrap = Wrap(axis="none") if tilt > MAX_WRAP_TILT_DEG else panel.wrap
    return replace(panel, placement=placement, wrap=wrap)


def read_garmentcode(path: str | Path, *, seam_tolerance: float = 0.02) -> Pattern:
    """Read a GarmentCode ``*_specification.json``."""
    path = Path(path)
    try:
        with open(path, encoding="utf-8") as f:
            spec = json.load(f)
    except json.JSONDecodeError as e:
        raise PatternError(f"{path}: not valid JSON: {' '.join(str(e).split())}") from None
    return pattern_from_spec(spec, source=str(path), seam_tolerance=seam_tolerance)
