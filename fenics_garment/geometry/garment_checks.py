"""Sanity checks of a generated garment surface before it becomes a shell mesh.

A loft through badly shaped sections can overshoot (a garment metres wide) or fold back on
itself; either would give a meaningless contact problem, so both are refused with the reason:

* **bounded**: a convex closed curve of perimeter P is at most P/2 wide, so no garment node may
  lie further than half the largest garment girth (plus a margin) from the others
  horizontally, nor outside the levels' height range (plus a margin);
* **no fold**: across every edge shared by two cells, the outward cell normals turn by less
  than ``MAX_TURN`` degrees (a fold turns the surface by about 180°).
"""

from __future__ import annotations

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
