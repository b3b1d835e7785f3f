"""A population of human bodies from MakeHuman's CC0 macro targets, exported as scanners would.

MakeHuman (CC0 assets, ``meshes/makehuman/README.md``) shapes its base mesh hm08 with *macro
targets*: per-vertex displacements for the corners of a grid of macro variables, blended with
weights that are products of one-dimensional hat functions of the slider values:

* gender ``g`` ∈ [0, 1] (0 female, 1 male): female = 1 − g, male = g;
* age ``a`` ∈ [0, 1], piecewise linear in years (1 y at 0, 25 y at 0.5, 90 y at 1): baby, child,
  young, old are hats with nodes at 0, 0.1875 (10 y), 0.5 and 1;
* muscle, weight, height, proportions, breast size (cup) and firmness ∈ [0, 1]: a low corner
  weighting max(0, 1 − 2 v), a high corner max(0, 2 v − 1) and the average corner the rest
  (muscle, weight: 1 − low − high; height, proportions, cup, firmness: 1 − max(low, high));
* ethnicity: three weights that sum to one (african, asian, caucasian).

A target's weight is the product of the weights of the corners named in its file name, e.g.
``height/female-young-maxmuscle-averageweight-maxheight`` has the weight
female · young · maxmuscle · averageweight · maxheight. The target families are

* ``macrodetails/<ethnic>-<gender>-<age>`` (the ethnic and sexual shape),
* ``macrodetails/universal-<gender>-<age>-<muscle>-<weight>`` (build),
* ``macrodetails/height/<gender>-<age>-<muscle>-<weight>-<min|max>height``,
* ``macrodetails/proportions/<gender>-<age>-<muscle>-<weight>-<ideal|uncommon>proportions``,
* ``breast/female-<age>-<muscle>-<weight>-<cup>-<firmness>`` (no file for average cup and
  average firmness together: that is the unmorphed breast).

This module implements that scheme from its description (it reads the targets, not MakeHuman's
code). The targets are vendored in ``meshes/makehuman/targets/macro.npz.xz``: the young, old and
child corners (no baby), dense over the 19,158 vertices of hm08, in MakeHuman's own storage
unit (int16, 1e-3 of the base mesh's decimetre).

:func:`population` is a set of bodies spanning every macro variable to its extremes, all in
MakeHuman's rest A-pose but four T-posed copies (:attr:`Body.pose`, :func:`posed_vertices`: the
arms raised by MPFB2's CC0 game-engine rig, :mod:`.rig`);
:func:`export` writes one as a scanner or body tool would: STL (binary or ascii), PLY (binary or
ascii), OBJ (quads, with the eyes, as MakeHuman exports) or GLB, in mm, cm, m or inches, with
any coordinate axis up.
"""

from __future__ import annotations

import gzip
import io
import itertools
import lzma
from dataclasses import asdict, dataclass, field
from functools import cache
from pathlib import Path

import numpy as np
import numpy.typing as npt

from . import rig
from .orientation import ROTATIONS, UNITS

Array = npt.NDArray[np.float64]

MAKEHUMAN = Path(__file__).resolve().parents[2] / "meshes" / "makehuman"
BASE = MAKEHUMAN / "base.obj.gz"
TARGETS = MAKEHUMAN / "targets" / "macro.npz.xz"
#: MakeHuman's storage unit of a target displacement, in the base mesh's decimetres
TARGET_UNIT = 1e-3
#: the groups of the base mesh an OBJ export keeps besides the body (MakeHuman's export of a
#: human without clothes: the body and its eyes, no helper geometry or joint cubes)
OBJ_EXTRA_GROUPS = ("helper-l-eye", "helper-r-eye")
FORMATS = ("stl", "stl-ascii", "ply", "ply-ascii", "obj", "glb")
SUFFIX = {"stl": ".stl", "stl-ascii": ".stl", "ply": ".ply", "ply-ascii": ".ply", "obj": ".obj",
          "glb": ".glb"}  # fmt: skip
ETHNIC = ("african", "asian", "caucasian")
AGES = ("baby", "child", "young", "old")
#: MakeHuman's age slider: (slider value, years) of its nodes
AGE_NODES = ((0.0, 1.0), (0.5, 25.0), (1.0, 90.0))


@dataclass(frozen=True)
class Macro:
    """MakeHuman's macro sliders (0.5: MakeHuman's default; ethnic: weights, normalised)."""

    gender: float = 0.5  # 0 female, 1 male
    age: float = 0.5  # 0: 1 year, 0.5: 25 years, 1: 90 years
    muscle: float = 0.5
    weight: float = 0.5
    height: float = 0.5
    proportions: float = 0.5  # 0 uncommon, 1 ideal
    cup: float = 0.5  # breast size
    firmness: float = 0.5
    ethnic: tuple[float, float, float] = (1 / 3, 1 / 3, 1 / 3)  # african, asian, caucasian

    def __post_init__(self) -> None:
        for k, v in asdict(self).items():
            if k != "ethnic" and not 0.0 <= v <= 1.0:
                raise ValueError(f"{k} = {v}: a macro slider is in [0, 1]")
        if min(self.ethnic) < 0 or sum(self.ethnic) <= 0:
            raise ValueError(f"ethnic weights {self.ethnic}: non-negative, not all zero")

    @property
    def age_years(self) -> float:
        return float(np.interp(self.age, *zip(*AGE_NODES, strict=True)))

    @staticmethod
    def age_of(years: float) -> float:
        """The age slider for ``years`` (1–90)."""
        s, y = zip(*AGE_NODES, strict=True)
        return float(np.interp(years, y, s))


def _three(v: float, names: tuple[str, str, str], peak_average: bool) -> dict[str, float]:
    """Low, average, high corner weights of a slider ``v`` (MakeHuman's hats, see module doc)."""
    lo, hi = max(0.0, 1.0 - 2.0 * v), max(0.0, 2.0 * v - 1.0)
    mid = 1.0 - max(lo, hi) if peak_average else 1.0 - lo - hi
    return dict(zip(names, (lo, mid, hi), strict=True))


def corner_weights(m: Macro) -> dict[str, float]:
    """The weight of every corner name of the macro grid (``female``, ``young``, ``maxcup`` …)."""
    w: dict[str, float] = {"female": 1.0 - m.gender, "male": m.gender}
    knee = Macro.age_of(10.0)  # the child node: 10 years, 0.1875
    a = m.age
    young = max(0.0, (a - knee) / (0.5 - knee)) if a < 0.5 else 2.0 - 2.0 * a
    w |= {"baby": max(0.0, 1.0 - a / knee) if a < 0.5 else 0.0,
          "child": max(0.0, min(1.0, a / knee) - young) if a < 0.5 else 0.0,
          "young": young, "old": max(0.0, 2.0 * a - 1.0)}  # fmt: skip
    w |= _three(m.muscle, ("minmuscle", "averagemuscle", "maxmuscle"), False)
    w |= _three(m.weight, ("minweight", "averageweight", "maxweight"), False)
    w |= _three(m.height, ("minheight", "averageheight", "maxheight"), True)
    w |= _three(m.proportions, ("uncommonproportions", "regularproportions", "idealproportions"),
                True)  # fmt: skip
    w |= _three(m.cup, ("mincup", "averagecup", "maxcup"), True)
    w |= _three(m.firmness, ("minfirmness", "averagefirmness", "maxfirmness"), True)
    total = sum(m.ethnic)
    w |= {e: x / total for e, x in zip(ETHNIC, m.ethnic, strict=True)}
    return w


def target_weights(m: Macro, names: list[str] | None = None) -> dict[str, float]:
    """Weight of each target of ``names`` (default: the vendored ones) for the sliders ``m``;
    targets of weight zero are left out."""
    w = corner_weights(m) | {"universal": 1.0}
    out = {}
    for name in names if names is not None else list(_targets()):
        k = float(np.prod([w[c] for c in name.rsplit("/", 1)[-1].split("-")]))
        if k != 0.0:
            out[name] = k
    return out


@cache
def _targets() -> dict[str, npt.NDArray[np.int16]]:
    with np.load(io.BytesIO(lzma.decompress(TARGETS.read_bytes()))) as z:
        return {k: z[k] for k in z.files}


@dataclass
class BaseMesh:
    """hm08 as written in its OBJ: positions (decimetres, Y up, facing +z) and faces per group."""

    vertices: Array
    groups: dict[str, list[list[int]]] = field(default_factory=dict)

    def faces(self, groups: tuple[str, ...] = ("body",)) -> list[list[int]]:
        return [f for g in groups for f in self.groups.get(g, [])]


@cache
def base_mesh() -> BaseMesh:
    verts, groups, cur = [], {}, ""
    for line in gzip.decompress(BASE.read_bytes()).decode().splitlines():
        if line.startswith("v "):
            verts.append([float(w) for w in line.split()[1:4]])
        elif line.startswith("g "):
            cur = line.split()[1]
        elif line.startswith("f "):
            groups.setdefault(cur, []).append([int(w.split("/")[0]) - 1 for w in line.split()[1:]])
    return BaseMesh(np.array(verts), groups)


def body_vertices(m: Macro) -> Array:
    """All 19,158 vertices of hm08 shaped by the sliders (decimetres, Y up, facing +z)."""
    v = base_mesh().vertices.copy()
    t = _targets()
    for name, k in target_weights(m).items():
        v += (k * TARGET_UNIT) * t[name]
    return v


def joint_centre(v_dm: Array, cube: str) -> Array:
    """The centre of hm08's joint cube ``cube`` (the mean of its vertices) on the body ``v_dm``."""
    return v_dm[np.unique(np.concatenate(base_mesh().groups[cube]))].mean(axis=0)


def posed_vertices(m: Macro, pose: str = "A") -> Array:
    """:func:`body_vertices` in ``pose``: "A" MakeHuman's rest pose, "T" the arms raised to
    the horizontal by MPFB2's game-engine rig (:mod:`.rig`; the legs keep the rest stance)."""
    v = body_vertices(m)
    return rig.pose_vertices(v, lambda cube: joint_centre(v, cube), pose)


def to_package_frame(v_dm: Array) -> Array:
    """MakeHuman's frame (dm, Y up, facing +z) to the package's (m, Z up, facing −y)."""
    return 0.1 * v_dm @ ROTATIONS["y"].T


@dataclass(frozen=True)
class Body:
    """One body of the population and how it is exported."""

    name: str
    macro: Macro
    fmt: str = "stl"
    units: str = "mm"
    up: str = "z"
    #: the body turned about its vertical by this many degrees (counter-clockwise seen from
    #: above) before the up axis is laid: 0 faces −y with Z up and +z with Y up; 90 faces +x
    turn: int = 0
    #: "A": MakeHuman's rest pose; "T": the arms raised to the horizontal (:mod:`.rig`)
    pose: str = "A"

    @property
    def vertices(self) -> Array:
        """All of hm08's vertices of this body in its pose (MakeHuman's frame, decimetres)."""
        return posed_vertices(self.macro, self.pose)

    @property
    def file_name(self) -> str:
        return f"{self.name}{SUFFIX[self.fmt]}"

    def as_dict(self) -> dict:
        d = asdict(self)
        d["macro"]["ethnic"] = list(self.macro.ethnic)
        d["age_years"] = round(self.macro.age_years, 1)
        return d


def _designs() -> list[tuple[str, Macro]]:
    """(name, sliders): MakeHuman's defaults, every slider alone at both extremes for a woman and
    a man, and combined extremes."""
    F, M = Macro(gender=0.0), Macro(gender=1.0)
    out: list[tuple[str, Macro]] = [("neutral", Macro()), ("female", F), ("male", M)]
    teen, old = Macro.age_of(15.0), 1.0
    alone = {"teen": {"age": teen}, "old": {"age": old}, "thin": {"weight": 0.0},
             "heavy": {"weight": 1.0}, "flabby": {"muscle": 0.0}, "muscular": {"muscle": 1.0},
             "short": {"height": 0.0}, "tall": {"height": 1.0},
             "uncommon": {"proportions": 0.0}, "ideal": {"proportions": 1.0}}  # fmt: skip
    for (sex, base), (tag, kw) in itertools.product((("f", F), ("m", M)), alone.items()):
        out.append((f"{sex}-{tag}", Macro(**{**asdict(base), **kw})))
    combos = {
        "f-mincup": dict(gender=0.0, cup=0.0, firmness=0.0),
        "f-maxcup": dict(gender=0.0, cup=1.0, firmness=0.5),
        "f-maxcup-soft-heavy": dict(gender=0.0, cup=1.0, firmness=0.0, weight=1.0),
        "f-short-heavy-old": dict(gender=0.0, height=0.0, weight=1.0, age=old),
        "f-tall-thin-young": dict(gender=0.0, height=1.0, weight=0.0, muscle=0.0),
        "f-short-thin-teen": dict(gender=0.0, height=0.2, weight=0.0, age=teen),
        "m-tall-heavy-muscular": dict(gender=1.0, height=1.0, weight=1.0, muscle=1.0),
        "m-short-heavy-flabby-old": dict(gender=1.0, height=0.0, weight=1.0, muscle=0.0,
                                         age=old),
        "m-tall-thin-uncommon": dict(gender=1.0, height=1.0, weight=0.0, proportions=0.0),
        "m-short-thin-teen": dict(gender=1.0, height=0.2, weight=0.0, age=teen),
        "african-f": dict(gender=0.0, ethnic=(1.0, 0.0, 0.0)),
        "asian-m": dict(gender=1.0, ethnic=(0.0, 1.0, 0.0)),
        "caucasian-m-heavy": dict(gender=1.0, weight=1.0, ethnic=(0.0, 0.0, 1.0)),
        "x-androgynous-heavy": dict(gender=0.5, weight=1.0, muscle=1.0, age=0.75),
    }  # fmt: skip
    out += [(k, Macro(**kw)) for k, kw in combos.items()]
    return out


#: the shapes that also come in a T-pose: a woman and a man, a heavy woman and the tall heavy
#: muscular man (the widest arms), each with the format, units and up axis given here
T_POSED = (("female", "obj", "cm", "y"), ("male", "ply", "mm", "-z"),
           ("f-heavy", "glb", "m", "y"), ("m-tall-heavy-muscular", "stl", "in", "x"))  # fmt: skip


def population() -> list[Body]:
    """The bodies (37 shapes, 43 files), each with an export format, units and up axis: the
    formats cycle fastest, then the units, and the up axis steps once per body against them,
    so that every format meets every unit and every format several up axes. Then two turned
    copies and four T-posed copies (:data:`T_POSED`) of some of the shapes."""
    ups = ("y", "z", "-z", "x", "-y", "-x")
    units = ("mm", "cm", "m", "in")
    out = [Body(name, m, FORMATS[k % 6], units[(k // 6) % 4], ups[(k + k // 6) % 6])
           for k, (name, m) in enumerate(_designs())]  # fmt: skip
    # a scanner's subject need not face the way the package expects (−y with Z up): the same
    # woman and man turned a quarter and a half turn (distinct files, not distinct shapes)
    f, m = Macro(gender=0.0), Macro(gender=1.0)
    out += [Body("female-turned-180", f, "stl", "mm", "z", 180),
            Body("male-turned-90", m, "ply", "m", "z", 90)]  # fmt: skip
    # scanners and body tools also take their subjects with the arms out (a T-pose)
    shape = {b.name: b.macro for b in out}
    return [*out, *(Body(f"{name}-t-pose", shape[name], fmt, units, up, pose="T")
                     for name, fmt, units, up in T_POSED)]  # fmt: skip


def by_name(name: str) -> Body:
    for b in population():
        if b.name == name:
            return b
    raise KeyError(name)


def export(body: Body, folder: str | Path, *, fmt: str | None = None, units: str | None = None,
           up: str | None = None) -> Path:  # fmt: skip
    """Write ``body`` (its format, units and up axis unless given) into ``folder``.

    The file's frame is the package's (Z up, facing −y) turned so that ``up`` is the file's up
    axis (the inverse of :data:`~.orientation.ROTATIONS`; Y up: MakeHuman's own frame, facing
    +z), in ``units``, with MakeHuman's origin (not on the floor).
    """
    import trimesh

    fmt, units, up = fmt or body.fmt, units or body.units, up or body.up
    c, s = np.cos(np.radians(body.turn)), np.sin(np.radians(body.turn))
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    v = to_package_frame(body.vertices) @ turn.T @ ROTATIONS[up] / UNITS[units]
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    stem = f"{body.name}-{fmt}-{units}-{up.replace('-', 'neg')}" if (fmt, units, up) != (
        body.fmt, body.units, body.up) else body.name  # fmt: skip
    path = folder / f"{stem}{SUFFIX[fmt]}"
    base = base_mesh()
    if fmt == "obj":  # quads and all, as MakeHuman's exporter writes
        _write_obj(path, v, base, ("body", *OBJ_EXTRA_GROUPS), body)
        return path
    faces = base.faces()
    tri = [f[:3] for f in faces] + [[f[0], f[2], f[3]] for f in faces if len(f) == 4]
    used = np.unique(np.array(tri))
    remap = np.full(len(v), -1)
    remap[used] = np.arange(len(used))
    mesh = trimesh.Trimesh(v[used], remap[np.array(tri)], process=False)
    if fmt.startswith("stl"):
        mesh.export(path, file_type="stl_ascii" if fmt == "stl-ascii" else "stl")
    elif fmt.startswith("ply"):
        mesh.export(path, file_type="ply", encoding="ascii" if fmt == "ply-ascii" else "binary")
    else:
        mesh.export(path, file_type="glb")
    return path


def _write_obj(path: Path, v: Array, base: BaseMesh, groups: tuple[str, ...], body: Body) -> None:
    faces = {g: base.groups[g] for g in groups}
    used = np.unique(np.concatenate([np.concatenate(f) for f in faces.values()]))
    index = np.zeros(len(v), dtype=np.int64)
    index[used] = np.arange(1, len(used) + 1)
    lines = [f"# MakeHuman body {body.name} (CC0 base mesh and macro targets): "
             f"{body.macro}", f"# units {body.units}"]  # fmt: skip
    lines += [f"v {x:.6g} {y:.6g} {z:.6g}" for x, y, z in v[used]]
    for g, fs in faces.items():
        lines.append(f"g {g}")
        lines += ["f " + " ".join(str(index[i]) for i in f) for f in fs]
    path.write_text("\n".join(lines) + "\n")
