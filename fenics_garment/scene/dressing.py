"""Dressing: shrink the body inside the garment, then grow it back in steps.

The garment is cut with its pattern ease, so where the ease is negative its stress-free shape lies
inside the body. The body is first shrunk by s₀ = (deepest initial penetration) + margin — every
contact point is then outside it — and s is driven back to 0 (``ContactState.shrink``; seed paper
§4.1 step 4 "for each time step"). A step whose Newton solve fails is undone and halved (like
:class:`fenics_garment.solve.LoadStepper`, which drives the load factor rather than the shrink);
after ``max_cuts`` halvings in a row :class:`DressingFailed` is raised, with the last converged
state left in the model and the report of the steps so far.

The regularising spring (:class:`~fenics_garment.scene.build.Regularisation`) is on at c₀
during the steps (fading it with the shrink made Newton fail near s = 0 on the gilet), then
released at s = 0: solves with a weaker spring each time until c = 0. The answer is the c = 0
state and the pressure change of the last release solve is reported as the regularisation's
effect. By default the spring pulls towards the garment as it was placed around the shrunk body
(``spring_anchor = "start"``): the dressing is then a quasi-static path of one problem, the
body's shrink s and the spring c its parameters, and refining its steps converges (cotton gilet,
35 mm, friction while growing, 4 / 8 / 16 grow steps: underbust mean 0.1401 / 0.1402 / 0.1400
kPa). A spring to the previous solve (``"previous"``, the older default) is a pseudo-time
damper instead: every solve lets the garment drift a little further under gravity and the
garment's own forces, so the answer followed the number of solves with no limit (same gilet,
4 / 8 / 16 / 32 steps: 0.139 / 0.131 / 0.113 / 0.081 kPa; record ``cotton_gilet:friction-growing
+steps-N`` in ``benchmarks/results/convergence.json``).

With friction the answer depends on the path (the anchors of sticking points are where the
garment was when friction came on, moved by every solve since), so the path is part of the
problem statement. ``schedule = "fixed"`` (the default) makes it the same on every mesh: the
body grows through the shrinks s₀(1 − k/steps) and the spring is released through
c₀·rᵏ (``release_ratio`` r), then 0; a failed solve inserts a sub-step on the way to the same
schedule point (the cut step grows back after easy solves, never past that point), so a mesh
that needs one differs from the others only there (the records count them). ``"adaptive"``
lets the steps follow Newton (grow the step after an easy solve; the spring follows the force it
still carries, :func:`_release`): fewer solves, but each mesh takes its own path. (The
scatter of the gilets' frictional p95 between meshes was measured to come mostly from the stick
penalty and the spring scaling with the cell size, not from the path: the fixed schedule alone
changed the cotton gilet's upper-chest p95 by ≤ 2 %; ``scene.build``.)

Only the answer is converged to the solver's tolerance (snes_rtol × the scene's force scale):
the c = 0 solve and, with the augmented Lagrangian, one last pass at the final multipliers. The
solves on the way — grow steps, release solves with a spring, the multiplier passes, whose only
use is their penetration — stop at ``path_tolerance`` × that scale, which saves Newton's last one
or two quadratic iterations of each. With ``release_multipliers`` the multipliers are updated
after each release solve too, so that they have nearly converged by c = 0.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

from fenics_garment._stack import MPI
from fenics_garment.contact import uzawa
from fenics_garment.scene.config import DRESSING_PREDICTORS, DRESSING_SCHEDULES, DressingConfig
from fenics_garment.solve import CYCLING_REASON, NONFINITE_REASON, NonlinearSolver, reason_name


@dataclass
class DressStep:
    shrink: float  # body shrink after the step [m] (stage "sew": the sewing parameter w)
    iterations: int
    reason: int
    cuts: int  # halvings before this step converged
    seconds: float
    regularisation: float  # c [Pa/m] during the step
    #: "sew" (a flat rest state reached, body shrunk), "dress" (body growing) or "release"
    #: (spring released at s = 0)
    stage: str = "dress"
    # r_k/r_(k-1) of the last two Newton iterations (quadratic convergence: the last ≪ the one
    # before); empty when the solve took fewer than two iterations
    final_ratios: list[float] = field(default_factory=list)
    residuals: list[float] = field(default_factory=list)  # ‖F‖ of every Newton iterate


def final_ratios(solver: NonlinearSolver) -> list[float]:
    """The residual ratios r_k/r_(k−1) of the last two iterations of the solver's last solve."""
    r = solver.residual_history()
    return [float(r[k] / r[k - 1]) for k in range(max(len(r) - 2, 1), len(r)) if r[k - 1] > 0]


@dataclass
class DressReport:
    shrink0: float = 0.0  # initial shrink s₀ [m]
    penetration0: float = 0.0  # deepest initial penetration of the pattern [m]
    steps: list[DressStep] = field(default_factory=list)
    failures: list[tuple[float, int, int]] = field(default_factory=list)  # (target s, its, reason)
    #: Newton's residual norms of each failed try (cycling, slow or diverging: the history says)
    failure_residuals: list[list[float]] = field(default_factory=list)
    regularisation_effect: float = float("nan")  # max |Δp| / max p when c → 0
    final_regularisation: float = 0.0  # c of the final answer [Pa/m]
    # c·max|u − u_prev| of the last accepted solve [Pa]: bounds the force the spring took from
    # the physical equilibrium (0 once released)
    spring_traction: float = 0.0
    residual_atol: float = 0.0  # absolute Newton tolerance used [N] (_absolute_tolerance)
    al_updates: int = 0
    al_penetration: list[float] = field(default_factory=list)
    al_kappa: list[float] = field(default_factory=list)  # the penalty of each pass [Pa/m]
    al_recoveries: list[str] = field(default_factory=list)  # after failed passes (uzawa)
    al_iterations: list[int] = field(default_factory=list)  # Newton its of each pass (uzawa)
    al_converged: bool = True  # the penetration reached the tolerance (or no multipliers used)
    al_message: str = ""  # why not, when not
    answer_atol: float = 0.0  # the absolute tolerance the answer's last solve met [N]
    answer_note: str = ""  # why that is the path tolerance, when it is
    completed: bool = False
    #: the coarser garment levels this dressing started from (``scene.sequence``), coarsest first
    levels: list[dict] = field(default_factory=list)
    #: why the mesh sequence was not used, when it was not (a coarser level did not dress, the
    #: levels did not fit, or the carried state did not settle): the dressing then ran directly
    sequence_failed: str = ""

    @property
    def newton_iterations(self) -> int:
        """Newton iterations of the accepted dressing and release solves."""
        return sum(s.iterations for s in self.steps)

    @property
    def all_newton_iterations(self) -> int:
        """Every Newton iteration of the dressing: the accepted solves, the failed tries and the
        augmented Lagrangian's passes."""
        return self.newton_iterations + sum(f[1] for f in self.failures) + sum(self.al_iterations)

    def as_dict(self) -> dict:
        return {
            "shrink0_m": self.shrink0,
            "penetration0_m": self.penetration0,
            "steps": [s.__dict__ for s in self.steps],
            "failed_attempts": [
                {"target_shrink_m": s, "iterations": i, "reason": r, "residuals": h}
                for (s, i, r), h in zip(self.failures, self.failure_residuals, strict=True)
            ],
            "cuts": len(self.failures),
            "newton_iterations": self.newton_iterations,
            # null (not NaN, which is not JSON) when the spring could not be released
            "regularisation_effect": (
                None if math.isnan(self.regularisation_effect) else self.regularisation_effect
            ),
            "final_regularisation_Pa_per_m": self.final_regularisation,
            "spring_traction_max_Pa": self.spring_traction,
            "residual_atol_N": self.residual_atol,
            "augmented_lagrangian_updates": self.al_updates,
            "augmented_lagrangian_penetration_m": self.al_penetration,
            "augmented_lagrangian_kappa_Pa_per_m": self.al_kappa,
            "augmented_lagrangian_recoveries": self.al_recoveries,
            "augmented_lagrangian_newton_iterations": self.al_iterations,
            "augmented_lagrangian_converged": self.al_converged,
            "augmented_lagrangian_message": self.al_message,
            "answer_atol_N": self.answer_atol,
            "answer_note": self.answer_note,
            "all_newton_iterations": self.all_newton_iterations,
            "completed": self.completed,
            "sequence": self.levels,
            "sequence_failed": self.sequence_failed,
        }


class DressingFailed(RuntimeError):
    """Newton failed ``max_cuts + 1`` times in a row; the model holds the last converged state."""

    def __init__(self, report: DressReport, shrink: float, message: str):
        self.report, self.shrink = report, shrink
        super().__init__(message)


@contextmanager
def unshrunk(st):
    """The contact state refreshed against the unshrunk body (s = 0) inside the block; the
    shrink put back after it (the gaps are those of s = 0 until the next refresh)."""
    saved = float(st.shrink.value)
    st.shrink.value = 0.0
    st.refresh()
    try:
        yield st
    finally:
        st.shrink.value = saved


def initial_penetration(contact) -> float:
    """Deepest penetration [m] of the undeformed pattern into the unshrunk body (≤ 0: none)."""
    with unshrunk(contact.state) as st:
        return uzawa.max_penetration(st)


def _force_scale(built, solver: NonlinearSolver) -> float:
    """‖F‖ of the undressed pattern (q = 0, s = 0, no spring) [N]: the forces the fit creates,
    the scene's natural force scale. Deterministic, so a resumed run gets the same value."""
    model, st, reg = built.model, built.contact.state, built.regularisation
    q_saved, s_saved, c_saved = model.q.x.array.copy(), float(st.shrink.value), float(reg.c.value)
    model.q.x.array[:] = 0.0
    model.q.x.scatter_forward()
    st.shrink.value, reg.c.value = 0.0, 0.0
    try:
        return solver.residual_norm()
    finally:
        model.q.x.array[:] = q_saved
        model.q.x.scatter_forward()
        st.shrink.value, reg.c.value = s_saved, c_saved
        st.refresh()


def _absolute_tolerance(f_ref: float, solver: NonlinearSolver) -> float:
    """Raise the solver's absolute tolerance to rtol × ``f_ref`` (:func:`_force_scale`).

    Without it every solve is judged relative to its own first residual, and the release solves,
    which start close to equilibrium (‖F₀‖ ~ 1e-3), ground on at the linear tail of Newton with
    the refreshed contact normal (residual halving per iteration) to 15 iterations or failed:
    measured on the cotton gilet.
    """
    rtol = solver.problem.solver.getTolerances()[0]
    return solver.raise_atol(rtol * f_ref)


def _max_pressure(contact, comm: MPI.Comm) -> float:
    """The largest contact pressure over all ranks [Pa]."""
    p = contact.pressure_values()
    return comm.allreduce(float(np.abs(p).max()) if len(p) else 0.0, op=MPI.MAX)


def _max_pressure_change(contact, before: np.ndarray, comm: MPI.Comm) -> float:
    after = contact.pressure_values()
    d = float(np.abs(after - before).max()) if len(after) else 0.0
    top = float(np.abs(after).max()) if len(after) else 0.0
    d, top = comm.allreduce(d, op=MPI.MAX), comm.allreduce(top, op=MPI.MAX)
    return d / top if top > 0 else 0.0


@dataclass
class Progress:
    """Where a dressing is: enough, with the model's arrays, to continue it (``checkpoint``).

    ``stage`` is ``"grow"`` (the body grows from ``shrink`` in steps of ``step``), ``"sew"``
    (after the growth, a flat rest state is reached from the placed mesh's in steps of the
    sewing parameter, :func:`_sew`), ``"release"``
    (s = 0; the spring is released: ``c`` is the next spring constant to try, ``retries`` the
    failures in a row, ``spring`` the spring force of the last accepted solve, ``solves`` the
    release solves so far) or ``"done"`` (every solve converged; only the outputs are left).
    ``mu`` is the scene's friction coefficient (off while the body grows).
    """

    report: DressReport
    stage: str = "grow"
    shrink: float = 0.0
    step: float = 0.0
    retries: int = 0
    c: float = 0.0
    mu: float = 0.0
    spring: float = 0.0  # c·max|u − u_prev| of the last accepted release solve [Pa]
    solves: int = 0
    # fixed schedule: the schedule's c a sub-step (inserted after a failure) leads back to
    # (< 0: none)
    c_target: float = -1.0
    kappa: float = 0.0  # the contact penalty after the multiplier updates (0: the scene's) [Pa/m]
    tight: bool = False  # the next release solve keeps c, to the answer's tolerance; then c = 0
    #: stage "sew" (before "grow", a garment with a flat rest state): the sewing parameter w
    #: reached so far and its next step
    sewn: float = 1.0
    sew_step: float = 0.0

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
        # a checkpoint written before the histories were kept: none for its failures
        r.setdefault("failure_residuals", [[] for _ in r["failures"]])
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
    friction_while_growing: bool = DressingConfig.friction_while_growing,
    on_checkpoint: Callable[[Progress], None] | None = None,
    resume: Progress | None = None,
    schedule: str = "fixed",
    release_ratio: float = DressingConfig.release_ratio,
    predictor: str = DressingConfig.predictor,
    path_tolerance: float = DressingConfig.path_tolerance,
    release_multipliers: bool = DressingConfig.release_multipliers,
    sew_steps: int = DressingConfig.sew_steps,
) -> DressReport:
    """Grow the body from s₀ back to 0 (see module doc); returns the :class:`DressReport`.

    Args:
        built: a :class:`fenics_garment.scene.build.Built`.
        solver: Newton on ``built.model`` with ``built.contact.refresh`` as pre-residual hook.
        steps: initial number of equal steps in s.
        margin: s₀ exceeds the deepest initial penetration by this [m].
        first_step: override the first step (as a fraction of s₀), e.g. to force a cut in tests.
        augmented_lagrangian: (tolerance [m], max updates) for Uzawa at s = 0, or None (penalty);
            a normal law that is not a constraint is refused before any solve
            (:func:`uzawa.require_constraint`).
        friction_while_growing: keep Coulomb friction on while the body grows (the default:
            friction acts while a garment goes on). Off, friction is switched on at s = 0,
            where the slip since the last step is zero, so it holds the garment where the
            frictionless growth put it: the free-end hoop equilibrium of Laplace's law that the
            tube and limb scenes verify. The switch is ``ContactState.friction_on``, a factor
            on the friction law's traction: a law is switched however it holds its μ.
        on_checkpoint: called with the :class:`Progress` after every converged solve (the model
            then holds the converged state), e.g. to write a checkpoint.
        resume: continue from this progress; the caller has put the model's arrays back
            (``checkpoint.restore``). The same steps follow as in the uninterrupted run.
        schedule: ``"fixed"`` (the same path on every mesh) or ``"adaptive"`` (module doc).
        release_ratio: factor on the spring constant per release solve of the fixed schedule
            (:func:`_release`); its square root takes twice the solves along the same path.
        predictor: where Newton starts a grow step: ``"none"`` (the last converged state) or
            ``"secant"`` (:func:`secant_start`, once two grow solves have converged).
    """
    if schedule not in DRESSING_SCHEDULES:
        raise ValueError(f"schedule must be one of {DRESSING_SCHEDULES}, got {schedule!r}")
    if predictor not in DRESSING_PREDICTORS:
        raise ValueError(f"predictor must be one of {DRESSING_PREDICTORS}, got {predictor!r}")
    fixed = schedule == "fixed"
    model, contact, reg = built.model, built.contact, built.regularisation
    rest = model.geometry.rest
    st = contact.state
    comm = model.geometry.mesh.comm
    q = model.q
    mu = built.mu
    if augmented_lagrangian is not None:
        uzawa.require_constraint(st)  # a soft normal law: refused before any solve
    f_ref = _force_scale(built, solver)
    atol = _absolute_tolerance(f_ref, solver)  # deterministic: the same on a resume
    # the solves on the way (grow, release with a spring, multiplier passes) stop at the path
    # tolerance; the answer's (c = 0, the last pass at the final multipliers) at atol
    path_atol = max(atol, path_tolerance * f_ref)
    if resume is None:
        rep = DressReport()
        rep.penetration0 = initial_penetration(contact)
        s0 = max(rep.penetration0, 0.0) + margin
        rep.shrink0 = s0
        ds = s0 / steps if first_step is None else first_step * s0
        pr = Progress(rep, "grow", s0, ds, c=reg.c0, mu=float(mu.value) if mu is not None else 0.0)
        st.shrink.value = s0
        reg.c.value = reg.c0
        reg.place(q)
        if rest is not None:  # the body grows into the placed garment, then it is sewn
            pr.sewn, pr.sew_step = 0.0, 1.0 / sew_steps
        st.refresh()
        st.accept_step()
    else:
        pr, rep = resume, resume.report
        if pr.kappa > 0.0:  # the multiplier updates raised the penalty (uzawa: stiffen)
            contact.kappa.value = pr.kappa
        st.shrink.value = pr.shrink
        reg.c.value = pr.c
        st.refresh()
    if rest is not None:
        rest.sewn.value = pr.sewn
    rep.residual_atol = atol
    s0 = rep.shrink0
    grid = s0 / steps if first_step is None else first_step * s0  # the fixed schedule's step
    if not friction_while_growing and pr.stage == "grow":
        st.friction_on.value = 0.0  # off while the body grows, however the law is written
    cuts = 0
    last = None  # (shrink, state) of the converged grow solve before the current one
    solver.set_atol(path_atol)
    # a grow step caught in a cycle goes on with the other line search: the dress on f-old had
    # 16 steps cycling between two contact states (residual 0.39 / 0.062 N, …), each halved;
    # 244 s of dressing, 88 s going on with "l2" (benchmarks.bodies)
    grow_solve = _retrying(solver, q, st, cycles_only=True)
    while pr.stage == "grow" and pr.shrink > 0.0:
        s, ds = pr.shrink, pr.step
        target = max(s - ds, 0.0)
        if fixed:  # never past the next schedule point
            target = max(target, grid * (math.ceil(s / grid - 1e-9) - 1))
        if target < 1e-3 * s0:  # do not leave a sliver of a step at the end
            target = 0.0
        if target == s:  # the step is below round-off: no progress is possible
            raise DressingFailed(rep, s, f"dressing stopped: the step {ds:.3g} m is below "
                                 f"round-off at shrink {s * 1e3:.3f} mm")  # fmt: skip
        q_conv = q.x.array.copy()
        st.shrink.value = target
        if predictor == "secant" and last is not None:
            q.x.array[:] = secant_start(q_conv, *last, s, target)
            q.x.scatter_forward()
        t0 = time.perf_counter()
        its, reason = grow_solve()
        if reason > 0:
            last = (s, q_conv) if rep.steps else None  # a solve, not the placed garment
            rec = DressStep(target, its, reason, cuts, time.perf_counter() - t0, float(reg.c.value))
            rec.final_ratios = final_ratios(solver)
            rec.residuals = solver.residual_history().tolist()
            rep.steps.append(rec)
            rep.spring_traction = rec.regularisation * reg.stretch(q)
            st.accept_step()
            reg.accept_step(q)
            cuts = 0
            easy = ds * grow if its <= grow_below else ds
            if fixed:  # back to the schedule's step once on a schedule point; between two, a
                # cut step grows back after easy solves (never past the next point): the dress
                # from flat pieces at 29.2 mm cut its step 16-fold at 12 mm and took 40 solves
                # of 0.07 mm to the next point at 9.3 mm
                on_grid = abs(target / grid - round(target / grid)) < 1e-9
                pr.shrink, pr.step = target, grid if on_grid else min(easy, grid)
            else:
                pr.shrink, pr.step = target, easy
            if on_step:
                on_step(rec)
            if on_checkpoint:
                on_checkpoint(pr)
            continue
        # failed: restore the last converged state and halve the step
        st.shrink.value = s
        _undo(q, q_conv, st, rep, solver, (target, its, reason))
        if on_failure:
            on_failure(target, its, reason)
        cuts += 1
        pr.step = (s - target) / 2  # half the way tried (a grown step may have been cut short)
        if cuts > max_cuts:
            nan = ("; the residual was NaN/Inf: a material or load value too large for "
                   "floating point?" if reason == NONFINITE_REASON else "")  # fmt: skip
            raise DressingFailed(
                rep, s,
                f"dressing stopped: Newton failed {cuts} times in a row going from shrink "
                f"{s * 1e3:.3f} mm towards {target * 1e3:.3f} mm (last SNES reason {reason}, "
                f"{reason_name(reason)}, after {its} iterations); the last converged state "
                f"(shrink {s * 1e3:.3f} mm) is kept{nan}",
            )  # fmt: skip
    if pr.stage == "grow" and rest is not None and pr.sewn < 1.0:
        pr.stage = "sew"
    if pr.stage == "sew":  # on the body: contact holds the garment while its seams pull
        # (friction as while the body grew: without friction_while_growing it comes on after
        # the sewing, where the slip is zero, and the garment settles frictionless first)
        _sew(pr, built, solver, max_cuts, on_step, on_failure, on_checkpoint)
        pr.stage = "grow"
    if pr.stage == "grow":
        _friction_on(st, mu, pr.mu)  # the garment sticks where it was put (slip = 0)
        pr.stage = "release"
        pr.c = float(reg.c.value)
        if reg.c0 == 0.0:
            rep.regularisation_effect = 0.0
        else:
            rep.final_regularisation = pr.c
    else:
        _friction_on(st, mu, pr.mu)
    if pr.stage == "release":
        kappa = None
        if augmented_lagrangian is not None and release_multipliers:
            kappa = float(contact.kappa.value)
        with _final_solves(solver):
            _release(
                pr, built, solver, comm, on_step, on_checkpoint, fixed=fixed, ratio=release_ratio,
                tolerances=(path_atol, atol), multipliers=kappa,
            )  # fmt: skip
        solver.set_atol(atol)
        rep.answer_atol = atol
        if augmented_lagrangian is not None:
            _multipliers(pr, built, solver, *augmented_lagrangian, (path_atol, atol))
        rep.completed = True
        pr.stage = "done"
        if on_checkpoint:
            on_checkpoint(pr)
    return rep


def _undo(
    q, q_conv: np.ndarray, st, rep: DressReport, solver: NonlinearSolver, failure: tuple
) -> None:
    """A failed solve: the last converged state back (its parameter already reset by the
    caller), the contact state refreshed, the failure (target, iterations, reason) and its
    residual history recorded."""
    q.x.array[:] = q_conv
    q.x.scatter_forward()
    st.refresh()
    rep.failures.append(failure)
    rep.failure_residuals.append(solver.residual_history().tolist())


def _sew(
    pr: Progress, built, solver: NonlinearSolver, max_cuts: int, on_step, on_failure, on_checkpoint
) -> None:
    """Sew a garment whose rest state is flat pattern pieces: raise the sewing parameter w of
    its rest state (:class:`~fenics_garment.shell.rest.FlatRest`) from the placed mesh's (0)
    to the pattern's (1) in steps of ``pr.sew_step``, on the grown body with the spring on; a
    failed step is tried once more with the other line search (:func:`_retrying`: the dress
    at 39.7 mm failed its first step with full Newton steps at every size down to w = 1/64),
    then undone and halved (as the body's growth). Sewn on the body, the garment
    is held by contact while the flat pieces pull it into the shape they can take (sewn
    around the shrunk body, the free garment's buckling under the pieces' misfit stalled
    Newton: the cotton gilet, 25 mm, 20 cuts in 277 solves)."""
    rest, q = built.model.geometry.rest, built.model.q
    st, rep = built.contact.state, pr.report
    full = 1.0 / built.scene.dressing.sew_steps
    solve = _retrying(solver, q, st)  # a failed step: once more with the other line search
    cuts = 0
    while pr.sewn < 1.0:
        w = min(pr.sewn + pr.sew_step, 1.0)
        if 1.0 - w < 1e-9:
            w = 1.0
        q_conv = q.x.array.copy()
        rest.sewn.value = w
        t0 = time.perf_counter()
        its, reason = solve()
        if reason > 0:
            rec = DressStep(w, its, reason, cuts, time.perf_counter() - t0,
                            float(built.regularisation.c.value), stage="sew")  # fmt: skip
            rec.final_ratios = final_ratios(solver)
            rec.residuals = solver.residual_history().tolist()
            rep.steps.append(rec)
            st.accept_step()
            built.regularisation.accept_step(q)
            pr.sewn, cuts = w, 0
            if its <= 4:  # an easy step: back towards the schedule's step
                pr.sew_step = min(2 * pr.sew_step, full)
            if on_step:
                on_step(rec)
            if on_checkpoint:
                on_checkpoint(pr)
            continue
        rest.sewn.value = pr.sewn
        _undo(q, q_conv, st, rep, solver, (w, its, reason))
        if on_failure:
            on_failure(w, its, reason, "sewn")
        cuts += 1
        pr.sew_step /= 2
        if cuts > max_cuts:
            raise DressingFailed(
                rep, float(st.shrink.value),
                f"dressing stopped: sewing the flat pattern failed {cuts} times in a row going "
                f"from w = {pr.sewn:.4f} towards {w:.4f} (last SNES reason {reason}, "
                f"{reason_name(reason)}, after {its} iterations): the pattern is too far from "
                "the placed garment for its seams to close",
            )  # fmt: skip


def _friction_on(st, mu, value: float) -> None:
    """Friction on (``ContactState.friction_on``), at the scene's coefficient ``value``."""
    st.friction_on.value = 1.0
    if mu is not None:
        mu.value = value


def _multipliers(
    pr: Progress, built, solver: NonlinearSolver, tol: float, max_updates: int,
    tolerances: tuple[float, float],
) -> None:  # fmt: skip
    """Uzawa at s = 0 (:func:`uzawa.augmented_lagrangian`) to the penetration ``tol`` [m], its
    passes at the path tolerance, then the answer at the last multipliers to the solver's
    (``tolerances`` = (path, answer) absolute tolerances [N]).

    A converging run is never thrown away: the loop itself goes on past ``max_updates`` while it
    contracts; if the answer's solve fails (on the dress from flat pieces at 29.2 and 25 mm it
    cycled or diverged at c = 0 after the multipliers had converged) the last converged pass is
    kept, converged to the path tolerance (``DressReport.answer_atol``); if the penetration
    does not reach ``tol`` the last converged state is kept too and ``DressReport.al_message``
    says so — the result check ``multiplier_penetration`` then fails (exit 4), not the run.
    """
    path_atol, atol = tolerances
    contact, st, q, rep = built.contact, built.contact.state, built.model.q, pr.report
    solve = _retrying(solver, q, st)
    released = _snapshot(q, st, contact)
    with _final_solves(solver):
        solver.set_atol(path_atol)
        al = uzawa.augmented_lagrangian(
            st, float(contact.kappa.value), solve, tol=ANSWER_MARGIN * tol,
            max_updates=max_updates, stiffen=contact.kappa, unknown=q,
        )  # fmt: skip
        al.converged = bool(al.penetration) and al.penetration[-1] <= tol
        solver.set_atol(atol)
        rep.al_updates = max(len(al.penetration) - 1, 0)
        rep.answer_atol = path_atol
        if not al.penetration:  # no pass converged: the released state back
            uzawa.put_back(st, q, contact.kappa, *released)
        elif path_atol > atol:  # the answer, at the last multipliers, at the solver's tolerance
            kept = _snapshot(q, st, contact)
            its, reason = solve()
            al.newton_iterations.append(its)
            al.kappa.append(al.kappa[-1])
            if reason > 0:
                rep.answer_atol = atol
                al.penetration.append(uzawa.max_penetration(st))
                al.converged = al.penetration[-1] <= tol
            else:
                uzawa.put_back(st, q, contact.kappa, *kept)
                rep.answer_note = (
                    f"the solve at the final multipliers to the answer's tolerance {atol:.3g} N "
                    f"failed (SNES reason {reason}, {reason_name(reason)}): the answer is the "
                    f"last multiplier pass, converged to {path_atol:.3g} N"
                )
        else:
            rep.answer_atol = atol
    rep.al_penetration = al.penetration
    rep.al_kappa = al.kappa
    rep.al_recoveries = al.recoveries
    rep.al_iterations = al.newton_iterations
    rep.al_converged = al.converged
    pr.kappa = float(contact.kappa.value)
    if not al.converged:
        pen = uzawa.max_penetration(st)
        what = (
            "no multiplier pass converged (the released state is kept)"
            if not al.penetration
            else f"{rep.al_updates} multiplier updates (penalty {al.kappa[-1]:.3g} Pa/m)"
        )
        rep.al_message = (
            f"augmented Lagrangian: penetration {pen:.3g} m not below {tol:.3g} m after {what}; "
            "the last converged state is the answer"
        )
    st.accept_step()


#: The multiplier passes (at the path tolerance) aim at this fraction of the penetration
#: tolerance, so that the answer's solve at the last multipliers, to the tighter tolerance, stays
#: within it: on the scan dress of f-ideal the passes reached 4.572 µm against 4.6 µm and the
#: answer's solve moved it to 4.603 µm (+0.7 %): exit 4 for 0.06 % of the tolerance.
ANSWER_MARGIN = 0.9


def _snapshot(q, st, contact) -> tuple[np.ndarray, np.ndarray, float]:
    """(unknown, multipliers, penalty) now: what :func:`uzawa.put_back` restores."""
    return q.x.array.copy(), st.lam.x.array.copy(), float(contact.kappa.value)


def secant_start(
    q: np.ndarray, shrink_prev: float, q_prev: np.ndarray, shrink: float, target: float
) -> np.ndarray:
    """Newton's start for the grow step ``shrink`` → ``target``: the converged state ``q`` plus
    the change of the last grow step (``q_prev`` at ``shrink_prev`` → ``q``) scaled to the new
    step, q + (s − s_target)/(s_prev − s) (q − q_prev) — the secant (linear extrapolation in
    the shrink) of the path q(s)."""
    return q + (shrink - target) / (shrink_prev - shrink) * (q - q_prev)


def _release(
    pr: Progress,
    built,
    solver: NonlinearSolver,
    comm: MPI.Comm,
    on_step: Callable[[DressStep], None] | None = None,
    on_checkpoint: Callable[[Progress], None] | None = None,
    *,
    fixed: bool = False,
    ratio: float = DressingConfig.release_ratio,
    tolerances: tuple[float, float] | None = None,
    multipliers: float | None = None,
) -> None:
    """Pseudo-transient continuation at s = 0: solve, accept, weaken the spring, until c = 0.

    With ``fixed`` the spring constants are c₀·``ratio``ᵏ down to c₀·:data:`C_ZERO`, then 0 (the
    same on every mesh); a failed solve is retried, every second time with a sub-step half-way
    (in log c) from the last c that converged, after which the schedule goes on from the c that
    failed; a solve that needs no Newton iteration and leaves the spring unstretched (anchored
    at the previous step: nothing moves, so it carries no force) is followed by c = 0 at once,
    and so is one after which the spring's largest traction is negligible
    (:data:`SPRING_NEGLIGIBLE` of the largest contact pressure); when that solve took no Newton
    iteration at the path tolerance, the same c is first solved to the answer's tolerance
    (``Progress.tight``). Otherwise (adaptive):

    The spring pulls towards the previous step, so each solve is an exact equilibrium up to the
    spring traction c |u − u_prev|; while the garment still moves (a loose skirt finding its
    drape under gravity) the spring keeps Newton in its basin, and once it has stopped moving
    the spring does no work. So c follows the spring force still carried, c·max|u − u_prev|:
    after each accepted solve c is multiplied by the ratio of the last two spring forces,
    bounded to [:data:`MIN_RATIO`, :data:`MAX_RATIO`] ("switched evolution relaxation" of
    pseudo-transient continuation: Mulder & Van Leer, J. Comput. Phys. 59 (1985) 232–246;
    Kelley & Keyes, SIAM J. Numer. Anal. 35 (1998) 508–523). Up to :data:`RELEASE_MAX_IT`
    Newton iterations are allowed per solve. A failed solve is undone and
    c raised back half-way (in log c) towards the last c that converged, or to 3c if it was
    that c; c below c₀·:data:`C_ZERO` becomes 0. The answer is the c = 0 solve, and the
    pressure change of that last solve is reported as the regularisation's effect. After
    :data:`MAX_FAILS` failures in a row or :data:`MAX_RELEASE_SOLVES` solves the last converged
    state is kept with its c (``final_regularisation`` > 0) and the effect is that of its last
    solve. ``pr`` carries the schedule's state (c to try, failures in a row, the last spring
    force), so a resumed run takes the same solves.

    ``tolerances``: (path, answer) absolute Newton tolerances of the solves with a spring and of
    the c = 0 solve (None: the solver's as it is). ``multipliers``: the penalty κ with which the
    augmented-Lagrangian multipliers are updated after each release solve with a spring, before
    one that still has a spring (None: not updated here).
    """
    if built.regularisation.c0 == 0.0:
        return
    _release_loop(
        pr, built, solver, comm, on_step, on_checkpoint, fixed, ratio, tolerances, multipliers
    )


@contextmanager
def _final_solves(solver: NonlinearSolver):
    """The settings of the solves at s = 0 (release, multiplier updates): up to
    :data:`RELEASE_MAX_IT` Newton iterations, :data:`RELEASE_LINE_SEARCH`."""
    max_it = solver.set_max_it(max(RELEASE_MAX_IT, solver.problem.solver.getTolerances()[3]))
    line_search = solver.set_line_search(RELEASE_LINE_SEARCH)
    try:
        yield
    finally:
        solver.set_max_it(max_it)
        solver.set_line_search(line_search)


def _retrying(
    solver: NonlinearSolver, q, state, cycles_only: bool = False
) -> Callable[[], tuple[int, int]]:
    """``solver.solve``, and after a failure the same solve once more from the same start with
    the other line search (:data:`RETRY_LINE_SEARCH`), as a failed release solve is retried.
    The dress at 31.8 mm: a multiplier-update pass failed with full Newton steps, then its plain
    Uzawa step too, and the run ended at 5.1 % of h (it had reached 0.96 % with "l2").

    A solve stopped in a cycle (:data:`~fenics_garment.solve.CYCLING_REASON`: the iterates
    alternate between a few contact states near the answer) goes on from its last iterate
    instead. ``cycles_only``: other failures are returned as they are (the grow steps, where a
    halved step is the better remedy for a diverging Newton)."""

    def solve() -> tuple[int, int]:
        start = q.x.array.copy()
        its, reason = solver.solve()
        if reason > 0 or (cycles_only and reason != CYCLING_REASON):
            return its, reason
        if reason != CYCLING_REASON:  # a cycle is near the answer: go on from where it is
            q.x.array[:] = start
            q.x.scatter_forward()
        state.refresh()
        kind = solver.problem.solver.getLineSearch().getType()
        other = RETRY_LINE_SEARCH if kind != RETRY_LINE_SEARCH else RELEASE_LINE_SEARCH
        previous = solver.set_line_search(other)
        try:
            again, reason = solver.solve()
        finally:
            solver.set_line_search(previous)
        return its + again, reason

    return solve


def _release_loop(
    pr: Progress, built, solver, comm, on_step, on_checkpoint, fixed, ratio: float,
    tolerances: tuple[float, float] | None, multipliers: float | None,
) -> None:  # fmt: skip
    model, contact, reg = built.model, built.contact, built.regularisation
    rep = pr.report
    while pr.solves < MAX_RELEASE_SOLVES:
        pr.solves += 1
        c = pr.c
        if tolerances is not None:  # (path, answer): the c = 0 solve is the answer
            solver.set_atol(tolerances[1] if c == 0.0 or pr.tight else tolerances[0])
        before = contact.pressure_values()
        q_conv = model.q.x.array.copy()
        reg.c.value = c
        t0 = time.perf_counter()
        its, reason = solver.solve()
        if reason <= 0:
            rep.failures.append((0.0, its, reason))
            rep.failure_residuals.append(solver.residual_history().tolist())
            model.q.x.array[:] = q_conv
            model.q.x.scatter_forward()
            contact.state.refresh()
            pr.retries += 1
            released_once = any(step.stage == "release" for step in rep.steps)
            if pr.retries > (MAX_FAILS if released_once else MAX_FAILS_UNRELEASED):
                reg.c.value = rep.final_regularisation
                return
            # the other line search next (neither wins everywhere: full steps cycle between
            # stick and slip on the gilet, the l2 search stalled on the loose dress) and, every
            # second failure, a stiffer spring: half-way (in log c) back towards the last c
            # that converged or, if that c itself failed (a skirt still folding), 3c
            kind = solver.problem.solver.getLineSearch().getType()
            solver.set_line_search(
                RETRY_LINE_SEARCH if kind == RELEASE_LINE_SEARCH else RELEASE_LINE_SEARCH
            )
            if pr.retries % 2 == 0:
                last = rep.final_regularisation
                if fixed and pr.c_target < 0:
                    pr.c_target = c  # the schedule goes on from here after the sub-step
                pr.c = C_ZERO * reg.c0 if c == 0 else (
                    (last * c) ** 0.5 if c < 0.999 * last else 3 * c)  # fmt: skip
            continue
        pr.retries = 0
        moved = reg.stretch(model.q)
        rec = DressStep(0.0, its, reason, 0, time.perf_counter() - t0, c, "release")
        rec.final_ratios = final_ratios(solver)
        rec.residuals = solver.residual_history().tolist()
        rep.steps.append(rec)
        rep.final_regularisation = c
        rep.spring_traction = c * moved
        rep.regularisation_effect = _max_pressure_change(contact, before, comm)
        negligible = c * moved <= SPRING_NEGLIGIBLE * _max_pressure(contact, comm)
        contact.state.accept_step()
        reg.accept_step(model.q)
        if on_step:
            on_step(rec)
        if c == 0.0:
            pr.c = 0.0
        elif fixed:
            if pr.c_target >= 0 and c > pr.c_target:  # a sub-step: back to the schedule
                pr.c = pr.c_target
            elif its == 0 and moved == 0.0:  # nothing moved and the spring carries no force
                pr.c = 0.0  # (anchored at the previous step): the rest is a no-op
            elif negligible:  # the spring's largest traction is a negligible load: drop it
                pr.c = 0.0
            else:
                pr.c = c * ratio if c * ratio >= C_ZERO * reg.c0 else 0.0
            if pr.c_target >= 0 and pr.c <= pr.c_target:
                pr.c_target = -1.0
        else:
            # switched evolution relaxation: c follows the spring force it still carries
            spring = c * moved
            ratio = spring / pr.spring if pr.spring > 0 else 1 / 3  # (pr.spring = 0: first)
            pr.c = c * min(max(ratio, MIN_RATIO), MAX_RATIO)
            pr.spring = spring
            if pr.c < C_ZERO * reg.c0:
                pr.c = 0.0
        if pr.tight:  # the spring's last solve, converged to the answer's tolerance: now c = 0
            pr.tight, pr.c = False, 0.0
        elif pr.c == 0.0 < c and its == 0 and tolerances and tolerances[0] > tolerances[1]:
            # c = 0 would follow a solve that took no iteration because its start was already
            # within the path tolerance: the state is an equilibrium to that tolerance only,
            # and the c = 0 Jacobian of a loose skirt is nearly singular. The dress at 22.5 mm:
            # full Newton steps at c = 0 from there diverged (0.0039 → 5.7 → … → 374 N, a
            # failed try of 5 iterations, 8 more with the "l2" search); converged at the same
            # c to the answer's tolerance first (9 iterations), c = 0 took 6 with full steps.
            # Not after a solve that iterated: on the cotton gilet (c = 97 Pa/m, 2 iterations)
            # that cost 5 more and c = 0 took 9 instead of 5.
            pr.tight, pr.c = True, c
        if multipliers is not None and pr.c > 0.0:
            # the multipliers converge with the release; not before the c = 0 solve, whose
            # pressure change is the spring's effect alone (regularisation_effect)
            uzawa.update_multiplier(contact.state, multipliers)
        if on_checkpoint:
            on_checkpoint(pr)
        if c == 0.0:
            return


#: Release schedule of :func:`_release`.
#: With the fixed schedule the spring goes to 0 at once after an accepted solve in which its
#: largest traction c·max|u − u_a| was at most this fraction of the largest contact pressure:
#: the solves that would weaken it further (c₀/4ᵏ down to c₀·C_ZERO) start near Newton's floor
#: and grind there with line-searched steps. Cotton gilet at 35 mm (2 ranks): the old schedule
#: took 14 solves and 87 Newton iterations, its last four (c = 6 … 0.1 Pa/m) starting within
#: 30× the absolute tolerance and ending linearly (ratio 0.59, 0.25); jumping to 0 after
#: c = 98 Pa/m (spring ≈ 7e-4 of the largest pressure) takes 9 solves, 59 iterations, ends
#: quadratically (9.9e-5 → 1.3e-7 N), and gives the same region mean, p95 and sensor p95 to
#: 4 digits and the same contact force to 7 (35.66511 N) as the old schedule and as a jump after
#: c = 6.1 Pa/m; the largest pointwise pressure change of the jump is 0.7 % (reported as
#: ``regularisation_effect``).
SPRING_NEGLIGIBLE = 1e-3
#: A spring not released to 0 whose last weakening changed the pressure by less than this is
#: reported as negligible (else the run warns).
RELEASE_TOLERANCE = 0.01
#: Bounds of the factor on c per accepted release solve (SER: the ratio of the spring forces of
#: the last two solves; 1/3 after the first): at least 20 % weaker each time, at most 10×.
MIN_RATIO, MAX_RATIO = 0.1, 0.8
C_ZERO = 1e-5
MAX_FAILS = 8
#: Failures in a row allowed before any release solve has converged. The cotton gilet on a
#: 16,242-dof mesh (made in another environment; this code makes 16,206 dofs here, which release)
#: failed all 11 attempts at c = 7.7e3 … 2e5 Pa/m (with μ = 0.4 and with μ = 0 alike), 75 s of a
#: 126 s run; attempt 3 is the first raise (3c), which a folding skirt needs.
MAX_FAILS_UNRELEASED = 3
MAX_RELEASE_SOLVES = 40
#: Newton iterations allowed per release solve: the cotton gilet needs up to 18 as stick and slip
#: settle (15 made every solve below c ≈ 2e3 Pa/m fail; 30 released it to c = 0).
RELEASE_MAX_IT = 30
#: Line search of the release solves and the multiplier updates, and the one a failed solve is
#: retried with. Full Newton steps on the current contact (smooth body, P2B-P2B, spring anchored
#: at the start): 48 / 44 / 72 Newton iterations against 59 / 56 / 98 with the "l2" search on
#: the cotton gilet (35 mm), the nylon gilet (35 mm) and the cotton dress (30 mm), the same
#: region mean, p95 and sensor p95 to 4 digits, and 82 / 82 / 115 residual evaluations against
#: 204–317 (the l2 search's plateaus of 0.9 per iteration were damped steps). On the older P1
#: gilet full steps cycled between stick and slip below c ≈ 460 Pa/m and "l2" released it: a
#: failed solve is retried with the other search.
RELEASE_LINE_SEARCH = "basic"
RETRY_LINE_SEARCH = "l2"
