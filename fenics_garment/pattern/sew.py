"""Sewing the placed flat panels into one conforming surface around the body.

Method: a spring relaxation of the panels' node nets. Every order-2 triangle is split into its
4 sub-triangles through the edge nodes, and the energy

    ½ Σ_edges (|xᵢ − xⱼ| − Lᵢⱼ)² + ½ β Σ_hinges (|xₖ − xₗ| − Lₖₗ)²
        + ½ σ Σ_seams (|xₐ − x_b| − g)² + ½ κ Σ_nodes min(φ(xᵢ), 0)²

is minimised by L-BFGS whose initial inverse Hessian is the factorised projective-dynamics
matrix (the weighted graph Laplacian of the springs; Liu, Bouaziz & Kavan, "Quasi-Newton
methods for real-time simulation of hyperelastic materials", ACM TOG 36(3), 2017; plain
projective-dynamics iterations, measured first, converged an order of magnitude slower).
``Lᵢⱼ`` are the **flat** lengths of the sub-triangle edges; the hinge springs join the two far
nodes of every pair of sub-triangles sharing an edge (flat length too: they resist folding,
β = 0.1); the seam springs (σ = 1) pull partners together, their rest length ``g`` shrinking
from the initial gap to zero in a few steps; φ is the signed distance to the body's surface
offset by ``clearance`` (κ = 5), linearised at the closest point found by libigl's AABB
tree (:class:`~fenics_garment.contact.search.SearchSurface`) and searched again only for the
nodes that moved and may have come within ``band`` of the body (the distance is 1-Lipschitz).

Stages: (1) the seams shrink, (2) every group of partners is merged into one node at their
mean position and the merged net is relaxed again.

The report (``Sewn.report``) gives the seam gap before merging, the edge strain against the
flat lengths (RMS and max), the sub-triangles folded against their neighbours, the largest
penetration into the body and the number of node pairs touching that are not mesh neighbours
(a self-contact proxy), with the times and iteration counts.

numpy's BLAS is kept out of the loops (``einsum`` instead of ``dot``): on a busy 2-core
machine OpenBLAS's threads contended and made the relaxation 25× slower (measured).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from fenics_garment.shell.rest import FlatCells

from .mesh import FlatPanels

Array = npt.NDArray[np.float64]
IArray = npt.NDArray[np.int64]

#: sub-triangles of a 6-node triangle (v0, v1, v2, m01, m12, m20), counter-clockwise as it is
SUB_TRIANGLES = np.array([[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]])


@dataclass(eq=False)
class Sewn:
    """The sewn surface: merged nodes and the report of the relaxation.

    ``points`` (K, 3) are the merged nodes' positions; ``node_of`` (N,) maps each flat node to
    its merged node (partners share one); ``cells`` (M, 6 or 3) are the flat cells in merged
    numbering; ``subtriangles`` (4M, 3) the sub-triangles (merged numbering) and
    ``sub_cell`` their cell; ``panel_sign`` (n_panels,) is +1 where a panel's flat
    counter-clockwise side faces away from the body, −1 where it faces the body.
    """

    points: Array
    node_of: IArray
    cells: IArray
    subtriangles: IArray
    sub_cell: IArray
    panel_sign: Array
    report: dict[str, float] = field(default_factory=dict)


def merge_map(n: int, pairs: IArray) -> IArray:
    """Union-find of the seam pairs: the merged index (0 … K−1, in order of first node) of
    every one of ``n`` nodes."""
    parent = np.arange(n)

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b in np.asarray(pairs, dtype=np.int64):
        ra, rb = find(int(a)), find(int(b))
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    roots = np.array([find(i) for i in range(n)])
    _, node_of = np.unique(roots, return_inverse=True)
    return node_of.astype(np.int64)


def _subtriangles(cells: IArray) -> tuple[IArray, IArray]:
    if cells.shape[1] == 6:
        sub = cells[:, SUB_TRIANGLES].reshape(-1, 3)
        return sub, np.repeat(np.arange(len(cells)), 4)
    return cells.copy(), np.arange(len(cells))


def _edges_and_hinges(tri: IArray) -> tuple[IArray, IArray]:
    """Unique undirected edges of a triangle list, and the far node pairs across inner edges."""
    e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    opp = np.concatenate([tri[:, 2], tri[:, 0], tri[:, 1]])
    e_sorted = np.sort(e, axis=1)
    uniq, inv = np.unique(e_sorted, axis=0, return_inverse=True)
    inv = inv.ravel()
    order = np.argsort(inv, kind="stable")
    k = inv[order]
    same = np.flatnonzero(k[1:] == k[:-1])
    hinges = np.column_stack([opp[order[same]], opp[order[same + 1]]])
    hinges = hinges[hinges[:, 0] != hinges[:, 1]]
    return uniq, hinges


def _incidence(pairs: IArray, n: int) -> sp.csr_matrix:
    m = len(pairs)
    rows = np.repeat(np.arange(m), 2)
    vals = np.tile([1.0, -1.0], m)
    return sp.csr_matrix((vals, (rows, pairs.ravel())), shape=(m, n))


class _Collider:
    """Signed distance to the body offset by ``clearance``, searched only where needed."""

    def __init__(self, body: Any, clearance: float, band: float, move: float) -> None:
        from fenics_garment.contact.search import SearchSurface

        self.surface = SearchSurface(body.vertices, body.triangles)
        self.clearance, self.band, self.move = clearance, band, move
        self.queries = 0

    def start(self, X: Array) -> None:
        self.X_last = X.copy()
        self.d_last = np.full(len(X), -np.inf)
        self.c = np.zeros_like(X)
        self.n = np.zeros_like(X)
        self.searched = np.zeros(len(X), dtype=bool)
        self.update(X)

    def update(self, X: Array) -> bool:
        """Search the nodes that may have come near the body; whether any was."""
        travel = np.linalg.norm(X - self.X_last, axis=1)
        need = (self.d_last - travel < self.band) & ((travel > self.move) | ~self.searched)
        if need.any():
            cp = self.surface.closest(X[need], normal="gradient")
            self.c[need], self.n[need] = cp.point, cp.normal
            self.d_last[need] = cp.distance
            self.X_last[need] = X[need]
            self.searched[need] = True
            self.queries += int(need.sum())
            return True
        return False

    def phi(self, X: Array) -> Array:
        """Linearised signed distance to the offset surface (exact where just searched)."""
        return np.einsum("ij,ij->i", X - self.c, self.n) - self.clearance

    def exact(self, X: Array) -> Array:
        return self.surface.closest(X, normal="gradient").distance


def sew(
    flat: FlatPanels,
    X0: Array,
    body: Any = None,
    *,
    clearance: float = 0.002,
    bending: float = 0.1,
    seam_weight: float = 1.0,
    contact_weight: float = 5.0,
    shrink_steps: int = 4,
    shrink_iterations: int = 12,
    merged_iterations: int = 100,
    band: float = 0.02,
) -> Sewn:
    """Relax the placed panels ``X0`` (N, 3) until the seams close, merge the partners, relax.

    ``body``: anything with ``vertices``/``triangles`` (a closed outward surface) to stay
    ``clearance`` [m] outside, or None. ``bending``, ``seam_weight``, ``contact_weight``: the
    weights of the hinge springs, the seam springs and the contact penalty (edges: 1). The seam
    rest lengths shrink to zero in ``shrink_steps`` steps of ``shrink_iterations`` L-BFGS
    iterations, then the merged net gets ``merged_iterations`` (module doc). ``band`` [m]:
    nodes farther than this from the body are not searched until they come closer.
    Returns :class:`Sewn` with ``report``.
    """
    t0 = time.perf_counter()
    X = np.array(X0, dtype=np.float64)
    n = len(X)
    xy = flat.xy
    sub, sub_cell = _subtriangles(flat.cells)
    edges, hinges = _edges_and_hinges(sub)
    rest_e = np.linalg.norm(xy[edges[:, 0]] - xy[edges[:, 1]], axis=1)
    rest_h = np.linalg.norm(xy[hinges[:, 0]] - xy[hinges[:, 1]], axis=1)
    pairs = flat.pairs[flat.pairs[:, 0] != flat.pairs[:, 1]]
    move = 0.3 * float(np.median(rest_e))
    collider = _Collider(body, clearance, band, move) if body is not None else None
    ne, nh = len(edges), len(hinges)
    gap0 = np.linalg.norm(X[pairs[:, 0]] - X[pairs[:, 1]], axis=1)
    report: dict[str, float] = {"nodes": float(n), "initial_seam_gap": float(gap0.max(initial=0))}
    # stage 1: the seams shrink
    if len(pairs):
        if collider is not None:
            collider.start(X)
        springs = np.concatenate([edges, hinges, pairs])
        npair = len(pairs)
        weight = np.concatenate([np.ones(ne), np.full(nh, bending), np.full(npair, seam_weight)])
        precond = np.concatenate([np.ones(ne, bool), np.zeros(nh, bool), np.ones(npair, bool)])
        lu, n_it = None, 0
        for level in np.linspace(1.0, 0.0, shrink_steps + 1)[1:]:
            rest = np.concatenate([rest_e, rest_h, level * gap0])
            X, lu, m = _lbfgs(X, springs, rest, weight, precond, collider, shrink_iterations,
                              contact_weight, clearance, lu)  # fmt: skip
            n_it += m
        report["iterations_seams"] = float(n_it)
    report["seconds_seams"] = time.perf_counter() - t0
    gap = np.linalg.norm(X[pairs[:, 0]] - X[pairs[:, 1]], axis=1)
    report["seam_gap_max"] = float(gap.max(initial=0.0))
    # stage 2: merged
    node_of = merge_map(n, flat.pairs)
    k = int(node_of.max()) + 1
    Xm = np.zeros((k, 3))
    np.add.at(Xm, node_of, X)
    Xm /= np.bincount(node_of, minlength=k)[:, None]
    msprings = node_of[np.concatenate([edges, hinges])]
    keep = msprings[:, 0] != msprings[:, 1]
    msprings, mrest = msprings[keep], np.concatenate([rest_e, rest_h])[keep]
    mw = np.concatenate([np.ones(ne), np.full(nh, bending)])[keep]
    mpre = np.concatenate([np.ones(ne, bool), np.zeros(nh, bool)])[keep]
    if collider is not None:
        collider.start(Xm)
    Xm, _, n_it = _lbfgs(Xm, msprings, mrest, mw, mpre, collider, merged_iterations,
                         contact_weight, clearance)  # fmt: skip
    report["iterations_merged"] = float(n_it)
    report["seconds_relax"] = time.perf_counter() - t0
    msub = node_of[sub]
    quality, sign = _quality(Xm, msub, node_of[edges], rest_e, collider, flat, sub_cell)
    report.update(quality)
    report["seconds"] = time.perf_counter() - t0
    if collider is not None:
        report["body_queries"] = float(collider.queries)
    cells = node_of[flat.cells]
    return Sewn(Xm, node_of, cells, msub, sub_cell, sign, report)


def _dot(a: Array, b: Array) -> float:
    return float(np.einsum("ij,ij->", a, b))  # not BLAS: its threads contend on a busy machine


#: the preconditioner's weight on every node (edges: 1), which makes it definite
NODE_WEIGHT = 0.01


def _lbfgs(
    X: Array,
    springs: IArray,
    rest: Array,
    weight: Array,
    precond: npt.NDArray[np.bool_],
    collider: _Collider | None,
    iterations: int,
    contact_weight: float,
    clearance: float,
    lu: Any = None,
    history: int = 8,
    tol: float = 1e-6,
) -> tuple[Array, Any, int]:
    """Minimise the springs' energy ``Σ w/2 (|xᵢ − xⱼ| − L)²`` plus a penalty
    ``contact_weight/2 · min(φ, 0)²`` on the (linearised) distance φ to the offset body by
    L-BFGS whose initial inverse Hessian is a projective-dynamics matrix, the weighted graph
    Laplacian of the ``precond`` springs plus :data:`NODE_WEIGHT` (plus ``contact_weight``
    on the nodes in contact at the start), factorised once (Liu, Bouaziz & Kavan,
    "Quasi-Newton methods for real-time simulation of hyperelastic materials", ACM TOG
    36(3), 2017). The hinge springs are left out of that matrix: they double its
    factor's fill for little gain. ``lu``: a factor to reuse (same nodes). Stops when no
    node moves more than ``tol`` [m] in an iteration. Returns the positions, the factor and
    the number of iterations made."""
    n = len(X)
    D = _incidence(springs, n)
    DtW = (D.T @ sp.diags(weight)).tocsr()
    if lu is None:
        Dp = D[np.flatnonzero(precond)]
        c = np.full(n, NODE_WEIGHT)
        if collider is not None:
            collider.update(X)
            c = c + contact_weight * (collider.searched & (collider.phi(X) < 0.5 * clearance))
        A = (Dp.T @ sp.diags(weight[precond]) @ Dp + sp.diags(c)).tocsc()
        lu = splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                  options={"SymmetricMode": True})  # fmt: skip

    def springs_energy(X: Array) -> tuple[float, Array]:
        d = D @ X
        length = np.sqrt(np.einsum("ij,ij->i", d, d))
        r = length - rest
        E = 0.5 * float(np.einsum("i,i,i->", weight, r, r))
        return E, DtW @ (d * (r / np.maximum(length, 1e-300))[:, None])

    def contact_energy(X: Array) -> tuple[float, Array | float]:
        if collider is None:
            return 0.0, 0.0
        ph = np.minimum(collider.phi(X), 0.0) * collider.searched
        return 0.5 * contact_weight * float(np.einsum("i,i->", ph, ph)), (
            contact_weight * ph[:, None] * collider.n
        )

    def energy(X: Array) -> tuple[float, Array, float, Array]:
        Es, gs = springs_energy(X)
        Ec, gc = contact_energy(X)
        return Es + Ec, gs + gc, Es, gs

    S: list[Array] = []
    Y: list[Array] = []
    E, g, Es, gs = energy(X)
    it = 0
    while it < iterations:
        it += 1
        if collider is not None and collider.update(X):
            Ec, gc = contact_energy(X)  # the springs' part has not changed
            E, g = Es + Ec, gs + gc
        q = g.copy()
        alphas = []
        for s_, y_ in zip(reversed(S), reversed(Y), strict=True):
            a = _dot(s_, q) / _dot(y_, s_)
            alphas.append(a)
            q -= a * y_
        r = lu.solve(q)
        for (s_, y_), a in zip(zip(S, Y, strict=True), reversed(alphas), strict=True):
            b = _dot(y_, r) / _dot(y_, s_)
            r += (a - b) * s_
        step = -r
        slope = _dot(g, step)
        if slope >= 0:
            S, Y = [], []
            step = -lu.solve(g)
            slope = _dot(g, step)
        t = 1.0
        for _ in range(12):
            E_new, g_new, Es_new, gs_new = energy(X + t * step)
            if E_new <= E + 1e-4 * t * slope:
                break
            t *= 0.5
        s_, y_ = t * step, g_new - g
        if _dot(s_, y_) > 1e-12 * _dot(s_, s_):
            S.append(s_)
            Y.append(y_)
            if len(S) > history:
                S.pop(0)
                Y.pop(0)
        X, E, g, Es, gs = X + s_, E_new, g_new, Es_new, gs_new
        if np.einsum("ij,ij->i", s_, s_).max() < tol * tol:
            break
    return X, lu, it


def _quality(X, sub, edges, rest, collider, flat, sub_cell) -> tuple[dict[str, float], Array]:
    """Strain, folds, penetration and self-contact of the merged net."""
    from scipy.spatial import cKDTree

    out: dict[str, float] = {}
    length = np.linalg.norm(X[edges[:, 0]] - X[edges[:, 1]], axis=1)
    strain = length / rest - 1.0
    out["strain_rms"] = float(np.sqrt(np.mean(strain**2)))
    out["strain_max"] = float(np.abs(strain).max())
    p = X[sub]
    nt = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    panel = flat.cell_panel[sub_cell]
    sign = np.ones(len(flat.names))
    if collider is not None:
        centre = p.mean(axis=1)
        cp = collider.surface.closest(centre, normal="gradient")
        for pi in range(len(flat.names)):
            sel = panel == pi
            sign[pi] = 1.0 if np.sum(np.einsum("ij,ij->i", nt[sel], cp.normal[sel])) >= 0 else -1.0
        d = collider.exact(X)
        out["penetration_max"] = float(max(0.0, -d.min()))
        out["clearance_min"] = float(d.min())
    nt = nt * sign[panel][:, None]
    nv = np.zeros_like(X)
    for j in range(3):
        np.add.at(nv, sub[:, j], nt)
    nbar = nv[sub].sum(axis=1)
    out["inverted"] = float(np.sum(np.einsum("ij,ij->i", nt, nbar) <= 0))
    out["area_ratio_min"] = float(
        (0.5 * np.linalg.norm(nt, axis=1) / _flat_area(flat, sub_cell)).min()
    )
    # self-contact proxy: nodes closer than a third of the shortest rest edge that are not
    # within two rings of each other in the merged net
    r = rest.min() / 3.0
    close = cKDTree(X).query_pairs(r, output_type="ndarray")
    if len(close):
        n = len(X)
        A = sp.csr_matrix((np.ones(2 * len(edges)), (edges.ravel(), edges[:, ::-1].ravel())),
                          shape=(n, n))  # fmt: skip
        A2 = A @ A + A
        near = np.asarray(A2[close[:, 0], close[:, 1]]).ravel() > 0
        out["self_contacts"] = float(np.sum(~near))
    else:
        out["self_contacts"] = 0.0
    return out, sign


def _flat_area(flat: FlatPanels, sub_cell: IArray) -> Array:
    sub, _ = _subtriangles(flat.cells)
    q = flat.xy[sub]
    a = q[:, 1] - q[:, 0]
    b = q[:, 2] - q[:, 0]
    return 0.5 * np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])


# ---------------------------------------------------------------------------------------------
# The garment mesh
# ---------------------------------------------------------------------------------------------


def _assemble(pattern: Any, flat: FlatPanels, sewn: Sewn, order: int) -> dict[str, Any]:
    """Renumber (vertices first), orient, name edges; the arrays of the garment."""
    from fenics_garment.geometry.garments import nodal_normals

    from .mesh import edge_group_name

    k = len(sewn.points)
    is_vertex = np.zeros(k, dtype=bool)
    is_vertex[sewn.node_of[flat.vertex]] = True
    new = np.empty(k, dtype=np.int64)
    nv = int(is_vertex.sum())
    new[is_vertex] = np.arange(nv)
    new[~is_vertex] = nv + np.arange(k - nv)
    X = np.empty_like(sewn.points)
    X[new] = sewn.points
    cells = new[sewn.cells]
    c = np.sort(cells, axis=1)
    bad = np.flatnonzero(np.any(c[:, 1:] == c[:, :-1], axis=1))
    if len(bad):
        from fenics_garment.geometry.errors import GeometryError

        panel = flat.names[int(flat.cell_panel[bad[0]])]
        raise GeometryError(
            f"sewing merged two nodes of one cell ({len(bad)} cells, panel {panel!r}): a seam "
            "range is shorter than the element size or pairs neighbouring nodes"
        )
    cflat = flat.xy[flat.cells].copy()
    flip = sewn.panel_sign[flat.cell_panel] < 0
    perm = [0, 2, 1, 5, 4, 3] if order == 2 else [0, 2, 1]
    cells[flip] = cells[flip][:, perm]
    cflat[flip] = cflat[flip][:, perm]
    cflat[flip, :, 1] *= -1.0
    # edges: one line per boundary segment (a seam's side a only)
    names_of = {}
    seg_name = []
    for s in range(len(flat.segments)):
        seam = int(flat.segment_seam[s])
        if seam >= 0:
            seg_name.append(pattern.seam_name(seam))
        else:
            key = (int(flat.segment_panel[s]), int(flat.segment_edge[s]))
            if key not in names_of:
                names_of[key] = edge_group_name(pattern, flat.names[key[0]], key[1])
            seg_name.append(names_of[key])
    seg = new[sewn.node_of[flat.segments]]
    lines: dict[str, list[IArray]] = {}
    seen: set[tuple[int, int]] = set()
    for s, name in enumerate(seg_name):
        key = tuple(sorted((int(seg[s, 0]), int(seg[s, 2]))))
        if key in seen:
            continue
        seen.add(key)
        lines.setdefault(name, []).append(seg[s])
    edges = {name: 100 + i for i, name in enumerate(sorted(lines))}
    line_nodes = {name: np.array(v, dtype=np.int64) for name, v in lines.items()}
    panels = {name: i + 1 for i, name in enumerate(flat.names)}
    cell_panel = (flat.cell_panel + 1).astype(np.int32)
    points = X[:nv]
    tri = cells[:, :3]
    normal = nodal_normals(points, tri)
    # warp: the grain (flat +x) through each cell's affine map, averaged at the vertices
    q = cflat[:, :3]
    p = points[tri]
    F = np.stack([p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]], axis=2)  # (m, 3, 2)
    G = np.stack([q[:, 1] - q[:, 0], q[:, 2] - q[:, 0]], axis=2)  # (m, 2, 2)
    ex = np.linalg.solve(G, np.broadcast_to([1.0, 0.0], (len(G), 2))[..., None])[..., 0]
    w_cell = np.einsum("mij,mj->mi", F, ex)  # F G⁻¹ e_x: the flat x axis in 3-D
    area = 0.5 * np.abs(G[:, 0, 0] * G[:, 1, 1] - G[:, 0, 1] * G[:, 1, 0])
    warp = np.zeros_like(points)
    for j in range(3):
        np.add.at(warp, tri[:, j], area[:, None] * w_cell)
    warp -= np.einsum("ij,ij->i", warp, normal)[:, None] * normal
    warp /= np.linalg.norm(warp, axis=1)[:, None] + 1e-300
    return {
        "X": X,
        "nv": nv,
        "cells6": cells,
        "cell_flat": cflat,
        "line_nodes": line_nodes,
        "surface": {
            "kind": "pattern",
            "points": points,
            "cells": tri,
            "cell_panel": cell_panel,
            "panels": panels,
            "edges": edges,
            "edge_nodes": {n: v[:, [0, 2]] for n, v in line_nodes.items()},
            "warp": warp,
            "normal": normal,
        },
    }


def _discrete_model(g: Any, data: dict[str, Any], order: int) -> None:
    """The merged mesh as a gmsh discrete model with panel and edge physical groups."""
    X = data["X"] if order == 2 else data["X"][: data["nv"]]
    base = g.model.addDiscreteEntity(2)
    g.model.mesh.addNodes(2, base, np.arange(1, len(X) + 1, dtype=np.uint64), X.ravel())
    surf = data["surface"]
    cells = data["cells6"]
    etype, ltype = (9, 8) if order == 2 else (2, 1)
    next_el = 1
    for name, tag in surf["panels"].items():
        sel = np.flatnonzero(surf["cell_panel"] == tag)
        s = g.model.addDiscreteEntity(2)
        el = np.arange(next_el, next_el + len(sel), dtype=np.uint64)
        next_el += len(sel)
        g.model.mesh.addElementsByType(s, etype, el, (cells[sel] + 1).ravel().astype(np.uint64))
        g.model.addPhysicalGroup(2, [s], tag, name=name)
    for name, tag in surf["edges"].items():
        ln = data["line_nodes"][name]
        ln = ln[:, [0, 2, 1]] if order == 2 else ln[:, [0, 2]]
        c = g.model.addDiscreteEntity(1)
        el = np.arange(next_el, next_el + len(ln), dtype=np.uint64)
        next_el += len(ln)
        g.model.mesh.addElementsByType(c, ltype, el, (ln + 1).ravel().astype(np.uint64))
        g.model.addPhysicalGroup(1, [c], tag, name=name)


def pattern_garment(
    pattern: Any,
    body: Any,
    h: float,
    comm: Any | None = None,
    order: int = 2,
    refine: Any = None,
    *,
    clearance: float = 0.002,
    sew_options: dict[str, Any] | None = None,
) -> tuple[Any, FlatCells]:
    """A garment sewn from a pattern around ``body``: (GarmentSurface, FlatCells).

    Mesh the panels flat (:func:`~.mesh.mesh_panels`, size ``h`` [m], ``refine``), place
    them (:func:`~.mesh.place`), sew (:func:`sew`, ``clearance`` [m] from the body,
    ``sew_options``), then build a gmsh discrete model of the merged mesh (6-node triangles
    at ``order`` 2, 3-node at 1) with a physical group per panel (cells, tags 1… in pattern
    order, named after the panel) and per named edge (3-node lines, tags 100… by sorted
    name: each seam by :meth:`~.model.Pattern.seam_name`, each free edge by
    :func:`~.mesh.edge_group_name`), and with ``comm`` convert it to DOLFINx
    (:func:`~fenics_garment.geometry.gmsh_utils.to_dolfinx`).

    The :class:`~fenics_garment.geometry.garments.GarmentSurface` has ``kind="pattern"``,
    vertex ``points`` first in gmsh order (the edge nodes are gmsh nodes after them), outward
    ``cells``, ``warp`` (the panels' grain through each cell's map, averaged at vertices,
    tangent, unit), ``normal``, ``levels=[]`` and ``info`` (the sewing report, ``sew``'s
    doc). The :class:`FlatCells` holds the flat coordinates of every cell's nodes.
    Everything is built on rank 0 of ``comm`` and broadcast.
    """
    from fenics_garment.geometry.errors import GeometryError
    from fenics_garment.geometry.garments import GarmentSurface, _first_line
    from fenics_garment.geometry.gmsh_utils import garment_mesh, gmsh_session, shared_result

    from .mesh import mesh_panels, place
    from .model import PatternError

    t0 = time.perf_counter()
    data, err = None, None
    if comm is None or comm.rank == 0:
        try:
            flat = mesh_panels(pattern, h, order=order, refine=refine)
            t1 = time.perf_counter()
            X0 = place(flat, pattern, body)
            t2 = time.perf_counter()
            sewn = sew(flat, X0, body, clearance=clearance, **(sew_options or {}))
            data = _assemble(pattern, flat, sewn, order)
            data["info"] = {**sewn.report, "seconds_mesh": t1 - t0, "seconds_place": t2 - t1}
        except (PatternError, GeometryError) as e:
            err = str(e)
        except Exception as e:  # gmsh raises a bare Exception with its last error
            err = f"could not sew the pattern {pattern.name!r}: {_first_line(e)}"
    data = shared_result(comm, data, err)
    meshdata = None
    if comm is not None:
        with gmsh_session(comm, 0, name=f"pattern_{pattern.name}") as g:
            if g is not None:
                _discrete_model(g, data, order)
            meshdata = garment_mesh(comm, g.model if g is not None else None, "sewn")
    info = {**data["info"], "seconds_total": time.perf_counter() - t0,
            "cells": float(len(data["cells6"]))}  # fmt: skip
    rest = FlatCells(data["cells6"], data["cell_flat"], data["surface"]["cell_panel"])
    surface = GarmentSurface(levels=[], meshdata=meshdata, info=info, rest=rest, **data["surface"])
    return surface, rest


def flat_girth(garment: Any, z: float) -> float:
    """The length in the flat pattern pieces of the garment's section at height ``z``: each
    cell's crossing segment (P1 vertices) measured between the flat positions of its two
    crossing points. The girth the pattern provides along that line (the placed mesh's own
    section may be longer: the wrap stands off where the body narrows)."""
    tri = np.asarray(garment.cells)
    cn = np.asarray(garment.rest.cell_nodes)[:, :3]
    if not np.array_equal(np.sort(cn, axis=1), np.sort(tri, axis=1)):
        raise ValueError("the flat pieces' cells are not the garment's cells")
    x = garment.points
    zz = x[tri, 2] - z
    zz[zz == 0.0] = 1e-15
    flat = np.asarray(garment.rest.cell_flat)[:, :3]
    # the flat coordinate of each of the cell's vertices, in the order of ``tri``
    pos = np.argmax(tri[:, :, None] == cn[:, None, :], axis=2)
    uv = np.take_along_axis(flat, pos[:, :, None], axis=1)
    total = 0.0
    above = zz > 0
    cut = above.any(axis=1) & ~above.all(axis=1)
    for c in np.flatnonzero(cut):
        pts = []
        for a, b in ((0, 1), (1, 2), (2, 0)):
            if above[c, a] != above[c, b]:
                t = zz[c, a] / (zz[c, a] - zz[c, b])
                pts.append(uv[c, a] + t * (uv[c, b] - uv[c, a]))
        total += float(np.linalg.norm(pts[1] - pts[0]))
    return total


def fit_levels(garment: Any, body: Any) -> list[Any]:
    """The fit of a sewn pattern, as the built-in garments' construction table: at each body
    landmark level the garment goes all round (closed sections), the body's tape girth, the
    pattern's girth along that level (:func:`flat_girth`), their ratio − 1 as the ease and
    the clearance (girth difference / 2π): the pattern's own sizing on this body."""
    from fenics_garment.geometry import sections as sec
    from fenics_garment.geometry.errors import MissingRegion
    from fenics_garment.geometry.garments import GarmentLevel

    z = garment.points[:, 2]
    lo, hi = z.min() + 0.01, z.max() - 0.01
    rows = []
    for name, zl in sorted(body.landmarks.items(), key=lambda kv: kv[1]):
        if not lo < zl < hi:
            continue
        chains = sec.slice_chains(garment.points, garment.triangles(), zl)
        if not chains or not all(closed for _, closed in chains):
            continue  # an armhole or an open front: not a girth
        try:
            g_body = body.girth(name)
        except (MissingRegion, ValueError):
            continue
        g = flat_girth(garment, zl)
        rows.append(GarmentLevel(name, float(zl), g_body, g / g_body - 1.0, g,
                                 (g - g_body) / (2 * np.pi)))  # fmt: skip
    return rows
