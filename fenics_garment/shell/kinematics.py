r"""Kinematics of the geometrically nonlinear Naghdi (Reissner–Mindlin) shell on a surface mesh.

The mid-surface moves by the displacement u; the director is rotated from its reference d₀ by a
finite rotation R(θ) parametrised by the *total rotation vector* θ (three components):

.. math::
    \phi = X + u, \qquad d = R(\theta)\, d_0, \qquad
    R(\theta) = \exp(\hat\theta) = I + \frac{\sin|\theta|}{|\theta|}\hat\theta
      + \frac{1-\cos|\theta|}{|\theta|^2}\hat\theta^2 .

The exponential map is regular for |θ| < 2π, so there is no singularity at the ±90° rotations a
draped garment reaches (the two-angle director of many Naghdi codes is singular there). Near θ = 0
the coefficients use their Taylor series so that UFL's derivatives stay finite.

Strains are expressed with the surface deformation gradient F = P + ∇u (∇ is the tangential
gradient on the manifold mesh and P = I − n⊗n the tangent projector) in an orthonormal local frame
(e₁, e₂) of the reference tangent plane (seed paper eq. (10)–(11)):

.. math::
    \varepsilon_{\alpha\beta} = \tfrac12 (e_\alpha\cdot F^T F e_\beta - \delta_{\alpha\beta})
        \quad\text{(Green–Lagrange membrane strain)}\\
    \kappa_{\alpha\beta} = \operatorname{sym}(e_\alpha\cdot F^T \nabla d\, e_\beta)
        - \operatorname{sym}(e_\alpha\cdot \nabla d_0\, e_\beta) \quad\text{(bending)}\\
    \gamma_\alpha = e_\alpha\cdot F^T d - e_\alpha\cdot d_0 \quad\text{(transverse shear)}

Subtracting the reference values makes the mesh configuration stress free even though the
averaged director d₀ is only approximately normal to a faceted mesh. The drilling strain
δ = ½(R e₁·F e₂ − R e₂·F e₁) vanishes when the in-plane part of R equals the rotation of the polar
decomposition of F; it ties the drilling component of θ to the in-plane rotation of the
displacement field (never to zero), which removes its zero-energy mode without locking.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fenics_garment._stack import dolfinx, ufl
from fenics_garment.shell.geometry import (
    cell_normal,
    cell_orientation,
    local_frame,
    nodal_director,
    tangent_projector,
)
from fenics_garment.shell.rest import FlatRest

_SMALL = 1e-6  # |θ|² below which the Taylor branch of the exponential map is used


def skew(v: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """The skew matrix v̂ with v̂ a = v × a."""
    return ufl.as_matrix([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def rotation_matrix(theta: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """R = exp(θ̂) (Rodrigues' formula) with Taylor branches for the coefficients near θ = 0."""
    a2 = ufl.dot(theta, theta)
    a = ufl.sqrt(a2 + ufl.conditional(ufl.lt(a2, _SMALL), 1.0, 0.0))  # never sqrt(0) in a branch
    c1 = ufl.conditional(ufl.lt(a2, _SMALL), 1 - a2 / 6 + a2**2 / 120, ufl.sin(a) / a)
    c2 = ufl.conditional(ufl.lt(a2, _SMALL), 0.5 - a2 / 24 + a2**2 / 720, (1 - ufl.cos(a)) / a2)
    T = skew(theta)
    return ufl.Identity(3) + c1 * T + c2 * T * T


def rotate(theta: ufl.core.expr.Expr, v: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """R(θ) v without forming R: v + c₁ θ×v + c₂ (θ(θ·v) − |θ|² v), since θ̂v = θ×v and
    θ̂²v = θ×(θ×v) = θ(θ·v) − |θ|² v; c₁, c₂ as in :func:`rotation_matrix` (same branches).

    Equal to ``rotation_matrix(theta) * v`` to rounding; its derivatives are cheaper (no 3×3
    products with zero entries to expand), which is what the Jacobian kernel pays for.
    """
    a2 = ufl.dot(theta, theta)
    a = ufl.sqrt(a2 + ufl.conditional(ufl.lt(a2, _SMALL), 1.0, 0.0))
    c1 = ufl.conditional(ufl.lt(a2, _SMALL), 1 - a2 / 6 + a2**2 / 120, ufl.sin(a) / a)
    c2 = ufl.conditional(ufl.lt(a2, _SMALL), 0.5 - a2 / 24 + a2**2 / 720, (1 - ufl.cos(a)) / a2)
    return v + c1 * ufl.cross(theta, v) + c2 * (ufl.dot(theta, v) * theta - a2 * v)


def warp_constant(mesh: dolfinx.mesh.Mesh, direction) -> dolfinx.fem.Constant:
    """A uniform warp direction as a ``fem.Constant`` (data of the compiled forms, not code)."""
    c = dolfinx.fem.Constant(mesh, np.zeros(3, dtype=dolfinx.default_scalar_type))
    c.value[:] = _checked_direction(direction)
    return c


def _checked_direction(direction) -> np.ndarray:
    try:
        w = np.asarray(direction, dtype=np.float64).reshape(3)
    except (TypeError, ValueError):
        raise ValueError(f"warp direction must be 3 numbers, got {direction!r}") from None
    if not np.all(np.isfinite(w)) or np.linalg.norm(w) == 0.0:
        raise ValueError(f"warp direction must be a finite nonzero vector, got {tuple(w)}")
    return w


@dataclass(frozen=True)
class ShellGeometry:
    """What the shell needs to know about its reference surface, computed from the mesh.

    The warp is *data* of the forms: a uniform direction given as three numbers becomes a
    ``fem.Constant`` (:meth:`set_warp` changes it in place), a field is a ``fem.Function``; so
    a new warp direction reuses the compiled forms (no JIT; a literal vector would be folded
    into the kernels and recompile them, 65–140 s cold for the shell's forms).
    """

    mesh: dolfinx.mesh.Mesh
    orientation: dolfinx.fem.Function  # DG0, ±1
    director: dolfinx.fem.Function  # d₀, continuous, unit at the nodes
    warp: ufl.core.expr.Expr  # a vector field, projected onto each tangent plane for e₁
    #: a flat stress-free rest state (sewing-pattern panels, :mod:`.rest`), or None: the mesh
    #: itself is stress free
    rest: FlatRest | None = None

    @classmethod
    def from_mesh(
        cls,
        mesh: dolfinx.mesh.Mesh,
        *,
        warp=(1.0, 0.0, 0.0),
        outward=None,
        director_degree: int = 2,
        rest: dolfinx.fem.Function | None = None,
    ) -> ShellGeometry:
        """Orient the cells, average the director, and set the warp direction (three numbers:
        a ``fem.Constant``; or a ``fem.Function``/UFL vector field, used as given).

        ``rest``: a flat map (:mod:`.rest`) makes the flat panels the stress-free state; the
        warp then comes from the panels' grain lines and ``warp`` is not used by the strains.
        """
        if mesh.topology.dim != 2 or mesh.geometry.dim != 3:
            raise ValueError(
                f"a shell needs a surface mesh in 3D (tdim 2, gdim 3); got tdim "
                f"{mesh.topology.dim}, gdim {mesh.geometry.dim}"
            )
        s = cell_orientation(mesh, outward)
        d0 = nodal_director(mesh, s, director_degree)
        w = warp if isinstance(warp, ufl.core.expr.Expr) else warp_constant(mesh, warp)
        flat = None if rest is None else FlatRest(rest)
        return cls(mesh=mesh, orientation=s, director=d0, warp=w, rest=flat)

    def set_warp(self, direction) -> None:
        """Change a uniform warp direction in place: the next assembly uses it, no recompile.

        Only for a warp made from three numbers (a ``fem.Constant``); a warp field is changed
        through its own Function's values.
        """
        if not isinstance(self.warp, dolfinx.fem.Constant):
            raise ValueError(
                "set_warp needs a uniform warp (made from three numbers); this geometry's warp "
                f"is a {type(self.warp).__name__}: change its values instead"
            )
        self.warp.value[:] = _checked_direction(direction)

    @property
    def normal(self) -> ufl.core.expr.Expr:
        """Oriented unit normal of the cells (discontinuous across faceted edges)."""
        return cell_normal(self.mesh, self.orientation)

    @property
    def d0(self) -> ufl.core.expr.Expr:
        """Reference director, renormalised at quadrature points."""
        d = self.director
        return d / ufl.sqrt(ufl.dot(d, d))

    def frame(self) -> tuple[ufl.core.expr.Expr, ufl.core.expr.Expr]:
        """(e₁, e₂): warp and weft of the stress-free fabric, unit in its metric."""
        if self.rest is not None:
            return self.rest.frame(self.normal)
        return local_frame(self.normal, self.warp)

    @property
    def rest_area(self) -> ufl.core.expr.Expr | None:
        """dA_rest / dA_mesh (the flat panels' area per mesh area), None if the mesh is the
        rest state (ratio 1, left out of the forms)."""
        return None if self.rest is None else self.rest.area_ratio


@dataclass(frozen=True)
class ShellKinematics:
    """Strains of the current configuration (u, θ), all in the local frame (e₁, e₂)."""

    F: ufl.core.expr.Expr  # 3×3 surface deformation gradient, F = P + ∇u
    R: ufl.core.expr.Expr  # 3×3 rotation of the director
    d: ufl.core.expr.Expr  # current director
    e1: ufl.core.expr.Expr
    e2: ufl.core.expr.Expr
    membrane: ufl.core.expr.Expr  # 2×2 Green–Lagrange strain ε
    bending: ufl.core.expr.Expr  # 2×2 curvature change κ
    shear: ufl.core.expr.Expr  # 2-vector transverse shear strain γ
    drilling: ufl.core.expr.Expr  # scalar drilling strain δ
    #: dA_rest/dA_mesh when the frame (e₁, e₂) is that of flat pattern pieces (the strains
    #: are then per unit rest area; an area per mesh area is multiplied by it), else None
    rest_area: ufl.core.expr.Expr | None = None


def shell_kinematics(
    geometry: ShellGeometry, u: ufl.core.expr.Expr, theta: ufl.core.expr.Expr
) -> ShellKinematics:
    """Membrane, bending, shear and drilling strains of the displacement u and rotation θ.

    Written with the deformed tangent vectors F e_α and the director's derivatives ∇d e_α
    (ε_αβ = ½(F e_α·F e_β − δ_αβ), κ_αβ = sym(F e_α·∇d e_β) − …, γ_α = F e_α·d − e_α·d₀) and
    with :func:`rotate` instead of the matrix R: the same strains as the matrix products of
    the module docstring, to rounding (3e-16 relative on a residual and a Jacobian product at
    rotations ≈ 0.3 rad), in kernels FFCx makes cheaper — measured on a P2B-P2B cylinder patch
    (16×16, order-2 geometry, interleaved assemblies, CPU time): Jacobian 0.75× (median of 15),
    residual 0.68×.
    """
    n = geometry.normal
    P = tangent_projector(n)
    e1, e2 = geometry.frame()
    e = (e1, e2)
    d0 = geometry.d0
    F = P + ufl.grad(u)
    d = rotate(theta, d0)
    Fe = (F * e1, F * e2)
    gd = ufl.grad(d)
    gde = (gd * e1, gd * e2)
    Pd0 = P * ufl.grad(d0)
    # rest metric and curvature: the mesh's own (a curved mesh is stress free), or those of
    # flat panels (metric δ in their frame, curvature 0), reached from the mesh's as the
    # sewing parameter w of the flat rest state goes from 0 to 1 (w = 1: the pattern)
    w = None if geometry.rest is None else geometry.rest.sewn

    def rest_metric(a: int, b: int) -> ufl.core.expr.Expr | float:
        delta = 1.0 if a == b else 0.0
        return delta if w is None else w * delta + (1 - w) * ufl.dot(e[a], e[b])

    def rest_curvature(a: int, b: int) -> ufl.core.expr.Expr:
        k = 0.5 * (ufl.dot(e[a], Pd0 * e[b]) + ufl.dot(e[b], Pd0 * e[a]))
        return k if w is None else (1 - w) * k

    eps = ufl.as_matrix([[0.5 * (ufl.dot(Fe[a], Fe[b]) - rest_metric(a, b))
                          for b in range(2)] for a in range(2)])  # fmt: skip

    kap = ufl.as_matrix(
        [[0.5 * (ufl.dot(Fe[a], gde[b]) + ufl.dot(Fe[b], gde[a])) - rest_curvature(a, b)
          for b in range(2)] for a in range(2)]
    )  # fmt: skip
    gam = ufl.as_vector([ufl.dot(Fe[a], d) - ufl.dot(e[a], d0) for a in range(2)])
    drill = 0.5 * (ufl.dot(rotate(theta, e1), Fe[1]) - ufl.dot(rotate(theta, e2), Fe[0]))
    return ShellKinematics(F=F, R=rotation_matrix(theta), d=d, e1=e1, e2=e2, membrane=eps,
                           bending=kap, shear=gam, drilling=drill,
                           rest_area=geometry.rest_area)  # fmt: skip
