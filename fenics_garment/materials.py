"""Shell materials: isotropic solids and orthotropic fabrics, as stiffness resultants per width.

A shell needs four constitutive blocks, all per unit reference width, in an orthonormal local
frame (e1 = warp, e2 = weft, in the tangent plane):

* membrane  N = A ε     (A11, A22, A12, A66)  [N/m]
* bending   M = D κ     (D11, D22, D12, D66)  [N·m]
* shear     Q = S γ     (S1, S2)              [N/m]
* mass per area ρh                           [kg/m²]

For an isotropic plate A = Eh/(1−ν²)[1 ν; ν 1], A66 = Gh, D = A h²/12, S = κ_s G h. Fabrics do
not obey D = Eh³/12(1−ν²) — the yarns slide and bend individually — so :class:`Fabric` takes the
bending rigidities as measured (KES-FB2 pure bending) independently of the tensile moduli.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from fenics_garment import units

SHEAR_CORRECTION = 5.0 / 6.0  # Reissner's transverse shear correction factor


class MaterialError(ValueError):
    """A material parameter is outside its physical range."""


def _positive(name: str, value: float, what: str) -> None:
    if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
        raise MaterialError(f"{what}: {name} must be a positive finite number, got {value!r}")


@dataclass(frozen=True)
class ShellStiffness:
    """Stiffness resultants of a shell in its local (warp, weft) frame, SI units."""

    A11: float
    A22: float
    A12: float
    A66: float
    D11: float
    D22: float
    D12: float
    D66: float
    S1: float
    S2: float
    thickness: float
    mass_per_area: float

    @property
    def membrane_scale(self) -> float:
        """A representative membrane stiffness (N/m), e.g. to scale penalties."""
        return 0.5 * (self.A11 + self.A22)

    @property
    def bending_scale(self) -> float:
        """A representative bending stiffness (N·m)."""
        return 0.5 * (self.D11 + self.D22)

    @property
    def effective_thickness(self) -> float:
        """t_eff = √(12 D/A): the thickness of the isotropic plate with the same D/A ratio.

        It sets the membrane/shear-to-bending stiffness ratio that PSRI weighs (α = t_eff²/h²);
        for an isotropic shell it is the thickness itself.
        """
        return math.sqrt(12.0 * self.bending_scale / self.membrane_scale)


@dataclass(frozen=True)
class Isotropic:
    """A linear elastic isotropic shell of thickness ``thickness``: (E, ν, ρ)."""

    E: float
    nu: float
    thickness: float
    density: float = 0.0
    name: str = "isotropic"

    def __post_init__(self) -> None:
        _positive("E", self.E, self.name)
        _positive("thickness", self.thickness, self.name)
        if not (-1.0 < self.nu < 0.5):
            raise MaterialError(f"{self.name}: Poisson ratio must lie in (-1, 0.5), got {self.nu}")
        if self.density < 0:
            raise MaterialError(f"{self.name}: density must be >= 0, got {self.density}")

    def stiffness(self) -> ShellStiffness:
        E, nu, h = self.E, self.nu, self.thickness
        G = E / (2.0 * (1.0 + nu))
        a = E * h / (1.0 - nu**2)
        d = E * h**3 / (12.0 * (1.0 - nu**2))
        s = SHEAR_CORRECTION * G * h
        return ShellStiffness(
            A11=a, A22=a, A12=nu * a, A66=G * h,
            D11=d, D22=d, D12=nu * d, D66=0.5 * (1.0 - nu) * d,
            S1=s, S2=s, thickness=h, mass_per_area=self.density * h,
        )  # fmt: skip


@dataclass(frozen=True)
class Fabric:
    """An orthotropic woven or knitted fabric, warp along e1 and weft along e2 (SI units).

    How each Kawabata (KES-F) quantity maps onto the model (see :func:`Fabric.from_kes`):

    * tensile modulus warp/weft (KES-FB1, gf/cm² as tabulated by the seed paper's Table 2, i.e.
      already divided by thickness) → E1, E2; membrane A11 = E1 h/(1−ν12ν21), A22 = E2 h/(…).
    * shear modulus (KES-FB1 shear, gf/cm²) → in-plane G12; A66 = G12 h.
    * bending rigidity warp/weft (KES-FB2, gf·cm²/cm) → D11, D22 directly (per unit width).
    * thickness (KES-FB3 at 0.5 gf/cm²) → h, and density → mass per area ρh.

    Not measured by the KES and therefore assumed (stated, replaceable): the in-plane Poisson ratio
    ν12 (default 0.3), the bending coupling D12 = ν12 √(D11 D22), the twisting rigidity
    D66 = (1−ν12)/2 √(D11 D22) (the isotropic-plate relations applied to the geometric mean), and
    the transverse shear stiffness S = κ_s G12 h.
    """

    E_warp: float
    E_weft: float
    G12: float
    B_warp: float
    B_weft: float
    thickness: float
    density: float
    nu12: float = 0.3
    name: str = "fabric"
    source: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        for key in ("E_warp", "E_weft", "G12", "B_warp", "B_weft", "thickness"):
            _positive(key, getattr(self, key), self.name)
        if self.density < 0:
            raise MaterialError(f"{self.name}: density must be >= 0, got {self.density}")
        nu21 = self.nu12 * self.E_weft / self.E_warp
        if not (0.0 <= self.nu12 and self.nu12 * nu21 < 1.0):
            raise MaterialError(
                f"{self.name}: Poisson ratio ν12={self.nu12} gives ν12·ν21={self.nu12 * nu21:.3g}"
                " (must be >= 0 and < 1 for a positive definite membrane stiffness)"
            )

    @classmethod
    def from_kes(
        cls,
        *,
        tensile_warp_gf_cm2: float,
        tensile_weft_gf_cm2: float,
        shear_gf_cm2: float,
        bending_warp_gf_cm2_cm: float,
        bending_weft_gf_cm2_cm: float,
        thickness_cm: float,
        density_g_cm3: float,
        nu12: float = 0.3,
        name: str = "fabric",
        source: str = "",
    ) -> Fabric:
        """Build a fabric from Kawabata-unit data (see the class docstring for the mapping)."""
        return cls(
            E_warp=units.gf_per_cm2_to_pa(tensile_warp_gf_cm2),
            E_weft=units.gf_per_cm2_to_pa(tensile_weft_gf_cm2),
            G12=units.gf_per_cm2_to_pa(shear_gf_cm2),
            B_warp=units.gf_cm2_per_cm_to_nm(bending_warp_gf_cm2_cm),
            B_weft=units.gf_cm2_per_cm_to_nm(bending_weft_gf_cm2_cm),
            thickness=units.cm_to_m(thickness_cm),
            density=units.g_per_cm3_to_kg_per_m3(density_g_cm3),
            nu12=nu12,
            name=name,
            source=source,
        )

    def stiffness(self) -> ShellStiffness:
        h = self.thickness
        nu21 = self.nu12 * self.E_weft / self.E_warp
        den = 1.0 - self.nu12 * nu21
        dm = math.sqrt(self.B_warp * self.B_weft)
        s = SHEAR_CORRECTION * self.G12 * h
        return ShellStiffness(
            A11=self.E_warp * h / den,
            A22=self.E_weft * h / den,
            A12=self.nu12 * self.E_weft * h / den,
            A66=self.G12 * h,
            D11=self.B_warp,
            D22=self.B_weft,
            D12=self.nu12 * dm,
            D66=0.5 * (1.0 - self.nu12) * dm,
            S1=s,
            S2=s,
            thickness=h,
            mass_per_area=self.density * h,
        )


@dataclass(frozen=True)
class TensionStrainCurve:
    """A measured uniaxial tension–strain curve: tension per unit *reference* width T [N/m]
    against engineering strain e = λ − 1 (as KES-FB1 and strip tests report it), piecewise
    linear between the samples, from (0, 0).

    Beyond the samples the curve continues with its last slope; below zero strain with its first
    (a fabric buckles in compression long before that stiffness matters; stated, replaceable).
    The tension must not decrease (a convex strain energy: Newton's tangent stays positive).
    Used by :func:`fenics_garment.shell.energy.tabulated_membrane`.
    """

    strain: tuple[float, ...]
    tension: tuple[float, ...]
    name: str = "curve"
    source: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        e = np.asarray(self.strain, dtype=float)
        t = np.asarray(self.tension, dtype=float)
        what = f"tension–strain curve {self.name!r}"
        if e.ndim != 1 or e.shape != t.shape or len(e) < 2:
            raise MaterialError(f"{what}: strain and tension need the same length ≥ 2")
        if not (np.all(np.isfinite(e)) and np.all(np.isfinite(t))):
            raise MaterialError(f"{what}: samples must be finite")
        if e[0] != 0.0 or t[0] != 0.0:
            raise MaterialError(f"{what}: must start at (0, 0), got ({e[0]}, {t[0]})")
        if np.any(np.diff(e) <= 0):
            raise MaterialError(f"{what}: strains must increase strictly")
        if np.any(np.diff(t) < 0) or t[1] <= 0:
            raise MaterialError(f"{what}: tension must not decrease and must rise at first")
        object.__setattr__(self, "strain", tuple(float(x) for x in e))
        object.__setattr__(self, "tension", tuple(float(x) for x in t))

    @property
    def slopes(self) -> np.ndarray:
        """dT/de of each segment [N/m]."""
        return np.diff(self.tension) / np.diff(self.strain)

    def tension_at(self, e):
        """T(e) [N/m], linear beyond the samples with the end slopes."""
        e = np.asarray(e, dtype=float)
        k = self.slopes
        x = np.asarray(self.strain)
        ramps = sum(dk * np.maximum(e - xi, 0.0) for dk, xi in zip(np.diff(k), x[1:-1],
                                                                    strict=True))  # fmt: skip
        return k[0] * e + ramps

    def energy_at(self, e):
        """W(e) = ∫₀ᵉ T de' [J/m²]: the strain energy per reference area of a uniaxial stretch."""
        e = np.asarray(e, dtype=float)
        k = self.slopes
        x = np.asarray(self.strain)
        ramps = sum(dk * np.maximum(e - xi, 0.0) ** 2 for dk, xi in zip(np.diff(k), x[1:-1],
                                                                         strict=True))  # fmt: skip
        return 0.5 * (k[0] * e**2 + ramps)


_TABLE2 = (
    "Seed paper (finite-element mechanical contact model based on Mindlin–Reissner shell theory "
    "for a 3D human body and garment), Table 2, KES-measured. The table labels the bending column "
    "'gf/cm²'; we read it as the KES bending rigidity B in gf·cm²/cm."
)

#: Nylon fabric of the seed paper's Table 2.
NYLON = Fabric.from_kes(
    tensile_warp_gf_cm2=11867.7,
    tensile_weft_gf_cm2=13409.7,
    shear_gf_cm2=2546.1,
    bending_warp_gf_cm2_cm=3.725,
    bending_weft_gf_cm2_cm=4.576,
    thickness_cm=0.062,
    density_g_cm3=0.408,
    name="nylon",
    source=_TABLE2,
)

#: Cotton fabric of the seed paper's Table 2.
COTTON = Fabric.from_kes(
    tensile_warp_gf_cm2=11712.5,
    tensile_weft_gf_cm2=11070.9,
    shear_gf_cm2=1105.8,
    bending_warp_gf_cm2_cm=1.494,
    bending_weft_gf_cm2_cm=1.26,
    thickness_cm=0.046,
    density_g_cm3=0.404,
    name="cotton",
    source=_TABLE2,
)


@dataclass(frozen=True)
class BodyTissue:
    """The body's soft tissue as the seed paper models it (Table 1): E, ν, density (SI)."""

    E: float
    nu: float
    density: float
    source: str = ""


#: Seed paper, Table 1: density 0.6 g/cm³, tensile modulus 205 gf/cm², Poisson ratio 0.3.
BODY = BodyTissue(
    E=units.gf_per_cm2_to_pa(205.0),
    nu=0.3,
    density=units.g_per_cm3_to_kg_per_m3(0.6),
    source="Seed paper, Table 1 (material parameters of the human body)",
)

FABRICS: dict[str, Fabric] = {"nylon": NYLON, "cotton": COTTON}


def fabric(name: str) -> Fabric:
    """A built-in fabric by name, with a clear error listing the known ones."""
    try:
        return FABRICS[name.lower()]
    except KeyError:
        raise MaterialError(
            f"unknown fabric {name!r}; built-in fabrics: {', '.join(sorted(FABRICS))}"
        ) from None
