"""Output faults agreed on by every rank (issue 48): a writer error on any rank is one collective
decision (``output.agree``), the ADIOS2 writer's C++ exceptions are caught and the writer never
closed again (its destructor would abort the process), exit code 5 with one line, ``run.json``
says what failed, nothing partial is left under a real name, and the run resumes.

A full disk is made for real where a tmpfs can be mounted (root); the faults of one rank only
are injected: a VTX writer that fails at its n-th frame, as ADIOS2 does on a full disk.
"""

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from test_reliability import small_tube

from fenics_garment import cli, output
from fenics_garment._stack import MPI, dolfinx
from fenics_garment.scene import config
from fenics_garment.scene import folder as run_folder

ROOT = Path(__file__).parent.parent
MPIEXEC = Path(sys.executable).parent / "mpiexec"
FOLDER = "tube-on-cylinder"
ENOSPC = "[ADIOS2 EXCEPTION] couldn't write to file data.0 : errno = 28: No space left on device"


def _failing_writer(at: int, ranks: tuple[int, ...]):
    """A VTXWriter whose ``at``-th write raises on ``ranks`` after its collective part, as
    ADIOS2's aggregating rank does on a full disk (the data gathered, the file write failed)."""
    base = dolfinx.io.VTXWriter

    class Failing(base):
        writes = 0

        def write(self, t: float) -> None:
            super().write(t)
            Failing.writes += 1
            if Failing.writes == at and MPI.COMM_WORLD.rank in ranks:
                raise RuntimeError(ENOSPC)

    return Failing


def _tmp() -> Path:
    comm = MPI.COMM_WORLD
    return Path(comm.bcast(tempfile.mkdtemp() if comm.rank == 0 else None, root=0))


def _nothing_partial(folder: Path) -> None:
    assert not [p.name for p in folder.rglob("*") if ".part" in p.name]
    assert not (folder / "dressing.bp").exists() and not (folder / "summary.json").exists()


def _scene_file(root: Path) -> str:
    path = root / "tube.toml"
    if MPI.COMM_WORLD.rank == 0:
        path.write_text(config.dumps(small_tube()))
    MPI.COMM_WORLD.Barrier()
    return str(path)


def _fails_then_resumes(monkeypatch, capsys, ranks: tuple[int, ...], resume: bool) -> None:
    root = _tmp()
    monkeypatch.setattr(dolfinx.io, "VTXWriter", _failing_writer(3, ranks))
    code = cli.main(["run", "-q", _scene_file(root), "-o", str(root)])
    err = capsys.readouterr().err.strip()
    folder = root / FOLDER
    assert code == 5
    if MPI.COMM_WORLD.rank == 0:
        assert len(err.splitlines()) == 1 and "No space left on device" in err, err
        assert f"--resume {folder}" in err
        state = json.loads((folder / "run.json").read_text())
        assert state["status"] == "failed" and "No space left on device" in state["error"]
        _nothing_partial(folder)
    monkeypatch.undo()
    if not resume:
        return
    assert cli.main(["run", "-q", "--resume", str(folder)]) == 0
    if MPI.COMM_WORLD.rank == 0:
        assert json.loads((folder / "run.json").read_text())["status"] == "completed"
        assert (folder / "dressing.bp").is_dir()


RESUME = [False, pytest.param(True, marks=pytest.mark.slow)]


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial")
@pytest.mark.parametrize("resume", RESUME)
def test_a_vtx_fault_is_exit_5_and_the_run_resumes(monkeypatch, capsys, resume):
    _fails_then_resumes(monkeypatch, capsys, (0,), resume)


@pytest.mark.mpi
@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="needs mpiexec -n 2")
@pytest.mark.parametrize("resume", RESUME)
def test_a_vtx_fault_of_one_rank_is_decided_by_both(monkeypatch, capsys, resume):
    """Rank 1's writer fails alone: both ranks end with exit 5 (no rank waits for ever)."""
    _fails_then_resumes(monkeypatch, capsys, (1,), resume)


@pytest.mark.mpi
@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="needs mpiexec -n 2")
def test_agree_is_one_decision():
    comm = MPI.COMM_WORLD
    assert output.agree(comm, None) is None
    assert output.agree(comm, "disk full" if comm.rank == 1 else None) == "disk full"


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial")
def test_run_json_is_written_in_place_on_a_full_disk(tmp_path, monkeypatch):
    path = tmp_path / "run.json"
    run_folder.write_state(path, {"status": "running"})
    assert path.stat().st_size == run_folder.STATE_BYTES

    def full(*args, **kw):
        raise OSError(28, os.strerror(28), str(path))

    monkeypatch.setattr(output, "write_text", full)
    run_folder.write_state(path, {"status": "failed", "error": "cannot write x: disk full"})
    assert json.loads(path.read_text())["status"] == "failed"


def _long_path(root: Path) -> Path:
    path = root / ("d" * 200)
    while len(str(path)) < 4100:
        path = path / ("d" * 200)
    return path


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial")
@pytest.mark.parametrize("what", ["path", "name"])  # PATH_MAX 4096; NAME_MAX 255
def test_an_output_path_the_system_cannot_hold_is_refused(tmp_path, capsys, what):
    root = _long_path(tmp_path) if what == "path" else tmp_path / ("x" * 300)
    assert cli.main(["run", "-q", _scene_file(tmp_path), "-o", str(root)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "-o/--output" in err and len(err) < 1000, err


# -- real small disks (root: tmpfs) ------------------------------------------------------------
def _mount(where: Path, size: str) -> bool:
    where.mkdir()
    if os.geteuid() != 0:
        return False
    cmd = ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)]
    return subprocess.run(cmd, capture_output=True).returncode == 0


@pytest.mark.slow
@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="runs its own processes")
@pytest.mark.parametrize("ranks", [1, 2])
@pytest.mark.parametrize("size", ["600k", "1200k", "2600k"])  # before, at, after a checkpoint
def test_a_real_full_disk_then_resume(tmp_path, ranks, size):
    disk = tmp_path / "disk"
    if not _mount(disk, size):
        pytest.skip("needs root and tmpfs mounts")
    try:
        launch = [str(MPIEXEC), "-n", str(ranks)] if ranks > 1 else []
        cmd = [*launch, sys.executable, "-m", "fenics_garment.cli", "run", "-q"]
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        p = subprocess.run([*cmd, _scene_file(tmp_path), "-o", str(disk)], env=env,
                           capture_output=True, text=True, timeout=600)  # fmt: skip
        lines = [ln for ln in p.stderr.splitlines() if ln and not ln.startswith("[mpiexec@")]
        assert p.returncode == 5 and len(lines) == 1, p.stderr[-3000:]
        folder = disk / FOLDER
        assert json.loads((folder / "run.json").read_text())["status"] == "failed"
        _nothing_partial(folder)
        subprocess.run(["mount", "-o", "remount,size=64m", str(disk)], check=True)
        resumable = (folder / "checkpoint" / "progress.json").exists()
        assert ("--resume" in lines[0]) == resumable and ("start it again" in lines[0]) != (
            resumable)  # fmt: skip
        again = ["--resume", str(folder)] if resumable else [_scene_file(tmp_path), "-o", str(disk)]
        p = subprocess.run([*cmd, *again], env=env, capture_output=True, text=True, timeout=600)
        assert p.returncode == 0, p.stderr[-3000:]
    finally:
        subprocess.run(["umount", "-l", str(disk)], capture_output=True)
