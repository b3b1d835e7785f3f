"""Garment-mesh convergence of the demo scenes: per region, mean / p95 / max pressure on a
sequence of garment meshes, the observed order, the Richardson extrapolation and error bars.

Each scene of :data:`LEVELS` is run (``fenics_garment.scene.run.run`` through
``benchmarks.scenes.spawn``: its own ``mpiexec -n 2`` subprocess, no VTX/XDMF/pictures) on
garment mesh sizes h₀, h₀/√2, h₀/2, … (the ratio of the issue "Trustworthy scene answers"),
with the scene's element and contact as shipped. For every region and statistic the last three
levels give :func:`fenics_garment.scene.error_bars.three_level` (observed order, extrapolated
value, grid convergence index of each level). The scene's own ``--error-bars`` estimate at a
level (Richardson with h and √2 h, rate 1) is set beside the three-level error there, so the two
can be compared; the record says which level meets the ±3 % target for the p95 of the key
regions.

Writes ``benchmarks/results/convergence.json`` and ``convergence-<scene>.png``.

    python -m benchmarks.convergence [--quick] [scene ...] [--levels N] [--reuse]
                                     [--variant friction-off|adaptive|steps-8|…]
    python -m benchmarks.convergence --reanalyse

With ≥ 4 levels every statistic also gets :func:`fenics_garment.scene.error_bars.least_squares`
(the fit of all levels after Eça & Hoekstra, made for scattered data; its coverage of the true
error on synthetic data is measured by ``benchmarks.estimators``). ``--reanalyse`` recomputes
the analysis and plot of every stored record from its runs, running nothing.

``--reuse`` keeps the stored completed runs of the same levels and dressing schedule and runs
only the missing ones (e.g. a fourth level). ``--variant adaptive`` dresses with the adaptive
schedule (``[dressing] schedule``; key ``<scene>:adaptive``).

``--variant steps-8`` (8 grow steps), ``friction-growing`` (``[dressing]
friction_while_growing``) and their combination ``friction-growing+steps-8`` measure the
dressing path's part of a frictional answer: the same meshes with twice the grow steps, and
with friction on while the body grows. ``anchor-start`` (``[dressing] spring_anchor``) anchors
the dressing spring at the garment as placed instead of the previous solve, ``release-R`` takes
the factor R per release solve (``release_ratio``) and ``spring-X`` the spring c₀ = X E h / L²
(``regularisation``); any of these combine with ``+``. ``body-X`` meshes the body with
triangles of X m instead of the scene's (e.g. ``body-0.0075``: the garment levels on a body finer
than the finest garment, so the garment's part of the error is measured alone).
``armhole-R`` refines the armholes to cells of R × h (``[garment] refine_edges``, ``edge_ratio``;
a graded sequence: every level's edge cells shrink with its h). ``penalty-X`` sets ``[physics]
penalty_length`` to X m, ``penalty-cells`` to 0 (κ scaled by the garment's cells, as every
record made before that key existed: those without a ``penalty_length`` in their runs).
``kappa-X`` sets the penalty scale ``[physics] kappa_hat`` to X. ``predictor-secant`` starts
each grow step's Newton from the secant of the last two (``[dressing] predictor``).

``--variant friction-off`` (μ = 0, recorded as ``<scene>:friction-off``) takes friction out: a
frictionless answer does not depend on the dressing path, so its convergence isolates the
discretisation error of the shell and the contact from whatever shapes a frictional one (the
path, the stick stiffness, the spring).
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from pathlib import Path

from benchmarks import check_args
from benchmarks import scenes as scene_bench
from fenics_garment.scene.error_bars import STATS, least_squares, richardson_error, three_level

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RESULTS = HERE / "results"
SCENES = ROOT / "fenics_garment" / "scenes"
RATIO = 2.0**-0.5
#: Coarsest garment mesh size [m] and number of levels per scene.
LEVELS = {
    "cotton_gilet": (0.035, 4),
    "nylon_gilet": (0.035, 4),
    "cotton_dress": (0.045, 4),
    "sleeve_on_arm": (0.014, 3),
    "compression_stocking": (0.016, 3),
    "tube_on_cylinder": (0.02, 3),
}
#: Limbs are meshed with at most h and with a number of elements per turn of curvature
#: (``[garment] per_turn``): both are refined by the ratio, from this coarsest count.
PER_TURN = {"sleeve_on_arm": 17, "compression_stocking": 12}
QUICK = {"tube_on_cylinder": (0.04, 3)}
#: Regions whose p95 the issue asks to know to ±3 %.
KEY_REGIONS = ("waist", "upper_chest", "bust", "underbust", "upper_back")
#: The percentile statistics the study judges: the suffix of their verdicts' keys
#: (``key<suffix>_p95_within_target``) and their label.
P95_STATS = {
    "p95": ("", "p95"),
    "sensor_p95": ("_sensor", "p95 of a 2 cm sensor's reading"),
    "body_sensor_p95": ("_body_sensor", "p95 of a 2 cm sensor on the skin"),
}
TARGET = 0.03


def sizes(h0: float, n: int) -> list[float]:
    return [h0 * RATIO**k for k in range(n)]


def run_scene(stem: str, h0: float, n: int, say, variant: str = "default",
              known: list[dict] = ()) -> list[dict]:  # fmt: skip
    """The runs of ``stem`` on ``n`` levels from ``h0``; a completed run of ``known`` on the same
    mesh with the scene's current dressing schedule is kept instead of being run again."""
    recs = []
    for k, h in enumerate(sizes(h0, n)):
        same = [r for r in known if r.get("status") == "ok" and math.isclose(r["mesh_size"], h)
                and same_path(r, stem, variant)]  # fmt: skip
        if same:
            recs.append(same[-1])
            say(f"  {stem} h = {h * 1e3:5.1f} mm  kept from the record")
            continue
        t0 = time.perf_counter()
        spec = {"scene": str(SCENES / f"{stem}.toml"), "mesh_size": h, "variant": variant}
        if stem in PER_TURN:
            spec["per_turn"] = round(PER_TURN[stem] / RATIO**k)
        r = scene_bench.spawn(spec, timeout=scene_bench.LEVEL_TIMEOUT)
        r["stem"] = stem
        recs.append(r)
        if r["status"] != "ok":
            say(f"  {stem} h = {h * 1e3:.1f} mm: FAILED ({r.get('error', '')[-200:]!r})")
            continue
        pen = r.get("max_penetration_over_thickness", float("nan"))
        say(f"  {stem} h = {h * 1e3:5.1f} mm  {r['dofs']:7d} dofs  {r['solves']:2d} solves  "
            f"{r['newton_its']:3d} its  {r['failed_attempts']} failed  completed "
            f"{r['completed']}  c_final {r['final_regularisation']:.2g}  penetration "
            f"{pen:.2%} h  {time.perf_counter() - t0:6.1f} s")  # fmt: skip
    return recs


#: Grow steps of the records made before they were recorded: every garment scene then had 4
#: (the dress has 5 since its third step of 4 failed once on the shipped mesh).
LEGACY_GROW_STEPS = 4


def same_path(rec: dict, stem: str, variant: str) -> bool:
    """Whether ``rec`` was dressed along the path a run of ``stem`` with ``variant`` takes now:
    the same schedule and number of grow steps (both change a frictional answer), and the same
    stress-free state of the garment (loft or flat pattern pieces)."""
    steps = scene_bench.grow_steps(variant, config_steps(stem))
    return (rec.get("schedule") == schedule_of(stem, variant)
            and rec.get("grow_steps", LEGACY_GROW_STEPS) == steps
            and rec.get("rest", "loft") == rest_of(stem, variant)
            and record_body(rec, stem) == body_of(stem, variant))  # fmt: skip


def body_of(stem: str, variant: str) -> str:
    """The body a run of ``stem`` with ``variant`` dresses (:func:`benchmarks.scenes.body_label`;
    the variant "human" puts a mannequin scene's garment on the human)."""
    return _shipped_body(stem, human=True if "human" in variant.split("+") else None)


def record_body(rec: dict, stem: str) -> str:
    """The body of a record; one made before records named it was on the shipped scene's body
    as it was then: the dress form for a mannequin (the human only with the variant "human")."""
    if rec.get("body"):
        return rec["body"]
    return _shipped_body(stem, human="human" in str(rec.get("variant", "")).split("+"))


def _shipped_body(stem: str, human: bool | None) -> str:
    """The label (:func:`benchmarks.scenes.body_label`) of the shipped scene ``stem``'s body,
    with ``human`` set to the given value (None: as shipped)."""
    from dataclasses import replace

    from fenics_garment.scene import config

    b = config.load(SCENES / f"{stem}.toml").body
    return scene_bench.body_label(b if human is None else replace(b, human=human))


def rest_of(stem: str, variant: str) -> str:
    """The garment's stress-free state a run of ``stem`` with ``variant`` has (a record made
    before it was recorded: "loft", the only one then)."""
    from fenics_garment.scene import config

    for part in variant.split("+"):
        if part.startswith("rest-"):
            return part[len("rest-") :]
    return config.load(SCENES / f"{stem}.toml").garment.rest


def config_steps(stem: str) -> int:
    """The grow steps of the shipped scene ``stem``."""
    from fenics_garment.scene import config

    return config.load(SCENES / f"{stem}.toml").dressing.steps


def schedule_of(stem: str, variant: str) -> str:
    """The dressing schedule a run of ``stem`` with ``variant`` uses (benchmarks.scenes.child)."""
    from fenics_garment.scene import config

    return "adaptive" if variant == "adaptive" else config.load(
        SCENES / f"{stem}.toml").dressing.schedule  # fmt: skip


def analyse(recs: list[dict]) -> dict:
    """Per region and statistic: values per level, observed order, extrapolation, errors."""
    ok = [r for r in recs if r["status"] == "ok"]  # incomplete ones are flagged, not dropped
    out: dict = {"sizes": [r["mesh_size"] for r in ok], "dofs": [r["dofs"] for r in ok],
                 "completed": [r["completed"] for r in ok],
                 "penetration_over_thickness": [r["max_penetration_over_thickness"] for r in ok],
                 "regions": {}}  # fmt: skip
    if len(ok) < 3:
        out["note"] = f"only {len(ok)} completed levels: no three-level estimate"
        return out
    hs = [r["mesh_size"] for r in ok]
    for name in ok[-1]["regions_p95_kPa"]:
        row = {}
        for s in STATS:
            if any(f"regions_{s}_kPa" not in r for r in ok):  # a record from before the statistic
                continue
            vals = [r[f"regions_{s}_kPa"].get(name, 0.0) for r in ok]
            if max(vals) <= 0.0:
                continue
            conv = three_level(hs, vals)
            row[s] = conv.as_dict()
            rel = [e / abs(v) if v else math.inf for e, v in zip(conv.error, vals, strict=True)]
            row[s]["relative_error"] = rel
            # the scene's own --error-bars estimate at each level (its coarse level: the one
            # before, √2 h)
            own = [math.nan] * len(vals)
            for k in range(1, len(vals)):
                own[k] = richardson_error(vals[k], vals[k - 1])
            row[s]["error_bars_estimate"] = own
            if len(vals) >= 4:  # all levels, fitted (made for scattered data)
                ls = least_squares(hs, vals)
                row[s]["least_squares"] = {
                    **ls.as_dict(),
                    "relative_error": [
                        e / abs(v) if v else math.inf for e, v in zip(ls.error, vals, strict=True)
                    ],
                }
        if row:
            out["regions"][name] = row
    for s, (key, _) in P95_STATS.items():
        met = [all(out["regions"][n][s]["relative_error"][k] <= TARGET
                   for n in KEY_REGIONS if s in out["regions"].get(n, {}))
               for k in range(len(ok))]  # fmt: skip
        if any(s in row for row in out["regions"].values()):
            out[f"key{key}_p95_within_target"] = met
            out[f"coarsest{key}_meeting_target_m"] = next(
                (h for h, m in zip(hs, met, strict=True) if m), None
            )
        rows = {n: out["regions"][n][s] for n in KEY_REGIONS if s in out["regions"].get(n, {})}
        if rows and all("least_squares" in c for c in rows.values()):
            out[f"key{key}_p95_least_squares_met"] = [
                n for n, c in rows.items() if c["least_squares"]["relative_error"][-1] <= TARGET
            ]
    return out


def markdown(d: dict) -> str:
    """The report's "convergence" section: per scene, runs and per-region p95 over the meshes."""
    out = ["Garment-mesh convergence (`python -m benchmarks.convergence`): per scene the runs, "
           "then per region the p95 [kPa] on each mesh, the observed order (nan: not monotone), "
           "the finest value's uncertainty (`scene.error_bars.three_level`) and the scene's own "
           "`--error-bars` estimate at the finest mesh (h against √2 h, rate 1).", ""]  # fmt: skip
    for stem, sc in d.get("scenes", {}).items():
        ana = sc.get("analysis", {})
        runs = [r for r in sc.get("runs", []) if r.get("status") == "ok"]
        degree = runs[0].get("geometry_degree") or 1 if runs else None
        geometry = {1: "straight-sided (order 1)", 2: "curved (order 2)"}.get(degree, "?")
        out += [f"### {stem}", "", sc.get("note", ""),
                f"Element {runs[0]['element'] if runs else '?'}, garment geometry {geometry}.", "",
                "| h [mm] | dofs | solves | Newton its | failed tries | completed | "
                "penetration / h | wall [s] |", "|---|---|---|---|---|---|---|---|"]  # fmt: skip
        for r in sc.get("runs", []):
            if r.get("status") != "ok":
                out.append(f"| {1e3 * r['mesh_size']:.1f} | failed | | | | | | |")
                continue
            out.append(
                f"| {1e3 * r['mesh_size']:.1f} | {r['dofs']} | {r['solves']} | "
                f"{r['newton_its']} | {r['failed_attempts']} | {r['completed']} | "
                f"{r['max_penetration_over_thickness']:.2%} | {r['wall_s']:.0f} |"
            )
        out += force_table(runs)
        for s, (suffix, label) in P95_STATS.items():
            rows = [(n, row[s]) for n, row in ana.get("regions", {}).items() if s in row]
            if not rows:
                continue
            out += ["", f"| region | {label} per mesh | order | finest ± uncertainty | "
                    "--error-bars | least squares: finest ± U (order, fit) |",
                    "|---|---|---|---|---|---|"]  # fmt: skip
            for name, c in rows:
                vals = " / ".join(f"{v:.3f}" for v in c["values"])
                ls = c.get("least_squares")
                lsq = (f"± {ls['error'][-1]:.3f} ({ls['relative_error'][-1]:.1%}; "
                       f"{ls['order']:.2f}, {ls['fit']})" if ls else "–")  # fmt: skip
                out.append(
                    f"| {name} | {vals} | {c['order']:.2f} | {c['values'][-1]:.3f} ± "
                    f"{c['error'][-1]:.3f} | {c['error_bars_estimate'][-1]:.3f} | {lsq} |"
                )
            key = f"key{suffix}_p95_within_target"
            out += ["", f"Key regions' {label} within ±{TARGET:.0%} at each mesh: "
                    f"{ana.get(key)}", ""]  # fmt: skip
            met = ana.get(key.replace("_within_target", "_least_squares_met"))
            if met is not None:
                out += [f"Within ±{TARGET:.0%} at the finest mesh by the least-squares "
                        f"estimate: {len(met)} of {len(KEY_REGIONS)} "
                        f"({', '.join(met) or 'none'}).", ""]  # fmt: skip
        png = f"convergence-{stem.replace(':', '-')}.png"
        if (RESULTS / png).exists():
            out += [f"![convergence-{stem}]({png})", ""]
    return "\n".join(out)


def force_table(runs: list[dict]) -> list[str]:
    """Rows of the key regions' normal force [N] and contact area [cm²] per mesh (records that
    keep them: ``regions_force_N``; "–" for older ones). A region whose force is steady while
    its pressures rise is being pressed on a smaller area, not loaded more."""
    if not any(r.get("regions_force_N") for r in runs):
        return []
    out = ["", "| region | force per mesh [N] | contact area per mesh [cm²] |", "|---|---|---|"]
    for name in KEY_REGIONS:
        force = [(r.get("regions_force_N") or {}).get(name) for r in runs]
        area = [(r.get("regions_area_m2") or {}).get(name) for r in runs]
        out.append(f"| {name} | " + " / ".join("–" if f is None else f"{f:.3f}" for f in force)
                   + " | " + " / ".join("–" if a is None else f"{1e4 * a:.0f}" for a in area)
                   + " |")  # fmt: skip
    return out


def plot(stem: str, ana: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    stats = [s for s in P95_STATS if any(s in r for r in ana["regions"].values())]
    fig, axes = plt.subplots(1, len(stats), figsize=(6.4 * len(stats), 4.2), squeeze=False)
    for ax, s in zip(axes[0], stats, strict=True):
        for name, row in ana["regions"].items():
            if s not in row:
                continue
            c = row[s].get("least_squares") or row[s]  # the fit of all levels when ≥ 4
            ax.errorbar([1e3 * h for h in c["sizes"]], c["values"], yerr=c["error"],
                        marker="o", capsize=3, label=f"{name} (p = {c['order']:.2g})")  # fmt: skip
        ax.set_xscale("log")
        ax.invert_xaxis()
        ax.set_xlabel("garment mesh size h [mm]")
        what = P95_STATS[s][1]
        bars = ("least squares, all levels" if len(ana["sizes"]) >= 4 else
                "grid convergence index")  # fmt: skip
        ax.set_ylabel(f"{what} [kPa]")
        ax.set_title(f"{stem}: {what} per region\n(error bars: {bars})", fontsize=9)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(RESULTS / f"convergence-{stem.replace(':', '-')}.png", dpi=110)
    plt.close(fig)


def reanalyse(path: Path = RESULTS / "convergence.json") -> int:
    """Recompute every stored record's analysis and plot from its runs (no scene is run)."""
    data = json.loads(path.read_text())
    for key, sc in data["scenes"].items():
        sc["analysis"] = analyse(sc["runs"])
        if sc["analysis"]["regions"]:
            plot(key, sc["analysis"])
    path.write_text(json.dumps(data, indent=1, default=float))
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    bad = check_args(argv, __doc__, {"--quick", "--reuse", "--reanalyse"},
                     {"--levels", "--variant"}, LEVELS)  # fmt: skip
    if bad is not None:
        return bad
    if "--reanalyse" in argv:
        return reanalyse()
    quick = "--quick" in argv
    n_override = None
    if "--levels" in argv:
        n_override = int(argv[argv.index("--levels") + 1])
    table = QUICK if quick else LEVELS
    names = [a for a in argv if a in LEVELS] or list(table)
    variant = argv[argv.index("--variant") + 1] if "--variant" in argv else "default"
    say = lambda *a: print(*a, flush=True)  # noqa: E731
    path = RESULTS / "convergence.json"
    data = json.loads(path.read_text()) if path.exists() else {"scenes": {}}
    for stem in names:
        h0, n = table.get(stem, LEVELS[stem])
        n = n_override or n
        say(f"{stem}: garment meshes {[round(h * 1e3, 1) for h in sizes(h0, n)]} mm")
        key = stem if variant == "default" else f"{stem}:{variant}"
        known = data["scenes"].get(key, {}).get("runs", []) if "--reuse" in argv else []
        recs = run_scene(stem, h0, n, say, variant, known)
        ana = analyse(recs)
        data["scenes"][key] = {"runs": recs, "analysis": ana, "loadavg": os.getloadavg()}
        RESULTS.mkdir(exist_ok=True)
        path.write_text(json.dumps(data, indent=1, default=float))
        if ana["regions"]:
            plot(key, ana)
            for name, row in ana["regions"].items():
                if "p95" in row:
                    c = row["p95"]
                    say(
                        f"    {name:<12} p95 {c['values'][-1]:.3f} ± {c['error'][-1]:.3f} kPa "
                        f"(order {c['order']:.2f}, extrapolated {c['extrapolated']:.3f})"
                    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
