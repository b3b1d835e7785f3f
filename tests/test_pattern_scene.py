"""Scenes of garments sewn from flat patterns (``[garment] kind = "pattern"``).

* A flat rectangle sewn edge to edge into a tight tube on a rigid cylinder (the seam included,
  merged nodes): Laplace's law for a tube whose rest state is the flat rectangle
  (``verification.contact.tube_pressure(flat=True)``: the membrane part as for any tube, the
  bending term of a flat rest curvature) within 1 %.
* A malformed pattern is refused before meshing with one line naming the panel and edge.
"""

import math
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from fenics_garment._stack import MPI
from fenics_garment.scene import config
from fenics_garment.scene.run import run
from fenics_garment.verification.contact import band_pressure, tube_pressure

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
    """Force over deformed area of the contact points in the middle half of the tube."""
    return band_pressure(result.built, L / 4, 3 * L / 4)


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


def test_garmentcode_pattern_is_placed_in_our_frame(tmp_path):
    """A GarmentCode specification (y up, facing +z, cm) sewn round the mannequin (z up,
    facing −y): its front panel ends up in front of the body (y < 0), its back behind, the
    garment between the hip and the shoulders, not inside the body."""
    import json

    from fenics_garment.geometry import MeshSizes, make_mannequin, measurements
    from fenics_garment.pattern.io import read_pattern
    from fenics_garment.pattern.sew import pattern_garment

    def panel(z: float, flip: bool) -> dict:
        v = [[-25, 0], [25, 0], [23, 45], [-23, 45]]
        if flip:  # GarmentCode draws a back panel clockwise as seen from the front
            v = [[-x, y] for x, y in v]
        return {"translation": [0, 95, z], "rotation": [0, 0, 0], "vertices": v,
                "edges": [{"endpoints": [i, (i + 1) % 4]} for i in range(4)]}  # fmt: skip

    spec = {"pattern": {"panels": {"front": panel(25, False), "back": panel(-20, True)},
                        # the sides at the body's left (GarmentCode +x) and right (−x): the
                        # back's outline is mirrored, so its +x side is its edge 3
                        "stitches": [[{"panel": "front", "edge": 1}, {"panel": "back", "edge": 3}],
                                     [{"panel": "front", "edge": 3},
                                      {"panel": "back", "edge": 1}]]},
            "properties": {"units_in_meter": 100}}  # fmt: skip
    path = tmp_path / "top_specification.json"
    path.write_text(json.dumps(spec))
    body = make_mannequin(measurements("88"), MeshSizes(0.025, 0.025), z_range=(0.7, 1.55))
    gm, _ = pattern_garment(read_pattern(path), body, 0.04)
    x = gm.points
    front = x[np.unique(gm.cells[gm.cell_panel == gm.panels["front"]])]
    back = x[np.unique(gm.cells[gm.cell_panel == gm.panels["back"]])]
    assert front[:, 1].mean() < -0.05 and back[:, 1].mean() > 0.05
    assert 0.85 < x[:, 2].min() and x[:, 2].max() < 1.45  # GarmentCode's 95 … 140 cm
    assert gm.info["penetration_max"] < 0.002 and gm.info["inverted"] == 0


def test_a_dxf_without_seams_is_refused_in_one_line(capsys, tmp_path):
    """DXF-AAMA carries no seams: its pieces, dressed as they are, would fall off the body."""
    from fenics_garment.cli import main
    from fenics_garment.pattern.dxf import write_dxf
    from fenics_garment.pattern.io import read_pattern

    shipped = Path(__file__).parent.parent / "fenics_garment" / "scenes"
    write_dxf(read_pattern(shipped / "patterns" / "darted_top.toml"), tmp_path / "top.dxf")
    text = (shipped / "darted_top.toml").read_text()
    scene = tmp_path / "scene.toml"
    scene.write_text(text.replace("patterns/darted_top.toml", "top.dxf"))
    code = main(["run", str(scene), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and "sewn to no other panel" in err[0] and "companion" in err[0], err


def test_a_panel_of_another_fabric_is_refused_in_one_line(capsys, tmp_path):
    """A garment is of one fabric (the scene's): a panel naming another is refused before
    meshing, not simulated in the scene's fabric without a word."""
    from fenics_garment.cli import main

    shipped = Path(__file__).parent.parent / "fenics_garment" / "scenes"
    pattern = (shipped / "patterns" / "darted_top.toml").read_text()
    assert "[[panel]]" in pattern
    (tmp_path / "top.toml").write_text(
        pattern.replace("[[panel]]", '[[panel]]\nfabric = "nylon"', 1)
    )
    text = (shipped / "darted_top.toml").read_text()
    scene = tmp_path / "scene.toml"
    scene.write_text(text.replace("patterns/darted_top.toml", "top.toml"))
    code = main(["check", str(scene)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and "'nylon'" in err[0] and "one fabric" in err[0], err


@pytest.mark.slow
def test_builtin_gilet_from_flat_pieces(tmp_path):
    """The built-in gilet cut into princess-seamed flat pieces (rest = "pattern") dresses with
    every result check passed, and its pieces, written as a pattern, are the flat map's: six
    panels whose areas add up to the flat area ∫ j dA of the shell's rest state."""
    import ufl

    from fenics_garment.pattern.io import read_pattern

    scene = config.load(Path(__file__).parent.parent / "demos" / "cotton_gilet.toml")
    scene = replace(scene, garment=replace(scene.garment, mesh_size=0.04, rest="pattern"))
    res = run(scene, _folder(MPI.COMM_WORLD) / "out", quiet=True)
    assert res.completed and all(c.ok for c in res.checks), [c for c in res.checks if not c.ok]
    m = res.built.model
    flat_area = m.energy_value(m.geometry.rest_area * ufl.dx(m.geometry.mesh))
    if MPI.COMM_WORLD.rank == 0:
        p = read_pattern(res.folder / "pattern.toml")
        assert set(p.panels) == {"front", "back", "front_side_left", "front_side_right",
                                 "back_side_left", "back_side_right"}  # fmt: skip
        assert sum(q.area for q in p.panels.values()) == pytest.approx(flat_area, rel=2e-3)
        seams = {s.name.rstrip("_2") for s in p.seams}
        assert {"side_seam_left", "shoulder_seam_right", "princess_front_left"} <= seams
