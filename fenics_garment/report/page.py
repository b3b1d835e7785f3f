"""``report.html``: one self-contained page per run, built from the files of its folder alone.

Sections: the run's facts and checks, an interactive 3D view of the pressure (WebGL,
``viewer.js``), the pressure maps (PNG), the region table with the pressure chart (error bars,
comfort bands), the dressing's history and the time split. Pictures, data, script and style are
inlined: the page works offline and can be mailed as one file.
"""

from __future__ import annotations

import base64
import csv
import json
import time
from html import escape
from importlib import resources
from pathlib import Path

import numpy as np

from fenics_garment import output
from fenics_garment.report import charts
from fenics_garment.report.surfaces import Surface, read_surfaces

#: The report's file name in a run folder.
REPORT_FILE = "report.html"
#: The pressure maps of a run, with their captions, in the order shown.
MAPS = (("pressure_body.png", "Pressure on the body (front, back)"),
        ("pressure_garment.png", "Pressure on the garment (front, back)"),
        ("pressure_pattern.png", "Pressure on the flat pattern pieces"))  # fmt: skip
#: A check within this fraction of its limit (on the passing side) is shown as "warn".
WARN_MARGIN = 0.2


class ReportError(RuntimeError):
    """The folder is not the output folder of a run (no ``summary.json``)."""


def _asset(name: str) -> str:
    return resources.files("fenics_garment.report").joinpath(name).read_text(encoding="utf-8")


def _b64(data: bytes) -> str:
    return base64.b64encode(data).decode("ascii")


def _num(v, digits: int = 3) -> str:
    if v is None:
        return "–"
    if isinstance(v, float):
        return f"{v:.{digits}g}"
    return escape(str(v))


def _table(header: list[str], rows: list[list[str]], text: tuple[int, ...] = (0,)) -> str:
    """An HTML table (cells already HTML); the columns ``text`` left-aligned (-1: the last)."""
    n = len(header)

    def cls(j: int) -> str:
        return ' class="text"' if j in text or j - n in text else ""

    head = "".join(f"<th{cls(j)}>{h}</th>" for j, h in enumerate(header))
    body = "".join(
        "<tr>" + "".join(f"<td{cls(j)}>{c}</td>" for j, c in enumerate(r)) + "</tr>" for r in rows
    )
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


# ------------------------------------------------------------------------------------------------
# Reading the folder
# ------------------------------------------------------------------------------------------------


def read_run(folder: Path) -> tuple[dict, dict]:
    """(summary.json, run.json) of the run in ``folder`` (run.json may be missing: {})."""
    try:
        summary = json.loads((folder / "summary.json").read_text())
    except FileNotFoundError:
        raise ReportError(f"{folder} has no summary.json: is it the output folder of a run "
                          "(<output root>/<scene name>/)?") from None  # fmt: skip
    except ValueError as err:
        raise ReportError(f"{folder / 'summary.json'} is not valid JSON: {err}") from None
    try:
        state = json.loads((folder / "run.json").read_text())
    except (OSError, ValueError):
        state = {}
    return summary, state if isinstance(state, dict) else {}


def region_rows(folder: Path, summary: dict) -> list[dict]:
    """The region table: the summary's, else ``pressure_regions.csv``'s."""
    if summary.get("regions"):
        return summary["regions"]
    path = folder / "pressure_regions.csv"
    if not path.is_file():
        return []
    rows = list(csv.DictReader(path.read_text().splitlines()))
    for r in rows:
        for k, v in r.items():
            try:
                r[k] = float(v)
            except (TypeError, ValueError):
                pass
    return rows


# ------------------------------------------------------------------------------------------------
# Sections
# ------------------------------------------------------------------------------------------------


def check_status(check: dict) -> str:
    """ "pass", "warn" (passes within :data:`WARN_MARGIN` of its limit), "fail" or "n/a"."""
    value, limit, ok = check.get("value"), check.get("limit"), bool(check.get("ok", True))
    if value is None:
        return "fail" if not ok else "n/a"
    if not ok:
        return "fail"
    at_most = value <= limit  # a passing value is on its good side of the limit
    near = value > (1 - WARN_MARGIN) * limit if at_most else value < (1 + WARN_MARGIN) * limit
    return "warn" if near else "pass"


def _chip(status: str, kind: str | None = None) -> str:
    """``status`` as a coloured label; ``kind``: its colour class (pass, warn, fail, na)."""
    kind = kind or status.replace("/", "")
    return f'<span class="chip {kind}">{escape(status)}</span>'


def checks_section(summary: dict) -> str:
    checks = summary.get("checks") or {}
    rows = []
    for name, c in checks.items():
        side = ""  # which side of the limit passes: seen from a value and its verdict
        if c.get("value") is not None:
            side = "≤ " if (c["value"] <= c["limit"]) == c.get("ok") else "≥ "
        rows.append([escape(name), _chip(check_status(c)), _num(c.get("value")),
                     f"{side}{_num(c.get('limit'))}", escape(c.get("what", ""))])  # fmt: skip
    table = _table(["check", "result", "value", "limit", "what"], rows, text=(0, -1))
    note = (
        f'<p class="small">warn: passes, but within {WARN_MARGIN:.0%} of its limit; fail: '
        "the run printed a WARNING and exited with code 4 (README, exit codes).</p>"
    )
    return '<h2 id="checks">Result checks</h2>' + (table + note if rows else "<p>No checks.</p>")


def header_section(folder: Path, summary: dict, state: dict) -> str:
    name = escape(str(summary.get("scene", folder.name)))
    # from the summary: run.json says "running" while the run writes its report
    status = ("stopped" if not summary.get("completed", False) else
              "completed" if summary.get("checks_passed", True) else "checks failed")  # fmt: skip
    kind = {"completed": "pass", "checks failed": "warn"}.get(status, "fail")
    facts = [
        ("garment", f"{summary.get('fabric', '?')} {summary.get('garment', '?')}"),
        ("element", summary.get("element")),
        ("dofs", summary.get("dofs")),
        ("ranks", summary.get("ranks")),
        ("max pressure", f"{summary.get('max_pressure_kPa', 0):.3g} kPa"),
        ("contact force", f"{summary.get('contact_force_N', 0):.3g} N"),
        ("contact area", f"{summary.get('contact_area_garment_m2', 0) * 1e4:.4g} cm²"),
        ("run id", state.get("run_id") or summary.get("run_id")),
    ]
    items = "".join(f"<div><span>{k}</span> {escape(str(v))}</div>" for k, v in facts if v)
    message = summary.get("message")
    why = f"<p>{escape(message)}</p>" if message else ""
    nav = "".join(f'<a href="#{a}">{t}</a>' for a, t in (
        ("view3d", "3D view"), ("maps", "maps"), ("regions", "regions"), ("checks", "checks"),
        ("dressing", "dressing"), ("time", "time")))  # fmt: skip
    return (f"<h1>{name}: contact pressure</h1><p>{_chip(status, kind)} "
            f'<span class="small">fenics-garment run report</span></p>{why}'
            f'<div class="facts">{items}</div><nav>{nav}</nav>')  # fmt: skip


def _top_pressure_kpa(surfaces: dict[str, Surface]) -> float:
    """The colour bar's top: the 99th percentile of the garment's contact pressure (as in the
    PNG maps: one hot node would make the rest one colour), else the body's."""
    for name in ("garment", "body"):
        if name in surfaces:
            p = surfaces[name].pressure
            if np.any(p > 0):
                return float(np.percentile(p[p > 0], 99)) * 1e-3
    return 1.0


def viewer_section(surfaces: dict[str, Surface]) -> str:
    """The 3D view: the surfaces as base64 arrays in a JSON script block, drawn by viewer.js."""
    if not surfaces:
        return ('<h2 id="view3d">3D view</h2><p>No surfaces in this folder (report_surfaces.npz, '
                "or body_pressure.vtu and final_state.xdmf).</p>")  # fmt: skip
    data = {
        "vmax_kPa": _top_pressure_kpa(surfaces),
        "surfaces": {
            name: {"vertices": _b64(s.vertices.astype("<f4").tobytes()),
                   "triangles": _b64(s.triangles.astype("<u4").tobytes()),
                   "pressure": _b64(s.pressure.astype("<f4").tobytes())}
            for name, s in surfaces.items()
        },
    }  # fmt: skip
    options = [("garment", "Pressure on the garment (body grey)"),
               ("body", "Pressure on the body (garment hidden)"),
               ("both", "Pressure on both")]  # fmt: skip
    if "garment" not in surfaces:
        options = [options[1]]
    select = "".join(f'<option value="{v}">{t}</option>' for v, t in options)
    counts = ", ".join(f"{n} {len(s.triangles)} triangles" for n, s in surfaces.items())
    return (
        '<h2 id="view3d">3D view</h2>'
        '<div class="viewer3d" data-source="surface-data">'
        '<canvas class="view" width="820" height="560"></canvas>'
        f'<div class="side"><select class="show">{select}</select>'
        '<div><button data-yaw="0">front</button> <button data-yaw="3.14159">back</button> '
        '<button data-yaw="1.5708">side</button></div>'
        '<canvas class="colourbar" width="130" height="300"></canvas>'
        '<div class="readout"></div>'
        '<div class="small">drag: rotate<br>wheel: zoom<br>double-click: reset<br>'
        "hover: the pressure there</div>"
        '<div class="status"></div></div></div>'
        f'<p class="small">{counts} (decimated for the page when large).</p>'
        f'<script type="application/json" id="surface-data">{json.dumps(data)}</script>'
    )  # fmt: skip


def maps_section(folder: Path) -> str:
    parts = []
    for name, caption in MAPS:
        path = folder / name
        if path.is_file():
            parts.append(f"<figure><img alt=\"{escape(caption)}\" src=\"data:image/png;base64,"
                         f"{_b64(path.read_bytes())}\"><figcaption>{escape(caption)} "
                         f"({name})</figcaption></figure>")  # fmt: skip
    body = "".join(parts) or "<p>No pressure maps ([output] pictures = false).</p>"
    return f'<h2 id="maps">Pressure maps</h2><div class="maps">{body}</div>'


def _with_err(r: dict, stat: str) -> str:
    v, err = r.get(f"{stat}_kPa"), r.get(f"{stat}_err_kPa")
    if v is None:
        return "–"
    return f"{v:.3g} ± {err:.2g}" if isinstance(err, float) and np.isfinite(err) else f"{v:.3g}"


def regions_section(rows: list[dict], summary: dict) -> str:
    cols = ["mean", "p95", "max", "sensor_p95", "body_sensor_p95"]
    cols = [c for c in cols if any(f"{c}_kPa" in r for r in rows)]
    header = ["region", "contact [cm²]", "force [N]",
              *[f"{charts.STAT_LABEL.get(c, c)} [kPa]" for c in cols], "p95 [mmHg]",
              "comfort (p95)"]  # fmt: skip
    table = []
    for r in rows:
        comfort = r.get("comfort_range") or r.get("comfort", "")
        table.append([escape(str(r.get("region", ""))), f"{r.get('contact_area_m2', 0) * 1e4:.4g}",
                      _num(r.get("force_N")), *[_with_err(r, c) for c in cols],
                      _num(r.get("p95_mmHg")), escape(str(comfort))])  # fmt: skip
    bands, lower = [], 0.0
    for upper, name in output.COMFORT_BANDS:
        bands.append(f"{name} {lower:g}–{upper:g} kPa" if np.isfinite(upper)
                     else f"{name} ≥ {lower:g} kPa")  # fmt: skip
        lower = upper
    bars = summary.get("error_bars")
    how = "No error bars (run with --error-bars for them)."
    if isinstance(bars, dict):
        how = f"Error bars: {escape(bars.get('method', ''))} (rate {bars.get('rate')})."
    return ('<h2 id="regions">Pressure per body region</h2>'
            + _table(header, table, text=(0, -1))
            + charts.pressure_chart(rows)
            + f'<p class="small">Points: statistics of the contact pressure in each region; '
            f"sensor: a sensor of [output] sensor_instrument at the garment's contact points; skin "
            f"sensor: lying on the body. {how} Comfort bands (Gupta &amp; Zakaria 2020, Table "
            f"13.5): {escape('; '.join(bands))}.</p>")  # fmt: skip


def sensors_section(summary: dict) -> str:
    """The readings of the sensors at anatomical points (:mod:`fenics_garment.sensors`), those
    with no garment on their pad listed apart, or why there are none."""
    rows = summary.get("sensors") or []
    if not rows:
        why = summary.get("sensors_skipped") or "none in this run"
        return f'<h2 id="sensors">Sensors</h2><p class="small">No sensors: {escape(why)}.</p>'
    on = [r for r in rows if r.get("points", 1) > 0]
    off = [r["sensor"] for r in rows if r.get("points", 1) == 0]
    table = [[escape(r["sensor"]), _num(r["reading_kPa"]), _num(r["reading_mmHg"]),
              "yes" if r.get("covered") else f"in part ({r.get('cover', 0):.0%})",
              f"{r['x_m']:.3f}, {r['y_m']:.3f}, {r['z_m']:.3f}"] for r in on]  # fmt: skip
    d = rows[0]["diameter_m"] * 1e3
    note = (
        f'<p class="small">A round pad of {d:g} mm ({escape(rows[0]["instrument"])}) at '
        "each point, placed from the body's landmarks; its reading is the contact force on "
        "the pad over the garment area over it. Covered: the garment reaches past the "
        "pad's rim all round."
    )
    if off:
        note += f" No garment within {d / 2:g} mm of: {escape(', '.join(off))}."
    return (
        '<h2 id="sensors">Sensors at anatomical points</h2>'
        + _table(["sensor", "kPa", "mmHg", "covered", "centre x, y, z [m]"], table)
        + note
        + "</p>"
    )


def _step_row(k: int, s: dict) -> list[str]:
    stage = s.get("stage", "dress")
    where = (f"shrink {s['shrink'] * 1e3:.3g} mm" if stage == "dress"
             else f"sewn {s['shrink']:.3g}" if stage == "sew" else "shrink 0")  # fmt: skip
    ratios = s.get("final_ratios") or []
    return [str(k), escape(stage), where, f"{s.get('regularisation', 0):.3g}",
            str(s.get("iterations", "")), str(s.get("cuts", 0)), f"{s.get('seconds', 0):.2f}",
            ", ".join(f"{r:.2g}" for r in ratios)]  # fmt: skip


def dressing_section(summary: dict) -> str:
    d = summary.get("dressing") or {}
    steps, failed = d.get("steps") or [], d.get("failed_attempts") or []
    facts = (f"{len(steps)} solves, {d.get('newton_iterations', 0)} Newton iterations "
             f"({d.get('all_newton_iterations', 0)} with failed tries and multiplier passes), "
             f"{d.get('cuts', 0)} cut(s); initial shrink {d.get('shrink0_m', 0) * 1e3:.3g} mm; "
             f"spring at the end c = {d.get('final_regularisation_Pa_per_m', 0):.3g} Pa/m, its "
             f"last release changed the pressure by "
             f"{_num(d.get('regularisation_effect'))}.")  # fmt: skip
    al = d.get("augmented_lagrangian_penetration_m") or []
    if al:
        facts += (
            f" Augmented Lagrangian: {len(al)} passes, penetration "
            + " → ".join(f"{p:.2g}" for p in al)
            + " m."
        )
    table = _table(["#", "stage", "where", "spring c [Pa/m]", "Newton its", "cuts", "s",
                    "last ratios r_k/r_k−1"],
                   [_step_row(k + 1, s) for k, s in enumerate(steps)], text=(0, 1, 2))  # fmt: skip
    fails = ""
    if failed:
        fails = "<h3>Failed tries (undone, step halved)</h3>" + _table(
            ["target shrink [mm]", "its", "SNES reason"],
            [[f"{f.get('target_shrink_m', 0) * 1e3:.3g}", str(f.get("iterations")),
              str(f.get("reason"))] for f in failed])  # fmt: skip
    return ('<h2 id="dressing">Dressing: convergence history</h2>'
            f"<p>{escape(facts)}</p>{charts.residual_chart(steps, failed)}"
            f"<details><summary>every solve</summary>{table}{fails}</details>")  # fmt: skip


def time_section(summary: dict) -> str:
    times = dict(summary.get("time_s") or {})
    parts = [k for k in charts.TIME_PARTS if times.get(k)]
    total = times.get("total") or sum(times[k] for k in parts)
    rows = [[escape(k.replace("_", " ")), f"{times[k]:.2f}",
             f"{times[k] / total:.0%}" if total else "–"] for k in parts]  # fmt: skip
    rows.append(["total (build to outputs)", f"{total:.2f}", ""])
    solver = summary.get("solver_time_s") or {}
    parts_in = ("jit", "residual", "jacobian", "hooks", "jacobian_hooks", "solve")
    inside = [[escape(k), f"{v:.2f}"] for k, v in solver.items() if k in parts_in]
    return ('<h2 id="time">Time split</h2>' + charts.time_bar(times)
            + _table(["part", "seconds", "share"], rows)
            + ("<details><summary>inside Newton</summary>"
               + _table(["part", "seconds"], inside) + "</details>" if inside else ""))  # fmt: skip


def files_section(folder: Path) -> str:
    rows = []
    for p in sorted(folder.iterdir()):
        if p.name.startswith(".") or p.name == REPORT_FILE:
            continue
        size = p.stat().st_size if p.is_file() else sum(
            f.stat().st_size for f in p.rglob("*") if f.is_file())  # fmt: skip
        rows.append([escape(p.name + ("/" if p.is_dir() else "")), f"{size / 1e3:.1f}"])
    scene = folder / "scene_used.toml"
    used = (f"<details><summary>scene_used.toml</summary><pre>{escape(scene.read_text())}</pre>"
            "</details>" if scene.is_file() else "")  # fmt: skip
    return '<h2 id="files">Files of the run</h2>' + _table(["file", "kB"], rows) + used


# ------------------------------------------------------------------------------------------------
# The page
# ------------------------------------------------------------------------------------------------


def build_html(folder: Path) -> str:
    """The report of the run in ``folder`` as one HTML string (raises :class:`ReportError`)."""
    folder = Path(folder)
    summary, state = read_run(folder)
    surfaces = read_surfaces(folder)
    body = "".join([
        header_section(folder, summary, state),
        checks_section(summary),
        viewer_section(surfaces),
        maps_section(folder),
        regions_section(region_rows(folder, summary), summary),
        sensors_section(summary),
        dressing_section(summary),
        time_section(summary),
        files_section(folder),
    ])  # fmt: skip
    title = escape(f"{summary.get('scene', folder.name)}: fenics-garment report")
    script = f"<script>{_asset('viewer.js')}</script>" if surfaces else ""
    return (
        f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>{title}</title>'
        f'<meta name="viewport" content="width=device-width, initial-scale=1">'
        f"<style>{_asset('report.css')}</style></head><body>{body}{script}</body></html>\n"
    )


def write_report(folder: Path) -> tuple[Path, float]:
    """Write ``report.html`` into the run folder ``folder``; returns (its path, seconds)."""
    t0 = time.perf_counter()
    folder = Path(folder)
    html = build_html(folder)
    path = output.atomic_write(folder / REPORT_FILE,
                               lambda p: p.write_text(html, encoding="utf-8"))  # fmt: skip
    return path, time.perf_counter() - t0
