"""Contact terms as UFL: the contact virtual work built from the laws of
:mod:`fenics_garment.contact.laws` (the one definition of each law), on the state's inputs.

Notation (all at the contact points, per unit *reference* area of the garment):

* g = g_k + n_k·(u − u_k)   the gap linearised about the current iterate (``ContactState``),
* ⟨a⟩₊ = max(a, 0),
* t_N = normal_law(c)       the normal contact traction [Pa], default ⟨λ − κ g⟩₊ (penalty: λ = 0),
* Δu_T = (I − n⊗n)(u − u_old)  the tangential slip increment since the last converged step,
* t_T = s · friction.law(c) the tangential traction, s the dressing's friction switch (0 or 1).

:func:`tractions` is the one place where the laws are composed: the residual, the outputs and
the point-wise updates (``ContactState``, ``uzawa``) all take their tractions from it.
Integrate the returned densities with ``state.dx`` (the contact-point rule).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from fenics_garment._stack import ufl
from fenics_garment.contact import laws
from fenics_garment.contact.laws import FrictionLaw, coulomb_return_map
from fenics_garment.contact.laws import macaulay as macaulay  # re-exported

if TYPE_CHECKING:
    from fenics_garment.contact.state import ContactState

Expr = ufl.core.expr.Expr


def law_inputs(state: ContactState, kappa: Expr | None = None, *,
               refreshed: bool = False) -> laws.Inputs:  # fmt: skip
    """The documented inputs of the laws (:class:`laws.Inputs`) at the state's contact points.

    ``refreshed=False``: linearised about the Newton iterate (the residual: g of
    :meth:`ContactState.linearised_gap`, the normal with its turning on a smooth body, the slip
    and position of the unknown u); ``True``: the point values of the last refresh (g_k, n_k,
    u_k), for the point-wise updates. ``kappa`` defaults to the state's penalty.
    """
    if kappa is None:
        kappa = state.kappa if state.kappa is not None else state.friction.kappa_t
    if refreshed:
        gap, normal, u = state.gap, state.normal_fn, state.u_k
    else:
        gap, normal, u = state.linearised_gap(), state.contact_normal(), state.u
    f = state.friction
    warp, weft = state.frame if state.frame is not None else (None, None)
    return laws.Inputs(
        gap=gap, gap_rate=gap - state.gap_old, multiplier=state.lam, kappa=kappa,
        position=ufl.SpatialCoordinate(state.mesh) + u, normal=normal, warp=warp, weft=weft,
        slip=slip_increment(state, u),
        mu=f.mu if f is not None else None, kappa_t=f.kappa_t if f is not None else None,
    )  # fmt: skip


def friction_law_traction(state: ContactState, c: laws.Inputs) -> Expr:
    """t_T = s · friction.law(c): the friction law switched by ``state.friction_on`` (s)."""
    return state.friction_on * state.friction.law(c)


def tractions(state: ContactState, kappa: Expr | None = None, *,
              refreshed: bool = False) -> tuple[Expr, Expr | None]:  # fmt: skip
    """(t_N, t_T) of the laws in use: t_N = normal_law(c), t_T = s · friction.law(c with
    c.normal_traction = t_N) (None when frictionless), c = :func:`law_inputs`."""
    c = law_inputs(state, kappa, refreshed=refreshed)
    t_n = state.normal_law(c)
    if state.friction is None:
        return t_n, None
    return t_n, friction_law_traction(state, replace(c, normal_traction=t_n))


def normal_traction(state: ContactState, kappa: Expr) -> Expr:
    """t_N of the state's normal law (``state.normal_law``) at the linearised gap: the traction
    per reference area the residual uses (penalty when λ = 0)."""
    return tractions(state, kappa)[0]


def slip_increment(state: ContactState, u: Expr | None = None) -> Expr:
    """Δu_T = (I − n⊗n)(u − u_old): tangential slip since the anchor u_old (rigid body), n the
    refreshed normal; u defaults to the state's unknown displacement."""
    n = state.normal_fn
    du = (state.u if u is None else u) - state.u_old
    return du - ufl.dot(du, n) * n


def contact_residual(state: ContactState, v: Expr, kappa: Expr) -> ufl.Form:
    """Virtual work of the contact tractions on the test displacement v (residual sign: + internal).

    R_c(v) = −∫ t_N n·v dA − ∫ t_T·v dA   (over the reference area, at the contact points)

    with (t_N, t_T) of :func:`tractions` (``state.normal_law``, ``state.friction``). n is
    ``state.contact_normal()``: the refreshed normal, plus its turning H_k δ on a smooth body,
    so that R_c is the variation of the penalty energy of the linearised gap.
    """
    t_n, t_t = tractions(state, kappa)
    form = -t_n * ufl.dot(state.contact_normal(), v) * state.dx
    if t_t is not None:
        form += -ufl.dot(t_t, v) * state.dx
    return form


@dataclass(frozen=True)
class Friction:
    """Coulomb friction of one fabric–skin pair.

    Attributes:
        mu: friction coefficient (UFL Constant or float), e.g. :data:`MU_SKIN_COTTON`.
        kappa_t: tangential (stick) penalty [Pa/m]; take it equal to the normal penalty.
        law: the friction law c -> t_T of the inputs c (:class:`laws.Inputs`: the slip, t_N,
            μ, κ_T, the warp and weft, …; :mod:`fenics_garment.contact.laws`); the residual,
            the stick/slip anchor update and the reaction all use it.
    """

    mu: Expr
    kappa_t: Expr
    law: FrictionLaw = coulomb_return_map


#: Skin–cotton friction coefficient used as the default, 0.4: a dry-skin value at the low end of the
#: 0.3–0.9 range quoted for skin against cotton fabrics. Gerhardt, Strässle, Lenz, Spencer &
#: Derler, "Influence of epidermal hydration on the friction of human skin against textiles",
#: J. R. Soc. Interface 5 (2008) 1317–1328, doi:10.1098/rsif.2008.0034 (inner forearm against a
#: cotton/polyester hospital fabric) report that the coefficient rises by 26 % (men) to 43 %
#: (women) from very dry to normally moist skin and more than doubles against wet fabric; use
#: ≈ 0.6–0.9 for moist skin. The absolute dry value is not restated in that abstract and was not
#: re-checked against the paper's figures here: treat 0.4 as a nominal value to replace.
MU_SKIN_COTTON: float = 0.4


#: The body's tensile modulus from the paper's Table 1 (205 gf/cm², Poisson's ratio 0.3), in Pa:
#: 205 gf/cm² × 9.80665e-3 N/gf / 1e-4 m²/cm² — seed paper, "A finite-element mechanical contact
#: model based on Mindlin–Reissner shell theory for a three-dimensional human body and garment",
#: Table 1.
BODY_MODULUS_PA: float = 205 * 9.80665e-3 / 1e-4
BODY_POISSON: float = 0.3


@dataclass(frozen=True)
class SoftTissue:
    """A compliant body: a Winkler (elastic foundation) layer of soft tissue over a rigid core.

    The skin gives under pressure by δ = ⟨−g⟩₊ with t_N = k δ, k = E_oed / depth, where
    E_oed = E (1 − ν) / ((1 + ν)(1 − 2ν)) is the laterally confined (oedometric) modulus of the
    layer. Use ``stiffness`` as the contact κ: the "penetration" is then the physical tissue
    compression and the pressure no longer depends on a numerical penalty.

    Attributes:
        depth: tissue depth over the rigid core [m] (a scene parameter: no default value in the
            paper; e.g. 0.01–0.03 m of subcutaneous tissue).
        E: tissue modulus [Pa], default the paper's Table 1 value.
        nu: tissue Poisson ratio, default the paper's Table 1 value.
    """

    depth: float
    E: float = BODY_MODULUS_PA
    nu: float = BODY_POISSON

    @property
    def stiffness(self) -> float:
        """k = E (1 − ν) / ((1 + ν)(1 − 2ν) depth)  [Pa/m]."""
        return self.E * (1 - self.nu) / ((1 + self.nu) * (1 - 2 * self.nu) * self.depth)

    @property
    def shear_stiffness(self) -> float:
        """k_T = G / depth = E / (2 (1 + ν) depth)  [Pa/m]: the layer's tangential stiffness,
        the skin's give under a sticking garment before it slides (the stick penalty κ_T)."""
        return self.E / (2 * (1 + self.nu) * self.depth)


def default_penalty(
    membrane_stiffness: float, element_size: float, kappa_hat: float = 10.0
) -> float:
    """κ = κ̂ E h / ℓ²  [Pa/m], ℓ the garment element size.

    Scaled so that one contact point's stiffness κ ℓ² is κ̂ times the membrane's E h: the
    conditioning is then mesh-independent. The relative pressure error of the pure penalty is
    ≈ −1.3 E h / (κ R²) = −1.3 (ℓ/R)² / κ̂ on a body of radius R (STACK.md), e.g. −0.2 % at
    ℓ/R = 0.12, κ̂ = 10 (measured −0.21 % on the Laplace tube); the augmented Lagrangian removes
    it without raising κ.
    """
    return kappa_hat * membrane_stiffness / element_size**2
