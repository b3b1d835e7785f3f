"""Checkpoints of a dressing, one per converged solve, so that a killed run can be resumed.

A checkpoint lives in ``<run folder>/checkpoint/``:

* ``state-<k>.r<rank>.npz`` — each rank's owned-and-ghost values of everything that carries
  history: the shell unknowns ``q``, the regularisation's ``q_prev``, the contact state's
  multipliers ``lam`` (augmented Lagrangian), ``u_old`` (friction: the position of the last
  converged step) and ``gap_old`` (the gap there: the contact laws' gap rate, and which points
  are transiently deep), and the broad phase's last exact search (``x0``, ``d0``, ``n0``);
* ``progress.json`` — the number ``k`` of the latest complete checkpoint, the ranks, a
  fingerprint of the scene, what the state depends on besides it (:func:`depends`: package
  version, terms hooks' sources, input files, meshes), the SHA-256 of every rank file and the
  dressing's :class:`~fenics_garment.scene.dressing.Progress` (stage, shrink, step, spring
  constant, the report so far); sealed by a SHA-256 of all that (:func:`seal`).

Every file is written to a temporary name and renamed (``output.atomic_write``); the rank files
of checkpoint ``k`` are all in place before ``progress.json`` names ``k``, and those of ``k − 1``
are removed after. A run killed at any moment therefore leaves a complete checkpoint or none.
Resuming re-builds the scene (deterministic: same meshes, same partition on the same number of
ranks), puts the arrays back and replays the remaining steps, so the answer is the one of the
uninterrupted run. A different scene or number of ranks is refused with :class:`ResumeError`,
and so is a damaged checkpoint (truncated or missing rank files, unknown keys, values of the
wrong type or shape), one that lies (values of the right type that no dressing has,
:func:`meaning`; a file changed after it was written: the seal or a digest does not match) and
one whose dependencies changed (:func:`check_depends`, one line naming what): reading and
restoring are collective, so every rank raises the same error.
A checkpoint that cannot be written (full disk, read-only folder) raises
:class:`~fenics_garment.output.OutputError` on every rank, leaving the previous one intact.
"""

from __future__ import annotations

import hashlib
import inspect
import io
import itertools
import json
import math
import zipfile
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from fenics_garment import __version__, bounded, output
from fenics_garment._stack import MPI
from fenics_garment.bounded import shown
from fenics_garment.scene import config
from fenics_garment.scene.dressing import Progress

FORMAT = 2
FOLDER = "checkpoint"


class ResumeError(ValueError):
    """A run cannot be resumed from its folder (no checkpoint, other scene, other ranks)."""


def fingerprint(scene: config.Scene) -> str:
    """SHA-256 of the scene with every default filled in, the output folder excluded (a run
    folder may be moved); the error-bar switch is included (it changes what the run does)."""
    plain = replace(scene, output=replace(scene.output, folder=""))
    text = config.dumps(plain).split("\n", 1)[1]  # without the comment naming the source file
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _digest_file(path: Path) -> str:
    h = hashlib.sha256()
    try:
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
    except OSError as err:
        return f"unreadable ({err.strerror})"
    return h.hexdigest()[:16]


def _hook_source(hook: Callable) -> str:
    """The file that defines ``hook`` (its module's source), or its qualified name."""
    try:
        return inspect.getsourcefile(inspect.unwrap(hook)) or ""
    except TypeError:
        return ""


def depends(scene: config.Scene, hooks: Sequence[Callable]) -> dict[str, str]:
    """What a checkpoint's state depends on besides the scene's values (which
    :func:`fingerprint` covers): the package version, the source of every terms hook and the
    files the scene reads (scan, pattern), by digest. :func:`check_depends` compares them on
    resume; the meshes are compared after the build (:func:`mesh_digest`)."""
    found = {"fenics-garment version": __version__}
    for hook in hooks:
        source = _hook_source(hook)
        name = f"terms hook {getattr(hook, '__qualname__', hook)!s} ({source or 'no source'})"
        found[name] = _digest_file(Path(source)) if source else "no source file"
    files = [scene.body.file if scene.body.kind == "scan" else "",
             scene.garment.pattern if scene.garment.kind == "pattern" else ""]  # fmt: skip
    for name in filter(None, files):
        found[f"file {name}"] = _digest_file(config.scene_file(scene, name))
    return found


def check_depends(
    meta: dict, now: dict[str, str], run_folder: Path, later: Sequence[str] = ()
) -> None:
    """ResumeError naming the first dependency that changed since the checkpoint (``later``:
    keys not known yet, compared by a later call)."""
    then = meta.get("depends") or {}
    for key in sorted((set(then) | set(now)) - set(later)):
        if then.get(key) != now.get(key):
            what = ("is new" if key not in then else "is gone" if key not in now
                    else f"changed ({then[key]} then, {now[key]} now)")  # fmt: skip
            raise ResumeError(f"{run_folder}: the checkpoint cannot be continued: "
                              f"{bounded.cut(key, 200)} {what} since it was written; run the "
                              "scene from the start")  # fmt: skip


def mesh_digest(built) -> str:
    """SHA-256 of the body and garment meshes as built (rank 0's, on every rank): another gmsh
    or a changed mesher would make other meshes from the same scene."""
    comm = built.model.geometry.mesh.comm
    digest = None
    if comm.rank == 0:
        h = hashlib.sha256()
        g, b = built.garment, built.body
        for a in (g.points, g.cells, b.vertices, b.triangles):
            h.update(np.ascontiguousarray(a).tobytes())
        digest = h.hexdigest()[:16]
    return comm.bcast(digest, root=0)


#: Arrays a checkpoint written before they were added lacks (zero then).
OPTIONAL = ("gap_old",)


def _arrays(built) -> dict[str, np.ndarray]:
    st = built.contact.state
    arrays = {
        "q": built.model.q.x.array,
        "q_prev": built.regularisation.q_prev.x.array,
        "lam": st.lam.x.array,
        "u_old": st.u_old.x.array,
        "gap_old": st.gap_old.x.array,  # the laws' gap rate (a checkpoint without it: zero)
    }
    return arrays | st.search_memory()


def exists(run_folder: Path) -> bool:
    """Whether ``run_folder`` has a checkpoint to resume from (its ``progress.json``)."""
    return (Path(run_folder) / FOLDER / "progress.json").is_file()


def _rank_file(folder: Path, k: int, rank: int) -> Path:
    return folder / f"state-{k}.r{rank}.npz"


class Writer:
    """Writes the checkpoints of one run (collective: every rank calls :meth:`write`)."""

    def __init__(self, run_folder: Path, scene: config.Scene, comm: MPI.Comm, start: int = 0,
                 depends: dict | None = None):  # fmt: skip
        self.folder = Path(run_folder) / FOLDER
        self.scene_id = fingerprint(scene)
        self.depends = depends or {}
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

        buf = io.BytesIO()
        np.savez(buf, **_arrays(built))
        data = buf.getvalue()
        try:
            output.guarded(comm, lambda: output.atomic_write(path, lambda t: t.write_bytes(data)),
                           root_only=False)  # fmt: skip
            files = comm.allgather(hashlib.sha256(data).hexdigest())
            meta = {"format": FORMAT, "checkpoint": k, "ranks": comm.size,
                    "scene": self.scene_id, "error_bars": self.error_bars,
                    "depends": self.depends, "files": files,
                    "progress": progress.as_dict()}  # fmt: skip
            meta["seal"] = seal(meta)
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
        meta = json.loads(bounded.read_bytes(path, bounded.MAX_PROGRESS_BYTES, "checkpoint"))
        bounded.check_depth(meta, str(path))
    except (OSError, ValueError) as err:
        why = bounded.cut(f"{type(err).__name__}: {err}", 200)
        raise ResumeError(f"{damaged} ({why}){again}") from None
    except RecursionError:
        raise ResumeError(f"{damaged} (nested deeper than {bounded.MAX_DEPTH} levels)"
                          f"{again}") from None  # fmt: skip
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
        why = bounded.cut(f"{type(err).__name__} {err}", 200)
        raise ResumeError(f"{damaged} (its progress: {why}){again}") from None
    if bad or progress.stage not in STAGES:
        stage = "stage " + shown(progress.stage)
        raise ResumeError(f"{damaged} (progress {bad or stage}){again}")
    if wrong := meaning(progress):
        raise ResumeError(f"{path}: its progress contradicts itself: {wrong}{again}")
    if meta.get("seal") != seal(meta):
        raise ResumeError(f"{path}: changed after it was written (its seal does not match its "
                          f"content){again}")  # fmt: skip
    return meta


STAGES = ("grow", "sew", "release", "done")
STEP_STAGES = ("sew", "dress", "release")
_SCALARS = {"float": (int, float), "int": (int,), "str": (str,), "bool": (bool,)}


def _rules(p: Progress) -> list[tuple[bool, str]]:
    """(holds, what it says) for every rule a dressing's progress obeys (``dressing.dress``)."""
    r = p.report
    dress = [st.shrink for st in r.steps if st.stage == "dress"]
    sew = [st.shrink for st in r.steps if st.stage == "sew"]
    release = [st.regularisation for st in r.steps if st.stage == "release"]
    grown = p.stage != "grow"
    return [
        (r.shrink0 >= 0, f"the initial shrink {r.shrink0:g} m is negative"),
        (0 <= p.shrink <= r.shrink0, f"shrink {p.shrink:g} m is outside [0, the initial shrink "
         f"{r.shrink0:g} m]"),
        (not grown or p.shrink == 0, f"stage {p.stage!r} with the body still shrunk by "
         f"{p.shrink:g} m (it is reached at shrink 0)"),
        (grown or p.shrink == 0 or p.step > 0, f"step {p.step:g} m is not positive"),
        (not dress or dress[-1] == p.shrink, f"shrink {p.shrink:g} m is not that of the last "
         f"solve ({dress[-1] if dress else 0:g} m)"),
        (all(a >= b for a, b in itertools.pairwise(dress)),
         "the shrink of the solves does not decrease"),
        (all(0 <= s <= r.shrink0 for s in dress), "a solve's shrink is outside [0, s0]"),
        (all(0 <= w <= 1 for w in [*sew, p.sewn, p.sew_step]), "a sewing value is outside [0, 1]"),
        (all(a <= b for a, b in itertools.pairwise(sew)), "the sewing goes backwards"),
        (all(a >= b for a, b in itertools.pairwise(release)),
         "the spring constant of the release solves grows"),
        (p.c >= 0 and p.spring >= 0 and p.kappa >= 0 and p.mu >= 0,
         f"a negative value (spring constant {p.c:g}, spring force {p.spring:g}, penalty "
         f"{p.kappa:g}, friction coefficient {p.mu:g})"),
        (p.c_target == -1 or p.c_target >= 0, f"c_target {p.c_target:g}"),
        (p.retries >= 0 and 0 <= p.solves <= len(r.steps), f"{p.retries} retries, {p.solves} "
         f"release solves of {len(r.steps)} solves"),
        ((p.stage == "done") == r.completed, f"stage {p.stage!r} with completed = {r.completed}"),
        (all(st.stage in STEP_STAGES for st in r.steps), "a solve of an unknown stage"),
        (all(st.iterations >= 0 and st.cuts >= 0 and st.seconds >= 0 and st.regularisation >= 0
             for st in r.steps), "a solve with a negative count, time or spring constant"),
    ]  # fmt: skip


def meaning(progress: Progress) -> str:
    """The first rule of :func:`_rules` that ``progress`` breaks, "" if none: values of the
    right type that no dressing can have (a stage the shrink has not reached, a negative step
    or spring constant, a schedule that goes backwards) are refused as damage is."""
    return next((what for ok, what in _rules(progress) if not ok), "")


def seal(meta: dict) -> str:
    """SHA-256 of everything in ``meta`` but its seal: a progress file edited after it was
    written (by hand, by another tool) no longer matches."""
    plain = {k: v for k, v in meta.items() if k != "seal"}
    return hashlib.sha256(json.dumps(plain, sort_keys=True).encode()).hexdigest()


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


def _load_rank_file(
    path: Path, targets: dict[str, np.ndarray], digest: str
) -> dict[str, np.ndarray]:
    """The arrays of one rank file, checked against the rebuilt scene's and against its digest
    in progress.json; raises ResumeError."""
    again = "; run the scene from the start"
    try:
        raw = path.read_bytes()
        with np.load(io.BytesIO(raw), allow_pickle=False) as data:
            saved = {k: data[k] for k in data.files}
    except FileNotFoundError:
        raise ResumeError(f"{path}: missing (the checkpoint is incomplete){again}") from None
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError) as err:
        raise ResumeError(f"{path}: damaged ({type(err).__name__}: {err}){again}") from None
    for name, target in targets.items():
        if name in ("x0", "d0", "n0"):
            continue
        if name not in saved and name in OPTIONAL:
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
    if hashlib.sha256(raw).hexdigest() != digest:
        raise ResumeError(f"{path}: changed after it was written (its digest is not the one "
                          f"progress.json records){again}")  # fmt: skip
    return saved


def restore(built, run_folder: Path, meta: dict) -> Progress:
    """Put the arrays of checkpoint ``meta`` back into ``built``; returns the progress
    (collective: a damaged file on any rank is a ResumeError on every rank)."""
    comm = built.model.geometry.mesh.comm
    progress = Progress.from_dict(meta["progress"])
    if wrong := _against_scene(progress, built):
        raise ResumeError(f"{run_folder}: the checkpoint's progress does not fit the rebuilt "
                          f"scene: {wrong}; run the scene from the start")  # fmt: skip
    path = _rank_file(Path(run_folder) / FOLDER, meta["checkpoint"], comm.rank)
    targets = _arrays(built)
    saved, message = None, None
    files = meta.get("files")
    digest = files[comm.rank] if isinstance(files, list) and len(files) == comm.size else ""
    try:
        saved = _load_rank_file(path, targets, str(digest))
    except ResumeError as err:
        message = str(err)
    message = next((m for m in comm.allgather(message) if m), None)
    if message:
        raise ResumeError(message)
    for name, target in targets.items():
        if name not in ("x0", "d0", "n0"):
            target[:] = saved[name] if name in saved else 0.0  # (OPTIONAL arrays)
    if "x0" in saved:
        built.contact.state.restore_search_memory({k: saved[k] for k in ("x0", "d0", "n0")})
    return progress


def _against_scene(p: Progress, built) -> str:
    """What in ``p`` contradicts the rebuilt problem (its friction coefficient; an initial
    shrink below the scene's margin), "" if nothing (the same on every rank)."""
    mu = float(built.mu.value) if built.mu is not None else 0.0
    if abs(p.mu - mu) > 1e-12 * max(1.0, abs(mu)):
        return f"friction coefficient {p.mu:g}, the scene's {mu:g}"
    margin = built.scene.dressing.margin
    if any(st.stage == "dress" for st in p.report.steps) and p.report.shrink0 < margin:
        return f"initial shrink {p.report.shrink0:g} m below the scene's margin {margin:g} m"
    return ""
