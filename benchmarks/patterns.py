"""Garments from flat patterns (issue "Garments from sewing patterns"): what the flat rest state
changes, and how robustly pattern garments dress.

``compare``: each shipped scene of :data:`COMPARE` is dressed twice on the same body, mesh, ease
and dressing path: with its body-fitted loft as the stress-free state (``rest = "loft"``, the
scenes' previous model) and with the loft flattened into princess-seamed flat pattern pieces
(``rest = "pattern"``, :mod:`fenics_garment.pattern.flatten`). Per key region: sensor p95,
mean pressure and contact force, and their change loft → pattern.

``sweep``: each pattern garment of :data:`SWEEP` on ``n`` garment meshes evenly spaced in log h;
a run *stalls* when it does not dress or keeps its spring (``benchmarks.sweep.stalled``).

Writes ``benchmarks/results/patterns.json``; ``table`` prints the stored record as Markdown
(the "patterns" section of REPORT.md).

    python -m benchmarks.patterns compare [scene ...]
    python -m benchmarks.patterns sweep [scene ...] [--n N]
    python -m benchmarks.patterns table
"""

from __future__ import annotations

import json
import os
import sys

from benchmarks import check_args, convergence
from benchmarks import scenes as scene_bench
from benchmarks import sweep as sweep_bench

RESULTS = convergence.RESULTS / "patterns.json"
#: the shipped scenes compared loft → pattern, at their shipped meshes
COMPARE = ("cotton_gilet", "nylon_gilet", "cotton_dress")
#: pattern garment scene: (coarsest, finest) garment mesh [m], meshes; "rest-pattern" variant
#: of a built-in scene, or a scene that is a pattern file's (kind = "pattern")
SWEEP = {
    # 10 meshes each, from coarse to the finest that fits the session's hour of sweeping (the
    # shipped 12.4 mm gilet and 22.5 mm dress are in the comparison above)
    "cotton_gilet": (0.040, 0.0175, 10),
    "cotton_dress": (0.050, 0.025, 10),
    "sleeve_on_arm": (0.016, 0.008, 10),
    "compression_stocking": (0.016, 0.008, 10),
    "darted_top": (0.040, 0.0175, 10),
}
KEY = ("waist", "upper_chest", "bust", "underbust", "upper_back")


def _load() -> dict:
    return json.loads(RESULTS.read_text()) if RESULTS.exists() else {}


def _store(section: str, stem: str, recs) -> None:
    data = _load()
    data.setdefault(section, {})[stem] = {"runs": recs, "loadavg": os.getloadavg()}
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(data, indent=1, default=float))


def _variant(stem: str) -> str:
    """The variant that makes ``stem`` a pattern garment (none: it is one already)."""
    from fenics_garment.scene import config

    kind = config.load(convergence.SCENES / f"{stem}.toml").garment.kind
    return "default" if kind == "pattern" else "rest-pattern"


def compare(stem: str, say) -> list[dict]:
    from fenics_garment.scene import config

    h = config.load(convergence.SCENES / f"{stem}.toml").garment.mesh_size
    recs = []
    for rest in ("loft", "pattern"):
        spec = {"scene": str(convergence.SCENES / f"{stem}.toml"), "mesh_size": h,
                "variant": f"rest-{rest}"}  # fmt: skip
        r = dict(scene_bench.spawn(spec, timeout=scene_bench.LEVEL_TIMEOUT), stem=stem, rest=rest)
        say(f"  {rest:8}" + sweep_bench.line(r))
        recs.append(r)
        _store("compare", stem, recs)
    return recs


def sweep(stem: str, say, n: int | None = None) -> list[dict]:
    """Dress ``stem`` on the sweep's meshes; a mesh already in the record (a run that ended,
    stalled or not) is taken from it, so an interrupted sweep continues."""
    import math

    coarse, fine, m = SWEEP[stem]
    known = [r for r in _load().get("sweep", {}).get(stem, {}).get("runs", [])
             if r.get("status") == "ok"]  # fmt: skip
    recs = []
    for h in sweep_bench.meshes(coarse, fine, n or m):
        same = [r for r in known if math.isclose(r["mesh_size"], h, rel_tol=1e-9)]
        if same:
            r = same[-1]
        else:
            spec = {"scene": str(convergence.SCENES / f"{stem}.toml"), "mesh_size": h,
                    "variant": _variant(stem)}  # fmt: skip
            if stem in convergence.PER_TURN:  # a limb's cells follow its curvature: refined
                # in elements per turn with h, as in its convergence study
                spec["per_turn"] = round(convergence.PER_TURN[stem] * coarse / h)
            r = dict(scene_bench.spawn(spec, timeout=scene_bench.LEVEL_TIMEOUT), stem=stem)
        say(sweep_bench.line(r) + ("  (from the record)" if same else ""))
        recs.append(r)
        _store("sweep", stem, recs)
    return recs


def _pct(a: float | None, b: float | None) -> str:
    if a is None or b is None or not a:
        return "–"
    return f"{100 * (b / a - 1):+.0f} %"


def markdown(data: dict | None = None) -> str:
    data = _load() if data is None else data
    out = [
        "Flat pattern pieces against the body-fitted loft as the garment's stress-free state "
        "(`python -m benchmarks.patterns compare`): the same body, ease, mesh and dressing "
        "path; the pattern is the loft flattened (ARAP) into princess-seamed pieces. Per key "
        "region: sensor p95 [kPa], mean [kPa] and contact force [N], loft → pattern.",
        "",
    ]
    for stem, v in data.get("compare", {}).items():
        runs = {r.get("rest"): r for r in v["runs"] if r.get("status") == "ok"}
        if set(runs) != {"loft", "pattern"}:
            out.append(f"{stem}: incomplete ({[r.get('status') for r in v['runs']]})")
            continue
        lo, pa = runs["loft"], runs["pattern"]
        out += [f"**{stem}** ({lo['mesh_size'] * 1e3:.1f} mm, {lo['dofs']} dofs; wall "
                f"{lo['wall_s']:.0f} s → {pa['wall_s']:.0f} s, Newton its {lo['newton_its']} → "
                f"{pa['newton_its']})", "",
                "| region | sensor p95 loft | pattern | change | mean loft | pattern | change "
                "| force loft [N] | pattern | change |", "|---" * 10 + "|"]  # fmt: skip
        for k in KEY:
            row = [k]
            for key, fmt in (("regions_sensor_p95_kPa", ".3f"), ("regions_mean_kPa", ".3f"),
                             ("regions_force_N", ".2f")):  # fmt: skip
                a, b = lo.get(key, {}).get(k), pa.get(key, {}).get(k)
                row += [format(a, fmt) if a is not None else "–",
                        format(b, fmt) if b is not None else "–", _pct(a, b)]  # fmt: skip
            out.append("| " + " | ".join(row) + " |")
        out.append("")
    out += ["Dressing sweep of the pattern garments (`python -m benchmarks.patterns sweep`); a "
            "stall is a run that did not dress or kept its stabilising spring.", "",
            *sweep_bench.TABLE_HEAD]  # fmt: skip
    out += [sweep_bench.table_row(stem, v["runs"]) for stem, v in data.get("sweep", {}).items()]
    kept = [(stem, r["mesh_size"]) for stem, v in data.get("sweep", {}).items()
            for r in v["runs"] if r.get("answer_note")]  # fmt: skip
    if kept:
        out += ["", "Answers converged to the path tolerance only (the last solve at the final "
                "multipliers failed; the last converged multiplier pass is the answer, its "
                "penetration within the tolerance): "
                + ", ".join(f"{s} at {h * 1e3:.1f} mm" for s, h in kept) + "."]  # fmt: skip
    loads = [r["loadavg"][0] for v in data.get("sweep", {}).values() for r in v["runs"]
             if r.get("loadavg")]  # fmt: skip
    if loads:
        out.append(
            f"Machine load (1-min load average on 2 cores) during the runs: "
            f"{min(loads):.1f}–{max(loads):.1f}: wall times are not comparable."
        )
    return "\n".join(out)


def main(argv: list[str]) -> int:
    bad = check_args(argv, __doc__, (), {"--n"}, {"compare", "sweep", "table", *SWEEP, *COMPARE})
    if bad is not None:
        return bad
    say = lambda *a: print(*a, flush=True)  # noqa: E731
    if argv[:1] == ["table"] or not argv:
        print(markdown())
        return 0
    n = int(argv[argv.index("--n") + 1]) if "--n" in argv else None
    if argv[0] == "compare":
        for stem in [a for a in argv[1:] if a in COMPARE] or list(COMPARE):
            say(f"{stem}: loft against pattern")
            compare(stem, say)
    elif argv[0] == "sweep":
        for stem in [a for a in argv[1:] if a in SWEEP] or list(SWEEP):
            say(f"{stem}: pattern sweep")
            sweep(stem, say, n)
    print(markdown())
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
