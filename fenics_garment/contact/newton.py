"""Stop-gap SNES helpers until ``fenics_garment.solve`` lands: pre-residual hooks, checked solve.

``NonlinearProblem``'s residual callback copies the SNES iterate into the unknown Function and
assembles. :func:`add_pre_residual_hooks` wraps that callback so that each hook (e.g.
``ContactState.refresh``) sees the iterate first: the contact state (gap, normal, u_k) is then
always the one of the point where the residual is evaluated, and the Jacobian SNES evaluates
next, at the same point, uses it too.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from fenics_garment._stack import PETSc, dolfinx

Hook = Callable[[dolfinx.fem.Function], None]


@dataclass
class CallbackTimes:
    """Wall time [s] spent in the SNES callbacks (accumulated; ``reset`` to zero them)."""

    hooks_s: float = 0.0
    residual_s: float = 0.0
    jacobian_s: float = 0.0
    residuals: int = 0
    jacobians: int = 0

    def reset(self) -> None:
        self.hooks_s = self.residual_s = self.jacobian_s = 0.0
        self.residuals = self.jacobians = 0


def add_pre_residual_hooks(
    problem: dolfinx.fem.petsc.NonlinearProblem, u: dolfinx.fem.Function, hooks: Sequence[Hook]
) -> CallbackTimes:
    """Call every hook with the current iterate before each residual evaluation of SNES.

    Returns the callback timers (hooks, residual assembly, Jacobian assembly).
    """
    snes = problem.solver
    times = CallbackTimes()
    b, (func, args, kargs) = snes.getFunction()
    args = args or ()
    kargs = kargs or {}

    def residual(snes_: PETSc.SNES, x: PETSc.Vec, f: PETSc.Vec) -> None:
        t0 = time.perf_counter()
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        dolfinx.fem.petsc.assign(x, u)
        for hook in hooks:
            hook(u)
        t1 = time.perf_counter()
        func(snes_, x, f, *args, **kargs)
        times.hooks_s += t1 - t0
        times.residual_s += time.perf_counter() - t1
        times.residuals += 1

    snes.setFunction(residual, b)
    A, P, (jfunc, jargs, jkargs) = snes.getJacobian()
    jargs = jargs or ()
    jkargs = jkargs or {}

    def jacobian(snes_: PETSc.SNES, x: PETSc.Vec, J: PETSc.Mat, Pm: PETSc.Mat) -> None:
        t0 = time.perf_counter()
        jfunc(snes_, x, J, Pm, *jargs, **jkargs)
        times.jacobian_s += time.perf_counter() - t0
        times.jacobians += 1

    snes.setJacobian(jacobian, A, P)
    return times


@dataclass
class SolveReport:
    """Outcome of one nonlinear solve."""

    converged: bool
    reason: int
    iterations: int
    residuals: list[float]

    def ratios(self) -> list[float]:
        """Ratios r_{k+1}/r_k of successive residual norms (quadratic convergence: they → 0)."""
        r = self.residuals
        return [r[k + 1] / r[k] for k in range(len(r) - 1) if r[k] > 0]

    def orders(self) -> list[float]:
        """Observed convergence orders log(r_{k+1}/r_k)/log(r_k/r_{k-1}) (≈ 2 when quadratic)."""
        r = np.asarray(self.residuals)
        out = []
        for k in range(1, len(r) - 1):
            a, b = np.log(r[k + 1] / r[k]), np.log(r[k] / r[k - 1])
            if np.isfinite(a) and np.isfinite(b) and b != 0:
                out.append(float(a / b))
        return out


def solve(problem: dolfinx.fem.petsc.NonlinearProblem) -> SolveReport:
    """Run SNES and report convergence (``NonlinearProblem.solve`` does not raise on failure)."""
    snes = problem.solver
    snes.setConvergenceHistory(length=200, reset=True)
    problem.solve()
    reason = snes.getConvergedReason()
    hist, _ = snes.getConvergenceHistory()
    return SolveReport(reason > 0, int(reason), snes.getIterationNumber(), [float(v) for v in hist])
