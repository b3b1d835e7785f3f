"""Each distinct contact point is searched once (``ContactState``), with the values of a search of
every point, checked against independent references.

The ``"lumped"`` rule puts 7 points on each cell (vertices, edge midpoints, centroid); on a
straight-sided (P1-geometry) garment the vertices and midpoints are shared by neighbouring cells.

* A plane body, on which the smooth distance is exact (``test_contact_smooth``): the gap at every
  point equals the height of X + u(X) above the plane, X mapped from the reference point by the
  cell's affine map and u a quadratic field (exact in P2), minus the offset — so a wrongly mapped
  shared point would show. The search visits n_vertices + n_edges + n_cells points.
* A sphere body: gap, normal and Hessian of the deduplicated search equal those of searching all
  7 points of every cell (the earlier code path) to rounding, and the gap is the exact distance
  |x| − R to the body mesh's discretisation error.
"""

import numpy as np
import pytest

from fenics_garment._stack import MPI, dolfinx
from fenics_garment.contact.primitives import icosphere
from fenics_garment.contact.smooth import SmoothBody
from fenics_garment.contact.state import ContactState
from fenics_garment.shell.geometry import parametric_surface_mesh

OFFSET = 2e-4  # half the fabric thickness [m]


def _plane(half: float = 0.2, n: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """The plane z = 0 as an n × n grid of right triangles, normals up."""
    s = np.linspace(-half, half, n + 1)
    X, Y = np.meshgrid(s, s, indexing="ij")
    v = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]
    tri = np.vstack([np.column_stack([a.ravel(), b.ravel(), c.ravel()]),
                     np.column_stack([a.ravel(), c.ravel(), d.ravel()])])  # fmt: skip
    return v, tri


def _lift(x: np.ndarray) -> np.ndarray:
    """A quadratic displacement u(X) (3, N): exactly representable in P2."""
    return np.vstack([1e-3 * x[1], -5e-4 * x[0], 2e-3 + 0.05 * x[0] ** 2 - 0.03 * x[0] * x[1]])


def _sheet(mapping, degree: int = 1) -> tuple[dolfinx.mesh.Mesh, dolfinx.fem.Function]:
    mesh = parametric_surface_mesh(MPI.COMM_SELF, mapping, (-0.05, 0.05), (-0.04, 0.04), (5, 4),
                                   degree=degree)  # fmt: skip
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (3,)))
    u = dolfinx.fem.Function(V)
    u.interpolate(_lift)
    return mesh, u


def _reference_points(mesh: dolfinx.mesh.Mesh, state: ContactState) -> np.ndarray:
    """X at every contact point (cells × points, 3) from the cells' affine maps (P1 geometry)."""
    X = mesh.geometry.x[mesh.geometry.dofmaps[0][state._cells]]  # (cells, 3 vertices, 3)
    xi = state.points
    return (X[:, None, 0] + xi[None, :, :1] * (X[:, None, 1] - X[:, None, 0])
            + xi[None, :, 1:2] * (X[:, None, 2] - X[:, None, 0])).reshape(-1, 3)  # fmt: skip


def test_each_shared_point_is_searched_once_with_the_exact_plane_gap():
    mesh, u = _sheet(lambda a, b: np.vstack([a, b, 0.01 + 0 * a]))
    state = ContactState(mesh, u, SmoothBody(*_plane()), offset=OFFSET, rule="lumped")
    state.refresh()
    top = mesh.topology
    top.create_connectivity(1, 0)
    n_cells = top.index_map(2).size_local
    assert state.timings.searched == top.index_map(0).size_local + top.index_map(1).size_local \
        + n_cells  # fmt: skip
    assert state.timings.points == 7 * n_cells
    X = _reference_points(mesh, state)
    exact = X[:, 2] + _lift(X.T)[2] - OFFSET
    assert np.abs(state.local_values(state.gap) - exact).max() < 1e-15
    assert np.abs(state.local_values(state.normal_fn) - [0.0, 0.0, 1.0]).max() < 1e-14


@pytest.mark.parametrize("degree", [1, 2])
def test_deduplicated_search_equals_the_search_of_every_point(degree):
    R = 0.1

    def cap(a, b):
        return 0.1005 * np.vstack([np.cos(a) * np.cos(b), np.sin(a) * np.cos(b), np.sin(b)])

    mesh, u = _sheet(cap, degree)
    u.x.array[:] *= 0.1  # points within ±0.5 mm of the skin: the Hessian is computed
    body = SmoothBody(*icosphere(R, 4))
    values = []
    for dedupe in (True, False):
        state = ContactState(mesh, u, body, offset=OFFSET, rule="lumped")
        if not dedupe:
            state._unique = None  # the search of all 7 points of every cell
        state.refresh()
        values.append([state.local_values(f) for f in (state.gap, state.normal_fn)]
                      + [state.hessian.x.array.reshape(-1, 9)[state._dofs]])  # fmt: skip
        searched = state.timings.searched
    assert searched == values[0][0].size  # the second run searched every point
    for a, b in zip(*values, strict=True):
        assert np.abs(a - b).max() <= 1e-12 * max(np.abs(b).max(), 1.0)
    assert np.abs(values[0][2]).max() > 1.0  # the Hessian is there (≈ 1/R on the tangent plane)
    x = state._x_expr.eval(mesh, state._cells).reshape(-1, 3)
    exact = np.linalg.norm(x, axis=1) - R - OFFSET
    assert np.abs(values[0][0] - exact).max() < 2e-5  # the body mesh's error (edge 4 mm)


@pytest.mark.parametrize("degree", [1, 2])
def test_lumped_pressure_is_the_cells_force_over_its_area(degree):
    """``garment_pressure`` with the lumped rule: one value per cell, Σ t_N w / Σ w over the
    cell's 7 points (t_N = κ⟨−g⟩₊ from the gaps, unit area stretch), whether or not the search
    shares points between cells (straight or curved cells)."""
    from fenics_garment._stack import ufl
    from fenics_garment.contact import pressure, terms

    def cap(a, b):
        return 0.0998 * np.vstack([np.cos(a) * np.cos(b), np.sin(a) * np.cos(b), np.sin(b)])

    mesh, u = _sheet(cap, degree)
    u.x.array[:] *= 0.1
    state = ContactState(mesh, u, SmoothBody(*icosphere(0.1, 4)), offset=OFFSET, rule="lumped")
    state.refresh()
    kappa = dolfinx.fem.Constant(mesh, 1e6)
    p = pressure.garment_pressure(state, terms.normal_traction(state, kappa), ufl.as_ufl(1.0))
    t_n = np.maximum(-1e6 * state.local_values(state.gap), 0.0).reshape(-1, 7)
    w = state.weights
    exact = np.repeat(t_n @ w / w.sum(), 7)
    if degree == 1:
        assert np.abs(p - exact).max() <= 1e-12 * np.abs(exact).max()
    else:  # curved cells: dA varies over the cell, so compare the per-cell structure only
        assert np.ptp(p.reshape(-1, 7), axis=1).max() <= 1e-12 * np.abs(p).max()
        assert np.abs(p - exact).max() <= 0.02 * np.abs(exact).max()
    assert np.all(t_n.max(axis=1) > 0.0)
