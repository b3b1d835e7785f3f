"""Compression garments on limbs: the arm, the sleeve, RAL-GZ 387 classes, Laplace per level.

The sleeve scene (demos/sleeve_on_arm.toml) is dressed once and each level's mean pressure in a
±1 cm band is compared with the free-end Laplace pressure of that level (compression.py). The
stocking scene is slower (~60–80 s on the shared machine) and marked ``slow``.
"""

import math
import tempfile
from pathlib import Path

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
        ("[garment]\nkind = 'sleeve'\n", "garment.kind", "needs an arm body"),
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


def straight_edge_bias(ease: float, per_turn: int = 24) -> float:
    """Relative excess of the hoop strain E = (λ² − 1)/2 when the garment's reference mesh is
    straight-sided but its P2 displacement bends each deformed edge onto the round limb: the
    deformed hoop is an arc over each chord, arc/chord − 1 ≈ θ²/24 with θ = 2π/per_turn."""
    lam = 1.0 / (1.0 + ease)
    arc = 1.0 + (2 * math.pi / per_turn) ** 2 / 24
    return ((lam * arc) ** 2 - 1.0) / (lam**2 - 1.0) - 1.0


@pytest.mark.slow  # 29 s of CPU; 50 s wall at load 3.5, 97 s at load 7 on the shared 2 cores
def test_sleeve_obeys_laplace_per_level(sleeve_run):
    assert sleeve_run.completed and sleeve_run.report.final_regularisation == 0.0
    checks = {c.level: c for c in cp.level_checks(sleeve_run.built, list(ARM_GIRTHS), 0.01)}
    ease = sleeve_run.built.scene.garment.ease
    # Interior levels (12 cm from either free edge). P2B-P2B on the straight-sided garment mesh
    # (24 cells per turn) carries the known O(h²) bias of straight_edge_bias: +4.6 % forearm,
    # +4.8 % elbow; around it, facets of the arm and the fabric's own ±0.3 % of girth (≈ ±3 % of
    # a 7 % hoop strain) and the taper cos 4° −0.2 %: 4 %. Measured +7.0 % at the forearm (with
    # the P1-P1 draft element −2.9 % / −2.1 %; spring released to c = 0, μ = 0.3).
    for level in ("forearm", "elbow"):
        bias = straight_edge_bias(ease[level])
        assert checks[level].rel_error == pytest.approx(bias, abs=0.04), level
    # The wrist and upper-arm levels are 2.5 cm from the free edges, where the arm's stubs meet
    # the taper and the loft is not prismatic: the arm's girth dips from 15.50 cm at the wrist to
    # 15.15 cm 1 cm below it (the sleeve's hem section repeats the wrist's, so it is stretched
    # less there). Measured −8.4 % / −4.7 %, held to 10 %; not claimed as agreement.
    for level in ("wrist", "upper_arm"):
        assert checks[level].rel_error == pytest.approx(0.0, abs=0.10), level
    # graduated: tightest at the wrist
    p = [checks[k].simulated_pa for k in ARM_GIRTHS]
    assert p == sorted(p, reverse=True)


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="known gap (issue 15): on P2B-P2B with the straight-sided garment mesh (159,588 dofs) "
    "the ankle is 21.57 mmHg, +8.2 % above Laplace (calf +9.5 %), so RAL class II; the "
    "predicted straight-edge bias is +2.7 % at 28 cells per turn; the P1-P1 draft element gave "
    "19.3 mmHg. A curved (P2) garment geometry is the fix; this turns into a pass then.",
)
def test_stocking_ankle_in_class_one():
    res = run(config.load(DEMOS / "compression_stocking.toml"), _tmp(), quiet=True)
    assert res.completed
    levels = ["ankle_left", "calf_left", "knee_left", "thigh_left"]
    checks = {c.level: c for c in cp.level_checks(res.built, levels, 0.01)}
    ankle = checks["ankle"]
    assert cp.ral_class(ankle.simulated_mmhg) == "I"  # measured 19.3 mmHg (Laplace 19.9)
    assert ankle.rel_error == pytest.approx(0.0, abs=0.05)
    assert ankle.simulated_pa > checks["calf"].simulated_pa > checks["thigh"].simulated_pa
