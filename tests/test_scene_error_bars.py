"""Discretisation error bars (two garment meshes, Richardson) against Laplace's law on the tube.

Measured on the tight tube (P1-P1, augmented Lagrangian to 1 µm, 5 mm body triangles), force
over deformed area in the middle half vs Laplace's law with free ends: −1.41 / −0.44 / −0.10 % at
garment mesh sizes 8 / 4 / 2 cm (observed rate 1.5–2.2), so the bars' r = 1 is conservative;
the region mean: +0.27 / +0.03 / +0.04 %. At 1 cm the error grows again (+0.95 %): the garment
nodes then resolve the body's 5 mm facets (31 µm sagitta against 7 mm of interference, ≈ 0.45 %
of the hoop strain) — a body-mesh error that refining the garment cannot see.

With the P2B-P2B element the region mean is +9.6 / +2.7 % at 4 / 2 cm: the garment's reference
geometry is still straight-sided (P1) while its P2 displacement bends each deformed edge onto
the round body, so the deformed hoop is an arc over a chord — arc/chord − 1 ≈ (h/R)²/24, 0.67 %
of stretch at h = 4 cm, R = 10 cm, ≈ +10 % of the hoop strain — an O(h²) error that a curved
(P2) garment geometry would remove. So the bars are checked at 2 cm here.
"""

import tempfile
from dataclasses import replace
from pathlib import Path

import pytest
from test_scene_run import SCENE, _laplace

from fenics_garment._stack import MPI
from fenics_garment.scene import config, error_bars
from fenics_garment.scene.run import run


def test_richardson_error_recovers_a_manufactured_error():
    # Q_h = Q + C h^r with Q = 1, C = 3, r = 2, h = 0.1: the estimate is the exact error
    q, c, h = 1.0, 3.0, 0.1
    rho = error_bars.RATIO
    fine, coarse = q + c * h**2, q + c * (rho * h) ** 2
    assert error_bars.richardson_error(fine, coarse, rate=2.0) == pytest.approx(c * h**2)
    # the default r = 1 is (ρ² − 1)/(ρ − 1) = 1 + ρ ≈ 2.4 times larger: conservative
    assert error_bars.richardson_error(fine, coarse) == pytest.approx((1 + rho) * c * h**2)
    # on meshes h and 2h (ratio=2) the same formula is the classical (Q_h − Q_2h)/(2^r − 1)
    coarse2 = q + c * (2 * h) ** 2
    assert error_bars.richardson_error(fine, coarse2, rate=2.0, ratio=2.0) == pytest.approx(
        c * h**2
    )


def test_comfort_range_names_the_bands_the_bar_touches():
    # Table 13.5 bands: < 0.4 negligible, 0.4–1.3 comfortable
    assert error_bars.comfort_range(1.0, 0.1) == "comfortable"
    assert error_bars.comfort_range(0.38, 0.05) == "negligible … comfortable"


def test_error_bar_covers_the_true_error_of_the_tube():
    comm = MPI.COMM_WORLD
    tmp = Path(comm.bcast(tempfile.mkdtemp() if comm.rank == 0 else None, root=0))
    s = config.load(SCENE)
    # the straight-sided garment mesh: a case with a discretisation error to cover (its
    # chord-to-arc stretch, +1.9 % at 2 cm; on the curved mesh the error left, 0.2 %, is the
    # free ends' and the multiplier tolerance's, which the bar does not claim to cover)
    s = replace(
        s,
        garment=replace(s.garment, mesh_size=0.02, geometry="straight"),
        physics=replace(s.physics, contact="augmented-lagrangian", tolerance=1e-3,
                        max_updates=10),
        output=replace(s.output, vtx=False, xdmf=False, pictures=False, error_bars=True),
    )  # fmt: skip
    result = run(s, tmp, quiet=True)
    row = result.regions[0]
    exact_kpa = _laplace(result) * 1e-3
    error = abs(row["mean_kPa"] - exact_kpa)
    print(f"\ntube mean {row['mean_kPa']:.5f} ± {row['mean_err_kPa']:.5f} kPa, "
          f"Laplace {exact_kpa:.5f} kPa (error {error:.5f})")  # fmt: skip
    assert result.summary["error_bars"]["coarse_dofs"] < result.summary["dofs"]
    assert error <= row["mean_err_kPa"]
    assert row["mean_err_kPa"] < 0.1 * exact_kpa  # and the bar is not uselessly wide
    assert row["comfort_range"] == "comfortable"  # 0.44 kPa ± 0.001
    # the summary on disk has the bars too
    text = (result.folder / "pressure_regions.csv").read_text()
    assert "mean_err_kPa" in text.splitlines()[0]
