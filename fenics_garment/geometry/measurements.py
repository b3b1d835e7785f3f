"""Body measurements: what they mean, default sizes, and overrides.

Definitions follow ISO 8559-1:2017 ("Size designation of clothes — Anthropometric definitions
for body measurement"): girths are horizontal tape measurements (the tape bridges hollows, so a
girth is the perimeter of the *convex hull* of the horizontal section), heights are vertical
distances from the floor, shoulder width is the biacromial breadth.

Where the numbers come from:

* **Torso girths** (mid-neck, bust, under-bust, waist): ASTM D5585-11e1, "Standard Tables of
  Body Measurements for Adult Female Misses Figure Type, Size Range 00–20", Table 1 (inch-pound
  units), rows "Mid-Neck Girth", "Chest/Bust Girth", "Under-Bust Girth" and "Waist Girth Curvy" /
  "Waist Girth Straight" — transcribed below in inches, converted to metres in ``units``.
  ``measurements("US10")`` is that table's size 10; an EN 13402-3 size code (``"88"`` = bust
  girth 88 cm, 4 cm steps) takes the bust girth from the code and the other torso girths
  interpolated in the ASTM table at that bust girth.
* **Hip girth** of an EN size: EN 13402-3 labels bottoms by hip girth in 4 cm steps; the pairing
  bust 88 ↔ hip 96 (bust + 8 cm) is **our assumption**, not a table value.
* **Everything else** (shoulder width, limb girths, arm lengths, head girth, the landmark
  heights as fractions of stature) is **our own round-number proportion for an adult woman**,
  not from a standard or a survey; limb girths scale with the hip, shoulder width with the bust.
  For a real wearer pass measured values as overrides: every field can be overridden.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from itertools import pairwise

import numpy as np

from fenics_garment.units import inch_to_m

# Landmark levels, bottom to top, used by the mannequin, the region tagger and the garments.
TORSO_LEVELS = (
    "crotch",
    "hip",
    "abdomen",
    "waist",
    "underbust",
    "bust",
    "upper_chest",
    "shoulder",
    "neck_base",
    "neck",
)
LEG_LEVELS = ("ankle", "calf", "knee", "thigh")


@dataclass(frozen=True)
class Measurements:
    """Body measurements in metres (SI). Girths are tape girths (ISO 8559-1), heights from floor."""

    stature: float = 1.68
    neck_girth: float = 0.34
    shoulder_width: float = 0.38  # biacromial breadth
    bust_girth: float = 0.88  # EN 13402-3 bust step (size "88")
    underbust_girth: float = 0.75
    waist_girth: float = 0.72
    hip_girth: float = 0.96  # EN 13402-3 hip step (size "96")
    thigh_girth: float = 0.56
    knee_girth: float = 0.37
    calf_girth: float = 0.35
    ankle_girth: float = 0.22
    # Arms and head, for the human mannequin (geometry.human). ISO 8559-1 definitions: upper-arm
    # girth half-way between acromion and elbow, elbow girth over the olecranon, wrist girth
    # over the styloid processes, head girth the largest horizontal girth over the brow ridges
    # and the back of the head; arm lengths along the arm (acromion to radiale, radiale to
    # stylion), hand length from the wrist crease to the tip of the middle finger. Values: our
    # round numbers for an adult woman (the arm girths are those of the separate arm,
    # mannequin.ARM_GIRTHS; no survey table was at hand), not from a standard or a survey.
    upper_arm_girth: float = 0.27
    elbow_girth: float = 0.235
    forearm_girth: float = 0.215
    wrist_girth: float = 0.155
    head_girth: float = 0.55
    upper_arm_length: float = 0.31
    forearm_length: float = 0.24
    hand_length: float = 0.18
    # Heights of the levels as fractions of stature (illustrative proportions, see module doc).
    neck_height: float = 0.875
    neck_base_height: float = 0.845
    shoulder_height: float = 0.815
    upper_chest_height: float = 0.755
    bust_height: float = 0.72
    underbust_height: float = 0.67
    waist_height: float = 0.625
    abdomen_height: float = 0.575
    hip_height: float = 0.515
    crotch_height: float = 0.465
    thigh_height: float = 0.43
    knee_height: float = 0.285
    calf_height: float = 0.205
    ankle_height: float = 0.06

    def height(self, level: str) -> float:
        """Height of a landmark level above the floor in metres."""
        return getattr(self, f"{level}_height") * self.stature

    def girth(self, level: str) -> float | None:
        """Requested tape girth at a level, or None where no girth is specified."""
        return getattr(self, f"{level}_girth", None)

    def __post_init__(self) -> None:
        heights = [getattr(self, f"{lv}_height") for lv in ("ankle", "calf", "knee", "thigh")]
        heights += [getattr(self, f"{lv}_height") for lv in TORSO_LEVELS]
        if any(b <= a for a, b in pairwise(heights)):
            raise ValueError(f"landmark heights must increase from ankle to neck, got {heights}")
        for f in fields(self):
            if getattr(self, f.name) <= 0:
                raise ValueError(f"{f.name} must be positive")


# ASTM D5585-11e1, Table 1 (inches), sizes 00 … 20: the rows this model uses.
_ASTM_SIZES = ("00", "0", "2", "4", "6", "8", "10", "12", "14", "16", "18", "20")
_ASTM_IN = {
    "neck_girth": (12.375, 12.625, 12.875, 13.125, 13.375, 13.625, 13.875, 14.25, 14.625, 15.0,
                   15.5, 16.0),  # "Mid-Neck Girth"
    "bust_girth": (31.125, 31.75, 33.0, 34.125, 35.25, 36.25, 37.25, 38.75, 40.375, 42.125,
                   44.0, 46.0),  # "Chest/Bust Girth"
    "underbust_girth": (25.75, 26.5, 27.25, 28.0, 29.0, 30.0, 31.0, 32.5, 34.0, 35.75, 37.625,
                        39.625),  # "Under-Bust Girth"
    "waist_curvy": (23.875, 24.625, 25.375, 26.125, 27.0, 28.0, 29.0, 30.75, 32.5, 34.5, 36.75,
                    39.0),  # "Waist Girth Curvy"
    "waist_straight": (25.375, 26.125, 26.875, 27.625, 28.5, 29.5, 30.5, 32.25, 34.0, 36.0,
                       38.25, 40.5),  # "Waist Girth Straight"
}  # fmt: skip

# EN 13402-3 bust-girth codes [cm] offered; hip = bust + 8 cm (our assumption, see module doc).
_EN_BUST_CM = (80, 84, 88, 92, 96, 100, 104)

#: Every size code :func:`measurements` accepts.
SIZE_CODES: tuple[str, ...] = tuple(str(b) for b in _EN_BUST_CM) + tuple(
    f"US{s}" for s in _ASTM_SIZES
)


def astm_table(figure: str = "curvy") -> dict[str, np.ndarray]:
    """The ASTM D5585-11e1 torso girths in metres, one array per measurement, sizes 00 … 20."""
    if figure not in ("curvy", "straight"):
        raise ValueError(f"figure must be 'curvy' or 'straight', not {figure!r}")
    table = {k: inch_to_m(np.asarray(v)) for k, v in _ASTM_IN.items() if not k.startswith("w")}
    table["waist_girth"] = inch_to_m(np.asarray(_ASTM_IN[f"waist_{figure}"]))
    return table


def _torso_girths(size: str, figure: str) -> dict[str, float]:
    """Neck, bust, under-bust and waist girths [m] of a size code (see module doc)."""
    table = astm_table(figure)
    if size.upper().startswith("US"):
        code = size[2:]
        if code not in _ASTM_SIZES:
            raise KeyError(
                f"unknown ASTM D5585 size {size!r}; known: US" + ", US".join(_ASTM_SIZES)
            )
        i = _ASTM_SIZES.index(code)
        return {k: float(v[i]) for k, v in table.items()}
    if not size.isdigit() or int(size) not in _EN_BUST_CM:
        known = ", ".join(str(b) for b in _EN_BUST_CM)
        raise KeyError(f"unknown size {size!r}; known: EN 13402-3 bust codes {known}, "
                       f"or ASTM D5585 sizes US00 … US20")  # fmt: skip
    bust = int(size) / 100.0
    b = table["bust_girth"]
    return {k: float(np.interp(bust, b, v)) for k, v in table.items()}


def measurements(size: str = "88", figure: str = "curvy", **overrides: float) -> Measurements:
    """Measurements for a size code, then ``overrides`` applied (all in metres).

    ``size``: an EN 13402-3 bust-girth code in cm (``"80"`` … ``"104"``) or an ASTM D5585 misses
    size (``"US00"`` … ``"US20"``); ``figure``: the ASTM waist row, ``"curvy"`` or ``"straight"``.

    >>> round(measurements("US10").bust_girth, 5)  # 37 1/4 in
    0.94615
    """
    torso = _torso_girths(size, figure)
    base = Measurements()
    kb = torso["bust_girth"] / base.bust_girth
    hip = torso["bust_girth"] + 0.08
    kh = hip / base.hip_girth
    scaled = {
        **torso,
        "hip_girth": hip,
        "shoulder_width": base.shoulder_width * kb,
        "thigh_girth": base.thigh_girth * kh,
        "knee_girth": base.knee_girth * kh,
        "calf_girth": base.calf_girth * kh,
        "ankle_girth": base.ankle_girth * kh,
        **{f"{k}_girth": getattr(base, f"{k}_girth") * kh
           for k in ("upper_arm", "elbow", "forearm", "wrist")},
    }  # fmt: skip
    unknown = set(overrides) - {f.name for f in fields(Measurements)}
    if unknown:
        raise TypeError(f"unknown measurement(s): {sorted(unknown)}")
    return replace(base, **{**scaled, **overrides})
