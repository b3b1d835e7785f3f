"""The smooth body's Hessian computed only before a Jacobian (``ContactState.update_hessian``)
gives what computing it at every refresh gives, checked against independent references.

* State level, on a sphere body: the deferred Hessian equals the one of a full refresh bit for
  bit, and both match the exact distance Hessian (I − e⊗e)/|x| of the sphere |x| = R to the body
  mesh's discretisation error; when the displacement has changed since the deferred refresh, the
  Hessian is that of the current iterate (a full refresh there).
* Solver level, the tight spherical cap of ``verification.contact`` on the smooth body: the
  same Newton iteration counts and pressures as a solver that refreshes the Hessian at every
  residual, and the pressure of Laplace's law for the cap (``cap_pressure``) to 2 % (pure
  penalty, no multiplier updates: the penalty's own error is −1.7 % here).
"""

import numpy as np

from fenics_garment._stack import MPI, dolfinx
from fenics_garment.contact.primitives import icosphere
from fenics_garment.contact.smooth import SmoothBody
from fenics_garment.contact.state import ContactState
from fenics_garment.shell.geometry import parametric_surface_mesh

R = 0.1


def _cap_state(body: SmoothBody) -> tuple[ContactState, dolfinx.fem.Function]:
    """A P1 patch of the sphere of radius 0.1 mm below R (every point in contact, shallower
    than HESSIAN_DEPTH) with a P2 displacement."""
    mesh = parametric_surface_mesh(
        MPI.COMM_SELF,
        lambda a, b: 0.0999 * np.vstack([np.cos(a) * np.cos(b), np.sin(a) * np.cos(b), np.sin(b)]),
        (0.0, 0.8), (0.1, 0.7), (5, 4), degree=1,
    )  # fmt: skip
    u = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (3,))))
    return ContactState(mesh, u, body, offset=0.0, rule="lumped"), u


def _hessian(state: ContactState) -> np.ndarray:
    return state.hessian.x.array.reshape(-1, 3, 3)[state._dofs].copy()


def test_deferred_hessian_is_the_hessian_of_its_iterate():
    body = SmoothBody(*icosphere(R, 4))
    full, u_full = _cap_state(body)
    lazy, u_lazy = _cap_state(body)
    rng = np.random.default_rng(1)
    du = rng.normal(scale=2e-5, size=u_full.x.array.shape)
    u_full.x.array[:] = u_lazy.x.array[:] = du
    full.refresh()
    lazy.refresh(defer_hessian=True)
    assert np.abs(_hessian(lazy)).max() == 0.0  # not computed yet
    assert np.array_equal(full.gap.x.array, lazy.gap.x.array)
    lazy.update_hessian()
    assert np.array_equal(_hessian(full), _hessian(lazy))
    x = full._x_expr.eval(full.mesh, full._cells).reshape(-1, 3)
    e = x / np.linalg.norm(x, axis=1)[:, None]
    exact = (np.eye(3) - e[:, :, None] * e[:, None, :]) / np.linalg.norm(x, axis=1)[:, None, None]
    assert np.abs(_hessian(lazy) - exact).max() < 0.05 / R  # body edges 4 mm: a few % of 1/R
    lazy.refresh(defer_hessian=True)
    u_lazy.x.array[:] = u_full.x.array[:] = 2 * du  # moved after the refresh
    full.refresh()
    lazy.update_hessian()
    assert np.array_equal(_hessian(full), _hessian(lazy))
    assert np.array_equal(full.gap.x.array, lazy.gap.x.array)


def test_cap_newton_is_unchanged_by_the_deferral():
    from fenics_garment.materials import Isotropic
    from fenics_garment.solve import NonlinearSolver
    from fenics_garment.verification import contact as scenes

    material = Isotropic(E=1.0e6, nu=0.3, thickness=1.0e-3)
    runs = []
    for deferred in (True, False):
        scene = scenes.tight_cap(MPI.COMM_WORLD, material, n=6, n_body=64, surface=SmoothBody)
        if not deferred:  # the Hessian at every refresh, as before the deferral
            opts = {"snes_rtol": 1e-10, "snes_atol": 1e-10, "snes_stol": 0.0, "snes_max_it": 30}
            scene.solver = NonlinearSolver(scene.model, scene.bcs, petsc_options=opts,
                                           pre_residual=[scene.contact.refresh],
                                           prefix="always_")  # fmt: skip
        rep = scenes.dress_case(scene)
        runs.append((rep.iterations, scenes.mid_pressure(scene), scene.solver.timings))
    (its_d, p_d, t_d), (its_a, p_a, _) = runs
    print(f"\ndeferred Hessian: its {its_d}, p {p_d:.6f} Pa; always: its {its_a}, p {p_a:.6f} Pa; "
          f"Laplace {scene.reference:.6f} Pa")  # fmt: skip
    assert its_d == its_a
    assert abs(p_d - p_a) <= 1e-9 * abs(p_a)
    assert abs(p_d / scene.reference - 1) < 0.02
    assert t_d.jacobian_hooks > 0.0 and t_d.residual_evaluations > t_d.jacobian_evaluations
