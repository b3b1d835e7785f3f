"""Boundary conditions of the shell: clamped, simply supported, symmetry planes, prescribed.

The unknown is q = (u, θ) with u the displacement and θ the total rotation vector, both in
Cartesian components. Edges are selected by a geometric marker ``where(x) -> bool array`` on the
mesh boundary (or by explicit edge indices).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np

from fenics_garment._stack import MPI, dolfinx, ufl

Marker = Callable[[np.ndarray], np.ndarray]


def boundary_edges(mesh, where: Marker | np.ndarray) -> np.ndarray:
    """Boundary edges whose vertices satisfy ``where`` (or ``where`` itself if it is an array)."""
    if isinstance(where, np.ndarray):
        return where.astype(np.int32)
    mesh.topology.create_connectivity(1, 2)
    return dolfinx.mesh.locate_entities_boundary(mesh, 1, where)


def fix_components(
    model,
    where: Marker | np.ndarray,
    *,
    u: Iterable[int] = (),
    theta: Iterable[int] = (),
    value: dolfinx.fem.Constant | float = 0.0,
) -> list[dolfinx.fem.DirichletBC]:
    """Dirichlet conditions on Cartesian components of u and θ along the selected edges."""
    mesh = model.geometry.mesh
    edges = boundary_edges(mesh, where)
    bcs = []
    for field, comps in ((0, u), (1, theta)):
        for i in comps:
            sub = model.Q.sub(field).sub(i)
            dofs = dolfinx.fem.locate_dofs_topological(sub, 1, edges)
            val = value if isinstance(value, dolfinx.fem.Constant) else (
                dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(value)))  # fmt: skip
            bcs.append(dolfinx.fem.dirichletbc(val, dofs, sub))
    return bcs


def clamped(model, where: Marker | np.ndarray) -> list[dolfinx.fem.DirichletBC]:
    """u = 0 and θ = 0."""
    return fix_components(model, where, u=(0, 1, 2), theta=(0, 1, 2))


def simply_supported(model, where: Marker | np.ndarray) -> list[dolfinx.fem.DirichletBC]:
    """u = 0, rotations free ("soft" simple support of a shell edge)."""
    return fix_components(model, where, u=(0, 1, 2))


def symmetry_plane(model, where: Marker | np.ndarray, axis: int) -> list[dolfinx.fem.DirichletBC]:
    """Mirror symmetry about the plane x_axis = const.

    The displacement normal to the plane vanishes; with a Cartesian rotation vector the two
    rotation components lying in the plane vanish (the rotation axis must be normal to it).
    """
    in_plane = tuple(i for i in range(3) if i != axis)
    return fix_components(model, where, u=(axis,), theta=in_plane)


def fix_point_dofs(
    model, point: np.ndarray, *, u: Iterable[int] = (), theta: Iterable[int] = (), tol=1e-8
) -> list[dolfinx.fem.DirichletBC]:
    """Dirichlet conditions at the mesh node at ``point`` (e.g. to remove a rigid mode)."""
    p = np.asarray(point, dtype=np.float64)

    def at(x):
        return np.linalg.norm(x.T - p[None, :], axis=1) < tol

    bcs = []
    for field, comps in ((0, u), (1, theta)):
        for i in comps:
            sub = model.Q.sub(field).sub(i)
            Vc, _ = sub.collapse()
            dofs = dolfinx.fem.locate_dofs_geometrical((sub, Vc), at)
            zero = dolfinx.fem.Function(Vc)
            bcs.append(dolfinx.fem.dirichletbc(zero, dofs, sub))
    return bcs


def symmetry_plane_penalty(
    model, point, normal, *, penalty: float = 1e4, tol: float = 1e-8
) -> dolfinx.fem.Constant:
    """Mirror symmetry about the plane through ``point`` with normal ``normal`` (any direction),
    by a penalty energy on the boundary edges that lie in the plane; returns the penalty factor
    as a Constant (change it without recompiling).

    :func:`symmetry_plane` fixes Cartesian components and so needs an axis-aligned plane. Here the
    same conditions, u·n = 0 and θ ∥ n (the rotation vector normal to the plane, i.e.
    θ − (θ·n)n = 0), are added to the internal energy as

        Π_pen = ½ ∫ κ_u (u·n)² + κ_θ |θ − (θ·n) n|² ds   over the edges in the plane,

    with κ_u = ``penalty`` · A₁₁/h and κ_θ = ``penalty`` · (D₁₁/h + S h) (membrane, bending and
    shear stiffness over the cell size h), so the constraint is met to ≈ 1/``penalty`` of the
    displacement there whatever the material. Symmetric Jacobian. The edges are picked by the
    quadrature points' distance to the plane (< ``tol`` × the mesh's extent), not by a mesh
    tag, so the term goes with any other boundary measures of the model.
    """
    mesh = model.geometry.mesh
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    p = np.asarray(point, dtype=np.float64)
    x = mesh.geometry.x
    extent = mesh.comm.allreduce(float(np.ptp(x, axis=0).max()) if len(x) else 0.0, op=MPI.MAX)
    nv = ufl.as_vector(n.tolist())
    X = ufl.SpatialCoordinate(mesh)
    on_plane = ufl.conditional(ufl.lt(abs(ufl.dot(X - ufl.as_vector(p.tolist()), nv)),
                                      tol * extent), 1.0, 0.0)  # fmt: skip
    st = model.stiffness
    h = model.h_cell
    factor = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(penalty))
    k_u = factor * st.A11 / h
    k_t = factor * (st.D11 / h + max(st.S1, st.S2) * h)
    u, theta = model.u, model.theta
    un = ufl.dot(u, nv)
    t_in = theta - ufl.dot(theta, nv) * nv
    psi = 0.5 * on_plane * (k_u * un**2 + k_t * ufl.dot(t_in, t_in))
    model.add_energy(psi, ufl.Measure("ds", domain=mesh, metadata={"quadrature_degree": 4}))
    return factor
