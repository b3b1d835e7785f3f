"""TEST MODEL ONLY — a St. Venant–Kirchhoff membrane and the verification scenes of the contact.

To be replaced by the shell's membrane term (``fenics_garment.shell``) once it lands on main.
The membrane lives on a manifold mesh (tdim 2, gdim 3), where UFL's ``grad(x)`` is the 3×3
identity: the deformation gradient is built on the tangent projector P = J (JᵀJ)⁻¹ Jᵀ.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import basix.ufl
import numpy as np

from fenics_garment._stack import MPI, PETSc, dolfinx, ufl
from fenics_garment.contact import terms
from fenics_garment.contact.primitives import cylinder
from fenics_garment.contact.search import BodySurface
from fenics_garment.contact.state import ContactState
from fenics_garment.solve import NonlinearSolver


# -- geometry ---------------------------------------------------------------------------------
def manifold_mesh(comm: MPI.Comm, x: np.ndarray, cells: np.ndarray) -> dolfinx.mesh.Mesh:
    """A P1 triangle mesh in 3D from numpy arrays given on rank 0."""
    el = basix.ufl.element("Lagrange", "triangle", 1, shape=(3,))
    if comm.rank != 0:
        x, cells = np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    return dolfinx.mesh.create_mesh(comm, cells.astype(np.int64), el, x)


def tube_mesh(comm: MPI.Comm, r0: float, length: float, n_theta: int, n_z: int):
    """Tube of radius r0 about the z axis, z ∈ [−L/2, L/2], structured, all diagonals alike.

    Every vertex then has valence 6 and the same lumped (one-third) area: alternating diagonals
    give valences 4 and 8 and a nodal contact area, hence nodal pressure, varying by 2×.
    """
    θ = np.linspace(0, 2 * np.pi, n_theta, endpoint=False)
    z = np.linspace(-length / 2, length / 2, n_z + 1)
    x = np.array([[r0 * np.cos(t), r0 * np.sin(t), zk] for zk in z for t in θ])
    i, k = np.meshgrid(np.arange(n_theta), np.arange(n_z), indexing="ij")
    i, k = i.ravel(), k.ravel()
    a, b = k * n_theta + i, k * n_theta + (i + 1) % n_theta
    c, d = a + n_theta, b + n_theta
    return manifold_mesh(
        comm, x, np.vstack([np.column_stack([a, b, d]), np.column_stack([a, d, c])])
    )


def strip_mesh(comm: MPI.Comm, rho: float, theta: float, tail: float, width: float, n_s: int,
               n_w: int):  # fmt: skip
    """Strip wrapped on a circle of radius rho (axis z) by angle theta, with straight tails.

    Centre line (in the xy plane): from (rho, −tail) up the tangent line x = rho to (rho, 0),
    around the arc φ ∈ [0, θ], then along the tangent at φ = θ for a length ``tail``.
    Returns the mesh and the arc length of the centre line s ∈ [0, 2 tail + rho θ].
    """
    total = 2 * tail + rho * theta
    s = np.linspace(0, total, n_s + 1)
    w = np.linspace(-width / 2, width / 2, n_w + 1)
    pts = []
    for sk in s:
        if sk <= tail:
            p = (rho, sk - tail)
        elif sk <= tail + rho * theta:
            φ = (sk - tail) / rho
            p = (rho * np.cos(φ), rho * np.sin(φ))
        else:
            e = sk - tail - rho * theta
            p = (rho * np.cos(theta) - e * np.sin(theta), rho * np.sin(theta) + e * np.cos(theta))
        pts.append(p)
    x = np.array([[px, py, wk] for (px, py) in pts for wk in w])
    nw = n_w + 1
    i, k = np.meshgrid(np.arange(n_s), np.arange(n_w), indexing="ij")
    i, k = i.ravel(), k.ravel()
    a, b = i * nw + k, i * nw + k + 1
    c, d = a + nw, b + nw
    cells = np.vstack([np.column_stack([a, c, d]), np.column_stack([a, d, b])])
    return manifold_mesh(comm, x, cells), total


# -- the test membrane ------------------------------------------------------------------------
def tangent_projector(mesh: dolfinx.mesh.Mesh):
    """P = J (JᵀJ)⁻¹ Jᵀ: projector onto the tangent plane of the reference surface."""
    J = ufl.Jacobian(mesh)
    return J * ufl.inv(J.T * J) * J.T


def green_strain(u, mesh: dolfinx.mesh.Mesh):
    """E = ½(FᵀF − P) with F = P + ∇u (∇u is tangential on a manifold mesh)."""
    P = tangent_projector(mesh)
    F = P + ufl.grad(u)
    return 0.5 * (F.T * F - P)


def area_stretch(u, mesh: dolfinx.mesh.Mesh):
    """J_s = da/dA = √det(aᵀa)/√det(JᵀJ), a = (I + ∇u) J the deformed tangent basis."""
    J = ufl.Jacobian(mesh)
    a = (ufl.Identity(3) + ufl.grad(u)) * J
    return ufl.sqrt(ufl.det(a.T * a) / ufl.det(J.T * J))


@dataclass(frozen=True)
class Fabric:
    """Orthotropic fabric (plane stress): warp modulus E1, weft E2, ν12 (warp load → weft
    contraction), in-plane shear G12, thickness h. Isotropic: :meth:`isotropic`."""

    E1: float
    E2: float
    nu12: float
    G12: float
    h: float

    @classmethod
    def isotropic(cls, E: float, nu: float, h: float) -> Fabric:
        return cls(E, E, nu, E / (2 * (1 + nu)), h)

    @property
    def nu21(self) -> float:
        return self.nu12 * self.E2 / self.E1


def membrane_energy(u, mesh, fabric: Fabric, warp) -> ufl.core.expr.Expr:
    """ψ_m = h/2 [Q11 E11² + 2 Q12 E11 E22 + Q22 E22² + 4 G12 E12²]  (SVK, plane stress).

    E11 = d·E·d (warp d), E22 = tr E − E11, E12² = d·E·E·d − E11²;
    Q11 = E1/(1−ν12ν21), Q22 = E2/(1−ν12ν21), Q12 = ν12 Q22.
    """
    E = green_strain(u, mesh)
    den = 1 - fabric.nu12 * fabric.nu21
    q11, q22 = fabric.E1 / den, fabric.E2 / den
    q12 = fabric.nu12 * q22
    e11 = ufl.dot(warp, E * warp)
    e22 = ufl.tr(E) - e11
    e12sq = ufl.dot(E * warp, E * warp) - e11**2
    return 0.5 * fabric.h * (q11 * e11**2 + 2 * q12 * e11 * e22 + q22 * e22**2
                             + 4 * fabric.G12 * e12sq)  # fmt: skip


# -- analytic references ----------------------------------------------------------------------
def laplace_tube_pressure(R_c: float, r0: float, E_hoop: float, nu_hz: float, h: float) -> float:
    """Exact pressure of a free-ended SVK tube of rest radius r0 stretched onto radius R_c.

    E_θθ = ((R_c/r0)² − 1)/2; S_zz = 0 ⇒ E_zz = −ν_θz E_θθ, λ_z = √(1 − 2ν_θz E_θθ);
    S_θθ = E_θ h E_θθ; Cauchy hoop force n_θθ = (λ_θ/λ_z) S_θθ; p = n_θθ/R_c
    = E_θ h E_θθ/(λ_z r0).  (STACK.md, "Penalty contact of a tight tube".)
    """
    e = ((R_c / r0) ** 2 - 1) / 2
    lz = np.sqrt(1 - 2 * nu_hz * e)
    return E_hoop * h * e / (lz * r0)


# -- scenes -----------------------------------------------------------------------------------
@dataclass
class Scene:
    mesh: dolfinx.mesh.Mesh
    u: dolfinx.fem.Function
    state: ContactState
    problem: NonlinearSolver
    kappa: dolfinx.fem.Constant
    fabric: Fabric
    bcs: list = field(default_factory=list)
    extra: dict = field(default_factory=dict)


SNES_OPTIONS = {
    "snes_type": "newtonls",
    "snes_linesearch_type": "basic",
    "snes_rtol": 1e-10,
    "snes_atol": 1e-9,
    "snes_stol": 0.0,
    "snes_max_it": 30,
    "snes_divergence_tolerance": -1,
    "ksp_type": "preonly",
    "pc_type": "lu",
    "pc_factor_mat_solver_type": "mumps",
}


@dataclass
class MembraneModel:
    """What :class:`NonlinearSolver` needs of a model: the unknown and the residual form."""

    q: dolfinx.fem.Function
    F: ufl.Form

    def residual(self) -> ufl.Form:
        return self.F

    def jacobian(self, F: ufl.Form) -> ufl.Form:
        return ufl.derivative(F, self.q, ufl.TrialFunction(self.q.function_space))


def build_problem(mesh, u, energy, state, kappa, bcs, friction=None, prefix="contact_",
                  options=None):  # fmt: skip
    """Residual = δ(membrane energy) + contact virtual work; the refresh as pre-residual hook."""
    v = ufl.TestFunction(u.function_space)
    F = ufl.derivative(energy, u, v) + terms.contact_residual(state, v, kappa, friction)
    opts = dict(SNES_OPTIONS)
    opts.update(options or {})
    return NonlinearSolver(MembraneModel(u, F), bcs, pre_residual=[state.refresh],
                           petsc_options=opts, prefix=prefix)  # fmt: skip


def laplace_tube(
    comm: MPI.Comm,
    *,
    n_theta: int = 48,
    n_z: int = 8,
    fabric: Fabric | None = None,
    warp: str = "axial",
    kappa_hat: float = 10.0,
    rule: str = "vertex",
    degree: int = 1,
    R: float = 0.1,
    r0: float = 0.093,
    L: float = 0.1,
    n_body: int = 1024,
    normal: str = "gradient",
    kappa: float | None = None,
) -> Scene:
    """Tight tube (rest radius r0, ease −7 %) on a rigid cylinder of radius R (STACK.md set-up)."""
    fabric = fabric or Fabric.isotropic(1e6, 0.3, 1e-3)
    mesh = tube_mesh(comm, r0, L, n_theta, n_z)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", degree, (3,)))
    u = dolfinx.fem.Function(V, name="u")
    body = BodySurface(*cylinder(R, -L, L, n_body, 4))
    state = ContactState(mesh, u, body, offset=fabric.h / 2, rule=rule, band=0.02, normal=normal)
    x = ufl.SpatialCoordinate(mesh)
    r = ufl.sqrt(x[0] ** 2 + x[1] ** 2)
    axial = ufl.as_vector([0.0, 0.0, 1.0])
    hoop = ufl.as_vector([-x[1] / r, x[0] / r, 0.0])
    d = axial if warp == "axial" else hoop
    energy = membrane_energy(u, mesh, fabric, d) * ufl.dx(metadata={"quadrature_degree": 2})
    h_e = 2 * np.pi * r0 / n_theta
    if kappa is None:
        kappa = terms.default_penalty(fabric.E1 * fabric.h, h_e, kappa_hat)
    kappa = dolfinx.fem.Constant(mesh, kappa)
    # zero-stiffness modes (axial slide, spin): fix u_y, u_z at the node (r0, 0, 0), which the
    # exact solution satisfies (STACK.md).
    node = dolfinx.mesh.locate_entities(
        mesh, 0, lambda p: np.isclose(p[0], r0) & np.isclose(p[1], 0) & np.isclose(p[2], 0)
    )
    mesh.topology.create_connectivity(0, 2)
    bcs = []
    for comp in (1, 2):
        dofs = dolfinx.fem.locate_dofs_topological(V.sub(comp), 0, node)
        bcs.append(dolfinx.fem.dirichletbc(PETSc.ScalarType(0), dofs, V.sub(comp)))
    E_hoop, nu_hz = (fabric.E2, fabric.nu21) if warp == "axial" else (fabric.E1, fabric.nu12)
    ref = laplace_tube_pressure(R + fabric.h / 2, r0, E_hoop, nu_hz, fabric.h)
    problem = build_problem(mesh, u, energy, state, kappa, bcs)
    return Scene(mesh, u, state, problem, kappa, fabric, bcs, {"reference": ref, "R": R,
                                                               "r0": r0, "L": L})  # fmt: skip


def strip_direction(mesh: dolfinx.mesh.Mesh, rho: float, theta: float) -> dolfinx.fem.Function:
    """Unit centre-line tangent of the wrapped strip (DG0), from the cell midpoints."""
    V = dolfinx.fem.functionspace(mesh, ("DG", 0, (3,)))
    d = dolfinx.fem.Function(V)

    def tangent(p: np.ndarray) -> np.ndarray:
        x, y = p[0], p[1]
        φ = np.arctan2(y, x)
        t = np.vstack([-np.sin(φ), np.cos(φ), np.zeros_like(x)])
        t[:, y < 0] = np.array([[0.0], [1.0], [0.0]])
        after = φ > theta
        t[:, after] = np.array([[-np.sin(theta)], [np.cos(theta)], [0.0]])
        return t

    d.interpolate(tangent)
    return d


def capstan_strip(
    comm: MPI.Comm,
    *,
    mu: float,
    theta: float = np.pi / 2,
    R: float = 0.1,
    tail: float = 0.05,
    width: float = 0.02,
    n_s: int = 120,
    n_w: int = 2,
    prestrain: float = 0.02,
    kappa_hat: float = 10.0,
) -> Scene:
    """Membrane strip (E = 1 MPa, ν = 0, h = 1 mm) over a rigid cylinder by angle θ.

    End A (s = 0) is clamped; end B is pulled along its tail (u_x = −δ, u_y = 0 at θ = π/2).
    A prestrain e₀ along the strip puts it in tension on the cylinder from the start.
    """
    assert np.isclose(theta, np.pi / 2), "the B-end Dirichlet data assume θ = π/2"
    fabric = Fabric.isotropic(1e6, 0.0, 1e-3)
    rho = R + fabric.h / 2 - 1e-6  # start just inside, so that the contact is active at once
    mesh, total = strip_mesh(comm, rho, theta, tail, width, n_s, n_w)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (3,)))
    u = dolfinx.fem.Function(V, name="u")
    body = BodySurface(*cylinder(R, -0.05, 0.05, 2048, 2))
    state = ContactState(mesh, u, body, offset=fabric.h / 2, band=0.01)
    d = strip_direction(mesh, rho, theta)
    E = green_strain(u, mesh) + prestrain * ufl.outer(d, d)  # rest length shorter by e₀
    q = fabric.E1 / (1 - fabric.nu12**2)
    psi = 0.5 * fabric.h * q * ((1 - fabric.nu12) * ufl.inner(E, E) + fabric.nu12 * ufl.tr(E) ** 2)
    energy = psi * ufl.dx(metadata={"quadrature_degree": 2})
    h_e = total / n_s
    kappa = dolfinx.fem.Constant(mesh, terms.default_penalty(fabric.E1 * fabric.h, h_e, kappa_hat))
    friction = terms.Friction(mu=dolfinx.fem.Constant(mesh, mu), kappa_t=kappa)
    fdim = 1
    mesh.topology.create_connectivity(fdim, 2)
    end_a = dolfinx.mesh.locate_entities_boundary(mesh, fdim, lambda p: np.isclose(p[1], -tail))
    end_b = dolfinx.mesh.locate_entities_boundary(mesh, fdim, lambda p: np.isclose(p[0], -tail))
    delta = dolfinx.fem.Constant(mesh, 0.0)
    dofs_a = [dolfinx.fem.locate_dofs_topological(V.sub(c), fdim, end_a) for c in range(3)]
    dofs_b = [dolfinx.fem.locate_dofs_topological(V.sub(c), fdim, end_b) for c in range(3)]
    zero = PETSc.ScalarType(0)
    bcs = [dolfinx.fem.dirichletbc(zero, dofs_a[c], V.sub(c)) for c in range(3)]
    bcs.append(dolfinx.fem.dirichletbc(delta, dofs_b[0], V.sub(0)))
    bcs.append(dolfinx.fem.dirichletbc(zero, dofs_b[1], V.sub(1)))
    problem = build_problem(mesh, u, energy, state, kappa, bcs, friction, prefix="capstan_")
    v = ufl.TestFunction(V)
    internal = dolfinx.fem.form(ufl.derivative(energy, u, v))
    extra = {"delta": delta, "internal": internal, "dofs_a": dofs_a[1], "dofs_b": dofs_b[0],
             "theta": theta}  # fmt: skip
    return Scene(mesh, u, state, problem, kappa, fabric, bcs, extra)


def end_tensions(scene: Scene) -> tuple[float, float]:
    """Tension forces [N] at the held end A (along +y) and the pulled end B (along −x).

    They are the elastic internal forces at the end dofs (the tails carry no contact).
    """
    b = dolfinx.fem.assemble_vector(scene.extra["internal"])
    b.scatter_reverse(dolfinx.la.InsertMode.add)
    n_owned = scene.u.function_space.dofmap.index_map.size_local * 3
    da, db = scene.extra["dofs_a"], scene.extra["dofs_b"]
    ta = b.array[da[da < n_owned]].sum()
    tb = b.array[db[db < n_owned]].sum()
    comm = scene.mesh.comm
    return -comm.allreduce(ta, op=MPI.SUM), -comm.allreduce(tb, op=MPI.SUM)
