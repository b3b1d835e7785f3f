"""Posing hm08's arms by linear blend skinning with MPFB2's game-engine rig (CC0).

The rig data (``meshes/makehuman/rig/arms.json.xz``; provenance in ``meshes/makehuman/README.md``)
are the arm chains of MPFB2's ``rigs/standard/rig.game_engine.json`` — each clavicle and every
bone below it (upper arm, forearm, hand, fingers) — with their vertex weights from
``weights.game_engine.json`` and the rotations the arm chains get in MPFB2's
``poses/game_engine_fk/t-pose.json``. The rig is read here from its file format, not from MPFB2's
code:

* a bone's head and tail are the centres of two of hm08's joint cubes (the "CUBE" strategy:
  the mean of the cube's vertices), so they follow the morphed body; positions are in
  Blender's frame (metres, Z up, facing −y): (x, −z, y) / 10 of MakeHuman's decimetres, Y up;
* a bone's rest frame is Blender's: its Y axis along head → tail, turned from the world Y axis
  by the least rotation, then rolled about itself by the bone's ``roll``;
* a pose rotation is an Euler XYZ triple in radians in the bone's own rest frame (the matrix
  Rz · Ry · Rx), applied after the parent's pose: posed(b) = posed(parent) · rest(parent)⁻¹ ·
  rest(b) · R(b); a bone without a rotation follows its parent rigidly;
* a vertex moves by the weighted sum of posed(b) · rest(b)⁻¹ over its bones (weights sum to 1
  in the file, to within 1e-4); the weight that is not on an arm chain stays in place (the
  clavicles' parent, the spine, is not posed).

Checked against independent references (``tests/test_rig.py``): the rig's own default joint
positions are the cube centres of MakeHuman's default body to 2e-7 m, and the T-pose brings
the upper arms of every build to within 2° of horizontal, mirror-symmetric.
"""

from __future__ import annotations

import json
import lzma
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]

RIG = Path(__file__).resolve().parents[2] / "meshes" / "makehuman" / "rig" / "arms.json.xz"
#: MakeHuman's frame (decimetres, Y up, facing +z) to the rig's (Blender: metres, Z up, facing
#: −y), as MPFB2 loads the base mesh (checked: ``tests/test_rig.py``)
TO_RIG = 0.1 * np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
#: the poses a body can take: "A" is MakeHuman's rest pose (no skinning)
POSES = ("A", "T")


@dataclass(frozen=True)
class Bone:
    """One bone of the rig: its parent's name, the joint cubes of its head and tail, its roll."""

    name: str
    parent: str
    head: str
    tail: str
    roll: float


@dataclass(frozen=True)
class Rig:
    """The arm chains: bones (parents before children), weights (vertex numbers, weights) and
    the poses' rotations (Euler XYZ, radians, per bone)."""

    bones: tuple[Bone, ...]
    weights: dict[str, tuple[npt.NDArray[np.int64], Array]]
    poses: dict[str, dict[str, Array]]


@cache
def load(path: Path = RIG) -> Rig:
    """The vendored rig data (see the module docstring)."""
    d = json.loads(lzma.decompress(path.read_bytes()))
    bones = tuple(Bone(b["name"], b["parent"], b["head"], b["tail"], b["roll"])
                  for b in d["bones"])  # fmt: skip
    weights = {k: (np.array(w["vertices"], dtype=np.int64), np.array(w["weights"]))
               for k, w in d["weights"].items()}  # fmt: skip
    poses = {p: {k: np.array(r) for k, r in rot.items()} for p, rot in d["poses"].items()}
    return Rig(bones, weights, poses)


def rotation(axis: Array, angle: float) -> Array:
    """The rotation by ``angle`` (radians) about ``axis`` (Rodrigues' formula)."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)


def euler_xyz(angles: Array) -> Array:
    """Blender's Euler XYZ rotation: about X first, then Y, then Z (Rz · Ry · Rx)."""
    x, y, z = angles
    return rotation([0, 0, 1], z) @ rotation([0, 1, 0], y) @ rotation([1, 0, 0], x)


def bone_frame(head: Array, tail: Array, roll: float) -> Array:
    """A bone's rest frame (4×4, rig frame): Y along head → tail, reached from the world Y axis
    by the least rotation, then rolled by ``roll`` about itself; origin at the head."""
    n = (tail - head) / np.linalg.norm(tail - head)
    axis = np.cross([0.0, 1.0, 0.0], n)
    s = float(np.linalg.norm(axis))
    if s > 1e-9:
        align = rotation(axis, float(np.arctan2(s, n[1])))
    else:  # along ±Y: no rotation, or a half turn about Z
        align = np.eye(3) if n[1] > 0 else np.diag([-1.0, -1.0, 1.0])
    m = np.eye(4)
    m[:3, :3] = align @ rotation([0, 1, 0], roll)
    m[:3, 3] = head
    return m


def rest_frames(rig: Rig, centre: Callable[[str], Array]) -> dict[str, Array]:
    """Every bone's rest frame on a body whose joint cube ``name`` is centred at
    ``centre(name)`` (MakeHuman's frame, decimetres)."""
    return {b.name: bone_frame(TO_RIG @ centre(b.head), TO_RIG @ centre(b.tail), b.roll)
            for b in rig.bones}  # fmt: skip


def posed_frames(rig: Rig, rest: dict[str, Array], rotations: dict[str, Array]) -> dict[str, Array]:
    """Every bone's posed frame (4×4): its parent's pose carried over, then its own rotation."""
    posed: dict[str, Array] = {}
    for b in rig.bones:  # parents come first
        local = np.eye(4)
        local[:3, :3] = euler_xyz(rotations.get(b.name, np.zeros(3)))
        above = posed[b.parent] @ np.linalg.inv(rest[b.parent]) if b.parent in posed else np.eye(4)
        posed[b.name] = above @ rest[b.name] @ local
    return posed


def skin(v: Array, rig: Rig, rest: dict[str, Array], posed: dict[str, Array]) -> Array:
    """Linear blend skinning of ``v`` (rig frame): each vertex moved by its bones' posed · rest⁻¹
    in proportion to its weights; the rest of its weight leaves it in place."""
    out = v.copy()
    for name, (idx, w) in rig.weights.items():
        m = posed[name] @ np.linalg.inv(rest[name])
        moved = v[idx] @ m[:3, :3].T + m[:3, 3]
        out[idx] += w[:, None] * (moved - v[idx])
    return out


def pose_vertices(v_dm: Array, centre: Callable[[str], Array], pose: str) -> Array:
    """hm08's vertices ``v_dm`` (MakeHuman's frame, decimetres) in ``pose`` (one of
    :data:`POSES`), the joints at ``centre(cube name)`` of the same body."""
    if pose not in POSES:
        raise ValueError(f"pose {pose!r}: one of {POSES}")
    if pose == "A":
        return v_dm
    rig = load()
    rest = rest_frames(rig, centre)
    posed = posed_frames(rig, rest, rig.poses[pose])
    return skin(v_dm @ TO_RIG.T, rig, rest, posed) @ np.linalg.inv(TO_RIG).T
