"""The dress's skirt is fair: no bulge between hem and hip (issue 40 item 3, "the scan dress's
skirt bulges sideways over the hips").

Measured by :func:`~fenics_garment.geometry.garment_checks.skirt_bulge` (the largest rise of the
skirt's radius going up at one polar angle, in metres) on the dress of the human mannequin and
of five MakeHuman population bodies, at h = 3 cm, order 1. Before the fix (one loft of degree
≤ 3 through all the levels, skirt sections widened around the legs independently) the bulges
were 37, 38, 36, 51, 43 and 54 mm (female, human, f-heavy, m-heavy, f-short-heavy-old,
f-maxcup-soft-heavy), 27 mm on the torso dress form; with the skirt lofted through monotone
guide rings and nested skirt sections 0.4, 0, 0.3, 0.4, 2.1 and 0.2 mm, 0 on the dress form.
The measure must also see a bulge: a dent and a bump pressed into a fair dress on purpose.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from fenics_garment._stack import MPI
from fenics_garment.geometry import MeshSizes, make_mannequin, measurements
from fenics_garment.geometry import garments as gm
from fenics_garment.geometry import population as pop
from fenics_garment.geometry.body import BodySurface
from fenics_garment.geometry.garment_checks import MAX_BULGE, skirt_bulge
from fenics_garment.geometry.human import make_human
from fenics_garment.geometry.scan import load_scan

pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial")

BODIES = [
    "dress form",
    "human",
    "female",
    "f-heavy",
    "m-heavy",
    "f-short-heavy-old",
    "f-maxcup-soft-heavy",
]
#: a dress at h = 3 cm, order 1 is meshed in about 2 s; the guide rings must keep it fast
MAX_SECONDS = 30.0


def _body(name: str, folder) -> BodySurface:
    if name == "dress form":  # the armless, headless torso (test_geometry_garments)
        return make_mannequin(measurements("88"), MeshSizes(0.025, 0.025), z_range=(0.3, 1.55))
    if name == "human":
        return make_human(measurements("88"), MeshSizes(coarse=0.03, fine=0.03))
    return load_scan(pop.export(pop.by_name(name), folder))[0]


def _fairness(body: BodySurface, dress: gm.GarmentSurface):
    z = {lv.name: lv.z for lv in dress.levels}
    axis = body.section("hip")[1].mean(axis=0)
    return skirt_bulge(dress.points, dress.cells, z["skirt_0"], z["hip"], axis)


@pytest.mark.parametrize("name", BODIES)
def test_the_dress_skirt_has_no_bulge(name: str, tmp_path) -> None:
    body = _body(name, tmp_path)
    t = time.perf_counter()
    dress = gm.make_dress(body, h=0.03, order=1)
    assert time.perf_counter() - t < MAX_SECONDS
    f = _fairness(body, dress)
    assert f.bulge <= MAX_BULGE, f
    assert f.concavity <= MAX_BULGE, f


def test_the_measure_sees_a_bulge(tmp_path) -> None:
    """A fair dress (the female body's) with a Gaussian bump of 2 cm pushed out on its front
    at mid-skirt: the measure reports more than 1 cm there (the bump less the flare over its
    half-width: 13.7 mm measured); pushed in (a dent), the radius rises again above it; the fair
    dress itself stays within the limit."""
    body = _body("female", tmp_path)
    dress = gm.make_dress(body, h=0.03, order=1)
    z = {lv.name: lv.z for lv in dress.levels}
    axis = body.section("hip")[1].mean(axis=0)
    assert _fairness(body, dress).bulge <= MAX_BULGE
    zc = 0.5 * (z["skirt_1"] + z["skirt_2"])
    p = dress.points
    d = p[:, :2] - axis
    r = np.linalg.norm(d, axis=1)
    theta = np.arctan2(d[:, 1], d[:, 0])
    w = np.exp(-(((p[:, 2] - zc) / 0.05) ** 2) - ((theta + np.pi / 2) / 0.5) ** 2)
    for sign in (1.0, -1.0):  # a bump, a dent
        moved = p.copy()
        moved[:, :2] += (sign * 0.02 * w / np.maximum(r, 1e-9))[:, None] * d
        f = skirt_bulge(moved, dress.cells, z["skirt_0"], z["hip"], axis)
        assert 0.01 < f.bulge < 0.025, (sign, f)
        assert abs(f.bulge_angle + 90.0) < 30.0, (sign, f)
