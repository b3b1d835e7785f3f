"""A sewing pattern: flat panels bounded by curves, seams joining edge ranges, grain lines.

All lengths are metres once a pattern is read (:data:`UNITS` converts the file's unit). A
panel lives in its own plane with coordinates (x, y); its outline is a closed chain of edges,
each a :class:`Line`, :class:`Arc`, :class:`Bezier` or :class:`Polyline` in the panel's
coordinates, ``edges[i].end == edges[i + 1].start`` and the last ending where the first starts.
A :class:`Seam` sews a range of one edge to a range of another (of the same panel for a dart);
``reversed`` says that the two ranges run against each other (the usual case for two panels
laid out side by side, both outlines counter-clockwise).

The readers (:mod:`.io`, :mod:`.garmentcode`, :mod:`.dxf`) return every outline
counter-clockwise, so that a panel's local +z (``placement.rotation @ e_z``) is the right side
of the fabric, the garment's outside; :mod:`.validate` refuses malformed patterns. The mesher
(:mod:`.mesh`) samples the edges at equal arc length so that both sides of a seam get the same
nodes. Nothing here knows about gmsh or DOLFINx.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]

#: metres per unit of a pattern file
UNITS: dict[str, float] = {"mm": 1e-3, "cm": 1e-2, "m": 1.0}


class PatternError(ValueError):
    """A malformed pattern; the message is one line naming the panel and the edge."""


def _pt(p) -> Array:
    a = np.asarray(p, dtype=np.float64).reshape(2)
    return a


def _arclength_table(curve, n: int = 400) -> tuple[Array, Array]:
    t = np.linspace(0.0, 1.0, n + 1)
    p = curve.point(t)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    return t, s


class _Curve:
    """Shared behaviour: arc length, equal-arc-length sampling, ranges."""

    start: Array
    end: Array

    def point(self, t) -> Array:  # pragma: no cover - every subclass defines it
        raise NotImplementedError

    @cached_property
    def _table(self) -> tuple[Array, Array]:
        return _arclength_table(self)

    @property
    def length(self) -> float:
        return float(self._table[1][-1])

    def parameter_at(self, fraction) -> Array:
        """The curve parameter t at a fraction (0 … 1) of the arc length."""
        t, s = self._table
        return np.interp(np.asarray(fraction, dtype=float) * s[-1], s, t)

    def sample(self, n: int, f0: float = 0.0, f1: float = 1.0) -> Array:
        """n + 1 points at equal arc length between the arc-length fractions f0 and f1."""
        return self.point(self.parameter_at(np.linspace(f0, f1, n + 1)))


@dataclass(frozen=True, eq=False)
class Line(_Curve):
    start: Array
    end: Array

    def __post_init__(self) -> None:
        object.__setattr__(self, "start", _pt(self.start))
        object.__setattr__(self, "end", _pt(self.end))

    def point(self, t) -> Array:
        t = np.atleast_1d(np.asarray(t, dtype=float))[:, None]
        return (1 - t) * self.start + t * self.end


@dataclass(frozen=True, eq=False)
class Arc(_Curve):
    """A circular arc from ``start`` to ``end`` through the point ``through``."""

    start: Array
    end: Array
    through: Array

    def __post_init__(self) -> None:
        for k in ("start", "end", "through"):
            object.__setattr__(self, k, _pt(getattr(self, k)))

    @cached_property
    def circle(self) -> tuple[Array, float, float, float]:
        """Centre, radius, start angle and signed sweep angle."""
        a, b, c = self.start, self.through, self.end
        d = 2 * (a[0] * (b[1] - c[1]) + b[0] * (c[1] - a[1]) + c[0] * (a[1] - b[1]))
        if abs(d) < 1e-14 * max(1.0, np.abs([a, b, c]).max()) ** 2:
            raise PatternError("an arc's three points are on a line")
        sa, sb, sc = a @ a, b @ b, c @ c
        centre = np.array([
            sa * (b[1] - c[1]) + sb * (c[1] - a[1]) + sc * (a[1] - b[1]),
            sa * (c[0] - b[0]) + sb * (a[0] - c[0]) + sc * (b[0] - a[0]),
        ]) / d  # fmt: skip
        r = float(np.linalg.norm(a - centre))

        def ang(p):
            return np.arctan2(p[1] - centre[1], p[0] - centre[0])

        a0, am, a1 = ang(a), ang(b), ang(c)
        ccw = (a1 - a0) % (2 * np.pi)
        sweep = ccw if (am - a0) % (2 * np.pi) < ccw else ccw - 2 * np.pi
        return centre, r, float(a0), float(sweep)

    def point(self, t) -> Array:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        centre, r, a0, sweep = self.circle
        ang = a0 + t * sweep
        return centre + r * np.stack([np.cos(ang), np.sin(ang)], axis=1)

    @property
    def length(self) -> float:
        return self.circle[1] * abs(self.circle[3])


@dataclass(frozen=True, eq=False)
class Bezier(_Curve):
    """A quadratic (one control point) or cubic (two) Bézier curve."""

    start: Array
    end: Array
    controls: tuple

    def __post_init__(self) -> None:
        object.__setattr__(self, "start", _pt(self.start))
        object.__setattr__(self, "end", _pt(self.end))
        object.__setattr__(self, "controls", tuple(_pt(c) for c in self.controls))
        if len(self.controls) not in (1, 2):
            n = len(self.controls)
            raise PatternError(f"a Bézier edge needs 1 or 2 control points, got {n}")

    def point(self, t) -> Array:
        t = np.atleast_1d(np.asarray(t, dtype=float))[:, None]
        P = [self.start, *self.controls, self.end]
        n = len(P) - 1
        from math import comb

        return sum(comb(n, k) * t**k * (1 - t) ** (n - k) * P[k] for k in range(n + 1))


@dataclass(frozen=True, eq=False)
class Polyline(_Curve):
    """A digitised curve (DXF outlines): straight pieces through ``points``."""

    points: Array

    def __post_init__(self) -> None:
        p = np.asarray(self.points, dtype=np.float64).reshape(-1, 2)
        if len(p) < 2:
            raise PatternError("a polyline edge needs at least 2 points")
        object.__setattr__(self, "points", p)

    @property
    def start(self) -> Array:  # type: ignore[override]
        return self.points[0]

    @property
    def end(self) -> Array:  # type: ignore[override]
        return self.points[-1]

    @property
    def length(self) -> float:
        """Exact: the sum of the pieces (the sampled table would cut the corners)."""
        return float(np.linalg.norm(np.diff(self.points, axis=0), axis=1).sum())

    def point(self, t) -> Array:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        p = self.points
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        u = t * s[-1]
        return np.stack([np.interp(u, s, p[:, 0]), np.interp(u, s, p[:, 1])], axis=1)


Curve = Line | Arc | Bezier | Polyline


def arc_from_radius(start, end, radius: float, *, large: bool = False, ccw: bool = True) -> Arc:
    """The arc from ``start`` to ``end`` of the given radius, as SVG's elliptical-arc flags.

    ``large``: the arc sweeps more than 180°; ``ccw``: it turns counter-clockwise (y up), i.e.
    it bulges to the right of the chord start → end: outwards on a counter-clockwise outline.
    A radius below half the chord is raised to it (a half circle), as SVG does; the caller
    refuses it first where a file must be exact.
    """
    a, b = _pt(start), _pt(end)
    chord = b - a
    c = float(np.linalg.norm(chord))
    if c == 0.0:
        raise PatternError("an arc's two ends are the same point")
    r = max(float(radius), c / 2)
    u = chord / c
    n = np.array([-u[1], u[0]])  # left of start → end
    d = np.sqrt(max(r * r - c * c / 4, 0.0))
    centre = (a + b) / 2 + (d if ccw != large else -d) * n
    through = centre - r * n if ccw else centre + r * n
    return Arc(a, b, through)


def reverse_curve(curve: Curve) -> Curve:
    """The same curve run from its end to its start."""
    if isinstance(curve, Line):
        return Line(curve.end, curve.start)
    if isinstance(curve, Arc):
        return Arc(curve.end, curve.start, curve.through)
    if isinstance(curve, Bezier):
        return Bezier(curve.end, curve.start, tuple(reversed(curve.controls)))
    return Polyline(curve.points[::-1].copy())


def transform_curve(curve: Curve, matrix, offset=(0.0, 0.0)) -> Curve:
    """The curve under the map p ↦ matrix @ p + offset (a similarity for an arc)."""
    m, o = np.asarray(matrix, float).reshape(2, 2), _pt(offset)

    def f(p):
        return np.asarray(p, float) @ m.T + o

    if isinstance(curve, Line):
        return Line(f(curve.start), f(curve.end))
    if isinstance(curve, Arc):
        return Arc(f(curve.start), f(curve.end), f(curve.through))
    if isinstance(curve, Bezier):
        return Bezier(f(curve.start), f(curve.end), tuple(f(c) for c in curve.controls))
    return Polyline(f(curve.points))


def rotation_xyz(degrees) -> Array:
    """The rotation matrix of intrinsic X-Y-Z Euler angles in degrees, R = Rx(a) Ry(b) Rz(c)
    (scipy's ``Rotation.from_euler("XYZ", ...)``, as GarmentCode's panels write theirs)."""
    a, b, c = np.radians(np.asarray(degrees, float).reshape(3))
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    rz = np.array([[cc, -sc, 0], [sc, cc, 0], [0, 0, 1]])
    return rx @ ry @ rz


def euler_xyz(rotation) -> Array:
    """The intrinsic X-Y-Z Euler angles in degrees of a rotation matrix (inverse of
    :func:`rotation_xyz`; at gimbal lock, b = ±90°, the Z angle is set to 0)."""
    r = np.asarray(rotation, float).reshape(3, 3)
    b = np.arcsin(np.clip(r[0, 2], -1.0, 1.0))
    if abs(r[0, 2]) < 1 - 1e-12:
        a = np.arctan2(-r[1, 2], r[2, 2])
        c = np.arctan2(-r[0, 1], r[0, 0])
    else:
        a, c = np.arctan2(r[2, 1], r[1, 1]), 0.0
    return np.degrees([a, b, c])


@dataclass(frozen=True, eq=False)
class Edge:
    """One edge of a panel's outline, with an optional name (``"side_left"``, ``"hem"``…)."""

    curve: Curve
    name: str = ""

    @property
    def length(self) -> float:
        return self.curve.length


@dataclass(frozen=True, eq=False)
class Placement:
    """Where a panel starts around the body: its plane point (x, y, 0) goes to
    ``rotation @ (x, y, 0) + translation`` (metres), before the automatic wrap."""

    translation: Array = field(default_factory=lambda: np.zeros(3))
    rotation: Array = field(default_factory=lambda: np.eye(3))

    def __post_init__(self) -> None:
        object.__setattr__(self, "translation", np.asarray(self.translation, float).reshape(3))
        object.__setattr__(self, "rotation", np.asarray(self.rotation, float).reshape(3, 3))

    def apply(self, xy: Array) -> Array:
        xy = np.asarray(xy, float)
        p = np.column_stack([xy, np.zeros(len(xy))])
        return p @ self.rotation.T + self.translation


#: the axes a panel can be wrapped around (:class:`Wrap`); "none" leaves it flat as placed
WRAP_AXES = ("torso", "arm_left", "arm_right", "leg_left", "leg_right", "none")


@dataclass(frozen=True)
class Wrap:
    """How the automatic placement (:func:`.mesh.place`) bends a panel around the body.

    The panel is drawn as seen from outside the garment with its y axis up; it is wrapped
    isometrically (arc length kept) around a vertical generalised cylinder about ``axis``
    (the torso, or a limb of a scan: its own straightened axis). ``azimuth`` [degrees, from
    the body's left (+x) counter-clockwise seen from above: front −90, back 90] is where the
    panel's centre goes (None: from its name, ``front``/``back``/``left``/``right``, or laid
    around in pattern order); ``top`` is the height [m] of the panel's top or a landmark name
    (None: the neck base on a torso, else the panel centred on the body's levels).
    """

    axis: str = "torso"
    azimuth: float | None = None
    top: float | str | None = None

    def __post_init__(self) -> None:
        if self.axis not in WRAP_AXES:
            raise PatternError(f"wrap axis {self.axis!r} is not one of {WRAP_AXES}")


@dataclass(frozen=True, eq=False)
class Panel:
    """A flat piece of fabric: a closed outline, its grain (warp) direction in the panel's
    plane, its fabric name (None: the scene's fabric), an optional placement and an optional
    wrap spec (:class:`Wrap`; None: the defaults)."""

    name: str
    edges: tuple[Edge, ...]
    grain: Array
    fabric: str | None = None
    placement: Placement | None = None
    wrap: Wrap | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "edges", tuple(self.edges))
        g = np.asarray(self.grain, float).reshape(2)
        if not np.all(np.isfinite(g)) or np.linalg.norm(g) == 0:
            raise PatternError(f"panel {self.name!r}: the grain line has no direction")
        object.__setattr__(self, "grain", g / np.linalg.norm(g))

    def edge_index(self, key: int | str) -> int:
        """The index of an edge given by index or name."""
        if isinstance(key, (int, np.integer)):
            if not 0 <= key < len(self.edges):
                raise PatternError(
                    f"panel {self.name!r}: no edge {key} (it has {len(self.edges)} edges)"
                )
            return int(key)
        for i, e in enumerate(self.edges):
            if e.name == key:
                return i
        names = [e.name for e in self.edges if e.name]
        raise PatternError(f"panel {self.name!r}: no edge named {key!r} (edges: {names})")

    def outline(self, spacing: float) -> Array:
        """The closed outline sampled at about ``spacing`` (last point not repeated)."""
        parts = [e.curve.sample(max(1, int(np.ceil(e.length / spacing))))[:-1] for e in self.edges]
        return np.concatenate(parts)

    @property
    def area(self) -> float:
        p = self.outline(min(e.length for e in self.edges) / 8)
        return 0.5 * float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))


@dataclass(frozen=True)
class EdgeRange:
    """The arc-length fractions [f0, f1] of edge ``edge`` of panel ``panel`` (0 … 1: whole)."""

    panel: str
    edge: int
    f0: float = 0.0
    f1: float = 1.0


@dataclass(frozen=True)
class Seam:
    """Two edge ranges sewn together; ``reversed``: a's f0 meets b's f1 (and a's f1 b's f0).

    ``kind`` is ``"seam"`` or ``"dart"`` (both sides on one panel); ``name`` names the seam in
    the mesh's edge tags (``side_seam_left``…), empty for a generated name.
    """

    a: EdgeRange
    b: EdgeRange
    reversed: bool = True
    name: str = ""
    kind: str = "seam"


@dataclass(frozen=True, eq=False)
class Pattern:
    """Panels by name and the seams that join them. ``source`` is the file it was read from."""

    name: str
    panels: dict[str, Panel]
    seams: tuple[Seam, ...] = ()
    source: str = ""

    def panel(self, name: str) -> Panel:
        if name not in self.panels:
            raise PatternError(f"{self.name}: no panel {name!r} (panels: {list(self.panels)})")
        return self.panels[name]

    def range_length(self, r: EdgeRange) -> float:
        p = self.panel(r.panel)
        return p.edges[p.edge_index(r.edge)].length * abs(r.f1 - r.f0)

    def seam_name(self, i: int) -> str:
        s = self.seams[i]
        return s.name or f"{s.kind}_{i}"
