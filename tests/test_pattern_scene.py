"""Scenes of garments sewn from flat patterns (``[garment] kind = "pattern"``).

* A flat rectangle sewn edge to edge into a tight tube on a rigid cylinder (the seam included,
  merged nodes): Laplace's law for a tube whose rest state is the flat rectangle
  (``verification.contact.tube_pressure(flat=True)``: the membrane part as for any tube, the
  bending term of a flat rest curvature) within 1 %.
* A malformed pattern is refused before meshing with one line naming the panel and edge.
"""

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest

from fenics_garment._stack import MPI
from fenics_garment.contact import pressure as cpressure
from fenics_garment.scene import config
from fenics_garment.scene.run import run
from fenics_garment.verification.contact import tube_pressure

R, L, EASE = 0.1, 0.2, -0.07


def _files(folder: Path, width: float, seam_to: str = "left") -> Path:
    (folder / "tube.toml").write_text(f"""
name = "tube"
units = "m"
[[panel]]
name = "tube"
grain = [0, 1]
wrap = {{ axis = "torso", top = {L} }}
start = [0, 0]
edges = [{{ to = [{width!r}, 0], name = "hem" }}, {{ to = [{width!r}, {L}], name = "right" }},
         {{ to = [0, {L}], name = "top" }}, {{ name = "left" }}]
[[seam]]
name = "seam"
a = {{ panel = "tube", edge = "right" }}
b = {{ panel = "tube", edge = "{seam_to}" }}
""")
    scene = folder / "scene.toml"
    scene.write_text(f"""
name = "sewn-tube"
[body]
kind = "cylinder"
radius = {R}
length = {L}
mesh_size = 0.005
[garment]
kind = "pattern"
pattern = "tube.toml"
fabric = "cotton"
mesh_size = 0.02
[physics]
gravity = false
friction = 0.3           # holds spin and axial slide; on after the sewing (slip 0 there)
penalty_length = 0.0
[dressing]
steps = 2
friction_while_growing = false
""")
    return scene


def _folder(comm) -> Path:
    return Path(comm.bcast(tempfile.mkdtemp() if comm.rank == 0 else None, root=0))


def _mid_pressure(result) -> float:
    b = result.built
    st, c = b.contact.state, b.contact
    f = cpressure.point_forces(st, c.traction)
    a = cpressure.point_areas(st, c.area_stretch())
    z = cpressure.positions(st)[:, 2]
    sel = np.abs(z - L / 2) < L / 4
    comm = b.model.geometry.mesh.comm
    return comm.allreduce(f[sel].sum(), op=MPI.SUM) / comm.allreduce(a[sel].sum(), op=MPI.SUM)


def test_sewn_rectangle_obeys_laplace():
    comm = MPI.COMM_WORLD
    folder = _folder(comm)
    r0 = R * (1 + EASE)
    scene = config.load(_files(folder, 2 * math.pi * r0))
    res = run(scene, folder / "out", quiet=True)
    assert res.completed
    g = res.built.garment
    assert "seam" in g.edges and g.rest is not None  # sewn, flat rest state
    assert res.built.model.geometry.rest is not None
    s = res.built.model.stiffness
    ref = tube_pressure(R + s.thickness / 2, r0, s, warp="axial", flat=True)
    p = _mid_pressure(res)
    print(f"\nsewn tube: p = {p:.2f} Pa, Laplace (flat rest) {ref:.2f} Pa, "
          f"{100 * (p / ref - 1):+.3f} %")  # fmt: skip
    assert p == pytest.approx(ref, rel=0.01)
    # the fit table of the sewn pattern: the rectangle is 7 % short of the cylinder's girth
    mid = [lv for lv in g.levels if lv.name == "mid"]
    assert mid and mid[0].ease == pytest.approx(EASE, abs=1e-3)
    assert mid[0].garment_girth == pytest.approx(2 * math.pi * r0, rel=1e-4)
    # the flat pieces written back as a pattern (ours and DXF-AAMA + seams): the rectangle
    from fenics_garment.pattern.io import read_pattern

    if comm.rank == 0:
        for name in ("pattern.toml", "pattern_seams.toml"):
            back = read_pattern(res.folder / name)
            (panel,) = back.panels.values()
            assert panel.area == pytest.approx(2 * math.pi * r0 * L, rel=1e-3)
            assert len(back.seams) == 1 and back.seams[0].name == "seam"


def test_malformed_pattern_is_refused_in_one_line(capsys):
    comm = MPI.COMM_WORLD
    folder = _folder(comm)
    scene = _files(folder, 2 * math.pi * R, seam_to="lft")  # a seam naming a missing edge
    from fenics_garment.cli import main

    code = main(["run", str(scene), "-o", str(folder / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and "tube" in err[0] and "lft" in err[0], err
