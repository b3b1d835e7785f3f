r"""A flat stress-free rest state: the shell's reference metric from sewing-pattern panels.

A woven garment is cut from flat panels. Its mesh, however, is the garment placed around the
body (sewn, curved). The *flat map* Y: mesh → ℝ² gives, on every cell, the flat coordinates of
its points in the cell's panel (x along the panel's grain, the warp; y across it, the weft). It is
a discontinuous P2 field: continuous inside a panel, jumping at seams and darts, where two panels'
coordinates meet.

With ∇Y the 2×3 tangential gradient of Y, the rest metric pulled back to the mesh is
G = ∇Y ∇Yᵀ, and the tangent vectors that are unit warp and weft *of the flat fabric* are

.. math::
    a_\alpha = \nabla Y^T G^{-1} f_\alpha, \qquad f_1 = (1, 0),\; f_2 = (0, 1),

so that ∇Y a_α = f_α. Used as the frame of the strains (:mod:`.kinematics`), they make
ε_αβ = ½(F a_α·F a_β − δ_αβ) the Green–Lagrange strain *from the flat panel*; the energy
densities are per unit flat area, so they are integrated with dA_flat = j dA_mesh,
j = √det G. The rest curvature is zero: κ_αβ = sym(F a_α·∇d a_β), without the subtraction of
the mesh's own curvature that makes a curved mesh stress free.

A mesh that is an isometric image of the panels (a rectangle wrapped on a cylinder) starts with
no membrane strain and with the bending strain of its curvature; a doubly curved placement
starts with the membrane strain that the flat fabric needs to take that shape.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fenics_garment._stack import dolfinx, ufl

#: degree of the flat map: that of a curved (order-2) mesh's coordinate element
FLAT_DEGREE = 2


def flat_space(mesh: dolfinx.mesh.Mesh) -> dolfinx.fem.FunctionSpace:
    """Discontinuous P2 with two components: the space of the flat map."""
    return dolfinx.fem.functionspace(mesh, ("DG", FLAT_DEGREE, (2,)))


def _cell_count(mesh: dolfinx.mesh.Mesh) -> int:
    imap = mesh.topology.index_map(mesh.topology.dim)
    return imap.size_local + imap.num_ghosts


def flat_map_from_cells(mesh: dolfinx.mesh.Mesh, values: npt.ArrayLike) -> dolfinx.fem.Function:
    """The flat map from per-cell values: ``values[c, i]`` the flat (x, y) of geometry node i of
    local cell c (owned and ghost cells, DOLFINx's geometry dof order).

    The DG P2 dofs of a cell and its geometry nodes are the same reference points in the same
    order (both are degree-2 Lagrange on the cell; :func:`check_dof_layout` verifies it).
    """
    V = flat_space(mesh)
    n = _cell_count(mesh)
    vals = np.asarray(values, dtype=np.float64)
    ndof = V.dofmap.cell_dofs(0).size if n else 0
    if vals.shape != (n, ndof, 2):
        raise ValueError(f"flat map: values of shape {vals.shape}, expected {(n, ndof, 2)}")
    Y = dolfinx.fem.Function(V, name="flat")
    dofs = V.dofmap.list[:n]
    Y.x.array.reshape(-1, 2)[dofs.reshape(-1)] = vals.reshape(-1, 2)
    return Y


def check_dof_layout(mesh: dolfinx.mesh.Mesh) -> float:
    """Largest distance between a DG P2 dof's point and the geometry node it is paired with
    (0 when :func:`flat_map_from_cells`'s pairing holds)."""
    V = dolfinx.fem.functionspace(mesh, ("DG", FLAT_DEGREE, (3,)))
    f = dolfinx.fem.Function(V)
    f.interpolate(lambda x: x)
    n = _cell_count(mesh)
    g = mesh.geometry.x[mesh.geometry.dofmaps[0][:n]]
    d = f.x.array.reshape(-1, 3)[V.dofmap.list[:n]]
    return float(np.abs(g - d).max()) if n else 0.0


@dataclass(eq=False)
class FlatCells:
    """The flat coordinates of every cell's nodes, as a mesh generator gives them: for input
    (original) cell k, the input node indices ``cell_nodes[k]`` (0-based, e.g. gmsh's node
    ids − 1, any order) and their flat (x, y) ``cell_flat[k]`` [m], x along the grain. Every
    rank holds the whole arrays (small next to the mesh)."""

    cell_nodes: npt.NDArray[np.int64]
    cell_flat: npt.NDArray[np.float64]
    #: the garment panel tag of each input cell (None: not known)
    cell_panel: npt.NDArray[np.int32] | None = None

    def on_mesh(self, mesh: dolfinx.mesh.Mesh) -> np.ndarray:
        """(local cells incl. ghosts, nodes per cell, 2): the flat coordinates in the order of
        the DOLFINx geometry dofmap (matched by input node index: DOLFINx may reorder)."""
        cn = np.asarray(self.cell_nodes, dtype=np.int64)
        cf = np.asarray(self.cell_flat, dtype=np.float64)
        n = _cell_count(mesh)
        orig = np.asarray(mesh.topology.original_cell_index, dtype=np.int64)[:n]
        gidx = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)
        node_ids = gidx[mesh.geometry.dofmaps[0][:n]]  # (n, k) input ids in DOLFINx order
        match = node_ids[:, :, None] == cn[orig][:, None, :]
        if not np.all(match.sum(axis=2) == 1):
            raise ValueError("flat map: a cell's nodes do not match the generator's cell")
        pos = match.argmax(axis=2)
        return np.take_along_axis(cf[orig], pos[:, :, None], axis=1)

    def flat_map(self, mesh: dolfinx.mesh.Mesh) -> dolfinx.fem.Function:
        """The flat map Y on ``mesh``."""
        return flat_map_from_cells(mesh, self.on_mesh(mesh))


def flat_map_from_function(
    mesh: dolfinx.mesh.Mesh,
    f: Callable[[np.ndarray], np.ndarray],
    period: tuple[float | None, float | None] = (None, None),
) -> dolfinx.fem.Function:
    """The flat map from a formula ``f(x) -> (2, N)`` of the mesh points (verification meshes).

    ``period``: a coordinate of Y that jumps by this period across a seam (a rectangle wrapped
    into a tube: x = Rθ with period 2πR) is unwrapped per cell, so that each cell sees its own
    panel's continuous coordinates.
    """
    n = _cell_count(mesh)
    x = mesh.geometry.x[mesh.geometry.dofmaps[0][:n]]  # (n, k, 3)
    vals = np.asarray(f(x.reshape(-1, 3).T), dtype=np.float64).T.reshape(n, -1, 2)
    for c, p in enumerate(period):
        if p:
            v = vals[:, :, c]
            ref = v[:, :1]
            vals[:, :, c] = ref + (v - ref + 0.5 * p) % p - 0.5 * p
    return flat_map_from_cells(mesh, vals)


class FlatRest:
    """The UFL side of a flat map Y: the flat warp/weft frame, the area ratio j and G."""

    def __init__(self, Y: dolfinx.fem.Function) -> None:
        self.Y = Y
        #: the sewing parameter w ∈ [0, 1]: the rest metric and curvature are w × the flat
        #: panels' + (1 − w) × the mesh's (w = 0: the placed mesh is stress free; the
        #: dressing raises w to 1 before it grows the body, ``scene.dressing``)
        self.sewn = dolfinx.fem.Constant(Y.function_space.mesh, dolfinx.default_scalar_type(1.0))

    @property
    def grad(self) -> ufl.core.expr.Expr:
        """∇Y, 2×3 (tangential gradient on the surface mesh)."""
        return ufl.grad(self.Y)

    @property
    def metric(self) -> ufl.core.expr.Expr:
        """G = ∇Y ∇Yᵀ (2×2): the flat panel's metric in the mesh's tangent plane."""
        g = self.grad
        return g * g.T

    @property
    def area_ratio(self) -> ufl.core.expr.Expr:
        """j = dA_flat / dA_mesh = √det G."""
        return ufl.sqrt(ufl.det(self.metric))

    def frame(self, normal: ufl.core.expr.Expr) -> tuple[ufl.core.expr.Expr, ufl.core.expr.Expr]:
        """(a₁, a₂) = ∇Yᵀ G⁻¹ (f₁, f₂): tangent vectors that are the flat warp and weft, unit
        and orthogonal in the flat metric; a₂ is flipped where (a₁, a₂, n) is left handed (a
        panel mirrored in the placement), so that F a₁ × F a₂ points along the oriented normal."""
        a1, a2 = self._tangents()
        return a1, self.handedness(normal) * a2

    def _tangents(self) -> tuple[ufl.core.expr.Expr, ufl.core.expr.Expr]:
        A = self.grad.T * ufl.inv(self.metric)  # 3×2
        return (ufl.as_vector([A[i, 0] for i in range(3)]),
                ufl.as_vector([A[i, 1] for i in range(3)]))  # fmt: skip

    def handedness(self, normal: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
        """+1 where the flat map keeps the orientation of the oriented normal, −1 where it
        mirrors it (then the strains' second axis is −y of the flat panel)."""
        a1, a2 = self._tangents()
        return ufl.sign(ufl.dot(ufl.cross(a1, a2), normal))
