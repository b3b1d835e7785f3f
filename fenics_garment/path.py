"""Path following through limit points: arc-length continuation and displacement control.

Load control (:class:`~fenics_garment.solve.LoadStepper`) raises the load factor λ and solves
F(q, λ) = 0 for q. It fails at a *limit point*, where the tangent stiffness K = ∂F/∂q is singular
and the load–deflection curve turns back (snap-through): beyond it there is no equilibrium near
the current one at a higher λ. Path following makes λ an unknown and adds one scalar equation,
the *constraint* g(q, λ) = 0, that picks the next point of the curve:

* **arc length** (Riks, Crisfield): the increment from the last converged point (q_n, λ_n) has
  a prescribed length, ‖Δq‖²_W + ψ² Δλ² = Δs². With ψ = 0 (Crisfield's *cylindrical* arc
  length, the default) only the displacements count. Limit points in λ (snap-through) and in
  the displacements (snap-back) are passed alike, because neither λ nor any one displacement is
  marched in.
* **displacement control**: one degree of freedom is prescribed, e·q = w (e.g. the deflection
  of the load point), and λ is the load that holds it there. It passes limit points in λ but not
  in w: a snap-back of the controlled dof is jumped (to another branch at the same w).

**Stopping exactly at a target.** ``ArcLength.run(..., stop_at_load=λ*)`` ends exactly at λ = λ*
the first time the path reaches it (rising or, after a limit point, falling), and
``stop_at=(probe, w*)`` where a displacement component (a :class:`DofProbe`, e.g. u_z at a
node) equals w*: the increment that crosses the target is *cut back* onto it — regula falsi
(Illinois) on its arc length from the last point before the crossing, each trial a converged
increment — and the state is then *pinned* on the target by a bordered Newton solve with the
constraint λ = λ* (resp. e·q = w*): the last point has λ = λ* exactly (resp. e·q = w* to
round-off), its residual converged like every point's (where the pin cannot converge, e.g. at
a limit point, the regula falsi goes on to within 1e-10 × max(1, |target|), or SolveFailed).
``reverse=True`` follows the path backwards from the current state (the direction opposite to
the last increment, or decreasing λ on a fresh path): how to come back to a λ* that the path
has passed; :meth:`LoadStepper.run(λ*, from_current=True) <fenics_garment.solve.LoadStepper.run>`
on a model beyond λ* does exactly that.

**Limit points** are detected, the arc refined there, and reported. After each converged
increment K is factorised at the new point (the factorisation the next predictor uses) and the
increment is compared with the tangent at its two ends:

* the λ component of the oriented tangent (the sign of the next predictor's Δλ) changed sign:
  the increment crossed a fold of λ (a maximum or a minimum, i.e. det K changed sign with its
  null vector not orthogonal to the load). Its load is the extremum of the cubic λ(s) through the
  ends and their slopes dλ/ds; the increment is retried at half the arc until that estimate is
  within ``limit_rtol`` of the nearer end;
* the increment turned more than ``max_turn`` degrees from either tangent, or its secant
  |Δλ|/Δs is ``jump_ratio`` times below |dλ/ds| at both ends: it jumped to another shape (e.g.
  over a maximum and a minimum close together, whose ends look alike) and is retried shorter.

At most ``max_refinements`` halvings per increment (and not below the smallest arc); the next arc
is sized to turn by at most ``max_turn``. Each fold is recorded in ``stats.limit_points``
(:class:`LimitPoint`) and announced by a :class:`LimitPointWarning`; a jump that refinement
could not resolve is counted in ``stats.jumps`` and warned about. Bergan's current stiffness
parameter, f·K⁻¹f at the path's start over f·K⁻¹f at the point, is on each :class:`PathPoint`
(``stiffness``; it also changes sign where f·K⁻¹f crosses zero with K regular, so it is reported
rather than used to decide). ``limit_points=False`` turns the detection off.

Both are solved by the *bordering* method: each Newton iteration factorises K once and solves it
twice, K δq_R = −F (the load-controlled Newton correction) and K δq_T = f (the tangent
displacement of the load direction f = −∂F/∂λ), then sets δq = δq_R + δλ δq_T with δλ chosen so
that the iterate satisfies the constraint: a quadratic equation for the arc length (of its two
roots, the one whose increment turns least from the previous iterate's is taken), a linear one
for displacement control. The predictor of an increment is the tangent, Δq = Δλ δq_T; the sign of
Δλ follows the previous increment (Feng's criterion, Δq_prev·W δq_T > 0), which turns λ back after
a limit point. Step sizes adapt to the Newton iteration count (Crisfield's (I_d / I)^½ rule) and
a failed increment is retried from the last converged point at half the step.

The loop is written here, on :class:`~fenics_garment.solve.NonlinearSolver`'s residual, Jacobian
and linear solver, rather than with PETSc's ``SNESNEWTONAL`` (:func:`newtonal_path`, kept for
comparison): ``SNESNEWTONAL`` (PETSc 3.25) takes a fixed arc length from λ = 0 in one
``SNESSolve`` and ends the whole path at the first increment that fails, with no cut-back, no
restart from an intermediate state and no stop other than λ ≥ λ_max; its constraint weighs every
dof alike (millimetres of displacement with radians of rotation). Dirichlet conditions and point
loads fit either (the tangent load is zero on the constrained rows and includes the point
forces).

The model's loads must scale with ``model.load_factor`` (F affine in λ): dead loads, follower
pressures and point loads of a :class:`~fenics_garment.shell.model.ShellModel` do.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from fenics_garment._stack import MPI, PETSc, dolfinx, ufl
from fenics_garment.solve import NonlinearSolver, SolveFailed


@dataclass
class PathPoint:
    """A converged point of the equilibrium path."""

    load_factor: float
    value: float  # the monitored quantity (e.g. a deflection); NaN without a monitor
    iterations: int  # Newton (corrector) iterations of the increment
    step: float  # arc length Δs (or prescribed-displacement increment) of the increment
    cuts: int  # step halvings before it converged
    landed: bool = False  # the point was cut back onto a target (stop_at_load / stop_at)
    #: Bergan's current stiffness parameter f·K⁻¹f at the path's first point over f·K⁻¹f here
    #: (1 at the start, → 0 at a limit point, negative beyond it); NaN where not computed
    stiffness: float = math.nan


@dataclass
class LimitPoint:
    """A limit point of λ (a fold: λ has a local maximum or minimum along the path) that an
    increment crossed: the orientation of the tangent's λ component changed sign."""

    load_factor: float  # λ at the fold, from the cubic (Hermite) through the increment's ends
    kind: str  # "maximum" or "minimum" of λ
    increment: int  # index in the follower's ``history`` of the point after the fold
    arc: float  # arc length (step) of the increment that crossed it
    resolved: bool  # the increment was refined until the estimate met ``limit_rtol``


class LimitPointWarning(UserWarning):
    """Path following crossed a limit point of the load (or jumped over a snap it could not
    resolve by refining the arc)."""


# -- tangent load f = −∂F/∂λ -------------------------------------------------------------------
def tangent_load_form(model) -> ufl.Form | None:
    """The form of f(q) = −∂F/∂λ, the load direction, or None when the model has no form loads.

    A model with a ``tangent_load()`` method gives it itself (a
    :class:`~fenics_garment.shell.model.ShellModel`: dead work, follower pressures and point
    loads; the solver's :class:`~fenics_garment.shell.loads.PointLoad` vector is added by the
    caller). Any other model is differentiated by difference, f = F(q, 0) − F(q, 1), exact for F
    affine in λ (it assembles the internal forces twice).
    """
    if hasattr(model, "tangent_load"):
        return model.tangent_load()
    F = model.residual()
    lam = model.load_factor
    mesh = lam.ufl_domain()
    zero = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(0.0))
    one = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(1.0))
    return ufl.replace(F, {lam: zero}) - ufl.replace(F, {lam: one})


class _TangentLoad:
    """Assembles f(q) (+ the solver's point loads) with zeros on the Dirichlet rows."""

    def __init__(self, solver: NonlinearSolver, jit_options: dict | None = None):
        from fenics_garment.solve import JIT_OPTIONS

        self.solver = solver
        form = tangent_load_form(solver.model)
        jit = JIT_OPTIONS if jit_options is None else jit_options
        self.form = None if form is None else dolfinx.fem.form(form, jit_options=jit)
        loads = getattr(solver.model, "loads", None)
        follows = (
            loads is None or bool(loads["follower"]) or any(f for _, _, f in loads.get("point", ()))
        )
        self.constant = form is None or not follows
        self._cache: PETSc.Vec | None = None

    def assemble(self, x: PETSc.Vec, f: PETSc.Vec) -> None:
        """f ← f(q) at the state ``x`` (copied into the model's unknown first)."""
        if self._cache is not None:  # constant loads: assembled once
            self._cache.copy(f)
            return
        from dolfinx.fem.petsc import assemble_vector, set_bc

        dolfinx.la.petsc._ghost_update(x, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)
        dolfinx.fem.petsc.assign(x, self.solver.model.q)
        with f.localForm() as fl:
            fl.set(0.0)
        if self.form is not None:
            assemble_vector(f, self.form)
        dolfinx.la.petsc._ghost_update(f, PETSc.InsertMode.ADD, PETSc.ScatterMode.REVERSE)
        if self.solver.f_point is not None:
            f.axpy(1.0, self.solver.f_point)
        set_bc(f, self.solver.bcs, alpha=0.0)  # boundary values do not move with λ
        dolfinx.la.petsc._ghost_update(f, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)
        if self.constant:
            self._cache = f.copy()


# -- probes --------------------------------------------------------------------------------------
class DofProbe:
    """One scalar dof of the unknown, e.g. u_z at a mesh node: e·q with e a unit vector.

    Build it with :meth:`at_point`, or from a vector ``e`` of the mixed space directly.
    """

    def __init__(self, model, e: PETSc.Vec):
        self.model = model
        self.e = e
        self.comm = e.getComm().tompi4py()

    @classmethod
    def at_point(
        cls, model, point: Sequence[float], component: int, field: int = 0, tol: float = 1e-8
    ) -> DofProbe:
        """The dof of u (``field`` 0) or θ (1), Cartesian ``component`` 0–2, at a mesh node.

        At a vertex the dof is the point value also for the P2+bubble displacement (the bubble
        vanishes there).
        """
        p = np.asarray(point, dtype=np.float64)
        sub = model.Q.sub(field).sub(component)
        Vc, _ = sub.collapse()
        dofs = dolfinx.fem.locate_dofs_geometrical(
            (sub, Vc), lambda x: np.linalg.norm(x.T - p[None, :], axis=1) < tol
        )[0]
        n_owned = model.Q.dofmap.index_map.size_local * model.Q.dofmap.index_map_bs
        owned = dofs[dofs < n_owned]
        comm = model.Q.mesh.comm
        if comm.allreduce(len(owned), op=MPI.SUM) != 1:
            raise ValueError(f"no single mesh node at {tuple(p)} (field {field}, comp {component})")
        return cls(model, _unit_vector(model.Q, owned))

    def of(self, x: PETSc.Vec) -> float:
        """e·x for a vector of the mixed space."""
        return float(self.e.dot(x))

    def __call__(self) -> float:
        """The dof's current value in ``model.q``."""
        e = self.e.array_r
        local = float(np.dot(e, self.model.q.x.array[: len(e)]))
        return self.comm.allreduce(local, op=MPI.SUM)


def _unit_vector(Q, owned_local: np.ndarray) -> PETSc.Vec:
    e = dolfinx.fem.petsc.create_vector(Q)
    e.zeroEntries()
    with e.localForm() as el:
        el.array[np.asarray(owned_local, dtype=np.int64)] = 1.0
    e.assemble()
    return e


def displacement_weights(model) -> PETSc.Vec:
    """Diagonal weights W of the arc length: 1 on the displacement dofs, 0 on the rotations."""
    w = dolfinx.fem.petsc.create_vector(model.Q)
    w.zeroEntries()
    _, dofs = model.Q.sub(0).collapse()
    n_owned = model.Q.dofmap.index_map.size_local * model.Q.dofmap.index_map_bs
    dofs = np.asarray(dofs)
    with w.localForm() as wl:
        wl.array[dofs[dofs < n_owned]] = 1.0
    w.assemble()
    return w


# -- the bordering loop ----------------------------------------------------------------------------
@dataclass
class _Stats:
    """Work of a path follower, accumulated over its runs."""

    increments: int = 0
    cuts: int = 0
    newton_iterations: int = 0
    factorisations: int = 0
    wall: float = 0.0
    landing_solves: int = 0  # trial increments and pins that cut a crossing back onto a target
    refinements: int = 0  # converged increments rejected and retried shorter at a limit point
    limit_points: list[LimitPoint] = field(default_factory=list)
    jumps: int = 0  # increments accepted although they still looked like a skipped snap


class _PathFollower:
    """Newton with a bordered constraint on (q, λ); subclasses give predictor and corrector."""

    def __init__(
        self,
        solver: NonlinearSolver,
        *,
        monitor: Callable[[], float] | None = None,
        max_it: int = 12,
        target_iterations: int = 4,
        max_growth: float = 2.0,
        max_cuts: int = 8,
        rtol: float = 1e-8,
        on_step: Callable[[PathPoint], None] | None = None,
        limit_points: bool = True,
        limit_rtol: float = 1e-3,
        jump_ratio: float = 2.0,
        max_turn: float = 10.0,
        max_refinements: int = 12,
    ):
        self.solver = solver
        self.model = solver.model
        self.monitor = monitor
        self.max_it, self.target_iterations = max_it, target_iterations
        self.max_growth, self.max_cuts = max_growth, max_cuts
        self.rtol = rtol
        self.on_step = on_step
        self.limit_points, self.limit_rtol = limit_points, limit_rtol
        self.jump_ratio, self.max_refinements = jump_ratio, max_refinements
        self.max_turn = max_turn
        self.history: list[PathPoint] = []
        self.stats = _Stats()
        p = solver.problem
        self.x = p.x
        self.r = p.b
        self.f = p.b.duplicate()
        self.dq_r = p.b.duplicate()
        self.dq_t = p.b.duplicate()
        self.Dq = p.b.duplicate()  # increment from the last converged point
        self.Dq_prev = p.b.duplicate()
        self.Dq_prev.zeroEntries()
        self.x_n = p.b.duplicate()
        self.tangent = _TangentLoad(solver)
        self.ksp = p.solver.getKSP()
        self.ksp.setOperators(p.A, p.P_mat if p.P_mat is not None else p.A)
        self.lam = float(self.model.load_factor.value)
        self.Dlam_prev = 0.0
        self._x_start = p.b.duplicate()  # the point before an increment that crossed a target
        self.w: PETSc.Vec | None = None  # diagonal weights of the path's norm (None: all dofs)
        self._wv = p.b.duplicate()
        self._Dq_prev_old = p.b.duplicate()
        self._t0 = p.b.duplicate()  # the tangent dq_t at the start of the increment
        self._Dlam_prev_old = 0.0
        self._lam_n = self.lam
        self._tangent_ready = False  # K is factorised and dq_t, f are those of the current x
        self._sigma0, self._slope0 = 0.0, math.nan  # λ direction and |dλ/ds| at the start
        self._fKf0: float | None = None  # f·K⁻¹f at the path's first point (stiffness parameter)

    # -- PETSc plumbing
    def _sync_in(self) -> None:
        dolfinx.fem.petsc.assign(self.model.q, self.x)

    def _sync_out(self, x: PETSc.Vec) -> None:
        dolfinx.la.petsc._ghost_update(x, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)
        dolfinx.fem.petsc.assign(x, self.model.q)

    def _residual(self, lam: float) -> float:
        self.model.load_factor.value = lam
        self.solver.problem.solver.computeFunction(self.x, self.r)
        return float(self.r.norm())

    def _wdot(self, a: PETSc.Vec, b: PETSc.Vec) -> float:
        if self.w is None:
            return float(a.dot(b))
        self._wv.pointwiseMult(self.w, b)
        return float(a.dot(self._wv))

    def _factorise_and_tangent(self) -> bool:
        p = self.solver.problem
        p.solver.computeJacobian(self.x, p.A, p.P_mat if p.P_mat is not None else p.A)
        self.stats.factorisations += 1
        self.tangent.assemble(self.x, self.f)
        self._sync_out(self.x)  # the tangent load copied x into q; keep them equal
        self.ksp.solve(self.f, self.dq_t)
        return bool(np.isfinite(self.dq_t.norm()))

    # -- constraint (subclasses)
    def _predict(self, step: float) -> float:  # returns Δλ of the tangent predictor
        raise NotImplementedError

    def _correct(self, step: float, Dlam: float) -> float | None:  # δλ, or None: no solution
        raise NotImplementedError

    def _adjust_step(self, step: float) -> float:  # e.g. land on a target
        return step

    def _slope(self) -> float:  # |dλ/ds| along the tangent dq_t (s: the step's measure)
        raise NotImplementedError

    def _value(self) -> float:
        return float(self.monitor()) if self.monitor is not None else math.nan

    # -- one increment
    def _increment(self, step: float, tol: float) -> int | None:
        """Advance by one increment of size ``step``; iterations, or None (state restored)."""
        x, lam_n = self.x, self.lam
        step = self._step = self._adjust_step(step)
        x.copy(self.x_n)
        self._lam_n = lam_n
        self.model.load_factor.value = lam_n
        ok = True if self._tangent_ready else self._factorise_and_tangent()
        self._tangent_ready = False
        Dlam = self._predict(step) if ok else math.nan
        if not np.isfinite(Dlam):
            return self._restore()
        self._sigma0, self._slope0 = math.copysign(1.0, Dlam), self._slope()
        self.dq_t.copy(self._t0)
        if self._fKf0 is None:
            self._fKf0 = float(self.f.dot(self.dq_t))
        self.Dq.set(0.0)
        self.Dq.axpy(Dlam, self.dq_t)
        x.axpy(1.0, self.Dq)
        self._sync_out(x)
        for it in range(1, self.max_it + 1):
            rnorm = self._residual(lam_n + Dlam)
            if not np.isfinite(rnorm):
                return self._restore()
            if rnorm <= tol:
                self.lam = lam_n + Dlam
                self.Dq_prev.copy(self._Dq_prev_old)  # kept for _reject
                self._Dlam_prev_old = self.Dlam_prev
                self.Dlam_prev = Dlam
                self.Dq.copy(self.Dq_prev)
                self.stats.newton_iterations += it - 1
                return max(it - 1, 1)
            if not self._factorise_and_tangent():
                return self._restore()
            self.ksp.solve(self.r, self.dq_r)
            self.dq_r.scale(-1.0)
            dlam = self._correct(step, Dlam)
            if dlam is None or not np.isfinite(dlam):
                return self._restore()
            self.dq_r.axpy(dlam, self.dq_t)  # δq = δq_R + δλ δq_T
            self.Dq.axpy(1.0, self.dq_r)
            Dlam += dlam
            x.axpy(1.0, self.dq_r)
            self._sync_out(x)
        self.stats.newton_iterations += self.max_it
        return self._restore()

    def _restore(self) -> None:
        self._tangent_ready = False
        self.x_n.copy(self.x)
        self._sync_out(self.x)
        self.model.load_factor.value = self.lam
        return None

    def _reject(self) -> None:
        """Undo the increment just converged: back to the point before it."""
        self._restore()
        self._Dq_prev_old.copy(self.Dq_prev)
        self.Dlam_prev = self._Dlam_prev_old
        self.lam = self._lam_n
        self.model.load_factor.value = self.lam

    def _examine(self) -> _Verdict:
        """After an increment from (x_n, λ_n) converged: factorise K at the new point (kept for
        the next predictor) and compare the path's tangent at the two ends.

        * the λ component of the oriented tangent (the sign of the next predictor's Δλ)
          changed sign: the increment crossed a limit point (fold) of λ; its load is the
          extremum of the cubic (Hermite) λ(s) through the two ends and their slopes dλ/ds;
        * no change of sign, but the secant |Δλ|/Δs is ``jump_ratio`` times below |dλ/ds| at
          both ends: the path between was far softer than at either end, i.e. the increment
          jumped over a snap (a maximum and a minimum of λ) — the corrector converged on the
          far branch.
        """
        verdict = _Verdict()
        ok = self._factorise_and_tangent()
        self._tangent_ready = ok
        if not ok:
            return verdict
        fkf = float(self.f.dot(self.dq_t))
        if self._fKf0 and fkf != 0.0:
            verdict.stiffness = self._fKf0 / fkf
        if not self.limit_points:
            return verdict
        h, lam0, lam1 = self._step, self._lam_n, self.lam
        sigma1 = math.copysign(1.0, self._predict(1.0))
        d0, d1 = self._sigma0 * self._slope0 * h, sigma1 * self._slope() * h  # dλ/dt, t ∈ [0, 1]
        if not (np.isfinite(d0) and np.isfinite(d1)) or h <= 0.0:
            return verdict
        verdict.turn = max(
            self._angle(self.Dq, self._t0, self._sigma0), self._angle(self.Dq, self.dq_t, sigma1)
        )
        if sigma1 != self._sigma0:
            lam_star = _hermite_extremum(lam0, lam1, d0, d1)
            kind = "maximum" if self._sigma0 > 0 else "minimum"
            end = max(lam0, lam1) if kind == "maximum" else min(lam0, lam1)
            scale = max(abs(lam_star), abs(lam0), abs(lam1))
            verdict.fold = (lam_star, kind)
            verdict.refine = abs(lam_star - end) > self.limit_rtol * scale
        elif abs(lam1 - lam0) * self.jump_ratio < min(abs(d0), abs(d1)):
            verdict.jump = True
        if verdict.turn > self.max_turn:
            verdict.jump = verdict.fold is None
            verdict.refine = True
        verdict.refine = verdict.refine or verdict.jump
        return verdict

    def _angle(self, a: PETSc.Vec, b: PETSc.Vec, sign: float) -> float:
        """The angle (degrees) between ``a`` and ``sign`` × ``b`` in the path's norm."""
        ab = math.sqrt(self._wdot(a, a) * self._wdot(b, b))
        if not ab > 0.0:
            return 0.0
        return math.degrees(math.acos(min(max(sign * self._wdot(a, b) / ab, -1.0), 1.0)))

    def _tolerance(self) -> float:
        self.tangent.assemble(self.x, self.f)
        self._sync_out(self.x)
        atol = self.solver.problem.solver.getTolerances()[1]
        return max(atol, self.rtol * float(self.f.norm()))

    def _run(
        self,
        step: float,
        *,
        max_steps: int,
        min_step: float,
        max_step: float,
        stop: Callable[[PathPoint], bool] | None,
        lambda_max: float | None,
        target: _Target | None = None,
    ) -> list[PathPoint]:
        t0 = time.perf_counter()
        self._sync_in()
        self._tangent_ready = False
        self.lam = float(self.model.load_factor.value)
        tol = self._tolerance()
        if self.lam != 0.0 and not self._residual(self.lam) <= tol and self._residual(0.0) <= tol:
            self.lam = 0.0  # an unloaded state (e.g. q = 0 of a new model, whose λ is 1)
        self.model.load_factor.value = self.lam
        cuts = done = refined = 0
        try:
            while done < max_steps:
                f_n, lam_n = (target.gap(self) if target else 0.0), self.lam
                its = self._increment(step, tol)
                verdict = _Verdict()
                if its is not None:
                    verdict = self._examine()
                    if verdict.refine and refined < self.max_refinements and step / 2 >= min_step:
                        self._reject()  # the arc crossed a fold unresolved or jumped: shorter
                        self.stats.refinements += 1
                        refined += 1
                        step /= 2
                        continue
                landed = False
                if its is not None and target is not None:
                    f_c = target.gap(self)
                    if f_c == 0.0 or (f_n != 0.0 and (f_c > 0.0) != (f_n > 0.0)):
                        its = self._land(target, self._step, tol, lam_n, f_n, f_c)
                        landed = True
                if its is None:
                    cuts += 1
                    self.stats.cuts += 1
                    step /= 2
                    if cuts > self.max_cuts or step < min_step:
                        raise SolveFailed(
                            self.lam, self.max_it, 0,
                            f"path following failed after λ = {self.lam:.6g} "
                            f"({len(self.history)} increments; step {2 * step:.3g} cut "
                            f"{cuts} times)",
                        )  # fmt: skip
                    continue
                point = PathPoint(
                    self.lam, self._value(), its, self._step, cuts, landed, verdict.stiffness
                )
                self.history.append(point)
                self.stats.increments += 1
                done += 1
                self._report(verdict, lam_n, refined)
                refined = 0
                if self.on_step:
                    self.on_step(point)
                cuts = 0
                if landed or (stop is not None and stop(point)):
                    break
                if lambda_max is not None and self.lam >= lambda_max:
                    break
                factor = min(
                    max(math.sqrt(self.target_iterations / max(its, 1)), 0.5), self.max_growth
                )
                if self.limit_points and verdict.turn > 0.0:  # the arc that turns by max_turn
                    factor = min(factor, max(self.max_turn / verdict.turn, 0.5))
                step = min(max(step * factor, min_step), max_step)
        finally:
            self.model.load_factor.value = self.lam
            self.stats.wall += time.perf_counter() - t0
        return self.history

    def _report(self, verdict: _Verdict, lam_n: float, refined: int) -> None:
        """Record and announce (on rank 0) a limit point or a jump the accepted increment
        crossed."""
        index = len(self.history) - 1
        announce = self.x.getComm().tompi4py().rank == 0
        where = (
            f"between λ = {lam_n:.6g} and {self.lam:.6g} (increment {index}, arc {self._step:.3g})"
        )
        if verdict.fold is not None:
            lam_star, kind = verdict.fold
            resolved = not verdict.refine
            self.stats.limit_points.append(LimitPoint(lam_star, kind, index, self._step, resolved))
            note = "" if resolved else f", not resolved after {refined} refinements"
            if announce:
                warnings.warn(
                    f"path following crossed a limit point: λ {kind} ≈ {lam_star:.6g} "
                    f"{where}{note}",
                    LimitPointWarning, stacklevel=4,
                )  # fmt: skip
        elif verdict.jump:
            self.stats.jumps += 1
            if announce:
                warnings.warn(
                    f"path following may have jumped over a snap {where}: the increment turns "
                    f"{verdict.turn:.0f}° from the path's tangents or its load changes far less "
                    f"than they predict, still after {refined} refinements of the arc; take a "
                    "smaller first step",
                    LimitPointWarning, stacklevel=4,
                )  # fmt: skip

    # -- landing on a target (stop_at_load, stop_at)
    def _land(
        self, target: _Target, step: float, tol: float, lam_n: float, f_n: float, f_c: float
    ) -> int:
        """The increment of arc ``step`` from (x_n, λ_n) crossed ``target`` (gap f_n before, f_c
        after, opposite signs): cut it back onto the target. Returns the Newton iterations;
        the state is on the target (pinned), or within ``target.tol`` of it, else SolveFailed."""
        self._tangent_ready = False
        self.x_n.copy(self._x_start)
        its_total = 0
        s_lo, g_lo, s_hi, g_hi = 0.0, f_n, step, f_c
        f, side = f_c, 0
        pin_at = math.inf  # |gap| of the last failed pin: retried only 100× closer
        for _ in range(self.MAX_LANDING):
            if f == 0.0:
                return max(its_total, 1)
            if abs(f) < 1e-2 * pin_at:
                its = self._pin(target, tol)
                self.stats.landing_solves += 1
                if its is not None:
                    return max(its_total + its, 1)
                pin_at = abs(f)
            if abs(f) <= target.tol:  # e.g. at a limit point, where no pin converges
                return max(its_total, 1)
            # Illinois: regula falsi whose retained end has its gap halved when kept twice
            s = s_hi - g_hi * (s_hi - s_lo) / (g_hi - g_lo)
            if not (min(s_lo, s_hi) < s < max(s_lo, s_hi)):
                s = 0.5 * (s_lo + s_hi)
            self._x_start.copy(self.x)
            self._sync_out(self.x)
            self.lam = lam_n
            its = self._increment(s, tol)
            self.stats.landing_solves += 1
            if its is None:  # a shorter arc than one that converged: not expected
                raise SolveFailed(
                    self.lam, its_total, 0,
                    f"path following crossed {target.name} = {target.value:.10g} but an "
                    f"increment of arc {s:.3g} back towards it failed (state left at the point "
                    f"before the crossing, λ = {self.lam:.10g})",
                )  # fmt: skip
            its_total += its
            f = target.gap(self)
            if (f > 0.0) == (g_hi > 0.0):
                s_hi, g_hi = s, f
                if side == 1:
                    g_lo *= 0.5
                side = 1
            else:
                s_lo, g_lo = s, f
                if side == -1:
                    g_hi *= 0.5
                side = -1
        raise SolveFailed(
            self.lam, its_total, 0,
            f"path following could not land on {target.name} = {target.value:.10g}: "
            f"{target.name} = {target.value + f:.10g} after {self.MAX_LANDING} trials",
        )  # fmt: skip

    def _pin(self, target: _Target, tol: float) -> int | None:
        """Bordered Newton from the current state with the target as the constraint (λ = λ*, or
        e·q = w*); iterations, or None with the state restored."""
        self._tangent_ready = False
        x = self.x
        x.copy(self.x_n)
        lam0 = self.lam
        lam = target.value if target.kind == "load" else self.lam
        for it in range(self.PIN_MAX_IT + 1):
            rnorm = self._residual(lam)
            if not np.isfinite(rnorm):
                break
            on_target = target.kind == "load" or abs(target.gap_of(self, x)) <= 1e-14 * max(
                1.0, abs(target.value))  # fmt: skip
            if it >= 1 and rnorm <= tol and on_target:  # one correction at least: to round-off
                self.lam = lam
                self.stats.newton_iterations += it
                return max(it, 1)
            if it == self.PIN_MAX_IT or not self._factorise_and_tangent():
                break
            self.ksp.solve(self.r, self.dq_r)
            self.dq_r.scale(-1.0)
            dlam = 0.0
            if target.kind == "value":
                et = target.probe.of(self.dq_t)
                if et == 0.0:
                    break
                dlam = (target.value - target.probe.of(x) - target.probe.of(self.dq_r)) / et
                self.dq_r.axpy(dlam, self.dq_t)
            x.axpy(1.0, self.dq_r)
            lam += dlam
            self._sync_out(x)
        self.stats.newton_iterations += self.PIN_MAX_IT
        self.x_n.copy(x)
        self._sync_out(x)
        self.lam = lam0
        self.model.load_factor.value = lam0
        return None

    #: regula falsi trials (and pins) to land on a target; Newton iterations of a pin
    MAX_LANDING = 40
    PIN_MAX_IT = 8


@dataclass
class _Verdict:
    """What :meth:`_PathFollower._examine` found on a converged increment."""

    stiffness: float = math.nan
    fold: tuple[float, str] | None = None  # (λ at the fold, "maximum" / "minimum")
    jump: bool = False
    refine: bool = False
    turn: float = 0.0  # degrees between the increment and the tangents at its ends


def _hermite_extremum(lam0: float, lam1: float, d0: float, d1: float) -> float:
    """The extremum of the cubic λ(t), t ∈ [0, 1], with λ(0) = lam0, λ(1) = lam1, λ'(0) = d0 and
    λ'(1) = d1 of opposite signs (one root of λ' in (0, 1)); an end value if none is found."""
    delta = lam1 - lam0
    a, b, c = -6.0 * delta + 3.0 * (d0 + d1), 6.0 * delta - 4.0 * d0 - 2.0 * d1, d0
    roots = np.roots([a, b, c]) if a != 0.0 else ([-c / b] if b != 0.0 else [])
    ts = [float(r.real) for r in np.atleast_1d(roots) if abs(r.imag) < 1e-12 and 0 <= r.real <= 1]
    if not ts:
        return max(lam0, lam1) if d0 > 0 else min(lam0, lam1)
    t = ts[0]
    h00, h10, h01, h11 = (2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t, -2 * t**3 + 3 * t**2,
                          t**3 - t**2)  # fmt: skip
    return h00 * lam0 + h10 * d0 + h01 * lam1 + h11 * d1


@dataclass
class _Target:
    """Where path following must stop exactly: λ = value ("load") or probe = value ("value")."""

    kind: str
    value: float
    probe: DofProbe | None = None

    @property
    def name(self) -> str:
        return "λ" if self.kind == "load" else "the probed dof"

    @property
    def tol(self) -> float:
        return 1e-10 * max(1.0, abs(self.value))

    def gap(self, follower: _PathFollower) -> float:
        return self.gap_of(follower, follower.x)

    def gap_of(self, follower: _PathFollower, x: PETSc.Vec) -> float:
        if self.kind == "load":
            return follower.lam - self.value
        return self.probe.of(x) - self.value


class ArcLength(_PathFollower):
    """Crisfield's arc-length continuation (cylindrical for ψ = 0) on a NonlinearSolver.

    The constraint is ‖Δq‖²_W + ψ² Δλ² = Δs² with W = ``weights`` (diagonal, as a vector):
    ``"displacement"`` (1 on u, 0 on θ, so that Δs is a length; the default for a shell model),
    ``"all"`` (every dof; the default for other models) or a PETSc vector.
    ``run(initial_load_step)`` sizes the first arc so that its tangent predictor is the load
    step Δλ₀.

    Keywords of every path follower: ``monitor`` (a scalar recorded on each point), ``max_it``,
    ``target_iterations``, ``max_growth``, ``max_cuts``, ``rtol`` (residual tolerance relative to
    the load vector), ``on_step``; limit points (module doc): ``limit_points`` (True),
    ``limit_rtol`` (1e-3), ``max_turn`` (10°), ``jump_ratio`` (2), ``max_refinements`` (12).
    """

    def __init__(
        self,
        solver: NonlinearSolver,
        *,
        weights: str | PETSc.Vec | None = None,
        psi: float = 0.0,
        **kw,
    ):
        super().__init__(solver, **kw)
        if weights is None:  # a shell (u, θ): the displacements; anything else: every dof
            weights = "displacement" if hasattr(solver.model, "kinematics") else "all"
        if isinstance(weights, str):
            if weights == "displacement":
                weights = displacement_weights(solver.model)
            elif weights == "all":
                weights = None
            else:
                raise ValueError(f"weights must be 'displacement', 'all' or a Vec, got {weights!r}")
        self.w = weights
        self.psi2 = psi * psi
        self._fresh_sign = 1.0
        self._a = solver.problem.b.duplicate()

    def _slope(self) -> float:
        return 1.0 / math.sqrt(self._wdot(self.dq_t, self.dq_t) + self.psi2)

    def _predict(self, step: float) -> float:
        tt = self._wdot(self.dq_t, self.dq_t)
        dlam = step / math.sqrt(tt + self.psi2)
        if self.history or self.Dlam_prev != 0.0:
            sign = self._wdot(self.Dq_prev, self.dq_t) + self.psi2 * self.Dlam_prev
            dlam = math.copysign(dlam, sign) if sign != 0 else dlam
        else:  # a fresh path: up in λ, or down with run(..., reverse=True)
            dlam *= self._fresh_sign
        return dlam

    def _correct(self, step: float, Dlam: float) -> float | None:
        a = self._a  # Δq + δq_R
        self.Dq.copy(a)
        a.axpy(1.0, self.dq_r)
        t = self.dq_t
        A = self._wdot(t, t) + self.psi2
        B = 2.0 * (self._wdot(t, a) + self.psi2 * Dlam)
        C = self._wdot(a, a) + self.psi2 * Dlam * Dlam - step * step
        disc = B * B - 4.0 * A * C
        if disc < 0:
            return None  # no real root: the caller cuts the step
        sq = math.sqrt(disc)
        q = -0.5 * (B + math.copysign(sq, B))
        roots = [q / A, C / q] if q != 0 else [-B / (2 * A)]
        # the root whose new increment turns least from the current one (Crisfield 1981)
        aDq = self._wdot(a, self.Dq)
        tDq = self._wdot(t, self.Dq)
        return max(roots, key=lambda r: aDq + r * tDq + self.psi2 * (Dlam + r) * Dlam)

    def arc_for_load_step(self, load_step: float) -> float:
        """The arc length Δs of a tangent step Δλ = ``load_step`` from the current state."""
        self._sync_in()
        self.lam = float(self.model.load_factor.value)
        if not self._factorise_and_tangent():
            raise SolveFailed(self.lam, 0, 0, "the tangent stiffness is singular or not finite")
        return abs(load_step) * math.sqrt(self._wdot(self.dq_t, self.dq_t) + self.psi2)

    def run(
        self,
        initial_load_step: float,
        *,
        max_steps: int = 200,
        max_step_ratio: float = 4.0,
        min_step_ratio: float = 1e-4,
        stop: Callable[[PathPoint], bool] | None = None,
        lambda_max: float | None = None,
        stop_at_load: float | None = None,
        stop_at: tuple[DofProbe, float] | None = None,
        reverse: bool = False,
    ) -> list[PathPoint]:
        """Follow the path from the current state; stop after ``max_steps`` increments, when
        ``stop(point)`` is true or when λ ≥ ``lambda_max`` (at the first point beyond it).

        ``stop_at_load = λ*``: stop *exactly* at λ = λ* the first time the path reaches it
        from the current state, rising or falling (the last point has ``landed = True`` and
        λ = λ* to round-off; module doc). ``stop_at = (probe, w*)``: likewise where the dof of
        the :class:`DofProbe` equals w* (e.g. ``DofProbe.at_point(model, p, 2)``: u_z at p).
        ``reverse``: go back along the path (opposite to the last increment; on a fresh path,
        towards decreasing λ), e.g. to come back to a λ* the path has passed.

        The arc length of the first increment is that of a tangent step Δλ₀ =
        ``|initial_load_step|``; later ones adapt within [``min_step_ratio``,
        ``max_step_ratio``] × that, and are refined at limit points (module doc). A state out
        of equilibrium at the model's λ but in equilibrium at λ = 0 (q = 0 of a new
        :class:`~fenics_garment.shell.model.ShellModel`, whose λ is 1) starts at λ = 0."""
        if stop_at_load is not None and stop_at is not None:
            raise ValueError("give stop_at_load or stop_at, not both")
        target = None
        if stop_at_load is not None:
            target = _Target("load", float(stop_at_load))
        elif stop_at is not None:
            probe, value = stop_at
            if not isinstance(probe, DofProbe):
                raise TypeError(f"stop_at needs (DofProbe, value), got {type(probe).__name__}")
            target = _Target("value", float(value), probe)
        ds = self.ds0 = self.arc_for_load_step(initial_load_step)
        if reverse:
            self.Dq_prev.scale(-1.0)
            self.Dlam_prev = -self.Dlam_prev
        self._fresh_sign = -1.0 if reverse else 1.0
        return self._run(
            ds, max_steps=max_steps, min_step=min_step_ratio * ds, max_step=max_step_ratio * ds,
            stop=stop, lambda_max=lambda_max, target=target,
        )  # fmt: skip


class DisplacementControl(_PathFollower):
    """Prescribe one dof (a :class:`DofProbe`), e·q = w, and solve for the load factor.

    ``run(increment, target)`` moves w from its current value to ``target`` in steps that start
    at ``increment`` and adapt to the Newton iterations like the arc length, landing on the
    target. λ may rise and fall (snap-through), but a snap-back of the controlled dof itself
    cannot be followed, and it is not detected either: beyond the turn Newton lands on another
    branch at the same w (the 6.35 mm hinged roof: λ P_ref jumps from +382 N to −376 N between
    w_C = 16.2 and 17.2 mm, where the path turns back at 17.0 mm). Use :class:`ArcLength` there.
    """

    def __init__(self, solver: NonlinearSolver, probe: DofProbe, **kw):
        kw.setdefault("monitor", probe)
        super().__init__(solver, **kw)
        self.probe = probe
        self.sign, self.target = 1.0, 0.0
        self._w_n = 0.0

    def _adjust_step(self, step: float) -> float:
        self._w_n = self.probe.of(self.x)
        remaining = abs(self.target - self._w_n)
        return remaining if step > remaining or remaining - step < 0.3 * step else step

    def _predict(self, step: float) -> float:
        et = self.probe.of(self.dq_t)
        return self.sign * step / et if et != 0 else math.nan

    def _slope(self) -> float:
        et = abs(self.probe.of(self.dq_t))
        return 1.0 / et if et != 0 else math.inf

    def _correct(self, step: float, Dlam: float) -> float | None:
        et = self.probe.of(self.dq_t)
        if et == 0:
            return None
        # e·(x + δq_R + δλ δq_T) = w_n ± step
        w = self._w_n + self.sign * step
        return (w - self.probe.of(self.x) - self.probe.of(self.dq_r)) / et

    def run(
        self,
        increment: float,
        target: float,
        *,
        max_steps: int = 200,
        max_increment: float | None = None,
        min_increment: float | None = None,
    ) -> list[PathPoint]:
        """Move the controlled dof from its current value to ``target``."""
        self._sync_in()
        self.target = target
        self.sign = math.copysign(1.0, target - self.probe())
        step = abs(increment)
        max_inc = abs(max_increment) if max_increment is not None else 8 * step
        min_inc = abs(min_increment) if min_increment is not None else 1e-4 * step
        tol = 1e-12 * max(abs(target), 1.0)

        def reached(point: PathPoint) -> bool:
            return abs(point.value - target) <= tol

        return self._run(
            step, max_steps=max_steps, min_step=min_inc, max_step=max_inc, stop=reached,
            lambda_max=None,
        )  # fmt: skip


# -- PETSc's SNESNEWTONAL, for comparison ------------------------------------------------------
@dataclass
class NewtonALResult:
    history: list[PathPoint] = field(default_factory=list)
    reason: int = 0
    iterations: int = 0
    wall: float = 0.0


def newtonal_path(
    solver: NonlinearSolver,
    step_size: float,
    *,
    psisq: float = 0.0,
    lambda_max: float = 1.0,
    lambda_min: float = -1.0,
    max_steps: int = 200,
    max_it: int = 25,
    correction: str = "exact",
    monitor: Callable[[], float] | None = None,
    prefix: str = "garment_newtonal_",
) -> NewtonALResult:
    """The whole path from λ = 0 and q = 0 (``model.q`` is reset) to ``lambda_max`` with PETSc's
    ``SNESNEWTONAL``.

    Fixed arc length ``step_size`` (every dof weighted alike, plus ``psisq`` Δλ²), the
    residual and Jacobian of ``solver`` (its callbacks, with λ read from the SNES), the tangent
    load of :func:`tangent_load_form` plus the point loads. One failed increment ends the path
    (``reason`` < 0). Needs petsc4py ≥ 3.22 (``SNES.Type.NEWTONAL``).
    """
    S = PETSc.SNES
    for name in ("setNewtonALFunction", "getNewtonALLoadParameter", "setNewtonALCorrectionType"):
        if not hasattr(S, name):
            raise RuntimeError(f"petsc4py has no SNES.{name}: SNESNEWTONAL needs PETSc >= 3.22")
    if not hasattr(S.Type, "NEWTONAL"):
        raise RuntimeError("this PETSc has no SNESNEWTONAL")
    t0 = time.perf_counter()
    model, p = solver.model, solver.problem
    base = p.solver
    b_vec, (residual_cb, _, _) = base.getFunction()
    _, _, (jacobian_cb, _, _) = base.getJacobian()
    tangent = _TangentLoad(solver)
    model.q.x.array[:] = 0.0
    model.q.x.scatter_forward()
    snes = PETSc.SNES().create(p.x.getComm())
    snes.setType(PETSc.SNES.Type.NEWTONAL)

    def residual(snes_, x, b):
        model.load_factor.value = snes_.getNewtonALLoadParameter()
        residual_cb(snes_, x, b)

    def jacobian(snes_, x, J, P):
        model.load_factor.value = snes_.getNewtonALLoadParameter()
        jacobian_cb(snes_, x, J, P)

    def tangent_load(snes_, x, f):
        tangent.assemble(x, f)

    result = NewtonALResult()
    values: list[tuple[float, float, int]] = []
    last_it = [0]

    def record(snes_, its, fnorm):
        if snes_.getConvergedReason() > 0:
            dolfinx.fem.petsc.assign(snes_.getSolution(), model.q)
            value = float(monitor()) if monitor is not None else math.nan
            values.append((snes_.getNewtonALLoadParameter(), value, its - last_it[0]))
            last_it[0] = its

    snes.setFunction(residual, b_vec.duplicate())
    snes.setJacobian(jacobian, p.A, p.P_mat if p.P_mat is not None else p.A)
    snes.setNewtonALFunction(tangent_load)
    snes.setMonitor(record)
    ctype = {"exact": S.NewtonALCorrectionType.EXACT, "normal": S.NewtonALCorrectionType.NORMAL}
    snes.setNewtonALCorrectionType(ctype[correction])
    rtol, atol, stol, _ = base.getTolerances()
    snes.setTolerances(rtol=rtol, atol=atol, stol=stol, max_it=max_it)
    ksp, base_ksp = snes.getKSP(), base.getKSP()
    ksp.setType(base_ksp.getType())
    ksp.getPC().setType(base_ksp.getPC().getType())
    if base_ksp.getPC().getType() in ("lu", "cholesky"):
        ksp.getPC().setFactorSolverType(base_ksp.getPC().getFactorSolverType())
    opts = PETSc.Options()
    settings = {
        "snes_newtonal_step_size": step_size,
        "snes_newtonal_psisq": psisq,
        "snes_newtonal_lambda_max": lambda_max,
        "snes_newtonal_lambda_min": lambda_min,
        "snes_newtonal_max_continuation_steps": max_steps,
    }
    snes.setOptionsPrefix(prefix)
    for k, v in settings.items():
        opts[f"{prefix}{k}"] = v
    try:
        snes.setFromOptions()
    finally:
        for k in settings:
            del opts[f"{prefix}{k}"]
    x = p.x.duplicate()
    x.zeroEntries()
    snes.solve(None, x)
    dolfinx.fem.petsc.assign(x, model.q)
    model.load_factor.value = snes.getNewtonALLoadParameter()
    result.reason = int(snes.getConvergedReason())
    result.iterations = int(snes.getIterationNumber())
    result.history = [PathPoint(lam, val, its, step_size, 0) for lam, val, its in values]
    result.wall = time.perf_counter() - t0
    snes.destroy()
    x.destroy()
    return result
