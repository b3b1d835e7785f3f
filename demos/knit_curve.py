"""A ``[physics] terms`` hook: the garment's membrane law from tension–strain curves.

Put ``terms = "knit_curve.py:terms"`` under ``[physics]`` of a scene beside this file to dress
the garment with the knit-like J-shaped curves of
:data:`fenics_garment.verification.contact.KNIT_LIKE_WARP` / ``KNIT_LIKE_WEFT`` (synthetic,
not a measurement) instead of the scene fabric's linear membrane law; the bending, shear and
mass stay the fabric's. For a measured curve, replace them by
``TensionStrainCurve(strain=(0, …), tension=(0, …))`` (tension per unit reference width
[N/m] against engineering strain, warp and weft).
"""

from __future__ import annotations

from fenics_garment.shell.energy import tabulated_membrane
from fenics_garment.verification.contact import KNIT_LIKE_WARP, KNIT_LIKE_WEFT


def terms(built) -> None:
    """Replace the membrane law of the built problem (before the solve)."""
    built.model.membrane = tabulated_membrane(KNIT_LIKE_WARP, KNIT_LIKE_WEFT)
