"""Fuzzing with fixed seeds: corrupted scene files and scan meshes give a clear error or load.

* Scene files (``config.load`` + the pre-build limits, many cases, fast): random byte flips,
  truncations, unknown keys, and every key of every bundled scene set to a wrong type or to an
  extreme number (−1, 0, ±1e300, NaN, ±inf, 1e-300, 10¹⁸). The outcome must be a
  :class:`SceneError`/``PreflightError`` (both ``ValueError``) with a message, or a valid scene.
* A few of the scenes that pass the pre-build limits go through ``fenics-garment check`` (builds
  the meshes): exit code 0 or 2 with a one-line message, no traceback; one in a real process.
* Scan files (STL, OBJ, PLY, MSH of a closed 1.7 m surface): byte flips and truncations give
  :class:`ScanError` or load.
* PETSc option values (every supported option × extremes and wrong types, unknown names) and
  checkpoint files (byte flips and truncations of ``progress.json`` and a rank file): a
  ``PetscOptionError`` / ``ResumeError`` with a message, or accepted. Errors on one MPI rank
  and environment faults (full disk, read-only folders) are in ``test_reliability_ranks.py``
  and ``test_reliability_folders.py``. (These found a ``sys.exit(1)`` in meshio's STL reader and an
  empty ``min()`` in the landmark search, both now ScanError.)
"""

import os
import random
import shutil
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest

from fenics_garment import cli
from fenics_garment._stack import MPI
from fenics_garment.geometry import ScanError
from fenics_garment.geometry.scan import load_scan
from fenics_garment.scene import config, preflight

ROOT = Path(__file__).parent.parent
DEMOS = sorted((ROOT / "demos").glob("*.toml"))
EXTREMES = [-1, 0, 1e300, -1e300, float("nan"), float("inf"), -float("inf"), 1e-300, 10**18]
WRONG_TYPES = ["text", True, [1, 2], {"a": 1}]
pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial")


def _outcome(load) -> str:
    """'ok' or 'error'; any other exception, or an error without a message, fails the test."""
    try:
        scene = load()
        preflight.scene_limits(scene)
    except (config.SceneError, preflight.PreflightError) as err:
        assert len(str(err)) > 20 and "\n" not in str(err), repr(err)
        return "error"
    return "ok"


def _toml(data: dict) -> str:
    """TOML text of a (possibly invalid) scene table."""
    v = config._toml_value
    lines = [f"{k} = {v(x)}" for k, x in data.items() if not isinstance(x, dict)]
    for section, table in data.items():
        if isinstance(table, dict):
            lines += [f"[{section}]", *(f"{k} = {v(x)}" for k, x in table.items())]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("demo", DEMOS, ids=lambda p: p.stem)
def test_scene_byte_flips_and_truncations(demo, tmp_path):
    rng = random.Random(20261123)
    data = demo.read_bytes()
    path = tmp_path / "fuzzed.toml"
    seen = {"ok": 0, "error": 0}
    for _ in range(60):
        b = bytearray(data)
        for _ in range(rng.randint(1, 4)):
            b[rng.randrange(len(b))] = rng.randrange(256)
        path.write_bytes(bytes(b))
        seen[_outcome(lambda: config.load(path))] += 1
        path.write_bytes(data[: rng.randrange(len(data))])
        seen[_outcome(lambda: config.load(path))] += 1
    assert seen["error"] > 20  # the fuzzing does reach the checks


@pytest.mark.parametrize("demo", DEMOS, ids=lambda p: p.stem)
def test_scene_wrong_types_extremes_and_unknown_keys(demo):
    rng = random.Random(7)
    base = config.to_dict(config.load(demo))
    outcomes = []
    for section, table in base.items():
        if not isinstance(table, dict):
            continue
        for key in table:
            for value in EXTREMES + WRONG_TYPES:
                data = config.to_dict(config.load(demo))
                data[section][key] = value
                outcomes.append(_outcome(lambda d=data: config.from_dict(d, str(demo))))
        for _ in range(3):
            data = config.to_dict(config.load(demo))
            word = "".join(rng.choice("abcdefghijklmnopqrstuvwxyz_") for _ in range(8))
            data[section][word] = rng.choice(EXTREMES + WRONG_TYPES)
            assert _outcome(lambda d=data: config.from_dict(d, str(demo))) == "error"
    assert outcomes.count("error") > 100 and outcomes.count("ok") > 10


def _cli_check(tmp_path: Path, name: str, data: dict, capsys) -> int:
    path = tmp_path / f"{name}.toml"
    path.write_text(_toml(data))
    code = cli.main(["check", str(path)])
    captured = capsys.readouterr()
    if code == 2:
        err = captured.err.strip()
        assert err.startswith("error: ") and len(err.splitlines()) == 1, err
    else:
        assert code == 0 and "ok" in captured.out
    return code


def _tube(section: str, key: str, value) -> dict:
    data = config.to_dict(config.load(ROOT / "demos" / "tube_on_cylinder.toml"))
    data["body"]["mesh_size"] = 0.01
    data[section][key] = value
    return data


CHECKED = [  # scenes that pass config.load; `check` builds them (or stops before building)
    ("margin_huge", _tube("dressing", "margin", 1e300), 2),
    ("ease_large", _tube("garment", "ease", 0.99), 0),
    ("garment_mesh_huge", _tube("garment", "mesh_size", 0.9), 2),
    ("garment_mesh_tiny", _tube("garment", "mesh_size", 1e-300), 2),
    ("body_mesh_tiny", _tube("body", "mesh_size", 1e-300), 2),
    ("radius_huge", _tube("body", "radius", 1e300), 2),
    ("steps_endless", _tube("dressing", "steps", 10**18), 2),
    ("cuts_endless", _tube("dressing", "max_cuts", 10**18), 2),
    ("kappa_huge", _tube("physics", "kappa_hat", 1e300), 2),
    ("short_cylinder", _tube("body", "length", 0.002), 0),
]


@pytest.mark.parametrize("name, data, code", CHECKED, ids=[c[0] for c in CHECKED])
def test_check_command_on_extreme_scenes(name, data, code, tmp_path, capsys):
    assert _cli_check(tmp_path, name, data, capsys) == code


@pytest.mark.parametrize(
    "key, value, words",
    [
        ("z_range", [1.9, 2.5], "crops away"),
        ("measurements", {"waist_girth": 1e3}, "not a human body"),
        ("measurements", {"waist_height": 0.8}, "heights must increase"),
    ],
)
def test_check_command_on_impossible_mannequins(key, value, words, tmp_path, capsys):
    data = config.to_dict(config.load(ROOT / "demos" / "cotton_gilet.toml"))
    data["body"][key] = value
    if key == "z_range":  # the torso mannequin's crop (a human mannequin is built whole)
        data["body"]["human"] = False
    assert _cli_check(tmp_path, "gilet", data, capsys) == 2


def test_check_in_a_real_process_has_no_traceback(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_bytes(b'name = "x"\n[body]\nkind = "cyl\xffinder"\n')
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    p = subprocess.run([sys.executable, "-m", "fenics_garment.cli", "check", str(path)],
                       env=env, capture_output=True, text=True, timeout=300)  # fmt: skip
    assert p.returncode == 2
    lines = [ln for ln in p.stderr.splitlines() if not ln.startswith(("nanobind", " - leaked"))]
    assert lines[0].startswith("error: ") and "UTF-8" in lines[0]
    assert "Traceback" not in p.stderr


# -- scan files ---------------------------------------------------------------------------------
def _closed_surface(n: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """A closed UV ellipsoid, 0.3 m wide and 1.7 m tall, feet at z = 0."""
    th = np.linspace(0, np.pi, n + 1)[1:-1]
    ph = np.linspace(0, 2 * np.pi, 2 * n, endpoint=False)
    ring = [[np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)] for t in th for p in ph]
    v = np.array([[0, 0, 1.0], *ring, [0, 0, -1.0]]) * [0.15, 0.15, 0.85] + [0, 0, 0.85]
    m = 2 * n
    tri = [[0, 1 + j, 1 + (j + 1) % m] for j in range(m)]
    for i in range(n - 2):
        for j in range(m):
            a, b = 1 + i * m + j, 1 + i * m + (j + 1) % m
            tri += [[a, a + m, b], [b, a + m, b + m]]
    last = 1 + (n - 2) * m
    tri += [[last + j, len(v) - 1, last + (j + 1) % m] for j in range(m)]
    return v, np.array(tri)


@pytest.mark.parametrize("ext", [".stl", ".obj", ".ply", ".msh"])
def test_corrupted_scan_files(ext, tmp_path):
    v, t = _closed_surface()
    base = tmp_path / f"base{ext}"
    kw = {"file_format": "gmsh22", "binary": False} if ext == ".msh" else {}
    meshio.write(base, meshio.Mesh(v, [("triangle", t)]), **kw)
    data = base.read_bytes()
    rng = random.Random(ext)  # str seeds are hashed with SHA-512: the same every run
    path = tmp_path / f"case{ext}"
    errors = 0
    for i in range(30):
        b = bytearray(data)
        if i % 2:
            b = b[: rng.randrange(len(b))]
        else:
            for _ in range(rng.randint(1, 6)):
                b[rng.randrange(len(b))] = rng.randrange(256)
        path.write_bytes(bytes(b))
        try:
            load_scan(path)
        except ScanError as err:
            assert str(err), "empty message"
            errors += 1
    assert errors >= 10


# -- PETSc option values (issue 18) -----------------------------------------------------------
def test_petsc_option_values():
    """Every supported option with extreme numbers and wrong types, and unknown names: a
    PetscOptionError with a one-line message, or accepted (never another exception)."""
    from fenics_garment.petsc_options import OPTIONS, PetscOptionError, check_options

    values = EXTREMES + WRONG_TYPES + ["", "lu", "newtonls", -(2**40), 2**40, 0.5, 3]
    seen = {"ok": 0, "error": 0}
    for key in [*OPTIONS, "mat_mumps_icntl_14", "mat_mumps_cntl_1", "snes_typo", "-snes_type"]:
        for value in values:
            try:
                check_options({key: value})
                seen["ok"] += 1
            except PetscOptionError as err:
                assert len(str(err)) > 20 and "\n" not in str(err), repr(err)
                seen["error"] += 1
    assert seen["error"] > 300 and seen["ok"] > 30


# -- checkpoint corruption (issue 18) ---------------------------------------------------------
@pytest.fixture(scope="module")
def checkpointed(tmp_path_factory):
    """A finished small-tube run (its last checkpoint kept) and its built scene."""
    from test_reliability import small_tube

    from fenics_garment.scene.run import run

    result = run(small_tube(output={"vtx": False}), tmp_path_factory.mktemp("ck"), quiet=True)
    return result


def test_corrupted_checkpoints(checkpointed, tmp_path):
    """Byte flips and truncations of progress.json and of the rank file: a ResumeError with a
    message, or a checkpoint that loads (never another exception)."""
    from fenics_garment.scene import checkpoint

    src = checkpointed.folder
    scene = config.load(src / "scene_used.toml")
    folder = tmp_path / "run"
    shutil.copytree(src / "checkpoint", folder / "checkpoint")
    meta_path = folder / "checkpoint" / "progress.json"
    (rank_file,) = (folder / "checkpoint").glob("state-*.r0.npz")
    originals = {meta_path: meta_path.read_bytes(), rank_file: rank_file.read_bytes()}
    rng = random.Random(18)
    errors = 0
    for i in range(80):
        target = meta_path if i % 2 else rank_file
        for p, data in originals.items():
            p.write_bytes(data)
        b = bytearray(originals[target])
        if i % 4 < 2:
            b = b[: rng.randrange(len(b))]
        else:
            for _ in range(rng.randint(1, 8)):
                b[rng.randrange(len(b))] = rng.randrange(256)
        target.write_bytes(bytes(b))
        try:
            meta = checkpoint.read(folder, scene, MPI.COMM_WORLD)
            checkpoint.restore(checkpointed.built, folder, meta)
        except checkpoint.ResumeError as err:
            assert len(str(err)) > 20 and "\n" not in str(err), repr(err)
            errors += 1
    assert errors >= 40
