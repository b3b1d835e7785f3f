"""A parametric dress-form mannequin (torso, neck and legs; no arms, no head) lofted in gmsh/OCC.

Each landmark level gets a horizontal section: a superellipse with its own width, front depth
and back depth (:class:`~.sections.SectionShape`), scaled so that its perimeter is the requested
tape girth. OpenCASCADE's ``ThruSections`` lofts a smooth solid through the sections; a loft
interpolates its sections, so the surface passes exactly through each landmark curve and the
girth there is the requested one (up to the mesh's chord error, ≈ h²/(24 r²) relatively).
Legs are lofted separately and fused with the torso.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import BSpline

from .body import BodySurface, finish_body
from .gmsh_utils import gmsh_session
from .measurements import Measurements, measurements
from .sections import SectionShape

# Section proportions per level: (half width, front depth, back depth, superellipse exponent).
# Only ratios matter for girth levels. Our own estimates of a dress form's shape (not data).
TORSO_SHAPES: dict[str, tuple[float, float, float, float]] = {
    "crotch": (0.165, 0.095, 0.125, 2.3),
    "hip": (0.175, 0.100, 0.140, 2.3),
    "abdomen": (0.160, 0.110, 0.115, 2.3),
    "waist": (0.135, 0.092, 0.090, 2.3),
    "underbust": (0.140, 0.088, 0.092, 2.4),
    "bust": (0.155, 0.125, 0.092, 2.2),
    "upper_chest": (0.155, 0.095, 0.095, 2.5),
    "neck_base": (0.060, 0.055, 0.055, 2.0),
    "neck": (0.055, 0.055, 0.055, 2.0),
}
LEG_SHAPES: dict[str, tuple[float, float, float, float]] = {
    "ankle": (0.030, 0.034, 0.036, 2.0),
    "calf": (0.050, 0.050, 0.062, 2.0),
    "knee": (0.052, 0.056, 0.052, 2.2),
    "thigh": (0.080, 0.095, 0.098, 2.1),
}
# Girths of the levels that are not measurements, relative to measured ones (estimates).
DERIVED_GIRTHS = {
    "crotch": ("hip_girth", 0.90),
    "abdomen": None,  # mean of waist and hip
    "upper_chest": ("bust_girth", 0.97),
    "neck_base": ("neck_girth", 1.12),
}
LEG_CENTRE_X = {"ankle": 0.070, "calf": 0.075, "knee": 0.078, "thigh": 0.090}  # at size 88


@dataclass(frozen=True)
class MeshSizes:
    """Target element sizes (m): ``fine`` inside ``band`` = (z_min, z_max), ``coarse`` outside.

    ``per_circle`` caps the size by curvature (gmsh's MeshSizeFromCurvature: elements per 2π
    of turning): a polygon of n sides around a circle is short by ≈ π²/(6n²) of its
    perimeter, so n = 24 keeps girths of thin limbs within 0.3 % at any target size.
    """

    coarse: float = 0.03
    fine: float = 0.015
    band: tuple[float, float] | None = None
    per_circle: int = 24


def torso_sections(m: Measurements) -> dict[str, tuple[float, np.ndarray]]:
    """Height and (x, y) curve of every torso level, each scaled to its girth."""
    out: dict[str, tuple[float, np.ndarray]] = {}
    for level, (hw, f, b, n) in TORSO_SHAPES.items():
        shape = SectionShape(hw, f, b, n)
        g = _girth(m, level)
        out[level] = (m.height(level), shape.points(720, shape.scale_for_girth(g)))
    # the shoulder line is set by the biacromial breadth, not a girth
    sh = SectionShape(m.shoulder_width / 2 + 0.012, 0.055, 0.065, 2.4)
    out["shoulder"] = (m.height("shoulder"), sh.points(720))
    top = m.height("neck") + 0.035
    out["neck_top"] = (top, out["neck"][1])
    order = ["crotch", "hip", "abdomen", "waist", "underbust", "bust", "upper_chest"]
    order += ["shoulder", "neck_base", "neck", "neck_top"]
    return {k: out[k] for k in order}


def leg_sections(m: Measurements, side: int) -> dict[str, tuple[float, np.ndarray]]:
    """Sections of the left (side=+1, +x) or right (side=−1) leg, ankle to crotch."""
    k = m.hip_girth / 0.96
    out: dict[str, tuple[float, np.ndarray]] = {}
    for level, params in LEG_SHAPES.items():
        shape = SectionShape(*params)  # scaled about its own centre, then moved sideways
        pts = shape.points(720, shape.scale_for_girth(getattr(m, f"{level}_girth")))
        out[level] = (m.height(level), pts + np.array([side * LEG_CENTRE_X[level] * k, 0.0]))
    z0 = m.height("ankle") - 0.03
    bottom = out["ankle"][1]
    top_z = m.height("crotch") + 0.05
    th = out["thigh"][1]
    cx = th[:, 0].mean()
    top = (th - [cx, 0.0]) * 0.8 + [side * 0.085 * k, 0.0]
    return {"ankle_bottom": (z0, bottom), **out, "top": (top_z, top)}


def _girth(m: Measurements, level: str) -> float:
    g = m.girth(level)
    if g is not None:
        return g
    if level == "abdomen":
        return 0.5 * (m.waist_girth + m.hip_girth)
    name, ratio = DERIVED_GIRTHS[level]  # type: ignore[misc]
    return ratio * getattr(m, name)


def add_loft(
    g,
    secs: dict[str, tuple[float, np.ndarray]],
    n_pts: int = 24,
    solid: bool = True,
    max_degree: int = -1,
    guide: float = 0.0,
    guide_top: float = np.inf,
):
    """OCC loft through closed sections; each wire is a back half and a front half.

    ``max_degree`` caps the degree of the loft surface across the sections (−1: OCC's default).
    With OCC's default the dress's flared skirt (sections 15 cm apart below a narrow waist)
    overshoots into a fold that crosses the garment's axis near the hem: the dress uses 3.

    ``guide`` > 0 [m]: rings are added between the sections, at most ``guide`` apart, on a
    shape-preserving (monotone, PCHIP) interpolation of the sections' points in height
    (:func:`guide_rings`), so that the loft cannot overshoot between unevenly spaced sections;
    only between sections at or below ``guide_top`` [m] (the dress: its skirt).

    The halves meet at the lateral points (+x and −x), so an open loft yields two faces
    (back first, then front) sharing the side lines; returns the OCC entities made. The halves
    are the two pieces of one periodic spline (:func:`ring_wire`), so the surface is smooth
    across the side lines.
    """
    from .sections import resample_by_angle

    rings = []
    for z, pts in secs.values():
        p = resample_by_angle(pts, n_pts, centre=pts.mean(axis=0))
        rings.append(np.column_stack([p, np.full(n_pts, z)]))
    if guide > 0:
        rings = guide_rings(rings, guide, guide_top)
    return loft_rings(g, rings, solid, max_degree)


def guide_rings(rings: list[np.ndarray], spacing: float, top: float = np.inf) -> list[np.ndarray]:
    """``rings`` (horizontal, bottom to top, the same number of points from the same angle)
    with rings added between them (between those at or below ``top`` [m] only) at most
    ``spacing`` apart in height, their points on the
    monotone piecewise-cubic (PCHIP) interpolation in height of each point's x and y.

    A loft is a spline through its sections: between sections unevenly spaced in height it
    overshoots, as a polynomial does. The scan gilet of MakeHuman's short, heavy, old woman
    (sections 1.4 cm apart at under-bust and bust, 10 cm at hip and abdomen) had its front
    dip 6.7 cm inside the belly between hip and abdomen, and come 2 cm out in front of the
    abdomen above it; on the PCHIP rings no point leaves the range of its neighbouring
    sections."""
    from scipy.interpolate import PchipInterpolator

    z = np.array([r[0, 2] for r in rings])
    if len(rings) < 3 or np.any(np.diff(z) <= 0):
        return rings
    xy = np.stack([r[:, :2] for r in rings])  # (levels, points, 2)
    f = PchipInterpolator(z, xy, axis=0)
    out = []
    for z0, z1, ring in zip(z[:-1], z[1:], rings[:-1], strict=True):
        out.append(ring)
        n = int(np.ceil((z1 - z0) / spacing)) if z1 <= top else 1
        for zk in z0 + (z1 - z0) * np.arange(1, n) / n:
            out.append(np.column_stack([f(zk), np.full(len(ring), zk)]))
    return [*out, rings[-1]]


def loft_rings(g, rings: list[np.ndarray], solid: bool = True, max_degree: int = -1):
    """OCC loft through closed 3-D rings ((n, 3) points each, n even, the same start and turning
    sense on every ring), each wire made by :func:`ring_wire`. Sections need not be horizontal:
    the human's arms are lofted through rings normal to their own axis (:mod:`.human`). Returns
    the OCC entities made."""
    wires = [ring_wire(g, ring) for ring in rings]
    return g.model.occ.addThruSections(
        wires, makeSolid=solid, makeRuled=False, maxDegree=max_degree
    )


def ring_wire(g, ring: np.ndarray) -> int:
    """A closed wire through the ring of points ``ring`` (n, 3), n even: the periodic cubic
    B-spline interpolating them (uniform knots) as two clamped pieces meeting at points 0 and
    n/2 — for a horizontal section resampled by angle, the lateral points +x and −x, so a back
    half (+x → +y → −x) and a front half (−x → −y → +x). Returns the wire.

    The pieces are exact restrictions of one C² curve (:func:`periodic_halves`), so the section
    has one tangent and one curvature at the side lines. Two splines interpolating the halves
    separately met at a kink, 9.7° at the size-88 waist and 12.5° at the underbust: a garment in
    hoop tension T over a kink of angle θ carries a line force Tθ, and the pressure at the sides
    grew without limit as the garment mesh was refined (waist p95 +5–6 % per √2 level).
    """
    occ = g.model.occ
    ends = [occ.addPoint(*ring[0]), occ.addPoint(*ring[len(ring) // 2])]  # shared by the halves
    curves = []
    for k, (ctrl, knots) in enumerate(periodic_halves(ring)):
        inner = [occ.addPoint(*c) for c in ctrl[1:-1]]
        tags = [ends[k], *inner, ends[1 - k]]
        mult = [4] + [1] * (len(knots) - 2) + [4]
        curves.append(occ.addBSpline(tags, degree=3, knots=knots.tolist(), multiplicities=mult))
        occ.remove([(0, t) for t in inner])
    return occ.addWire(curves)


def periodic_halves(p: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """The periodic cubic B-spline through the closed polygon ``p`` (n, d), node i at knot i,
    split at knots 0 and n/2: per half its control points and distinct knots (clamped ends).

    The control points Q solve (Q_{i−1} + 4 Q_i + Q_{i+1}) / 6 = p_i (cyclic); each half is cut
    out by raising its end knots to multiplicity 3 (Boehm insertion: the curve is unchanged).
    """
    n = len(p)
    if n % 2:
        raise ValueError(f"a section needs an even number of points, not {n}")
    a = (4.0 * np.eye(n) + np.roll(np.eye(n), 1, axis=1) + np.roll(np.eye(n), -1, axis=1)) / 6
    q = np.linalg.solve(a, p)
    t = np.arange(-3.0, n + 4.0)
    curve = BSpline(t, q[np.arange(-1, n + 2) % n], 3)
    halves = []
    for lo, hi in ((0.0, n / 2), (n / 2, float(n))):
        c = curve.insert_knot(lo, 2).insert_knot(hi, 2)
        i_lo, i_hi = np.searchsorted(c.t, lo), np.searchsorted(c.t, hi)
        halves.append((c.c[i_lo - 1 : i_hi], np.arange(lo, hi + 0.5)))
    return halves


def make_mannequin(
    m: Measurements | None = None,
    sizes: MeshSizes | None = None,
    z_range: tuple[float, float] | None = None,
    legs: bool = True,
    order: int = 1,
) -> BodySurface:
    """Loft, fuse, crop to ``z_range`` (m), mesh, orient outward and tag regions.

    Args:
        m: body measurements (default: :func:`~.measurements.measurements` size 88).
        sizes: element sizes; give ``band`` to refine where a garment will touch.
        z_range: keep only the body between these heights (flat caps close it).
        legs: loft and fuse the legs (a gilet or dress scene may leave them out).
        order: 1 or 2. With 2, the gmsh mesh is made second order and every curved
            6-node triangle is split into 4 flat ones, so vertices lie on the smooth surface.

    Runs gmsh in this process (call it on every rank, or on one and broadcast: it is
    deterministic). Returns a :class:`BodySurface`.
    """
    m = m or measurements()
    sizes = sizes or MeshSizes()
    torso = torso_sections(m)
    legs_secs = [leg_sections(m, +1), leg_sections(m, -1)] if legs else []
    with gmsh_session(name="mannequin") as g:
        occ = g.model.occ
        parts = add_loft(g, torso)
        for ls in legs_secs:
            parts += add_loft(g, ls)
        vols = [(3, t) for d, t in parts if d == 3]
        if len(vols) > 1:
            vols, _ = occ.fuse(vols[:1], vols[1:])
        if z_range is not None:
            box = occ.addBox(-1.0, -1.0, z_range[0], 2.0, 2.0, z_range[1] - z_range[0])
            vols, _ = occ.intersect(vols, [(3, box)])
        occ.synchronize()
        _size_field(g, sizes)
        g.option.setNumber("Mesh.Algorithm", 6)
        g.model.mesh.generate(2)
        if order == 2:
            g.model.mesh.setOrder(2)
        vertices, triangles = _surface_arrays(g, order)
    landmarks = {k: z for k, (z, _) in torso.items()}
    sections = {k: p for k, (z, p) in torso.items()}
    for side, ls in zip(("left", "right")[: len(legs_secs)], legs_secs, strict=True):
        for k in ("ankle", "calf", "knee", "thigh"):
            landmarks[k] = ls[k][0]
            sections[f"{k}_{side}"] = ls[k][1]
    return finish_body(vertices, triangles, landmarks, sections, m)


def _size_field(g, sizes: MeshSizes) -> None:
    g.option.setNumber("Mesh.MeshSizeMax", sizes.coarse)
    g.option.setNumber("Mesh.MeshSizeMin", min(sizes.fine, sizes.coarse) / 4)
    g.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    g.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    g.option.setNumber("Mesh.MeshSizeFromCurvature", sizes.per_circle)
    if sizes.band is None:
        g.option.setNumber("Mesh.MeshSizeMax", min(sizes.fine, sizes.coarse))
        return
    f = g.model.mesh.field.add("Box")
    g.model.mesh.field.setNumber(f, "VIn", sizes.fine)
    g.model.mesh.field.setNumber(f, "VOut", sizes.coarse)
    for k, v in zip(("XMin", "XMax", "YMin", "YMax"), (-1, 1, -1, 1), strict=True):
        g.model.mesh.field.setNumber(f, k, v)
    g.model.mesh.field.setNumber(f, "ZMin", sizes.band[0])
    g.model.mesh.field.setNumber(f, "ZMax", sizes.band[1])
    g.model.mesh.field.setNumber(f, "Thickness", 0.1)
    g.model.mesh.field.setAsBackgroundMesh(f)


def _surface_arrays(g, order: int) -> tuple[np.ndarray, np.ndarray]:
    """All surface triangles of the current model with contiguous 0-based vertex numbers."""
    tags, coords, _ = g.model.mesh.getNodes()
    pos = np.empty(int(tags.max()) + 1, dtype=np.int64)
    pos[tags.astype(np.int64)] = np.arange(len(tags))
    etype = 2 if order == 1 else 9
    _, nodes = g.model.mesh.getElementsByType(etype)
    conn = pos[nodes.astype(np.int64)].reshape(-1, 3 if order == 1 else 6)
    if order == 2:  # split each 6-node triangle into four: corners 0-2, mid-edges 3 (01), 4, 5
        a, b, c, ab, bc, ca = conn.T
        conn = np.concatenate(
            [np.column_stack(t) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))]
        )
    vertices = coords.reshape(-1, 3)
    used, inv = np.unique(conn.ravel(), return_inverse=True)
    return vertices[used], inv.reshape(conn.shape).astype(np.int64)


# ------------------------------------------------------------------------------------------------
# An arm on its own (a body for sleeves): vertical, wrist at z = 0, upper arm on top.
# ------------------------------------------------------------------------------------------------

#: Levels of the arm, wrist to upper arm.
ARM_LEVELS = ("wrist", "forearm", "elbow", "upper_arm")
#: Default arm girths [m]: **our own round-number proportions** for the size-88 woman of
#: :mod:`.measurements` (the ASTM D5585 rows transcribed there are torso girths only; no arm
#: girth table was at hand), in the range of an adult woman's wrist (~15–16 cm), forearm, elbow
#: and biceps (~26–28 cm) tape girths. Pass measured values to :func:`make_arm` for a wearer.
ARM_GIRTHS = {k: getattr(Measurements(), f"{k}_girth") for k in ARM_LEVELS}  # 15.5 … 27 cm
#: Distance of each level above the wrist [m] (our estimate: forearm 24 cm, the upper-arm girth
#: taken 12 cm above the elbow).
ARM_HEIGHTS = {"wrist": 0.0, "forearm": 0.12, "elbow": 0.24, "upper_arm": 0.36}
#: Depth / width of each section (mildly elliptic, the wrist flattest): our estimates.
ARM_ASPECT = {"wrist": 0.8, "forearm": 0.9, "elbow": 0.92, "upper_arm": 0.92}
#: Region numbers of the arm's bands (own numbering, after the torso/leg regions' 1–15).
ARM_REGIONS = {"wrist": 21, "forearm": 22, "elbow": 23, "upper_arm": 24}


def arm_sections(
    girths: dict[str, float] | None = None,
    aspect: dict[str, float] | None = None,
    stub: float = 0.05,
) -> dict[str, tuple[float, np.ndarray]]:
    """Height and (x, y) ellipse of every arm level, each scaled to its girth, plus a
    ``hand`` section ``stub`` below the wrist and a ``shoulder`` one ``stub`` above the upper
    arm that repeat their neighbours (so a sleeve can end short of the body's flat caps)."""
    g = {**ARM_GIRTHS, **(girths or {})}
    asp = {**ARM_ASPECT, **(aspect or {})}
    unknown = set(g) - set(ARM_LEVELS)
    if unknown:
        raise ValueError(f"unknown arm level(s) {sorted(unknown)}; known: {ARM_LEVELS}")
    if any(v <= 0 for v in g.values()) or any(not 0.3 <= v <= 1.0 for v in asp.values()):
        raise ValueError("arm girths must be positive and aspect ratios in [0.3, 1]")
    out: dict[str, tuple[float, np.ndarray]] = {}
    for level in ARM_LEVELS:
        shape = SectionShape(1.0, asp[level], asp[level], 2.0)
        out[level] = (ARM_HEIGHTS[level], shape.points(720, shape.scale_for_girth(g[level])))
    hand = (ARM_HEIGHTS["wrist"] - stub, out["wrist"][1])
    top = (ARM_HEIGHTS["upper_arm"] + stub, out["upper_arm"][1])
    return {"hand": hand, **out, "shoulder": top}


def make_arm(
    girths: dict[str, float] | None = None,
    h: float = 0.008,
    aspect: dict[str, float] | None = None,
) -> BodySurface:
    """A closed arm (OCC loft through :func:`arm_sections`, flat caps), outward, with regions
    ``wrist``/``forearm``/``elbow``/``upper_arm`` (bands split half-way between levels).

    The arm hangs straight (axis z): a sleeve's sections are then horizontal like every other
    garment's. Element size ``h`` [m], capped by 24 elements per turn (:class:`MeshSizes`).
    """
    secs = arm_sections(girths, aspect)
    with gmsh_session(name="arm") as g:
        add_loft(g, secs)
        g.model.occ.synchronize()
        _size_field(g, MeshSizes(coarse=h, fine=h))
        g.option.setNumber("Mesh.Algorithm", 6)
        g.model.mesh.generate(2)
        vertices, triangles = _surface_arrays(g, 1)
    from .surface import orient_outward

    tri = orient_outward(vertices, triangles)
    zs = np.array([secs[k][0] for k in ARM_LEVELS])
    cuts = 0.5 * (zs[1:] + zs[:-1])
    zc = vertices[tri].mean(axis=1)[:, 2]
    region = np.array([ARM_REGIONS[k] for k in ARM_LEVELS], np.int32)[np.searchsorted(cuts, zc)]
    landmarks = {k: secs[k][0] for k in ARM_LEVELS}
    sections = {k: secs[k][1] for k in ARM_LEVELS}
    return BodySurface(vertices, tri, region, dict(ARM_REGIONS), landmarks, sections)
