"""Sanity checks of a generated garment surface before it becomes a shell mesh.

A loft through badly shaped sections can overshoot (a garment metres wide) or fold back on
itself; either would give a meaningless contact problem, so both are refused with the reason:

* **bounded**: a convex closed curve of perimeter P is at most P/2 wide, so no garment node may
  lie further than half the largest garment girth (plus a margin) from the others
  horizontally, nor outside the levels' height range (plus a margin);
* **no fold**: across every edge shared by two cells, the outward cell normals turn by less
  than ``MAX_TURN`` degrees (a fold turns the surface by about 180°).

And a fairness measure of a skirt (:func:`skirt_bulge`): no bulge between hem and waist.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from .errors import GeometryError

Array = npt.NDArray[np.float64]

#: largest angle [°] between the normals of two neighbouring cells
MAX_TURN = 120.0
#: slack [m] on the bounding box
MARGIN = 0.05


def cell_normals(points: Array, cells: npt.NDArray[np.int64]) -> Array:
    """Unit normals of triangles (right-hand rule) or quadrilaterals (cross of diagonals)."""
    p = points[cells]
    if cells.shape[1] == 4:
        n = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
    else:
        n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return n / (np.linalg.norm(n, axis=1)[:, None] + 1e-300)


def largest_turn(points: Array, cells: npt.NDArray[np.int64]) -> float:
    """Largest angle [°] between the normals of two cells sharing an edge."""
    k = cells.shape[1]
    e = np.concatenate([cells[:, [j, (j + 1) % k]] for j in range(k)])
    owner = np.tile(np.arange(len(cells)), k)
    e = np.sort(e, axis=1)
    n = int(e.max()) + 1
    key = e[:, 0] * n + e[:, 1]
    order = np.argsort(key, kind="stable")
    key, owner = key[order], owner[order]
    same = np.flatnonzero(key[1:] == key[:-1])
    if not len(same):
        return 0.0
    nrm = cell_normals(points, cells)
    dots = np.einsum("ij,ij->i", nrm[owner[same]], nrm[owner[same + 1]])
    return float(np.degrees(np.arccos(np.clip(dots.min(), -1.0, 1.0))))


def check_garment(
    kind: str,
    points: Array,
    cells: npt.NDArray[np.int64],
    z_levels: list[float],
    max_girth: float,
) -> None:
    """Raise :class:`GeometryError` if the garment is unbounded or folded (module doc)."""
    used = points[np.unique(cells)]
    if not np.all(np.isfinite(used)):
        raise GeometryError(f"the {kind} mesh has non-finite node coordinates")
    width = float(np.ptp(used[:, :2], axis=0).max())
    if width > 0.5 * max_girth + MARGIN:
        raise GeometryError(
            f"the {kind} surface is {width:.3g} m wide, more than half its largest girth "
            f"({max_girth:.3g} m) allows: the loft overshoots (check the body's landmarks)"
        )
    lo, hi = min(z_levels) - MARGIN, max(z_levels) + MARGIN
    if used[:, 2].min() < lo or used[:, 2].max() > hi:
        raise GeometryError(
            f"the {kind} surface reaches z = {used[:, 2].min():.3g} … {used[:, 2].max():.3g} m, "
            f"outside its levels ({lo + MARGIN:.3g} … {hi - MARGIN:.3g} m)"
        )
    turn = largest_turn(points, cells)
    if turn > MAX_TURN:
        raise GeometryError(
            f"the {kind} surface folds: neighbouring cells turn by {turn:.0f}° "
            f"(> {MAX_TURN:.0f}°); check the body's landmarks or use a finer mesh_size"
        )


#: largest skirt bulge [m] (:func:`skirt_bulge`) a generated dress may have
MAX_BULGE = 0.005


@dataclass
class Fairness:
    """:func:`skirt_bulge`'s answer, lengths in metres.

    ``bulge``: the largest rise of the radius going up (module doc of :func:`skirt_bulge`);
    ``bulge_z`` and ``bulge_angle`` (degrees, from +x towards +y) where it is;
    ``concavity``: the largest depth of a ring inside its convex hull."""

    bulge: float
    bulge_z: float
    bulge_angle: float
    concavity: float


def _ring_radii(
    points: Array, cells: npt.NDArray[np.int64], z: float, axis: Array, angles: Array
) -> tuple[Array, float] | None:
    """The radius about ``axis`` of the surface's horizontal section at ``z`` at ``angles``
    (the outermost crossing per angle, interpolated periodically), and the section's depth
    inside its convex hull; None if the plane misses the surface."""
    from scipy.spatial import ConvexHull

    tri = cells if cells.shape[1] == 3 else np.vstack([cells[:, [0, 1, 2]], cells[:, [0, 2, 3]]])
    d = points[:, 2] - z
    pts = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        i, j = tri[:, a], tri[:, b]
        x = (d[i] < 0) != (d[j] < 0)
        t = d[i[x]] / (d[i[x]] - d[j[x]])
        pts.append(points[i[x], :2] + t[:, None] * (points[j[x], :2] - points[i[x], :2]))
    p = np.vstack(pts) - axis
    if len(p) < 8:
        return None
    th = np.arctan2(p[:, 1], p[:, 0])
    r = np.hypot(p[:, 0], p[:, 1])
    order = np.argsort(th)
    radii = np.interp(angles, th[order], r[order], period=2 * np.pi)
    hull = ConvexHull(p)
    eq = hull.equations  # n·x + c <= 0 inside; depth = least distance to a hull facet
    depth = float(np.max(np.min(-(p @ eq[:, :2].T + eq[:, 2]), axis=1)))
    return radii, depth


def skirt_bulge(
    points: Array,
    cells: npt.NDArray[np.int64],
    z_hem: float,
    z_top: float,
    axis: Array,
    step: float = 0.01,
    bins: int = 72,
) -> Fairness:
    """Fairness of a skirt between its hem ``z_hem`` and ``z_top`` (the waist) [m].

    The surface is cut by horizontal planes ``step`` apart (from 5 mm above the hem to 5 mm
    below ``z_top``); each section's radius r(θ, z) about the vertical line through ``axis``
    (x, y) is taken in ``bins`` polar angle bins. A skirt hangs from the waist over the hips and
    flares to the hem, so at every angle its radius does not grow going up: a **bulge** is a
    radius larger than one lower down at the same angle,

        bulge = max over θ, z of  r(θ, z) − min over z_hem ≤ z' ≤ z of r(θ, z')   [m],

    0 for a fair skirt; limit :data:`MAX_BULGE` (5 mm, a sixth of a 3 cm cell). A body whose
    belly or buttocks reach out further than its hips above the hip level would give the skirt
    a true bulge there, so ``z_top`` should be the waist or lower. ``concavity``: the largest
    depth [m] of a section point inside the section's convex hull (the sections are convex
    curves; a dent or a ring curling inwards shows here).
    """
    angles = -np.pi + (np.arange(bins) + 0.5) * 2 * np.pi / bins
    zs = np.arange(z_hem + 0.005, z_top - 0.005 + 1e-12, step)
    rows, depth, used = [], 0.0, []
    for z in zs:
        got = _ring_radii(points, cells, float(z), np.asarray(axis, float), angles)
        if got is None:
            continue
        rows.append(got[0])
        depth = max(depth, got[1])
        used.append(z)
    if len(rows) < 2:
        raise ValueError(f"the surface has fewer than two sections in z = {z_hem} … {z_top}")
    r = np.array(rows)  # (heights, angles), bottom to top
    rise = r - np.minimum.accumulate(r, axis=0)
    k, j = np.unravel_index(int(np.argmax(rise)), rise.shape)
    return Fairness(float(rise[k, j]), float(used[k]), float(np.degrees(angles[j])), depth)
