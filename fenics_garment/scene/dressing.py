"""Dressing: shrink the body inside the garment, then grow it back in adaptive steps.

The garment is cut with its pattern ease, so where the ease is negative its stress-free shape lies
inside the body. The body is first shrunk by s₀ = (deepest initial penetration) + margin — every
contact point is then outside it — and s is driven back to 0 (``ContactState.shrink``; seed paper
§4.1 step 4 "for each time step"). A step whose Newton solve fails is undone and halved (like
:class:`fenics_garment.solve.LoadStepper`, which drives the load factor rather than the shrink);
after ``max_cuts`` halvings in a row :class:`DressingFailed` is raised, with the last converged
state left in the model and the report of the steps so far.

The pseudo-time regularisation (:class:`~fenics_garment.scene.build.Regularisation`) is on at c₀
during the steps (fading it with the shrink made Newton fail near s = 0 on the gilet), then
released at s = 0 in three solves, c₀/10, c₀/100 and 0 (measured on the cotton gilet: the
change of the last stage from c₀/10 was 2.5 %, too much to call negligible); the answer is the
c = 0 state and the pressure change of the last release solve is reported as the
regularisation's effect.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from fenics_garment._stack import MPI
from fenics_garment.contact import uzawa
from fenics_garment.solve import NonlinearSolver


@dataclass
class DressStep:
    shrink: float  # body shrink after the step [m]
    iterations: int
    reason: int
    cuts: int  # halvings before this step converged
    seconds: float
    regularisation: float  # c [Pa/m] during the step


@dataclass
class DressReport:
    shrink0: float = 0.0  # initial shrink s₀ [m]
    penetration0: float = 0.0  # deepest initial penetration of the pattern [m]
    steps: list[DressStep] = field(default_factory=list)
    failures: list[tuple[float, int, int]] = field(default_factory=list)  # (target s, its, reason)
    regularisation_effect: float = float("nan")  # max |Δp| / max p when c → 0
    final_regularisation: float = 0.0  # c of the final answer [Pa/m]
    al_updates: int = 0
    al_penetration: list[float] = field(default_factory=list)
    completed: bool = False

    @property
    def newton_iterations(self) -> int:
        return sum(s.iterations for s in self.steps)

    def as_dict(self) -> dict:
        return {
            "shrink0_m": self.shrink0,
            "penetration0_m": self.penetration0,
            "steps": [s.__dict__ for s in self.steps],
            "failed_attempts": [
                {"target_shrink_m": s, "iterations": i, "reason": r} for s, i, r in self.failures
            ],
            "cuts": len(self.failures),
            "newton_iterations": self.newton_iterations,
            # null (not NaN, which is not JSON) when the spring could not be released
            "regularisation_effect": (
                None if math.isnan(self.regularisation_effect) else self.regularisation_effect
            ),
            "final_regularisation_Pa_per_m": self.final_regularisation,
            "augmented_lagrangian_updates": self.al_updates,
            "augmented_lagrangian_penetration_m": self.al_penetration,
            "completed": self.completed,
        }


class DressingFailed(RuntimeError):
    """Newton failed ``max_cuts + 1`` times in a row; the model holds the last converged state."""

    def __init__(self, report: DressReport, shrink: float, message: str):
        self.report, self.shrink = report, shrink
        super().__init__(message)


def initial_penetration(contact) -> float:
    """Deepest penetration [m] of the undeformed pattern into the unshrunk body (≤ 0: none)."""
    st = contact.state
    saved = float(st.shrink.value)
    st.shrink.value = 0.0
    st.refresh()
    pen = uzawa.max_penetration(st)
    st.shrink.value = saved
    return pen


def _max_pressure_change(contact, before: np.ndarray, comm: MPI.Comm) -> float:
    after = contact.pressure_values()
    d = float(np.abs(after - before).max()) if len(after) else 0.0
    top = float(np.abs(after).max()) if len(after) else 0.0
    d, top = comm.allreduce(d, op=MPI.MAX), comm.allreduce(top, op=MPI.MAX)
    return d / top if top > 0 else 0.0


def dress(
    built,
    solver: NonlinearSolver,
    *,
    steps: int,
    margin: float,
    max_cuts: int = 4,
    grow: float = 1.5,
    grow_below: int = 4,
    first_step: float | None = None,
    on_step: Callable[[DressStep], None] | None = None,
    on_failure: Callable[[float, int, int], None] | None = None,
    augmented_lagrangian: tuple[float, int] | None = None,
    friction_while_dressing: bool = False,
) -> DressReport:
    """Grow the body from s₀ back to 0 (see module doc); returns the :class:`DressReport`.

    Args:
        built: a :class:`fenics_garment.scene.build.Built`.
        solver: Newton on ``built.model`` with ``built.contact.refresh`` as pre-residual hook.
        steps: initial number of equal steps in s.
        margin: s₀ exceeds the deepest initial penetration by this [m].
        first_step: override the first step (as a fraction of s₀), e.g. to force a cut in tests.
        augmented_lagrangian: (tolerance [m], max updates) for Uzawa at s = 0, or None (penalty).
        friction_while_dressing: keep Coulomb friction on while the body grows. Off by default:
            stick/slip switching at many points at once made Newton fail on the gilet, and the
            dressing path is artificial anyway (the body grows; nobody pulls the garment on).
            Friction is switched on at s = 0, where the slip since the last step is zero, so it
            holds the garment where it was put (against gravity) for the final solves.
    """
    model, contact, reg = built.model, built.contact, built.regularisation
    st = contact.state
    comm = model.geometry.mesh.comm
    q = model.q
    rep = DressReport()
    rep.penetration0 = initial_penetration(contact)
    s0 = max(rep.penetration0, 0.0) + margin
    rep.shrink0 = s0
    s = s0
    ds = s0 / steps if first_step is None else first_step * s0
    st.shrink.value = s
    reg.c.value = reg.c0
    reg.accept_step(q)
    st.refresh()
    st.accept_step()
    mu = built.mu
    mu_value = float(mu.value) if mu is not None else 0.0
    if mu is not None and not friction_while_dressing:
        mu.value = 0.0
    cuts = 0
    while s > 0.0:
        target = max(s - ds, 0.0)
        if target < 1e-3 * s0:  # do not leave a sliver of a step at the end
            target = 0.0
        q_conv = q.x.array.copy()
        st.shrink.value = target
        t0 = time.perf_counter()
        its, reason = solver.solve()
        if reason > 0:
            s = target
            rec = DressStep(s, its, reason, cuts, time.perf_counter() - t0, float(reg.c.value))
            rep.steps.append(rec)
            st.accept_step()
            reg.accept_step(q)
            if on_step:
                on_step(rec)
            cuts = 0
            ds = ds * grow if its <= grow_below else ds
            continue
        # failed: restore the last converged state and halve the step
        q.x.array[:] = q_conv
        q.x.scatter_forward()
        st.shrink.value = s
        st.refresh()
        rep.failures.append((target, its, reason))
        if on_failure:
            on_failure(target, its, reason)
        cuts += 1
        ds /= 2
        if cuts > max_cuts:
            raise DressingFailed(
                rep, s,
                f"dressing stopped: Newton failed {cuts} times in a row going from shrink "
                f"{s * 1e3:.3f} mm towards {target * 1e3:.3f} mm (last SNES reason {reason} "
                f"after {its} iterations); the last converged state (shrink {s * 1e3:.3f} mm) "
                "is kept",
            )  # fmt: skip
    if mu is not None:
        mu.value = mu_value  # friction on: the garment sticks where it was put (slip = 0)
    _release(rep, built, solver, comm)
    if augmented_lagrangian is not None:
        tol, max_updates = augmented_lagrangian
        al = uzawa.augmented_lagrangian(
            st, float(contact.kappa.value), solver.solve, tol=tol, max_updates=max_updates
        )
        rep.al_updates = len(al.penetration) - 1
        rep.al_penetration = al.penetration
        if not al.converged:
            raise DressingFailed(
                rep, 0.0,
                f"augmented Lagrangian: penetration {al.penetration[-1:]} m not below {tol} m "
                f"after {max_updates} multiplier updates",
            )  # fmt: skip
        st.accept_step()
    rep.completed = True
    return rep


def _release(rep: DressReport, built, solver: NonlinearSolver, comm: MPI.Comm) -> None:
    """Final solves at s = 0 with the spring released in stages c₀/10 … c₀/10⁴, then 0.

    The answer is the c = 0 state; the pressure change of the last stage is reported as the
    regularisation's effect. A stage that fails is undone and retried from half-way (in log c),
    up to three times; then the previous state, with its c, is kept and reported
    (``final_regularisation`` > 0; the effect is then that of the last stage that converged, NaN
    if none did: the answer still carries the spring).
    """
    model, contact, reg = built.model, built.contact, built.regularisation
    if reg.c0 == 0.0:
        rep.regularisation_effect = 0.0
        return
    rep.final_regularisation = float(reg.c.value)
    stages = [0.1 * reg.c0, 0.01 * reg.c0, 1e-3 * reg.c0, 1e-4 * reg.c0, 0.0]
    retries = 0
    while stages:
        c = stages.pop(0)
        before = contact.pressure_values()
        q_conv = model.q.x.array.copy()
        c_prev = float(reg.c.value)
        reg.c.value = c
        its, reason = solver.solve()
        if reason <= 0:
            rep.failures.append((0.0, its, reason))
            model.q.x.array[:] = q_conv
            model.q.x.scatter_forward()
            reg.c.value = c_prev
            contact.state.refresh()
            if retries == 3 or c_prev == 0.0:
                return
            retries += 1
            mid = (c_prev * max(c, 1e-5 * reg.c0)) ** 0.5  # half-way in log c
            stages = [mid, c, *stages]
            continue
        rep.steps.append(DressStep(0.0, its, reason, 0, 0.0, c))
        rep.final_regularisation = c
        rep.regularisation_effect = _max_pressure_change(contact, before, comm)
        built.contact.state.accept_step()
        reg.accept_step(model.q)
