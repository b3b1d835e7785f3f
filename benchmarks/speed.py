"""Where a Newton iteration's time goes on the cotton gilet, before and after the speed-ups.

Issue 16 ("Fast scenes"), targets 2 and 3: the per-iteration split, measured.


* ``scene``: the cotton gilet demo (``demos/cotton_gilet.toml``, its 35 mm mesh, P2B-P2B) on
  2 ranks, each variant in its own ``mpiexec`` child of :func:`benchmarks.scenes.spawn`, one
  after the other in the same run, so that their ratios are comparable on this shared machine:

  - ``before``: the contact search as it was (:data:`BEFORE`) — on straight-sided cells every
    contact point of every cell searched (the lumped rule's 7 points, none shared), and the
    smooth body's Hessian computed at every residual evaluation;
  - ``after``: each distinct point searched once (``ContactState._unique``) and the Hessian
    computed only before a Jacobian (``ContactState.update_hessian``).

  Both on the straight-sided garment (``geometry = "straight"``, where point sharing is new) and
  on the curved one (the demo's default, where it was already shared). Per Newton iteration:
  Jacobian assembly, residual assembly, contact refresh (search and Hessian, inside the residual
  and Jacobian callbacks), the linear solve (factorisation + solve + SNES); and the answer
  (Newton iterations, contact force, largest change of a region's p95 pressure) beside it.
* ``kernels``: µs per cell and evaluation of the residual and Jacobian kernels on the gilet
  (serial, warm JIT cache): the whole forms, the contact part alone, the shell part as their
  difference.

Writes ``benchmarks/results/speed.json`` and prints the tables.

    python -m benchmarks.speed [scene] [kernels] [--quick]
    python -m benchmarks.speed table       (the stored record as Markdown)
"""

from __future__ import annotations

import json
import os
import sys
import time

from benchmarks import scenes

RESULTS = scenes.RESULTS / "speed.json"
MESH = 0.035  # the demo's garment mesh [m]
#: the contact search as on main before these changes (0ecc1c5): straight-sided cells shared no
#: point, curved (order-2) ones did (their edge midpoints are geometry nodes); the Hessian was
#: computed at every residual
BEFORE = {
    "straight": {"share_points": False, "contact_hessian": "always"},
    "curved": {"contact_hessian": "always"},
}
GEOMETRIES = {"quick": ["curved"], "default": ["straight", "curved"]}
REPEATS = 5  # kernel timings: the fastest of this many assemblies


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


# --------------------------------------------------------------------------------------------
# kernels: µs per cell
# --------------------------------------------------------------------------------------------
def _best(work, repeats: int = REPEATS) -> float:
    """The fastest of ``repeats`` calls of ``work()`` [s] (after one warm-up call)."""
    work()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        work()
        times.append(time.perf_counter() - t0)
    return min(times)


def kernels(say) -> dict:
    """Residual and Jacobian assembly of the gilet's forms, whole and contact-only (serial)."""
    from dataclasses import replace

    from dolfinx.fem import petsc as fp

    from fenics_garment._stack import MPI, dolfinx
    from fenics_garment.scene import build as scene_build
    from fenics_garment.scene import config
    from fenics_garment.solve import JIT_OPTIONS

    s = config.load(scenes.GILET)
    s = replace(s, garment=replace(s.garment, mesh_size=MESH))
    built = scene_build.build(s, MPI.COMM_WORLD)
    model = built.model
    built.contact.refresh()
    F = model.residual()
    parts = {"whole": (F, model.jacobian(F))}
    contact = sum(model._extra_residual[1:], model._extra_residual[0])
    parts["contact"] = (contact, model.jacobian(contact))
    cells = model.geometry.mesh.topology.index_map(2).size_local
    out = {"cells": cells, "dofs": model.Q.dofmap.index_map.size_global
           * model.Q.dofmap.index_map_bs, "us_per_cell": {}}  # fmt: skip
    for name, (f, j) in parts.items():
        t0 = time.perf_counter()
        ff = dolfinx.fem.form(f, jit_options=JIT_OPTIONS)
        jf = dolfinx.fem.form(j, jit_options=JIT_OPTIONS)
        jit = time.perf_counter() - t0
        A = fp.create_matrix(jf)
        b = fp.create_vector(ff.function_spaces[0])

        def vec(b=b, ff=ff) -> None:
            with b.localForm() as bl:
                bl.set(0.0)
            fp.assemble_vector(b, ff)

        def mat(A=A, jf=jf) -> None:
            A.zeroEntries()
            fp.assemble_matrix(A, jf)
            A.assemble()

        out["us_per_cell"][name] = {"residual": 1e6 * _best(vec) / cells,
                                    "jacobian": 1e6 * _best(mat) / cells, "jit_s": jit}  # fmt: skip
        A.destroy()
        b.destroy()
    w, c = out["us_per_cell"]["whole"], out["us_per_cell"]["contact"]
    out["us_per_cell"]["shell"] = {k: w[k] - c[k] for k in ("residual", "jacobian")}
    for name, v in out["us_per_cell"].items():
        say(f"  {name:8s} residual {v['residual']:7.1f} µs/cell, Jacobian {v['jacobian']:7.1f} "
            f"µs/cell")  # fmt: skip
    return out


# --------------------------------------------------------------------------------------------
# Markdown (benchmarks/report.py) and the command line
# --------------------------------------------------------------------------------------------
def markdown(data: dict) -> str:
    """The per-iteration split of every scene run, the after/before ratios, the kernel table."""
    lines = ["| geometry | variant | dofs | Newton its (dressing / all) | residuals / it | "
             "Jacobian [ms/it] | "
             "residual [ms/it] | contact [ms/it] | linear [ms/it] | total [ms/it] | "
             "dressing [s] | force [N] |", "|---" * 12 + "|"]  # fmt: skip
    ratios = []
    for r in data.get("scene", []):
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
    k = data.get("kernels")
    if k:
        lines += ["", f"Kernels, serial, {k['cells']} cells, {k['dofs']} dofs (fastest of "
                  f"{REPEATS} assemblies):", "", "| form | residual [µs/cell] | "
                  "Jacobian [µs/cell] |", "|---|---|---|"]  # fmt: skip
        for name, v in k["us_per_cell"].items():
            lines.append(f"| {name} | {v['residual']:.1f} | {v['jacobian']:.1f} |")
    meta = data.get("meta", {})
    if meta:
        lines += ["", "Run: " + ", ".join(f"{k} = {v}" for k, v in meta.items())]
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    from fenics_garment._stack import MPI

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
