"""T-posed bodies of the population: MPFB2's game-engine rig (``fenics_garment.geometry.rig``)
applied to MakeHuman's morphed bodies (issue 40: "A- and T-pose where the rig allows").

References, none computed by the code under test:

* MPFB2's own joint positions (``default_position`` of each bone's head and tail in
  ``rig.game_engine.json``, kept in the vendored file): those of MakeHuman's default body;
* the pose's intent, a T: upper arms horizontal, left and right mirror images; measured on the
  skinned joint cubes of hm08 (the centres of its ``joint-*-shoulder`` … cubes, which the
  skinning moves as any other vertex);
* the rest of the body: vertices of the legs and of the torso below the armpits do not move
  (their displacement against the A-pose body), and the arm's segments keep their lengths;
* the existing bodies: the SHA-256 of every A-pose body's vertices (rounded to 1e-9 dm) as the
  population of commit a9902f5 (before the T-pose) computed them, with its export settings;
* the armpit: the skin point at the top of the gap between arm and chest wall on the A-pose
  twin (at the armpit level of ``benchmarks/landmarks.py``, trimesh sections), carried into the
  T-pose by the skinning (the same vertex of hm08).
"""

from __future__ import annotations

import hashlib
import json
import lzma

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from benchmarks import landmarks as lm
from fenics_garment.geometry import population as pop
from fenics_garment.geometry import rig
from fenics_garment.geometry.anatomy import analyse

T_BODIES = [name for name, *_ in pop.T_POSED]
#: (format, units, up, turn, SHA-256 prefix of the vertices) of every body of the population
#: as it was before the T-pose (commit a9902f5, ``population.body_vertices``)
BEFORE = {
    "neutral": ("stl", "mm", "y", 0, "f68f44b8b20e03b6"),
    "female": ("stl-ascii", "mm", "z", 0, "c3f370bc171077bf"),
    "male": ("ply", "mm", "-z", 0, "08db94ec9eddad1e"),
    "f-teen": ("ply-ascii", "mm", "x", 0, "64d2307f3a31f463"),
    "f-old": ("obj", "mm", "-y", 0, "9545a2b4ecd6adcd"),
    "f-thin": ("glb", "mm", "-x", 0, "7e3dfe45b4a3c629"),
    "f-heavy": ("stl", "cm", "z", 0, "5658384427e62cc9"),
    "f-flabby": ("stl-ascii", "cm", "-z", 0, "8aec12b473b97d5a"),
    "f-muscular": ("ply", "cm", "x", 0, "47b20efc012c503c"),
    "f-short": ("ply-ascii", "cm", "-y", 0, "b2b433a0bd87e0e4"),
    "f-tall": ("obj", "cm", "-x", 0, "c49641ad1edd35b0"),
    "f-uncommon": ("glb", "cm", "y", 0, "1fe4fb1beb77e2b9"),
    "f-ideal": ("stl", "m", "-z", 0, "a1979020156f1a99"),
    "m-teen": ("stl-ascii", "m", "x", 0, "49b61568d9348bfb"),
    "m-old": ("ply", "m", "-y", 0, "03eca0ec8db21fd5"),
    "m-thin": ("ply-ascii", "m", "-x", 0, "65607e8b61e5b759"),
    "m-heavy": ("obj", "m", "y", 0, "fe724ad36f43bfa5"),
    "m-flabby": ("glb", "m", "z", 0, "a005bc2d3ee9e3e9"),
    "m-muscular": ("stl", "in", "x", 0, "16b9d333b5138700"),
    "m-short": ("stl-ascii", "in", "-y", 0, "f0431ce8369e4aff"),
    "m-tall": ("ply", "in", "-x", 0, "f6057ed4fcaddb52"),
    "m-uncommon": ("ply-ascii", "in", "y", 0, "071524f3280581b0"),
    "m-ideal": ("obj", "in", "z", 0, "7f35360134986cdd"),
    "f-mincup": ("glb", "in", "-z", 0, "54ecf51051f41b51"),
    "f-maxcup": ("stl", "mm", "-y", 0, "c3e954faf88faf09"),
    "f-maxcup-soft-heavy": ("stl-ascii", "mm", "-x", 0, "2865c803643406d2"),
    "f-short-heavy-old": ("ply", "mm", "y", 0, "cde9586b74b0f81d"),
    "f-tall-thin-young": ("ply-ascii", "mm", "z", 0, "f3b04c23d31ccd6f"),
    "f-short-thin-teen": ("obj", "mm", "-z", 0, "7c1820d6f1bc615d"),
    "m-tall-heavy-muscular": ("glb", "mm", "x", 0, "8a9cf311e61aa316"),
    "m-short-heavy-flabby-old": ("stl", "cm", "-x", 0, "c213729649e6a740"),
    "m-tall-thin-uncommon": ("stl-ascii", "cm", "y", 0, "979b2eda8ad5b59a"),
    "m-short-thin-teen": ("ply", "cm", "z", 0, "fff1ef44734924c7"),
    "african-f": ("ply-ascii", "cm", "-z", 0, "8d8c11adcce7c7e5"),
    "asian-m": ("obj", "cm", "x", 0, "6afac5ee55150a14"),
    "caucasian-m-heavy": ("glb", "cm", "-y", 0, "0dfa3b4e54f486a3"),
    "x-androgynous-heavy": ("stl", "m", "y", 0, "2e850e41ddfb36f9"),
    "female-turned-180": ("stl", "mm", "z", 180, "c3f370bc171077bf"),
    "male-turned-90": ("ply", "m", "z", 90, "08db94ec9eddad1e"),
}


def _triangles() -> np.ndarray:
    faces = pop.base_mesh().faces()
    return np.array([f[:3] for f in faces] + [[f[0], f[2], f[3]] for f in faces if len(f) == 4])


def _cube(v_dm: np.ndarray, name: str) -> np.ndarray:
    """A joint cube's centre in the package's frame (m, Z up), from its own vertices."""
    idx = np.unique(np.concatenate(pop.base_mesh().groups[name]))
    return pop.to_package_frame(v_dm[idx].mean(axis=0)[None])[0]


def _elevation(a: np.ndarray, b: np.ndarray) -> float:
    """Angle of a → b above the horizontal [degrees]."""
    d = b - a
    return float(np.degrees(np.arcsin(d[2] / np.linalg.norm(d))))


def test_existing_bodies_are_unchanged():
    """Every body of the population before the T-pose: same name, export settings and
    vertices; the new ones are T-posed copies of existing shapes."""
    bodies = {b.name: b for b in pop.population()}
    for name, (fmt, units, up, turn, digest) in BEFORE.items():
        b = bodies.pop(name)
        assert (b.fmt, b.units, b.up, b.turn, b.pose) == (fmt, units, up, turn, "A"), name
        got = hashlib.sha256(np.round(b.vertices, 9).tobytes()).hexdigest()[:16]
        assert got == digest, name
    assert sorted(bodies) == sorted(f"{n}-t-pose" for n in T_BODIES)
    shapes = {b.macro for b in pop.population() if b.pose == "A"}
    for b in bodies.values():
        assert b.pose == "T" and b.macro in shapes and b.fmt in pop.FORMATS


def test_rig_joints_are_makehuman_s_joint_cubes():
    """The bones' heads and tails, placed from the joint cubes of MakeHuman's default body,
    are MPFB2's stored positions (so: same vertex numbering, frame and cube strategy)."""
    raw = json.loads(lzma.decompress(rig.RIG.read_bytes()))
    v = pop.body_vertices(pop.Macro())
    for b in raw["bones"]:
        for end in ("head", "tail"):
            got = rig.TO_RIG @ pop.joint_centre(v, b[end])
            assert np.abs(got - b[f"{end}_default_m"]).max() < 1e-6, (b["name"], end)
    assert {b["name"] for b in raw["bones"]} >= {"clavicle_l", "upperarm_r", "hand_l"}


@pytest.mark.parametrize("name", T_BODIES)
def test_t_pose_raises_the_upper_arms_to_horizontal(name):
    body = pop.by_name(f"{name}-t-pose")
    va, vt = pop.body_vertices(body.macro), body.vertices
    for side, sgn in (("l", 1.0), ("r", -1.0)):
        sh, el, wr = (_cube(vt, f"joint-{side}-{j}") for j in ("shoulder", "elbow", "hand"))
        assert abs(_elevation(sh, el)) < 3.0  # measured 0.5–2.0°
        assert abs(_elevation(el, wr)) < 5.0  # measured 1.0–3.8°
        assert sgn * (el[0] - sh[0]) > 0.95 * np.linalg.norm(el - sh)  # sideways, not forwards
        rest = [_cube(va, f"joint-{side}-{j}") for j in ("shoulder", "elbow", "hand")]
        assert _elevation(rest[0], rest[1]) < -40.0  # the A-pose it came from: 47–49° down
        for p, q, p0, q0 in ((sh, el, rest[0], rest[1]), (el, wr, rest[1], rest[2])):
            assert np.linalg.norm(q - p) == pytest.approx(np.linalg.norm(q0 - p0), abs=2e-3)
    for j in ("shoulder", "elbow", "hand"):  # mirror images
        left, right = _cube(vt, f"joint-l-{j}"), _cube(vt, f"joint-r-{j}")
        assert np.abs(left * [-1, 1, 1] - right).max() < 1e-3


@pytest.mark.parametrize("name", T_BODIES)
def test_t_pose_moves_only_the_arms_and_keeps_the_body_closed(name):
    body = pop.by_name(f"{name}-t-pose")
    va, vt = pop.body_vertices(body.macro), body.vertices
    pa, pt = pop.to_package_frame(va), pop.to_package_frame(vt)
    tri = _triangles()
    used = np.unique(tri)
    moved = np.linalg.norm(pt - pa, axis=1)
    sh = [_cube(va, f"joint-{s}-shoulder") for s in "lr"]
    el = [_cube(va, f"joint-{s}-elbow") for s in "lr"]
    # the torso under the armpits (below the rest elbows, medial of the rest shoulder joints)
    # and the legs (below the crotch: the lowest point of the torso, at x = 0)
    torso = (np.abs(pa[:, 0]) < sh[0][0]) & (pa[:, 2] < el[0][2])
    assert moved[used[torso[used]]].max() < 1e-9
    legs = pa[:, 2] < pa[used, 2].min() + 0.4 * np.ptp(pa[used, 2])
    hands = np.abs(pa[:, 0]) > sh[0][0]
    assert moved[used[legs[used] & ~hands[used]]].max() < 1e-9
    assert moved[used].max() > 0.3  # the hands went up by more than 30 cm
    ma = trimesh.Trimesh(pa, tri, process=False)
    mt = trimesh.Trimesh(pt, tri, process=False)
    closed = trimesh.Trimesh(pt[used], np.searchsorted(used, tri), process=False)
    assert closed.is_watertight and closed.is_winding_consistent
    assert mt.volume == pytest.approx(ma.volume, rel=0.03)  # measured +1.2 to +1.9 %
    assert np.ptp(pt[used, 2]) == pytest.approx(np.ptp(pa[used, 2]), abs=1e-9)  # same stature
    assert el[0][0] > 0 > el[1][0]


def _anatomy(v_dm: np.ndarray):
    tri = _triangles()
    used = np.unique(tri)
    v = pop.to_package_frame(v_dm)[used]
    v[:, 2] -= v[:, 2].min()
    return analyse(v, np.searchsorted(used, tri)), v, np.searchsorted(used, tri)


def _axilla(v: np.ndarray, t: np.ndarray, sgn: float) -> int:
    """The vertex at the top of the gap between the arm and the chest wall of an A-posed body
    (``v``: all of hm08's vertices, floor at z = 0; ``t``: the body's triangles): at 1 mm under
    the armpit level of ``benchmarks/landmarks.py`` (the highest level at which the arm is a
    section piece of its own, searched as there from 5 cm under the nipples to MakeHuman's
    acromion vertex), the body vertex nearest to the middle of the closest pair of points of
    the arm's piece and the torso's."""
    tape = lm.Tape(v, t)
    lo, hi = float(v[list(lm.NIPPLES), 2].mean()) - 0.05, float(v[lm.MH_ACROMION, 2])
    z = lm._armpit(tape, lo, hi) - 0.001
    pieces = tape.pieces(z)
    torso = max((p for p in pieces if p[:, 0].min() < 0.0 < p[:, 0].max()), key=len)
    arm = max((p for p in pieces if (sgn * p[:, 0]).min() > 0.0),
              key=lambda p: (sgn * p[:, 0]).max())  # fmt: skip
    d, i = cKDTree(torso[:, :2]).query(arm[:, :2])
    k = int(np.argmin(d))
    used = np.unique(t)
    return int(used[cKDTree(v[used]).query(0.5 * (arm[k] + torso[i[k]]))[1]])


@pytest.mark.slow
@pytest.mark.parametrize("name", T_BODIES)
def test_t_pose_keeps_the_torso_landmarks_and_finds_the_armpits(name):
    """The anatomy of the T-posed body against its A-pose twin: the levels under the armpits
    within 1 cm (the arms do not move the torso there), both armpits found, within 1 cm of the
    A-pose armpit's skin point carried into the T-pose; ~40 s a body."""
    body = pop.by_name(f"{name}-t-pose")
    a, _, _ = _anatomy(pop.body_vertices(body.macro))
    t, _, _ = _anatomy(body.vertices)
    for k in ("crotch", "hip", "abdomen", "waist", "underbust", "bust", "thigh", "knee"):
        assert t.landmarks[k] == pytest.approx(a.landmarks[k], abs=0.01), k
    va = pop.to_package_frame(pop.body_vertices(body.macro))
    vt = pop.to_package_frame(body.vertices)
    floor = va[np.unique(_triangles()), 2].min()
    va[:, 2] -= floor
    vt[:, 2] -= floor
    for side, sgn in (("left", 1.0), ("right", -1.0)):
        ref = vt[_axilla(va, _triangles(), sgn)]  # the A-pose armpit's skin point, raised
        p = t.points[f"armpit_{side}"]
        assert p[2] == pytest.approx(ref[2], abs=0.01), side  # measured −0.6 to +0.4 cm
        assert abs(p[0]) == pytest.approx(abs(ref[0]), abs=0.01), side  # −0.5 to +0.4 cm
        assert sgn * p[0] > 0 and t.points[f"shoulder_{side}"][2] > p[2] + 0.05
        # the shoulder point over the arm root, not out on the arm
        assert abs(t.points[f"shoulder_{side}"][0]) < abs(ref[0]) + 0.05, side
    assert t.landmarks["armpit"] > a.landmarks["armpit"]  # the raised arm lifts the axilla
    assert t.landmarks["armpit"] < t.landmarks["shoulder"]
