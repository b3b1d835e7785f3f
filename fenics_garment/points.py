"""Values of finite element functions at fixed points, located once and evaluated many times.

A point value u(x) = Σ_j φ_j(X) u_j needs the cell K that contains x, the reference coordinates
X = F_K⁻¹(x) of x in K (a Newton solve for curved cells; on a surface mesh the least-squares
foot point) and the basis values φ_j(X). The first two depend only on the mesh and the points,
the third only on the element: :class:`PointEvaluator` computes them once, so a repeated
evaluation (a monitor at every load step, a probe on a path) costs one gather of the cell's
coefficients and a small dot product per point.

In parallel every point is owned by exactly one rank (DOLFINx's
``determine_point_ownership``: the rank whose cell contains it, the lowest one on a shared
boundary); the owner evaluates and the values are summed over the ranks, so the result is
identical on every rank.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from fenics_garment._stack import MPI, dolfinx


class PointEvaluator:
    """Evaluate functions on ``mesh`` at ``points`` (n, 3), given alike on every rank.

    ``padding``: how far (in the mesh's units) a point may lie from a cell and still be found
    (points of a curved surface rarely lie exactly on its faceted or quadratic cells).
    ``evaluator(f)`` returns an (n, value size) array, identical on every rank.
    """

    def __init__(self, mesh: dolfinx.mesh.Mesh, points: npt.ArrayLike, *, padding: float = 1e-6):
        pts = np.atleast_2d(np.asarray(points, dtype=np.float64))
        if pts.ndim != 2 or pts.shape[1] != 3 or not np.all(np.isfinite(pts)):
            raise ValueError(f"points must be finite and of shape (n, 3), got shape {pts.shape}")
        self.mesh = mesh
        self.points = pts
        comm = mesh.comm
        # rank 0 asks for all points; each is sent to the one rank that owns it
        query = pts if comm.rank == 0 else np.zeros((0, 3))
        own = dolfinx.geometry.determine_point_ownership(mesh, query, padding)
        owner = comm.bcast(np.asarray(own.src_owner, dtype=np.int64), root=0)
        if np.any(owner < 0):
            raise ValueError(f"points not found on the mesh (padding {padding}): {pts[owner < 0]}")
        #: indices (into ``points``) of the points this rank evaluates, and their cells
        self.index = np.flatnonzero(owner == comm.rank)
        self.cells = np.asarray(own.dest_cells, dtype=np.int32)
        found = np.asarray(own.dest_points, dtype=np.float64).reshape(-1, 3)
        if len(found) != len(self.index) or not np.allclose(found, pts[self.index], atol=1e-12):
            # the owned points come back in the order they were asked; match them if not
            near = np.linalg.norm(pts[None, :, :] - found[:, None, :], axis=2).argmin(axis=1)
            self.index = near
        self.reference = self._pull_back()
        # per space (held, so that its id is not reused): (φ_j(X_i), cell dofs) or None
        self._basis: dict[int, tuple] = {}

    def _pull_back(self) -> np.ndarray:
        """Reference coordinates X of each owned point in its cell (once, per point)."""
        geo = self.mesh.geometry
        cmap, dofmap = geo.cmaps[0], geo.dofmaps[0]
        tdim = self.mesh.topology.dim
        X = np.zeros((len(self.cells), tdim))
        for i, (p, c) in enumerate(zip(self.points[self.index], self.cells, strict=True)):
            X[i] = cmap.pull_back(p[None, :], geo.x[dofmap[c]])[0]
        return X

    def _fast_path(self, V: dolfinx.fem.FunctionSpace) -> tuple[np.ndarray, np.ndarray] | None:
        """(basis values φ_j(X_i), cell dofs) for a collapsed space of an identity-mapped element
        without dof transformations (Lagrange, bubble-enriched Lagrange, blocked); None for
        others (they go through ``Function.eval``)."""
        key = id(V)
        if key not in self._basis:
            self._basis[key] = (V, None)
            element = V.ufl_element()
            scalar = element.sub_elements[0] if V.dofmap.bs > 1 else element
            simple = (
                not V.component()
                and not V.element.needs_dof_transformations
                and V.mesh is self.mesh
                and getattr(scalar, "map_type", None) is not None
                and scalar.map_type.name == "identity"
                and scalar.reference_value_size == 1
            )
            if simple:
                phi = scalar.tabulate(0, self.reference)[0]  # (points, dofs of a cell)
                self._basis[key] = (V, (phi, V.dofmap.list[self.cells]))
        return self._basis[key][1]

    def __call__(self, f: dolfinx.fem.Function) -> np.ndarray:
        V = f.function_space
        if V.mesh is not self.mesh:
            raise ValueError("the function lives on another mesh than this evaluator's")
        size = int(np.prod(f.ufl_shape)) if f.ufl_shape else 1
        local = np.zeros((len(self.points), size))
        if len(self.cells):
            fast = self._fast_path(V)
            if fast is not None:
                phi, dofs = fast
                coeffs = f.x.array.reshape(-1, V.dofmap.bs)[dofs]  # (points, dofs, block)
                local[self.index] = np.einsum("pj,pjc->pc", phi, coeffs)
            else:
                vals = f.eval(self.points[self.index], self.cells)
                local[self.index] = np.asarray(vals).reshape(len(self.cells), size)
        out = np.zeros_like(local)
        self.mesh.comm.Allreduce(local, out, op=MPI.SUM)
        return out
