"""Contact benchmark: the Laplace sleeve over a mesh sequence, penalty vs augmented Lagrangian.

Writes ``benchmarks/results/contact.json`` (one record per run: case, variant, cells, dofs,
ranks, wall_s, search_s, assemble_s, solve_s, newton_its, value, reference, rel_error) and
prints a table, plus the closest-point search time for 100k points on a 50k-triangle body.

    python benchmarks/contact.py [--quick]
    mpiexec -n 2 python benchmarks/contact.py
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from fenics_garment._stack import MPI

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

import contact_models as cm  # noqa: E402  (the test membrane, until the shell lands)
from test_contact_laplace import dress, mid_pressure  # noqa: E402

from fenics_garment.contact import newton, uzawa  # noqa: E402
from fenics_garment.contact.primitives import cylinder  # noqa: E402
from fenics_garment.contact.search import BodySurface  # noqa: E402


def run(n_theta: int, variant: str) -> dict:
    comm = MPI.COMM_WORLD
    kappa_hat = 10.0 if variant == "penalty" else 1.0
    scene = cm.laplace_tube(comm, n_theta=n_theta, n_z=max(2, n_theta // 6), kappa_hat=kappa_hat)
    scene.state.refresh()  # JIT and tree warm-up outside the timings
    times = scene.problem.callback_times
    times.reset()
    st = scene.state
    st.timings.search_s = st.timings.eval_s = 0.0
    comm.Barrier()
    t0 = time.perf_counter()
    reports = dress(scene)
    its = sum(r.iterations for r in reports)
    if variant == "augmented-lagrangian":
        rep = uzawa.augmented_lagrangian(
            st, float(scene.kappa.value), lambda: newton.solve(scene.problem),
            tol=0.01 * scene.fabric.h,
        )  # fmt: skip
        its += sum(rep.newton_iterations)
    wall = time.perf_counter() - t0
    value = mid_pressure(scene)
    ref = scene.extra["reference"]
    cells = scene.mesh.topology.index_map(2).size_global
    dofs = scene.u.function_space.dofmap.index_map.size_global * 3
    search = comm.allreduce(st.timings.search_s, op=MPI.MAX)
    assemble = comm.allreduce(times.residual_s + times.jacobian_s, op=MPI.MAX)
    hooks = comm.allreduce(times.hooks_s, op=MPI.MAX)
    return {
        "case": "laplace-sleeve",
        "variant": variant,
        "cells": cells,
        "dofs": dofs,
        "ranks": comm.size,
        "contact_points": comm.allreduce(st.timings.points, op=MPI.SUM),
        "searched_points": comm.allreduce(st.timings.searched, op=MPI.SUM),
        "refreshes": st.timings.refreshes,
        "wall_s": wall,
        "search_s": search,
        "assemble_s": assemble,
        "solve_s": wall - hooks - assemble,  # linear solve + SNES overhead
        "newton_its": its,
        "value": value,
        "reference": ref,
        "rel_error": value / ref - 1,
        "penetration_m": uzawa.max_penetration(st),
    }


def search_100k() -> dict:
    body = BodySurface(*cylinder(0.1, -0.3, 0.3, 512, 48))  # ≈ 50k triangles
    rng = np.random.default_rng(0)
    θ = rng.uniform(0, 2 * np.pi, 100_000)
    r = 0.1 + rng.uniform(-1e-3, 3e-3, θ.size)
    x = np.column_stack([r * np.cos(θ), r * np.sin(θ), rng.uniform(-0.25, 0.25, θ.size)])
    t0 = time.perf_counter()
    body.closest(x)
    return {"triangles": len(body.triangles), "points": len(x), "build_s": body.build_time,
            "search_s": time.perf_counter() - t0}  # fmt: skip


def main(argv: list[str]) -> int:
    comm = MPI.COMM_WORLD
    sizes = [24, 48, 96] if "--quick" in argv else [24, 48, 96, 192, 384]
    records = [run(n, v) for n in sizes for v in ("penalty", "augmented-lagrangian")]
    search = search_100k()
    if comm.rank == 0:
        out = HERE / "results" / "contact.json"
        out.parent.mkdir(exist_ok=True)
        out.write_text(json.dumps({"runs": records, "search_100k": search}, indent=1))
        head = f"{'variant':22} {'cells':>7} {'dofs':>7} {'pts':>7} {'its':>4} {'wall':>7} "
        head += f"{'search':>7} {'assem':>7} {'solve':>7} {'p [Pa]':>9} {'err %':>8} {'pen/h %':>8}"
        print(head)
        for r in records:
            print(f"{r['variant']:22} {r['cells']:7d} {r['dofs']:7d} {r['contact_points']:7d} "
                  f"{r['newton_its']:4d} {r['wall_s']:7.2f} {r['search_s']:7.3f} "
                  f"{r['assemble_s']:7.3f} {r['solve_s']:7.3f} {r['value']:9.2f} "
                  f"{100 * r['rel_error']:+8.3f} {r['penetration_m'] / 1e-5:8.2f}")  # fmt: skip
        print(f"search: {search['points']} points on {search['triangles']} triangles in "
              f"{search['search_s']:.3f} s (tree build {search['build_s']:.3f} s)")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
