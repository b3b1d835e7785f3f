"""The contact laws, each one UFL function of documented inputs, passed to the contact as a value.

A law is the *only* definition of its physics. The residual uses it on the gap and slip
linearised about the Newton iterate; the point-wise algorithms evaluate the very same function
on the refreshed point values (``ContactState.accept_step``: the stick/slip anchor;
``uzawa.update_multiplier``: λ ← t_N; ``ContactState.update_hessian``: which points carry
traction) and the outputs use it for the pressure. Replacing a law
(``contact.normal_law = my_law``, ``contact.friction = replace(contact.friction, law=my_law)``)
therefore changes all of them together. They are composed in one place,
:func:`fenics_garment.contact.terms.tractions`.

Every law takes one argument, an :class:`Inputs` ``c``, and returns a UFL expression:

* a normal law ``c -> t_N``: the normal traction t_N ≥ 0 [Pa] pressing the garment outwards
  along the body normal, per unit *reference* area of the garment;
* a friction law ``c -> t_T``: the tangential traction on the garment [Pa] (a 3-vector,
  opposing the slip), per unit reference area; ``c.normal_traction`` is the normal law's t_N.

Write a law in terms of its inputs rather than of values it closes over: the dressing switches
friction off while the body grows and on again (``ContactState.friction_on``, a factor on the
friction law's traction, so a law is switched however it is written), but a coefficient held
in a closure cannot follow a scene's ``[physics] friction``; ``c.mu`` does. Constants of the
law itself (a decay length, a ratio) are fine in a closure. An anisotropic law takes its
directions from ``c.warp`` and ``c.weft``; a law that depends on where it acts, from
``c.position``.

The contact's active set follows the law in use: a smooth body's Hessian (the turning of the
normal, needed for a consistent Jacobian) is computed at every point where the law carries
traction at the refreshed gap, wherever that is; the augmented Lagrangian applies only to a law
that is a constraint — one that uses ``c.multiplier`` (``uzawa.require_constraint``).

The anchor update derived from a friction law keeps the traction: after a converged step the
anchor moves so that the slip left is the one at which the law carries the traction it carries
now (``ContactState.elastic_slip``, found by evaluating the law). For the Coulomb return map
that is its elastic slip (a sticking point keeps its anchor and its traction, a slipping one
stays on the cone); for a law with no elastic range, such as a tanh regularisation, it is the
law's inverse at the traction, so a sustained load does not creep from step to step. The
update keeps the slip along the traction's direction: for a law whose traction is not collinear
with its slip (an anisotropic law, away from its yarn directions) it keeps the traction's
magnitude, not its direction.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from fenics_garment._stack import ufl

Expr = ufl.core.expr.Expr


@dataclass(frozen=True)
class Inputs:
    """What a contact law is given: UFL expressions at the contact points.

    In the residual they are linearised about the Newton iterate (the gap to second order on a
    smooth body); in the point-wise updates they are the refreshed point values. Directions are
    unit 3-vectors in the current configuration.

    Attributes:
        gap: g [m], the signed distance from the garment's mid-surface offset (h/2) to the
            body, > 0 open, < 0 overclosed.
        gap_rate: g − g_old [m], the change of the gap since the last converged load step (the
            quasi-static rate: per load step; 0 in the first solve).
        multiplier: λ [Pa], the augmented-Lagrangian multiplier (0 for a pure penalty; Uzawa
            sets it to t_N between solves). A normal law that uses it is a constraint.
        kappa: κ [Pa/m], the normal penalty.
        position: x = X + u [m], the garment point.
        normal: n, the body's outward normal at the closest point.
        warp, weft: the garment's warp and weft (yarn) directions, tangent to the garment
            (None when the contact has no shell frame, e.g. a bare ``ContactState``).
        slip: Δu_T = (I − n⊗n)(u − u_anchor) [m], the tangential slip since the stick/slip
            anchor (a 3-vector orthogonal to n).
        mu: μ, the scene's friction coefficient (None: frictionless contact).
        kappa_t: κ_T [Pa/m], the stick penalty (None: frictionless contact).
        normal_traction: t_N [Pa] of the normal law in use (friction laws only; None for a
            normal law).
    """

    gap: Expr
    gap_rate: Expr
    multiplier: Expr
    kappa: Expr
    position: Expr
    normal: Expr
    warp: Expr | None
    weft: Expr | None
    slip: Expr
    mu: Expr | None = None
    kappa_t: Expr | None = None
    normal_traction: Expr | None = None


#: c -> t_N, see the module doc.
NormalLaw = Callable[[Inputs], Expr]
#: c -> t_T, see the module doc.
FrictionLaw = Callable[[Inputs], Expr]


def macaulay(a: Expr) -> Expr:
    """⟨a⟩₊ = max(a, 0)."""
    return ufl.max_value(a, 0.0)


def augmented_lagrangian(c: Inputs) -> Expr:
    """t_N = ⟨λ − κ g⟩₊: the penalty law (λ = 0) and its augmented-Lagrangian form.

    It is the traction of the potential ψ_c(g) = ⟨λ − κ g⟩₊² / (2κ), t_N = −∂ψ_c/∂g (with λ = 0
    the penalty energy κ⟨−g⟩₊²/2), and Uzawa's update λ ← t_N is its fixed point at g = 0.
    """
    return macaulay(c.multiplier - c.kappa * c.gap)


def coulomb_return_map(c: Inputs, eps: float = 1e-30) -> Expr:
    """Regularised Coulomb friction in return-map form (elastic stick, then the Coulomb cone).

    t_T = −κ_T Δu_T                     if κ_T|Δu_T| ≤ μ t_N  (stick, elastic slip)
    t_T = −μ t_N Δu_T / |Δu_T|          otherwise            (slip)

    i.e. t_T = −κ_T Δu_T · min(1, μ t_N / (κ_T |Δu_T|)); ``eps`` keeps |Δu_T| differentiable
    at 0. Not derived from a potential: the Jacobian is non-symmetric (LU/MUMPS or GMRES).
    """
    slip, limit = c.slip, c.mu * c.normal_traction
    trial = c.kappa_t * ufl.sqrt(ufl.dot(slip, slip) + eps)
    scale = ufl.conditional(ufl.le(trial, limit), 1.0, limit / trial)
    return -c.kappa_t * scale * slip


def uses_multiplier(law: NormalLaw, c: Inputs) -> bool:
    """Whether the normal law's traction depends on ``c.multiplier`` (a Coefficient): then it
    is a constraint, which the augmented Lagrangian drives to g = 0; else a soft law."""
    t_n = law(c)
    return c.multiplier in ufl.algorithms.extract_coefficients(ufl.as_ufl(t_n))
