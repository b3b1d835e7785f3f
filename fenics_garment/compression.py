"""Compression garments on limbs: Laplace's law per level and the RAL-GZ 387 compression classes.

**Laplace's law at a level.** A tight tube of rest girth ``(1 + ease) G`` on a limb section of tape
girth ``G`` is stretched in the hoop by λ = (G + π h)/((1 + ease) G) (its mid-surface lies h/2
outside the skin). With the tension uniform around the section (no friction around it), the
contact force per unit length of a closed convex section is n_θθ ∮ κ ds = 2π n_θθ whatever its
shape, so the **mean** pressure around the section is n_θθ / R_eq with R_eq = (G + π h)/(2π):
an elliptic leg or arm is compared on its girth, not on a local radius (the pressure itself is
higher where the section is more curved). The free-end hoop force n_θθ and the bending part are
those of :func:`fenics_garment.verification.contact.tube_pressure` (S_zz = 0; the naive T/R is
wrong by
up to 9 %, see its module doc). Neglected: the limb's axial curvature and taper (a 4° taper
changes the normal by cos 4° = 0.998) and the axial stress friction leaves after dressing.

**RAL-GZ 387.** The compression classes of medical compression stockings by the pressure at the
ankle (the "B" measuring point): RAL Deutsches Institut für Gütesicherung und Kennzeichnung,
*RAL-GZ 387/1:2008 Medizinische Kompressionsstrümpfe — Gütesicherung*, class table as quoted
by manufacturers (e.g. ofa Bamberg, "Compression classes": I 2.4–2.8 kPa / 18–21 mmHg,
II 3.1–4.3 / 23–32, III 4.5–6.1 / 34–46, IV ≥ 6.5 / ≥ 49 mmHg; the same mmHg bands on
eurocom-info, the German compression-hosiery makers' association). The gaps between classes
(21–23, 32–34, 46–49 mmHg) belong to no class.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise

import numpy as np

from fenics_garment import units

#: RAL-GZ 387/1:2008 compression classes: (class, lowest, highest ankle pressure [mmHg]).
RAL_GZ_387: tuple[tuple[str, float, float], ...] = (
    ("I", 18.0, 21.0),  # light
    ("II", 23.0, 32.0),  # medium
    ("III", 34.0, 46.0),  # strong
    ("IV", 49.0, float("inf")),  # very strong
)


def ral_class(p_mmhg: float) -> str | None:
    """The RAL-GZ 387 class of an ankle pressure [mmHg], or None if it lies in no class band."""
    for name, lo, hi in RAL_GZ_387:
        if lo <= p_mmhg <= hi:
            return name
    return None


def describe_class(p_mmhg: float) -> str:
    """``class I (18–21 mmHg)``, or where the pressure falls outside the bands."""
    c = ral_class(p_mmhg)
    if c is not None:
        lo, hi = next((lo, hi) for n, lo, hi in RAL_GZ_387 if n == c)
        top = f"{hi:g}" if np.isfinite(hi) else "…"
        return f"class {c} ({lo:g}–{top} mmHg)"
    if p_mmhg < RAL_GZ_387[0][1]:
        return f"below class I (< {RAL_GZ_387[0][1]:g} mmHg)"
    for (a, _, hi), (b, lo, _) in pairwise(RAL_GZ_387):
        if hi < p_mmhg < lo:
            return f"between class {a} and {b} (no class)"
    return "no class"


def laplace_pressure(body_girth: float, ease: float, stiffness, bending: bool = True) -> float:
    """Analytic mean pressure [Pa] of a level (module doc): warp along the limb, hoop = weft."""
    from fenics_garment.verification.contact import tube_pressure

    h = stiffness.thickness
    r_c = body_girth / (2 * np.pi) + h / 2
    r0 = (1 + ease) * body_girth / (2 * np.pi)
    return tube_pressure(r_c, r0, stiffness, warp="axial", bending=bending)


def band_pressure(built, z: float, half_width: float) -> float:
    """Simulated mean pressure [Pa] in the band |z' − z| < ``half_width`` of a dressed scene:
    contact force over deformed area of the garment's contact points there (every rank). z' is
    the height, or on a scan's limb the distance along its centreline
    (:meth:`~fenics_garment.geometry.garments.GarmentSurface.axial`)."""
    from fenics_garment._stack import MPI
    from fenics_garment.contact import pressure as cpressure

    st, c = built.contact.state, built.contact
    f = cpressure.point_forces(st, c.traction)
    a = cpressure.point_areas(st, c.area_stretch())
    sel = np.abs(built.garment.axial(cpressure.positions(st)) - z) < half_width
    comm = built.model.geometry.mesh.comm
    area = comm.allreduce(float(a[sel].sum()), op=MPI.SUM)
    force = comm.allreduce(float(f[sel].sum()), op=MPI.SUM)
    return force / area if area > 0 else 0.0


@dataclass(frozen=True)
class LevelCheck:
    """Simulated vs Laplace pressure at one level of a limb garment."""

    level: str
    z: float
    body_girth: float
    ease: float
    laplace_pa: float
    simulated_pa: float

    @property
    def rel_error(self) -> float:
        return self.simulated_pa / self.laplace_pa - 1.0

    @property
    def simulated_mmhg(self) -> float:
        return units.pa_to_mmhg(self.simulated_pa)

    @property
    def laplace_mmhg(self) -> float:
        return units.pa_to_mmhg(self.laplace_pa)


def level_checks(built, levels: list[str], half_width: float = 0.01) -> list[LevelCheck]:
    """:class:`LevelCheck` of each garment level (names as in ``built.garment.levels``)."""
    s = built.model.stiffness
    out = []
    for name in levels:
        row = built.garment.level(name)
        lap = laplace_pressure(row.body_girth, row.ease, s)
        sim = band_pressure(built, row.z, half_width)
        base = name.removesuffix("_left").removesuffix("_right")
        out.append(LevelCheck(base, row.z, row.body_girth, row.ease, lap, sim))
    return out


def format_checks(checks: list[LevelCheck]) -> list[str]:
    """Table lines: level, girth, ease, Laplace and simulated pressure (kPa, mmHg), error."""
    lines = [f"  {'level':<10} {'girth':>6} {'ease':>6} {'Laplace':>15} {'simulated':>15} "
             f"{'error':>7}"]  # fmt: skip
    for c in checks:
        lines.append(
            f"  {c.level:<10} {c.body_girth * 100:5.1f}cm {c.ease:+6.1%} "
            f"{c.laplace_pa * 1e-3:5.2f} kPa {c.laplace_mmhg:4.1f} mmHg "
            f"{c.simulated_pa * 1e-3:5.2f} kPa {c.simulated_mmhg:4.1f} mmHg {c.rel_error:+7.2%}"
        )
    return lines
