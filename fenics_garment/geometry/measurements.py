"""Body measurements: what they mean, default sizes, and overrides.

Definitions follow ISO 8559-1:2017 ("Size designation of clothes — Anthropometric definitions
for body measurement"): girths are horizontal tape measurements (the tape bridges hollows, so a
girth is the perimeter of the *convex hull* of the horizontal section), heights are vertical
distances from the floor, shoulder width is the biacromial breadth.

Size codes: EN 13402-3:2017 labels women's tops by bust girth in 4 cm steps (…, 84, 88, 92, …)
and bottoms by hip girth in 4 cm steps. The table below uses that scheme for the bust and hip
girths. **All other numbers in it (waist, neck, limb girths, heights as fractions of stature)
are our own illustrative, round-number proportions for an adult woman — they are NOT copied
from the standard's tables (which we did not have) or from a survey.** For a real wearer pass
the measured values as overrides; every field can be overridden.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from itertools import pairwise

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


# size code -> (bust girth, hip girth) in metres, EN 13402-3 4-cm steps; the secondary girths
# scale with the bust/hip ratio to the default (illustrative proportions, see module doc).
_SIZE_STEPS = {"80": (0.80, 0.88), "84": (0.84, 0.92), "88": (0.88, 0.96), "92": (0.92, 1.00),
               "96": (0.96, 1.04), "100": (1.00, 1.08), "104": (1.04, 1.12)}  # fmt: skip


def measurements(size: str = "88", **overrides: float) -> Measurements:
    """Measurements for a bust-girth size code (EN 13402-3 style, cm), then ``overrides`` applied.

    >>> measurements("92", waist_girth=0.80).waist_girth
    0.8
    """
    if size not in _SIZE_STEPS:
        raise KeyError(f"unknown size {size!r}; known: {', '.join(_SIZE_STEPS)}")
    base = Measurements()
    bust, hip = _SIZE_STEPS[size]
    kb, kh = bust / base.bust_girth, hip / base.hip_girth
    scaled = {
        "bust_girth": bust,
        "hip_girth": hip,
        "underbust_girth": base.underbust_girth * kb,
        "waist_girth": base.waist_girth * kb,
        "neck_girth": base.neck_girth * kb,
        "shoulder_width": base.shoulder_width * kb,
        "thigh_girth": base.thigh_girth * kh,
        "knee_girth": base.knee_girth * kh,
        "calf_girth": base.calf_girth * kh,
        "ankle_girth": base.ankle_girth * kh,
    }
    unknown = set(overrides) - {f.name for f in fields(Measurements)}
    if unknown:
        raise TypeError(f"unknown measurement(s): {sorted(unknown)}")
    return replace(base, **{**scaled, **overrides})
