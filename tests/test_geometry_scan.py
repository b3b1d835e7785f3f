"""Scan import: deliberately messy files (made here from the mannequin) give a clean body or a
clear error."""

import meshio
import numpy as np
import pytest

from fenics_garment.geometry import MeshSizes, ScanError, make_mannequin
from fenics_garment.geometry.regions import REGIONS
from fenics_garment.geometry.scan import load_scan
from fenics_garment.geometry.surface import areas, edges, signed_volume


@pytest.fixture(scope="module")
def body():
    return make_mannequin(sizes=MeshSizes(0.025, 0.025))


def _quads_and_triangles(t, rng):
    """Merge random pairs of edge-neighbours into quads (a, b, d, c)."""
    uniq, te = edges(t)
    owner = {}
    for i, es in enumerate(te):
        for e in es:
            owner.setdefault(int(e), []).append(i)
    used = np.zeros(len(t), bool)
    existing = {tuple(e) for e in uniq.tolist()}
    quads = []
    for e in rng.permutation(len(uniq))[: len(uniq) // 3]:
        if len(owner[int(e)]) != 2:
            continue
        i, j = owner[int(e)]
        if used[i] or used[j]:
            continue
        a = next(v for v in t[i] if v not in uniq[e])
        k = list(t[i]).index(a)
        b, c = t[i][(k + 1) % 3], t[i][(k + 2) % 3]
        d = next(v for v in t[j] if v not in uniq[e])
        if (min(a, d), max(a, d)) in existing:  # the reader's fan split would add that edge
            continue
        existing.add((min(a, d), max(a, d)))
        quads.append([a, b, d, c])
        used[i] = used[j] = True
    return t[~used], np.array(quads)


def _messy(body, rng, hole=2):
    """Triangle soup (every face its own vertices), 30 % flipped, a hole, a floating speck."""
    t = body.triangles.copy()
    t = np.delete(t, rng.choice(len(t), 1), axis=0) if hole == 1 else t
    if hole == 2:  # the first two triangles out: one or two small holes
        t = t[2:]
    flip = rng.random(len(t)) < 0.3
    t[flip] = t[flip][:, ::-1]
    speck = np.array([[0.5, 0.5, 0.5], [0.51, 0.5, 0.5], [0.5, 0.51, 0.5], [0.5, 0.5, 0.51]])
    v = np.vstack([body.vertices, speck])
    n = len(body.vertices)
    t = np.vstack([t, n + np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])])
    return v, t


def test_obj_mm_yup_quads_soup_flips_hole_speck(body, tmp_path):
    rng = np.random.default_rng(1)
    v, t = _messy(body, rng)
    tri, quads = _quads_and_triangles(t, rng)
    soup_v = np.concatenate([v[tri].reshape(-1, 3), v[quads].reshape(-1, 3)]) * 1000.0
    soup_tri = np.arange(3 * len(tri)).reshape(-1, 3)
    soup_quad = 3 * len(tri) + np.arange(4 * len(quads)).reshape(-1, 4)
    yup = np.column_stack([soup_v[:, 0], soup_v[:, 2], -soup_v[:, 1]])  # Y-up, facing +z
    path = tmp_path / "scan.obj"
    meshio.write(path, meshio.Mesh(yup, [("triangle", soup_tri), ("quad", soup_quad)]))
    scan, report = load_scan(path)
    assert report["units"] == "mm" and report["up"] == "y"
    assert report["dropped_pieces"] == 1 and report["holes_filled"] >= 1
    assert report["welded_vertices"] > 0
    info = scan.check()
    assert info["closed_manifold"] and info["components"] == 1
    ref_vol = signed_volume(body.vertices, body.triangles)
    # outward, same body: quads re-split the other way and the filled holes move the volume by
    # −0.20 % (measured on the default ASTM-proportioned body)
    assert info["volume"] == pytest.approx(ref_vol, rel=3e-3)
    ref_area = areas(body.vertices, body.triangles).sum()
    assert info["area"] == pytest.approx(ref_area, rel=1e-2)  # quads re-split the other way
    # upright, facing −y again: the bust reaches further forward (−y) than the hips, the hips
    # (buttocks) further back (mannequin.TORSO_SHAPES: bust front 0.125 / back 0.092, hip 0.100
    # / 0.140, before scaling)
    bust, hip = scan.sections["bust"][:, 1], scan.sections["hip"][:, 1]
    assert bust.min() < hip.min() - 0.01 and hip.max() > bust.max() + 0.01
    assert set(scan.regions) == set(REGIONS) - {"arms", "head"}  # armless, headless
    # landmark heights: same as the mannequin's after the floor shift (no feet), within 5 cm
    shift = body.vertices[:, 2].min()
    for k in ("crotch", "hip", "waist", "bust"):
        assert scan.landmarks[k] + shift == pytest.approx(body.landmarks[k], abs=0.05)


def test_stl_cm_upside_down(body, tmp_path):
    v = body.vertices * 100.0 * np.array([1.0, -1.0, -1.0])  # rotated by π about x: head down
    path = tmp_path / "scan.stl"
    meshio.write(path, meshio.Mesh(v, [("triangle", body.triangles)]), binary=True)
    scan, report = load_scan(path)
    assert report["units"] == "cm" and report["up"] == "-z"
    assert scan.check()["volume"] == pytest.approx(
        signed_volume(body.vertices, body.triangles), 2e-3
    )


def test_big_hole_is_a_clear_error(body, tmp_path):
    c = body.vertices[body.triangles].mean(axis=1)
    keep = ~((np.abs(c[:, 2] - body.landmarks["waist"]) < 0.03) & (c[:, 1] < 0))
    path = tmp_path / "holey.ply"
    meshio.write(path, meshio.Mesh(body.vertices, [("triangle", body.triangles[keep])]))
    with pytest.raises(ScanError, match="not closed"):
        load_scan(path)
