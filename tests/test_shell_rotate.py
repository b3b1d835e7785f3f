"""``kinematics.rotate``: R(θ)v by the vector Rodrigues formula, against rotations known in closed
form (a rotation by φ about a coordinate axis) and against the matrix R(θ) applied to v, in
both branches of the exponential map's coefficients (|θ|² below and above the Taylor switch)."""

import numpy as np
import pytest

from fenics_garment._stack import MPI, dolfinx, ufl
from fenics_garment.shell.kinematics import rotate, rotation_matrix


def _value(expr, mesh) -> np.ndarray:
    e = dolfinx.fem.Expression(expr, np.array([[1.0 / 3.0, 1.0 / 3.0]]))
    return e.eval(mesh, np.array([0], dtype=np.int32)).ravel()


@pytest.mark.parametrize("phi", [1e-5, 0.3, 2.0, 3.0])
def test_rotation_about_z_of_the_x_axis(phi):
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, 1, 1)
    theta = dolfinx.fem.Constant(mesh, np.array([0.0, 0.0, phi]))
    v = ufl.as_vector([1.0, 0.0, 0.0])
    exact = [np.cos(phi), np.sin(phi), 0.0]
    assert np.abs(_value(rotate(theta, v), mesh) - exact).max() < 1e-15
    w = dolfinx.fem.Constant(mesh, np.array([0.3, -0.5, 0.8]))
    t = dolfinx.fem.Constant(mesh, phi * np.array([0.48, 0.6, 0.64]))  # a unit axis times φ
    diff = _value(rotate(t, w) - rotation_matrix(t) * w, mesh)
    assert np.abs(diff).max() < 1e-15
