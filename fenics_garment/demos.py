"""Bundled demos, runnable as ``fenics-garment demo [NAME]`` (and by ``make demo``).

The default (``make demo``) is the cotton gilet of the seed paper. The scene demos
(``cotton-gilet``, ``nylon-gilet``, ``cotton-dress``, ``tube-on-cylinder``, ``sleeve-on-arm``,
``compression-stocking``) run the TOML scenes in ``demos/`` through
:mod:`fenics_garment.scene.run`. ``semicylinder`` is the package's large-rotation shell benchmark
(Sze, Liu & Lo 2004, §3.7) written as a ParaView time series with the load-displacement curve
compared with the reference.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class Demo:
    name: str
    summary: str
    run: Callable[..., int]


def _semicylinder(output: Path, quiet: bool = False, n: int = 20, steps: int = 5) -> int:
    from fenics_garment._stack import MPI, dolfinx
    from fenics_garment.materials import Isotropic
    from fenics_garment.points import PointEvaluator
    from fenics_garment.shell import bcs as B
    from fenics_garment.shell.geometry import parametric_surface_mesh
    from fenics_garment.shell.kinematics import ShellGeometry
    from fenics_garment.shell.loads import PointLoad
    from fenics_garment.shell.model import ShellModel
    from fenics_garment.solve import LoadStepper, NonlinearSolver

    comm = MPI.COMM_WORLD
    say = (lambda *a: print(*a, flush=True)) if comm.rank == 0 and not quiet else (lambda *a: 0)
    out = Path(output) / "semicylinder"
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.Barrier()
    t0 = time.perf_counter()
    r, L, P = 1.016, 3.048, 2000.0
    mesh = parametric_surface_mesh(
        comm, lambda a, y: np.array([r * np.sin(a), y, r * np.cos(a)]),
        (-math.pi / 2, math.pi / 2), (0, L), (n, n),
    )  # fmt: skip
    model = ShellModel(ShellGeometry.from_mesh(mesh, warp=(0, 1, 0)),
                       Isotropic(E=2.0685e7, nu=0.3, thickness=0.03))  # fmt: skip
    bottom = lambda x: np.isclose(np.abs(x[0]), r) & np.isclose(x[2], 0.0, atol=1e-9)  # noqa: E731
    bcs = B.clamped(model, lambda x: np.isclose(x[1], 0.0)) + B.fix_components(
        model, bottom, u=(2,), theta=(1,)
    )
    say(f"Sze et al. (2004) §3.7 pinched semi-cylinder: {n}×{n} mesh, "
        f"{model.Q.dofmap.index_map.size_global} nodes × 6 dofs, {comm.size} rank(s)")  # fmt: skip
    say("compiling the shell forms (FFCx JIT; cached for later runs) ...")
    solver = NonlinearSolver(model, bcs, point_loads=[PointLoad((0.0, L, r), (0.0, 0.0, -P))])
    disp = model.displacement()
    probe = PointEvaluator(mesh, [[0.0, L, r]])  # located once, read at every step
    curve = []
    with dolfinx.io.VTXWriter(comm, out / "displacement.bp", [disp], engine="BP4") as vtx:

        def on_step(rec):
            disp.x.array[:] = model.displacement().x.array
            vtx.write(rec.load_factor)
            w = probe(disp)[0, 2]
            curve.append((rec.load_factor * P, -w))
            say(
                f"  load {rec.load_factor * P:7.1f} N   -w = {-w:.5f} m   "
                f"Newton its {rec.iterations}" + (f"  (step cut {rec.cuts}×)" if rec.cuts else "")
            )

        LoadStepper(solver, steps=steps, on_step=on_step).run()
    value = curve[-1][1]
    ref = 1.71505  # Sze, Liu & Lo, Finite Elem. Anal. Des. 40 (2004), Table 7, P = 2000
    summary = {
        "case": "sze-3.7-semicylinder", "mesh": f"{n}x{n}", "ranks": comm.size,
        "minus_w_at_load": value, "reference": ref, "rel_error": (value - ref) / ref,
        "newton_iterations": solver.timings.newton_iterations, "wall_s": time.perf_counter() - t0,
        "load_displacement": curve,
    }  # fmt: skip
    if comm.rank == 0:
        tmp = out / "summary.json.part"
        tmp.write_text(json.dumps(summary, indent=2))
        tmp.replace(out / "summary.json")
        _plot_curve(out / "load_displacement.png", curve, ref, P)
    err = 100 * (value - ref) / ref
    say(f"-w at the load point: {value:.5f} m (reference {ref}, error {err:+.2f} %)")
    say(f"outputs in {out.resolve()}:")
    say("  displacement.bp (ParaView), summary.json, load_displacement.png")
    return 0


def _plot_curve(path: Path, curve, ref: float, P: float) -> None:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:  # pictures are optional
        return
    c = np.array(curve)
    fig, ax = plt.subplots(figsize=(5, 3.5))
    ax.plot(c[:, 1], c[:, 0], "o-", label="fenics-garment")
    ax.plot([ref], [P], "r*", ms=12, label="Sze et al. 2004 (P = 2000)")
    ax.set_xlabel("−w at load point [m]")
    ax.set_ylabel("load P [N]")
    ax.grid(True)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


#: The bundled scene files (package data; ``demos/*.toml`` are links to them).
SCENES = Path(__file__).resolve().parent / "scenes"


def _run_scene(scene_file: str, output: Path, quiet: bool):
    from fenics_garment.scene import config
    from fenics_garment.scene.run import run

    return run(config.load(SCENES / scene_file), Path(output), quiet=quiet)


def _scene_demo(scene_file: str) -> Callable[..., int]:
    """A demo that runs a bundled scene file (``fenics-garment run demos/<scene_file>``)."""

    def run_demo(output: Path, quiet: bool = False) -> int:
        from fenics_garment.scene.run import exit_code

        return exit_code(_run_scene(scene_file, output, quiet))

    return run_demo


def _limb_demo(scene_file: str, levels: tuple[str, ...], ankle: str | None = None):
    """A scene demo that then compares each limb level with Laplace's law and, for a stocking,
    names the RAL-GZ 387 class of the ankle pressure (:mod:`fenics_garment.compression`)."""

    def run_demo(output: Path, quiet: bool = False) -> int:
        from fenics_garment import compression as cp
        from fenics_garment._stack import MPI

        result = _run_scene(scene_file, output, quiet)
        checks = cp.level_checks(result.built, list(levels), half_width=0.01)
        if MPI.COMM_WORLD.rank == 0 and not quiet:
            print("mean pressure in a ±1 cm band at each level vs Laplace's law (free ends):")
            print("\n".join(cp.format_checks(checks)))
            if ankle is not None:
                p = next(c for c in checks if c.level == ankle).simulated_mmhg
                verdict = "in" if cp.ral_class(p) == "I" else "NOT in"
                print(f"ankle pressure {p:.1f} mmHg: {cp.describe_class(p)} of RAL-GZ 387; "
                      f"{verdict} class I (18–21 mmHg)")  # fmt: skip
        from fenics_garment.scene.run import exit_code

        return exit_code(result)

    return run_demo


REGISTRY: dict[str, Demo] = {
    "semicylinder": Demo(
        "semicylinder",
        "pinched semi-cylinder, Sze et al. 2004 §3.7: large-rotation shell vs reference",
        _semicylinder,
    ),
    "cotton-gilet": Demo(
        "cotton-gilet",
        "a fitted cotton gilet dressed on a size-88 mannequin: pressure per body region (kPa)",
        _scene_demo("cotton_gilet.toml"),
    ),
    "nylon-gilet": Demo(
        "nylon-gilet",
        "the same gilet in the seed paper's nylon (stiffer in shear and bending)",
        _scene_demo("nylon_gilet.toml"),
    ),
    "cotton-dress": Demo(
        "cotton-dress",
        "a cotton one-piece dress, skirt hanging under gravity (seed paper figs 14-15)",
        _scene_demo("cotton_dress.toml"),
    ),
    "darted-top": Demo(
        "darted-top",
        "a top sewn from its flat pattern file (front with two darts, back): the user's own "
        "pattern",
        _scene_demo("darted_top.toml"),
    ),
    "tube-on-cylinder": Demo(
        "tube-on-cylinder",
        "a tight sleeve on a cylinder: the scene runner against Laplace's law (seconds)",
        _scene_demo("tube_on_cylinder.toml"),
    ),
    "sleeve-on-arm": Demo(
        "sleeve-on-arm",
        "a graduated compression sleeve on an arm: pressure per level vs Laplace's law",
        _limb_demo("sleeve_on_arm.toml", ("wrist", "forearm", "elbow", "upper_arm")),
    ),
    "compression-stocking": Demo(
        "compression-stocking",
        "a graduated stocking on a leg: ankle pressure (mmHg) and its RAL-GZ 387 class",
        _limb_demo(
            "compression_stocking.toml",
            ("ankle_left", "calf_left", "knee_left", "thigh_left"),
            ankle="ankle",
        ),
    ),
}
DEFAULT = "cotton-gilet"
