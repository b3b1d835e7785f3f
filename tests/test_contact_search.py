"""Closest point, signed distance and normals against analytic spheres and cylinders."""

import numpy as np
import pytest

from fenics_garment.contact.primitives import cylinder, icosphere
from fenics_garment.contact.search import BroadPhase, SearchSurface

R = 0.1


@pytest.fixture(scope="module")
def sphere() -> SearchSurface:
    return SearchSurface(*icosphere(R, 4))  # 5120 triangles, edges ≈ 7.7 mm


@pytest.fixture(scope="module")
def cyl() -> SearchSurface:
    return SearchSurface(*cylinder(R, -0.2, 0.2, 128, 64))


def _sagitta(body: SearchSurface) -> float:
    # the largest gap between an inscribed facet and the circle/sphere through its vertices
    return body.max_edge**2 / (4.0 * R)


def test_outside_on_vertex_rays_is_exact(sphere):
    # for a polyhedron inscribed in a sphere, the vertex is the closest point of every point on
    # the outward ray through it: v·(w − v) = v·w − R² ≤ 0 for all other vertices w.
    v = sphere.vertices[::7]
    for d in (1e-8, 1e-4, 0.03):
        res = sphere.closest(v * (1.0 + d / R), normal="gradient")
        np.testing.assert_allclose(res.distance, d, rtol=1e-9, atol=1e-15)
        np.testing.assert_array_equal(res.point, v)
        np.testing.assert_allclose(res.normal, v / R, atol=1e-16 / d)


def test_random_points_sphere_against_analytic(sphere):
    rng = np.random.default_rng(1)
    x = rng.normal(size=(20000, 3))
    x *= (rng.uniform(0.5, 1.5, len(x)) * R / np.linalg.norm(x, axis=1))[:, None]
    exact = np.linalg.norm(x, axis=1) - R
    res = sphere.closest(x)
    s = _sagitta(sphere)
    assert np.abs(res.distance - exact).max() <= s
    clear = np.abs(exact) > s
    assert np.all(np.sign(res.distance[clear]) == np.sign(exact[clear]))
    # closest points lie on the facets: within a sagitta inside the sphere
    r = np.linalg.norm(res.point, axis=1)
    assert r.max() <= R * (1 + 1e-12) and r.min() >= R - s


@pytest.mark.parametrize("depth", [1e-8, 1e-6, 1e-3])
def test_points_just_inside_are_inside(sphere, depth):
    # just inside vertices, edge midpoints and face centroids: where a naive face-normal sign
    # flips. The pseudonormal sign must see all of them as inside.
    v, f = sphere.vertices, sphere.triangles
    on_surface = np.vstack([v, 0.5 * (v[f[:, 0]] + v[f[:, 1]]), v[f].mean(axis=1)])
    nrm = on_surface / np.linalg.norm(on_surface, axis=1)[:, None]
    res = sphere.closest(on_surface - depth * nrm)
    assert np.all(res.distance < 0.0)
    res = sphere.closest(on_surface + depth * nrm)
    assert np.all(res.distance > 0.0)


def test_cylinder_side_distance_and_normals(cyl):
    rng = np.random.default_rng(2)
    n = 5000
    θ = rng.uniform(0, 2 * np.pi, n)
    r = rng.uniform(0.8 * R, 1.2 * R, n)
    z = rng.uniform(-0.1, 0.1, n)
    x = np.column_stack([r * np.cos(θ), r * np.sin(θ), z])
    res = cyl.closest(x, normal="phong")
    s = R * (1 - np.cos(np.pi / 128))  # sagitta of a side facet
    assert np.abs(res.distance - (r - R)).max() <= s
    radial = np.column_stack([np.cos(θ), np.sin(θ), np.zeros(n)])
    # Phong normal within the facet half-angle of the radial direction; face normal is not
    h = 2 * np.pi / 128
    assert np.arccos(np.clip((res.normal * radial).sum(1), -1, 1)).max() < 0.51 * h
    grad = cyl.closest(x, normal="gradient")
    out = r > R + s
    assert np.arccos(np.clip((grad.normal[out] * radial[out]).sum(1), -1, 1)).max() < 0.51 * h


def test_phong_normal_is_continuous_across_edges(cyl):
    # two points 1e-7 m apart on either side of a side edge: the facet normal jumps by the
    # facet angle, the Phong normal does not.
    θ = 2 * np.pi / 128 * 10
    t = np.array([-np.sin(θ), np.cos(θ), 0.0])
    p = np.array([R * np.cos(θ), R * np.sin(θ), 0.0123]) - 1e-6 * np.array(
        [np.cos(θ), np.sin(θ), 0]
    )
    x = np.vstack([p - 1e-7 * t, p + 1e-7 * t])
    face = cyl.closest(x, normal="face").normal
    phong = cyl.closest(x, normal="phong").normal
    assert np.linalg.norm(face[0] - face[1]) > 0.04
    assert np.linalg.norm(phong[0] - phong[1]) < 1e-4


def test_orientation_is_fixed_for_inward_meshes():
    v, f = icosphere(R, 2)
    body = SearchSurface(v, f[:, ::-1])
    assert body.closest(np.array([[0.0, 0.0, 2 * R]])).distance[0] > 0


def test_broad_phase_skips_far_points_exactly(sphere):
    rng = np.random.default_rng(3)
    x = rng.normal(size=(4000, 3))
    x *= (rng.uniform(0.9, 3.0, len(x)) * R / np.linalg.norm(x, axis=1))[:, None]
    bp = BroadPhase(band=0.01)
    bp.query(sphere, x)
    assert bp.skipped_fraction == 0.0
    x1 = x + 1e-3 * rng.normal(size=x.shape)
    d1, n1, _ = bp.query(sphere, x1)
    exact = sphere.closest(x1)
    near = exact.distance < 0.01
    assert 0.5 < bp.skipped_fraction < 1.0
    np.testing.assert_array_equal(d1[near], exact.distance[near])
    np.testing.assert_array_equal(n1[near], exact.normal[near])
    assert np.all(d1[~near] <= exact.distance[~near] + 1e-15)  # a lower bound where skipped
    assert np.all(d1[~near] > 0.01)
