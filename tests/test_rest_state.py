"""The flat rest state of sewing-pattern panels (fenics_garment.shell.rest), against exact
solutions:

* a flat rectangle wrapped into a tight tube on a rigid cylinder: Laplace's law, with the
  bending term of a flat (not cylindrical) rest state (``tube_pressure(flat=True)``);
* a flat disc forced onto a sphere: the small-strain in-plane forces
  N_rr = E t (a² − r²)/(16R²), N_θθ = E t (a² − 3r²)/(16R²) (Airy, ∇⁴φ = −E K; see
  fenics_garment/verification/rest.py), within 2 % at a/R = 0.05 and converging with h;
* an isometric placement starts without membrane strain, and a mirrored panel gives the same
  answer.
"""

from fenics_garment._stack import MPI, dolfinx, ufl  # noqa: I001

import numpy as np
import pytest

from fenics_garment.contact import uzawa
from fenics_garment.materials import Fabric, Isotropic
from fenics_garment.shell.rest import check_dof_layout
from fenics_garment.verification import contact as cases
from fenics_garment.verification.rest import disc_on_sphere

ISO = Isotropic(E=1.0e6, nu=0.3, thickness=1.0e-3)
ORTHO = Fabric(**cases.ORTHO)
H = 1.0e-3


@pytest.mark.parametrize(
    "material, warp", [(ISO, "axial"), (ORTHO, "hoop")], ids=["isotropic", "warp-hoop"]
)
def test_laplace_tube_from_a_flat_rectangle(material, warp):
    scene = cases.tight_tube(MPI.COMM_WORLD, material, warp=warp, rest="flat")
    assert check_dof_layout(scene.model.geometry.mesh) < 1e-12
    rep = cases.dress_case(scene)
    al = uzawa.augmented_lagrangian(
        scene.state, float(scene.contact.kappa.value), scene.solver.solve, tol=0.01 * H
    )
    assert al.converged, al
    p, ref = cases.mid_pressure(scene), scene.reference
    s = scene.model.stiffness
    R_c = scene.R + s.thickness / 2
    stress_free_cylinder = cases.tube_pressure(R_c, scene.r0, s, warp=warp)
    print(f"\n{warp}: p = {p:.4f} Pa, flat-rest Laplace {ref:.4f} Pa (stress-free cylinder "
          f"{stress_free_cylinder:.4f}), error {100 * (p / ref - 1):+.4f} %, "
          f"its {rep.iterations}")  # fmt: skip
    assert abs(p / ref - 1) < 0.01
    assert max(rep.iterations) <= 4  # Newton stays quadratic with the flat rest state


def test_isometric_placement_has_no_membrane_strain():
    """A rectangle wrapped on a cylinder is isometric: ε = 0 at q = 0 (up to the curved P2
    geometry's interpolation of the circle, which is O(h²) pointwise and O(h⁴) on average),
    and κ is the cylinder's curvature (zero rest curvature)."""
    rms, mean = [], []
    for n in ((8, 4), (16, 8)):
        m = cases.tight_tube(MPI.COMM_WORLD, ISO, rest="flat", n=n).model
        kin = m.kinematics()
        area = m.energy_value(dolfinx.fem.Constant(m.geometry.mesh, 1.0) * m.dx_full)
        eps2 = m.energy_value(ufl.inner(kin.membrane, kin.membrane) * m.dx_full)
        rms.append(np.sqrt(eps2 / area))
        mean.append(m.energy_value(kin.membrane[1, 1] * m.dx_full) / area)  # hoop: e₂
        kap = m.energy_value(kin.bending[1, 1] * m.dx_full) / area
        assert kap == pytest.approx(1 / 0.093, rel=1e-3)  # r0 = 0.093 m
    print(f"\nRMS membrane strain {rms[0]:.2e} → {rms[1]:.2e}, mean hoop strain "
          f"{mean[0]:.1e} → {mean[1]:.1e}")  # fmt: skip
    assert rms[0] / rms[1] > 3.5  # O(h²)
    assert abs(mean[1]) < 1e-6


def test_disc_forced_onto_a_sphere():
    a, R = 0.05, 1.0
    errs = [disc_on_sphere(MPI.COMM_WORLD, a=a, R=R, h=a / n).force_error() for n in (8, 16)]
    rate = np.log2(errs[0] / errs[1])
    print(f"\ndisc a/R = {a / R}: L2 error of N {errs[0]:.2%} (h = a/8), {errs[1]:.2%} "
          f"(h = a/16), observed order {rate:.1f}")  # fmt: skip
    assert errs[1] < 0.02
    assert rate > 2.0


@pytest.mark.slow
def test_disc_trend_with_a_over_R():
    """Away from a ≪ R the finite-strain answer departs from the small-strain one, by O(a²/R²)."""
    a = 0.05
    errs = {aR: disc_on_sphere(MPI.COMM_WORLD, a=a, R=a / aR, h=a / 16).force_error()
            for aR in (0.1, 0.3)}  # fmt: skip
    print("\n" + ", ".join(f"a/R = {k}: {v:.2%}" for k, v in errs.items()))
    assert errs[0.1] < 0.02
    assert errs[0.3] > errs[0.1]


@pytest.mark.slow
def test_mirrored_panel_gives_the_same_answer():
    """Y = (−x, y) is a left-handed flat map: the frame is flipped back, same forces."""
    from fenics_garment.verification import rest as vr

    a = 0.05
    base = disc_on_sphere(MPI.COMM_WORLD, a=a, h=a / 8)
    orig = vr.flat_map_from_function
    try:
        vr.flat_map_from_function = lambda mesh, f: orig(mesh, lambda x: f(x) * [[-1.0], [1.0]])
        mirrored = disc_on_sphere(MPI.COMM_WORLD, a=a, h=a / 8)
    finally:
        vr.flat_map_from_function = orig
    assert mirrored.force_error() == pytest.approx(base.force_error(), rel=1e-6)
