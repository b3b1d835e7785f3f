"""Linear solvers against mesh size: direct MUMPS, MUMPS block low-rank, CG + GAMG (issue 16, 7).

The case is the Scordelis–Lo roof (:func:`fenics_garment.verification.shells.scordelis_lo_model`,
P2B-P2B, quarter roof n×n, reference 0.3024), solved as in the verification suite: the full
nonlinear model at a small load, one load step, Newton (2 iterations: the step and the check).
Each run is a fresh ``mpiexec`` child (peak memory per run), one after the other. Per run: dofs,
Newton and Krylov iterations, the time split per Newton iteration (Jacobian and residual
assembly, linear solve = factorisation or AMG set-up + solve), the deflection's error against
the reference and its difference from the MUMPS answer on the same mesh, peak RSS per rank.

Solvers (:data:`fenics_garment.petsc_options.LINEAR_SOLVERS`): ``direct`` (MUMPS LDLᵀ),
``direct-blr`` (MUMPS block low-rank, ICNTL(35) = 1, CNTL(7) = 1e-9), ``gamg`` (CG + GAMG with the
rigid-body near-nullspace, SOR smoothing) and ``gamg-plain`` (the same without the near-nullspace,
small meshes only: to show what the rigid-body modes buy).

**Cost model.** For each solver the time per Newton iteration (assembly + linear solve) on p
ranks and N dofs is modelled as

    T(N, p) = c · N^a / p + m · √(N/p) · log₂ p

the work term (exponent a and constant c fitted by least squares to the 1-rank runs from
``FIT_FROM`` dofs up) divided evenly over the ranks, plus a communication term: the halo of a
partition of a surface mesh has ∝ √(N/p) dofs, exchanged over log₂ p levels (reductions, the
multigrid's coarse levels, the factorisation's separator tree); m is fitted to the 2-rank run at
the largest size (set to 0 if that run was faster than the work term alone). Its prediction for
a 1M-dof garment on 64 ranks is printed with these assumptions: the per-dof work and the
iteration count measured here persist (the CG + GAMG count is nearly mesh independent), the
ranks are perfectly load balanced, a network as fast per byte as the shared memory of the
2-rank runs, and the direct solver's factorisation parallelising like its work term (optimistic
for MUMPS, whose top separators are dense fronts few ranks share).

    python -m benchmarks solvers [--quick]
    python -m benchmarks.solvers [--quick] [--sizes 16,32,64,128] [--ranks 1,2] [--append]

(``--append``: add to the stored runs instead of starting afresh, e.g. ``--ranks 2 --append``
for the 2-rank runs at a moment the shared machine is quiet.)
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks import check_args
from benchmarks.scenes import child_main, spawn_module

RESULTS = Path(__file__).resolve().parent / "results" / "solvers.json"
SOLVERS = ("direct", "direct-blr", "gamg", "gamg-plain")
SIZES = {"quick": [8, 16], "default": [16, 32, 64, 128]}
PLAIN_MAX_N = 32  # GAMG without near-nullspace only up to this mesh (1061 its at n = 16)
FIT_FROM = 30_000  # dofs: smaller runs are dominated by fixed costs
REFERENCE = 0.3024  # MacNeal & Harder 1985 (fenics_garment.verification.shells.scordelis_lo)
TARGET = (1_000_000, 64)  # the prediction: a 1M-dof garment on 64 ranks


# --------------------------------------------------------------------------------------------
# child
# --------------------------------------------------------------------------------------------
def child(spec: dict) -> dict:
    import resource

    from fenics_garment._stack import MPI, PETSc
    from fenics_garment.petsc_options import LINEAR_SOLVERS
    from fenics_garment.shell.model import evaluate_at_points
    from fenics_garment.solve import LoadStepper, NonlinearSolver
    from fenics_garment.verification import shells

    comm = MPI.COMM_WORLD
    name = spec["solver"]
    opts = dict(LINEAR_SOLVERS[name.removesuffix("-plain")])
    if name == "gamg-plain":
        opts["ksp_max_it"] = 20_000
    t0 = time.perf_counter()
    model, bcs = shells.scordelis_lo_model(spec["n"], comm=comm)
    t_mesh = time.perf_counter() - t0
    t0 = time.perf_counter()
    solver = NonlinearSolver(model, bcs, petsc_options=opts)
    if name == "gamg-plain":
        solver.problem.A.setNearNullSpace(PETSc.NullSpace())
    t_setup = time.perf_counter() - t0
    comm.Barrier()
    t0 = time.perf_counter()
    LoadStepper(solver, steps=1).run()
    t_run = time.perf_counter() - t0
    w = evaluate_at_points(model.displacement(), [shells.SCORDELIS_LO_POINT])[0, 2]
    value = -w / shells.LINEAR_SCALE
    tm = solver.timings
    its = max(tm.newton_iterations, 1)
    linear = tm.solve - tm.residual - tm.jacobian
    rss = comm.gather(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, root=0)
    return {
        "case": "scordelis-lo", "solver": name, "n": spec["n"], "ranks": comm.size,
        "dofs": model.Q.dofmap.index_map.size_global * model.Q.dofmap.index_map_bs,
        "ksp_type": solver.options["ksp_type"], "pc_type": solver.options["pc_type"],
        "newton_its": tm.newton_iterations, "krylov_its": tm.linear_iterations,
        "krylov_its_per_newton": tm.linear_iterations / its,
        "mesh_s": t_mesh, "setup_s": t_setup, "jit_s": tm.jit, "run_s": t_run,
        "jacobian_s": tm.jacobian / max(tm.jacobian_evaluations, 1),
        "residual_s": tm.residual / max(tm.residual_evaluations, 1),
        "linear_s": linear / its,
        "per_newton_s": tm.solve / its,
        "value": value, "reference": REFERENCE, "rel_error": value / REFERENCE - 1,
        "peak_rss_mb_per_rank": rss, "loadavg": os.getloadavg(), "status": "ok",
    }  # fmt: skip


# --------------------------------------------------------------------------------------------
# parent
# --------------------------------------------------------------------------------------------
def spawn(spec: dict, ranks: int = 1, timeout: float = 3600) -> dict:
    """One solver run (:func:`child`) in its own ``mpiexec -n ranks``."""
    rec = spawn_module("benchmarks.solvers", spec, ranks, timeout)
    rec.setdefault("wall_s", rec.get("wall_s_parent"))  # the whole child, start-up included
    return rec


def plan(mode: str, sizes: list[int] | None, ranks: tuple[int, ...]) -> list[tuple[dict, int]]:
    """1-rank runs of every solver at every size, then 2-rank runs at the largest size."""
    sizes = sizes or SIZES[mode]
    runs = []
    for n in sizes if 1 in ranks else []:
        for s in SOLVERS:
            if s == "gamg-plain" and n > PLAIN_MAX_N:
                continue
            runs.append(({"n": n, "solver": s}, 1))
    if 2 in ranks:
        runs += [({"n": max(sizes), "solver": s}, 2) for s in ("direct", "direct-blr", "gamg")]
    return runs


def fit(recs: list[dict]) -> dict:
    """The cost model of the module docstring for one solver's records (see there)."""
    one = sorted((r for r in recs if r["ranks"] == 1), key=lambda r: r["dofs"])
    use = [r for r in one if r["dofs"] >= FIT_FROM] if len(one) > 2 else one
    if len(use) < 2:
        use = one[-2:]
    if len(use) < 2:
        return {}
    N = np.array([r["dofs"] for r in use], dtype=float)
    T = np.array([r["per_newton_s"] for r in use])
    a, logc = np.polyfit(np.log(N), np.log(T), 1)
    c = math.exp(logc)
    out = {"a": float(a), "c": c, "fitted_on_dofs": N.tolist(), "m": 0.0}
    two = [r for r in recs if r["ranks"] == 2]
    if two:
        r = max(two, key=lambda r: r["dofs"])
        work = c * r["dofs"] ** a / 2
        out["m"] = max((r["per_newton_s"] - work) / math.sqrt(r["dofs"] / 2), 0.0)
        same = [x for x in one if x["dofs"] == r["dofs"]]
        if same:
            out["speedup_2_ranks"] = same[0]["per_newton_s"] / r["per_newton_s"]
        out["two_rank_dofs"] = r["dofs"]
    N1, p = TARGET
    work = c * N1**a / p
    comm = out["m"] * math.sqrt(N1 / p) * math.log2(p)
    its = [r["krylov_its_per_newton"] for r in use]
    out |= {"predicted_dofs": N1, "predicted_ranks": p, "predicted_work_s": work,
            "predicted_comm_s": comm, "predicted_per_newton_s": work + comm,
            "krylov_its_per_newton": its}  # fmt: skip
    return out


HEADER = (f"{'solver':11} {'n':>4} {'ranks':>5} {'dofs':>8} {'newton':>6} {'krylov/N':>8} "
          f"{'jac s':>7} {'res s':>6} {'linear s':>9} {'per N s':>8} {'err %':>8} "
          f"{'vs MUMPS':>9} {'RSS MB':>7} {'load':>5}")  # fmt: skip


def row(r: dict, direct: dict | None) -> str:
    head = f"{r['solver']:11} {r['n']:4d} {r['ranks']:5d} "
    if r.get("status") != "ok":
        return head + f"FAILED ({r.get('error', '')[-120:]!r})"
    diff = abs(r["value"] - direct["value"]) / abs(direct["value"]) if direct else math.nan
    return head + (
        f"{r['dofs']:8d} {r['newton_its']:6d} {r['krylov_its_per_newton']:8.0f} "
        f"{r['jacobian_s']:7.2f} {r['residual_s']:6.2f} {r['linear_s']:9.2f} "
        f"{r['per_newton_s']:8.2f} {100 * r['rel_error']:+8.3f} {diff:9.1e} "
        f"{max(r['peak_rss_mb_per_rank']):7.0f} {r['loadavg'][0]:5.1f}"
    )


def markdown(d: dict) -> str:
    """The stored record as Markdown tables (for REPORT.md)."""
    runs = d.get("runs", [])
    direct = {(r["n"], r["ranks"]): r for r in runs
              if r.get("solver") == "direct" and r.get("status") == "ok"}  # fmt: skip
    lines = ["Scordelis–Lo roof, P2B-P2B, one load step (2 Newton iterations); times per Newton "
             "iteration; `vs MUMPS`: relative difference of the deflection from the direct "
             "solver's on the same mesh (`python -m benchmarks solvers`).", "",
             "| solver | n | ranks | dofs | Krylov its / Newton | Jacobian s | residual s | "
             "linear s | per Newton s | error % | vs MUMPS | RSS MB/rank | load |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for r in runs:
        if r.get("status") != "ok":
            lines.append(f"| {r.get('solver')} | {r.get('n')} | {r.get('ranks')} | failed: "
                         f"{str(r.get('error', ''))[-80:]} |||||||||")  # fmt: skip
            continue
        dr = direct.get((r["n"], r["ranks"])) or direct.get((r["n"], 1))
        diff = abs(r["value"] - dr["value"]) / abs(dr["value"]) if dr else math.nan
        lines.append(
            f"| {r['solver']} | {r['n']} | {r['ranks']} | {r['dofs']} | "
            f"{r['krylov_its_per_newton']:.0f} | {r['jacobian_s']:.2f} | {r['residual_s']:.3f} | "
            f"{r['linear_s']:.2f} | {r['per_newton_s']:.2f} | {100 * r['rel_error']:+.3f} | "
            f"{diff:.1e} | {max(r['peak_rss_mb_per_rank']):.0f} | {r['loadavg'][0]:.1f} |"
        )
    lines += ["", "Cost model T(N, p) = c·N^a/p + m·√(N/p)·log₂p per Newton iteration "
              "(assumptions: `benchmarks/solvers.py`), prediction for "
              f"{TARGET[0]:,} dofs on {TARGET[1]} ranks:", "",
              "| solver | a | c | m | 2-rank speed-up | predicted work s | predicted comm s | "
              "predicted per Newton s |", "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for s, f in d.get("model", {}).items():
        if not f:
            continue
        lines.append(
            f"| {s} | {f['a']:.2f} | {f['c']:.3g} | {f['m']:.3g} | "
            f"{f.get('speedup_2_ranks', math.nan):.2f} | {f['predicted_work_s']:.2f} | "
            f"{f['predicted_comm_s']:.2f} | {f['predicted_per_newton_s']:.2f} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    argv = list(argv or [])
    if child_main(argv, child):
        return 0
    bad = check_args(argv, __doc__, {"--quick", "--append"}, {"--sizes", "--ranks"}, ())
    if bad is not None:
        return bad
    mode = "quick" if "--quick" in argv else "default"
    sizes = None
    if "--sizes" in argv:
        sizes = [int(x) for x in argv[argv.index("--sizes") + 1].split(",")]
    ranks = (1, 2)
    if "--ranks" in argv:
        ranks = tuple(int(x) for x in argv[argv.index("--ranks") + 1].split(","))
    say = lambda *a: print(*a, flush=True)  # noqa: E731
    data = {"meta": {"mode": mode, "loadavg_start": list(os.getloadavg()),
                     "note": "shared 2-core machine: times comparable within one run"},
            "runs": []}  # fmt: skip
    if "--append" in argv and RESULTS.exists():  # e.g. the 2-rank runs when the load is low
        data["runs"] = json.loads(RESULTS.read_text())["runs"]
    t0 = time.perf_counter()
    say(HEADER)
    direct = {(r["n"], r["ranks"]): r for r in data["runs"]
              if r.get("solver") == "direct" and r.get("status") == "ok"}  # fmt: skip
    for spec, nranks in plan(mode, sizes, ranks):
        r = spawn(spec, nranks)
        if r.get("status") == "ok" and r["solver"] == "direct":
            direct[(r["n"], r["ranks"])] = r
        say(row(r, direct.get((spec["n"], nranks)) or direct.get((spec["n"], 1))))
        data["runs"].append(r)
        RESULTS.parent.mkdir(exist_ok=True)
        RESULTS.write_text(json.dumps(data, indent=1))
    ok = [r for r in data["runs"] if r.get("status") == "ok"]
    data["model"] = {s: fit([r for r in ok if r["solver"] == s]) for s in SOLVERS}
    data["meta"]["total_s"] = time.perf_counter() - t0
    RESULTS.write_text(json.dumps(data, indent=1))
    say("")
    say(markdown(data))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
