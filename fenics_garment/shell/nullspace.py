r"""The rigid-body modes of the shell: the near-nullspace an algebraic multigrid needs.

A free shell moves rigidly without strain: three translations and three rotations. For the
*linearised* shell (the Jacobian at any state is close to it where rotations are moderate) an
infinitesimal rigid motion of the mixed unknown q = (u, θ) is

.. math::
    u = c + \omega\times x, \qquad \theta = \omega

(θ is the total rotation vector in global coordinates, :mod:`fenics_garment.shell.kinematics`).
Every strain of the model vanishes to first order for it: with ∇u = ω̂P and δd = ω×d₀,
δε_αβ = sym(e_α·ω̂e_β) = 0 (skew), δγ_α = (ω×e_α)·d₀ + e_α·(ω×d₀) = 0, δκ_αβ likewise, and the
drilling strain ½(R e₁·F e₂ − R e₂·F e₁) has the linear part ½(2ω·(e₁×e₂) − 2ω·(e₁×e₂)) = 0.
So the six fields span the kernel of the unsupported shell's stiffness K (checked in
``tests/test_nullspace.py``: ‖K v‖ ≈ 1e-16 ‖K‖‖v‖).

Smoothed-aggregation AMG (PETSc GAMG) builds its coarse spaces from these vectors restricted to
aggregates; with the default (constant) near-nullspace it would only know 1 of the 6 modes per
unknown and the shell solve stalls (measured: GMRES + GAMG does not converge in 500 iterations on
the Scordelis–Lo roof without them).

The vectors are interpolated into the sub-spaces of the mixed space (P2 + cubic bubble is exact
for the linear field ω×x on a geometry of degree ≤ 2: the bubble coefficients are 0), so they sit
on the correct dofs of the mixed layout whatever the element.

The matrix keeps block size 1: DOLFINx numbers the x, y, z dofs of one node of u or θ as aligned
triples, but a block size set on its assembled matrix breaks the next assembly (the local-to-global
map stays scalar: measured, the reassembled Jacobian differed by 40× its norm), and GAMG with
block size 3 took as many iterations (Scordelis–Lo 16×16: 202 against 197) as with 1.
"""

from __future__ import annotations

import numpy as np

from fenics_garment._stack import PETSc, dolfinx


def rigid_body_fields(Q: dolfinx.fem.FunctionSpace) -> list[dolfinx.fem.Function]:
    """The six rigid-body modes as Functions of the mixed (u, θ) space ``Q``: translations along
    e₁, e₂, e₃ (θ = 0), then rotations about e₁, e₂, e₃ through the origin (u = ω×x, θ = ω)."""
    modes = []
    for k in range(6):
        q = dolfinx.fem.Function(Q)
        axis = np.zeros(3)
        axis[k % 3] = 1.0
        if k < 3:
            q.sub(0).interpolate(lambda x, a=axis: np.outer(a, np.ones(x.shape[1])))
        else:
            q.sub(0).interpolate(lambda x, a=axis: np.cross(a, x.T).T)
            q.sub(1).interpolate(lambda x, a=axis: np.outer(a, np.ones(x.shape[1])))
        q.x.scatter_forward()
        modes.append(q)
    return modes


def _centred(Q: dolfinx.fem.FunctionSpace) -> np.ndarray:
    """The centroid of the mesh nodes (all ranks): rotations about it are better conditioned
    than about a far origin (the vectors are orthonormalised anyway, but x ≈ 1e3 m coordinates
    would cancel digits)."""
    x = Q.mesh.geometry.x
    n = Q.mesh.geometry.index_map().size_local
    comm = Q.mesh.comm
    s = comm.allreduce(x[:n].sum(axis=0))
    return s / comm.allreduce(n)


def near_nullspace(Q: dolfinx.fem.FunctionSpace) -> PETSc.NullSpace:
    """The rigid-body modes as an orthonormal PETSc ``NullSpace`` for ``Mat.setNearNullSpace``.

    Rotations are taken about the centroid of the mesh (the span is the same as about the
    origin; only the conditioning differs). The vectors are orthonormalised (modified
    Gram–Schmidt) as PETSc expects.
    """
    c = _centred(Q)
    modes = rigid_body_fields(Q)
    # rotations about c: u = ω×(x − c) = ω×x − ω×c, i.e. subtract the translation ω×c
    for k in range(3):
        axis = np.zeros(3)
        axis[k] = 1.0
        shift = np.cross(axis, c)
        for i in range(3):
            modes[3 + k].x.array[:] -= shift[i] * modes[i].x.array
    imap = Q.dofmap.index_map
    n = imap.size_local * Q.dofmap.index_map_bs
    vecs = []
    for q in modes:
        v = PETSc.Vec().createMPI((n, PETSc.DETERMINE), comm=Q.mesh.comm)
        v.array[:] = q.x.array[:n]
        vecs.append(v)
    for i, v in enumerate(vecs):  # modified Gram–Schmidt
        for w in vecs[:i]:
            v.axpy(-v.dot(w), w)
        v.normalize()
    return PETSc.NullSpace().create(vectors=vecs, comm=Q.mesh.comm)
