"""A torso garment's shoulder strap on a segmented body (``garments._top_cuts``): when the
neckline's ease leaves less than ``MIN_STRAP`` between the neckline and the armhole (which starts
a clearance inside the arm root), the neckline narrows towards the neck itself and the
extra clearance gives way to ``MIN_ARMHOLE_CLEARANCE``; only a body whose own neck leaves no strap
is refused, in one line."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fenics_garment.geometry import garments as gm
from fenics_garment.geometry.errors import GeometryError
from fenics_garment.geometry.human import make_human
from fenics_garment.geometry.mannequin import MeshSizes
from fenics_garment.geometry.measurements import measurements


@pytest.fixture(scope="module")
def human():
    return make_human(measurements("88"), MeshSizes(coarse=0.03, fine=0.03))


def _room(body) -> tuple[float, float]:
    """(half-width of the body's own neck at mid-neck, x of the nearer arm root) [m]."""
    x_body = float(body.section("neck")[1][:, 0].max())
    x_root = min(abs(float(body.points[f"armpit_{s}"][0])) for s in ("left", "right"))
    return x_body, x_root


def test_a_wide_neckline_gives_way_to_the_strap(human):
    """A 150 % neckline ease would put the neckline beyond the arm roots: the dress is still
    made, and the fabric at the shoulder line between the neck and the armhole is at least
    MIN_STRAP wide on either side."""
    x_body, x_root = _room(human)
    assert x_root - gm.MIN_ARMHOLE_CLEARANCE - x_body > gm.MIN_STRAP  # the body has room
    dress = gm.make_dress(human, ease={"neck_base": 1.5}, h=0.03)
    z_nb = human.landmarks["neck_base"]
    top = dress.points[dress.points[:, 2] > z_nb - 0.01]  # the straps' top
    for s in (1.0, -1.0):
        x = s * top[:, 0]
        x = x[x > 0]
        assert len(x) and x.max() - x.min() >= gm.MIN_STRAP - 0.01, (s, x.min(), x.max())


def test_a_body_without_room_for_a_strap_is_refused_in_one_line(human):
    """Arm roots moved to 2 cm outside the neck: no strap fits, whatever the ease."""
    x_body, _ = _room(human)
    points = dict(human.points)
    for s, side in ((1.0, "left"), (-1.0, "right")):
        p = np.array(points[f"armpit_{side}"], dtype=float)
        p[0] = s * (x_body + 0.02)
        points[f"armpit_{side}"] = p
    body = dataclasses.replace(human, points=points)
    with pytest.raises(GeometryError, match="no room for a shoulder strap") as err:
        gm.make_dress(body, h=0.03)
    assert "\n" not in str(err.value)
