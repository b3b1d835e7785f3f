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

* the displacement and rotation: the coarse fields interpolated into the fine spaces
  (``interpolate_nonmatching``: evaluated at the fine element's interpolation points, each
  located in the coarse mesh within :data:`PADDING` of its surface);
* the contact state at each fine contact point, from the coarse contact point nearest in the
  reference configuration: the augmented-Lagrangian multiplier and the friction's elastic slip
  e = u_k − u_old (the anchor is then u_old = u_k − e, so a sticking point carries its tangential
  traction on, as between two accepted steps: ``ContactState.accept_step``);
* the spring's anchor: the carried state.

With friction the answer depends on the path; here the path is the coarse mesh's and the fine
level adds its own short release, so a sequenced answer is a different (path) discretisation
of the same problem. How far it moves the regions' pressures is measured against the direct
dressing on the same mesh (README, "Mesh sequencing").
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from fenics_garment._stack import MPI, dolfinx
from fenics_garment.scene.config import Scene
from fenics_garment.scene.dressing import DressReport, Progress

#: How far [m] a fine P2 node may lie from the coarse garment surface and still be found: the two
#: quadratic meshes of one curved pattern differ by far less than this.
PADDING = 2e-3


def coarse_scenes(scene: Scene) -> list[Scene]:
    """The scene at each garment mesh size of ``[dressing] sequence``, coarsest first, with no
    outputs and no sequence of their own."""
    out = replace(scene.output, vtx=False, xdmf=False, pictures=False, error_bars=False)
    d = replace(scene.dressing, sequence=())
    g = scene.garment

    def level(h: float) -> Scene:
        per_turn = max(8, round(g.per_turn * g.mesh_size / h))
        return replace(scene, garment=replace(g, mesh_size=h, per_turn=per_turn),
                       dressing=d, output=out)  # fmt: skip

    return [level(h) for h in scene.dressing.sequence]


class _Transfer:
    """Interpolation from the coarse garment mesh into the fine one's displacement element (and
    any space with its interpolation points): the fine points are located in the coarse mesh
    once (within :data:`PADDING`; a point found in no coarse cell is an error, not a silent
    zero), as locating them is most of the cost (≈ 1.8 s at 268k dofs on 2 ranks)."""

    def __init__(self, coarse_q: dolfinx.fem.Function, fine_q: dolfinx.fem.Function):
        self.V = fine_q.function_space.sub(0).collapse()[0]
        mesh = self.V.mesh
        tdim = mesh.topology.dim
        self.cells = np.arange(mesh.topology.index_map(tdim).size_local, dtype=np.int32)
        source = coarse_q.function_space.sub(0).collapse()[0]
        self.data = dolfinx.fem.create_interpolation_data(self.V, source, self.cells, PADDING)
        lost = int(np.count_nonzero(np.asarray(self.data.src_owner) < 0))
        if mesh.comm.allreduce(lost, op=MPI.SUM):
            raise SequenceError(
                f"{lost} points of the finer garment mesh lie farther than {PADDING * 1e3:g} mm "
                "from the coarser one: the garment levels are not meshes of one surface"
            )

    def __call__(self, source: dolfinx.fem.Function, V: dolfinx.fem.FunctionSpace):
        """``source`` interpolated into ``V`` (a fine space with :attr:`V`'s points)."""
        target = dolfinx.fem.Function(V)
        target.interpolate_nonmatching(source, self.cells, self.data)
        target.x.scatter_forward()
        return target


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
    ``fine`` (the same scene on a finer garment mesh; module doc). Both states are refreshed."""
    cs, fs = coarse.contact.state, fine.contact.state
    q = fine.model.q
    transfer = _Transfer(coarse.model.q, q)
    for i in range(q.function_space.num_sub_spaces):  # displacement, rotation
        V, dofs = q.function_space.sub(i).collapse()
        q.x.array[dofs] = transfer(coarse.model.q.sub(i).collapse(), V).x.array
    q.x.scatter_forward()
    cs.refresh()
    fs.refresh()
    scalar = q.function_space.sub(0).sub(0).collapse()[0]

    def carried(values: np.ndarray, V: dolfinx.fem.FunctionSpace) -> np.ndarray:
        """Coarse contact-point values at the fine contact points (``local_values`` order)."""
        source = _nodal_field(cs, values, V.value_shape)
        return fs.evaluate(transfer(source, V)).reshape(-1, *V.value_shape)

    fs.set_local_values(fs.lam, carried(cs.local_values(cs.lam), scalar))
    slip = cs.local_values(cs.u_k) - cs.local_values(cs.u_old)  # the elastic slip e
    fs.set_local_values(fs.u_old, fs.local_values(fs.u_k) - carried(slip, transfer.V))
    fs.refresh()
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
    for f in (built.model.q, st.lam, st.u_old, st.u_k, reg.q_prev):
        f.x.array[:] = 0.0
        f.x.scatter_forward()
    built.contact.kappa.value = kappa
    reg.c.value = reg.c0
    st.refresh()
