"""The augmented-Lagrangian loop's control flow when a raised penalty is more than Newton takes.

A model problem replaces the shell: one contact point on a spring K under a load F, so the
penetration at penalty κ with multiplier λ is g = (F − λ)/(K + κ) (exact), and Newton "fails"
above a given penalty. The loop must go back to the last converged pass and go on there (plain
Uzawa at fixed κ contracts by K/(K + κ) per update), not give up with the penetration above
the tolerance.
"""

from __future__ import annotations

import numpy as np
import pytest

from fenics_garment.contact import uzawa


class _Field:
    """What the loop touches of a DOLFINx Function: ``x.array`` and ``x.scatter_forward``."""

    def __init__(self):
        self.x = self
        self.array = np.zeros(1)

    def scatter_forward(self):
        pass


class _Constant:
    def __init__(self, value: float):
        self.value = value


class _Point:
    """One contact point on a spring K under a load F: g = −(F − λ)/(K + κ)."""

    load, spring = 100.0, 100.0  # a stiff structure: plain Uzawa at κ = 1 barely contracts

    def __init__(self):
        self.gap, self.lam = _Field(), _Field()
        self.refresh = lambda: None

    def solve(self, kappa: float) -> None:
        self.gap.array[:] = -(self.load - self.lam.array) / (self.spring + kappa)


@pytest.fixture
def point(monkeypatch):
    def update(state, kappa, previous=None):  # plain Uzawa: λ ← ⟨λ − κ g⟩₊
        state.lam.array[:] = np.maximum(state.lam.array - kappa * state.gap.array, 0.0)

    monkeypatch.setattr(uzawa, "max_penetration", lambda state: float(-state.gap.array[0]))
    monkeypatch.setattr(uzawa, "persisting_penetration", lambda state, gap, last: float(-gap[0]))
    monkeypatch.setattr(uzawa, "update_multiplier", update)
    monkeypatch.setattr(uzawa, "require_constraint", lambda state: None)  # the law is update's
    return _Point()


def _failing_above(point: _Point, largest: float, max_updates: int) -> uzawa.UzawaReport:
    """The loop from κ = 1 (raised as it stalls) with Newton "failing" above ``largest``."""
    kappa = _Constant(1.0)

    def solve():
        if kappa.value > largest:
            return 3, -3
        point.solve(kappa.value)
        return 3, 2

    return uzawa.augmented_lagrangian(
        point, 1.0, solve, tol=1e-6, max_updates=max_updates, stiffen=kappa, unknown=point.gap
    )


def test_a_failed_raise_goes_back_and_converges_at_the_last_penalty(point):
    largest = 500.0  # Newton "fails" above this penalty (the third raise, κ = 1000)
    al = _failing_above(point, largest, max_updates=40)
    assert al.converged
    assert max(al.kappa) > largest  # a raise was tried and failed ...
    assert al.kappa[-1] <= largest  # ... and the loop went on at the penalty that converged
    assert al.penetration[-1] <= 1e-6
    # at the exact solution the multiplier carries the load the spring does not
    assert point.lam.array[0] == pytest.approx(point.load, rel=1e-5)


def test_a_failure_at_a_converged_penalty_is_tried_once_more_then_ends_the_loop(point):
    kappa = _Constant(1.0)
    calls = []

    def solve():
        calls.append(kappa.value)
        if len(calls) >= 3:
            return 3, -3
        point.solve(kappa.value)
        return 3, 2

    al = uzawa.augmented_lagrangian(
        point, 1.0, solve, tol=1e-9, max_updates=20, stiffen=None, unknown=point.gap
    )
    assert not al.converged
    assert al.recoveries == ["plain step"]
    assert len(calls) == 4


def test_a_failed_tenfold_raise_is_tried_again_smaller(point):
    # the ×10 raise to 100 fails, the ×√10 one to 31.6 does not
    al = _failing_above(point, 50.0, max_updates=80)
    assert al.converged
    assert al.recoveries[0] == "smaller raise"
    assert 10.0 * np.sqrt(10.0) in [pytest.approx(k) for k in al.kappa]
    assert point.lam.array[0] == pytest.approx(point.load, rel=1e-5)


def test_a_point_that_has_just_touched_is_not_a_stall():
    """The penalty is raised on the penetration of the points that penetrated in the last pass
    too: one that has only now come into contact has no multiplier yet."""
    from types import SimpleNamespace

    from fenics_garment._stack import MPI

    state = SimpleNamespace(mesh=SimpleNamespace(comm=MPI.COMM_SELF))
    last = np.array([-1e-5, 1e-4, 2e-6])
    gap = np.array([-2e-6, -8e-6, 1e-6])
    assert uzawa.persisting_penetration(state, gap, last) == pytest.approx(2e-6)
    assert uzawa.persisting_penetration(state, gap, None) == pytest.approx(8e-6)


def test_the_loop_goes_on_past_its_count_while_it_contracts(point):
    """Plain Uzawa at κ = 100 on K = 100 halves the penetration per update (ρ = K/(K + κ)):
    from 0.5 m to 1e-3 m takes ⌈log2 500⌉ = 9 updates. Given 3, the loop goes on while each
    update takes ≥ 10 % off (a converging run is not thrown away for a count) and converges."""
    al = uzawa.augmented_lagrangian(
        point, 100.0, lambda: (point.solve(100.0), (3, 2))[1], tol=1e-3, max_updates=3
    )
    assert al.converged
    assert len(al.penetration) - 1 == 9
    ratios = np.array(al.penetration[1:]) / np.array(al.penetration[:-1])
    assert ratios == pytest.approx(0.5)


def test_a_loop_that_stops_contracting_ends_at_its_count():
    # within the count: always on; past it: on while the last update took ≥ 10 % off
    assert uzawa._go_on([1.0, 0.95, 0.93], max_updates=3)
    assert not uzawa._go_on([1.0, 0.95, 0.93, 0.92], max_updates=3)
    assert uzawa._go_on([1.0, 0.5, 0.25, 0.12], max_updates=3)
    # and never past EXTRA_UPDATES × the count
    halving = [0.5**k for k in range(3 * uzawa.EXTRA_UPDATES + 1)]
    assert not uzawa._go_on(halving, max_updates=3)
