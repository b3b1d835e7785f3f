"""Augmented Lagrangian: penetration ≤ 1 % of h, and Laplace's law tightened at a soft penalty."""

from fenics_garment._stack import MPI  # noqa: I001

import contact_models as cm
from fenics_garment.contact import newton, uzawa
from test_contact_laplace import mid_pressure


def test_augmented_lagrangian_penetration_and_pressure():
    scene = cm.laplace_tube(MPI.COMM_WORLD, kappa_hat=1.0)
    st, h = scene.state, scene.fabric.h
    pen0 = scene.extra["R"] + h / 2 - scene.extra["r0"]
    st.shrink.value = 0.5 * pen0
    assert newton.solve(scene.problem).converged
    st.shrink.value = 0.0
    penalty = newton.solve(scene.problem)
    assert penalty.converged
    pen_penalty = uzawa.max_penetration(st)
    err_penalty = mid_pressure(scene) / scene.extra["reference"] - 1
    rep = uzawa.augmented_lagrangian(
        st, float(scene.kappa.value), lambda: newton.solve(scene.problem), tol=0.01 * h
    )
    err = mid_pressure(scene) / scene.extra["reference"] - 1
    print(
        f"\npenalty κ̂=1: penetration {pen_penalty:.2e} m ({100 * pen_penalty / h:.1f} % of h), "
        f"pressure error {100 * err_penalty:+.3f} %\n"
        f"augmented Lagrangian: penetration per pass {[f'{p:.1e}' for p in rep.penetration]}, "
        f"Newton its {rep.newton_iterations}, pressure error {100 * err:+.4f} %"
    )
    assert rep.converged
    assert rep.penetration[-1] <= 0.01 * h
    assert abs(err) < 0.002
