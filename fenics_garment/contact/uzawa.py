"""Augmented-Lagrangian (Uzawa) loop: drive the penetration below a tolerance at a moderate κ.

Each pass solves the nonlinear problem with the multiplier λ fixed (traction
t_N = ⟨λ − κ g⟩₊, see :func:`fenics_garment.contact.terms.normal_traction`), then updates

    λ ← ⟨λ − κ g⟩₊          (at the converged state; λ is a traction per reference area [Pa])

until max(−g) ≤ tol. κ stays where the penalty is well conditioned (κ̂ ≈ 1–10), so the
penetration error of the penalty (≈ −1.3 E h/(κ R²) in relative pressure, STACK.md) is removed
without raising κ.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from fenics_garment._stack import MPI
from fenics_garment.contact.state import ContactState


@dataclass
class UzawaReport:
    """Penetration [m] and Newton iterations of each augmented-Lagrangian pass."""

    converged: bool = False
    penetration: list[float] = field(default_factory=list)
    newton_iterations: list[int] = field(default_factory=list)


def max_penetration(state: ContactState) -> float:
    """max(−g) over all ranks [m] (≤ 0 when nothing penetrates)."""
    g = state.local_values(state.gap)
    local = float(-g.min()) if len(g) else -np.inf
    return state.mesh.comm.allreduce(local, op=MPI.MAX)


def update_multiplier(state: ContactState, kappa: float) -> None:
    """λ ← ⟨λ − κ g⟩₊ at every contact point (g from the last refresh = the converged state)."""
    lam = state.lam.x.array
    lam[:] = np.maximum(0.0, lam - kappa * state.gap.x.array)
    state.lam.x.scatter_forward()


def augmented_lagrangian(
    state: ContactState,
    kappa: float,
    solve: Callable[[], tuple[int, int]],
    *,
    tol: float,
    max_updates: int = 20,
) -> UzawaReport:
    """Solve, update λ, repeat until the penetration is ≤ ``tol`` [m] (e.g. 1 % of h).

    ``solve()`` returns (Newton iterations, SNES reason), e.g. ``NonlinearSolver.solve``.
    """
    report = UzawaReport()
    for _ in range(max_updates + 1):
        its, reason = solve()
        report.newton_iterations.append(its)
        if reason <= 0:
            return report
        pen = max_penetration(state)
        report.penetration.append(pen)
        if pen <= tol:
            report.converged = True
            return report
        update_multiplier(state, kappa)
    return report
