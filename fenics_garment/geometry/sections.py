"""Horizontal cross-sections: analytic shapes, perimeters, offsets, and slices of triangle meshes.

Conventions used throughout the geometry package: metres, +z up, the body faces **−y** (anterior
= −y), so the body's left side is **+x**. A closed section is an (n, 2) array of (x, y) points
without the first point repeated, counter-clockwise seen from above.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.spatial import ConvexHull

Array = npt.NDArray[np.float64]


@dataclass(frozen=True)
class SectionShape:
    """A superellipse with different front and back depths, before scaling to a girth.

    ``|x/a|^n + |y/b|^n = 1`` with ``b = front`` for y < 0 (anterior) and ``b = back`` for y > 0;
    ``n = 2`` is an ellipse, larger ``n`` is boxier. Only ratios matter: the mannequin scales the
    shape so that its perimeter equals the requested girth.
    """

    half_width: float
    front: float
    back: float
    exponent: float = 2.0
    centre: tuple[float, float] = (0.0, 0.0)

    def points(self, n: int = 720, scale: float = 1.0) -> Array:
        """``n`` points at equal parameter steps, starting at +x and turning counter-clockwise."""
        t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
        c, s = np.cos(t), np.sin(t)
        e = 2.0 / self.exponent
        x = self.half_width * np.sign(c) * np.abs(c) ** e
        b = np.where(s < 0, self.front, self.back)
        y = b * np.sign(s) * np.abs(s) ** e
        return np.column_stack([x * scale + self.centre[0], y * scale + self.centre[1]])

    def scale_for_girth(self, girth: float, n: int = 4000) -> float:
        """The uniform scale (about the centre) that makes the perimeter equal to ``girth``."""
        return girth / perimeter(self.points(n))


def perimeter(pts: Array, closed: bool = True) -> float:
    """Length of a polyline (closed by default)."""
    d = np.diff(np.vstack([pts, pts[:1]]) if closed else pts, axis=0)
    return float(np.sum(np.linalg.norm(d, axis=1)))


def tape_girth(pts: Array) -> float:
    """ISO 8559-1 girth of a section: the tape bridges hollows, i.e. the convex hull perimeter."""
    return float(ConvexHull(np.asarray(pts)[:, :2]).area)  # in 2-D, ``area`` is the perimeter


def convex_hull(pts: Array) -> Array:
    """Counter-clockwise convex hull vertices of a 2-D point set."""
    return np.asarray(pts)[ConvexHull(np.asarray(pts)[:, :2]).vertices, :2]


def polygon_area(pts: Array) -> float:
    """Signed area (positive when counter-clockwise)."""
    x, y = pts[:, 0], pts[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def centroid(pts: Array) -> Array:
    """Area centroid of a simple closed polygon."""
    x, y = pts[:, 0], pts[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cr = x * yn - xn * y
    a = 0.5 * np.sum(cr)
    return np.array([np.sum((x + xn) * cr), np.sum((y + yn) * cr)]) / (6.0 * a)


def _vertex_normals(pts: Array) -> Array:
    """Outward unit normals at the vertices of a counter-clockwise closed polygon."""
    t = np.roll(pts, -1, axis=0) - np.roll(pts, 1, axis=0)
    n = np.column_stack([t[:, 1], -t[:, 0]])
    return n / np.linalg.norm(n, axis=1)[:, None]


def offset_to_perimeter(pts: Array, target: float, iterations: int = 6) -> tuple[Array, float]:
    """Offset a convex counter-clockwise curve along its normals until its perimeter is ``target``.

    Steiner's formula for a convex curve, ``P(d) = P(0) + 2πd``, gives the first guess of the
    normal distance ``d``; a few Newton steps remove the discretisation error. ``d < 0`` moves
    inwards (a tight garment) and is valid while ``|d|`` is below the smallest curvature radius.
    Returns the offset points and ``d``.
    """
    nrm = _vertex_normals(pts)
    d = (target - perimeter(pts)) / (2.0 * np.pi)
    for _ in range(iterations):
        p = perimeter(pts + d * nrm)
        d += (target - p) / (2.0 * np.pi)
    return pts + d * nrm, float(d)


def resample_by_angle(pts: Array, n: int, centre: Array | None = None) -> Array:
    """Points where ``n`` equally spaced rays from ``centre`` cross a star-shaped closed polygon.

    Ray k has angle ``2πk/n`` (k = 0 points to +x), so k = 0 and k = n/2 are the lateral points
    where front and back panels meet.
    """
    c = centroid(pts) if centre is None else np.asarray(centre)
    a = pts - c
    b = np.roll(pts, -1, axis=0) - pts
    out = np.empty((n, 2))
    for k, th in enumerate(2.0 * np.pi * np.arange(n) / n):
        u = np.array([np.cos(th), np.sin(th)])
        den = u[0] * b[:, 1] - u[1] * b[:, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (u[1] * a[:, 0] - u[0] * a[:, 1]) / den  # where the edge crosses the ray line
            s = a[:, 0] * u[0] + a[:, 1] * u[1] + t * (b[:, 0] * u[0] + b[:, 1] * u[1])
        ok = (t >= -1e-12) & (t <= 1 + 1e-12) & (s > 0) & np.isfinite(t)
        i = np.flatnonzero(ok)[np.argmax(s[ok])]
        out[k] = pts[i] + t[i] * b[i]
    return out


def slice_loops(vertices: Array, triangles: npt.NDArray[np.int64], z: float) -> list[Array]:
    """Closed loops where the plane ``z`` cuts a triangle surface, as (k, 2) arrays (x, y).

    Loops are oriented counter-clockwise seen from above. Open chains (a plane through a hole
    or an open garment edge) are returned as they are; :func:`slice_chains` tells them apart.
    """
    return [p for p, _ in slice_chains(vertices, triangles, z)]


def section_length(vertices: Array, triangles: npt.NDArray[np.int64], z: float) -> float:
    """Total length of the section of a surface by the plane ``z`` (closed loops and chains)."""
    return float(sum(perimeter(p, closed=c) for p, c in slice_chains(vertices, triangles, z)))


def slice_chains(
    vertices: Array, triangles: npt.NDArray[np.int64], z: float
) -> list[tuple[Array, bool]]:
    """Like :func:`slice_loops`, with a flag per piece: True for a closed loop."""
    v = np.asarray(vertices)
    tri = np.asarray(triangles)
    zz = v[:, 2] - z
    span = np.ptp(v[:, 2]) or 1.0
    while np.any(np.abs(zz) < 1e-12 * span):  # keep vertices off the plane
        z += 1e-9 * span
        zz = v[:, 2] - z
    above = zz[tri] > 0
    cut = np.flatnonzero(above.any(axis=1) & ~above.all(axis=1))
    if cut.size == 0:
        return []
    # For each cut triangle, the two crossed edges (as sorted vertex pairs) and their points;
    # edges are numbered in the order first met going through the local edges (0, 1), (1, 2),
    # (2, 0) of all cut triangles in turn.
    n_v = len(v)
    keys_l, segs_l = [], []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        a, b = tri[cut, i], tri[cut, j]
        s = np.flatnonzero(above[cut, i] != above[cut, j])
        keys_l.append(np.minimum(a[s], b[s]).astype(np.int64) * n_v + np.maximum(a[s], b[s]))
        segs_l.append(s)
    key_all, seg_all = np.concatenate(keys_l), np.concatenate(segs_l)
    uniq, first, inv = np.unique(key_all, return_index=True, return_inverse=True)
    rank = np.empty(len(uniq), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(uniq))
    edge_of = rank[inv.ravel()]
    seg_pair = np.full((cut.size, 2), -1, dtype=np.int64)
    order = np.argsort(seg_all, kind="stable")  # per segment, its first then second edge
    seg_pair[seg_all[order[0::2]], 0] = edge_of[order[0::2]]
    seg_pair[seg_all[order[1::2]], 1] = edge_of[order[1::2]]
    kk = np.column_stack([uniq // n_v, uniq % n_v])[np.argsort(rank)]
    keys = range(len(kk))
    t = zz[kk[:, 0]] / (zz[kk[:, 0]] - zz[kk[:, 1]])
    pts = v[kk[:, 0], :2] + t[:, None] * (v[kk[:, 1], :2] - v[kk[:, 0], :2])
    edge_segs: list[list[int]] = [[] for _ in keys]
    pair: list[list[int]] = seg_pair.tolist()  # plain lists: the walk below is scalar work
    for s, (e0, e1) in enumerate(pair):
        edge_segs[e0].append(s)
        edge_segs[e1].append(s)
    used = [False] * cut.size
    loops: list[tuple[Array, bool]] = []
    # start open chains at edges with a single segment, then closed loops anywhere
    starts = [e for e, ss in enumerate(edge_segs) if len(ss) == 1]
    starts += list(range(len(keys)))
    for e_start in starts:
        free = [s for s in edge_segs[e_start] if not used[s]]
        if not free:
            continue
        chain = [e_start]
        e, s = e_start, free[0]
        closed = False
        while True:
            used[s] = True
            e = pair[s][1] if pair[s][0] == e else pair[s][0]
            if e == e_start:
                closed = True
                break
            chain.append(e)
            nxt = [q for q in edge_segs[e] if not used[q]]
            if not nxt:
                break
            s = nxt[0]
        p = pts[chain]
        if len(p) >= 3 and polygon_area(p) < 0:
            p = p[::-1]
        loops.append((p, closed))
    return loops


def offset_by(pts: Array, d: float) -> Array:
    """Move every point of a counter-clockwise closed curve ``d`` along its outward normal."""
    return pts + d * _vertex_normals(pts)


def signed_distance_2d(points: Array, polygon: Array) -> Array:
    """Distance of points to a closed polygon, negative inside (for clearance checks)."""
    a = polygon
    b = np.roll(polygon, -1, axis=0)
    ab = b - a
    ap = points[:, None, :] - a[None, :, :]
    t = np.clip(np.einsum("pki,ki->pk", ap, ab) / np.einsum("ki,ki->k", ab, ab), 0.0, 1.0)
    dist = np.linalg.norm(ap - t[..., None] * ab[None], axis=2).min(axis=1)
    return np.where(contains(polygon, points), -dist, dist)


def contains(polygon: Array, points: Array) -> npt.NDArray[np.bool_]:
    """Even-odd point-in-polygon test (numpy only, vectorised over edges and points)."""
    p = np.atleast_2d(points)
    a = np.asarray(polygon)
    b = np.roll(a, -1, axis=0)
    inside = np.zeros(len(p), dtype=bool)
    step = max(1, 2_000_000 // max(len(a), 1))
    for s in range(0, len(p), step):
        q = p[s : s + step, None, :]
        y0, y1, x0, x1 = a[None, :, 1], b[None, :, 1], a[None, :, 0], b[None, :, 0]
        crosses = (y0 > q[..., 1]) != (y1 > q[..., 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            xs = x0 + (q[..., 1] - y0) * (x1 - x0) / (y1 - y0)
        inside[s : s + step] = (np.count_nonzero(crosses & (q[..., 0] < xs), axis=1) % 2) == 1
    return inside
