"""The scene kind ``drape`` (issue 47, item 2): the instrument's drape coefficient against the
shadow of a tilted flat specimen, the fabric's values and their units, refusal of bad fabric
input, and (slow) a whole ``fenics-garment run`` of the shipped drape scene on a coarse mesh."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from fenics_garment import drape, measured
from fenics_garment.cli import main
from fenics_garment.scene import config
from fenics_garment.scene import drape as drape_scene

SCENES = Path(__file__).parent.parent / "fenics_garment" / "scenes"
R_P, R_S = 0.09, 0.15  # BS 5058: 180 mm pedestal, 300 mm specimen


def polar_annulus(n_phi: int = 720, n_r: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """A structured triangulation of the flat annulus R_P ≤ r ≤ R_S (its own, not gmsh's)."""
    r = np.linspace(R_P, R_S, n_r)
    phi = np.linspace(0.0, 2 * math.pi, n_phi, endpoint=False)
    R, P = np.meshgrid(r, phi, indexing="ij")
    x = np.stack([R * np.cos(P), R * np.sin(P), 0 * R], axis=-1).reshape(-1, 3)
    idx = np.arange(n_r * n_phi).reshape(n_r, n_phi)
    a, b = idx[:-1], np.roll(idx[:-1], -1, axis=1)
    c, d = idx[1:], np.roll(idx[1:], -1, axis=1)
    tris = np.concatenate([np.stack([a, b, d], -1).reshape(-1, 3),
                           np.stack([a, d, c], -1).reshape(-1, 3)])  # fmt: skip
    return x, tris


@pytest.mark.parametrize("alpha_deg", [0.0, 20.0, 45.0])
def test_dc_of_a_tilted_flat_specimen(alpha_deg):
    # tilted by α about the x axis, the flat specimen's shadow is an ellipse of area
    # π R_S² cos α; the pedestal's disc covers the projected hole (an ellipse inside it), so
    # DC = (R_S² cos α − R_P²)/(R_S² − R_P²)
    a = math.radians(alpha_deg)
    x, tris = polar_annulus()
    rot = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    xt = x @ rot.T
    dc, area = drape.drape_coefficient(xt[:, :2], tris, R_P, R_S, 2.5e-4)
    exact = (R_S**2 * math.cos(a) - R_P**2) / (R_S**2 - R_P**2)
    assert dc == pytest.approx(exact, abs=2e-3)
    assert area == pytest.approx(math.pi * R_S**2 * math.cos(a), rel=1e-3)


def test_flat_specimen_mesh_has_dc_one():
    # the instrument on the undeformed order-2 specimen mesh (a very coarse one): its raster
    # agrees with its outline, and the outline is the circle to its polygon's deficit
    mesh = drape.annulus_mesh(drape.MPI.COMM_SELF, R_P, R_S, 0.03)
    cells = mesh.geometry.dofmaps[0]
    dc_raster, dc_exact = drape.flat_coefficients(mesh.geometry.x, drape._sub_triangles(cells),
                                                  R_P, R_S, 5e-4)  # fmt: skip
    assert dc_raster == pytest.approx(dc_exact, abs=drape_scene.LIMITS["instrument"])
    n_hem = int(np.sum(np.hypot(*mesh.geometry.x[:, :2].T) > R_S * (1 - 1e-6)))
    deficit = (2 * math.pi / n_hem) ** 2 / 6 * R_S**2 / (R_S**2 - R_P**2)  # regular n-gon
    assert 1 - 3 * deficit < dc_exact < 1.0


def test_scene_values_are_converted_as_the_data_file_s():
    # M-B as a scene's own KES values: the same SI fabric as the data file's record
    kes = {"B_gf_cm2_per_cm": 0.067, "twoHB_gf_cm_per_cm": 0.033, "W_mg_cm2": 16.29,
           "T_mm": 0.407}  # fmt: skip
    s = config.from_dict({"kind": "drape", "name": "mb", "drape": {"kes": kes}})
    own, rec = drape_scene.fabric_of(s), measured.by_id("M-B")
    for k in ("mass_per_area", "thickness", "B_warp", "B_weft", "twoHB"):
        assert getattr(own, k) == getattr(rec, k)
    # the factors by hand: 1 gf = 9.80665e-3 N, 1 cm = 1e-2 m, 1 mg/cm² = 1e-2 kg/m²
    assert own.B_warp == pytest.approx(0.067 * 9.80665e-3 * 1e-4 / 1e-2, rel=1e-12)
    assert own.twoHB == pytest.approx(0.033 * 9.80665e-3 * 1e-2 / 1e-2, rel=1e-12)
    assert own.mass_per_area == pytest.approx(16.29e-6 / 1e-4, rel=1e-12)
    # CLO3D-style (P-m6): g·mm²/s² = 1e-3 kg × 1e-6 m² / s², g/s² = 1e-3 N/m
    clo = {"areal_mass_g_m2": 253.36, "thickness_mm": 0.62, "stretch_warp_g_s2": 473860,
           "stretch_weft_g_s2": 404746, "shear_g_s2": 126000, "bending_warp_g_mm2_s2": 7430,
           "bending_weft_g_mm2_s2": 3700}  # fmt: skip
    c = drape_scene.fabric_of(config.from_dict({"kind": "drape", "drape": {"clo3d": clo}}))
    assert c.B_warp == pytest.approx(7.43e-6, rel=1e-12)
    assert c.stretch_warp == pytest.approx(473.86, rel=1e-12)
    assert c.mass_per_area == pytest.approx(0.25336, rel=1e-12)


BAD = [
    ({"fabric": "P-m7"}, "drape.fabric", "did you mean"),
    ({"fabric": "M-B", "kes": {"B_gf_cm2_per_cm": 0.1, "W_mg_cm2": 10.0, "T_mm": 0.3}},
     "drape.fabric", "once"),
    ({}, "drape.fabric", "once"),
    ({"kes": {"B_gf_cm2_per_cm": 0.1, "W_mg_cm2": 10.0}}, "drape.kes", "missing T_mm"),
    ({"kes": {"B_gf_cm2_per_cm": -0.1, "W_mg_cm2": 10.0, "T_mm": 0.3}}, "drape.kes",
     "positive"),
    ({"kes": {"B_gf_cm2_per_cm": 0.1, "W_mg_cm2": 10.0, "T_mm": 0.3, "B_gf_cm2": 1.0}},
     "drape.kes.B_gf_cm2", "unknown key"),
    ({"kes": {"B": 0.1}}, "drape.kes.B", "unknown key"),
    ({"kes": {"B_gf_cm2_per_cm": 0.1, "W_mg_cm2": 10.0, "T_mm": 0.3}, "bending": "hysteresis"},
     "drape.bending", "2HB"),
    ({"fabric": "P-m6", "bending": "hysteresis"}, "drape.bending", "2HB"),
    ({"fabric": "M-B", "bending": "plastic"}, "drape.bending", "one of"),
    ({"fabric": "M-B", "mesh_size": 0.05}, "drape.mesh_size", "half the overhang"),
    ({"fabric": "M-B", "pedestal_diameter": 0.3}, "drape.specimen_diameter", "larger"),
    ({"fabric": "M-B", "dc_measured": 1.2}, "drape.dc_measured", "[0, 1]"),
]  # fmt: skip


@pytest.mark.parametrize(("table", "key", "words"), BAD)
def test_bad_fabric_input_is_refused(table, key, words):
    with pytest.raises(config.SceneError) as err:
        config.from_dict({"kind": "drape", "drape": table}, "d.toml")
    assert err.value.key == key and words in str(err.value)


def test_sections_of_the_other_kind_are_refused():
    with pytest.raises(config.SceneError) as err:
        config.from_dict({"kind": "drape", "drape": {"fabric": "M-B"}, "body": {"size": "92"}})
    assert err.value.key == "body"
    with pytest.raises(config.SceneError) as err:
        config.from_dict({"drape": {"fabric": "M-B"}})
    assert err.value.key == "drape"


def test_drape_scene_round_trips_and_garment_text_is_unchanged():
    s = config.load(SCENES / "drape_wool_tropical.toml")
    text = config.dumps(s)
    assert "[drape]" in text and "[body]" not in text and 'kind = "drape"' in text
    assert config.from_dict(__import__("tomllib").loads(text)) == s
    g = config.dumps(config.load(SCENES / "tube_on_cylinder.toml"))
    assert "kind" not in g.split("[body]")[0] and "[drape]" not in g


def test_cli_refuses_bad_fabric_in_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('kind = "drape"\n[drape.kes]\nB_gf_cm2_per_cm = 0.1\nW_mg_cm2 = 0\nT_mm = 0.3\n')
    assert main(["run", str(bad), "-o", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert (
        len(err) == 1 and "[drape.kes]" in err[0] and "W_mg_cm2 must be a positive number" in err[0]
    )


@pytest.mark.slow
def test_run_the_drape_scene_on_a_coarse_mesh(tmp_path):
    import meshio

    scene = tmp_path / "coarse.toml"
    text = (SCENES / "drape_wool_tropical.toml").read_text()
    scene.write_text(text.replace("mesh_size = 0.012", "mesh_size = 0.025"))
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 0
    out = tmp_path / "drape-wool-tropical"
    s = json.loads((out / "summary.json").read_text())
    assert s["completed"] and s["checks_passed"] and s["bending"] == "hysteresis"
    # the hanging fabric's shadow lies between the pedestal's and the flat specimen's
    assert 0.0 < s["dc"] < 1.0 and s["nodes"] >= 2
    assert s["dc_measured"] == measured.by_id("M-B").dc_measured
    for name in ("drape.png", "final_state.xdmf", "scene_used.toml", "run.json"):
        assert (out / name).is_file()
    assert (out / "drape.bp").is_dir()
    with meshio.xdmf.TimeSeriesReader(out / "final_state.xdmf") as r:
        points, _ = r.read_points_cells()
        _, data, _ = r.read_data(0)
    z = points[:, 2] + data["displacement"][:, 2]
    assert np.allclose(z, data["height"]) and z.min() < -0.01  # the annulus hangs down
    assert json.loads((out / "run.json").read_text())["status"] == "completed"
