"""Units and up axis of a body scan, detected from its shape (or given), and the turn upright.

* **Up axis.** The vertical axis is the coordinate axis along which the surface *area* is spread
  most (largest area-weighted variance of the triangle centroids). Weighting by area, not by
  vertex, keeps densely meshed heads and hands from pulling it; in an A-pose the arms add little
  to the width, and in a T-pose the arms are a small part of the area, so the length of the body
  still wins although the arm span equals the stature.
* **Up or down.** Near the feet a horizontal section cuts two separate outlines (the feet or
  ankles), near the crown one (the head): the end with more *outer* outlines (not nested inside
  another, larger than 5 % of the biggest one, so eye sockets, ears or nostrils do not count)
  is down. Ties (legs together, a torso only) keep the positive direction; give ``up``.
* **Facing.** Standing upright, a body is wider from side to side than from front to back, and
  its feet point forward: the horizontal axis of largest area-weighted variance is its width
  (a quarter turn when that is y), and the soles (the lowest 3 % of the stature) reach further
  forward than the ankles above them (5–8 %). The body is turned about the vertical, by a
  multiple of 90°, to face −y; without feet to tell the front (the soles less than 1 % of the
  stature ahead of or behind the ankles: a torso, a dress form) it keeps its facing.
* **Units.** A full standing body is 1.0–2.5 m tall; in mm, cm, dm, m and inches these ranges
  do not overlap (inches and centimetres stay apart up to 2.54 × the lower bound), so the
  height along the up axis names the unit. MakeHuman's tallest body is 2.45 m
  (:mod:`.population`): with 2.3 m as the upper bound it was read in inches as 0.97 m. A part
  of a body (a torso only) falls outside all of them and is read as mm / cm / m by size, as
  before; give ``units`` or ``scale`` for anything else.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from . import sections as sec
from . import surface as srf
from .errors import ScanError

Array = npt.NDArray[np.float64]
IArray = npt.NDArray[np.int64]

#: metres per unit
UNITS: dict[str, float] = {"mm": 0.001, "cm": 0.01, "dm": 0.1, "m": 1.0, "in": 0.0254}
#: a full standing adult or child from 1.0 to 2.5 m tall (upper < 2.54 × lower: the ranges
#: in inches and centimetres must not meet)
STATURE_RANGE = (1.0, 2.5)

# proper rotations taking the named up axis to +z (for "y": (x, y, z) -> (x, -z, y), so a Y-up
# model facing +z, the usual OBJ/glTF convention, ends facing -y as the package expects)
ROTATIONS: dict[str, Array] = {
    "z": np.eye(3),
    "-z": np.diag([1.0, -1.0, -1.0]),
    "y": np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]]),
    "-y": np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]]),
    "x": np.array([[0, 0, -1.0], [0, 1.0, 0], [1.0, 0, 0]]),
    "-x": np.array([[0, 0, 1.0], [0, 1.0, 0], [-1.0, 0, 0]]),
}


def vertical_axis(vertices: Array, triangles: IArray) -> int:
    """0, 1 or 2: the axis of largest area-weighted variance of the triangle centroids."""
    c = vertices[triangles].mean(axis=1)
    w = srf.areas(vertices, triangles)
    mean = (w[:, None] * c).sum(axis=0) / w.sum()
    var = (w[:, None] * (c - mean) ** 2).sum(axis=0)
    return int(np.argmax(var))


def outer_outlines(vertices: Array, triangles: IArray, z: float, min_fraction: float = 0.05) -> int:
    """Number of outlines of the section at ``z`` that are not nested in another one and have
    at least ``min_fraction`` of the largest one's area."""
    loops = [p for p in sec.slice_loops(vertices, triangles, z) if len(p) > 2]
    if not loops:
        return 0
    area = np.array([abs(sec.polygon_area(p)) for p in loops])
    big = [i for i in np.argsort(-area) if area[i] >= min_fraction * area.max()]
    outer = [
        i
        for i in big
        if not any(area[j] > area[i] and sec.contains(loops[j], loops[i][:1])[0] for j in big)
    ]
    return len(outer)


def detect_up(vertices: Array, triangles: IArray) -> str:
    """``"z"``, ``"-y"``, … : the up direction by the rules in the module docstring."""
    ax = vertical_axis(vertices, triangles)
    name = "xyz"[ax]
    v = vertices @ ROTATIONS[name].T
    lo, hi = v[:, 2].min(), v[:, 2].max()
    fr = (0.03, 0.05, 0.07)
    n_lo = sum(outer_outlines(v, triangles, lo + f * (hi - lo)) for f in fr)
    n_hi = sum(outer_outlines(v, triangles, hi - f * (hi - lo)) for f in fr)
    return ("-" + name) if n_hi > n_lo else name


def detect_units(height: float) -> str:
    """The unit in which ``height`` (the extent along the up axis) is a plausible stature;
    else, for a part of a body, mm above 250, cm above 2.5, otherwise m."""
    for name, k in UNITS.items():
        if STATURE_RANGE[0] <= height * k <= STATURE_RANGE[1]:
            return name
    return "mm" if height > 250.0 else ("cm" if height > 2.5 else "m")


def scale_of(units: str | None, scale: float | None, height: float) -> tuple[float, str]:
    """Metres per file unit and a label for the report, from ``scale``, ``units`` or detection."""
    if scale is not None:
        if not (np.isfinite(scale) and scale > 0):
            raise ScanError(f"scale must be a positive number, got {scale}")
        return float(scale), f"scale {scale:g}"
    units = units or detect_units(height)
    if units not in UNITS:
        raise ScanError(
            f"unknown units {units!r}", f"use one of {', '.join(UNITS)} or a scale (m per unit)"
        )
    return UNITS[units], units


def rotation(up: str) -> Array:
    """The rotation that takes the ``up`` axis to +z; :class:`ScanError` for an unknown name."""
    if up not in ROTATIONS:
        raise ScanError(f"unknown up axis {up!r}", f"use one of {', '.join(ROTATIONS)}")
    return ROTATIONS[up]


#: the turns about the vertical, counter-clockwise seen from above [degrees]
TURNS = (0, 90, 180, 270)


def turn_matrix(degrees: int) -> Array:
    """The rotation about +z by ``degrees`` (a multiple of 90: exact)."""
    c, s = [(1, 0), (0, 1), (-1, 0), (0, -1)][(degrees // 90) % 4]
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def detect_turn(vertices: Array, triangles: IArray) -> int:
    """The turn of :data:`TURNS` about the vertical that makes an upright body (+z up) face −y
    (module docstring: width axis, then the feet)."""
    c = vertices[triangles].mean(axis=1)
    w = srf.areas(vertices, triangles)
    mean = (w[:, None] * c).sum(axis=0) / w.sum()
    var = (w[:, None] * (c - mean) ** 2).sum(axis=0)
    depth = 0 if var[1] > 1.3 * var[0] else 1  # front to back: y, unless clearly wider in y
    lo, h = c[:, 2].min(), np.ptp(c[:, 2])
    soles = c[:, 2] < lo + 0.03 * h
    ankles = (c[:, 2] > lo + 0.05 * h) & (c[:, 2] < lo + 0.08 * h)
    ahead = 0.0
    if w[soles].sum() > 0 and w[ankles].sum() > 0:
        ahead = (np.average(c[soles, depth], weights=w[soles])
                 - np.average(c[ankles, depth], weights=w[ankles]))  # fmt: skip
    if abs(ahead) < 0.01 * h:  # no feet to tell the front: as it is (a refusal downstream
        return 0  # is better than a body turned the wrong way round)
    if depth == 1:
        return 0 if ahead < 0 else 180
    return 90 if ahead < 0 else 270  # facing −x: a quarter turn counter-clockwise; +x: three
