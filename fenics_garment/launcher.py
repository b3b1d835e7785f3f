"""``fenics-garment run -n N …``: the package starts its own MPI job and stands between it and
the terminal.

MPICH's ``mpiexec`` (hydra) does not survive the terminal it was started from: a SIGHUP (the
terminal closed) or a SIGPIPE (its stdout read by ``head``, which went away) ends it, and its
proxies then kill the ranks with SIGKILL before they can say anything or mark their run folder.
:func:`launch` starts ``mpiexec -n N python -m fenics_garment.cli run …`` (the ``mpiexec`` next
to the Python interpreter, or ``$MPIEXEC``) in a session of its own, with SIGHUP ignored, and

* relays the job's stdout and stderr while its own are alive; once a reader is gone (EPIPE, EIO)
  it drops that stream and keeps draining the job's, so the job is never blocked nor signalled;
* passes SIGINT, SIGTERM and SIGHUP on to every rank as the signal :data:`interrupt.RELAY`
  names (``mpiexec`` passes those on; it does not pass SIGHUP, and a second SIGINT makes it kill
  the job), which the ranks take for the signal the launcher received: the run stops at its next
  poll, rank 0 prints the one line with the ``--resume`` command, ``run.json`` says
  "interrupted". A signal received before every rank has its handlers (rank 0 writes
  :data:`interrupt.READY` in the launcher's folder) is held until they have; a second one before
  that stops the job at once;
* returns the job's exit code (130, 143, 129 after a signal; 128 + s, with a line, if ``mpiexec``
  itself was ended by signal s).

The launcher loads no numerical library and does not initialise MPI. Under ``mpiexec -n N``
(or in the launcher's job) ``run -n N`` only checks that the job has N ranks.
"""

from __future__ import annotations

import contextlib
import os
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Sequence
from pathlib import Path

from fenics_garment import interrupt

#: Environment variables that say this process is a rank of an MPI job (MPICH/hydra, Open MPI,
#: PMIx), besides the launcher's own.
RANK_VARIABLES = ("PMI_RANK", "PMI_SIZE", "OMPI_COMM_WORLD_SIZE", "PMIX_RANK")
#: Seconds the launcher holds a signal waiting for the ranks' handlers; after that it relays it
#: anyway (rank 0 on another node cannot write the launcher's folder).
READY_LIMIT = 300.0
#: The same when no temporary folder could be made for rank 0 to write in.
READY_GUESS = 30.0
#: Seconds the relays may take to pass the job's last output on after it ended.
DRAIN = 10.0
#: seconds to wait for the ranks that outlived a killed mpiexec to be gone (:func:`_end_orphans`)
ORPHAN_WAIT = 10.0
#: Exit code of a launch that could not start (no ``mpiexec``): refused, as bad input.
EXIT_REFUSED = 2


class LaunchError(RuntimeError):
    """No ``mpiexec`` to start the job with."""


def inside_job() -> bool:
    """Whether this process is a rank of an MPI job (then ``run -n N`` launches nothing)."""
    return interrupt.launched() or any(os.environ.get(v) for v in RANK_VARIABLES)


def mpiexec_command() -> list[str]:
    """``$MPIEXEC`` (split as the shell would), else the ``mpiexec`` next to the Python
    interpreter, else the first on ``PATH``."""
    given = os.environ.get("MPIEXEC", "").strip()
    if given:
        return shlex.split(given)
    beside = Path(sys.executable).parent / "mpiexec"
    if os.access(beside, os.X_OK):
        return [str(beside)]
    found = shutil.which("mpiexec")
    if found is None:
        raise LaunchError(
            "no mpiexec next to the Python interpreter nor on PATH: set "
            "MPIEXEC, or start the ranks with `mpiexec -n N fenics-garment run …`"
        )
    return [found]


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view) :]


class _Relay(threading.Thread):
    """Copies the job's stream ``source`` to this process's ``target`` fd until the job closes
    it; once ``target`` fails (its reader gone, the terminal closed) it only drains ``source``."""

    def __init__(self, source: int, target: int):
        super().__init__(daemon=True)
        self.source, self.target, self.alive = source, target, True

    def run(self) -> None:
        while True:
            try:
                data = os.read(self.source, 65536)
            except OSError:
                break
            if not data:
                break
            if self.alive:
                try:
                    _write_all(self.target, data)
                except OSError:
                    self.alive = False
        os.close(self.source)


def _say(line: str) -> None:
    """``error: line`` on stderr, if it is still there."""
    try:
        _write_all(2, f"error: {line}\n".encode(errors="replace"))
    except OSError:
        pass


class _Job:
    """The launched job and the signals the launcher received."""

    def __init__(self, folder: Path, started: float, limit: float = READY_LIMIT):
        self.folder, self.started, self.limit = folder, started, limit
        self.proc: subprocess.Popen | None = None
        self.held = 0  # a signal received before the ranks were ready
        self.relayed = 0  # signals passed on
        self.stopped = 0  # the signal that made the launcher stop the job at once

    def ready(self) -> bool:
        late = time.monotonic() - self.started > self.limit
        return late or (self.folder / interrupt.READY).exists()

    def on_signal(self, signum: int, frame: object) -> None:
        if self.stopped:
            return
        if self.held or self.proc is None or not self.ready():
            if self.held:  # a second signal while the ranks start: stop them at once
                self.stopped = signum
                if self.proc is not None:
                    self.proc.kill()  # hydra's proxies then end the ranks
                return
            self.held = signum
            return
        self._relay(signum)

    def deliver_held(self) -> None:
        if self.held and self.proc is not None and not self.stopped and self.ready():
            signum, self.held = self.held, 0
            self._relay(signum)

    def _relay(self, signum: int) -> None:
        assert self.proc is not None
        try:
            self.proc.send_signal(interrupt.RELAY[signal.Signals(signum)])
            self.relayed += 1
        except (ProcessLookupError, OSError):
            pass


def _ignore_hangup() -> None:  # (in the child, before mpiexec is executed)
    signal.signal(signal.SIGHUP, signal.SIG_IGN)


def launch(ranks: int, argv: Sequence[str]) -> int:
    """Run ``fenics-garment`` with ``argv`` on ``ranks`` MPI ranks under ``mpiexec`` and return
    its exit code (see the module's documentation)."""
    try:
        command = [*mpiexec_command(), "-n", str(ranks), sys.executable, "-m",
                   "fenics_garment.cli", *argv]  # fmt: skip
    except LaunchError as err:
        _say(str(err))
        return EXIT_REFUSED
    try:
        folder, limit = Path(tempfile.mkdtemp(prefix="fenics-garment-launch-")), READY_LIMIT
    except OSError:  # no temporary folder: the ranks cannot say they are ready; guess
        folder, limit = Path(os.devnull), READY_GUESS
    job = _Job(folder, time.monotonic(), limit)
    saved = {s: signal.getsignal(s) for s in interrupt.SIGNALS}
    for s in interrupt.SIGNALS:
        signal.signal(s, job.on_signal)
    signal.signal(signal.SIGPIPE, signal.SIG_IGN)
    try:
        env = {**os.environ, interrupt.LAUNCHER_ENV: str(folder)}
        (out, out_w), (err, err_w) = os.pipe(), os.pipe()
        try:
            job.proc = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=out_w,
                                        stderr=err_w, env=env, start_new_session=True,
                                        preexec_fn=_ignore_hangup)  # fmt: skip
        except OSError as error:
            _say(f"could not start {command[0]}: {error.strerror or error}")
            for fd in (out, out_w, err, err_w):
                os.close(fd)
            return EXIT_REFUSED
        os.close(out_w)
        os.close(err_w)
        relays = [_Relay(out, 1), _Relay(err, 2)]
        for relay in relays:
            relay.start()
        code = _wait(job)
        t0 = time.monotonic()
        for relay in relays:
            relay.join(max(DRAIN - (time.monotonic() - t0), 0.1))
    finally:
        for s, handler in saved.items():
            signal.signal(s, handler)
        if folder.is_dir():
            shutil.rmtree(folder, ignore_errors=True)
    return _exit_code(job, code, ranks, argv)


def _descendants(pid: int) -> set[int]:
    """The processes under ``pid`` (Linux's /proc; empty elsewhere). MPICH's hydra starts its
    proxies and the ranks each in a session of their own, so once mpiexec is gone they are
    found by no process group: only by having been seen under it."""
    found, todo = set(), [pid]
    while todo:
        p = todo.pop()
        try:
            tasks = os.listdir(f"/proc/{p}/task")
        except OSError:
            continue
        for t in tasks:
            try:
                kids = Path(f"/proc/{p}/task/{t}/children").read_text().split()
            except OSError:
                continue
            for k in map(int, kids):
                if k not in found:
                    found.add(k)
                    todo.append(k)
    return found


def _started(pid: int) -> str | None:
    """The start time of process ``pid`` (field 22 of /proc/pid/stat), None if it is gone: a
    pid seen under mpiexec is the same process only while this is unchanged."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[19]
    except (OSError, IndexError):
        return None


def _end_orphans(pids: dict[int, str | None], limit: float = ORPHAN_WAIT) -> None:
    """SIGKILL the job's processes that outlived mpiexec (a rank still holding the output
    folder's lock would refuse the ``--resume`` the launcher points to) and wait until they
    are gone, :data:`ORPHAN_WAIT` seconds at most. Only a pid whose start time is the one seen
    under mpiexec is signalled (not a later process that got the same pid)."""
    pids = {p: t for p, t in pids.items() if t is not None and _started(p) == t}
    for p in pids:
        with contextlib.suppress(OSError):
            os.kill(p, signal.SIGKILL)
    end = time.monotonic() + limit
    while time.monotonic() < end and any(_started(p) == t for p, t in pids.items()):
        time.sleep(0.05)


def _wait(job: _Job) -> int:
    assert job.proc is not None
    seen: dict[int, str | None] = {}
    last = 0.0
    while True:
        try:
            code = job.proc.wait(timeout=0.05)
        except subprocess.TimeoutExpired:
            job.deliver_held()
            if time.monotonic() - last > 0.5:  # the job's tree, while mpiexec holds it
                seen |= {p: _started(p) for p in _descendants(job.proc.pid) if p not in seen}
                last = time.monotonic()
            continue
        if code < 0:  # mpiexec itself was killed: its ranks may live on, orphaned
            _end_orphans(seen)
        return code


def _exit_code(job: _Job, code: int, ranks: int, argv: Sequence[str]) -> int:
    if job.stopped:
        from fenics_garment.bounded import cut

        again = cut(shlex.join(["fenics-garment", *argv]), 400)
        name = interrupt.signal_name(job.stopped)
        _say(f"interrupted by {name} a second time while the {ranks} rank(s) were starting: "
             f"stopped at once; start it again with `{again}`")  # fmt: skip
        return 128 + job.stopped
    if code < 0:
        name = interrupt.signal_name(-code)
        _say(f"mpiexec was ended by {name}, and with it the ranks; a run continues from its last "
             f"checkpoint with `fenics-garment run -n {ranks} --resume FOLDER`")  # fmt: skip
        return 128 - code
    return code
