"""Small inline SVG charts for the report (no plotting library: plain SVG text)."""

from __future__ import annotations

import math
from html import escape

from fenics_garment.output import COMFORT_BANDS

#: Colours of the statistics of a region (points of the pressure chart) and of the dressing's
#: stages (residual history).
STAT_STYLE = {"mean": "#1f77b4", "p95": "#d62728", "sensor_p95": "#2ca02c",
              "body_sensor_p95": "#9467bd"}  # fmt: skip
STAT_LABEL = {"mean": "mean", "p95": "p95", "sensor_p95": "sensor p95",
              "body_sensor_p95": "skin sensor p95"}  # fmt: skip
STAGE_STYLE = {"dress": "#1f77b4", "sew": "#ff7f0e", "release": "#2ca02c", "failed": "#d62728"}
BAND_FILL = ("#e8f5e9", "#c8e6c9", "#fff3c4", "#ffe0b2", "#ffcdd2")


def nice_ticks(top: float, n: int = 5) -> list[float]:
    """Round tick values from 0 to at least ``top``."""
    if top <= 0 or not math.isfinite(top):
        return [0.0, 1.0]
    raw = top / n
    mag = 10 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1, 2, 2.5, 5, 10) if m * mag >= raw)
    return [k * step for k in range(math.ceil(top / step - 1e-9) + 1)]


def _fmt(v: float) -> str:
    return f"{v:.4g}"


def _svg(width: int, height: int, body: list[str], label: str) -> str:
    return (f'<svg viewBox="0 0 {width} {height}" '
            f'width="{width}" height="{height}" role="img" aria-label="{escape(label)}">'
            + "".join(body) + "</svg>")  # fmt: skip


def pressure_chart(regions: list[dict]) -> str:
    """Per region in contact: mean, p95 and the sensors' p95 [kPa] as points with their error
    bars (``<stat>_err_kPa``, when the run had them), over the comfort bands."""
    rows = [r for r in regions if r.get("contact_area_m2", 0) > 0]
    if not rows:
        return "<p>No region is in contact.</p>"
    stats = [s for s in STAT_STYLE if any(f"{s}_kPa" in r for r in rows)]
    top = max(r.get(f"{s}_kPa", 0) + (r.get(f"{s}_err_kPa") or 0) for r in rows for s in stats)
    ticks = nice_ticks(1.15 * max(top, 0.1))
    ymax = ticks[-1]
    left, right, up, low = 56, 170, 14, 70
    width = left + right + max(360, 80 * len(rows))
    height = 320
    plot_w, plot_h = width - left - right, height - up - low

    def y(v: float) -> float:
        return up + plot_h * (1 - min(v, ymax) / ymax)

    out = []
    lower = 0.0
    for (upper, name), fill in zip(COMFORT_BANDS, BAND_FILL, strict=True):
        if lower >= ymax:
            break
        y0, y1 = y(min(upper, ymax)), y(lower)
        out.append(f'<rect x="{left}" y="{y0:.1f}" width="{plot_w}" height="{y1 - y0:.1f}" '
                   f'fill="{fill}"><title>{escape(name)}: {lower:g}–{upper:g} kPa</title></rect>'
                   f'<text x="{left + plot_w - 4}" y="{y0 + 12:.1f}" text-anchor="end" '
                   f'class="band">{escape(name)}</text>')  # fmt: skip
        lower = upper
    for t in ticks:
        out.append(f'<line x1="{left - 4}" x2="{left + plot_w}" y1="{y(t):.1f}" y2="{y(t):.1f}" '
                   f'class="grid"/><text x="{left - 7}" y="{y(t) + 4:.1f}" '
                   f'text-anchor="end">{t:g}</text>')  # fmt: skip
    out.append(f'<text x="14" y="{up + plot_h / 2}" transform="rotate(-90 14 {up + plot_h / 2})" '
               'text-anchor="middle">pressure [kPa]</text>')  # fmt: skip
    slot = plot_w / len(rows)
    for i, r in enumerate(rows):
        cx = left + slot * (i + 0.5)
        out.append(f'<text x="{cx:.1f}" y="{up + plot_h + 18}" text-anchor="middle">'
                   f'{escape(str(r["region"]))}</text>')  # fmt: skip
        for j, s in enumerate(stats):
            if f"{s}_kPa" not in r:
                continue
            x = cx + (j - (len(stats) - 1) / 2) * min(14.0, slot / (len(stats) + 1))
            out.append(_point(x, r[f"{s}_kPa"], r.get(f"{s}_err_kPa"), y, s, r["region"]))
    for j, s in enumerate(stats):  # legend
        ly = up + 14 + 18 * j
        out.append(
            f'<circle cx="{width - right + 20}" cy="{ly}" r="4" fill="{STAT_STYLE[s]}"/>'
            f'<text x="{width - right + 30}" y="{ly + 4}">{STAT_LABEL[s]}</text>'
        )
    if any(f"{s}_err_kPa" in r for r in rows for s in stats):
        ly = up + 14 + 18 * len(stats)
        out.append(f'<text x="{width - right + 14}" y="{ly + 4}">│ error bar</text>')
    out.append(f'<rect x="{left}" y="{up}" width="{plot_w}" height="{plot_h}" class="frame"/>')
    return _svg(width, height, out, "pressure per region with comfort bands")


def _point(x: float, value: float, err: float | None, y, stat: str, region: str) -> str:
    colour = STAT_STYLE[stat]
    tip = f"{region}: {STAT_LABEL[stat]} {value:.3g} kPa"
    bar = ""
    if err is not None and math.isfinite(err):
        tip += f" ± {err:.2g}"
        bar = (
            f'<line x1="{x:.1f}" x2="{x:.1f}" y1="{y(value + err):.1f}" '
            f'y2="{y(max(value - err, 0.0)):.1f}" stroke="{colour}" stroke-width="1.5"/>'
        )
    return (f'<g class="point">{bar}<circle cx="{x:.1f}" cy="{y(value):.1f}" r="4" '
            f'fill="{colour}"><title>{escape(tip)}</title></circle></g>')  # fmt: skip


def residual_chart(steps: list[dict], failed: list[dict]) -> str:
    """Newton's residual norm ‖F‖ at every iteration of every solve, one after the other
    (log scale), coloured by the dressing's stage; failed tries in red."""
    runs = [(s.get("stage", "dress"), s.get("residuals") or []) for s in steps]
    runs += [("failed", f.get("residuals") or []) for f in failed]
    values = [v for _, rs in runs for v in rs if v > 0 and math.isfinite(v)]
    if not values:
        return "<p>No residual history was recorded.</p>"
    lo = math.floor(math.log10(min(values)))
    hi = math.ceil(math.log10(max(values)))
    hi = max(hi, lo + 1)
    n = sum(len(rs) for _, rs in runs)
    left, right, up, low = 56, 120, 12, 40
    width, height = 760, 280
    plot_w, plot_h = width - left - right, height - up - low

    def xy(k: int, v: float) -> str:
        return (
            f"{left + plot_w * k / max(n - 1, 1):.1f},"
            f"{up + plot_h * (hi - math.log10(v)) / (hi - lo):.1f}"
        )

    out = []
    for e in range(lo, hi + 1):
        yy = up + plot_h * (hi - e) / (hi - lo)
        out.append(f'<line x1="{left}" x2="{left + plot_w}" y1="{yy:.1f}" y2="{yy:.1f}" '
                   f'class="grid"/><text x="{left - 6}" y="{yy + 4:.1f}" '
                   f'text-anchor="end">1e{e}</text>')  # fmt: skip
    k = 0
    for i, (stage, rs) in enumerate(runs):
        pts = [(k + j, v) for j, v in enumerate(rs) if v > 0 and math.isfinite(v)]
        k += len(rs)
        if not pts:
            continue
        colour = STAGE_STYLE.get(stage, "#555")
        path = " ".join(xy(a, v) for a, v in pts)
        out.append(
            f'<polyline points="{path}" fill="none" stroke="{colour}" stroke-width="1.5">'
            f"<title>solve {i + 1} ({stage}): {len(rs) - 1} iterations</title></polyline>"
        )
    for j, stage in enumerate(s for s in STAGE_STYLE if any(r[0] == s for r in runs)):
        ly = up + 12 + 18 * j
        out.append(f'<line x1="{width - right + 12}" x2="{width - right + 30}" y1="{ly}" '
                   f'y2="{ly}" stroke="{STAGE_STYLE[stage]}" stroke-width="2"/>'
                   f'<text x="{width - right + 36}" y="{ly + 4}">{stage}</text>')  # fmt: skip
    out.append(
        f'<text x="{left + plot_w / 2}" y="{height - 8}" text-anchor="middle">'
        "Newton iterate, all solves in order</text>"
    )
    out.append(f'<text x="14" y="{up + plot_h / 2}" transform="rotate(-90 14 {up + plot_h / 2})" '
               'text-anchor="middle">‖F‖ [N]</text>')  # fmt: skip
    out.append(f'<rect x="{left}" y="{up}" width="{plot_w}" height="{plot_h}" class="frame"/>')
    return _svg(width, height, out, "Newton residual history of the dressing")


#: Parts of a run's wall time, in the order they happen ("total" is their sum and more).
TIME_PARTS = ("geometry_and_model", "sequence", "jit", "dressing", "checkpoint", "outputs",
              "report")  # fmt: skip
TIME_COLOURS = ("#8c564b", "#17becf", "#ff7f0e", "#1f77b4", "#7f7f7f", "#2ca02c", "#e377c2")


def time_bar(times: dict[str, float]) -> str:
    """The run's time split as one stacked horizontal bar."""
    parts = [(k, float(times[k]), c) for k, c in zip(TIME_PARTS, TIME_COLOURS, strict=True)
             if times.get(k)]  # fmt: skip
    total = sum(v for _, v, _ in parts)
    if total <= 0:
        return "<p>No time was recorded.</p>"
    width, height, x = 760, 64, 0.0
    out = []
    for name, v, colour in parts:
        w = 740 * v / total
        out.append(
            f'<rect x="{10 + x:.1f}" y="6" width="{w:.1f}" height="26" fill="{colour}">'
            f"<title>{name}: {v:.2f} s ({v / total:.0%})</title></rect>"
        )
        if w > 6.5 * len(name) + 8:  # the label fits on its part
            out.append(f'<text x="{10 + x + w / 2:.1f}" y="24" text-anchor="middle" '
                       f'class="onbar">{name.replace("_", " ")}</text>')  # fmt: skip
        x += w
    out.append(
        f'<text x="10" y="52">0 s</text><text x="750" y="52" text-anchor="end">'
        f"{_fmt(total)} s</text>"
    )
    return _svg(width, height, out, "time split of the run")
