"""Contact terms as UFL: the contact virtual work built from the laws of
:mod:`fenics_garment.contact.laws` (the one definition of each law), on the state's inputs.

Notation (all at the contact points, per unit *reference* area of the garment):

* g = g_k + n_k·(u − u_k)   the gap linearised about the current iterate (``ContactState``),
* ⟨a⟩₊ = max(a, 0),
* t_N = law(g, λ, κ)        the normal contact traction [Pa], default ⟨λ − κ g⟩₊ (penalty: λ = 0),
* Δu_T = (I − n⊗n)(u − u_old)  the tangential slip increment since the last converged step.

Integrate the returned densities with ``state.dx`` (the contact-point rule).
"""

from __future__ import annotations

from dataclasses import dataclass

from fenics_garment._stack import ufl
from fenics_garment.contact.laws import FrictionLaw, coulomb_return_map
from fenics_garment.contact.laws import macaulay as macaulay  # re-exported
from fenics_garment.contact.state import ContactState


def normal_traction(state: ContactState, kappa: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """t_N of the state's normal law (``state.normal_law``) at the linearised gap: the traction
    per reference area the residual uses (penalty when λ = 0)."""
    return state.normal_law(state.linearised_gap(), state.lam, kappa)


def slip_increment(state: ContactState) -> ufl.core.expr.Expr:
    """Δu_T = (I − n⊗n)(u − u_old): tangential slip since the anchor u_old (rigid body)."""
    n = state.normal_fn
    du = state.u - state.u_old
    return du - ufl.dot(du, n) * n


def friction_traction(
    state: ContactState, friction: Friction, t_n: ufl.core.expr.Expr
) -> ufl.core.expr.Expr:
    """t_T of ``friction.law`` (default :func:`laws.coulomb_return_map`) at the slip of the
    iterate, per reference area."""
    return friction.law(slip_increment(state), t_n, friction.mu, friction.kappa_t)


def contact_residual(
    state: ContactState,
    v: ufl.core.expr.Expr,
    kappa: ufl.core.expr.Expr,
    friction: Friction | None = None,
) -> ufl.Form:
    """Virtual work of the contact tractions on the test displacement v (residual sign: + internal).

    R_c(v) = −∫ t_N n·v dA − ∫ t_T·v dA   (over the reference area, at the contact points)

    with t_N of ``state.normal_law`` and t_T of ``friction.law``. n is
    ``state.contact_normal()``: the refreshed normal, plus its turning H_k δ on a smooth body,
    so that R_c is the variation of the penalty energy of the linearised gap.
    """
    t_n = normal_traction(state, kappa)
    form = -t_n * ufl.dot(state.contact_normal(), v) * state.dx
    if friction is not None:
        t_t = friction_traction(state, friction, t_n)
        form += -ufl.dot(t_t, v) * state.dx
    return form


@dataclass(frozen=True)
class Friction:
    """Coulomb friction of one fabric–skin pair.

    Attributes:
        mu: friction coefficient (UFL Constant or float), e.g. :data:`MU_SKIN_COTTON`.
        kappa_t: tangential (stick) penalty [Pa/m]; take it equal to the normal penalty.
        law: the friction law (Δu_T, t_N, μ, κ_T) -> t_T (:mod:`fenics_garment.contact.laws`);
            the residual, the stick/slip anchor update and the reaction all use it.
    """

    mu: ufl.core.expr.Expr
    kappa_t: ufl.core.expr.Expr
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
