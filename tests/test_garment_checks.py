"""Generated garment surfaces are refused with a one-line reason when unbounded, folded, when
gmsh fails or hangs, or when DOLFINx refuses the mesh; hand-made surfaces as references."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from fenics_garment.geometry.errors import GeometryError
from fenics_garment.geometry.garment_checks import check_garment, largest_turn


def _cylinder(r=0.15, h=0.4, n=32, m=8):
    """An open cylinder: n around, m up, triangles turning outward."""
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    z = np.linspace(1.0, 1.0 + h, m + 1)
    pts = np.array([[r * np.cos(t), r * np.sin(t), zz] for zz in z for t in a])
    cells = []
    for j in range(m):
        for i in range(n):
            p, q = j * n + i, j * n + (i + 1) % n
            cells += [[p, q, q + n], [p, q + n, p + n]]
    return pts, np.array(cells)


def test_a_cylinder_passes():
    pts, cells = _cylinder()
    # a regular 32-gon turns by 360/32 = 11.25° from cell to cell around
    assert largest_turn(pts, cells) == pytest.approx(360.0 / 32, abs=0.5)
    check_garment("tube", pts, cells, [1.0, 1.4], 2 * np.pi * 0.15)


def test_a_fold_is_refused():
    pts, cells = _cylinder()
    pts[:, 2] = np.where(pts[:, 2] > 1.2 + 1e-9, 2.4 - pts[:, 2], pts[:, 2])  # fold at 1.2 m
    with pytest.raises(GeometryError, match="folds"):
        check_garment("tube", pts, cells, [1.0, 1.4], 2 * np.pi * 0.15)


def test_an_overshooting_loft_is_refused():
    pts, cells = _cylinder()
    pts[5, 0] = 3.0  # one node 3 m out: a convex section of girth 0.94 m is at most 0.47 m wide
    with pytest.raises(GeometryError, match="wide"):
        check_garment("gilet", pts, cells, [1.0, 1.4], 2 * np.pi * 0.15)
    pts, cells = _cylinder()
    with pytest.raises(GeometryError, match="outside its levels"):
        check_garment("gilet", pts, cells, [1.1, 1.2], 2 * np.pi * 0.15)


def test_gmsh_hang_is_a_one_line_error_with_exit_2():
    code = (
        "import time\n"
        "from fenics_garment.geometry.gmsh_utils import time_limit\n"
        "with time_limit(0.5, 'the gilet'):\n"
        "    time.sleep(30)\n"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: gmsh did not finish the gilet")


def test_gmsh_exception_becomes_geometry_error():
    from fenics_garment.geometry import garments as gm

    def build(g):
        raise Exception("Wrong topology of boundary mesh for parametrization\nmore detail")

    with pytest.raises(GeometryError, match=r"gmsh could not build the gilet: Wrong topology"):
        gm._finish("gilet", None, build, [])
