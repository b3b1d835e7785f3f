"""Body regions from landmark heights: the same rule for the mannequin and for scans.

A triangle's region follows from the height of its centroid (bands between landmark levels,
split half-way between neighbouring levels) and, on the torso, from whether it lies in front of
or behind the body's centre (anterior = −y). Pressure is reported per region later, so every
region of a full body is non-empty; a body cropped to a band only carries the regions in it.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

REGIONS: dict[str, int] = {
    "neck": 1,
    "shoulders": 2,
    "upper_chest": 3,
    "bust": 4,
    "underbust": 5,
    "upper_back": 6,
    "waist": 7,
    "abdomen": 8,
    "lower_back": 9,
    "hips": 10,
    "buttocks": 11,
    "thighs": 12,
    "knees": 13,
    "calves": 14,
    "ankles": 15,
    "arms": 16,
    "head": 17,
}


def tag_regions(
    vertices: npt.NDArray[np.float64],
    triangles: npt.NDArray[np.int64],
    landmarks: dict[str, float],
    centre_y: dict[str, float] | None = None,
    part: npt.NDArray[np.int32] | None = None,
) -> npt.NDArray[np.int32]:
    """Region number (see :data:`REGIONS`) of each triangle.

    ``landmarks`` maps level names (``neck_base``, ``shoulder``, ``upper_chest``, ``bust``,
    ``underbust``, ``waist``, ``abdomen``, ``hip``, ``crotch``, ``thigh``, ``knee``, ``calf``,
    ``ankle``) to heights in metres; ``centre_y`` gives the y of the torso centre at the levels
    (default 0) to split front from back. ``part`` (:data:`~.anatomy.PARTS` per triangle, from
    the segmentation of a scan) puts arms and head in their own regions and keeps the torso
    bands on the torso and the leg bands on the legs.
    """
    L = landmarks
    c = vertices[triangles].mean(axis=1)
    z, y, x = c[:, 2], c[:, 1], c[:, 0]
    lv = [k for k in ("crotch", "hip", "abdomen", "waist", "underbust", "bust", "upper_chest")]
    cy = np.zeros_like(z)
    if centre_y:
        zs = np.array([L[k] for k in lv if k in centre_y])
        ys = np.array([centre_y[k] for k in lv if k in centre_y])
        if len(zs):
            cy = np.interp(z, zs, ys)
    back = y > cy

    def mid(a: str, b: str) -> float:
        return 0.5 * (L[a] + L[b])

    r = np.zeros(len(z), dtype=np.int32)
    R = REGIONS
    sel = z >= L["neck_base"]
    r[sel] = R["neck"]
    band = (z >= mid("upper_chest", "shoulder")) & ~sel
    r[band] = R["shoulders"]
    upper = (z >= mid("waist", "underbust")) & (z < mid("upper_chest", "shoulder"))
    r[upper & back] = R["upper_back"]
    front = upper & ~back
    r[front & (z >= mid("bust", "upper_chest"))] = R["upper_chest"]
    r[front & (z >= mid("underbust", "bust")) & (z < mid("bust", "upper_chest"))] = R["bust"]
    r[front & (z < mid("underbust", "bust"))] = R["underbust"]
    r[(z >= mid("abdomen", "waist")) & (z < mid("waist", "underbust"))] = R["waist"]
    belly = (z >= mid("hip", "abdomen")) & (z < mid("abdomen", "waist"))
    r[belly & ~back] = R["abdomen"]
    r[belly & back] = R["lower_back"]
    pelvis = (z >= L["crotch"]) & (z < mid("hip", "abdomen"))
    # buttocks: the back sector within 60° of +y, the rest of the pelvis band is "hips"
    ang = np.arctan2(y - cy, np.abs(x))
    r[pelvis] = R["hips"]
    r[pelvis & (ang > np.radians(30.0))] = R["buttocks"]
    if "thigh" in L:
        r[(z < L["crotch"]) & (z >= mid("thigh", "knee"))] = R["thighs"]
        r[(z < mid("thigh", "knee")) & (z >= mid("knee", "calf"))] = R["knees"]
        r[(z < mid("knee", "calf")) & (z >= mid("calf", "ankle"))] = R["calves"]
        r[z < mid("calf", "ankle")] = R["ankles"]
    else:
        r[z < L["crotch"]] = R["thighs"]
    if part is not None:
        from .anatomy import PARTS

        r[part == PARTS["head"]] = R["head"]
        r[(part == PARTS["arm_left"]) | (part == PARTS["arm_right"])] = R["arms"]
    return r
