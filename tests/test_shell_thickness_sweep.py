"""Locking: the error at a fixed mesh must not grow as the thickness goes to zero.

Before the rotation bubble (element P2B-P2, PSRI), the clamped plate on the 8×8 quarter mesh had
−0.44 / −9.4 / −21.3 % at t/a = 1e-2 / 1e-3 / 1e-4 (shear locking); with P2B-P2B (Arnold &
Brezzi 1997) it has −0.33 / −1.20 / −1.23 %.
"""

import math

import pytest

from fenics_garment.verification import shells

THIN = (1e-2, 1e-3, 1e-4)


def test_clamped_plate_thickness_sweep():
    """Kirchhoff reference w D/(q a⁴) = 0.00126532 (Timoshenko & Woinowsky-Krieger, Table 35) is
    the thin limit; at t/a = 1e-2 the Reissner–Mindlin deflection exceeds it by O((t/a)²), so the
    sweep stops there (t/a = 0.1 would need a Mindlin reference)."""
    errors = {t: shells.square_plate(8, "clamped", thickness=t).rel_error for t in THIN}
    print({t: f"{100 * e:+.3f} %" for t, e in errors.items()})
    assert all(abs(e) < 0.015 for e in errors.values())
    # No growth as t → 0 (a locking element loses a factor ≈ 2 per decade here).
    assert abs(errors[1e-4]) < 1.1 * abs(errors[1e-3])


def test_clamped_plate_thin_limit_converges():
    """At t/a = 1e-4 the error falls ≈ 4× per mesh halving (measured −4.90 / −1.23 / −0.35 % on
    4×4 / 8×8 / 16×16): the element converges at rate 2 in the thin limit instead of locking."""
    e4, e8 = (abs(shells.square_plate(n, "clamped", thickness=1e-4).rel_error) for n in (4, 8))
    assert e8 < e4 / 3.5


def test_roof_converges_to_published_value():
    """Scordelis–Lo, 0.3024 (MacNeal & Harder 1985): measured −0.48 % (4×4), −0.08 % (8×8)."""
    e4, e8 = (abs(shells.scordelis_lo(n).rel_error) for n in (4, 8))
    assert e8 < 0.002
    assert e8 < e4 / 4


@pytest.mark.slow
def test_roof_thickness_sweep():
    """No published roof values exist for t ≠ 0.25, so each thickness is compared with the same
    model on a 32×32 mesh (deflection under the load 90·(t/0.25)³).

    Measured on 16×16 against 32×32: −0.005 / +0.025 / −0.15 % at t/R = 1e-1 / 1e-2 / 1e-3.
    At t/R = 1e-4 the roof needs finer meshes (16×16: −2.9 %, 32×32: −0.3 % against 48×48),
    but far less than without PSRI (fully integrated P2B-P2B: −77 % on 16×16).
    """
    R = 25.0
    for ratio in (1e-1, 1e-2, 1e-3):
        t = ratio * R
        coarse, fine = (shells.scordelis_lo(n, thickness=t).value for n in (16, 32))
        err = coarse / fine - 1
        print(f"t/R = {ratio:g}: {100 * err:+.3f} %")
        assert math.isfinite(err) and abs(err) < 0.005
