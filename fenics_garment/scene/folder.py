"""The state of a run folder: one writer at a time, no stale outputs, a completed marker.

* ``.lock`` — made with ``O_EXCL`` by the run writing the folder (its host, pid and run id). A
  second run into the same folder is refused (:class:`FolderBusy`) while the first lives; a lock
  left by a killed run (same host, process gone) is taken over.
* A fresh run (not ``--resume``) first removes the outputs an earlier run left (only the files
  and folders this package writes), so a killed re-run cannot leave its new ``scene_used.toml``
  beside an old, complete-looking ``summary.json``.
* ``run.json`` — ``run_id`` (also in ``summary.json``), ``status`` (``running``, then
  ``completed``, ``checks failed``, ``stopped`` or ``failed``), start and end time, ranks, and for
  a resumed run the id it continued. ``status = completed`` is written last, after every output:
  it is the completed marker.

Only rank 0 touches the files; the answers are broadcast (every rank raises the same error).
"""

from __future__ import annotations

import json
import os
import shutil
import socket
import time
import uuid
from pathlib import Path

from fenics_garment import output
from fenics_garment._stack import MPI
from fenics_garment.jit_wait import pid_alive
from fenics_garment.scene.preflight import PreflightError

STATE = "run.json"
LOCK = ".lock"
#: What a run writes into its folder (a fresh run removes these, nothing else).
OUTPUT_FILES = ("summary.json", "pressure_regions.csv", "pressure_sensors.csv",
                "final_state.xdmf", "body_pressure.vtu", "pressure_garment.png",
                "pressure_body.png", "scene_used.toml", "report.html",
                "report_surfaces.npz", "drape.png", STATE)  # fmt: skip
OUTPUT_DIRS = ("dressing.bp", "drape.bp", "checkpoint")
NESTED = "coarse_level"  # the error bars' coarse run, a run folder of its own


class FolderBusy(PreflightError):
    """Another live run is writing the folder."""


def _holder(lock: Path) -> dict:
    try:
        return json.loads(lock.read_text())
    except (OSError, ValueError):
        return {}


def _take(lock: Path, me: dict) -> str | None:
    """Make the lock file; None, or why not (a live holder)."""
    for _ in range(2):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            held = _holder(lock)
            pid, host = held.get("pid"), held.get("host")
            if held and host == me["host"] and pid == me["pid"]:
                return None  # this process holds it (the error bars' fine level): nested

            if held and host == me["host"] and isinstance(pid, int) and not pid_alive(pid):
                lock.unlink(missing_ok=True)  # left by a killed run
                continue
            if not held and time.time() - lock.stat().st_mtime > 60:
                lock.unlink(missing_ok=True)  # empty and old: its writer died before writing
                continue
            who = f"pid {pid} on {host}" if held else "an unknown process"
            return (f"another run ({who}, run id {held.get('run_id', '?')}) is writing "
                    f"{lock.parent}; wait for it to end or choose another -o/--output (if that "
                    f"run is dead, remove {lock})")  # fmt: skip
        with os.fdopen(fd, "w") as f:
            f.write(json.dumps(me))
        return None
    return f"cannot take the lock {lock}"


def _clear(folder: Path) -> None:
    for name in OUTPUT_FILES:
        (folder / name).unlink(missing_ok=True)
    for name in OUTPUT_DIRS:
        if (folder / name).is_dir():
            shutil.rmtree(folder / name)
    nested = folder / NESTED
    if nested.is_dir():
        for sub in nested.iterdir():
            if sub.is_dir() and ((sub / STATE).exists() or (sub / "scene_used.toml").exists()):
                _clear(sub)
                if not any(sub.iterdir()):
                    sub.rmdir()
        if not any(nested.iterdir()):
            nested.rmdir()
    for stray in folder.glob(".*.part*"):  # temporary files of a killed writer
        if stray.is_dir():
            shutil.rmtree(stray)
        else:
            stray.unlink(missing_ok=True)


class RunFolder:
    """The lock and the state file of one run's folder (collective: every rank calls)."""

    def __init__(self, path: Path, comm: MPI.Comm):
        self.path, self.comm = Path(path), comm
        self.run_id = comm.bcast(uuid.uuid4().hex[:12] if comm.rank == 0 else None, root=0)
        self.state: dict = {}
        self._locked = False

    def _collective(self, work) -> None:
        """Run ``work()`` on rank 0; its error message (if any) is raised on every rank."""
        message, busy = None, False
        if self.comm.rank == 0:
            try:
                message = work()
                busy = message is not None
            except OSError as err:
                message = f"cannot write the run folder {self.path}: {err.strerror or err}"
        message, busy = self.comm.bcast((message, busy), root=0)
        if message:
            raise (FolderBusy if busy else PreflightError)(message)

    def acquire(self) -> None:
        me = {"pid": os.getpid(), "host": socket.gethostname(), "run_id": self.run_id,
              "started": time.strftime("%Y-%m-%dT%H:%M:%S%z")}  # fmt: skip
        self._collective(lambda: _take(self.path / LOCK, me))
        self._locked = True

    def release(self) -> None:
        if self._locked and self.comm.rank == 0:
            lock = self.path / LOCK
            if _holder(lock).get("run_id") == self.run_id:
                lock.unlink(missing_ok=True)
        self._locked = False

    def start(self, *, fresh: bool, clear: bool = True) -> None:
        """Clear an earlier run's outputs (``fresh`` and ``clear``) and mark the folder running."""
        previous = self.read_state().get("run_id") if not fresh else None

        def work() -> None:
            if fresh and clear:
                _clear(self.path)
            self.state = {"run_id": self.run_id, "status": "running", "ranks": self.comm.size,
                          "started": time.strftime("%Y-%m-%dT%H:%M:%S%z")}  # fmt: skip
            if previous:
                self.state["resumed_from"] = previous
            self._write()

        self._collective(work)

    def finish(self, status: str, *, collective: bool = True, **detail: str) -> None:
        """Write the final ``status`` (and ``detail``: what failed, the signal and stage of an
        interruption). ``collective=False`` (on an error path, where the other ranks may be
        anywhere): rank 0 only, best effort, never raises."""

        def work() -> None:
            self.state.update(status=status, finished=time.strftime("%Y-%m-%dT%H:%M:%S%z"),
                              **detail)  # fmt: skip
            self._write()

        if collective:
            self._collective(work)
        elif self.comm.rank == 0 and self.state:
            try:
                work()
            except OSError:
                pass

    def read_state(self) -> dict:
        text = None
        if self.comm.rank == 0:
            try:
                text = (self.path / STATE).read_text()
            except OSError:
                text = None
        text = self.comm.bcast(text, root=0)
        try:
            state = json.loads(text) if text else {}
        except ValueError:
            state = {}
        return state if isinstance(state, dict) else {}

    def _write(self) -> None:
        write_state(self.path / STATE, self.state)

    def mark_failed(self, error: str) -> None:
        """``run.json`` says ``failed`` with ``error``, written from any rank (best effort): for
        a rank that stops the job alone (``mpi_guard.abort``), where rank 0 cannot write it."""
        self._mark(status="failed", error=error)

    def mark_interrupted(self, signum: int, stage: str) -> None:
        """``run.json`` says ``interrupted`` (a second signal stops the process at once)."""
        from fenics_garment.interrupt import signal_name

        self._mark(status="interrupted", signal=signal_name(signum), stage=stage)

    def _mark(self, **detail: str) -> None:
        try:
            state = json.loads((self.path / STATE).read_text())
            state.update(finished=time.strftime("%Y-%m-%dT%H:%M:%S%z"), **detail)
            write_state(self.path / STATE, state)
        except (OSError, ValueError, AttributeError):
            pass


#: Bytes of ``run.json``: its text padded with blanks (valid JSON), so that the final status
#: can be written in place when the disk is full.
STATE_BYTES = 4096


def write_state(path: Path, state: dict) -> None:
    """``run.json`` padded to :data:`STATE_BYTES`, written to a temporary name and renamed; on
    a full disk (no room for the new file) overwritten in place, within the bytes it has."""
    text = json.dumps(state, indent=1) + "\n"
    try:
        output.write_text(path, text.ljust(STATE_BYTES))
    except OSError:
        data = text.encode()
        with open(path, "r+b") as f:
            size = os.fstat(f.fileno()).st_size
            if len(data) > size:
                raise
            f.write(data.ljust(size))


def inside(root: Path, name: str) -> Path:
    """``root/name``, refused (PreflightError) when it is not a folder directly in ``root``."""
    folder = Path(root) / name
    if folder.resolve().parent != Path(root).resolve():
        raise PreflightError(f"the scene name {name!r} would put the run folder outside "
                             f"{root} ({folder.resolve()}); use a plain file name")  # fmt: skip
    return folder
