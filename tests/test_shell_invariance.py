"""Frame invariance of the shell: a finite rigid motion produces no strain, hence no residual."""

import math

import numpy as np
import pytest

from fenics_garment._stack import MPI, PETSc, dolfinx
from fenics_garment.materials import Isotropic
from fenics_garment.shell.geometry import parametric_surface_mesh
from fenics_garment.shell.kinematics import ShellGeometry
from fenics_garment.shell.model import ShellModel


def _rotation(axis, angle):
    a = np.asarray(axis, dtype=float)
    a /= np.linalg.norm(a)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def _residual_norm(model, form):
    b = dolfinx.fem.petsc.assemble_vector(form)
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    return b.norm()


@pytest.mark.parametrize("angle", [0.3, 2.5])  # well past 90°: no singular parametrisation
def test_rigid_rotation_gives_zero_residual(angle):
    r, L = 1.0, 2.0
    mesh = parametric_surface_mesh(
        MPI.COMM_WORLD, lambda a, y: np.array([r * np.sin(a), y, r * np.cos(a)]),
        (-math.pi / 2, math.pi / 2), (0, L), (4, 4),
    )  # fmt: skip
    model = ShellModel(ShellGeometry.from_mesh(mesh, warp=(0, 1, 0)),
                       Isotropic(E=1e7, nu=0.3, thickness=0.02))  # fmt: skip
    form = dolfinx.fem.form(model.residual())
    axis = np.array([1.0, 2.0, 0.5])
    R0 = _rotation(axis, angle)
    c = np.array([0.1, -0.2, 0.3])
    Vu, map_u = model.Q.sub(0).collapse()
    Vt, map_t = model.Q.sub(1).collapse()
    fu = dolfinx.fem.Function(Vu)
    fu.interpolate(lambda x: (R0 - np.eye(3)) @ x + c[:, None])
    ft = dolfinx.fem.Function(Vt)
    rv = angle * axis / np.linalg.norm(axis)
    ft.interpolate(lambda x: np.tile(rv[:, None], (1, x.shape[1])))
    model.q.x.array[map_u] = fu.x.array
    model.q.x.array[map_t] = ft.x.array
    rigid = _residual_norm(model, form)
    # The same displacement with the rotation withheld shears the shell: a non-zero reference.
    model.q.x.array[map_t] = 0.0
    strained = _residual_norm(model, form)
    assert strained > 1.0
    assert rigid < 1e-9 * strained
