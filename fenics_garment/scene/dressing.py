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


@dataclass
class Progress:
    """Where a dressing is: enough, with the model's arrays, to continue it (``checkpoint``).

    ``stage`` is ``"grow"`` (the body grows from ``shrink`` in steps of ``step``), ``"release"``
    (s = 0; the spring stages ``stages`` are still to do, after ``retries`` retries) or ``"done"``
    (every solve converged; only the outputs are left). ``c`` is the spring constant and ``mu``
    the scene's friction coefficient (off while the body grows).
    """

    report: DressReport
    stage: str = "grow"
    shrink: float = 0.0
    step: float = 0.0
    stages: list[float] = field(default_factory=list)
    retries: int = 0
    c: float = 0.0
    mu: float = 0.0

    def as_dict(self) -> dict:
        r = self.report
        rep = {**r.__dict__, "steps": [s.__dict__ for s in r.steps],
               "failures": [list(f) for f in r.failures]}  # fmt: skip
        return {**self.__dict__, "report": rep}

    @classmethod
    def from_dict(cls, d: dict) -> Progress:
        r = dict(d["report"])
        r["steps"] = [DressStep(**s) for s in r["steps"]]
        r["failures"] = [tuple(f) for f in r["failures"]]
        return cls(**{**d, "report": DressReport(**r)})


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
    on_checkpoint: Callable[[Progress], None] | None = None,
    resume: Progress | None = None,
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
        on_checkpoint: called with the :class:`Progress` after every converged solve (the model
            then holds the converged state), e.g. to write a checkpoint.
        resume: continue from this progress; the caller has put the model's arrays back
            (``checkpoint.restore``). The same steps follow as in the uninterrupted run.
    """
    model, contact, reg = built.model, built.contact, built.regularisation
    st = contact.state
    comm = model.geometry.mesh.comm
    q = model.q
    mu = built.mu
    if resume is None:
        rep = DressReport()
        rep.penetration0 = initial_penetration(contact)
        s0 = max(rep.penetration0, 0.0) + margin
        rep.shrink0 = s0
        ds = s0 / steps if first_step is None else first_step * s0
        pr = Progress(rep, "grow", s0, ds, c=reg.c0, mu=float(mu.value) if mu is not None else 0.0)
        st.shrink.value = s0
        reg.c.value = reg.c0
        reg.accept_step(q)
        st.refresh()
        st.accept_step()
    else:
        pr, rep = resume, resume.report
        st.shrink.value = pr.shrink
        reg.c.value = pr.c
        st.refresh()
    s0 = rep.shrink0
    if mu is not None and not friction_while_dressing and pr.stage == "grow":
        mu.value = 0.0
    cuts = 0
    while pr.stage == "grow" and pr.shrink > 0.0:
        s, ds = pr.shrink, pr.step
        target = max(s - ds, 0.0)
        if target < 1e-3 * s0:  # do not leave a sliver of a step at the end
            target = 0.0
        if target == s:  # the step is below round-off: no progress is possible
            raise DressingFailed(rep, s, f"dressing stopped: the step {ds:.3g} m is below "
                                 f"round-off at shrink {s * 1e3:.3f} mm")  # fmt: skip
        q_conv = q.x.array.copy()
        st.shrink.value = target
        t0 = time.perf_counter()
        its, reason = solver.solve()
        if reason > 0:
            rec = DressStep(target, its, reason, cuts, time.perf_counter() - t0, float(reg.c.value))
            rep.steps.append(rec)
            st.accept_step()
            reg.accept_step(q)
            cuts = 0
            pr.shrink, pr.step = target, ds * grow if its <= grow_below else ds
            if on_step:
                on_step(rec)
            if on_checkpoint:
                on_checkpoint(pr)
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
        pr.step = ds / 2
        if cuts > max_cuts:
            raise DressingFailed(
                rep, s,
                f"dressing stopped: Newton failed {cuts} times in a row going from shrink "
                f"{s * 1e3:.3f} mm towards {target * 1e3:.3f} mm (last SNES reason {reason} "
                f"after {its} iterations); the last converged state (shrink {s * 1e3:.3f} mm) "
                "is kept",
            )  # fmt: skip
    if pr.stage == "grow":
        if mu is not None:
            mu.value = pr.mu  # friction on: the garment sticks where it was put (slip = 0)
        pr.stage = "release"
        pr.stages = [] if reg.c0 == 0.0 else [f * reg.c0 for f in (0.1, 0.01, 1e-3, 1e-4, 0.0)]
        if reg.c0 == 0.0:
            rep.regularisation_effect = 0.0
        else:
            rep.final_regularisation = float(reg.c.value)
    elif mu is not None:
        mu.value = pr.mu
    if pr.stage == "release":
        _release(pr, built, solver, comm, on_checkpoint)
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
        pr.stage = "done"
        if on_checkpoint:
            on_checkpoint(pr)
    return rep


def _release(
    pr: Progress,
    built,
    solver: NonlinearSolver,
    comm: MPI.Comm,
    on_checkpoint: Callable[[Progress], None] | None = None,
) -> None:
    """Final solves at s = 0 with the spring released in stages c₀/10 … c₀/10⁴, then 0.

    The answer is the c = 0 state; the pressure change of the last stage is reported as the
    regularisation's effect. A stage that fails is undone and retried from half-way (in log c),
    up to three times; then the previous state, with its c, is kept and reported
    (``final_regularisation`` > 0; the effect is then that of the last stage that converged, NaN
    if none did: the answer still carries the spring). ``pr.stages`` holds the stages to go.
    """
    model, contact, reg = built.model, built.contact, built.regularisation
    rep = pr.report
    while pr.stages:
        c = pr.stages.pop(0)
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
            if pr.retries == 3 or c_prev == 0.0:
                pr.stages = []
                return
            pr.retries += 1
            mid = (c_prev * max(c, 1e-5 * reg.c0)) ** 0.5  # half-way in log c
            pr.stages = [mid, c, *pr.stages]
            continue
        rep.steps.append(DressStep(0.0, its, reason, 0, 0.0, c))
        rep.final_regularisation = c
        rep.regularisation_effect = _max_pressure_change(contact, before, comm)
        built.contact.state.accept_step()
        reg.accept_step(model.q)
        pr.c = c
        if on_checkpoint:
            on_checkpoint(pr)
