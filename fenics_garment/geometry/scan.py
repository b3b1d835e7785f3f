"""Body-scan import: read (meshio), clean, scale, turn upright, find landmarks, tag regions.

Real scans come as quads and n-gons, in several pieces (floor, props, floating specks), with
small holes (armpits, crotch, soles), inconsistent face orientation, duplicated vertices, in
millimetres or centimetres and with any up axis. :func:`load_scan` repairs what can be repaired
without guessing (weld, drop degenerate faces, keep the largest piece, fill small holes, orient
outward) and raises :class:`~.errors.ScanError` with the reason otherwise.

Assumed pose: standing, arms away from the torso (or no arms), a full body from the feet up
(landmark search uses fractions of the stature). After turning upright the scan's own front
stays where it was; for a Y-up scan facing +z (the usual OBJ convention) the front ends at −y.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import numpy.typing as npt

from . import sections as sec
from . import surface as srf
from .body import BodySurface, finish_body
from .errors import ScanError

Array = npt.NDArray[np.float64]
_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}
# proper rotations taking the named up axis to +z (for "y": (x, y, z) -> (x, -z, y))
_UP = {
    "z": np.eye(3),
    "-z": np.diag([1.0, -1.0, -1.0]),
    "y": np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]]),
    "-y": np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]]),
    "x": np.array([[0, 0, -1.0], [0, 1.0, 0], [1.0, 0, 0]]),
    "-x": np.array([[0, 0, 1.0], [0, 1.0, 0], [-1.0, 0, 0]]),
}


def read_polygons(path: str | Path) -> tuple[Array, npt.NDArray[np.int64]]:
    """Vertices and triangles (quads and n-gons fan-split) of any meshio-readable surface."""
    import meshio

    p = Path(path)
    if not p.is_file():
        raise ScanError(f"{p}: no such file", "check the path (relative to the working directory)")
    if p.suffix.lower() == ".ply":
        with p.open("rb") as f:  # meshio's PLY reader loops forever on a header cut short
            if b"end_header" not in f.read(1 << 16):
                raise ScanError(f"{p}: PLY header without end_header", "is the file truncated?")
    try:
        m = meshio.read(p)
    # meshio raises ReadError, ValueError, IndexError … on broken files; its STL reader even
    # calls sys.exit(1) on some (found by tests/test_fuzz.py)
    except (Exception, SystemExit) as e:
        raise ScanError(
            f"{p}: not a readable mesh ({type(e).__name__}: {e})",
            "expected OBJ, PLY, STL, MSH or another meshio format; is the file truncated?",
        ) from e
    blocks = [c.data for c in m.cells if c.dim == 2 and len(c.data)]
    if not blocks or len(m.points) == 0:
        raise ScanError(f"{p}: no surface cells", "expected triangles, quads or polygons")
    v = np.asarray(m.points[:, :3], dtype=np.float64)
    if not np.all(np.isfinite(v)):
        raise ScanError(f"{p}: {int((~np.isfinite(v)).any(axis=1).sum())} vertices are NaN/Inf")
    t = srf.triangulate(blocks)
    if t.min() < 0 or t.max() >= len(v):
        raise ScanError(f"{p}: faces refer to vertices that do not exist (file corrupted?)")
    return v, t


def detect_units(extent: float) -> str:
    """A human from 0.25 m (a torso part) to 2.5 m tall: extents > 250 are mm, > 2.5 are cm."""
    return "mm" if extent > 250.0 else ("cm" if extent > 2.5 else "m")


def detect_up(vertices: Array, triangles: npt.NDArray[np.int64]) -> str:
    """The longest axis is vertical; the end whose slice near the tip has fewer loops is up
    (one neck/head vs two ankles). Ties keep the positive direction."""
    ext = np.ptp(vertices, axis=0)
    ax = int(np.argmax(ext))
    name = "xyz"[ax]
    lo, hi = vertices[:, ax].min(), vertices[:, ax].max()
    rot = _UP[name]
    v = vertices @ rot.T
    n_lo = len(sec.slice_loops(v, triangles, lo + 0.08 * (hi - lo)))
    n_hi = len(sec.slice_loops(v, triangles, hi - 0.08 * (hi - lo)))
    return ("-" + name) if n_hi > n_lo else name


def clean_surface(
    vertices: Array,
    triangles: npt.NDArray[np.int64],
    units: str | None = None,
    up: str | None = None,
    max_hole_edges: int = 40,
) -> tuple[Array, npt.NDArray[np.int64], dict]:
    """Scale to metres, weld, keep the largest piece, fill small holes, orient outward, stand up.

    Returns the arrays and a report (units, up, welded vertices, dropped pieces, holes filled).
    """
    report: dict = {}
    extent = float(np.ptp(vertices, axis=0).max())
    units = units or detect_units(extent)
    if units not in _UNITS:
        raise ScanError(f"unknown units {units!r}", "use 'm', 'cm' or 'mm'")
    v = vertices * _UNITS[units]
    report["units"] = units
    size = extent * _UNITS[units]
    if not 0.2 <= size <= 2.6:  # a torso part … a tall adult
        raise ScanError(
            f"the scan is {size:.4g} m across in {units!r}: not a human body",
            "give the units explicitly (units='mm', 'cm' or 'm')",
        )
    n0 = len(v)
    v, t = srf.merge_duplicate_vertices(v, triangles, tol=1e-6 * extent * _UNITS[units])
    t = srf.drop_degenerate(t)
    v, t = srf._compact(v, t)
    report["welded_vertices"] = n0 - len(v)
    if np.any(srf.edge_valence(t) > 2):
        raise ScanError("non-manifold edges (three or more faces on one edge)", "repair the scan")
    labels = srf.components(t)
    if labels.max() > 0:
        area = np.bincount(labels, weights=srf.areas(v, t))
        keep = int(np.argmax(area))
        report["dropped_pieces"] = int(labels.max())
        t = t[labels == keep]
        v, t = srf._compact(v, t)
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
    up = up or detect_up(v, t)
    report["up"] = up
    v = v @ _UP[up].T
    v[:, 2] -= v[:, 2].min()
    xy = v[:, :2].mean(axis=0)
    v[:, :2] -= xy
    return v, t, report


def _torso_loop(v, t, z, centre) -> Array | None:
    loops = [p for p in sec.slice_loops(v, t, z) if len(p) > 2]
    inside = [p for p in loops if _contains(p, centre)]
    return max(inside, key=lambda p: abs(sec.polygon_area(p))) if inside else None


def _contains(p: Array, c: Array) -> bool:
    return bool(sec.contains(p, np.asarray(c))[0])


def locate_landmarks(vertices: Array, triangles: npt.NDArray[np.int64]) -> dict[str, float]:
    """Landmark heights of an upright full body (feet at z = 0): waist = narrowest torso section,
    hip = widest below it, bust = widest above it, knee = narrowest leg section, etc."""
    v, t = vertices, triangles
    H = float(v[:, 2].max())
    c = np.zeros(2)
    zs = np.linspace(0.30 * H, 0.98 * H, 137)
    torso = {z: _torso_loop(v, t, z, c) for z in zs}
    ok = [z for z in zs if torso[z] is not None]
    if not ok:
        raise ScanError("no torso section contains the body axis", "is the scan a standing body?")
    crotch = ok[0]
    g = {z: sec.tape_girth(torso[z]) for z in ok}

    def arg(fn, lo, hi):
        cand = [z for z in ok if lo <= z <= hi]
        if not cand:
            raise ScanError(f"no torso section between {lo:.2f} and {hi:.2f} m")
        return fn(cand, key=g.get)

    waist = arg(min, crotch + 0.12 * H, 0.72 * H)
    hip = arg(max, crotch, waist)
    bust = arg(max, waist + 0.04 * H, 0.78 * H)
    underbust = arg(min, waist + 0.02 * H, bust - 0.01 * H)
    top = max(ok)
    neck = arg(min, bust + 0.08 * H, top - 0.01 * H)
    width = {z: float(np.ptp(torso[z][:, 0])) for z in ok}
    shoulder = max((z for z in ok if bust < z < neck), key=width.get)
    marks = {
        "crotch": crotch,
        "hip": hip,
        "abdomen": 0.5 * (hip + waist),
        "waist": waist,
        "underbust": underbust,
        "bust": bust,
        "upper_chest": bust + 0.4 * (shoulder - bust),
        "shoulder": shoulder,
        "neck_base": shoulder + 0.6 * (neck - shoulder),
        "neck": neck,
    }
    # legs: slices below the crotch, the loop on the +x side
    zl = np.linspace(0.02 * H, crotch - 0.01 * H, 90)
    leg = {}
    for z in zl:
        loops = [p for p in sec.slice_loops(v, t, z) if p[:, 0].mean() > 0 and len(p) > 2]
        if loops:
            leg[z] = sec.tape_girth(max(loops, key=lambda p: abs(sec.polygon_area(p))))
    zl = [z for z in zl if z in leg]
    knee = min((z for z in zl if 0.22 * H <= z <= 0.34 * H), key=leg.get)
    calf = max((z for z in zl if 0.12 * H <= z < knee - 0.03 * H), key=leg.get)
    ankle = min((z for z in zl if 0.03 * H <= z < calf - 0.03 * H), key=leg.get)
    marks.update(ankle=ankle, calf=calf, knee=knee, thigh=crotch - 0.035 * H)
    return marks


def load_scan(
    path: str | Path,
    units: str | None = None,
    up: str | None = None,
    max_hole_edges: int = 40,
    remesh: float | None = None,
) -> tuple[BodySurface, dict]:
    """Read, clean, optionally remesh (target size in m), locate landmarks and tag regions."""
    v, t = read_polygons(path)
    v, t, report = clean_surface(v, t, units, up, max_hole_edges)
    if remesh:
        v, t = remesh_surface(v, t, remesh)
        t = srf.orient_outward(v, t)
    try:
        marks = locate_landmarks(v, t)
    except ScanError:
        raise
    except ValueError as e:  # an empty range of sections (found by tests/test_fuzz.py)
        raise ScanError(f"{path}: body landmarks not found ({e})", "is it a standing body?") from e
    body = BodySurface(v, t, np.zeros(len(t), np.int32), {}, marks)
    secs = {}
    for k in marks:
        try:
            secs[k] = body.section(k)[1]
        except (ValueError, KeyError):
            continue
    return finish_body(v, t, marks, secs), report


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
