"""Run folders, checkpoints and the environment (issue 18, items 4, 5, 6 and 8): a damaged
checkpoint is a one-line ResumeError (exit 2), an error-bar run resumes with its error bars,
a folder has one writer and no stale outputs, a full disk or a read-only checkpoint folder is a
one-line error with nothing half-written.
"""

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from test_reliability import _run_until, small_tube

from fenics_garment import cli
from fenics_garment._stack import MPI
from fenics_garment.scene import config
from fenics_garment.scene import folder as run_folder
from fenics_garment.scene.run import run

pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial")


def _resume_error(folder: Path, capsys, *words) -> str:
    assert cli.main(["run", "--resume", str(folder), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and len(err.splitlines()) == 1, err
    for w in words:
        assert w in err, err
    return err


@pytest.fixture(scope="module")
def interrupted(tmp_path_factory):
    """A small-tube run stopped right after its second checkpoint (module-wide, read only)."""
    mp = pytest.MonkeyPatch()
    try:
        folder = _run_until(small_tube(), tmp_path_factory.mktemp("ckpt"), 2, mp)
    finally:
        mp.undo()
    return folder


def _copy(folder: Path, tmp_path: Path) -> Path:
    dst = tmp_path / folder.name
    shutil.copytree(folder, dst)
    (dst / run_folder.LOCK).unlink(missing_ok=True)
    return dst


def _edit_meta(folder: Path, edit) -> None:
    path = folder / "checkpoint" / "progress.json"
    meta = json.loads(path.read_text())
    path.write_text(json.dumps(edit(meta)))


def _set(d: dict, dotted: str, value) -> dict:
    *head, last = dotted.split(".")
    t = d
    for k in head:
        t = t[k]
    t[last] = value
    return d


META_DAMAGE = [
    ("checkpoint", "2", "'checkpoint' missing or not int"),
    ("ranks", 1.5, "'ranks' missing or not int"),
    ("format", 99, "format 99"),
    ("progress.shrink", "abc", "shrink = 'abc'"),
    ("progress.stage", "flying", "stage 'flying'"),
    ("progress.report.steps", {"a": 1}, "its progress"),
    ("progress.report", "none", "progress"),
]


@pytest.mark.parametrize("key, value, words", META_DAMAGE, ids=[m[0] for m in META_DAMAGE])
def test_damaged_progress_file_is_a_resume_error(interrupted, tmp_path, capsys, key, value,
                                                 words):  # fmt: skip
    folder = _copy(interrupted, tmp_path)
    _edit_meta(folder, lambda m: _set(m, key, value))
    _resume_error(folder, capsys, words, "from the start")


def test_truncated_or_foreign_progress_file(interrupted, tmp_path, capsys):
    folder = _copy(interrupted, tmp_path)
    path = folder / "checkpoint" / "progress.json"
    text = path.read_text()
    path.write_text(text[: len(text) // 2])
    _resume_error(folder, capsys, "damaged", "JSONDecodeError")
    path.write_text("[1, 2, 3]")
    _resume_error(folder, capsys, "not a JSON object")
    path.write_bytes(b"\xff\xfe\x00")
    _resume_error(folder, capsys, "damaged")


def _rank_file(folder: Path) -> Path:
    (path,) = (folder / "checkpoint").glob("state-*.r0.npz")
    return path


def _rewrite(path: Path, change) -> None:
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    arrays = change(arrays)
    with open(path, "wb") as f:
        np.savez(f, **arrays)


RANK_DAMAGE = [
    ("truncated", lambda p: p.write_bytes(p.read_bytes()[: len(p.read_bytes()) // 3]), "damaged"),
    ("missing", lambda p: p.unlink(), "missing"),
    ("not_a_zip", lambda p: p.write_bytes(os.urandom(4000)), "damaged"),
    ("wrong_key", lambda p: _rewrite(p, lambda a: {("qq" if k == "q" else k): v
                                                   for k, v in a.items()}), "no 'q' array"),
    ("wrong_shape", lambda p: _rewrite(p, lambda a: {**a, "q": a["q"][:-3]}), "rebuilt scene"),
    ("wrong_type", lambda p: _rewrite(p, lambda a: {**a, "lam": a["lam"].astype(str)}),
     "rebuilt scene"),
    ("nan", lambda p: _rewrite(p, lambda a: {**a, "q": a["q"] * np.nan}), "NaN/Inf"),
]  # fmt: skip


@pytest.mark.parametrize("damage, words", [(d[1], d[2]) for d in RANK_DAMAGE],
                         ids=[d[0] for d in RANK_DAMAGE])  # fmt: skip
def test_damaged_rank_file_is_a_resume_error(interrupted, tmp_path, capsys, damage, words):
    folder = _copy(interrupted, tmp_path)
    damage(_rank_file(folder))
    _resume_error(folder, capsys, words)


# -- 5. resume of an error-bar run -----------------------------------------------------------
@pytest.mark.slow
def test_an_error_bar_run_resumes_with_its_error_bars(tmp_path, monkeypatch):
    """Stopped in the coarse level, then in the fine one: `--resume` finishes both and gives
    the uninterrupted run's error bars (before: they were silently dropped)."""
    s = small_tube(output={"error_bars": True, "vtx": False})
    ref = run(s, tmp_path / "ref", quiet=True)
    folder = _run_until(s, tmp_path / "cut", 2, monkeypatch)  # the coarse level's 2nd checkpoint
    used = config.load(folder / "scene_used.toml")
    assert used.output.error_bars
    assert cli.main(["run", "--resume", str(folder), "-q"]) == 0
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["error_bars"]["coarse_dofs"] == ref.summary["error_bars"]["coarse_dofs"]
    got, want = summary["regions"][0], ref.summary["regions"][0]
    for k in ("mean_kPa", "p95_kPa", "mean_err_kPa", "p95_err_kPa"):
        assert got[k] == pytest.approx(want[k], rel=1e-9, abs=1e-12), k
    assert json.loads((folder / "run.json").read_text())["status"] == "completed"


def test_resume_without_error_bars_names_them(tmp_path, monkeypatch, capsys):
    s = small_tube(output={"error_bars": True, "vtx": False})
    _run_until(s, tmp_path, 2, monkeypatch)  # coarse level, checkpoint 2
    coarse = tmp_path / s.name / "coarse_level" / s.name
    assert (coarse / "checkpoint" / "progress.json").exists()
    # the whole run's folder has no checkpoint of its own yet: resuming it as a plain run
    plain = tmp_path / "plain.toml"
    plain.write_text(config.dumps(small_tube(output={"vtx": False})))
    assert cli.main(["run", str(plain), "--resume", str(tmp_path / s.name), "-q"]) == 2
    assert "no checkpoint" in capsys.readouterr().err


# -- 6. the output folder's state ------------------------------------------------------------
def test_a_killed_rerun_leaves_no_stale_complete_looking_outputs(tmp_path, monkeypatch):
    s = small_tube(output={"vtx": False})
    first = run(s, tmp_path, quiet=True)
    folder = first.folder
    assert json.loads((folder / "run.json").read_text())["status"] == "completed"
    assert json.loads((folder / "summary.json").read_text())["run_id"] == first.summary["run_id"]
    _run_until(s, tmp_path, 1, monkeypatch)  # a fresh re-run, stopped after one solve
    assert not (folder / "summary.json").exists() and not (folder / "final_state.xdmf").exists()
    state = json.loads((folder / "run.json").read_text())
    assert state["status"] == "failed" and state["run_id"] != first.summary["run_id"]
    assert not (folder / run_folder.LOCK).exists()


def _live_lock(folder: Path, pid: int) -> None:
    import socket

    folder.mkdir(parents=True, exist_ok=True)
    (folder / run_folder.LOCK).write_text(
        json.dumps({"pid": pid, "host": socket.gethostname(), "run_id": "other"})
    )


def test_a_second_writer_is_refused_while_the_first_lives(tmp_path, capsys):
    s = small_tube()
    scene = tmp_path / "s.toml"
    scene.write_text(config.dumps(s))
    other = subprocess.Popen(["sleep", "60"])
    try:
        _live_lock(tmp_path / "out" / s.name, other.pid)
        assert cli.main(["run", str(scene), "-q", "-o", str(tmp_path / "out")]) == 2
        err = capsys.readouterr().err
        assert f"another run (pid {other.pid}" in err and len(err.strip().splitlines()) == 1
    finally:
        other.kill()
        other.wait()
    # the same lock once its process is gone: taken over
    f = run_folder.RunFolder(tmp_path / "out" / s.name, MPI.COMM_WORLD)
    f.acquire()
    assert json.loads((f.path / run_folder.LOCK).read_text())["run_id"] == f.run_id
    f.release()
    assert not (f.path / run_folder.LOCK).exists()


@pytest.mark.slow
def test_two_real_processes_into_one_folder(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text(config.dumps(small_tube(output={"vtx": False})))
    cmd = [sys.executable, "-m", "fenics_garment.cli", "run", str(scene), "-q", "-o",
           str(tmp_path / "out")]  # fmt: skip
    first = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True)
    lock = tmp_path / "out" / "tube-on-cylinder" / run_folder.LOCK
    t0 = time.time()
    while not lock.exists() and time.time() - t0 < 120:
        time.sleep(0.2)
    second = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert first.wait(timeout=600) == 0
    assert second.returncode == 2 and "another run" in second.stderr
    assert "Traceback" not in second.stderr + first.stderr.read()


def test_a_name_cannot_leave_the_output_root(tmp_path, capsys):
    out = tmp_path / "root" / "out"
    out.mkdir(parents=True)
    path = tmp_path / "root" / "s.toml"
    path.write_text(config.dumps(small_tube()).replace('name = "tube-on-cylinder"', 'name = ".."'))
    assert cli.main(["run", str(path), "-q", "-o", str(out)]) == 2
    assert "plain folder name" in capsys.readouterr().err
    assert sorted(p.name for p in (tmp_path / "root").iterdir()) == ["out", "s.toml"]
    assert not any(out.iterdir())


# -- 8. environment faults -------------------------------------------------------------------
def _mount_tmpfs(where: Path, size: str) -> bool:
    where.mkdir(parents=True, exist_ok=True)
    if os.geteuid() != 0 or shutil.which("mount") is None:
        return False
    p = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)],
                       capture_output=True)  # fmt: skip
    return p.returncode == 0


def _umount(where: Path) -> None:
    # lazy: a VTX writer given up after the fault keeps its (emptied) files open until exit
    subprocess.run(["umount", "-l", str(where)], capture_output=True)


def _no_partial_files(folder: Path) -> None:
    stray = [p for p in folder.rglob("*") if ".part" in p.name]
    assert not stray, stray


def test_a_full_disk_is_exit_5_with_nothing_half_written(tmp_path, capsys):
    disk = tmp_path / "disk"
    if not _mount_tmpfs(disk, "1m"):
        pytest.skip("needs root and tmpfs mounts for a 1 MB disk")
    try:
        scene = tmp_path / "s.toml"
        scene.write_text(config.dumps(small_tube()))
        assert cli.main(["run", str(scene), "-o", str(disk), "-q"]) == 5
        err = capsys.readouterr().err.strip()
        assert "No space left on device" in err and len(err.splitlines()) == 1, err
        folder = disk / "tube-on-cylinder"
        assert f"--resume {folder}" in err
        _no_partial_files(folder)
        assert not (folder / "summary.json").exists()
        assert json.loads((folder / "run.json").read_text())["status"] == "failed"
        # more space: the run continues from its last checkpoint and completes
        subprocess.run(["mount", "-o", "remount,size=64m", str(disk)], check=True)
        assert cli.main(["run", "--resume", str(folder), "-q"]) == 0
        assert json.loads((folder / "summary.json").read_text())["checks_passed"]
    finally:
        _umount(disk)


def test_a_read_only_checkpoint_folder_is_refused_up_front(interrupted, tmp_path, capsys):
    folder = _copy(interrupted, tmp_path)
    ckpt = folder / "checkpoint"
    if os.geteuid() == 0:  # root ignores permissions: a read-only bind mount
        ok = subprocess.run(["mount", "--bind", "-o", "ro", str(ckpt), str(ckpt)],
                            capture_output=True).returncode == 0  # fmt: skip
        if not ok:
            pytest.skip("root without bind mounts cannot make a read-only folder")
    else:
        ckpt.chmod(0o555)
    try:
        err = _resume_error(folder, capsys, "cannot write the output folder", "checkpoint")
        assert "Read-only file system" in err or "ermission denied" in err
    finally:
        if os.geteuid() == 0:
            _umount(ckpt)
        else:
            ckpt.chmod(0o755)


def test_an_injected_enospc_in_a_checkpoint_keeps_the_previous_one(tmp_path, capsys,
                                                                   monkeypatch):  # fmt: skip
    """Where no tmpfs can be mounted: the third checkpoint's write fails with ENOSPC at the
    file-system call. Exit 5, one line; checkpoint 2 stays complete and the resumed run (disk
    "freed") completes."""
    import errno

    real = Path.write_bytes
    calls = {"n": 0}

    def full_disk(self, data):
        if self.name.startswith(".state-"):
            calls["n"] += 1
            if calls["n"] == 3:
                real(self, data[: len(data) // 2])  # part of it, as a full disk does
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(self))
        return real(self, data)

    scene = tmp_path / "s.toml"
    scene.write_text(config.dumps(small_tube(output={"vtx": False})))
    with monkeypatch.context() as m:
        m.setattr(Path, "write_bytes", full_disk)
        assert cli.main(["run", str(scene), "-o", str(tmp_path / "out"), "-q"]) == 5
    err = capsys.readouterr().err.strip()
    assert "No space left on device" in err and len(err.splitlines()) == 1, err
    folder = tmp_path / "out" / "tube-on-cylinder"
    _no_partial_files(folder)
    meta = json.loads((folder / "checkpoint" / "progress.json").read_text())
    assert meta["checkpoint"] == 2 and (folder / "checkpoint" / "state-2.r0.npz").exists()
    assert not (folder / "checkpoint" / "state-3.r0.npz").exists()
    assert cli.main(["run", "--resume", str(folder), "-q"]) == 0
