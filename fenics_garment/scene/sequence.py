"""Mesh sequencing of the dressing: the path on a coarser garment mesh, the answer on the scene's.

Most of a dressing's Newton iterations follow the path — the body grows back through its shrink
steps and the spring is released — and only the last solves are the answer. On a converged
(fine) garment mesh every one of them costs a factorisation of the full Jacobian. With
``[dressing] sequence = [h₁, …]`` the whole dressing runs on the garment meshed at h₁ (then h₂,
…, each finer), and each level's dressed state is carried over to the next: the fine level only
settles from it — a short release of a spring anchored at the carried state, the c = 0 solve
and the multiplier passes, all at the fine mesh and its tolerances — so the answer is an
equilibrium of the fine discretisation (nested iteration; e.g. Kelley, *Iterative Methods for
Linear and Nonlinear Equations*, SIAM 1995, §8.4 "mesh independence", and PETSc's
``-snes_grid_sequence``).

What is carried over (:func:`carry_over`):

* the displacement and rotation: the coarse fields interpolated into the fine spaces (evaluated
  at the fine element's interpolation points, each projected onto the nearest coarse cell, at
  most :data:`PADDING` away: :class:`_Coarse`);
* the contact state at each fine contact point, interpolated the same way from the coarse
  contact points (those of the nodal rules are Lagrange nodes: :func:`_nodal_field`): the
  augmented-Lagrangian multiplier and the friction's elastic slip e = u_k − u_old (the anchor is
  then u_old = u_k − e, so a sticking point carries its tangential traction on, as between two
  accepted steps: ``ContactState.accept_step``), and the penalty raise of the coarse passes;
* the spring's anchor: the carried state.

With friction the answer depends on the path; here the path is the coarse mesh's and the fine
level adds its own short release, so a sequenced answer is a different (path) discretisation
of the same problem. How far it moves the regions' pressures is measured against the direct
dressing on the same mesh (docs/verification/performance.md, "Mesh sequencing").
"""

from __future__ import annotations

from dataclasses import replace

import basix
import numpy as np
from scipy.spatial import cKDTree

from fenics_garment._stack import MPI, dolfinx
from fenics_garment.scene.config import Scene
from fenics_garment.scene.dressing import DressReport, Progress

#: How far [m] a fine P2 node may lie from the coarse garment surface and still be found: the two
#: quadratic meshes of one curved pattern differ by far less than this.
PADDING = 2e-3


def coarse_scenes(scene: Scene) -> list[Scene]:
    """The scene at each garment mesh size of ``[dressing] sequence`` that is coarser than the
    scene's own (the loader requires all to be; a scene made coarser in code, e.g. the coarse
    level of ``--error-bars``, drops the rest), coarsest first, with no outputs and no sequence
    of their own."""
    out = replace(
        scene.output, vtx=False, xdmf=False, pictures=False, error_bars=False, report=False
    )
    d = replace(scene.dressing, sequence=[])
    g = scene.garment

    def level(h: float) -> Scene:
        per_turn = max(8, round(g.per_turn * g.mesh_size / h))
        return replace(scene, garment=replace(g, mesh_size=h, per_turn=per_turn),
                       dressing=d, output=out)  # fmt: skip

    return [level(h) for h in scene.dressing.sequence if h > g.mesh_size]


#: Candidate coarse cells per point (nearest by the centroid of their nodes) and Gauss–Newton
#: passes of the projection onto each (:class:`_Coarse`).
CANDIDATES, PROJECTIONS = 8, 4


class _Coarse:
    """A coarser garment level's reference geometry, replicated on every rank, and the values
    of its functions at any points near it.

    A point is projected onto each of its :data:`CANDIDATES` nearest cells: Gauss–Newton on the
    cell's (curved) coordinate map, its reference coordinates kept inside the triangle, so a
    point beyond the coarse mesh's edge takes the value at the edge; the nearest projection
    wins. Replicated (a level's cells are a few thousand), every rank locates its own points
    with no communication: DOLFINx's non-matching interpolation, which sends each point to a
    rank whose cell holds it, failed its pull-back on 2 ranks for points near the curved
    armholes of the dress at 31.8 mm."""

    def __init__(self, mesh: dolfinx.mesh.Mesh):
        self.comm = mesh.comm
        n = mesh.topology.index_map(mesh.topology.dim).size_local
        self.n_owned = n
        g = mesh.geometry
        cmap = g.cmaps[0]
        self.coordinate = basix.create_element(
            basix.ElementFamily.P, basix.CellType.triangle, cmap.degree,
            basix.LagrangeVariant(int(cmap.variant)),
        )  # fmt: skip
        self.nodes = _gather(self.comm, g.x[g.dofmaps[0][:n]])  # (cells, nodes, 3)
        self.tree = cKDTree(self.nodes.mean(axis=1))
        self._located: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def locate(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(cell, reference coordinates) of the nearest point of the coarse surface to each
        of the points ``x`` (n, 3); the last call's answer is kept (the fields of one fine
        element share their points)."""
        if self._located is not None and np.array_equal(self._located[0], x):
            return self._located[1:]
        k = min(CANDIDATES, len(self.nodes))
        cand = self.tree.query(x, k)[1].reshape(len(x), k)
        pts = np.repeat(x, k, axis=0)
        nodes = self.nodes[cand.ravel()]  # (n k, nodes, 3)
        X = np.full((len(pts), 2), 1.0 / 3.0)
        for _ in range(PROJECTIONS):
            tab = self.coordinate.tabulate(1, X)[:, :, :, 0]  # (3, n k, nodes)
            y = np.einsum("pj,pjd->pd", tab[0], nodes)
            J = np.stack([np.einsum("pj,pjd->pd", tab[i], nodes) for i in (1, 2)], axis=2)
            JtJ = np.einsum("pdi,pdj->pij", J, J)
            step = np.linalg.solve(JtJ, np.einsum("pdi,pd->pi", J, pts - y)[..., None])[..., 0]
            X = _into_triangle(X + step)
        y = np.einsum("pj,pjd->pd", self.coordinate.tabulate(0, X)[0, :, :, 0], nodes)
        dist = np.linalg.norm(pts - y, axis=1).reshape(len(x), k)
        best = dist.argmin(axis=1)
        rows = np.arange(len(x))
        far = float(dist[rows, best].max()) if len(x) else 0.0
        if self.comm.allreduce(far, op=MPI.MAX) > PADDING:
            raise SequenceError(
                f"points of the finer garment mesh lie up to "
                f"{1e3 * self.comm.allreduce(far, op=MPI.MAX):.2g} mm from the coarser one "
                f"(more than {PADDING * 1e3:g} mm): the levels are not meshes of one surface"
            )  # fmt: skip
        cells = cand[rows, best]
        Xb = X.reshape(len(x), k, 2)[rows, best]
        self._located = (x.copy(), cells, Xb)
        return cells, Xb

    def interpolate(self, f: dolfinx.fem.Function, V: dolfinx.fem.FunctionSpace):
        """The coarse Function ``f`` interpolated into the fine space ``V``."""
        element = f.function_space.ufl_element()
        scalar = element.sub_elements[0] if element.num_sub_elements else element
        bs = f.function_space.dofmap.bs
        dofs = f.function_space.dofmap.list[: self.n_owned]
        values = _gather(self.comm, f.x.array.reshape(-1, bs)[dofs])  # (cells, dofs, bs)

        def at(x: np.ndarray) -> np.ndarray:
            cells, X = self.locate(np.ascontiguousarray(x.T))
            phi = scalar.tabulate(0, X)[0]  # (points, dofs)
            return np.einsum("pj,pjb->bp", phi, values[cells])

        target = dolfinx.fem.Function(V)
        target.interpolate(at)
        target.x.scatter_forward()
        return target


def _into_triangle(X: np.ndarray) -> np.ndarray:
    """Reference coordinates moved into the reference triangle (ξ₁, ξ₂ ≥ 0, ξ₁ + ξ₂ ≤ 1)."""
    X = np.maximum(X, 0.0)
    s = X.sum(axis=1, keepdims=True)
    return np.where(s > 1.0, X / np.maximum(s, 1e-300), X)


def _gather(comm: MPI.Comm, a: np.ndarray) -> np.ndarray:
    return np.concatenate(comm.allgather(np.ascontiguousarray(a)), axis=0)


def _nodal_field(state, values: np.ndarray, shape: tuple[int, ...]) -> dolfinx.fem.Function:
    """The point values ``values`` (in :meth:`ContactState.local_values` order) of a nodal
    contact rule as a Lagrange Function: the rule's vertex (and edge-midpoint) points are the
    nodes of P1 (P2), in the reference cell's order that DOLFINx's dofs follow too."""
    degree = {"vertex": 1, "vertex+edge": 2, "lumped": 2}.get(state.rule)
    if degree is None:
        raise SequenceError(f"mesh sequencing needs a nodal contact rule, not {state.rule!r}")
    V = dolfinx.fem.functionspace(state.mesh, ("Lagrange", degree, shape))
    f = dolfinx.fem.Function(V)
    dofs = V.dofmap.list[state.owned_cells]  # (cells, nodes)
    bs = V.dofmap.bs
    per_cell = np.reshape(values, (len(state.owned_cells), len(state.points), bs))
    f.x.array.reshape(-1, bs)[dofs] = per_cell[:, : dofs.shape[1]]
    f.x.scatter_forward()
    return f


def carry_over(coarse, fine) -> None:
    """Put the dressed state of ``coarse`` (a :class:`~fenics_garment.scene.build.Built`) into
    ``fine`` (the same scene on a finer garment mesh; module doc). Both contact states are
    refreshed at their displacement first (the fine one's gap, normal and u_k are then those of
    the carried state)."""
    cs, fs = coarse.contact.state, fine.contact.state
    q = fine.model.q
    transfer = _Coarse(coarse.model.geometry.mesh)
    for i in range(q.function_space.num_sub_spaces):  # displacement, rotation
        V, dofs = q.function_space.sub(i).collapse()
        q.x.array[dofs] = transfer.interpolate(coarse.model.q.sub(i).collapse(), V).x.array
    q.x.scatter_forward()
    cs.refresh()
    fs.refresh()
    vector, scalar = (q.function_space.sub(0).collapse()[0],
                      q.function_space.sub(0).sub(0).collapse()[0])  # fmt: skip

    def carried(values: np.ndarray, V: dolfinx.fem.FunctionSpace) -> np.ndarray:
        """Coarse contact-point values at the fine contact points (``local_values`` order)."""
        source = _nodal_field(cs, values, V.value_shape)
        return fs.evaluate(transfer.interpolate(source, V)).reshape(-1, *V.value_shape)

    fs.set_local_values(fs.lam, carried(cs.local_values(cs.lam), scalar))
    slip = cs.local_values(cs.u_k) - cs.local_values(cs.u_old)  # the elastic slip e
    fs.set_local_values(fs.u_old, fs.local_values(fs.u_k) - carried(slip, vector))
    fine.regularisation.place(q)


class SequenceError(ValueError):
    """The garment levels of a mesh sequence do not fit together."""


def settling(fine, levels: list[dict], stiffening: float = 1.0) -> Progress:
    """Where the dressing of ``fine`` starts once a coarser level's state is carried over: the
    release, at ``sequence_spring`` × c₀ (the spring anchored at the carried state), with
    friction on and the contact penalty raised by the factor ``stiffening`` by which the coarser
    level's multiplier passes raised theirs; ``levels``: the coarser levels' records
    (``DressReport.levels``)."""
    c = fine.scene.dressing.sequence_spring * fine.regularisation.c0
    report = DressReport(levels=levels, final_regularisation=c)
    mu = float(fine.mu.value) if fine.mu is not None else 0.0
    kappa = stiffening * float(fine.contact.kappa.value)
    return Progress(report, stage="release", c=c, mu=mu, kappa=kappa)


def reset(built, kappa: float) -> None:
    """Put ``built`` back to the undressed pattern with the contact penalty ``kappa`` (after a
    settling that failed, before the direct dressing)."""
    st, reg = built.contact.state, built.regularisation
    for f in (built.model.q, st.lam, st.u_old, st.gap_old, st.u_k, reg.q_prev):
        f.x.array[:] = 0.0
        f.x.scatter_forward()
    built.contact.kappa.value = kappa
    reg.c.value = reg.c0
    st.refresh()
