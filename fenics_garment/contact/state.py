"""Contact points on the garment and their gap / normal Functions, refreshed from the iterate.

The contact points are the points of a quadrature rule on each garment cell (``rule``):

* ``"vertex"`` — the cell vertices, equal weights (nodal enforcement, lumped): measured best for
  P1 (smooth pressure, 3 Newton iterations; see STACK.md "Penalty contact of a tight tube").
* ``"vertex+edge"`` — vertices and edge midpoints, equal weights (nodal enforcement for P2).
* ``"lumped"`` — vertices, edge midpoints and centroid with weights 3/60, 8/60, 27/60 of the
  area: the positive, degree-3 (P2⊕bubble mass-lumping) rule; the choice for the P2B shell.
* ``"gauss<d>"`` — the default Gauss rule of degree ``d`` (over-constrains P1; for comparison).

Every quantity lives in a quadrature-space Function on those points, so the contact terms work
whether the displacement ``u`` is a plain vector Function or ``ufl.split(q)[0]`` of a mixed one:

* ``gap``      g_k = d(x_k) − h/2 − s, signed distance of the current point x_k = X + u_k to the
  body minus the half-thickness offset and the body "shrink" ``s`` (dressing load parameter);
* ``normal``   n_k, the smoothed body normal at the closest point;
* ``u_k``      the displacement at the points when the state was refreshed, so that the gap is
  linearised about the current iterate, g ≈ g_k + n_k·(u − u_k) (exact at u = u_k);
* ``lam``      the augmented-Lagrangian multiplier (normal traction per reference area) [Pa];
* ``u_old``    the displacement at the last converged load step (friction slip increment);
* ``gap_old``  the gap at the last converged load step (the laws' gap rate g − g_old);
* ``hessian``  H_k, the distance's Hessian, for a smooth body only
  (:class:`fenics_garment.contact.smooth.SmoothBody`): the gap is then linearised to second order,
  g ≈ g_k + n_k·δ + ½ δ·H_k δ, and the contact direction is n ≈ n_k + H_k δ, δ = u − u_k, so the
  Jacobian holds the turning of the body normal (consistent: quadratic Newton). On the faceted
  body H_k = 0 almost everywhere and unbounded (1/d) over edges, so it is left out there.
  It is computed at the points where the normal law in use carries traction at the refreshed
  gap (:meth:`ContactState.update_hessian`): the Jacobian needs it exactly there, for any law.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import basix
import basix.ufl
import numpy as np
import numpy.typing as npt

from fenics_garment._stack import dolfinx, ufl
from fenics_garment.contact import laws, terms
from fenics_garment.contact.search import BroadPhase, SearchSurface

F64 = npt.NDArray[np.float64]

#: Passes of the anchor's fixed point (:meth:`ContactState.elastic_slip`) and the traction [Pa]
#: below which a point carries none (its elastic slip is then 0).
ANCHOR_ITERATIONS, TRACTION_FLOOR = 6, 1e-12
#: Points that penetrate deeper than this [m] beyond their gap at the last converged step (or
#: beyond g = 0, if that was open) get no Hessian term: right after a dressing step (millimetres
#: of new penetration, t_N = κ × depth) its −t_N H, a negative stiffness over convex parts, made
#: Newton diverge (SNES −9 on 5 of 19 cotton-gilet steps); converged penetrations are ≤ 0.14 mm
#: with the penalty (README), so every point has it at the end and Newton is quadratic. Measured
#: from the last converged gap, a soft law's own overclosure (an exponential pressure law's
#: millimetre) is not mistaken for a transient.
HESSIAN_DEPTH = 1e-3


def contact_rule(rule: str, cell: str = "triangle") -> tuple[F64, F64]:
    """Reference points and weights of the contact-point rule (see module docstring)."""
    ct = getattr(basix.CellType, cell)
    vertices = np.asarray(basix.geometry(ct), dtype=np.float64)
    volume = basix.cell.volume(ct)
    if rule == "vertex":
        pts = vertices
    elif rule == "vertex+edge":
        edges = basix.topology(ct)[1]
        mids = np.array([0.5 * (vertices[a] + vertices[b]) for a, b in edges])
        pts = np.vstack([vertices, mids])
    elif rule == "lumped":
        edges = basix.topology(ct)[1]
        mids = np.array([0.5 * (vertices[a] + vertices[b]) for a, b in edges])
        pts = np.vstack([vertices, mids, vertices.mean(axis=0, keepdims=True)])
        w = np.array([3.0] * 3 + [8.0] * 3 + [27.0]) / 60.0 * volume
        if cell != "triangle":
            raise ValueError("the 'lumped' rule is for triangles")
        return pts, w
    elif rule.startswith("gauss"):
        pts, wts = basix.make_quadrature(ct, int(rule[5:]))
        return np.asarray(pts, dtype=np.float64), np.asarray(wts, dtype=np.float64)
    else:
        raise ValueError(
            f"unknown contact rule {rule!r}: 'vertex', 'vertex+edge', 'lumped' or 'gauss<d>'"
        )
    return pts, np.full(len(pts), volume / len(pts))


def _point_keys(mesh: dolfinx.mesh.Mesh, cells: npt.NDArray[np.int32], rule: str,
                n_points: int) -> npt.NDArray[np.int64] | None:  # fmt: skip
    """One integer per contact point (cells × points of the rule): equal for the same point.

    The nodal rules' points are cell vertices, then edge midpoints in the reference cell's edge
    order (:func:`contact_rule`), then (``"lumped"``) the centroid. DOLFINx numbers a cell's
    vertices and edges in that same reference order, so a point shared by two cells gets the
    vertex or edge index as its key: vertex v → v, edge e → n_v + e, centroid of cell c →
    n_v + n_e + c. ``None`` for the Gauss rules (no point is shared).

    The garment's position x = X + u is continuous, so both cells of a shared point give the
    same x (to rounding: the two cells' basis functions are evaluated separately).
    """
    if rule not in ("vertex", "vertex+edge", "lumped"):
        return None
    top, tdim = mesh.topology, mesh.topology.dim
    reference = basix.topology(getattr(basix.CellType, top.cell_name()))
    n_vertices, n_edges = len(reference[0]), len(reference[1])
    vertices = top.connectivity(tdim, 0).array.reshape(-1, n_vertices)[cells]
    keys = [vertices.astype(np.int64)]
    n_v = top.index_map(0).size_local + top.index_map(0).num_ghosts
    if rule != "vertex":
        top.create_connectivity(tdim, 1)
        edges = top.connectivity(tdim, 1).array.reshape(-1, n_edges)
        keys.append(n_v + edges[cells].astype(np.int64))
        n_e = top.index_map(1).size_local + top.index_map(1).num_ghosts
        if rule == "lumped":
            keys.append((n_v + n_e + cells.astype(np.int64))[:, None])
    out = np.hstack(keys)
    if out.shape[1] != n_points:  # pragma: no cover - a rule whose layout is not the above
        raise ValueError(f"contact rule {rule!r}: {n_points} points, {out.shape[1]} keys")
    return out


def _unique_points(mesh: dolfinx.mesh.Mesh, cells: npt.NDArray[np.int32], rule: str,
                   n_points: int) -> tuple[np.ndarray, np.ndarray] | None:  # fmt: skip
    """(first, inverse): the contact points searched (one per distinct point, the first cell's
    copy) and, for every point, which of them it is; ``None`` when no point is shared."""
    keys = _point_keys(mesh, cells, rule, n_points)
    if keys is None:
        return None
    return np.unique(keys.ravel(), return_index=True, return_inverse=True)[1:]


@dataclass
class SearchTimings:
    """Accumulated wall time [s] and call counts of the refresh."""

    search_s: float = 0.0
    eval_s: float = 0.0
    refreshes: int = 0
    points: int = 0
    searched: int = 0
    skipped_fraction: float = 0.0


class ContactState:
    """Gap, normal and reference displacement at the garment's contact points.

    Args:
        mesh: the garment mesh (tdim 2, gdim 3).
        u: the garment displacement as a UFL expression (a Function or ``ufl.split(q)[0]``).
        body: the body surface (replicated on every rank, search tree built once).
        offset: distance kept between the garment mid-surface and the skin, h/2 [m].
        rule: contact-point rule (``"vertex"``, ``"vertex+edge"``, ``"lumped"``, ``"gauss<d>"``).
        normal: ``"gradient"`` (default: consistent with the exact distance, so Newton is
            quadratic; the mid-surface is kept h/2 outside the skin, where the distance is C¹ on
            convex parts) or ``"phong"`` (continuous everywhere, also deep inside, but not the
            derivative of the faceted distance: Newton then converges only linearly, ≈ 0.2 per
            iteration on the tube test).
        band: broad-phase band [m]: points provably farther than this are not searched.
    """

    def __init__(
        self,
        mesh: dolfinx.mesh.Mesh,
        u: ufl.core.expr.Expr,
        body: SearchSurface,
        *,
        offset: float,
        rule: str = "vertex",
        normal: str = "gradient",
        band: float = 0.02,
    ) -> None:
        self.mesh, self.body, self.offset, self.normal = mesh, body, offset, normal
        cell = mesh.topology.cell_name()
        self.points, self.weights = contact_rule(rule, cell)
        self.rule = rule
        self.dx = ufl.Measure(
            "dx",
            domain=mesh,
            metadata={
                "quadrature_rule": "custom",
                "quadrature_points": self.points,
                "quadrature_weights": self.weights,
            },
        )
        qs = basix.ufl.quadrature_element(cell, (), points=self.points, weights=self.weights)
        qv = basix.ufl.quadrature_element(cell, (3,), points=self.points, weights=self.weights)
        self.Qs = dolfinx.fem.functionspace(mesh, qs)
        self.Qv = dolfinx.fem.functionspace(mesh, qv)
        self.gap = dolfinx.fem.Function(self.Qs, name="gap")
        self.normal_fn = dolfinx.fem.Function(self.Qv, name="normal")
        self.u_k = dolfinx.fem.Function(self.Qv, name="u_k")
        self.lam = dolfinx.fem.Function(self.Qs, name="multiplier")
        self.u_old = dolfinx.fem.Function(self.Qv, name="u_old")
        self.gap_old = dolfinx.fem.Function(self.Qs, name="gap_old")
        self.hessian: dolfinx.fem.Function | None = None
        if body.smooth:
            qt = basix.ufl.quadrature_element(
                cell, (3, 3), points=self.points, weights=self.weights
            )
            self.hessian = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, qt), name="H")
        self.shrink = dolfinx.fem.Constant(mesh, 0.0)  # dressing: body shrunk by s [m]
        self.u = u
        x = ufl.SpatialCoordinate(mesh)
        self._x_expr = dolfinx.fem.Expression(x + u, self.points)
        self._u_expr = dolfinx.fem.Expression(u, self.points)
        n_owned = mesh.topology.index_map(mesh.topology.dim).size_local
        self._cells = np.arange(n_owned, dtype=np.int32)
        self._dofs = self.Qs.dofmap.list[self._cells].ravel()
        self._broad = BroadPhase(band=band)
        self._unique = _unique_points(mesh, self._cells, rule, len(self.points))
        self._pending: tuple | None = None  # a deferred Hessian (refresh)
        self.timings = SearchTimings()
        self.u_k.x.array[:] = 0.0
        self.friction = None  # terms.Friction: set by contact.shell.attach
        #: the dressing's friction switch: t_T = friction_on · friction.law(c) (0 while the body
        #: grows, unless friction_while_growing), so a law is switched however it is written
        self.friction_on = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(1.0))
        self.kappa: dolfinx.fem.Constant | None = None  # normal penalty (friction's t_N)
        self.normal_law: laws.NormalLaw = laws.augmented_lagrangian  # c -> t_N (laws.Inputs)
        #: (warp, weft) unit directions on the deformed garment (laws.Inputs): set by attach
        self.frame: tuple[ufl.core.expr.Expr, ufl.core.expr.Expr] | None = None
        self._compiled: dict[tuple, dolfinx.fem.Expression] = {}  # see evaluate()

    # -- the pre-residual hook ------------------------------------------------------------------
    def refresh(
        self, _: dolfinx.fem.Function | None = None, *, defer_hessian: bool = False
    ) -> None:
        """Recompute gap, normal and u_k from the current displacement (a pre-residual hook).

        The argument is ignored: the state evaluates its own ``u`` expression, which refers to
        the Function SNES has just updated.

        ``defer_hessian``: a smooth body's Hessian is computed only when :meth:`update_hessian`
        asks for it (the pre-Jacobian hook), and the Hessian Function keeps its values until
        then. The residual at the refreshed iterate does not depend on them: there δ = u − u_k
        vanishes (to rounding: u_k is u evaluated at the same points), so g = g_k and n = n_k.
        A Newton iteration evaluates the residual more often than the Jacobian (each line-search
        trial, the converged iterate), so most refreshes skip the Hessian.
        """
        t0 = time.perf_counter()
        xq = self._x_expr.eval(self.mesh, self._cells).reshape(-1, 3)
        uq = self._u_expr.eval(self.mesh, self._cells).reshape(-1, 3)
        t1 = time.perf_counter()
        smooth = self.hessian is not None
        points = xq if self._unique is None else xq[self._unique[0]]
        d, nrm, hess = self._broad.query(self.body, points, self.normal, defer_hessian=smooth)
        searched = len(points)
        if self._unique is not None:
            d, nrm = d[self._unique[1]], nrm[self._unique[1]]
        t2 = time.perf_counter()
        dofs = self._dofs
        self.gap.x.array[dofs] = d - self.offset + float(self.shrink.value)
        for k in range(3):
            self.normal_fn.x.array[3 * dofs + k] = nrm[:, k]
            self.u_k.x.array[3 * dofs + k] = uq[:, k]
        for f in (self.gap, self.normal_fn, self.u_k):
            f.x.scatter_forward()
        self._pending = (hess, xq) if smooth and defer_hessian else None
        if smooth and not defer_hessian:
            self._set_hessian(hess)
        tm = self.timings
        tm.eval_s += t1 - t0
        tm.search_s += t2 - t1
        tm.refreshes += 1
        tm.points = len(d)
        tm.searched = round(searched * (1.0 - self._broad.skipped_fraction))
        tm.skipped_fraction = self._broad.skipped_fraction

    def update_hessian(self) -> None:
        """The Hessian of a refresh made with ``defer_hessian`` (a pre-Jacobian hook).

        If the displacement has changed since that refresh, a full refresh at the current
        iterate is made instead, so the Jacobian always gets the Hessian of its own iterate.
        It is computed at the points :meth:`hessian_points` picks from the law in use.
        """
        if self._pending is None:
            return
        later, x_at = self._pending
        t0 = time.perf_counter()
        xq = self._x_expr.eval(self.mesh, self._cells).reshape(-1, 3)
        if not np.array_equal(xq, x_at):
            self.refresh()
            return
        self._set_hessian(later)
        self._pending = None
        self.timings.search_s += time.perf_counter() - t0

    def hessian_points(self) -> npt.NDArray[np.bool_]:
        """The owned contact points (flat, cells × points) that get the smooth body's Hessian.

        The contact Jacobian at the refreshed iterate is −t_N'(g) (n·δu)(n·w) − t_N (H δu)·w
        (δ = u − u_k = 0 there): H is needed exactly where the normal law in use carries
        traction at the refreshed gap, t_N(c) ≠ 0, evaluated from the law — for a law that
        still pushes at a positive gap (an exponential pressure–overclosure law) as for the
        penalty. Left out: points more than :data:`HESSIAN_DEPTH` deeper than at the last
        converged step (transients). Without a penalty (a bare state) the law cannot be
        evaluated: every point.
        """
        g = self.local_values(self.gap)
        if self.kappa is None and self.friction is None:
            carries = np.ones(len(g), dtype=bool)
        else:
            carries = self.evaluate(self.refreshed_traction()).ravel() != 0.0
        deep = g < np.minimum(self.local_values(self.gap_old), 0.0) - HESSIAN_DEPTH
        return carries & ~deep

    def _set_hessian(self, later: Callable[..., F64]) -> None:
        """Compute the Hessian of the searched points (one per distinct point) at the
        :meth:`hessian_points` and write it into its Function (zero elsewhere)."""
        assert self.hessian is not None
        where = self.hessian_points()
        if self._unique is not None:  # a searched point needs it if any of its copies does
            need = np.zeros(len(self._unique[0]), dtype=bool)
            np.logical_or.at(need, self._unique[1], where)
            hess = later(need)[self._unique[1]]
        else:
            hess = later(where)
        hess[~where] = 0.0
        dofs = self._dofs
        for k in range(9):
            self.hessian.x.array[9 * dofs + k] = hess[:, k // 3, k % 3]
        self.hessian.x.scatter_forward()

    __call__ = refresh

    # -- helpers ------------------------------------------------------------------------------
    def linearised_gap(self) -> ufl.core.expr.Expr:
        """g = g_k + n_k·δ (+ ½ δ·H_k δ on a smooth body), δ = u − u_k: exact at the refresh
        point, with the distance's first (and second) derivative there."""
        du = self.u - self.u_k
        g = self.gap + ufl.dot(self.normal_fn, du)
        if self.hessian is not None:
            g += 0.5 * ufl.dot(du, ufl.dot(self.hessian, du))
        return g

    def contact_normal(self) -> ufl.core.expr.Expr:
        """n = n_k (+ H_k δ on a smooth body): the gap's gradient at u, to the same order."""
        if self.hessian is None:
            return self.normal_fn
        return self.normal_fn + ufl.dot(self.hessian, self.u - self.u_k)

    def accept_step(self) -> None:
        """Mark the current state as converged: the friction slip restarts from here.

        With friction (``self.friction``, set by :func:`fenics_garment.contact.shell.attach`) the
        anchor moves to u_old ← u_k − e, with e the slip at which the friction law carries the
        traction it carries now (:meth:`elastic_slip`; :mod:`fenics_garment.contact.laws`): for
        the Coulomb return map the anchor moves by the plastic part of the slip only, so a point
        that sticks keeps its anchor and the tangential traction it carries (e.g. holding a garment
        up against gravity) is carried on into the next step instead of restarting from zero —
        restarting let a sustained tangential load creep by μ t_N / κ_T every step. A point that
        slips keeps the elastic slip μ t_N / κ_T, so its traction stays on the Coulomb cone.

        The normal part of the step always moves the anchor (t_T is tangential): the anchor is
        a point on the skin. Left behind, the normal motion accumulated over the dressing
        (2.5 mm median on the sleeve, against an elastic slip μ t_N / κ_T ≈ 0.01 mm) turned
        into tangential "slip" (I − n⊗n)(u − u_old) wherever the faceted body's normal turned by
        a fraction of a degree, and Newton cycled between stick and slip.

        The gap becomes g_old (the laws' gap rate g − g_old restarts from here).
        """
        if self.friction is None:
            self.u_old.x.array[:] = self.u_k.x.array
        else:
            elastic = self.elastic_slip()
            self.assign(self.u_old, self.u_k - elastic)
        self.gap_old.x.array[:] = self.gap.x.array

    def elastic_slip(self, iterations: int = ANCHOR_ITERATIONS) -> dolfinx.fem.Function:
        """The slip e (a point Function) at which the friction law carries the traction t_T it
        carries now: law(e) = t_T, along the current slip (:meth:`refreshed_friction`).

        Found by evaluating the law, never by restating it: e₀ = −t_T/κ_T (the stick penalty's
        slip), then e ← e |t_T| / |law(e)|, a fixed point of the law's secant. For the Coulomb
        return map e₀ is already exact (its elastic slip, μ t_N/κ_T on the cone); for a law with
        no elastic range (e.g. a tanh regularisation, |law(e)| concave in |e|) the iteration
        contracts by 1 − |e| |law|'/|law| per pass (≈ ⅔ (|t_T|/μ t_N)²), so a sustained load
        keeps its traction across accepted steps instead of creeping.
        """
        target = dolfinx.fem.Function(self.Qv)
        self.assign(target, self.refreshed_friction())
        e = dolfinx.fem.Function(self.Qv)
        self.assign(e, -target / self.friction.kappa_t)
        c = terms.law_inputs(self, refreshed=True)
        c = replace(c, normal_traction=self.normal_law(c), slip=e)  # the law at the slip e
        size = ufl.sqrt(ufl.dot(target, target))
        for _ in range(iterations):
            t = terms.friction_law_traction(self, c)
            scale = size / ufl.max_value(ufl.sqrt(ufl.dot(t, t)), TRACTION_FLOOR)
            self.assign(e, e * scale)
        return e

    # -- the laws at the refreshed points (no linearisation: u = u_k) ---------------------------
    def refreshed_traction(self, kappa: ufl.core.expr.Expr | None = None) -> ufl.core.expr.Expr:
        """t_N of ``self.normal_law`` at u = u_k, where the linearised gap is the refreshed gap
        g_k (:func:`terms.tractions` with ``refreshed``; for :meth:`evaluate`)."""
        return terms.tractions(self, kappa, refreshed=True)[0]

    def refreshed_slip(self) -> ufl.core.expr.Expr:
        """Δu_T = (I − n_k⊗n_k)(u_k − u_old) at the refreshed points."""
        du = self.u_k - self.u_old
        return du - ufl.dot(du, self.normal_fn) * self.normal_fn

    def refreshed_friction(self) -> ufl.core.expr.Expr:
        """t_T of ``self.friction.law`` at the refreshed points (the anchor update's traction)."""
        return terms.tractions(self, refreshed=True)[1]

    # -- public accessors of the contact points ---------------------------------------------------
    @property
    def owned_cells(self) -> np.ndarray:
        """The owned garment cells, in the order of every per-point array of this state."""
        return self._cells

    @property
    def shared_points(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(first, inverse) when contact points sit on geometry nodes shared by cells: the flat
        point array indexed by ``first`` has one entry per node, and ``inverse`` maps every
        cell-point to its node (``np.unique``); None when the points are per cell."""
        return self._unique

    def evaluate(self, expr: ufl.core.expr.Expr) -> F64:
        """``expr`` at the owned contact points, shape (cells, points × value size).

        The compiled ``fem.Expression`` is kept per UFL expression (its signature), so repeated
        calls with the same law do not recompile."""
        key = (expr.ufl_shape, repr(expr))
        compiled = self._compiled.get(key)
        if compiled is None:
            compiled = self._compiled[key] = dolfinx.fem.Expression(expr, self.points)
        return compiled.eval(self.mesh, self._cells)

    def assign(self, f: dolfinx.fem.Function, expr: ufl.core.expr.Expr) -> None:
        """Set the point Function ``f`` (on ``Qs`` or ``Qv``) to ``expr`` at every owned point,
        then update the ghosts."""
        self.set_local_values(f, self.evaluate(expr))

    def set_local_values(self, f: dolfinx.fem.Function, values: npt.ArrayLike) -> None:
        """Set the owned point values of a quadrature Function (on ``Qs`` or ``Qv``; in the
        order of :meth:`local_values`), then update the ghosts."""
        bs = f.function_space.dofmap.index_map_bs
        f.x.array.reshape(-1, bs)[self._dofs] = np.reshape(values, (-1, bs))
        f.x.scatter_forward()

    def positions(self) -> F64:
        """Current positions x = X + u of the owned contact points, (n, 3)."""
        return self._x_expr.eval(self.mesh, self._cells).reshape(-1, 3)

    def search_memory(self) -> dict[str, np.ndarray]:
        """The broad phase's last exact search (points, distances, normals), for a checkpoint;
        empty before the first search."""
        return self._broad.memory()

    def restore_search_memory(self, memory: dict[str, np.ndarray]) -> None:
        """Put back a :meth:`search_memory` (a resumed run then searches the same points)."""
        self._broad.restore(memory)

    def local_values(self, f: dolfinx.fem.Function) -> F64:
        """The owned point values of a quadrature Function (scalar (n,) or vector (n, 3))."""
        bs = f.function_space.dofmap.index_map_bs
        if bs == 1:
            return f.x.array[self._dofs].copy()
        return f.x.array.reshape(-1, bs)[self._dofs].copy()
