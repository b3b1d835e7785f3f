"""Bad input gives a clear error that names the file or the value and says what to do.

Scans, materials, body measurements and PETSc options; the scene-file errors are tested with the
scene runner. Each case checks the error's type and that its message names the culprit.
"""

import meshio
import numpy as np
import pytest

from fenics_garment import materials
from fenics_garment.geometry import ScanError, measurements
from fenics_garment.geometry.scan import load_scan

TETRA_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
TETRA_T = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])


def _write(path, v, t):
    meshio.write(path, meshio.Mesh(v, [("triangle", t)]))
    return path


# -- scans --------------------------------------------------------------------------------------
def test_missing_scan_file(tmp_path):
    with pytest.raises(ScanError, match=r"nope.obj: no such file"):
        load_scan(tmp_path / "nope.obj")


def test_garbage_scan_file(tmp_path):
    p = tmp_path / "scan.stl"
    p.write_bytes(b"\x00\xff" * 37)
    with pytest.raises(ScanError, match=r"scan.stl: not a readable mesh"):
        load_scan(p)


def test_truncated_obj_faces_refer_to_missing_vertices(tmp_path):
    p = tmp_path / "cut.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 9\n")
    with pytest.raises(ScanError, match=r"do not exist|not a readable mesh"):
        load_scan(p)


def test_scan_without_faces(tmp_path):
    p = tmp_path / "points.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")
    with pytest.raises(ScanError, match=r"points.obj"):
        load_scan(p)


def test_a_1_7_km_person(tmp_path):
    # 1000× too big for the declared units
    p = _write(tmp_path / "giant.ply", TETRA_V * 1700.0, TETRA_T)
    with pytest.raises(ScanError, match=r"1700 m across.*not a human body"):
        load_scan(p, units="m")


def test_nan_vertices(tmp_path):
    v = TETRA_V.copy()
    v[2, 1] = np.nan
    p = _write(tmp_path / "nan.ply", v, TETRA_T)
    with pytest.raises(ScanError, match=r"NaN"):
        load_scan(p)


def test_non_manifold_scan(tmp_path):
    v = np.vstack([TETRA_V, [[0.3, 0.3, -1.0]]])
    t = np.vstack([TETRA_T, [[0, 1, 4]]])  # a fin on edge (0, 1): three faces share it
    with pytest.raises(ScanError, match=r"non-manifold"):
        load_scan(_write(tmp_path / "fin.stl", v, t), units="m")


def test_open_scan(tmp_path):
    # a cylinder side without caps: holes of 48 edges each, more than max_hole_edges = 40
    n = 48
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = np.column_stack([0.15 * np.cos(a), 0.15 * np.sin(a)])
    v = np.vstack([np.column_stack([ring, np.zeros(n)]), np.column_stack([ring, np.ones(n)])])
    i = np.arange(n)
    j = (i + 1) % n
    t = np.vstack([np.column_stack([i, j, n + j]), np.column_stack([i, n + j, n + i])])
    with pytest.raises(ScanError, match=r"not closed: 2 hole"):
        load_scan(_write(tmp_path / "tube.obj", v, t))


def test_unknown_units(tmp_path):
    with pytest.raises(ScanError, match=r"unknown units 'inch'"):
        load_scan(_write(tmp_path / "t.ply", TETRA_V, TETRA_T), units="inch")


# -- materials ----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "change, message",
    [
        ({"thickness": -1e-3}, "thickness"),
        ({"thickness": 0.0}, "thickness"),
        ({"E_weft": 0.0}, "E_weft"),
        ({"B_warp": -1e-6}, "B_warp"),
        ({"density": -10.0}, "density"),
        ({"nu12": 2.0}, "Poisson"),
        ({"nu12": -0.1}, "Poisson"),
    ],
)
def test_invalid_fabric(change, message):
    base = dict(E_warp=1e6, E_weft=5e5, G12=1e5, B_warp=1e-5, B_weft=1e-5, thickness=1e-3,
                density=300.0, nu12=0.3, name="test-fabric")  # fmt: skip
    with pytest.raises(materials.MaterialError, match=message):
        materials.Fabric(**{**base, **change})


def test_unknown_fabric_name():
    with pytest.raises(materials.MaterialError, match=r"denim.*cotton, nylon"):
        materials.fabric("denim")


# -- body measurements --------------------------------------------------------------------------
def test_negative_girth():
    with pytest.raises(ValueError, match=r"waist_girth must be positive"):
        measurements("88", waist_girth=-0.7)


def test_unknown_measurement_name():
    with pytest.raises(TypeError, match=r"wasit_girth"):
        measurements("88", wasit_girth=0.7)


def test_landmarks_out_of_order():
    with pytest.raises(ValueError, match=r"heights must increase"):
        measurements("88", waist_height=0.80)


# -- PETSc options ------------------------------------------------------------------------------
def test_petsc_option_petsc_rejects():
    from fenics_garment._stack import MPI
    from fenics_garment.materials import Isotropic
    from fenics_garment.shell.geometry import parametric_surface_mesh
    from fenics_garment.shell.kinematics import ShellGeometry
    from fenics_garment.shell.model import ShellModel
    from fenics_garment.solve import NonlinearSolver

    mesh = parametric_surface_mesh(
        MPI.COMM_SELF, lambda x, y: np.array([x, y, 0 * x]), (0, 1), (0, 1), (2, 2)
    )
    model = ShellModel(ShellGeometry.from_mesh(mesh, warp=(1, 0, 0)), Isotropic(1e6, 0.3, 1e-2))
    # refused before PETSc sees it (fenics_garment.petsc_options), with a suggestion
    with pytest.raises(ValueError, match=r"ksp_type\] must be one of .*no_such_krylov"):
        NonlinearSolver(model, [], petsc_options={"ksp_type": "no_such_krylov"})


def test_truncated_binary_stl(tmp_path):
    # (meshio's STL reader even calls sys.exit(1) on some corrupted files: tests/test_fuzz.py)
    p = tmp_path / "cut.stl"
    meshio.write(p, meshio.Mesh(TETRA_V, [("triangle", TETRA_T)]), binary=True)
    p.write_bytes(p.read_bytes()[:-10])
    with pytest.raises(ScanError, match=r"cut.stl: not a readable mesh"):
        load_scan(p)


def test_ply_header_cut_short(tmp_path):
    # meshio's PLY reader loops forever when end_header is missing (found by tests/test_fuzz.py)
    p = _write(tmp_path / "cut.ply", TETRA_V, TETRA_T)
    p.write_bytes(p.read_bytes()[:60])
    with pytest.raises(ScanError, match=r"cut.ply: PLY header without end_header"):
        load_scan(p)


def test_scene_file_not_utf8(tmp_path):
    from fenics_garment.scene import config

    p = tmp_path / "scene.toml"
    p.write_bytes(b'name = "a\xff"\n')
    with pytest.raises(config.SceneError, match=r"scene.toml: not a UTF-8 text file"):
        config.load(p)
    with pytest.raises(config.SceneError, match=r"a folder, not a scene file"):
        config.load(tmp_path)  # a directory
