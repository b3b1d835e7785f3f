"""Stress: plate thickness over four decades, h/L = 1e-1 … 1e-4, one fixed 8×8 quarter mesh.

The thin end (1e-2 … 1e-4) is ``tests/test_shell_thickness_sweep.py``'s clamped-plate sweep
(Kirchhoff reference, error must not grow as t → 0), re-run here through the same case function
so the stress table holds all four decades. The thick end, h/L = 1e-1, has no Kirchhoff
reference; it is checked against the Reissner–Mindlin deflection of the hard simply supported
plate from Marcus' relation (Wang, Reddy & Lee, *Shear Deformable Beams and Plates*, Elsevier
2000, eq. 7.3.9): w_M = w_K + ℳ/(κ G t), ℳ the Marcus moment, ∇²ℳ = −q with ℳ = 0 on the
edges — the Poisson problem of the unit square, whose centre value is 0.0736713 q a² (the
Prandtl stress function of square torsion, Timoshenko & Goodier, *Theory of Elasticity*, 3rd
ed., §109). With κ = 5/6, G = E/(2(1+ν)): D/(κ G t) = t²/(5(1−ν)), so w D/(q a⁴) =
0.00406235 + 0.0736713 · 0.01/3.5 = 0.00427284 at t/a = 0.1, ν = 0.3 (5.2 % above Kirchhoff).
Measured (P2B-P2B): clamped −0.33 / −1.20 / −1.23 % at 1e-2 / 1e-3 / 1e-4.
"""

import math

import pytest

from fenics_garment.verification import shells

KIRCHHOFF_SS = 0.00406235  # Timoshenko & Woinowsky-Krieger, Table 8 (as in the case function)
MARCUS_CENTRE = 0.0736713  # ℳ/(q a²) at the centre of the simply supported square


def mindlin_ss_deflection(t_over_a: float, nu: float = 0.3) -> float:
    """Hard simply supported square plate, centre w D/(q a⁴), Reissner–Mindlin (Marcus)."""
    return KIRCHHOFF_SS + MARCUS_CENTRE * t_over_a**2 / (5 * (1 - nu))


@pytest.mark.stress
@pytest.mark.slow  # nightly: `make test-slow` (also in .ci/run)
@pytest.mark.parametrize("ratio", [1e-2, 1e-3, 1e-4])
def test_thin_clamped_plate(ratio):
    r = shells.square_plate(8, "clamped", thickness=ratio)
    print(f"\nh/L = {ratio:g}: clamped plate 8×8, error {r.rel_error:+.3%} (Kirchhoff)")
    assert math.isfinite(r.value) and abs(r.rel_error) < 0.015


@pytest.mark.stress
def test_thick_plate_against_mindlin():
    r = shells.square_plate(8, "simply-supported", thickness=0.1)
    ref = mindlin_ss_deflection(0.1)
    err = r.value / ref - 1
    print(f"\nh/L = 0.1: simply supported plate 8×8, {r.value:.6g} vs Mindlin {ref:.6g}: "
          f"error {err:+.3%} (Kirchhoff would say {r.value / KIRCHHOFF_SS - 1:+.2%})")  # fmt: skip
    assert math.isfinite(r.value) and abs(err) < 0.01
