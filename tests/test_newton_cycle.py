"""A Newton iteration that cycles is stopped (``CYCLING_REASON``), one that converges is not."""

import math

import numpy as np
import ufl

from fenics_garment._stack import MPI, dolfinx
from fenics_garment.solve import CYCLING_REASON, NonlinearSolver, newton_cycle, reason_name


def test_a_two_cycle_is_found_after_two_repeated_periods():
    # the dress at 22.5 mm, the multipliers' last pass (full Newton steps): a 2-cycle from k = 2
    r = [0.0025, 0.0034] + [0.00031, 0.0033] * 3
    found = [newton_cycle(r[: n + 1]) for n in range(len(r))]
    assert found.index(2) == 7  # r₂ … r₇: three copies of the period, two of them repeats
    assert not any(found[:7])


def test_a_cycle_of_ten_is_found_after_one_repeated_period():
    # the dress at 25.8 mm, the same pass: the same ten norms from k = 0, 10, 20
    period = [0.00058, 0.043, 0.0099, 0.068, 0.0019, 0.025, 0.035, 0.027, 0.063, 0.025]
    r = period * 3 + period[:1]
    found = [newton_cycle(r[: n + 1]) for n in range(len(r))]
    assert found.index(10) == 19 and not any(found[:19])


def test_converging_and_slow_iterations_are_not_cycles():
    quadratic = [0.0039, 0.12, 0.055, 0.022, 0.0096, 0.0034, 0.00029, 3.1e-6, 2.1e-9]
    non_monotone = [0.0021, 1.1, 0.54, 0.11, 0.15, 0.014, 0.013, 0.0015, 5.4e-5, 2.9e-8]
    plateau = list(0.99 ** np.arange(30))  # a damped search's 1 % per iteration
    for r in (quadratic, non_monotone, plateau):
        assert not any(newton_cycle(r[: n + 1]) for n in range(len(r)))


class _Arctan:
    """F(u) = ∫ atan(u) v dx: for a uniform u Newton is x ← x − (1 + x²) atan x, which has the
    2-cycle ±x* where x* − (1 + x*²) atan x* = −x*, i.e. x* = 1.3917452002707…"""

    def __init__(self, start: float):
        mesh = dolfinx.mesh.create_unit_interval(MPI.COMM_WORLD, 4)
        V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1))
        self.q = dolfinx.fem.Function(V)
        self.q.x.array[:] = start
        self.v = ufl.TestFunction(V)

    def residual(self):
        return ufl.atan(self.q) * self.v * ufl.dx

    def jacobian(self, F):
        return ufl.derivative(F, self.q)


def test_the_solver_stops_a_cycling_newton_at_once():
    x = 1.3917452002707
    assert abs(2 * x - (1 + x * x) * math.atan(x)) < 1e-12  # the cycle's start
    solver = NonlinearSolver(_Arctan(x), [], petsc_options={"snes_max_it": 30})
    its, reason = solver.solve()
    assert reason == CYCLING_REASON and reason_name(reason) == "diverged cycling"
    assert its <= 4 and solver.timings.cycles == 1  # not the 30 of max_it
    # the same solver from a start in Newton's basin converges as before
    solver.model.q.x.array[:] = 0.5
    its, reason = solver.solve()
    assert reason > 0 and its <= 6 and solver.timings.cycles == 1
