"""The contact laws, each one UFL function of documented inputs, passed to the contact as a value.

A law is the *only* definition of its physics. The residual uses it on the gap and slip
linearised about the Newton iterate; the point-wise algorithms evaluate the very same function
on the refreshed point values (``ContactState.accept_step``: the stick/slip anchor;
``uzawa.update_multiplier``: λ ← t_N) and the outputs use it for the pressure. Replacing a law
(``contact.normal_law = my_law``, ``contact.friction = replace(contact.friction, law=my_law)``)
therefore changes all three together.

Inputs, per unit *reference* area of the garment at the contact points:

* normal law ``(g, λ, κ) -> t_N``: the gap g [m] (> 0 open), the multiplier λ [Pa] (0 for a
  pure penalty; Uzawa updates it to t_N between solves) and the penalty κ [Pa/m]; returns the
  normal traction t_N ≥ 0 [Pa] pressing the garment outwards along the body normal;
* friction law ``(Δu_T, t_N, μ, κ_T) -> t_T``: the tangential slip since the anchor Δu_T [m]
  (a 3-vector orthogonal to the body normal), the normal traction t_N of the normal law, the
  friction coefficient μ and the stick penalty κ_T [Pa/m]; returns the tangential traction on
  the garment [Pa] (a 3-vector, opposing the slip).

The anchor update derived from a friction law keeps the traction: after a converged step the
anchor moves so that the slip left is the one at which the law carries the traction it carries
now (``ContactState.elastic_slip``, found by evaluating the law). For the Coulomb return map
that is its elastic slip (a sticking point keeps its anchor and its traction, a slipping one
stays on the cone); for a law with no elastic range, such as a tanh regularisation, it is the
law's inverse at the traction, so a sustained load does not creep from step to step.
"""

from __future__ import annotations

from collections.abc import Callable

from fenics_garment._stack import ufl

Expr = ufl.core.expr.Expr
#: (g, λ, κ) -> t_N, see the module doc.
NormalLaw = Callable[[Expr, Expr, Expr], Expr]
#: (Δu_T, t_N, μ, κ_T) -> t_T, see the module doc.
FrictionLaw = Callable[[Expr, Expr, Expr, Expr], Expr]


def macaulay(a: Expr) -> Expr:
    """⟨a⟩₊ = max(a, 0)."""
    return ufl.max_value(a, 0.0)


def augmented_lagrangian(g: Expr, lam: Expr, kappa: Expr) -> Expr:
    """t_N = ⟨λ − κ g⟩₊: the penalty law (λ = 0) and its augmented-Lagrangian form.

    It is the traction of the potential ψ_c(g) = ⟨λ − κ g⟩₊² / (2κ), t_N = −∂ψ_c/∂g (with λ = 0
    the penalty energy κ⟨−g⟩₊²/2), and Uzawa's update λ ← t_N is its fixed point at g = 0.
    """
    return macaulay(lam - kappa * g)


def coulomb_return_map(slip: Expr, t_n: Expr, mu: Expr, kappa_t: Expr, eps: float = 1e-30) -> Expr:
    """Regularised Coulomb friction in return-map form (elastic stick, then the Coulomb cone).

    t_T = −κ_T Δu_T                     if κ_T|Δu_T| ≤ μ t_N  (stick, elastic slip)
    t_T = −μ t_N Δu_T / |Δu_T|          otherwise            (slip)

    i.e. t_T = −κ_T Δu_T · min(1, μ t_N / (κ_T |Δu_T|)); ``eps`` keeps |Δu_T| differentiable
    at 0. Not derived from a potential: the Jacobian is non-symmetric (LU/MUMPS or GMRES).
    """
    norm = ufl.sqrt(ufl.dot(slip, slip) + eps)
    trial = kappa_t * norm
    scale = ufl.conditional(ufl.le(trial, mu * t_n), 1.0, mu * t_n / trial)
    return -kappa_t * scale * slip
