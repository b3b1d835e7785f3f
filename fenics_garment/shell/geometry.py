"""Reference geometry of a shell given only as a surface mesh (tdim 2, gdim 3).

A garment has no global chart, so everything the shell needs is computed from the mesh itself:

* a consistent orientation of the cells (DOLFINx may reorder a cell's vertices, which flips the
  sign of the Jacobian-based normal from cell to cell),
* the reference director d₀: a continuous unit vector field obtained by averaging the oriented
  cell normals at the nodes of a Lagrange space,
* a local orthonormal frame (e₁, e₂) in each tangent plane, e₁ along the projected warp direction.

The module also builds surface meshes from parametrisations, for benchmarks and simple garments.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

import basix.ufl
import numpy as np
import numpy.typing as npt

from fenics_garment._stack import MPI, dolfinx, ufl

# Cyclic vertex order of the reference cell boundary (quadrilaterals are tensor-product ordered).
_CYCLE = {"triangle": (0, 1, 2), "quadrilateral": (0, 1, 3, 2)}


# --------------------------------------------------------------------------------------------
# Meshes from parametrisations
# --------------------------------------------------------------------------------------------
def parametric_surface_mesh(
    comm: MPI.Comm,
    mapping: Callable[[np.ndarray, np.ndarray], np.ndarray],
    u_range: tuple[float, float],
    v_range: tuple[float, float],
    n: tuple[int, int],
    *,
    cell: str = "triangle",
    degree: int = 2,
    diagonal: str = "right",
) -> dolfinx.mesh.Mesh:
    """A structured surface mesh of ``mapping(u, v) -> (3, N)`` over a parameter rectangle.

    The geometry is of degree ``degree`` (1 or 2): with 2, the mesh nodes at edge midpoints and
    cell centres lie on the exact surface, which keeps the reference normals and curvature
    accurate on coarse meshes. The mesh is built on rank 0 and distributed.

    Args:
        comm: communicator.
        mapping: vectorised map from parameters (u, v) to points, returning shape (3, N).
        u_range, v_range: parameter intervals.
        n: number of cells (nu, nv) along u and v.
        cell: "triangle" or "quadrilateral".
        degree: geometry degree, 1 or 2.
        diagonal: "right" or "left" — direction of the triangle diagonals.
    """
    if degree not in (1, 2):
        raise ValueError(f"geometry degree must be 1 or 2, got {degree}")
    if cell not in _CYCLE:
        raise ValueError(f"cell must be 'triangle' or 'quadrilateral', got {cell!r}")
    nu, nv = n
    k = degree
    if comm.rank == 0:
        us = np.linspace(*u_range, k * nu + 1)
        vs = np.linspace(*v_range, k * nv + 1)
        U, V = np.meshgrid(us, vs, indexing="ij")
        x = np.asarray(mapping(U.ravel(), V.ravel()), dtype=np.float64).T.copy()

        def node(i, j):
            return i * (k * nv + 1) + j

        cells = []
        for i in range(nu):
            for j in range(nv):
                a, b = k * i, k * j
                c00, c10 = node(a, b), node(a + k, b)
                c01, c11 = node(a, b + k), node(a + k, b + k)
                if cell == "quadrilateral":
                    q = [c00, c10, c01, c11]
                    if k == 2:
                        q += [
                            node(a + 1, b),
                            node(a, b + 1),
                            node(a + 2, b + 1),
                            node(a + 1, b + 2),
                            node(a + 1, b + 1),
                        ]
                    cells.append(q)
                    continue
                if diagonal == "right":
                    tris = [(c00, c10, c11), (c00, c11, c01)]
                else:
                    tris = [(c00, c10, c01), (c10, c11, c01)]
                for t in tris:
                    tri = list(t)
                    if k == 2:
                        pos = {c00: (a, b), c10: (a + k, b), c01: (a, b + k), c11: (a + k, b + k)}

                        def mid(p, q, pos=pos):
                            (i0, j0), (i1, j1) = pos[p], pos[q]
                            return node((i0 + i1) // 2, (j0 + j1) // 2)

                        tri += [mid(t[1], t[2]), mid(t[0], t[2]), mid(t[0], t[1])]
                    cells.append(tri)
        cells = np.asarray(cells, dtype=np.int64)
    else:
        x = np.zeros((0, 3), dtype=np.float64)
        cells = np.zeros((0, ((k + 1) * (k + 2) // 2) if cell == "triangle" else (k + 1) ** 2),
                         dtype=np.int64)  # fmt: skip
    coord_el = basix.ufl.element("Lagrange", cell, k, shape=(3,))
    return dolfinx.mesh.create_mesh(comm, cells, coord_el, x)


# --------------------------------------------------------------------------------------------
# Orientation
# --------------------------------------------------------------------------------------------
def _cell_vertex_ids(mesh: dolfinx.mesh.Mesh, cells: np.ndarray) -> np.ndarray:
    """Original (input) global node numbers of the corner vertices of ``cells``, in cycle order."""
    cycle = list(_CYCLE[mesh.topology.cell_name()])
    dofs = mesh.geometry.dofmaps[0][cells][:, cycle]
    return mesh.geometry.input_global_indices[dofs]


def _local_normals(mesh: dolfinx.mesh.Mesh, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normal (from the cyclic corner order) and centroid of each cell, both (n, 3)."""
    cycle = list(_CYCLE[mesh.topology.cell_name()])
    X = mesh.geometry.x[mesh.geometry.dofmaps[0][cells][:, cycle]]
    if X.shape[1] == 3:
        nrm = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
    else:
        nrm = np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1])
    nrm /= np.linalg.norm(nrm, axis=1)[:, None]
    return nrm, X.mean(axis=1)


def _propagate_orientation(vertex_ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Flip flags making every connected patch consistently oriented, and a component label.

    Two cells sharing an edge are consistently oriented when they traverse it in opposite
    directions. A breadth-first sweep fixes each cell from an already fixed neighbour. Raises on a
    non-orientable (Möbius-like) surface.
    """
    n_cells, nv = vertex_ids.shape
    edge_cells: dict[tuple[int, int], list[tuple[int, int]]] = {}
    for c in range(n_cells):
        for k in range(nv):
            a, b = int(vertex_ids[c, k]), int(vertex_ids[c, (k + 1) % nv])
            key = (a, b) if a < b else (b, a)
            edge_cells.setdefault(key, []).append((c, 1 if a < b else -1))
    flip = np.zeros(n_cells, dtype=np.int8)  # 1: flip, 0: keep
    comp = np.full(n_cells, -1, dtype=np.int64)
    neighbours: list[list[tuple[int, bool]]] = [[] for _ in range(n_cells)]
    for pairs in edge_cells.values():
        if len(pairs) != 2:
            continue  # boundary edge, or non-manifold (left unconstrained)
        (c0, d0), (c1, d1) = pairs
        same = d0 == d1  # same traversal direction: one of the two must flip
        neighbours[c0].append((c1, same))
        neighbours[c1].append((c0, same))
    label = 0
    for seed in range(n_cells):
        if comp[seed] >= 0:
            continue
        comp[seed] = label
        queue = deque([seed])
        while queue:
            c = queue.popleft()
            for other, same in neighbours[c]:
                want = flip[c] ^ int(same)
                if comp[other] < 0:
                    comp[other] = label
                    flip[other] = want
                    queue.append(other)
                elif flip[other] != want:
                    raise ValueError(
                        "the surface mesh is not orientable (e.g. a Möbius strip): a shell needs "
                        "a consistent normal field"
                    )
        label += 1
    return flip, comp


def cell_orientation(
    mesh: dolfinx.mesh.Mesh,
    outward: Callable[[np.ndarray], np.ndarray] | None = None,
) -> dolfinx.fem.Function:
    """A DG0 function s = ±1 such that s·(J₀ × J₁) is a consistently oriented cell normal.

    The orientation is propagated over each connected patch (on rank 0, from the gathered corner
    vertices, so it is identical in parallel), then each patch is turned to agree with
    ``outward(x) -> (n, 3)`` if given (majority vote over the patch), else, for a closed patch,
    to point out of the enclosed volume, else away from the patch centroid (ties: towards +z).
    """
    tdim = mesh.topology.dim
    n_owned = mesh.topology.index_map(tdim).size_local
    owned = np.arange(n_owned, dtype=np.int32)
    ids = _cell_vertex_ids(mesh, owned)
    nrm, ctr = _local_normals(mesh, owned)
    area_vec = nrm  # unit normals; patches are judged by sums over cells
    if outward is not None:
        votes = np.einsum("ij,ij->i", nrm, np.asarray(outward(ctr), dtype=np.float64))
    else:
        votes = np.zeros(n_owned)
    orig = np.asarray(mesh.topology.original_cell_index[:n_owned], dtype=np.int64)
    comm = mesh.comm
    gathered = comm.gather((orig, ids, area_vec, ctr, votes), root=0)
    if comm.rank == 0:
        orig_all = np.concatenate([g[0] for g in gathered])
        ids_all = np.concatenate([g[1] for g in gathered])
        nrm_all = np.concatenate([g[2] for g in gathered])
        ctr_all = np.concatenate([g[3] for g in gathered])
        votes_all = np.concatenate([g[4] for g in gathered])
        order = np.argsort(orig_all)  # rank-independent processing order
        flip_sorted, comp_sorted = _propagate_orientation(ids_all[order])
        flip = np.empty_like(flip_sorted)
        comp = np.empty_like(comp_sorted)
        flip[order], comp[order] = flip_sorted, comp_sorted
        sign = 1.0 - 2.0 * flip
        n_oriented = nrm_all * sign[:, None]
        for label in np.unique(comp):
            sel = comp == label
            if outward is not None and abs(np.sum(votes_all[sel] * sign[sel])) > 0:
                score = np.sum(votes_all[sel] * sign[sel])
            else:
                # Closed patch: signed volume (divergence theorem with x·n) is positive outward.
                # Open patch: x·n relative to the centroid; flat patch: the normal's z (then x, y).
                rel = ctr_all[sel] - ctr_all[sel].mean(axis=0)
                score = np.sum(np.einsum("ij,ij->i", rel, n_oriented[sel]))
                if abs(score) < 1e-12 * max(1.0, np.abs(rel).max()) * sel.sum():
                    mean_n = n_oriented[sel].sum(axis=0)
                    axis = next((a for a in (2, 0, 1) if abs(mean_n[a]) > 1e-12), 2)
                    score = mean_n[axis]
            if score < 0:
                sign[sel] *= -1.0
        sign_by_orig = dict(zip(orig_all.tolist(), sign.tolist(), strict=True))
        per_rank = [np.array([sign_by_orig[int(o)] for o in g[0]]) for g in gathered]
    else:
        per_rank = None
    my_sign = comm.scatter(per_rank, root=0)
    DG0 = dolfinx.fem.functionspace(mesh, ("DG", 0))
    s = dolfinx.fem.Function(DG0, name="cell_orientation")
    s.x.array[:n_owned] = my_sign
    s.x.scatter_forward()
    return s


# --------------------------------------------------------------------------------------------
# Normals, directors, frames (UFL)
# --------------------------------------------------------------------------------------------
def cell_normal(mesh: dolfinx.mesh.Mesh, orientation: dolfinx.fem.Function) -> ufl.core.expr.Expr:
    """Oriented unit normal of the (possibly curved) cells: s (J₀ × J₁)/|J₀ × J₁|."""
    J = ufl.Jacobian(mesh)
    n = ufl.cross(J[:, 0], J[:, 1])
    return orientation * n / ufl.sqrt(ufl.dot(n, n))


def tangent_projector(normal: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """P = I − n⊗n. On a manifold mesh, UFL's grad(x) is the identity, not P (see STACK notes)."""
    return ufl.Identity(3) - ufl.outer(normal, normal)


def nodal_director(
    mesh: dolfinx.mesh.Mesh, orientation: dolfinx.fem.Function, degree: int = 2
) -> dolfinx.fem.Function:
    """The reference director d₀: oriented cell normals averaged at the nodes of vector P_degree.

    Each node receives the mean of the normals of the cells that share it, evaluated at the node
    (on curved cells the normal varies within the cell); the result is normalised node by node.
    Works in parallel: contributions of owned cells are summed across ranks.
    """
    cell = mesh.basix_cell()
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", degree, (3,)))
    W = dolfinx.fem.functionspace(
        mesh, basix.ufl.element("Lagrange", cell, degree, shape=(3,), discontinuous=True)
    )
    expr = dolfinx.fem.Expression(cell_normal(mesh, orientation), W.element.interpolation_points)
    nw = dolfinx.fem.Function(W)
    nw.interpolate(expr)

    n_owned = mesh.topology.index_map(mesh.topology.dim).size_local
    cdofs = V.dofmap.list[:n_owned]  # (cells, ndofs) blocked dofs of the CG space
    wdofs = W.dofmap.list[:n_owned]
    d0 = dolfinx.fem.Function(V, name="director")
    count = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("Lagrange", degree)))
    acc = d0.x.array.reshape(-1, 3)
    wv = nw.x.array.reshape(-1, 3)
    np.add.at(acc, cdofs.ravel(), wv[wdofs.ravel()])
    np.add.at(count.x.array, cdofs.ravel(), 1.0)
    d0.x.scatter_reverse(dolfinx.la.InsertMode.add)
    count.x.scatter_reverse(dolfinx.la.InsertMode.add)
    nloc = V.dofmap.index_map.size_local
    acc[:nloc] /= count.x.array[:nloc, None]
    acc[:nloc] /= np.linalg.norm(acc[:nloc], axis=1)[:, None]
    d0.x.scatter_forward()
    return d0


def local_frame(
    normal: ufl.core.expr.Expr, warp: ufl.core.expr.Expr | npt.ArrayLike
) -> tuple[ufl.core.expr.Expr, ufl.core.expr.Expr]:
    """Orthonormal tangent frame (e₁, e₂): e₁ = P w/|P w| along the warp, e₂ = n × e₁."""
    w = ufl.as_vector(warp) if not isinstance(warp, ufl.core.expr.Expr) else warp
    pw = tangent_projector(normal) * w
    e1 = pw / ufl.sqrt(ufl.dot(pw, pw))
    e2 = ufl.cross(normal, e1)
    return e1, e2
