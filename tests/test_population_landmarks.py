"""Landmarks of extreme bodies of the population against references that do not come from the
package (issue 40, item 2).

The references are ``benchmarks/landmarks.py``'s: MakeHuman's own measuring loops and points
(vertex indices of its base mesh, from the ``makehuman`` 1.3.2 wheel's measurement plugin; the
MPFB2 rig's nipples) and ISO 8559-1 levels measured with trimesh sections — each definition and
its source is listed there. The target: every landmark height within 1.5 cm and every girth
within 2 % (the record of all 37 bodies: ``benchmarks/results/landmarks.json``, REPORT.md
section "bodies").
"""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks import landmarks as lm
from fenics_garment.geometry import population as pop
from fenics_garment.geometry.anatomy import (
    depth_under_envelope,
    extreme,
    kneecap,
    narrowing_below,
)

#: the extremes of the population: the largest, softest breasts on a heavy woman; the short,
#: heavy, flabby old man (a waist without a narrowing); the tall thin man of uncommon
#: proportions; the short thin teenage girl; the heavy, muscular, androgynous body
EXTREMES = ("f-maxcup-soft-heavy", "m-short-heavy-flabby-old", "m-tall-thin-uncommon",
            "f-short-thin-teen", "x-androgynous-heavy")  # fmt: skip
#: bodies still missing the targets (measured, benchmarks/results/landmarks.json; issue 40 item 2
#: left open for them). The under-bust reference is the corner of the front profile under the bust
#: point (benchmarks/landmarks.py ``_fold``), where the girth changes steeply; the hip reference
#: the buttocks' rearmost point (ISO 8559-1), which all five now meet within 0.3 cm.
MISSES = {
    "m-short-heavy-flabby-old": "knee −3.4 cm, "
    "waist −2.6 cm, neck base −1.9 cm, neck girth +6.2 % (no neck between shoulders and double "
    "chin)",
    "f-maxcup-soft-heavy": "under-bust +2.4 cm / −5.3 % (the breast's lower part leaves the "
    "torso's outline 2.4 cm above the fold)",
    "m-tall-thin-uncommon": "thigh −1.7 cm, neck girth +2.9 % (height −0.5 cm × 5.5 %/cm)",
    "f-short-thin-teen": "calf +3.9 cm / +4.4 %, knee +3.6 cm / +8.4 %, under-bust +1.6 cm / "
    "+4.5 %, bust +2.7 cm, shoulder +2.8 cm",
    "x-androgynous-heavy": "knee −2.4 cm / −5.6 %, thigh +1.8 cm, neck girth +5.8 %",
}


def test_extreme_takes_the_middle_of_a_plateau() -> None:
    zs = np.linspace(0.0, 0.2, 101)
    sharp = 1.0 + 100.0 * (zs - 0.05) ** 2  # one clear minimum at 0.05 (0.5 % over ±7 mm)
    assert extreme(zs, sharp, widest=False) == pytest.approx(0.05)
    flat = np.where(np.abs(zs - 0.1) < 0.04, 1.0, 1.1)  # 1.0 from 0.06 to 0.14: no narrowing
    assert extreme(zs, flat, widest=False) == pytest.approx(0.1, abs=0.003)
    assert extreme(zs, -sharp, widest=True) == pytest.approx(0.05)


def test_kneecap_is_the_front_profile_s_bump_over_the_chord() -> None:
    zs = np.linspace(0.30, 0.60, 151)
    shin_to_thigh = 0.06 + 0.2 * (zs - 0.30)  # a leg leaning forward, straight
    bump = 0.005 * np.exp(-(((zs - 0.47) / 0.02) ** 2))  # a kneecap 5 mm proud at 0.47 m
    assert kneecap(zs, shin_to_thigh + bump, 0.32, 0.58, 1.7) == pytest.approx(0.47, abs=0.003)
    assert kneecap(zs, shin_to_thigh, 0.32, 0.58, 1.7) is None  # a lofted, straight leg


def test_fold_is_the_corner_behind_the_profile_s_envelope() -> None:
    zs = np.linspace(1.12, 1.00, 61)  # from the bust point down
    breast = 0.12 - 30.0 * (zs - 1.12) ** 2  # its underside meets the chest wall at 1.0835 m
    chest_wall = 0.08 + 0.2 * np.maximum(1.05 - zs, 0.0)  # the belly comes forward below
    depth = depth_under_envelope(zs, np.maximum(breast, chest_wall))
    assert zs[np.argmax(depth)] == pytest.approx(1.0835, abs=0.003)
    assert depth.min() >= -1e-12


def test_narrowing_under_the_knee_and_a_leg_without_one() -> None:
    zs = np.linspace(0.10, 0.50, 81)
    calf = 0.36 - 0.3 * (zs - 0.33) ** 2 + 0.5 * np.maximum(zs - 0.42, 0.0) ** 2 * 10
    assert narrowing_below(zs, calf) == pytest.approx(0.4, abs=0.03)
    assert narrowing_below(zs, 0.2 + 0.4 * zs) is None  # growing all the way to the knee


def _case(name: str):
    if name not in MISSES:
        return name
    miss = pytest.mark.xfail(strict=True, raises=AssertionError, reason=MISSES[name])
    return pytest.param(name, marks=miss)


def test_a_girth_error_is_the_height_error_times_the_girth_s_slope() -> None:
    """On a cone r(z) = r0 + a z, the tape's relative slope is a / r(z) (the polygon's perimeter
    is proportional to r), and a landmark 1 cm off where the girth changes 4 %/cm misses the
    2 % girth target within the 1.5 cm height target: the two targets ask for more than each
    other there (``height_limited``); our girth at our height against the tape there is exact."""
    import trimesh

    r0, a = 0.05, 0.2  # m, 1: girth slope at z = 0.25 m is a / r = 0.2 / 0.1 = 2 per metre
    ring = np.array([[r0 + a * z, z] for z in np.linspace(0.0, 0.5, 51)])
    cone = trimesh.creation.revolve(ring, sections=64)
    tape = lm.Tape(np.asarray(cone.vertices), np.asarray(cone.faces))
    z_ref, z_ours = 0.25, 0.26
    g_ref = tape.girth_at("waist", z_ref)
    g_ours = 2 * 64 * (r0 + a * z_ours) * np.sin(np.pi / 64)  # the 64-gon's own perimeter
    row = {"z": z_ref, "girth": g_ref, "ours_z": z_ours, "ours_girth": g_ours,
           "dz": z_ours - z_ref, "dg": g_ours / g_ref - 1.0}  # fmt: skip
    row |= lm.girth_terms(tape, "waist", row)
    assert row["girth_slope"] == pytest.approx(a / (r0 + a * z_ref), rel=1e-6)
    assert abs(row["dg_tape"]) < 1e-9  # the tape against the polygon's perimeter
    assert row["dg"] == pytest.approx(a * 0.01 / (r0 + a * z_ref), rel=1e-6)  # 2 %
    assert lm.height_limited(row | {"dg": 0.021})
    assert not lm.height_limited(row | {"dz": 0.016})  # a height miss is a miss of its own
    flat = row | {"girth_slope": 1.0}  # 1 %/cm: 1.5 % over the height target, within 2 %
    assert not lm.height_limited(flat)


def test_a_flat_chest_s_band_against_a_sphere_and_a_plane() -> None:
    """``flat_band``: the height over which the front stays within 3 mm of its reach at the
    nipples. On a sphere of radius r through them it is 2 √(r² − (r − 3 mm)²) (4.86 cm for
    r = 0.1 m); on a flat front, the whole ±5 cm looked at."""
    import trimesh

    nip = np.array([[0.0, -0.1, 1.0], [0.0, -0.1, 1.0]])
    ball = trimesh.creation.icosphere(subdivisions=6, radius=0.1)
    ball.apply_translation([0.0, 0.0, 1.0])
    band = lm.flat_band(lm.Tape(np.asarray(ball.vertices), np.asarray(ball.faces)), nip)
    exact = 2 * np.sqrt(0.1**2 - (0.1 - lm.FLAT_FRONT) ** 2)
    assert band == pytest.approx(exact, abs=0.005)  # each end to within its 2.5 mm step
    box = trimesh.creation.box([0.3, 0.2, 0.5])
    box.apply_translation([0.0, 0.0, 1.0])
    flat = lm.flat_band(lm.Tape(np.asarray(box.vertices), np.asarray(box.faces)), nip)
    assert flat == pytest.approx(2 * lm.FLAT_REACH)
    assert lm.flat_chest({"flat_band": flat}) and not lm.flat_chest({"flat_band": band - 0.02})


@pytest.mark.slow
@pytest.mark.parametrize("name", [_case(n) for n in EXTREMES])
def test_landmarks_of_extreme_bodies_against_references(name: str) -> None:
    record = lm.compare(pop.by_name(name))
    rows = record["levels"]
    assert set(rows) == set(lm.LEVELS)
    for level, row in rows.items():
        assert row["ours_z"] is not None, level
        print(f"{name} {level:10s} ref {row['z']:.4f} ours {row['ours_z']:.4f} "
              f"({100 * row['dz']:+.2f} cm)"
              + (f" girth {100 * row['dg']:+.2f} %" if "dg" in row else ""))  # fmt: skip
    bad = [(f.level, f.what) for f in lm.failures([record])]
    assert not bad, f"{name}: {bad}"


@pytest.mark.slow  # one body analysed: 6–10 s
def test_a_leg_s_centreline_takes_the_knee_and_calf_of_the_upright_body() -> None:
    """The stocking is built on each leg's centreline (``limbs``), whose sharpest bend put the
    knee 9.0 cm under MakeHuman's knee loop on the heavy man (and 5–11.6 cm on 7 more of the
    37 bodies). Both legs' centreline knee and calf now lie at the heights found on the upright
    body's sections, within the 1.5 cm target of the references (``benchmarks/landmarks.py``),
    the right leg by its own sections."""
    from fenics_garment.geometry.anatomy import analyse

    V, T, v = lm.body_mesh(pop.by_name("m-heavy"))
    ref = lm.references(V, T, v)
    a = analyse(V, T)
    for side in ("left", "right"):
        leg = a.limbs[f"leg_{side}"]
        for level in ("knee", "calf"):
            z = float(np.ravel(leg.point(level))[2])
            assert z == pytest.approx(ref[level]["z"], abs=lm.HEIGHT_TOL), (side, level)


@pytest.mark.slow  # two bodies analysed: 12–20 s
@pytest.mark.parametrize("name", ["female", "m-heavy"])
def test_the_acromion_against_makehuman_s_vertex(name: str) -> None:
    """The shoulder point half-way from the armpit's side to the corner of the shoulders'
    silhouette, against MakeHuman's acromion vertex (its ``shoulder-dist`` measure's end):
    within the 1.5 cm target on a woman (the top of the surface over the armpit point, the
    rule before, was +1.64 cm on her) and on a heavy man (+0.39 cm before; the silhouette's
    corner alone is 1.9 cm low on him)."""
    from fenics_garment.geometry.anatomy import analyse

    V, T, v = lm.body_mesh(pop.by_name(name))
    a = analyse(V, T)
    acromion = v[lm.MH_ACROMION]
    assert a.landmarks["shoulder"] == pytest.approx(acromion[2], abs=lm.HEIGHT_TOL)
    assert abs(a.points["shoulder_left"][0]) == pytest.approx(abs(acromion[0]), abs=0.02)
