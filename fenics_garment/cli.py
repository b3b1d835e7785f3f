"""The ``fenics-garment`` command line: ``info``, ``demo`` and ``run SCENE.toml``.

``main(argv) -> int`` is the whole program so that tests call it directly. Messages are printed
on rank 0 only; every rank runs the same commands so the program works under ``mpiexec -n N``.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
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


def _cmd_run(args: argparse.Namespace) -> int:
    from fenics_garment._stack import MPI
    from fenics_garment.scene import config
    from fenics_garment.scene.run import run

    try:
        scene = config.load(args.scene)
    except config.SceneError as err:
        if MPI.COMM_WORLD.rank == 0:
            print(f"error: {err}", file=sys.stderr)
        return 2
    result = run(scene, args.output, quiet=args.quiet)
    if not result.completed:
        if MPI.COMM_WORLD.rank == 0:
            print(f"error: {result.message}", file=sys.stderr)
        return 3
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

    p_run = sub.add_parser("run", help="dress a garment described by a scene file (TOML)")
    p_run.add_argument("scene", help="scene file, e.g. demos/cotton_gilet.toml")
    p_run.add_argument("-o", "--output", default=None,
                       help="output root (default: the scene's output.folder); "
                       "the run writes <root>/<scene name>/")  # fmt: skip
    p_run.add_argument("-q", "--quiet", action="store_true", help="no progress output")
    p_run.set_defaults(func=_cmd_run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    return int(args.func(args))


if __name__ == "__main__":
    sys.exit(main())
