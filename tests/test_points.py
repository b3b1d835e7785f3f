"""``PointEvaluator``: point values located once, evaluated repeatedly, against polynomials that
the spaces hold exactly (so the reference is the polynomial itself, to round-off).

* flat mesh, affine cells: a quadratic vector field in P2 and in P2 + cubic bubble (the shell's
  displacement element) — both contain the quadratics;
* cylinder with quadratic (isoparametric) cells: the coordinate field x is P2 in the reference
  coordinates, so a linear field A x + b is exact in P2 on the curved cells, and its point values
  test the pull-back X = F_K⁻¹(x) on curved cells.

The points include mesh vertices and edge midpoints (shared by several cells and, on 2 ranks,
by two ranks): each must be counted once. Run on 1 and 2 ranks (``mpi`` marker).
"""

import basix.ufl
import numpy as np
import pytest

from fenics_garment._stack import MPI, dolfinx
from fenics_garment.points import PointEvaluator
from fenics_garment.shell.geometry import parametric_surface_mesh


def quadratic(x):
    return np.array([x[0] ** 2 - x[0] * x[1] + 3 * x[1] + 1, 2 * x[1] ** 2 + x[0], x[0] * x[1]])


def linear(x):
    A = np.array([[1.0, -2.0, 0.5], [0.3, 0.0, 4.0], [-1.0, 1.0, 1.0]])
    return A @ x + np.array([[0.1], [0.2], [-0.3]])


def flat_points(n: int) -> np.ndarray:
    rng = np.random.default_rng(7)
    inner = np.column_stack([rng.uniform(0, 2, n), rng.uniform(0, 1, n), np.zeros(n)])
    shared = np.array([[1.0, 0.5, 0.0], [0.5, 0.25, 0.0], [0.0, 0.0, 0.0], [2.0, 1.0, 0.0]])
    return np.vstack([inner, shared])


@pytest.mark.mpi
@pytest.mark.parametrize("bubble", [False, True])
def test_quadratic_field_on_a_flat_mesh(bubble):
    mesh = parametric_surface_mesh(MPI.COMM_WORLD, lambda x, y: np.array([x, y, 0.0 * x]),
                                   (0, 2), (0, 1), (8, 4), degree=1)  # fmt: skip
    P = basix.ufl.element("Lagrange", "triangle", 2)
    if bubble:
        P = basix.ufl.enriched_element([P, basix.ufl.element("Bubble", "triangle", 3)])
    V = dolfinx.fem.functionspace(mesh, basix.ufl.blocked_element(P, shape=(3,)))
    f = dolfinx.fem.Function(V)
    f.interpolate(quadratic)
    pts = flat_points(50)
    ev = PointEvaluator(mesh, pts)
    assert mesh.comm.allreduce(len(ev.index)) == len(pts)  # each point owned once
    assert np.allclose(ev(f), quadratic(pts.T).T, rtol=0, atol=1e-12)
    f.x.array[:] *= -2.0  # new values, same evaluator
    assert np.allclose(ev(f), -2.0 * quadratic(pts.T).T, rtol=0, atol=1e-12)
    # a scalar function on another space of the same mesh, by the same evaluator
    g = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("Lagrange", 2)))
    g.interpolate(lambda x: quadratic(x)[2])
    assert np.allclose(ev(g)[:, 0], pts[:, 0] * pts[:, 1], rtol=0, atol=1e-12)


@pytest.mark.mpi
def test_linear_field_on_curved_cells():
    R = 1.5
    mesh = parametric_surface_mesh(MPI.COMM_WORLD,
                                   lambda a, z: np.array([R * np.cos(a), R * np.sin(a), z]),
                                   (0, np.pi), (0, 1), (6, 3), degree=2)  # fmt: skip
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (3,)))
    f = dolfinx.fem.Function(V)
    f.interpolate(linear)
    a = np.linspace(0.05, np.pi - 0.05, 23)
    z = np.linspace(0.0, 1.0, 23)
    # on the exact cylinder: off the quadratic cells by O(h³) ≈ 1e-3, inside the padding
    pts = np.column_stack([R * np.cos(a), R * np.sin(a), z])
    ev = PointEvaluator(mesh, pts, padding=1e-2)
    got = ev(f)
    # the reference: the field at the foot point of each x on its quadratic cell
    feet = mesh.comm.allreduce(_feet(ev), op=MPI.SUM)
    assert np.abs(feet - pts).max() < 2e-3  # the feet are near the points (cells are curved)
    assert np.allclose(got, linear(feet.T).T, rtol=0, atol=1e-11)


def _feet(ev: PointEvaluator) -> np.ndarray:
    """x_K(X) of each owned point: the point of its cell the evaluator evaluates at."""
    geo = ev.mesh.geometry
    out = np.zeros_like(ev.points)
    for i, X, c in zip(ev.index, ev.reference, ev.cells, strict=True):
        out[i] = geo.cmaps[0].push_forward(X[None, :], geo.x[geo.dofmaps[0][c]])[0]
    return out


def test_points_off_the_mesh_and_bad_shape():
    mesh = parametric_surface_mesh(MPI.COMM_WORLD, lambda x, y: np.array([x, y, 0.0 * x]),
                                   (0, 1), (0, 1), (2, 2), degree=1)  # fmt: skip
    with pytest.raises(ValueError, match="not found"):
        PointEvaluator(mesh, [[0.5, 0.5, 0.1]])
    with pytest.raises(ValueError, match="shape"):
        PointEvaluator(mesh, [[0.5, 0.5]])


@pytest.mark.mpi
def test_model_displacement_reuses_its_spaces():
    """``ShellModel.displacement()``: the spaces are built once; the values follow q exactly
    (a quadratic displacement is in both the P2B unknown and the P2 output)."""
    from fenics_garment.materials import Isotropic
    from fenics_garment.shell.kinematics import ShellGeometry
    from fenics_garment.shell.model import ShellModel

    mesh = parametric_surface_mesh(MPI.COMM_WORLD, lambda x, y: np.array([x, y, 0.0 * x]),
                                   (0, 2), (0, 1), (8, 4), degree=1)  # fmt: skip
    model = ShellModel(ShellGeometry.from_mesh(mesh), Isotropic(E=1.0, nu=0.3, thickness=0.01))
    pts = flat_points(20)
    ev = PointEvaluator(mesh, pts)
    first = model.displacement()
    model.q.sub(0).interpolate(quadratic)
    model.q.x.scatter_forward()
    second = model.displacement()
    assert second.function_space is first.function_space and second is not first
    assert np.allclose(ev(first), 0.0) and np.allclose(ev(second), quadratic(pts.T).T, atol=1e-12)
