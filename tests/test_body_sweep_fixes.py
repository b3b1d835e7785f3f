"""The body-population sweep's failures (``benchmarks/results/bodies.json``), each on the body it
failed on, read from its export as the sweep reads it.

* The scan gilet on the short, heavy, old woman was refused ("the garment starts 69.1 mm inside
  the body … level 'neck_base'"): the loft through its unevenly spaced levels (under-bust and
  bust 1.4 cm apart, hip and abdomen 10 cm) overshot 6.7 cm into the belly, and its neck base
  was on the shoulders' slope (1.68 × the neck girth), so that the straps left no room for
  the armholes. The tall, heavy, muscular man's neck was found at the crown of his head.
* The scan sleeve on the female body was refused by the body's nominal mesh size (1 cm) against
  the wrist's radius (19.3 mm), although the scan's own facets there are 5–9 mm round the arm.
* The scan gilet on the female body pressed 3.1 % of its contact force on the arms (check
  ``uncovered_contact``): its armholes were cut up to the arm roots.

References not from the code under test: trimesh's vertex normals and sections of the body.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from fenics_garment._stack import MPI
from fenics_garment.geometry import garments as gm
from fenics_garment.geometry import population as pop
from fenics_garment.geometry.anatomy import PARTS
from fenics_garment.geometry.scan import load_scan

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial")
#: the scan gilet's ease (demos/scan_gilet.toml)
EASE = {"hip": 0.03, "abdomen": 0.03, "waist": 0.02, "underbust": 0.03, "bust": 0.03,
        "upper_chest": 0.02, "shoulder": 0.03, "neck_base": 0.15}  # fmt: skip


@pytest.fixture(scope="module")
def bodies(tmp_path_factory) -> dict:
    folder = tmp_path_factory.mktemp("bodies")
    cache: dict = {}

    def get(name: str):
        if name not in cache:
            cache[name] = load_scan(pop.export(pop.by_name(name), folder))
        return cache[name]

    return cache | {"get": get}


def _tape(body, z: float) -> float:
    """trimesh's section of the body at ``z``: the convex-hull perimeter of the piece that
    straddles x = 0 (a tape round the neck: no arm reaches above the shoulder points), as
    ``test_population._torso_girth`` measures it."""
    from test_population import _torso_girth

    return _torso_girth(trimesh.Trimesh(body.vertices, body.triangles, process=False), z)


def _depth_inside(body, points: np.ndarray) -> np.ndarray:
    """How far [m] each point lies inside the body (0 outside), against its nearest vertex and
    trimesh's vertex normal there."""
    m = trimesh.Trimesh(body.vertices, body.triangles, process=False)
    _, i = cKDTree(m.vertices).query(points)
    return np.maximum(np.einsum("ij,ij->i", m.vertices[i] - points, m.vertex_normals[i]), 0.0)


def test_the_neck_base_is_off_the_shoulders_slope(bodies):
    body, rep = bodies["get"]("f-short-heavy-old")
    L = rep["landmarks"]
    assert L["shoulder"] < L["neck_base"] < L["neck"] < L["head"]
    ratio = _tape(body, L["neck_base"]) / _tape(body, L["neck"])
    assert ratio < 1.3, ratio  # was 1.68: 0.52 m of tape across the shoulders
    # where the rule of 60 % of the way up was not on the slope, it is kept
    body, rep = bodies["get"]("female")
    L = rep["landmarks"]
    narrow = 2.0 * L["neck"] - L["neck_base"]  # the neck level is mid-way base–narrowest girth
    assert L["neck_base"] == pytest.approx(L["shoulder"] + 0.6 * (narrow - L["shoulder"]))


def test_a_thick_neck_under_a_narrow_head_is_found(bodies):
    """The tall, heavy, muscular man: a thick neck under a head only 1.11 × its girth. The neck
    was the crown (34 cm above the shoulder points, 14 % of the stature). The head now starts
    at the chin's underside, within 1.5 cm of the menton found independently on the front of
    the mid-sagittal section (``benchmarks.landmarks._menton``, trimesh)."""
    from benchmarks.landmarks import Tape, _menton

    body, rep = bodies["get"]("m-tall-heavy-muscular")
    L = rep["landmarks"]
    H = float(body.vertices[:, 2].max())
    menton = _menton(Tape(body.vertices, body.triangles), L["shoulder"], H - 0.05)
    assert L["head"] == pytest.approx(menton, abs=0.015)
    assert L["shoulder"] < L["neck_base"] < L["neck"] < L["head"] < H - 0.1
    assert L["neck"] - L["shoulder"] < 0.07 * H


def test_the_gilet_stays_between_its_sections_and_clears_the_arms(bodies):
    """The scan gilet's pattern (before dressing) on the short, heavy, old woman and on the
    female body: no deeper than 15 mm inside the body (was 69 mm: the loft's overshoot into the
    belly) and at least 3 mm from the arms (was 1.5 mm and 1.9 mm)."""
    for name, deepest in (("f-short-heavy-old", 0.015), ("female", 0.015)):
        body, _ = bodies["get"](name)
        g = gm.make_gilet(body, ease=EASE, h=0.03, order=1)
        depth = _depth_inside(body, g.points)
        assert depth.max() < deepest, (name, depth.max(), g.points[np.argmax(depth)])
        arm = np.isin(body.part, [PARTS["arm_left"], PARTS["arm_right"]])
        arm_points = body.vertices[np.unique(body.triangles[arm])]
        clearance = cKDTree(arm_points).query(g.points)[0].min()
        assert clearance > 0.003, (name, clearance)


def test_loft_guide_rings_do_not_overshoot():
    """The guide rings between sections stay within their neighbours' range (PCHIP), where a
    spline through the sections alone would not."""
    from fenics_garment.geometry.mannequin import guide_rings

    zs = [0.0, 0.025, 0.13, 0.235, 0.27, 0.285, 0.37]  # the woman's levels' spacing
    fronts = [-0.059, -0.059, -0.081, -0.066, -0.060, -0.087, -0.053]
    ang = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    rings = [np.column_stack([0.15 * np.cos(ang), -f * np.sin(ang), np.full(24, z)])
             for z, f in zip(zs, fronts, strict=True)]  # fmt: skip
    out = guide_rings(rings, 0.02)
    z = np.array([r[0, 2] for r in out])
    assert np.all(np.diff(z) > 0) and np.max(np.diff(z)) <= 0.02 + 1e-12
    k = 18  # the point at the front (−y)
    for r in out:
        i = np.searchsorted(zs, r[0, 2], side="right") - 1
        lo, hi = sorted((rings[i][k, 1], rings[min(i + 1, len(zs) - 1)][k, 1]))
        assert lo - 1e-12 <= r[k, 1] <= hi + 1e-12


def test_the_scan_sleeve_is_checked_against_the_scans_own_facets(tmp_path, monkeypatch):
    """The female body's scan sleeve is built and passes the pre-solve checks (it was refused by
    the nominal body.mesh_size of 1 cm against the 19.3 mm wrist); the scan's facets are
    measured round the arm at the wrist, and a scan too coarse for its curvature is refused in
    one line that says to remesh it."""
    from dataclasses import replace

    from fenics_garment.scene import build, config, preflight

    path = pop.export(pop.by_name("female"), tmp_path)
    scene = config.load(ROOT / "demos" / "scan_sleeve.toml")
    scene = replace(scene, body=replace(scene.body, file=str(path)))
    built = build.build(scene, MPI.COMM_WORLD)
    r, where = preflight.smallest_body_radius(built)
    assert "wrist" in where and r < 2 * scene.body.mesh_size  # the nominal size was refused
    h = preflight.body_facet_size(built)
    assert h is not None and 0.002 < h < preflight.MAX_BODY_H_OVER_R * r
    preflight.check_built(built)  # no PreflightError
    monkeypatch.setattr(preflight, "MAX_BODY_H_OVER_R", 0.5 * h / r)
    with pytest.raises(preflight.PreflightError) as err:
        preflight.mesh_resolution(built)
    msg = str(err.value)
    assert "\n" not in msg and "[body.file]" in msg and "body.remesh = true" in msg, msg


@pytest.mark.slow  # a scan dress built on an exported body: ~45 s
def test_the_facets_under_a_loose_neckline_are_not_checked(tmp_path, monkeypatch):
    """The short woman's scan dress was refused for 23.2 mm facets at the neck base (limit
    23.05 mm, half its radius), where the dress has 25 % ease and does not touch: the facet
    check looks where the garment is fitted (preflight.LOOSE_EASE), and passes there."""
    from dataclasses import replace

    from fenics_garment.scene import build, config, preflight

    path = pop.export(pop.by_name("f-short"), tmp_path)
    scene = config.load(ROOT / "demos" / "scan_dress.toml")
    scene = replace(scene, body=replace(scene.body, file=str(path)))
    built = build.build(scene, MPI.COMM_WORLD)
    r_all, where_all = preflight.smallest_body_radius(built)
    r, where = preflight.smallest_body_radius(built, pressed=True)
    assert "neck_base" in where_all and "neck_base" not in where and r > r_all
    preflight.mesh_resolution(built)  # no PreflightError
    monkeypatch.setattr(preflight, "LOOSE_EASE", 1.0)  # every level, as before
    with pytest.raises(preflight.PreflightError, match="neck_base"):
        preflight.mesh_resolution(built)


@pytest.mark.slow  # two scan dresses built on exported bodies (15 s alone)
def test_a_body_whose_surface_crosses_itself_and_a_hanging_breast_are_dressed(tmp_path):
    """MakeHuman's short, heavy, flabby old man has thigh and calf overlapping behind the knee:
    the contact search's pseudonormal sign took a point 10 cm behind his leg as 110 mm inside
    it, and the dress was refused. A point the pseudonormal puts deeper than 2 mm inside is now
    confirmed by the generalised winding number (``search.WINDING_DEPTH``): the dress passes
    the pre-solve checks, and the garment's deepest point is inside the body by libigl's exact
    winding number (an independent inside/outside test).

    The hanging breast of the soft, heavy, max-cup woman was really inside the loft (41.8 mm at
    1.044 m, between the under-bust and bust sections at 1.025 and 1.056 m). The bodice now
    bridges it (``garments._under_the_overhang``): between the two levels no garment node lies
    more than 5 mm inside the body by libigl's signed distance (winding number), and the dress
    passes the pre-solve checks."""
    from dataclasses import replace

    import igl

    from fenics_garment.scene import build, config, preflight

    scene = config.load(ROOT / "demos" / "scan_dress.toml")

    def built_on(name: str):
        path = pop.export(pop.by_name(name), tmp_path)
        return build.build(replace(scene, body=replace(scene.body, file=str(path))),
                           MPI.COMM_WORLD)  # fmt: skip

    built = built_on("m-short-heavy-flabby-old")
    assert preflight.check_built(built) < 0.02  # was 110 mm, refused
    p, _ = preflight.deepest_point(built)
    b = built.body
    w = igl.winding_number(b.vertices, b.triangles.astype(np.int64), p[None, :].astype(float))
    assert w[0] > 0.5

    built = built_on("f-maxcup-soft-heavy")
    assert preflight.check_built(built) < 0.0418 / 2  # the deepest point, now elsewhere
    b, x = built.body, built.garment.points
    x = x[(x[:, 2] >= b.landmarks["underbust"]) & (x[:, 2] <= b.landmarks["bust"])]
    depth = igl.signed_distance(x, b.vertices, b.triangles.astype(np.int64))[0]
    assert len(x) > 20 and depth.min() > -0.005
