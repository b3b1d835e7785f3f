"""Mesh noise of the region pressures: one scene on several garment meshes of about one size.

gmsh meets a target size h with a mesh whose layout (the number of edges on each curve, hence
every node) jumps when h crosses a value at which a curve's length is a whole number of h —
the dress at 15.9 mm on the 7.5 mm body gave 158,580 dofs at h = 0.015909902… m and 158,688 at
0.0159099 m, and an upper-chest sensor p95 of 0.804 against 0.770 kPa. A region statistic on
one mesh of size h therefore carries a part that is not a smooth function of h, the *mesh
noise*. This benchmark dresses a scene on ``n`` meshes of sizes h (1 + k δ), k = 0 … n − 1,
δ = 0.5 % (enough to change the layout; a statistic converging at order p moves by about
p δ of its discretisation error, negligible beside the √2 ratio of the convergence levels),
through ``benchmarks.scenes.spawn`` (2 ranks, the scene as shipped), and records per key region
the mean, the sample standard deviation and the range of the p95, the sensor p95 and the mean
pressure. Level-to-level changes of a convergence study within this noise do not show an order,
and an error bar smaller than the noise is not credible.

Writes ``benchmarks/results/mesh_noise.json`` (section "mesh_noise" of REPORT.md).

    python -m benchmarks.mesh_noise [scene[@h] ...] [--n N] [--variant body-0.0075] [--delta δ]

``scene@h``: the garment size h [m] instead of the scene's own (e.g. ``cotton_gilet@0.0123744``).
"""

from __future__ import annotations

import json
import os
import statistics
import sys

from benchmarks import check_args, convergence
from benchmarks import scenes as scene_bench
from benchmarks.targets import default_mesh

RESULTS = convergence.RESULTS / "mesh_noise.json"
#: Relative change of the target size between the meshes (module doc).
DELTA = 0.005
STATS = ("p95", "sensor_p95", "body_sensor_p95", "mean")


def run(stem: str, h: float, n: int, variant: str, say, delta: float = DELTA) -> list[dict]:
    recs = []
    for k in range(n):
        size = h * (1.0 + k * delta)
        spec = {"scene": str(convergence.SCENES / f"{stem}.toml"), "mesh_size": size,
                "variant": variant}  # fmt: skip
        r = scene_bench.spawn(spec, timeout=scene_bench.LEVEL_TIMEOUT)
        recs.append(r)
        if r["status"] != "ok":
            say(f"  {stem} h = {size!r}: FAILED ({r.get('error', '')[-200:]!r})")
            continue
        say(f"  {stem} h = {size!r}  {r['dofs']} dofs  {r['newton_its']} its  "
            f"{r['failed_attempts']} failed  completed {r['completed']}  "
            f"{r['wall_s']:.0f} s")  # fmt: skip
    return recs


def analyse(recs: list[dict]) -> dict:
    """Per key region and statistic: values, mean, standard deviation and range (relative)."""
    ok = [r for r in recs if r.get("status") == "ok" and r.get("completed")]
    out: dict = {"meshes": len(ok), "dofs": [r["dofs"] for r in ok], "regions": {}}
    if len(ok) < 2:
        return out
    # gmsh may mesh a garment identically at nearby sizes (the dress at 30 mm did, δ = 0.5 %):
    # then nothing was measured, and a zero deviation must not read as "no noise"
    same = {json.dumps(r.get("regions_p95_kPa"), sort_keys=True) for r in ok}
    if len(same) == 1:
        out["identical"] = True
        return out
    for name in convergence.KEY_REGIONS:
        row = {}
        for s in STATS:
            vals = [r.get(f"regions_{s}_kPa", {}).get(name) for r in ok]
            if any(v is None for v in vals):
                continue
            m, sd = statistics.fmean(vals), statistics.stdev(vals)
            row[s] = {"values": vals, "mean": m, "std": sd,
                      "rel_std": sd / m if m else float("nan"),
                      "rel_range": (max(vals) - min(vals)) / m if m else float("nan")}  # fmt: skip
        out["regions"][name] = row
    return out


def markdown(d: dict) -> str:
    out = ["Mesh noise (`python -m benchmarks.mesh_noise`): each scene on garment meshes "
           "whose target sizes differ by a small relative step; per key region the values of "
           "each statistic [kPa], their standard deviation and range relative to their mean.",
           ""]  # fmt: skip
    for key, sc in d.get("scenes", {}).items():
        ana = sc.get("analysis", {})
        dofs = " / ".join(str(x) for x in ana.get("dofs", []))
        delta = sc.get("delta", DELTA)
        out += [f"### {key}", "", f"{ana.get('meshes', 0)} meshes (sizes h × (1 + k · {delta:g})), "
                f"dofs {dofs}.", ""]  # fmt: skip
        if ana.get("identical"):
            out += ["gmsh made the same mesh at every size: no noise measured (use a larger "
                    "`--delta`).", ""]  # fmt: skip
            continue
        out += ["| region | statistic | values | std | range |", "|---|---|---|---|---|"]
        for name, row in ana.get("regions", {}).items():
            for s, c in row.items():
                vals = " / ".join(f"{v:.3f}" for v in c["values"])
                out.append(f"| {name} | {s} | {vals} | {c['rel_std']:.1%} | "
                           f"{c['rel_range']:.1%} |")  # fmt: skip
        out.append("")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    bad = check_args(argv, __doc__, (), {"--n", "--variant", "--delta"},
                     lambda a: a.partition("@")[0] in convergence.LEVELS)  # fmt: skip
    if bad is not None:
        return bad
    n = int(argv[argv.index("--n") + 1]) if "--n" in argv else 3
    variant = argv[argv.index("--variant") + 1] if "--variant" in argv else "default"
    delta = float(argv[argv.index("--delta") + 1]) if "--delta" in argv else DELTA
    flags = {"--n", "--variant", "--delta"}
    names = [a for i, a in enumerate(argv) if not a.startswith("--")
             and (i == 0 or argv[i - 1] not in flags)] or ["cotton_gilet"]  # fmt: skip
    say = lambda *a: print(*a, flush=True)  # noqa: E731
    data = json.loads(RESULTS.read_text()) if RESULTS.exists() else {"scenes": {}}
    for name in names:
        stem, _, h = name.partition("@")
        size = float(h) if h else default_mesh(stem)
        key = f"{stem}@{size * 1e3:.1f}mm" + ("" if variant == "default" else f":{variant}")
        say(f"{key}: {n} meshes")
        recs = run(stem, size, n, variant, say, delta)
        data["scenes"][key] = {"runs": recs, "analysis": analyse(recs), "delta": delta,
                               "loadavg": os.getloadavg()}  # fmt: skip
        if data["scenes"][key]["analysis"].get("identical"):
            say(f"    the {n} meshes are identical: no noise measured; use a larger --delta")
        RESULTS.parent.mkdir(exist_ok=True)
        RESULTS.write_text(json.dumps(data, indent=1, default=float))
        for rname, row in data["scenes"][key]["analysis"].get("regions", {}).items():
            say("    " + rname.ljust(12) + "  ".join(
                f"{s} {c['mean']:.3f} ± {c['rel_std']:.1%} (range {c['rel_range']:.1%})"
                for s, c in row.items()))  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
