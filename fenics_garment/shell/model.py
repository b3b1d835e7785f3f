"""A shell model: function spaces, the energy Π as a sum of named terms, residual and Jacobian.

The model owns no solver. ``model.residual()`` and ``model.jacobian()`` are plain UFL forms that
:mod:`fenics_garment.solve` hands to PETSc SNES; contact or any other research term is added as
a further residual term.

Locking is cured as in Arnold & Brezzi, Locking-free finite element methods for shells,
Math. Comp. 66 (1997) 1–14 (their lowest method, k = 0):

* every field — displacement *and* rotation — is continuous P2 enriched with the cubic bubble,
* partial selective reduced integration (PSRI): membrane, shear (and drilling) energies are split
  as α·(full integration) + (1−α)·(reduced, degree-2 integration) with α = min(1, t_eff²/h²), so
  that as t/h → 0 the constraints are imposed only at the reduced points.

Why the rotation bubble: with P2 rotations the thin-limit constraint γ = 0 at the three reduced
points of each cell (6 conditions per cell) leaves too few (w, θ) pairs — about 7 unknowns per
cell against 6 constraints — and the clamped plate locks (8×8, t/a = 1e-4: −21 %). The θ bubble
adds 2 unknowns per cell (9 against 6) and the error stays at ≈ 1 % down to t/a = 1e-4.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import basix.ufl
import numpy as np

from fenics_garment._stack import dolfinx, ufl
from fenics_garment.materials import Fabric, Isotropic
from fenics_garment.points import PointEvaluator
from fenics_garment.shell import energy as terms
from fenics_garment.shell.kinematics import (
    ShellGeometry,
    ShellKinematics,
    rotate,
    shell_kinematics,
)


@dataclass(frozen=True)
class ElementVariant:
    """Displacement and rotation elements and the quadrature degrees (full, reduced)."""

    name: str
    u_degree: int
    bubble: bool
    theta_degree: int
    full_degree: int
    reduced_degree: int
    psri: bool = True
    theta_bubble: bool = False
    #: passes the verification table (``verification/shells.py``: the published linear and
    #: nonlinear thin-shell benchmarks) at the mesh densities the scenes use
    verified: bool = False


ELEMENTS: dict[str, ElementVariant] = {
    v.name: v
    for v in (
        # default on triangles: Arnold & Brezzi (1997), k = 0: P2 + cubic bubble for all fields
        ElementVariant("P2B-P2B", 2, True, 2, 4, 2, theta_bubble=True, verified=True),
        # without the rotation bubble: shear locks (clamped plate 8×8, t/a = 1e-4: −21 %)
        ElementVariant("P2B-P2", 2, True, 2, 4, 2),
        ElementVariant("P2-P2", 2, False, 2, 4, 2),
        ElementVariant("P2B-P2B-full", 2, True, 2, 4, 4, psri=False, theta_bubble=True),  # study
        ElementVariant("P2B-P2-full", 2, True, 2, 4, 4, psri=False),  # no locking cure: for study
        ElementVariant("Q2-Q2", 2, False, 2, 5, 3),  # quadrilaterals
        ElementVariant("P1-P1", 1, False, 1, 2, 1),  # draft: locks (docs/verification/shells.md)
    )
}

#: The element of every scene unless it says otherwise: the verified one on triangles.
DEFAULT_ELEMENT = "P2B-P2B"

EnergyTerm = Callable[[ShellKinematics, terms.StiffnessConstants], ufl.core.expr.Expr]


def _variant_for(mesh, name: str | None) -> ElementVariant:
    cell = mesh.topology.cell_name()
    if name is None:
        name = DEFAULT_ELEMENT if cell == "triangle" else "Q2-Q2"
    if name not in ELEMENTS:
        raise ValueError(f"unknown element variant {name!r}; choose one of {sorted(ELEMENTS)}")
    v = ELEMENTS[name]
    if v.bubble and cell != "triangle":
        raise ValueError(f"element {name} needs a triangle mesh; this mesh has {cell} cells")
    return v


@dataclass
class Discretisation:
    """What a model's forms are built on: the mixed space, the unknown, the switches and the
    measures. Shared by a model and its ``dataclasses.replace`` copies (same geometry and
    element), so terms already built on the unknown (contact, springs) stay valid."""

    geometry: ShellGeometry
    variant: ElementVariant
    Q: dolfinx.fem.FunctionSpace
    q: dolfinx.fem.Function
    load_factor: dolfinx.fem.Constant
    extra_switch: dolfinx.fem.Constant
    h_cell: dolfinx.fem.Function
    dx_full: ufl.Measure
    dx_reduced: ufl.Measure

    @classmethod
    def create(cls, geometry: ShellGeometry, variant: ElementVariant) -> Discretisation:
        mesh = geometry.mesh
        cell = mesh.basix_cell()
        v = variant
        Pu = basix.ufl.element("Lagrange", cell, v.u_degree)
        if v.bubble:
            Pu = basix.ufl.enriched_element([Pu, basix.ufl.element("Bubble", cell, 3)])
        Ue = basix.ufl.blocked_element(Pu, shape=(3,))
        Pt = basix.ufl.element("Lagrange", cell, v.theta_degree)
        if v.theta_bubble:
            Pt = basix.ufl.enriched_element([Pt, basix.ufl.element("Bubble", cell, 3)])
        Te = basix.ufl.blocked_element(Pt, shape=(3,))
        Q = dolfinx.fem.functionspace(mesh, basix.ufl.mixed_element([Ue, Te]))

        def one() -> dolfinx.fem.Constant:
            return dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(1.0))

        return cls(
            geometry, v, Q, dolfinx.fem.Function(Q, name="q"), one(), one(),
            terms.cell_size(mesh),
            ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": v.full_degree}),
            ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": v.reduced_degree}),
        )  # fmt: skip


@dataclass
class ShellModel:
    """Geometrically nonlinear Naghdi shell on ``geometry`` made of ``material``.

    The energy terms are fields, each a law ``(kin, C) -> ψ`` (:mod:`fenics_garment.shell.energy`):
    replace one by assignment (``model.membrane = my_law``) or with
    ``dataclasses.replace(model, membrane=my_law)`` before the solver is built. The copy shares
    the unknown and spaces (:class:`Discretisation`) and copies the added loads, energies and
    residual terms, so it works with contact attached; the outputs derived from a term
    (:meth:`membrane_forces`) follow the replaced law. Further terms: :meth:`add_energy`
    (a potential, varied with the rest), :meth:`add_residual` (any virtual work).
    """

    geometry: ShellGeometry
    material: Isotropic | Fabric
    element: str | None = None
    drilling_factor: float = 1.0
    membrane: EnergyTerm = terms.membrane_energy
    bending: EnergyTerm = terms.bending_energy
    shear: EnergyTerm = terms.shear_energy
    drilling: EnergyTerm = terms.drilling_energy
    # external loads, each a (work density or residual density, measure) pair, scaled by λ
    _work: list = field(default_factory=list, repr=False)
    _follower: list = field(default_factory=list, repr=False)
    _extra_residual: list = field(default_factory=list, repr=False)
    _energy: list = field(default_factory=list, repr=False)
    _point: list = field(default_factory=list, repr=False)  # (vertex point, force, follower)
    discretisation: Discretisation | None = field(default=None, repr=False, compare=False)
    _disp_spaces: tuple | None = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        mesh = self.geometry.mesh
        self.variant = _variant_for(mesh, self.element)
        d = self.discretisation
        if d is None or d.geometry is not self.geometry or d.variant != self.variant:
            d = self.discretisation = Discretisation.create(self.geometry, self.variant)
        # a replace() copy must not add to the lists of the model it was copied from
        self._work, self._follower = list(self._work), list(self._follower)
        self._extra_residual, self._energy = list(self._extra_residual), list(self._energy)
        self._point = list(self._point)
        self.Q, self.q = d.Q, d.q
        self.load_factor, self.extra_switch = d.load_factor, d.extra_switch
        self.h_cell, self.dx_full, self.dx_reduced = d.h_cell, d.dx_full, d.dx_reduced
        self.stiffness = self.material.stiffness()
        self.C = terms.StiffnessConstants.create(mesh, self.stiffness, self.drilling_factor)
        self.t_eff = dolfinx.fem.Constant(
            mesh, dolfinx.default_scalar_type(self.stiffness.effective_thickness)
        )

    # -- unknowns ---------------------------------------------------------------------------
    @property
    def u(self) -> ufl.core.expr.Expr:
        return ufl.split(self.q)[0]

    @property
    def theta(self) -> ufl.core.expr.Expr:
        return ufl.split(self.q)[1]

    def kinematics(self, q=None) -> ShellKinematics:
        u, theta = ufl.split(self.q if q is None else q)
        return shell_kinematics(self.geometry, u, theta)

    @property
    def psri_weight(self) -> ufl.core.expr.Expr:
        """α = min(1, t_eff²/h²): the fully integrated share of membrane and shear energy."""
        a = self.t_eff**2 / self.h_cell**2
        return ufl.conditional(ufl.lt(a, 1.0), a, 1.0)

    # -- energy -------------------------------------------------------------------------------
    def internal_energy(self) -> ufl.Form:
        kin = self.kinematics()
        C = self.C
        # Drilling is an in-plane constraint like the membrane strain: integrated like it. Under
        # reduced integration alone the cubic bubble of θ·n would be a zero-energy mode.
        psi_ms = self.per_rest_area(
            self.membrane(kin, C) + self.shear(kin, C) + self.drilling(kin, C)
        )
        Pi = self.per_rest_area(self.bending(kin, C)) * self.dx_full
        if self.variant.psri:
            alpha = self.psri_weight
            Pi += alpha * psi_ms * self.dx_full + (1 - alpha) * psi_ms * self.dx_reduced
        else:
            Pi += psi_ms * self.dx_full
        for density, measure in self._energy:
            psi = density if isinstance(density, ufl.core.expr.Expr) else density(kin, C)
            Pi += psi * measure
        return Pi

    def per_rest_area(self, density: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
        """A density per unit rest area as one per unit mesh area (× dA_rest/dA_mesh when the
        rest state is flat panels, :mod:`.rest`; unchanged when the mesh is the rest state)."""
        j = self.geometry.rest_area
        return density if j is None else density * j

    @property
    def added_energies(self) -> tuple:
        """The (density, measure) pairs of :meth:`add_energy`."""
        return tuple(self._energy)

    @property
    def added_residuals(self) -> tuple:
        """The forms and builders of :meth:`add_residual` (contact, springs, user terms)."""
        return tuple(self._extra_residual)

    @property
    def loads(self) -> dict[str, tuple]:
        """The dead loads ((work density, measure) pairs), follower pressures and point loads
        ((vertex, force Constant, follower) triples of :meth:`add_point_load`)."""
        return {"dead": tuple(self._work), "follower": tuple(self._follower),
                "point": tuple(self._point)}  # fmt: skip

    def membrane_forces(self) -> ufl.core.expr.Expr:
        """N = ∂ψ_m/∂ε [N/m] of the membrane law in use (2×2, warp/weft frame)."""
        return terms.membrane_forces(self.kinematics(), self.C, self.membrane)

    def add_work(self, density: ufl.core.expr.Expr, measure: ufl.Measure | None = None) -> None:
        """Add the work of a dead load (density per reference area or length), scaled by λ."""
        self._work.append((density, measure or self.dx_full))

    def add_gravity(self, g=(0.0, 0.0, -9.80665)) -> dolfinx.fem.Constant:
        """Self weight ρh g (g in m/s², default: standard gravity along −z)."""
        c = self.constant(g)
        self.add_work(self.per_rest_area(terms.gravity_work(self.u, self.C, c)))
        return c

    def constant(self, value) -> dolfinx.fem.Constant:
        """A ``fem.Constant`` on the mesh: loads given as numbers do not recompile the forms."""
        if isinstance(value, dolfinx.fem.Constant):
            return value
        arr = np.asarray(value, dtype=dolfinx.default_scalar_type)
        return dolfinx.fem.Constant(self.geometry.mesh, arr)

    def add_distributed_load(self, f) -> dolfinx.fem.Constant:
        """A dead load per unit reference area, f (N/m²) as a vector; returns its Constant."""
        c = self.constant(f)
        self.add_work(self.per_rest_area(terms.distributed_load_work(self.u, c)))
        return c

    def add_edge_load(self, t, ds: ufl.Measure) -> dolfinx.fem.Constant:
        """A dead line load t (N/m) on the edges of ``ds`` (a tagged boundary measure)."""
        c = self.constant(t)
        self.add_work(terms.edge_load_work(self.u, c), ds)
        return c

    def add_edge_moment(self, m, ds: ufl.Measure) -> dolfinx.fem.Constant:
        """A line moment m (N·m/m) about a fixed axis on the edges of ``ds``: work m·θ.

        Conservative for rotations about a fixed axis (plane bending, e.g. the roll-up).
        """
        c = self.constant(m)
        self.add_work(ufl.dot(c, self.theta), ds)
        return c

    def add_pressure(self, p) -> dolfinx.fem.Constant | ufl.core.expr.Expr:
        """A follower pressure p (Pa) on the deformed surface, along the oriented normal."""
        c = p if isinstance(p, ufl.core.expr.Expr) else self.constant(p)
        self._follower.append(c)
        return c

    def add_point_load(self, point, force, *, follower: bool = False) -> dolfinx.fem.Constant:
        """A point force (N) at a mesh vertex, scaled by λ; returns its Constant.

        Integrated with DOLFINx's vertex measure ``dP``, so it is a term of the model's forms
        (residual, Jacobian, tangent load) like the distributed loads. ``follower=False``: a dead
        force of fixed direction, the work λ f·u(x₀). ``follower=True``: the force turns with
        the shell's rotation at the point, λ R(θ(x₀)) f (a transverse force stays transverse);
        not conservative, its Jacobian is not symmetric. The point must be a vertex of the mesh
        (within 1e-8); for any other point of the surface pass a
        :class:`~fenics_garment.shell.loads.PointLoad` to the solver instead (dead only).
        """
        mesh = self.geometry.mesh
        p = np.asarray(point, dtype=np.float64)
        n_owned = mesh.topology.index_map(0).size_local
        verts = dolfinx.mesh.locate_entities(
            mesh, 0, lambda x: np.linalg.norm(x.T - p[None, :], axis=1) < 1e-8
        )
        owned = verts[verts < n_owned]
        if mesh.comm.allreduce(len(owned)) != 1:
            raise ValueError(
                f"point load at {tuple(p)}: not a vertex of the mesh; pass a PointLoad to the "
                "solver (point_loads=...) for a dead force anywhere on the surface"
            )
        c = self.constant(force)
        self._point.append((owned.astype(np.int32), c, bool(follower)))
        return c

    def _point_measure(self) -> ufl.Measure:
        """The vertex measure of the point loads, load i tagged i + 1 (one meshtags for all:
        a form takes one subdomain data per integral type). Owned vertices only, so that each
        point is counted once in parallel."""
        verts = np.concatenate([v for v, _, _ in self._point]).astype(np.int32)
        values = np.concatenate(
            [np.full(len(v), i + 1, dtype=np.int32) for i, (v, _, _) in enumerate(self._point)]
        )
        order = np.argsort(verts)
        tags = dolfinx.mesh.meshtags(self.geometry.mesh, 0, verts[order], values[order])
        return ufl.Measure("dP", domain=self.geometry.mesh, subdomain_data=tags)

    def _point_forces(self, v_u) -> ufl.core.expr.Expr | None:
        """Σ f_i·v(x_i), the follower ones rotated by R(θ(x_i)): the point loads at λ = 1."""
        if not self._point:
            return None
        dP = self._point_measure()
        terms_ = []
        for i, (_, c, follower) in enumerate(self._point):
            f = rotate(self.theta, c) if follower else c
            terms_.append(ufl.dot(f, v_u) * dP(i + 1))
        return sum(terms_[1:], terms_[0])

    def add_residual(self, form: ufl.Form | Callable[[], ufl.Form]) -> None:
        """Add a residual form (e.g. contact), linear in the test function of ``self.Q``, or a
        builder ``() -> form`` called when :meth:`residual` is (so that it uses the laws in use
        then, e.g. :class:`~fenics_garment.contact.shell.ShellContact`'s).

        Added forms are multiplied by ``self.extra_switch`` (1 = on), so that the solver can take
        the round-off floor of the internal forces alone without compiling a second form.
        """
        self._extra_residual.append(form)

    def add_energy(
        self, density: ufl.core.expr.Expr | EnergyTerm, measure: ufl.Measure | None = None
    ) -> None:
        """Add an energy density ψ to the internal energy, Π += ∫ ψ dA (default ``dx_full``).

        ``density``: a UFL expression of the unknown, or a law ``(kin, C) -> ψ`` like the shell
        terms (evaluated on the model's kinematics when the residual is built). It is varied with
        the rest of Π, so the Jacobian stays symmetric (e.g. an elastic foundation).
        """
        self._energy.append((density, measure or self.dx_full))

    def residual(self) -> ufl.Form:
        """F(q; δq) = δΠ_int − λ f + extra terms, with f the loads at λ = 1
        (:meth:`tangent_load`: dead work, follower pressures, point forces)."""
        F = ufl.derivative(self.internal_energy(), self.q, ufl.TestFunction(self.Q))
        f = self.tangent_load()
        if f is not None:
            F -= self.load_factor * f
        for extra in self._extra_residual:
            F += self.extra_switch * (extra if isinstance(extra, ufl.Form) else extra())
        return F

    def tangent_load(self) -> ufl.Form | None:
        """f = −∂F/∂λ at the current state (the load direction of path following): the dead
        work δW, minus the follower-pressure residual, plus the point forces; None without
        loads. The residual is affine in λ, so f does not depend on λ."""
        v = ufl.TestFunction(self.Q)
        v_u = ufl.split(v)[0]
        f = None
        if self._work:
            dead = [w * m for w, m in self._work]
            f = ufl.derivative(sum(dead[1:], dead[0]), self.q, v)
        if self._follower:
            kin = self.kinematics()
            for p in self._follower:
                term = -self.per_rest_area(terms.pressure_residual(kin, p, v_u)) * self.dx_full
                f = term if f is None else f + term
        points = self._point_forces(v_u)
        if points is not None:
            f = points if f is None else f + points
        return f

    def jacobian(self, F: ufl.Form) -> ufl.Form:
        return ufl.derivative(F, self.q, ufl.TrialFunction(self.Q))

    # -- post-processing ------------------------------------------------------------------------
    def displacement(self) -> dolfinx.fem.Function:
        """The displacement interpolated into vector P2 (for output and point values): a new
        Function each call, on spaces built at the first call (the P2 space, the collapsed
        displacement space of ``q`` and its dof map)."""
        if self._disp_spaces is None:
            V = dolfinx.fem.functionspace(self.geometry.mesh, ("Lagrange", 2, (3,)))
            U, dofs = self.Q.sub(0).collapse()
            self._disp_spaces = (V, dolfinx.fem.Function(U), np.asarray(dofs))
        V, u, dofs = self._disp_spaces
        u.x.array[:] = self.q.x.array[dofs]
        out = dolfinx.fem.Function(V, name="displacement")
        out.interpolate(u)
        return out

    def rest_free_floor(self) -> float | None:
        """The round-off floor of the internal forces when the rest state is not the mesh.

        At q = 0 a shell whose rest state is its mesh has only round-off internal forces (the
        solver measures that floor directly); one whose rest state is flat panels carries its
        real sewing forces there. Its floor is that of the same shell and mesh with the mesh as
        rest state: ‖δΠ_int(q = 0)‖ of such a twin (one more residual form to compile). None
        when the mesh is the rest state.
        """
        if self.geometry.rest is None:
            return None
        from dataclasses import replace as _replace

        twin = ShellModel(_replace(self.geometry, rest=None), self.material, self.element,
                          self.drilling_factor)  # fmt: skip
        F = ufl.derivative(twin.internal_energy(), twin.q, ufl.TestFunction(twin.Q))
        b = dolfinx.fem.assemble_vector(dolfinx.fem.form(F))
        b.scatter_reverse(dolfinx.la.InsertMode.add)
        n = twin.Q.dofmap.index_map.size_local * twin.Q.dofmap.index_map_bs
        comm = self.geometry.mesh.comm
        return float(np.sqrt(comm.allreduce(float(np.sum(b.array[:n] ** 2)))))

    def energy_value(self, form: ufl.Form) -> float:
        comm = self.geometry.mesh.comm
        return comm.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(form)))


def evaluate_at_points(f: dolfinx.fem.Function, points: np.ndarray) -> np.ndarray:
    """Values of ``f`` at ``points`` (n, 3), identical on every rank (owner evaluates, allreduce).

    Points must lie on the surface (within 1e-6 of a cell). It locates the points anew on each
    call: for repeated evaluation at the same points build a
    :class:`~fenics_garment.points.PointEvaluator` once.
    """
    return PointEvaluator(f.function_space.mesh, points)(f)
