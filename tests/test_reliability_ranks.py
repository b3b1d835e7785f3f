"""An error on one MPI rank ends every rank with its message (issue 18, item 3).

* in-process on 2 ranks (``mpiexec -n 2 python -m pytest -m mpi``): a truncated checkpoint of
  rank 1 is a ResumeError on both ranks (the restore is collective), exit code 2, no hang;
* real ``mpiexec -n 2`` jobs (from a serial test): a scan only rank 0 reads (it builds the body)
  that is damaged, and a scene refused on every rank, both end with exit code 2 and the message
  within seconds instead of hanging.
"""

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from test_reliability import _run_until, small_tube

from fenics_garment import cli
from fenics_garment._stack import MPI
from fenics_garment.scene import config

MPIEXEC = Path(sys.executable).parent / "mpiexec"


def _tmp(comm) -> Path:
    return Path(comm.bcast(tempfile.mkdtemp() if comm.rank == 0 else None, root=0))


@pytest.mark.mpi
@pytest.mark.skipif(MPI.COMM_WORLD.size != 2, reason="needs mpiexec -n 2")
def test_a_damaged_checkpoint_of_one_rank_stops_both(monkeypatch, capsys):
    comm = MPI.COMM_WORLD
    folder = _run_until(small_tube(), _tmp(comm), 2, monkeypatch)
    if comm.rank == 0:
        rank1 = folder / "checkpoint" / "state-2.r1.npz"
        rank1.write_bytes(rank1.read_bytes()[:100])
    comm.Barrier()
    assert cli.main(["run", "--resume", str(folder), "-q"]) == 2
    err = capsys.readouterr().err
    if comm.rank == 0:
        assert "state-2.r1.npz: damaged" in err and len(err.strip().splitlines()) == 1, err
    else:
        assert err == ""  # printed once, by rank 0


def _bad_scan_scene(tmp_path: Path) -> Path:
    scan = tmp_path / "body.obj"
    scan.write_text("v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n")
    scene = tmp_path / "scan.toml"
    scene.write_text('name = "scan"\n[body]\nkind = "scan"\nfile = "body.obj"\n'
                     '[garment]\nkind = "gilet"\n')  # fmt: skip
    return scene


def _nul_name_scene(tmp_path: Path) -> Path:
    scene = tmp_path / "nul.toml"
    scene.write_text(config.dumps(small_tube()).replace('"tube-on-cylinder"', '"tu\\u0000be"'))
    return scene


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1 or not MPIEXEC.exists(), reason="spawns mpiexec")
@pytest.mark.parametrize("make, words", [(_bad_scan_scene, "NaN"),
                                         (_nul_name_scene, "plain folder name")],
                         ids=["scan-read-on-rank-0", "name-refused-on-all"])  # fmt: skip
def test_an_error_on_any_rank_ends_the_job(tmp_path, make, words):
    scene = make(tmp_path)
    cmd = [str(MPIEXEC), "-n", "2", sys.executable, "-m", "fenics_garment.cli", "run",
           str(scene), "-q", "-o", str(tmp_path / "out")]  # fmt: skip
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=240)
    except subprocess.TimeoutExpired:
        pytest.fail("the MPI job hung")
    assert p.returncode == 2, p.stderr
    lines = [ln for ln in p.stderr.splitlines() if ln.startswith("error")]
    assert lines and words in lines[0], p.stderr
    assert "Traceback" not in p.stderr
    shutil.rmtree(tmp_path / "out", ignore_errors=True)
