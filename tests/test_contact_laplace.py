"""Laplace's law for a tight tube on a rigid cylinder: p = n_θθ / R (penalty and Newton rate)."""

from fenics_garment._stack import MPI  # noqa: I001

import numpy as np
import pytest

import contact_models as cm
from fenics_garment.contact import newton, pressure, terms

# Synthetic, strongly orthotropic test fabric (not a reference value): warp 4× stiffer than weft,
# so that warp-around vs warp-along the axis differ by ≈ 4× in pressure.
ORTHO = cm.Fabric(E1=2.0e6, E2=0.5e6, nu12=0.4, G12=2.0e5, h=1.0e-3)


def dress(scene: cm.Scene, steps=(0.5, 0.0)) -> list[newton.SolveReport]:
    """Dress the tube by shrinking the body and growing it back (shrink → 0)."""
    st = scene.state
    pen0 = scene.extra["R"] + scene.fabric.h / 2 - scene.extra["r0"]
    reports = []
    for s in steps:
        st.shrink.value = s * pen0
        rep = newton.solve(scene.problem)
        assert rep.converged, rep
        st.accept_step()
        reports.append(rep)
    return reports


def mid_pressure(scene: cm.Scene) -> float:
    """Mean pressure over the contact points with |z| < L/4 (all ranks)."""
    st = scene.state
    t_n = terms.normal_traction(st, scene.kappa)
    p = pressure.garment_pressure(st, t_n, cm.area_stretch(scene.u, scene.mesh))
    mid = np.abs(pressure.positions(st)[:, 2]) < scene.extra["L"] / 4
    comm = scene.mesh.comm
    return comm.allreduce(p[mid].sum(), op=MPI.SUM) / comm.allreduce(mid.sum(), op=MPI.SUM)


@pytest.mark.parametrize(
    "fabric, warp",
    [(cm.Fabric.isotropic(1e6, 0.3, 1e-3), "axial"), (ORTHO, "axial"), (ORTHO, "hoop")],
    ids=["isotropic", "warp-axial", "warp-hoop"],
)
def test_laplace_tube_penalty(fabric, warp):
    scene = cm.laplace_tube(MPI.COMM_WORLD, fabric=fabric, warp=warp)
    reports = dress(scene)
    p, ref = mid_pressure(scene), scene.extra["reference"]
    err = p / ref - 1
    pen = -MPI.COMM_WORLD.allreduce(scene.state.local_values(scene.state.gap).min(), op=MPI.MIN)
    print(f"\n{warp}: p = {p:.2f} Pa, Laplace {ref:.2f} Pa, error {100 * err:+.3f} %, "
          f"penalty penetration {pen:.2e} m = {100 * pen / fabric.h:.2f} % of h, "
          f"Newton its {[r.iterations for r in reports]}")  # fmt: skip
    assert abs(err) < 0.01


def test_newton_is_quadratic_near_the_solution():
    scene = cm.laplace_tube(MPI.COMM_WORLD)
    rep = dress(scene)[-1]
    r = rep.residuals
    print(
        "\nresidual norms",
        [f"{v:.2e}" for v in r],
        "ratios r_k+1/r_k²",
        [f"{r[k + 1] / r[k] ** 2:.2e}" for k in range(len(r) - 1)],
    )
    # quadratic: r_{k+1} ≤ C r_k² with a bounded C; the last steps gain ≥ 5 orders at once
    assert rep.iterations <= 5
    assert r[-1] / r[-2] < 1e-4 and r[-2] / r[-3] < 1e-2
