"""Refuse malformed sewing patterns, and orient outlines counter-clockwise.

:func:`validate` raises :class:`~.model.PatternError` with one line that names the pattern
(its file, else its name), the panel and the edge (index and name) for the first problem of:

* an outline of fewer than 2 edges, an edge of zero length or a degenerate arc (three points
  on a line); two edges are enough when one of them is curved (a half disc), and two straight
  edges enclose no area, which the area check refuses;
* an outline that is not closed: edge i's end is not edge i + 1's start (the last edge's end
  not the first's start) within :data:`CLOSURE_TOLERANCE` × max(1 m, the panel's size);
* an outline that crosses itself: the edges are sampled (:func:`outline_samples`, lines
  exactly, curves at about 1000 points a panel, polylines at their own points) and every
  pair of non-adjacent segments is tested for a proper crossing (vectorised, pruned by the
  bounding boxes of runs of consecutive segments: milliseconds for 2000 points);
* an outline that encloses no area, or (unless ``allow_clockwise``) runs clockwise; the
  readers orient outlines with :func:`oriented` (reverse the edge order and each curve, remap
  the seams: the geometry is untouched) after validating with ``allow_clockwise=True``, so
  the messages count edges as the file does;
* a seam range naming a missing panel or edge, with fractions outside [0, 1] or f0 == f1;
* a seam whose two ranges differ in length by more than ``seam_tolerance`` (relative to the
  longer one; both lengths in mm in the message);
* two seams (or darts) using overlapping ranges of one edge.

A missing grain line is the reader's to refuse (a :class:`~.model.Panel` always has one).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .model import (
    Arc,
    Array,
    Edge,
    EdgeRange,
    Line,
    Panel,
    Pattern,
    PatternError,
    Polyline,
    Seam,
    reverse_curve,
)

#: outline closure tolerance, relative to max(1 m, the panel's size) (so 1 µm for a garment)
CLOSURE_TOLERANCE = 1e-6
#: about this many samples per panel for the self-intersection test (lines take one segment)
CURVE_SAMPLES = 1000


def _where(pattern: Pattern) -> str:
    return pattern.source or pattern.name or "pattern"


def _edge_label(panel: Panel, i: int) -> str:
    name = panel.edges[i].name if 0 <= i < len(panel.edges) else ""
    return f"edge {i} {name!r}" if name else f"edge {i}"


def _range_label(pattern: Pattern, r: EdgeRange) -> str:
    p = pattern.panels.get(r.panel)
    edge = _edge_label(p, r.edge) if p is not None else f"edge {r.edge}"
    return f"panel {r.panel!r} {edge}"


def outline_samples(panel: Panel, n: int = CURVE_SAMPLES) -> tuple[Array, np.ndarray]:
    """The closed outline as points (last not repeated) and the edge index of the segment
    that starts at each point: lines one segment, polylines their own points, arcs and
    Bézier curves uniformly in their parameter, about ``n`` points over the outline."""
    lengths = np.array([e.length for e in panel.edges])
    perimeter = float(lengths.sum())
    pts, owner = [], []
    for i, (e, length) in enumerate(zip(panel.edges, lengths, strict=True)):
        c = e.curve
        if isinstance(c, Line):
            p = c.start[None, :]
        elif isinstance(c, Polyline):
            p = c.points[:-1]
        else:
            k = int(np.clip(np.ceil(n * length / perimeter), 8, n))
            p = c.point(np.linspace(0.0, 1.0, k + 1))[:-1]
        pts.append(p)
        owner.append(np.full(len(p), i))
    return np.concatenate(pts), np.concatenate(owner)


def signed_area(panel: Panel) -> float:
    """The area enclosed by the outline, positive when it runs counter-clockwise."""
    p, _ = outline_samples(panel)
    q = np.roll(p, -1, axis=0)
    return 0.5 * float(np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]))


def _cross(u: Array, v: Array) -> Array:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def first_crossing(points: Array, chunk: int = 16) -> tuple[int, int, Array] | None:
    """The first pair (i, j), i < j, of non-adjacent segments of the closed polygon ``points``
    that cross properly (touching does not count), and the crossing point; None if none do.

    Consecutive segments are grouped in chunks of ``chunk``; only chunks whose bounding boxes
    overlap have their segment pairs tested, all at once (vectorised): an outline of 2000
    points takes milliseconds.
    """
    a = np.asarray(points, float)
    m = len(a)
    if m < 4:
        return None
    b = np.roll(a, -1, axis=0)
    d = b - a
    scale = float(np.ptp(a, axis=0).max()) or 1.0
    eps = 1e-12 * scale * scale
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    nc = -(-m // chunk)
    pad = nc * chunk - m
    clo = np.concatenate([lo, np.repeat(lo[-1:], pad, axis=0)]).reshape(nc, chunk, 2).min(1)
    chi = np.concatenate([hi, np.repeat(hi[-1:], pad, axis=0)]).reshape(nc, chunk, 2).max(1)
    over = np.all((clo[:, None, :] <= chi[None, :, :]) & (clo[None, :, :] <= chi[:, None, :]), -1)
    ci, cj = np.nonzero(np.triu(over))
    k = np.arange(chunk)
    i = (ci[:, None, None] * chunk + k[None, :, None]).repeat(chunk, axis=2).ravel()
    j = (cj[:, None, None] * chunk + k[None, None, :]).repeat(chunk, axis=1).ravel()
    keep = (j < m) & (j > i + 1) & ~((i == 0) & (j == m - 1))
    i, j = i[keep], j[keep]
    keep = np.all((lo[i] <= hi[j]) & (lo[j] <= hi[i]), axis=1)
    i, j = i[keep], j[keep]
    o1 = _cross(d[i], a[j] - a[i])
    o2 = _cross(d[i], b[j] - a[i])
    o3 = _cross(d[j], a[i] - a[j])
    o4 = _cross(d[j], b[i] - a[j])
    hit = (((o1 > eps) & (o2 < -eps)) | ((o1 < -eps) & (o2 > eps))) & (
        ((o3 > eps) & (o4 < -eps)) | ((o3 < -eps) & (o4 > eps))
    )
    if not hit.any():
        return None
    first = np.flatnonzero(hit)
    h = first[np.lexsort((j[first], i[first]))[0]]
    u = o3[h] / (o3[h] - o4[h])
    return int(i[h]), int(j[h]), a[i[h]] + u * d[i[h]]


def _check_panel(where: str, panel: Panel, allow_clockwise: bool) -> None:
    head = f"{where}: panel {panel.name!r}"
    n = len(panel.edges)
    if n < 2:
        raise PatternError(f"{head}: an outline needs at least 2 edges, it has {n}")
    for i, e in enumerate(panel.edges):
        try:
            length = e.length
        except PatternError as err:
            raise PatternError(f"{head}, {_edge_label(panel, i)}: {err}") from None
        if not np.isfinite(length) or length <= 0.0:
            raise PatternError(f"{head}, {_edge_label(panel, i)}: the edge has no length")
        if isinstance(e.curve, Arc) and not np.isfinite(e.curve.circle[1]):
            raise PatternError(f"{head}, {_edge_label(panel, i)}: degenerate arc")
    ends = np.array([[e.curve.start, e.curve.end] for e in panel.edges])
    size = float(np.ptp(ends.reshape(-1, 2), axis=0).max())
    tol = CLOSURE_TOLERANCE * max(1.0, size)
    for i in range(n):
        k = (i + 1) % n
        gap = float(np.linalg.norm(panel.edges[i].curve.end - panel.edges[k].curve.start))
        if gap > tol:
            raise PatternError(
                f"{head}: the outline is not closed: {_edge_label(panel, i)} ends "
                f"{gap * 1e3:.6g} mm away from where {_edge_label(panel, k)} starts"
            )
    points, owner = outline_samples(panel)
    hit = first_crossing(points)
    if hit is not None:
        s, t, x = hit
        raise PatternError(
            f"{head}: the outline crosses itself: {_edge_label(panel, int(owner[s]))} crosses "
            f"{_edge_label(panel, int(owner[t]))} near ({x[0] * 1e3:.1f}, {x[1] * 1e3:.1f}) mm"
        )
    area = signed_area(panel)
    if abs(area) <= 1e-9 * max(size, 1e-3) ** 2:
        raise PatternError(f"{head}: the outline (edges 0 to {n - 1}) encloses no area")
    if area < 0 and not allow_clockwise:
        raise PatternError(
            f"{head}: the outline (edges 0 to {n - 1}) runs clockwise; "
            "orient it with fenics_garment.pattern.validate.oriented()"
        )


def _check_range(where: str, pattern: Pattern, seam: str, side: str, r: EdgeRange) -> None:
    head = f"{where}: {seam} side {side}"
    if r.panel not in pattern.panels:
        raise PatternError(
            f"{head}: no panel {r.panel!r} (edge {r.edge}; panels: {list(pattern.panels)})"
        )
    p = pattern.panels[r.panel]
    if not (isinstance(r.edge, (int, np.integer)) and 0 <= r.edge < len(p.edges)):
        raise PatternError(
            f"{head}: panel {r.panel!r} has no edge {r.edge!r} (it has {len(p.edges)} edges)"
        )
    f0, f1 = float(r.f0), float(r.f1)
    if not (0.0 <= f0 <= 1.0 and 0.0 <= f1 <= 1.0) or abs(f1 - f0) < 1e-12:
        raise PatternError(
            f"{head}: {_range_label(pattern, r)}: the range {f0:g} to {f1:g} is not a "
            "non-empty part of [0, 1]"
        )


def _seam_label(pattern: Pattern, k: int) -> str:
    s = pattern.seams[k]
    return f"{s.kind} {pattern.seam_name(k)!r}"


def _check_seams(where: str, pattern: Pattern, seam_tolerance: float) -> None:
    uses: dict[tuple[str, int], list[tuple[float, float, int]]] = {}
    for k, s in enumerate(pattern.seams):
        label = _seam_label(pattern, k)
        _check_range(where, pattern, label, "a", s.a)
        _check_range(where, pattern, label, "b", s.b)
        la, lb = pattern.range_length(s.a), pattern.range_length(s.b)
        if abs(la - lb) > seam_tolerance * max(la, lb):
            raise PatternError(
                f"{where}: {label}: {_range_label(pattern, s.a)} is {la * 1e3:.1f} mm, "
                f"{_range_label(pattern, s.b)} is {lb * 1e3:.1f} mm "
                f"({abs(la - lb) / max(la, lb):.1%} apart, tolerance {seam_tolerance:.1%})"
            )
        for r in (s.a, s.b):
            uses.setdefault((r.panel, int(r.edge)), []).append(
                (min(r.f0, r.f1), max(r.f0, r.f1), k)
            )
    for (panel, edge), spans in uses.items():
        spans.sort()
        lo0, hi0, k0 = spans[0]
        for lo1, hi1, k1 in spans[1:]:
            if min(hi0, hi1) - lo1 > 1e-9:
                who = (
                    f"{_seam_label(pattern, k0)} uses it twice"
                    if k0 == k1
                    else f"{_seam_label(pattern, k0)} and {_seam_label(pattern, k1)} overlap"
                )
                raise PatternError(
                    f"{where}: panel {panel!r} {_edge_label(pattern.panels[panel], edge)}: "
                    f"{who} ({lo0:g} to {hi0:g} and {lo1:g} to {hi1:g})"
                )
            if hi1 > hi0:
                lo0, hi0, k0 = lo1, hi1, k1


def validate(
    pattern: Pattern, *, seam_tolerance: float = 0.02, allow_clockwise: bool = False
) -> None:
    """Raise :class:`PatternError` (one line naming file, panel and edge) if the pattern is
    malformed (module docstring); return None if it is sound."""
    where = _where(pattern)
    for name, panel in pattern.panels.items():
        if name != panel.name:
            raise PatternError(f"{where}: panel {panel.name!r} is filed under {name!r}")
        _check_panel(where, panel, allow_clockwise)
    _check_seams(where, pattern, seam_tolerance)


def reversed_panel(panel: Panel) -> Panel:
    """The panel with its outline run the other way: edge i becomes edge n − 1 − i, each
    curve reversed; names, grain, fabric and placement kept (the geometry is unchanged)."""
    edges = tuple(Edge(reverse_curve(e.curve), e.name) for e in reversed(panel.edges))
    return replace(panel, edges=edges)


def _remap(r: EdgeRange, n: int) -> EdgeRange:
    return EdgeRange(r.panel, n - 1 - int(r.edge), 1.0 - r.f1, 1.0 - r.f0)


def oriented(pattern: Pattern) -> Pattern:
    """The pattern with every clockwise outline reversed (:func:`reversed_panel`) and the seams
    remapped: a range on a reversed panel moves to the new edge index and its fractions to
    1 − f, kept increasing, so the seam's ``reversed`` flips once per reversed side (two
    reversed sides, or a dart, keep it). Unchanged (the same object) if all run
    counter-clockwise."""
    flip = {name for name, p in pattern.panels.items() if signed_area(p) < 0}
    if not flip:
        return pattern
    panels = {name: reversed_panel(p) if name in flip else p for name, p in pattern.panels.items()}
    seams = []
    for s in pattern.seams:
        a, b, rev = s.a, s.b, s.reversed
        if a.panel in flip:
            a, rev = _remap(a, len(pattern.panels[a.panel].edges)), not rev
        if b.panel in flip:
            b, rev = _remap(b, len(pattern.panels[b.panel].edges)), not rev
        seams.append(Seam(a, b, rev, s.name, s.kind))
    return replace(pattern, panels=panels, seams=tuple(seams))


def normalised_range(r: EdgeRange) -> tuple[EdgeRange, bool]:
    """The range with f0 ≤ f1, and whether it was swapped (then the seam's ``reversed``
    flips, so that the same points meet)."""
    if r.f0 <= r.f1:
        return r, False
    return EdgeRange(r.panel, r.edge, r.f1, r.f0), True


def checked(pattern: Pattern, *, seam_tolerance: float = 0.02) -> Pattern:
    """What every reader returns: the pattern validated as the file has it (clockwise
    outlines allowed, so messages count edges as the file does), then :func:`oriented`."""
    validate(pattern, seam_tolerance=seam_tolerance, allow_clockwise=True)
    return oriented(pattern)
