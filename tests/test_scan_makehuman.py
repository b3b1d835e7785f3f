"""A real body mesh end to end: the MakeHuman base mesh (CC0, meshes/makehuman/README.md).

References, all independent of the code under test:

* the OBJ itself, read here by a 20-line parser: which faces are the ``body`` group, its height,
  its vertex and face counts;
* MakeHuman's own rig: the file has a small cube per skeleton joint (``joint-l-knee`` …), placed
  by MakeHuman's artists; their centres are reference positions for landmarks and body parts;
* a direct measurement of a section here (convex hull of the cut points, ISO 8559-1 tape girth);
* invariance: raising the arms into a T-pose must leave the torso girths below the armpits
  unchanged and still find the arms.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from fenics_garment.geometry import ScanError
from fenics_garment.geometry.anatomy import PARTS, analyse
from fenics_garment.geometry.regions import REGIONS
from fenics_garment.geometry.scan import clean_surface, load_scan
from fenics_garment.geometry.scan_read import read_polygons

MESH = Path(__file__).resolve().parents[1] / "meshes" / "makehuman" / "base.obj.gz"
TORSO_REGIONS = ("upper_chest", "bust", "underbust", "upper_back", "waist", "abdomen",
                 "lower_back", "hips", "buttocks")  # fmt: skip


@pytest.fixture(scope="module")
def ref():
    """Reference data straight from the file: Y-up decimetres -> our frame (z up, metres)."""
    from fenics_garment.geometry.population import base_mesh

    raw = base_mesh()  # the OBJ as written: positions and faces per group
    v, groups = raw.vertices, raw.groups
    body_idx = np.unique(np.concatenate([np.array(f) for f in groups["body"]]))
    floor = v[body_idx, 1].min()

    def to_ours(p: np.ndarray) -> np.ndarray:  # (x, y, z) Y-up facing +z -> (x, -z, y), m
        return 0.1 * np.array([p[0], -p[2], p[1] - floor])

    joints = {g[6:]: to_ours(v[np.unique(np.concatenate(f))].mean(axis=0))
              for g, f in groups.items() if g.startswith("joint-")}  # fmt: skip
    n_tri = sum(len(f) - 2 for f in groups["body"])
    positions = np.unique(np.round(v[body_idx], 6), axis=0)
    height = 0.1 * (v[body_idx, 1].max() - floor)
    return {"joints": joints, "triangles": n_tri, "positions": len(positions), "height": height}


@pytest.fixture(scope="module")
def scan():
    return load_scan(MESH)


def test_import_keeps_the_body_group_only(scan, ref):
    body, report = scan
    assert report["units"] == "dm" and report["up"] == "y"
    assert len(body.triangles) == ref["triangles"]  # the body group's quads split in two
    assert len(body.vertices) == ref["positions"]
    assert report["dropped_pieces"] > 100  # eyes, teeth, lashes, helpers, joint cubes
    assert report["height"] == pytest.approx(ref["height"], abs=1e-6)
    info = body.check()
    assert info["closed_manifold"] and info["components"] == 1 and info["volume"] > 0
    # upright, facing -y: the nose (front of the head) is in front of the back of the head
    head = body.vertices[body.vertices[:, 2] > body.landmarks["head"] + 0.05]
    assert -head[:, 1].min() > head[:, 1].max()


def test_landmarks_against_makehuman_joints(scan, ref):
    """Heights against the rig's joint centres (tolerances: the anatomical offsets named)."""
    body, _ = scan
    L, J = body.landmarks, ref["joints"]
    assert L["knee"] == pytest.approx(J["l-knee"][2], abs=0.03)  # knee girth at the joint
    assert 0.0 < L["ankle"] - J["l-ankle"][2] < 0.08  # minimum girth just above the malleoli
    assert 0.0 < L["shoulder"] - J["l-shoulder"][2] < 0.06  # acromion above the humeral head
    assert -0.12 < L["armpit"] - J["l-shoulder"][2] < 0.0  # the axilla below the joint
    assert L["neck_base"] == pytest.approx(J["neck"][2], abs=0.03)
    assert -0.15 < L["crotch"] - J["l-upper-leg"][2] < 0.0  # crotch below the hip joints
    order = ("ankle", "calf", "knee", "crotch", "hip", "waist", "bust", "armpit", "shoulder",
             "neck_base", "neck", "head")  # fmt: skip
    z = [L[k] for k in order]
    assert z == sorted(z)
    # the arm root plane lies between the spine and the shoulder joint, close to the joint
    assert 0.10 < body.arm_cut["left"] < J["l-shoulder"][0] + 0.01
    assert body.arm_cut["right"] == pytest.approx(-body.arm_cut["left"], abs=0.005)


def test_parts_and_regions_hold_the_joints(scan, ref):
    """The triangle nearest each joint centre carries the part that joint belongs to."""
    body, _ = scan
    c = body.vertices[body.triangles].mean(axis=1)
    expect = {
        "l-elbow": "arm_left", "r-elbow": "arm_right", "l-hand": "arm_left",
        "r-hand": "arm_right", "l-knee": "leg_left", "r-knee": "leg_right",
        "l-ankle": "leg_left", "head": "head", "spine-2": "torso", "spine-3": "torso",
    }  # fmt: skip
    for joint, part in expect.items():
        i = int(np.argmin(np.linalg.norm(c - ref["joints"][joint], axis=1)))
        assert body.part[i] == PARTS[part], joint
    # torso regions lie on the torso only; from the waist up, inside the arm root planes
    for name in TORSO_REGIONS:
        sel = body.triangles_of(name)
        assert np.all(body.part[sel] == PARTS["torso"]), name
        if name in ("upper_chest", "bust", "underbust", "upper_back", "waist"):
            assert np.all(np.abs(c[sel, 0]) <= body.arm_cut["left"] + 1e-9), name
    arm = body.triangles_of("arms")
    assert np.all(np.abs(c[arm, 0]) > body.arm_cut["left"] - 1e-9)
    assert set(body.regions) == set(REGIONS)


def _direct_girth(v, t, z, half_width):
    """Tape girth measured here: cut the triangles' edges by the plane z, keep the cut points
    with |x| < half_width, and take the convex hull's perimeter."""
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    a, b = v[e[:, 0]], v[e[:, 1]]
    cross = (a[:, 2] - z) * (b[:, 2] - z) < 0
    a, b = a[cross], b[cross]
    s = (z - a[:, 2]) / (b[:, 2] - a[:, 2])
    p = a[:, :2] + s[:, None] * (b[:, :2] - a[:, :2])
    p = p[np.abs(p[:, 0]) < half_width]
    return ConvexHull(p).area


def test_torso_girths_against_a_direct_measurement(scan):
    """Well below the armpits the hands hang ≥ 25 cm from the mid-plane: the cut points inside
    |x| < 0.25 m are the torso's alone."""
    body, report = scan
    for level in ("hip", "abdomen", "waist"):
        z = body.landmarks[level]
        direct = _direct_girth(body.vertices, body.triangles, z, 0.25)
        assert report["girths"][level] == pytest.approx(direct, rel=2e-3), level
    # above the armpits the section is clipped at the arm roots: no upper arm in the girth
    z = body.landmarks["upper_chest"]
    # (1 %: the clipped section is closed along the cut planes, the cut points here stop short
    # of them by up to a facet, by an amount that jumps with z: 0.3–2.9 % under the clipped
    # girth every 2 mm from 1.300 to 1.326 m; the largest within ±5 mm is the closest)
    direct = max(_direct_girth(body.vertices, body.triangles, z + dz, body.arm_cut["left"])
                 for dz in np.linspace(-0.005, 0.005, 6))  # fmt: skip
    assert report["girths"]["upper_chest"] == pytest.approx(direct, rel=1e-2)
    full = _direct_girth(body.vertices, body.triangles, z, 1.0)
    assert full > 1.2 * report["girths"]["upper_chest"]  # the arms would add over 20 %


def _raise_arms(v: np.ndarray, shoulder: dict[str, np.ndarray], angle: float) -> np.ndarray:
    """T-pose from the A-pose (the rig's shoulder–wrist line is 47° below horizontal): turn the
    arms up about a front-back axis through each shoulder
    joint, blending the angle over x = 0.17 … 0.22 m so the surface stays connected (the torso
    is narrower than 0.17 m above the hips). Only points above 0.915 m turn: the hips (up to
    0.894 m) stay, the hands (from 0.94 m) go with the arms."""
    out = v.copy()
    for s in (1.0, -1.0):
        j = shoulder["l-shoulder" if s > 0 else "r-shoulder"]
        w = np.clip((s * v[:, 0] - 0.17) / 0.05, 0.0, 1.0) * (v[:, 2] > 0.915)
        th = s * angle * w
        dx, dz = v[:, 0] - j[0], v[:, 2] - j[2]
        out[:, 0] = np.where(w > 0, j[0] + np.cos(th) * dx - np.sin(th) * dz, out[:, 0])
        out[:, 2] = np.where(w > 0, j[2] + np.sin(th) * dx + np.cos(th) * dz, out[:, 2])
    return out


def test_t_pose_keeps_torso_girths_and_finds_the_arms(scan, ref):
    body, report = scan
    J = ref["joints"]
    v = _raise_arms(body.vertices, {k: J[k] for k in ("l-shoulder", "r-shoulder")},
                    np.radians(47.0))  # fmt: skip
    wrist = _raise_arms(J["l-hand"][None, :], J, np.radians(47.0))[0]
    assert wrist[2] == pytest.approx(J["l-shoulder"][2], abs=0.03)  # the arms are horizontal
    assert np.ptp(v[:, 0]) > 0.8 * np.ptp(v[:, 2])
    t_pose = analyse(v, body.triangles)
    for level in ("hip", "waist", "bust"):
        assert t_pose.girths[level] == pytest.approx(report["girths"][level], rel=0.01), level
    assert t_pose.landmarks["armpit"] == pytest.approx(body.landmarks["armpit"], abs=0.03)
    c = v[body.triangles].mean(axis=1)
    hand = int(np.argmax(c[:, 0]))
    assert t_pose.part[hand] == PARTS["arm_left"]


@pytest.fixture(scope="module")
def raw_and_clean():
    v, t = read_polygons(MESH)
    _, ref_t, ref_rep = clean_surface(v, t)
    return v, t, len(ref_t), ref_rep["height"]


# file, units factor from dm, the case's up axis (the model is Y up)
FORMATS = {
    "scan.stl": ("binary STL", 100.0, "y"),  # mm
    "scan_ascii.stl": ("ascii STL", 10.0, "y"),  # cm
    "scan.ply": ("binary PLY", 0.1, "z"),  # m, Z up
    "scan_ascii.ply": ("ascii PLY", 1.0 / 0.254, "-x"),  # inches, lying on its side
    "scan.off": ("OFF", 1.0, "-y"),  # dm, upside down
    "scan.glb": ("GLB", 0.1, "y"),  # m
}
TO_UP = {
    "y": np.eye(3),
    "z": np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]),
    "-y": np.diag([1.0, -1, -1]),
    "-x": np.array([[0, -1.0, 0], [1, 0, 0], [0, 0, 1]]),
}


@pytest.mark.parametrize("name", list(FORMATS))
def test_formats_units_and_axes(name, raw_and_clean, tmp_path):
    """The body converted with trimesh's exporters (other formats, units and up axes) imports
    to the same surface."""
    import trimesh

    v, t, n_tri, height = raw_and_clean
    kind, k, up = FORMATS[name]
    m = trimesh.Trimesh(v @ TO_UP[up].T * k, t, process=False)
    path = tmp_path / name
    if kind == "ascii STL":
        path.write_text(trimesh.exchange.stl.export_stl_ascii(m))
    elif kind == "ascii PLY":
        path.write_bytes(trimesh.exchange.ply.export_ply(m, encoding="ascii"))
    else:
        m.export(path)
    vv, tt = read_polygons(path)
    _, ct, rep = clean_surface(vv, tt)
    assert rep["up"] == up
    assert rep["height"] == pytest.approx(height, rel=1e-5)
    assert len(ct) == n_tri
    assert rep["units"] == {100.0: "mm", 10.0: "cm", 0.1: "m", 1.0: "dm"}.get(k, "in")


def test_units_and_scale_given(tmp_path):
    v, t = read_polygons(MESH)
    _, _, rep = clean_surface(v, t, scale=0.05)  # a free scale: half the size
    assert rep["height"] == pytest.approx(0.5 * 1.66589, rel=1e-4)
    with pytest.raises(ScanError, match="unknown units 'ft'"):
        clean_surface(v, t, units="ft")
    with pytest.raises(ScanError, match="unknown up axis 'w'"):
        clean_surface(v, t, up="w")


@pytest.mark.slow
def test_gilet_on_the_scan_body(scan):
    """The gilet is cut from the segmented body: armholes at the arm roots, no overshoot, and
    nowhere deep inside the body (libigl's exact signed distance as the reference)."""
    import igl

    from fenics_garment.geometry import garments as gm

    body, _ = scan
    g = gm.make_gilet(body, h=0.03)  # check_garment ran inside: bounded, no fold
    for side in ("left", "right"):
        p = g.points[np.unique(g.edge_nodes[f"armhole_{side}"])]
        cut = body.arm_cut[side]
        assert np.all(np.abs(p[:, 0] - cut) < 0.05), side  # around the arm root plane
        assert p[:, 2].min() < body.landmarks["armpit"]  # reaching below the armpit
        root = body.points[f"arm_root_{side}"]
        assert np.ptp(p[:, 1]) > 0.8 * (root[1] - root[0])  # most of the arm root's depth
    dist = igl.signed_distance(g.points, body.vertices, body.triangles.astype(np.int64))[0]
    # the default ease is ≥ 2 %: the loft between levels may dip into the breasts a little
    # (measured 17 mm with -2 % at the bust), never through an arm (35 mm before the arm-root
    # armholes)
    assert dist.min() > -0.02


@pytest.mark.slow
def test_scan_gilet_scene_end_to_end(tmp_path):
    """demos/scan_gilet.toml dresses on the MakeHuman body (about 5 min on one core): the run
    completes with the spring released, and the gilet presses on the torso (and the arm roots
    its armholes hug), never on the head or the legs."""
    from fenics_garment.scene import config
    from fenics_garment.scene.run import run

    scene = config.load(Path(__file__).resolve().parents[1] / "demos" / "scan_gilet.toml")
    result = run(scene, tmp_path, quiet=True)
    assert result.completed and result.report.final_regularisation == 0.0
    touched = {r["region"] for r in result.regions if r.get("mean_kPa", 0) > 0}
    assert touched and touched <= set(TORSO_REGIONS) | {"shoulders", "neck", "arms"}
    # it hangs from the shoulders; with the bust level at the bust points its +3 % clears the
    # breasts (before, the bust level lay at the armpits and the loft from an under-bust 2 cm
    # above the waist cut 1 cm into them: 118 cm² of contact there; now none)
    assert {"shoulders", "upper_chest"} <= touched


@pytest.mark.slow
def test_dress_on_the_scan_body(scan):
    """The dress is cut from the segmented body: armholes at the arm roots, the skirt hanging
    clear of the arms and hands and around the legs, nowhere deep inside the body (libigl's
    exact signed distance to each part's triangles as the reference)."""
    import igl

    from fenics_garment.geometry import garments as gm

    body, _ = scan
    d = gm.make_dress(body, h=0.03)  # check_garment ran inside: bounded, no fold
    for side in ("left", "right"):
        p = d.points[np.unique(d.edge_nodes[f"armhole_{side}"])]
        # below the straps (whose inner edge, where the back scoop meets the armhole, is also
        # named armhole: measured x = 0.07 m at 1.38–1.41 m), round the arm root
        low = p[p[:, 2] < body.landmarks["armpit"] + 0.08]
        assert np.all(np.abs(low[:, 0] - body.arm_cut[side]) < 0.05), side
        assert p[:, 2].min() < body.landmarks["armpit"]

    def dist_to(*parts: str) -> np.ndarray:
        tri = body.triangles[np.isin(body.part, [PARTS[k] for k in parts])]
        return igl.signed_distance(d.points, body.vertices, tri.astype(np.int64))[0]

    # the MakeHuman knees stand wider apart than the hips: a cone from the hip section cut
    # 21 mm into them (measured); widened around the legs, the skirt touches them only where
    # the loft from the hip section passes the top of the thighs (measured −4.7 mm)
    assert dist_to("leg_left", "leg_right").min() > -0.01
    assert dist_to("arm_left", "arm_right").min() > 0.0  # measured 2.2 mm, at the armholes
    hem = d.points[np.unique(d.edge_nodes["hem"])]
    assert hem[:, 2].max() < body.landmarks["knee"] + 0.05  # a skirt down to the knees
    # as the gilet, the loft between levels may dip into the breasts (measured 9.4 mm)
    assert (
        igl.signed_distance(d.points, body.vertices, body.triangles.astype(np.int64))[0].min()
        > -0.02
    )


@pytest.mark.slow
def test_scan_dress_scene_end_to_end(tmp_path):
    """demos/scan_dress.toml dresses on the MakeHuman body (about 7 min of CPU on one core):
    the run completes with the spring released and every result check passed, and the body
    carries the dress's weight ρ h A g, A the pattern's area summed here over its triangles
    (the fabric's density and thickness from its data, materials.py): the vertical reaction
    is the weight, the horizontal one vanishes. The dress presses on the torso and, where the
    skirt rests on them, the thighs and knees: never on the arms, hands, head or ankles."""
    from fenics_garment.materials import fabric
    from fenics_garment.scene import config
    from fenics_garment.scene.run import run

    scene = config.load(Path(__file__).resolve().parents[1] / "demos" / "scan_dress.toml")
    result = run(scene, tmp_path, quiet=True)
    s = result.summary
    assert result.completed and result.report.final_regularisation == 0.0
    assert s["checks_passed"] and s["max_penetration_over_thickness"] < 0.01
    g = result.built.garment
    x, t = g.points, g.triangles()
    area = 0.5 * np.linalg.norm(np.cross(x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]]),
                                axis=1).sum()  # fmt: skip
    f = fabric("cotton")
    weight = f.density * f.thickness * area * 9.80665
    reaction = np.array(s["forces_N"]["reaction"])
    print(f"pattern {area:.4f} m², weight {weight:.4f} N, reaction {reaction} N")
    # 2 %: the pattern's flat triangles against the curved mesh the load acts on (+0.2 %)
    assert reaction[2] == pytest.approx(weight, rel=2e-2)
    assert np.hypot(reaction[0], reaction[1]) < 0.01 * weight
    touched = {r["region"] for r in result.regions if r.get("mean_kPa", 0) > 0}
    assert "waist" in touched and not touched & {"arms", "head", "neck", "ankles"}
    assert touched <= set(TORSO_REGIONS) | {"shoulders", "thighs", "knees", "calves"}


# Limb joints against the rig (measured: left and right alike, the mesh is symmetric). Offsets
# are along the limb's own axis at the landmark, + towards the tip; tolerances name the anatomy.
LIMB_JOINTS = {
    # joint: (limb, rig joint, axial offset range [m], max distance off the axis [m])
    # the elbow: the arm's sharpest bend, within 3 cm of the joint along the axis (measured
    # 2.3 cm) and inside the elbow's section (radius girth/2π = 3.6 cm; measured 2.9 cm off)
    "elbow": ("arm", "elbow", (-0.03, 0.03), 0.036),
    # the wrist: the narrowest forearm section, proximal to the carpal joint, where the hand
    # starts to widen (measured 4.1 cm before the joint; 3.3 cm off the forearm's axis: the
    # hand turns forward from there)
    "wrist": ("arm", "hand", (0.0, 0.07), 0.04),
    # the knee: the kneecap's level found on the upright body's sections (ISO 8559-1
    # mid-patella; the centreline's own sharpest bend, measured 0.7 cm from the joint here,
    # lay 5–11.6 cm low on 8 of MakeHuman's population bodies), 0.65 cm below the rig's knee
    # joint: measured −2.1 cm along the slanted leg's axis, which also picks up the joint's
    # anterior offset (it lies near the patella, 1 cm inside the front of the knee: measured
    # 5.2 cm off the axis)
    "knee": ("leg", "knee", (-0.03, 0.02), 0.06),
    # the ankle: the narrowest section above the malleoli, up to 8 cm above the joint (as the
    # horizontal ankle level above; measured 6.2 cm), the joint then in the heel (4.0 cm off)
    "ankle": ("leg", "ankle", (0.0, 0.08), 0.045),
}


@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("joint", list(LIMB_JOINTS))
def test_limb_joints_against_makehuman_rig(scan, ref, joint, side):
    """Elbows, wrists, knees, ankles found on each limb's own centreline, against the rig."""
    body, _ = scan
    kind, rig, (lo, hi), radial = LIMB_JOINTS[joint]
    limb = body.limbs[f"{kind}_{side}"]
    j = ref["joints"][f"{side[0]}-{rig}"]
    p, tangent, _, _ = (x[0] for x in limb.frame_at(limb.marks[joint]))
    along = float((j - p) @ tangent)  # > 0: the joint lies further towards the tip
    off = float(np.linalg.norm((j - p) - along * tangent))
    print(f"{joint} {side}: joint {along * 100:+.1f} cm along the axis, {off * 100:.1f} cm off")
    assert lo < along < hi
    assert off < radial
    assert np.allclose(body.points[f"{joint}_{side}"], p)


def test_limb_sections_against_a_direct_cut(scan):
    """Each limb level's girth is its section perpendicular to the limb: cut here by the plane
    through the centreline point normal to the axis, keep the cut points within 12 cm of the
    axis point on the limb's side, and take their convex hull's perimeter."""
    body, _ = scan
    v, t = body.vertices, body.triangles
    for name, limb in body.limbs.items():
        for level, s in limb.marks.items():
            p, tangent, _, _ = (x[0] for x in limb.frame_at(s))
            direct = _perpendicular_girth(v, t, p, tangent)
            own = ConvexHull(limb.sections[level]).area
            assert own == pytest.approx(direct, rel=0.01), (name, level)
    # the arm levels are ordered wrist < forearm < elbow < upper arm girth on this body
    g = {
        k: ConvexHull(body.limbs["arm_left"].sections[k]).area for k in body.limbs["arm_left"].marks
    }
    assert g["wrist"] < g["forearm"] < g["elbow"] < g["upper_arm"]


def _perpendicular_girth(v, t, p, tangent, reach=0.12):
    """Tape girth of the body cut by the plane through p normal to ``tangent``: the cut points
    within ``reach`` of p, their convex hull's perimeter (computed here, not by the package)."""
    d = (v - p) @ tangent
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    cross = d[e[:, 0]] * d[e[:, 1]] < 0
    a, b = e[cross, 0], e[cross, 1]
    w = d[a] / (d[a] - d[b])
    q = v[a] + w[:, None] * (v[b] - v[a])
    q = q[np.linalg.norm(q - p, axis=1) < reach]
    basis = np.linalg.svd(np.eye(3) - np.outer(tangent, tangent))[0][:, :2]
    return ConvexHull((q - p) @ basis).area


# garment, limb, the levels compared, tolerance on Laplace's law. Measured (shared 2-core
# machine, 1 rank): see demos/scan_sleeve.toml and demos/scan_stocking.toml.
LIMB_SCENES = {
    "scan_sleeve.toml": ("arm_left", ("forearm", "elbow"), 0.15),
    "scan_stocking.toml": ("leg_left", ("ankle", "knee"), 0.15),
}


#: Known failure: the scan stocking's ankle band is +29 % from Laplace (3760 against 2920 Pa,
#: 2026-12-04; calf +22 %, knee +15 %). Diagnosed so far (docs/guide/scan.md, "Your own body scan"):
#: * fixed: the stocking lofted through its 6 levels alone was not at the levels' ease between
#:   them (−8 % at the ankle, −0.6 % half-way to the calf, −9 % in the ankle band); it is now
#:   lofted through the leg's own sections every 2 cm (garments._follow_the_limb), its ease
#:   within 0.5 % of the graduation everywhere, and the pressure follows Laplace cut by cut
#:   (±15 % scatter) from 5 cm above the ankle to the welt;
#: * the calf and knee excess is the reference's: the spring anchored at the start holds the
#:   stocking axially while the leg grows (the stuck hoop state, tube_pressure(stuck=True):
#:   +7.4 % / +8.6 %), and the smooth contact surface's girth is +0.8 % / +0.2 % over the
#:   faceted cut (+10 % / +3 % of pressure at −8 % / −6 % ease);
#: * not explained: the ankle's peak (4290 Pa, 1.35 × the local Laplace) on the narrowest
#:   section, 1.2 cm from the hem, where the girth dips 1.5 % between the heel and the calf.
_LIMB_XFAIL = pytest.mark.xfail(reason="scan stocking: ankle band +29 % from Laplace", strict=False)
_LIMB_MARKS = {"scan_stocking.toml": [_LIMB_XFAIL]}


@pytest.mark.slow
@pytest.mark.parametrize(
    "scene_file", [pytest.param(f, marks=_LIMB_MARKS.get(f, [])) for f in LIMB_SCENES]
)
def test_limb_garment_on_the_scan_against_laplace(scene_file, tmp_path):
    """A sleeve (stocking) dressed on the scan's own left arm (leg): the run completes with the
    spring released and penetration below 1 % of the thickness; at each compared level the
    mean pressure in a ±1 cm band along the limb is Laplace's n_θθ / R_eq for the level's ease
    and the body's girth *cut here* perpendicular to the limb (compression.laplace_pressure:
    the free-end hoop force of the fabric's own stiffness; the limb's axial curvature, its
    taper and the friction left after dressing are what the tolerance is for)."""
    limb_name, levels, tol = LIMB_SCENES[scene_file]
    limb_garment_against_laplace(scene_file, limb_name, levels, tol, tmp_path)


def limb_garment_against_laplace(
    scene_file: str, limb_name: str, levels: tuple[str, ...], tol: float, tmp_path: Path
) -> None:
    """Dress the demo ``scene_file`` and compare its band pressures with Laplace's law at
    ``levels`` (the checks of :func:`test_limb_garment_on_the_scan_against_laplace`)."""
    from fenics_garment import compression as cp
    from fenics_garment.scene import config
    from fenics_garment.scene.run import run

    scene = config.load(Path(__file__).resolve().parents[1] / "demos" / scene_file)
    result = run(scene, tmp_path, quiet=True)
    assert result.completed and result.report.final_regularisation == 0.0
    assert result.summary["max_penetration_over_thickness"] < 0.01
    built = result.built
    limb = built.body.limbs[limb_name]
    s = built.model.stiffness
    for name in levels:
        row = next(r for r in built.garment.levels if r.name.startswith(name))
        p, tangent, _, _ = (x[0] for x in limb.frame_at(limb.length - row.z))
        girth = _perpendicular_girth(built.body.vertices, built.body.triangles, p, tangent)
        assert girth == pytest.approx(row.body_girth, rel=0.01), name
        lap = cp.laplace_pressure(girth, row.ease, s)
        sim = cp.band_pressure(built, row.z, 0.01)
        print(
            f"{scene_file} {name}: girth {girth:.4f} m, ease {row.ease:+.3f}, simulated "
            f"{sim:.0f} Pa, Laplace {lap:.0f} Pa ({sim / lap - 1:+.1%})"
        )
        assert sim == pytest.approx(lap, rel=tol), name


def _perimeter_across(points, cells, p, tangent):
    """Length of the garment's section by the plane through p normal to ``tangent``."""
    tri = cells if cells.shape[1] == 3 else np.concatenate([cells[:, :3], cells[:, [0, 2, 3]]])
    d = (points - p) @ tangent
    total = 0.0
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):  # the two crossed edges of each triangle
        a, b, c = tri[:, i], tri[:, j], tri[:, k]
        one = (d[a] * d[b] < 0) & (d[a] * d[c] < 0)  # vertex a alone on its side
        x = [points[a] + (d[a] / (d[a] - d[q]))[:, None] * (points[q] - points[a]) for q in (b, c)]
        total += float(np.linalg.norm(x[0] - x[1], axis=1)[one].sum())
    return total


@pytest.mark.parametrize("kind", ["sleeve", "stocking"])
def test_limb_garment_geometry_on_the_scan(scan, kind):
    """The sleeve (stocking) built around the scan's own limb: cut by the plane normal to the
    limb at each level, its girth is the construction table's (1 + ease) × the limb's girth;
    the right one is the left one mirrored (the MakeHuman mesh is left–right symmetric)."""
    from fenics_garment.geometry import garments as gm
    from fenics_garment.geometry.errors import GeometryError

    body, _ = scan
    make = gm.make_sleeve if kind == "sleeve" else gm.make_stocking
    limb = body.limbs["arm_left" if kind == "sleeve" else "leg_left"]
    left = make(body, side="left", h=0.015, per_turn=12)
    for row in left.levels:
        if row.name in ("hem", "top", "welt"):  # free edges: the cut plane meets them
            continue
        p, tangent, _, _ = (x[0] for x in limb.frame_at(limb.length - row.z))
        g = _perimeter_across(left.points, left.cells, p, tangent)
        assert g == pytest.approx(row.garment_girth, rel=0.01), row.name
    right = make(body, side="right", h=0.015, per_turn=12)
    for a, b in zip(left.levels, right.levels, strict=True):
        assert b.body_girth == pytest.approx(a.body_girth, rel=1e-3)
    import igl

    # the right nodes mirrored lie on the left surface (up to the chord sag of 15 mm facets on
    # a 2 cm radius, h²/8r = 1.4 mm; the two meshes' nodes differ)
    mirror = right.points * np.array([-1.0, 1.0, 1.0])
    d2 = igl.point_mesh_squared_distance(mirror, left.points, left.triangles())[0]
    assert np.sqrt(d2.max()) < 0.002
    assert np.allclose(np.linalg.norm(left.warp, axis=1), 1.0)
    assert np.abs(np.einsum("ij,ij->i", left.warp, left.normal)).max() < 1e-9
    with pytest.raises(GeometryError, match="side must be"):
        make(body, side="middle")
