"""Newton (PETSc SNES) and load stepping: the only module that drives PETSc solvers.

``NonlinearSolver`` wraps ``dolfinx.fem.petsc.NonlinearProblem`` and adds what a garment run needs:

* *pre-residual hooks* (e.g. refresh the contact gap from the current iterate) called with the
  iterate already copied into the unknown Function, and *pre-Jacobian hooks* likewise (e.g. the
  contact's Hessian, needed by the Jacobian only: it is skipped at the residual evaluations that
  no Jacobian follows — line-search trials, the converged iterate),
* dead point loads added to the residual vector, scaled by the load factor λ,
* a stop on a *cycling* Newton iteration (:func:`newton_cycle`: the residual norms repeat with
  a period of 1–10 iterations), with :data:`CYCLING_REASON`, so the caller's retry (another line
  search, a stiffer spring, a smaller step) starts at once instead of after ``max_it``
  iterations; ``timings.cycles`` counts them,
* a NaN/Inf check on every residual: PETSc's own norm check then ends the Newton solve with
  ``DIVERGED_FUNCTION_NANORINF`` (petsc4py 3.25 has no ``setFunctionDomainError``), so the load
  stepper or the dressing cuts the step instead of propagating NaNs; ``timings.nonfinite``
  counts them,
* a *progress* callback (``progress(its, fnorm, seconds)``, after every Newton iteration, with
  the wall time of that iteration): a large problem reports each iteration instead of going
  silent for minutes (``scene.run`` prints those that take long),
* the options checked against what this design supports (:mod:`fenics_garment.petsc_options`)
  before PETSc sees them,
* an iterative solver on request (``pc_type = "gamg"``, :data:`ITERATIVE_OPTIONS`): the shell's
  rigid-body modes are set as the Jacobian's near-nullspace, and without a ``ksp_type`` the
  Krylov method is CG for a symmetric Jacobian, GMRES otherwise,
* a direct solver by default, set on the KSP/PC objects directly (NonlinearProblem drops the
  options it does not consume at construction): MUMPS LDLᵀ (``cholesky``, half the flops of LU)
  when the Jacobian is symmetric — a model whose residual is the derivative of an energy, i.e.
  without follower loads or extra residual terms — MUMPS LU otherwise. The symbolic factorisation
  is done once and reused (the sparsity pattern never changes),
* the residual skips the Dirichlet *lifting* (a Jacobian-kernel assembly over the cells that touch
  constrained dofs) whenever the iterate already satisfies the boundary values, which is every
  Newton iterate after the first.

``LoadStepper`` increases λ from 0 to 1 with a predictor (tangent by default: one stale-Jacobian
Newton step at the new load, which costs a residual and a triangular solve), a step size adapted
to the Newton iteration count, loose corrector tolerances on the intermediate steps (the path of
an elastic problem need not be followed to round-off, only the final state), cut-back on
divergence, and raises :class:`SolveFailed` when it runs out of retries.
"""

from __future__ import annotations

import os
import time
import weakref
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from fenics_garment._stack import MPI, PETSc, dolfinx
from fenics_garment.petsc_options import LINEAR_SOLVERS, check_options

DEFAULT_SNES_OPTIONS: dict[str, object] = {
    "snes_type": "newtonls",
    "snes_linesearch_type": "basic",
    "snes_rtol": 1e-9,
    "snes_atol": 1e-12,
    # Newton converges quadratically, so a relative step below 1e-10 means the residual is at its
    # round-off floor; the absolute tolerance is also raised to 10× the measured floor (below).
    "snes_stol": 1e-10,
    "snes_max_it": 25,
    # PETSc's divergence test at its default: -1 is PETSC_DETERMINE in PETSc 3.25, i.e. a residual
    # 1e4 times the first one ends the solve (PETSC_UNLIMITED, -3, would switch it off). A
    # residual that grows in the first iterations (contact switching) stays below that; a step
    # that truly diverges is stopped early: the dress's (30 mm) third grow step stops after 6
    # iterations (DIVERGED_DTOL) and is cut, where without the test it runs to max_it (15) and is
    # cut all the same.
    "snes_divergence_tolerance": -1,
    "ksp_type": "preonly",
    # "lu", or "cholesky" when the Jacobian is symmetric (see NonlinearSolver(symmetric=...))
    "pc_type": "lu",
    "pc_factor_mat_solver_type": "mumps",
}

JIT_OPTIONS: dict[str, object] = {
    "cffi_extra_compile_args": (
        ["-O2", "-g0", "-march=native"] if os.environ.get("FENICS_GARMENT_NATIVE_JIT") else
        ["-O1", "-g0"]
    )
}  # fmt: skip
"""FFCx/CFFI options of the residual and Jacobian kernels. ``-O1`` by default, not DOLFINx's
``-O2``: the P1-P1 gilet's Jacobian is one 40,000-line kernel, which gcc compiled in 24.1 s at
-O1 against 34.6 s at -O2 (cold cache, serial) and which then assembled as fast (0.197 s against
0.205 s per assembly); -O0 compiles in 4.6 s but assembles 2.8× slower (0.576 s). With
``FENICS_GARMENT_NATIVE_JIT=1`` the kernels are compiled -O2 for this CPU (-march=native:
measured ≈ 10 % faster shell Jacobian assembly on a quiet machine, one recompile of every form,
and a JIT cache (~/.cache/fenics) that must not be shared with machines of another CPU)."""

ITERATIVE_OPTIONS: dict[str, object] = dict(LINEAR_SOLVERS["gamg"])
"""An iterative alternative to the direct solver (pass as ``petsc_options``): CG (symmetric
Jacobian) or GMRES + GAMG with the shell's rigid-body near-nullspace
(:data:`fenics_garment.petsc_options.LINEAR_SOLVERS`)."""


#: PETSc options left in the database for a solver's multigrid levels, by options prefix
_KEPT: dict[str, list[str]] = {}


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
#: SNES reason of a solve stopped by a NaN/Inf residual.
NONFINITE_REASON = int(PETSc.SNES.ConvergedReason.DIVERGED_FUNCTION_NANORINF)
#: SNES reason of a solve stopped because Newton cycles (not a PETSc code: PETSc's are > -20).
CYCLING_REASON = -100
_REASONS[CYCLING_REASON] = "diverged cycling"
#: Periods looked for by :func:`newton_cycle`, the relative agreement that counts as a repeat
#: and the fewest repeated iterations. Measured on the dress (full Newton steps, the multipliers'
#: last pass to the answer's tolerance): at 22.5 mm 0.0025, 0.0034, then 0.00031 / 0.0033 N
#: alternating, at 25.8 mm a cycle of 10 (0.00058, 0.043, 0.0099, 0.068, 0.0019, 0.025, 0.035,
#: 0.027, 0.063, 0.025, again from 0.00058), each until ``max_it`` (30): iterations that changed
#: nothing before the retry with the "l2" line search converged.
CYCLE_PERIODS, CYCLE_RTOL, CYCLE_REPEATS = range(1, 11), 1e-3, 4


def newton_cycle(residuals) -> int:
    """The period p of a cycle the residual norms r₀ … r_n have entered, 0 if none: each of the
    last max(p, :data:`CYCLE_REPEATS`) norms equals the one p iterations before it to
    :data:`CYCLE_RTOL` (the same iterates come back). A converging or merely slow Newton
    iteration (a damped line search's plateaus shrink the residual by ≥ 1 % per iteration) does
    not repeat itself that closely."""
    r = np.asarray(residuals, dtype=float)
    n = len(r) - 1
    for p in CYCLE_PERIODS:
        m = max(p, CYCLE_REPEATS)
        if n < m + p - 1:
            break
        a, b = r[n - m + 1 :], r[n - m - p + 1 : n - p + 1]
        if np.all(np.abs(a - b) <= CYCLE_RTOL * np.maximum(np.abs(a), np.abs(b))):
            return p
    return 0


def reason_name(reason: int) -> str:
    """PETSc's name of a SNES converged reason, e.g. -4 → "diverged function nanorinf"."""
    return _REASONS.get(int(reason), "unknown")


@dataclass
class Timings:
    """Wall-clock split, accumulated over a run.

    ``solve`` is the wall time inside SNES and includes ``residual`` and ``jacobian``
    (``solve − residual − jacobian`` is the linear solver plus SNES overhead); ``residual``
    includes the pre-residual ``hooks`` and ``jacobian`` the ``jacobian_hooks``. ``predictor`` is
    the load stepper's predictor (residual evaluations in it are counted in ``residual`` too).
    """

    jit: float = 0.0
    residual: float = 0.0
    jacobian: float = 0.0
    hooks: float = 0.0
    jacobian_hooks: float = 0.0
    solve: float = 0.0
    predictor: float = 0.0
    newton_iterations: int = 0
    linear_iterations: int = 0
    residual_evaluations: int = 0
    jacobian_evaluations: int = 0
    liftings: int = 0
    steps: int = 0
    cuts: int = 0
    nonfinite: int = 0  # residual evaluations that gave NaN/Inf (each ends its Newton solve)
    cycles: int = 0  # Newton solves stopped because they cycled (CYCLING_REASON)

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def is_symmetric(model) -> bool:
    """True when the model's residual is the derivative of an energy (symmetric Jacobian).

    A :class:`~fenics_garment.shell.model.ShellModel` without follower loads (pressures, follower
    point loads) and without extra residual terms (contact) qualifies; anything else (unknown
    models included) does not.
    """
    follower = getattr(model, "_follower", None)
    extra = getattr(model, "_extra_residual", None)
    points = getattr(model, "_point", [])
    return follower == [] and extra == [] and not any(f for _, _, f in points)


class NonlinearSolver:
    """SNES on the residual F(q) = 0 of ``model``, with hooks, point loads and timing.

    ``symmetric``: factorise with LDLᵀ (MUMPS ``cholesky``) instead of LU; ``None`` decides with
    :func:`is_symmetric` (and never overrides a ``pc_type`` given in ``petsc_options``).
    ``jit_options``: passed to DOLFINx's JIT (default :data:`JIT_OPTIONS`; ``{}``: DOLFINx's own).
    """

    def __init__(
        self,
        model,
        bcs: list,
        *,
        point_loads: list | None = None,
        pre_residual: list[Callable[[], None]] | None = None,
        pre_jacobian: list[Callable[[], None]] | None = None,
        petsc_options: dict | None = None,
        prefix: str = "garment_",
        symmetric: bool | None = None,
        jit_options: dict | None = None,
    ):
        from fenics_garment.shell.loads import point_load_vector

        self.model = model
        self.bcs = bcs
        self.hooks = list(pre_residual or [])
        self.jacobian_hooks = list(pre_jacobian or [])
        self.timings = Timings()
        self._cycled = False  # set by the monitor of a solve that cycles
        #: called after every Newton iteration as progress(its, ‖F‖, seconds of the iteration)
        self.progress: Callable[[int, float, float], None] | None = None
        self._t_iteration = time.perf_counter()
        opts = dict(DEFAULT_SNES_OPTIONS)
        if symmetric is None:
            symmetric = is_symmetric(model) and not self.hooks
        if symmetric and not (petsc_options and "pc_type" in petsc_options):
            opts["pc_type"] = "cholesky"
        if petsc_options:
            opts.update(check_options(petsc_options))
        if (
            opts["pc_type"] not in ("lu", "cholesky")
            and opts["ksp_type"] == "preonly"
            and not (petsc_options and "ksp_type" in petsc_options)
        ):  # an iterative preconditioner alone is no solver: CG for SPD Jacobians, else GMRES
            opts["ksp_type"] = "cg" if symmetric else "gmres"
        self.options = opts
        F = model.residual()
        J = model.jacobian(F)
        t0 = time.perf_counter()
        self.problem = dolfinx.fem.petsc.NonlinearProblem(
            F, model.q, bcs=bcs, J=J, petsc_options_prefix=prefix,
            petsc_options={k: v for k, v in opts.items() if not k.startswith(("ksp_", "pc_"))},
            jit_options=JIT_OPTIONS if jit_options is None else jit_options,
        )  # fmt: skip
        self.timings.jit += time.perf_counter() - t0
        try:
            self._setup_linear_solver(opts, prefix)
        except PETSc.Error as e:
            given = {k: v for k, v in (petsc_options or {}).items()
                     if k.startswith(("ksp_", "pc_", "mat_"))}  # fmt: skip
            raise ValueError(
                f"PETSc rejected the linear-solver options {given or opts}: error code {e.ierr} "
                "(unknown type or value; see https://petsc.org/release/manualpages/KSP/)"
            ) from e
        self.f_point = point_load_vector(model, point_loads) if point_loads else None
        if self.f_point is not None:
            self._zero_bc_rows(self.f_point)
        self._bc_gap = self.problem.b.duplicate()  # g − x on the constrained dofs
        self._install_callbacks()
        self.residual_floor = self._measure_floor(opts)

    def _setup_linear_solver(self, opts: dict, prefix: str) -> None:
        ksp = self.problem.solver.getKSP()
        ksp.setType(opts["ksp_type"])
        pc = ksp.getPC()
        pc.setType(opts["pc_type"])
        if opts["pc_type"] in ("lu", "cholesky"):
            pc.setFactorSolverType(opts["pc_factor_mat_solver_type"])
        if opts["pc_type"] == "gamg" and getattr(self.model, "Q", None) is not None:
            from fenics_garment.shell.nullspace import near_nullspace

            self.near_nullspace = near_nullspace(self.model.Q)
            mats = (self.problem.A, self.problem.P_mat)
            for mat in {id(m): m for m in mats if m is not None}.values():
                mat.setNearNullSpace(self.near_nullspace)
        self._user_ksp_options(ksp, opts, prefix)

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
        twin = getattr(model, "rest_free_floor", None)
        floor = twin() if twin is not None else None
        if floor is not None:  # flat panels: sewing forces at q = 0 are not noise
            return self._raise_atol(snes, floor)
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
        return self._raise_atol(snes, floor)

    @staticmethod
    def _raise_atol(snes, floor: float) -> float:
        """Raise the absolute tolerance to 10× the floor; returns the floor."""
        if not np.isfinite(floor):  # e.g. moduli that overflow: the solves will say so
            return floor
        atol = snes.getTolerances()[1]
        snes.setTolerances(atol=max(atol, 10.0 * floor))
        return floor

    # -- PETSc plumbing ------------------------------------------------------------------------
    def _user_ksp_options(self, ksp, opts: dict, prefix: str) -> None:
        extra = {k: v for k, v in opts.items() if k.startswith(("ksp_", "pc_", "mat_", "mg_"))}
        if opts["pc_type"] not in ("lu", "cholesky"):  # e.g. MUMPS has no ILU
            extra.pop("pc_factor_mat_solver_type", None)
        o = PETSc.Options()
        for k in _KEPT.pop(prefix, ()):  # a previous solver's multigrid level options
            o.delValue(f"{prefix}{k}")
        if not extra:
            return
        for k, v in extra.items():
            o[f"{prefix}{k}"] = v
        ksp.setFromOptions()
        # The multigrid levels are made, and read their options, at the first solve: keep those
        # in the database (under this solver's prefix) until another solver takes the prefix.
        kept = [k for k in extra if k.startswith("mg_")]
        for k in extra:
            if k not in kept:
                del o[f"{prefix}{k}"]
        if kept:
            _KEPT[prefix] = kept

    def _zero_bc_rows(self, vec) -> None:
        for bc in self.bcs:
            dofs, n_owned = bc._cpp_object.dof_indices()
            with vec.localForm() as vl:
                vl.array[dofs[:n_owned]] = 0.0

    def _lifting_needed(self, x) -> bool:
        """Whether some constrained dof of ``x`` differs from its boundary value (all ranks)."""
        if not self.bcs:
            return False
        gap = self._bc_gap
        with gap.localForm() as gl:
            gl.set(0.0)
        dolfinx.fem.petsc.set_bc(gap, self.bcs, x0=x, alpha=1.0)
        local = float(np.max(np.abs(gap.array_r), initial=0.0))
        return gap.comm.tompi4py().allreduce(local, op=MPI.MAX) > 0.0

    def _assemble_residual(self, x, b) -> None:
        """``dolfinx.fem.petsc.assemble_residual`` without the lifting when it adds nothing."""
        from dolfinx.fem.petsc import apply_lifting, assemble_vector, set_bc

        p = self.problem
        dolfinx.la.petsc._zero_vector(b)
        assemble_vector(b, p.F)
        if self._lifting_needed(x):
            apply_lifting(b, [p.J], bcs=[self.bcs], x0=[x], alpha=-1.0)
            self.timings.liftings += 1
        dolfinx.la.petsc._ghost_update(b, PETSc.InsertMode.ADD, PETSc.ScatterMode.REVERSE)
        set_bc(b, self.bcs, x0=x, alpha=-1.0)
        dolfinx.la.petsc._ghost_update(b, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)

    def _install_callbacks(self) -> None:
        from dolfinx.fem.petsc import assemble_jacobian

        snes = self.problem.solver
        p = self.problem
        jctx = {"u": p.u, "jacobian": p.J, "preconditioner": p.preconditioner, "bcs": self.bcs}
        model = self.model
        timings = self.timings
        # The SNES keeps these callbacks (in C, out of sight of Python's garbage collector): a
        # strong reference to the solver from them would be a cycle solver → problem → SNES →
        # callback → solver that is never freed, keeping the contact hooks and the body's
        # search tree alive until PETSc finalises (nanobind then reported them as leaked). With
        # a weak one the solver is freed when its user drops it, and NonlinearProblem.__del__
        # destroys the SNES.
        this = weakref.ref(self)

        def residual(snes_, x, b):
            solver = this()
            t0 = time.perf_counter()
            dolfinx.la.petsc._ghost_update(x, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)
            dolfinx.fem.petsc.assign(x, model.q)
            if solver.hooks:
                th = time.perf_counter()
                for hook in solver.hooks:
                    hook()
                timings.hooks += time.perf_counter() - th
            solver._assemble_residual(x, b)
            if solver.f_point is not None:
                b.axpy(-float(model.load_factor.value), solver.f_point)
            timings.residual_evaluations += 1
            timings.residual += time.perf_counter() - t0
            if not np.isfinite(b.norm()):
                timings.nonfinite += 1

        def jacobian(snes_, x, J, P):
            solver = this()
            t0 = time.perf_counter()
            if solver.jacobian_hooks:
                forward = PETSc.ScatterMode.FORWARD
                dolfinx.la.petsc._ghost_update(x, PETSc.InsertMode.INSERT, forward)
                dolfinx.fem.petsc.assign(x, model.q)
                for hook in solver.jacobian_hooks:
                    hook()
                timings.jacobian_hooks += time.perf_counter() - t0
            assemble_jacobian(snes_, x, J, P, **jctx)
            timings.jacobian_evaluations += 1
            timings.jacobian += time.perf_counter() - t0

        snes.setFunction(residual, p.b)
        snes.setJacobian(jacobian, p.A, p.P_mat)

        def stop_cycling(snes_, its, fnorm):
            solver = this()
            # the history (reset by solve()) already holds this iteration's norm
            history = snes_.getConvergenceHistory()[0]
            if snes_.getConvergedReason() == 0 and newton_cycle(history):
                solver._cycled = True
                snes_.setConvergedReason(PETSc.SNES.ConvergedReason.DIVERGED_LOCAL_MIN)
            now = time.perf_counter()
            if solver.progress is not None and its > 0:
                solver.progress(int(its), float(fnorm), now - solver._t_iteration)
            solver._t_iteration = now

        snes.setMonitor(stop_cycling)

    # -- solve -------------------------------------------------------------------------------
    def solve(self) -> tuple[int, int]:
        """One Newton solve from the current ``model.q``; returns (iterations, reason)."""
        snes = self.problem.solver
        snes.setConvergenceHistory(length=snes.getTolerances()[3] + 1, reset=True)
        self._cycled = False
        t0 = self._t_iteration = time.perf_counter()
        self.problem.solve()
        dt = time.perf_counter() - t0
        its, reason = snes.getIterationNumber(), snes.getConvergedReason()
        if self._cycled:
            reason = CYCLING_REASON
            self.timings.cycles += 1
        self.timings.newton_iterations += its
        self.timings.linear_iterations += snes.getLinearSolveIterations()
        self.timings.solve += dt
        return its, reason

    def residual_norm(self) -> float:
        """‖F(q)‖ at the current ``model.q`` (pre-residual hooks run, BCs applied)."""
        p = self.problem
        dolfinx.fem.petsc.assign(self.model.q, p.x)
        p.solver.computeFunction(p.x, p.b)
        return float(p.b.norm())

    def raise_atol(self, atol: float) -> float:
        """Absolute residual tolerance of the following solves: at least ``atol``; returns it."""
        snes = self.problem.solver
        if not np.isfinite(atol):  # a NaN/Inf force scale: keep the tolerance (solves fail)
            return snes.getTolerances()[1]
        atol = max(snes.getTolerances()[1], atol)
        snes.setTolerances(atol=atol)
        return atol

    def set_atol(self, atol: float) -> float:
        """Absolute residual tolerance of the following solves (not below the round-off floor
        measured at construction, 10× :attr:`residual_floor`); returns the previous one."""
        snes = self.problem.solver
        previous = snes.getTolerances()[1]
        snes.setTolerances(atol=max(atol, 10.0 * self.residual_floor))
        return previous

    def set_line_search(self, kind: str) -> str:
        """SNES line search of the following solves ("basic", "l2", "bt", …); returns the
        previous one."""
        ls = self.problem.solver.getLineSearch()
        previous = ls.getType()
        ls.setType(kind)
        return previous

    def set_max_it(self, max_it: int) -> int:
        """Newton iteration limit of the following solves; returns the previous limit."""
        snes = self.problem.solver
        previous = snes.getTolerances()[3]
        snes.setTolerances(max_it=max_it)
        return previous

    def set_rtol(self, rtol: float) -> None:
        """Change the relative (residual and step) tolerance of the following solves."""
        self.problem.solver.setTolerances(rtol=rtol)

    def stale_newton_step(self) -> bool:
        """q ← q − J₀⁻¹ F(q) with the last factorised Jacobian J₀ (no assembly, no factorisation).

        At a converged state with λ raised this is the tangent predictor. Returns False (q
        unchanged) when there is no factorisation yet or the step is not finite.
        """
        p = self.problem
        ksp = p.solver.getKSP()
        if not ksp.getPC().getOperators()[0].assembled or self.timings.jacobian_evaluations == 0:
            return False
        t0 = time.perf_counter()
        x, b = p.x, p.b
        dolfinx.fem.petsc.assign(self.model.q, x)
        p.solver.computeFunction(x, b)
        dq = x.duplicate()
        ksp.solve(b, dq)
        ok = np.isfinite(dq.norm())
        if ok:
            x.axpy(-1.0, dq)
            dolfinx.la.petsc._ghost_update(x, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)
            dolfinx.fem.petsc.assign(x, self.model.q)
        dq.destroy()
        self.timings.predictor += time.perf_counter() - t0
        return bool(ok)

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


PREDICTORS = ("tangent", "secant", "none")


@dataclass
class LoadStepper:
    """Drive λ from 0 to 1 in adaptive steps with a predictor and cut-back on failure.

    * ``predictor``: ``"tangent"`` (default; also ``True``) takes one Newton step at the new load
      with the last factorised Jacobian — the tangent of the load path, at the cost of a residual
      and a triangular solve; ``"secant"`` extrapolates the last two converged states;
      ``"none"`` (also ``False``) starts from the last converged state.
    * step size: a step that converges in ``its`` iterations scales the next one by
      ``clip(target_iterations / its, 0.5, max_growth)``; without ``target_iterations``, by
      ``max_growth`` when ``its <= grow_below`` and by 1 otherwise.
    * ``intermediate_rtol``: relative tolerance of the steps before the last one (``None``: the
      solver's own). An elastic load path need not be followed to round-off; only the final
      state is converged to the solver's tolerance.
    * A step whose Newton solve fails is restored and halved (up to ``max_cuts`` times in a row).
    """

    solver: NonlinearSolver
    steps: int = 10
    min_step: float = 1e-4
    max_cuts: int = 6
    grow_below: int = 4
    predictor: bool | str = "tangent"
    max_growth: float = 1.5
    target_iterations: int | None = None
    intermediate_rtol: float | None = 1e-3
    on_step: Callable[[StepRecord], None] | None = None
    history: list[StepRecord] = field(default_factory=list)

    def _predictor_kind(self) -> str:
        kind = {True: "tangent", False: "none"}.get(self.predictor, self.predictor)
        if kind not in PREDICTORS:
            raise ValueError(f"predictor must be one of {PREDICTORS}, got {self.predictor!r}")
        return kind

    def _next_step(self, step: float, its: int) -> float:
        if self.target_iterations is None:
            return step * (self.max_growth if its <= self.grow_below else 1.0)
        factor = self.target_iterations / max(its, 1)
        return step * min(max(factor, 0.5), self.max_growth)

    def _predict(self, kind: str, step: float, q_prev: np.ndarray, lam_prev: float, lam: float):
        q = self.solver.model.q
        if kind == "secant" and self.history and lam > lam_prev:
            q.x.array[:] = q.x.array + (step / (lam - lam_prev)) * (q.x.array - q_prev)
        elif kind == "tangent":
            self.solver.stale_newton_step()

    def run(
        self, target: float = 1.0, *, from_current: bool = False, back: bool = True
    ) -> list[StepRecord]:
        """Step λ to ``target`` and stop there exactly; returns the history of accepted steps.

        Starts from λ = 0 on this stepper's first run and from where it stopped on later runs.
        ``from_current=True`` starts from the model's current load factor and state instead —
        to continue after path following (:mod:`fenics_garment.path`), which leaves the model
        at a converged (q, λ) that this stepper has not seen.

        A model already *beyond* the target (``from_current=True`` at λ > ``target``, e.g. where
        an arc length with ``lambda_max`` stopped past it) is taken back along its equilibrium
        path: :class:`~fenics_garment.path.ArcLength` from the current state towards decreasing
        λ with ``stop_at_load=target``, which ends exactly at λ = ``target`` on the branch the
        model is on (a first load step of (λ − target)/``steps``). Where the path turns at a
        limit point before reaching the target, it stops with :class:`SolveFailed` naming the
        limit. ``back=False`` refuses instead (a one-line ValueError). Load stepping itself only
        increases λ and cannot stop at a displacement: for that use
        ``ArcLength.run(..., stop_at=(probe, w))`` or
        :class:`~fenics_garment.path.DisplacementControl`.
        """
        solver = self.solver
        model = solver.model
        q = model.q
        kind = self._predictor_kind()
        rtol = solver.problem.solver.getTolerances()[0]
        current = float(model.load_factor.value)
        lam = current if (self.history or from_current) else 0.0
        if from_current and lam > target + 1e-14:
            if back:
                return self._back_to(target, lam)
            raise ValueError(
                f"the model is at λ = {lam:.6g}, beyond the target {target:.6g}, and back=False: "
                f"run(target, from_current=True) takes it back along the path to λ = "
                f"{target:.6g}"
            )
        dlam = (target - lam) / self.steps
        q_prev = q.x.array.copy()
        lam_prev = lam
        cuts_in_row = 0
        try:
            while lam < target - 1e-14:
                step = min(dlam, target - lam)
                last = lam + step >= target - 1e-14
                q_conv = q.x.array.copy()
                model.load_factor.value = lam + step
                self._predict(kind, step, q_prev, lam_prev, lam)
                loose = self.intermediate_rtol is not None and not last
                solver.set_rtol(max(self.intermediate_rtol, rtol) if loose else rtol)
                its, reason = solver.solve()
                if reason > 0:
                    q_prev, lam_prev = q_conv, lam
                    lam += step
                    rec = StepRecord(lam, its, reason, cuts_in_row)
                    self.history.append(rec)
                    solver.timings.steps += 1
                    if self.on_step:
                        self.on_step(rec)
                    cuts_in_row = 0
                    dlam = self._next_step(step, its)
                    # do not leave a sliver for the last step
                    if target - lam < 1.3 * dlam:
                        dlam = target - lam
                else:
                    q.x.array[:] = q_conv
                    q.x.scatter_forward()
                    model.load_factor.value = lam
                    cuts_in_row += 1
                    solver.timings.cuts += 1
                    dlam = step / 2
                    if cuts_in_row > self.max_cuts or dlam < self.min_step * target:
                        raise SolveFailed(lam + step, its, reason)
        finally:
            solver.set_rtol(rtol)
        return self.history

    def _back_to(self, target: float, lam: float) -> list[StepRecord]:
        """From λ = ``lam`` > ``target`` back along the path to λ = ``target`` exactly."""
        from fenics_garment.path import ArcLength

        path = ArcLength(self.solver)

        def turned(_) -> bool:  # a minimum of λ above the target: the path leaves it
            return any(p.kind == "minimum" for p in path.stats.limit_points)

        points = path.run(
            (lam - target) / max(self.steps, 1), stop_at_load=target, reverse=True, stop=turned
        )
        for p in points:
            rec = StepRecord(p.load_factor, p.iterations, 1, p.cuts)
            self.history.append(rec)
            self.solver.timings.steps += 1
            if self.on_step:
                self.on_step(rec)
        if not (points and points[-1].landed):
            now = float(self.solver.model.load_factor.value)
            why = (
                f"the path turns at a minimum λ ≈ {path.stats.limit_points[-1].load_factor:.6g}"
                if turned(None)
                else f"it is at λ = {now:.6g} after {len(points)} increments"
            )
            raise SolveFailed(
                now, 0, 0,
                f"going back from λ = {lam:.6g} along the path did not reach λ = {target:.6g}: "
                f"{why}",
            )  # fmt: skip
        return self.history
