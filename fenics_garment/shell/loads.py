"""Point loads. DOLFINx has no point source, so a point force is put into the residual vector.

The virtual work of a force P at the point x₀ is P·δu(x₀) = Σᵢ P·φᵢ(x₀) δuᵢ: each basis function
of the displacement space contributes with its value at x₀. The rank that owns the cell containing
x₀ tabulates the basis there (``determine_point_ownership`` + pull-back), so it works for any point
of the surface, on any number of ranks, and with enriched (bubble) elements.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fenics_garment._stack import MPI, PETSc, dolfinx, ufl


@dataclass
class PointLoad:
    """A dead force ``force`` (N) applied at ``point`` of the shell, scaled by the load factor."""

    point: tuple[float, float, float]
    force: tuple[float, float, float]


def point_load_vector(model, loads: list[PointLoad]) -> PETSc.Vec:
    """The assembled vector f with fᵢ = Σ P·φᵢ(x₀) over the point loads (λ = 1)."""
    Q = model.Q
    mesh = model.geometry.mesh
    f = dolfinx.fem.petsc.create_vector(Q)
    f.zeroEntries()
    comm = mesh.comm
    pts = np.array([lp.point for lp in loads], dtype=np.float64).reshape(-1, 3)
    # Only rank 0 asks; the owner of each point answers.
    query = pts if comm.rank == 0 else np.zeros((0, 3))
    own = dolfinx.geometry.determine_point_ownership(mesh, query, 1e-6)
    cells = np.asarray(own.dest_cells, dtype=np.int32)
    dest_pts = np.asarray(own.dest_points, dtype=np.float64).reshape(-1, 3)
    n_found = comm.allreduce(len(cells), op=MPI.SUM)
    if n_found < len(loads):
        raise ValueError(f"point loads off the mesh: {[lp.point for lp in loads]}")
    if len(cells):
        geom = mesh.geometry
        for cell, x0 in zip(cells, dest_pts, strict=True):
            X = geom.x[geom.dofmaps[0][cell]]
            ref = geom.cmaps[0].pull_back(x0.reshape(1, 3), X)
            force = np.array(_loads_by_nearest(loads, x0).force)
            for comp in range(3):
                sub = Q.sub(0).sub(comp)
                trial = ufl.TrialFunction(sub)
                expr = dolfinx.fem.Expression(trial, ref, comm=MPI.COMM_SELF)
                vals = expr.eval(mesh, np.array([cell], dtype=np.int32)).reshape(-1)
                dofs = sub.dofmap.cell_dofs(cell)
                bs = sub.dofmap.bs
                idx = np.array([d * bs + k for d in dofs for k in range(bs)], dtype=np.int32)
                # The sub-space's dofmap indexes the parent (mixed) vector directly.
                with f.localForm() as fl:
                    fl.setValues(idx[: len(vals)], force[comp] * vals[: len(idx)],
                                 addv=PETSc.InsertMode.ADD_VALUES)  # fmt: skip
    f.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    return f


def _loads_by_nearest(loads: list[PointLoad], x0: np.ndarray) -> PointLoad:
    d = [np.linalg.norm(np.asarray(lp.point) - x0) for lp in loads]
    return loads[int(np.argmin(d))]
