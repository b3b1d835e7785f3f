"""Cropping the body to the garment's reach changes no search answer within the reach."""

import numpy as np

from fenics_garment.contact.primitives import cylinder
from fenics_garment.contact.search import SearchSurface, reach_mask

R = 0.1


def test_crop_gives_the_uncropped_answer_within_the_margin():
    v, f = cylinder(R, -0.4, 0.4, 96, 96)
    full = SearchSurface(v, f)
    rng = np.random.default_rng(3)
    # a "garment" band around the middle, 8 mm outside the surface
    th = rng.uniform(0, 2 * np.pi, 2000)
    z = rng.uniform(-0.05, 0.05, 2000)
    garment = np.column_stack([(R + 0.008) * np.cos(th), (R + 0.008) * np.sin(th), z])
    margin = 0.05
    keep = reach_mask(v, f, garment, margin)
    cropped = SearchSurface(v, f, keep=keep)
    assert cropped.dropped == len(f) - keep.sum() > len(f) // 2
    # query points that moved up to 2 cm from the garment, inside and outside the body
    x = garment + rng.uniform(-0.02, 0.02, garment.shape)
    a, b = full.closest(x), cropped.closest(x)
    # face ids are the whole body's (a closest point on a shared edge may name either face)
    assert np.mean(a.face == b.face) > 0.9
    assert np.allclose(a.point, b.point, rtol=0, atol=1e-15)
    assert np.allclose(a.distance, b.distance, rtol=0, atol=1e-15)
    assert np.allclose(a.normal, b.normal, rtol=0, atol=1e-15)


def test_reach_mask_keeps_every_triangle_of_a_box_around_the_body():
    v, f = cylinder(R, -0.2, 0.2, 32, 16)
    assert reach_mask(v, f, v, 0.0).all()
