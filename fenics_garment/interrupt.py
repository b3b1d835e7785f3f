"""SIGINT, SIGTERM and SIGHUP end a run between two steps, on every rank together; a closed
stdout does not end it at all.

:func:`install` (after the numerical stack is loaded: PETSc installs handlers of its own that
abort with code 59) makes the three signals set a flag. The run polls the flag at the points
where every rank is (:func:`poll`, collective: after every dressing step and between the
stages), so that a signal delivered to any rank stops all of them at the same place, with no
rank left waiting in a collective call. :func:`poll` raises :class:`Interrupted`, which the
command line turns into one line on rank 0 — the signal, the stage reached and the command that
continues the run — and the exit code 128 + the signal number (130, 143, 129). A second signal
before the next poll stops the process (every rank) at once, with the same line and code.

gmsh resets SIGINT to its default action while it runs (``gmsh.initialize(interruptible=True)``
in its Python API): the geometry code calls :func:`reinstall` after every gmsh session.

A closed stdout (``fenics-garment run … | head``) raised SIGPIPE, which killed the run without a
word; :func:`install` ignores SIGPIPE and :func:`tolerate_closed_output` sends what can no
longer be printed to ``/dev/null``, so the run goes on and writes its outputs.

Under the package's launcher (``fenics-garment run -n N``, :mod:`fenics_garment.launcher`) the
ranks also take the launcher's relayed signals (:data:`RELAYED`: MPICH's ``mpiexec`` passes
SIGQUIT, SIGALRM and SIGUSR1 on to every rank, but not SIGHUP), each standing for the signal the
launcher received. A signal that reaches a rank both directly and through the launcher (a kill
of the whole process tree) counts once, and so does one received directly again;
:func:`announce_ready` tells the launcher when every rank has its handlers, so that it holds a
signal received before rather than kill a starting rank.
"""

from __future__ import annotations

import errno
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

#: The signals that stop a run cleanly.
SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
#: The launcher's relay: the signal it sends ``mpiexec`` (which passes it on to every rank) for
#: each signal it receives. MPICH's ``mpiexec`` passes SIGINT, SIGQUIT, SIGTERM, SIGALRM and
#: SIGUSR1 on, not SIGHUP, and a second SIGINT makes it kill the job: none is relayed as itself,
#: so that a rank tells the launcher's signal from one sent to it directly.
RELAY = {signal.SIGINT: signal.SIGQUIT, signal.SIGTERM: signal.SIGALRM,
         signal.SIGHUP: signal.SIGUSR1}  # fmt: skip
RELAYED = {relay: signum for signum, relay in RELAY.items()}
#: Set by the launcher for its ranks: the folder where rank 0 says that every rank is ready.
LAUNCHER_ENV = "FENICS_GARMENT_LAUNCHER"
#: The name of that file.
READY = "ready"
_pending = 0
_installed = False
_stage = "starting"
#: (signal, "direct" or "relay") received so far.
_received: set[tuple[int, str]] = set()


class Interrupted(BaseException):  # (not Exception: no `except Exception` swallows it)
    """The run was stopped by ``signum`` at ``stage`` (``folder``: its run folder, when there is
    one; ``checkpoint``: whether a checkpoint to resume from was written)."""

    def __init__(self, signum: int, stage: str):
        self.signum, self.stage = signum, stage
        self.folder: Any = None
        self.checkpoint = False
        super().__init__(f"{signal_name(signum)} {stage}")

    @property
    def code(self) -> int:
        return 128 + self.signum


def signal_name(signum: int) -> str:
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


#: Called with the line before a second signal stops the process at once (best effort): the
#: run marks its ``run.json`` "interrupted".
ON_STOP: list[Callable[[int, str], None]] = []


def continuation() -> str:
    """How to continue the run stopped at once (replaced by the command line's, which knows
    the run folder and whether it has a checkpoint)."""
    return "the run continues from its last checkpoint with --resume"


def _handler(signum: int, frame: object) -> None:
    _received_signal(signum, "direct")


def _relay_handler(relay: int, frame: object) -> None:
    _received_signal(RELAYED[relay], "relay")


def _received_signal(signum: int, source: str) -> None:
    """Set the flag, or stop at once on a second signal. Under the launcher, the same signal
    received again directly, or through the launcher after directly, is the same signal: a kill
    of the whole process tree reaches a rank directly, through ``mpiexec`` (which passes SIGINT
    and SIGTERM on) and through the launcher; a second signal is the launcher's to pass on."""
    global _pending
    seen = {s for s, _ in _received}
    twin = (signum, "direct") in _received and (signum, "relay") not in _received
    again = launched() and source == "direct" and signum in seen
    _received.add((signum, source))
    if (source == "relay" and twin) or again:
        return
    if _pending:  # a second signal before the next poll: at once
        _stop_now(signum, everywhere=source == "relay")
    _pending = signum


#: Seconds a rank other than 0 waits before it ends, when every rank stops at once: rank 0
#: prints the line first (the launcher may end the job as soon as one rank has ended).
STOP_DRAIN = 0.5


def _stop_now(signum: int, everywhere: bool = False) -> None:
    """End the process (the job, on several ranks) with 128 + ``signum`` and one line, from the
    signal handler: not by an exception, which could surface inside a PETSc callback.
    ``everywhere``: the signal was relayed by the launcher to every rank, so each ends by itself
    and rank 0 alone prints the line (``MPI_Abort`` printed a line of its own on every rank)."""
    line = (f"interrupted by {signal_name(signum)} a second time {_stage}: stopped at once; "
            f"{continuation()}")  # fmt: skip
    for hook in ON_STOP:
        try:
            hook(signum, _stage)
        except Exception:  # best effort: the process ends anyway
            pass
    code = 128 + signum
    if "mpi4py.MPI" in sys.modules:
        from mpi4py import MPI

        several = MPI.Is_initialized() and MPI.COMM_WORLD.size > 1
        if several and everywhere:
            if MPI.COMM_WORLD.rank == 0:
                print(f"error: {line}", file=sys.stderr, flush=True)
            else:
                time.sleep(STOP_DRAIN)
            os._exit(code)
        if several:
            print(f"error (rank {MPI.COMM_WORLD.rank}): {line}", file=sys.stderr, flush=True)
            MPI.COMM_WORLD.Abort(code)
    print(f"error: {line}", file=sys.stderr, flush=True)
    os._exit(code)


def install() -> None:
    """Handle :data:`SIGNALS` (sets the flag :func:`poll` reads) and ignore SIGPIPE."""
    global _installed
    if threading.current_thread() is not threading.main_thread():
        return
    for s in SIGNALS:
        signal.signal(s, _handler)
    if launched():
        for relay in RELAYED:
            signal.signal(relay, _relay_handler)
    signal.signal(signal.SIGPIPE, signal.SIG_IGN)
    _installed = True


def launched() -> bool:
    """Whether this process is a rank started by the package's launcher."""
    return bool(os.environ.get(LAUNCHER_ENV))


def announce_ready(comm: Any) -> None:
    """Under the launcher: once every rank of ``comm`` has its handlers (collective), rank 0
    says so in the launcher's folder; until then the launcher holds the signals it receives."""
    if not launched():
        return
    comm.Barrier()
    if comm.rank == 0:
        try:
            (Path(os.environ[LAUNCHER_ENV]) / READY).touch()
        except OSError:  # another node's file system: the launcher stops waiting after a while
            pass


def reinstall() -> None:
    """:func:`install` again if it was installed (after a library that replaced the handlers)."""
    if _installed:
        install()


def set_stage(stage: str) -> None:
    """What the run is doing, for the interruption's message (``"while dressing, …"``)."""
    global _stage
    _stage = stage


def stage() -> str:
    return _stage


def pending() -> int:
    """The signal received and not yet acted on (0: none)."""
    return _pending


def poll(comm: Any) -> None:
    """Raise :class:`Interrupted` on every rank of ``comm`` when any rank received a signal
    (collective)."""
    global _pending
    signum = comm.allreduce(_pending, op=_max())
    if signum:
        _pending = 0
        raise Interrupted(signum, _stage)


def _max() -> Any:
    from fenics_garment._stack import MPI

    return MPI.MAX


class _Tolerant:
    """A text stream that, once its reader is gone (EPIPE), sends its output to /dev/null."""

    def __init__(self, stream: Any):
        self._stream = stream

    def _lost(self) -> None:
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, self._stream.fileno())
            os.close(devnull)
        except (OSError, ValueError):
            pass

    def _guard(self, work: Any) -> Any:
        try:
            return work()
        except OSError as err:
            if err.errno not in (errno.EPIPE, errno.EIO, errno.ECONNRESET):
                raise
            self._lost()
            return None

    def write(self, text: str) -> int:
        self._guard(lambda: self._stream.write(text))
        return len(text)

    def flush(self) -> None:
        self._guard(self._stream.flush)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def tolerate_closed_output() -> None:
    """Wrap ``sys.stdout`` and ``sys.stderr`` in :class:`_Tolerant` (idempotent)."""
    for name in ("stdout", "stderr"):
        stream = getattr(sys, name)
        if stream is not None and not isinstance(stream, _Tolerant):
            setattr(sys, name, _Tolerant(stream))
