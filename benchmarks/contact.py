"""Contact benchmark: the Laplace sleeve on the shell over a mesh sequence, and the search share.

* ``laplace-sleeve``: the tight tube of :func:`fenics_garment.verification.contact.tight_tube` (one
  eighth with symmetry planes, P2⊕bubble Naghdi shell, "lumped" contact rule), dressed with the
  penalty (κ̂ = 10, variant ``penalty``) and tightened by augmented-Lagrangian updates to 1 % of h
  (``augmented-lagrangian``); on the coarsest mesh also the other contact rules (``rule-…``).
* ``search-share``: the share of the Newton iterations spent in the closest-point search on a
  shell tube with ≈ 100k contact points (fewer with ``--quick``).

Writes ``benchmarks/results/contact.json`` (records: case, variant, cells, dofs, ranks, wall_s,
search_s, assemble_s, solve_s, newton_its, value, reference, rel_error, …) and prints a table.

    python -m benchmarks.contact [--quick]
    mpiexec -n 2 python -m benchmarks.contact
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from benchmarks import check_args
from fenics_garment._stack import MPI
from fenics_garment.contact import uzawa
from fenics_garment.materials import Isotropic
from fenics_garment.verification import contact as cases

HERE = Path(__file__).resolve().parent
MATERIAL = Isotropic(E=1.0e6, nu=0.3, thickness=1.0e-3)


def _record(scene: cases.ContactCase, variant: str, wall: float, its: int, comm) -> dict:
    st, tm = scene.state, scene.solver.timings
    value = cases.mid_pressure(scene)
    assemble = comm.allreduce(tm.residual + tm.jacobian - tm.hooks, op=MPI.MAX)
    search = comm.allreduce(st.timings.search_s, op=MPI.MAX)
    hooks = comm.allreduce(tm.hooks, op=MPI.MAX)
    return {
        "case": "laplace-sleeve",
        "variant": variant,
        "rule": st.rule,
        "cells": scene.model.geometry.mesh.topology.index_map(2).size_global,
        "dofs": scene.model.Q.dofmap.index_map.size_global * scene.model.Q.dofmap.index_map_bs,
        "ranks": comm.size,
        "contact_points": comm.allreduce(st.timings.points, op=MPI.SUM),
        "wall_s": wall,
        "search_s": search,
        "hooks_s": hooks,
        "assemble_s": assemble,
        "solve_s": wall - assemble - hooks,  # LU + SNES overhead
        "newton_its": its,
        "value": value,
        "reference": scene.reference,
        "rel_error": value / scene.reference - 1,
        "penetration_m": uzawa.max_penetration(st),
    }


def run(n: tuple[int, int], rule: str = "lumped", augmented: bool = True) -> list[dict]:
    """Penalty dressing, then (``augmented``) multiplier updates: one record each."""
    comm = MPI.COMM_WORLD
    scene = cases.tight_tube(comm, MATERIAL, n=n, rule=rule)
    st = scene.state
    st.refresh()  # search tree and Expression warm-up outside the timings
    st.timings.search_s = st.timings.eval_s = 0.0
    tm = scene.solver.timings  # the SNES callbacks hold this object: zero it in place
    tm.residual = tm.jacobian = tm.hooks = 0.0
    comm.Barrier()
    t0 = time.perf_counter()
    rep = cases.dress_case(scene)
    its = sum(rep.iterations)
    tag = "penalty" if rule == "lumped" else f"rule-{rule}"
    out = [_record(scene, tag, time.perf_counter() - t0, its, comm)]
    if augmented:
        al = uzawa.augmented_lagrangian(
            st, float(scene.contact.kappa.value), scene.solver.solve,
            tol=0.01 * MATERIAL.thickness,
        )  # fmt: skip
        its += sum(al.newton_iterations)
        tag = "augmented-lagrangian" if rule == "lumped" else f"rule-{rule}+AL"
        out.append(_record(scene, tag, time.perf_counter() - t0, its, comm))
    return out


def search_share(n: tuple[int, int]) -> dict:
    """Time split of the penalty dressing on a large tube: search share of the wall time."""
    (rec,) = run(n, augmented=False)
    its = max(rec["newton_its"], 1)
    rec = dict(rec, case="search-share")
    rec["search_per_iteration_s"] = rec["search_s"] / its
    rec["wall_per_iteration_s"] = rec["wall_s"] / its
    rec["search_share"] = rec["search_s"] / rec["wall_s"]
    return rec


def main(argv: list[str] | None = None) -> int:
    argv = list(argv or [])
    bad = check_args(argv, __doc__, {"--quick"}, (), ())
    if bad is not None:
        return bad
    quick = "--quick" in argv
    comm = MPI.COMM_WORLD
    sizes = [(8, 4), (16, 8)] if quick else [(8, 4), (16, 8), (32, 16), (64, 32)]
    records = []
    for n in sizes:
        records += run(n)
    if not quick:
        for rule in ("vertex", "vertex+edge", "gauss2"):  # one JIT each (~50 s cold)
            records += run(sizes[0], rule)
    # "lumped": 7 points per cell, 4 per cell after merging shared nodes: 2·96·48·… ≈ 4 n² pts
    big = (48, 24) if quick else (160, 80)
    share = search_share(big)
    records.append(share)
    if comm.rank == 0:
        out = HERE / "results" / "contact.json"
        out.parent.mkdir(exist_ok=True)
        out.write_text(json.dumps({"runs": records}, indent=1))
        print(
            f"{'case':15} {'variant':22} {'cells':>6} {'dofs':>7} {'pts':>7} {'its':>4} "
            f"{'wall':>7} {'search':>7} {'assem':>7} {'solve':>7} {'p [Pa]':>9} "
            f"{'err %':>8} {'pen/h %':>8}"
        )
        for r in records:
            print(
                f"{r['case']:15} {r['variant']:22} {r['cells']:6d} {r['dofs']:7d} "
                f"{r['contact_points']:7d} {r['newton_its']:4d} {r['wall_s']:7.2f} "
                f"{r['search_s']:7.3f} {r['assemble_s']:7.3f} {r['solve_s']:7.3f} "
                f"{r['value']:9.2f} {100 * r['rel_error']:+8.3f} "
                f"{100 * r['penetration_m'] / MATERIAL.thickness:8.3f}"
            )
        print(
            f"search share with {share['contact_points']} contact points ({comm.size} rank(s)): "
            f"{100 * share['search_share']:.1f} % of the wall time "
            f"({share['search_per_iteration_s']:.3f} s of {share['wall_per_iteration_s']:.3f} s "
            f"per Newton iteration)"
        )
    return 0


if __name__ == "__main__":
    import sys

    raise SystemExit(main(sys.argv[1:]))
