"""Contact on the shell: a :class:`ContactState` on the displacement of a ``ShellModel``.

:func:`attach` builds the state on ``model.u`` (the displacement part of the mixed unknown), adds
the contact virtual work R_c(v) = −∫ t_N n·v_u dA (at the contact points) to the model's residual
(as a builder: made from the contact's laws when the residual is) and returns a
:class:`ShellContact` whose ``solver_hooks`` are the pre-residual and pre-Jacobian hooks of
:class:`fenics_garment.solve.NonlinearSolver`::

    contact = attach(model, body, kappa_hat=10.0)
    solver = NonlinearSolver(model, bcs, **contact.solver_hooks())

The penalty κ is a ``fem.Constant``: changing it (or the material) does not recompile the form.

Contact-point rule for the P2⊕bubble displacement: ``"lumped"`` (vertices, edge midpoints and
centroid, weights 3/60, 8/60, 27/60), measured on the tight tube (1/8 tube, 8×4 cells, κ̂ = 10,
then augmented Lagrangian to 1 % of h): pressure error −0.05 %, 3 + 3 Newton iterations to dress,
2 per multiplier update. ``"vertex"`` leaves the edge-midpoint nodes free: they sag 5 mm into
the body and the pressure is −64 % off; ``"vertex+edge"`` (equal weights) −3.8 %, ``"gauss2"``
−2.1 % after the same multiplier updates.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

from fenics_garment._stack import MPI, dolfinx, ufl
from fenics_garment.contact import laws, pressure, terms
from fenics_garment.contact.search import SearchSurface
from fenics_garment.contact.state import ContactState


def area_stretch(kin) -> ufl.core.expr.Expr:
    """J_s = da/dA = |F e₁ × F e₂| per unit mesh area (e₁, e₂ the orthonormal reference frame
    of the shell; for flat pattern pieces, whose frame is orthonormal in the flat metric,
    × dA_rest/dA_mesh: the contact points' weights are mesh areas)."""
    c = ufl.cross(kin.F * kin.e1, kin.F * kin.e2)
    J = ufl.sqrt(ufl.dot(c, c))
    return J if kin.rest_area is None else J * kin.rest_area


def garment_frame(kin) -> tuple[ufl.core.expr.Expr, ufl.core.expr.Expr]:
    """(warp, weft): F e₁/|F e₁|, F e₂/|F e₂|, the yarn directions on the deformed garment (e₁
    the warp, e₂ the weft of the stress-free fabric), inputs of the laws (:class:`laws.Inputs`)."""
    a, b = kin.F * kin.e1, kin.F * kin.e2
    return a / ufl.sqrt(ufl.dot(a, a)), b / ufl.sqrt(ufl.dot(b, b))


@dataclass
class ShellContact:
    """Contact of a shell with a body: the state, the penalty and the contact laws.

    The laws are values (:mod:`fenics_garment.contact.laws`): ``normal_law`` c -> t_N and
    ``friction.law`` c -> t_T, of the documented inputs c (:class:`laws.Inputs`: the gap and
    its rate, the multiplier, the slip, μ, the warp and weft, …). Set them before the solver
    is built (the model's residual is assembled from them then): the residual, the stick/slip
    anchor update, the multiplier update, the smooth body's active set, the reaction and the
    pressure outputs all follow.
    """

    model: object
    state: ContactState
    kappa: dolfinx.fem.Constant

    @property
    def normal_law(self) -> laws.NormalLaw:
        """The normal contact law (kept on the state, whose point updates evaluate it)."""
        return self.state.normal_law

    @normal_law.setter
    def normal_law(self, law: laws.NormalLaw) -> None:
        self.state.normal_law = law

    @property
    def friction(self) -> terms.Friction | None:
        """Coulomb friction (μ, κ_T and its law), or None: frictionless."""
        return self.state.friction

    @friction.setter
    def friction(self, friction: terms.Friction | None) -> None:
        self.state.friction = friction

    def refresh(self, defer_hessian: bool = False) -> None:
        """Pre-residual hook: gap, normal and u_k at the current iterate (see
        :meth:`ContactState.refresh`)."""
        self.state.refresh(defer_hessian=defer_hessian)

    def update_hessian(self) -> None:
        """Pre-Jacobian hook: the smooth body's Hessian at the iterate of the last refresh."""
        self.state.update_hessian()

    def solver_hooks(self) -> dict[str, list[Callable[[], None]]]:
        """``NonlinearSolver`` hooks: refresh before each residual, the Hessian (which only the
        Jacobian needs) before each Jacobian. The same Newton iterates as refreshing it always.
        """
        refresh = partial(self.refresh, defer_hessian=True)
        return {"pre_residual": [refresh], "pre_jacobian": [self.update_hessian]}

    def accept_step(self) -> None:
        """After a converged load step: friction's anchor moves by the plastic slip only."""
        self.state.accept_step()

    def residual(self, v: ufl.core.expr.Expr) -> ufl.Form:
        """R_c(v) of the laws in use (:func:`terms.contact_residual`) on the test field v."""
        return terms.contact_residual(self.state, v, self.kappa)

    @property
    def traction(self) -> ufl.core.expr.Expr:
        """t_N of the normal law in use, per reference area [Pa]."""
        return terms.normal_traction(self.state, self.kappa)

    def area_stretch(self) -> ufl.core.expr.Expr:
        return area_stretch(self.model.kinematics())

    def pressure_values(self):
        """Pressure [Pa] at the owned contact points (force per deformed area)."""
        return pressure.garment_pressure(self.state, self.traction, self.area_stretch())

    def reaction(self, direction=(0.0, 0.0, 1.0)) -> float:
        """Total force [N] of the body on the garment along ``direction``: normal and friction
        tractions at the contact points, −R_c(e) for the constant test field e (collective).

        At equilibrium with no other support it balances the garment's weight — a conservation
        check that a regularising spring carries none of it."""
        e = ufl.as_vector([float(d) for d in direction])
        form = dolfinx.fem.form(-self.residual(e))
        comm = self.state.mesh.comm
        return comm.allreduce(dolfinx.fem.assemble_scalar(form), op=MPI.SUM)

    def pressure(self, name: str = "contact_pressure") -> dolfinx.fem.Function:
        """Contact pressure as a P1 Function on the garment (for XDMF/VTX output)."""
        return pressure.pressure_function(self.state, self.traction, self.area_stretch(), name=name)


def attach(
    model,
    body: SearchSurface,
    *,
    kappa: float | None = None,
    kappa_hat: float = 10.0,
    rule: str = "lumped",
    normal: str = "gradient",
    band: float = 0.02,
    mu: float | None = None,
    kappa_t: float | None = None,
) -> ShellContact:
    """Add normal contact with ``body`` to ``model`` (before the solver is built).

    Args:
        model: a :class:`fenics_garment.shell.model.ShellModel`.
        body: the body surface.
        kappa: penalty [Pa/m]; default :func:`terms.default_penalty` with the model's membrane
            stiffness, its largest cell size and ``kappa_hat``.
        rule, normal, band: see :class:`ContactState`.
        mu: Coulomb friction coefficient (None: frictionless, no friction term is assembled). It
            becomes ``contact.friction.mu``, a Constant. Call ``contact.accept_step()`` after
            each converged load step.
        kappa_t: the stick penalty κ_T [Pa/m] (``contact.friction.kappa_t``); None: κ. With
            the default κ, which scales as 1/ℓ², a sticking answer depends on the mesh; scenes
            pass the skin's tangential stiffness (``scene.build.stick_stiffness``).
    """
    mesh = model.geometry.mesh
    s = model.stiffness
    if kappa is None:
        h_max = mesh.comm.allreduce(float(model.h_cell.x.array.max()), op=MPI.MAX)
        kappa = terms.default_penalty(s.membrane_scale, h_max, kappa_hat)
    state = ContactState(
        mesh, model.u, body, offset=s.thickness / 2, rule=rule, normal=normal, band=band
    )
    k = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(kappa))
    friction = None
    if mu is not None:
        kt = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(kappa_t or kappa))
        friction = terms.Friction(dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(mu)), kt)
    state.friction, state.kappa = friction, k  # the point updates evaluate the laws with them
    state.frame = garment_frame(model.kinematics())
    contact = ShellContact(model, state, k)
    # added as a builder: the residual is made from the laws in use when the solver is built
    model.add_residual(lambda: contact.residual(ufl.split(ufl.TestFunction(model.Q))[0]))
    return contact
