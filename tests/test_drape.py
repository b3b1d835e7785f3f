"""The Cusick drape's measuring tools: the shadow area, the node count, the imperfection.

(The drape itself runs in ``python -m benchmarks.validation drape``: minutes per fabric.)"""

import math

import numpy as np
import pytest

from fenics_garment import drape as cusick


def test_shadow_area_is_the_union():
    # two unit squares overlapping on a 0.5 × 1 strip: union 1.5 m²
    xy = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0], [1.5, 0], [1.5, 1], [0.5, 1]], float)
    tris = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    assert cusick.shadow_area(xy, tris, 1e-3) == pytest.approx(1.5, rel=5e-3)


def test_shadow_area_adds_the_pedestal():
    far = np.array([[2.0, 2.0], [2.1, 2.0], [2.0, 2.1]])  # a small triangle off the disc
    a = cusick.shadow_area(far, np.array([[0, 1, 2]]), 1e-3, disc=0.09)
    assert a == pytest.approx(math.pi * 0.09**2 + 0.005, rel=5e-3)


def test_count_nodes():
    phi = np.linspace(-math.pi, math.pi, 400, endpoint=False)
    for n in (2, 5, 7, 10):
        r = 0.12 + 0.01 * np.cos(n * phi + 0.3) + 5e-4 * np.cos(40 * phi)  # mesh-scale ripple
        assert cusick.count_nodes(phi, r) == n
    assert cusick.count_nodes(phi, np.full_like(phi, 0.12)) == 0


def test_imperfection_is_seeded_and_vanishes_at_the_clamp():
    x = np.array([[0.09, 0.0, 0.0], [0.0, 0.15, 0.0], [-0.12, 0.05, 0.0]])
    a = cusick.imperfection(x, 0.09, 0.15, 1e-3, seed=3)
    assert a[0] == 0.0
    assert np.array_equal(a, cusick.imperfection(x, 0.09, 0.15, 1e-3, seed=3))
    assert not np.array_equal(a, cusick.imperfection(x, 0.09, 0.15, 1e-3, seed=4))
    assert np.all(np.abs(a) <= 1e-3 * math.sqrt(11))
