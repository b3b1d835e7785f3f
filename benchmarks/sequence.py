"""Mesh sequencing against the direct dressing (issue "Fast scenes", figure 1; ``scene.sequence``).

Each scene at its shipped garment mesh, dressed directly and through the coarser levels of
``SEQUENCES`` (the whole dressing on the coarse mesh, the state carried over, the answer settled
on the scene's mesh), one run after the other on 2 ranks with a warm JIT cache. Per run: the time
without JIT, the Newton iterations on the scene's mesh and on the coarse levels, and each key
region's sensor p95 against the direct run (the path's part of the error) and against the finest
level of the convergence study (record ``convergence.json``, ``<scene>:body-0.015``, 4.4 mm for
the gilets): the speed claim is a time ratio measured in one run, beside the error of both.

    python -m benchmarks.sequence [cotton_gilet|nylon_gilet ...]
    python -m benchmarks.sequence table        (the stored record as Markdown)

Writes ``benchmarks/results/sequence.json`` (section "sequence" of REPORT.md).
"""

from __future__ import annotations

import json
import sys

from benchmarks import check_args, convergence
from benchmarks import scenes as scene_bench

RESULTS = convergence.RESULTS / "sequence.json"
KEY_REGIONS = convergence.KEY_REGIONS
#: The coarser levels each scene is sequenced through: the study's levels (35 mm / √2ᵏ for the
#: gilets), coarse enough to cost little, fine enough that the carried state settles.
SEQUENCES: dict[str, list[float]] = {
    "cotton_gilet": [0.035 / 2**0.5],
    "nylon_gilet": [0.035 / 2**0.5],
}
REFERENCE = "body-0.015"  # the variant of the finest convergence study on the shipped body


def _load() -> dict:
    return json.loads(RESULTS.read_text()) if RESULTS.exists() else {"scenes": {}}


def _save(data: dict) -> None:
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(data, indent=1, default=float))


def reference(stem: str) -> dict | None:
    """The finest completed run of the study ``<stem>:body-0.015`` (sensor p95 per region)."""
    study = json.loads((convergence.RESULTS / "convergence.json").read_text())
    runs = study.get("scenes", {}).get(f"{stem}:{REFERENCE}", {}).get("runs", [])
    runs = [r for r in runs if r.get("status") == "ok" and r.get("completed")]
    return min(runs, key=lambda r: r["mesh_size"]) if runs else None


def measure(stem: str, say=print) -> dict:
    """The direct and the sequenced run of ``stem`` at its shipped mesh, one after the other."""
    from benchmarks.targets import default_mesh

    h = default_mesh(stem)
    base = {"scene": str(convergence.SCENES / f"{stem}.toml"), "mesh_size": h}
    runs = {}
    for name, seq in (("direct", []), ("sequenced", SEQUENCES[stem])):
        r = scene_bench.spawn({**base, "sequence": seq}, ranks=2)
        say(f"{stem} {name}: {r.get('status')} {r.get('warm_wall_s', float('nan')):.1f} s")
        runs[name] = r
    ref = reference(stem)
    if ref is not None:
        p95 = {k: ref["regions_sensor_p95_kPa"][k] for k in KEY_REGIONS}
        ref = {"mesh_size": ref["mesh_size"], "dofs": ref["dofs"], "sensor_p95_kPa": p95}
    return {"mesh_size": h, "sequence": SEQUENCES[stem], "runs": runs, "reference": ref}


def _its(r: dict) -> str:
    coarse = sum(lv["all_newton_iterations"] for lv in r.get("sequence", []))
    return f"{r['all_newton_its']}" + (f" + {coarse} coarse" if coarse else "")


def markdown(data: dict) -> str:
    lines = [
        "Mesh sequencing against the direct dressing at the shipped mesh (`python -m "
        "benchmarks.sequence`, 2 ranks, warm, one run after the other): time without JIT, "
        "Newton iterations (on the scene's mesh + on the coarser levels), sensor p95 per key "
        "region [kPa] with its change against the direct run and against the finest level of "
        "the convergence study.",
        "",
        "| scene (mesh) | dressing | time [s] | Newton its | "
        + " | ".join(KEY_REGIONS)
        + " | force [N] |",
        "|---|---|---|---|" + "---|" * len(KEY_REGIONS) + "---|",
    ]
    for stem, d in data.get("scenes", {}).items():
        runs, ref = d["runs"], d.get("reference")
        direct = runs.get("direct", {})
        for name, r in runs.items():
            if r.get("status") != "ok":
                lines.append(f"| {stem} | {name} | failed | | " + " | " * len(KEY_REGIONS))
                continue
            cells = []
            for k in KEY_REGIONS:
                v = r["regions_sensor_p95_kPa"][k]
                parts = [f"{v:.3f}"]
                if name != "direct" and direct.get("status") == "ok":
                    parts.append(f"{100 * (v / direct['regions_sensor_p95_kPa'][k] - 1):+.1f} %")
                if ref:
                    parts.append(f"{100 * (v / ref['sensor_p95_kPa'][k] - 1):+.1f} % ref")
                cells.append("; ".join(parts))
            ratio = ""
            if name != "direct" and direct.get("status") == "ok":
                ratio = f" ({r['warm_wall_s'] / direct['warm_wall_s']:.2f}×)"
            label = "direct" if name == "direct" else (
                "via " + " / ".join(f"{1e3 * h:.1f}" for h in d["sequence"]) + " mm")  # fmt: skip
            lines.append(
                f"| {stem} ({1e3 * d['mesh_size']:.1f} mm, {r['dofs']:,} dofs) | {label} | "
                f"{r['warm_wall_s']:.1f}{ratio} | {_its(r)} | "
                + " | ".join(cells)
                + f" | {r['contact_force_N']:.2f} |"
            )
        if ref:
            lines.append(f"| {stem}: reference, {1e3 * ref['mesh_size']:.1f} mm "
                         f"({ref['dofs']:,} dofs) | | | | "
                         + " | ".join(f"{ref['sensor_p95_kPa'][k]:.3f}" for k in KEY_REGIONS)
                         + " | |")  # fmt: skip
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    bad = check_args(argv, __doc__, (), (), ("table", *SEQUENCES))
    if bad is not None:
        return bad
    data = _load()
    if argv[:1] != ["table"]:
        for stem in [a for a in argv if a in SEQUENCES] or list(SEQUENCES):
            data["scenes"][stem] = measure(stem)
            _save(data)
    print(markdown(data))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
