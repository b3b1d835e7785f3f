"""Body-scan import: read (trimesh), clean, scale, stand up, segment, find landmarks, tag regions.

Real scans come as quads and n-gons, in several pieces (floor, props, floating specks, eyes,
teeth, clothing helpers), with small holes (armpits, crotch, soles), inconsistent face
orientation, duplicated vertices, in any unit and with any up axis. :func:`load_scan` repairs
what can be repaired without guessing (weld, drop degenerate faces, keep the body piece, fill
small holes, orient outward), detects units and up axis (:mod:`.orientation`), separates torso,
arms, legs and head and finds the landmarks (:mod:`.anatomy`), and raises
:class:`~.errors.ScanError` with the reason otherwise.

Assumed pose: standing, arms clear of the torso (A- or T-pose) or no arms, a full body from the
feet up. After turning upright the body is turned about the vertical to face −y when its width
and its feet say which way it faces (:mod:`.orientation`); otherwise its own front stays where it
was (for a Y-up scan facing +z, the usual OBJ/glTF convention, the front ends at −y).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import numpy.typing as npt

from . import orientation as ori
from . import surface as srf
from .anatomy import Anatomy, analyse
from .body import BodySurface, finish_body
from .errors import ScanError
from .measurements import Measurements
from .scan_read import read_polygons

IArray = npt.NDArray[np.int64]

Array = npt.NDArray[np.float64]


def _pieces(t: IArray, area_of: Array) -> tuple[IArray, dict]:
    """The body piece and a report of the rest (eyes, teeth, clothing helpers, specks).

    Of the pieces with at least half the area of the largest, a closed one wins over one with
    holes, then the larger area: clothing helpers around a body (MakeHuman's tights and skirt)
    are nearly as large but open, and they enclose *more* volume than the body, so volume is
    no criterion.
    """
    labels = srf.components(t)
    area = np.bincount(labels, weights=area_of)
    big = np.flatnonzero(area >= 0.5 * area.max())
    closed = {int(k): not srf.boundary_loops(t[labels == k]) for k in big}
    best = max(big, key=lambda k: (closed[int(k)], area[k]))
    dropped = int(labels.max())
    report = {
        "dropped_pieces": dropped,
        "dropped_area_fraction": float(1.0 - area[best] / area.sum()),
    }
    return t[labels == best], report


def clean_surface(
    vertices: Array,
    triangles: IArray,
    units: str | None = None,
    up: str | None = None,
    max_hole_edges: int = 40,
    scale: float | None = None,
) -> tuple[Array, IArray, dict]:
    """Weld, keep the body piece, fill small holes, orient outward, stand up, scale to metres.

    Everything up to the turn upright is independent of the units (tolerances relative to the
    size). Returns the arrays (floor at z = 0, centred on the area centroid in x and y) and a
    report: units, up, welded vertices, dropped pieces and their share of the area, holes filled.
    """
    report: dict = {}
    extent = float(np.ptp(vertices, axis=0).max())
    if extent <= 0:
        raise ScanError("all vertices coincide", "is this a body scan?")
    n0 = len(vertices)
    v, t = srf.merge_duplicate_vertices(vertices, triangles, tol=1e-6 * extent)
    t = srf.drop_degenerate(t)
    if len(t) == 0:
        raise ScanError("no faces left after removing degenerate ones")
    v, t = srf.compact(v, t)
    report["welded_vertices"] = n0 - len(v)
    t, parts = _pieces(t, srf.areas(v, t))
    report.update(parts)
    v, t = srf.compact(v, t)
    if np.any(srf.edge_valence(t) > 2):
        raise ScanError("non-manifold edges (three or more faces on one edge)", "repair the scan")
    t = srf.orient_consistently(t)
    v, t, filled = srf.fill_holes(v, t, max_hole_edges)
    report["holes_filled"] = filled
    left = srf.boundary_loops(t)
    if left:
        sizes = sorted(len(lp) for lp in left)
        raise ScanError(
            f"surface is not closed: {len(left)} hole(s) with {sizes} boundary edges",
            f"holes up to max_hole_edges={max_hole_edges} edges are filled; repair bigger ones",
        )
    t = srf.orient_outward(v, t)
    up = up or ori.detect_up(v, t)
    v = v @ ori.rotation(up).T
    report["up"] = up
    turn = ori.detect_turn(v, t)  # about the vertical, to face −y (orientation module docstring)
    v = v @ ori.turn_matrix(turn).T
    report["turned"] = turn
    height = float(np.ptp(v[:, 2]))
    k, label = ori.scale_of(units, scale, height)
    v = v * k
    report["units"] = label
    size = extent * k
    if not 0.2 <= size <= 2.6:  # a torso part … a tall adult
        raise ScanError(
            f"the scan is {size:.4g} m across in {label!r}: not a human body",
            "give the units (mm, cm, dm, m, in) or a scale (metres per file unit)",
        )
    report["height"] = float(np.ptp(v[:, 2]))
    v[:, 2] -= v[:, 2].min()
    c = v[t].mean(axis=1)
    w = srf.areas(v, t)
    v[:, :2] -= (w[:, None] * c[:, :2]).sum(axis=0) / w.sum()
    return v, t, report


def load_scan(
    path: str | Path,
    units: str | None = None,
    up: str | None = None,
    max_hole_edges: int = 40,
    remesh: float | None = None,
    scale: float | None = None,
    landmarks: dict[str, float] | None = None,
) -> tuple[BodySurface, dict]:
    """Read, clean, optionally remesh (target size in m), segment, locate landmarks, tag regions.

    Args:
        path: the scan file (formats: :mod:`.scan_read`).
        units: ``mm``, ``cm``, ``dm``, ``m`` or ``in``; None: detected from the height.
        up: the file's up axis (``x``, ``-x``, ``y``, ``-y``, ``z``, ``-z``); None: detected.
        max_hole_edges: holes with up to this many boundary edges are filled.
        remesh: a target triangle size [m] to remesh with gmsh (None: keep the scan's triangles).
        scale: metres per file unit (instead of ``units``).
        landmarks: heights [m above the floor] that replace detected landmark levels.

    Returns the body and a report (units, up, repairs, dropped pieces, landmark heights, torso
    girths, seconds per stage).
    """
    t0 = time.perf_counter()
    v, t = read_polygons(path)
    t1 = time.perf_counter()
    v, t, report = clean_surface(v, t, units, up, max_hole_edges, scale)
    if remesh:
        v, t = remesh_surface(v, t, remesh)
        t = srf.orient_outward(v, t)
    t2 = time.perf_counter()
    try:
        anat = analyse(v, t, landmarks)
    except ScanError as e:
        raise ScanError(f"{path}: {e.reason}", e.hint) from e
    except (ValueError, IndexError) as e:  # an empty range of sections (tests/test_fuzz.py)
        raise ScanError(f"{path}: body landmarks not found ({e})", "is it a standing body?") from e
    t3 = time.perf_counter()
    report["landmarks"] = dict(anat.landmarks)
    report["girths"] = dict(anat.girths)
    report["limbs"] = {n: dict(lb.marks) for n, lb in anat.limbs.items()}
    report["seconds"] = {"read": t1 - t0, "clean": t2 - t1, "anatomy": t3 - t2}
    return segmented_body(v, t, anat), report


def segmented_body(
    vertices: Array, triangles: IArray, anat: Anatomy, measurements: Measurements | None = None
) -> BodySurface:
    """A :class:`BodySurface` from a segmented surface: the anatomy's landmarks, torso tape
    sections, parts (regions on their part), landmark points, arm cuts and limbs (scans and the
    human mannequin, :mod:`.human`, alike)."""
    body = finish_body(vertices, triangles, anat.landmarks, dict(anat.sections), measurements,
                       part=anat.part)  # fmt: skip
    body.points = dict(anat.points)
    body.arm_cut = dict(anat.arm_cut)
    body.limbs = dict(anat.limbs)
    body.limb_problems = dict(anat.limb_problems)
    return body


def remesh_surface(vertices: Array, triangles: npt.NDArray[np.int64], h: float):
    """Remesh a closed triangle surface at size ``h`` with gmsh (classify, reparametrise)."""
    from .gmsh_utils import gmsh_session
    from .mannequin import _surface_arrays

    with gmsh_session(name="remesh") as g:
        s = g.model.addDiscreteEntity(2)
        g.model.mesh.addNodes(2, s, np.arange(1, len(vertices) + 1), vertices.ravel())
        el = np.arange(1, len(triangles) + 1)
        g.model.mesh.addElementsByType(s, 2, el, (triangles + 1).ravel())
        g.model.mesh.classifySurfaces(np.radians(40), True, True, np.pi)
        g.model.mesh.createGeometry()
        g.option.setNumber("Mesh.MeshSizeMax", h)
        g.option.setNumber("Mesh.MeshSizeMin", h / 3)
        g.model.mesh.generate(2)
        return _surface_arrays(g, 1)
