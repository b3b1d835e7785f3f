"""Limbs from geometry: a centreline through each arm and leg, its own sections and joints.

A limb of a segmented body (:data:`~.anatomy.PARTS`: ``arm_left`` … ``leg_right``) is read along
its own axis, which in an A-pose is neither vertical nor straight (MakeHuman's base mesh bends
its arms 47° at the elbow):

1. **Curve skeleton**: the geodesic distance over the limb's surface from its root (the
   vertices it shares with the torso) has level sets that ring the limb; the centroids of the
   rings (length weighted) form a first centreline (a level-set / Reeb-graph skeleton).
2. **Perpendicular sections**: the centreline is smoothed, resampled every ``STATION`` metres
   and given a twist-free (parallel-transported) section frame; the limb's own triangles are
   cut by the plane through each station perpendicular to the local tangent, the closed loop
   around the station is the limb's section (its tape girth, ISO 8559-1), and the section's
   centroid moves the station. Two rounds of this converge (the stations move < 1 mm).
3. **Joints**, as arc lengths ``s`` from the root:

   * elbow: the sharpest bend of the centreline (angle between chords ``BEND_CHORD`` behind
     and ahead) between 25 and 75 % of the way from the root to the wrist;
   * knee, calf: the stations at the heights found on the upright body's horizontal sections
     (``anatomy.leg_levels``: the kneecap, the widest girth under it); the centreline's own
     sharpest bend put the knee 5–11.6 cm under MakeHuman's knee loop on 8 of its 37
     population bodies (the calf's bulge bends it as much as the knee);
   * wrist, ankle: the narrowest section before the hand (foot) widens — the minimum girth in
     the distal half of the arm (45–85 % of the leg): ISO 8559-1 measures wrist and ankle
     girths at their narrowest, just above the wrist bones / malleoli;
   * forearm: half-way between elbow and wrist (the parametric arm's convention, 12 of 24 cm);
   * upper arm, thigh: ``ROOT_CLEARANCE`` × stature beyond the first station from which every
     section is the limb's own closed loop (clear of the torso; the thigh of the horizontal
     analysis is 3.5 % of the stature under the crotch too).

A :class:`Limb` is also a *straightened* body for the garment code: its landmarks are
``z' = length − s`` (growing towards the root, so a sleeve's wrist is low as on the parametric
arm), :meth:`Limb.section` gives the section in the station's frame, and :meth:`Limb.to_world`
maps a garment built in those coordinates back onto the limb (an isometry in each section
plane, so girths are kept).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from scipy.interpolate import CubicSpline
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from . import sections as sec
from .errors import ScanError

Array = npt.NDArray[np.float64]
IArray = npt.NDArray[np.int64]

#: spacing [m] of the centreline stations where sections are cut
STATION = 0.01
#: spacing [m] of the geodesic rings of the first centreline
RING_STEP = 0.01
#: half-length [m] of the chords whose angle measures the centreline's bend
BEND_CHORD = 0.08
#: upper arm and thigh levels: this fraction of the stature beyond the limb's free root
ROOT_CLEARANCE = 0.035
#: spacing [m] of the fine frame samples used to map garments to the limb
FINE = 0.002
#: Fourier harmonics kept in a limb's level sections (:func:`smooth_section`)
SECTION_HARMONICS = 12
#: the knee joint's height over the stature: 0.285 (Drillis & Contini 1966, the segment
#: proportions of D. A. Winter, *Biomechanics and Motor Control of Human Movement*, 4th ed.,
#: Wiley 2009, fig. 4.1); MakeHuman's rig knee lies at 0.268 of its stature, the human
#: mannequin's is built at 0.285 (measurements.Measurements.knee_height)
KNEE_HEIGHT = 0.285
#: the landmark levels of each limb kind, tip to root
ARM_MARKS = ("wrist", "forearm", "elbow", "upper_arm")
LEG_MARKS = ("ankle", "calf", "knee", "thigh")


@dataclass
class Limb:
    """One limb's centreline, section frames, girth profile and joints.

    Attributes:
        name: ``arm_left`` … ``leg_right``.
        s: (n,) arc length of the stations from the root [m].
        centre: (n, 3) centreline points; ``tangent`` (n, 3) unit, root to tip.
        e1, e2: (n, 3) section frame: (e1, e2, −tangent) is right-handed, e2 close to +y.
        girth: (n,) tape girth of each station's own section (NaN where it has none).
        marks: joint and level name -> arc length s from the root [m].
        sections: level name -> (k, 2) tape section in its station's (e1, e2) frame.
    """

    name: str
    s: Array
    centre: Array
    tangent: Array
    e1: Array
    e2: Array
    girth: Array
    marks: dict[str, float]
    sections: dict[str, Array] = field(default_factory=dict)
    #: the body's vertices and the limb's own triangles, for sections anywhere (section_at)
    vertices: Array | None = field(default=None, repr=False)
    triangles: IArray | None = field(default=None, repr=False)

    @property
    def length(self) -> float:
        return float(self.s[-1])

    def point(self, name: str) -> Array:
        """The centreline point of a landmark (``elbow``, ``wrist``, ``knee``, ``ankle`` …)."""
        return self.frame_at(self.marks[name])[0]

    def frame_at(self, s: float | Array) -> tuple[Array, Array, Array, Array]:
        """Centre, tangent, e1, e2 at arc length(s) ``s`` (linear between stations)."""
        s = np.atleast_1d(np.asarray(s, dtype=float))
        out = [np.column_stack([np.interp(s, self.s, a[:, i]) for i in range(3)])
               for a in (self.centre, self.tangent, self.e1, self.e2)]  # fmt: skip
        c, t, e1, e2 = out
        t /= np.linalg.norm(t, axis=1)[:, None]
        e2 -= np.einsum("ij,ij->i", e2, t)[:, None] * t
        e2 /= np.linalg.norm(e2, axis=1)[:, None]
        e1 = np.cross(e2, -t)
        return c, t, e1, e2

    # -- the limb as a straightened body for the garment code --------------------------------
    @property
    def landmarks(self) -> dict[str, float]:
        """Level name -> z' = length − s (grows towards the root)."""
        return {k: self.length - s for k, s in self.marks.items()}

    def section(self, level: str) -> tuple[float, Array]:
        """(z', tape section) of a level, as :meth:`.body.BodySurface.section` (``_left`` /
        ``_right`` suffixes ignored: a limb has one side)."""
        base = level.removesuffix("_left").removesuffix("_right")
        if base not in self.sections:
            from .errors import MissingRegion

            raise MissingRegion(level, tuple(self.sections))
        return self.landmarks[base], self.sections[base]

    def section_at(self, z: float) -> Array | None:
        """The limb's own smoothed tape section at z' = ``z`` in its station's frame (as the
        levels' sections), or None where the plane meets more than the limb."""
        if self.vertices is None or self.triangles is None:
            return None
        c, t, e1, e2 = (x[0] for x in self.frame_at(self.length - z))
        p = own_section(self.vertices, self.triangles, c, t, e1, e2)
        return None if p is None else smooth_section(sec.convex_hull(p))

    def to_world(self, x: Array) -> Array:
        """Straightened coordinates (x', y', z') -> points on the limb: C(s) + x' e1 + y' e2."""
        x = np.asarray(x, dtype=float)
        c, _, e1, e2 = self.frame_at(self.length - x[:, 2])
        return c + x[:, :1] * e1 + x[:, 1:2] * e2

    def axis_at(self, x: Array) -> Array:
        """The limb's unit axis (tangent towards the root) at straightened points ``x``."""
        return -self.frame_at(self.length - np.asarray(x)[:, 2])[1]

    def axial(self, points: Array) -> Array:
        """z' of world points: their nearest centreline point's, to ``FINE`` metres."""
        ss = np.arange(0.0, self.length + FINE, FINE)
        c = self.frame_at(ss)[0]
        _, i = cKDTree(c).query(np.asarray(points))
        return self.length - ss[i]


# ---------------------------------------------------------------------------------------------
# Curve skeleton
# ---------------------------------------------------------------------------------------------


def _geodesic_from_root(v: Array, t: IArray, mine: npt.NDArray[np.bool_]) -> Array:
    """Geodesic (edge-path) distance over the limb's triangles from the vertices it shares with
    the rest of the body; inf off the limb."""
    lt = t[mine]
    root = np.intersect1d(np.unique(lt), np.unique(t[~mine]))
    if not len(root):
        raise ScanError("a limb is not attached to the body")
    e = np.concatenate([lt[:, [0, 1]], lt[:, [1, 2]], lt[:, [2, 0]]])
    w = np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1)
    g = coo_matrix((w, (e[:, 0], e[:, 1])), shape=(len(v), len(v))).tocsr()
    return dijkstra(g, directed=False, indices=root, min_only=True)


def _ring_centroid(v: Array, lt: IArray, f: Array, level: float) -> Array | None:
    """Length-weighted centroid of the level set f = level on the triangles ``lt``."""
    fa = f[lt]
    above = fa > level
    cut = above.any(axis=1) & ~above.all(axis=1)
    tri, fa, above = lt[cut], fa[cut], above[cut]
    if not len(tri):
        return None
    ends = []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        crossed = above[:, i] != above[:, j]
        df = np.where(crossed, fa[:, j] - fa[:, i], 1.0)  # uncrossed edges: no division
        s = np.where(crossed, (level - fa[:, i]) / df, 0.0)
        p = v[tri[:, i]] + s[:, None] * (v[tri[:, j]] - v[tri[:, i]])
        ends.append(np.where(crossed[:, None], p, np.nan))
    ends_a = np.stack(ends, axis=1)  # (m, 3 edges, 3): two crossed edges per triangle
    ok = ~np.isnan(ends_a[..., 0])
    two = ok.sum(axis=1) == 2
    pts = ends_a[two][ok[two]].reshape(-1, 2, 3)
    ln = np.linalg.norm(pts[:, 1] - pts[:, 0], axis=1)
    if ln.sum() <= 0:
        return None
    return (ln[:, None] * pts.mean(axis=1)).sum(axis=0) / ln.sum()


def _rings(v: Array, t: IArray, mine: npt.NDArray[np.bool_]) -> Array:
    """First centreline: the centroids of the geodesic rings, root to tip."""
    f = _geodesic_from_root(v, t, mine)
    top = float(np.max(f[np.isfinite(f)]))
    lt = t[mine]
    pts = [_ring_centroid(v, lt, f, lv) for lv in np.arange(RING_STEP, top, RING_STEP)]
    pts = [p for p in pts if p is not None]
    if len(pts) < 8:
        raise ScanError("a limb is too short to follow (fewer than 8 rings of 1 cm)")
    return np.array(pts)


def _resample(c: Array, ds: float) -> tuple[Array, Array]:
    """Arc lengths and points every ``ds`` along a polyline (smoothed by a cubic spline)."""
    k = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(c, axis=0), axis=1))])
    keep = np.concatenate([[True], np.diff(k) > 1e-9])
    spline = CubicSpline(k[keep], c[keep], bc_type="natural")
    s = np.arange(0.0, k[-1] + 1e-12, ds)
    return s, spline(s)


def _smooth(c: Array, half: int = 2) -> Array:
    """Moving average over 2·half + 1 points (ends kept)."""
    out = c.copy()
    for i in range(1, len(c) - 1):
        a, b = max(0, i - half), min(len(c), i + half + 1)
        out[i] = c[a:b].mean(axis=0)
    return out


def _frames(c: Array) -> tuple[Array, Array, Array]:
    """Unit tangents and a parallel-transported (twist-free) frame e1, e2 (e2 starts at +y)."""
    t = np.gradient(c, axis=0)
    t /= np.linalg.norm(t, axis=1)[:, None]
    e2 = np.array([0.0, 1.0, 0.0])
    if abs(e2 @ t[0]) > 0.9:  # a limb along y: start from z instead
        e2 = np.array([0.0, 0.0, 1.0])
    e1s, e2s = [], []
    for tt in t:
        e2 = e2 - (e2 @ tt) * tt
        e2 /= np.linalg.norm(e2)
        e2s.append(e2)
        e1s.append(np.cross(e2, -tt))
    return t, np.array(e1s), np.array(e2s)


def own_section(v: Array, lt: IArray, c: Array, t: Array, e1: Array, e2: Array) -> Array | None:
    """The closed loop around ``c`` where the plane through ``c`` normal to ``t`` cuts the
    limb's triangles ``lt``, in (e1, e2) coordinates; None if no closed loop surrounds ``c``
    (at the root the cut reaches the torso, at the hand the fingers)."""
    q = (v - c) @ np.array([e1, e2, -t]).T
    near = np.abs(q[lt, 2]).min(axis=1) < 0.05
    loops = [p for p, closed in sec.slice_chains(q, lt[near], 0.0) if closed and len(p) > 2]
    around = [p for p in loops if sec.contains(p, np.zeros((1, 2)))[0]]
    if not around:
        return None
    return min(around, key=lambda p: abs(sec.polygon_area(p)))


def centreline(v: Array, t: IArray, mine: npt.NDArray[np.bool_], rounds: int = 2):
    """Stations (s, centre, tangent, e1, e2, girth) of a limb (module doc, steps 1–2)."""
    lt = t[mine]
    c = _rings(v, t, mine)
    for _ in range(rounds + 1):
        s, c = _resample(_smooth(c), STATION)
        tan, e1, e2 = _frames(c)
        girth = np.full(len(s), np.nan)
        moved = c.copy()
        for i in range(len(s)):
            p = own_section(v, lt, c[i], tan[i], e1[i], e2[i])
            if p is not None:
                hull = sec.convex_hull(p)
                girth[i] = sec.perimeter(hull)
                m = sec.centroid(p)
                moved[i] = c[i] + m[0] * e1[i] + m[1] * e2[i]
        c = moved
    s, c = _resample(c, STATION)
    tan, e1, e2 = _frames(c)
    girth = np.full(len(s), np.nan)
    for i in range(len(s)):
        p = own_section(v, lt, c[i], tan[i], e1[i], e2[i])
        girth[i] = sec.tape_girth(p) if p is not None else np.nan
    return s, c, tan, e1, e2, girth


# ---------------------------------------------------------------------------------------------
# Joints and levels
# ---------------------------------------------------------------------------------------------


def bend(s: Array, c: Array, chord: float = BEND_CHORD) -> Array:
    """Angle [°] between the chords from s − chord to s and from s to s + chord (0 at ends)."""
    out = np.zeros(len(s))
    for i in range(len(s)):
        if s[i] - chord < s[0] or s[i] + chord > s[-1]:
            continue
        a = c[i] - c[np.searchsorted(s, s[i] - chord)]
        b = c[min(np.searchsorted(s, s[i] + chord), len(s) - 1)] - c[i]
        cosang = a @ b / (np.linalg.norm(a) * np.linalg.norm(b))
        out[i] = np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0)))
    return out


def _pick(s: Array, values: Array, lo: float, hi: float, fn, what: str, name: str) -> float:
    """s of ``fn`` (np.nanargmin / np.nanargmax) of ``values`` over lo ≤ s ≤ hi."""
    sel = np.flatnonzero((s >= lo) & (s <= hi) & np.isfinite(values))
    if not len(sel):
        raise ScanError(
            f"{name}: no {what} found between {lo:.2f} and {hi:.2f} m along the limb",
            "is the limb whole (hand / foot included) and clear of the body?",
        )
    return float(s[sel[fn(values[sel])]])


#: a hand widens the arm's girth by this share over the wrist, going towards the fingertips
#: (MakeHuman's muscular woman: 12 cm of tape at the wrist, 23 cm over the palm 6 cm further)
HAND_WIDENING = 0.15


def before_the_hand(s: Array, girth: Array, lo: float, narrowest: float) -> float:
    """The wrist: going from ``lo`` towards the tip, the narrowest section before the girth
    grows by :data:`HAND_WIDENING` over it (the hand begins); ``narrowest`` (the narrowest
    section of the window) if it never does before it. Across the hand the narrowest section
    can be a finger: MakeHuman's muscular woman's arm narrowed to 12 cm at the wrist (s = 0.42
    m), widened to 23 cm over the palm and narrowed again to 11 cm at the fingers (0.53 m),
    where the sleeve, cut to there, folded over the hand."""
    best, g_best = None, np.inf
    for k in np.flatnonzero((s >= lo) & (s <= narrowest) & np.isfinite(girth)):
        if girth[k] < g_best:
            best, g_best = float(s[k]), float(girth[k])
        elif girth[k] > (1.0 + HAND_WIDENING) * g_best:
            return best
    return narrowest


def _free_root(s: Array, girth: Array, name: str) -> float:
    """The first station from which every later one (up to the middle) has its own section."""
    mid = np.flatnonzero(s <= 0.5 * s[-1])
    bad = [i for i in mid if not np.isfinite(girth[i])]
    k = bad[-1] + 1 if bad else 0
    if k >= len(mid):
        raise ScanError(f"{name}: no section of the limb alone in its upper half")
    return float(s[k])


def arm_marks(s: Array, c: Array, girth: Array, stature: float, name: str) -> dict[str, float]:
    """Wrist, elbow, forearm, upper arm of an arm (module doc, step 3)."""
    L = s[-1]
    wrist = _pick(s, girth, 0.5 * L, 0.9 * L, np.nanargmin, "wrist (narrowest section)", name)
    wrist = before_the_hand(s, girth, 0.5 * L, wrist)
    root = _free_root(s, girth, name)
    ang = bend(s, c)
    elbow = _pick(s, ang, root + 0.25 * (wrist - root), root + 0.75 * (wrist - root),
                  np.nanargmax, "elbow (sharpest bend)", name)  # fmt: skip
    upper = root + ROOT_CLEARANCE * stature
    if not upper < elbow:
        raise ScanError(f"{name}: the upper arm level is not above the elbow")
    return {"upper_arm": upper, "elbow": elbow, "forearm": 0.5 * (elbow + wrist), "wrist": wrist}


def leg_marks(
    s: Array, c: Array, girth: Array, stature: float, name: str, heights: dict[str, float]
) -> dict[str, float]:
    """Thigh, knee, calf, ankle of a leg (module doc, step 3); ``heights``: the knee and calf
    heights found on the upright body (``anatomy.leg_levels``), taken as the stations there."""
    L = s[-1]
    ankle = _pick(s, girth, 0.45 * L, 0.85 * L, np.nanargmin, "ankle (narrowest section)", name)
    if ankle >= s[s <= 0.85 * L][-1]:  # still narrowing at the window's end: a foot below?
        ankle = _footless_ankle(s, girth, ankle, name)
    root = _free_root(s, girth, name)
    knee = station_at(s, c, heights["knee"], root, ankle)
    calf = station_at(s, c, heights["calf"], knee, ankle)
    thigh = root + ROOT_CLEARANCE * stature
    if not thigh < knee:
        raise ScanError(f"{name}: the thigh level is not above the knee")
    return {"thigh": thigh, "knee": knee, "calf": calf, "ankle": ankle}


#: A leg that ends without a foot (the parametric human's legs end 3 cm below the ankle; a scan
#: cut above the feet): its ankle is the narrowest section down to this far from the end [m]
#: (past the rounded rim of the cut) ...
FOOTLESS_END = 0.015
#: ... when no section below it is this much wider (a foot widens the girth by 30 % and more).
FOOT_WIDENING = 0.05


def _footless_ankle(s: Array, girth: Array, ankle: float, name: str) -> float:
    """The ankle of a leg whose girth still narrows at the end of the search window (85 % of
    the leg, where a foot would begin): the narrowest section down to :data:`FOOTLESS_END`
    from the end if no section beyond it widens by :data:`FOOT_WIDENING` (no foot), else
    ``ankle`` as found."""
    L = s[-1]
    far = _pick(s, girth, 0.45 * L, L - FOOTLESS_END, np.nanargmin, "ankle", name)
    g0 = float(girth[np.flatnonzero(s == far)[0]])
    below = girth[(s > far) & np.isfinite(girth)]
    return far if not len(below) or below.max() <= (1 + FOOT_WIDENING) * g0 else ankle


def station_at(s: Array, c: Array, z: float, lo: float, hi: float) -> float:
    """The arc length of the centreline station nearest to height ``z`` strictly between the
    arc lengths ``lo`` and ``hi`` (their middle if there is none)."""
    inside = (s > lo) & (s < hi)
    if not inside.any():
        return float(0.5 * (lo + hi))
    return float(s[np.flatnonzero(inside)[np.argmin(np.abs(c[inside, 2] - z))]])


def analyse_limb(
    v: Array, t: IArray, mine: npt.NDArray[np.bool_], name: str,
    heights: dict[str, float] | None = None,
) -> Limb:  # fmt: skip
    """Centreline, girths, joints and level sections of one limb (module doc); ``heights``:
    a leg's knee and calf heights found on the upright body (:func:`leg_marks`; required for
    a leg)."""
    s, c, tan, e1, e2, girth = centreline(v, t, mine)
    stature = float(np.ptp(v[:, 2]))
    if name.startswith("arm"):
        marks = arm_marks(s, c, girth, stature, name)
    else:
        if heights is None:
            raise ValueError(f"{name}: a leg's knee and calf heights are required")
        marks = leg_marks(s, c, girth, stature, name, heights)
    lt = t[mine]
    limb = Limb(name, s, c, tan, e1, e2, girth, marks, vertices=v, triangles=lt)
    for level, sl in marks.items():
        cc, tt, a, b = (x[0] for x in limb.frame_at(sl))
        p = own_section(v, lt, cc, tt, a, b)
        if p is None:
            raise ScanError(f"{name}: no section of the limb alone at its {level}")
        limb.sections[level] = smooth_section(sec.convex_hull(p))
    return limb


def smooth_section(hull: Array, n: int = 720, harmonics: int = SECTION_HARMONICS) -> Array:
    """A convex section's radius about its centroid as a Fourier series cut at ``harmonics``,
    sampled at ``n`` angles (counter-clockwise from +e1).

    A limb's hull has 20–40 corners; offsetting it inwards point by point (a tight garment)
    crosses the points near each corner over each other, and the offset's perimeter stops
    following Steiner's formula (measured on the MakeHuman wrist: 1 mm inwards −6.3 mm of
    perimeter as expected, 2 mm only −5.8 mm). Rounding the corners shortens the curve by
    ≈ 0.5 %; it is scaled back about the centroid to the hull's perimeter, the tape girth.
    """
    c = sec.centroid(hull)
    pts = sec.resample_by_angle(hull, n, centre=c) - c
    r = np.linalg.norm(pts, axis=1)
    f = np.fft.rfft(r)
    f[harmonics + 1 :] = 0.0
    r = np.fft.irfft(f, n)
    th = 2.0 * np.pi * np.arange(n) / n
    out = r[:, None] * np.column_stack([np.cos(th), np.sin(th)])
    return c + out * (sec.perimeter(hull) / sec.perimeter(out))
