"""Virtual pressure sensors at named anatomical points (issue 47, item 5).

An experiment reads clothing pressure with a sensor taped to the skin at a named anatomical
point, not as a percentile over a region. A virtual sensor here is a round pad of an
instrument's diameter (:data:`INSTRUMENTS`: AMI Techno's air-pack sensors, 20 mm, the default;
Picopress, 50 mm) centred at a point of the body's surface placed from its landmarks
(:func:`place`), and it reads

    reading = Σ f_j / Σ a_j

over the garment's contact points j within the pad's radius of its centre (f_j the contact
force [N], a_j the deformed garment area [m²] the point carries; :func:`read`): the contact
force on the pad divided by the area over it. With the pad covered (``cover`` ≈ 1,
:func:`_cover`) that is the force on the pad over the pad's area; a pad the garment
covers only in part (the garment does not reach past its rim all round, beside a hem or an
armhole: :func:`_cover`) is reported with ``covered = false``: its reading is the mean over
the covered part.

Placement (the body stands with +z up, faces −y, its left at +x; heights are the body's
landmark levels, :mod:`fenics_garment.geometry.anatomy`), on the torso outline of the
horizontal section at that level (the section's points lie on the body's surface):

* ``bust_left`` / ``bust_right``: the bust point, the most forward point of the bust section
  between 10 % and 45 % of its width either side of its middle (as the anatomy's bust search);
* ``underbust_front``, ``waist_front``, ``abdomen``: the front of the section (smallest y) at its
  middle x;
* ``waist_back``: the back (largest y) at its middle x;
* ``underbust_side``, ``waist_side``, ``hip``: the left side (largest x) at the y of the
  section's area centroid (the hip sensor on the side, over the greater trochanter);
* ``scapula``: the back of the upper-chest section half-way from the middle to the left arm
  root (the arm cut, or the section's left edge on a body without arms);
* ``shoulder``: the top of the left shoulder, the highest surface point on the vertical line
  half-way between the neck (the neck-base section's left edge) and the shoulder point (the
  arm cut, or the shoulder section's left edge), at the y of the shoulder section's centroid.

Only a mannequin, human or scan has these landmarks; a cylinder or an arm has none, and
:func:`place` raises :class:`NoLandmarks` (the run reports ``sensors_skipped`` with its
reason instead of a table). A sensor whose level or section is missing is left out, with its
reason in :attr:`Placement.missing`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from . import units
from .geometry import anatomy

Array = npt.NDArray[np.float64]

#: Pressure-sensor instruments: name -> pad diameter [m].
INSTRUMENTS: dict[str, float] = {"ami": 0.020, "picopress": 0.050}
DEFAULT_INSTRUMENT = "ami"

#: The sensors: name -> (landmark level, placement rule of :func:`_site`).
SITES: dict[str, tuple[str, str]] = {
    "bust_left": ("bust", "bust_left"),
    "bust_right": ("bust", "bust_right"),
    "underbust_front": ("underbust", "front"),
    "underbust_side": ("underbust", "side"),
    "waist_front": ("waist", "front"),
    "waist_side": ("waist", "side"),
    "waist_back": ("waist", "back"),
    "shoulder": ("shoulder", "shoulder"),
    "scapula": ("upper_chest", "scapula"),
    "abdomen": ("abdomen", "front"),
    "hip": ("hip", "side"),
}


class NoLandmarks(ValueError):
    """The body has no anatomical landmarks (a cylinder or an arm): no sensors can be placed."""


@dataclass
class Placement:
    """Sensor centres on the body's surface (name -> (3,) point [m]) and the sensors left out."""

    centres: dict[str, Array]
    missing: dict[str, str] = field(default_factory=dict)  # name -> why


def _crossings(poly: Array, axis: int, value: float) -> Array:
    """The other coordinate where the closed polygon crosses the line coord[axis] = value."""
    a, b = poly, np.roll(poly, -1, axis=0)
    s, e = a[:, axis] - value, b[:, axis] - value
    hit = (s * e <= 0) & (s != e)
    t = s[hit] / (s[hit] - e[hit])
    o = 1 - axis
    return a[hit, o] + t * (b[hit, o] - a[hit, o])


def _centroid(poly: Array) -> Array:
    x, y = poly[:, 0], poly[:, 1]
    cross = x * np.roll(y, -1) - np.roll(x, -1) * y
    a = 0.5 * cross.sum()
    cx = ((x + np.roll(x, -1)) * cross).sum()
    cy = ((y + np.roll(y, -1)) * cross).sum()
    return np.array([cx, cy]) / (6.0 * a)


def _outline(v: Array, t: npt.NDArray[np.int64], z: float) -> Array | None:
    o = anatomy.torso_outline(v, t, z)
    return None if o is None else o.points


def _site(body, rule: str, z: float) -> Array | str:
    """The sensor centre of ``rule`` at height ``z``, or why there is none."""
    v, t = body.vertices, body.triangles
    p = _outline(v, t, z)
    if p is None:
        return f"no torso section at z = {z:.3f} m"
    xc = 0.5 * (p[:, 0].max() + p[:, 0].min())
    w = float(np.ptp(p[:, 0]))
    if rule in ("bust_left", "bust_right"):
        side = 1.0 if rule == "bust_left" else -1.0
        d = side * (p[:, 0] - xc)
        sel = (d >= 0.1 * w) & (d <= anatomy.BUST_REGION * w) & (p[:, 1] < p[:, 1].mean())
        if not sel.any():
            return "no front of the bust section"
        k = np.flatnonzero(sel)[np.argmin(p[sel, 1])]
        return np.array([p[k, 0], p[k, 1], z])
    if rule in ("front", "back"):
        ys = _crossings(p, 0, xc)
        y = ys.min() if rule == "front" else ys.max()
        return np.array([xc, y, z])
    if rule == "side":
        yc = _centroid(p)[1]
        return np.array([_crossings(p, 1, yc).max(), yc, z])
    arm = body.arm_cut.get("left")
    if rule == "scapula":
        edge = arm if arm is not None else float(p[:, 0].max())
        x0 = xc + 0.5 * (edge - xc)
        return np.array([x0, _crossings(p, 0, x0).max(), z])
    if rule == "shoulder":
        z_neck = body.landmarks.get("neck_base")
        pn = None if z_neck is None else _outline(v, t, z_neck)
        if pn is None:
            return "no neck-base section"
        edge = arm if arm is not None else float(p[:, 0].max())
        x0 = 0.5 * (float(pn[:, 0].max()) + edge)
        y0 = float(_centroid(p)[1])
        top = anatomy._surface_top(v, t, x0, y0)
        if top is None:
            return "no shoulder surface above the mid-shoulder"
        return np.array([x0, y0, top])
    raise ValueError(f"unknown sensor placement rule {rule!r}")


def place(body) -> Placement:
    """The sensor centres of :data:`SITES` on ``body`` (a :class:`~.geometry.body.BodySurface`);
    :class:`NoLandmarks` on a body without the torso's landmarks (a cylinder, an arm)."""
    marks = body.landmarks or {}
    if not any(level in marks for level, _ in SITES.values()):
        raise NoLandmarks(
            "the body has no anatomical landmarks (a cylinder or an arm): sensors are placed "
            "only on a mannequin, human or scan"
        )
    centres: dict[str, Array] = {}
    missing: dict[str, str] = {}
    for name, (level, rule) in SITES.items():
        if level not in marks:
            missing[name] = f"the body has no {level} level"
            continue
        got = _site(body, rule, float(marks[level]))
        if isinstance(got, str):
            missing[name] = got
        else:
            centres[name] = got
    return Placement(centres, missing)


def diameter_of(instrument: str) -> float:
    """The pad diameter [m] of a named instrument (:data:`INSTRUMENTS`)."""
    if instrument not in INSTRUMENTS:
        raise ValueError(f"unknown sensor instrument {instrument!r}; one of {sorted(INSTRUMENTS)}")
    return INSTRUMENTS[instrument]


def pad(output) -> tuple[str, float]:
    """The scene's pressure sensor, (name, pad diameter [m]), from its ``[output]``
    ``sensor_instrument`` and ``sensor_diameter`` (0: the instrument's own; another diameter
    makes a pad of that size, named "<instrument>, <d> mm pad"): the one sensor of the regions'
    sensor p95 and of the sensors at anatomical points."""
    d = diameter_of(output.sensor_instrument)
    if output.sensor_diameter in (0.0, d):
        return output.sensor_instrument, d
    return (
        f"{output.sensor_instrument}, {output.sensor_diameter * 1e3:g} mm pad",
        output.sensor_diameter,
    )


def read(
    centres: dict[str, Array], x: Array, force: Array, area: Array, diameter: float,
    instrument: str = "",
) -> list[dict]:  # fmt: skip
    """The table of the sensors at ``centres``: for each, Σ f_j / Σ a_j over the garment points
    j (positions ``x``, contact forces ``force`` [N], deformed areas ``area`` [m²]) within
    ``diameter``/2 of the centre (module doc), in kPa and mmHg, with the number of ``points``
    on the pad, its ``cover`` and ``covered`` (:func:`_cover`)."""
    from scipy.spatial import cKDTree

    r = 0.5 * diameter
    names = list(centres)
    rows: list[dict] = []
    if not names:
        return rows
    c = np.array([centres[n] for n in names])
    tree = cKDTree(x) if len(x) else None
    for name, ci in zip(names, c, strict=True):
        j = tree.query_ball_point(ci, r) if tree is not None else []
        f, a = float(np.sum(force[j])), float(np.sum(area[j]))
        p = f / a if a > 0 else 0.0
        rows.append({
            "sensor": name, "x_m": float(ci[0]), "y_m": float(ci[1]), "z_m": float(ci[2]),
            "instrument": instrument, "diameter_m": diameter,
            "reading_kPa": units.pa_to_kpa(p), "reading_mmHg": units.pa_to_mmhg(p),
            "force_N": f, "points": len(j),
        })  # fmt: skip
        rows[-1].update(_cover(tree, ci, r))
    return rows


#: The garment points that set the reach past a pad's rim (:func:`_cover`).
NEIGHBOURS = 32
#: Angular sectors round a pad in which the garment must reach past its rim (:func:`_cover`).
SECTORS = 8


def _cover(tree, centre: Array, r: float) -> dict:
    """How far the garment surrounds a pad of radius ``r``: ``cover`` is the share of
    :data:`SECTORS` equal angular sectors round the centre (in the plane of the garment's
    points nearby, their two principal directions) holding a garment point within ρ = r + s,
    s the distance to the centre's :data:`NEIGHBOURS`-th nearest garment point (a couple of
    garment cells: the contact points come in clusters, several at one place on the tube);
    ``covered`` when every sector does (the garment reaches past the pad's rim all round).

    The area share Σ a_j / (π r²) was tried and dropped: a pad of a couple of garment cells
    holds 2 to 14 contact points, whose areas made it scatter from 0.35 to 1.40 on the fully
    covered Laplace tube (2–4 cm cells, 20 mm pad); with 16 neighbours a pad there missed a
    sector at 4 cm cells."""
    if tree is None:
        return {"cover": 0.0, "covered": False}
    dist, _ = tree.query(centre, k=min(NEIGHBOURS, tree.n))
    rho = r + float(np.max(dist))
    j = tree.query_ball_point(centre, rho)
    if len(j) < 3:
        return {"cover": 0.0, "covered": False}
    d = tree.data[j] - centre
    q = tree.data[j] - tree.data[j].mean(axis=0)
    _, _, vt = np.linalg.svd(q, full_matrices=False)
    ang = np.arctan2(d @ vt[1], d @ vt[0])
    k = np.floor((ang + np.pi) / (2 * np.pi) * SECTORS).astype(int) % SECTORS
    cover = len(np.unique(k)) / SECTORS
    return {"cover": cover, "covered": bool(cover == 1.0)}
