"""Unit conversions (Kawabata units → SI) and material stiffness resultants."""

import math

import pytest

from fenics_garment import materials, units


def test_gram_force_conversions():
    # 1 gf = 1e-3 kg × 9.80665 m/s² (standard gravity); 1 cm² = 1e-4 m².
    assert units.gf_per_cm2_to_pa(1.0) == pytest.approx(98.0665, rel=1e-12)
    # KES bending rigidity: 1 gf·cm²/cm = 9.80665e-3 N × 1e-4 m² / 1e-2 m = 9.80665e-5 N·m.
    assert units.gf_cm2_per_cm_to_nm(1.0) == pytest.approx(9.80665e-5, rel=1e-12)
    assert units.gf_per_cm_to_n_per_m(1.0) == pytest.approx(0.980665, rel=1e-12)
    assert units.g_per_cm3_to_kg_per_m3(0.404) == pytest.approx(404.0)
    # 1 mmHg = 133.322 Pa (conventional), so 20 mmHg ≈ 2.666 kPa.
    assert units.pa_to_mmhg(2666.44775) == pytest.approx(20.0, rel=1e-6)


def test_table2_fabrics_in_si():
    # Seed paper Table 2, cotton: tensile warp 11712.5 gf/cm², thickness 0.046 cm,
    # bending warp 1.494 gf·cm²/cm, density 0.404 g/cm³.
    c = materials.COTTON
    assert c.E_warp == pytest.approx(11712.5 * 98.0665)
    assert c.thickness == pytest.approx(4.6e-4)
    assert c.B_warp == pytest.approx(1.494 * 9.80665e-5)
    s = c.stiffness()
    assert s.mass_per_area == pytest.approx(404.0 * 4.6e-4)
    # Orthotropic membrane stiffness: A11 = E1 h/(1 − ν12 ν21), ν21 = ν12 E2/E1.
    nu21 = 0.3 * c.E_weft / c.E_warp
    assert s.A11 == pytest.approx(c.E_warp * c.thickness / (1 - 0.3 * nu21))
    assert s.A12 == pytest.approx(0.3 * s.A22)  # ν12 E2 h/den = ν12 A22
    assert s.D11 == c.B_warp and s.D22 == c.B_weft  # measured, not Eh³/12


def test_isotropic_plate_relations():
    m = materials.Isotropic(E=2.0e9, nu=0.25, thickness=2e-3)
    s = m.stiffness()
    assert s.D11 == pytest.approx(2.0e9 * 8e-9 / (12 * (1 - 0.0625)))
    assert s.effective_thickness == pytest.approx(2e-3)
    assert s.A66 == pytest.approx(2.0e9 / 2.5 * 2e-3)
    assert s.S1 == pytest.approx(5 / 6 * 2.0e9 / 2.5 * 2e-3)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(E=1e6, nu=0.3, thickness=-1e-3), "thickness"),
        (dict(E=0.0, nu=0.3, thickness=1e-3), "E must be"),
        (dict(E=1e6, nu=0.5, thickness=1e-3), "Poisson"),
        (dict(E=1e6, nu=0.3, thickness=math.nan), "thickness"),
        (dict(E=1e6, nu=0.3, thickness=1e-3, density=-1.0), "density"),
    ],
)
def test_invalid_isotropic(kwargs, message):
    with pytest.raises(materials.MaterialError, match=message):
        materials.Isotropic(**kwargs)


def test_unknown_fabric_lists_known():
    with pytest.raises(materials.MaterialError, match="cotton, nylon"):
        materials.fabric("silk")
    assert materials.fabric("Nylon") is materials.NYLON
