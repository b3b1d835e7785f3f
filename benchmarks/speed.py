"""Where a Newton iteration's time goes on the cotton gilet, before and after the speed-ups.

Issue 16 ("Fast scenes"), targets 2 and 3: the per-iteration split, measured.


* ``scene``: the cotton gilet demo (``demos/cotton_gilet.toml``, its 35 mm mesh, P2B-P2B) on
  2 ranks, each variant in its own ``mpiexec`` child of :func:`benchmarks.scenes.spawn`, one
  after the other in the same run, so that their ratios are comparable on this shared machine:

  - ``before``: the code as it was (:data:`BEFORE`) — on straight-sided cells every contact
    point of every cell searched (the lumped rule's 7 points, none shared), the smooth body's
    Hessian computed at every residual evaluation, the shell strains written as matrix
    products (:func:`matrix_kinematics`);
  - ``after``: each distinct point searched once (``ContactState._unique``), the Hessian
    computed only before a Jacobian (``ContactState.update_hessian``), the strains of
    :func:`fenics_garment.shell.kinematics.shell_kinematics`.

  Both on the straight-sided garment (``geometry = "straight"``, where point sharing is new) and
  on the curved one (the demo's default, where it was already shared). Per Newton iteration:
  Jacobian assembly, residual assembly, contact refresh (search and Hessian, inside the residual
  and Jacobian callbacks), the linear solve (factorisation + solve + SNES); and the answer
  (Newton iterations, contact force, largest change of a region's p95 pressure) beside it.
* ``kernels``: µs per cell and evaluation of the residual and Jacobian kernels on the gilet
  (serial, warm JIT cache, interleaved rounds, CPU time): the whole forms with the strains as
  now and as matrix products, the contact part alone, the shell part as the difference.
* ``verification`` (recorded, not re-run here: the matrix formulation is not in the package
  any more): every shell verification case at its default mesh with the code before and after
  the kinematics rewrite — values and times.

Writes ``benchmarks/results/speed.json`` and prints the tables.

    python -m benchmarks.speed [scene] [kernels] [--quick]
    python -m benchmarks.speed table       (the stored record as Markdown)
"""

from __future__ import annotations

import json
import os
import sys
import time

from benchmarks import check_args, scenes

RESULTS = scenes.RESULTS / "speed.json"
MESH = 0.035  # the demo's garment mesh [m]
#: the contact search as on main before these changes (763f8c8): straight-sided cells shared no
#: point, curved (order-2) ones did (their edge midpoints are geometry nodes); the Hessian was
#: computed at every residual
#: and the shell strains were written as matrix products (:func:`matrix_kinematics`)
BEFORE = {
    "straight": {"share_points": False, "contact_hessian": "always", "kinematics": "matrix"},
    "curved": {"contact_hessian": "always", "kinematics": "matrix"},
}
GEOMETRIES = {"quick": ["curved"], "default": ["straight", "curved"]}
REPEATS = 9  # kernel timings: interleaved rounds of assemblies


def _load() -> dict:
    return json.loads(RESULTS.read_text()) if RESULTS.exists() else {}


def _save(data: dict) -> None:
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(data, indent=1, default=float))


# --------------------------------------------------------------------------------------------
# scene: the per-iteration split of one run
# --------------------------------------------------------------------------------------------
def split(rec: dict) -> dict[str, float]:
    """Per Newton iteration [ms]: Jacobian and residual assembly, contact refresh, linear solve.

    From ``solver_time_s``: the residual callback's time holds the pre-residual hooks (the
    contact refresh), the Jacobian callback's the pre-Jacobian hooks (the deferred Hessian);
    ``solve − residual − jacobian`` is the factorisation, the triangular solves and SNES.
    """
    st = rec["solver_time_s"]
    its = max(st["newton_iterations"], 1)
    jac_hooks = st.get("jacobian_hooks", 0.0)
    per = {
        "jacobian_ms": (st["jacobian"] - jac_hooks) / its,
        "residual_ms": (st["residual"] - st["hooks"]) / its,
        "contact_ms": (st["hooks"] + jac_hooks) / its,
        "linear_ms": (st["solve"] - st["residual"] - st["jacobian"]) / its,
    }
    per = {k: 1e3 * v for k, v in per.items()}
    per["total_ms"] = sum(per.values())
    per["residuals_per_iteration"] = st["residual_evaluations"] / its
    per["jacobian_ms_per_evaluation"] = (
        1e3 * (st["jacobian"] - jac_hooks) / max(st["jacobian_evaluations"], 1)
    )
    return per


def _p95_change(a: dict, b: dict) -> float:
    """Largest |Δ p95| over the regions [kPa] between two runs."""
    pa, pb = a["regions_p95_kPa"], b["regions_p95_kPa"]
    return max((abs(pa[k] - pb[k]) for k in pa), default=0.0)


def scene(mode: str, say) -> list[dict]:
    """``before`` (:data:`BEFORE`) and ``after`` on each geometry, one child run each."""
    out = []
    for geometry in GEOMETRIES[mode]:
        pair = {}
        for name, extra in (("before", BEFORE[geometry]), ("after", {})):
            spec = {"scene": str(scenes.GILET), "mesh_size": MESH, "geometry": geometry, **extra}
            rec = scenes.spawn(spec)
            rec.update(variant=name, geometry=geometry, spec=extra)
            if rec["status"] == "ok":
                rec["split"] = split(rec)
            pair[name] = rec
            say(_line(rec))
        out += list(pair.values())
        if all(r["status"] == "ok" for r in pair.values()):
            out.append(_ratios(pair["before"], pair["after"], geometry))
            say(_ratio_line(out[-1]))
    return out


def _ratios(b: dict, a: dict, geometry: str) -> dict:
    """after/before of every split entry and of the dressing time; the answers side by side."""
    return {
        "variant": "after/before",
        "geometry": geometry,
        "status": "ok",
        "ratio": {k: a["split"][k] / b["split"][k] for k in b["split"] if b["split"][k]},
        "dressing_ratio": a["dressing_s"] / b["dressing_s"],
        "newton_its": (b["newton_its"], a["newton_its"]),
        "contact_force_rel_change": abs(a["contact_force_N"] / b["contact_force_N"] - 1),
        "p95_change_kPa": _p95_change(a, b),
    }


def _line(r: dict) -> str:
    if r["status"] != "ok":
        return f"  {r['geometry']:8s} {r['variant']:7s} failed: {r.get('error', '')[-200:]}"
    s = r["split"]
    return (f"  {r['geometry']:8s} {r['variant']:7s} {r['dofs']} dofs, {r['newton_its']} "
            f"dressing its, {r['solver_time_s']['newton_iterations']} in all, "
            f"per iteration: Jacobian {s['jacobian_ms']:.0f} ms, residual {s['residual_ms']:.0f}"
            f" ms, contact {s['contact_ms']:.0f} ms, linear {s['linear_ms']:.0f} ms "
            f"(total {s['total_ms']:.0f} ms); dressing {r['dressing_s']:.1f} s, "
            f"force {r['contact_force_N']:.6f} N")  # fmt: skip


def _ratio_line(r: dict) -> str:
    q = r["ratio"]
    return (f"  {r['geometry']:8s} after/before: Jacobian {q['jacobian_ms']:.2f}, residual "
            f"{q['residual_ms']:.2f}, contact {q['contact_ms']:.2f}, linear {q['linear_ms']:.2f}, "
            f"total {q['total_ms']:.2f}; dressing {r['dressing_ratio']:.2f}; Newton its "
            f"{r['newton_its']}; force change {r['contact_force_rel_change']:.1e}, p95 change "
            f"{r['p95_change_kPa']:.1e} kPa")  # fmt: skip


def matrix_kinematics(geometry, u, theta):
    """The shell strains as the matrix products of the :mod:`fenics_garment.shell.kinematics`
    docstring with the 3×3 rotation R(θ) (the formulation before its rewrite with F e_α, ∇d e_α
    and :func:`~fenics_garment.shell.kinematics.rotate`): the benchmark's "before" kernel."""
    from fenics_garment._stack import ufl
    from fenics_garment.shell import kinematics as k

    P = k.tangent_projector(geometry.normal)
    e = geometry.frame()
    d0 = geometry.d0
    F = P + ufl.grad(u)
    R = k.rotation_matrix(theta)
    d = R * d0
    C, Fd, Pd0 = F.T * F, F.T * ufl.grad(d), P * ufl.grad(d0)

    def sym(M, a, b):
        return 0.5 * (ufl.dot(e[a], M * e[b]) + ufl.dot(e[b], M * e[a]))

    eps = ufl.as_matrix([[0.5 * (ufl.dot(e[a], C * e[b]) - float(a == b)) for b in range(2)]
                         for a in range(2)])  # fmt: skip
    kap = ufl.as_matrix([[sym(Fd, a, b) - sym(Pd0, a, b) for b in range(2)] for a in range(2)])
    gam = ufl.as_vector([ufl.dot(F * e[a], d) - ufl.dot(e[a], d0) for a in range(2)])
    drill = 0.5 * (ufl.dot(R * e[0], F * e[1]) - ufl.dot(R * e[1], F * e[0]))
    return k.ShellKinematics(F=F, R=R, d=d, e1=e[0], e2=e[1], membrane=eps, bending=kap,
                             shear=gam, drilling=drill)  # fmt: skip


# --------------------------------------------------------------------------------------------
# kernels: µs per cell
# --------------------------------------------------------------------------------------------
def _assemblers(f, j, dolfinx, fp, jit_options) -> tuple:
    """Compiled forms of ``f`` and ``j`` and two closures assembling them into fixed objects."""
    t0 = time.perf_counter()
    ff = dolfinx.fem.form(f, jit_options=jit_options)
    jf = dolfinx.fem.form(j, jit_options=jit_options)
    jit = time.perf_counter() - t0
    A = fp.create_matrix(jf)
    b = fp.create_vector(ff.function_spaces[0])

    def vec() -> None:
        with b.localForm() as bl:
            bl.set(0.0)
        fp.assemble_vector(b, ff)

    def mat() -> None:
        A.zeroEntries()
        fp.assemble_matrix(A, jf)
        A.assemble()

    return vec, mat, jit, (A, b)


def kernels(say) -> dict:
    """Residual and Jacobian assembly of the gilet's forms (serial): the whole forms with the
    shell strains as written now and as matrix products (:func:`matrix_kinematics`), and the
    contact part alone; the shell part is the difference. The assemblies of all forms are
    interleaved, :data:`REPEATS` rounds, CPU time of this process (less sensitive than wall time
    to the other jobs on the machine); the table has the fastest and the median round."""
    from dataclasses import replace

    import numpy as np
    from dolfinx.fem import petsc as fp

    from fenics_garment._stack import MPI, dolfinx
    from fenics_garment.scene import build as scene_build
    from fenics_garment.scene import config
    from fenics_garment.shell import model as shell_model
    from fenics_garment.solve import JIT_OPTIONS

    s = config.load(scenes.GILET)
    s = replace(s, garment=replace(s.garment, mesh_size=MESH))
    built = scene_build.build(s, MPI.COMM_WORLD)
    model = built.model
    built.contact.refresh()
    contact = sum(model._extra_residual[1:], model._extra_residual[0])
    forms = {"whole": model.residual(), "contact": contact}
    written = shell_model.shell_kinematics
    shell_model.shell_kinematics = matrix_kinematics
    try:
        forms["whole-matrix"] = model.residual()
    finally:
        shell_model.shell_kinematics = written
    run = {k: _assemblers(f, model.jacobian(f), dolfinx, fp, JIT_OPTIONS) for k, f in forms.items()}
    cells = model.geometry.mesh.topology.index_map(2).size_local
    times = {k: {"residual": [], "jacobian": []} for k in run}
    for _ in range(REPEATS + 1):  # the first round warms up
        for k, (vec, mat, _, _) in run.items():
            for kind, work in (("residual", vec), ("jacobian", mat)):
                t0 = time.process_time()
                work()
                times[k][kind].append(1e6 * (time.process_time() - t0) / cells)
    us = {k: {kind: {"min": float(np.min(v[1:])), "median": float(np.median(v[1:]))}
              for kind, v in t.items()} for k, t in times.items()}  # fmt: skip
    for k, (_, _, jit, objs) in run.items():
        us[k]["jit_s"] = jit
        for o in objs:
            o.destroy()
    for k in ("whole", "whole-matrix"):
        us[k.replace("whole", "shell")] = {
            kind: {q: us[k][kind][q] - us["contact"][kind][q] for q in ("min", "median")}
            for kind in ("residual", "jacobian")
        }
    dofs = model.Q.dofmap.index_map.size_global * model.Q.dofmap.index_map_bs
    out = {"cells": cells, "dofs": dofs, "geometry": s.garment.geometry, "us_per_cell": us}
    for k, v in us.items():
        say(f"  {k:13s} residual {v['residual']['median']:7.1f} µs/cell, Jacobian "
            f"{v['jacobian']['median']:7.1f} µs/cell (median)")  # fmt: skip
    return out


# --------------------------------------------------------------------------------------------
# Markdown (benchmarks/report.py) and the command line
# --------------------------------------------------------------------------------------------
def markdown(data: dict) -> str:
    """The per-iteration split of every scene run, the after/before ratios, the kernel table."""
    lines = _scene_tables(data.get("scene", []))
    earlier = data.get("scene_contact_only")
    if earlier:
        lines += ["", f"Earlier run, {earlier['note']}:", "", *_scene_tables(earlier["runs"])]
    return "\n".join(lines + _other_tables(data))


def _scene_tables(runs: list[dict]) -> list[str]:
    """The split of each scene run, then the after/before ratios."""
    lines = ["| geometry | variant | dofs | Newton its (dressing / all) | residuals / it | "
             "Jacobian [ms/it] | "
             "residual [ms/it] | contact [ms/it] | linear [ms/it] | total [ms/it] | "
             "dressing [s] | force [N] |", "|---" * 12 + "|"]  # fmt: skip
    ratios = []
    for r in runs:
        if r["variant"] == "after/before":
            ratios.append(r)
            continue
        if r["status"] != "ok":
            lines.append(f"| {r.get('geometry')} | {r['variant']} | run failed ||||||||||")
            continue
        s = r["split"]
        variant = r["variant"] + "".join(f", {k} = {v}" for k, v in r.get("spec", {}).items())
        lines.append(f"| {r['geometry']} | {variant} | {r['dofs']} | {r['newton_its']} / "
                     f"{r['solver_time_s']['newton_iterations']} | "
                     f"{s['residuals_per_iteration']:.1f} | {s['jacobian_ms']:.0f} | "
                     f"{s['residual_ms']:.0f} | {s['contact_ms']:.0f} | {s['linear_ms']:.0f} | "
                     f"{s['total_ms']:.0f} | {r['dressing_s']:.1f} | "
                     f"{r['contact_force_N']:.6f} |")  # fmt: skip
    if ratios:
        lines += ["", "| geometry | after/before: Jacobian | residual | contact | linear | "
                  "total per it | dressing | Newton its | force change | max Δp95 [kPa] |",
                  "|---|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
        for r in ratios:
            q = r["ratio"]
            lines.append(f"| {r['geometry']} | {q['jacobian_ms']:.2f} | {q['residual_ms']:.2f} | "
                         f"{q['contact_ms']:.2f} | {q['linear_ms']:.2f} | {q['total_ms']:.2f} | "
                         f"{r['dressing_ratio']:.2f} | {r['newton_its'][0]} → "
                         f"{r['newton_its'][1]} | {r['contact_force_rel_change']:.1e} | "
                         f"{r['p95_change_kPa']:.1e} |")  # fmt: skip
    return lines


def _other_tables(data: dict) -> list[str]:
    """The kernel table, the verification table and the run notes."""
    lines: list[str] = []
    k = data.get("kernels")
    if k:
        lines += [
            "",
            f"Kernels, serial, {k['cells']} cells, {k['dofs']} dofs, CPU time per cell "
            f"(fastest / median of {REPEATS} interleaved rounds); `-matrix`: the strains "
            "as matrix products (the formulation before):",
            "",
            "| form | residual [µs/cell] | Jacobian [µs/cell] |",
            "|---|---|---|",
        ]
        for name, v in k["us_per_cell"].items():
            r, j = v["residual"], v["jacobian"]
            if isinstance(r, dict):
                lines.append(f"| {name} | {r['min']:.1f} / {r['median']:.1f} | "
                             f"{j['min']:.1f} / {j['median']:.1f} |")  # fmt: skip
            else:  # an older record: one number
                lines.append(f"| {name} | {r:.1f} | {j:.1f} |")
    v = data.get("verification")
    if v:
        lines += ["", f"Shell verification before/after the kinematics rewrite ({v['how']}):", "",
                  "| case | before | after | reference | relative change | time after/before |",
                  "|---|---|---|---|---|---|"]  # fmt: skip
        for name, c in v["cases"].items():
            lines.append(f"| {name} | {c['before']:.10g} | {c['after']:.10g} | "
                         f"{c['reference']:.6g} | {c['rel_change']:.1e} | "
                         f"{c['time_ratio']:.2f} |")  # fmt: skip
    meta = data.get("meta", {})
    if meta:
        lines += ["", "Run: " + ", ".join(f"{k} = {v}" for k, v in meta.items())]
    return lines


def main(argv: list[str]) -> int:
    from fenics_garment._stack import MPI

    bad = check_args(argv, __doc__, {"--quick"}, (), ("table", "scene", "kernels"))
    if bad is not None:
        return bad
    say = print if MPI.COMM_WORLD.rank == 0 else (lambda *a, **k: None)
    data = _load()
    if "table" in argv:
        say(markdown(data))
        return 0
    mode = "quick" if "--quick" in argv else "default"
    parts = [a for a in argv if a in ("scene", "kernels")] or ["scene", "kernels"]
    meta = data.setdefault("meta", {"note": "shared 2-core machine: ratios within one run only"})
    for part in parts:
        meta[part] = {"mode": mode, "loadavg_start": [round(x, 2) for x in os.getloadavg()]}
    if "scene" in parts and MPI.COMM_WORLD.rank == 0:
        say(f"scene ({mode}): the cotton gilet at {MESH * 1e3:g} mm, 2 ranks")
        data["scene"] = scene(mode, say)
        _save(data)
    if "kernels" in parts:
        say("kernels (serial)")
        data["kernels"] = kernels(say)
    for part in parts:
        meta[part]["loadavg_end"] = [round(x, 2) for x in os.getloadavg()]
    if MPI.COMM_WORLD.rank == 0:
        _save(data)
        say(markdown(data))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
