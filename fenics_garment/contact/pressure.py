"""Contact pressure: normal contact force per deformed area, on the garment and on the body.

On the garment, at every contact point: p = t_N / J_s, where t_N is the normal traction per
*reference* area (the contact terms are integrated over the reference surface) and
J_s = da/dA the garment's area stretch there. (Dividing by the reference area instead is ≈ +5 %
off on a tight tube: STACK.md.)

On the body, two transfers:

* :func:`body_pressure` (force-conserving "push"): every contact point carries the force
  f = t_N w dA (w dA its reference area); the force is spread to the three vertices of the body
  triangle that holds its closest point with the barycentric weights, summed over ranks, and
  divided by the vertex's lumped (one-third) area. The total force is exact — use it for forces
  per region — but the field is only smooth where the body's triangles are larger than the
  spacing of the contact points (measured on the tight tube with a 0.6 mm body mesh under 18 mm
  garment cells: −100 … +790 % vertex to vertex).
* :func:`body_pressure_map` ("pull"): each body vertex takes the garment's P1 pressure at its
  closest point on the deformed garment — smooth at any relative resolution; for pictures and
  per-vertex statistics.
"""

from __future__ import annotations

import basix
import numpy as np
import numpy.typing as npt

from fenics_garment._stack import MPI, dolfinx, ufl
from fenics_garment.contact.search import SearchSurface
from fenics_garment.contact.state import ContactState

F64 = npt.NDArray[np.float64]


def garment_pressure(
    state: ContactState, t_n: ufl.core.expr.Expr, area_stretch: ufl.core.expr.Expr
) -> F64:
    """Pressure at the owned contact points [Pa] (order of ``state.local_values``).

    Contact force over deformed area, p = Σ t_N w dA / Σ J_s w dA, summed over the smallest
    unit the contact rule shares its force in. With the ``"vertex"`` rule a garment vertex is
    one contact point shared by its cells, so the sums run over the vertex's cell-points on this
    rank (the pointwise ratio would vary with the vertex valence on a structured mesh). With the
    other rules the sums run over each cell's points: the traction of a P2⊕bubble garment is
    split unevenly among a cell's vertex, edge and centroid points (as a P2 element's consistent
    load of a uniform pressure is zero at its vertices; only the cell's total is meaningful),
    so the pointwise ratio has a within-cell checkerboard — on the tight tube at 20 mm, 56 % of
    the points carried no traction and the area-weighted mean over the loaded ones was +41 %
    above Laplace's law (+2.7 % per cell, the rest of it the faceted rest geometry).
    """
    J = ufl.Jacobian(state.mesh)
    dA = ufl.sqrt(ufl.det(J.T * J))
    w = state.weights[None, :]
    force = state.evaluate(t_n * dA) * w
    area = state.evaluate(area_stretch * dA)
    area = area * w
    if state.rule != "vertex" or state.shared_points is None:
        ratio = force.sum(axis=1) / area.sum(axis=1)
        return np.repeat(ratio, force.shape[1])
    force, area = force.ravel(), area.ravel()
    inverse = state.shared_points[1]
    f_node = np.bincount(inverse, weights=force)
    a_node = np.bincount(inverse, weights=area)
    return (f_node / a_node)[inverse]


def point_forces(state: ContactState, t_n: ufl.core.expr.Expr) -> F64:
    """Normal contact force magnitude carried by each owned contact point [N]: t_N w |dA|."""
    J = ufl.Jacobian(state.mesh)
    dA = ufl.sqrt(ufl.det(J.T * J))
    vals = state.evaluate(t_n * dA)
    return (vals * state.weights[None, :]).ravel()


def point_areas(state: ContactState, area_stretch: ufl.core.expr.Expr) -> F64:
    """Deformed area carried by each owned contact point [m²]: J_s w |dA|."""
    J = ufl.Jacobian(state.mesh)
    dA = ufl.sqrt(ufl.det(J.T * J))
    vals = state.evaluate(area_stretch * dA)
    return (vals * state.weights[None, :]).ravel()


def positions(state: ContactState) -> F64:
    """Current positions x = X + u of the owned contact points, (n, 3)."""
    return state.positions()


def body_pressure(state: ContactState, t_n: ufl.core.expr.Expr, body: SearchSurface) -> F64:
    """Pressure on the body surface at its vertices [Pa], identical on every rank."""
    f = point_forces(state, t_n)
    active = f > 0
    res = body.closest(positions(state)[active])
    bary = body.barycentric(res.point, res.face)
    nodal = np.zeros(len(body.vertices))
    np.add.at(nodal, body.triangles[res.face].ravel(), (bary * f[active, None]).ravel())
    comm = state.mesh.comm
    nodal = comm.allreduce(nodal, op=MPI.SUM)
    v, t = body.vertices, body.triangles
    area = 0.5 * np.linalg.norm(np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]), axis=1)
    lumped = np.zeros(len(v))
    np.add.at(lumped, t.ravel(), np.repeat(area / 3.0, 3))
    return nodal / np.where(lumped > 0, lumped, 1.0)


def pressure_function(
    state: ContactState,
    t_n: ufl.core.expr.Expr,
    area_stretch: ufl.core.expr.Expr,
    name: str = "contact_pressure",
) -> dolfinx.fem.Function:
    """Contact pressure as a P1 Function on the garment (write it with XDMFFile / VTXWriter).

    Nodal force over nodal deformed area with the P1 hat functions N_a at the contact points:
    p_a = Σ_p t_N N_a(x_p) w_p dA / Σ_p J_s N_a(x_p) w_p dA (sums over all cells and ranks).
    With the ``"vertex"`` rule N_a(x_p) = δ_ap and p_a is exactly the vertex pressure of
    :func:`garment_pressure`; with other rules it is a lumped projection.
    """
    mesh = state.mesh
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1))
    J = ufl.Jacobian(mesh)
    dA = ufl.sqrt(ufl.det(J.T * J))
    cells = state.owned_cells
    w = state.weights[None, :]
    force = state.evaluate(t_n * dA) * w
    area = state.evaluate(area_stretch * dA) * w
    p1 = basix.create_element(basix.ElementFamily.P, basix.CellType.triangle, 1)
    N = p1.tabulate(0, state.points)[0, :, :, 0]  # (points, 3): N_a(x_p)
    dofs = V.dofmap.list[cells]  # (cells, 3)
    f = dolfinx.fem.Function(V)
    a = dolfinx.fem.Function(V)
    np.add.at(f.x.array, dofs.ravel(), (force @ N).ravel())
    np.add.at(a.x.array, dofs.ravel(), (area @ N).ravel())
    for g in (f, a):
        g.x.scatter_reverse(dolfinx.la.InsertMode.add)
        g.x.scatter_forward()
    out = dolfinx.fem.Function(V, name=name)
    out.x.array[:] = np.divide(f.x.array, a.x.array, out=np.zeros_like(f.x.array),
                               where=a.x.array > 0)  # fmt: skip
    return out


def body_pressure_map(
    p: dolfinx.fem.Function, u: dolfinx.fem.Function, body_vertices: F64, reach: float
) -> F64:
    """Garment pressure ``p`` (P1) pulled onto body vertices, identical on every rank [Pa].

    Each body vertex takes p at its closest point on the deformed garment (P1 vertices X + u,
    gathered on every rank); vertices farther than ``reach`` [m] from the garment get 0.
    ``u`` is the garment displacement (any vector Lagrange Function on the same mesh).
    """
    V = p.function_space
    mesh = V.mesh
    comm = mesh.comm
    W = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (3,)))
    w = dolfinx.fem.Function(W)
    w.interpolate(u)
    imap = V.dofmap.index_map
    n_owned = imap.size_local
    x = V.tabulate_dof_coordinates()[:n_owned] + w.x.array.reshape(-1, 3)[:n_owned]
    gidx = imap.local_range[0] + np.arange(n_owned)
    n_cells = mesh.topology.index_map(mesh.topology.dim).size_local
    cells = imap.local_to_global(V.dofmap.list[:n_cells].ravel()).reshape(-1, 3)
    n_global = imap.size_global
    xg = np.zeros((n_global, 3))
    pg = np.zeros(n_global)
    for gi, xi, pi in comm.allgather((gidx, x, p.x.array[:n_owned])):
        xg[gi], pg[gi] = xi, pi
    garment = SearchSurface(xg, np.vstack(comm.allgather(cells)))
    res = garment.closest(np.asarray(body_vertices, dtype=np.float64))
    bary = garment.barycentric(res.point, res.face)
    values = np.einsum("ij,ij->i", bary, pg[garment.triangles[res.face]])
    return np.where(np.abs(res.distance) <= reach, values, 0.0)
