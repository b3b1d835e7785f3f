"""Robust dressing (issue "Trustworthy scene answers", item 5): a sweep of garment meshes per scene.

Each scene of :data:`SWEEP` is dressed on ``n`` garment meshes spaced evenly in log h from the
coarsest to the finest level of its convergence study (``benchmarks/convergence.py``), with the
scene's element, contact and dressing schedule as shipped; a run *stalls* when it does not dress
(``completed`` false) or keeps a spring (c > 0 at the end). Runs of the convergence study on the
same mesh and schedule are taken from its record instead of being run again, and so are the
sweep's own earlier runs (an interrupted sweep continues). The limbs and the tube are swept on
the three levels of their convergence study (they are refined in elements per turn as well as in
h, ``convergence.PER_TURN``), read from its record.

Per run: dressed, spring released, solves, Newton iterations, cuts (failed tries), the largest
penetration over the thickness, wall time. Writes ``benchmarks/results/sweep.json``.

    python -m benchmarks.sweep [scene ...] [--n N]      (default: the scenes of SWEEP)
    python -m benchmarks.sweep table                     (the stored record as Markdown)
"""

from __future__ import annotations

import json
import math
import os
import sys
from dataclasses import replace

from benchmarks import check_args, convergence
from benchmarks import scenes as scene_bench

RESULTS = convergence.RESULTS / "sweep.json"
#: Scene: (coarsest, finest) garment mesh [m] and the number of meshes. 11 meshes put the
#: convergence study's levels h₀, h₀/√2, h₀/2 on the sweep (k = 0, 5, 10); the gilets' reach their
#: shipped levels, h₀/(2√2) for the cotton one (13 meshes) and h₀/4 for the nylon one (17), with
#: the study's levels at k = 0, 4, 8, …
SWEEP = {
    "cotton_gilet": (0.035, 0.035 * (2**-0.5) ** 3, 13),  # as the study's levels: bit for bit
    "nylon_gilet": (0.035, 0.035 * (2**-0.5) ** 4, 17),
    "cotton_dress": (0.045, 0.0225, 11),
}
#: Swept on the three levels of the convergence study (its record).
LEVELS_ONLY = ("sleeve_on_arm", "compression_stocking", "tube_on_cylinder")


def meshes(coarse: float, fine: float, n: int) -> list[float]:
    """``n`` sizes from ``coarse`` to ``fine``, evenly spaced in log h."""
    return [fine if k == n - 1 else coarse * (fine / coarse) ** (k / (n - 1)) for k in range(n)]


def _load(path) -> dict:
    return json.loads(path.read_text()) if path.exists() else {}


def stalled(r: dict) -> bool:
    """Not dressed, or dressed with the stabilising spring kept (c > 0)."""
    if r.get("status") != "ok" or r["final_regularisation"] > 0:
        return True
    return not r["completed"] and not above_tolerance(r)


def above_tolerance(r: dict) -> bool:
    """Dressed and released, but the augmented Lagrangian's multiplier updates ended with the
    penetration above its tolerance (``completed`` false, the message says so)."""
    return (r.get("status") == "ok" and not r["completed"] and r["final_regularisation"] == 0
            and "augmented Lagrangian" in r.get("message", ""))  # fmt: skip


def _known(stem: str) -> list[dict]:
    """Completed earlier runs of ``stem`` on the current schedule, release and dressing path
    (path tolerance, release multipliers) of the shipped scene (convergence and sweep; a record
    from before the release was recorded is run again, and so is a run that ended above the
    penetration tolerance or stalled)."""
    from fenics_garment.scene import config

    conv = _load(convergence.RESULTS / "convergence.json").get("scenes", {}).get(stem, {})
    mine = _load(RESULTS).get("scenes", {}).get(stem, {})
    release = scene_bench.release_settings()
    shipped = config.load(convergence.SCENES / f"{stem}.toml").dressing
    path = replace(shipped, sequence=[]).path()  # the sweep runs the direct path
    return [r for r in conv.get("runs", []) + mine.get("runs", [])
            if r.get("status") == "ok" and r.get("completed")
            and convergence.same_path(r, stem, "default")
            and r.get("release") == release
            and scene_bench.dressing_path(r) == path
            and r.get("variant", "default") == "default"]  # fmt: skip


def sweep(stem: str, say) -> list[dict]:
    coarse, fine, n = SWEEP[stem]
    known = _known(stem)
    recs = []
    for h in meshes(coarse, fine, n):
        same = [r for r in known if math.isclose(r["mesh_size"], h, rel_tol=1e-9)]
        if same:
            r = same[-1]
        else:
            spec = {"scene": str(convergence.SCENES / f"{stem}.toml"), "mesh_size": h}
            r = dict(scene_bench.spawn(spec, timeout=scene_bench.LEVEL_TIMEOUT), stem=stem)
        recs.append(r)
        say(line(r) + ("  (from the record)" if same else ""))
        _store(stem, recs)
    return recs


def _store(stem: str, recs: list[dict]) -> None:
    data = _load(RESULTS) or {"scenes": {}}
    data["scenes"][stem] = {"runs": recs, "loadavg": os.getloadavg()}
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(data, indent=1, default=float))


def line(r: dict) -> str:
    h = f"{r['mesh_size'] * 1e3:5.1f} mm"
    if r.get("status") != "ok":
        return f"  {h}: FAILED {r.get('error', '')[-160:]!r}"
    state = "STALLED" if stalled(r) else ("pen>tol" if above_tolerance(r) else "released")
    return (f"  {h} {r['dofs']:7d} dofs  {state:8}  solves {r['solves']:2d}  its "
            f"{r['newton_its']:3d}  cuts {r['failed_attempts']}  penetration "
            f"{r['max_penetration_over_thickness']:.2%} h  {r['wall_s']:6.1f} s")  # fmt: skip


TABLE_HEAD = [
    "| scene | meshes | h [mm] | dofs | stalls | penetration > tolerance | solves | "
    "Newton its | cuts | max penetration / h | wall [s] |",
    "|---" * 11 + "|",
]


def table_row(stem: str, runs: list[dict]) -> str:
    """One scene's sweep as a row of :data:`TABLE_HEAD`: spans over its runs, stalls counted."""
    ok = [r for r in runs if r.get("status") == "ok"]
    if not ok:
        return f"| {stem} | {len(runs)} | | | {len(runs)} |" + " |" * 6
    hs = [r["mesh_size"] * 1e3 for r in runs]

    def span(key: str) -> str:
        return f"{min(r[key] for r in ok)}–{max(r[key] for r in ok)}"

    pen = max(r["max_penetration_over_thickness"] for r in ok)
    return (f"| {stem} | {len(runs)} | {max(hs):.1f}–{min(hs):.1f} | "
            f"{min(r['dofs'] for r in ok)}–{max(r['dofs'] for r in ok)} | "
            f"{sum(stalled(r) for r in runs)} | {sum(above_tolerance(r) for r in runs)} | "
            f"{span('solves')} | {span('newton_its')} | {span('failed_attempts')} | {pen:.2%} | "
            f"{min(r['wall_s'] for r in ok):.0f}–{max(r['wall_s'] for r in ok):.0f} |")  # fmt: skip


def markdown(data: dict | None = None) -> str:
    """Per scene: the runs of the sweep and the limbs' convergence levels, and the stalls."""
    data = _load(RESULTS) if data is None else data
    conv = _load(convergence.RESULTS / "convergence.json").get("scenes", {})
    out = ["Dressing sweep (`python -m benchmarks.sweep`): every garment mesh from the coarsest "
           "to the finest converged level; a stall is a run that did not dress or kept its "
           "stabilising spring.", "", *TABLE_HEAD]  # fmt: skip
    rows = [(s, v["runs"]) for s, v in data.get("scenes", {}).items()]
    rows += [(s, conv[s]["runs"]) for s in LEVELS_ONLY if s in conv]
    out += [table_row(stem, runs) for stem, runs in rows]
    schedules = {r.get("schedule") for _, runs in rows for r in runs if r.get("status") == "ok"}
    out += ["", f"Dressing schedule of the runs: {', '.join(sorted(map(str, schedules)))}."]
    return "\n".join(out)


def main(argv: list[str]) -> int:
    bad = check_args(argv, __doc__, (), {"--n"}, {*SWEEP, "table"})
    if bad is not None:
        return bad
    if argv[:1] == ["table"]:
        print(markdown())
        return 0
    say = lambda *a: print(*a, flush=True)  # noqa: E731
    names = [a for a in argv if a in SWEEP] or list(SWEEP)
    for stem in names:
        coarse, fine, _ = SWEEP[stem]
        if "--n" in argv:
            SWEEP[stem] = (coarse, fine, int(argv[argv.index("--n") + 1]))
        say(f"{stem}: {SWEEP[stem][2]} garment meshes {coarse * 1e3:.1f} … {fine * 1e3:.1f} mm")
        sweep(stem, say)
    print(markdown())
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
