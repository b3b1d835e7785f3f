"""The human mannequin: the parametric torso and legs with two arms in an A-pose, a neck and a head.

Built from the same :class:`~.measurements.Measurements` as the dress form (:mod:`.mannequin`),
fused by OpenCASCADE into one closed solid and meshed by gmsh, then **segmented like a body
scan** (:func:`~.anatomy.analyse`): torso, arms, legs and head, the landmarks, the arm roots and
the regions all come from the geometry, so a gilet's armholes go round the arm roots and a
sleeve follows the arm as on a scan. Construction (metres; +z up, facing −y, left = +x):

* **Torso and legs**: the mannequin's sections (:func:`~.mannequin.torso_sections`,
  :func:`~.mannequin.leg_sections`), the neck carried up into the head.
* **Arms**: the axis starts at the shoulder joint J, ``SHOULDER_JOINT_DROP`` below the acromion
  (x = ±shoulder_width / 2), hangs ``Pose.abduction`` out from the vertical in the frontal plane
  for ``upper_arm_length`` to the elbow, bends forward by ``Pose.elbow_flexion`` and runs
  ``forearm_length`` to the wrist and ``hand_length`` to the finger tips. Sections normal to the
  axis, each scaled to its girth: a root section inside the torso, the upper arm half-way
  between J and the elbow (ISO 8559-1), the elbow (in the plane bisecting the bend: upper arm
  and forearm are two lofts sharing it, a mitre joint, :func:`arm_sections`), the forearm
  half-way with guide sections half-way on either side, the wrist, and three sections of a
  flat hand (palms turned to the thighs).
* **Head**: an ellipsoid whose horizontal girth at its widest is ``head_girth``, its crown at
  the stature, breadth / length ``HEAD_ASPECT``, height ``2 HEAD_SEMI_HEIGHT`` × stature.

The arms meet the torso in a crease and the elbow is a mitre: gmsh/OCC's fillet failed on both
("Could not compute fillet": on the crossing elbow lofts of an earlier version at 5 mm – 2 cm,
on the curves of the arm-root seam picked near the chest wall at 3 mm and 1 cm). There are no
feet (the legs end 3 cm below the ankle level, as the dress form's). Bad measurements (an arm
too thick for the shoulder or too little abduction, hands on the hips, a head smaller than the
neck) raise a one-line :class:`~.errors.GeometryError` before gmsh runs; gmsh's own failures
become one too, and gmsh runs under :data:`~.gmsh_utils.GMSH_TIME_LIMIT`.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise

import numpy as np
import numpy.typing as npt

from . import sections as sec
from .body import BodySurface
from .errors import GeometryError
from .gmsh_utils import GMSH_TIME_LIMIT, gmsh_session, time_limit
from .mannequin import (
    MeshSizes,
    _size_field,
    _surface_arrays,
    add_loft,
    leg_sections,
    ring_wire,
    torso_sections,
)
from .measurements import Measurements, measurements
from .sections import SectionShape

Array = npt.NDArray[np.float64]

#: the shoulder joint (the centre of the humeral head) below the acromion [m]: our estimate
SHOULDER_JOINT_DROP = 0.04
#: the shoulder joint inside the acromion [m] (the arm's axis starts medial to its outer edge)
SHOULDER_JOINT_INSET = 0.015
#: head breadth / head length (a cephalic index of 0.78: our round number, mid-range of the
#: "mesocephalic" 0.75–0.80 class)
HEAD_ASPECT = 0.78
#: half the height of the head ellipsoid over the stature (0.1 m at 1.68 m: our estimate)
HEAD_SEMI_HEIGHT = 0.06
#: the head's centre in front of the neck's [m] (the face forward of the spine: our estimate)
HEAD_FORWARD = 0.01
#: the neck is carried this far [m] above the neck level, into the head
NECK_INTO_HEAD = 0.06
#: the shoulder section of the human's torso: (half width beyond the acromion [m], front and
#: back depth [m], superellipse exponent). Deeper and boxier than the dress form's (0.012,
#: 0.055, 0.065, 2.4; mannequin.torso_sections), whose shoulder ends in a thin edge where the
#: arm's root has to fit (our estimates, not data)
HUMAN_SHOULDER = (0.012, 0.065, 0.070, 3.0)
#: the arm lofts' degree cap across their sections (mannequin.loft_rings): with OCC's default a
#: loft through the 8 unevenly spaced sections of a whole arm overshot 0.2 m forward of the
#: shoulder (measured at 2 cm elements: y from −0.235 m; with 3, −0.134 m, the hand's edge)
ARM_LOFT_DEGREE = 3
#: the arm's root section may reach this far [m] out of the torso's sections (linear between
#: them: the loft bulges a little beyond that stand-in) before the measurements are refused
ROOT_SLACK = 0.005
#: points per arm section of the loft
ARM_RING_POINTS = 24


@dataclass(frozen=True)
class Pose:
    """The arms' pose [degrees]: ``abduction`` of the upper arm from the vertical in the frontal
    plane (an A-pose; the MakeHuman base mesh's is 43°, tests/test_scan_makehuman.py), and the
    forward ``elbow_flexion`` of the forearm (the limb analysis finds the elbow as the arm's
    sharpest bend, :mod:`.limbs`; a straight arm has none)."""

    abduction: float = 40.0
    elbow_flexion: float = 15.0

    def __post_init__(self) -> None:
        if not 20.0 <= self.abduction <= 80.0:
            raise GeometryError(f"arm abduction must be 20–80° from the vertical, got "
                                f"{self.abduction:g}°")  # fmt: skip
        if not 5.0 <= self.elbow_flexion <= 60.0:
            raise GeometryError(f"elbow flexion must be 5–60°, got {self.elbow_flexion:g}°")


@dataclass(frozen=True)
class ArmSection:
    """One section of an arm: ``s`` along the axis from the shoulder joint [m] on the ``upper``
    arm's or the ``fore`` arm's straight line, tape ``girth`` [m], ``aspect`` = depth
    (front–back) / width, superellipse ``exponent``."""

    name: str
    segment: str
    s: float
    girth: float
    aspect: float = 1.0
    exponent: float = 2.0


def arm_sections(m: Measurements, pose: Pose) -> list[ArmSection]:
    """The arm's sections, root to finger tips, in two lofts that share the elbow's section: an
    ellipse in the plane bisecting the bend (the cut of a round arm by it), its perimeter the
    elbow girth. The union is a mitre joint: the bend sits at the elbow (one loft through the
    bend spread it, and :mod:`.limbs` found the sharpest bend 6.5 cm above the elbow section;
    two lofts crossing each other left millimetre-long edges and 2° slivers at the elbow).
    Guide sections half-way between elbow, forearm and wrist (girths and aspects the means of
    their neighbours) space the forearm's sections as evenly as the hand's: the loft is
    parametrised by section number, and with 12 cm gaps before 4–7 cm ones it bulged 8 % below
    the elbow. The hand's sections: our estimates of an adult woman's flat hand (palm 19 cm round,
    3.5 : 1 across; the fingers 17 cm; the tips 11 cm)."""
    lu, lf, lh = m.upper_arm_length, m.forearm_length, m.hand_length
    w = lu + lf
    k = 1.0 / np.cos(0.5 * np.radians(pose.elbow_flexion))
    return [
        ArmSection("root", "upper", -0.01, 0.85 * m.upper_arm_girth),
        ArmSection("upper_arm", "upper", 0.5 * lu, m.upper_arm_girth),
        ArmSection("elbow", "mitre", lu, m.elbow_girth, k),
        ArmSection(
            "forearm_upper", "fore", lu + 0.25 * lf, _mean(m.elbow_girth, m.forearm_girth), 1.05
        ),
        ArmSection("forearm", "fore", lu + 0.5 * lf, m.forearm_girth, 1.1),
        ArmSection(
            "forearm_lower", "fore", lu + 0.75 * lf, _mean(m.forearm_girth, m.wrist_girth), 1.18
        ),
        ArmSection("wrist", "fore", w, m.wrist_girth, 1.25),
        ArmSection("palm", "fore", w + 0.4 * lh, 0.19, 3.5, 2.4),
        ArmSection("fingers", "fore", w + 0.75 * lh, 0.17, 3.5, 2.4),
        ArmSection("tips", "fore", w + 0.97 * lh, 0.11, 2.5, 2.2),
    ]


def _mean(a: float, b: float) -> float:
    return 0.5 * (a + b)


@dataclass(frozen=True)
class ArmAxis:
    """The axis of one arm: joint J, elbow E, unit directions of upper arm and forearm."""

    joint: Array
    elbow: Array
    upper: Array
    fore: Array

    def at(self, s: float, segment: str) -> tuple[Array, Array]:
        """Point and unit normal of the section plane at ``s`` from the joint on the ``upper``
        arm's line, the ``fore`` arm's, or the elbow's ``mitre`` (the bisecting plane)."""
        if segment == "upper":
            return self.joint + s * self.upper, self.upper
        if segment == "mitre":
            t = self.upper + self.fore
            return self.elbow, t / np.linalg.norm(t)
        lu = float(np.linalg.norm(self.elbow - self.joint))
        return self.elbow + (s - lu) * self.fore, self.fore


def arm_axis(m: Measurements, pose: Pose, side: int) -> ArmAxis:
    """The left (side = +1) or right (−1) arm's axis (module doc)."""
    a, f = np.radians(pose.abduction), np.radians(pose.elbow_flexion)
    joint = np.array(
        [side * (0.5 * m.shoulder_width - SHOULDER_JOINT_INSET), 0.0,
         m.height("shoulder") - SHOULDER_JOINT_DROP]
    )  # fmt: skip
    upper = np.array([side * np.sin(a), 0.0, -np.cos(a)])
    fore = np.cos(f) * upper + np.sin(f) * np.array([0.0, -1.0, 0.0])  # forward is −y
    return ArmAxis(joint, joint + m.upper_arm_length * upper, upper, fore)


def arm_rings(m: Measurements, pose: Pose, side: int) -> dict[str, Array]:
    """3-D rings of one arm's sections (name -> (ARM_RING_POINTS, 3)), each in the plane
    normal to its line, its depth along the horizontal front–back direction projected (at the
    elbow's mitre the width is along the bend's axis, the same direction for both lines)."""
    axis = arm_axis(m, pose, side)
    out = {}
    for a in arm_sections(m, pose):
        c, t = axis.at(a.s, a.segment)
        ey = np.array([0.0, 1.0, 0.0]) - t[1] * t
        ey /= np.linalg.norm(ey)
        ew = np.cross(ey, t)
        shape = SectionShape(1.0, a.aspect, a.aspect, a.exponent)
        pts = shape.points(720, shape.scale_for_girth(a.girth))
        p = sec.resample_by_angle(pts, ARM_RING_POINTS, centre=np.zeros(2))
        out[a.name] = c + p[:, :1] * ew + p[:, 1:] * ey
    return out


def arm_lofts(m: Measurements, pose: Pose, side: int) -> list[list[Array]]:
    """The rings of the upper arm's loft and of the forearm's (with the hand); the elbow's
    ring ends the first and starts the second."""
    rings = arm_rings(m, pose, side)
    segs = {a.name: a.segment for a in arm_sections(m, pose)}
    upper = [r for n, r in rings.items() if segs[n] in ("upper", "mitre")]
    fore = [r for n, r in rings.items() if segs[n] in ("mitre", "fore")]
    return [upper, fore]


def _add_arm(g, m: Measurements, pose: Pose, side: int) -> list[tuple[int, int]]:
    """The two lofts of an arm, through one shared OCC wire at the elbow."""
    upper, fore = arm_lofts(m, pose, side)
    wires = [ring_wire(g, r) for r in upper]
    elbow = wires[-1]
    wires_fore = [elbow] + [ring_wire(g, r) for r in fore[1:]]
    out = []
    for ws in (wires, wires_fore):
        out += g.model.occ.addThruSections(ws, makeSolid=True, makeRuled=False,
                                           maxDegree=ARM_LOFT_DEGREE)  # fmt: skip
    return out


@dataclass(frozen=True)
class Head:
    """The head ellipsoid: centre and semi-axes (x: breadth, y: length, z: height) [m]."""

    centre: tuple[float, float, float]
    axes: tuple[float, float, float]

    def inside(self, p: Array, margin: float = 0.0) -> npt.NDArray[np.bool_]:
        """Points at least ``margin`` (approximately) inside the ellipsoid."""
        a = np.asarray(self.axes) - margin
        q = (np.atleast_2d(p) - np.asarray(self.centre)) / a
        return np.einsum("ij,ij->i", q, q) < 1.0


def head(m: Measurements) -> Head:
    """The head ellipsoid of ``m`` (module doc)."""
    shape = SectionShape(HEAD_ASPECT, 1.0, 1.0, 2.0)
    k = shape.scale_for_girth(m.head_girth)
    c = HEAD_SEMI_HEIGHT * m.stature
    return Head((0.0, -HEAD_FORWARD, m.stature - c), (HEAD_ASPECT * k, k, c))


def human_torso_sections(m: Measurements) -> dict[str, tuple[float, Array]]:
    """The mannequin's torso sections, the shoulder one deeper (:data:`HUMAN_SHOULDER`) and the
    top one moved up into the head."""
    secs = torso_sections(m)
    z_sh = secs["shoulder"][0]
    hw, front, back, n = HUMAN_SHOULDER
    secs["shoulder"] = (z_sh, SectionShape(0.5 * m.shoulder_width + hw, front, back, n).points(720))
    z_top = m.height("neck") + NECK_INTO_HEAD
    secs["neck_top"] = (z_top, secs["neck"][1])
    return secs


# ---------------------------------------------------------------------------------------------
# Checks of the measurements before gmsh runs (one-line GeometryError instead of a bad solid)
# ---------------------------------------------------------------------------------------------


def _torso_levels(secs: dict[str, tuple[float, Array]]) -> list[tuple[float, Array]]:
    """The loft's sections, each resampled on 180 rays from its centre (once: the checks ask
    for many heights, and resampling every level per point cost 2.6 s a check)."""
    return [(z, sec.resample_by_angle(p, 180, centre=p.mean(axis=0))) for z, p in secs.values()]


def _torso_polygon(levels: list[tuple[float, Array]], z: float) -> Array | None:
    """The torso section at ``z``, linear between the loft's resampled sections (a close
    stand-in for the loft), or None outside them."""
    for (z0, a), (z1, b) in pairwise(levels):
        if z0 <= z <= z1:
            w = (z - z0) / (z1 - z0)
            return (1 - w) * a + w * b
    return None


def _inside_torso(levels: list[tuple[float, Array]], pts: Array) -> npt.NDArray[np.bool_]:
    out = np.zeros(len(pts), bool)
    for i, p in enumerate(pts):
        poly = _torso_polygon(levels, float(p[2]))
        out[i] = poly is not None and bool(sec.contains(poly, p[None, :2])[0])
    return out


def check_human(m: Measurements, pose: Pose) -> None:
    """Refuse measurements the construction cannot build (module doc), before gmsh runs."""
    torso = human_torso_sections(m)
    levels = _torso_levels(torso)
    rings = arm_rings(m, pose, +1)
    root = rings["root"]
    c = root.mean(axis=0)
    r = np.linalg.norm(root - c, axis=1)[:, None]
    if not _inside_torso(levels, c + (root - c) * np.maximum(1.0 - ROOT_SLACK / r, 0.0)).all():
        raise GeometryError(
            f"the arm root does not fit inside the shoulder: upper_arm_girth "
            f"{m.upper_arm_girth:.3g} m is too large for shoulder_width {m.shoulder_width:.3g} m "
            f"and the chest at {pose.abduction:g}° abduction (give a smaller upper-arm girth, a "
            "wider shoulder or more abduction)"
        )
    for name in ("forearm", "wrist", "palm", "fingers", "tips"):
        if _inside_torso(levels, rings[name]).any():
            raise GeometryError(
                f"the {name} touches the torso: raise the arm abduction ({pose.abduction:g}°) "
                "or give smaller arm girths"
            )
    hd = head(m)
    z_top, neck = torso["neck_top"]
    top = np.column_stack([neck, np.full(len(neck), z_top)])
    if not hd.inside(top, margin=0.003).all():
        raise GeometryError(
            f"the neck does not fit inside the head: head_girth {m.head_girth:.3g} m is too "
            f"small for neck_girth {m.neck_girth:.3g} m"
        )
    if hd.centre[2] - hd.axes[2] <= m.height("neck"):
        raise GeometryError("the head reaches below the neck level: check stature and heights")


# ---------------------------------------------------------------------------------------------
# Build
# ---------------------------------------------------------------------------------------------


def human_surface(
    m: Measurements | None = None, sizes: MeshSizes | None = None, pose: Pose | None = None
) -> tuple[Array, npt.NDArray[np.int64]]:
    """Vertices and triangles of the human (module doc), one closed surface, not yet
    segmented. Runs gmsh in this process under :data:`~.gmsh_utils.GMSH_TIME_LIMIT`."""
    m = m or measurements()
    sizes = sizes or MeshSizes()
    pose = pose or Pose()
    check_human(m, pose)
    with time_limit(GMSH_TIME_LIMIT, "the human body"), gmsh_session(name="human") as g:
        try:
            _fuse_human(g, m, pose)
            _size_field(g, sizes)
            g.option.setNumber("Mesh.Algorithm", 6)
            g.model.mesh.generate(2)
        except Exception as e:  # gmsh raises a bare Exception with its last error
            first = (str(e).strip().splitlines() or [type(e).__name__])[0]
            raise GeometryError(f"gmsh could not build the human body: {first}") from e
        return _surface_arrays(g, 1)


def _fuse_human(g, m: Measurements, pose: Pose) -> None:
    """Loft torso, legs and arms, add the head, fuse them into one volume."""
    occ = g.model.occ
    parts = add_loft(g, human_torso_sections(m))
    for side in (+1, -1):
        parts += add_loft(g, leg_sections(m, side))
        parts += _add_arm(g, m, pose, side)
    hd = head(m)
    ball = occ.addSphere(*hd.centre, 1.0)
    occ.dilate([(3, ball)], *hd.centre, *hd.axes)
    vols = [(3, t) for d, t in parts if d == 3] + [(3, ball)]
    out, _ = occ.fuse(vols[:1], vols[1:])
    occ.synchronize()
    if len([dt for dt in out if dt[0] == 3]) != 1:
        raise GeometryError(f"the human body's parts fused into {len(out)} pieces, not one")


def make_human(
    m: Measurements | None = None,
    sizes: MeshSizes | None = None,
    pose: Pose | None = None,
    landmarks: dict[str, float] | None = None,
) -> BodySurface:
    """The human mannequin, meshed and segmented as a scan is (module doc).

    Args:
        m: body measurements (default size 88); arm and head fields included.
        sizes: element sizes (:class:`~.mannequin.MeshSizes`; curvature keeps 24 per turn on
            the arms).
        pose: the arms' pose.
        landmarks: heights [m] replacing detected landmark levels (as for a scan).
    """
    from .anatomy import analyse
    from .errors import ScanError
    from .scan import segmented_body

    m = m or measurements()
    v, t = human_surface(m, sizes, pose)
    try:
        anat = analyse(v, t, landmarks)
    except ScanError as e:
        raise GeometryError(f"the human body could not be segmented: {e}") from e
    return segmented_body(v, t, anat, m)
