"""The PETSc options a garment solve accepts (scene `[solver.petsc]`, `NonlinearSolver`).

The solver is Newton with a line search (the dressing switches between line searches, so every
SNES type without one — ``ksponly``, ``newtontr``, ``ngmres`` … — would crash PETSc in
``getLineSearch``) on a KSP + PC, a direct MUMPS factorisation by default. Only the options of
that design are accepted, each with its kind and range; anything else is refused before PETSc
sees it, with the reason (PETSc itself would ignore a misspelt option silently, crash on some
combinations, or raise a bare error code). Pure Python: no PETSc object is made here.
"""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Callable, Mapping

#: SNES types with the line search the dressing drives.
SNES_TYPES = ("newtonls",)
LINE_SEARCHES = ("basic", "bt", "l2", "secant", "cp", "nleqerr")
KSP_TYPES = ("preonly", "gmres", "fgmres", "lgmres", "cg", "minres", "bcgs", "bcgsl", "tfqmr",
             "gcr", "richardson")  # fmt: skip
PC_TYPES = ("lu", "cholesky", "ilu", "icc", "gamg", "hypre", "jacobi", "bjacobi", "asm", "sor",
            "none")  # fmt: skip
FACTOR_SOLVERS = ("mumps", "petsc", "superlu", "superlu_dist", "umfpack", "cholmod")
SHIFT_TYPES = ("none", "nonzero", "positive_definite", "inblocks")


class PetscOptionError(ValueError):
    """An option the solver does not support, or a value of the wrong kind or range."""

    def __init__(self, key: str, message: str):
        self.key = key
        super().__init__(f"[solver.petsc.{key}] {message}")


Check = Callable[[str, object], object]


def _number(value: object) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value)


def _real(lo: float, hi: float, *, lo_open: bool = False, extra: tuple[float, ...] = ()) -> Check:
    """A finite number in [lo, hi] (or (lo, hi] with ``lo_open``), or one of ``extra``."""

    def check(key: str, value: object) -> object:
        v = _number(value)
        if v is None:
            raise PetscOptionError(key, f"must be a number, got {_describe(value)}")
        if v in extra:
            return value
        inside = math.isfinite(v) and (lo < v if lo_open else lo <= v) and v <= hi
        if not inside:
            bracket = "(" if lo_open else "["
            also = f" (or {', '.join(f'{e:g}' for e in extra)})" if extra else ""
            raise PetscOptionError(key, f"must lie in {bracket}{lo:g}, {hi:g}]{also}, got {v!r}")
        return value

    return check


def _integer(lo: int, hi: int) -> Check:
    def check(key: str, value: object) -> object:
        if isinstance(value, bool) or not isinstance(value, int):
            raise PetscOptionError(key, f"must be an integer, got {_describe(value)}")
        if not lo <= value <= hi:
            raise PetscOptionError(key, f"must lie in [{lo}, {hi}], got {value}")
        return value

    return check


def _choice(allowed: tuple[str, ...], why: str = "") -> Check:
    def check(key: str, value: object) -> object:
        if not isinstance(value, str):
            raise PetscOptionError(key, f"must be a string, got {_describe(value)}")
        if value not in allowed:
            close = difflib.get_close_matches(value, allowed, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise PetscOptionError(
                key, f"must be one of {', '.join(allowed)}; got {value!r}{hint}{why}"
            )
        return value

    return check


def _flag(key: str, value: object) -> object:
    """A switch such as ``snes_monitor``: true / false (or "" for PETSc's bare flag)."""
    if value is True or value == "":
        return ""  # PETSc's bare flag
    if value is False:
        return value
    raise PetscOptionError(key, f"must be true or false, got {_describe(value)}")


#: Newton tolerances: looser ones stop Newton before the pressure has converged (the scene
#: default is rtol 1e-8; the residual is in newtons, a garment's forces are 1–100 N).
NEWTON_TOL = _real(0.0, 1e-4)
NEWTON_ATOL = _real(0.0, 1e-3)
#: Linear-solver tolerances (an inexact Newton step is fine, a meaningless one is not).
TOL = _real(0.0, 1e-2)
_SNES_WHY = ": the dressing needs a Newton line search (other SNES types have none)"

#: option name -> check of its value.
OPTIONS: dict[str, Check] = {
    "snes_type": _choice(SNES_TYPES, _SNES_WHY),
    "snes_linesearch_type": _choice(LINE_SEARCHES),
    "snes_rtol": NEWTON_TOL,
    "snes_stol": NEWTON_TOL,
    "snes_atol": NEWTON_ATOL,
    "snes_max_it": _integer(1, 1000),
    "snes_max_funcs": _integer(1, 1_000_000),
    # -3 (PETSC_UNLIMITED) switches the test off, -1 (PETSC_DETERMINE) is PETSc's default 1e4
    "snes_divergence_tolerance": _real(1.0, 1e300, extra=(-1.0, -3.0)),
    "snes_linesearch_damping": _real(0.0, 1.0, lo_open=True),
    "snes_linesearch_max_it": _integer(1, 100),
    "snes_linesearch_maxstep": _real(0.0, 1e300, lo_open=True),
    "ksp_type": _choice(KSP_TYPES),
    "ksp_rtol": TOL,
    "ksp_atol": NEWTON_ATOL,
    "ksp_divtol": _real(1.0, 1e300),
    "ksp_max_it": _integer(1, 100_000),
    "ksp_gmres_restart": _integer(1, 10_000),
    "pc_type": _choice(PC_TYPES),
    "pc_factor_mat_solver_type": _choice(FACTOR_SOLVERS),
    "pc_factor_shift_type": _choice(SHIFT_TYPES),
    "pc_factor_shift_amount": _real(0.0, 1e10),
    "pc_gamg_threshold": _real(-1.0, 1.0),
    "pc_gamg_agg_nsmooths": _integer(0, 10),
    "pc_hypre_type": _choice(("boomeramg", "pilut", "euclid")),
    "mg_levels_ksp_type": _choice(("chebyshev", "richardson", "gmres", "cg")),
    "mg_levels_pc_type": _choice(("jacobi", "sor", "bjacobi", "asm", "none")),
    "mg_levels_ksp_max_it": _integer(1, 100),
}
#: Linear solvers by name (scene ``[solver] linear``; the options of ``[solver.petsc]`` go on top):
#:
#: * ``direct``: MUMPS LDLᵀ or LU (:class:`~fenics_garment.solve.NonlinearSolver` chooses), the
#:   default: fastest up to the largest garments measured here (``benchmarks/solvers.py``);
#: * ``direct-blr``: the same with MUMPS block low-rank compression (ICNTL(35) = 1, automatic;
#:   CNTL(7) = 1e-9 the dropping threshold: the factors are exact to about that, well below the
#:   Newton tolerance): fewer flops and less memory on large meshes;
#: * ``gamg``: a Krylov method (CG when the Jacobian is symmetric, GMRES otherwise) preconditioned
#:   by smoothed-aggregation AMG with the shell's six rigid-body modes as near-nullspace
#:   (:mod:`fenics_garment.shell.nullspace`) and SOR smoothing: iterations nearly independent
#:   of the mesh (Scordelis–Lo roof: 83 / 92 / 99 at 9.6k / 38k / 84k dofs), work ∝ dofs, the
#:   path that scales past one machine. Without the rigid-body modes GAMG needed 1061 iterations
#:   at 9.6k dofs.
LINEAR_SOLVERS: dict[str, dict[str, object]] = {
    "direct": {},
    "direct-blr": {"mat_mumps_icntl_35": 1, "mat_mumps_cntl_7": 1e-9},
    "gamg": {"pc_type": "gamg", "ksp_rtol": 1e-8, "ksp_max_it": 2000,
             "ksp_gmres_restart": 200, "mg_levels_pc_type": "sor"},
}  # fmt: skip

FLAGS = ("snes_monitor", "snes_converged_reason", "snes_linesearch_monitor", "snes_view",
         "ksp_monitor", "ksp_converged_reason", "ksp_view", "options_left")  # fmt: skip
OPTIONS |= dict.fromkeys(FLAGS, _flag)

#: MUMPS integer and real controls by number (ICNTL(1…60), CNTL(1…15)).
_MUMPS = re.compile(r"^mat_mumps_(icntl|cntl)_(\d+)$")


def _describe(value: object) -> str:
    kind = {list: "an array", dict: "a table"}.get(type(value), type(value).__name__)
    return f"{kind} {value!r}"


def _mumps_check(key: str) -> Check | None:
    m = _MUMPS.match(key)
    if not m:
        return None
    n = int(m.group(2))
    if m.group(1) == "icntl":
        return _integer(-(2**31), 2**31 - 1) if 1 <= n <= 60 else None
    return _real(-1e300, 1e300) if 1 <= n <= 15 else None


def check_options(options: Mapping[str, object]) -> dict[str, object]:
    """The options, each checked against :data:`OPTIONS`; raises :class:`PetscOptionError`.

    A switch set to ``false`` is dropped (PETSc has no "off" value for it); ``true`` becomes
    PETSc's bare flag ``""``.
    """
    checked: dict[str, object] = {}
    for key, value in options.items():
        if not isinstance(key, str):
            raise PetscOptionError(str(key), "option names are strings")
        check = OPTIONS.get(key) or _mumps_check(key)
        if check is None:
            close = difflib.get_close_matches(key, list(OPTIONS), n=1, cutoff=0.6)
            hint = f"did you mean {close[0]!r}?" if close else "supported: " + ", ".join(OPTIONS)
            raise PetscOptionError(key, f"is not an option this solver supports; {hint}")
        value = check(key, value)
        if value is False:
            continue
        checked[key] = value
    return checked
