"""The ``fenics-garment`` command line: ``info``, ``demo``, ``run SCENE.toml``, ``check`` and
``report FOLDER``.

``main(argv) -> int`` is the whole program so that tests call it directly. Messages are printed
on rank 0 only; every rank runs the same commands so the program works under ``mpiexec -n N``.
``run -n N`` started outside an MPI job is the package's launcher
(:mod:`fenics_garment.launcher`): it starts ``mpiexec -n N`` with the same arguments itself.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from fenics_garment import __version__


def _jit_cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "fenics"


def stack_info() -> dict[str, str]:
    """Versions of the numerical stack, the MPI library and the state of the FFCx JIT cache."""
    import petsc4py

    import gmsh

    from fenics_garment._stack import MPI, STACK, PETSc, dolfinx

    cache = _jit_cache_dir()
    n_compiled = len(list(cache.glob("**/*.so"))) if cache.is_dir() else 0
    return {
        "fenics-garment": __version__,
        "python": sys.version.split()[0],
        "stack": STACK,
        "dolfinx": dolfinx.__version__,
        "petsc": ".".join(str(v) for v in PETSc.Sys.getVersion()),
        "petsc4py": petsc4py.__version__,
        "mpi library": MPI.Get_library_version().splitlines()[0].strip(),
        "mpi ranks": str(MPI.COMM_WORLD.size),
        "gmsh": gmsh.__version__,
        "ffcx jit cache": (
            f"warm ({n_compiled} compiled forms in {cache})"
            if n_compiled
            else f"cold (nothing compiled yet in {cache}); the first run JIT-compiles its forms"
        ),
    }


def _cmd_info(args: argparse.Namespace) -> int:
    from fenics_garment._stack import MPI

    info = stack_info()
    if MPI.COMM_WORLD.rank == 0:
        width = max(map(len, info))
        for key, value in info.items():
            print(f"{key:<{width}}  {value}")
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    from fenics_garment import demos

    if args.list or (args.name is None and not demos.DEFAULT):
        for name, demo in demos.REGISTRY.items():
            print(f"{name:<24} {demo.summary}")
        return 0
    name = args.name or demos.DEFAULT
    if name not in demos.REGISTRY:
        print(
            f"unknown demo {name!r}; available: {', '.join(demos.REGISTRY)}",
            file=sys.stderr,
        )
        return 2
    return demos.REGISTRY[name].run(Path(args.output), quiet=args.quiet)


#: Exit codes (documented in ``run --help`` and the README); a signal s: 128 + s.
EXIT_INTERNAL, EXIT_INPUT, EXIT_OUTPUT, EXIT_INTERRUPTED = 1, 2, 5, 130


def _input_errors() -> tuple[type[Exception], ...]:
    """Errors of the user's input or set-up: a one-line message and exit code 2."""
    from fenics_garment.geometry.errors import GeometryError, ScanError
    from fenics_garment.materials import MaterialError
    from fenics_garment.petsc_options import PetscOptionError
    from fenics_garment.scene.checkpoint import ResumeError
    from fenics_garment.scene.config import SceneError
    from fenics_garment.scene.preflight import PreflightError

    return (SceneError, ScanError, MaterialError, PreflightError, ResumeError, GeometryError,
            PetscOptionError, _RanksError)  # fmt: skip


class _RanksError(ValueError):
    """``run -n N`` inside a job of another size (an input error: exit 2)."""


#: Characters of an error line (an echoed value is cut well before; this is the last guard).
LINE = 1000


def _one_line(err: BaseException) -> str:
    from fenics_garment.bounded import cut

    return cut(" ".join(str(err).split()), LINE) or type(err).__name__


def _continue_command(err, args: argparse.Namespace) -> str:
    """The command that continues a stopped run from its checkpoint, or starts it again."""
    folder = getattr(err, "folder", None) or getattr(args, "resume", None)
    resumable = folder is not None and (err.checkpoint or getattr(args, "resume", None))
    return continuation(args, folder if resumable else None)


def continuation(args: argparse.Namespace, folder: Path | str | None) -> str:
    """``continue with `… --resume FOLDER``` (a folder with a checkpoint), else ``start it again
    with `…``` (the run of ``args``)."""
    import shlex

    from fenics_garment._stack import MPI
    from fenics_garment.interrupt import launched

    n = MPI.COMM_WORLD.size
    launch = f"mpiexec -n {n} fenics-garment run" if n > 1 else "fenics-garment run"
    if launched():  # started by `fenics-garment run -n N`: continued the same way
        launch = f"fenics-garment run -n {n}"
    if folder is not None:
        return f"continue with `{launch} --resume {shlex.quote(str(folder))}`"
    scene = shlex.quote(str(args.scene)) if getattr(args, "scene", None) else "SCENE"
    out = f" -o {shlex.quote(args.output)}" if getattr(args, "output", None) else ""
    return f"start it again with `{launch} {scene}{out}` (no checkpoint yet)"


def _interrupted(err, args: argparse.Namespace) -> str:
    from fenics_garment.interrupt import signal_name

    if getattr(args, "func", None) is not _cmd_run:
        return f"interrupted by {signal_name(err.signum)} {err.stage}"
    return f"interrupted by {signal_name(err.signum)} {err.stage}; " + _continue_command(err, args)


def _run_guarded(args: argparse.Namespace, warnings: Sequence[str] = ()) -> int:
    """``args.func(args)`` with every error turned into one line and an exit code; an error on
    one MPI rank ends every rank (:mod:`fenics_garment.mpi_guard`)."""
    from fenics_garment import interrupt, mpi_guard
    from fenics_garment._stack import MPI
    from fenics_garment.output import OutputError

    mpi_guard.setup()
    interrupt.install()  # after the stack: PETSc's own handlers abort with code 59
    interrupt.announce_ready(MPI.COMM_WORLD)  # (to the launcher of `run -n N`, if any)
    if MPI.COMM_WORLD.rank == 0:
        for warning in warnings:
            print(f"warning: {warning}", file=sys.stderr, flush=True)
    try:
        interrupt.set_stage("before the run started")
        code = int(args.func(args))
        interrupt.set_stage("after the command had finished (its outputs are complete)")
        interrupt.poll(MPI.COMM_WORLD)
        return code
    except interrupt.Interrupted as err:
        return mpi_guard.end_together(err.code, _interrupted(err, args))
    except _input_errors() as err:
        return mpi_guard.end_together(EXIT_INPUT, _one_line(err))
    except OutputError as err:
        hint = ("; nothing half-written is left (run.json says what failed): free space (or "
                "fix the permissions), then ")  # fmt: skip
        return mpi_guard.end_together(EXIT_OUTPUT, _one_line(err) + hint
                                      + _continue_command(err, args))  # fmt: skip
    except KeyboardInterrupt:
        return mpi_guard.end_together(EXIT_INTERRUPTED, "interrupted; a run continues from "
                                      "its last checkpoint with --resume")  # fmt: skip
    except Exception as err:
        if os.environ.get("FENICS_GARMENT_TRACEBACK"):
            import traceback

            traceback.print_exc()
        return mpi_guard.end_together(
            EXIT_INTERNAL, f"internal error: {type(err).__name__}: {_one_line(err)} (a bug: "
            "please report it; FENICS_GARMENT_TRACEBACK=1 shows the traceback)")  # fmt: skip


def _ranks(text: str) -> int:
    """``-n N``: a number of MPI ranks (argparse type)."""
    try:
        n = int(text)
    except ValueError:
        n = 0
    if not 1 <= n <= MAX_RANKS:
        raise argparse.ArgumentTypeError(f"a number of ranks from 1 to {MAX_RANKS}, not "
                                         f"{text[:40]!r}")  # fmt: skip
    return n


#: The most ranks ``run -n`` starts.
MAX_RANKS = 4096


def _load_scene(args: argparse.Namespace):
    """The scene of ``run``: SCENE, or the resumed folder's scene_used.toml."""
    from fenics_garment.scene import config

    if args.scene is None and args.resume is None:
        raise config.SceneError("", "", "give a scene file, or --resume FOLDER")
    if args.scene is None:
        used = Path(args.resume) / "scene_used.toml"
        if not used.is_file():
            raise config.SceneError(str(used), "", "no such file: is the folder the output "
                                    "folder of a run (<output root>/<scene name>/)?")  # fmt: skip
        return config.load(used)
    return config.load(args.scene)


def _resumable(args: argparse.Namespace, scene) -> Path | None:
    """The run folder of ``args`` when it has a checkpoint, else None."""
    from fenics_garment.scene import checkpoint

    root = Path(args.output or scene.output.folder)
    folder = Path(args.resume) if args.resume else root / scene.name
    return folder if checkpoint.exists(folder) else None


def _cmd_run(args: argparse.Namespace) -> int:
    from fenics_garment import interrupt
    from fenics_garment._stack import MPI
    from fenics_garment.scene.run import exit_code, run

    size = MPI.COMM_WORLD.size
    if args.ranks is not None and args.ranks != size:
        raise _RanksError(f"-n {args.ranks}: this job has {size} MPI rank(s); under mpiexec "
                          "leave -n out (or give the job's size), or start `fenics-garment run "
                          "-n N …` by itself: it starts mpiexec")  # fmt: skip
    scene = _load_scene(args)
    interrupt.continuation = lambda: continuation(args, _resumable(args, scene))
    if args.error_bars:
        scene = replace(scene, output=replace(scene.output, error_bars=True))
    if args.check:
        return _check(scene)
    result = run(scene, args.output, quiet=args.quiet, resume=args.resume,
                 checkpoints=not args.no_checkpoints)  # fmt: skip
    code = exit_code(result)
    if MPI.COMM_WORLD.rank == 0 and code:
        failed = [c.name for c in result.checks if not c.ok]
        why = result.message or (f"the result failed its check(s) {', '.join(failed)} (see "
                                 f"'checks' in {result.folder / 'summary.json'})")  # fmt: skip
        print(f"error: {why}", file=sys.stderr)
    return code


def _check(scene) -> int:
    """Validate ``scene``, build its body, garment and model and run the pre-solve checks."""
    from fenics_garment._stack import MPI
    from fenics_garment.scene import build, preflight

    comm = MPI.COMM_WORLD
    if scene.kind == "drape":
        from fenics_garment.scene import drape

        line = drape.check(scene, comm)
        if comm.rank == 0:
            print(line)
        return 0
    preflight.scene_limits(scene)
    if scene.garment.kind == "pattern" and comm.rank == 0:
        from fenics_garment.pattern.io import describe, read_pattern
        from fenics_garment.scene.config import scene_file

        print("\n".join(describe(read_pattern(scene_file(scene, scene.garment.pattern)))))
    built = build.build(scene, comm)
    pen = preflight.check_built(built)
    r, where = preflight.smallest_body_radius(built)
    if comm.rank == 0:
        print(f"{scene.source or scene.name}: ok — body {len(built.body.triangles)} triangles "
              f"(smallest radius {r * 1e3:.1f} mm, {where}); garment "
              f"{len(built.garment.cells)} cells, {built.dofs} dofs on {comm.size} rank(s); "
              f"initial penetration {max(pen, 0.0) * 1e3:.1f} mm")  # fmt: skip
        g = built.garment
        if g.rest is not None:
            i = g.info
            gap, rms, top = i.get("seam_gap_max", 0), i.get("strain_rms", 0), i.get("strain_max", 0)
            print(f"sewn: seam gap before merging {gap * 1e3:.1f} mm, edge strain against the "
                  f"flat pieces {rms:.2%} RMS, {top:.1%} max, {i.get('inverted', 0):.0f} folded "
                  "cells")  # fmt: skip
        if g.levels:
            print("fit (level: body girth → garment girth, ease):  " + ";  ".join(
                f"{lv.name} {lv.body_girth * 100:.1f} → {lv.garment_girth * 100:.1f} cm "
                f"{lv.ease:+.1%}" for lv in g.levels))  # fmt: skip
    return 0


def _cmd_check(args: argparse.Namespace) -> int:
    from fenics_garment.scene import config

    return _check(config.load(args.scene))


def _cmd_report(args: argparse.Namespace) -> int:
    """Rebuild ``report.html`` of a run folder from its files (no solve; rank 0 writes)."""
    from mpi4py import MPI

    from fenics_garment.report import ReportError, write_report

    folder = Path(args.folder)
    if MPI.COMM_WORLD.rank != 0:
        return 0
    if not folder.is_dir():
        print(f"error: no such folder: {folder}", file=sys.stderr)
        return EXIT_INPUT
    try:
        path, seconds = write_report(folder)
    except ReportError as err:
        print(f"error: {_one_line(err)}", file=sys.stderr)
        return EXIT_INPUT
    if not args.quiet:
        print(f"{path} ({path.stat().st_size / 1e6:.1f} MB, {seconds:.1f} s)")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fenics-garment",
        description="Where, and how hard, does a garment press on a body? "
        "(Naghdi shell + contact in FEniCSx/DOLFINx 0.11)",
    )
    parser.add_argument("--version", action="version", version=f"fenics-garment {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    p_info = sub.add_parser("info", help="versions of DOLFINx, PETSc, MPI, gmsh; JIT cache state")
    p_info.set_defaults(func=_cmd_info)

    p_demo = sub.add_parser("demo", help="run a bundled demo (default: the main demo)")
    p_demo.add_argument("name", nargs="?", help="demo name (see --list)")
    p_demo.add_argument("--list", action="store_true", help="list the bundled demos")
    p_demo.add_argument("-o", "--output", default="output", help="output folder (default: output/)")
    p_demo.add_argument("-q", "--quiet", action="store_true", help="no progress output")
    p_demo.set_defaults(func=_cmd_demo)

    p_run = sub.add_parser(
        "run",
        help="dress a garment described by a scene file (TOML)",
        description="Dress the garment of SCENE and write <output root>/<scene name>/. After "
        "every converged dressing step a checkpoint is written to <that folder>/checkpoint/; "
        "a run that was killed continues with `run --resume <that folder>` (same number of MPI "
        "ranks), which reads the folder's scene_used.toml and gives the same answer as an "
        "uninterrupted run. With -n N the command starts the N MPI ranks itself (through the "
        "mpiexec next to the Python interpreter, or $MPIEXEC) and stays between them and the "
        "terminal: the way to run on several ranks when the terminal may close or the output "
        "is piped (`| head`, `| tee`); mpiexec run directly dies of a SIGHUP or of a closed "
        "stdout and takes the ranks with it before they can report. Exit codes: 0 done; 1 "
        "internal error (a bug); 2 bad input or a run refused before solving (one-line "
        "message); 3 the dressing did not converge (the "
        "outputs of the last converged state are written); 4 done, but a result check "
        "(penetration, spring, force balance, contact area) failed: a WARNING each, see "
        "'checks' in summary.json; 5 a file could not be written (disk full, read-only "
        "folder; the line says what failed, run.json too): free space and --resume; 129, "
        "130, 143 stopped by SIGHUP, SIGINT (Ctrl-C), SIGTERM: the line names the stage "
        'reached and the command that continues the run; run.json says "interrupted".',
    )
    p_run.add_argument("scene", nargs="?",
                       help="scene file, e.g. demos/cotton_gilet.toml (optional with --resume: "
                       "then it must be the scene of the interrupted run)")  # fmt: skip
    p_run.add_argument("-o", "--output", default=None,
                       help="output root (default: the scene's output.folder); "
                       "the run writes <root>/<scene name>/")  # fmt: skip
    p_run.add_argument("-q", "--quiet", action="store_true", help="no progress output")
    p_run.add_argument("-n", "--ranks", type=_ranks, default=None, metavar="N",
                       help="run on N MPI ranks, started by this command (it outlives a closed "
                       "terminal and a closed stdout, passes Ctrl-C, SIGTERM and SIGHUP on to "
                       "the ranks, which stop at their next step with the --resume line, and "
                       "exits with their code); under mpiexec -n N it must be N")  # fmt: skip
    p_run.add_argument("--resume", metavar="FOLDER", default=None,
                       help="continue the interrupted run whose output folder is FOLDER "
                       "(<root>/<scene name>/) from its last checkpoint")  # fmt: skip
    p_run.add_argument(
        "--no-checkpoints",
        action="store_true",
        help="do not write checkpoints (a killed run then starts over)",
    )
    p_run.add_argument("--check", action="store_true", help="only validate (as `check`)")
    p_run.add_argument("--error-bars", action="store_true",
                       help="also solve on a sqrt(2)x coarser garment mesh first: a Richardson "
                       "error bar on every region's pressure ([output] error_bars)")  # fmt: skip
    p_run.set_defaults(func=_cmd_run)

    p_check = sub.add_parser(
        "check",
        help="validate a scene and build its meshes without solving",
        description="Validate SCENE, build its body, garment and shell model and run the "
        "pre-solve checks (body mesh fine enough for its curvature, garment not too deep "
        "inside the body, every MPI rank owning garment cells). Exit code 0: ok; 2: the "
        "one-line error says what to change.",
    )
    p_check.add_argument("scene", help="scene file")
    p_check.set_defaults(func=_cmd_check)

    p_report = sub.add_parser(
        "report",
        help="rebuild report.html of a run's output folder",
        description="Write FOLDER/report.html from the files of the run in FOLDER (summary.json, "
        "the pressure maps, report_surfaces.npz or body_pressure.vtu and final_state.xdmf): "
        "one self-contained page, offline, with the pressure maps, the region table and chart "
        "(error bars, comfort bands), the result checks, the dressing's convergence history, "
        "the time split and a 3D view of the pressure. A run writes it at its end by itself "
        "([output] report). Exit code 0: written; 2: FOLDER is not a run's output folder.",
    )
    p_report.add_argument("folder", help="the output folder of a run (<output root>/<scene name>/)")
    p_report.add_argument("-q", "--quiet", action="store_true", help="print nothing")
    p_report.set_defaults(func=_cmd_report)
    return parser


def _release_objects() -> None:
    """Free a stopped run's objects (reference cycles) while their libraries are loaded: at
    interpreter exit nanobind reports those it finds as leaks, many lines on stderr."""
    import gc

    gc.collect()


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    if getattr(args, "ranks", None) is not None:
        from fenics_garment import launcher

        if not launcher.inside_job():  # the launcher: mpiexec -n N runs this command again
            return launcher.launch(args.ranks, list(sys.argv[1:] if argv is None else argv))
    from fenics_garment import environment, interrupt

    warnings = environment.prepare()  # before the stack is loaded (HOME, JIT cache, backend)
    interrupt.tolerate_closed_output()
    code = _run_guarded(args, warnings)
    _release_objects()
    return code


if __name__ == "__main__":
    sys.exit(main())
