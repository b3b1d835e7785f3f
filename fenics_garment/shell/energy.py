r"""The shell's energy as a sum of named terms, each a short function returning UFL.

Densities are per unit *reference* area. With the stiffness resultants of
:mod:`fenics_garment.materials` (local frame e₁ = warp, e₂ = weft):

.. math::
    \psi_m = \tfrac12 (A_{11}\varepsilon_{11}^2 + 2A_{12}\varepsilon_{11}\varepsilon_{22}
             + A_{22}\varepsilon_{22}^2 + 4A_{66}\varepsilon_{12}^2) \\
    \psi_b = \tfrac12 (D_{11}\kappa_{11}^2 + 2D_{12}\kappa_{11}\kappa_{22}
             + D_{22}\kappa_{22}^2 + 4D_{66}\kappa_{12}^2) \\
    \psi_s = \tfrac12 (S_1\gamma_1^2 + S_2\gamma_2^2), \qquad
    \psi_d = \tfrac12 k_d\, \delta^2 .

To replace a term, write a function with the same signature and pass it to
:class:`fenics_garment.shell.model.ShellModel` (``replace(model, membrane=my_membrane)``).
External work terms return the work of the loads on u; a follower pressure is not conservative
and is returned as a residual contribution instead.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from fenics_garment._stack import dolfinx, ufl
from fenics_garment.materials import ShellStiffness, TensionStrainCurve
from fenics_garment.shell.kinematics import ShellKinematics


@dataclass(frozen=True)
class StiffnessConstants:
    """Stiffness resultants as ``fem.Constant`` s: changing a value does not recompile a form."""

    A11: dolfinx.fem.Constant
    A22: dolfinx.fem.Constant
    A12: dolfinx.fem.Constant
    A66: dolfinx.fem.Constant
    D11: dolfinx.fem.Constant
    D22: dolfinx.fem.Constant
    D12: dolfinx.fem.Constant
    D66: dolfinx.fem.Constant
    S1: dolfinx.fem.Constant
    S2: dolfinx.fem.Constant
    mass_per_area: dolfinx.fem.Constant
    drilling: dolfinx.fem.Constant

    @classmethod
    def create(cls, mesh, s: ShellStiffness, drilling_factor: float = 1e-3) -> StiffnessConstants:
        def c(v: float) -> dolfinx.fem.Constant:
            return dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(v))

        return cls(
            **{k: c(getattr(s, k)) for k in ("A11", "A22", "A12", "A66", "D11", "D22", "D12",
                                              "D66", "S1", "S2", "mass_per_area")},
            drilling=c(drilling_factor * s.A66),
        )  # fmt: skip

    def assign(self, s: ShellStiffness, drilling_factor: float = 1e-3) -> None:
        """Set new material values in place (same compiled forms)."""
        for k in ("A11", "A22", "A12", "A66", "D11", "D22", "D12", "D66", "S1", "S2",
                  "mass_per_area"):  # fmt: skip
            getattr(self, k).value = getattr(s, k)
        self.drilling.value = drilling_factor * s.A66


def _orthotropic_quadratic(e, c11, c22, c12, c66):
    return 0.5 * (c11 * e[0, 0] ** 2 + 2 * c12 * e[0, 0] * e[1, 1] + c22 * e[1, 1] ** 2
                  + 4 * c66 * e[0, 1] ** 2)  # fmt: skip


def membrane_energy(kin: ShellKinematics, C: StiffnessConstants) -> ufl.core.expr.Expr:
    """ψ_m = ½ ε : A : ε, orthotropic in the (warp, weft) frame."""
    return _orthotropic_quadratic(kin.membrane, C.A11, C.A22, C.A12, C.A66)


def membrane_forces(
    kin: ShellKinematics,
    C: StiffnessConstants,
    membrane: Callable[[ShellKinematics, StiffnessConstants], ufl.core.expr.Expr] = membrane_energy,
) -> ufl.core.expr.Expr:
    """N = ∂ψ_m/∂ε [N/m]: the membrane stress resultants (2×2, warp/weft frame) of the law
    ``membrane`` (default :func:`membrane_energy`), by differentiating it with respect to the
    membrane strain ε (the other kinematic fields held fixed) — never restated, so a replaced
    law gives its own forces (``ShellModel.membrane_forces`` passes the law in use)."""
    eps = ufl.variable(kin.membrane)
    return ufl.diff(membrane(replace(kin, membrane=eps), C), eps)


def tabulated_membrane(
    warp: TensionStrainCurve, weft: TensionStrainCurve
) -> Callable[[ShellKinematics, StiffnessConstants], ufl.core.expr.Expr]:
    """A membrane law from measured tension–strain curves, warp and weft (replaces
    :func:`membrane_energy`: ``ShellModel(..., membrane=tabulated_membrane(warp, weft))``).

    ψ_m = W₁(e₁) + W₂(e₂) + 2 A66 ε₁₂², with e_α = √(1 + 2ε_αα) − 1 the engineering strain of
    the warp and weft threads (ε the Green–Lagrange strain in the warp/weft frame) and
    W(e) = ∫₀ᵉ T de the curve's energy. A piecewise-linear T(e) = k₀ e + Σᵢ Δkᵢ ⟨e − eᵢ⟩ (slope
    jumps Δkᵢ at the interior samples eᵢ) gives W(e) = ½k₀e² + ½Σᵢ Δkᵢ⟨e − eᵢ⟩²: C¹, convex
    for a non-decreasing curve. Uniaxially along a thread, S = dW/dε = T(e)/λ, so the nominal
    tension per reference width λS is the curve's T(e) exactly.

    No Poisson coupling between warp and weft (the curves are uniaxial; a woven fabric's
    in-plane Poisson effect is small at the strains of wear) and the in-plane shear keeps the
    material's A66. The samples are ``fem.Constant`` s, so curves with the same number of samples
    share one compiled form.
    """

    def law(kin: ShellKinematics, C: StiffnessConstants) -> ufl.core.expr.Expr:
        domain = ufl.domain.extract_unique_domain(C.A66)
        eps = kin.membrane
        psi = 2 * C.A66 * eps[0, 1] ** 2
        for a, curve in enumerate((warp, weft)):
            k = curve.slopes
            e = ufl.sqrt(1 + 2 * eps[a, a]) - 1
            k0 = dolfinx.fem.Constant(domain, dolfinx.default_scalar_type(k[0]))
            psi += 0.5 * k0 * e**2
            if len(k) > 1:
                knots = dolfinx.fem.Constant(domain, np.asarray(curve.strain[1:-1]))
                jumps = dolfinx.fem.Constant(domain, np.diff(k))
                for i in range(len(k) - 1):
                    psi += 0.5 * jumps[i] * ufl.max_value(e - knots[i], 0.0) ** 2
        return psi

    # named by its curves in the records of the terms in use (summary.json)
    law.__qualname__ = law.__name__ = f"tabulated_membrane[{warp.name} / {weft.name}]"
    return law


def bending_energy(kin: ShellKinematics, C: StiffnessConstants) -> ufl.core.expr.Expr:
    """ψ_b = ½ κ : D : κ, with the measured (not t³-derived) bending rigidities."""
    return _orthotropic_quadratic(kin.bending, C.D11, C.D22, C.D12, C.D66)


def shear_energy(kin: ShellKinematics, C: StiffnessConstants) -> ufl.core.expr.Expr:
    """ψ_s = ½ (S₁ γ₁² + S₂ γ₂²)."""
    g = kin.shear
    return 0.5 * (C.S1 * g[0] ** 2 + C.S2 * g[1] ** 2)


def drilling_energy(kin: ShellKinematics, C: StiffnessConstants) -> ufl.core.expr.Expr:
    """ψ_d = ½ k_d δ², δ tied to the in-plane rotation of the displacement (not to zero)."""
    return 0.5 * C.drilling * kin.drilling**2


def gravity_work(
    u: ufl.core.expr.Expr, C: StiffnessConstants, g: ufl.core.expr.Expr
) -> ufl.core.expr.Expr:
    """W_g = ρh g·u per reference area (mass is conserved, so reference area is right)."""
    return C.mass_per_area * ufl.dot(g, u)


def distributed_load_work(u: ufl.core.expr.Expr, f: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """W = f·u for a dead load f per unit reference area (e.g. a roof's self weight)."""
    return ufl.dot(f, u)


def edge_load_work(u: ufl.core.expr.Expr, t: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """W = t·u for a dead line load t per unit reference edge length (integrate with ds)."""
    return ufl.dot(t, u)


def pressure_residual(
    kin: ShellKinematics, p: ufl.core.expr.Expr, v: ufl.core.expr.Expr
) -> ufl.core.expr.Expr:
    """Follower pressure p on the deformed surface: −p (F e₁ × F e₂)·v per reference area.

    (F e₁ × F e₂) is the deformed normal times the area ratio, so p acts on the deformed area
    along the deformed normal. Not derivable from a potential in general: a residual term.
    """
    return -p * ufl.dot(ufl.cross(kin.F * kin.e1, kin.F * kin.e2), v)


def cell_size(mesh) -> dolfinx.fem.Function:
    """Cell diameter as a DG0 Function (computed once; CellDiameter fails in P2 Expressions)."""
    tdim = mesh.topology.dim
    n = mesh.topology.index_map(tdim).size_local + mesh.topology.index_map(tdim).num_ghosts
    X = mesh.geometry.x[mesh.geometry.dofmaps[0][:n]]
    diam = np.zeros(n)
    for i in range(X.shape[1]):
        for j in range(i + 1, X.shape[1]):
            diam = np.maximum(diam, np.linalg.norm(X[:, i] - X[:, j], axis=1))
    h = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("DG", 0)), name="cell_size")
    h.x.array[:n] = diam
    return h


#: The slider's elastic range κ_y [1/m] of :class:`HystereticBending` unless given: 0.05 cm⁻¹,
#: a tenth of the smallest curvature at which KES-FB2 reads 2HB (0.5 cm⁻¹, Kawabata, The
#: standardization and analysis of hand evaluation, 2nd ed., Textile Machinery Society of Japan
#: 1980) — our choice, stated: the slider is rigid to within it.
YIELD_CURVATURE = 5.0


class HystereticBending:
    r"""A bending law with hysteresis (KES-FB2 2HB), replacing :func:`bending_energy`:
    ``ShellModel(..., bending=HystereticBending(twoHB))`` or ``model.bending = law``.

    Each of the warp and weft bending moments is the elastic one plus a Coulomb-like friction
    moment m_α, |m_α| ≤ HB_α = 2HB_α/2, that opposes the change of curvature: a friction slider
    (a Jenkins element: a stiff spring k_α = HB_α/κ_y in series with a Coulomb slider of
    threshold HB_α) in parallel with the elastic law,

    .. math::
        M_{αα} = \partial\psi_{\rm el}/\partial\kappa_{αα} + m_α, \qquad
        m_α = k_α(\kappa_{αα} - \kappa^p_α), \quad |m_α| \le HB_α .

    Under pure bending beyond κ_y the moment–curvature loop is the KES loop: M = Bκ ± HB, its
    width 2HB at every curvature. The history is the slip κᵖ_α at the quadrature points of the
    bending integral. Within a step the law is the implicit-Euler incremental potential of the
    slider from the last accepted slip κᵖₙ (a Huber function of e = κ − κᵖₙ: ½k e² for
    k|e| ≤ HB, else HB|e| − HB²/2k; convex and C¹, so the Jacobian stays symmetric and
    positive); :meth:`commit` accepts a converged step (return mapping: κᵖ = κ − clip(k e,
    ±HB)/k). A solver path that never commits keeps κᵖ = 0: a nonlinear elastic law, not a
    hysteresis (the drape's path, :func:`fenics_garment.drape.relax`, commits every accepted
    step). Twisting (κ₁₂) stays elastic: the KES measures no twisting hysteresis.

    ``degree``: the quadrature degree of the bending integral (the element's full degree, 4 for
    the P2 elements; a mismatch is refused by the form compiler). ``elastic``: the elastic law
    it adds to (default :func:`bending_energy`).
    """

    def __init__(
        self,
        twoHB_warp: float,
        twoHB_weft: float | None = None,
        *,
        yield_curvature: float = YIELD_CURVATURE,
        degree: int = 4,
        elastic: Callable[[ShellKinematics, StiffnessConstants], ufl.core.expr.Expr] = (
            bending_energy
        ),
    ) -> None:
        weft = twoHB_warp if twoHB_weft is None else twoHB_weft
        for name, v in (("2HB warp", twoHB_warp), ("2HB weft", weft),
                        ("yield curvature", yield_curvature)):  # fmt: skip
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"hysteretic bending: {name} must be positive, got {v!r}")
        self.twoHB = (float(twoHB_warp), float(weft))
        self.yield_curvature = float(yield_curvature)
        self.degree = degree
        self.elastic = elastic
        self.__name__ = self.__qualname__ = (
            f"hysteretic_bending[2HB {self.twoHB[0]:.4g}/{self.twoHB[1]:.4g} N·m/m, "
            f"κ_y {self.yield_curvature:g}/m]"
        )
        self._slip: dolfinx.fem.Function | None = None
        self._update: tuple | None = None  # (Expression, scratch Function)
        self._consts: tuple | None = None

    @property
    def slip(self) -> dolfinx.fem.Function | None:
        """κᵖ (warp, weft) [1/m] at the quadrature points (None before the law is used)."""
        return self._slip

    def _state(self, mesh) -> None:
        import basix.ufl

        if self._slip is not None and self._slip.function_space.mesh is mesh:
            return
        Qe = basix.ufl.quadrature_element(mesh.basix_cell(), value_shape=(2,),
                                          degree=self.degree)  # fmt: skip
        V = dolfinx.fem.functionspace(mesh, Qe)
        self._slip = dolfinx.fem.Function(V, name="bending_slip")
        hb = [0.5 * t for t in self.twoHB]

        def c(v: float) -> dolfinx.fem.Constant:
            return dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(v))

        self._consts = tuple((c(h), c(h / self.yield_curvature)) for h in hb)
        self._update = None

    def friction_moments(self, kin: ShellKinematics) -> list[ufl.core.expr.Expr]:
        """m_α = clip(k_α (κ_αα − κᵖ_α), ±HB_α) [N·m/m] of the current step (warp, weft)."""
        out = []
        for a, (hb, k) in enumerate(self._consts):
            m = k * (kin.bending[a, a] - self._slip[a])
            out.append(ufl.max_value(ufl.min_value(m, hb), -hb))
        return out

    def __call__(self, kin: ShellKinematics, C: StiffnessConstants) -> ufl.core.expr.Expr:
        self._state(_mesh_of(kin.bending))
        psi = self.elastic(kin, C)
        for a, (hb, k) in enumerate(self._consts):
            e = kin.bending[a, a] - self._slip[a]
            inside = 0.5 * k * e**2
            outside = hb * abs(e) - hb**2 / (2 * k)
            psi += ufl.conditional(ufl.le(k * abs(e), hb), inside, outside)
        self._kin = kin
        return psi

    def commit(self) -> None:
        """Accept the current (converged) state: κᵖ ← κ − m/k (the slip the step made)."""
        if self._slip is None:
            return
        if self._update is None:
            kin = self._kin
            m = self.friction_moments(kin)
            slip = ufl.as_vector([kin.bending[a, a] - m[a] / self._consts[a][1]
                                  for a in range(2)])  # fmt: skip
            V = self._slip.function_space
            self._update = (dolfinx.fem.Expression(slip, V.element.interpolation_points),
                            dolfinx.fem.Function(V))  # fmt: skip
        expr, scratch = self._update
        scratch.interpolate(expr)
        self._slip.x.array[:] = scratch.x.array
        self._slip.x.scatter_forward()

    def reset(self) -> None:
        """Forget the history (κᵖ = 0)."""
        if self._slip is not None:
            self._slip.x.array[:] = 0.0


def _mesh_of(expr: ufl.core.expr.Expr):
    """The DOLFINx mesh of the first Function in ``expr`` (the shell's unknown)."""
    from ufl.algorithms import extract_coefficients

    for c in extract_coefficients(expr):
        if isinstance(c, dolfinx.fem.Function):
            return c.function_space.mesh
    raise ValueError("the expression holds no Function: no mesh to put the history on")


def commit_history(model) -> None:
    """Accept a converged step in every law of ``model`` that has a history (a ``commit``
    method, e.g. :class:`HystereticBending`): call after each accepted step of a path."""
    for law in (model.membrane, model.bending, model.shear, model.drilling):
        commit = getattr(law, "commit", None)
        if commit is not None:
            commit()
