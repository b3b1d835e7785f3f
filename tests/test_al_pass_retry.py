"""A failed multiplier-update pass is retried once from the same start with the other line
search (``scene.dressing._retrying``), as a failed release solve is; only converged passes count
as multiplier updates (``contact.uzawa.augmented_lagrangian``)."""

from __future__ import annotations

import numpy as np
import pytest

from fenics_garment.contact import uzawa
from fenics_garment.scene import dressing


class _Vector:
    def __init__(self, n: int):
        self.array = np.zeros(n)

    def scatter_forward(self):
        pass


class _Function:
    def __init__(self, n: int):
        self.x = _Vector(n)


class _LineSearch:
    def __init__(self):
        self.kind = dressing.RELEASE_LINE_SEARCH

    def getType(self):
        return self.kind


class _Solver:
    """Newton that fails with full steps and converges with the retry's line search, moving the
    unknown in both cases (a failed solve leaves its last iterate behind)."""

    def __init__(self, q: _Function):
        self.q, self.ls = q, _LineSearch()
        self.problem = type(
            "P", (), {"solver": type("S", (), {"getLineSearch": lambda s: self.ls})()}
        )()
        self.starts: list[tuple[str, float]] = []

    def set_line_search(self, kind: str) -> str:
        previous, self.ls.kind = self.ls.kind, kind
        return previous

    def solve(self) -> tuple[int, int]:
        self.starts.append((self.ls.kind, float(self.q.x.array[0])))
        self.q.x.array[:] += 1.0
        return (30, -5) if self.ls.kind == dressing.RELEASE_LINE_SEARCH else (7, 2)


def test_a_failed_pass_is_solved_again_from_its_start_with_the_other_line_search():
    q = _Function(3)
    refreshed = []
    state = type("St", (), {"refresh": lambda self: refreshed.append(True)})()
    solver = _Solver(q)
    its, reason = dressing._retrying(solver, q, state)()
    assert reason > 0 and its == 37
    # both tries started from q = 0, the second with the retry line search
    assert solver.starts == [(dressing.RELEASE_LINE_SEARCH, 0.0), (dressing.RETRY_LINE_SEARCH, 0.0)]
    assert refreshed  # the contact state was refreshed at the restored start
    assert solver.ls.kind == dressing.RELEASE_LINE_SEARCH  # and the line search put back


def test_a_cycling_solve_goes_on_from_its_last_iterate_with_the_other_line_search():
    """A Newton iteration caught in a cycle (``solve.CYCLING_REASON``) is near the answer: the
    retry starts where it stopped, not from the start (the dress on f-old: 16 cycling grow
    steps, each 9 iterations thrown away and the step halved, 244 s; going on with "l2": 88 s)."""
    q = _Function(3)
    state = type("St", (), {"refresh": lambda self: None})()
    solver = _Solver(q)
    fail = solver.solve

    def cycling():
        its, reason = fail()
        return (its, dressing.CYCLING_REASON) if reason <= 0 else (its, reason)

    solver.solve = cycling
    its, reason = dressing._retrying(solver, q, state)()
    assert reason > 0 and its == 37
    assert solver.starts == [(dressing.RELEASE_LINE_SEARCH, 0.0), (dressing.RETRY_LINE_SEARCH, 1.0)]
    # the grow steps retry cycles only: another failure is returned for the step to be halved
    q.x.array[:] = 0.0
    solver.solve, solver.starts = fail, []
    assert dressing._retrying(solver, q, state, cycles_only=True)() == (30, -5)
    assert solver.starts == [(dressing.RELEASE_LINE_SEARCH, 0.0)]


def test_failed_passes_do_not_count_as_multiplier_updates(monkeypatch):
    """A point on a spring K under a load F (g = −(F − λ)/(K + κ)); every other pass fails.
    With failed passes counted, 6 passes would allow only 3 updates; here 5 updates are made."""
    load, spring = 100.0, 100.0
    gap, lam = _Function(1), _Function(1)
    state = type("St", (), {"gap": gap, "lam": lam, "refresh": lambda self: None})()
    monkeypatch.setattr(uzawa, "max_penetration", lambda s: float(-s.gap.x.array[0]))
    monkeypatch.setattr(uzawa, "persisting_penetration", lambda s, g, last: 0.0)  # never a stall
    monkeypatch.setattr(uzawa, "require_constraint", lambda s: None)  # the law is update's

    def update(s, kappa, previous=None):
        s.lam.x.array[:] = np.maximum(s.lam.x.array - kappa * s.gap.x.array, 0.0)

    monkeypatch.setattr(uzawa, "update_multiplier", update)
    calls = []

    def solve():
        calls.append(1)
        if len(calls) == 3:  # one failed pass, recovered with the plain step
            return 25, -5
        gap.x.array[:] = -(load - lam.x.array) / (spring + 1.0)
        return 3, 2

    al = uzawa.augmented_lagrangian(state, 1.0, solve, tol=1e-12, max_updates=5, unknown=gap)
    assert al.recoveries == ["plain step"]
    assert len(al.penetration) == 6  # the first pass and 5 updates, besides the failed one
    assert al.penetration[-1] == pytest.approx(load / (spring + 1) * (spring / (spring + 1)) ** 5,
                                               rel=1e-9)  # fmt: skip


def test_a_slow_contraction_close_to_the_tolerance_keeps_the_penalty():
    """A raise only when the contraction would need more than PLAIN_UPDATES updates."""
    assert uzawa.updates_to_reach(4.6e-6, 7.9e-6, 0.33) == pytest.approx(0.487, abs=1e-3)
    assert uzawa.updates_to_reach(1e-6, 1e-4, 0.99) > uzawa.PLAIN_UPDATES
    assert uzawa.updates_to_reach(1e-6, 1e-4, 1.0) == float("inf")
    assert uzawa.updates_to_reach(1e-6, 1e-7, 0.9) == 0.0
