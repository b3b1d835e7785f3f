"""Stress: extreme fabric — warp 100× stiffer than weft, bending rigidity 10⁻⁶ of E h³/12.

A limp, strongly orthotropic fabric in a tight tube on a rigid cylinder, warp along and around
the axis: the pressure must still follow Laplace's law with the finite-strain orthotropic hoop
force (verification/contact.py ``tube_pressure``) within 1 %, dressing
and augmented Lagrangian to 1 % of h converging. Measured: warp along the axis +0.16 %
(18.08 vs 18.05 Pa), around it +0.16 % (1854.5 vs 1851.4 Pa), 2–3 Newton iterations per step.
"""

from fenics_garment._stack import MPI  # noqa: I001

import pytest

from fenics_garment.contact import uzawa
from fenics_garment.verification import contact as cases
from fenics_garment.materials import Fabric

E, H = 2.0e6, 1.0e-3
LIMP = 1e-6 * E * H**3 / 12
EXTREME = Fabric(E_warp=E, E_weft=E / 100, G12=E / 200, B_warp=LIMP, B_weft=LIMP / 100,
                 thickness=H, density=0.0, nu12=0.3, name="ortho-100-limp")  # fmt: skip


@pytest.mark.stress
@pytest.mark.parametrize("warp", ["axial", "hoop"])
def test_extreme_orthotropy_and_limp_bending(warp):
    sc = cases.tight_tube(MPI.COMM_WORLD, EXTREME, warp=warp)
    rep = cases.dress_case(sc)
    al = uzawa.augmented_lagrangian(
        sc.state, float(sc.contact.kappa.value), sc.solver.solve, tol=0.01 * H
    )
    p = cases.mid_pressure(sc)
    err = p / sc.reference - 1
    pen = al.penetration[-1] / H
    print(f"\nwarp {warp}: p = {p:.2f} Pa vs {sc.reference:.2f} Pa ({err:+.3%}); Newton its "
          f"{rep.iterations} + {al.newton_iterations}; penetration {pen:.2%} h")  # fmt: skip
    assert al.converged
    assert abs(err) < 0.01
