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
