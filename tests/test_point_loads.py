"""Point loads as model terms (``ShellModel.add_point_load``, vertex measure dP), dead and
follower, against the elastica of a cantilever under a tip force.

The reference is computed here, independently of the shell: the inextensible elastica
EI θ' = M, M' = −k cos θ (dead vertical tip force k EI/L²) or M' = −k cos(θ − θ_L) (follower
force normal to the tip), θ(0) = 0, M(L) = 0, solved as a boundary value problem (scipy's
``solve_bvp``, tolerance 1e-10). For k = 4 it gives the dead tip (u, w)/L = (−0.3289, 0.6700)
(Sze et al. 2004 §3.1 quote ABAQUS −3.287 / 6.698 for L = 10), the follower (−0.6573, 0.7862).
"""

import numpy as np
import pytest
from scipy.integrate import solve_bvp

from fenics_garment._stack import MPI
from fenics_garment.materials import Isotropic
from fenics_garment.shell import bcs as B
from fenics_garment.shell.geometry import parametric_surface_mesh
from fenics_garment.shell.kinematics import ShellGeometry
from fenics_garment.shell.model import ShellModel, evaluate_at_points
from fenics_garment.solve import LoadStepper, NonlinearSolver, is_symmetric

L, WIDTH, H, E = 10.0, 1.0, 0.1, 1.2e6
EI = E * WIDTH * H**3 / 12


def elastica_tip(k: float, follower: bool) -> tuple[float, float, float]:
    """(u/L, w/L, θ_L) of the cantilever elastica under the tip force k EI/L²."""
    s = np.linspace(0.0, 1.0, 201)

    def rhs(s, y, p):
        th, M = y[0], y[1]
        dM = -k * (np.cos(th - p[0]) if follower else np.cos(th))
        return np.vstack([M, dM, np.cos(th), np.sin(th)])

    def bc(ya, yb, p):
        return np.array([ya[0], yb[1], ya[2], ya[3], yb[0] - p[0]])

    guess = np.vstack([k * (s - s**2 / 2), k * (1 - s), s, k * (s**2 / 2 - s**3 / 6)])
    sol = solve_bvp(rhs, bc, s, guess, p=[k / 2], tol=1e-10, max_nodes=100000)
    assert sol.success, sol.message
    return sol.y[2, -1] - 1.0, sol.y[3, -1], sol.p[0]


def test_elastica_reference():
    """The reference itself: small k is linear beam theory, w/L = k/3, θ_L = k/2."""
    _, w, th = elastica_tip(1e-3, follower=False)
    assert w == pytest.approx(1e-3 / 3, rel=1e-6) and th == pytest.approx(5e-4, rel=1e-6)


def cantilever(follower: bool, k: float = 4.0, n: int = 16):
    mesh = parametric_surface_mesh(MPI.COMM_WORLD, lambda x, y: np.array([x, y, 0.0 * x]),
                                   (0, L), (0, WIDTH), (n, max(1, n // 8)))  # fmt: skip
    model = ShellModel(ShellGeometry.from_mesh(mesh, warp=(1, 0, 0)),
                       Isotropic(E=E, nu=0.0, thickness=H))  # fmt: skip
    P = k * EI / L**2
    for y in (0.0, WIDTH):  # half the force at each tip corner
        model.add_point_load((L, y, 0.0), (0.0, 0.0, P / 2), follower=follower)
    solver = NonlinearSolver(model, B.clamped(model, lambda x: np.isclose(x[0], 0.0)))
    LoadStepper(solver, steps=8).run()
    tip = evaluate_at_points(model.displacement(), [[L, WIDTH / 2, 0.0]])[0]
    return model, solver, tip


@pytest.mark.parametrize("follower", [False, True], ids=["dead", "follower"])
def test_tip_point_load_against_elastica(follower):
    """16×2 P2B-P2B strip, the tip force as two corner point loads, k = P L²/EI = 4.

    Measured (u, w) against the elastica, n = 8 / 16 / 32: dead −0.81 / −0.15 / −0.02 % and
    −0.41 / −0.07 / −0.004 %; follower −1.56 / −0.39 / −0.10 % and −0.33 / −0.07 / −0.02 %:
    second-order convergence to the beam, so 0.5 % at n = 16.
    """
    model, solver, tip = cantilever(follower)
    u_ref, w_ref, _ = elastica_tip(4.0, follower)
    print(
        f"follower={follower}: u {tip[0] / L:.5f} vs {u_ref:.5f}, w {tip[2] / L:.5f} vs {w_ref:.5f}"
    )
    assert tip[0] / L == pytest.approx(u_ref, rel=5e-3)
    assert tip[2] / L == pytest.approx(w_ref, rel=5e-3)
    assert is_symmetric(model) is (not follower)
    assert solver.options["pc_type"] == ("lu" if follower else "cholesky")


def test_point_load_must_be_a_vertex():
    mesh = parametric_surface_mesh(MPI.COMM_WORLD, lambda x, y: np.array([x, y, 0.0 * x]),
                                   (0, 1), (0, 1), (2, 2))  # fmt: skip
    model = ShellModel(ShellGeometry.from_mesh(mesh, warp=(1, 0, 0)),
                       Isotropic(E=1.0, nu=0.0, thickness=0.1))  # fmt: skip
    with pytest.raises(ValueError, match="not a vertex"):
        model.add_point_load((0.3, 0.3, 0.0), (0.0, 0.0, 1.0))
