"""The pattern of a meshed garment: its flat pieces as a :class:`~.model.Pattern`, to write as
our format or DXF-AAMA (a built-in garment's flattened pieces, for a garment CAD system or to
edit and dress as ``kind = "pattern"``).

Each piece (:func:`fenics_garment.output.pattern_pieces`) becomes a panel whose outline is its
boundary in flat coordinates (vertex and edge nodes, so a curved seam keeps its shape), split
into edges where the garment's edge name changes (``hem``, ``armhole_left``, ``side_seam_left``,
``princess_front_left`` …). An edge name shared by two pieces is a seam between them. The
grain is +x (the flat coordinates' warp).
"""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np

from .model import Edge, EdgeRange, Line, Panel, Pattern, PatternError, Polyline, Seam

#: the P2 cell's boundary: (vertex, edge node, vertex) in DOLFINx / basix node order (edge
#: nodes of edges (1, 2), (0, 2), (0, 1)) and in gmsh's (edges (0, 1), (1, 2), (2, 0))
_SIDES = {"basix": ((0, 5, 1), (1, 3, 2), (2, 4, 0)), "gmsh": ((0, 3, 1), (1, 4, 2), (2, 5, 0))}


def _sides(cf: np.ndarray) -> tuple:
    """The boundary sides of the cells' node order: the order in which each side's edge node
    sits at the middle of its two vertices in the flat pieces (cells nearly straight-sided)."""

    def miss(sides: tuple) -> float:
        return sum(float(np.abs(cf[:, m] - 0.5 * (cf[:, i] + cf[:, j])).mean())
                   for i, m, j in sides)  # fmt: skip

    return min(_SIDES.values(), key=miss)


def _loop(sides: list[tuple[int, int, int]]) -> list[tuple[int, int, int]]:
    """Chain oriented boundary sides (a, mid, b) into one closed loop."""
    nxt = {a: (a, m, b) for a, m, b in sides}
    if len(nxt) != len(sides):
        raise PatternError("a piece's boundary passes twice through a node")
    start = min(nxt)
    loop, a = [], start
    for _ in range(len(sides)):
        s = nxt[a]
        loop.append(s)
        a = s[2]
        if a == start:
            break
    if len(loop) != len(sides):
        raise PatternError("a piece has more than one boundary (a hole): not a pattern piece")
    return loop


def _outline(cells: np.ndarray, cn: np.ndarray, cf: np.ndarray, sides_of: tuple) -> tuple:
    """The boundary loop of one piece as (node, edge node, node) sides, with each piece node's
    flat position and mesh node. A piece node is a mesh node *at a flat position*: the two
    sides of a seam within one piece (a tube's, a dart's) are the same mesh nodes at
    different places of the piece."""
    ids: dict[tuple, int] = {}
    flat, node = {}, {}

    def fid(c: int, i: int) -> int:
        key = (int(cn[c, i]), *np.round(cf[c, i], 9).tolist())
        if key not in ids:
            ids[key] = len(ids)
            flat[ids[key]], node[ids[key]] = cf[c, i], int(cn[c, i])
        return ids[key]

    count: Counter = Counter()
    oriented = []
    for c in cells:
        for i, m, j in sides_of:
            a, mid, b = fid(c, i), fid(c, m), fid(c, j)
            count[(min(a, b), max(a, b))] += 1
            oriented.append((a, mid, b))
    sides = [s for s in oriented if count[(min(s[0], s[2]), max(s[0], s[2]))] == 1]
    return _loop(sides), flat, node


def garment_pattern(garment: Any, name: str) -> Pattern:
    """The flat pieces of ``garment`` (a GarmentSurface with ``rest``) as a pattern, each
    piece named after the garment panel of most of its cells (``piece_<k>`` if unknown)."""
    from fenics_garment.output import pattern_pieces

    rest = garment.rest
    cell_panel = rest.cell_panel
    cn, cf = np.asarray(rest.cell_nodes), np.asarray(rest.cell_flat)
    piece = pattern_pieces(cn, cf)
    names_of = {tag: n for n, tag in garment.panels.items()}
    edge_name = {}
    for ename, pairs in garment.edge_nodes.items():
        for a, b in np.asarray(pairs)[:, :2]:
            edge_name[(min(a, b), max(a, b))] = ename
    sides_of = _sides(cf)
    glob: Counter = Counter()  # a pair of vertices on two cells: inside the garment (a seam)
    for i, _, j in sides_of:
        for a, b in zip(cn[:, i].tolist(), cn[:, j].tolist(), strict=True):
            glob[(min(a, b), max(a, b))] += 1
    panels, owners = {}, {}
    for k in range(int(piece.max()) + 1):
        cells = np.flatnonzero(piece == k)
        if cell_panel is not None:
            tag = Counter(np.asarray(cell_panel)[cells].tolist()).most_common(1)[0][0]
            pname = names_of.get(tag, f"piece_{k}")
        else:
            pname = f"piece_{k}"
        while pname in panels:
            pname += "_"
        loop, flat, node = _outline(cells, cn, cf, sides_of)

        def label(a: int, b: int, node: dict = node) -> str:
            key = (min(node[a], node[b]), max(node[a], node[b]))
            name = edge_name.get(key, "")
            return f"seam:{name}" if glob[key] == 2 else name

        labels = [label(a, b) for a, _, b in loop]
        # start the outline where the name changes, so that no edge wraps round the start
        cut = next((i for i in range(len(loop)) if labels[i] != labels[i - 1]), 0)
        loop, labels = loop[cut:] + loop[:cut], labels[cut:] + labels[:cut]
        edges, run = [], [loop[0]]
        seen = {node[loop[0][0]], node[loop[0][2]]}  # the garment nodes of the current run
        for side, label, prev in zip(loop[1:], labels[1:], labels, strict=False):
            # a new edge where the name changes, and where a seam comes back along itself: the
            # two legs of a dart meet at its tip and are sewn to each other (same name)
            if label != prev or (label.startswith("seam:") and node[side[2]] in seen):
                edges.append((prev, run))
                run, seen = [], {node[side[0]]}
            run.append(side)
            seen.add(node[side[2]])
        edges.append((labels[-1], run))
        out = []
        for label, run in edges:
            pts = [flat[run[0][0]]] + [p for a, m, b in run for p in (flat[m], flat[b])]
            curve = Polyline(np.array(pts)) if len(pts) > 2 else Line(pts[0], pts[-1])
            out.append(Edge(curve, label.removeprefix("seam:")))
            if label.startswith("seam:"):  # its partner has the same vertices
                key = frozenset(node[v] for a, _, b in run for v in (a, b))
                owners.setdefault(key, []).append((pname, len(out) - 1))
        panels[pname] = Panel(pname, tuple(out), np.array([1.0, 0.0]))
    seams, used = [], Counter()
    for sides in owners.values():
        if len(sides) != 2:
            raise PatternError(f"a seam of the garment joins {len(sides)} piece edges, not 2")
        label = panels[sides[0][0]].edges[sides[0][1]].name or "seam"
        used[label] += 1
        tag = label if used[label] == 1 else f"{label}_{used[label]}"
        seams.append(Seam(EdgeRange(*sides[0]), EdgeRange(*sides[1]), True, tag))
    return Pattern(name, panels, tuple(seams))
