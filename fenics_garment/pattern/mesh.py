"""Flat panels meshed by gmsh with seam nodes paired one to one, and their initial placement.

:func:`mesh_panels` samples every edge of every panel at equal arc length and meshes each panel
(triangles, order 2) in one gmsh session:

* an edge is split at the ends ``f0``/``f1`` of the seam ranges on it; each piece of a seam gets
  the **same** number of segments on both sides, ``n = ⌈max(Lₐ, L_b)/h⌉``, at equal arc length
  over its range, so the boundary nodes pair one to one (respecting :attr:`.Seam.reversed`);
  a free piece gets ``⌈L/h⌉`` segments;
* every boundary segment is a straight gmsh line with no inner node (transfinite, 2 nodes), so
  the boundary vertices are exactly the samples; after ``setOrder(2)`` the segment's edge node is
  moved from the chord's midpoint to the curve's arc-length midpoint, so the flat P2 outline
  follows arcs and Béziers (interior edge nodes stay at midpoints);
* each panel's coordinates are rotated so that its grain is +x (``FlatPanels.rotation``).

Arc length: lines, arcs and polylines are parametrised proportionally to arc length already;
Béziers are inverted by bisection on a Gauss–Legendre arc-length integral (≈1e-14 relative),
not on :class:`~.model.Bezier`'s 400-chord table (≈1e-6).

:func:`place` gives every flat node its initial 3-D position (the drawn side of each panel
outward, module doc of :mod:`.sew` for the sewing that follows).
"""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from fenics_garment.geometry import sections as sec
from fenics_garment.geometry.gmsh_utils import GMSH_TIME_LIMIT, gmsh_session, time_limit

from .model import Arc, Bezier, Line, Pattern, PatternError, Polyline, Wrap

Array = npt.NDArray[np.float64]
IArray = npt.NDArray[np.int64]

#: free edge names that name the garment's edge across panels (``hem`` on front and back is
#: one edge tag ``hem``); other free edges are tagged ``<panel>_<edge name>``
SHARED_EDGE_PREFIXES = ("hem", "neckline", "armhole", "opening", "top", "welt", "waistband",
                        "cuff", "collar", "hood", "leg_opening")  # fmt: skip


# ---------------------------------------------------------------------------------------------
# Arc length
# ---------------------------------------------------------------------------------------------

_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)


def _bezier_speed(P: Array, t: Array) -> Array:
    from math import comb

    k = len(P) - 1
    Q = k * np.diff(P, axis=0)
    t = t[..., None]
    d = sum(comb(k - 1, j) * t**j * (1 - t) ** (k - 1 - j) * Q[j] for j in range(k))
    return np.linalg.norm(d, axis=-1)


def _bezier_params(curve: Bezier, fractions: Array, panels: int = 256) -> Array:
    """Parameters t at arc-length ``fractions`` of a Bézier curve (≈1e-14 relative)."""
    P = np.array([curve.start, *curve.controls, curve.end])
    edges = np.linspace(0.0, 1.0, panels + 1)
    a, b = edges[:-1], edges[1:]

    def integral(lo: Array, hi: Array) -> Array:
        x = 0.5 * (hi - lo)[:, None] * _GL_X + 0.5 * (hi + lo)[:, None]
        return 0.5 * (hi - lo) * (_bezier_speed(P, x) @ _GL_W)

    cum = np.concatenate([[0.0], np.cumsum(integral(a, b))])
    target = np.clip(np.asarray(fractions, float), 0.0, 1.0) * cum[-1]
    k = np.clip(np.searchsorted(cum, target, side="right") - 1, 0, panels - 1)
    lo, hi = a[k].copy(), b[k].copy()
    base = cum[k]
    for _ in range(48):
        mid = 0.5 * (lo + hi)
        below = base + integral(a[k], mid) < target
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return 0.5 * (lo + hi)


def curve_length(curve: Any) -> float:
    """Arc length of an edge's curve (exact for lines, arcs, polylines; quadrature for Béziers)."""
    if isinstance(curve, Bezier):
        P = np.array([curve.start, *curve.controls, curve.end])
        e = np.linspace(0.0, 1.0, 257)
        x = 0.5 * np.diff(e)[:, None] * _GL_X + 0.5 * (e[1:] + e[:-1])[:, None]
        return float(np.sum(0.5 * np.diff(e) * (_bezier_speed(P, x) @ _GL_W)))
    return float(curve.length)


def sample_curve(curve: Any, f0: float, f1: float, n: int) -> Array:
    """``n + 1`` points at equal arc length from fraction ``f0`` to ``f1`` (either order)."""
    fr = np.linspace(f0, f1, n + 1)
    if isinstance(curve, (Line, Arc, Polyline)):
        t = fr  # parametrised proportionally to arc length
    elif isinstance(curve, Bezier):
        t = _bezier_params(curve, fr)
    else:
        t = curve.parameter_at(fr)
    return curve.point(t)


# ---------------------------------------------------------------------------------------------
# Flat meshes
# ---------------------------------------------------------------------------------------------


@dataclass(eq=False)
class FlatPanels:
    """All panels' flat meshes in one numbering (not merged: a seam's two sides are different
    nodes, listed in ``pairs``).

    Attributes:
        names: panel names, in the pattern's order (index = ``node_panel`` value).
        xy: (N, 2) flat coordinates, each panel rotated so that its grain is +x [m].
        node_panel: (N,) panel index of each node.
        vertex: (N,) True for triangle vertices, False for the order-2 edge nodes.
        cells: (M, 6) triangles in gmsh's tri6 order (v0, v1, v2, m01, m12, m20),
            counter-clockwise in ``xy``.
        cell_panel: (M,) panel index of each cell.
        segments: (S, 3) boundary segments (start vertex, edge node, end vertex), along the
            edge's curve direction.
        segment_panel, segment_edge: (S,) the panel and the edge (index in the panel).
        segment_seam: (S,) the seam index (into ``pattern.seams``), −1 on a free edge.
        pairs: (P, 2) seam partners: the node on side ``a`` and the node on side ``b``
            (vertices and edge nodes alike), in order along side ``a``'s range.
        pair_seam: (P,) the seam of each pair.
        rotation: (n_panels, 2, 2) ``xy = rotation[p] @ (x, y)`` of the panel's drawing.
        h: the target element size [m].
    """

    names: list[str]
    xy: Array
    node_panel: npt.NDArray[np.int32]
    vertex: npt.NDArray[np.bool_]
    cells: IArray
    cell_panel: npt.NDArray[np.int32]
    segments: IArray
    segment_panel: npt.NDArray[np.int32]
    segment_edge: npt.NDArray[np.int32]
    segment_seam: npt.NDArray[np.int32]
    pairs: IArray
    pair_seam: npt.NDArray[np.int32]
    rotation: Array
    h: float

    @property
    def panel_xy(self) -> Array:
        """(N, 2) node coordinates in their panel's drawing frame (before the grain rotation)."""
        return np.einsum("nji,nj->ni", self.rotation[self.node_panel], self.xy)

    def seam_sides(self, seam: int) -> tuple[IArray, IArray]:
        """The paired nodes of one seam: side a's and side b's, in order along side a."""
        sel = self.pair_seam == seam
        return self.pairs[sel, 0], self.pairs[sel, 1]


def edge_group_name(pattern: Pattern, panel: str, edge: int) -> str:
    """The edge tag of a free edge: its name if it names a garment edge shared by panels
    (:data:`SHARED_EDGE_PREFIXES`: ``hem``, ``neckline``, ``armhole_left``…), else
    ``<panel>_<edge name>`` (``<panel>_edge<i>`` if unnamed)."""
    e = pattern.panel(panel).edges[edge]
    if e.name and e.name.startswith(SHARED_EDGE_PREFIXES):
        return e.name
    return f"{panel}_{e.name or f'edge{edge}'}"


@dataclass
class _Piece:
    edge: int
    a: float  # arc-length fractions in the curve's direction, a < b
    b: float
    seam: int = -1
    side: int = -1  # 0: the seam's a side, 1: its b side
    n: int = 1
    name: str = ""


def _pieces(pattern: Pattern, h: float, refine: Any) -> dict[str, list[_Piece]]:
    """Split every edge at the seam range ends; segment counts shared by both sides."""
    ranges: dict[tuple[str, int], list[tuple[float, float, int, int]]] = {}
    for s, seam in enumerate(pattern.seams):
        if seam.kind not in ("seam", "dart"):
            raise PatternError(f"seam {s}: kind must be 'seam' or 'dart', got {seam.kind!r}")
        for side, r in enumerate((seam.a, seam.b)):
            p = pattern.panel(r.panel)
            e = p.edge_index(r.edge)
            lo, hi = sorted((float(r.f0), float(r.f1)))
            if not (0.0 <= lo < hi <= 1.0):
                raise PatternError(
                    f"{pattern.seam_name(s)}: panel {r.panel!r} edge {e}: range "
                    f"[{r.f0}, {r.f1}] is not inside [0, 1] or is empty"
                )
            ranges.setdefault((r.panel, e), []).append((lo, hi, s, side))
    seam_len = np.zeros((len(pattern.seams), 2))
    out: dict[str, list[_Piece]] = {}
    for pname, panel in pattern.panels.items():
        pieces: list[_Piece] = []
        for e, edge in enumerate(panel.edges):
            rs = sorted(ranges.get((pname, e), []))
            for (_, hi0, s0, _), (lo1, _, s1, _) in itertools.pairwise(rs):
                if lo1 < hi0 - 1e-9:
                    raise PatternError(
                        f"panel {pname!r} edge {e}: the ranges of {pattern.seam_name(s0)} and "
                        f"{pattern.seam_name(s1)} overlap"
                    )
            cuts = sorted({0.0, 1.0, *[r[0] for r in rs], *[r[1] for r in rs]})
            cuts = [c for i, c in enumerate(cuts) if i == 0 or c - cuts[i - 1] > 1e-9]
            L = curve_length(edge.curve)
            for a, b in itertools.pairwise(cuts):
                hit = [r for r in rs if r[0] <= a + 1e-9 and b <= r[1] + 1e-9]
                if hit:
                    _, _, s, side = hit[0]
                    seam_len[s, side] = L * (b - a)
                    pieces.append(_Piece(e, a, b, s, side, name=pattern.seam_name(s)))
                else:
                    name = edge_group_name(pattern, pname, e)
                    size = h * (refine.ratio if refine is not None and refine.selects(name) else 1)
                    n = max(1, int(np.ceil(L * (b - a) / size - 1e-9)))
                    pieces.append(_Piece(e, a, b, n=n, name=name))
        out[pname] = pieces
    for s in range(len(pattern.seams)):
        name = pattern.seam_name(s)
        size = h * (refine.ratio if refine is not None and refine.selects(name) else 1)
        n = max(1, int(np.ceil(seam_len[s].max() / size - 1e-9)))
        for pieces in out.values():
            for pc in pieces:
                if pc.seam == s:
                    pc.n = n
    return out


def _cross2(a: Array, b: Array) -> Array:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _grain_rotation(grain: Array) -> Array:
    gx, gy = grain / np.linalg.norm(grain)
    return np.array([[gx, gy], [-gy, gx]])


def mesh_panels(
    pattern: Pattern,
    h: float,
    *,
    order: int = 2,
    refine: Any = None,
    time_limit_s: float | None = GMSH_TIME_LIMIT,
) -> FlatPanels:
    """Mesh every panel flat (triangles of order ``order``, size ``h`` [m]) with paired seams.

    ``refine``: an :class:`~fenics_garment.geometry.garments.EdgeRefinement` whose ``edges``
    select seam names or free-edge tags (:func:`edge_group_name`): their segments are
    ``ratio × h`` and the cells grow back to ``h`` over ``band``. Raises
    :class:`~.model.PatternError` for an outline that does not close or overlapping ranges.
    """
    if order not in (1, 2):
        raise ValueError(f"panel mesh order must be 1 or 2, got {order}")
    if not h > 0:
        raise ValueError(f"element size h must be > 0, got {h}")
    if not pattern.panels:
        raise PatternError(f"{pattern.name}: no panels")
    pieces = _pieces(pattern, h, refine)
    names = list(pattern.panels)
    rotation = np.array([_grain_rotation(pattern.panels[n].grain) for n in names])
    # outline vertices and segments per panel, in the panel's grain frame
    outlines = []
    for pi, pname in enumerate(names):
        panel = pattern.panels[pname]
        verts, mids, seg_piece = [], [], []
        for k, pc in enumerate(pieces[pname]):
            smp = sample_curve(panel.edges[pc.edge].curve, pc.a, pc.b, 2 * pc.n) @ rotation[pi].T
            if verts:
                gap = np.linalg.norm(smp[0] - verts[-1])
                if gap > 1e-6 * max(h, 1e-3):
                    raise PatternError(
                        f"panel {pname!r}: edge {pc.edge} does not start where the previous "
                        f"edge ends (gap {gap:.3g} m)"
                    )
                verts.pop()
            verts.extend(smp[0::2])
            mids.extend(smp[1::2])
            seg_piece.extend([k] * pc.n)
        if np.linalg.norm(verts[-1] - verts[0]) > 1e-6 * max(h, 1e-3):
            raise PatternError(f"panel {pname!r}: the outline does not close")
        verts.pop()
        outlines.append((np.array(verts), np.array(mids), np.array(seg_piece)))

    with gmsh_session(name="panels") as g, time_limit(time_limit_s, "the flat panels"):
        geo = g.model.geo
        surf_of, lines_of = [], []
        named: dict[str, list[int]] = {}
        for pi, (v, _, seg_piece) in enumerate(outlines):
            nv = len(v)
            seg_len = np.linalg.norm(np.roll(v, -1, axis=0) - v, axis=1)
            lc = 0.5 * (seg_len + np.roll(seg_len, 1))
            pts = [geo.addPoint(x, y, 0.0, float(s)) for (x, y), s in zip(v, lc, strict=True)]
            lines = [geo.addLine(pts[k], pts[(k + 1) % nv]) for k in range(nv)]
            loop = geo.addCurveLoop(lines)
            surf_of.append(geo.addPlaneSurface([loop]))
            lines_of.append(lines)
            for k, ln in enumerate(lines):
                named.setdefault(pieces[names[pi]][seg_piece[k]].name, []).append(ln)
        geo.synchronize()
        for lines in lines_of:
            for ln in lines:
                g.model.mesh.setTransfiniteCurve(ln, 2)
        g.option.setNumber("Mesh.MeshSizeMax", h)
        g.option.setNumber("Mesh.MeshSizeMin", h / 20)
        g.option.setNumber("Mesh.MeshSizeFromPoints", 1)
        g.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
        g.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 1)
        g.option.setNumber("Mesh.Algorithm", 6)
        if refine is not None:
            sel = {k: v for k, v in named.items() if refine.selects(k)}
            if sel:
                refine.apply(g, sel)
        g.model.mesh.generate(2)
        if order == 2:
            g.model.mesh.setOrder(2)
        tags, coords, _ = g.model.mesh.getNodes()
        tags = tags.astype(np.int64)
        index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
        index[tags] = np.arange(len(tags))
        xy = coords.reshape(-1, 3)[:, :2].copy()
        etype = 9 if order == 2 else 2
        ltype = 8 if order == 2 else 1
        k_el = 6 if order == 2 else 3
        cells, cell_panel = [], []
        for pi, s in enumerate(surf_of):
            _, en = g.model.mesh.getElementsByType(etype, s)
            c = index[en.astype(np.int64).reshape(-1, k_el)]
            cells.append(c)
            cell_panel.append(np.full(len(c), pi, dtype=np.int32))
        seg_rows = []
        for pi, lines in enumerate(lines_of):
            for ln in lines:
                _, en = g.model.mesh.getElementsByType(ltype, ln)
                if len(en) != (3 if order == 2 else 2):
                    raise PatternError(f"panel {names[pi]!r}: a boundary segment was split")
                e = index[en.astype(np.int64)]
                seg_rows.append([e[0], e[2], e[1]] if order == 2 else [e[0], -1, e[1]])
    cells_a = np.concatenate(cells)
    cell_panel_a = np.concatenate(cell_panel)
    segs = np.array(seg_rows, dtype=np.int64)
    # the boundary edge nodes at the curve's arc-length midpoints; panel and edge of segments
    seg_panel, seg_edge, seg_seam, seg_side, seg_pc = [], [], [], [], []
    row = 0
    for pi, (v, mids, seg_piece) in enumerate(outlines):
        n = len(v)
        s = segs[row : row + n]
        if np.abs(xy[s[:, 0]] - v).max() > 1e-9 * max(1.0, np.abs(v).max()):
            raise PatternError(f"panel {names[pi]!r}: gmsh moved a boundary vertex")
        if order == 2:
            xy[s[:, 1]] = mids
        pcs = pieces[names[pi]]
        seg_panel.append(np.full(n, pi, dtype=np.int32))
        seg_edge.append(np.array([pcs[k].edge for k in seg_piece], dtype=np.int32))
        seg_seam.append(np.array([pcs[k].seam for k in seg_piece], dtype=np.int32))
        seg_side.append(np.array([pcs[k].side for k in seg_piece], dtype=np.int32))
        seg_pc.append(np.array(seg_piece, dtype=np.int64))
        row += n
    # cells counter-clockwise in xy
    p = xy[cells_a[:, :3]]
    flip = _cross2(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]) < 0
    if order == 2:
        cells_a[flip] = cells_a[flip][:, [0, 2, 1, 5, 4, 3]]
    else:
        cells_a[flip] = cells_a[flip][:, [0, 2, 1]]
    node_panel = np.zeros(len(xy), dtype=np.int32)
    node_panel[cells_a.ravel()] = np.repeat(cell_panel_a, cells_a.shape[1])
    vertex = np.zeros(len(xy), dtype=bool)
    vertex[cells_a[:, :3].ravel()] = True
    seg_panel_a, seg_seam_a = np.concatenate(seg_panel), np.concatenate(seg_seam)
    seg_side_a, seg_pc_a = np.concatenate(seg_side), np.concatenate(seg_pc)
    pairs, pair_seam = _pair(pattern, segs, seg_panel_a, seg_pc_a, seg_seam_a, seg_side_a, names,
                             pieces, order)  # fmt: skip
    return FlatPanels(
        names=names,
        xy=xy,
        node_panel=node_panel,
        vertex=vertex,
        cells=cells_a,
        cell_panel=cell_panel_a,
        segments=segs,
        segment_panel=seg_panel_a,
        segment_edge=np.concatenate(seg_edge),
        segment_seam=seg_seam_a,
        pairs=pairs,
        pair_seam=pair_seam,
        rotation=rotation,
        h=float(h),
    )


def _pair(pattern, segs, seg_panel, seg_pc, seg_seam, seg_side, names, pieces, order):
    """Node sequences of both sides of every seam, paired one to one."""
    out, out_seam = [], []
    for s, seam in enumerate(pattern.seams):
        seqs = []
        for side, r in enumerate((seam.a, seam.b)):
            pi = names.index(r.panel)
            sel = np.flatnonzero((seg_seam == s) & (seg_side == side) & (seg_panel == pi))
            # the segments of a piece are consecutive along the outline (the closing wrap-around
            # only ever joins different pieces, as every outline starts at an edge start)
            ss = segs[sel]
            if order == 2:
                seq = np.concatenate([ss[:, [0, 1]].ravel(), ss[-1:, 2]])
            else:
                seq = np.concatenate([ss[:, 0], ss[-1:, 2]])
            if r.f0 > r.f1:
                seq = seq[::-1]
            seqs.append(seq)
        a, b = seqs
        if seam.reversed:
            b = b[::-1]
        if len(a) != len(b):  # pragma: no cover - both sides get the same count
            raise PatternError(f"{pattern.seam_name(s)}: {len(a)} and {len(b)} nodes")
        out.append(np.column_stack([a, b]))
        out_seam.append(np.full(len(a), s, dtype=np.int32))
    if not out:
        return np.zeros((0, 2), dtype=np.int64), np.zeros(0, dtype=np.int32)
    return np.concatenate(out), np.concatenate(out_seam)


# ---------------------------------------------------------------------------------------------
# Placement
# ---------------------------------------------------------------------------------------------

#: least clearance [m] of the wrap cylinder from the body's hull (before sewing)
WRAP_CLEARANCE = 0.005


def _name_azimuth(name: str) -> tuple[float | None, int]:
    """The azimuth [rad] a panel's name asks for and a side shift (+1: towards the body's
    left from the centre line, −1 towards its right, 0: centred)."""
    words = set(re.split(r"[^a-z]+", name.lower()))
    left, right = "left" in words, "right" in words
    side = 1 if left and not right else -1 if right and not left else 0
    if "front" in words:
        return -np.pi / 2, side
    if "back" in words:
        return np.pi / 2, -side  # seen from above, the back's left is towards decreasing angle
    if side:
        return (0.0 if side > 0 else np.pi), 0
    return None, 0


def _axis_source(body: Any, axis: str) -> tuple[Any, Any, str]:
    """What a wrap axis wraps around: (source with sections, limb frame or None, side filter)."""
    if axis == "torso":
        return body, None, ""
    limbs = getattr(body, "limbs", None) or {}
    if axis in limbs:
        return limbs[axis], limbs[axis], ""
    if limbs:
        why = getattr(body, "limb_problems", {}).get(axis, "not found")
        raise PatternError(f"wrap axis {axis!r}: the body has no such limb ({why})")
    return body, None, axis.rsplit("_", 1)[-1]


def _hull_points(src: Any, frame: Any, side: str, z0: float, z1: float) -> Array:
    """Section points of the body (or limb, in its straightened frame) between heights."""
    pts = []
    zs = np.linspace(z0, z1, max(2, int(np.ceil((z1 - z0) / 0.01)) + 1))
    if frame is not None:
        for z in zs:
            p = src.section_at(float(z))
            if p is not None:
                pts.append(p)
        return np.concatenate(pts) if pts else np.zeros((0, 2))
    v, t = src.vertices, src.triangles
    lo, hi = v[:, 2].min() + 1e-4, v[:, 2].max() - 1e-4
    cut = getattr(src, "arm_cut", {}) or {}
    for z in zs:
        if not lo <= z <= hi:
            continue
        loops = sec.slice_loops(v, t, float(z))
        if cut and not side:
            loops = [lp for lp in loops if cut.get("right", -np.inf) < lp[:, 0].mean()
                     < cut.get("left", np.inf)]  # fmt: skip
        if side and len(loops) > 1:
            sign = 1.0 if side == "left" else -1.0
            loops = [lp for lp in loops if sign * lp[:, 0].mean() > 0]
        pts.extend(loops)
    sections = getattr(src, "sections", {})
    sided = any(k.endswith(("_left", "_right")) for k in sections)
    for level, p in sections.items():
        base = level.removesuffix("_left").removesuffix("_right")
        z = src.landmarks.get(base)
        if z is None or not z0 <= z <= z1:
            continue
        if side and (not level.endswith(side) if sided else level != base):
            continue  # a leg's own sections, or the whole body's if it is the limb
        if not side and level != base and cut:
            continue
        pts.append(p)
    return np.concatenate(pts) if pts else np.zeros((0, 2))


def _default_top(src: Any, axis: str, height: float) -> float:
    marks = src.landmarks
    if axis == "torso" and "neck_base" in marks:
        return float(marks["neck_base"])
    zs = [float(z) for z in marks.values()]
    if not zs:
        v = src.vertices
        zs = [float(v[:, 2].min()), float(v[:, 2].max())]
    return 0.5 * (min(zs) + max(zs)) + 0.5 * height


class _WrapCurve:
    """A closed convex curve (counter-clockwise from above), parametrised by arc length."""

    def __init__(self, pts: Array) -> None:
        self.pts = pts
        seg = np.linalg.norm(np.roll(pts, -1, axis=0) - pts, axis=1)
        self.s = np.concatenate([[0.0], np.cumsum(seg)])
        self.length = float(self.s[-1])
        self.centre = sec.centroid(pts)
        ang = np.arctan2(pts[:, 1] - self.centre[1], pts[:, 0] - self.centre[0])
        self.ang = np.unwrap(np.concatenate([ang, ang[:1]]))

    def at(self, s: Array) -> Array:
        s = np.mod(s, self.length)
        closed = np.vstack([self.pts, self.pts[:1]])
        return np.column_stack([np.interp(s, self.s, closed[:, 0]),
                                np.interp(s, self.s, closed[:, 1])])  # fmt: skip

    def s_of(self, azimuth: float) -> float:
        a0 = self.ang[0]
        a = a0 + np.mod(azimuth - a0, 2 * np.pi)
        return float(np.interp(a, self.ang, self.s))


def place(
    flat: FlatPanels, pattern: Pattern, body: Any, *, clearance: float = WRAP_CLEARANCE
) -> Array:
    """Initial 3-D positions (N, 3) of the flat nodes (not merged), the drawn side outward.

    A panel is drawn as seen from outside the garment, y up (its +z normal is the outward one).

    * With a :class:`~.model.Placement`, the panel goes there (``rotation @ (x, y, 0) +
      translation``); unless its wrap axis is ``"none"`` or the placed plane is not vertical
      (normal more than 60° from horizontal), it is then bent isometrically around the circle
      about the body's vertical axis through its placed centre (radius: its distance from the
      axis, at least the body's hull plus ``clearance`` over its span). On a scan's limb axis a
      placed panel stays flat.
    * Without one, the panels of each wrap axis are wrapped isometrically around one
      generalised vertical cylinder: the convex hull of the body's sections over their height
      range, offset by ``clearance`` and further if needed so that its perimeter is at least the
      sum of the panels' widths. Panel centres go to their :class:`~.model.Wrap` azimuth, or by
      name (``front`` −90°, ``back`` 90°, ``left`` 0°, ``right`` 180°; ``front_left`` starts at
      the centre front and extends towards the body's left, and so on), the rest in pattern
      order around; the panel's top at ``Wrap.top`` (default: the neck base on a torso, else
      the panel centred on the body's levels). On a scan's limb the wrap is made in the
      limb's straightened frame and mapped onto it (:meth:`~fenics_garment.geometry.limbs.
      Limb.to_world`).
    """
    pxy = flat.panel_xy
    X = np.zeros((len(pxy), 3))
    rings: dict[str, list[int]] = {}
    for pi, name in enumerate(flat.names):
        panel = pattern.panels[name]
        wrap = panel.wrap or Wrap()
        nodes = flat.node_panel == pi
        if panel.placement is not None:
            X[nodes] = panel.placement.apply(pxy[nodes])
            if wrap.axis != "none":
                src, frame, side = _axis_source(body, wrap.axis)
                if frame is None:
                    X[nodes] = _wrap_placed(X[nodes], src, side, clearance)
            continue
        if wrap.axis == "none":
            X[nodes] = np.column_stack([pxy[nodes], np.zeros(int(nodes.sum()))])
            continue
        rings.setdefault(wrap.axis, []).append(pi)
    for axis, members in rings.items():
        _wrap_ring(flat, pattern, body, axis, members, pxy, X, clearance)
    return X


def _wrap_ring(flat, pattern, body, axis, members, pxy, X, clearance) -> None:
    src, frame, side = _axis_source(body, axis)
    info = []
    for pi in members:
        p = pxy[flat.node_panel == pi]
        wrap = pattern.panels[flat.names[pi]].wrap or Wrap()
        (x0, y0), (x1, y1) = p.min(axis=0), p.max(axis=0)
        top = wrap.top
        if isinstance(top, str):
            if top not in src.landmarks:
                raise PatternError(f"panel {flat.names[pi]!r}: wrap top {top!r} is no landmark")
            top = float(src.landmarks[top])
        elif top is None:
            top = _default_top(src, axis, y1 - y0)
        info.append((pi, x0, x1, y1, float(top), float(top) - (y1 - y0)))
    z0 = min(i[5] for i in info)
    z1 = max(i[4] for i in info)
    hull_pts = _hull_points(src, frame, side, z0, z1)
    if len(hull_pts) < 3:
        raise PatternError(f"wrap axis {axis!r}: the body has no section between z = "
                           f"{z0:.3f} and {z1:.3f} m")  # fmt: skip
    dense = sec.resample_by_angle(sec.convex_hull(hull_pts), 720)
    width = sum(i[2] - i[1] for i in info)
    curve_pts = sec.offset_by(dense, clearance)
    if width > sec.perimeter(curve_pts):
        curve_pts, _ = sec.offset_to_perimeter(dense, width)
    curve = _WrapCurve(curve_pts)
    # centres along the curve
    cursor = None
    for pi, x0, x1, y1, top, _ in info:
        wrap = pattern.panels[flat.names[pi]].wrap or Wrap()
        w = x1 - x0
        if wrap.azimuth is not None:
            sc = curve.s_of(np.radians(wrap.azimuth))
        else:
            az, shift = _name_azimuth(flat.names[pi])
            if az is not None:
                sc = curve.s_of(az) + shift * 0.5 * w
            else:
                sc = curve.s_of(-np.pi / 2) if cursor is None else cursor + 0.5 * w
        cursor = sc + 0.5 * w
        nodes = flat.node_panel == pi
        p = pxy[nodes]
        s = sc + (p[:, 0] - 0.5 * (x0 + x1))
        xy = curve.at(s)
        z = top - (y1 - p[:, 1])
        P = np.column_stack([xy, z])
        X[nodes] = P if frame is None else frame.to_world(P)


def _wrap_placed(P: Array, body: Any, side: str, clearance: float) -> Array:
    """Bend a placed flat panel around the body's vertical axis through its centre."""
    c3 = 0.5 * (P.min(axis=0) + P.max(axis=0))
    q = P - c3
    _, _, vt = np.linalg.svd(q, full_matrices=False)
    n = vt[2]
    if abs(n[2]) > np.cos(np.radians(30.0)):
        return P
    hull_pts = _hull_points(body, None, side, float(P[:, 2].min()), float(P[:, 2].max()))
    if len(hull_pts) < 3:
        return P
    hull = sec.offset_by(sec.resample_by_angle(sec.convex_hull(hull_pts), 720), clearance)
    centre = sec.centroid(hull)
    rad = c3[:2] - centre
    phi = float(np.arctan2(rad[1], rad[0]))
    radial = np.array([np.cos(phi), np.sin(phi), 0.0])
    n_h = n if n @ radial >= 0 else -n
    d = float(np.dot(c3[:2] - centre, n_h[:2]))
    up = np.array([0.0, 0.0, 1.0]) - n_h[2] * n_h
    up /= np.linalg.norm(up)
    t_h = np.cross(up, n_h)  # seen from outside, to the right: increasing azimuth
    u, v = q @ t_h, q @ up
    hr = np.linalg.norm(hull - centre, axis=1)
    ha = np.arctan2(hull[:, 1] - centre[1], hull[:, 0] - centre[0])
    R = max(d, 1e-3)
    for _ in range(3):  # the radius that clears the hull over the panel's span
        span = (u.max() - u.min()) / (2 * R) + 1e-3
        near = np.abs(np.angle(np.exp(1j * (ha - phi)))) <= span
        R = max(d, float(hr[near].max()) if near.any() else d)
    th = phi + u / R
    return np.column_stack([centre[0] + R * np.cos(th), centre[1] + R * np.sin(th), c3[2] + v])
