"""The shell's rigid-body near-nullspace and the GAMG linear solver built on it.

Independent checks: (1) the six rigid-body fields are in the kernel of the linear stiffness K of
an *unsupported* shell, ‖K v‖ ≈ 0 relative to ‖K‖‖v‖, while a non-rigid field is not (the check
can fail); (2) CG + GAMG with these vectors solves the Scordelis–Lo roof to the answer of the
direct MUMPS factorisation, in fewer than half the Krylov iterations GAMG needs without them.
"""

import numpy as np

from fenics_garment._stack import PETSc, dolfinx
from fenics_garment.petsc_options import LINEAR_SOLVERS
from fenics_garment.shell.model import evaluate_at_points
from fenics_garment.shell.nullspace import near_nullspace, rigid_body_fields
from fenics_garment.solve import JIT_OPTIONS, LoadStepper, NonlinearSolver
from fenics_garment.verification.shells import SCORDELIS_LO_POINT, scordelis_lo_model


def _stiffness(model):
    """K = ∂F/∂q at q = 0, no boundary conditions (the free shell)."""
    import dolfinx.fem.petsc as fp

    J = dolfinx.fem.form(model.jacobian(model.residual()), jit_options=JIT_OPTIONS)
    K = fp.assemble_matrix(J)
    K.assemble()
    return K


def _relative_action(K, array) -> float:
    n = K.getLocalSize()[1]
    v = K.createVecRight()
    v.array[:] = array[:n]
    y = K.createVecLeft()
    K.mult(v, y)
    return y.norm() / (K.norm(PETSc.NormType.FROBENIUS) * v.norm())


def test_rigid_body_modes_are_the_kernel_of_the_free_shell():
    model, bcs = scordelis_lo_model(4, supported=False)
    assert bcs == []
    K = _stiffness(model)
    for k, q in enumerate(rigid_body_fields(model.Q)):
        assert _relative_action(K, q.x.array) < 1e-13, f"mode {k}"
    # a bending field (u = x² e₃, θ = 0) is not a rigid motion: K sees it
    w = dolfinx.fem.Function(model.Q)
    w.sub(0).interpolate(lambda x: np.vstack([0 * x[0], 0 * x[0], x[0] ** 2]))
    assert _relative_action(K, w.x.array) > 1e-6
    # the PETSc vectors: orthonormal, and still in the kernel
    ns = near_nullspace(model.Q)
    vecs = ns.getVecs()
    assert len(vecs) == 6
    gram = np.array([[a.dot(b) for b in vecs] for a in vecs])
    assert np.allclose(gram, np.eye(6), atol=1e-12)
    for v in vecs:
        y = K.createVecLeft()
        K.mult(v, y)
        assert y.norm() / K.norm(PETSc.NormType.FROBENIUS) < 1e-13


def _solve(petsc_options, near=True):
    model, bcs = scordelis_lo_model(8)
    solver = NonlinearSolver(model, bcs, petsc_options=petsc_options)
    if not near:
        solver.problem.A.setNearNullSpace(PETSc.NullSpace())  # none: GAMG's default
    LoadStepper(solver, steps=1).run()
    w = evaluate_at_points(model.displacement(), [SCORDELIS_LO_POINT])[0, 2]
    return w, solver


def test_gamg_with_rigid_body_modes_matches_mumps():
    w_direct, direct = _solve(LINEAR_SOLVERS["direct"])
    w_gamg, gamg = _solve(LINEAR_SOLVERS["gamg"])
    assert direct.options["pc_type"] == "cholesky"
    assert gamg.options["ksp_type"] == "cg"  # symmetric Jacobian: CG chosen
    assert gamg.near_nullspace is not None
    # ksp_rtol 1e-8: the answers agree to far below the discretisation error (0.1 %)
    assert abs(w_gamg - w_direct) <= 1e-7 * abs(w_direct)
    its = gamg.timings.linear_iterations
    _, plain = _solve(LINEAR_SOLVERS["gamg"], near=False)
    assert its < 0.5 * plain.timings.linear_iterations, (its, plain.timings.linear_iterations)
