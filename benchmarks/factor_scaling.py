"""Where the second rank is lost on the gilet (issue "Fast scenes", figure 5): the linear solve of
the cotton gilet's own Jacobian on 1 and 2 ranks, by solver.

The scene's 2-rank speed-up (1.33×, ``benchmarks.scenes`` part ``parallel``) is bounded by its
linear solve: at the shipped mesh MUMPS' numeric factorisation is about half of a 1-rank run.
This benchmark isolates that solve:

1. A 2-rank child dresses the shipped cotton gilet (no outputs) and writes the Jacobians of
   Newton iterations K, K+1, K+2 of its dressing (PETSc binary, with each rank's row range:
   DOLFINx's partition of the garment).
2. Children on 1 and on 2 ranks (2 ranks: the scene's own row partition), interleaved for
   ``--rounds`` rounds, load J_K and time each linear solver: the numeric factorisation (or
   preconditioner set-up) and the solve of one right-hand side, the fastest of 3 refactorisations
   of the same matrix, the symbolic analysis done once before, as in the scene.
3. A factorisation kept over Newton iterations (the remedy that would cut the factorisations'
   share): GMRES on J_{K+1} and J_{K+2} preconditioned by the LU of J_K, its iterations.

The ceiling printed last is Amdahl's law with the linear share s of the 1-rank scene run (record
``scenes.json``, part ``parallel``) and the linear speed-up r measured here, everything else at
the machine's 2×: 1 / (s / r + (1 − s) / 2).

    python -m benchmarks.factor_scaling [--rounds N] [--iteration K] [--mesh-size H]

``--mesh-size H`` dumps the gilet at garment mesh H [m] instead of the shipped one (the solvers'
cost at the converged meshes; the record is then ``factor_scaling-<H in mm>.json``).

Writes ``benchmarks/results/factor_scaling.json`` (section of ``REPORT.md``).
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

from benchmarks import check_args
from benchmarks.scenes import GILET, child_main, spawn_module

RESULTS = Path(__file__).resolve().parent / "results"
RECORD = RESULTS / "factor_scaling.json"
_LU = {"pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}
_KRYLOV = {"ksp_type": "gmres", "ksp_rtol": 1e-10, "ksp_gmres_restart": 200, "ksp_max_it": 500}
#: The linear solvers compared, as PETSc options (``sub_``: each rank's block).
SOLVERS: dict[str, dict[str, object]] = {
    "mumps": {"ksp_type": "preonly", **_LU},  # the scene's
    "mumps-pord": {"ksp_type": "preonly", **_LU, "mat_mumps_icntl_7": 4},
    "mumps-metis": {"ksp_type": "preonly", **_LU, "mat_mumps_icntl_7": 5},
    "mumps-scotch": {"ksp_type": "preonly", **_LU, "mat_mumps_icntl_7": 3},
    # the ordering computed in parallel (PT-Scotch): its separators split the tree between ranks
    "mumps-ptscotch": {"ksp_type": "preonly", **_LU, "mat_mumps_icntl_28": 2,
                       "mat_mumps_icntl_29": 1},
    # block low-rank factors at a loose tolerance, corrected by GMRES
    "mumps-blr-gmres": {**_KRYLOV, **_LU, "mat_mumps_icntl_35": 1, "mat_mumps_cntl_7": 1e-6},
    "mumps-blr4-gmres": {**_KRYLOV, **_LU, "mat_mumps_icntl_35": 1, "mat_mumps_cntl_7": 1e-4},
    "superlu_dist": {"ksp_type": "preonly", "pc_type": "lu",
                     "pc_factor_mat_solver_type": "superlu_dist"},
    "asm-2": {**_KRYLOV, "pc_type": "asm", "pc_asm_overlap": 2, "sub_pc_type": "lu",
              "sub_pc_factor_mat_solver_type": "mumps"},
    "asm-5": {**_KRYLOV, "pc_type": "asm", "pc_asm_overlap": 5, "sub_pc_type": "lu",
              "sub_pc_factor_mat_solver_type": "mumps"},
}  # fmt: skip
STALE = {**_KRYLOV, "ksp_max_it": 100, **_LU}  # GMRES + the LU of an older Jacobian


# --------------------------------------------------------------------------------------------
# children
# --------------------------------------------------------------------------------------------
def dump_child(spec: dict) -> dict:
    """Dress the shipped gilet; write its Jacobians ``spec["iterations"]`` to ``spec["folder"]``."""
    from dataclasses import replace

    from fenics_garment._stack import MPI, PETSc, dolfinx
    from fenics_garment.scene import config
    from fenics_garment.scene.run import run

    fem_petsc = dolfinx.fem.petsc
    comm = MPI.COMM_WORLD
    wanted, folder = set(spec["iterations"]), Path(spec["folder"])
    count, ranges = [0], {}
    assemble = fem_petsc.assemble_jacobian

    def writing(*args, **kwargs):  # the solver's Jacobian callback, counted
        out = assemble(*args, **kwargs)
        count[0] += 1
        if count[0] in wanted:
            J = next(a for a in args if isinstance(a, PETSc.Mat))
            viewer = PETSc.Viewer().createBinary(str(folder / f"J{count[0]}.bin"), "w", comm=comm)
            J.view(viewer)
            viewer.destroy()
            ranges[count[0]] = comm.allgather(J.getOwnershipRange())
        return out

    scene = config.load(GILET)
    scene = replace(scene, output=replace(scene.output, vtx=False, xdmf=False, pictures=False))
    if spec.get("mesh_size"):
        scene = replace(scene, garment=replace(scene.garment, mesh_size=spec["mesh_size"]))
    fem_petsc.assemble_jacobian = writing  # the solver looks it up when it installs its callbacks
    try:
        res = run(scene, folder, quiet=True, checkpoints=False)
    finally:
        fem_petsc.assemble_jacobian = assemble
    first = ranges[min(ranges)]
    # each rank's own split of the run (they wait for each other at every assembly's exchange)
    split = comm.allgather(res.summary["solver_time_s"])
    return {"dofs": first[-1][1], "rows": [b - a for a, b in first], "iterations": sorted(ranges),
            "per_rank_solver_time_s": split}  # fmt: skip


def _load(path: str, rows: list[int]):
    from fenics_garment._stack import MPI, PETSc

    comm = MPI.COMM_WORLD
    A = PETSc.Mat().create(comm)
    A.setType("aij")
    n = sum(rows)
    local = rows[comm.rank] if len(rows) == comm.size else PETSc.DECIDE
    A.setSizes(((local, n), (local, n)))
    viewer = PETSc.Viewer().createBinary(path, "r", comm=comm)
    A.load(viewer)
    viewer.destroy()
    return A


def _ksp(name: str, opts: dict, A, P):
    from fenics_garment._stack import PETSc

    prefix = f"fs_{name.replace('-', '_')}_"
    db = PETSc.Options()
    for k, v in opts.items():
        db[prefix + k] = v
    ksp = PETSc.KSP().create(A.getComm())
    ksp.setOptionsPrefix(prefix)
    ksp.setOperators(A, P)
    ksp.setFromOptions()
    return ksp


def solve_child(spec: dict) -> dict:
    """Time every solver of :data:`SOLVERS` on J_K; GMRES with the stale LU on the later ones."""
    from fenics_garment._stack import MPI, PETSc

    comm = MPI.COMM_WORLD
    paths, rows = spec["paths"], spec["rows"]
    A = _load(paths[0], rows)
    b = A.createVecLeft()
    b.setRandom()
    x, r = A.createVecRight(), A.createVecLeft()
    out = {"ranks": comm.size, "solvers": {}, "stale": []}
    for name in spec["solvers"]:
        ksp = _ksp(name, SOLVERS[name], A, A)
        try:
            ksp.setUp()  # symbolic analysis (and a first factorisation): once, as in the scene
            ksp.solve(b, x)
        except PETSc.Error as e:  # an option this build lacks (e.g. an ordering package)
            out["solvers"][name] = {"error": f"PETSc error {e.ierr}"}
            ksp.destroy()
            continue
        best = []
        for k in range(3):
            A.scale(1.0 + 1e-12 * (1 if k % 2 else -1))  # a new matrix state: refactorise
            comm.Barrier()
            t0 = time.perf_counter()
            ksp.solve(b, x)  # PCSetUp sees the new state: numeric factorisation, then the solve
            best.append(time.perf_counter() - t0)
        A.mult(x, r)
        r.axpy(-1.0, b)
        out["solvers"][name] = {"total_s": comm.allreduce(min(best), MPI.MAX),
                                "krylov_its": ksp.getIterationNumber(),
                                "residual": r.norm() / b.norm()}  # fmt: skip
        ksp.destroy()
    if spec.get("stale"):
        for path in paths[1:]:
            B = _load(path, rows)
            ksp = _ksp("stale", STALE, B, A)
            ksp.solve(b, x)
            out["stale"].append({"matrix": Path(path).stem, "krylov_its": ksp.getIterationNumber(),
                                 "converged": ksp.getConvergedReason() > 0})  # fmt: skip
            ksp.destroy()
            B.destroy()
    out["loadavg"] = os.getloadavg()
    return out


def child(spec: dict) -> dict:
    return dump_child(spec) if spec["kind"] == "dump" else solve_child(spec)


# --------------------------------------------------------------------------------------------
# parent
# --------------------------------------------------------------------------------------------
def ceiling(share: float, speedup: float) -> float:
    """Amdahl: the 2-rank speed-up of a run whose fraction ``share`` gains ``speedup`` and the
    rest the machine's 2×."""
    return 1.0 / (share / speedup + (1.0 - share) / 2.0)


def _scene_share() -> dict | None:
    """The linear share of the fastest stored 1-rank run of the scenes benchmark (``parallel``)."""
    path = RESULTS / "scenes.json"
    if not path.exists():
        return None
    runs = [r for r in json.loads(path.read_text()).get("runs", [])
            if r.get("part") == "parallel" and r.get("ranks") == 1 and r.get("status") == "ok"
            and not r.get("side_by_side")]  # fmt: skip
    if not runs:
        return None
    r = min(runs, key=lambda r: r["warm_wall_s"])
    return {"linear_share": r["linear_solver_s"] / r["warm_wall_s"], "dofs": r["dofs"],
            "warm_wall_s": r["warm_wall_s"]}  # fmt: skip


def analyse(data: dict) -> dict:
    """Per solver: the fastest 1- and 2-rank times over the rounds, their ratio against the
    1-rank MUMPS (the scene's solver on one rank), and the Amdahl ceiling of the scene."""
    best: dict[tuple[str, int], dict] = {}
    for rec in data["rounds"]:
        if rec.get("status") != "ok":
            continue
        for name, s in rec["solvers"].items():
            if "error" in s:
                continue
            key = (name, rec["ranks"])
            if key not in best or s["total_s"] < best[key]["total_s"]:
                best[key] = s
    base = best.get(("mumps", 1))
    share = data.get("scene")
    rows = []
    limit = (lambda r: ceiling(share["linear_share"], r)) if share else (lambda r: None)
    for name in SOLVERS:
        one, two = best.get((name, 1)), best.get((name, 2))
        if not (one and two and base):
            continue
        speedup = base["total_s"] / two["total_s"]
        rows.append({"solver": name, "one_s": one["total_s"], "two_s": two["total_s"],
                     "its_one": one["krylov_its"], "its_two": two["krylov_its"],
                     "speedup_vs_mumps_1": speedup,
                     "ceiling": limit(speedup)})  # fmt: skip
    return {"table": rows}


def markdown(d: dict) -> str:
    share = d.get("scene") or {}
    h = d.get("mesh_size")
    mesh = "shipped mesh" if not h else f"garment mesh {1e3 * h:.1f} mm"
    lines = [f"The cotton gilet's own Jacobian ({mesh}, {d.get('dofs', 0):,} dofs, Newton "
             f"iteration {d.get('iteration')} of its dressing), its linear solve on 1 and 2 ranks "
             "(`python -m benchmarks.factor_scaling`): numeric factorisation or preconditioner "
             "set-up + one solve, the fastest of 3 refactorisations and of "
             f"{d.get('n_rounds', 0)} interleaved rounds. Speed-up: 1-rank MUMPS (the scene's "
             "solver) over the 2-rank time. "
             + (f"Ceiling: the scene's 2-rank speed-up if everything but the linear solve gained "
                f"2× (linear share {share['linear_share']:.2f} of the fastest stored 1-rank scene "
                "run, `scenes.json`)." if share else "No scene run at this mesh: no ceiling."),
             "",
             "| solver | 1 rank [s] | 2 ranks [s] | Krylov its (1 / 2 ranks) | speed-up | "
             "ceiling of the scene |", "|---|---|---|---|---|---|"]  # fmt: skip
    for r in d.get("analysis", {}).get("table", []):
        ceil = "" if r["ceiling"] is None else f"{r['ceiling']:.2f}×"
        lines.append(f"| {r['solver']} | {r['one_s']:.3f} | {r['two_s']:.3f} | "
                     f"{r['its_one']} / {r['its_two']} | {r['speedup_vs_mumps_1']:.2f}× | "
                     f"{ceil} |")  # fmt: skip
    stale = [s for rec in d.get("rounds", []) if rec.get("status") == "ok"
             for s in rec.get("stale", [])]  # fmt: skip
    if stale:
        seen = {}
        for s in stale:
            seen.setdefault(s["matrix"], s)
        parts = [f"{k}: {v['krylov_its']} its" + ("" if v["converged"] else " (not converged)")
                 for k, v in seen.items()]  # fmt: skip
        lines += ["", f"GMRES preconditioned by the LU of J{d.get('iteration')} (a factorisation "
                  "kept over Newton iterations) on the next Jacobians: " + ", ".join(parts)
                  + " (rtol 1e-10, at most 100)."]  # fmt: skip
    split = d.get("scene_split")
    if split:
        lines += ["", "Each rank's own time split of the 2-rank dump run (the shipped scene; every "
                  "assembly ends in an exchange between the ranks, so a rank that finishes first "
                  "waits there and the two splits agree) [s]: "
                  + "; ".join(f"rank {k}: residual {t['residual']:.1f}, Jacobian "
                              f"{t['jacobian']:.1f}, linear solve and waiting "
                              f"{t['solve'] - t['residual'] - t['jacobian']:.1f}"
                              for k, t in enumerate(split)) + "."]  # fmt: skip
    return "\n".join(lines)


def spawn(spec: dict, ranks: int) -> dict:
    return spawn_module("benchmarks.factor_scaling", spec, ranks, timeout=1800)


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if child_main(argv, child):
        return 0
    bad = check_args(argv, __doc__, (), {"--rounds", "--iteration", "--mesh-size"}, ())
    if bad is not None:
        return bad
    rounds = int(argv[argv.index("--rounds") + 1]) if "--rounds" in argv else 2
    k = int(argv[argv.index("--iteration") + 1]) if "--iteration" in argv else 30
    h = float(argv[argv.index("--mesh-size") + 1]) if "--mesh-size" in argv else None
    record = RECORD if h is None else RESULTS / f"factor_scaling-{1e3 * h:.1f}.json"
    with tempfile.TemporaryDirectory() as tmp:
        print(f"dressing the cotton gilet on 2 ranks to Newton iteration {k} ...", flush=True)
        dump = spawn({"kind": "dump", "folder": tmp, "iterations": [k, k + 1, k + 2],
                      "mesh_size": h}, 2)  # fmt: skip
        if dump.get("status") != "ok":
            print(f"the dump run failed: {dump.get('error')}", file=sys.stderr)
            return 1
        paths = [str(Path(tmp) / f"J{i}.bin") for i in dump["iterations"]]
        data = {"dofs": dump["dofs"], "iteration": k, "mesh_size": h, "rows": dump["rows"],
                "n_rounds": rounds, "scene": _scene_share() if h is None else None,
                "loadavg_start": os.getloadavg(), "rounds": [],
                "scene_split": dump["per_rank_solver_time_s"]}  # fmt: skip
        for j in range(rounds):
            for ranks in (1, 2):
                spec = {"kind": "solve", "paths": paths, "rows": dump["rows"],
                        "solvers": list(SOLVERS), "stale": j == 0 and ranks == 1}  # fmt: skip
                rec = spawn(spec, ranks)
                data["rounds"].append(dict(rec, round=j))
                if rec.get("status") == "ok":
                    times = ", ".join(f"{n} {s['total_s']:.3f} s ({s['krylov_its']} its)"
                                      if "error" not in s else f"{n} {s['error']}"
                                      for n, s in rec["solvers"].items())  # fmt: skip
                    print(f"  round {j}, {ranks} rank(s): {times}", flush=True)
                else:
                    print(f"  round {j}, {ranks} rank(s): FAILED {rec.get('error')}", flush=True)
    data["analysis"] = analyse(data)
    RESULTS.mkdir(exist_ok=True)
    record.write_text(json.dumps(data, indent=1, default=float))
    print(markdown(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
