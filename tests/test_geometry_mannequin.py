"""The parametric mannequin: requested girths, a closed outward surface, all regions present."""

import numpy as np
import pytest

from fenics_garment.geometry import MeshSizes, MissingRegion, make_mannequin, measurements
from fenics_garment.geometry.sections import SectionShape, perimeter, slice_loops, tape_girth


@pytest.fixture(scope="module")
def body():
    return make_mannequin(measurements("88"), MeshSizes(coarse=0.02, fine=0.02))


def test_sections_perimeter_of_circle_and_ellipse():
    # independent references: 2πr, and Ramanujan's ellipse perimeter
    r = 0.1
    assert perimeter(SectionShape(r, r, r).points(2000)) == pytest.approx(2 * np.pi * r, rel=1e-5)
    a, b = 0.15, 0.1
    h = ((a - b) / (a + b)) ** 2
    ram = np.pi * (a + b) * (1 + 3 * h / (10 + np.sqrt(4 - 3 * h)))
    assert perimeter(SectionShape(a, b, b).points(4000)) == pytest.approx(ram, rel=1e-5)


def test_slice_of_a_cube_is_its_perimeter():
    v = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], float)
    q = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    t = np.array([tri for a, b, c, d in q for tri in ((a, b, c), (a, c, d))])
    (loop,) = slice_loops(v, t, 0.3)
    assert tape_girth(loop) == pytest.approx(4.0)


@pytest.mark.parametrize(
    "level", ["neck", "bust", "underbust", "waist", "hip", "thigh", "knee", "calf", "ankle"]
)
def test_girths_match_request(body, level):
    requested = body.measurements.girth(level)
    sides = ["_left", "_right"] if level in ("thigh", "knee", "calf", "ankle") else [""]
    for s in sides:
        assert body.girth(level + s) == pytest.approx(requested, rel=0.01)


def test_overrides_change_the_surface():
    m = measurements("88", waist_girth=0.80)
    b = make_mannequin(m, MeshSizes(coarse=0.025, fine=0.025), z_range=(0.9, 1.2), legs=False)
    assert b.girth("waist") == pytest.approx(0.80, rel=0.01)


def test_closed_manifold_outward(body):
    info = body.check()
    assert info["closed_manifold"]
    assert info["components"] == 1
    assert info["volume"] > 0.03  # m³: an adult torso + legs is tens of litres, and positive


def test_every_region_present(body):
    from fenics_garment.geometry.regions import REGIONS

    expected = set(REGIONS) - {"arms", "head"}  # the parametric mannequin has neither
    assert set(body.regions) == expected
    for name in expected:
        assert body.triangles_of(name).size > 0
    with pytest.raises(MissingRegion) as err:
        body.triangles_of("elbow")
    assert "waist" in str(err.value)


def test_crop_keeps_only_the_band():
    b = make_mannequin(sizes=MeshSizes(0.03, 0.015, band=(1.0, 1.3)), z_range=(0.85, 1.45))
    z = b.vertices[:, 2]
    assert z.min() == pytest.approx(0.85, abs=1e-6) and z.max() == pytest.approx(1.45, abs=1e-6)
    assert b.check()["closed_manifold"] and b.check()["volume"] > 0
    assert "thighs" not in b.regions and "waist" in b.regions
    # finer inside the band: shorter edges at the waist than at the hip cap
    assert b.girth("waist") == pytest.approx(b.measurements.waist_girth, rel=0.01)


def test_astm_size_table_in_metres():
    # ASTM D5585-11e1 Table 1, size 10: bust 37 1/4 in, under-bust 31 in, curvy waist 29 in,
    # straight waist 30 1/2 in, mid-neck 13 7/8 in; 1 in = 0.0254 m exactly.
    m = measurements("US10")
    assert m.bust_girth == pytest.approx(37.25 * 0.0254, rel=1e-12)
    assert m.underbust_girth == pytest.approx(31.0 * 0.0254, rel=1e-12)
    assert m.waist_girth == pytest.approx(29.0 * 0.0254, rel=1e-12)
    assert m.neck_girth == pytest.approx(13.875 * 0.0254, rel=1e-12)
    assert measurements("US10", figure="straight").waist_girth == pytest.approx(30.5 * 0.0254)


def test_en_size_interpolates_the_astm_torso():
    # Bust 88 cm lies between ASTM sizes 4 (34 1/8 in) and 6 (35 1/4 in); the under-bust is
    # interpolated linearly between 28 and 29 in at the same fraction.
    m = measurements("88")
    b4, b6 = 34.125 * 0.0254, 35.25 * 0.0254
    f = (0.88 - b4) / (b6 - b4)
    assert m.bust_girth == 0.88
    assert m.underbust_girth == pytest.approx((28.0 + f) * 0.0254, rel=1e-12)
    assert m.underbust_girth < m.bust_girth and m.waist_girth < m.underbust_girth


@pytest.mark.parametrize("size", ["86", "US22", "M", ""])
def test_unknown_size_is_a_clear_error(size):
    with pytest.raises(KeyError, match="unknown"):
        measurements(size)


def test_second_order_body():
    # order 2: every 6-node triangle split in four flat ones through its mid-edge nodes (which gmsh
    # puts on the curved loft): still one closed, outward, manifold surface with the requested
    # girths and all regions
    from fenics_garment.geometry.regions import REGIONS

    m = measurements("88")
    kw = dict(z_range=(0.95, 1.25), legs=False)
    b1 = make_mannequin(m, MeshSizes(coarse=0.05, fine=0.05), **kw)
    b2 = make_mannequin(m, MeshSizes(coarse=0.05, fine=0.05), order=2, **kw)
    info = b2.check()
    assert info["closed_manifold"] and info["components"] == 1 and info["volume"] > 0
    assert len(b2.triangles) == 4 * len(b1.triangles)
    for level in ("waist", "underbust"):
        assert b2.girth(level) == pytest.approx(m.girth(level), rel=0.01)
    assert {r for r in b2.regions if len(b2.triangles_of(r))} == {
        r for r in b1.regions if len(b1.triangles_of(r))
    }
    assert set(b2.regions) <= set(REGIONS)


@pytest.mark.parametrize("level", ["waist", "underbust", "bust", "hip"])
def test_sections_are_smooth_across_the_side_lines(level):
    """The back and front halves of a section meet with one tangent and (to 5 %) one
    curvature at +x and −x: a kink of angle θ there would carry a line force Tθ from a garment
    in hoop tension T (a pressure that grows without limit as the garment mesh is refined)."""
    import gmsh

    from fenics_garment.geometry.gmsh_utils import gmsh_session
    from fenics_garment.geometry.mannequin import ring_wire, torso_sections
    from fenics_garment.geometry.sections import resample_by_angle

    z, pts = torso_sections(measurements("88"))[level]
    with gmsh_session(name="wire") as g:
        p = resample_by_angle(pts, 24, centre=pts.mean(axis=0))
        ring_wire(g, np.column_stack([p, np.full(24, z)]))
        g.model.occ.synchronize()
        (_, back), (_, front) = g.model.getEntities(1)

        def ends(c):
            lo, hi = (b[0] for b in gmsh.model.getParametrizationBounds(1, c))
            out = []
            for u in (lo, hi):
                d = np.array(gmsh.model.getDerivative(1, c, [u]))
                out.append((np.array(gmsh.model.getValue(1, c, [u])), d / np.linalg.norm(d),
                            gmsh.model.getCurvature(1, c, [u])[0]))  # fmt: skip
            return out

        (b0, b1), (f0, f1) = ends(back), ends(front)
    for (xa, ta, ka), (xb, tb, kb) in ((b1, f0), (f1, b0)):  # at −x, then at +x
        assert np.linalg.norm(xa - xb) < 1e-9
        assert abs(xa[1]) < 0.02 and abs(xa[0]) > 0.1  # a lateral point
        assert np.degrees(np.arccos(min(1.0, ta @ tb))) < 0.01
        assert ka == pytest.approx(kb, rel=0.05)
