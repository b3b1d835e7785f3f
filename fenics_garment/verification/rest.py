r"""Verification of the flat rest state (:mod:`fenics_garment.shell.rest`): a flat disc forced
onto a sphere.

A flat elastic disc of radius a laid on a rigid sphere of radius R must take the sphere's
Gaussian curvature K = 1/R². It cannot do so isometrically, so in-plane stresses arise even
though no load acts in the plane. For small strain (a ≪ R) the plane-stress Airy function φ
satisfies the compatibility equation with a Gaussian-curvature source,
∇⁴φ = −E K (Föppl–von Kármán; e.g. Audoly & Pomeau, *Elasticity and Geometry*, OUP 2010,
§ 6.2), independent of ν. The axisymmetric solution regular at the centre is
φ = −E K r⁴/64 + A r²/2, so σ_rr = φ'/r = −E K r²/16 + A, σ_θθ = φ'' = −3 E K r²/16 + A, and the
free edge σ_rr(a) = 0 gives A = E K a²/16:

.. math::
    \sigma_{rr} = \frac{E}{16 R^2}(a^2 - r^2), \qquad
    \sigma_{\theta\theta} = \frac{E}{16 R^2}(a^2 - 3 r^2),

tension E a²/(16R²) at the centre and hoop compression −E a²/(8R²) at the edge (the geodesic
circle of radius r on the sphere is 2πR sin(r/R) < 2πr long). The membrane forces are t σ.

The model: a quarter disc (symmetry planes x = 0 and y = 0), meshed flat by gmsh, placed on the
sphere by the geodesic polar map (flat radius r → polar angle r/R; not isometric: the solver
finds the equilibrium), the flat disc as the rest state, and the sphere as a bilateral
constraint ½ k (|x + u| − R)² per unit area (pressed on, no lift-off).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fenics_garment._stack import MPI, dolfinx, ufl
from fenics_garment.geometry.gmsh_utils import gmsh_session, to_dolfinx
from fenics_garment.shell import bcs as shell_bcs
from fenics_garment.shell.kinematics import ShellGeometry
from fenics_garment.shell.model import ShellModel
from fenics_garment.shell.rest import flat_map_from_function
from fenics_garment.solve import NonlinearSolver


def disc_on_sphere_forces(E: float, t: float, a: float, R: float, r) -> tuple:
    """(N_rr, N_θθ) [N/m] of the small-strain free-edged disc on the sphere (module docstring)."""
    c = E * t / (16.0 * R**2)
    return c * (a**2 - r**2), c * (a**2 - 3 * r**2)


def quarter_disc_mesh(comm: MPI.Comm, a: float, h: float) -> dolfinx.mesh.Mesh:
    """A flat quarter disc x, y ≥ 0, x² + y² ≤ a² in the plane z = 0, curved order 2."""
    with gmsh_session(comm, 0, name="quarter_disc") as g:
        if g is not None:
            occ = g.model.occ
            disc = occ.addDisk(0, 0, 0, a, a)
            box = occ.addRectangle(0, 0, 0, 2 * a, 2 * a)
            occ.intersect([(2, disc)], [(2, box)])
            occ.synchronize()
            surfaces = [s for _, s in g.model.getEntities(2)]
            g.model.addPhysicalGroup(2, surfaces, 1)
            g.option.setNumber("Mesh.MeshSizeMax", h)
            g.option.setNumber("Mesh.MeshSizeMin", h)
            g.model.mesh.generate(2)
            g.model.mesh.setOrder(2)
        mesh = to_dolfinx(comm, g.model if g is not None else None, 0).mesh
    return mesh


@dataclass
class DiscOnSphere:
    model: ShellModel
    solver: NonlinearSolver
    a: float
    R: float
    E: float
    t: float

    def force_error(self, inner: float = 1.0) -> float:
        """‖N − N_exact‖ / ‖N_exact‖ in L² over the flat disc (r ≤ inner·a), N in the flat
        Cartesian frame (the rest frame of the strains: warp x, weft y)."""
        m = self.model
        # ∂ψ/∂ε of a law written with ε₁₂ alone (4 A66 ε₁₂²) puts the whole shear force in
        # N₁₂ and none in N₂₁: the symmetric part is the membrane force tensor
        N = ufl.sym(m.membrane_forces())
        Y = m.geometry.rest.Y
        r = ufl.sqrt(ufl.dot(Y, Y) + 1e-30)
        n = Y / r
        tng = ufl.as_vector([-n[1], n[0]])
        Nrr, Ntt = disc_on_sphere_forces(self.E, self.t, self.a, self.R, r)
        # N is in the strains' frame: flat x and ±flat y (−y where the flat map mirrors)
        s = m.geometry.rest.handedness(m.geometry.normal)
        n, tng = ufl.as_vector([n[0], s * n[1]]), ufl.as_vector([tng[0], s * tng[1]])
        N_ex = Nrr * ufl.outer(n, n) + Ntt * ufl.outer(tng, tng)
        inside = ufl.conditional(ufl.le(r, inner * self.a), 1.0, 0.0)
        w = m.per_rest_area(inside)
        err = m.energy_value(ufl.inner(N - N_ex, N - N_ex) * w * m.dx_full)
        ref = m.energy_value(ufl.inner(N_ex, N_ex) * w * m.dx_full)
        return float(np.sqrt(err / ref))


def disc_on_sphere(
    comm: MPI.Comm,
    *,
    a: float = 0.05,
    R: float = 1.0,
    h: float | None = None,
    E: float = 1.0e6,
    nu: float = 0.3,
    t: float = 5.0e-4,
    k: float | None = None,
) -> DiscOnSphere:
    """The quarter disc on the sphere, built and solved (module docstring). ``h``: cell size
    (default a/8); ``k``: the sphere's penalty [N/m³] (default 1e4 E t / a², stiff enough that
    the radial misfit it leaves changes the forces by < 1e-4)."""
    from fenics_garment.materials import Isotropic

    h = a / 8 if h is None else h
    mesh = quarter_disc_mesh(comm, a, h)
    Y = flat_map_from_function(mesh, lambda x: x[:2])
    x = mesh.geometry.x
    r = np.hypot(x[:, 0], x[:, 1])
    s = np.where(r > 0, R * np.sin(r / R) / np.where(r > 0, r, 1.0), 1.0)
    x[:, 0] *= s
    x[:, 1] *= s
    x[:, 2] = R * np.cos(r / R)
    geo = ShellGeometry.from_mesh(mesh, warp=(1.0, 0.0, 0.0), outward=lambda p: p, rest=Y)
    model = ShellModel(geo, Isotropic(E=E, nu=nu, thickness=t))
    k = 1e4 * E * t / a**2 if k is None else k
    X = ufl.SpatialCoordinate(mesh)
    phi = X + model.u
    kc = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(k))
    model.add_energy(0.5 * kc * (ufl.sqrt(ufl.dot(phi, phi)) - R) ** 2)
    bcs = shell_bcs.symmetry_plane(model, lambda p: np.isclose(p[0], 0.0), 0)
    bcs += shell_bcs.symmetry_plane(model, lambda p: np.isclose(p[1], 0.0), 1)
    # forces of order E t a²/R² · a: the penalty's round-off (~1e-10 N at the default k) sets
    # the reachable residual
    opts = {"snes_rtol": 1e-8, "snes_atol": 1e-9, "snes_stol": 0.0, "snes_max_it": 30}
    solver = NonlinearSolver(model, bcs, petsc_options=opts, prefix=f"disc{id(model)}_")
    its, reason = solver.solve()
    if reason <= 0:
        raise RuntimeError(f"disc on sphere: SNES reason {reason} after {its} iterations")
    return DiscOnSphere(model, solver, a, R, E, t)
