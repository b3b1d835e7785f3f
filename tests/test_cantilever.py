"""A clamped strip bending under its own weight against the heavy elastica, the ASTM D1388
bending length, and the measured-fabric data with its unit conversions.

The reference is computed here, independently of ``verification/cantilever.py`` (which uses
``solve_bvp``): by shooting on the clamp curvature κ₀ = θ'(0) with ``solve_ivp`` and ``brentq``,
for the inextensible heavy elastica θ'' = −Γ(1 − s) cos θ, θ(0) = 0, θ'(1) = 0, Γ = W L³/B.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from fenics_garment import measured, units
from fenics_garment.verification import cantilever


def shoot(gamma: float) -> tuple[float, float, float]:
    """(tip drop δ/L, tip x/L, tip angle θ(1)) of the heavy elastica by shooting.

    θ'(1) = κ₀ − Γ∫(1 − s) cos θ ds is ≥ 0 at κ₀ = Γ/2 (cos θ ≤ 1). Below, κ₀ is lowered in
    steps of Γ/200 until θ'(1) < 0: the first sign change from above is the hanging branch
    (0 ≤ θ < π/2; at small κ₀ and large Γ the strip would curl up through θ < 0 instead)."""

    def rhs(s, y):
        th, k, _, _ = y
        return [k, -gamma * (1 - s) * math.cos(th), math.cos(th), math.sin(th)]

    def run(k0: float):
        return solve_ivp(rhs, (0.0, 1.0), [0.0, k0, 0.0, 0.0], rtol=1e-12, atol=1e-13,
                         method="DOP853")  # fmt: skip

    def end_slope(k: float) -> float:
        return float(run(k).y[1, -1])

    hi = gamma / 2
    lo = hi - gamma / 200
    while end_slope(lo) >= 0:
        hi, lo = lo, lo - gamma / 200
    k0 = brentq(end_slope, lo, hi, xtol=1e-14, rtol=1e-14)
    th, _, x, z = run(k0).y[:, -1]
    return float(z), float(x), float(th)


@pytest.mark.parametrize("gamma", [0.01, 1.0, 10.0, 100.0])
def test_module_elastica_against_shooting(gamma):
    """The module's collocation reference agrees with this file's shooting to 1e-7."""
    e = cantilever.heavy_elastica(gamma)
    drop, x, th = shoot(gamma)
    assert e.tip_drop == pytest.approx(drop, rel=1e-7)
    assert e.tip_x == pytest.approx(x, rel=1e-7)
    assert e.tip_angle == pytest.approx(th, rel=1e-7)


def test_elastica_small_gamma_is_euler_bernoulli():
    """Γ → 0: δ/L = Γ/8 and θ(1) = Γ/6 (the linear cantilever under uniform load)."""
    drop, _, th = shoot(1e-3)
    assert drop == pytest.approx(1e-3 / 8, rel=1e-3)
    assert th == pytest.approx(1e-3 / 6, rel=1e-3)


def test_peirce_41_5_degrees():
    """ASTM D1388's 41.5°: Peirce's approximation makes c = L/2 there, i.e. Γ = 8. The exact
    elastica reaches 41.5° at Γ* with c/(B/W)^(1/3) = Γ*^(1/3)/2 within 0.1 % of 1."""
    g = cantilever.chord_gamma()
    drop, x, _ = shoot(g)
    assert math.degrees(math.atan2(drop, x)) == pytest.approx(41.5, abs=1e-6)
    assert g ** (1 / 3) / 2 == pytest.approx(1.0, abs=1e-3)


def test_master_curve():
    """The shell strip (ν = 0, h/L = 0.01, 16 × 1 cell pairs, P2B-P2B) along one load path,
    Γ = 10⁻² … 10²: tip drop and tip angle within 1 % of the shooting reference.

    Measured: largest |error| 0.05 % (drop, Γ = 10) on 16 × 1; on 8 × 1 0.60 %. ≈ 7 s with a
    warm JIT cache (the cold compile of the strip's forms ≈ 45 s on this machine)."""
    points, _ = cantilever.master_curve(n=16)
    assert [p.gamma for p in points] == sorted(cantilever.MASTER_GAMMAS)
    for p in points:
        drop, _, th = shoot(p.gamma)
        e_drop = p.model.tip_drop / drop - 1
        e_th = p.model.tip_angle / th - 1
        print(f"Γ = {p.gamma:6g}: δ/L {p.model.tip_drop:.6f} (ref {drop:.6f}, {e_drop:+.3%}), "
              f"θ(1) {p.model.tip_angle:.6f} (ref {th:.6f}, {e_th:+.3%})")  # fmt: skip
        assert abs(e_drop) < 0.01 and abs(e_th) < 0.01


@pytest.mark.slow
def test_bending_length_of_a_measured_fabric():
    """ASTM D1388 on Matsudaira's polyester faille (M-F): the shell strip (25 mm wide, the
    fabric's B and W under standard gravity) at 41.5° gives c within 1 % of the elastica's
    c = Γ*^(1/3)/2 (B/W)^(1/3) with B = D11 — the strip bends as a plate (Searle's
    parameter b²/(R t) ≫ 1). Measured: −0.32 % (16 × 4 cell pairs, ≈ 35 s)."""
    m = measured.by_id("M-F")
    r = cantilever.bending_length(measured.to_fabric(m), n=16, n_width=4)
    exact = cantilever.chord_gamma() ** (1 / 3) / 2 * (m.B_warp / m.weight_per_area) ** (1 / 3)
    print(f"M-F: c = {100 * r.c:.4f} cm, elastica {100 * exact:.4f} cm, Γ* = {r.gamma:.4f}")
    assert abs(r.c / exact - 1) < 0.01


# -- the data file and its one conversion function -------------------------------------------
def test_unit_conversions():
    # CLO3D labels read literally: 1 g/s² = 1e-3 kg/s² = 1e-3 N/m; 1 g·mm²/s² = 1e-9 N·m
    assert units.clo3d_stretch_to_n_per_m(477226) == pytest.approx(477.226, rel=1e-12)
    assert units.clo3d_bending_to_nm(1950) == pytest.approx(1.95e-6, rel=1e-12)
    # KES: 1 gf·cm²/cm = 9.80665e-5 N·m, 1 gf·cm/cm = 9.80665e-3 N·m/m, 1 mg/cm² = 1e-2 kg/m²
    assert units.gf_cm2_per_cm_to_nm(0.118) == pytest.approx(0.118 * 9.80665e-5, rel=1e-12)
    assert units.gf_cm_per_cm_to_nm_per_m(0.124) == pytest.approx(0.124 * 9.80665e-3, rel=1e-12)
    assert units.mg_per_cm2_to_kg_per_m2(12.38) == pytest.approx(0.1238, rel=1e-12)
    assert units.g_per_m2_to_kg_per_m2(135.17) == pytest.approx(0.13517, rel=1e-12)
    assert units.mm_to_m(0.31) == pytest.approx(3.1e-4, rel=1e-12)


def test_measured_fabrics_in_si():
    fabrics = {f.id: f for f in measured.fabrics()}
    assert sorted(fabrics) == ["M-A", "M-B", "M-F", "P-m1", "P-m2", "P-m3", "P-m5", "P-m6"]
    p = fabrics["P-m1"]  # Petrak 2025, Tables 1, 4, 5
    assert p.mass_per_area == pytest.approx(0.13517)
    assert p.thickness == pytest.approx(0.31e-3)
    assert p.B_warp == pytest.approx(1950e-9) and p.B_weft == pytest.approx(610e-9)
    assert p.stretch_warp == pytest.approx(477.226) and p.shear == pytest.approx(41.0)
    assert (p.dc_measured, p.dc_clo3d) == (0.223, 0.349)
    assert p.specimen_diameter == pytest.approx(0.3) and p.pedestal_diameter == pytest.approx(0.18)
    m = fabrics["M-A"]  # Matsudaira 2015, Tables 1, 2
    assert m.B_warp == m.B_weft == pytest.approx(0.118 * 9.80665e-5)
    assert m.twoHB == pytest.approx(0.124 * 9.80665e-3)
    assert m.mass_per_area == pytest.approx(0.1238) and m.thickness == pytest.approx(0.497e-3)
    assert (m.dc_measured, m.nodes_measured) == (0.829, 2)
    # Peirce's c of cotton broadcloth: (B/W)^(1/3) = (1.157e-5 N·m / 1.214 N/m²)^(1/3) = 2.12 cm
    c = cantilever.peirce_bending_length(m.B_warp, m.weight_per_area)
    assert c == pytest.approx(0.02120, rel=1e-3)
    # the shell material: stiffness per width as given, mass per area, measured bending
    s = measured.to_fabric(p).stiffness()
    assert s.D11 == p.B_warp and s.mass_per_area == pytest.approx(p.mass_per_area)
    nu21 = 0.3 * p.stretch_weft / p.stretch_warp
    assert s.A11 == pytest.approx(p.stretch_warp / (1 - 0.3 * nu21))
    # the stated rule for the fabrics without membrane data: the same values for all of them
    a, b = (measured.to_fabric(fabrics[k]).stiffness() for k in ("M-A", "M-F"))
    assert a.A11 == pytest.approx(b.A11) and a.A66 == pytest.approx(b.A66)
    petrak = [f for f in fabrics.values() if f.source == "petrak2025"]
    assert np.mean([f.shear for f in petrak]) == pytest.approx(a.A66)


@pytest.mark.slow
def test_plate_and_beam_limits():
    """ν = 0.3: a narrow strip bends as a beam (B_eff = D(1 − ν²)), a wide one as a plate in
    cylindrical bending (B_eff → D), B_eff read off the elastica with the same tip drop at
    Γ = W L³/D = 3. Measured: b = 0.01 m 0.9157 (beam 0.91); b = 1 m 0.9890 (≈ 20 s)."""
    _, narrow = cantilever.effective_rigidity(0.01, n_width=2)
    _, wide = cantilever.effective_rigidity(1.0, n_width=8)
    print(f"B_eff/D: b = 0.01 m {narrow:.4f}, b = 1 m {wide:.4f}")
    assert abs(narrow / (1 - 0.3**2) - 1) < 0.01
    assert 0.98 < wide < 1.0
