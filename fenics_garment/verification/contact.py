"""Verification scenes of contact on the shell, with their exact pressures.

* :func:`tight_tube` — a tube of rest radius r0 pulled over a rigid cylinder of radius R > r0
  (Laplace's law, free ends). One eighth is modelled: the quarter circle θ ∈ [0, π/2] and the
  half length z ∈ [0, L/2], with symmetry planes x = 0, y = 0 and z = 0; these also remove the
  zero-stiffness modes of a frictionless tube (spin, axial slide) without biasing the answer.
* :func:`tight_cap` — a spherical cap of rest radius r0 on a rigid sphere of radius R > r0,
  its edge held at the exact (homogeneous, equal-biaxial) solution u = (λ − 1)X, θ = 0.

Both dress by shrinking the body (``ContactState.shrink``) and growing it back. The warp is a
P2 vector Function (axial, hoop or fixed), so every scene and material shares one compiled form.

Exact pressures, mid-surface contact radius R_c = R + h/2, stretch λ = R_c/r0, Green–Lagrange
E = (λ² − 1)/2, SVK membrane (A = stiffness resultants in the local frame):

* tube (free ends, S_zz = 0): E_zz = −ν_θz E, λ_z = √(1 + 2E_zz), S_θθ = E_θ h E,
  n_θθ = (λ/λ_z) S_θθ, p_m = n_θθ/R_c;
* cap (equal biaxial stretch): S₁ = (A11 + A12) E, S₂ = (A12 + A22) E along the two frame
  directions, n_α = S_α, p_m = (n₁ + n₂)/R_c (Laplace's law for a membrane on a sphere; for an
  orthotropic fabric A11 ≠ A22 and the isotropic shortcut 2(A11 + A12)E/R_c is off, e.g. 4.6 %
  for nylon);
* bending: the director stays radial, κ = (λ − 1)/r0 in the curved directions; the virtual
  work of the uniform moment adds p_b = D_θθ (λ − 1)/(r0² R_c) on the tube (with λ_z = 1 in
  the bending energy's area, since κ_zz = 0 the moment does no axial work) and
  p_b = (D11 + 2 D12 + D22)(λ − 1)/(r0 R_c²) on the cap: both from dΠ/dR_c per deformed area.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fenics_garment._stack import MPI, dolfinx
from fenics_garment.contact import pressure
from fenics_garment.contact import shell as shell_contact
from fenics_garment.contact.primitives import cylinder, sphere_patch
from fenics_garment.contact.search import SearchSurface
from fenics_garment.materials import Fabric, TensionStrainCurve
from fenics_garment.shell import bcs as shell_bcs
from fenics_garment.shell.energy import tabulated_membrane
from fenics_garment.shell.geometry import parametric_surface_mesh
from fenics_garment.shell.kinematics import ShellGeometry
from fenics_garment.shell.model import ShellModel
from fenics_garment.shell.rest import flat_map_from_function
from fenics_garment.solve import NonlinearSolver

#: Synthetic, strongly orthotropic test fabric: warp 4× stiffer than weft (not a reference value).
ORTHO = dict(E_warp=2.0e6, E_weft=0.5e6, G12=2.0e5, B_warp=1.0e-4, B_weft=2.5e-5,
             thickness=1.0e-3, density=0.0, nu12=0.4, name="ortho-test")  # fmt: skip


@dataclass
class ContactCase:
    model: ShellModel
    contact: shell_contact.ShellContact
    solver: NonlinearSolver
    bcs: list
    reference: float
    R: float
    r0: float
    extra: dict = field(default_factory=dict)

    @property
    def state(self):
        return self.contact.state

    @property
    def penetration0(self) -> float:
        """Initial penetration of the undeformed garment [m]: R_c − r0."""
        return self.R + self.model.stiffness.thickness / 2 - self.r0


def _warp_function(mesh, kind: str) -> dolfinx.fem.Function:
    W = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (3,)))
    w = dolfinx.fem.Function(W, name="warp")

    def field_(x):
        r = np.hypot(x[0], x[1])
        if kind == "axial":
            return np.vstack([0 * x[0], 0 * x[0], 1 + 0 * x[0]])
        if kind == "hoop":
            return np.vstack([-x[1] / r, x[0] / r, 0 * x[0]])
        if kind == "x":
            return np.vstack([1 + 0 * x[0], 0 * x[0], 0 * x[0]])
        raise ValueError(f"warp must be 'axial', 'hoop' or 'x', not {kind!r}")

    w.interpolate(field_)
    return w


def _distort_tube_mesh(mesh, r0: float, L: float, n: tuple[int, int], amount: float) -> None:
    """Move the interior vertices of a P2 tube mesh within the cylinder by up to ``amount`` of a
    cell (a fixed pseudo-random hash of their position, so ranks agree) and put each edge node
    back at its edge's parameter midpoint: straight-sided (in (θ, z)) but distorted triangles on
    the exact surface."""
    dt, dz = np.pi / 2 / n[0], L / 2 / n[1]
    x = mesh.geometry.x
    t, z = np.arctan2(x[:, 1], x[:, 0]), x[:, 2].copy()

    def hash01(a, b, seed):
        return np.modf(np.abs(np.sin(12.9898 * a + 78.233 * b + seed) * 43758.5453))[0] - 0.5

    inside = (t > 1e-9) & (t < np.pi / 2 - 1e-9) & (z > 1e-12) & (z < L / 2 - 1e-12)
    cells = mesh.geometry.dofmaps[0]
    verts = np.unique(cells[:, :3])
    tv, zv = t.copy(), z.copy()
    i = verts[inside[verts]]
    tv[i] += amount * dt * hash01(t[i] / dt, z[i] / dz, 0.0)
    zv[i] += amount * dz * hash01(t[i] / dt, z[i] / dz, 1.7)
    for node, (a, b) in ((3, (1, 2)), (4, (0, 2)), (5, (0, 1))):  # basix P2 triangle edges
        k = cells[:, node]
        tv[k] = 0.5 * (tv[cells[:, a]] + tv[cells[:, b]])
        zv[k] = 0.5 * (zv[cells[:, a]] + zv[cells[:, b]])
    x[:, 0], x[:, 1], x[:, 2] = r0 * np.cos(tv), r0 * np.sin(tv), zv


def tube_pressure(
    R_c: float,
    r0: float,
    s,
    *,
    warp: str = "axial",
    bending: bool = True,
    stuck: bool = False,
    flat: bool = False,
):
    """Exact free-end pressure of a tight shell tube [Pa] (module docstring).

    ``flat``: the tube is a flat rectangle of width 2πr0 sewn into a tube (rest curvature 0),
    not a stress-free cylinder. The membrane part is the same; the bending strain is
    κ = F a_θ·∇d a_θ = λ²/R_c = λ/r0 instead of (λ − 1)/r0, so with the energy
    π r0 D (λ/r0)² per unit length, p_b = dΠ/dR_c / (2π R_c) = D λ/(r0² R_c) (÷ λ_z per
    deformed area, as for the stress-free cylinder).

    ``s`` is the :class:`ShellStiffness`; with the warp along the axis the hoop is direction 2.
    ``stuck``: the tube held axially by friction from the moment it touches (a tube dressed
    with friction on while the body grows): its axial strain stays 0 instead of the free
    contraction −(A_tz/A_zz) E, so the hoop force is A_tt E, not (A_tt − A_tz²/A_zz) E.
    """
    if warp == "axial":
        a_tt, a_zz, a_tz, d_tt = s.A22, s.A11, s.A12, s.D22
    else:
        a_tt, a_zz, a_tz, d_tt = s.A11, s.A22, s.A12, s.D11
    lam = R_c / r0
    e = (lam**2 - 1) / 2
    e_zz = 0.0 if stuck else -a_tz / a_zz * e
    lz = np.sqrt(1 + 2 * e_zz)
    S = a_tt * e + a_tz * e_zz
    p = (lam / lz) * S / R_c
    if bending:
        p += d_tt * (lam if flat else lam - 1) / (r0**2 * R_c) / lz
    return float(p)


def cap_pressure(R_c: float, r0: float, s, *, bending: bool = True) -> float:
    """Exact equal-biaxial pressure of a tight shell cap [Pa]: p = (n₁ + n₂)/R_c (+ bending).

    n₁ = (A11 + A12) E and n₂ = (A12 + A22) E are the membrane forces along the two frame
    directions under the equal-biaxial Green–Lagrange strain E = (λ² − 1)/2."""
    lam = R_c / r0
    e = (lam**2 - 1) / 2
    p = (s.A11 + 2 * s.A12 + s.A22) * e / R_c
    if bending:
        p += (s.D11 + 2 * s.D12 + s.D22) * (lam - 1) / (r0 * R_c**2)
    return float(p)


def _solver(model, bcs, contact, options):
    opts = {"snes_rtol": 1e-10, "snes_atol": 1e-10, "snes_stol": 0.0, "snes_max_it": 30}
    opts.update(options or {})
    return NonlinearSolver(model, bcs, **contact.solver_hooks(), petsc_options=opts,
                           prefix=f"contact{id(model)}_")  # fmt: skip


def tight_tube(
    comm: MPI.Comm,
    material,
    *,
    warp: str = "axial",
    n: tuple[int, int] = (8, 4),
    R: float = 0.1,
    r0: float = 0.093,
    L: float = 0.1,
    kappa_hat: float = 10.0,
    kappa: float | None = None,
    rule: str = "lumped",
    element: str | None = None,
    n_body: int = 1021,
    n_body_z: int = 4,
    distortion: float = 0.0,
    options: dict | None = None,
    surface: type[SearchSurface] = SearchSurface,
    rest: str = "mesh",
    membrane=None,
) -> ContactCase:
    """One eighth of a tight tube (rest radius r0, length L) on a rigid cylinder of radius R.

    ``membrane``: a membrane law replacing the quadratic one (e.g.
    :func:`~fenics_garment.shell.energy.tabulated_membrane`); the reference stays that of the
    quadratic law (see :func:`curve_tube` for the tabulated one).

    ``rest="flat"``: the tube's stress-free state is the flat rectangle (2πr0 × L, warp along
    the axis or around it as ``warp`` says) rather than the cylinder it is placed on
    (:mod:`fenics_garment.shell.rest`); the reference is then :func:`tube_pressure` with
    ``flat=True``.

    ``n`` = (cells around the quarter circle, cells along the half length); the body cylinder
    (z ∈ [−L, L]) has ``n_body`` facets around and ``n_body_z`` along. ``distortion`` moves the
    interior nodes within the surface by up to that fraction of a cell (pseudo-random, fixed):
    the geometry stays exact, the triangles get distorted. ``surface``: the body's class
    (:class:`SearchSurface`, faceted, or :class:`fenics_garment.contact.smooth.SmoothBody`).
    """
    mesh = parametric_surface_mesh(
        comm, lambda t, z: np.vstack([r0 * np.cos(t), r0 * np.sin(t), z]),
        (0.0, np.pi / 2), (0.0, L / 2), n,
    )  # fmt: skip
    if distortion:
        _distort_tube_mesh(mesh, r0, L, n, distortion)
    if rest not in ("mesh", "flat"):
        raise ValueError(f"rest must be 'mesh' or 'flat', got {rest!r}")
    flat = rest == "flat"
    Y = None
    if flat:  # the rectangle's coordinates, grain (x) along the warp

        def unrolled(x):
            s_hoop = r0 * np.arctan2(x[1], x[0])
            return np.vstack([x[2], s_hoop] if warp == "axial" else [s_hoop, x[2]])

        Y = flat_map_from_function(mesh, unrolled)
    geo = ShellGeometry.from_mesh(
        mesh, warp=_warp_function(mesh, warp), outward=lambda x: x * np.array([1.0, 1.0, 0.0]),
        rest=Y,
    )  # fmt: skip
    model = ShellModel(geo, material, element=element)
    if membrane is not None:
        model.membrane = membrane
    body = surface(*cylinder(R, -L, L, n_body, n_body_z))
    contact = shell_contact.attach(model, body, kappa=kappa, kappa_hat=kappa_hat, rule=rule)
    bcs = (
        shell_bcs.symmetry_plane(model, lambda x: np.isclose(x[0], 0.0), 0)
        + shell_bcs.symmetry_plane(model, lambda x: np.isclose(x[1], 0.0), 1)
        + shell_bcs.symmetry_plane(model, lambda x: np.isclose(x[2], 0.0), 2)
    )
    solver = _solver(model, bcs, contact, options)
    s = model.stiffness
    R_c = R + s.thickness / 2
    ref = tube_pressure(R_c, r0, s, warp=warp, flat=flat)
    return ContactCase(model, contact, solver, bcs, ref, R, r0,
                 {"L": L, "warp": warp, "membrane_only": tube_pressure(R_c, r0, s, warp=warp,
                                                                       bending=False)})  # fmt: skip


#: A knit-like J-shaped tension–strain pair (synthetic, for verification: not a measurement):
#: soft at first (yarns straighten, loops deform), stiffening as the yarns themselves stretch.
#: Tension per unit reference width [N/m] at engineering strain 0 … 40 %; the weft curve is
#: half the warp's.
KNIT_LIKE_WARP = TensionStrainCurve(
    strain=(0.0, 0.02, 0.05, 0.10, 0.20, 0.40), tension=(0.0, 2.0, 6.0, 16.0, 60.0, 250.0),
    name="knit-like warp (synthetic)",
)  # fmt: skip
KNIT_LIKE_WEFT = TensionStrainCurve(
    strain=KNIT_LIKE_WARP.strain, tension=tuple(0.5 * t for t in KNIT_LIKE_WARP.tension),
    name="knit-like weft (synthetic)",
)  # fmt: skip


def curve_tube_pressure(R_c: float, r0: float, hoop: TensionStrainCurve, d_tt: float) -> float:
    """Exact free-end pressure of a tight tube of a :func:`tabulated_membrane` fabric [Pa].

    Without warp/weft coupling the free ends leave the axial strain 0 (S_zz = T_z(e_z)/λ_z = 0),
    so the hoop force per deformed axial length is the curve's tension at the wrapped strain
    e = R_c/r0 − 1 and p = T(e)/R_c, plus the bending part D_θθ(λ − 1)/(r0² R_c) of
    :func:`tube_pressure`."""
    lam = R_c / r0
    return float(hoop.tension_at(lam - 1) / R_c + d_tt * (lam - 1) / (r0**2 * R_c))


def curve_tube(
    comm: MPI.Comm,
    warp_curve: TensionStrainCurve = KNIT_LIKE_WARP,
    weft_curve: TensionStrainCurve = KNIT_LIKE_WEFT,
    *,
    warp: str = "axial",
    B: tuple[float, float] = (1.0e-4, 2.5e-5),
    shear: float = 20.0,
    thickness: float = 1.0e-3,
    **kwargs,
) -> ContactCase:
    """:func:`tight_tube` of a fabric whose membrane law is the tension–strain curves
    (:func:`~fenics_garment.shell.energy.tabulated_membrane`), bending ``B`` (warp, weft) [N·m]
    and in-plane shear stiffness ``shear`` [N/m]; reference :func:`curve_tube_pressure`.

    The fabric's linear moduli (used for the penalty scale and the PSRI weight only) are the
    curves' initial slopes over the thickness."""
    k_warp, k_weft = warp_curve.slopes[0], weft_curve.slopes[0]
    material = Fabric(E_warp=k_warp / thickness, E_weft=k_weft / thickness,
                      G12=shear / thickness, B_warp=B[0], B_weft=B[1], thickness=thickness,
                      density=0.0, nu12=0.0, name="curve-fabric")  # fmt: skip
    law = tabulated_membrane(warp_curve, weft_curve)
    case = tight_tube(comm, material, warp=warp, membrane=law, **kwargs)
    R_c = case.R + thickness / 2
    hoop, d_tt = (weft_curve, B[1]) if warp == "axial" else (warp_curve, B[0])
    case.reference = curve_tube_pressure(R_c, case.r0, hoop, d_tt)
    case.extra["membrane_only"] = curve_tube_pressure(R_c, case.r0, hoop, 0.0)
    case.extra["strain"] = R_c / case.r0 - 1
    case.extra["hoop_curve"] = hoop.name
    # the quadratic law with the curve's initial slope: how far the curve is from linear here
    case.extra["linear_law"] = tube_pressure(R_c, case.r0, material.stiffness(), warp=warp)
    return case


def tight_cap(
    comm: MPI.Comm,
    material,
    *,
    n: int = 8,
    half_angle: float = np.pi / 6,
    R: float = 0.1,
    r0: float = 0.093,
    kappa_hat: float = 10.0,
    kappa: float | None = None,
    rule: str = "lumped",
    element: str | None = None,
    n_body: int = 160,
    options: dict | None = None,
    surface: type[SearchSurface] = SearchSurface,
) -> ContactCase:
    """A spherical cap (a cube-sphere face patch, |x/z|, |y/z| ≤ tan(half_angle)) of rest radius
    r0 on a rigid sphere of radius R; its edge follows the exact solution u = (λ(s) − 1)X, θ = 0,
    with λ(s) = (R_c − s)/r0 for the body shrink s."""
    t = np.tan(half_angle)

    def cube_sphere(a, b):
        v = np.vstack([a, b, np.ones_like(a)])
        return r0 * v / np.linalg.norm(v, axis=0)

    mesh = parametric_surface_mesh(comm, cube_sphere, (-t, t), (-t, t), (n, n))
    geo = ShellGeometry.from_mesh(mesh, warp=_warp_function(mesh, "x"), outward=lambda x: x)
    model = ShellModel(geo, material, element=element)
    body = surface(*sphere_patch(R, np.pi / 4, n_body))
    contact = shell_contact.attach(model, body, kappa=kappa, kappa_hat=kappa_hat, rule=rule)
    # edge: u = (λ − 1) X with a Function value, θ = 0
    Vu, _ = model.Q.sub(0).collapse()
    u_edge = dolfinx.fem.Function(Vu)
    edges = shell_bcs.boundary_edges(mesh, lambda x: np.full(x.shape[1], True))
    dofs = dolfinx.fem.locate_dofs_topological((model.Q.sub(0), Vu), 1, edges)
    bcs = [dolfinx.fem.dirichletbc(u_edge, dofs, model.Q.sub(0))]
    bcs += shell_bcs.fix_components(model, edges, theta=(0, 1, 2))
    solver = _solver(model, bcs, contact, options)
    s = model.stiffness
    R_c = R + s.thickness / 2

    def set_edge(shrink: float) -> None:
        lam = (R_c - shrink) / r0
        u_edge.interpolate(lambda x: (lam - 1) * x)

    ref = cap_pressure(R_c, r0, s)
    return ContactCase(model, contact, solver, bcs, ref, R, r0,
                 {"set_edge": set_edge, "half_angle": half_angle,
                  "membrane_only": cap_pressure(R_c, r0, s, bending=False)})  # fmt: skip


@dataclass
class SolveHistory:
    iterations: list[int] = field(default_factory=list)
    residuals: list[list[float]] = field(default_factory=list)


def dress_case(scene: ContactCase, steps=(0.5, 0.0)) -> SolveHistory:
    """Shrink the body by s = f·(R_c − r0) for each f of ``steps`` and solve (ending at f = 0)."""
    st = scene.state
    rep = SolveHistory()
    for f in steps:
        shrink = f * scene.penetration0
        st.shrink.value = shrink
        if "set_edge" in scene.extra:
            scene.extra["set_edge"](shrink)
        its, reason = scene.solver.solve()
        if reason <= 0:
            raise RuntimeError(f"dressing step f={f} failed: SNES reason {reason} after {its}")
        rep.iterations.append(its)
        rep.residuals.append(scene.solver.residual_history().tolist())
        st.accept_step()
    return rep


def mid_pressure(scene: ContactCase, where=None) -> float:
    """Contact force over deformed area, Σ t_N w dA / Σ J_s w dA, over the contact points of
    the cells in the region far from the edges (all ranks).

    Tube: z < L/4 (mid-length; the free end is at z = L/2). Cap: within half the half-angle of
    the pole. A cell is in the region when the mean position of its contact points is, and then
    all its points are: a band that cut through a row of cells and kept only some of each
    cell's points would weight that row's points unevenly (measured +1.13 % on a 10×5 tube).
    ``where(x)`` selects on those cell positions (shape (cells, 3)).
    """
    st = scene.state
    t_n = scene.contact.traction
    force = pressure.point_forces(st, t_n)
    area = pressure.point_areas(st, scene.contact.area_stretch())
    per_cell = len(st.weights)
    x = pressure.positions(st).reshape(-1, per_cell, 3).mean(axis=1)
    if where is None:
        if "L" in scene.extra:
            sel = x[:, 2] < scene.extra["L"] / 4
        else:
            ang = np.arctan2(np.hypot(x[:, 0], x[:, 1]), x[:, 2])
            sel = ang < scene.extra["half_angle"] / 2
    else:
        sel = where(x)
    sel = np.repeat(sel, per_cell)
    comm = scene.model.geometry.mesh.comm
    return comm.allreduce(force[sel].sum(), op=MPI.SUM) / comm.allreduce(
        area[sel].sum(), op=MPI.SUM
    )


# -- capstan (Euler–Eytelwein) ----------------------------------------------------------------
def _strip_path(s: np.ndarray, w: np.ndarray, rho: float, theta: float, tail: float):
    """Centre line from (rho, −tail) up the tangent x = rho, around the arc φ ∈ [0, θ] of radius
    rho, then ``tail`` along the tangent at φ = θ; w across the strip (along z)."""
    phi = np.clip((s - tail) / rho, 0.0, theta)
    before = np.minimum(s - tail, 0.0)  # ≤ 0 on tail A
    after = np.maximum(s - tail - rho * theta, 0.0)  # ≥ 0 on tail B
    x = rho * np.cos(phi) - after * np.sin(theta)
    y = rho * np.sin(phi) + before + after * np.cos(theta)
    return np.vstack([x, y, w])


def capstan_strip(
    comm: MPI.Comm,
    *,
    mu: float,
    theta: float = np.pi / 2,
    R: float = 0.1,
    tail: float = 0.05,
    width: float = 0.02,
    n: tuple[int, int] | None = None,
    E: float = 1.0e6,
    thickness: float = 1.0e-3,
    kappa_hat: float = 10.0,
    options: dict | None = None,
) -> ContactCase:
    """A shell strip (ν = 0) wrapped on a rigid cylinder by an angle θ ∈ (0, 3π/2], with
    straight tails.

    End A (tail along y, at y = −tail) is clamped; end B (the tail along the tangent
    t_B = (−sin θ, cos θ, 0) at the end of the arc) has its rotations fixed and is pulled along
    its tail, u = δ t_B (:func:`pull`; ``extra["delta"]`` holds δ). The friction coefficient is
    ``contact.friction.mu`` (a Constant: set it to 0 to pre-tension the strip, :func:`pretension`).
    The reference value is the capstan ratio e^{μθ} of the tail tensions at slip. ``n``: cells
    along and across the strip, default 80 per π/2 of wrap plus the tails' share, and 2.
    """
    from fenics_garment.materials import Isotropic

    if not 0.0 < theta <= 1.5 * np.pi + 1e-12:
        raise ValueError(f"wrap angle θ must be in (0, 3π/2] (the tails would cross), got {theta}")
    rho = R + thickness / 2
    total = 2 * tail + rho * theta
    if n is None:
        n = (max(16, round(80 * total / (2 * tail + rho * np.pi / 2))), 2)
    mesh = parametric_surface_mesh(
        comm, lambda s, w: _strip_path(s, w, rho, theta, tail),
        (0.0, total), (-width / 2, width / 2), n,
    )  # fmt: skip
    geo = ShellGeometry.from_mesh(
        mesh, warp=(0.0, 0.0, 1.0), outward=lambda x: x * np.array([1.0, 1.0, 0.0])
    )
    model = ShellModel(geo, Isotropic(E=E, nu=0.0, thickness=thickness))
    body = SearchSurface(*cylinder(R, -0.05, 0.05, 2048, 2))
    contact = shell_contact.attach(model, body, kappa_hat=kappa_hat, mu=mu, band=0.01)
    t_b = np.array([-np.sin(theta), np.cos(theta)])
    b_end = _strip_path(np.array([total]), np.zeros(1), rho, theta, tail)[:2, 0]

    def end_b(x):
        return np.hypot(x[0] - b_end[0], x[1] - b_end[1]) < 1e-9

    pull_xy = [dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(0.0)) for _ in range(2)]
    bcs = shell_bcs.clamped(
        model, lambda x: np.isclose(x[1], -tail) & np.isclose(x[0], rho, atol=1e-9)
    )
    for i in range(2):
        bcs += shell_bcs.fix_components(model, end_b, u=(i,), value=pull_xy[i])
    bcs += shell_bcs.fix_components(model, end_b, theta=(0, 1, 2))
    solver = _solver(model, bcs, contact, options)
    delta = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(0.0))
    extra = {"delta": delta, "pull_xy": pull_xy, "t_b": t_b, "tail": tail, "rho": rho,
             "theta": theta, "width": width, "EA": E * thickness * width,
             "length": total}  # fmt: skip
    return ContactCase(model, contact, solver, bcs, float(np.exp(mu * theta)), R, rho, extra)


def pull(scene: ContactCase, delta: float) -> None:
    """Set the pull of the strip's end B: u = δ t_B (along its tail, outwards)."""
    scene.extra["delta"].value = delta
    for c, t in zip(scene.extra["pull_xy"], scene.extra["t_b"], strict=True):
        c.value = delta * t


def pretension(scene: ContactCase, stretch: float, *, steps: int = 4, max_cuts: int = 6) -> list:
    """Pull end B, frictionless, to the mean stretch ``stretch`` (δ = (stretch − 1)·length) in
    ``steps`` equal increments, halving an increment whose Newton solve fails; restores μ.

    Returns the Newton iterations of the accepted increments; after an increment that took
    ≤ 8 iterations the next one doubles again (up to the nominal). Why steps: the strip starts
    exactly wrapped (gap 0), so the first increment moves the whole contact zone from an
    unloaded to a pressed state at once; too large a jump leaves Newton's region of
    convergence (2 increments diverge on a stiffer strip or a smaller cylinder).
    """
    friction = scene.contact.friction.mu
    mu = float(friction.value)
    friction.value = 0.0
    target = (stretch - 1.0) * scene.extra["length"]
    done, step, cuts, its_log = 0.0, target / steps, 0, []
    q = scene.model.q
    try:
        while done < target * (1 - 1e-12):
            step = min(step, target - done)
            q_old = q.x.array.copy()
            pull(scene, done + step)
            its, reason = scene.solver.solve()
            if reason > 0:
                scene.contact.accept_step()
                done += step
                its_log.append(its)
                cuts = 0
                if its <= 8:  # easy: back up towards the nominal increment
                    step = min(2 * step, target / steps)
                continue
            q.x.array[:] = q_old
            q.x.scatter_forward()
            cuts += 1
            step /= 2
            if cuts > max_cuts:
                raise RuntimeError(
                    f"pre-tension failed at δ = {done + 2 * step:.3g} m after {cuts} halvings"
                )
    finally:
        friction.value = mu
    return its_log


def capstan_slip_pull(scene: ContactCase, tension: float) -> float:
    """The extra pull of end B [m] at which the whole wrap starts to slip, from a uniform
    pre-tension ``tension`` [N] (small-strain estimate, to size the pull increments).

    At the onset of full slip the tension is T(φ) = T₀ e^{μφ} along the wrap (φ from the held
    side) and T₀ e^{μθ} in tail B, so the strip has lengthened by
    Δ = (T₀/EA) [ρ((e^{μθ} − 1)/μ − θ) + ℓ_tail (e^{μθ} − 1)] over its pre-tensioned state.
    """
    e = scene.extra
    mu = float(scene.contact.friction.mu.value)
    ratio = np.exp(mu * e["theta"])
    wrap = (ratio - 1) / mu - e["theta"] if mu > 0 else 0.0
    return tension / e["EA"] * (e["rho"] * wrap + e["tail"] * (ratio - 1))


def tail_tensions(scene: ContactCase) -> tuple[float, float]:
    """Tension forces [N] in the held tail A and the pulled tail B, from their stretch.

    A straight, contact-free tail of this ν = 0 SVK strip is in uniaxial tension: stretch
    λ = ℓ/L between two points on its centre line, Green strain E = (λ² − 1)/2, force
    T = λ · E h w · E (first Piola–Kirchhoff force per reference width × width).
    """
    from fenics_garment.points import PointEvaluator

    tail, rho, th = scene.extra["tail"], scene.extra["rho"], scene.extra["theta"]
    s = np.array(
        [0.3 * tail, 0.7 * tail, 2 * tail + rho * th - 0.7 * tail, 2 * tail + rho * th - 0.3 * tail]
    )
    X = _strip_path(s, np.zeros(4), rho, th, tail).T
    if "tail_probe" not in scene.extra:  # located once, evaluated at every step
        scene.extra["tail_probe"] = PointEvaluator(scene.model.geometry.mesh, X)
    x = X + scene.extra["tail_probe"](scene.model.displacement())
    out = []
    for i, j in ((0, 1), (2, 3)):
        lam = np.linalg.norm(x[j] - x[i]) / np.linalg.norm(X[j] - X[i])
        out.append(lam * scene.extra["EA"] * (lam**2 - 1) / 2)
    return out[0], out[1]


def band_pressure(built, z0: float, z1: float) -> float:
    """Contact force over deformed area of a scene's contact points with z0 < z < z1 (all
    ranks): a band of a tube away from its free ends, for Laplace's law."""
    st, c = built.contact.state, built.contact
    f = pressure.point_forces(st, c.traction)
    a = pressure.point_areas(st, c.area_stretch())
    z = pressure.positions(st)[:, 2]
    sel = (z > z0) & (z < z1)
    comm = built.model.geometry.mesh.comm
    return comm.allreduce(f[sel].sum(), op=MPI.SUM) / comm.allreduce(a[sel].sum(), op=MPI.SUM)
