"""Augmented-Lagrangian (Uzawa) loop: drive the penetration below a tolerance at a moderate κ.

Each pass solves the nonlinear problem with the multiplier λ fixed (traction
t_N = ⟨λ − κ g⟩₊, see :func:`fenics_garment.contact.terms.tractions`), then updates

    λ ← ⟨λ − κ g⟩₊          (at the converged state; λ is a traction per reference area [Pa])

until max(−g) ≤ tol. κ stays where the penalty is well conditioned (κ̂ ≈ 1–10), so the
penetration error of the penalty (≈ −1.3 E h/(κ R²) in relative pressure, STACK.md) is removed
without raising κ — unless the penetration stalls: given the form's penalty Constant
(``stiffen=``), κ is raised ×:data:`STIFFEN_FACTOR` whenever an update reduced the largest
penetration by less than :data:`SUFFICIENT_DECREASE` and that contraction would need more
than :data:`PLAIN_UPDATES` further updates to reach the tolerance (the multiplier method's
penalty update, Bertsekas, *Constrained Optimization and Lagrange Multiplier Methods*,
Academic Press 1982, §2.2; Nocedal & Wright, *Numerical Optimization*, 2nd ed. 2006,
Alg. 17.4). On the cotton gilet
at 35 mm one free-edge vertex at the armpit wrapped the body's shoulder rim and its penetration
went 188 → 169 → 74 → 112 → 116 → 114 µm at fixed κ.

The loop applies to a normal law that is a constraint, one whose traction uses the multiplier λ
(:func:`fenics_garment.contact.laws.uses_multiplier`); a soft law (e.g. an exponential
pressure–overclosure law) wants a gap of its own, which the loop would try to drive to zero
update after update: :func:`require_constraint` refuses it before any solve.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from fenics_garment._stack import MPI, dolfinx
from fenics_garment.contact import laws, terms
from fenics_garment.contact.state import ContactState


class SoftLawError(ValueError):
    """The augmented Lagrangian was asked for with a normal law that is not a constraint."""


def require_constraint(state: ContactState) -> None:
    """Raise :class:`SoftLawError` (one line) if the state's normal law does not use the
    multiplier λ: the augmented Lagrangian would drive to g = 0 a gap the law does not want
    (16 multiplier updates and a failed run, on the tube with an exponential law)."""
    law = state.normal_law
    if not laws.uses_multiplier(law, terms.law_inputs(state, refreshed=True)):
        name = getattr(law, "__qualname__", repr(law))
        raise SoftLawError(
            f"the normal law {name} does not use the multiplier (c.multiplier): it is a soft "
            "law, not a constraint, and the augmented Lagrangian cannot apply to it; use the "
            'penalty ([physics] contact = "penalty")'
        )


@dataclass
class UzawaReport:
    """Penetration [m] and Newton iterations of each augmented-Lagrangian pass."""

    converged: bool = False
    penetration: list[float] = field(default_factory=list)
    newton_iterations: list[int] = field(default_factory=list)
    kappa: list[float] = field(default_factory=list)  # the penalty of each pass [Pa/m]
    #: what was done after each failed pass: "plain step" (the extrapolated multiplier step
    #: overshot: the plain one), "smaller raise" (κ ×√10 instead of ×10), "no raise"
    recoveries: list[str] = field(default_factory=list)
    tolerance: float = 0.0  # the penetration tolerance [m]


def max_penetration(state: ContactState) -> float:
    """max(−g) over all ranks [m] (≤ 0 when nothing penetrates)."""
    g = state.local_values(state.gap)
    local = float(-g.min()) if len(g) else -np.inf
    return state.mesh.comm.allreduce(local, op=MPI.MAX)


#: Penalty raise of a stalled update, the decrease that counts as progress, and the most raises.
STIFFEN_FACTOR, SUFFICIENT_DECREASE, MAX_STIFFEN = 10.0, 0.25, 3
#: The raise tried instead when a ×STIFFEN_FACTOR raise made Newton fail.
SMALL_RAISE = STIFFEN_FACTOR**0.5
#: Failed passes put back and tried again, in all (they do not count as multiplier updates).
MAX_RECOVERIES = MAX_STIFFEN + 2
#: A slow contraction raises κ only if it would need more than this many further updates to reach
#: the tolerance: on the cotton gilet (24.7 mm) the raise to 100× the scene's penalty at 7.9 µm
#: against a 4.6 µm tolerance (contraction 0.33: one more plain update) cost two passes of 18 and
#: 23 Newton iterations, where a plain update costs 4-5.
PLAIN_UPDATES = 3


def updates_to_reach(tol: float, pen: float, rho: float) -> float:
    """Further updates a contraction ρ per update needs to take the penetration ``pen`` to
    ``tol`` (∞ when ρ ≥ 1)."""
    if pen <= tol:
        return 0.0
    if rho >= 1.0:
        return math.inf
    return math.log(tol / pen) / math.log(rho) if rho > 0.0 else 1.0


#: Largest observed contraction ρ of a point's penetration that :func:`update_multiplier`
#: extrapolates (the step on λ is then at most 1/(1 − ρ) = 10× the plain Uzawa step).
MAX_CONTRACTION = 0.9


def update_multiplier(
    state: ContactState, kappa: float, previous_gap: np.ndarray | None = None
) -> None:
    """λ ← t_N(g, λ, κ / (1 − ρ)) at every contact point, with t_N the state's normal law
    (``state.normal_law``, default ⟨λ − κ g⟩₊) at the refreshed gap g (the converged state) and
    ρ = g/g_prev the point's observed contraction (0 on the first update).

    ρ = 0 is the plain Uzawa step. Where a point's penetration falls only slowly from one update
    to the next — the structure around it is much stiffer than the penalty that point carries,
    e.g. a free-edge vertex of a P2 garment with a small tributary weight, whose penetration
    on the cotton gilet fell by only 5 % per update — the step is extrapolated: for one point
    on a spring K with the penalty κ', g_{k+1} = ρ g_k with ρ = K/(K + κ'), and the step
    κ' g_k/(1 − ρ) = (K + κ') g_k lands on g = 0 (Aitken's Δ² extrapolation of the multiplier
    sequence). ρ is used only where the point penetrated both times and less now, and is capped
    at :data:`MAX_CONTRACTION`. The law is evaluated, not restated: the extrapolated penalty
    κ/(1 − ρ) is a point Function passed to it as its κ.
    """
    g = state.gap.x.array
    gain = np.ones_like(g)
    if previous_gap is not None:
        both = (g < 0.0) & (previous_gap < g)
        rho = np.zeros_like(g)
        rho[both] = np.minimum(g[both] / previous_gap[both], MAX_CONTRACTION)
        gain = 1.0 / (1.0 - rho)
    step = _point_penalty(state)
    step.x.array[:] = kappa * gain
    new = dolfinx.fem.Function(state.Qs)
    state.assign(new, state.refreshed_traction(step))
    state.lam.x.array[:] = new.x.array
    state.lam.x.scatter_forward()


#: The extrapolated-penalty point Function of each state (made once: one compiled law).
_PENALTIES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _point_penalty(state: ContactState) -> dolfinx.fem.Function:
    """The point Function of κ/(1 − ρ) for ``state``."""
    if state not in _PENALTIES:
        _PENALTIES[state] = dolfinx.fem.Function(state.Qs, name="uzawa_penalty")
    return _PENALTIES[state]


def augmented_lagrangian(
    state: ContactState,
    kappa: float,
    solve: Callable[[], tuple[int, int]],
    *,
    tol: float,
    max_updates: int = 20,
    stiffen=None,
    unknown=None,
) -> UzawaReport:
    """Solve, update λ, repeat until the penetration is ≤ ``tol`` [m] (e.g. 1 % of h).

    ``solve()`` returns (Newton iterations, SNES reason), e.g. ``NonlinearSolver.solve``.
    ``stiffen``: the penalty ``fem.Constant`` of the contact form (its value is ``kappa``);
    when given, a stalled update raises it (module doc) and it keeps its last value.
    ``unknown``: the model's unknown Function; when given, a failed solve puts it, λ and κ back
    to the last converged pass (so what is reported is a converged state, not the iterate
    Newton gave up on), and the pass is tried again once with a gentler step (``recoveries``):
    after a failed ×10 raise with κ ×√10 (then, if that fails too, at the last κ that converged
    with no further raise: on the cotton gilet at 35 mm the third raise, κ = 1000× the scene's,
    failed at 6.5 µm against a 4.6 µm tolerance); after a failed pass at an unchanged κ with the
    plain (not extrapolated) multiplier step.
    """
    require_constraint(state)
    report = UzawaReport(tolerance=tol)
    previous = None
    last_gap = None  # the gap of the last converged pass
    raises = 0
    last = None
    # Only converged passes count as updates; a failed pass is put back and tried again at most
    # MAX_RECOVERIES times in all (each kind of recovery is itself bounded: one "plain step",
    # one "smaller raise" per raise, one "no raise").
    while len(report.recoveries) <= MAX_RECOVERIES and _go_on(report.penetration, max_updates):
        its, reason = solve()
        report.newton_iterations.append(its)
        report.kappa.append(kappa)
        if reason <= 0:
            if last is None or unknown is None:
                return report
            q, lam, kappa_ok, gap_ok, previous_ok = last
            put_back(state, unknown, stiffen, q, lam, kappa_ok)
            if kappa == kappa_ok:
                if previous_ok is None or "plain step" in report.recoveries:
                    return report  # failed at a penalty that had converged: nothing left
                # the extrapolated step overshot: the plain Uzawa step from the same pass
                report.recoveries.append("plain step")
                update_multiplier(state, kappa, None)
                previous = gap_ok
                continue
            if kappa > SMALL_RAISE * kappa_ok * (1.0 + 1e-12):
                # the raise was more than Newton could take: a smaller one from the same pass
                report.recoveries.append("smaller raise")
                update_multiplier(state, kappa_ok, None)  # the plain step of the converged pass
                kappa = SMALL_RAISE * kappa_ok
                stiffen.value = kappa
                previous = None
                continue
            # go on at the last penalty that converged, with no more raises (the report's κ
            # list shows the failed passes)
            report.recoveries.append("no raise")
            kappa, raises = kappa_ok, MAX_STIFFEN
            update_multiplier(state, kappa, previous_ok)
            previous = gap_ok
            continue
        pen = max_penetration(state)
        report.penetration.append(pen)
        if pen <= tol:
            report.converged = True
            return report
        gap = state.gap.x.array.copy()
        if unknown is not None:
            last = (unknown.x.array.copy(), state.lam.x.array.copy(), kappa, gap, previous)
        stalled = False
        if len(report.penetration) > 1:
            rho = persisting_penetration(state, gap, last_gap) / report.penetration[-2]
            stalled = rho > SUFFICIENT_DECREASE and updates_to_reach(tol, pen, rho) > PLAIN_UPDATES
        last_gap = gap
        if stiffen is not None and stalled and raises < MAX_STIFFEN:
            raises += 1
            kappa *= STIFFEN_FACTOR
            stiffen.value = kappa
            previous = None  # the contraction seen at the old κ says nothing about the new one
        update_multiplier(state, kappa, previous)
        previous = gap
    return report


#: Past ``max_updates`` the loop goes on while each update still takes at least this fraction
#: off the largest penetration (it is converging: a run is not thrown away for a count), up to
#: :data:`EXTRA_UPDATES` × ``max_updates`` updates in all.
CONTINUE_DECREASE, EXTRA_UPDATES = 0.1, 3


def _go_on(penetration: list[float], max_updates: int) -> bool:
    """Whether the loop makes another pass after the converged passes ``penetration``: within
    ``max_updates`` updates always; beyond, while the last update contracted by at least
    :data:`CONTINUE_DECREASE` (the scan dress on a heavier MakeHuman body stopped at 5.41 µm
    against a 4.6 µm tolerance after its 3 updates while still contracting)."""
    updates = len(penetration) - 1
    if updates < max_updates:
        return True
    if updates >= EXTRA_UPDATES * max(max_updates, 1) or len(penetration) < 2:
        return False
    return penetration[-1] <= (1.0 - CONTINUE_DECREASE) * penetration[-2]


def persisting_penetration(state: ContactState, gap: np.ndarray, last: np.ndarray | None) -> float:
    """max(−g) over the points that penetrated in the last pass too (all ranks) [m].

    The penalty is raised only when these stall: a point that has just come into contact has no
    multiplier yet, and the next update gives it one at the same κ. On the cotton gilet at
    24.7 mm the largest penetration went 6.7 → 5.5 µm at one armhole point with λ = 0 there, and
    the ×10 raise this triggered was more than Newton could take."""
    old = np.ones(len(gap), dtype=bool) if last is None else last < 0.0
    local = float(-gap[old].min()) if old.any() else -np.inf
    return state.mesh.comm.allreduce(local, op=MPI.MAX)


def put_back(state: ContactState, unknown, stiffen, q, lam, kappa: float) -> None:
    """Restore a converged state: the unknown, the multipliers and the penalty (``stiffen``,
    the penalty Constant, may be None)."""
    unknown.x.array[:] = q
    unknown.x.scatter_forward()
    state.lam.x.array[:] = lam
    state.lam.x.scatter_forward()
    if stiffen is not None:
        stiffen.value = kappa
    state.refresh()
