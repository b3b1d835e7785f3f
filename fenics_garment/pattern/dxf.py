"""Read and write DXF-AAMA / ASTM D6673 pattern files (through ``ezdxf``).

The format (ASTM D6673-10, "Sewn Products Pattern Data Interchange—Data Format", withdrawn
2019 and still the industry's exchange format; AAMA's DXF before it): a DXF file (R12/R13)
with one BLOCK per pattern piece, inserted once in the model space, and the piece's
features on numbered layers:

====== ===================================================================
layer  content (ASTM D6673 / AAMA layer convention)
====== ===================================================================
1      piece boundary (the cut line), and the style's / piece's system text
2      turn points (corners) of layers 1, 8, 11, 14, as POINT entities
3      curve points
4      notches
5, 6   grade reference line, mirror line
7      grain line
8      internal lines; 11 internal cut-outs; 13 drill holes; 14 sew lines
====== ===================================================================

Sources: the layer tables published by Lectra/Romans CAD ("AAMA layer convention") and by
the Patro project's notes on ASTM D6673; the system-text keys ("Piece Name: …",
"Units: …") as pattern CAD writes them.

**Reading.** Each piece becomes a :class:`Piece`: its name from the block's
``Piece Name: …`` text (else the block name); its boundary from the layer-1 entities (LWPOLYLINE,
POLYLINE, LINE, ARC, SPLINE; several are chained end to end within 1e-5 of the piece's size;
bulges and curves flattened to 1e-4 of it); its grain from the first layer-7 line (first
point to last). Block coordinates are used (the INSERT's position in the marker is not the
piece's shape). The outline is made counter-clockwise and split into edges at the layer-2
turn points that lie on it (within 1e-3 of the piece's size; others belong to internal
lines); without turn points, at the vertices where the outline turns by more than
:data:`CORNER_ANGLE`; with fewer than two split points, at the point half the perimeter
away. **Edge numbering** (what a companion file's seams refer to): counter-clockwise, edge 0
starting at the split point nearest the lower-left corner of the piece's bounding box (min
x, min y). Edges are :class:`~.model.Polyline` curves (:class:`~.model.Line` when they have
2 points).

**Units**, first found of: the ``units`` argument (a companion's ``dxf_units``); a
``Units: …`` text (``mm``, ``cm``, ``m``, ``in``/``ENGLISH`` = inches; ``METRIC`` is
ambiguous — CLO writes it for centimetres, others for millimetres — and is resolved by a
``$INSUNITS`` of mm or cm, else refused); ``$INSUNITS`` (1 in, 2 ft, 4 mm, 5 cm, 6 m); else
the file is refused. A text outranks ``$INSUNITS`` because writers set the header wrongly
(ezdxf's own default is metres).

**Seams** do not exist in AAMA: they come from a companion file of our format that names the
DXF (``source = "x.dxf"``, :mod:`.io`).

**Writing** (:func:`write_dxf`): R2000, centimetres (``Units: METRIC`` text and
``$INSUNITS`` 5, so both readings agree), one block per panel: the outline as a closed
POLYLINE on layer 1 (curves sampled every ``spacing``), a POINT on layer 2 at every edge's
start, the grain as a LINE on layer 7, ``Piece Name: …`` on layer 1; optionally a companion
file with the seams, fabrics, placements and edge names, edges renumbered as the reader
numbers them.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .model import (
    UNITS,
    Array,
    Edge,
    Line,
    Pattern,
    PatternError,
    Polyline,
)

#: a vertex where the outline turns by more than this (degrees) splits edges (no turn points)
CORNER_ANGLE = 30.0
#: metres per unit of $INSUNITS codes
INSUNITS = {1: 0.0254, 2: 0.3048, 4: 1e-3, 5: 1e-2, 6: 1.0}
#: metres per unit of "Units: …" texts (METRIC is resolved by $INSUNITS)
TEXT_UNITS = {
    **UNITS,
    "in": 0.0254,
    "inch": 0.0254,
    "inches": 0.0254,
    "english": 0.0254,
    "millimeters": 1e-3,
    "millimetres": 1e-3,
    "centimeters": 1e-2,
    "centimetres": 1e-2,
    "meters": 1.0,
    "metres": 1.0,
}
BOUNDARY, TURN_POINTS, GRAIN = "1", "2", "7"
_CURVES = {"LWPOLYLINE", "POLYLINE", "LINE", "ARC", "SPLINE"}
_NAME = re.compile(r"^\s*piece\s*name\s*:\s*(.*?)\s*$", re.IGNORECASE)
_UNITS = re.compile(r"^\s*units?\s*:\s*(.*?)\s*$", re.IGNORECASE)


@dataclass(frozen=True, eq=False)
class Piece:
    """A DXF pattern piece: its name, counter-clockwise edges (metres) and grain (or None)."""

    name: str
    edges: tuple[Edge, ...]
    grain: Array | None
    block: str


def _ezdxf():
    try:
        import ezdxf
    except ImportError:  # pragma: no cover - a dependency
        raise PatternError("reading DXF needs ezdxf (pip install ezdxf)") from None
    return ezdxf


def _texts(entities) -> list[str]:
    out = []
    for e in entities:
        t = e.dxftype()
        if t == "TEXT":
            out.append(e.dxf.text)
        elif t == "MTEXT":
            out += e.plain_text().splitlines()
    return out


def _layer(e) -> str:
    return str(e.dxf.get("layer", "0")).strip()


def _units(doc, units: str | None, where: str) -> float:
    if units is not None:
        if units.lower() not in TEXT_UNITS:
            raise PatternError(f"{where}: unknown unit {units!r} (known: {list(TEXT_UNITS)})")
        return TEXT_UNITS[units.lower()]
    texts = _texts(doc.modelspace())
    for b in doc.blocks:
        if not b.is_any_layout:
            texts += _texts(b)
    code = int(doc.header.get("$INSUNITS", 0) or 0)
    for t in texts:
        m = _UNITS.match(t)
        if not m:
            continue
        word = m.group(1).lower()
        if word in TEXT_UNITS:
            return TEXT_UNITS[word]
        if word == "metric":
            if code in (4, 5):
                return INSUNITS[code]
            raise PatternError(
                f"{where}: 'Units: METRIC' says neither mm nor cm and $INSUNITS does not "
                "either; give dxf_units in the companion file (or units= to read_dxf)"
            )
        raise PatternError(f"{where}: unknown unit {m.group(1)!r} in a 'Units:' text")
    if code in INSUNITS:
        return INSUNITS[code]
    raise PatternError(
        f"{where}: no units (no 'Units:' text, $INSUNITS {code}); give dxf_units in the "
        "companion file (or units= to read_dxf)"
    )


def _points(entity, flat: float) -> Array:
    from ezdxf import path as ezpath

    p = ezpath.make_path(entity)
    return np.array([(v.x, v.y) for v in p.flattening(flat)], dtype=float)


def _chain(parts: list[Array], tol: float, where: str) -> Array:
    """One closed loop (last point not repeated) from open or closed point lists."""
    parts = [p for p in parts if len(p) >= 2]
    if not parts:
        raise PatternError(f"{where}: no boundary on layer {BOUNDARY}")
    loop = parts.pop(0)
    while parts:
        end = loop[-1]
        d = [
            (min(np.linalg.norm(p[0] - end), np.linalg.norm(p[-1] - end)), k)
            for k, p in enumerate(parts)
        ]
        dist, k = min(d)
        if dist > tol:
            break
        p = parts.pop(k)
        if np.linalg.norm(p[0] - end) > np.linalg.norm(p[-1] - end):
            p = p[::-1]
        loop = np.vstack([loop, p[1:]])
    if parts or np.linalg.norm(loop[0] - loop[-1]) > tol:
        raise PatternError(f"{where}: the boundary (layer {BOUNDARY}) is not one closed outline")
    loop = loop[:-1]
    keep = np.r_[True, np.linalg.norm(np.diff(loop, axis=0), axis=1) > tol * 1e-6]
    loop = loop[keep]
    if np.linalg.norm(loop[-1] - loop[0]) <= tol * 1e-6:
        loop = loop[:-1]
    return loop


def _area(p: Array) -> float:
    q = np.roll(p, -1, axis=0)
    return 0.5 * float(np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]))


def _splits(loop: Array, turns: list[Array], tol: float) -> list[int]:
    idx: set[int] = set()
    for t in turns:
        d = np.linalg.norm(loop - t, axis=1)
        k = int(np.argmin(d))
        if d[k] <= tol:
            idx.add(k)
    if not idx:
        v_in = loop - np.roll(loop, 1, axis=0)
        v_out = np.roll(loop, -1, axis=0) - loop
        turn = np.degrees(
            np.abs(
                np.arctan2(
                    v_in[:, 0] * v_out[:, 1] - v_in[:, 1] * v_out[:, 0],
                    np.sum(v_in * v_out, axis=1),
                )
            )
        )
        idx = set(np.flatnonzero(turn > CORNER_ANGLE).tolist())
    lo = loop.min(axis=0)
    if len(idx) < 2:
        seg = np.linalg.norm(np.roll(loop, -1, axis=0) - loop, axis=1)
        s = np.concatenate([[0.0], np.cumsum(seg)])
        first = min(idx) if idx else int(np.argmin(np.linalg.norm(loop - lo, axis=1)))
        target = (s[first] + s[-1] / 2) % s[-1]
        idx = {first, int(np.argmin(np.abs(s[:-1] - target)))}
    order = sorted(idx)
    d = [(float(np.linalg.norm(loop[k] - lo)), k) for k in order]
    start = order.index(min(d)[1])
    return order[start:] + order[:start]


def _edges(loop: Array, splits: list[int]) -> tuple[Edge, ...]:
    n = len(loop)
    out = []
    for a, b in zip(splits, splits[1:] + splits[:1], strict=True):
        idx = np.arange(a, a + ((b - a) % n or n) + 1) % n
        pts = loop[idx]
        out.append(Edge(Line(pts[0], pts[-1]) if len(pts) == 2 else Polyline(pts)))
    return tuple(out)


def _has_boundary(block) -> bool:
    return any(_layer(e) == BOUNDARY and e.dxftype() in _CURVES for e in block)


def _blocks(doc) -> list:
    """The pieces' blocks: those inserted in the model space, in order (each once), or, in a
    file without inserts, every block with a boundary."""
    names: list[str] = []
    for e in doc.modelspace():
        if e.dxftype() == "INSERT" and e.dxf.name not in names:
            names.append(e.dxf.name)
    blocks = [doc.blocks.get(n) for n in names] if names else list(doc.blocks)
    return [b for b in blocks if b is not None and not b.is_any_layout and _has_boundary(b)]


def read_dxf_pieces(path: str | Path, *, units: str | None = None) -> list[Piece]:
    """The pieces of a DXF-AAMA / ASTM D6673 file, in metres (module docstring)."""
    ezdxf = _ezdxf()
    from ezdxf import bbox

    path = Path(path)
    where = str(path)
    try:
        doc = ezdxf.readfile(path)
    except OSError as e:
        raise PatternError(f"{where}: cannot read: {' '.join(str(e).split())}") from None
    except ezdxf.DXFError as e:
        raise PatternError(f"{where}: not a valid DXF file: {' '.join(str(e).split())}") from None
    scale = _units(doc, units, where)
    pieces: list[Piece] = []
    for block in _blocks(doc):
        ents = list(block)
        name = block.name
        for t in _texts(ents):
            m = _NAME.match(t)
            if m and m.group(1):
                name = m.group(1)
                break
        w = f"{where}: piece {name!r}"
        if any(p.name == name for p in pieces):
            raise PatternError(f"{w}: two pieces have this name")
        bounds = [e for e in ents if _layer(e) == BOUNDARY and e.dxftype() in _CURVES]
        if not bounds:
            raise PatternError(f"{w}: no boundary on layer {BOUNDARY}")
        box = bbox.extents(bounds)
        size = float(max(box.size.x, box.size.y)) if box.has_data else 0.0
        if not size > 0:
            raise PatternError(f"{w}: the boundary (layer {BOUNDARY}) has no extent")
        loop = _chain([_points(e, 1e-4 * size) for e in bounds], 1e-5 * size, w)
        if len(loop) < 3:
            raise PatternError(f"{w}: the boundary has fewer than 3 points")
        if _area(loop) < 0:
            loop = loop[::-1].copy()
        turns = [
            np.array([e.dxf.location.x, e.dxf.location.y])
            for e in ents
            if _layer(e) == TURN_POINTS and e.dxftype() == "POINT"
        ]
        splits = _splits(loop, turns, 1e-3 * size)
        grain = None
        for e in ents:
            if _layer(e) == GRAIN and e.dxftype() in _CURVES:
                g = _points(e, 1e-4 * size)
                if len(g) >= 2 and np.linalg.norm(g[-1] - g[0]) > 0:
                    grain = g[-1] - g[0]
                    break
        pieces.append(Piece(name, _edges(loop * scale, splits), grain, block.name))
    if not pieces:
        raise PatternError(f"{where}: no pattern piece (no block with a layer-1 boundary)")
    return pieces


def read_dxf(
    path: str | Path, *, units: str | None = None, seam_tolerance: float = 0.02
) -> Pattern:
    """A DXF file as a :class:`Pattern` without seams (validated; every piece needs a grain
    line; seams come from a companion file, :mod:`.io`)."""
    from .model import Panel
    from .validate import checked

    panels = {}
    for p in read_dxf_pieces(path, units=units):
        if p.grain is None:
            raise PatternError(f"{path}: piece {p.name!r}: no grain line (layer {GRAIN})")
        panels[p.name] = Panel(p.name, p.edges, p.grain)
    return checked(Pattern(Path(path).stem, panels, (), str(path)), seam_tolerance=seam_tolerance)


# ---------------------------------------------------------------------------------- writing


def _outline_points(panel, spacing: float) -> tuple[Array, list[int]]:
    """The outline's points (metres) and the index of each edge's start among them."""
    pts, starts = [], []
    for e in panel.edges:
        starts.append(sum(len(p) for p in pts))
        c = e.curve
        if isinstance(c, Line):
            pts.append(c.start[None, :])
        elif isinstance(c, Polyline):
            pts.append(c.points[:-1])
        else:
            pts.append(c.sample(max(2, int(np.ceil(e.length / spacing))))[:-1])
    return np.concatenate(pts), starts


def _block_name(name: str, used: set[str]) -> str:
    base = re.sub(r'[<>/\\":;?*|=`,\s]+', "_", name) or "piece"
    out, k = base, 1
    while out.upper() in used:
        k += 1
        out = f"{base}_{k}"
    used.add(out.upper())
    return out


def dxf_edge_start(points: Array, starts: list[int]) -> int:
    """Which edge the reader numbers 0: the one starting nearest the lower-left corner."""
    lo = points.min(axis=0)
    d = [(float(np.linalg.norm(points[s] - lo)), k) for k, s in enumerate(starts)]
    return min(d)[1]


def write_dxf(
    pattern: Pattern,
    path: str | Path,
    *,
    spacing: float = 1e-3,
    companion: str | Path | None = None,
) -> None:
    """Write the pattern as a DXF-AAMA-style file (module docstring), curves sampled every
    ``spacing`` metres; ``companion`` (a .toml or .json path): also write our-format
    companion naming the DXF, with the seams, fabrics, placements and edge names."""
    from . import io
    from .validate import oriented

    ezdxf = _ezdxf()
    pattern = oriented(pattern)
    cm = 1e-2
    doc = ezdxf.new("R2000", setup=False)
    doc.header["$INSUNITS"] = 5
    doc.header["$MEASUREMENT"] = 1
    for layer in (BOUNDARY, TURN_POINTS, GRAIN):
        doc.layers.add(layer)
    msp = doc.modelspace()
    msp.add_text(f"Style Name: {pattern.name}", dxfattribs={"layer": BOUNDARY, "height": 1.0})
    msp.add_text("Units: METRIC", dxfattribs={"layer": BOUNDARY, "height": 1.0}).set_placement(
        (0, -2)
    )
    used: set[str] = set()
    x0 = 0.0
    first: dict[str, int] = {}
    for panel in pattern.panels.values():
        pts, starts = _outline_points(panel, spacing)
        first[panel.name] = dxf_edge_start(pts, starts)
        p = pts / cm
        block = doc.blocks.new(_block_name(panel.name, used))
        block.add_polyline2d([tuple(v) for v in p], close=True, dxfattribs={"layer": BOUNDARY})
        for s in starts:
            block.add_point(tuple(p[s]), dxfattribs={"layer": TURN_POINTS})
        lo, hi = p.min(axis=0), p.max(axis=0)
        centre = (lo + hi) / 2
        half = 0.2 * float(min(hi - lo)) * panel.grain
        block.add_line(tuple(centre - half), tuple(centre + half), dxfattribs={"layer": GRAIN})
        block.add_text(
            f"Piece Name: {panel.name}", dxfattribs={"layer": BOUNDARY, "height": 1.0}
        ).set_placement((centre[0], centre[1] + 2.0))
        msp.add_blockref(block.name, (x0 - lo[0], -lo[1]))
        x0 += float(hi[0] - lo[0]) + 5.0
    path = Path(path)
    doc.saveas(path)
    if companion is not None:
        companion = Path(companion)
        header = f"seams etc. of {path.name} (format: fenics_garment/pattern/io.py)"
        io.write_data(companion_data(pattern, path, companion, first), companion, header)


def companion_data(pattern: Pattern, dxf: Path, companion: Path, first: dict[str, int]) -> dict:
    """Our format's companion of a DXF written by :func:`write_dxf`: edges renumbered from
    ``first[panel]`` (the DXF's edge 0), lengths in mm."""
    from . import io

    scale = UNITS["mm"]
    rel = os.path.relpath(dxf.resolve(), companion.resolve().parent)
    tables = []
    for p in pattern.panels.values():
        n, k0 = len(p.edges), first[p.name]
        t: dict = {"name": p.name}
        if p.fabric is not None:
            t["fabric"] = p.fabric
        if p.placement is not None:
            t["placement"] = io.placement_data(p.placement, scale)
        if p.wrap is not None:
            t["wrap"] = io.wrap_data(p.wrap, scale)
        if any(e.name for e in p.edges):
            t["edge_names"] = [p.edges[(k + k0) % n].name for k in range(n)]
        tables.append(t)

    def edge_map(panel: str, i: int) -> int:
        return (i - first[panel]) % len(pattern.panels[panel].edges)

    out: dict = {"name": pattern.name, "units": "mm", "source": Path(rel).as_posix()}
    if tables:
        out["panel"] = tables
    if pattern.seams:
        out["seam"] = [io.seam_data(pattern, s, edge_map) for s in pattern.seams]
    return out
