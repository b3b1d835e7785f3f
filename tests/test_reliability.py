"""Restarts and pre-solve checks: a resumed run gives the uninterrupted answer; hopeless runs stop
before any solve with a one-line message (CLI exit code 2).

The interruption is simulated in-process (an exception right after a checkpoint is written);
``test_reliability_kill.py`` kills a real process with SIGKILL.
"""

import json
import os
import re
import shutil
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from fenics_garment import cli
from fenics_garment._stack import MPI
from fenics_garment.scene import checkpoint, config
from fenics_garment.scene.checkpoint import ResumeError
from fenics_garment.scene.run import garment_arrays, run

DEMOS = Path(__file__).parent.parent / "demos"


def small_tube(**changes) -> config.Scene:
    """The tube demo with a coarser body (faster), no pictures; ``changes``: section overrides."""
    s = config.load(DEMOS / "tube_on_cylinder.toml")
    s = replace(s, body=replace(s.body, mesh_size=0.01), output=replace(s.output, pictures=False))
    for section, kw in changes.items():
        s = replace(s, **{section: replace(getattr(s, section), **kw)})
    return s


def _tmp(comm=MPI.COMM_WORLD) -> Path:
    return Path(comm.bcast(tempfile.mkdtemp() if comm.rank == 0 else None, root=0))


class Interrupted(Exception):
    pass


def _run_until(scene, root: Path, k: int, monkeypatch) -> Path:
    """Run ``scene`` and stop it right after checkpoint ``k``; returns the run folder."""
    write = checkpoint.Writer.write

    def write_then_stop(self, built, progress):
        write(self, built, progress)
        if self.k == k:
            raise Interrupted

    with monkeypatch.context() as m:
        m.setattr(checkpoint.Writer, "write", write_then_stop)
        with pytest.raises(Interrupted):
            run(scene, root, quiet=True)
    return root / scene.name


@pytest.fixture(scope="module")
def reference():
    """An uninterrupted run of the small tube: the answer every resume must give."""
    result = run(small_tube(), _tmp(), quiet=True)
    return result, garment_arrays(result.built)


def _same_steps(a, b) -> None:
    key = [(s.shrink, s.iterations, s.cuts, s.regularisation) for s in a.steps]
    assert key == [(s.shrink, s.iterations, s.cuts, s.regularisation) for s in b.steps]
    assert a.failures == b.failures


@pytest.mark.parametrize("k", [1, 4])  # while the body grows; during the spring release
def test_resume_gives_the_uninterrupted_answer(reference, k, monkeypatch):
    ref, (x_ref, p_ref) = reference
    folder = _run_until(small_tube(), _tmp(), k, monkeypatch)
    meta = json.loads((folder / "checkpoint" / "progress.json").read_text())
    assert meta["checkpoint"] == k and meta["ranks"] == MPI.COMM_WORLD.size
    assert not (folder / "summary.json").exists()  # stopped before the outputs
    resumed = run(config.load(folder / "scene_used.toml"), quiet=True, resume=folder)
    x, p = garment_arrays(resumed.built)
    # the same steps replayed from the same arrays: equal to round-off (in fact bit for bit)
    assert np.abs(p - p_ref).max() <= 1e-10 * np.abs(p_ref).max()
    assert np.abs(x - x_ref).max() <= 1e-12
    _same_steps(resumed.report, ref.report)
    assert resumed.summary["completed"] and resumed.summary["time_s"]["checkpoint"] >= 0
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["regions"][0]["mean_kPa"] == pytest.approx(
        ref.summary["regions"][0]["mean_kPa"], rel=1e-10
    )


def test_checkpoint_time_is_small(reference):
    ref, _ = reference
    t = ref.summary["time_s"]
    # 7 checkpoints of a 2 352-dof garment: measured ≈ 0.1 s against ≈ 3 s of dressing
    assert 0 < t["checkpoint"] < 0.2 * t["dressing"]


def test_resume_a_finished_run_only_rewrites_the_outputs(reference):
    ref, (_, p_ref) = reference
    root = _tmp()
    if MPI.COMM_WORLD.rank == 0:
        shutil.copytree(ref.folder, root / ref.folder.name)
    MPI.COMM_WORLD.Barrier()
    resumed = run(small_tube(), quiet=True, resume=root / ref.folder.name)
    assert resumed.report.newton_iterations == ref.report.newton_iterations
    assert len(resumed.report.steps) == len(ref.report.steps)
    assert np.array_equal(garment_arrays(resumed.built)[1], p_ref)


def test_resume_refuses_another_scene(reference):
    ref, _ = reference
    other = small_tube(garment={"ease": -0.05})
    with pytest.raises(ResumeError, match="another scene"):
        run(other, quiet=True, resume=ref.folder)


def test_resume_refuses_another_number_of_ranks(reference, tmp_path):
    ref, _ = reference
    folder = _tmp() / "copy"
    comm = MPI.COMM_WORLD
    if comm.rank == 0:
        shutil.copytree(ref.folder, folder)
        meta_path = folder / "checkpoint" / "progress.json"
        meta = json.loads(meta_path.read_text())
        meta["ranks"] = comm.size + 1
        meta["seal"] = checkpoint.seal(meta)  # a consistent checkpoint of another rank count
        meta_path.write_text(json.dumps(meta))
    comm.Barrier()
    with pytest.raises(ResumeError, match=rf"written by {comm.size + 1} MPI rank.*mpiexec -n"):
        run(small_tube(), quiet=True, resume=folder)


def test_resume_without_checkpoint_through_the_cli(tmp_path, capsys):
    folder = tmp_path / "tube-on-cylinder"
    folder.mkdir()
    (folder / "scene_used.toml").write_text(config.dumps(small_tube()))
    assert cli.main(["run", "--resume", str(folder), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert "no checkpoint to resume from" in err and len(err.splitlines()) == 1
    assert cli.main(["run", "--resume", str(tmp_path / "nothing"), "-q"]) == 2
    assert "scene_used.toml" in capsys.readouterr().err


# -- checks before any solve -------------------------------------------------------------------
def _cli_error(argv, capsys) -> str:
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and len(err.splitlines()) == 1, err
    assert "Traceback" not in err
    return err


def _scene_file(tmp_path: Path, scene: config.Scene) -> str:
    path = tmp_path / "scene.toml"
    path.write_text(config.dumps(scene))
    return str(path)


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial CLI check")
def test_output_folder_under_a_file(tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    scene = _scene_file(tmp_path, small_tube())
    err = _cli_error(["run", scene, "-q", "-o", str(blocker / "out")], capsys)
    assert "cannot write the output folder" in err and "a_file" in err and "-o/--output" in err


@pytest.mark.skipif(
    MPI.COMM_WORLD.size > 1 or os.geteuid() == 0, reason="serial; root ignores permissions"
)
def test_output_folder_read_only(tmp_path, capsys):
    ro = tmp_path / "ro"
    ro.mkdir(mode=0o555)
    scene = _scene_file(tmp_path, small_tube())
    err = _cli_error(["run", scene, "-q", "-o", str(ro)], capsys)
    assert "cannot write the output folder" in err and "ermission denied" in err


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial CLI check")
def test_body_mesh_too_coarse_for_its_curvature(tmp_path, capsys):
    s = small_tube(body={"mesh_size": 0.06})  # radius 0.1 m: at most r/2 = 0.05 m
    err = _cli_error(["check", _scene_file(tmp_path, s)], capsys)
    assert "[body.mesh_size] = 0.06 m is too coarse" in err and "<= 0.05 m" in err


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial CLI check")
def test_garment_starting_too_deep_inside_the_body(tmp_path, capsys):
    # 49 % smaller than the cylinder plus a 3.5 cm margin: the body would shrink by > 0.8 R
    s = small_tube(garment={"ease": -0.49}, dressing={"margin": 0.035})
    err = _cli_error(["run", _scene_file(tmp_path, s), "-q", "-o", str(tmp_path)], capsys)
    assert "inside the body" in err and "80% of its smallest radius" in err
    assert "less negative garment.ease" in err
    assert not (tmp_path / s.name / "summary.json").exists()


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial CLI check")
def test_check_a_good_scene(tmp_path, capsys):
    assert cli.main(["check", _scene_file(tmp_path, small_tube())]) == 0
    out = capsys.readouterr().out
    assert "ok" in out and re.search(r"garment \d+ cells", out) and "initial penetration" in out


def test_zero_density_is_valid_and_weightless():
    s = config.from_dict({"garment": {"fabric_overrides": {"density": 0.0}}})
    assert s.garment.fabric_overrides["density"] == 0.0
    for bad in ({"thickness": 0.0}, {"E_warp": 0.0}, {"density": -1.0}):
        with pytest.raises(config.SceneError, match=f"fabric_overrides.{next(iter(bad))}"):
            config.from_dict({"garment": {"fabric_overrides": bad}})
