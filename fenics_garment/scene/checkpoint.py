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
uninterrupted run. A different scene or number of ranks is refused with :class:`ResumeError`,
and so is a damaged checkpoint (truncated or missing rank files, unknown keys, values of the
wrong type or shape): reading and restoring are collective, so every rank raises the same error.
A checkpoint that cannot be written (full disk, read-only folder) raises
:class:`~fenics_garment.output.OutputError` on every rank, leaving the previous one intact.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import zipfile
from dataclasses import replace
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
    """SHA-256 of the scene with every default filled in, the output folder excluded (a run
    folder may be moved); the error-bar switch is included (it changes what the run does)."""
    plain = replace(scene, output=replace(scene.output, folder=""))
    text = config.dumps(plain).split("\n", 1)[1]  # without the comment naming the source file
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _arrays(built) -> dict[str, np.ndarray]:
    st = built.contact.state
    arrays = {
        "q": built.model.q.x.array,
        "q_prev": built.regularisation.q_prev.x.array,
        "lam": st.lam.x.array,
        "u_old": st.u_old.x.array,
    }
    return arrays | st.search_memory()


def exists(run_folder: Path) -> bool:
    """Whether ``run_folder`` has a checkpoint to resume from (its ``progress.json``)."""
    return (Path(run_folder) / FOLDER / "progress.json").is_file()


def _rank_file(folder: Path, k: int, rank: int) -> Path:
    return folder / f"state-{k}.r{rank}.npz"


class Writer:
    """Writes the checkpoints of one run (collective: every rank calls :meth:`write`)."""

    def __init__(self, run_folder: Path, scene: config.Scene, comm: MPI.Comm, start: int = 0):
        self.folder = Path(run_folder) / FOLDER
        self.scene_id = fingerprint(scene)
        self.error_bars = scene.output.error_bars
        self.comm = comm
        self.k = start
        self.seconds = 0.0
        output.guarded(comm, lambda: self.folder.mkdir(parents=True, exist_ok=True))

    def write(self, built, progress: Progress) -> None:
        import time

        t0 = time.perf_counter()
        comm, k = self.comm, self.k + 1
        path = _rank_file(self.folder, k, comm.rank)

        def save(tmp: Path) -> None:
            buf = io.BytesIO()
            np.savez(buf, **_arrays(built))
            tmp.write_bytes(buf.getvalue())

        try:
            output.guarded(comm, lambda: output.atomic_write(path, save), root_only=False)
            meta = {"format": FORMAT, "checkpoint": k, "ranks": comm.size,
                    "scene": self.scene_id, "error_bars": self.error_bars,
                    "progress": progress.as_dict()}  # fmt: skip
            text = json.dumps(meta, indent=1)
            output.guarded(comm, lambda: output.write_text(self.folder / "progress.json", text))
        except output.OutputError:
            path.unlink(missing_ok=True)  # checkpoint k − 1 stays the valid one
            raise
        old = _rank_file(self.folder, k - 1, comm.rank)
        output.guarded(comm, lambda: old.unlink(missing_ok=True), root_only=False)
        self.k = k
        self.seconds += time.perf_counter() - t0


#: progress.json: key -> type.
_META = {"format": int, "checkpoint": int, "ranks": int, "scene": str, "progress": dict}


def _read_meta(run_folder: Path) -> dict:
    """progress.json, checked (rank 0); raises ResumeError."""
    path = Path(run_folder) / FOLDER / "progress.json"
    if not path.exists():
        raise ResumeError(
            f"{run_folder}: no checkpoint to resume from ({path} is missing); "
            "run the scene from the start"
        )
    damaged = f"{path}: damaged or not a checkpoint of this version"
    again = "; run the scene from the start (or remove the folder)"
    try:
        meta = json.loads(path.read_text())
    except (OSError, ValueError) as err:
        raise ResumeError(f"{damaged} ({type(err).__name__}: {err}){again}") from None
    if not isinstance(meta, dict):
        raise ResumeError(f"{damaged} (not a JSON object){again}")
    for key, kind in _META.items():
        if not isinstance(meta.get(key), kind) or isinstance(meta.get(key), bool):
            raise ResumeError(f"{damaged} ({key!r} missing or not {kind.__name__}){again}")
    if meta["format"] != FORMAT or meta["checkpoint"] < 1 or meta["ranks"] < 1:
        raise ResumeError(f"{damaged} (format {meta['format']}, checkpoint "
                          f"{meta['checkpoint']}, ranks {meta['ranks']}){again}")  # fmt: skip
    try:
        progress = Progress.from_dict(meta["progress"])
        bad = _wrong_fields(progress) or _wrong_fields(progress.report)
        bad = bad or next((b for st in progress.report.steps if (b := _wrong_fields(st))), "")
    except (TypeError, KeyError, ValueError, AttributeError) as err:
        raise ResumeError(f"{damaged} (its progress: {type(err).__name__} {err}){again}") from None
    if bad or progress.stage not in STAGES:
        raise ResumeError(f"{damaged} (progress {bad or 'stage ' + repr(progress.stage)}){again}")
    return meta


STAGES = ("grow", "release", "done")
_SCALARS = {"float": (int, float), "int": (int,), "str": (str,), "bool": (bool,)}


def _wrong_fields(obj) -> str:
    """The first field of a dataclass whose value does not have its annotated scalar type, or
    is not a list where a list is annotated; "" if none."""
    from dataclasses import fields

    for f in fields(obj):
        v, kind = getattr(obj, f.name), str(f.type)
        if kind in _SCALARS:
            ok = isinstance(v, _SCALARS[kind]) and (kind == "bool" or not isinstance(v, bool))
            ok = ok and (kind != "float" or math.isfinite(v) or math.isnan(v))
        else:
            ok = not kind.startswith("list") or isinstance(v, list)
        if not ok:
            return f"{f.name} = {v!r} (not {kind})"
    return ""


def _collective(comm: MPI.Comm, work):
    """``work()`` on rank 0, its result or its ResumeError on every rank."""
    result, message = None, None
    if comm.rank == 0:
        try:
            result = work()
        except ResumeError as err:
            message = str(err)
    result, message = comm.bcast((result, message), root=0)
    if message:
        raise ResumeError(message)
    return result


def read(run_folder: Path, scene: config.Scene, comm: MPI.Comm) -> dict:
    """The checkpoint's metadata, checked against ``scene`` and the number of ranks
    (collective)."""
    meta = _collective(comm, lambda: _read_meta(run_folder))
    if meta["ranks"] != comm.size:
        raise ResumeError(
            f"{run_folder}: the checkpoint was written by {meta['ranks']} MPI rank(s), this run "
            f"has {comm.size}; resume with `mpiexec -n {meta['ranks']} fenics-garment run "
            "--resume ...` (the mesh partition must be the same)"
        )
    if meta["scene"] != fingerprint(scene):
        bars = meta.get("error_bars")
        hint = (
            " (the run was made with --error-bars: resume it with --error-bars, or "
            "without a scene file)"
            if bars is True and not scene.output.error_bars
            else ""
        )
        raise ResumeError(
            f"{run_folder}: the checkpoint belongs to another scene than the one given (the "
            "scene file changed since?); resume with the folder's own scene_used.toml, or run "
            f"the new scene from the start{hint}"
        )  # fmt: skip
    return meta


def _load_rank_file(path: Path, targets: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The arrays of one rank file, checked against the rebuilt scene's; raises ResumeError."""
    again = "; run the scene from the start"
    try:
        with np.load(path, allow_pickle=False) as data:
            saved = {k: data[k] for k in data.files}
    except FileNotFoundError:
        raise ResumeError(f"{path}: missing (the checkpoint is incomplete){again}") from None
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError) as err:
        raise ResumeError(f"{path}: damaged ({type(err).__name__}: {err}){again}") from None
    for name, target in targets.items():
        if name in ("x0", "d0", "n0"):
            continue
        if name not in saved:
            raise ResumeError(f"{path}: has no {name!r} array{again}")
        a = saved[name]
        if a.shape != target.shape or a.dtype.kind not in "fi":
            raise ResumeError(f"{path}: {name} has {a.shape} {a.dtype} values, the rebuilt "
                              f"scene {target.shape}{again}")  # fmt: skip
        if not np.all(np.isfinite(a)):
            raise ResumeError(f"{path}: {name} holds NaN/Inf values{again}")
    if any(k in saved for k in ("x0", "d0", "n0")):
        if not all(k in saved for k in ("x0", "d0", "n0")):
            raise ResumeError(f"{path}: the search arrays x0, d0, n0 are incomplete{again}")
    return saved


def restore(built, run_folder: Path, meta: dict) -> Progress:
    """Put the arrays of checkpoint ``meta`` back into ``built``; returns the progress
    (collective: a damaged file on any rank is a ResumeError on every rank)."""
    comm = built.model.geometry.mesh.comm
    path = _rank_file(Path(run_folder) / FOLDER, meta["checkpoint"], comm.rank)
    targets = _arrays(built)
    saved, message = None, None
    try:
        saved = _load_rank_file(path, targets)
    except ResumeError as err:
        message = str(err)
    message = next((m for m in comm.allgather(message) if m), None)
    if message:
        raise ResumeError(message)
    for name, target in targets.items():
        if name not in ("x0", "d0", "n0"):
            target[:] = saved[name]
    if "x0" in saved:
        built.contact.state.restore_search_memory({k: saved[k] for k in ("x0", "d0", "n0")})
    return Progress.from_dict(meta["progress"])
