"""Stress: distorted triangles (minimum angle down to 7°) under contact.

The tight tube of the Laplace test with its interior vertices moved within the cylinder by up to
0.5 and 0.8 of a cell (``tight_tube(distortion=...)``: straight-sided in (θ, z), exact surface):
Laplace's pressure within 1 %. Measured (P2B-P2B): min angle 20° +0.21 %, 7.4° +0.20 %.
At distortion 1.0 (min angle 2.0°) the two-step dressing diverges (SNES reason −9) with
P2B-P2B (it passed at −0.24 % with P2B-P2): such meshes need smaller dressing steps.
"""

from fenics_garment._stack import MPI  # noqa: I001

import numpy as np
import pytest

from fenics_garment.contact import uzawa
from fenics_garment.verification import contact as cases
from fenics_garment.materials import Isotropic

ISO = Isotropic(E=1.0e6, nu=0.3, thickness=1.0e-3)
H = 1.0e-3


def min_angle_deg(mesh) -> float:
    p = mesh.geometry.x[mesh.geometry.dofmaps[0][:, :3]]
    angles = []
    for k in range(3):
        a, b = p[:, (k + 1) % 3] - p[:, k], p[:, (k + 2) % 3] - p[:, k]
        cos = np.einsum("ij,ij->i", a, b) / np.linalg.norm(a, axis=1) / np.linalg.norm(b, axis=1)
        angles.append(np.degrees(np.arccos(np.clip(cos, -1, 1))))
    return float(MPI.COMM_WORLD.allreduce(np.min(angles), op=MPI.MIN))


@pytest.mark.stress
@pytest.mark.slow  # nightly: `make test-slow` (also in .ci/run)
@pytest.mark.parametrize("distortion, max_angle", [(0.5, 25.0), (0.8, 10.0)])
def test_distorted_mesh(distortion, max_angle):
    sc = cases.tight_tube(MPI.COMM_WORLD, ISO, distortion=distortion)
    angle = min_angle_deg(sc.model.geometry.mesh)
    assert angle < max_angle  # the mesh really is that bad
    cases.dress_case(sc)
    al = uzawa.augmented_lagrangian(
        sc.state, float(sc.contact.kappa.value), sc.solver.solve, tol=0.01 * H
    )
    err = cases.mid_pressure(sc) / sc.reference - 1
    print(f"\nmin angle {angle:.1f}°: error {err:+.3%}, multiplier updates {len(al.penetration)}")
    assert al.converged and abs(err) < 0.01
