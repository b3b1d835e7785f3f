"""Flat panels meshed with paired seams, placed, sewn into one conforming garment mesh."""

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from fenics_garment._stack import MPI
from fenics_garment.geometry import MeshSizes, make_mannequin, measurements
from fenics_garment.geometry.garments import cylinder_body
from fenics_garment.pattern.mesh import mesh_panels, place
from fenics_garment.pattern.model import (
    Arc,
    Bezier,
    Edge,
    EdgeRange,
    Line,
    Panel,
    Pattern,
    Seam,
    Wrap,
)
from fenics_garment.pattern.sew import pattern_garment, sew


def _rectangle(name, w, h, names=("hem", "right", "top", "left"), grain=(0, 1)):
    c = [(0, 0), (w, 0), (w, h), (0, h)]
    edges = [Edge(Line(c[i], c[(i + 1) % 4]), names[i]) for i in range(4)]
    return Panel(name, edges, grain=grain)


def _cross2(a, b):
    return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]


def _boundary_loops(cells):
    e = np.sort(np.concatenate([cells[:, [0, 1]], cells[:, [1, 2]], cells[:, [2, 0]]]), axis=1)
    uniq, count = np.unique(e, axis=0, return_counts=True)
    free = uniq[count == 1]
    nxt = {}
    for a, b in free:
        nxt.setdefault(a, []).append(b)
        nxt.setdefault(b, []).append(a)
    assert all(len(v) == 2 for v in nxt.values())  # manifold boundary
    seen, loops = set(), 0
    for start in nxt:
        if start in seen:
            continue
        loops += 1
        stack = [start]
        while stack:
            v = stack.pop()
            if v not in seen:
                seen.add(v)
                stack.extend(nxt[v])
    return loops


def _components(cells):
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = cells.max() + 1
    e = np.concatenate([cells[:, [0, 1]], cells[:, [1, 2]]])
    g = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    return connected_components(g, directed=False)[0]


# -- (a) a rectangle sewn edge to edge into a tube around a cylinder -------------------------


def test_tube_wraps_isometrically_and_closes():
    R, r_tube, L, h = 0.1, 0.11, 0.2, 0.01
    body = cylinder_body(R, L, h=0.01)
    panel = _rectangle("tube", 2 * np.pi * r_tube, L)
    seam = Seam(EdgeRange("tube", "right"), EdgeRange("tube", "left"), True, "seam")
    pattern = Pattern("tube", {"tube": panel}, (seam,))
    gm, rest = pattern_garment(pattern, body, h, comm=MPI.COMM_WORLD)
    # every node (the curved mesh's edge nodes too) on the tube's radius
    x = gm.mesh.geometry.x
    assert np.abs(np.linalg.norm(x[:, :2], axis=1) / r_tube - 1).max() < 1e-3
    assert np.abs(np.linalg.norm(gm.points[:, :2], axis=1) / r_tube - 1).max() < 1e-3
    # closed: the seam's nodes are merged, two boundary loops (hem and top) remain
    assert _boundary_loops(gm.cells) == 2
    assert set(gm.edges) == {"seam", "hem", "top"}
    seam_length = np.linalg.norm(np.diff(gm.points[gm.edge_nodes["seam"]], axis=1), axis=2)
    assert seam_length.sum() == pytest.approx(L, rel=1e-4)
    assert _components(gm.cells) == 1
    # isometric: each 3-D edge (chord) equals its flat length to 1e-3
    X = gm.points  # the vertices (the cells' first three nodes)
    nodes, flat = rest.cell_nodes, rest.cell_flat
    for i, j in ((0, 1), (1, 2), (2, 0)):
        d3 = np.linalg.norm(X[nodes[:, i]] - X[nodes[:, j]], axis=1)
        d2 = np.linalg.norm(flat[:, i] - flat[:, j], axis=1)
        assert np.abs(d3 / d2 - 1).max() < 1e-3
    # flat triangles counter-clockwise, cells outward, warp vertical (the grain was +y)
    q = flat[:, :3]
    assert np.all(_cross2(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0]) > 0)
    p = gm.points[gm.cells]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert np.all(np.einsum("ij,ij->i", n[:, :2], p.mean(axis=1)[:, :2]) > 0)
    assert np.abs(gm.warp[:, 2]).min() > 0.999
    assert gm.info["inverted"] == 0 and gm.info["strain_max"] < 1e-3
    # the flat rest in DOLFINx's node order: the same lengths as the mesh's own nodes
    on = rest.on_mesh(gm.mesh)
    dm = gm.mesh.geometry.dofmaps[0]
    assert on.shape == (len(dm), 6, 2)
    d3 = np.linalg.norm(x[dm[:, 0]] - x[dm[:, 1]], axis=1)
    d2 = np.linalg.norm(on[:, 0] - on[:, 1], axis=1)
    assert np.abs(d3 / d2 - 1).max() < 1e-3


# -- (b) front and back panels sewn around the mannequin --------------------------------------


def gilet_pattern():
    """A sleeveless two-panel top: side and shoulder seams (drawn as seen from outside)."""

    def panel(name, neck_depth, front):
        a, b = ("left", "right") if front else ("right", "left")
        e = [
            Edge(Line((-0.25, 0), (0.25, 0)), "hem"),
            Edge(Bezier((0.25, 0), (0.227, 0.41), [(0.17, 0.17), (0.20, 0.28)]), f"side_{a}"),
            Edge(Bezier((0.227, 0.41), (0.13, 0.62), [(0.14, 0.47)]), f"armhole_{a}"),
            Edge(Line((0.13, 0.62), (0.085, 0.64)), f"shoulder_{a}"),
            Edge(Arc((0.085, 0.64), (-0.085, 0.64), (0.0, 0.64 - neck_depth)), "neckline"),
            Edge(Line((-0.085, 0.64), (-0.13, 0.62)), f"shoulder_{b}"),
            Edge(Bezier((-0.13, 0.62), (-0.227, 0.41), [(-0.14, 0.47)]), f"armhole_{b}"),
            Edge(Bezier((-0.227, 0.41), (-0.25, 0), [(-0.20, 0.28), (-0.17, 0.17)]), f"side_{b}"),
        ]
        return Panel(name, e, grain=(0, 1), wrap=Wrap(top=0.84 + 0.64))

    seams = []
    for side in ("left", "right"):
        for part in ("side", "shoulder"):
            a, b = EdgeRange("front", f"{part}_{side}"), EdgeRange("back", f"{part}_{side}")
            seams.append(Seam(a, b, True, f"{part}_seam_{side}"))
    panels = {"front": panel("front", 0.08, True), "back": panel("back", 0.02, False)}
    return Pattern("gilet", panels, tuple(seams))


@pytest.fixture(scope="module")
def torso():
    return make_mannequin(measurements("88"), MeshSizes(0.025, 0.025), z_range=(0.3, 1.55))


def test_front_and_back_sew_into_one_surface(torso):
    from fenics_garment.contact.search import SearchSurface

    gm, rest = pattern_garment(gilet_pattern(), torso, 0.03)
    info = gm.info
    assert info["inverted"] == 0
    assert info["seam_gap_max"] < 0.01  # before merging; 0.25 m apart when placed
    assert info["penetration_max"] < 0.002
    assert info["self_contacts"] == 0
    assert info["strain_rms"] < 0.05
    assert _components(gm.cells) == 1
    assert set(gm.panels) == {"front", "back"}
    assert set(gm.edges) == {
        "hem", "neckline", "armhole_left", "armhole_right", "side_seam_left",
        "side_seam_right", "shoulder_seam_left", "shoulder_seam_right",
    }  # fmt: skip
    # hem, neckline, two armholes: four boundary loops
    assert _boundary_loops(gm.cells) == 4
    # cells outward (away from the body) and not folded against their neighbours
    p = gm.points[gm.cells]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    cp = SearchSurface(torso.vertices, torso.triangles).closest(p.mean(axis=1), "gradient")
    assert np.mean(np.einsum("ij,ij->i", n, cp.normal) > 0) > 0.97
    assert np.all(np.einsum("ij,ij->i", n, gm.normal[gm.cells].sum(axis=1)) > 0)
    # the seams are where front and back meet, on their sides of the body
    left = gm.points[np.unique(gm.edge_nodes["side_seam_left"])]
    assert np.all(left[:, 0] > 0.1)
    sh = gm.points[np.unique(gm.edge_nodes["shoulder_seam_right"])]
    assert np.all(sh[:, 0] < 0) and sh[:, 2].min() > torso.landmarks["upper_chest"]
    # every cell's flat triangle counter-clockwise; lengths of the flat rest = the panels'
    q = rest.cell_flat[:, :3]
    assert np.all(_cross2(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0]) > 0)
    # the warp (panels' grain, vertical in the drawing) is mostly vertical on the body
    assert np.median(gm.warp[:, 2]) > 0.95


# -- (c) a dart closes a disc into a cone ----------------------------------------------------


@pytest.mark.parametrize("wedge", [60.0, 120.0])
def test_dart_closes_into_the_closed_form_cone(wedge):
    L, alpha = 0.2, np.radians(wedge)
    ta, tb = -np.pi / 2 + alpha / 2, 1.5 * np.pi - alpha / 2
    pa, pb = L * np.array([np.cos(ta), np.sin(ta)]), L * np.array([np.cos(tb), np.sin(tb)])
    edges = [
        Edge(Line((0, 0), pa), "dart_a"),
        Edge(Arc(pa, pb, (0.0, L)), "hem"),
        Edge(Line(pb, (0, 0)), "dart_b"),
    ]
    disc = Panel("disc", edges, grain=(0, 1), wrap=Wrap("none"))
    dart = Seam(EdgeRange("disc", "dart_a"), EdgeRange("disc", "dart_b"), True, "", "dart")
    pattern = Pattern("cone", {"disc": disc}, (dart,))
    flat = mesh_panels(pattern, 0.012)
    xy = flat.panel_xy
    r = np.linalg.norm(xy, axis=1)
    X0 = place(flat, pattern, None)  # flat, as drawn (wrap "none")
    assert np.allclose(X0[:, :2], xy) and np.all(X0[:, 2] == 0)
    X0[:, 2] = 0.2 * (L - r)  # a shallow cone to break the plane's symmetry
    sewn = sew(flat, X0, None, merged_iterations=250)
    apex = sewn.points[sewn.node_of[np.argmin(r)]]
    rim = np.unique(sewn.node_of[r > L * (1 - 1e-9)])
    u = sewn.points[rim] - apex
    u /= np.linalg.norm(u, axis=1)[:, None]
    axis = u.mean(axis=0) / np.linalg.norm(u.mean(axis=0))
    half = np.arccos(u @ axis).mean()
    # the rim's circumference is the sector's remaining arc (2π − α) L: sin(half) = 1 − α/2π
    assert half == pytest.approx(np.arcsin(1 - alpha / (2 * np.pi)), rel=0.01)
    assert sewn.report["inverted"] == 0
    assert sewn.report["seam_gap_max"] < 1e-3
    assert pattern.seam_name(0) == "dart_0"


# -- (d) both sides of a curved seam get the same nodes at equal arc length ------------------


def _bezier_arc_positions(curve, fractions):
    P = np.array([curve.start, *curve.controls, curve.end])

    def speed(t):
        d = (1 - t) ** 2 * (P[1] - P[0]) + 2 * t * (1 - t) * (P[2] - P[1]) + t**2 * (P[3] - P[2])
        return 3 * np.hypot(*d)

    def s(t):
        return quad(speed, 0.0, t, epsabs=1e-14, epsrel=1e-13, limit=200)[0]

    total = s(1.0)
    ts = [brentq(lambda t, f=f: s(t) - f * total, 0.0, 1.0, xtol=1e-15) for f in fractions]
    return np.array([curve.point(t)[0] for t in ts]), total


def test_curved_seam_sides_pair_at_equal_arc_length():
    arc = Arc((0.3, 0.0), (0.0, 0.3), (0.3 / np.sqrt(2), 0.3 / np.sqrt(2)))
    a = Panel(
        "a",
        [Edge(Line((0, 0), (0.3, 0)), "bottom"), Edge(arc, "curve"), Edge(Line((0, 0.3), (0, 0)))],
        grain=(1, 1),
    )
    bez = Bezier((0.0, 0.0), (0.0, 0.4), [(0.25, 0.05), (0.1, 0.35)])
    b = Panel(
        "b",
        [Edge(bez, "curve"), Edge(Line((0, 0.4), (-0.2, 0.4))), Edge(Line((-0.2, 0.4), (0, 0)))],
        grain=(0, 1),
    )
    # a's arc from 20 % to 90 % of its length against the whole Bézier, running against it
    seam = Seam(EdgeRange("a", "curve", 0.2, 0.9), EdgeRange("b", "curve"), True, "curved")
    flat = mesh_panels(Pattern("two", {"a": a, "b": b}, (seam,)), 0.01)
    side_a, side_b = flat.seam_sides(0)
    assert len(side_a) == len(side_b) and len(side_a) % 2 == 1
    n2 = len(side_a) - 1  # vertices and edge nodes alternate: 2n segments of half length
    assert n2 // 2 == int(np.ceil(max(bez.length, 0.7 * arc.length) / 0.01))
    assert np.all(flat.vertex[side_a[::2]]) and not np.any(flat.vertex[side_a[1::2]])
    xy = flat.panel_xy
    # side a: equal angles on the circle from 20 % to 90 %
    centre, radius, a0, sweep = arc.circle
    ang = a0 + sweep * np.linspace(0.2, 0.9, n2 + 1)
    expect_a = centre + radius * np.column_stack([np.cos(ang), np.sin(ang)])
    assert np.abs(xy[side_a] - expect_a).max() < 1e-9 * arc.length
    # side b: equal arc length on the Bézier (independent quadrature), reversed against a
    expect_b, total = _bezier_arc_positions(bez, np.linspace(1.0, 0.0, n2 + 1))
    assert np.abs(xy[side_b] - expect_b).max() < 1e-9 * total
    # the grain rotation: panel a's grain (1, 1) is +x in the flat frame
    ga = flat.rotation[flat.names.index("a")] @ (np.array([1.0, 1.0]) / np.sqrt(2))
    assert np.allclose(ga, [1.0, 0.0])
    # the segments of the seam carry its index, the others −1
    on_seam = flat.segment_seam >= 0
    assert set(flat.segment_seam[on_seam]) == {0}
    assert on_seam.sum() == n2  # n segments on each side


# -- a placed panel: bent around the body's axis; its back side out is mirrored in the flat ---


@pytest.mark.parametrize("back_out", [False, True])
def test_placed_panel_wraps_and_faces_out(back_out):
    import dataclasses

    from fenics_garment.pattern.model import Placement

    body = cylinder_body(0.1, 0.2, h=0.01)
    # the panel's (x, y) plane stood up in front of the body (y = −0.12): drawn side towards −y,
    # or (back_out) towards the body, mirrored so that it still runs left to right
    rot = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]]) if back_out else None
    rot = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]) if rot is None else rot
    z0 = 0.2 if back_out else 0.0
    place_at = Placement(translation=(-0.1, -0.12, z0), rotation=rot)
    panel = dataclasses.replace(_rectangle("front", 0.2, 0.2), placement=place_at)
    pattern = Pattern("placed", {"front": panel})
    flat = mesh_panels(pattern, 0.02)
    X0 = place(flat, pattern, body)
    # bent isometrically around the axis at its placed distance, centre kept
    assert np.allclose(np.linalg.norm(X0[:, :2], axis=1), 0.12)
    assert np.allclose(np.ptp(np.arctan2(X0[:, 1], X0[:, 0])) * 0.12, 0.2)
    gm, rest = pattern_garment(pattern, body, 0.02)
    p = gm.points[gm.cells]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert np.all(np.einsum("ij,ij->i", n[:, :2], p.mean(axis=1)[:, :2]) > 0)
    q = rest.cell_flat[:, :3]
    assert np.all(_cross2(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0]) > 0)
    # flat x along the grain (the panel's y), flat y the panel's −x, mirrored if back out
    sign = -1.0 if back_out else 1.0
    xy = flat.panel_xy
    first = flat.cells[0]
    got = rest.cell_flat[0]
    want = np.column_stack([xy[first, 1], -sign * xy[first, 0]])
    assert np.allclose(np.sort(got, axis=0), np.sort(want, axis=0))


def test_a_darted_garment_is_written_back_as_its_pattern(torso):
    """The flat pieces of the darted top (patterns/darted_top.toml: a front with two darts, a
    back) written back as a pattern (``pattern.export.garment_pattern``): each dart's two legs,
    which meet at its tip and carry the same name, are two edges of the front sewn to each
    other (before, they were one edge and the export failed: "a seam joins 1 piece edges")."""
    from pathlib import Path

    from fenics_garment.pattern.export import garment_pattern
    from fenics_garment.pattern.io import read_pattern

    root = Path(__file__).resolve().parents[1]
    pattern = read_pattern(root / "fenics_garment" / "scenes" / "patterns" / "darted_top.toml")
    gm, _ = pattern_garment(pattern, torso, 0.03)
    out = garment_pattern(gm, "darted")
    assert set(out.panels) == {"front", "back"}
    darts = [s for s in out.seams if s.a.panel == s.b.panel]
    assert len(darts) == 2
    for s in darts:
        edges = out.panels["front"].edges
        assert s.a.panel == "front" and edges[s.a.edge].name == edges[s.b.edge].name
        assert edges[s.a.edge].name.startswith("dart") and abs(s.a.edge - s.b.edge) == 1
    assert len(out.seams) == 6  # and the two side and two shoulder seams
