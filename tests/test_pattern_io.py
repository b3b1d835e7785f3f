"""Sewing-pattern readers and writers (fenics_garment.pattern: io, garmentcode, dxf, validate).

Serial and fast; no DOLFINx. Every length and area is checked against a closed form: arc
length r·θ, the quadratic Bézier's arc-length integral, circular-segment areas, the
(2/3)-triangle area between a parabola and its chord, polygon areas.
"""

import json
import math

import ezdxf
import numpy as np
import pytest

from fenics_garment.pattern import (
    Arc,
    Bezier,
    Edge,
    EdgeRange,
    Line,
    Panel,
    Pattern,
    PatternError,
    Placement,
    Polyline,
    Seam,
    Wrap,
)
from fenics_garment.pattern.io import read_pattern, write_pattern
from fenics_garment.pattern.model import arc_from_radius, euler_xyz, rotation_xyz
from fenics_garment.pattern.validate import first_crossing, oriented, signed_area, validate

# ------------------------------------------------------------------------- closed forms


def quad_bezier_length(p0, p1, p2) -> float:
    """∫₀¹ |B'(t)| dt of a quadratic Bézier, B' = 2(b + t a): the closed form of
    ∫ √(At² + Bt + C) dt."""
    p0, p1, p2 = (np.asarray(p, float) for p in (p0, p1, p2))
    a, b = p0 - 2 * p1 + p2, p1 - p0
    A, B, C = a @ a, 2 * a @ b, b @ b

    def F(t):
        q = math.sqrt(A * t * t + B * t + C)
        return (2 * A * t + B) * q / (4 * A) + (4 * A * C - B * B) / (8 * A**1.5) * math.log(
            2 * math.sqrt(A) * q + 2 * A * t + B
        )

    return 2 * (F(1.0) - F(0.0))


def tri_area(p0, p1, p2) -> float:
    (x0, y0), (x1, y1), (x2, y2) = p0, p1, p2
    return 0.5 * abs((x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0))


def shoelace(p) -> float:
    p = np.asarray(p, float)
    q = np.roll(p, -1, axis=0)
    return 0.5 * float(np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]))


def one_line_error(fn, *needles):
    with pytest.raises(PatternError) as info:
        fn()
    msg = str(info.value)
    assert "\n" not in msg, msg
    for n in needles:
        assert n in msg, f"{n!r} not in {msg!r}"
    return msg


# ------------------------------------------------------------------------- our format

SKIRT = """
name = "skirt"
units = "mm"

[[panel]]
name = "front"
fabric = "jersey"
grain = [0, 1]
start = [0, 0]
placement = { translation = [-200, 900, 150], rotation = [10, 20, 30] }
wrap = { axis = "torso", azimuth = -90, top = "waist" }
edges = [
  { to = [400, 0], name = "hem" },
  { to = [400, 600], name = "side_left" },
  { to = [0, 600], name = "waist", curve = "arc", radius = 250, ccw = true },
  { name = "side_right", curve = "bezier", controls = [[-20, 300]] },
]

# the back is drawn clockwise: the reader turns it round and remaps the seams
[[panel]]
name = "back"
grain = [0, 1]
edges = [
  { from = [0, 0], to = [0, 600], name = "side_left" },
  { to = [400, 600], name = "waist", curve = "arc", through = [200, 650] },
  { to = [400, 0], name = "side_right", curve = "polyline", points = [[410, 300]] },
  { to = [0, 0], name = "hem" },
]

[[seam]]
name = "side_seam_left"
a = { panel = "front", edge = "side_left" }
b = { panel = "back", edge = "side_left" }
reversed = false

[[seam]]
name = "half_right"
a = { panel = "front", edge = 3, from = 0.5, to = 1 }
b = { panel = "front", edge = "hem", from = 0.75, to = 0 }
kind = "dart"
"""


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_our_format_reads_closed_forms(tmp_path):
    pat = read_pattern(write(tmp_path, "skirt.toml", SKIRT))
    front, back = pat.panels["front"], pat.panels["back"]
    assert pat.name == "skirt" and front.fabric == "jersey" and back.fabric is None
    # the waist arc: radius 250 mm over a 400 mm chord, turning counter-clockwise
    theta = 2 * math.asin(0.2 / 0.25)
    waist = front.edges[2].curve
    assert isinstance(waist, Arc)
    assert waist.length == pytest.approx(0.25 * theta, rel=1e-12)
    assert waist.point(0.5)[0] == pytest.approx([0.2, 0.6 + 0.25 - 0.25 * math.cos(theta / 2)])
    side = front.edges[3].curve
    assert isinstance(side, Bezier) and np.allclose(side.end, [0, 0])  # `to` left out: closes
    q = quad_bezier_length([0, 0.6], [-0.02, 0.3], [0, 0])
    assert side.length == pytest.approx(q, rel=1e-5)  # the model's 400-chord table
    segment = 0.25**2 / 2 * (theta - math.sin(theta))
    bulge = 2 / 3 * tri_area([0, 0.6], [-0.02, 0.3], [0, 0])
    assert signed_area(front) == pytest.approx(0.4 * 0.6 + segment + bulge, rel=1e-5)
    # placement: intrinsic XYZ Euler angles; wrap kept as data
    assert np.allclose(front.placement.translation, [-0.2, 0.9, 0.15])
    assert np.allclose(front.placement.rotation, rotation_xyz([10, 20, 30]))
    assert front.wrap == Wrap("torso", -90.0, "waist")
    # the clockwise back is now counter-clockwise, its edges renumbered
    assert signed_area(back) > 0
    assert [e.name for e in back.edges] == ["hem", "side_right", "waist", "side_left"]
    assert np.allclose(back.edges[0].curve.start, [0, 0])
    assert np.allclose(back.edges[3].curve.start, [0, 0.6])
    # the seam still joins the hems: front side_left f0 (hem) meets back side_left's hem end
    s = pat.seams[0]
    assert s.b == EdgeRange("back", 3, 0.0, 1.0) and s.reversed is True
    a_hem = front.edges[s.a.edge].curve.point(s.a.f0)[0]
    b_hem = back.edges[s.b.edge].curve.point(s.b.f1 if s.reversed else s.b.f0)[0]
    assert a_hem[1] == pytest.approx(0.0) and b_hem[1] == pytest.approx(0.0)
    # from > to is read as to … from with `reversed` flipped
    d = pat.seams[1]
    assert d.kind == "dart" and d.b == EdgeRange("front", 0, 0.0, 0.75) and d.reversed is False
    assert pat.range_length(d.a) == pytest.approx(q / 2, rel=1e-5)
    assert pat.range_length(d.b) == pytest.approx(0.3, rel=1e-12)


def test_darts_in_panel(tmp_path):
    text = """
units = "cm"
[[panel]]
name = "p"
grain = [1, 0]
start = [0, 0]
darts = [["in", "out"]]
edges = [
  { to = [40, 0] }, { to = [40, 30] }, { to = [25, 30] },
  { to = [20, 20], name = "in" }, { to = [15, 30], name = "out" }, { to = [0, 30] }, {},
]
"""
    pat = read_pattern(write(tmp_path, "d.toml", text))
    (s,) = pat.seams
    assert (s.kind, s.a.edge, s.b.edge, s.reversed) == ("dart", 3, 4, True)
    assert pat.range_length(s.a) == pytest.approx(math.hypot(0.05, 0.1), rel=1e-12)
    assert signed_area(pat.panels["p"]) == pytest.approx(0.4 * 0.3 - 0.5 * 0.1 * 0.1)


@pytest.mark.parametrize("suffix, units", [(".toml", "mm"), (".json", "cm"), (".toml", "m")])
def test_round_trip_exact(tmp_path, suffix, units):
    pat = read_pattern(write(tmp_path, "skirt.toml", SKIRT))
    out = tmp_path / f"again{suffix}"
    write_pattern(pat, out, units=units)
    back = read_pattern(out)
    assert back.name == pat.name and list(back.panels) == list(pat.panels)
    for name, p in pat.panels.items():
        q = back.panels[name]
        assert (q.fabric, q.wrap) == (p.fabric, p.wrap)
        assert np.abs(q.grain - p.grain).max() < 1e-15
        if p.placement is not None:
            assert np.abs(q.placement.translation - p.placement.translation).max() < 1e-12
            assert np.abs(q.placement.rotation - p.placement.rotation).max() < 1e-12
        assert len(q.edges) == len(p.edges)
        for e, f in zip(p.edges, q.edges, strict=True):
            assert (type(e.curve), e.name) == (type(f.curve), f.name)
            for key in ("start", "end", "through", "points"):
                if hasattr(e.curve, key):
                    assert np.abs(getattr(e.curve, key) - getattr(f.curve, key)).max() < 1e-12
            if isinstance(e.curve, Bezier):
                assert np.abs(np.subtract(e.curve.controls, f.curve.controls)).max() < 1e-12
    assert back.seams == pat.seams


def test_euler_xyz_inverse():
    for angles in ([10, 20, 30], [0, 90, 0], [-170, 45, 120]):
        r = rotation_xyz(angles)
        assert np.allclose(r @ r.T, np.eye(3))
        assert np.abs(rotation_xyz(euler_xyz(r)) - r).max() < 1e-12
    # R = Rx Ry Rz: a rotation about x after one about z (applied to the vector first)
    assert np.allclose(rotation_xyz([90, 0, 90]) @ [1, 0, 0], [0, 0, 1])


def test_arc_from_radius_flags():
    for large in (False, True):
        for ccw in (False, True):
            arc = arc_from_radius([0, 0], [1, 0], 1.0, large=large, ccw=ccw)
            theta = 2 * math.asin(0.5)
            assert arc.length == pytest.approx(2 * math.pi - theta if large else theta)
            assert arc.circle[3] > 0 if ccw else arc.circle[3] < 0
            # counter-clockwise: the arc's middle is right of the chord (below it here)
            assert (arc.through[1] < 0) == ccw


# ------------------------------------------------------------------------- GarmentCode

R, U, V = 25.0, 0.5, 0.1  # cm; the circle radius and the quadratic's edge-relative control


def garmentcode_spec(stitch_edge=0):
    cubic = [[2 * U / 3, 2 * V / 3], [1 / 3 + 2 * U / 3, 2 * V / 3]]  # the quadratic, elevated
    return {
        "pattern": {
            "panels": {
                # front: counter-clockwise seen from outside (z > 0), as GarmentCode draws it
                "front": {
                    "translation": [-20, 80, 20],
                    "rotation": [0, 0, 0],
                    "vertices": [[0, 0], [40, 0], [40, 60], [0, 60]],
                    "edges": [
                        {"endpoints": [0, 1], "label": "hem"},
                        {
                            "endpoints": [1, 2],
                            "curvature": {"type": "quadratic", "params": [[U, V]]},
                        },
                        {"endpoints": [2, 3], "curvature": {"type": "circle", "params": [R, 0, 1]}},
                        {"endpoints": [3, 0], "curvature": {"type": "cubic", "params": cubic}},
                    ],
                },
                # back (z < 0): clockwise in its own plane, i.e. counter-clockwise from behind
                "back": {
                    "translation": [-20, 80, -20],
                    "rotation": [0, 0, 0],
                    "vertices": [[0, 0], [0, 60], [40, 60], [40, 0]],
                    "edges": [
                        {"endpoints": [0, 1], "curvature": [U, -V]},  # legacy quadratic
                        {"endpoints": [1, 2], "curvature": {"type": "circle", "params": [R, 0, 0]}},
                        {
                            "endpoints": [2, 3],
                            "curvature": {
                                "type": "cubic",
                                "params": [
                                    [2 * U / 3, -2 * V / 3],
                                    [1 / 3 + 2 * U / 3, -2 * V / 3],
                                ],
                            },
                        },
                        {"endpoints": [3, 0], "label": "hem"},
                    ],
                },
            },
            "stitches": [
                [{"panel": "front", "edge": 1}, {"panel": "back", "edge": stitch_edge}],
                [{"panel": "front", "edge": 3}, {"panel": "back", "edge": 2}, "right_wrong"],
            ],
        },
        "properties": {"units_in_meter": 100, "curvature_coords": "relative"},
    }


def test_garmentcode_closed_forms(tmp_path):
    path = tmp_path / "tube_specification.json"
    path.write_text(json.dumps(garmentcode_spec()))
    pat = read_pattern(path)
    assert pat.name == "tube" and set(pat.panels) == {"front", "back"}
    front, back = pat.panels["front"], pat.panels["back"]
    # circle: radius 25 cm over a 40 cm chord
    theta = 2 * math.asin(20 / 25)
    for p in (front, back):
        arc = p.edges[2 if p is front else 1].curve
        assert isinstance(arc, Arc)
        assert arc.length == pytest.approx(0.25 * theta, rel=1e-12)
    # quadratic: control = start + u (end − start) + v (end − start) turned +90°
    q = quad_bezier_length([0.40, 0.0], [0.34, 0.30], [0.40, 0.60])
    assert np.allclose(front.edges[1].curve.controls[0], [0.34, 0.30])
    for e in (front.edges[1], front.edges[3], back.edges[0], back.edges[2]):
        assert e.length == pytest.approx(q, rel=1e-5)
    # the front's circle (right = 1) bulges outwards (up), its sides inwards
    seg = 0.25**2 / 2 * (theta - math.sin(theta))
    inward = 2 / 3 * tri_area([0.40, 0.0], [0.34, 0.30], [0.40, 0.60])
    assert signed_area(front) == pytest.approx(0.24 + seg - 2 * inward, rel=1e-5)
    # the back: circle right = 0 bulges left of (0,60)→(40,60): up, outwards; v = −0.1 on
    # its sides, which run the other way round: inwards too
    assert signed_area(back) == pytest.approx(0.24 + seg - 2 * inward, rel=1e-5)
    # the clockwise back was mirrored x ↦ −x, its rotation turned about y: same 3D points,
    # outline counter-clockwise, local +z out of the body (GarmentCode's −z for a back panel,
    # +y in our frame: z up, the body facing −y)
    assert np.allclose(back.placement.rotation @ [0, 0, 1], [0, 1, 0])
    assert np.allclose(front.placement.rotation @ [0, 0, 1], [0, -1, 0])
    corners = back.placement.apply(np.array([e.curve.start for e in back.edges]))
    # GarmentCode's (x, y, z) = (−0.2, 0.8, −0.2) … is our (x, −z, y)
    assert np.allclose(
        corners, [[-0.2, 0.2, 0.8], [-0.2, 0.2, 1.4], [0.2, 0.2, 1.4], [0.2, 0.2, 0.8]]
    )
    assert np.allclose(back.grain, [0, 1]) and np.allclose(front.grain, [0, 1])
    assert [e.name for e in front.edges] == ["hem", "", "", ""]
    # stitches: GarmentCode joins edge 1's end to edge 2's start unless "right_wrong"
    s0, s1 = pat.seams
    assert (s0.a, s0.b, s0.reversed, s0.kind) == (
        EdgeRange("front", 1),
        EdgeRange("back", 0),
        True,
        "seam",
    )
    assert s1.reversed is False
    assert pat.range_length(s0.a) == pytest.approx(pat.range_length(s0.b), rel=1e-9)


def test_garmentcode_unknown_stitch_edge(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(garmentcode_spec(stitch_edge=7)))
    one_line_error(lambda: read_pattern(path), "'back'", "edge 7", "stitch 0", str(path))


# ------------------------------------------------------------------------- DXF


def aama_dxf(path, *, front_clockwise=True):
    """Two AAMA pieces written with ezdxf itself: boundary on layer 1, turn points on 2,
    grain on 7, units mm ($INSUNITS 4)."""
    doc = ezdxf.new("R2000")
    doc.units = ezdxf.units.MM
    msp = doc.modelspace()
    # front: a 300 × 500 rectangle, its top digitised with collinear points, drawn clockwise
    front = [(0, 0), (0, 500), *[(50 * k, 500) for k in range(1, 6)], (300, 500), (300, 0)]
    if not front_clockwise:
        front = front[::-1]
    b = doc.blocks.new("FRONT_BLOCK")
    b.add_lwpolyline(front, close=True, dxfattribs={"layer": "1"})
    for c in [(0, 0), (300, 0), (300, 500), (0, 500)]:
        b.add_point(c, dxfattribs={"layer": "2"})
    b.add_point((150, 250), dxfattribs={"layer": "2"})  # a turn point of an internal line
    b.add_line((150, 100), (150, 400), dxfattribs={"layer": "7"})
    b.add_text("Piece Name: front", dxfattribs={"layer": "1"})
    msp.add_blockref("FRONT_BLOCK", (0, 0))
    # back: no turn points; corners found by angle; its top a circular arc of radius 300
    # over the 300 chord (60°) digitised in 24 chords (2.5° a vertex)
    yc = 500 - 300 * math.cos(math.radians(30))
    arc = [
        (150 + 300 * math.cos(a), yc + 300 * math.sin(a))
        for a in np.linspace(math.radians(60), math.radians(120), 25)
    ]
    arc[0], arc[-1] = (300, 500), (0, 500)
    back = [(0, 0), (320, 0), *arc]
    b = doc.blocks.new("BACK")
    b.add_polyline2d(back, close=True, dxfattribs={"layer": "1"})
    b.add_line((150, 450), (150, 50), dxfattribs={"layer": "7"})
    msp.add_blockref("BACK", (400, 0))
    doc.saveas(path)
    return np.array(front, float), np.array(back, float), arc


def test_dxf_reads_areas_edges_grain(tmp_path):
    path = tmp_path / "tube.dxf"
    _, back_pts, _ = aama_dxf(path)
    pat = read_pattern(path)
    assert list(pat.panels) == ["front", "BACK"]  # no piece-name text: the block's name
    front, back = pat.panels["front"], pat.panels["BACK"]
    assert signed_area(front) == pytest.approx(0.3 * 0.5, rel=1e-12)
    assert signed_area(back) == pytest.approx(abs(shoelace(back_pts)) * 1e-6, rel=1e-12)
    # the turn points split the front in 4 (its top's collinear points stay in one edge),
    # counter-clockwise from the lower-left corner
    assert [type(e.curve) for e in front.edges] == [Line, Line, Polyline, Line]
    assert np.allclose(
        [e.curve.start for e in front.edges], [[0, 0], [0.3, 0], [0.3, 0.5], [0, 0.5]]
    )
    assert [e.length for e in front.edges] == pytest.approx([0.3, 0.5, 0.3, 0.5], rel=1e-12)
    # the back: corners by angle (> 30°): the arc (2.5° a vertex) is one edge
    assert len(back.edges) == 4
    chords = 24 * 2 * 0.3 * math.sin(math.radians(60) / 24 / 2)  # 24 chords of the arc
    assert back.edges[2].length == pytest.approx(chords, rel=1e-12)
    assert back.edges[2].length == pytest.approx(0.3 * math.pi / 3, rel=1e-3)
    trapezoid = 0.5 * (0.32 + 0.3) * 0.5
    segment = 0.3**2 / 2 * (math.pi / 3 - math.sin(math.pi / 3))
    assert signed_area(back) == pytest.approx(trapezoid + segment, rel=1e-3)
    assert np.allclose(front.grain, [0, 1]) and np.allclose(back.grain, [0, -1])


def test_dxf_with_companion_seams(tmp_path):
    aama_dxf(tmp_path / "tube.dxf", front_clockwise=False)
    comp = write(
        tmp_path,
        "tube.toml",
        """
units = "mm"
source = "tube.dxf"
[[panel]]
name = "front"
fabric = "jersey"
edge_names = ["hem", "side_left", "waist", "side_right"]
[[seam]]
name = "side"
a = { panel = "front", edge = "side_left" }
b = { panel = "BACK", edge = 3 }
""",
    )
    pat = read_pattern(comp)
    (s,) = pat.seams
    assert pat.panels["front"].fabric == "jersey"
    assert s.a == EdgeRange("front", 1) and s.b == EdgeRange("BACK", 3)
    assert pat.range_length(s.a) == pytest.approx(0.5, rel=1e-12)
    assert pat.range_length(s.b) == pytest.approx(0.5, rel=1e-12)


def test_write_dxf_round_trip(tmp_path):
    from fenics_garment.pattern.dxf import write_dxf

    pat = read_pattern(write(tmp_path, "skirt.toml", SKIRT))
    write_dxf(pat, tmp_path / "out.dxf", spacing=1e-3, companion=tmp_path / "out.toml")
    again = read_pattern(tmp_path / "out.toml")
    assert list(again.panels) == list(pat.panels)
    for name, p in pat.panels.items():
        q = again.panels[name]
        assert signed_area(q) == pytest.approx(signed_area(p), rel=1e-4)
        assert sorted(e.name for e in q.edges) == sorted(e.name for e in p.edges)
        for e in p.edges:
            f = q.edges[q.edge_index(e.name)]
            assert f.length == pytest.approx(e.length, rel=1e-4)
        assert (q.fabric, q.wrap) == (p.fabric, p.wrap)
        assert np.allclose(q.grain, p.grain)
    for s, t in zip(pat.seams, again.seams, strict=True):
        assert (s.name, s.kind) == (t.name, t.kind)
        for r, u in ((s.a, t.a), (s.b, t.b)):
            name = pat.panels[r.panel].edges[r.edge].name
            assert again.panels[u.panel].edges[u.edge].name == name
            assert again.range_length(u) == pytest.approx(pat.range_length(r), rel=1e-4)


# ------------------------------------------------------------------------- refusals


def square(name="sq", *, names=("bottom", "right", "top", "left"), size=0.1):
    pts = np.array([[0, 0], [size, 0], [size, size], [0, size]])
    edges = [Edge(Line(pts[i], pts[(i + 1) % 4]), names[i]) for i in range(4)]
    return Panel(name, tuple(edges), [0, 1])


def bad_toml(tmp_path, body, units='"mm"'):
    return write(tmp_path, "bad.toml", f"units = {units}\n" + body)


PANEL = """
[[panel]]
name = "front"
grain = [0, 1]
start = [0, 0]
edges = [{{ to = [100, 0], name = "hem" }}, {{ to = [100, 100], name = "side" }},
         {{ to = [0, 100], name = "top" }}, {{ to = {last}, name = "back_edge" }}]
"""


def test_refuse_open_outline(tmp_path):
    p = bad_toml(tmp_path, PANEL.format(last="[0, 1]"))
    one_line_error(lambda: read_pattern(p), str(p), "'front'", "'back_edge'", "'hem'", "closed")


def test_refuse_self_intersection(tmp_path):
    body = """
[[panel]]
name = "bow"
grain = [0, 1]
start = [0, 0]
edges = [{ to = [100, 100], name = "diag_up" }, { to = [100, 0], name = "right" },
         { to = [0, 100], name = "diag_down" }, { name = "left" }]
"""
    p = bad_toml(tmp_path, body)
    one_line_error(lambda: read_pattern(p), "'bow'", "'diag_up'", "'diag_down'", "crosses")


def test_self_intersection_is_fast_on_2000_points():
    import time

    t = np.linspace(0, 2 * np.pi, 2000, endpoint=False)
    star = np.column_stack([np.cos(t), np.sin(t)]) * (1 + 0.3 * np.sin(7 * t))[:, None]
    t0 = time.perf_counter()
    assert first_crossing(star) is None
    assert time.perf_counter() - t0 < 2.0
    star[1000] = [5, 0]  # a spike that crosses the outline
    assert first_crossing(star) is not None


def test_refuse_too_few_edges_and_no_area(tmp_path):
    one = """
[[panel]]
name = "blob"
grain = [0, 1]
start = [0, 0]
edges = [{ curve = "polyline", points = [[100, 0], [100, 100]], name = "all" }]
"""
    p = bad_toml(tmp_path, one)
    one_line_error(lambda: read_pattern(p), "'blob'", "at least 2 edges")
    two = """
[[panel]]
name = "flat"
grain = [0, 1]
start = [0, 0]
edges = [{ to = [100, 0], name = "out" }, { name = "back" }]
"""
    p = bad_toml(tmp_path, two)
    one_line_error(lambda: read_pattern(p), "'flat'", "no area")


def test_refuse_clockwise_in_validate():
    sq = square()
    cw = Panel(
        "cw",
        tuple(Edge(Line(e.curve.end, e.curve.start), e.name) for e in reversed(sq.edges)),
        [0, 1],
    )
    pat = Pattern("p", {"cw": cw}, source="p.toml")
    one_line_error(lambda: validate(pat), "p.toml", "'cw'", "clockwise")
    fixed = oriented(pat)
    validate(fixed)
    assert [e.name for e in fixed.panels["cw"].edges] == ["bottom", "right", "top", "left"]


def test_refuse_degenerate_arc(tmp_path):
    body = PANEL.format(last="[0, 0]").replace(
        '{ to = [0, 100], name = "top" }',
        '{ to = [0, 100], name = "top", curve = "arc", through = [50, 100] }',
    )
    p = bad_toml(tmp_path, body)
    one_line_error(lambda: read_pattern(p), "'front'", "'top'", "line")


SEAMED = """
[[panel]]
name = "a"
grain = [0, 1]
start = [0, 0]
edges = [{ to = [100, 0], name = "hem" }, { to = [100, 200], name = "side" },
         { to = [0, 200], name = "top" }, { name = "other" }]
[[panel]]
name = "b"
grain = [0, 1]
start = [0, 0]
edges = [{ to = [100, 0], name = "hem" }, { to = [100, SIDE], name = "side" },
         { to = [0, SIDE], name = "top" }, { name = "other" }]
"""


def seamed(tmp_path, seams, side="200"):
    return bad_toml(tmp_path, SEAMED.replace("SIDE", side) + seams)


def test_refuse_seam_length_mismatch(tmp_path):
    seam = '[[seam]]\nname = "s"\na = { panel = "a", edge = "side" }\n'
    seam += 'b = { panel = "b", edge = "side" }\n'
    read_pattern(seamed(tmp_path, seam, side="203"))  # 1.5 %: within 2 %
    p = seamed(tmp_path, seam, side="210")
    msg = one_line_error(lambda: read_pattern(p), "'s'", "'a'", "'b'", "'side'")
    assert "200.0 mm" in msg and "210.0 mm" in msg
    read_pattern(p, seam_tolerance=0.05)


@pytest.mark.parametrize(
    "side_b, needles",
    [
        ('{ panel = "c", edge = "side" }', ["no panel 'c'", "'side'"]),
        ('{ panel = "b", edge = "sidee" }', ["'b'", "no edge named 'sidee'"]),
        ('{ panel = "b", edge = 4 }', ["'b'", "no edge 4"]),
        ('{ panel = "b", edge = "side", from = 0, to = 1.5 }', ["'b'", "'side'", "[0, 1]"]),
        ('{ panel = "b", edge = "side", from = 0.5, to = 0.5 }', ["'b'", "'side'", "[0, 1]"]),
    ],
)
def test_refuse_bad_seam_ranges(tmp_path, side_b, needles):
    p = seamed(tmp_path, f'[[seam]]\na = {{ panel = "a", edge = "side" }}\nb = {side_b}\n')
    one_line_error(lambda: read_pattern(p), str(p), *needles)


OVERLAP = """
[[seam]]
name = "one"
a = { panel = "a", edge = "side", from = 0, to = 0.6 }
b = { panel = "b", edge = "side", from = 0, to = 0.6 }
[[seam]]
name = "two"
a = { panel = "a", edge = "side", from = START, to = 1 }
b = { panel = "b", edge = "other", from = START, to = 1 }
"""


def test_refuse_overlapping_seams(tmp_path):
    p = seamed(tmp_path, OVERLAP.replace("START", "0.5"))
    one_line_error(lambda: read_pattern(p), "'a'", "'side'", "'one'", "'two'", "overlap")
    read_pattern(seamed(tmp_path, OVERLAP.replace("START", "0.6")))  # touching is fine


def test_refuse_missing_grain_unknown_units_unknown_keys(tmp_path):
    p = bad_toml(tmp_path, PANEL.format(last="[0, 0]").replace("grain = [0, 1]\n", ""))
    one_line_error(lambda: read_pattern(p), "'front'", "grain")
    p = bad_toml(tmp_path, PANEL.format(last="[0, 0]"), units='"furlong"')
    one_line_error(lambda: read_pattern(p), "'furlong'")
    p = bad_toml(
        tmp_path, PANEL.format(last="[0, 0]").replace("grain =", "grian = [1, 0]\ngrain =")
    )
    one_line_error(lambda: read_pattern(p), "'front'", "'grian'")
    p = bad_toml(
        tmp_path,
        PANEL.format(last="[0, 0]").replace('name = "top" }', 'name = "top", through = [1, 2] }'),
    )
    one_line_error(lambda: read_pattern(p), "'front'", "'top'", "'through'")


def test_refuse_dxf_without_grain(tmp_path):
    doc = ezdxf.new("R2000")
    doc.units = ezdxf.units.CM
    b = doc.blocks.new("P")
    b.add_lwpolyline([(0, 0), (10, 0), (10, 10), (0, 10)], close=True, dxfattribs={"layer": "1"})
    b.add_text("Piece Name: pocket", dxfattribs={"layer": "1"})
    doc.modelspace().add_blockref("P", (0, 0))
    doc.saveas(tmp_path / "p.dxf")
    one_line_error(lambda: read_pattern(tmp_path / "p.dxf"), "'pocket'", "grain", "layer 7")


def test_model_objects_validate_directly():
    a, b = square("a"), square("b")
    ok = Pattern("p", {"a": a, "b": b}, (Seam(EdgeRange("a", 1), EdgeRange("b", 3)),))
    validate(ok)
    bad = Pattern("p", {"a": a, "b": b}, (Seam(EdgeRange("a", 1), EdgeRange("b", 9)),))
    one_line_error(lambda: validate(bad), "'b'", "no edge 9")
    placed = Panel("a", a.edges, [1, 1], "cotton", Placement([0, 1, 0]), Wrap("arm_left", 0.0))
    validate(Pattern("p", {"a": placed}))
