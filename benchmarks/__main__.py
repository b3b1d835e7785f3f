"""One command for the benchmark suite: run, write JSON records, write the Markdown report.

    python -m benchmarks [--quick|--full] [--repeat N] [name ...]

``name`` is a suite (``shells``, ``contact``, ``scenes``, ``solvers``) or a shell case of
:data:`fenics_garment.verification.shells.CASES` (then only those shell cases run). Without
names the shells and contact suites run. Each suite writes
``benchmarks/results/<suite>.json``; the report
``benchmarks/results/REPORT.md`` (tables, work–precision PNGs) is rebuilt from all JSON files.
The contact suite runs its ``--quick`` sizes unless ``--full`` is given (its own full size takes
tens of minutes). ``scenes`` (gilet cost growth, 1 vs 2 ranks, skips on/off, the FEniCSx-Shells
peer, the stress table; ``benchmarks/scenes.py``) runs only when named, e.g.
``python -m benchmarks scenes`` or ``python -m benchmarks scenes growth peer``. ``solvers``
(direct MUMPS, MUMPS block low-rank and CG + GAMG against mesh size on the Scordelis–Lo roof, 1
and 2 ranks, and a cost model; ``benchmarks/solvers.py``) likewise runs only when named, and so
does ``validation`` (heavy elastica, plate or beam, fabrics' bending lengths, the tension–strain
law's tube; ``benchmarks/validation.py``, whose ``drape`` parts run on their own).
"""

from __future__ import annotations

import sys
import time

from benchmarks import check_args, contact, report, scenes, shells, solvers, validation
from fenics_garment._stack import MPI
from fenics_garment.verification import shells as shell_cases

SUITES = ("shells", "contact", "scenes", "solvers", "validation")
DEFAULT_SUITES = ["shells", "contact"]


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    bad = check_args(argv, __doc__, {"--quick", "--full"}, {"--repeat"},
                     {*SUITES, *scenes.PARTS, *shell_cases.CASES})  # fmt: skip
    if bad is not None:
        return bad
    flags = [a for a in argv if a.startswith("--")]
    mode, repeat, names = shells.parse(argv)
    parts = [n for n in names if n in scenes.PARTS]
    cases = [n for n in names if n not in SUITES and n not in scenes.PARTS]
    suites = [n for n in names if n in SUITES] or (
        ["shells"] if cases else ["scenes"] if parts else DEFAULT_SUITES
    )
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *a, **k: None)
    t0 = time.perf_counter()
    if "shells" in suites:
        rep = ["--repeat", str(repeat)] if repeat > 1 else []
        shells.main([a for a in flags if a != "--repeat"] + rep + cases)
    if "contact" in suites:
        contact.main(["--quick"] if mode != "full" else [])
    if "scenes" in suites and comm.rank == 0:  # it starts its own mpiexec subprocesses
        scenes.main(parts + (["--quick"] if mode == "quick" else []))
    if "solvers" in suites and comm.rank == 0:  # its own mpiexec children, 1 and 2 ranks
        solvers.main(["--quick"] if mode == "quick" else [])
    if "validation" in suites and comm.rank == 0:  # elastica, fabrics, curve tube (no drape)
        validation.main([])
    if comm.rank == 0:
        report.write_report(say=say)
    say(f"benchmarks ({mode}: {', '.join(suites)}) done in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
