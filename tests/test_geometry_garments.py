"""Garments: girth = (1 + ease) × requested girth, clearance as constructed, tags, orientation."""

import numpy as np
import pytest

from fenics_garment.geometry import MeshSizes, MissingRegion, make_mannequin, measurements
from fenics_garment.geometry.errors import GeometryError
from fenics_garment.geometry.garments import (
    EdgeRefinement,
    cylinder_body,
    intended_clearance,
    make_dress,
    make_gilet,
    make_stocking,
    make_tube,
)
from fenics_garment.geometry.quality import quality_report
from fenics_garment.geometry.sections import signed_distance_2d, slice_loops


@pytest.fixture(scope="module")
def torso():
    return make_mannequin(measurements("88"), MeshSizes(0.025, 0.025), z_range=(0.3, 1.55))


@pytest.fixture(scope="module")
def gilet(torso):
    return make_gilet(torso, h=0.02)


def _outward_fraction(gm, axis_xy):
    tri = gm.triangles()
    p = gm.points[tri]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    rad = p.mean(axis=1)[:, :2] - axis_xy
    # judge only the walls (normal within 45° of horizontal): on shoulder straps and the flared
    # skirt's top the radial direction says little about which side is out
    wall = np.abs(n[:, 2]) < np.linalg.norm(n[:, :2], axis=1)
    return np.mean(np.einsum("ij,ij->i", n[wall, :2], rad[wall]) > 0)


@pytest.mark.parametrize("level", ["hip", "waist", "underbust", "bust"])
def test_gilet_girth_is_ease_times_requested(torso, gilet, level):
    row = gilet.level(level)
    requested = torso.measurements.girth(level) * (1.0 + row.ease)
    assert row.ease == pytest.approx(0.03 if level != "hip" else 0.04, abs=1e-9)
    assert gilet.girth(row.z) == pytest.approx(requested, rel=0.01)


@pytest.mark.parametrize("level", ["hip", "waist", "bust", "upper_chest"])
def test_gilet_clearance_equals_construction(torso, gilet, level):
    row = gilet.level(level)
    # Steiner: a convex curve offset by d gains 2πd of perimeter
    assert row.clearance == pytest.approx(row.ease * row.body_girth / (2 * np.pi), rel=0.02)
    _, body_curve = torso.section(level)
    pts = np.concatenate(slice_loops(gilet.points, gilet.triangles(), row.z))
    d = signed_distance_2d(pts, body_curve)
    assert np.median(d) == pytest.approx(row.clearance, abs=5e-4)


def test_min_clearance_is_respected(torso):
    gm = make_gilet(torso, ease=0.0, h=0.03, min_clearance=0.01)
    rows = intended_clearance(gm)
    assert all(r.clearance >= 0.01 - 1e-12 for r in rows)
    w = gm.level("waist")
    assert w.ease == pytest.approx(2 * np.pi * 0.01 / w.body_girth, rel=0.02)
    assert gm.girth(w.z) == pytest.approx((1 + w.ease) * torso.measurements.waist_girth, rel=0.01)


def test_gilet_tags_and_orientation(gilet):
    assert set(gilet.panels) == {"front", "back"}
    expected = {"hem", "neckline", "armhole_left", "armhole_right", "side_seam_left"}
    expected |= {"side_seam_right", "shoulder_seam_left", "shoulder_seam_right"}
    assert set(gilet.edges) == expected
    for name in expected:
        assert len(gilet.edge_nodes[name]) > 0
    for tag in gilet.panels.values():
        assert np.any(gilet.cell_panel == tag)
    with pytest.raises(MissingRegion):
        gilet.edge("collar")
    assert _outward_fraction(gilet, np.zeros(2)) > 0.99
    # warp: unit, tangent, and mostly vertical on the body of the gilet
    assert np.allclose(np.linalg.norm(gilet.warp, axis=1), 1.0)
    assert np.abs(np.einsum("ij,ij->i", gilet.warp, gilet.normal)).max() < 1e-9
    assert np.median(gilet.warp[:, 2]) > 0.9
    q = quality_report(gilet.points, gilet.cells)
    assert q["min_angle_deg"] > 5 and q["mean_min_angle_deg"] > 40


def test_gilet_front_opening(torso):
    gm = make_gilet(torso, h=0.03, front_opening=0.02)
    assert set(gm.panels) == {"front_left", "front_right", "back"}
    assert {"opening_left", "opening_right"} <= set(gm.edges)


def test_dress_skirt_flare_and_tags(torso):
    dress = make_dress(torso, h=0.03, flare=0.25)
    hip = dress.level("hip")
    sk = dress.level("skirt_1")
    # the skirt gains (flare × fraction) of the hip girth by construction
    assert sk.garment_girth == pytest.approx((1 + hip.ease + 0.25 * 2 / 3) * hip.body_girth, 1e-3)
    assert dress.girth(sk.z) == pytest.approx(sk.garment_girth, rel=0.01)
    assert dress.girth(dress.level("waist").z) == pytest.approx(
        1.03 * torso.measurements.waist_girth, rel=0.01
    )
    assert {"hem", "neckline", "armhole_left", "armhole_right"} <= set(dress.edges)
    assert _outward_fraction(dress, np.zeros(2)) > 0.99
    # the skirt is a flared wall: no part of it folds in towards the axis (OCC's default loft
    # degree made a fold across the axis near the hem)
    c = dress.points[dress.triangles()].mean(axis=1)
    skirt = c[:, 2] < hip.z
    hip_hull = torso.section("hip")[1]
    r_body = np.linalg.norm(hip_hull - hip_hull.mean(axis=0), axis=1).min()
    assert np.linalg.norm(c[skirt, :2] - hip_hull.mean(axis=0), axis=1).min() > r_body


def _edge_lengths(gm, names):
    pairs = np.concatenate([gm.edge_nodes[n] for n in names])
    return np.linalg.norm(gm.points[pairs[:, 0]] - gm.points[pairs[:, 1]], axis=1)


def test_edge_refinement_sizes(torso):
    """Along the refined edges the segments are ratio × h (the size asked for), elsewhere h;
    the rest of the garment far from them keeps the uniform mesh's cell count per area."""
    h = 0.03
    plain = make_gilet(torso, h=h)
    fine = make_gilet(torso, h=h, refine=EdgeRefinement(("armhole",), ratio=0.25, band=0.03))
    arm = ["armhole_left", "armhole_right"]
    assert np.median(_edge_lengths(plain, arm)) == pytest.approx(h, rel=0.25)
    assert np.median(_edge_lengths(fine, arm)) == pytest.approx(0.25 * h, rel=0.25)
    # the hem is 0.3 m below the armholes: untouched
    assert np.median(_edge_lengths(fine, ["hem"])) == pytest.approx(h, rel=0.25)
    assert len(fine.cells) > 1.2 * len(plain.cells)
    with pytest.raises(GeometryError, match="no edge named cuff"):
        make_gilet(torso, h=h, refine=EdgeRefinement(("cuff",)))
    with pytest.raises(ValueError, match="ratio"):
        EdgeRefinement(ratio=0.0)


def test_stocking_graduated_negative_ease(torso):
    st = make_stocking(torso, "left", h=0.012)
    m = torso.measurements
    for level, ease in (("ankle", -0.20), ("calf", -0.16), ("knee", -0.13), ("thigh", -0.10)):
        row = st.level(f"{level}_left")
        assert row.ease == pytest.approx(ease)
        assert row.clearance < 0
        assert st.girth(row.z) == pytest.approx((1 + ease) * m.girth(level), rel=0.01)
    assert {"hem", "welt", "seam_left", "seam_right"} == set(st.edges)
    centre = torso.section("knee_left")[1].mean(axis=0)
    assert _outward_fraction(st, centre) > 0.99


@pytest.mark.parametrize("quads", [False, True])
def test_tube_on_cylinder(quads):
    R, ease = 0.1, -0.07
    body = cylinder_body(R, 0.2, h=0.02)
    tube = make_tube(body, ease, h=0.015, quads=quads)
    assert tube.cells.shape[1] == (4 if quads else 3)
    assert tube.girth(0.1) == pytest.approx((1 + ease) * 2 * np.pi * R, rel=0.01)
    r = np.linalg.norm(tube.points[:, :2], axis=1)
    assert np.median(r) == pytest.approx(R * (1 + ease), abs=2e-4)  # clearance = ease·R
    assert tube.level("mid").clearance == pytest.approx(ease * R, rel=1e-3)
    assert _outward_fraction(tube, np.zeros(2)) == 1.0
    q = quality_report(tube.points, tube.cells)
    assert q["min_angle_deg"] > (30 if not quads else 20)
