"""Sewing patterns: flat panels, seams and grain lines (:mod:`.model`), their readers, and the
flat meshes sewn into a garment whose stress-free reference is the flat panels."""

from .model import (
    UNITS,
    Arc,
    Bezier,
    Edge,
    EdgeRange,
    Line,
    Panel,
    Pattern,
    PatternError,
    Placement,
    Polyline,
    Seam,
    Wrap,
)

__all__ = [
    "UNITS",
    "Arc",
    "Bezier",
    "Edge",
    "EdgeRange",
    "Line",
    "Panel",
    "Pattern",
    "PatternError",
    "Placement",
    "Polyline",
    "Seam",
    "Wrap",
]
