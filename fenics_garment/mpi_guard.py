"""An error on one MPI rank ends every rank, with its message, instead of a hang.

Under ``mpiexec -n N`` an exception on one rank leaves the others waiting forever in their next
collective call. :func:`end_together` is called by a rank that failed: it joins a non-blocking
barrier on a communicator of its own (so it cannot be matched by the other ranks' ordinary
collectives). If every rank fails — a bad scene, a refused resume: the usual case, each rank
raising the same error — the barrier completes within :data:`GRACE` seconds, rank 0 prints the
message once and every rank returns the exit code. If some rank is still working (or waiting in
a collective), the failed rank prints its message, marked with its rank, and aborts the whole
job with ``MPI_Abort`` and the exit code.
"""

from __future__ import annotations

import sys
import time

from fenics_garment._stack import MPI

#: Seconds a failed rank waits for the others to fail too before aborting the job.
GRACE = 5.0
#: Seconds between printing the message and ``MPI_Abort``: the launcher forwards a rank's stderr
#: through a pipe, and an abort right after the print can kill the forwarder before it has passed
#: the line on (seen once in CI under load: exit code 2 and an empty stderr).
DRAIN = 1.0
_comm: MPI.Comm | None = None


def setup() -> None:
    """Make the error communicator (collective: every rank calls it once, at start-up)."""
    global _comm
    if _comm is None and MPI.COMM_WORLD.size > 1:
        _comm = MPI.COMM_WORLD.Dup()


def wait(req: MPI.Request, grace: float) -> bool:
    """Whether the non-blocking request ``req`` completes within ``grace`` seconds."""
    t0 = time.monotonic()
    while not req.Test():
        if time.monotonic() - t0 > grace:
            return False
        time.sleep(0.01)
    return True


def _all_failed(comm: MPI.Comm, grace: float) -> bool:
    return wait(comm.Ibarrier(), grace)


def end_together(code: int, message: str, *, grace: float = GRACE) -> int:
    """Print ``error: message`` once and return ``code`` if every rank failed; otherwise print
    it from this rank and abort every rank with ``code`` (does not return)."""
    world = MPI.COMM_WORLD
    if world.size == 1 or _comm is None:
        print(f"error: {message}", file=sys.stderr, flush=True)
        return code
    if _all_failed(_comm, grace):
        if world.rank == 0:
            print(f"error: {message}", file=sys.stderr, flush=True)
        return code
    return abort(code, message)


#: Called with the message by :func:`abort` before the job ends (best effort: e.g. to mark the
#: run folder's ``run.json`` failed from this rank, where rank 0 cannot).
ON_ABORT: list = []


def abort(code: int, message: str) -> int:
    """Print ``message`` marked with this rank and end every rank of the job with ``code``."""
    world = MPI.COMM_WORLD
    for hook in ON_ABORT:
        try:
            hook(message)
        except Exception:  # best effort: the job ends anyway
            pass
    print(f"error (rank {world.rank} of {world.size}; the other ranks are stopped): {message}",
          file=sys.stderr, flush=True)  # fmt: skip
    time.sleep(DRAIN)
    world.Abort(code)
    return code  # not reached
