"""The HTML report of a run (``fenics_garment.report``), built from a synthetic run folder: its
sections, the checks as in summary.json, the data inlined, nothing fetched from the network;
the decimation of the 3D view's surfaces; ``fenics-garment report FOLDER``."""

import base64
import json
import re
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

from fenics_garment.cli import main
from fenics_garment.report import REPORT_FILE, Surface, build_html, write_surfaces
from fenics_garment.report.page import check_status
from fenics_garment.report.surfaces import decimate, read_surfaces


def _png(path: Path, w: int = 4, h: int = 3) -> bytes:
    """A tiny valid RGB PNG (no image library)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data))
            + kind
            + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
        )

    raw = b"".join(b"\x00" + b"".join(bytes([40 * x, 60 * y, 200]) for x in range(w))
                   for y in range(h))  # fmt: skip
    data = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))  # fmt: skip
    path.write_bytes(data)
    return data


def _sphere(n: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """A UV sphere of radius 0.1 m: (vertices, triangles)."""
    theta = np.linspace(0, np.pi, n + 1)[1:-1]
    phi = np.linspace(0, 2 * np.pi, 2 * n, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    v = 0.1 * np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1).reshape(-1, 3)
    v = np.vstack([v, [[0, 0, 0.1], [0, 0, -0.1]]])
    m = 2 * n
    tri = []
    for i in range(len(theta) - 1):
        for j in range(m):
            a, b = i * m + j, i * m + (j + 1) % m
            tri += [[a, a + m, b], [b, a + m, b + m]]
    top, bottom = len(v) - 2, len(v) - 1
    last = (len(theta) - 1) * m
    tri += [[top, j, (j + 1) % m] for j in range(m)]
    tri += [[bottom, last + (j + 1) % m, last + j] for j in range(m)]
    return v, np.array(tri)


CHECKS = {
    "penetration": {"name": "penetration", "value": 0.2, "limit": 1.0, "what": "pen", "ok": True},
    "spring": {"name": "spring", "value": 0.009, "limit": 0.01, "what": "spring", "ok": True},
    "force_balance": {"name": "force_balance", "value": 0.05, "limit": 0.02, "what": "fb",
                      "ok": False},
    "contact_area": {"name": "contact_area", "value": None, "limit": 0.5, "what": "area",
                     "ok": True},
}  # fmt: skip


def _summary() -> dict:
    region = {"region": "torso", "contact_area_m2": 0.05, "force_N": 40.0, "mean_kPa": 0.8,
              "mean_mmHg": 6.0, "p95_kPa": 1.4, "p95_mmHg": 10.5, "max_kPa": 2.1,
              "max_mmHg": 15.7, "sensor_p95_kPa": 1.2, "sensor_p95_mmHg": 9.0,
              "p95_err_kPa": 0.15, "comfort": "critical for casual wear",
              "comfort_range": "comfortable – critical for casual wear"}  # fmt: skip
    free = {"region": "arm", "contact_area_m2": 0.0, "force_N": 0.0, "mean_kPa": 0.0,
            "p95_kPa": 0.0, "max_kPa": 0.0, "comfort": "negligible"}  # fmt: skip
    steps = [{"shrink": 0.004, "iterations": 3, "reason": 2, "cuts": 0, "seconds": 0.5,
              "regularisation": 100.0, "stage": "dress", "final_ratios": [0.1, 0.01],
              "residuals": [10.0, 0.1, 1e-3, 1e-7]},
             {"shrink": 0.0, "iterations": 2, "reason": 2, "cuts": 1, "seconds": 0.4,
              "regularisation": 0.0, "stage": "release", "final_ratios": [0.01],
              "residuals": [1.0, 1e-2, 1e-6]}]  # fmt: skip
    return {
        "scene": "synthetic-scene", "completed": True, "message": "", "checks_passed": False,
        "checks": CHECKS, "garment": "gilet", "fabric": "cotton", "element": "P2B-P2B",
        "dofs": 1234, "ranks": 1, "max_pressure_kPa": 2.1, "contact_force_N": 40.0,
        "contact_area_garment_m2": 0.05, "regions": [region, free],
        "dressing": {"steps": steps, "newton_iterations": 5, "all_newton_iterations": 9,
                     "cuts": 1, "shrink0_m": 0.008,
                     "failed_attempts": [{"target_shrink_m": 0.002, "iterations": 4,
                                          "reason": -5, "residuals": [10.0, 20.0, 40.0]}]},
        "time_s": {"geometry_and_model": 1.0, "jit": 2.0, "dressing": 6.0, "outputs": 0.5,
                   "total": 9.5, "report": 0.25},
        "solver_time_s": {"residual": 1.0, "jacobian": 2.0, "solve": 3.0},
        "error_bars": {"method": "Richardson", "rate": 1.0},
        "sensors": [{"sensor": "waist_side", "x_m": 0.14, "y_m": 0.0, "z_m": 1.05,
                     "instrument": "ami", "diameter_m": 0.02, "reading_kPa": 0.731,
                     "reading_mmHg": 5.48, "force_N": 0.23, "points": 12, "cover": 1.0,
                     "covered": True},
                    {"sensor": "bust_left", "x_m": 0.09, "y_m": -0.12, "z_m": 1.2,
                     "instrument": "ami", "diameter_m": 0.02, "reading_kPa": 0.0,
                     "reading_mmHg": 0.0, "force_N": 0.0, "points": 0, "cover": 0.0,
                     "covered": False}],
    }  # fmt: skip


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    run = tmp_path / "synthetic-scene"
    run.mkdir()
    (run / "summary.json").write_text(json.dumps(_summary()))
    (run / "run.json").write_text(json.dumps({"run_id": "abc123", "status": "checks failed"}))
    (run / "scene_used.toml").write_text('name = "synthetic-scene"\n')
    _png(run / "pressure_body.png")
    _png(run / "pressure_garment.png", 5, 2)
    v, tri = _sphere()
    write_surfaces(run, Surface.of(v, tri, 1e3 * np.clip(v[:, 2] * 20, 0, None)),
                   Surface.of(1.05 * v, tri, 800.0 * np.ones(len(v))))  # fmt: skip
    return run


def test_report_has_every_section_and_inlines_its_data(folder: Path):
    html = build_html(folder)
    for anchor in ("view3d", "maps", "regions", "sensors", "checks", "dressing", "time", "files"):
        assert f'id="{anchor}"' in html, anchor
    # the sensors' readings, and the one with no garment on its pad apart
    sensors = html[html.index('id="sensors"') : html.index('id="dressing"')]
    assert "waist_side" in sensors and "0.731" in sensors and "5.48" in sensors
    assert "No garment within 10 mm of: bust_left" in sensors
    # every picture inlined byte for byte
    for name in ("pressure_body.png", "pressure_garment.png"):
        assert base64.b64encode((folder / name).read_bytes()).decode() in html
    # the 3D view's data: the surfaces as written, decoded back from the page
    data = json.loads(re.search(r'id="surface-data">(.*?)</script>', html, re.S).group(1))
    stored = read_surfaces(folder)
    for name in ("body", "garment"):
        tri = np.frombuffer(base64.b64decode(data["surfaces"][name]["triangles"]), "<u4")
        p = np.frombuffer(base64.b64decode(data["surfaces"][name]["pressure"]), "<f4")
        np.testing.assert_array_equal(tri.reshape(-1, 3), stored[name].triangles)
        np.testing.assert_array_equal(p, stored[name].pressure)
    assert data["vmax_kPa"] == pytest.approx(0.8)  # the garment's 99th percentile
    assert 'getContext("webgl"' in html  # the viewer inlined
    # offline: nothing is loaded from anywhere
    assert not re.search(r"https?://", html)
    assert not re.search(r"<(script|link|img)[^>]*(src|href)=\"(?!data:)", html)
    assert "synthetic-scene" in html and "abc123" in html and "checks failed" in html
    assert "0.15" in html  # the error bar of the region's p95
    assert "comfortable – critical for casual wear" in html


def test_checks_table_matches_summary(folder: Path):
    html = build_html(folder)
    table = re.search(r'id="checks".*?<tbody>(.*?)</tbody>', html, re.S).group(1)
    rows = re.findall(r"<tr>(.*?)</tr>", table, re.S)
    shown = {}
    for row in rows:
        cells = re.findall(r"<td[^>]*>(.*?)</td>", row, re.S)
        shown[cells[0]] = re.sub(r"<[^>]+>", "", cells[1])
    assert shown == {"penetration": "pass", "spring": "warn", "force_balance": "fail",
                     "contact_area": "n/a"}  # fmt: skip
    assert shown == {n: check_status(c) for n, c in CHECKS.items()}


def test_check_status_sides():
    assert check_status({"value": 0.79, "limit": 1.0, "ok": True}) == "pass"
    assert check_status({"value": 0.81, "limit": 1.0, "ok": True}) == "warn"
    assert check_status({"value": 1.3, "limit": 0.5, "ok": True}) == "pass"  # an at-least check
    assert check_status({"value": 0.55, "limit": 0.5, "ok": True}) == "warn"
    assert check_status({"value": 0.4, "limit": 0.5, "ok": False}) == "fail"
    assert check_status({"value": None, "limit": 0.5, "ok": False}) == "fail"  # NaN


def test_decimate_keeps_shape_and_pressure_range():
    v, tri = _sphere(80)
    p = 1e3 * (1 + v[:, 2] / 0.1)
    s = Surface.of(v, tri, p)
    small = decimate(s, 2000)
    assert 500 < len(small.triangles) <= 2000 < len(tri)
    r = np.linalg.norm(small.vertices, axis=1)
    assert r.max() <= 0.1 + 1e-6 and r.min() > 0.09  # still the sphere
    assert small.pressure.min() >= p.min() - 1e-3 and small.pressure.max() <= p.max() + 1e-3
    assert small.triangles.max() < len(small.vertices)
    assert decimate(s, len(tri)) is s


def test_cli_report_rebuilds_and_refuses_other_folders(folder: Path, capsys):
    assert main(["report", str(folder)]) == 0
    page = (folder / REPORT_FILE).read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>") and 'id="view3d"' in page
    assert str(folder / REPORT_FILE) in capsys.readouterr().out
    assert main(["report", str(folder.parent)]) == 2
    assert "no summary.json" in capsys.readouterr().err


def test_report_without_surfaces_file_reads_the_vtu(folder: Path):
    """An older run (no report_surfaces.npz): the 3D view's body comes from body_pressure.vtu."""
    import meshio

    (folder / "report_surfaces.npz").unlink()
    v, tri = _sphere(6)
    p = np.linspace(0, 500, len(v))
    meshio.write(
        folder / "body_pressure.vtu",
        meshio.Mesh(v, [("triangle", tri)], point_data={"contact_pressure": p}),
    )
    found = read_surfaces(folder)
    assert list(found) == ["body"]
    np.testing.assert_allclose(found["body"].pressure, p, rtol=1e-6)
    assert "Pressure on the body" in build_html(folder)
