"""Faceted vs smooth body surface (issue 15 item 3): Newton, stalls and the body-mesh error.

* ``runs``: both gilets (``demos/cotton_gilet.toml``, ``demos/nylon_gilet.toml``) with
  ``[physics] body_surface`` = ``"faceted"`` and ``"smooth"`` at garment meshes ``SIZES``; per run:
  completed / stalled, spring released to c = 0, solves, Newton iterations, failed attempts, the
  residual ratio r_k/r_(k−1) of the last iteration of every converged solve, contact-search time.
* ``refine``: each gilet at garment mesh ``--garment H`` (default the first of ``SIZES``) on the
  body meshes 15 and 7.5 mm (``--bodies 3``: and 3.75 mm): the change of every region's p95
  pressure per halving of the body mesh (the body-mesh part of the error), per surface, element
  and dressing schedule. ``--reuse`` keeps the stored completed runs of the same kind.

Each run is one ``mpiexec -n 2`` child of :func:`benchmarks.scenes.spawn` (spec fields
``body_surface``, ``body_mesh_size``). Writes ``benchmarks/results/smooth_body.json`` (kept after
every run) and prints the tables; times are on a shared 2-core machine (loadavg recorded).

    python -m benchmarks.smooth_body [--quick] [runs] [refine] [--garment H] [--surface S]
                                     [--bodies N] [--reuse] [cotton|nylon ...]
    python -m benchmarks.smooth_body table            (the stored record as Markdown tables)
    python -m benchmarks.smooth_body row FOLDER ...   (the underbust row of run folders' maps)
"""

from __future__ import annotations

import json
import os
import sys

import numpy as np

from benchmarks import check_args, scenes

RESULTS = scenes.RESULTS / "smooth_body.json"
SCENES = {"cotton": scenes.GILET, "nylon": scenes.NYLON}
SURFACES = ("faceted", "smooth")
SIZES = {"quick": [0.015], "default": [0.015, 0.0155]}
BODY = 0.015  # the demo scenes' body mesh size [m]


def _load() -> dict:
    return json.loads(RESULTS.read_text()) if RESULTS.exists() else {"runs": []}


def _save(data: dict) -> None:
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(data, indent=1, default=float))


def _key(r: dict) -> tuple:
    return (r["scene_name"], r["body_surface"], r["mesh_size"], r.get("body_mesh_size", BODY),
            r.get("element") or "", r.get("schedule") or "")  # fmt: skip


def run_one(data: dict, name: str, surface: str, h: float, body: float = BODY) -> dict:
    """One gilet run, stored in ``data`` (replacing an earlier run of the same key)."""
    spec = {"scene": str(SCENES[name]), "mesh_size": h, "body_surface": surface,
            "body_mesh_size": body}  # fmt: skip
    rec = dict(scenes.spawn(spec), scene_name=name, body_surface=surface, body_mesh_size=body)
    data["runs"] = [r for r in data["runs"] if _key(r) != _key(rec)] + [rec]
    _save(data)
    print(row(rec), flush=True)
    return rec


def last_ratios(rec: dict) -> list[float]:
    """The last-iteration residual ratio of every converged solve that took ≥ 2 iterations."""
    return [fr[-1] for _, its, fr in rec.get("final_ratios", []) if fr and its >= 2]


def row(r: dict) -> str:
    head = (f"{r['scene_name']:6} {r['body_surface']:7} h={r['mesh_size']:<6} "
            f"body={r['body_mesh_size']:<6}")  # fmt: skip
    if r.get("status") != "ok":
        return f"{head} FAILED {r.get('error', '')[-120:]!r}"
    lr = last_ratios(r)
    state = "released" if r["completed"] and r["final_regularisation"] == 0 else (
        "c>0" if r["completed"] else "STALLED")  # fmt: skip
    return (f"{head} {state:8} solves {r['solves']:3d} its {r['newton_its']:4d} fails "
            f"{r['failed_attempts']:2d}  last ratio median {np.median(lr):.1e} max {max(lr):.1e}  "
            f"search {r['contact_search_s']:6.1f} s of {r['dressing_s']:6.1f} s  "
            f"load {r['loadavg'][0]:.1f}")  # fmt: skip


def refinement_table(data: dict, stat: str = "p95", coarse: float = BODY) -> dict:
    """``stat`` (p95 or sensor_p95) change per region [%] when the body mesh goes from ``coarse``
    to ``coarse``/2, for every pair of completed runs that differ only in the body mesh (scene,
    surface, garment mesh, element, dressing schedule); the latest run of each kind."""
    out = {}
    ok = {_key(r): r for r in data["runs"] if r.get("status") == "ok" and r["completed"]}
    for key, b in ok.items():
        name, surface, h, body, element, schedule = key
        a = ok.get((name, surface, h, coarse, element, schedule))
        if body != coarse / 2 or a is None or f"regions_{stat}_kPa" not in a:
            continue
        pa, pb = a[f"regions_{stat}_kPa"], b[f"regions_{stat}_kPa"]
        label = f"{name}/{surface}, garment {h * 1e3:.1f} mm {element or 'P1-P1'} {schedule}"
        out[label.strip()] = {
            k: 100.0 * (pb[k] / pa[k] - 1.0) for k in pa if k in pb and pa[k] > 0.02
        }
    return out


def _how(r: dict) -> str:
    """Element and dressing schedule of a run (the early runs: P1-P1, adaptive)."""
    return f"{r.get('element') or 'P1-P1'}, {r.get('schedule') or 'adaptive'}"


def markdown(data: dict) -> str:
    """The runs as a Markdown table, then the body-refinement p95 changes per region."""
    lines = ["| gilet | body | element, dressing | garment h | body h | outcome | solves | "
             "Newton its | failed tries | last-iteration ratio: median / max | "
             "search / dressing [s] |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for r in sorted(data["runs"], key=_key):
        if r.get("status") != "ok":
            lines.append(f"| {r['scene_name']} | {r['body_surface']} | {_how(r)} | "
                         f"{r['mesh_size']} | {r['body_mesh_size']} | failed |"
                         + " |" * 5)  # fmt: skip
            continue
        lr = last_ratios(r)
        state = (
            "released to c = 0"
            if r["completed"] and r["final_regularisation"] == 0
            else (
                f"spring kept (c = {r['final_regularisation']:.2g})"
                if r["completed"]
                else "stalled"
            )
        )
        lines.append(f"| {r['scene_name']} | {r['body_surface']} | {_how(r)} | "
                     f"{r['mesh_size'] * 1e3:.1f} mm | "
                     f"{r['body_mesh_size'] * 1e3:g} mm | {state} | {r['solves']} | "
                     f"{r['newton_its']} | {r['failed_attempts']} | {np.median(lr):.1e} / "
                     f"{max(lr):.1e} | {r['contact_search_s']:.0f} / "
                     f"{r['dressing_s']:.0f} |")  # fmt: skip
    for stat, fine in [(s, f) for s in ("p95", "sensor_p95") for f in ("", "_fine")]:
        ref = data.get(f"refinement_{stat}{fine}_change_percent", {})
        if not ref:
            continue
        regions = sorted({k for v in ref.values() for k in v})
        step = "7.5 → 3.75" if fine else "15 → 7.5"
        lines += ["", f"| {stat} change, body {step} mm [%] | " + " | ".join(regions) + " |",
                  "|---|" + "---|" * len(regions)]  # fmt: skip
        for case, v in ref.items():
            cells = [f"{v[k]:+.1f}" if k in v else "" for k in regions]
            lines.append(f"| {case} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def underbust_row(folder: str, z: float = 1.215, half: float = 0.012) -> dict:
    """Spottiness of the body pressure along the front underbust crease of a gilet run folder
    (``<run>/<scene>/body_pressure.vtu``): the largest vertex pressure in each 1 cm of width
    (|x| < 10 cm, front y < 0, |z − z_row| < ``half``); a row of spots has max/min ≫ 1.
    ``z``: the row's height on the size-88 mannequin (the peak of the front median profile)."""
    import meshio

    m = meshio.read(f"{folder}/body_pressure.vtu")
    x, p = m.points, m.point_data["contact_pressure"]
    band = (x[:, 1] < 0) & (np.abs(x[:, 2] - z) < half) & (np.abs(x[:, 0]) < 0.10)
    mx = np.array([p[band & (np.abs(x[:, 0] - c) < 0.005)].max()
                   for c in np.arange(-0.095, 0.10, 0.01)])  # fmt: skip
    return {"mean_kPa": mx.mean() * 1e-3, "min_kPa": mx.min() * 1e-3, "max_kPa": mx.max() * 1e-3,
            "max_over_min": mx.max() / mx.min(), "cv": mx.std() / mx.mean()}  # fmt: skip


def main(argv: list[str]) -> int:
    if argv[:1] != ["row"]:  # row takes run folders
        bad = check_args(argv, __doc__, {"--quick", "--reuse"},
                         {"--garment", "--surface", "--bodies"},
                         {"table", "runs", "refine", *SCENES})  # fmt: skip
        if bad is not None:
            return bad
    if argv[:1] == ["table"]:  # print the stored record
        print(markdown(_load()))
        return 0
    if argv[:1] == ["row"]:  # python -m benchmarks.smooth_body row RUN_FOLDER/cotton-gilet ...
        for folder in argv[1:]:
            print(folder, json.dumps(underbust_row(folder)))
        return 0
    mode = "quick" if "--quick" in argv else "default"
    parts = [a for a in argv if a in ("runs", "refine")] or ["runs", "refine"]
    # refine: the garment mesh [m] and the surfaces (default: the first size, both surfaces)
    h_ref = float(argv[argv.index("--garment") + 1]) if "--garment" in argv else SIZES[mode][0]
    surfaces = [argv[argv.index("--surface") + 1]] if "--surface" in argv else SURFACES[::-1]
    names = [a for a in argv if a in SCENES] or list(SCENES)
    bodies = [BODY / 2**k for k in range(int(argv[argv.index("--bodies") + 1]))] if (
        "--bodies" in argv) else [BODY, BODY / 2]  # fmt: skip
    data = _load()
    data.setdefault("meta", {})["loadavg_start"] = list(os.getloadavg())
    if "runs" in parts:
        for surface in SURFACES[::-1]:
            for name in SCENES:
                for h in SIZES[mode]:
                    run_one(data, name, surface, h)
    if "refine" in parts:
        for surface in surfaces:
            for name in names:
                for body in bodies:
                    # a stored run of this scene, surface and meshes (the current element and
                    # dressing: the runs that record them)
                    if "--reuse" in argv and any(
                        _key(r)[:4] == (name, surface, h_ref, body) and r.get("element")
                        and r.get("status") == "ok" and r["completed"] for r in data["runs"]
                    ):  # fmt: skip
                        print(f"{name} {surface} h={h_ref} body={body}: kept from the record")
                        continue
                    run_one(data, name, surface, h_ref, body)
    for stat in ("p95", "sensor_p95"):
        data[f"refinement_{stat}_change_percent"] = refinement_table(data, stat)
        data[f"refinement_{stat}_fine_change_percent"] = refinement_table(data, stat, BODY / 2)
    _save(data)
    print(markdown(data))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
