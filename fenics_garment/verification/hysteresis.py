"""Pure bending through a loading–unloading cycle: the moment–curvature loop of the hysteretic
bending law (:class:`~fenics_garment.shell.energy.HystereticBending`, issue 47 item 3).

A strip [0, L] × [0, b], warp along x, clamped at x = 0, carries the line moment M (per unit
width, about −y) on its edge x = L. With ν12 = 0 (no bending coupling, D12 = 0) it bends into a
circular arc of uniform curvature κ = θ(L)/L, θ(L) the tip rotation, at any rotation — the
KES-FB2 pure-bending test. M runs 0 → M_max → −M_max → M_max in equal steps, each step
committed (the history of the law). The analytic loop (the test's) is that of the friction
slider: M = Bκ ± HB on its plastic branches, a loop of width 2HB at every curvature.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from fenics_garment._stack import MPI
from fenics_garment.materials import Fabric
from fenics_garment.shell import bcs as B
from fenics_garment.shell.energy import HystereticBending, commit_history
from fenics_garment.shell.geometry import parametric_surface_mesh
from fenics_garment.shell.kinematics import ShellGeometry
from fenics_garment.shell.model import ShellModel, evaluate_at_points
from fenics_garment.solve import NonlinearSolver
from fenics_garment.verification.shells import edge_measure


@dataclass
class BendingLoop:
    moment: np.ndarray  # M [N·m/m] of each step
    curvature: np.ndarray  # κ = θ(L)/L [1/m]
    newton_its: int
    wall_s: float


def moment_cycle(m_max: float, steps: int) -> np.ndarray:
    """0 → m_max → −m_max → m_max in ``steps`` equal steps per quarter of the amplitude."""
    up = np.linspace(0.0, m_max, steps + 1)[1:]
    down = np.linspace(m_max, -m_max, 2 * steps + 1)[1:]
    return np.concatenate([up, down, -down])


def bending_loop(
    material: Fabric,
    law: HystereticBending | None,
    moments: np.ndarray,
    *,
    length: float = 0.004,
    width: float = 0.01,
    n: int = 4,
    petsc_options: dict | None = None,
    comm=MPI.COMM_WORLD,
) -> BendingLoop:
    """The strip's curvature at each moment of ``moments`` (the module doc); ``law``: the
    bending law (None: the elastic one)."""
    t0 = time.perf_counter()
    L, b = length, width
    mesh = parametric_surface_mesh(comm, lambda x, y: np.array([x, y, 0.0 * x]),
                                   (0.0, L), (0.0, b), (n, 1))  # fmt: skip
    model = ShellModel(ShellGeometry.from_mesh(mesh, warp=(1, 0, 0)), material)
    if law is not None:
        model.bending = law
    m = model.add_edge_moment((0.0, 0.0, 0.0), edge_measure(mesh, lambda x: np.isclose(x[0], L)))
    bcs = B.clamped(model, lambda x: np.isclose(x[0], 0.0))
    solver = NonlinearSolver(model, bcs, petsc_options=petsc_options)
    tip = np.array([[L, b / 2, 0.0]])
    kappa = []
    for M in moments:
        m.value[:] = (0.0, -M, 0.0)  # about −y: the tip curls up (+z) for M > 0
        _its, reason = solver.solve()
        if reason <= 0:
            raise RuntimeError(f"pure bending: Newton failed at M = {M:.4g} N·m/m ({reason})")
        commit_history(model)
        theta = evaluate_at_points(model.q.sub(1).collapse(), tip)[0]
        kappa.append(-theta[1] / L)
    return BendingLoop(np.asarray(moments, float), np.asarray(kappa),
                       solver.timings.newton_iterations, time.perf_counter() - t0)  # fmt: skip


def loop_width(loop: BendingLoop, kappa: float) -> float:
    """The moment of the rising branch (the last two fifths of :func:`moment_cycle`) minus that
    of the falling branch (the middle two fifths) at curvature ``kappa``, by linear
    interpolation: 2HB where both branches slip."""
    n = len(loop.moment) // 5  # steps per quarter: n up, 2n down, 2n up
    fall = slice(n, 3 * n)
    rise = slice(3 * n, 5 * n)
    k_f, m_f = loop.curvature[fall][::-1], loop.moment[fall][::-1]
    k_r, m_r = loop.curvature[rise], loop.moment[rise]
    return float(np.interp(kappa, k_r, m_r) - np.interp(kappa, k_f, m_f))
