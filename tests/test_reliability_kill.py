"""Kill a real run with SIGKILL after its first checkpoint, resume it, compare with a whole run.

The tube demo with a coarser body and 6 dressing steps (so that the kill lands while it dresses)
runs in a subprocess through the CLI; when ``checkpoint/progress.json`` appears the process is
killed. ``run --resume`` then completes it. Checked: the pressures equal those of an
uninterrupted run, and no file in the folder that looks whole is half-written (each is written
to a temporary name and renamed; only ``.*part*`` names may be left by the kill).
"""

import json
import os
import signal
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import meshio
import numpy as np
import pytest

from fenics_garment._stack import MPI
from fenics_garment.scene import config

ROOT = Path(__file__).parent.parent
pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="runs its own processes")


def _scene(tmp: Path) -> Path:
    s = config.load(ROOT / "demos" / "tube_on_cylinder.toml")
    s = replace(s, body=replace(s.body, mesh_size=0.01), output=replace(s.output, pictures=False),
                dressing=replace(s.dressing, steps=6, grow=1.0))  # fmt: skip
    path = tmp / "tube.toml"
    path.write_text(config.dumps(s))
    return path


def _cli(*args: str, **kw) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "fenics_garment.cli", *args]
    return subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, **kw)


def _pressure(folder: Path) -> np.ndarray:
    with meshio.xdmf.TimeSeriesReader(folder / "final_state.xdmf") as r:
        r.read_points_cells()
        _, point_data, _ = r.read_data(0)
    return point_data["contact_pressure"]


def _looks_whole(folder: Path) -> None:
    for path in folder.rglob("*"):
        if path.is_dir() or ".part" in path.name:
            continue
        if path.suffix == ".json":
            json.loads(path.read_text())
        elif path.suffix == ".npz":
            with np.load(path) as d:
                [d[k] for k in d.files]
        elif path.suffix == ".toml":
            config.load(path)
        elif path.suffix in (".vtu", ".xdmf"):
            meshio.read(path) if path.suffix == ".vtu" else _pressure(folder)


def test_sigkill_then_resume(tmp_path):
    scene = _scene(tmp_path)
    whole = _cli("run", str(scene), "-q", "-o", str(tmp_path / "whole"))
    killed = _cli("run", str(scene), "-q", "-o", str(tmp_path / "killed"))
    folder = tmp_path / "killed" / "tube-on-cylinder"
    progress = folder / "checkpoint" / "progress.json"
    t0 = time.monotonic()
    while not progress.exists() and killed.poll() is None and time.monotonic() - t0 < 300:
        time.sleep(0.002)
    assert killed.poll() is None, "the run ended before its first checkpoint was seen"
    killed.send_signal(signal.SIGKILL)
    killed.wait()
    assert killed.returncode == -signal.SIGKILL
    k = json.loads(progress.read_text())["checkpoint"]
    assert k >= 1 and not (folder / "summary.json").exists()
    print(f"killed after checkpoint {k}")
    _looks_whole(folder)

    resumed = _cli("run", "--resume", str(folder))
    out, err = resumed.communicate(timeout=600)
    assert resumed.returncode == 0, err.decode()
    assert b"resuming from checkpoint" in out
    assert whole.wait(timeout=600) == 0, whole.stderr.read().decode()
    p_ref = _pressure(tmp_path / "whole" / "tube-on-cylinder")
    p = _pressure(folder)
    assert np.abs(p - p_ref).max() <= 1e-10 * np.abs(p_ref).max()
    a = json.loads((folder / "summary.json").read_text())
    b = json.loads((tmp_path / "whole" / "tube-on-cylinder" / "summary.json").read_text())
    assert a["dressing"]["newton_iterations"] == b["dressing"]["newton_iterations"]
    assert a["regions"] == b["regions"]
    _looks_whole(folder)
