"""Boundary conditions of the shell: clamped, simply supported, symmetry planes, prescribed.

The unknown is q = (u, θ) with u the displacement and θ the total rotation vector, both in
Cartesian components. Edges are selected by a geometric marker ``where(x) -> bool array`` on the
mesh boundary (or by explicit edge indices).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np

from fenics_garment._stack import dolfinx

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
