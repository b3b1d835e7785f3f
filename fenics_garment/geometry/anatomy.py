"""Anatomy from geometry: torso, arms, legs and head of an upright body, and its landmarks.

The body is read from horizontal sections (feet at z = 0, +z up, facing −y, its left at +x,
centred near x = 0), not from fixed fractions of the stature:

* **Torso outline** at a height: the largest outer outline of the section whose x-range
  contains the body's mid-plane x = 0 (legs and arms never straddle it; hands are smaller).
* **Crotch**: the lowest height from which the torso outline exists (the legs have merged).
* **Armpits**: going up from the narrowest section below the widest one (the waist below the
  arms), the first height
  where the torso outline's lateral extent grows by more than ``ARM_JUMP`` between
  neighbouring sections: there the arm joins the torso. The same rule holds in an A-pose (the
  chest wall jumps to the arm's outer side) and a T-pose (the chest jumps to the arm span);
  coming down from the arms instead is fooled by a T-pose's nearly horizontal arm underside.
  The armpit point is the torso outline's lateral extreme just below; the vertical plane
  through it is the arm root (**arm cut**). Under a raised arm the jump comes where the web of
  skin from the chest wall to the arm has flattened: the armpit is followed down the web to
  the wall (``WEB_SLOPE``).
* **Arms**: the triangles beyond the arm cut that are connected (beyond it) to the most
  lateral point on that side. **Legs**: the rest below the crotch, split at x = 0.
* **Shoulder points** (acromions): on the shoulders' front silhouette, half-way across from
  the armpit's side to the silhouette's corner over the arm (:func:`acromion`); in a T-pose,
  the highest point of the surface on the vertical line through each armpit point.
* **Neck**: the smallest torso girth between the shoulders and the face lies just under the
  chin; the **head** starts where, going up, the girth first exceeds ``HEAD_FLARE`` × that
  girth (the chin's underside, the menton), or lower where the front comes forward abruptly
  under the chin (:func:`_chin`: a double chin, whose girth does not flare), or under a head
  less wide than that, from its widest section down (:func:`_neck_and_head`); the **neck base**
  60 % of the way from the shoulder points to that narrowest girth (the side neck point's
  level), higher where that is still on the shoulders' slope (:func:`_neck_base`), and the
  **neck** level (mid-neck girth) half-way between the neck base and the narrowest girth.
* **Torso girths** above the armpits are measured on the section clipped to the arm cuts, so
  the upper arms never count; below the armpits the torso outline is on its own.
* **Bust**: the level of the bust points, the most forward points of the chest going down
  from the armpits (ISO 8559-1 bust girth: across the bust points); **under-bust**: just below
  the breasts, at the inframammary fold — the corner of the front profile under the bust
  points, the point deepest behind its forward envelope (a small breast or a large one);
  on a flat chest, a fixed share of the way from the bust to the waist; **waist**: the natural
  waist, the narrowest torso girth below the under-bust (the middle of a plateau, :func:`extreme`,
  where there is no narrowing); **hip**: the level of the buttocks' greatest prominence, their
  rearmost point between the thighs and the waist
  (:func:`torso_levels`). Knee: the kneecap, the most prominent point of the leg's front
  profile (ISO 8559-1 mid-patella); calf and ankle: the widest / narrowest leg girths below it
  (:func:`leg_levels`).
* Validated on MakeHuman's population against its own measuring loops and ISO 8559-1 levels
  measured independently (``benchmarks/landmarks.py``, ``tests/test_population_landmarks.py``).
* **Limbs** (:mod:`.limbs`): each arm and leg followed along its own centreline, its sections
  perpendicular to it, elbows and wrists, knees and ankles found on the limb itself
  (:attr:`Anatomy.limbs`; their centreline points in :attr:`Anatomy.points` as
  ``elbow_left`` …). A limb that cannot be followed is left out with its reason in
  :attr:`Anatomy.limb_problems` (only a garment on that limb needs it).

Girths are tape girths (convex hull perimeter, ISO 8559-1). Overrides (heights in metres)
replace any detected level.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from . import sections as sec
from .errors import ScanError
from .limbs import KNEE_HEIGHT, Limb, analyse_limb
from .measurements import LEG_LEVELS, TORSO_LEVELS

Array = npt.NDArray[np.float64]
IArray = npt.NDArray[np.int64]

#: lateral drop [m] between neighbouring sections that marks an arm leaving the torso
ARM_JUMP = 0.02
#: Under a raised arm (a T-pose) the skin runs from the chest wall out to the arm's underside
#: as a sloping web, and the outline's jump (ARM_JUMP) comes only where the web has flattened:
#: on MakeHuman's T-posed woman 2.9 cm above and 4.7 cm lateral of the skin point that was her
#: armpit in the A-pose. Below the jump, the outline's lateral extent growing by more than this
#: many times the height step (flatter than 45°: an underside rather than a wall) is still the
#: web; the armpit is where the wall begins (our assumption; :func:`_arm_root`). Only under a
#: raised arm: beside a hanging arm (an A-pose) the outline may widen as much over one section
#: into the armpit's own fold (MakeHuman's short thin teenage girl: 5 mm, where the jump's
#: armpit is within 0.03 mm of the reference, ``benchmarks/landmarks.py``).
WEB_SLOPE = 1.0
#: ... the arm hangs if it is beside the torso this far [fraction of the stature] under the
#: armpit: a hanging upper arm (0.186 of the stature long, Drillis & Contini, see
#: ACROMION_REACH; 47–49° below the horizontal in MakeHuman's A-pose, ``tests/test_rig.py``)
#: reaches about 0.13 of the stature below its shoulder joint, a raised one's underside a few
#: centimetres below the web
ARM_HANG = 0.05
#: girth ratio over the narrowest neck girth where the head (the chin's underside) begins: the
#: narrowest girth lies just under the chin (MakeHuman's bodies: within 2 mm of the menton), and
#: the girth grows there by 10 % within 5–8 mm (``benchmarks/landmarks.py``)
HEAD_FLARE = 1.1
#: :func:`_chin`: the chin's underside is where the front of the body near its mid-plane (within
#: ``CHIN_BAND`` [m] of it) comes forward by ``CHIN_JUMP`` of the stature (1 cm on a 1.67 m body)
#: within one step of ``CHIN_STEP`` of it (4 mm); on MakeHuman's population within 3 mm of the
#: menton measured independently (``benchmarks/landmarks.py``), also under a double chin, where
#: the girth does not flare (``HEAD_FLARE``)
CHIN_BAND, CHIN_JUMP, CHIN_STEP = 0.015, 0.006, 0.0025
#: a head less wide than HEAD_FLARE × its neck: the girth falls by this share from the head's
#: widest section down to the neck (MakeHuman's heavy men: 10 %; noise: under 1 %)
NECK_DIP = 0.05
#: largest girth at the base of the neck over the neck girth: below it the section is on the
#: shoulders' slope (MakeHuman's bodies: 1.10–1.23 at 60 % of the way from the shoulder points
#: up to the neck, and up to 2.4 × at the shoulder points)
NECK_BASE_FLARE = 1.25
#: The kneecap is looked for between the calf and this share of the way from the calf up to the
#: crotch: the knee joint lies at 0.285 of the stature (:data:`~.limbs.KNEE_HEIGHT`), the calf
#: about 0.21 and the crotch 0.47 (Drillis & Contini's proportions), 30 % of the way; the top
#: of the patella 3–4 cm higher. Above it the thigh's muscles bulge forward too (the vastus
#: medialis and rectus femoris: MakeHuman's muscular men 4–7 mm over the chord, more than their
#: kneecap) — a wider window finds them instead (:func:`kneecap`).
KNEE_REACH = 0.4
#: A kneecap stands at least this far [fraction of the stature] in front of the straight line
#: from the shin's front to the thigh's front (MakeHuman's population: 3.5–29 mm; 1 mm on a
#: 1.67 m body is below a scan's noise); a leg with less (the human mannequin's lofted leg,
#: straight from thigh to ankle) shows no knee: the proportional height is taken.
KNEECAP_MIN = 0.0006
#: A lower leg without a calf bulge (its girth rising from the ankle all the way to the knee,
#: MakeHuman's thin or short women: no ISO 8559-1 calf, the maximum girth of the calf, below
#: the knee) has its calf level this share of the way from the ankle to the knee: the median
#: over the 31 bodies of MakeHuman's population that have a bulge (0.57–0.93; by this module's
#: levels, ``benchmarks/landmarks.py``). On the 5 without one, against MakeHuman's calf loop:
#: +0.04, +0.54, +1.89 cm, and +3.85 and +4.48 cm where our knee is itself 3.6 and 1.8 cm off
#: (the short thin girl, the 2.32 m tall thin woman); the widest girth under the knee, the rule
#: before: +5.7 to +15.2 cm. The parametric mannequin's proportions
#: (measurements.py: ankle 0.06, calf 0.205, knee 0.285 of the stature) give 0.644 too.
CALF_SHARE = 0.644
#: :func:`extreme`: a girth within this share of the narrowest (widest) ...
PLATEAU = 0.005
#: ... over more than this height [m] has no apparent extreme: the middle of it is taken
PLATEAU_SPAN = 0.03
#: Depth [fraction of the stature] by which the front must recede below the bust's most forward
#: point for it to count (:func:`bust_level`; the unit of FOLD_CLIFF): 0.2 %, 3.3 mm on a
#: 1.67 m body. The fold under the MakeHuman base mesh's small breasts is 4–6 mm deep, and the
#: front of its chest wobbles by about 1 mm between sections (its facets are 1 cm across).
FOLD_DEPTH = 0.002
#: A drop of the front under the bust points by more than this many FOLD_DEPTHs between two
#: sections of the fold search (2.5 mm apart on a 1.67 m body) is the underside of a large
#: breast seen from the front: the fold is just below it (MakeHuman's female body with its
#: largest cup: 2–3 cm a step at the breast's lower edge; elsewhere below 0.3 cm a step), where
#: the breast's lower part leaves the torso's outline and the profile under it is cut short.
FOLD_CLIFF = 4.0
#: The inframammary fold lies at least this far [fraction of the stature] behind the front
#: profile's envelope (1 mm on a 1.67 m body, the shallowest dent a tape shows): the breast's
#: fold is 4–30 mm deep on MakeHuman's women, the lower edge of the pectoral muscle 1.6–4 mm on
#: its men — there MakeHuman's underbust loop passes 0.8–2 cm from it, against 1.4–4.8 cm from
#: the flat-chest rule (FLAT_UNDERBUST); a chest without either has no fold.
FOLD_MIN_DEPTH = 0.0006
#: How far below the bust point the fold is looked for [fraction of the stature]: the lower half
#: of a breast, 2.5 cm (MakeHuman's base mesh) to 8 cm (its female body with the largest cup);
#: 6 %, 10 cm on a 1.67 m body. A flat chest has none within it.
FOLD_REACH = 0.06
#: A flat chest (no fold within FOLD_REACH): the under-bust this share of the way from the bust
#: down to the narrowest girth (MakeHuman's male body: its underbust measuring loop 6.7 cm under
#: the nipples, 35 % of the 19 cm from the nipples to the narrowest girth; our assumption)
FLAT_UNDERBUST = 0.35
#: The bust points are looked for within this share of the torso's width either side of its
#: middle (MakeHuman's bodies: 0.26–0.37 at the bust points' level).
BUST_REGION = 0.45
#: the leg levels a leg's centreline takes from the upright body's sections (:func:`find_limbs`):
#: the kneecap and the calf found there; on the centreline alone (its sharpest bend) the knee
#: lay 5–11.6 cm under MakeHuman's knee loop on 8 of its 37 bodies (``benchmarks/landmarks.py``)
LIMB_LEVELS = ("knee", "calf")
#: :func:`acromion`: the arm's top must come down to the armpit's height within this far
#: [fraction of the stature] out from the armpit's side, the upper arm's length (0.186 of the
#: stature, Drillis & Contini 1966, D. A. Winter, *Biomechanics and Motor Control of Human
#: Movement*, 4th ed., Fig. 4.1): an A-posed arm does so before the elbow (MakeHuman's bodies:
#: 0.064–0.074), a T-posed one only beyond it, at the hand (0.32; the corner of the arm's
#: silhouette found there lay 15–20 cm out on the arm)
ACROMION_REACH = 0.186
#: landmark levels a scene may override (heights in metres above the floor)
LANDMARKS = (*LEG_LEVELS, *TORSO_LEVELS, "armpit", "head")
#: body parts, numbered per triangle in :attr:`Anatomy.part`
PARTS = {"torso": 0, "head": 1, "arm_left": 2, "arm_right": 3, "leg_left": 4, "leg_right": 5}


@dataclass(frozen=True)
class Outline:
    """One outer outline of a horizontal section."""

    points: Array
    area: float
    xmin: float
    xmax: float


@dataclass
class Anatomy:
    """Landmark heights, points, the arm cuts and a body part per triangle."""

    landmarks: dict[str, float]
    points: dict[str, Array]
    arm_cut: dict[str, float]  # "left" -> x of the left arm root plane (> 0), "right" (< 0)
    part: npt.NDArray[np.int32]
    girths: dict[str, float] = field(default_factory=dict)
    sections: dict[str, Array] = field(default_factory=dict)  # torso-only tape sections
    limbs: dict[str, Limb] = field(default_factory=dict)  # "arm_left" … (module doc)
    limb_problems: dict[str, str] = field(default_factory=dict)  # limb -> why it is missing

    def torso_section(self, vertices: Array, triangles: IArray, z: float) -> Array:
        """The torso's tape (convex hull) section at ``z``, clipped to the arm cuts."""
        return torso_section(vertices, triangles, z, self.arm_cut, self.landmarks.get("armpit"))


def outlines(vertices: Array, triangles: IArray, z: float) -> list[Outline]:
    """Outer outlines of the section at ``z`` (nested ones, e.g. around a hollow, dropped)."""
    loops = [p for p in sec.slice_loops(vertices, triangles, z) if len(p) > 2]
    res = [Outline(p, abs(sec.polygon_area(p)), float(p[:, 0].min()), float(p[:, 0].max()))
           for p in loops]  # fmt: skip
    res.sort(key=lambda o: -o.area)
    outer: list[Outline] = []
    for o in res:
        if not any(sec.contains(b.points, o.points[:1])[0] for b in outer):
            outer.append(o)
    return outer


def torso_outline(vertices: Array, triangles: IArray, z: float) -> Outline | None:
    """The largest outer outline at ``z`` whose x-range contains x = 0, or None."""
    for o in outlines(vertices, triangles, z):
        if o.xmin < 0.0 < o.xmax:
            return o
    return None


def clip_x(poly: Array, lo: float, hi: float) -> Array:
    """A closed polygon clipped to the strip lo ≤ x ≤ hi (Sutherland–Hodgman, two edges)."""

    def half(p: Array, x0: float, keep_below: bool) -> Array:
        if len(p) == 0:
            return p
        s = (x0 - p[:, 0]) if keep_below else (p[:, 0] - x0)
        out = []
        for i in range(len(p)):
            j = (i + 1) % len(p)
            if s[i] >= 0:
                out.append(p[i])
            if (s[i] >= 0) != (s[j] >= 0):
                t = s[i] / (s[i] - s[j])
                out.append(p[i] + t * (p[j] - p[i]))
        return np.array(out).reshape(-1, 2)

    return half(half(poly, hi, True), lo, False)


def torso_section(
    vertices: Array, triangles: IArray, z: float, cut: dict[str, float], armpit: float | None
) -> Array:
    """Convex hull of the torso outline at ``z``; above the ``armpit`` height clipped to the arm
    cut planes (below it the arms are separate outlines, and hips may be wider than the cut)."""
    o = torso_outline(vertices, triangles, z)
    if o is None:
        raise ScanError(f"no torso section at z = {z:.3f} m")
    pts = o.points
    if armpit is not None and z >= armpit:
        pts = clip_x(pts, cut.get("right", -np.inf), cut.get("left", np.inf))
    return sec.convex_hull(pts)


def _refine(f, a: float, b: float, steps: int = 7) -> float:
    """Bisection on a boolean ``f`` with f(a) != f(b); returns the end on f(a)'s side."""
    fa = f(a)
    for _ in range(steps):
        m = 0.5 * (a + b)
        if f(m) == fa:
            a = m
        else:
            b = m
    return a


def analyse(
    vertices: Array, triangles: IArray, overrides: dict[str, float] | None = None
) -> Anatomy:
    """Segment an upright full body and locate its landmarks (module docstring)."""
    v, t = vertices, triangles
    H = float(v[:, 2].max())
    zs = np.linspace(0.25 * H, 0.995 * H, 250)
    torso = [torso_outline(v, t, z) for z in zs]
    have = np.array([o is not None for o in torso])
    if not have.any():
        raise ScanError("no section straddles the body's mid-plane", "is it a standing body?")
    # crotch: lowest section from which the torso outline exists for the next 5 sections
    run = np.convolve(have.astype(int), np.ones(5, int), "valid") == 5
    if not run.any():
        raise ScanError("no continuous torso found", "is it a standing body?")
    k0 = int(np.argmax(run))
    crotch = zs[k0] if k0 == 0 else _refine(
        lambda z: torso_outline(v, t, z) is not None, zs[k0], zs[k0 - 1]
    )  # fmt: skip
    upper = [k for k in range(k0, len(zs)) if have[k] and zs[k] > crotch + 0.35 * (H - crotch)]
    if not upper:
        raise ScanError("no upper body found above the crotch", "is it a standing body?")
    armpit, cut, pts = {}, {}, {}
    for side, sgn in (("left", 1.0), ("right", -1.0)):
        found = _arm_root(v, t, zs, torso, upper, sgn)
        if found is not None:
            z_ap, p = found
            top = _surface_top(v, t, p[0], p[1])
            if top is None or top <= z_ap:
                raise ScanError(f"no shoulder above the {side} armpit")
            armpit[side], cut[side] = z_ap, float(p[0])
            pts[f"armpit_{side}"] = np.array([p[0], p[1], z_ap])
            pts[f"shoulder_{side}"] = np.array([p[0], p[1], top])
            pts[f"arm_root_{side}"] = _arm_root_box(v, t, float(p[0]), z_ap, top)
    if len(armpit) == 1:
        missing = ({"left", "right"} - set(armpit)).pop()
        raise ScanError(
            f"the {missing} arm does not leave the torso",
            "the arms must hang clear of the torso (A- or T-pose); or set the landmarks",
        )

    z_ap = min(armpit.values()) if armpit else None

    def girth(z: float) -> float:
        return sec.tape_girth(torso_section(v, t, z, cut, z_ap))

    def front(z: float) -> Array | None:  # the torso outline below the armpits (bust search)
        o = torso_outline(v, t, z)
        return None if o is None else o.points

    if armpit:
        z_armpit = min(armpit.values())
        z_shoulder = 0.5 * (pts["shoulder_left"][2] + pts["shoulder_right"][2])
    else:  # no arms: the shoulder is the widest upper-body section, no armpit
        width = {k: torso[k].xmax - torso[k].xmin for k in upper}
        z_shoulder = float(zs[max(upper, key=width.get)])
        # only bounds the search for the bust: 91 % of the shoulder height, between the bust
        # (0.72 / 0.815 = 0.88) and the upper chest (0.755 / 0.815 = 0.93) of the parametric
        # mannequin's proportions (measurements.py; our assumption, not a survey value)
        z_armpit = 0.91 * z_shoulder
    marks: dict[str, float] = {"crotch": crotch, "shoulder": z_shoulder}
    if armpit:
        marks["armpit"] = z_armpit
    lo_neck = z_shoulder + 0.01 * H
    chin = _chin(v, t, z_shoulder, H)
    top = H - 0.005 * H if chin is None else max(chin, lo_neck + 0.01 * H)
    narrow, head = _neck_and_head(v, t, girth, lo_neck, top)
    if chin is not None:  # the chin's underside, where the girth may not flare (double chin)
        head = chin if head is None else min(head, chin)
    if head is not None:
        marks["head"] = head
    if armpit:  # the acromions, from the shoulders' silhouette above the armpits
        z_base = _neck_base(girth, z_shoulder, narrow)
        neck = torso_outline(v, t, z_base)
        for side, sgn in (("left", 1.0), ("right", -1.0)):
            half = H * 0.03 if neck is None else (neck.xmax if sgn > 0 else -neck.xmin)
            p = pts[f"armpit_{side}"]
            found = acromion(v, t, sgn, half, abs(p[0]), armpit[side], z_base + 0.006 * H, H)
            if found is not None:
                pts[f"shoulder_{side}"] = np.array([sgn * found[0], p[1], found[1]])
        z_shoulder = 0.5 * (pts["shoulder_left"][2] + pts["shoulder_right"][2])
        marks["shoulder"] = z_shoulder
    marks["neck_base"] = _neck_base(girth, z_shoulder, narrow)
    marks["neck"] = 0.5 * (marks["neck_base"] + narrow)  # mid-neck
    marks.update(torso_levels(girth, crotch, z_armpit, z_shoulder, H, front, bool(armpit)))
    marks.update(leg_levels(v, t, crotch, H))
    right = leg_levels(v, t, crotch, H, side=-1.0)
    if overrides:
        marks.update(overrides)
        right.update({k: z for k, z in overrides.items() if k in right})
    marks = {k: float(z) for k, z in marks.items()}
    check_order(marks)
    part = body_parts(v, t, marks, cut)
    girths = {k: girth(marks[k]) for k in TORSO_LEVELS if k in marks and k != "crotch"}
    sections = {k: torso_section(v, t, marks[k], cut, z_ap) for k in girths}
    on_legs = {"leg_left": {k: marks[k] for k in LIMB_LEVELS},
               "leg_right": {k: right[k] for k in LIMB_LEVELS}}  # fmt: skip
    limbs, problems = find_limbs(v, t, part, on_legs)
    for name, limb in limbs.items():
        side = name.split("_")[1]
        for joint in ("elbow", "wrist", "knee", "ankle"):
            if joint in limb.marks:
                pts[f"{joint}_{side}"] = limb.point(joint)
    return Anatomy(marks, pts, cut, part, girths, sections, limbs, problems)


def find_limbs(
    v: Array, t: IArray, part: npt.NDArray[np.int32], heights: dict[str, dict[str, float]]
) -> tuple[dict[str, Limb], dict[str, str]]:
    """Every arm and leg followed along its centreline (:mod:`.limbs`), and the reason for
    each one that could not be; ``heights``: per limb, levels already found on the upright
    body (:data:`LIMB_LEVELS` of each leg, :func:`leg_levels`) that its centreline takes over."""
    limbs, problems = {}, {}
    for name in ("arm_left", "arm_right", "leg_left", "leg_right"):
        mine = part == PARTS[name]
        if not mine.any():
            problems[name] = f"no {name.replace('_', ' ')} was found on the body"
            continue
        try:
            limbs[name] = analyse_limb(v, t, mine, name, heights.get(name))
        except ScanError as e:
            problems[name] = str(e)
    return limbs, problems


def _arm_root(
    v: Array, t: IArray, zs: Array, torso: list, upper: list[int], sgn: float
) -> tuple[float, Array] | None:
    """(armpit height, armpit point (x, y)) on one side, or None if no arm leaves the torso."""

    def reach(o: Outline) -> float:
        return o.xmax if sgn > 0 else -o.xmin

    ext = {k: reach(torso[k]) for k in upper}
    k_wide = max(upper, key=ext.get)  # arms included
    below = [k for k in upper if k < k_wide]
    if not below:
        return None
    k = min(below, key=ext.get) + 1  # from the narrowest below it (the waist) upwards
    while k in ext and k - 1 in ext and ext[k] < ext[k - 1] + ARM_JUMP:
        k += 1
    if k not in ext or k - 1 not in ext:
        return None
    j = k - 1  # down the web under a raised arm to the chest wall (WEB_SLOPE)
    while j - 1 in ext and ext[j] - ext[j - 1] > WEB_SLOPE * (zs[j] - zs[j - 1]):
        j -= 1
    below = float(zs[k - 1]) - ARM_HANG * float(v[:, 2].max())
    if j < k - 1 and not _arm_hangs(v, t, below, sgn, ext[k - 1]):
        o = torso[j]
        return float(zs[j]), o.points[np.argmax(sgn * o.points[:, 0])]
    thr = 0.5 * (ext[k - 1] + ext[k])

    def attached(z: float) -> bool:
        o = torso_outline(v, t, z)
        return o is not None and reach(o) > thr

    z_ap = _refine(attached, zs[k - 1], zs[k])
    o = torso_outline(v, t, z_ap)
    if o is None:
        return None
    return z_ap, o.points[np.argmax(sgn * o.points[:, 0])]


def _arm_hangs(v: Array, t: IArray, z: float, sgn: float, reach: float) -> bool:
    """Whether a piece of the section at ``z`` (:data:`ARM_HANG` under the armpit) lies wholly
    beyond the torso's lateral extent ``reach`` on the side ``sgn`` and starts within an upper
    arm's length of it (:data:`ACROMION_REACH`): an arm hanging beside the torso (an A-pose),
    not a raised one (whose hand may droop below the armpit's height, 0.3 of the stature out,
    and whose underside may sag a little below the web: the tall, heavy, muscular man's)."""
    H = float(v[:, 2].max())
    return any(reach < (sgn * p[:, 0]).min() < reach + ACROMION_REACH * H
               for p in sec.slice_loops(v, t, z) if len(p) > 2)  # fmt: skip


def shoulder_silhouette(
    v: Array, t: IArray, sgn: float, s0: float, z_lo: float, z_hi: float, step: float
) -> tuple[Array, Array]:
    """The shoulder's silhouette seen from the front on one side (``sgn`` +1: +x): at distances
    ``s`` from the mid-plane, every ``step`` from ``s0`` outwards, the highest point of the
    body's section by the vertical plane x = sgn s between ``z_lo`` and ``z_hi``; it stops where
    no point is left. Returns (s, z_top)."""
    vv = v[:, [1, 2, 0]]  # (y, z, x): slice_loops cuts at constant third coordinate
    ss, zt = [], []
    for s in np.arange(s0, s0 + 1.0, step):
        pieces = sec.slice_loops(vv, t, sgn * s)
        z = [float(q[(q[:, 1] > z_lo) & (q[:, 1] < z_hi), 1].max(initial=-np.inf)) for q in pieces]
        if not z or max(z) == -np.inf:
            break
        ss.append(s)
        zt.append(max(z))
    return np.array(ss), np.array(zt)


def acromion(
    v: Array, t: IArray, sgn: float, s_neck: float, s_armpit: float, z_armpit: float,
    z_neck: float, H: float,
) -> tuple[float, float] | None:  # fmt: skip
    """The acromion on one side (distance from the mid-plane, height), from the front
    silhouette of the shoulder (:func:`shoulder_silhouette`, from the neck's side at its base,
    ``s_neck``, up to ``z_neck``, 1 cm above the neck's base): its **corner** is the point
    standing furthest above the chord from the neck's side to where the arm's top has come
    down to the armpit's height (in an A-pose; the deltoid's top); the acromion lies half-way
    across from the armpit's side (``s_armpit``, the torso's lateral extent there) to the
    corner, on the silhouette.

    On MakeHuman's 37 bodies against its acromion vertex (``benchmarks/landmarks.py``): within
    1.5 cm on 35, +2.0 and +2.8 cm on the two teenage girls (the corner alone is 1.3–4.2 cm low
    on the men, whose deltoids bulge beyond the acromion; the top of the surface over the
    armpit point, the rule before, 1.5–2.6 cm high on the women, whose armpit lies 1.5–2.5 cm
    medial of it). None if the arm's top never comes down to the armpit's height within reach
    (:data:`ACROMION_REACH`; a T-pose): the caller keeps the top over the armpit."""
    s, z = shoulder_silhouette(v, t, sgn, s_neck, z_armpit - 0.2 * H, z_neck, 0.0015 * H)
    low = np.flatnonzero(z <= z_armpit)
    if len(s) < 5 or not len(low) or low[0] < 4 or s[low[0]] > s_armpit + ACROMION_REACH * H:
        return None
    s, z = s[: low[0] + 1], z[: low[0] + 1]
    chord = z[0] + (s - s[0]) * (z[-1] - z[0]) / (s[-1] - s[0])
    corner = float(s[int(np.argmax(z - chord))])
    mid = 0.5 * (s_armpit + corner)
    return mid, float(np.interp(mid, s, z))


def _arm_root_box(v: Array, t: IArray, x: float, z_ap: float, z_top: float) -> Array:
    """(y_min, y_max, z_min, z_max) of the arm root: the outline of the body's section by the
    vertical plane through the armpit (x = const) that contains the point half-way up between
    armpit and shoulder point, above the armpit."""
    vv = v[:, [1, 2, 0]]  # (y, z, x): slice_loops cuts at constant third coordinate
    z_mid = 0.5 * (z_ap + z_top)
    loops = [p for p in sec.slice_loops(vv, t, x) if len(p) > 2]
    inside = [p for p in loops if p[:, 1].min() <= z_mid <= p[:, 1].max()]
    if not inside:
        return np.array([np.nan, np.nan, z_ap, z_top])
    p = max(inside, key=lambda q: abs(sec.polygon_area(q)))
    p = p[p[:, 1] >= z_ap - 1e-3]
    return np.array([p[:, 0].min(), p[:, 0].max(), z_ap, z_top])


def _chin(v: Array, t: IArray, lo: float, H: float) -> float | None:
    """The chin's underside (menton, ISO 8559-1): going up from ``lo`` in steps of
    :data:`CHIN_STEP` of the stature, the first height where the front of the torso outline
    within ``CHIN_BAND`` of its middle comes forward by more than :data:`CHIN_JUMP` of the
    stature within one step (the lower end of that step); None without such a jump (no head,
    or a head without a chin)."""
    step, prev = CHIN_STEP * H, None
    for z in np.arange(lo, 0.95 * H, step):
        o = torso_outline(v, t, z)
        p = None if o is None else o.points
        sel = None if p is None else np.abs(p[:, 0] - 0.5 * (o.xmin + o.xmax)) <= CHIN_BAND
        if sel is None or not sel.any():
            prev = None
            continue
        f = float(-p[sel, 1].min())
        if prev is not None and f - prev > CHIN_JUMP * H:
            return float(z - step)
        prev = f
    return None


def _neck_and_head(v: Array, t: IArray, girth, lo: float, hi: float) -> tuple[float, float | None]:
    """Going up from ``lo``: the neck is the running girth minimum at the height where the girth
    first exceeds ``HEAD_FLARE`` times it (the jaw: the head starts there).

    A thick neck under a head less than ``HEAD_FLARE`` times as wide (MakeHuman's heavy men:
    head 1.11 × the neck girth) is found from the top down instead: the head's widest section
    is the first girth maximum that the girth falls :data:`NECK_DIP` below going down, the neck
    the smallest girth under it, the head from half-way up in girth from neck to head (before,
    the neck was the smallest girth up to ``hi``: the crown, 34 cm above the shoulders of the
    tall, heavy, muscular man). Without a head at all the neck is the smallest girth up to
    ``hi``."""
    zn = [z for z in np.linspace(lo, hi, 60) if torso_outline(v, t, z) is not None]
    if not zn:
        raise ScanError("no neck found above the shoulders")
    gs = [girth(z) for z in zn]
    best_z, best_g, prev = zn[0], np.inf, zn[0]
    for z, g in zip(zn, gs, strict=True):
        if g < best_g:
            best_z, best_g = z, g
        elif g > HEAD_FLARE * best_g:
            return float(best_z), 0.5 * float(prev + z)  # between the samples either side
        prev = z
    k_max, k_head = len(gs) - 1, None
    for k in range(len(gs) - 1, -1, -1):  # from the crown down to the head's widest section
        if gs[k] > gs[k_max]:
            k_max = k
        elif gs[k] < (1.0 - NECK_DIP) * gs[k_max]:
            k_head = k_max
            break
    if k_head is None:
        return float(best_z), None
    k_neck = int(np.argmin(gs[:k_head]))
    half = 0.5 * (gs[k_neck] + gs[k_head])
    k_jaw = next(k for k in range(k_neck, k_head + 1) if gs[k] >= half)
    return float(zn[k_neck]), float(zn[k_jaw])


def _neck_base(girth, shoulder: float, neck: float) -> float:
    """The base of the neck: 60 % of the way up from the shoulder points to the neck, or higher
    where that is still on the slope of the shoulders — its girth more than
    :data:`NECK_BASE_FLARE` × the neck girth — the height between them where the girth comes
    down to that (bisection). MakeHuman's bodies at 60 %: 1.10–1.23 × the neck girth, but the
    short, heavy, old woman (sloping shoulders, a short neck) 1.68 × (0.52 m of tape across the
    shoulders' slope, where the gilet's neckline and straps were cut)."""
    z = shoulder + 0.6 * (neck - shoulder)
    limit = NECK_BASE_FLARE * girth(neck)
    if girth(z) <= limit:
        return z
    return _refine(lambda zz: girth(zz) > limit, z, neck, steps=10)


def torso_levels(
    girth,
    crotch: float,
    armpit: float,
    shoulder: float,
    H: float,
    outline=None,
    arm_roots: bool = False,
) -> dict:
    """Torso levels from the girth (``girth(z)``, the tape girth of the torso) and the torso's
    outline below the armpits (``outline(z)``: its points, or None):

    * bust: the bust points' level — going down from the armpits, the most forward point of the
      chest's front (within :data:`BUST_REGION` of the width of the middle) before the front
      recedes by :data:`FOLD_DEPTH` (:func:`bust_level`); without such a point, or without
      ``outline``, the widest girth between waist and armpit;
    * under-bust: the inframammary fold under the bust points (:func:`fold_level`), or on a flat
      chest :data:`FLAT_UNDERBUST` of the way from the bust down to the narrowest girth;
    * waist: the narrowest girth between a quarter of the crotch–armpit span and the under-bust
      (1 % of the stature below it), at most three quarters up the span; the middle of a plateau
      where the waist has no narrowing (:func:`extreme`);
    * hip: the greatest prominence of the buttocks (:func:`buttocks_level`) between 3 % of the
      stature above the crotch (below, the tape spans both thighs) and 2 % under the waist;
      without ``outline`` the widest girth there; abdomen half-way hip–waist; upper chest 40 %
      of the way from the bust to the shoulder (our convention, as in the parametric
      mannequin's proportions), and with ``arm_roots`` (a body with arms: ``armpit`` is their
      root) from the higher of bust and armpit: a section just above the armpits is mostly arm
      root (on the MakeHuman base mesh 1.22 m of tape 4 mm above them, against 0.89 m 5 cm
      higher, clipped to the arm cuts alike), and a garment lofted through it bulges round the
      arms."""
    span = armpit - crotch
    zs = np.linspace(crotch + 0.005 * H, armpit - 0.002 * H, 90)
    g = np.array([girth(z) for z in zs])

    def arg(fn, lo: float, hi: float) -> float:
        sel = (zs >= lo) & (zs <= hi)
        if not sel.any():
            raise ScanError(f"no torso section between {lo:.3f} and {hi:.3f} m")
        i = np.flatnonzero(sel)[fn(g[sel])]
        return float(zs[i])

    narrowest = arg(np.argmin, crotch + 0.25 * span, crotch + 0.75 * span)
    found = None
    if outline is not None:
        found = bust_level(outline, narrowest + 0.01 * H, armpit - 0.002 * H, H)
    if found is None:  # no forward bust point: the widest girth
        bust, under = arg(np.argmax, narrowest + 0.04 * H, armpit), None
    else:
        bust, half_gap = found
        under = fold_level(outline, bust, half_gap, max(narrowest, bust - FOLD_REACH * H), H)
    if under is None:
        under = bust - FLAT_UNDERBUST * (bust - narrowest)
    lo, hi = crotch + 0.25 * span, min(crotch + 0.75 * span, under - 0.01 * H)
    sel = (zs >= lo) & (zs <= hi)
    if not sel.any():
        raise ScanError(f"no torso section between {lo:.3f} and {hi:.3f} m")
    waist = extreme(zs[sel], g[sel], widest=False)
    lo, hi = crotch + 0.03 * H, waist - 0.02 * H  # above: not the span across the thighs
    hip = None if outline is None else buttocks_level(outline, lo, hi, H)
    if hip is None:  # no outline to read the buttocks from: the widest girth
        hip = arg(np.argmax, lo, hi)
    return {
        "hip": hip,
        "abdomen": 0.5 * (hip + waist),
        "waist": waist,
        "underbust": under,
        "bust": bust,
        "upper_chest": (top := max(bust, armpit) if arm_roots else bust) + 0.4 * (shoulder - top),
    }


def buttocks_level(outline, lo: float, hi: float, H: float) -> float | None:
    """The hip level (ISO 8559-1 hip girth: the horizontal girth at the level of the greatest
    prominence of the buttocks; ISAK's gluteal girth: their greatest posterior protuberance):
    between ``lo`` and ``hi``, every 0.2 % of the stature ``H``, the height of the torso
    outline's rearmost point (+y); None without an outline there.

    Not the widest girth: a belly wider than the buttocks (MakeHuman's short, heavy, flabby old
    man: his widest girth 7.8 cm above MakeHuman's hip loop) moves the widest girth up to it."""
    best_z, best_y = None, -np.inf
    for z in np.arange(lo, hi, 0.002 * H):
        p = outline(z)
        if p is not None and float(p[:, 1].max()) > best_y:
            best_z, best_y = float(z), float(p[:, 1].max())
    return best_z


def _front_of(p: Array, near) -> float | None:
    """The forward projection (−y) of the most forward point of outline ``p`` among the points
    whose lateral offset from the outline's middle satisfies ``near(offset, width)``."""
    xc = 0.5 * (p[:, 0].max() + p[:, 0].min())
    w = float(np.ptp(p[:, 0]))
    sel = near(np.abs(p[:, 0] - xc), w) & (p[:, 1] < p[:, 1].mean())
    return float(-p[sel, 1].min()) if sel.any() else None


def bust_level(outline, lo: float, hi: float, H: float) -> tuple[float, float] | None:
    """Going down from ``hi`` in steps of 0.15 % of the stature: the height of the chest's most
    forward point before the front recedes by :data:`FOLD_DEPTH` (the bust points), and their
    half-distance (lateral offset from the middle); None if the front keeps coming forward down
    to ``lo`` (no bust points)."""
    best_z, best_f = None, -np.inf
    for z in np.arange(hi, lo, -0.0015 * H):
        p = outline(z)
        f = None if p is None else _front_of(p, lambda d, w: d <= BUST_REGION * w)
        if f is None:
            continue
        if f > best_f:
            best_z, best_f = float(z), f
        elif f < best_f - FOLD_DEPTH * H:
            break
    else:
        return None
    p = outline(best_z)
    xc = 0.5 * (p[:, 0].max() + p[:, 0].min())
    w = float(np.ptp(p[:, 0]))
    gaps = []
    for side in (1.0, -1.0):
        d = side * (p[:, 0] - xc)
        sel = (d >= 0.1 * w) & (d <= BUST_REGION * w) & (p[:, 1] < p[:, 1].mean())
        if sel.any():
            gaps.append(float(d[sel][np.argmin(p[sel, 1])]))
    return best_z, (float(np.mean(gaps)) if gaps else 0.25 * w)


def depth_under_envelope(z: Array, f: Array) -> Array:
    """How far each point (z, f) of a profile lies behind its forward envelope: the upper convex
    hull of the points (the straight tape laid over the profile's bulges)."""
    hull: list[int] = []
    for i in np.argsort(z):
        while len(hull) >= 2:
            a, b = hull[-2], hull[-1]
            if (z[b] - z[a]) * (f[i] - f[a]) - (f[b] - f[a]) * (z[i] - z[a]) >= 0.0:
                hull.pop()  # b lies on or under the chord a–i
            else:
                break
        hull.append(int(i))
    return np.interp(z, z[hull], f[hull]) - f


def fold_level(outline, bust: float, half_gap: float, lo: float, H: float) -> float | None:
    """The inframammary fold (ISO 8559-1 under-bust girth: just below the breasts, where the
    breast's lower contour meets the chest wall): on the front profile under the bust points —
    the most forward reach within 35 % of ``half_gap`` of their lateral offset, every 0.15 % of
    the stature from the ``bust`` level down to ``lo`` — the point deepest behind the profile's
    forward envelope (:func:`depth_under_envelope`: the corner under the breast, or under a
    man's pectoral muscle); just below where the front drops by :data:`FOLD_CLIFF`
    FOLD_DEPTHs within one step (the underside of a large breast). None when the deepest point
    lies less than :data:`FOLD_MIN_DEPTH` of the stature behind the envelope (a flat chest)."""

    def near(d, w):
        return np.abs(d - half_gap) <= 0.35 * half_gap

    zs, fs = [], []
    for z in np.arange(bust, lo, -0.0015 * H):
        p = outline(z)
        f = None if p is None else _front_of(p, near)
        if f is None:
            continue
        if fs and fs[-1] - f > FOLD_CLIFF * FOLD_DEPTH * H:
            return float(z)  # off the underside of a large breast: the fold is just below
        zs.append(float(z))
        fs.append(f)
    if len(zs) < 3:
        return None
    depth = depth_under_envelope(np.array(zs), np.array(fs))
    k = int(np.argmax(depth))
    return zs[k] if depth[k] >= FOLD_MIN_DEPTH * H else None


def extreme(zs: Array, g: Array, widest: bool) -> float:
    """The height of the narrowest (``widest``: the widest) girth ``g`` over the heights ``zs``;
    where the girth stays within :data:`PLATEAU` of that extreme over more than
    :data:`PLATEAU_SPAN` of height (no apparent narrowing or bulge: a heavy body's waist, a
    long even calf), the middle of the heights within it — a tape laid anywhere there reads the
    same to 0.5 %, and the middle is the level least far from all of them."""
    best = float(g.max() if widest else g.min())
    near = zs[np.abs(g - best) <= PLATEAU * abs(best)]
    if float(near.max() - near.min()) > PLATEAU_SPAN:
        return 0.5 * float(near.min() + near.max())
    return float(zs[np.argmax(g) if widest else np.argmin(g)])


def kneecap(zs: Array, front: Array, lo: float, hi: float, H: float) -> float | None:
    """The kneecap's most anterior point (ISO 8559-1 knee girth: at the mid-patella): the height
    where the leg's front profile ``front`` (its most forward reach, −y, at the heights ``zs``)
    stands furthest in front of the straight line joining the front at ``lo`` (the shin, at the
    calf) and at ``hi`` (the thigh, :data:`KNEE_REACH`); None if it stands less than
    :data:`KNEECAP_MIN` of the stature ``H`` in front of it (a straight leg: no kneecap)."""
    sel = (zs >= lo) & (zs <= hi)
    if sel.sum() < 3:
        return None
    z, f = zs[sel], front[sel]
    chord = f[0] + (z - z[0]) * (f[-1] - f[0]) / (z[-1] - z[0])
    k = int(np.argmax(f - chord))
    return float(z[k]) if f[k] - chord[k] >= KNEECAP_MIN * H else None


def narrowing_below(zs: Array, g: Array) -> float | None:
    """The narrowing under the knee: going down from the top of ``zs`` (the kneecap), the
    narrowest girth ``g`` before the girth grows again by more than :data:`PLATEAU` of it (into
    the calf); None if it never does (a leg tapering from the knee down to the ankle)."""
    k_min = len(zs) - 1
    for k in range(len(zs) - 1, -1, -1):
        if g[k] < g[k_min]:
            k_min = k
        elif g[k] > (1.0 + PLATEAU) * g[k_min]:
            return float(zs[k_min])
    return None


def leg_levels(v: Array, t: IArray, crotch: float, H: float, side: float = 1.0) -> dict[str, float]:
    """Left leg (+x; ``side`` −1: the right leg), from its horizontal sections every 0.5 % of
    the stature (tape girth and front profile):

    * knee: the kneecap (:func:`kneecap`, ISO 8559-1 mid-patella), looked for from the widest
      girth under the proportional knee height :data:`~.limbs.KNEE_HEIGHT` × stature (above
      12 % of the stature: the calf's range) up :data:`KNEE_REACH` of the way to the crotch;
    * calf: the widest girth (ISO 8559-1 calf girth: the maximum girth of the lower leg)
      between 12 % of the stature and the narrowing under the knee (:func:`narrowing_below`);
      a leg without one, its girth falling all the way from the knee to the ankle (a thin
      leg without a calf bulge), has its calf :data:`CALF_SHARE` of the way from the ankle to
      the knee;
    * ankle: the narrowest girth between 3 % of the stature and 3 % under the calf (ISO
      8559-1: the minimum girth above the malleoli);
    * thigh: 3.5 % of the stature under the crotch.

    Narrowest and widest girths follow :func:`extreme` (the middle of a plateau).

    A leg without a kneecap — straight from thigh to ankle, as the human mannequin's lofted leg
    (knee girth 0.37 m over a 0.35 m calf) — has nothing to mark the knee: the knee is then the
    proportional height, and the calf :data:`CALF_SHARE` of the way up to it. (The
    stature is the body's top above the floor: on a headless scan the proportional height falls
    short.)"""
    zl = np.arange(0.02 * H, crotch - 0.01 * H, 0.005 * H)
    leg, fwd = {}, {}
    for z in zl:
        mine = [o for o in outlines(v, t, z) if min(side * o.xmin, side * o.xmax) > -0.02
                and side * o.points[:, 0].mean() > 0]  # fmt: skip
        if mine:  # the largest: the leg, not a hand
            leg[float(z)] = sec.tape_girth(mine[0].points)
            fwd[float(z)] = float(-mine[0].points[:, 1].min())
    zk = sorted(leg)

    def within(lo: float, hi: float) -> Array:
        c = [z for z in zk if lo <= z <= hi]
        if not c:
            raise ScanError(f"no leg section between {lo:.3f} and {hi:.3f} m")
        return np.array(c)

    def girths(zs: Array) -> Array:
        return np.array([leg[float(z)] for z in zs])

    z_knee = KNEE_HEIGHT * H
    calf_range = within(0.12 * H, z_knee - 0.02 * H)
    calf = extreme(calf_range, girths(calf_range), widest=True)
    zs = np.array(zk)
    knee = kneecap(zs, np.array([fwd[z] for z in zk]), calf, calf + KNEE_REACH * (crotch - calf), H)
    bulge = False
    if knee is None or knee <= calf + 0.01 * H:
        knee = z_knee
    else:
        below = within(0.12 * H, knee)
        narrow = narrowing_below(below, girths(below))
        if narrow is not None and narrow > 0.12 * H + 0.02 * H:
            calf_range, bulge = within(0.12 * H, narrow), True
    calf = extreme(calf_range, girths(calf_range), widest=True)
    ankle_range = within(0.03 * H, calf - 0.03 * H)
    ankle = extreme(ankle_range, girths(ankle_range), widest=False)
    if not bulge:  # no calf maximum under the knee: the calf's usual share of ankle to knee
        calf = ankle + CALF_SHARE * (knee - ankle)
    return {"ankle": ankle, "calf": calf, "knee": knee, "thigh": crotch - 0.035 * H}


def check_order(marks: dict[str, float]) -> None:
    """Landmark heights must increase from ankle to neck (detected or overridden)."""
    order = [k for k in (*LEG_LEVELS, *TORSO_LEVELS) if k in marks]
    z = [marks[k] for k in order]
    bad = [f"{a} {za:.3f} ≥ {b} {zb:.3f}" for (a, za), (b, zb)
           in zip(zip(order, z, strict=True), zip(order[1:], z[1:], strict=True), strict=False)
           if zb <= za]  # fmt: skip
    if bad:
        raise ScanError(
            "landmark heights out of order: " + "; ".join(bad),
            "set them in [body.landmarks] (metres above the floor)",
        )


def _surface_top(v: Array, t: IArray, x: float, y: float) -> float | None:
    """Highest z where the vertical line through (x, y) meets the surface."""
    p = v[t]
    a, b, c = p[:, 0], p[:, 1], p[:, 2]
    d = (b[:, 1] - c[:, 1]) * (a[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (a[:, 1] - c[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):  # vertical triangles: d = 0, no hit
        l1 = ((b[:, 1] - c[:, 1]) * (x - c[:, 0]) + (c[:, 0] - b[:, 0]) * (y - c[:, 1])) / d
        l2 = ((c[:, 1] - a[:, 1]) * (x - c[:, 0]) + (a[:, 0] - c[:, 0]) * (y - c[:, 1])) / d
        l3 = 1.0 - l1 - l2
        hit = (l1 >= 0) & (l2 >= 0) & (l3 >= 0) & np.isfinite(l1) & np.isfinite(l2)
        if not hit.any():
            return None
        z = l1 * a[:, 2] + l2 * b[:, 2] + l3 * c[:, 2]
    return float(z[hit].max())


def body_parts(
    v: Array, t: IArray, marks: dict[str, float], cut: dict[str, float]
) -> npt.NDArray[np.int32]:
    """Part number (:data:`PARTS`) per triangle: arms beyond the arm cuts (connected to the most
    lateral point), legs below the crotch, head above the jaw, torso the rest."""
    c = v[t].mean(axis=1)
    part = np.full(len(t), PARTS["torso"], dtype=np.int32)
    if "head" in marks:
        part[c[:, 2] >= marks["head"]] = PARTS["head"]
    low = c[:, 2] < marks["crotch"]
    part[low & (c[:, 0] >= 0)] = PARTS["leg_left"]
    part[low & (c[:, 0] < 0)] = PARTS["leg_right"]
    for side, sgn in (("left", 1.0), ("right", -1.0)):
        if side not in cut:
            continue
        beyond = sgn * c[:, 0] > sgn * cut[side]
        idx = np.flatnonzero(beyond)
        if not len(idx):
            continue
        lab = _components_of(t, idx)
        tip = int(np.argmax(sgn * c[idx, 0]))
        part[idx[lab == lab[tip]]] = PARTS[f"arm_{side}"]
    return part


def _components_of(t: IArray, idx: IArray) -> IArray:
    """Edge-connected component labels of the triangle subset ``t[idx]``."""
    sub = t[idx]
    und = np.sort(np.concatenate([sub[:, [0, 1]], sub[:, [1, 2]], sub[:, [2, 0]]]), axis=1)
    n = int(und.max()) + 1
    key = und[:, 0].astype(np.int64) * n + und[:, 1]
    _, e = np.unique(key, return_inverse=True)
    m = len(sub)
    g = coo_matrix((np.ones(3 * m), (np.tile(np.arange(m), 3), e.ravel())))
    _, lab = connected_components(g @ g.T, directed=False)
    return lab
