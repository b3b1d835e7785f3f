"""Unit conversions, all in one place: the Kawabata Evaluation System (KES) and the paper's tables.

The package works in SI internally (m, kg, s, N, Pa). Fabric data measured with the KES are given
in gram-force based units; these constants convert them. 1 gf = 9.80665e-3 N (the standard
acceleration of gravity, CGPM 1901, times one gram).
"""

from __future__ import annotations

GRAVITY = 9.80665  # m/s², standard acceleration of gravity (3rd CGPM, 1901)
GRAM_FORCE = 1e-3 * GRAVITY  # N

CM = 1e-2  # m
MM = 1e-3  # m
INCH = 0.0254  # m, exact (international inch, 1959)


def gf_per_cm2_to_pa(value: float) -> float:
    """Stress or modulus: gf/cm² → Pa (1 gf/cm² = 98.0665 Pa)."""
    return value * GRAM_FORCE / CM**2


def gf_cm2_per_cm_to_nm(value: float) -> float:
    """KES bending rigidity B per unit width: gf·cm²/cm → N·m²/m = N·m (1 → 9.80665e-5 N·m)."""
    return value * GRAM_FORCE * CM**2 / CM


def gf_per_cm_to_n_per_m(value: float) -> float:
    """Force per unit width (KES tensile/shear stiffness per width): gf/cm → N/m."""
    return value * GRAM_FORCE / CM


def gf_cm_per_cm_to_nm_per_m(value: float) -> float:
    """KES bending hysteresis 2HB (moment per unit width): gf·cm/cm → N·m/m (1 → 9.80665e-3)."""
    return value * GRAM_FORCE * CM / CM


def mg_per_cm2_to_kg_per_m2(value: float) -> float:
    """Areal mass (KES W): mg/cm² → kg/m² (1 mg/cm² = 10 g/m² = 1e-2 kg/m²)."""
    return value * 1e-6 / CM**2


def g_per_m2_to_kg_per_m2(value: float) -> float:
    """Areal mass (fabric 'weight'): g/m² → kg/m²."""
    return value * 1e-3


def mm_to_m(value: float) -> float:
    """Length: mm → m."""
    return value * MM


def clo3d_stretch_to_n_per_m(value: float) -> float:
    """CLO3D's stretch or shear input, labelled g/s², read literally as a force per unit width:
    1 g/s² = 1e-3 kg/s² = 1e-3 N/m. (A reading of the unit label, not confirmed by CLO3D's
    documentation of how it uses the number.)"""
    return value * 1e-3


def clo3d_bending_to_nm(value: float) -> float:
    """CLO3D's bending input, labelled g·mm²/s², read literally as a moment per unit curvature
    per unit width: 1 g·mm²/s² = 1e-3 kg × 1e-6 m²/s² = 1e-9 N·m. (A reading of the unit
    label, as :func:`clo3d_stretch_to_n_per_m`.)"""
    return value * 1e-3 * MM**2


def g_per_cm3_to_kg_per_m3(value: float) -> float:
    """Density: g/cm³ → kg/m³."""
    return value * 1e3


def cm_to_m(value: float) -> float:
    """Length: cm → m."""
    return value * CM


def inch_to_m(value):
    """Inches (e.g. ASTM body-measurement tables) to metres; scalars or arrays."""
    return value * INCH


def pa_to_kpa(value: float) -> float:
    """Pressure: Pa → kPa."""
    return value * 1e-3


MMHG = 133.322387415  # Pa per mmHg (conventional millimetre of mercury, 13.5951 g/cm³ × g_n)


def pa_to_mmhg(value: float) -> float:
    """Pressure: Pa → mmHg."""
    return value / MMHG
