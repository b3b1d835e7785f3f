"""Checkpoints that cannot lie (issue 48): every value read back is checked against its meaning,
the progress file is sealed and the rank files' digests recorded in it, and the checkpoint
records what the state depends on besides the scene (package version, terms hooks' sources,
input files, meshes); ``--resume`` refuses a mismatch with one line naming it (exit code 2).
"""

import math
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from test_reliability import _run_until, small_tube

from benchmarks.reliability import edit_progress
from fenics_garment import cli
from fenics_garment._stack import MPI
from fenics_garment.scene import checkpoint, config
from fenics_garment.scene import folder as run_folder
from fenics_garment.scene.dressing import DressReport, DressStep, Progress

pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial")


# -- the rules, on progress objects (no run) ---------------------------------------------------
def _growing() -> Progress:
    """The progress of a dressing after two grow solves (shrink 2 of 6 mm)."""
    steps = [DressStep(0.004, 2, 2, 0, 0.5, 100.0), DressStep(0.002, 2, 2, 0, 0.5, 100.0)]
    return Progress(DressReport(shrink0=0.006, steps=steps), "grow", 0.002, 0.002, c=100.0)


def _releasing() -> Progress:
    p = _growing()
    p.report.steps.append(DressStep(0.0, 2, 2, 0, 0.5, 100.0))
    p.report.steps += [DressStep(0.0, 1, 2, 0, 0.5, c, stage="release") for c in (25.0, 6.0)]
    return replace(p, stage="release", shrink=0.0, c=1.5, solves=2)


def test_true_progress_obeys_every_rule():
    assert checkpoint.meaning(_growing()) == ""
    assert checkpoint.meaning(_releasing()) == ""


LIES = [
    ("stage release while the body is shrunk", lambda p: replace(p, stage="release"), "stage"),
    ("stage done, not completed", lambda p: replace(p, stage="done", shrink=0.0), "shrink"),
    ("negative shrink", lambda p: replace(p, shrink=-0.001), "shrink"),
    ("NaN shrink", lambda p: replace(p, shrink=math.nan), "shrink"),
    ("shrink beyond the initial", lambda p: replace(p, shrink=0.01), "outside"),
    ("shrink not the last solve's", lambda p: replace(p, shrink=0.003), "last solve"),
    ("negative step", lambda p: replace(p, step=-0.001), "step"),
    ("zero step", lambda p: replace(p, step=0.0), "step"),
    ("negative spring constant", lambda p: replace(p, c=-1.0), "negative"),
    ("negative friction", lambda p: replace(p, mu=-0.3), "negative"),
    ("negative retries", lambda p: replace(p, retries=-1), "retries"),
    ("more release solves than solves", lambda p: replace(p, solves=99), "release solves"),
    ("sewing beyond 1", lambda p: replace(p, sewn=1.5), "sewing"),
]  # fmt: skip


@pytest.mark.parametrize("lie, words", [(x[1], x[2]) for x in LIES], ids=[x[0] for x in LIES])
def test_a_lie_of_the_right_type_is_found(lie, words):
    assert words in checkpoint.meaning(lie(_growing()))


def test_a_schedule_that_goes_backwards_is_found():
    p = _growing()
    p.report.steps.reverse()
    assert "does not decrease" in checkpoint.meaning(replace(p, shrink=0.004))
    r = _releasing()
    r.report.steps[-1].regularisation = 50.0
    assert "spring constant of the release solves grows" in checkpoint.meaning(r)
    r = _releasing()
    r.report.steps[0].iterations = -2
    assert "negative count" in checkpoint.meaning(r)


# -- through --resume (one interrupted run) ----------------------------------------------------
@pytest.fixture(scope="module")
def interrupted(tmp_path_factory):
    """A small-tube run stopped right after its first checkpoint, while the body grows (read
    only; at the second the body has its size, where a "release" stage would be no lie)."""
    mp = pytest.MonkeyPatch()
    try:
        return _run_until(small_tube(), tmp_path_factory.mktemp("lies"), 1, mp)
    finally:
        mp.undo()


def _copy(folder: Path, tmp_path: Path) -> Path:
    dst = tmp_path / folder.name
    shutil.copytree(folder, dst)
    (dst / run_folder.LOCK).unlink(missing_ok=True)
    return dst


def _refused(folder: Path, capsys) -> str:
    assert cli.main(["run", "--resume", str(folder), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and len(err.splitlines()) == 1, err
    return err


def _stage(value):
    return lambda m: m["progress"].update(stage=value)


SLOW = pytest.mark.slow  # refused after the build
EDITS = [
    pytest.param(_stage("release"), False, "contradicts itself: stage 'release'",
                 id="stage, unsealed"),
    pytest.param(lambda m: m["progress"].update(spring=1.234), False,
                 "changed after it was written", id="a plausible value, unsealed"),
    pytest.param(_stage("release"), True, "contradicts itself: stage 'release'",
                 id="stage, resealed"),
    pytest.param(lambda m: m["progress"].update(step=-1e-3), True, "step -0.001",
                 id="step, resealed"),
    pytest.param(lambda m: m["progress"].update(c=-5.0), True, "negative value",
                 id="spring, resealed"),
    pytest.param(lambda m: m["depends"].update({"fenics-garment version": "0.0.1"}), True,
                 "fenics-garment version changed (0.0.1 then", id="version"),
    pytest.param(lambda m: m["depends"].update(meshes="0" * 16), True, "meshes changed",
                 id="meshes", marks=SLOW),
    pytest.param(lambda m: m["progress"].update(mu=0.05), True,
                 "does not fit the rebuilt scene: friction coefficient 0.05", id="friction",
                 marks=SLOW),
]  # fmt: skip


@pytest.mark.parametrize("change, reseal, words", EDITS)
def test_a_lying_progress_file_is_refused(interrupted, tmp_path, capsys, change, reseal, words):
    folder = _copy(interrupted, tmp_path)
    edit_progress(folder, change, reseal=reseal)
    assert words in _refused(folder, capsys)


@pytest.mark.slow  # (refused after the build)
def test_a_rank_file_rewritten_with_valid_arrays_is_refused(interrupted, tmp_path, capsys):
    folder = _copy(interrupted, tmp_path)
    (path,) = (folder / "checkpoint").glob("state-*.r0.npz")
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    with open(path, "wb") as f:
        np.savez(f, **{**arrays, "q": arrays["q"] * 1.01})
    assert "its digest is not the one progress.json records" in _refused(folder, capsys)


@pytest.mark.slow
def test_a_terms_hook_edited_before_resume_is_refused(tmp_path, monkeypatch, capsys):
    hook = tmp_path / "law.py"
    hook.write_text("def terms(built):\n    pass\n")
    s = small_tube(physics={"terms": f"{hook}:terms"})
    scene = tmp_path / "tube.toml"
    scene.write_text(config.dumps(s))
    folder = _run_until(config.load(scene), tmp_path / "out", 1, monkeypatch)
    hook.write_text("def terms(built):\n    built.model.membrane = built.model.membrane\n")
    err = _refused(folder, capsys)
    assert "terms hook terms" in err and "law.py" in err and "changed" in err
