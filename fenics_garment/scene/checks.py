"""Checks that every scene result carries (``summary.json`` → ``checks``).

A dressing can converge to a wrong answer without any solver noticing: a penalty so soft that the
garment sinks into the body, a spring that still carries the load, a garment that slid off the
body. Each check compares an observable of the final state with an independent bound:

* ``penetration``: deepest penetration of the garment's mid-surface into the skin (h/2 kept
  outside) over the fabric thickness h, at most :data:`LIMITS` ``["penetration"]`` = 1: a
  garment sunk into the body deeper than it is thick (a penalty too soft for the mesh, the
  penetration p/κ growing like 1/κ̂) has a pressure error of the order of that depth over the
  fit's interference (ease × radius);
* ``spring``: the largest traction the stabilising spring still carries over the largest contact
  pressure (0 once released to c = 0);
* ``force_balance``: |applied load + body reaction| over the larger of the two (the body's normal
  and friction tractions summed as vectors, the weight λ ρh g A): at an equilibrium free of the
  spring the two cancel, since the internal forces do no work on a rigid translation;
* ``multiplier_penetration``: with the augmented Lagrangian, the deepest penetration at the end
  over the scene's tolerance (``[physics] tolerance`` × h), at most 1: a multiplier loop that
  stopped short keeps its last converged state as the answer and fails this check;
* ``uncovered_contact``: the contact force on body parts the garment does not cover (arms and
  head for a gilet or a dress, :data:`UNCOVERED`) over the whole contact force, at most
  :data:`LIMITS` ``["uncovered_contact"]``: a torso garment pressing on an arm has an armhole
  cut too small for this body (not applicable to a pattern, whose pieces may cover anything,
  or on a body without those regions);
* ``contact_area``: the area in contact at the end over the area of the pattern that started
  inside the body (where it is tight, it must end up on the body; not applicable to a garment
  that is nowhere tight).

A failed check is printed as a WARNING; the CLI then exits with code 4 (the outputs are written).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from fenics_garment._stack import MPI, dolfinx, ufl
from fenics_garment.contact import pressure as cpressure

#: The bound of each check (see the module doc).
LIMITS = {
    "penetration": 1.0,
    "spring": 0.01,
    "force_balance": 0.02,
    "multiplier_penetration": 1.0,
    "uncovered_contact": 1e-3,
    "contact_area": 0.5,
}
#: The body regions each garment kind does not cover (``geometry.regions.REGIONS``).
UNCOVERED = {kind: ("arms", "head") for kind in ("gilet", "dress", "stocking")}
#: Which side of the bound is good: the contact area ratio must be at least its limit.
AT_LEAST = ("contact_area",)


@dataclass(frozen=True)
class Check:
    name: str
    value: float | None  # None: not applicable
    limit: float
    what: str

    @property
    def ok(self) -> bool:
        if self.value is None:
            return True
        if math.isnan(self.value):
            return False
        return self.value >= self.limit if self.name in AT_LEAST else self.value <= self.limit

    def as_dict(self) -> dict:
        v = self.value
        return {**asdict(self), "value": None if v is None or math.isnan(v) else v, "ok": self.ok}

    def warning(self) -> str:
        side = "below" if self.name in AT_LEAST else "above"
        shown = "NaN" if self.value is None or math.isnan(self.value) else f"{self.value:.3g}"
        return f"WARNING: check {self.name!r} failed: {self.what} = {shown}, {side} {self.limit:g}"


def tight_area(built) -> float:
    """Reference area [m²] of the contact points of the undeformed pattern inside the unshrunk
    body (collective). Call before the dressing moves the garment (q = 0)."""
    st = built.contact.state
    saved = float(st.shrink.value)
    st.shrink.value = 0.0
    st.refresh()
    g = st.local_values(st.gap)
    a = cpressure.point_areas(st, ufl.as_ufl(1.0))
    st.shrink.value = saved
    st.refresh()
    return st.mesh.comm.allreduce(float(a[g < 0].sum()), op=MPI.SUM)


def forces(built) -> tuple[np.ndarray, np.ndarray]:
    """(applied dead load, body reaction) as 3-vectors [N] (collective)."""
    model, c = built.model, built.contact
    mesh = model.geometry.mesh
    e = dolfinx.fem.Constant(mesh, np.zeros(3))
    reaction = dolfinx.fem.form(-c.residual(e))
    applied = None
    if built.gravity is not None:
        w = model.load_factor * model.C.mass_per_area * ufl.dot(built.gravity, e) * model.dx_full
        applied = dolfinx.fem.form(w)
    out = np.zeros((2, 3))
    for k in range(3):
        e.value[:] = np.eye(3)[k]
        for j, form in enumerate((applied, reaction)):
            if form is not None:
                out[j, k] = mesh.comm.allreduce(dolfinx.fem.assemble_scalar(form), op=MPI.SUM)
    return out[0], out[1]


def _ratio(num: float, den: float) -> float:
    if den > 0:
        return num / den
    return 0.0 if num == 0 else math.inf


def uncovered_force(kind: str, rows: list[dict]) -> float | None:
    """Contact force on the regions ``kind`` does not cover over the whole contact force, from
    the region table ``rows`` (``output.region_table``); None when not applicable."""
    names = {r["region"] for r in rows}
    skipped = [n for n in UNCOVERED.get(kind, ()) if n in names]
    if not skipped:
        return None
    total = sum(r["force_N"] for r in rows)
    return _ratio(sum(r["force_N"] for r in rows if r["region"] in skipped), total)


def result_checks(
    built, measures: dict, spring_traction: float, tight: float, applied_reaction,
    regions: list[dict] | None = None,
) -> list[Check]:  # fmt: skip
    """The checks of the module doc on the final state.

    ``measures``: the run's contact measures (``max_penetration_m``, ``max_pressure_kPa``,
    ``contact_area_garment_m2``, ``contact_force_N``); ``tight``: :func:`tight_area` of the
    pattern; ``applied_reaction``: :func:`forces`; ``regions``: the region table.
    """
    thickness = _thickness(built)
    p_max = measures["max_pressure_kPa"] * 1e3
    applied, reaction = applied_reaction
    scale = max(np.linalg.norm(applied), np.linalg.norm(reaction), measures["contact_force_N"])
    imbalance = _ratio(float(np.linalg.norm(applied + reaction)), scale)
    area = measures["contact_area_garment_m2"]
    physics = built.scene.physics
    al_tol = (
        physics.tolerance * built.model.stiffness.thickness
        if physics.contact == "augmented-lagrangian"
        else 0.0
    )
    return [
        Check("penetration", measures["max_penetration_m"] / thickness, LIMITS["penetration"],
              "deepest penetration into the body / fabric thickness"),
        Check("spring", _ratio(spring_traction, p_max), LIMITS["spring"],
              "stabilising spring traction / largest contact pressure"),
        Check("force_balance", imbalance, LIMITS["force_balance"],
              "|applied load + body reaction| / the larger force"),
        Check("multiplier_penetration",
              measures["max_penetration_m"] / al_tol if al_tol > 0 else None,
              LIMITS["multiplier_penetration"],
              "deepest penetration / the augmented Lagrangian's tolerance"),
        Check("uncovered_contact",
              uncovered_force(built.scene.garment.kind, regions or []),
              LIMITS["uncovered_contact"],
              "contact force on arms and head / the whole contact force"),
        Check("contact_area", area / tight if tight > 0 else None, LIMITS["contact_area"],
              "contact area / area of the pattern that started inside the body"),
    ]  # fmt: skip


def _thickness(built) -> float:
    from fenics_garment.scene.build import make_fabric

    return make_fabric(built.scene).thickness
