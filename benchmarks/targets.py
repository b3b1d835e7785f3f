"""The seven figures of the issue "Fast scenes", each beside its target, with the run it comes from.

Every figure is read from the record of the benchmark that measured it: ``targets.json`` for the
demo scenes at their shipped mesh (``measure``; else the sweep's nearest mesh) and for the
fresh-clone ``make demo``, ``scenes.json`` for the peer and the 1-against-2-rank runs,
``solvers.json`` for the linear-solver path; the table shows the load average and the mesh of
that run. Times on this shared 2-core machine are only comparable within one run; the ratios
are.

    python -m benchmarks.targets              # print the table (also a section of REPORT.md)
    python -m benchmarks.targets measure [--rounds N]
                                              # run the three demo scenes at their shipped mesh
                                              # (2 ranks, warm; N interleaved rounds, default 2,
                                              # each scene's fastest kept) into targets.json
    python -m benchmarks.targets fresh-demo   # clone this repository into a temporary folder,
                                              # time `make demo` there, store it in targets.json

The fresh-clone run uses this machine's pip cache (no network) and an empty FFCx JIT cache
(``XDG_CACHE_HOME`` pointed at the temporary folder, ``PIP_CACHE_DIR`` kept), so its time is
set-up + cold compilation + the demo, as for a new user with the wheels already downloaded.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks import check_args

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RESULTS = HERE / "results"
DEMO_SCENES = ("cotton_gilet", "nylon_gilet", "cotton_dress")
#: The issue's targets.
END_TO_END_S = 60.0
ITS_PER_SOLVE = 6.0
PEER_RATIO = 0.5
SPEEDUP_2_RANKS = 1.6
FRESH_DEMO_S = 120.0
LARGE_DOFS = 500_000


def _read(name: str) -> dict:
    p = RESULTS / f"{name}.json"
    return json.loads(p.read_text()) if p.exists() else {}


def _other_meshes(scenes: dict) -> str:
    """The 2-rank speed-ups measured at other garment meshes (``scenes --mesh-size``)."""
    found = []
    for key, par in sorted(scenes.get("summary", {}).items()):
        one = next((r for r in scenes.get("runs", []) if r.get("part") == key), None)
        if key.startswith("parallel-") and par and par.get("speedup_warm") and one:
            found.append(f"{par['speedup_warm']:.2f}× at h = {1e3 * one['mesh_size']:.1f} mm "
                         f"({one['dofs']:,} dofs)")  # fmt: skip
    return ("; " + ", ".join(found)) if found else ""


def _linear_bound() -> str:
    """The MUMPS solve's own 2-rank speed-up on the gilet's Jacobian at its shipped mesh
    (``factor_scaling-<h mm>.json``, else ``factor_scaling.json``) and the ceiling it sets on the
    scene's when measured, or nothing when not measured."""
    name = f"factor_scaling-{1e3 * default_mesh('cotton_gilet'):.1f}"
    data = _read(name) or _read(name := "factor_scaling")
    rows = {r["solver"]: r for r in data.get("analysis", {}).get("table", [])}
    m = rows.get("mumps")
    if not m:
        return ""
    h = f"h = {1e3 * data['mesh_size']:.1f} mm" if data.get("mesh_size") else "the shipped mesh"
    cap = f", which caps the scene at {m['ceiling']:.2f}×" if m.get("ceiling") else ""
    return (f"; its linear solve alone (MUMPS, {h}) {m['speedup_vs_mumps_1']:.2f}×{cap} "
            f"({name}.json)")  # fmt: skip


def default_mesh(stem: str) -> float:
    """The garment mesh size the scene ships with."""
    from fenics_garment.scene import config

    return config.load(ROOT / "fenics_garment" / "scenes" / f"{stem}.toml").garment.mesh_size


def at_default(
    sweep: dict, stem: str, scenes: dict | None = None, own: dict | None = None
) -> dict | None:
    """The completed 2-rank run of ``stem`` with the current release nearest to its default mesh
    (in log h): from the sweep, and for the cotton gilet also the 2-rank run of the scenes
    benchmark's part "parallel" (which runs at the shipped mesh)."""
    runs = [r for r in (own or {}).get("demo_runs", []) if r.get("stem") == stem]
    if runs:  # measured for this table, at the shipped mesh, one after the other
        ok = runs[-1].get("status") == "ok"
        return dict(runs[-1], source="targets.json, measure") if ok else None
    runs = list(sweep.get("scenes", {}).get(stem, {}).get("runs", []))
    if stem == "cotton_gilet" and scenes:
        runs += [
            dict(r, source="scenes.json, parallel")
            for r in scenes.get("runs", [])
            if r.get("part") == "parallel"
        ]
    runs = [
        dict({"source": "sweep.json"}, **r)
        for r in runs
        if r.get("status") == "ok" and r.get("release") and r["ranks"] == 2
    ]
    if not runs:
        return None
    h = default_mesh(stem)
    return min(runs, key=lambda r: abs(math.log(r["mesh_size"] / h)))


def per_newton_ms(r: dict) -> dict[str, float]:
    """Where the time of one Newton iteration goes in run ``r`` [ms], over every Newton iteration
    of the run (accepted solves, failed tries, multiplier passes): residual and Jacobian assembly
    (without the contact hooks), the linear solve, the contact hooks (gap, normal, search) and
    the rest of the dressing (multiplier and anchor updates, pressure checks)."""
    st = r["solver_time_s"]
    n = max(st.get("newton_iterations", r["newton_its"]), 1)
    hooks, jac_hooks = st.get("hooks", 0.0), st.get("jacobian_hooks", 0.0)
    parts = {
        "residual": st["residual"] - (hooks - jac_hooks),
        "Jacobian": st["jacobian"] - jac_hooks,
        "linear solve": r["linear_solver_s"],
        "contact hooks": hooks,
    }
    parts["rest of the dressing"] = max(r["dressing_s"] - st["solve"], 0.0)
    return {k: 1e3 * v / n for k, v in parts.items()}


def all_solves(r: dict) -> tuple[int, int]:
    """(Newton iterations, solves) of the whole dressing: the accepted solves, the failed tries
    and the augmented Lagrangian's passes, on the scene's mesh and on the coarser levels of a
    mesh sequence (older records: the accepted solves only)."""
    if r.get("all_newton_its") is None:
        return r["newton_its"], r["solves"]
    its = r["all_newton_its"] + sum(lv["all_newton_iterations"] for lv in r.get("sequence", []))
    solves = r["solves"] + r["failed_attempts"] + len(r.get("al_its") or [])
    solves += sum(lv["solves"] + lv["failed_attempts"] + lv.get("multiplier_passes", 0)
                  for lv in r.get("sequence", []))  # fmt: skip
    return its, solves


def _src(r: dict, what: str = "") -> str:
    what = what if not r.get("source") else r["source"]
    load = (r.get("loadavg") or [math.nan])[0]
    via = "".join(f" via {1e3 * lv['mesh_size_m']:.1f} mm" for lv in r.get("sequence", []))
    return f"{what}, h = {1e3 * r['mesh_size']:.1f} mm{via}, {r['dofs']} dofs, load {load:.1f}"


def rows() -> list[tuple[str, str, str, str, str]]:
    """(figure, target, measured, met, source) for the seven figures."""
    sweep, scenes, solvers, own = (
        _read("sweep"),
        _read("scenes"),
        _read("solvers"),
        _read("targets"),
    )
    out = []
    demo = {s: at_default(sweep, s, scenes, own) for s in DEMO_SCENES}
    for s, r in demo.items():
        if r is None:
            out.append(
                (
                    f"1. {s} end to end, warm, 2 ranks",
                    f"≤ {END_TO_END_S:.0f} s",
                    "not measured",
                    "–",
                    "sweep.json: no run with the current release",
                )
            )
            continue
        t = r["warm_wall_s"]
        rounds = [x for x in r.get("warm_wall_s_rounds", []) if x is not None]
        spread = f"; rounds {' / '.join(f'{x:.1f}' for x in rounds)} s" if len(rounds) > 1 else ""
        out.append(
            (
                f"1. {s} end to end, warm, 2 ranks",
                f"≤ {END_TO_END_S:.0f} s",
                f"{t:.1f} s ({t / END_TO_END_S:.2f}× the target{spread})",
                "yes" if t <= END_TO_END_S else "no",
                _src(r, "sweep.json"),
            )
        )
    for s, r in demo.items():
        if r is None:
            continue
        ms = per_newton_ms(r)
        asm = ms["residual"] + ms["Jacobian"]
        ratio = asm / ms["linear solve"]
        out.append(
            (
                f"2. {s}: assembly / linear solve per Newton iteration",
                "≤ 1",
                f"{asm:.0f} / {ms['linear solve']:.0f} ms = {ratio:.2f}",
                "yes" if ratio <= 1 else "no",
                _src(r, "sweep.json"),
            )
        )
    for s, r in demo.items():
        if r is None:
            continue
        its, solves = all_solves(r)
        ok = its / solves <= ITS_PER_SOLVE and r["failed_attempts"] == 0
        out.append(
            (
                f"3. {s}: Newton its per solve (all solves: dressing, release, failed tries, "
                "multiplier passes), failed tries",
                f"≤ {ITS_PER_SOLVE:.0f}, 0",
                f"{its / solves:.2f} ({its} / {solves}; accepted dressing and release solves "
                f"{r['newton_its']} / {r['solves']}), {r['failed_attempts']}",
                "yes" if ok else "no",
                _src(r, "sweep.json"),
            )
        )
    peer = scenes.get("summary", {}).get("peer")
    if peer:
        ok = peer["time_ratio"] <= PEER_RATIO and abs(peer["ours_error"]) <= abs(peer["peer_error"])
        out.append(
            (
                "4. semi-cylinder time / FEniCSx-Shells (10 steps)",
                f"≤ {PEER_RATIO}",
                f"wall {peer['time_ratio']:.2f}, CPU {peer['cpu_ratio']:.2f} at "
                f"{100 * peer['ours_error']:+.2f} % vs {100 * peer['peer_error']:+.2f} %",
                "wall yes, CPU no"
                if ok and peer["cpu_ratio"] > PEER_RATIO
                else ("yes" if ok else "no"),
                "scenes.json, part peer (one run, interleaved)",
            )
        )
    par = scenes.get("summary", {}).get("parallel")
    ones = [r for r in scenes.get("runs", []) if r.get("part") == "parallel"
            and r.get("status") == "ok" and r["ranks"] == 1
            and not r.get("side_by_side")]  # fmt: skip
    one = min(ones, key=lambda r: r["warm_wall_s"], default=None)  # the run the ratio quotes
    if par and one:
        sp = par["speedup_warm"]
        out.append(
            (
                "5. 2 ranks / 1 rank, cotton gilet",
                f"≥ {SPEEDUP_2_RANKS}",
                f"{sp:.2f}× warm wall, {par['speedup_dressing']:.2f}× dressing"
                + _linear_bound()
                + _other_meshes(scenes),
                "yes" if sp >= SPEEDUP_2_RANKS else "no",
                _src(one, "scenes.json, part parallel")
                + (
                    ""
                    if math.isclose(one["mesh_size"], default_mesh("cotton_gilet"), rel_tol=1e-3)
                    else " (not the default mesh)"
                ),
            )
        )
    fd = own.get("fresh_demo")
    if fd:
        t = fd["total_s"]
        out.append(
            (
                "6. fresh clone `make demo`, set-up included",
                f"≤ {FRESH_DEMO_S:.0f} s",
                f"{t:.0f} s (set-up {fd['setup_s']:.0f} s, demo {fd['demo_s']:.0f} s)",
                "yes" if t <= FRESH_DEMO_S else "no",
                f"targets.json, {fd['when']}, load {fd['loadavg'][0]:.1f}, pip cache warm, "
                "JIT cache cold",
            )
        )
    else:
        out.append(
            (
                "6. fresh clone `make demo`, set-up included",
                f"≤ {FRESH_DEMO_S:.0f} s",
                "not measured",
                "–",
                "python -m benchmarks.targets fresh-demo",
            )
        )
    ok_runs = [r for r in solvers.get("runs", []) if r.get("status") == "ok"]
    if ok_runs:
        from benchmarks.solvers import fit

        big = max(ok_runs, key=lambda r: (r["dofs"], -r["per_newton_s"]))
        model = fit([r for r in ok_runs if r["solver"] == big["solver"]])
        pred = (
            f"; model: {model['predicted_per_newton_s']:.2f} s per Newton iteration for "
            f"{model['predicted_dofs']:,} dofs on {model['predicted_ranks']} ranks"
            if model
            else "; no cost model yet (needs the 2-rank runs)"
        )
        out.append(
            (
                "7. linear-solver path past one machine",
                f"≥ {LARGE_DOFS:,} dofs + model",
                f"{big['solver']}: {big['dofs']:,} dofs, {big['per_newton_s']:.1f} s per "
                f"Newton iteration on {big['ranks']} rank(s)" + pred,
                "yes" if big["dofs"] >= LARGE_DOFS and model else "partly",
                f"solvers.json, Scordelis-Lo n = {big['n']}, load {big['loadavg'][0]:.1f}",
            )
        )
    return out


def markdown() -> str:
    lines = [
        'Each target of the issue "Fast scenes" beside the run that measured it '
        "(`python -m benchmarks.targets`).",
        "",
        "| figure | target | measured | met | run |",
        "|---|---|---|---|---|",
    ]
    lines += [f"| {' | '.join(r)} |" for r in rows()]
    r = at_default(_read("sweep"), "cotton_gilet", _read("scenes"), _read("targets"))
    if r:
        ms = per_newton_ms(r)
        src = _src(r, "sweep.json")
        lines += [
            "",
            f"Where one Newton iteration of the cotton gilet's dressing goes ({src}; "
            "the hooks are the contact gap/normal updates and the search): "
            + ", ".join(f"{k} {v:.0f} ms" for k, v in ms.items())
            + ".",
        ]
    return "\n".join(lines)


def fresh_demo(say=print) -> dict:
    """Clone this repository (its committed HEAD) into a temporary folder and time `make demo`."""
    tmp = Path(tempfile.mkdtemp(prefix="fg-fresh-"))
    try:
        subprocess.run(["git", "clone", "-q", str(ROOT), str(tmp / "repo")], check=True)
        env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH")}
        env["PATH"] = os.pathsep.join(p for p in env["PATH"].split(os.pathsep) if ".venv" not in p)
        env["PIP_CACHE_DIR"] = env.get("PIP_CACHE_DIR") or str(Path.home() / ".cache" / "pip")
        env["XDG_CACHE_HOME"] = str(tmp / "cache")  # an empty FFCx JIT cache
        load = list(os.getloadavg())
        t0 = time.perf_counter()
        subprocess.run(
            ["make", ".venv/.installed-stamp"],
            cwd=tmp / "repo",
            env=env,
            check=True,
            capture_output=True,
        )
        t1 = time.perf_counter()
        p = subprocess.run(
            ["make", "demo"], cwd=tmp / "repo", env=env, capture_output=True, text=True
        )
        t2 = time.perf_counter()
        if p.returncode != 0:
            raise SystemExit(f"make demo failed in the fresh clone: {p.stderr[-400:]}")
        rec = {
            "total_s": t2 - t0,
            "setup_s": t1 - t0,
            "demo_s": t2 - t1,
            "loadavg": load,
            "commit": subprocess.run(
                ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True
            ).stdout.strip(),
            "when": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        }
        say(
            f"fresh clone: set-up {rec['setup_s']:.0f} s, demo {rec['demo_s']:.0f} s, "
            f"total {rec['total_s']:.0f} s"
        )
        return rec
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def measure(say=print, rounds: int = 2) -> list[dict]:
    """The demo scenes at their shipped mesh, 2 ranks, one after the other (warm JIT cache), in
    ``rounds`` interleaved rounds: each scene's fastest run is kept (as every time in REPORT.md,
    the fastest of the repeats: this shared machine's speed drifts by 10–15 % over minutes),
    with the times of all its rounds (``warm_wall_s_rounds``)."""
    from benchmarks import scenes as scene_bench

    runs: dict[str, list[dict]] = {stem: [] for stem in DEMO_SCENES}
    for k in range(rounds):
        for stem in DEMO_SCENES:
            spec = {"scene": str(ROOT / "fenics_garment" / "scenes" / f"{stem}.toml"),
                    "mesh_size": default_mesh(stem), "sequence": True}  # fmt: skip
            r = {**scene_bench.spawn(spec, ranks=2), "stem": stem}
            say(f"{stem} (round {k + 1}): {r.get('status')} "
                f"{r.get('warm_wall_s', float('nan')):.1f} s warm")  # fmt: skip
            runs[stem].append(r)
    recs = []
    for rs in runs.values():
        ok = [r for r in rs if r.get("status") == "ok"]
        best = min(ok, key=lambda r: r["warm_wall_s"]) if ok else rs[-1]
        recs.append({**best, "warm_wall_s_rounds": [r.get("warm_wall_s") for r in rs]})
    return recs


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    bad = check_args(argv, __doc__, (), ("--rounds",), ("measure", "fresh-demo"))
    if bad is not None:
        return bad
    rounds = argv[argv.index("--rounds") + 1] if "--rounds" in argv else "2"
    if not rounds.isdigit() or int(rounds) < 1:
        print(f"--rounds takes a whole number ≥ 1, got {rounds!r}")
        return 2
    rounds = int(rounds)
    if argv[:1] == ["measure"]:
        data = _read("targets")
        data["demo_runs"] = measure(rounds=rounds)
        RESULTS.mkdir(exist_ok=True)
        (RESULTS / "targets.json").write_text(json.dumps(data, indent=1, default=float))
    if argv[:1] == ["fresh-demo"]:
        data = _read("targets")
        data["fresh_demo"] = fresh_demo()
        (RESULTS / "targets.json").write_text(json.dumps(data, indent=1))
    print(markdown())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
