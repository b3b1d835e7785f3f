"""Newton (PETSc SNES) and load stepping: the only module that drives PETSc solvers.

``NonlinearSolver`` wraps ``dolfinx.fem.petsc.NonlinearProblem`` and adds what a garment run needs:

* *pre-residual hooks* (e.g. refresh the contact gap from the current iterate) called with the
  iterate already copied into the unknown Function,
* dead point loads added to the residual vector, scaled by the load factor λ,
* a NaN/Inf check on every residual (SNES is told the point is outside the domain, so the line
  search or the load stepper backs off instead of propagating NaNs),
* MUMPS LU by default, set on the KSP/PC objects directly (NonlinearProblem drops the options it
  does not consume at construction), with the symbolic factorisation reused between iterations.

``LoadStepper`` increases λ from 0 to 1 with a secant predictor, adaptive step size and cut-back on
divergence, and raises :class:`SolveFailed` when it runs out of retries.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from fenics_garment._stack import PETSc, dolfinx

DEFAULT_SNES_OPTIONS: dict[str, object] = {
    "snes_type": "newtonls",
    "snes_linesearch_type": "basic",
    "snes_rtol": 1e-9,
    "snes_atol": 1e-12,
    # Newton converges quadratically, so a relative step below 1e-10 means the residual is at its
    # round-off floor; the absolute tolerance is also raised to 10× the measured floor (below).
    "snes_stol": 1e-10,
    "snes_max_it": 25,
    # A residual that grows in the first iterations (contact switching, a large load step) is not
    # a failure by itself; divergence is judged by max_it, NaN checks and the load stepper.
    "snes_divergence_tolerance": -1,
    "ksp_type": "preonly",
    "pc_type": "lu",
    "pc_factor_mat_solver_type": "mumps",
}


class SolveFailed(RuntimeError):
    """A load step could not be converged even after the allowed step cuts."""

    def __init__(self, load_factor: float, iterations: int, reason: int, message: str = ""):
        self.load_factor, self.iterations, self.reason = load_factor, iterations, reason
        super().__init__(
            message
            or f"Newton failed at load factor λ={load_factor:.6g} after {iterations} iterations "
            f"(SNES reason {reason}: {_REASONS.get(reason, 'unknown')})"
        )


_REASONS = {
    int(getattr(PETSc.SNES.ConvergedReason, k)): k.lower().replace("_", " ")
    for k in dir(PETSc.SNES.ConvergedReason)
    if k.isupper()
}


@dataclass
class Timings:
    """Wall-clock split, accumulated over a run."""

    jit: float = 0.0
    residual: float = 0.0
    jacobian: float = 0.0
    hooks: float = 0.0
    solve: float = 0.0
    newton_iterations: int = 0
    linear_iterations: int = 0
    residual_evaluations: int = 0
    steps: int = 0
    cuts: int = 0

    def as_dict(self) -> dict:
        return dict(self.__dict__)


class NonlinearSolver:
    """SNES on the residual F(q) = 0 of ``model``, with hooks, point loads and timing."""

    def __init__(
        self,
        model,
        bcs: list,
        *,
        point_loads: list | None = None,
        pre_residual: list[Callable[[], None]] | None = None,
        petsc_options: dict | None = None,
        prefix: str = "garment_",
    ):
        from fenics_garment.shell.loads import point_load_vector

        self.model = model
        self.bcs = bcs
        self.hooks = list(pre_residual or [])
        self.timings = Timings()
        opts = dict(DEFAULT_SNES_OPTIONS)
        if petsc_options:
            opts.update(petsc_options)
        F = model.residual()
        J = model.jacobian(F)
        t0 = time.perf_counter()
        self.problem = dolfinx.fem.petsc.NonlinearProblem(
            F, model.q, bcs=bcs, J=J, petsc_options_prefix=prefix,
            petsc_options={k: v for k, v in opts.items() if not k.startswith(("ksp_", "pc_"))},
        )  # fmt: skip
        self.timings.jit += time.perf_counter() - t0
        snes = self.problem.solver
        ksp = snes.getKSP()
        ksp.setType(opts["ksp_type"])
        pc = ksp.getPC()
        pc.setType(opts["pc_type"])
        if opts["pc_type"] == "lu":
            pc.setFactorSolverType(opts["pc_factor_mat_solver_type"])
        self._user_ksp_options(ksp, opts, prefix)
        self.f_point = point_load_vector(model, point_loads) if point_loads else None
        if self.f_point is not None:
            self._zero_bc_rows(self.f_point)
        self._install_callbacks()
        self.residual_floor = self._measure_floor(opts)

    def _measure_floor(self, opts: dict) -> float:
        """The round-off floor of the internal forces at the reference state (λ = 0, q = 0).

        Strains are differences of O(1) metric terms, so the residual has a noise of about
        ε_machine × stiffness that Newton cannot go below; an absolute tolerance under it stalls.
        The absolute tolerance is raised to 10× this floor. Extra residual terms (contact) and the
        pre-residual hooks are switched off meanwhile: a garment that starts inside the body has a
        contact force at q = 0 that is not noise. Models without ``load_factor`` and
        ``extra_switch`` Constants are not measured (floor 0).
        """
        model, snes = self.model, self.problem.solver
        switches = [getattr(model, name, None) for name in ("load_factor", "extra_switch")]
        if any(c is None for c in switches):
            return 0.0
        saved = [float(c.value) for c in switches]
        q_saved = model.q.x.array.copy()
        hooks, self.hooks = self.hooks, []
        try:
            model.q.x.array[:] = 0.0
            for c in switches:
                c.value = 0.0
            x = self.problem.x
            dolfinx.fem.petsc.assign(model.q, x)
            b = self.problem.b.duplicate()
            snes.computeFunction(x, b)
            floor = b.norm()
            b.destroy()
        finally:
            self.hooks = hooks
            model.q.x.array[:] = q_saved
            for c, v in zip(switches, saved, strict=True):
                c.value = v
        atol = snes.getTolerances()[1]
        snes.setTolerances(atol=max(atol, 10.0 * floor))
        return floor

    # -- PETSc plumbing ------------------------------------------------------------------------
    def _user_ksp_options(self, ksp, opts: dict, prefix: str) -> None:
        extra = {k: v for k, v in opts.items() if k.startswith(("ksp_", "pc_", "mat_"))}
        if not extra:
            return
        o = PETSc.Options()
        for k, v in extra.items():
            o[f"{prefix}{k}"] = v
        ksp.setFromOptions()
        for k in extra:
            del o[f"{prefix}{k}"]

    def _zero_bc_rows(self, vec) -> None:
        for bc in self.bcs:
            dofs, n_owned = bc._cpp_object.dof_indices()
            with vec.localForm() as vl:
                vl.array[dofs[:n_owned]] = 0.0

    def _install_callbacks(self) -> None:
        from dolfinx.fem.petsc import assemble_jacobian, assemble_residual

        snes = self.problem.solver
        p = self.problem
        rctx = {"u": p.u, "residual": p.F, "jacobian": p.J, "bcs": self.bcs}
        jctx = {"u": p.u, "jacobian": p.J, "preconditioner": p.preconditioner, "bcs": self.bcs}
        model = self.model
        timings = self.timings

        def residual(snes_, x, b):
            t0 = time.perf_counter()
            if self.hooks:
                dolfinx.la.petsc._ghost_update(
                    x, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD
                )
                dolfinx.fem.petsc.assign(x, model.q)
                th = time.perf_counter()
                for hook in self.hooks:
                    hook()
                timings.hooks += time.perf_counter() - th
            assemble_residual(snes_, x, b, **rctx)
            if self.f_point is not None:
                b.axpy(-float(model.load_factor.value), self.f_point)
            timings.residual_evaluations += 1
            timings.residual += time.perf_counter() - t0
            norm = b.norm()
            if not np.isfinite(norm):
                snes_.setFunctionDomainError()

        def jacobian(snes_, x, J, P):
            t0 = time.perf_counter()
            assemble_jacobian(snes_, x, J, P, **jctx)
            timings.jacobian += time.perf_counter() - t0

        snes.setFunction(residual, p.b)
        snes.setJacobian(jacobian, p.A, p.P_mat)

    # -- solve -------------------------------------------------------------------------------
    def solve(self) -> tuple[int, int]:
        """One Newton solve from the current ``model.q``; returns (iterations, reason)."""
        snes = self.problem.solver
        snes.setConvergenceHistory(length=snes.getTolerances()[3] + 1, reset=True)
        t0 = time.perf_counter()
        self.problem.solve()
        dt = time.perf_counter() - t0
        its, reason = snes.getIterationNumber(), snes.getConvergedReason()
        self.timings.newton_iterations += its
        self.timings.linear_iterations += snes.getLinearSolveIterations()
        self.timings.solve += dt
        return its, reason

    def residual_history(self) -> np.ndarray:
        """Residual norms ‖F(q_k)‖ of the last :meth:`solve`, k = 0 … iterations."""
        return np.asarray(self.problem.solver.getConvergenceHistory()[0])


def convergence_rates(residuals) -> dict[str, list[float]]:
    """Newton rate diagnostics of a residual history r_0, r_1, …

    ``ratio``: r_{k+1}/r_k (→ 0 for superlinear convergence); ``quadratic``: r_{k+1}/r_k²
    (bounded when quadratic); ``order``: log(r_{k+1}/r_k)/log(r_k/r_{k−1}) (≈ 2 when quadratic).
    """
    r = np.asarray(residuals, dtype=float)
    ok = r[:-1] > 0
    ratio = np.where(ok, r[1:] / np.where(ok, r[:-1], 1.0), np.nan)
    quad = np.where(ok, r[1:] / np.where(ok, r[:-1], 1.0) ** 2, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        lr = np.log(ratio)
        order = lr[1:] / lr[:-1]
    return {"ratio": ratio.tolist(), "quadratic": quad.tolist(), "order": order.tolist()}


@dataclass
class StepRecord:
    load_factor: float
    iterations: int
    reason: int
    cuts: int


@dataclass
class LoadStepper:
    """Drive λ from 0 to 1 in adaptive steps with a secant predictor.

    A step whose Newton solve fails is restored and halved (up to ``max_cuts`` times in a row);
    a step that converges in few iterations lets the next one grow.
    """

    solver: NonlinearSolver
    steps: int = 10
    min_step: float = 1e-4
    max_cuts: int = 6
    grow_below: int = 4
    predictor: bool = True
    on_step: Callable[[StepRecord], None] | None = None
    history: list[StepRecord] = field(default_factory=list)

    def run(self, target: float = 1.0) -> list[StepRecord]:
        model = self.solver.model
        q = model.q
        lam = float(model.load_factor.value) if self.history else 0.0
        dlam = (target - lam) / self.steps
        q_prev = q.x.array.copy()
        lam_prev = lam
        cuts_in_row = 0
        while lam < target - 1e-14:
            step = min(dlam, target - lam)
            q_conv = q.x.array.copy()
            if self.predictor and self.history and lam > lam_prev:
                q.x.array[:] = q_conv + (step / (lam - lam_prev)) * (q_conv - q_prev)
            model.load_factor.value = lam + step
            its, reason = self.solver.solve()
            if reason > 0:
                q_prev, lam_prev = q_conv, lam
                lam += step
                rec = StepRecord(lam, its, reason, cuts_in_row)
                self.history.append(rec)
                self.solver.timings.steps += 1
                if self.on_step:
                    self.on_step(rec)
                cuts_in_row = 0
                if its <= self.grow_below:
                    dlam = step * 1.5
                else:
                    dlam = step
            else:
                q.x.array[:] = q_conv
                q.x.scatter_forward()
                model.load_factor.value = lam
                cuts_in_row += 1
                self.solver.timings.cuts += 1
                dlam = step / 2
                if cuts_in_row > self.max_cuts or dlam < self.min_step * target:
                    raise SolveFailed(lam + step, its, reason)
        return self.history
