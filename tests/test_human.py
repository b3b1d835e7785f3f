"""The human mannequin (geometry.human): arms in an A-pose and a head on the parametric body,
segmented as a scan is.

References, all independent of the segmentation under test:

* the construction's inputs: the requested girths (measurements), the arm's axis (shoulder
  joint, elbow and wrist points) and section girths, the head girth;
* OpenCASCADE's exact solids: the arm root's lowest point (the armpit) is the lowest point of
  the overlap of the upper-arm loft with the torso loft, computed here by gmsh;
* a direct measurement here: the convex hull perimeter of the body's cut by a plane (ISO 8559-1
  tape girth), and the generalised winding number (libigl) for the surface's self-intersection.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from fenics_garment.geometry import GeometryError, MeshSizes, measurements
from fenics_garment.geometry import sections as sec
from fenics_garment.geometry.anatomy import PARTS
from fenics_garment.geometry.human import (
    Pose,
    arm_axis,
    arm_lofts,
    arm_rings,
    check_human,
    head,
    human_torso_sections,
    make_human,
)
from fenics_garment.geometry.quality import quality_report
from fenics_garment.geometry.regions import REGIONS

M = measurements("88")
TORSO_REGIONS = ("upper_chest", "bust", "underbust", "upper_back", "waist", "abdomen",
                 "lower_back", "hips", "buttocks")  # fmt: skip


#: The arm's girths are checked at the limb analysis's own stations, within 2.5 %: at the
#: construction's rings the body's girths are the requested ones to 0.3 % (elbow / forearm /
#: wrist −0.26 / −0.28 / −0.26 % at 1.5 cm elements), but the detected wrist (the loft's
#: narrowest section) lies 1.7 cm towards the hand, where the smooth (periodic-spline) loft is
#: 2 % narrower (measured 0.1519 m against 0.155 m), and the forearm station is placed from it.
@pytest.fixture(scope="module")
def body():
    """The default human at 3 cm elements (about 20k triangles, 15 s)."""
    return make_human(M, MeshSizes(coarse=0.03, fine=0.03))


def test_one_closed_outward_surface_of_fair_quality(body):
    info = body.check()
    assert info["closed_manifold"] and info["components"] == 1
    # the dress form's torso and legs are about 0.05 m³ (test_geometry_mannequin: > 0.03), the
    # arms (2 × ≈ 1.5 l) and head (4/3 π abc ≈ 3.3 l) add some 6 l
    assert 0.04 < info["volume"] < 0.08
    q = quality_report(body.vertices, body.triangles)
    # measured 5.2° (where the torso loft's side line crosses the armpit seam: a 1 mm edge), 53°
    assert q["min_angle_deg"] > 4.0 and q["mean_min_angle_deg"] > 45.0


def test_no_self_intersection(body):
    """Just inside every triangle the winding number is 1, just outside 0: a surface that
    crossed itself (an arm through the torso, the neck out of the head) would give 2 or 1 there.
    """
    import igl

    v, t = body.vertices, body.triangles.astype(np.int64)
    p = v[t]
    c = p.mean(axis=1)
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None]
    eps = 2e-4  # far below the 3 cm triangles, far above round-off
    w_in = igl.winding_number(v, t, c - eps * n)
    w_out = igl.winding_number(v, t, c + eps * n)
    assert np.abs(w_in - 1.0).max() < 0.1
    assert np.abs(w_out).max() < 0.1


@pytest.mark.parametrize("level", ["hip", "waist", "bust"])
def test_torso_girths_against_the_measurements(body, level):
    """The segmented torso's girths and levels against the requested measurements: at the
    construction height the body's tape girth (measured here) is the requested one; the
    anatomy's narrowest / widest torso girth is within 1.5 % of it, 2.5 cm from its level (the
    torso loft's own narrowest girth lies 2.2 cm above the waist section: 0.667 m at 1.072 m
    against 0.674 m at 1.050 m, −1.0 % with the smooth (periodic-spline) sections, measured on
    the loft alone at 1 cm elements)."""
    want, z = M.girth(level), M.height(level)
    loops = sec.slice_loops(body.vertices, body.triangles, z)
    torso = next(p for p in loops if p[:, 0].min() < 0 < p[:, 0].max())
    assert ConvexHull(torso).area == pytest.approx(want, rel=5e-3)
    assert body.girth(level) == pytest.approx(want, rel=0.015)  # BodySurface: at the detected z
    assert body.landmarks[level] == pytest.approx(z, abs=0.025)


def _armpit_of_the_construction(side: int) -> np.ndarray:
    """The lowest point of the overlap of the torso loft with the upper-arm loft (OCC)."""
    from fenics_garment.geometry.gmsh_utils import gmsh_session
    from fenics_garment.geometry.human import ARM_LOFT_DEGREE
    from fenics_garment.geometry.mannequin import add_loft, loft_rings

    with gmsh_session(name="armpit") as g:
        torso = [dt for dt in add_loft(g, human_torso_sections(M)) if dt[0] == 3]
        upper = arm_lofts(M, Pose(), side)[0]
        arm = [dt for dt in loft_rings(g, upper, max_degree=ARM_LOFT_DEGREE) if dt[0] == 3]
        common, _ = g.model.occ.intersect(torso, arm)
        g.model.occ.synchronize()
        g.option.setNumber("Mesh.MeshSizeMax", 0.003)
        g.model.mesh.generate(2)
        assert common
        faces = g.model.getBoundary(common, combined=True, oriented=False)
        x = [g.model.mesh.getNodes(2, f, includeBoundary=True)[1] for _, f in faces]
        x = np.concatenate(x).reshape(-1, 3)
        return x[np.argmin(x[:, 2])]


def test_arm_roots_against_the_construction(body):
    """Armpits at the lowest point where the arm leaves the torso (OCC, computed here), the arm
    root plane through the chest wall there, the shoulder points near the acromion height."""
    for side, s in (("left", 1), ("right", -1)):
        apex = _armpit_of_the_construction(s)
        # the segmentation's sections are 5 mm apart (then bisected): the first attached one is
        # at most a few mm above the apex (the 3 cm mesh's chords move it too)
        assert body.points[f"armpit_{side}"][2] == pytest.approx(apex[2], abs=0.005), side
        # the arm root plane goes through the chest wall where the arm leaves it
        assert body.arm_cut[side] == pytest.approx(apex[0], abs=0.005), side
        # the shoulder point: on the shoulder's top slope inside the acromion, up to 3 cm above
        # the acromion's height (the slope rises towards the neck base, 5 cm higher)
        assert 0.0 < body.points[f"shoulder_{side}"][2] - M.height("shoulder") < 0.03, side
        root = body.points[f"arm_root_{side}"]
        r_root = 0.85 * M.upper_arm_girth / (2 * np.pi)  # the arm's root section (human.py)
        assert root[1] - root[0] > 2 * r_root  # the arm root is deeper than the arm


@pytest.mark.parametrize("side", ["left", "right"])
def test_arm_joints_and_girths_against_the_construction(body, side):
    """The limb analysis (its own centreline, perpendicular sections) finds the elbow and the
    wrist of the construction within 2 cm (its stations are limbs.STATION = 1 cm apart, and
    the loft's narrowest section need not be the wrist section itself: measured 2 / 17 mm for
    elbow / wrist with the smooth, periodic-spline sections), their girths within 1.5 %."""
    s = 1 if side == "left" else -1
    limb = body.limbs[f"arm_{side}"]
    axis = arm_axis(M, Pose(), s)
    wrist = arm_rings(M, Pose(), s)["wrist"].mean(axis=0)
    for joint, ref in (("elbow", axis.elbow), ("wrist", wrist)):
        off = np.linalg.norm(limb.point(joint)[0] - ref)
        print(f"{joint} {side}: {off * 1e3:.1f} mm from the construction")
        assert off < 0.02, joint
    for level in ("elbow", "forearm", "wrist"):
        girth = ConvexHull(limb.sections[level]).area
        print(f"{level} {side}: girth {girth:.4f} m, requested {M.girth(level):.4f} m")
        assert girth == pytest.approx(M.girth(level), rel=0.025), level


def test_knees_at_the_construction(body):
    """The human's lofted leg tapers from thigh to ankle without a calf or a narrowing (knee
    girth 0.37 m over a 0.35 m calf, a straight leg): nothing on the surface marks its knee, so
    the rule falls back to the proportional height (limbs.KNEE_HEIGHT, Drillis & Contini's
    0.285 × stature, which the construction also uses: this checks that the monotone girth
    and the straight centreline no longer pull the knee away from it — before, the horizontal
    knee was found at 0.547 m and the limb's at 0.567 m against 0.479 m). The real knee of a
    scan is checked against MakeHuman's rig in tests/test_scan_makehuman.py."""
    z = M.height("knee")
    assert body.landmarks["knee"] == pytest.approx(z, abs=0.015)
    assert body.landmarks["calf"] < body.landmarks["knee"] < body.landmarks["thigh"]
    for side in ("left", "right"):
        limb = body.limbs[f"leg_{side}"]
        assert limb.point("knee")[0, 2] == pytest.approx(z, abs=0.015), side
        assert limb.marks["thigh"] < limb.marks["knee"] < limb.marks["calf"], side


def test_ankles_of_the_footless_legs_at_the_construction(body):
    """The human's legs end 3 cm below the ankle, without a foot: the leg still narrows where a
    foot would begin (85 % of the leg), so the ankle is the narrowest section down to the cut's
    rim (limbs._footless_ankle). Before, it stopped at 85 %: 11 cm from the end, at a 28.2 cm
    girth against the 22 cm requested, and the stocking's ankle pressure fell from RAL class I
    (19.9 mmHg on the dress form's legs) to 15.6 mmHg."""
    z = M.height("ankle")
    for side in ("left", "right"):
        limb = body.limbs[f"leg_{side}"]
        assert limb.point("ankle")[0, 2] == pytest.approx(z, abs=0.02), side
        assert ConvexHull(limb.sections["ankle"]).area == pytest.approx(M.ankle_girth, rel=0.03)


def test_head_and_neck(body):
    """The head's widest horizontal girth is the requested head girth; the neck and the head's
    start (the jaw) lie between the construction's neck level and the head ellipsoid."""
    hd = head(M)
    z = hd.centre[2]
    loops = sec.slice_loops(body.vertices, body.triangles, z)
    # 1 %: the chords of 3 cm triangles on the head's ≈ 9 cm radius are short by h²/(24 r²)
    # ≈ 0.5 % (measured −0.53 %)
    girth = sec.tape_girth(max(loops, key=lambda p: abs(sec.polygon_area(p))))
    assert girth == pytest.approx(M.head_girth, rel=0.01)
    L = body.landmarks
    bottom = hd.centre[2] - hd.axes[2]
    assert M.height("neck_base") < L["neck"] < bottom < L["head"] < z
    c = body.vertices[body.triangles].mean(axis=1)
    assert np.all(body.part[c[:, 2] > z] == PARTS["head"])


def test_parts_and_regions(body):
    """Every region, each on its part: torso regions on the torso and inside the arm roots,
    the arms' region beyond them, the hands on the arms."""
    assert set(body.regions) == set(REGIONS)
    c = body.vertices[body.triangles].mean(axis=1)
    for name in TORSO_REGIONS:
        sel = body.triangles_of(name)
        assert np.all(body.part[sel] == PARTS["torso"]), name
    assert np.all(np.abs(c[body.triangles_of("arms"), 0]) > body.arm_cut["left"] - 1e-9)
    for s, side in ((1, "left"), (-1, "right")):
        tips = arm_rings(M, Pose(), s)["tips"].mean(axis=0)
        i = int(np.argmin(np.linalg.norm(c - tips, axis=1)))
        assert body.part[i] == PARTS[f"arm_{side}"]


def test_gilet_armholes_round_the_arm_roots(body):
    """The gilet's armholes go round the arm roots (below the armpit, most of the root's depth,
    near the arm root plane) and its shoulder seams lie on the shoulders; the garment is
    bounded and unfolded (garment_checks, inside make_gilet) and nowhere deep in the body."""
    import igl

    from fenics_garment.geometry import garments as gm

    g = gm.make_gilet(body, h=0.035, order=1)
    for side in ("left", "right"):
        p = g.points[np.unique(g.edge_nodes[f"armhole_{side}"])]
        cut = body.arm_cut[side]
        assert np.all(np.abs(p[:, 0] - cut) < 0.05), side
        assert p[:, 2].min() < body.landmarks["armpit"]
        root = body.points[f"arm_root_{side}"]
        assert np.ptp(p[:, 1]) > 0.8 * (root[1] - root[0])
        seam = g.points[np.unique(g.edge_nodes[f"shoulder_seam_{side}"])]
        # on top of the shoulder: between the neck and the arm root, above the armpit, close
        # to the skin (the shoulder's ease is +2 %: a few mm of clearance)
        assert np.all(np.abs(seam[:, 0]) < abs(cut) + 0.01)
        assert seam[:, 2].min() > body.landmarks["armpit"]
        d = igl.signed_distance(seam, body.vertices, body.triangles.astype(np.int64))[0]
        assert np.all(np.abs(d) < 0.015), side
    dist = igl.signed_distance(g.points, body.vertices, body.triangles.astype(np.int64))[0]
    assert dist.min() > -0.02  # the default ease ≥ 2 %: dips between levels only


def test_sleeve_on_the_human_arm(body):
    """The sleeve follows the human's own arm (as on a scan): its levels' body girths are the
    arm's construction girths."""
    from fenics_garment.geometry import garments as gm

    s = gm.make_sleeve(body, h=0.02, side="right", order=1, per_turn=12)
    assert s.frame is body.limbs["arm_right"]
    for level in ("wrist", "forearm", "elbow"):
        assert s.level(level).body_girth == pytest.approx(M.girth(level), rel=0.025), level


@pytest.mark.parametrize(
    ("override", "pose", "message"),
    [
        ({"upper_arm_girth": 0.45}, Pose(), "arm root does not fit"),
        ({"head_girth": 0.36}, Pose(), "neck does not fit inside the head"),
        ({"upper_arm_girth": 0.35}, Pose(), "arm root does not fit"),
        ({}, Pose(abduction=25.0), "arm root does not fit .* at 25° abduction"),
    ],
)
def test_bad_measurements_are_one_line_errors(override, pose, message):
    """Refused before gmsh runs, with the reason in one line."""
    with pytest.raises(GeometryError, match=message) as err:
        check_human(measurements("88", **override), pose)
    assert "\n" not in str(err.value)


def test_bad_pose_is_a_one_line_error():
    with pytest.raises(GeometryError, match="abduction"):
        Pose(abduction=5.0)


DEMOS = __import__("pathlib").Path(__file__).resolve().parents[1] / "demos"


@pytest.mark.parametrize(
    ("text", "key", "words"),
    [
        ("[body]\nkind = 'scan'\nfile = 'x.obj'\nhuman = true\n", "body.human",
         "only a mannequin"),
        ("[body]\nhuman = true\nlandmarks = { wiast = 1.0 }\n", "body.landmarks.wiast",
         "did you mean 'waist'"),
        ("[body]\nhuman = false\n[garment]\nkind = 'sleeve'\n", "garment.kind",
         "human = true"),
    ],
)  # fmt: skip
def test_scene_keys_of_the_human(tmp_path, text, key, words):
    from fenics_garment.scene import config

    path = tmp_path / "scene.toml"
    path.write_text(text)
    with pytest.raises(config.SceneError) as err:
        config.load(path)
    assert err.value.key == key and words in str(err.value)


def test_human_scene_loads_and_a_sleeve_may_use_its_arm(tmp_path):
    from fenics_garment.scene import config

    s = config.load(DEMOS / "human_gilet.toml")
    assert s.body.kind == "mannequin" and s.body.human and s.garment.kind == "gilet"
    path = tmp_path / "sleeve.toml"
    path.write_text("[body]\nhuman = true\n[garment]\nkind = 'sleeve'\nside = 'right'\n")
    assert config.load(path).garment.side == "right"


def test_human_sleeve_scene_builds_its_sleeve_on_the_arm():
    """demos/human_sleeve.toml: the sleeve is cut from the human's own left arm (coarse body)."""
    from dataclasses import replace

    from fenics_garment._stack import MPI
    from fenics_garment.scene import config
    from fenics_garment.scene.build import make_garment

    scene = config.load(DEMOS / "human_sleeve.toml")
    body = make_human(M, MeshSizes(coarse=0.03, fine=0.03))
    scene = replace(scene, garment=replace(scene.garment, geometry="straight", mesh_size=0.03))
    g = make_garment(scene, body, MPI.COMM_SELF)
    assert g.kind == "sleeve" and g.frame is body.limbs["arm_left"]
    wrist = g.level("wrist")
    assert wrist.body_girth == pytest.approx(M.wrist_girth, rel=0.025)
    assert wrist.garment_girth == pytest.approx((1 - 0.07) * wrist.body_girth, rel=1e-3)


def test_preflight_refuses_an_arm_too_thick_for_the_shoulder(tmp_path):
    from fenics_garment.scene import config
    from fenics_garment.scene.preflight import PreflightError, mannequin_limits

    path = tmp_path / "scene.toml"
    path.write_text("[body]\nhuman = true\nmeasurements = { upper_arm_girth = 0.45 }\n")
    with pytest.raises(PreflightError, match="arm root does not fit") as err:
        mannequin_limits(config.load(path))
    assert "\n" not in str(err.value)


@pytest.mark.slow
def test_human_gilet_scene_dresses(tmp_path):
    """demos/human_gilet.toml at a coarse body (2 cm) dresses on one rank: the run completes
    with the spring released, penetration ≤ 1 % of the thickness, every result check passes
    (force balance among them), and the gilet presses on the torso and the arm roots its
    armholes hug, never on the head, the hands or the legs."""
    from dataclasses import replace

    from fenics_garment.scene import config
    from fenics_garment.scene.run import run

    scene = config.load(DEMOS / "human_gilet.toml")
    scene = replace(scene, body=replace(scene.body, mesh_size=0.02))
    result = run(scene, tmp_path, quiet=True)
    s = result.summary
    print({k: s[k] for k in ("max_penetration_over_thickness", "contact_force_N") if k in s})
    print(s["checks"])
    assert result.completed and result.report.final_regularisation == 0.0
    assert s["max_penetration_over_thickness"] <= 0.01
    assert s["checks_passed"] and s["checks"]["force_balance"]["ok"]
    touched = {r["region"] for r in result.regions if r.get("mean_kPa", 0) > 0}
    assert touched and touched <= set(TORSO_REGIONS) | {"shoulders", "neck", "arms"}
    assert {"waist", "underbust", "upper_back"} <= touched


@pytest.mark.slow
def test_human_sleeve_against_laplace(tmp_path):
    """demos/human_sleeve.toml: the sleeve dressed on the human's own left arm, followed along
    its centreline as a scan's, completes with the spring released and penetration below 1 %
    of the thickness; at the forearm and elbow the mean pressure in a ±1 cm band is Laplace's
    n_θθ / R_eq for the level's ease and the arm's girth cut perpendicular to it (the checks of
    the scan's limbs, tests/test_scan_makehuman.py; 15 % as there: the arm's axial curvature at
    the elbow, its taper, and the sleeve's axial hold while the arm grows (the stuck hoop
    state, +7 %) are what Laplace neglects). Measured (1 rank): forearm 2370 Pa against 2199 Pa
    (+7.8 %), elbow 1933 against 1790 Pa (+8.0 %). The upper arm is not compared: the A-pose
    arm hangs so close to the chest there that a plane normal to it cuts the torso too."""
    from test_scan_makehuman import limb_garment_against_laplace

    limb_garment_against_laplace("human_sleeve.toml", "arm_left", ("forearm", "elbow"), 0.15,
                                 tmp_path)  # fmt: skip
