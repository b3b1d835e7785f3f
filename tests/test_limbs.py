"""Compression garments on limbs: the arm, the sleeve, RAL-GZ 387 classes, Laplace per level.

The sleeve scene (demos/sleeve_on_arm.toml) is dressed once and each level's mean pressure in a
±1 cm band is compared with the free-end Laplace pressure of that level (compression.py). The
stocking scene is slower (~60–80 s on the shared machine) and marked ``slow``.
"""

import tempfile
from pathlib import Path

import numpy as np
import pytest

from fenics_garment import compression as cp
from fenics_garment._stack import MPI
from fenics_garment.geometry.garments import make_sleeve
from fenics_garment.geometry.mannequin import ARM_GIRTHS, make_arm
from fenics_garment.scene import config
from fenics_garment.scene.run import run

DEMOS = Path(__file__).parent.parent / "demos"


@pytest.mark.parametrize(
    ("mmhg", "name"),
    [(17.9, None), (18.0, "I"), (21.0, "I"), (22.0, None), (23.0, "II"), (32.0, "II"),
     (40.0, "III"), (47.5, None), (49.0, "IV"), (80.0, "IV")],
)  # fmt: skip
def test_ral_gz_387_classes(mmhg, name):
    assert cp.ral_class(mmhg) == name


def test_describe_class():
    assert cp.describe_class(19.5) == "class I (18–21 mmHg)"
    assert cp.describe_class(22.0).startswith("between class I and II")
    assert cp.describe_class(10.0).startswith("below class I")


def test_arm_girths_and_regions():
    arm = make_arm(h=0.01)
    assert arm.check()["closed_manifold"]
    for level, g in ARM_GIRTHS.items():
        assert arm.girth(level) == pytest.approx(g, rel=0.005)  # 24 facets per turn: −0.3 %
    assert set(arm.regions) == {"wrist", "forearm", "elbow", "upper_arm"}


def test_sleeve_levels_follow_the_ease():
    sl = make_sleeve(make_arm(h=0.01), ease={"wrist": -0.1}, h=0.006)  # 24 edges per turn
    w = sl.level("wrist")
    assert w.ease == pytest.approx(-0.1) and sl.level("elbow").ease == pytest.approx(-0.06)
    assert sl.girth(w.z) == pytest.approx(w.garment_girth, rel=0.005)
    assert {"hem", "top"} <= set(sl.edges)


@pytest.mark.parametrize(
    ("text", "key", "words"),
    [
        ("[body]\nkind = 'arm'\n[garment]\nkind = 'gilet'\n", "garment.kind", "mannequin or scan"),
        ("[garment]\nkind = 'sleeve'\n", "garment.kind", "needs an arm or scan body"),
        ("[body]\nkind = 'arm'\n[garment]\nkind = 'sleeve'\nside = 'up'\n", "garment.side", "left"),
        ("[body]\nkind = 'arm'\nmeasurements = { wrist = 0.15 }\n[garment]\nkind = 'sleeve'\n",
         "body.measurements.wrist", "wrist_girth"),
        ("[body]\nkind = 'arm'\n[garment]\nkind = 'sleeve'\nease = { wirst = -0.1 }\n",
         "garment.ease.wirst", "wrist"),
        ("[garment]\nkind = 'stocking'\n", "body.legs", "legs = true"),
        ("[body]\nlegs = true\n[garment]\nkind = 'stocking'\nside = 'middle'\n", "garment.side",
         "left"),
    ],
)  # fmt: skip
def test_limb_scene_errors(text, key, words):
    import tomllib

    with pytest.raises(config.SceneError) as err:
        config.from_dict(tomllib.loads(text), "s.toml")
    assert err.value.key == key and words in str(err.value)


def test_limb_demo_scenes_load():
    for f in ("sleeve_on_arm.toml", "compression_stocking.toml"):
        config.load(DEMOS / f)


def _tmp() -> Path:
    comm = MPI.COMM_WORLD
    return Path(comm.bcast(tempfile.mkdtemp() if comm.rank == 0 else None, root=0))


@pytest.fixture(scope="module")
def sleeve_run():
    return run(config.load(DEMOS / "sleeve_on_arm.toml"), _tmp(), quiet=True)


@pytest.mark.slow  # 29 s of CPU; 50 s wall at load 3.5, 97 s at load 7 on the shared 2 cores
def test_sleeve_obeys_laplace_per_level(sleeve_run):
    assert sleeve_run.completed and sleeve_run.report.final_regularisation == 0.0
    checks = {c.level: c for c in cp.level_checks(sleeve_run.built, list(ARM_GIRTHS), 0.01)}
    # Interior levels (12 cm from either free edge), P2B-P2B on the curved garment mesh.
    # Measured +3.8 % forearm, +2.7 % elbow (the straight-sided garment mesh gave +7.0 %, its
    # predicted chord-to-arc bias +4.6 %). The body is not the cause (the smooth arm's girth is
    # the section's to 0.005 %); Laplace's law for a straight free-ended tube leaves out the
    # arm's taper and axial curvature and the axial tension friction holds, which the mesh
    # study (benchmarks/convergence.py, sleeve_on_arm) puts at a few percent: held to 5 %.
    for level in ("forearm", "elbow"):
        assert checks[level].rel_error == pytest.approx(0.0, abs=0.05), level
    # The wrist and upper-arm levels are 2.5 cm from the free edges, where the arm's stubs meet
    # the taper (its girth dips from 15.50 cm at the wrist to 15.15 cm 1 cm below it). Measured
    # −0.5 % / −0.9 % (straight-sided garment mesh: −8.4 % / −4.7 %), held to the same 5 %.
    for level in ("wrist", "upper_arm"):
        assert checks[level].rel_error == pytest.approx(0.0, abs=0.05), level
    # graduated: tightest at the wrist
    p = [checks[k].simulated_pa for k in ARM_GIRTHS]
    assert p == sorted(p, reverse=True)


@pytest.mark.slow  # on the human: 144,456 dofs, 360–400 s on 1 rank at load 3–5
def test_stocking_ankle_in_class_one():
    res = run(config.load(DEMOS / "compression_stocking.toml"), _tmp(), quiet=True)
    assert res.completed
    levels = ["ankle_left", "calf_left", "knee_left", "thigh_left"]
    checks = {c.level: c for c in cp.level_checks(res.built, levels, 0.01)}
    ankle = checks["ankle"]
    # P2B-P2B on the curved garment mesh, on the human mannequin: 20.1 mmHg against Laplace's
    # 19.7 (+2.1 %); on the dress form's legs alone 19.87 against 19.93 (−0.3 %); the
    # straight-sided mesh gave 21.57 (+8.2 %, class II), the P1-P1 draft element 19.3
    assert cp.ral_class(ankle.simulated_mmhg) == "I"
    assert ankle.rel_error == pytest.approx(0.0, abs=0.03)
    assert ankle.simulated_pa > checks["calf"].simulated_pa > checks["thigh"].simulated_pa


def test_the_wrist_is_the_narrowest_section_before_the_hand():
    """A forearm tapering to its wrist at 0.42 m, a palm widening the girth to twice that, and
    fingers narrower than the wrist at the tip: the wrist is the narrowest section before the
    hand widens the girth by ``HAND_WIDENING``, not the fingers (MakeHuman's muscular woman,
    whose sleeve was cut to her fingers and folded over the hand); without a hand, the
    narrowest section."""
    from fenics_garment.geometry.limbs import before_the_hand

    s = np.linspace(0.0, 0.59, 60)
    forearm = 0.22 - 0.24 * s  # 0.12 m at 0.42 m
    palm = 0.12 + 0.11 * np.sin(np.clip((s - 0.42) / 0.12, 0.0, 1.0) * np.pi)  # 0.23 at 0.48
    girth = np.where(s <= 0.42, forearm, palm - 0.4 * np.clip(s - 0.52, 0.0, None))
    assert girth[-1] < girth[np.argmin(np.abs(s - 0.42))]  # the fingertips: narrower still
    tip = float(s[np.nanargmin(np.where(s >= 0.295, girth, np.nan))])
    assert tip > 0.55
    assert before_the_hand(s, girth, 0.295, tip) == pytest.approx(0.42, abs=0.01)
    assert before_the_hand(s, forearm, 0.295, 0.59) == 0.59  # no hand: the narrowest stays
