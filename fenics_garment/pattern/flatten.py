"""Flat panels of a garment surface: 3D → 2D pattern flattening, as garment CAD does it.

A built-in garment is designed in 3D (a body-fitted loft, :mod:`fenics_garment.geometry.garments`,
sized by the girth ease at the body's levels). A pattern maker turns such a design into cutting
pattern pieces by *flattening* each panel into the plane with the least distortion of lengths:
here the as-rigid-as-possible (ARAP) parametrisation (Liu, Zhang, Xu, Gotsman & Gortler,
*A local/global approach to mesh parameterization*, SGP 2008; libigl's ``arap_solve`` with
``dim = 2``, started from libigl's least-squares conformal map). The panels keep the loft's
lengths on average, so the pattern has the design's girths and ease; where the body is doubly
curved no flat piece fits it, and the fabric cut from the flat pattern must stretch and shear
there once sewn — the strain the flat rest state (:mod:`fenics_garment.shell.rest`) puts into
the shell.

Each panel's flat coordinates are turned so that its grain line (the mean of the garment's
warp directions mapped into the plane) is +x, the shell's warp axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fenics_garment.shell.rest import FlatCells

Array = npt.NDArray[np.float64]
IArray = npt.NDArray[np.int64]

#: the four linear triangles of a 6-node (DOLFINx / basix order: vertices 0-2, then the nodes
#: of edges (1, 2), (0, 2), (0, 1)) curved triangle, each oriented like the cell
P2_SUBTRIANGLES = np.array([[0, 5, 4], [1, 3, 5], [2, 4, 3], [3, 4, 5]])


@dataclass(frozen=True)
class Flattening:
    """Flat coordinates of a panel's nodes and how far the flat piece is from the 3D one."""

    uv: Array  # (n, 2)
    rms_strain: float  # RMS over edges of |flat length / 3D length − 1|
    max_strain: float
    flipped: int  # triangles whose flat orientation is reversed (0 for a valid pattern piece)


def _edge_strain(x: Array, uv: Array, tris: IArray) -> tuple[float, float]:
    e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    l3 = np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1)
    l2 = np.linalg.norm(uv[e[:, 0]] - uv[e[:, 1]], axis=1)
    s = l2 / np.maximum(l3, 1e-300) - 1.0
    return float(np.sqrt(np.mean(s**2))), float(np.abs(s).max())


def flatten(x: Array, tris: IArray, iterations: int = 60) -> Flattening:
    """ARAP flattening of one panel (a triangulated topological disc) into the plane.

    ``x``: (n, 3) points; ``tris``: (m, 3) triangles. The result is a rigid motion away from
    any other minimiser; its orientation follows the triangles' (counter-clockwise flat
    triangles where the 3D ones are counter-clockwise about their normal).
    """
    import igl

    x = np.ascontiguousarray(x, dtype=np.float64)
    t = np.ascontiguousarray(tris, dtype=np.int64)
    loop = igl.boundary_loop(t)
    if len(loop) < 3:
        raise ValueError("a panel to flatten must be a disc with one boundary")
    # LSCM start: two boundary points far apart fixed at their 3D distance
    far = loop[np.argmax(np.linalg.norm(x[loop] - x[loop[0]], axis=1))]
    b = np.array([loop[0], far], dtype=np.int64)
    d = float(np.linalg.norm(x[far] - x[loop[0]]))
    uv0, _ = igl.lscm(x, t, b, np.array([[0.0, 0.0], [d, 0.0]]))
    data = igl.ARAPData()
    data.max_iter = iterations
    data.with_dynamics = True  # regularises the free (unpinned) problem, as libigl's tutorial 503
    igl.arap_precomputation(x, t, 2, np.zeros(0, dtype=np.int32), data)
    uv = igl.arap_solve(np.zeros((0, 2)), data, uv0)
    # orientation: flat triangles counter-clockwise, like the 3D cells about their normals
    a = uv[t[:, 1]] - uv[t[:, 0]]
    c = uv[t[:, 2]] - uv[t[:, 0]]
    signed = a[:, 0] * c[:, 1] - a[:, 1] * c[:, 0]
    if np.sum(signed < 0) > np.sum(signed > 0):
        uv[:, 1] *= -1.0
        signed = -signed
    rms, mx = _edge_strain(x, uv, t)
    return Flattening(uv, rms, mx, int(np.sum(signed <= 0)))


def grain_angle(x: Array, uv: Array, tris: IArray, warp: Array) -> float:
    """The angle in the flat plane of the panel's mean warp direction (``warp``: one 3D
    tangent vector per triangle), each triangle's warp mapped by its 3D → flat affine map and
    weighted by the flat area."""
    e1, e2 = x[tris[:, 1]] - x[tris[:, 0]], x[tris[:, 2]] - x[tris[:, 0]]
    f1, f2 = uv[tris[:, 1]] - uv[tris[:, 0]], uv[tris[:, 2]] - uv[tris[:, 0]]
    # warp = α e1 + β e2 in the 3D triangle (least squares), mapped to α f1 + β f2
    E = np.stack([e1, e2], axis=2)  # (m, 3, 2)
    rhs = np.einsum("mki,mk->mi", E, warp)[:, :, None]
    coef = np.linalg.solve(np.einsum("mki,mkj->mij", E, E), rhs)[:, :, 0]
    w = coef[:, :1] * f1 + coef[:, 1:] * f2
    w /= np.maximum(np.linalg.norm(w, axis=1), 1e-300)[:, None]
    area = 0.5 * np.abs(f1[:, 0] * f2[:, 1] - f1[:, 1] * f2[:, 0])
    m = (w * area[:, None]).sum(axis=0)
    return float(np.arctan2(m[1], m[0]))


def rotate(uv: Array, angle: float) -> Array:
    """uv turned by −angle about its centroid (a direction at ``angle`` becomes +x)."""
    c, s = np.cos(-angle), np.sin(-angle)
    p = uv - uv.mean(axis=0)
    return np.column_stack([c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1]])


@dataclass(frozen=True)
class PanelFlattening:
    """The flat coordinates of every cell's 6 nodes and how well each panel flattened."""

    cells: FlatCells
    panels: dict[str, Flattening]


def flatten_cells(
    cell_nodes: IArray,
    node_x: Array,
    cell_panel: npt.NDArray[np.int32],
    panels: dict[str, int],
    cell_warp: Array,
) -> PanelFlattening:
    """Flatten every panel of a curved (6-node) triangle mesh given as plain arrays.

    ``cell_nodes`` (m, 6) node indices into ``node_x`` in DOLFINx's node order, ``cell_panel``
    the panel tag of each cell, ``cell_warp`` (m, 3) the warp direction at each cell.
    """
    m = len(cell_nodes)
    flat = np.full((m, 6, 2), np.nan)
    result = {}
    for name, tag in panels.items():
        cells = np.flatnonzero(cell_panel == tag)
        if cells.size == 0:
            continue
        nodes, local = np.unique(cell_nodes[cells], return_inverse=True)
        local = local.reshape(-1, 6)
        tris = local[:, P2_SUBTRIANGLES].reshape(-1, 3)
        x = node_x[nodes]
        fl = flatten(x, tris)
        warp = np.repeat(cell_warp[cells], 4, axis=0)
        uv = rotate(fl.uv, grain_angle(x, fl.uv, tris, warp))
        result[name] = Flattening(uv, fl.rms_strain, fl.max_strain, fl.flipped)
        flat[cells] = uv[local]
    if np.isnan(flat).any():
        raise ValueError("flattening: some cells belong to no panel")
    cells = FlatCells(np.asarray(cell_nodes, dtype=np.int64), flat, np.asarray(cell_panel))
    return PanelFlattening(cells, result)


def garment_flat_map(garment, comm=None):
    """The flat map (:mod:`fenics_garment.shell.rest`) of a meshed 3D garment whose panels are
    flattened into their pattern pieces; returns (the DG P2 Function, :class:`PanelFlattening`).

    Collective: every rank sends its owned cells (input index, input node ids, node points,
    panel tag, warp) to rank 0, which flattens each panel and sends the flat coordinates back.
    """
    mesh = garment.mesh
    comm = mesh.comm if comm is None else comm
    tdim = mesh.topology.dim
    n = mesh.topology.index_map(tdim).size_local
    dm = mesh.geometry.dofmaps[0][:n]
    if dm.shape[1] != 6:
        raise ValueError("a pattern rest state needs a curved (order-2) triangle garment mesh")
    ids = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)[dm]
    x = mesh.geometry.x[dm]
    orig = np.asarray(mesh.topology.original_cell_index, dtype=np.int64)[:n]
    tags = np.zeros(n, dtype=np.int32)
    ct = garment.cell_tags
    own = ct.indices < n
    tags[ct.indices[own]] = ct.values[own]
    warp_nodes = garment.node_values(garment.warp)  # NaN at the edge nodes
    warp = np.nanmean(warp_nodes[dm[:, :3]], axis=1)
    parts = comm.gather((orig, ids, x, tags, warp), root=0)
    result = None
    if comm.rank == 0:
        orig_all = np.concatenate([p[0] for p in parts])
        m = int(orig_all.max()) + 1
        cell_nodes = np.zeros((m, 6), dtype=np.int64)
        cell_panel = np.zeros(m, dtype=np.int32)
        cell_warp = np.zeros((m, 3))
        n_nodes = int(max(p[1].max() for p in parts if len(p[1]))) + 1
        node_x = np.zeros((n_nodes, 3))
        for o, i, xx, t, w in parts:
            cell_nodes[o], cell_panel[o], cell_warp[o] = i, t, w
            node_x[i.reshape(-1)] = xx.reshape(-1, 3)
        result = flatten_cells(cell_nodes, node_x, cell_panel, garment.panels, cell_warp)
    result = comm.bcast(result, root=0)
    return result.cells.flat_map(mesh), result
