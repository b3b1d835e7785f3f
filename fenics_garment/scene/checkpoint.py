"""Checkpoints of a dressing, one per converged solve, so that a killed run can be resumed.

A checkpoint lives in ``<run folder>/checkpoint/``:

* ``state-<k>.r<rank>.npz`` — each rank's owned-and-ghost values of everything that carries
  history: the shell unknowns ``q``, the regularisation's ``q_prev``, the contact state's
  multipliers ``lam`` (augmented Lagrangian) and ``u_old`` (friction: the position of the last
  converged step), and the broad phase's last exact search (``x0``, ``d0``, ``n0``);
* ``progress.json`` — the number ``k`` of the latest complete checkpoint, the ranks, a
  fingerprint of the scene and the dressing's :class:`~fenics_garment.scene.dressing.Progress`
  (stage, shrink, step, spring constant, the report so far).

Every file is written to a temporary name and renamed (``output.atomic_write``); the rank files
of checkpoint ``k`` are all in place before ``progress.json`` names ``k``, and those of ``k − 1``
are removed after. A run killed at any moment therefore leaves a complete checkpoint or none.
Resuming re-builds the scene (deterministic: same meshes, same partition on the same number of
ranks), puts the arrays back and replays the remaining steps, so the answer is the one of the
uninterrupted run. A different scene or number of ranks is refused with :class:`ResumeError`.
"""

from __future__ import annotations

import hashlib
import io
import json
from pathlib import Path

import numpy as np

from fenics_garment import output
from fenics_garment._stack import MPI
from fenics_garment.scene import config
from fenics_garment.scene.dressing import Progress

FORMAT = 1
FOLDER = "checkpoint"


class ResumeError(ValueError):
    """A run cannot be resumed from its folder (no checkpoint, other scene, other ranks)."""


def fingerprint(scene: config.Scene) -> str:
    """SHA-256 of the scene with every default filled in (the output folder excluded)."""
    text = config.dumps(scene).split("\n", 1)[1]  # without the comment naming the source file
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _arrays(built) -> dict[str, np.ndarray]:
    st = built.contact.state
    arrays = {
        "q": built.model.q.x.array,
        "q_prev": built.regularisation.q_prev.x.array,
        "lam": st.lam.x.array,
        "u_old": st.u_old.x.array,
    }
    bp = st._broad
    if bp._x0 is not None:
        arrays |= {"x0": bp._x0, "d0": bp._d0, "n0": bp._n0}
    return arrays


def _rank_file(folder: Path, k: int, rank: int) -> Path:
    return folder / f"state-{k}.r{rank}.npz"


class Writer:
    """Writes the checkpoints of one run (collective: every rank calls :meth:`write`)."""

    def __init__(self, run_folder: Path, scene: config.Scene, comm: MPI.Comm, start: int = 0):
        self.folder = Path(run_folder) / FOLDER
        self.scene_id = fingerprint(scene)
        self.comm = comm
        self.k = start
        self.seconds = 0.0
        if comm.rank == 0:
            self.folder.mkdir(parents=True, exist_ok=True)
        comm.Barrier()

    def write(self, built, progress: Progress) -> None:
        import time

        t0 = time.perf_counter()
        comm, k = self.comm, self.k + 1
        path = _rank_file(self.folder, k, comm.rank)

        def save(tmp: Path) -> None:
            buf = io.BytesIO()
            np.savez(buf, **_arrays(built))
            tmp.write_bytes(buf.getvalue())

        output.atomic_write(path, save)
        comm.Barrier()
        if comm.rank == 0:
            meta = {"format": FORMAT, "checkpoint": k, "ranks": comm.size,
                    "scene": self.scene_id, "progress": progress.as_dict()}  # fmt: skip
            output.write_text(self.folder / "progress.json", json.dumps(meta, indent=1))
        comm.Barrier()
        old = _rank_file(self.folder, k - 1, comm.rank)
        if old.exists():
            old.unlink()
        self.k = k
        self.seconds += time.perf_counter() - t0


def read(run_folder: Path, scene: config.Scene, comm: MPI.Comm) -> dict:
    """The checkpoint's metadata, checked against ``scene`` and the number of ranks."""
    path = Path(run_folder) / FOLDER / "progress.json"
    if not path.exists():
        raise ResumeError(
            f"{run_folder}: no checkpoint to resume from ({path} is missing); "
            "run the scene from the start"
        )
    try:
        meta = json.loads(path.read_text())
        assert meta["format"] == FORMAT
    except (ValueError, KeyError, AssertionError) as err:
        raise ResumeError(f"{path}: not a checkpoint of this version ({err})") from None
    if meta["ranks"] != comm.size:
        raise ResumeError(
            f"{run_folder}: the checkpoint was written by {meta['ranks']} MPI rank(s), this run "
            f"has {comm.size}; resume with `mpiexec -n {meta['ranks']} fenics-garment run "
            "--resume ...` (the mesh partition must be the same)"
        )
    if meta["scene"] != fingerprint(scene):
        raise ResumeError(
            f"{run_folder}: the checkpoint belongs to another scene than the one given (the "
            "scene file changed since?); resume with the folder's own scene_used.toml, or run "
            "the new scene from the start"
        )
    return meta


def restore(built, run_folder: Path, meta: dict) -> Progress:
    """Put the arrays of checkpoint ``meta`` back into ``built``; returns the progress."""
    comm = built.model.geometry.mesh.comm
    path = _rank_file(Path(run_folder) / FOLDER, meta["checkpoint"], comm.rank)
    with np.load(path) as data:
        saved = {k: data[k] for k in data.files}
    for name, target in _arrays(built).items():
        if name in ("x0", "d0", "n0"):
            continue
        if saved[name].shape != target.shape:
            raise ResumeError(f"{path}: {name} has {saved[name].shape} values, the rebuilt "
                              f"scene {target.shape}; run the scene from the start")  # fmt: skip
        target[:] = saved[name]
    bp = built.contact.state._broad
    if "x0" in saved:
        bp._x0, bp._d0, bp._n0 = saved["x0"].copy(), saved["d0"].copy(), saved["n0"].copy()
    return Progress.from_dict(meta["progress"])
