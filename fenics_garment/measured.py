"""Measured fabrics (``data/fabrics_measured.toml``): the inputs and measured values, in SI.

The data file keeps every number in the unit of its source (the key says which). The one
conversion to SI is :func:`si_inputs`, built from :mod:`fenics_garment.units`; everything else
(the cantilever's bending lengths, drape scenes) reads :class:`MeasuredFabric` records.

Two sources (see the data file for papers, tables and transcriptions):

* Petrak et al. 2025: areal mass, thickness and CLO3D's converted inputs (stretch, shear,
  bending per warp/weft) — with the literal reading of CLO3D's unit labels
  (:func:`~fenics_garment.units.clo3d_stretch_to_n_per_m`,
  :func:`~fenics_garment.units.clo3d_bending_to_nm`), stated beside any result using them;
* Matsudaira et al. 2015: KES-FB2 bending rigidity B and hysteresis 2HB (one value, used for
  warp and weft), weight W, thickness T. No tensile or shear values: :data:`MISSING_MEMBRANE_RULE`.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from functools import cache
from importlib.resources import files

from fenics_garment import units
from fenics_garment.materials import Fabric

GRAVITY = units.GRAVITY

MISSING_MEMBRANE_RULE = (
    "fabrics without tensile and shear data (Matsudaira 2015) get the mean of the Petrak 2025 "
    "fabrics' converted stretch (warp and weft together) and shear stiffness, the same for all"
)


@dataclass(frozen=True)
class MeasuredFabric:
    """One fabric's inputs and measured values in SI (None where the source has none)."""

    id: str
    name: str
    source: str
    mass_per_area: float  # kg/m²
    thickness: float  # m
    B_warp: float  # N·m (bending rigidity per unit width)
    B_weft: float  # N·m
    stretch_warp: float | None  # N/m (membrane stiffness per unit width)
    stretch_weft: float | None  # N/m
    shear: float | None  # N/m
    twoHB: float | None  # N·m/m (KES bending hysteresis width 2HB; of the warp)
    dc_measured: float
    dc_clo3d: float | None
    nodes_measured: int | None
    specimen_diameter: float  # m
    pedestal_diameter: float  # m
    twoHB_weft: float | None = None  # N·m/m (None: as the warp's)

    @property
    def weight_per_area(self) -> float:
        """W = m g [N/m²] under standard gravity."""
        return self.mass_per_area * GRAVITY


#: The keys of a fabric's material values in KES-FB units (Matsudaira's records; a drape scene's
#: ``[drape.kes]``): required, then optional (B of the weft, 2HB of the weft: default the warp's).
KES_KEYS = ("B_gf_cm2_per_cm", "W_mg_cm2", "T_mm")
KES_OPTIONAL = ("twoHB_gf_cm_per_cm", "B_weft_gf_cm2_per_cm", "twoHB_weft_gf_cm_per_cm")
#: The keys of CLO3D-style converted values (Petrak's records; a drape scene's ``[drape.clo3d]``).
CLO3D_KEYS = ("areal_mass_g_m2", "thickness_mm", "stretch_warp_g_s2", "stretch_weft_g_s2",
              "shear_g_s2", "bending_warp_g_mm2_s2", "bending_weft_g_mm2_s2")  # fmt: skip
CLO3D_OPTIONAL = ("twoHB_gf_cm_per_cm",)


def material_si(values: dict[str, float]) -> dict[str, float | None]:
    """The material fields of :class:`MeasuredFabric` in SI from values in their sources' units:
    the KES form (:data:`KES_KEYS`) or the CLO3D-style form (:data:`CLO3D_KEYS`). The only
    place where these units are converted (data file and drape scenes alike):

    * CLO3D-style (Petrak): g/m² → kg/m², mm → m, stretch/shear g/s² → N/m (×1e-3), bending
      g·mm²/s² → N·m (×1e-9);
    * KES (Matsudaira): B gf·cm²/cm → N·m (×9.80665e-5), 2HB gf·cm/cm → N·m/m (×9.80665e-3),
      W mg/cm² → kg/m² (×1e-2), T mm → m.

    Raises ValueError for a missing, unknown, non-positive or non-finite value.
    """
    clo3d = any(k in values for k in CLO3D_KEYS)
    keys, optional = (CLO3D_KEYS, CLO3D_OPTIONAL) if clo3d else (KES_KEYS, KES_OPTIONAL)
    form = "CLO3D-style" if clo3d else "KES"
    missing = [k for k in keys if k not in values]
    unknown = [k for k in values if k not in keys and k not in optional]
    if missing:
        raise ValueError(f"{form} values: missing {', '.join(missing)}")
    if unknown:
        raise ValueError(f"{form} values: unknown key {unknown[0]!r}; known: "
                         f"{', '.join(keys + optional)}")  # fmt: skip
    for k, v in values.items():
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) or v <= 0:
            raise ValueError(f"{form} values: {k} must be a positive number, got {v!r}")
    hb = values.get("twoHB_gf_cm_per_cm")
    twoHB = None if hb is None else units.gf_cm_per_cm_to_nm_per_m(hb)
    if clo3d:
        return {
            "mass_per_area": units.g_per_m2_to_kg_per_m2(values["areal_mass_g_m2"]),
            "thickness": units.mm_to_m(values["thickness_mm"]),
            "B_warp": units.clo3d_bending_to_nm(values["bending_warp_g_mm2_s2"]),
            "B_weft": units.clo3d_bending_to_nm(values["bending_weft_g_mm2_s2"]),
            "stretch_warp": units.clo3d_stretch_to_n_per_m(values["stretch_warp_g_s2"]),
            "stretch_weft": units.clo3d_stretch_to_n_per_m(values["stretch_weft_g_s2"]),
            "shear": units.clo3d_stretch_to_n_per_m(values["shear_g_s2"]),
            "twoHB": twoHB, "twoHB_weft": twoHB,
        }  # fmt: skip
    B = units.gf_cm2_per_cm_to_nm(values["B_gf_cm2_per_cm"])
    B_weft = values.get("B_weft_gf_cm2_per_cm")
    hb_weft = values.get("twoHB_weft_gf_cm_per_cm")
    return {
        "mass_per_area": units.mg_per_cm2_to_kg_per_m2(values["W_mg_cm2"]),
        "thickness": units.mm_to_m(values["T_mm"]),
        "B_warp": B,
        "B_weft": B if B_weft is None else units.gf_cm2_per_cm_to_nm(B_weft),
        "stretch_warp": None, "stretch_weft": None, "shear": None,
        "twoHB": twoHB,
        "twoHB_weft": twoHB if hb_weft is None else units.gf_cm_per_cm_to_nm_per_m(hb_weft),
    }  # fmt: skip


def material_values(record: dict) -> dict[str, float]:
    """The material values of a data-file record or a scene table (its keys of
    :data:`KES_KEYS`, :data:`CLO3D_KEYS` and their optional ones)."""
    known = KES_KEYS + KES_OPTIONAL + CLO3D_KEYS + CLO3D_OPTIONAL
    return {k: v for k, v in record.items() if k in known}


def si_inputs(record: dict, source: dict) -> MeasuredFabric:
    """The SI record of one ``[[fabric]]`` table of the data file (with its ``[sources.*]``):
    its material values through :func:`material_si`, the specimen sizes of its source."""
    values = material_values(record)
    if not any(k in values for k in ("bending_warp_g_mm2_s2", "B_gf_cm2_per_cm")):
        raise ValueError(f"fabric {record.get('id')!r}: neither CLO3D nor KES bending values")
    return MeasuredFabric(
        id=record["id"],
        name=record["name"],
        source=record["source"],
        dc_measured=float(record["dc_measured"]),
        dc_clo3d=record.get("dc_clo3d"),
        nodes_measured=record.get("nodes_measured"),
        specimen_diameter=units.mm_to_m(source["specimen_diameter_mm"]),
        pedestal_diameter=units.mm_to_m(source["pedestal_diameter_mm"]),
        **material_si(values),
    )


@cache
def _raw() -> dict:
    return tomllib.loads(files("fenics_garment").joinpath("data/fabrics_measured.toml").read_text())


def sources() -> dict[str, dict]:
    """The ``[sources.*]`` tables (paper, transcription, what was measured)."""
    return _raw()["sources"]


def fabrics() -> list[MeasuredFabric]:
    """Every fabric of the data file, in SI, in file order."""
    raw = _raw()
    return [si_inputs(r, raw["sources"][r["source"]]) for r in raw["fabric"]]


def by_id(fabric_id: str) -> MeasuredFabric:
    for f in fabrics():
        if f.id == fabric_id:
            return f
    raise KeyError(f"no measured fabric {fabric_id!r}; known: {[f.id for f in fabrics()]}")


def membrane_rule() -> tuple[float, float]:
    """(stretch, shear) [N/m] of :data:`MISSING_MEMBRANE_RULE`."""
    known = [f for f in fabrics() if f.stretch_warp is not None]
    stretch = sum(f.stretch_warp + f.stretch_weft for f in known) / (2 * len(known))
    shear = sum(f.shear for f in known) / len(known)
    return stretch, shear


def to_fabric(m: MeasuredFabric, *, nu12: float = 0.3) -> Fabric:
    """The shell material of a measured fabric: the stiffnesses per unit width divided by the
    thickness give the moduli of :class:`~fenics_garment.materials.Fabric` (so that
    A11 = stretch/(1 − ν12 ν21) ≈ stretch, A66 = shear, D = B as measured, ρh = areal mass)."""
    if m.stretch_warp is None:
        stretch, shear = membrane_rule()
        sw = se = stretch
    else:
        sw, se, shear = m.stretch_warp, m.stretch_weft, m.shear
    h = m.thickness
    return Fabric(E_warp=sw / h, E_weft=se / h, G12=shear / h, B_warp=m.B_warp,
                  B_weft=m.B_weft, thickness=h, density=m.mass_per_area / h, nu12=nu12,
                  name=m.id, source=sources()[m.source]["paper"])  # fmt: skip
