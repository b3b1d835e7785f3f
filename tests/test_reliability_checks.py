"""Every scene result carries its own checks (summary.json ``checks``), and scenes whose answer
would be wrong are refused before any solve (issue 18, items 1, 2 and 7).

Each check is compared with an independent value: the penalty penetration p/κ with p from
Laplace's law for the tight tube, the garment's weight ρ h A g from the fabric's data.
"""

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest
from test_reliability import small_tube

from fenics_garment import cli
from fenics_garment._stack import MPI
from fenics_garment.materials import fabric
from fenics_garment.scene import build, config, preflight
from fenics_garment.scene.dressing import DressingFailed, dress
from fenics_garment.scene.run import run
from fenics_garment.solve import NONFINITE_REASON, NonlinearSolver
from fenics_garment.verification.contact import tube_pressure

pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial")
G = 9.80665


def _scene_file(tmp_path: Path, scene: config.Scene, name: str = "scene") -> str:
    path = tmp_path / f"{name}.toml"
    path.write_text(config.dumps(scene))
    return str(path)


def _one_line_error(argv, capsys, code: int = 2) -> str:
    assert cli.main(argv) == code
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and len(err.splitlines()) == 1, err
    return err


# -- 1. the NaN/Inf guard --------------------------------------------------------------------
def test_a_non_finite_residual_cuts_the_step_instead_of_raising():
    """Moduli of 1e300 Pa overflow the residual to Inf: the solve stops with PETSc's NaN/Inf
    reason (before: AttributeError from the missing setFunctionDomainError) and the dressing
    cuts its steps, then stops with a message saying why."""
    s = small_tube(garment={"fabric_overrides": {"E_warp": 1e300, "E_weft": 1e300}})
    built = build.build(s, MPI.COMM_WORLD)
    solver = NonlinearSolver(built.model, built.bcs, pre_residual=[built.contact.refresh])
    built.contact.state.shrink.value = 0.0
    its, reason = solver.solve()
    assert reason == NONFINITE_REASON and its == 0 and solver.timings.nonfinite >= 1
    with pytest.raises(DressingFailed, match="NaN/Inf"):
        dress(built, solver, steps=2, margin=0.002, max_cuts=1)


# -- 2. checks on every result ---------------------------------------------------------------
@pytest.fixture(scope="module")
def soft_penalty(tmp_path_factory):
    """The tube with κ̂ = 0.2 (penalty): it sinks into the body by more than its thickness."""
    tmp = tmp_path_factory.mktemp("soft")
    s = small_tube(physics={"kappa_hat": 0.2, "contact": "penalty"})
    code = cli.main(["run", _scene_file(tmp, s), "-q", "-o", str(tmp)])
    return code, json.loads((tmp / s.name / "summary.json").read_text()), s


def test_a_too_soft_penalty_is_a_warning_and_exit_code_4(soft_penalty):
    code, summary, s = soft_penalty
    assert code == 4 and summary["completed"] and not summary["checks_passed"]
    pen = summary["checks"]["penetration"]
    assert not pen["ok"] and pen["value"] > pen["limit"]
    # independent: penalty traction p = κ·(−g) with Laplace's p for the tube
    b = build.build(s, MPI.COMM_WORLD)
    h = fabric("cotton").thickness
    r0 = s.body.radius * (1 + s.garment.ease)
    p = tube_pressure(s.body.radius + h / 2, r0 + 0 * h, b.model.stiffness)
    expected = p / float(b.contact.kappa.value)
    assert summary["max_penetration_m"] == pytest.approx(expected, rel=0.3)
    for name in ("spring", "force_balance", "contact_area"):
        assert summary["checks"][name]["ok"], name


def test_the_default_tube_passes_every_check(tmp_path):
    s = small_tube(physics={"gravity": True})
    result = run(s, tmp_path, quiet=True)
    c = result.summary["checks"]
    assert result.summary["checks_passed"] and all(v["ok"] for v in c.values())
    assert c["spring"]["value"] == 0.0 and c["contact_area"]["value"] > 0.9
    # the body carries the tube's weight ρ h A g: A the pattern's area, (1 + ease) 2πR L
    f = fabric("cotton")
    area = (1 + s.garment.ease) * 2 * math.pi * s.body.radius * s.body.length
    weight = f.density * f.thickness * area * G
    forces = result.summary["forces_N"]
    assert forces["applied"][2] == pytest.approx(-weight, rel=2e-2)
    assert forces["reaction"][2] == pytest.approx(weight, rel=2e-2)
    assert c["force_balance"]["value"] < 1e-3


def test_a_multiplier_loop_that_cannot_reach_its_tolerance_keeps_its_answer(tmp_path, capsys):
    """No multiplier update allowed (``max_updates = 0``) and a tolerance of 1e-4 h (the least
    ``physics.tolerance`` accepts): the augmented Lagrangian stops after its first pass with the
    penetration above it. The run keeps
    its last converged state as the answer, writes its outputs and fails the check
    ``multiplier_penetration`` (exit 4), not the dressing (exit 3); the answer is an
    equilibrium (the force balance holds)."""
    physics = {"contact": "augmented-lagrangian", "tolerance": 1e-4, "max_updates": 0}
    s = small_tube(physics=physics)
    code = cli.main(["run", _scene_file(tmp_path, s), "-o", str(tmp_path)])
    out = capsys.readouterr().out
    summary = json.loads((tmp_path / s.name / "summary.json").read_text())
    assert code == 4 and summary["completed"]
    d = summary["dressing"]
    assert not d["augmented_lagrangian_converged"]
    assert "not below" in d["augmented_lagrangian_message"] and "WARNING" in out
    check = summary["checks"]["multiplier_penetration"]
    h = fabric("cotton").thickness
    assert not check["ok"]
    assert check["value"] == pytest.approx(summary["max_penetration_m"] / (1e-4 * h), rel=1e-6)
    assert summary["checks"]["force_balance"]["ok"]
    assert (tmp_path / s.name / "pressure_regions.csv").exists()
    assert (tmp_path / s.name / "final_state.xdmf").exists()


# -- refused before solving ------------------------------------------------------------------
REFUSED = [
    ("dressing", "regularisation", 1e300, "regularisation"),
    ("dressing", "regularisation", 0.0, "nothing would hold"),
    ("physics", "kappa_hat", 1e-3, "kappa_hat"),
    ("garment", "fabric_overrides", {"E_warp": 1e300}, "not a fabric"),
    ("garment", "fabric_overrides", {"thickness": 1.0}, "not a fabric"),
]


@pytest.mark.parametrize("section, key, value, words", REFUSED, ids=lambda v: str(v)[:20])
def test_scenes_with_a_knowably_wrong_answer_are_refused(section, key, value, words):
    s = small_tube(**{section: {key: value}})
    with pytest.raises(preflight.PreflightError, match=words):
        preflight.scene_limits(s)


@pytest.mark.parametrize("kind, body, ease", [
    ("tube", "cylinder", {"mdi": -0.05}),
    ("gilet", "mannequin", {"wiast": 0.02}),
    ("dress", "mannequin", {"hips": 0.02}),
])  # fmt: skip
def test_a_misspelt_ease_level_is_refused(kind, body, ease):
    with pytest.raises(config.SceneError, match=r"garment\.ease\.\w+\] unknown key"):
        config.from_dict({"body": {"kind": body}, "garment": {"kind": kind, "ease": ease}})


@pytest.mark.parametrize("name", ["..", ".", "a/b", "x\x00y", "\\\\server", " "])
def test_names_that_leave_the_output_root_are_refused(name):
    words = r"\[name\] (must be a plain folder name|has a control character)"
    with pytest.raises(config.SceneError, match=words):
        config.from_dict({"name": name})


def test_cli_refuses_a_zero_spring_without_friction(tmp_path, capsys):
    s = small_tube(dressing={"regularisation": 0.0}, physics={"friction": 0.0})
    err = _one_line_error(["run", _scene_file(tmp_path, s), "-q", "-o", str(tmp_path)], capsys)
    assert "regularisation" in err and not (tmp_path / s.name).exists()


# -- 7. [solver.petsc] -----------------------------------------------------------------------
BAD_PETSC = [
    ({"snes_type": "ksponly"}, "Newton line search"),
    ({"snes_type": "newtontr"}, "Newton line search"),
    ({"snes_max_it": [1, 2]}, "must be an integer, got an array"),
    ({"ksp_type": {"a": 1}}, "must be a string, got a table"),
    ({"snes_rtol": -1.0}, "must lie in"),
    ({"snes_rtol": "tight"}, "must be a number"),
    ({"snes_linesearch_type": "bts"}, "did you mean .bt."),
    ({"snes_rtl": 1e-8}, "did you mean 'snes_rtol'"),
    ({"pc_type": "lu2"}, "did you mean 'lu'"),
    ({"mat_mumps_icntl_99": 1}, "not an option"),
    ({"snes_monitor": 3}, "true or false"),
]


@pytest.mark.parametrize("options, words", BAD_PETSC, ids=lambda v: str(v)[:30])
def test_unsupported_petsc_options_are_refused_before_petsc_sees_them(options, words):
    s = small_tube(solver={"petsc": options})
    with pytest.raises(preflight.PreflightError, match=r"\[solver\.petsc\.\w+\] .*" + words):
        preflight.scene_limits(s)


def test_supported_petsc_options_pass():
    good = {"snes_linesearch_type": "bt", "ksp_type": "gmres", "pc_type": "gamg",
            "ksp_rtol": 1e-8, "mat_mumps_icntl_14": 80, "snes_monitor": False}  # fmt: skip
    preflight.scene_limits(small_tube(solver={"petsc": good}))


def test_ksponly_in_a_real_process_is_a_message_not_a_segfault(tmp_path):
    s = small_tube(solver={"petsc": {"snes_type": "ksponly"}})
    p = subprocess.run([sys.executable, "-m", "fenics_garment.cli", "run",
                        _scene_file(tmp_path, s), "-q", "-o", str(tmp_path)],
                       capture_output=True, text=True, timeout=300)  # fmt: skip
    assert p.returncode == 2, p.stderr
    assert "snes_type" in p.stderr and "Traceback" not in p.stderr


# -- smaller items ---------------------------------------------------------------------------
def test_a_large_cylinder_is_not_refused_for_the_garment_triangles():
    """The garment's triangle estimate uses the garment's area (a tube: 2πRL), not the body's:
    a 10 m cylinder with a 0.5 m body mesh and a 2 cm garment mesh makes 73k garment triangles
    (2πRL / (√3/4 h²)), far below the limit (the body's area would have made 3.7M)."""
    s = small_tube(body={"radius": 10.0, "mesh_size": 0.5})
    assert 2 * math.pi * 10 * 0.2 / (math.sqrt(3) / 4 * 0.02**2) < preflight.MAX_TRIANGLES / 20
    preflight.scene_limits(s)


def test_the_fingerprint_ignores_the_output_folder_but_not_the_error_bars():
    from fenics_garment.scene.checkpoint import fingerprint

    s = small_tube()
    assert fingerprint(s) == fingerprint(small_tube(output={"folder": "elsewhere"}))
    assert fingerprint(s) != fingerprint(small_tube(output={"error_bars": True}))


def test_a_missing_scan_is_refused_on_every_rank_relative_to_the_scene(tmp_path):
    (tmp_path / "scenes").mkdir()
    path = tmp_path / "scenes" / "scan.toml"
    path.write_text('[body]\nkind = "scan"\nfile = "body.obj"\n')
    s = config.load(path)
    with pytest.raises(preflight.PreflightError, match="relative to the scene file"):
        preflight.scene_limits(s)
    (tmp_path / "scenes" / "body.obj").write_text("v 0 0 0\n")
    preflight.scene_limits(s)  # found next to the scene file, not in the working directory


def test_contact_on_an_arm_is_a_failed_check_for_a_torso_garment():
    """The force on regions a garment does not cover, over the whole contact force: 0.094 N on an
    arm (2 cm² at 0.47 kPa, the gilet on the heavier MakeHuman body) against 20 N in all."""
    from fenics_garment.scene.checks import LIMITS, uncovered_force

    rows = [{"region": "waist", "force_N": 19.906}, {"region": "arms", "force_N": 2e-4 * 470.0},
            {"region": "head", "force_N": 0.0}]  # fmt: skip
    share = uncovered_force("gilet", rows)
    assert share == pytest.approx(0.094 / 20.0)
    assert share > LIMITS["uncovered_contact"]
    assert uncovered_force("dress", rows[:1] + rows[2:]) == 0.0
    # a pattern may cover the arms; a body without arm and head regions has nothing to check
    assert uncovered_force("pattern", rows) is None
    assert uncovered_force("gilet", rows[:1]) is None
