"""Typed errors of the geometry layer: each says what was asked for and what exists instead."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class MissingRegion(KeyError):
    """A region, panel or edge tag was looked up by a name the surface does not carry."""

    name: str
    available: tuple[str, ...]

    def __str__(self) -> str:
        return f"no region named {self.name!r}; available: {', '.join(self.available) or 'none'}"


@dataclass
class ScanError(ValueError):
    """A body scan could not be turned into one closed, orientable surface."""

    reason: str
    hint: str = ""

    def __str__(self) -> str:
        return self.reason + (f" ({self.hint})" if self.hint else "")


@dataclass
class GeometryError(RuntimeError):
    """gmsh/OpenCASCADE could not build a requested shape (e.g. a cut that missed the garment)."""

    what: str

    def __str__(self) -> str:
        return self.what
