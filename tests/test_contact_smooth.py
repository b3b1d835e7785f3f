"""The smooth (IMLS) body surface of ``contact.smooth`` against independent references.

* distance and normal to a sphere and a cylinder sampled as triangle meshes: the exact values
  |x| − R and √(x² + y²) − R (elementary geometry); the error falls with the mesh size at the
  observed rate ≈ 2 and is ≥ 5× below the faceted mesh's own distance error;
* gradient and Hessian against central finite differences of f and ∇f;
* continuity across a concave edge, where the faceted distance's gradient jumps by the dihedral
  angle (the reference: the two face normals of the V-shaped surface);
* exact on a plane (f = z, H = 0) and a robust sign deep inside (the faceted pseudonormal).
"""

import numpy as np
import pytest

from fenics_garment.contact.primitives import cylinder, icosphere
from fenics_garment.contact.search import SearchSurface
from fenics_garment.contact.smooth import SmoothBody

R = 0.1


def _shell_points(rng, n: int, depth: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points at signed distance d ∈ [−depth, depth] from the sphere |x| = R, and the exact
    distance and outward normal there."""
    e = rng.normal(size=(n, 3))
    e /= np.linalg.norm(e, axis=1, keepdims=True)
    d = rng.uniform(-depth, depth, n)
    return e * (R + d)[:, None], d, e


def _sphere_errors(sub: int) -> tuple[float, float, float, float]:
    v, t = icosphere(R, sub)
    smooth, faceted = SmoothBody(v, t), SearchSurface(v, t)
    x, d, e = _shell_points(np.random.default_rng(sub), 2000, 0.003)
    res = smooth.closest(x)
    g = res.normal
    angle = np.arccos(np.clip(np.einsum("ij,ij->i", g / np.linalg.norm(g, axis=1)[:, None], e),
                              -1.0, 1.0))  # fmt: skip
    return (
        float(np.abs(res.distance - d).max()),
        float(np.abs(faceted.closest(x).distance - d).max()),
        float(angle.max()),
        float(np.abs(np.linalg.norm(g, axis=1) - 1.0).max()),
    )


def test_sphere_distance_converges():
    errs = [_sphere_errors(s) for s in (3, 4, 5)]  # edge 16.5, 8.3, 4.1 mm on R = 100 mm
    dist = np.array([e[0] for e in errs])
    rates = np.log2(dist[:-1] / dist[1:])
    faceted, normal, unit = ([e[i] for e in errs] for i in (1, 2, 3))
    print(f"\nsmooth distance error {dist} m (rates {rates}), faceted {faceted} m; "
          f"normal error {np.degrees(normal)} deg; |∇f| − 1 {unit}")  # fmt: skip
    assert np.all(rates > 1.8)
    assert all(e[0] < e[1] / 5 for e in errs)
    assert errs[-1][2] < np.radians(0.1)
    assert errs[-1][3] < 2e-4  # the traction t_N ∇f has the magnitude t_N to 0.02 %


def test_cylinder_distance_converges():
    errs = []
    for n in (64, 128, 256):
        v, t = cylinder(R, -0.2, 0.2, n, n // 4)
        body = SmoothBody(v, t)
        rng = np.random.default_rng(n)
        th, z = rng.uniform(0, 2 * np.pi, 2000), rng.uniform(-0.1, 0.1, 2000)
        d = rng.uniform(-0.003, 0.003, 2000)
        x = np.column_stack([(R + d) * np.cos(th), (R + d) * np.sin(th), z])
        errs.append(np.abs(body.closest(x).distance - d).max())
    rates = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    print(f"\ncylinder smooth distance error {errs} m, rates {rates}")
    assert np.all(rates > 1.8)


def _vee(angle: float, n: int = 24, half: float = 0.1):
    """An open V-shaped surface z = tan(angle)|x| (concave edge along y at x = 0), normals up."""
    s = np.linspace(-half, half, n + 1)
    X, Y = np.meshgrid(s, s, indexing="ij")
    v = np.column_stack([X.ravel(), Y.ravel(), np.tan(angle) * np.abs(X.ravel())])
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]
    tri = np.vstack([np.column_stack([a.ravel(), b.ravel(), c.ravel()]),
                     np.column_stack([a.ravel(), c.ravel(), d.ravel()])])  # fmt: skip
    return v, tri


def test_gradient_and_hessian_match_finite_differences():
    v, t = _vee(np.radians(20.0))
    body = SmoothBody(v, t)
    rng = np.random.default_rng(3)
    x = np.column_stack([rng.uniform(-0.03, 0.03, 40), rng.uniform(-0.03, 0.03, 40),
                         rng.uniform(0.0, 0.01, 40)])  # fmt: skip
    _, g, h, _ = body.smooth_distance(x)
    eps = 1e-6
    for k in range(3):
        dx = np.zeros(3)
        dx[k] = eps
        fp, gp, _, _ = body.smooth_distance(x + dx)
        fm, gm, _, _ = body.smooth_distance(x - dx)
        assert np.abs((fp - fm) / (2 * eps) - g[:, k]).max() < 1e-8
        assert np.abs((gp - gm) / (2 * eps) - h[:, :, k]).max() < 1e-6 * np.abs(h).max()
    assert np.abs(h - h.transpose(0, 2, 1)).max() < 1e-10 * np.abs(h).max()


def test_normal_is_continuous_over_a_concave_edge():
    """Across the crease of a 20° V (each face tilted by 20°), the faceted gradient jumps by 40°;
    the smooth one turns continuously: its change across ±ε falls in proportion to ε (the
    rounded crease's curvature × 2ε), measured 10.6° at ε = 1 mm and 0.11° at ε = 10 µm."""
    angle = np.radians(20.0)
    v, t = _vee(angle)
    faceted, smooth = SearchSurface(v, t), SmoothBody(v, t)
    jumps_f, jumps_s = [], []
    for eps in (1e-3, 1e-5):
        x = np.array([[-eps, 0.001, 0.004], [eps, 0.001, 0.004]])
        nf = faceted.closest(x, "gradient").normal
        ns = smooth.closest(x).normal
        ns = ns / np.linalg.norm(ns, axis=1)[:, None]
        jumps_f.append(np.degrees(np.arccos(np.clip(nf[0] @ nf[1], -1, 1))))
        jumps_s.append(np.degrees(np.arccos(np.clip(ns[0] @ ns[1], -1, 1))))
    print(f"\nnormal jump across the crease: faceted {jumps_f} deg, smooth {jumps_s} deg")
    assert jumps_f[-1] == pytest.approx(2 * np.degrees(angle), rel=1e-6)
    assert jumps_s[-1] < 0.2 and jumps_s[-1] < jumps_s[0] / 50


def test_exact_on_a_plane_and_sign_deep_inside():
    v, t = _vee(0.0)  # the plane z = 0
    body = SmoothBody(v, t)
    rng = np.random.default_rng(5)
    x = np.column_stack([rng.uniform(-0.05, 0.05, (50, 2)), rng.uniform(-0.01, 0.01, 50)])
    res = body.closest(x)
    assert np.allclose(res.distance, x[:, 2], atol=1e-14)
    assert np.allclose(res.normal, [0.0, 0.0, 1.0], atol=1e-14)
    assert np.abs(res.hessian).max() < 1e-10
    vs, ts = icosphere(R, 3)
    sphere = SmoothBody(vs, ts)
    deep = np.array([[0.0, 0.0, 0.0], [0.03, 0.0, 0.0], [0.0, 0.0, R - 1.5 * sphere.band]])
    assert np.all(sphere.closest(deep).distance < 0.0)  # faceted pseudonormal sign there


def test_contact_jacobian_is_consistent():
    """The assembled Jacobian of the contact residual on a smooth sphere equals the central
    finite difference of the residual (refreshed at each perturbed state) to 1e-8; without the
    Hessian term it is off by the normal's turning (0.7 % here): the linearisation is consistent."""
    import dolfinx.fem.petsc

    from fenics_garment._stack import MPI, dolfinx, ufl
    from fenics_garment.contact import terms
    from fenics_garment.contact.state import ContactState
    from fenics_garment.shell.geometry import parametric_surface_mesh

    r0 = 0.0995  # 0.5 mm inside the body: every point in contact, above HESSIAN_DEPTH
    mesh = parametric_surface_mesh(
        MPI.COMM_SELF,
        lambda a, b: r0 * np.vstack([np.cos(a) * np.cos(b), np.sin(a) * np.cos(b), np.sin(b)]),
        (0.0, 1.0), (0.1, 0.9), (6, 6),
    )  # fmt: skip
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (3,)))
    u = dolfinx.fem.Function(V)
    state = ContactState(mesh, u, SmoothBody(*icosphere(R, 3)), offset=0.0, rule="vertex")
    kappa = dolfinx.fem.Constant(mesh, 1e5)
    F = terms.contact_residual(state, ufl.TestFunction(V), kappa)
    F_form, J_form = dolfinx.fem.form(F), dolfinx.fem.form(ufl.derivative(F, u))
    rng = np.random.default_rng(0)
    u0 = rng.normal(scale=5e-5, size=u.x.array.shape)  # depths stay 0.5 ± 0.2 mm
    d = rng.normal(scale=1e-4, size=u.x.array.shape)

    def residual(q):
        u.x.array[:] = q
        state.refresh()
        return dolfinx.fem.petsc.assemble_vector(F_form).array.copy()

    eps = 1e-4
    fd = (residual(u0 + eps * d) - residual(u0 - eps * d)) / (2 * eps)
    residual(u0)
    assert np.all(state.gap.x.array < 0.0)

    def jd():
        A = dolfinx.fem.petsc.assemble_matrix(J_form)
        A.assemble()
        x, y = A.createVecs()
        x.array[:] = d
        A.mult(x, y)
        return y.array.copy()

    err = np.linalg.norm(jd() - fd) / np.linalg.norm(fd)
    state.hessian.x.array[:] = 0.0
    err_first_order = np.linalg.norm(jd() - fd) / np.linalg.norm(fd)
    print(
        f"\nJacobian vs finite differences: {err:.1e} (without the Hessian {err_first_order:.1e})"
    )
    assert err < 1e-8
    assert err_first_order > 1e-3


@pytest.mark.slow
def test_laplace_tube_on_the_smooth_body():
    """The tight tube of ``test_contact_shell`` on the smooth body (near-isotropic body triangles:
    the IMLS support is 2 × the median edge): Laplace's pressure (free ends, the same exact
    reference) to 1 %, penetration ≤ 1 % of h after the multiplier updates."""
    from fenics_garment._stack import MPI
    from fenics_garment.contact import uzawa
    from fenics_garment.materials import Isotropic
    from fenics_garment.verification import contact as cases

    h = 1.0e-3
    scene = cases.tight_tube(MPI.COMM_WORLD, Isotropic(E=1.0e6, nu=0.3, thickness=h),
                              n_body=512, n_body_z=32, surface=SmoothBody)  # fmt: skip
    rep = cases.dress_case(scene)
    al = uzawa.augmented_lagrangian(
        scene.state, float(scene.contact.kappa.value), scene.solver.solve, tol=0.01 * h
    )
    p, ref = cases.mid_pressure(scene), scene.reference
    err, pen = 100 * (p / ref - 1), al.penetration[-1] / h
    print(f"\nsmooth body: p = {p:.3f} Pa, Laplace {ref:.3f} Pa, error {err:+.3f} %; "
          f"Newton its {rep.iterations}; penetration {pen:.2%} of h")  # fmt: skip
    assert abs(p / ref - 1) < 0.01
    assert al.penetration[-1] <= 0.01 * h


@pytest.mark.slow
def test_tube_scene_on_the_smooth_body(tmp_path):
    """``demos/tube_on_cylinder.toml`` with ``[physics] body_surface = "smooth"``: the whole scene
    (dressing, release) completes and the mid-tube pressure obeys Laplace's law to 2 %, the
    tolerance of the faceted scene's test (tests/test_scene_run.py)."""
    from dataclasses import replace
    from pathlib import Path

    from fenics_garment.scene import config
    from fenics_garment.scene.run import run

    s = config.load(Path(__file__).parent.parent / "demos" / "tube_on_cylinder.toml")
    s = replace(s, physics=replace(s.physics, body_surface="smooth"),
                output=config.OutputConfig(vtx=False, xdmf=False, pictures=False))  # fmt: skip
    res = run(s, tmp_path, quiet=True)
    assert res.completed and res.report.final_regularisation == 0.0
    import test_scene_run as faceted  # the same reference and the same measurement

    p, ref = faceted._mid_pressure(res), faceted._laplace(res)
    print(f"\ntube scene, smooth body: p = {p:.2f} Pa, Laplace {ref:.2f} Pa, "
          f"error {100 * (p / ref - 1):+.3f} %")  # fmt: skip
    assert p == pytest.approx(ref, rel=0.02)
