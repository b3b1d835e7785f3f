"""Virtual sensors at anatomical points (fenics_garment.sensors): placement on the body's
surface at its landmark heights and facing, the reading against Laplace's law on the tube, and
the clean skip on a body without landmarks."""

import csv
import json
import tempfile
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from fenics_garment import sensors
from fenics_garment._stack import MPI
from fenics_garment.geometry.mannequin import MeshSizes, make_mannequin
from fenics_garment.scene import config
from fenics_garment.scene.run import gathered_points, run
from fenics_garment.verification.contact import tube_pressure

TUBE = Path(__file__).parent.parent / "demos" / "tube_on_cylinder.toml"


@pytest.fixture(scope="module")
def body():
    return make_mannequin(sizes=MeshSizes(coarse=0.04, fine=0.04), legs=False)


def _segment_distance(q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", q - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
    return np.linalg.norm(q - (a + t[:, None] * ab), axis=1)


def _distance_to_triangles(q: np.ndarray, tri: np.ndarray) -> float:
    """The distance of point q to the nearest of the triangles (m, 3, 3): inside a triangle's
    projection its plane's distance, else the nearest edge's."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1)[:, None]
    h = np.einsum("ij,ij->i", q - a, n)
    f = q - h[:, None] * n  # the foot on each plane
    inside = np.ones(len(tri), bool)
    for u, w in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ij,ij->i", np.cross(w - u, f - u), n) >= -1e-15
    edges = np.minimum.reduce([_segment_distance(q, u, w) for u, w in ((a, b), (b, c), (c, a))])
    return float(np.where(inside, np.abs(h), edges).min())


def test_sensors_lie_on_the_surface_at_their_landmarks_and_facing(body):
    placed = sensors.place(body)
    assert placed.missing == {} and set(placed.centres) == set(sensors.SITES)
    c = placed.centres
    tri = body.vertices[body.triangles]
    dist = [_distance_to_triangles(q, tri) for q in c.values()]
    assert max(dist) < 1e-9  # on the surface (brute-force point-to-triangle distance)
    for name, (level, _) in sensors.SITES.items():
        if name != "shoulder":
            assert c[name][2] == pytest.approx(body.landmarks[level], abs=1e-12), name
    # the shoulder sensor is on top of the shoulder, above the shoulder level, below the neck
    assert body.landmarks["shoulder"] <= c["shoulder"][2] < body.landmarks["neck_base"]
    v = body.vertices

    def extent(z: float) -> np.ndarray:  # the body's (min, max) of x and y near height z
        near = v[np.abs(v[:, 2] - z) < 0.03]
        return near[:, :2].min(axis=0), near[:, :2].max(axis=0)

    # front = −y (the body faces −y), back = +y, left side = +x
    for name in ("waist_front", "underbust_front", "abdomen"):
        lo, hi = extent(c[name][2])
        assert c[name][1] < 0 and abs(c[name][0]) < 1e-9, name
        assert c[name][1] < lo[1] + 0.1 * (hi[1] - lo[1]), name  # the front, not the middle
    lo, hi = extent(c["waist_back"][2])
    assert c["waist_back"][1] > hi[1] - 0.1 * (hi[1] - lo[1])
    for name in ("waist_side", "underbust_side", "hip"):
        lo, hi = extent(c[name][2])
        assert c[name][0] > hi[0] - 0.1 * (hi[0] - lo[0]), name
        assert abs(c[name][1]) < 0.25 * (hi[1] - lo[1]), name
    assert c["bust_left"][0] > 0 > c["bust_right"][0]
    assert c["bust_left"][1] < 0 and c["bust_right"][1] < 0
    assert c["scapula"][0] > 0 and c["scapula"][1] > 0
    assert c["shoulder"][0] > 0


def test_reading_is_force_over_area_within_the_pad():
    """A plane grid of points with pressure p: a pad well inside reads p with cover ≈ 1; a pad
    beyond the grid's edge by half its radius reads p and is marked as covered in part (the
    garment reaches past its rim on one side only)."""
    h = 1e-3
    g = np.arange(-0.05, 0.05 + h / 2, h)
    X, Y = np.meshgrid(g, g)
    keep = X.ravel() <= 1e-12
    x = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])[keep]
    area = np.full(len(x), h * h)
    p = 3000.0
    centres = {"in": np.array([-0.03, 0.0, 0.0]), "edge": np.array([0.005, 0.0, 0.0])}
    rows = sensors.read(centres, x, p * area, area, 0.02, "ami")
    a, e = rows
    assert a["reading_kPa"] == pytest.approx(3.0, rel=1e-12)
    assert a["reading_mmHg"] == pytest.approx(3000.0 / 133.322387415, rel=1e-9)
    assert a["cover"] == pytest.approx(1.0, rel=0.02) and a["covered"]
    assert e["reading_kPa"] == pytest.approx(3.0, rel=1e-12)
    assert e["points"] > 0 and e["cover"] <= 5 / 8  # the garment on one side only
    assert not e["covered"]


def test_a_pad_off_the_garment_is_listed_apart():
    """A pad 1 m from the garment (a torso sensor under a stocking) holds no garment point: the
    run's table lists it apart, not as a reading of 0 kPa."""
    from fenics_garment.scene.run import _print_sensors

    x = np.array([[0.0, 0.0, 0.0], [1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0]])
    area = np.full(3, 1e-6)
    centres = {"ankle": np.zeros(3), "bust_left": np.array([0.0, 0.0, 1.0])}
    rows = sensors.read(centres, x, 1e3 * area, area, 0.02, "ami")
    assert [r["points"] for r in rows] == [3, 0]
    lines: list[str] = []
    _print_sensors(lines.append, {"sensors": rows})
    assert any(ln.split()[0] == "ankle" for ln in lines)
    assert not any(ln.split()[0] == "bust_left" for ln in lines)
    assert lines[-1].strip().startswith("sensors with no garment within 10 mm")
    assert lines[-1].strip().endswith(": bust_left")


def test_instruments():
    assert sensors.diameter_of("ami") == 0.020 and sensors.diameter_of("picopress") == 0.050
    with pytest.raises(ValueError, match="unknown sensor instrument"):
        sensors.diameter_of("kikuhime")


def test_one_sensor_for_the_regions_and_the_anatomical_points():
    """``[output] sensor_instrument`` sets the pad of both the regions' sensor p95 and the
    sensors at anatomical points; ``sensor_diameter`` (0: the instrument's) another pad size."""
    out = config.OutputConfig()
    assert sensors.pad(out) == ("ami", 0.020)
    assert sensors.pad(replace(out, sensor_instrument="picopress")) == ("picopress", 0.050)
    assert sensors.pad(replace(out, sensor_diameter=0.020)) == ("ami", 0.020)
    assert sensors.pad(replace(out, sensor_diameter=0.030)) == ("ami, 30 mm pad", 0.030)


def test_unknown_instrument_is_refused(tmp_path):
    text = TUBE.read_text() + '\n[output]\nsensor_instrument = "picopres"\n'
    if "[output]" in TUBE.read_text():
        text = TUBE.read_text().replace("[output]", '[output]\nsensor_instrument = "picopres"')
    f = tmp_path / "s.toml"
    f.write_text(text)
    with pytest.raises(Exception, match="picopress"):
        config.load(f)


def test_cylinder_is_skipped():
    with pytest.raises(sensors.NoLandmarks, match="no anatomical landmarks"):
        sensors.place(SimpleNamespace(landmarks={}))


@pytest.fixture(scope="module")
def tube():
    comm = MPI.COMM_WORLD
    folder = Path(comm.bcast(tempfile.mkdtemp() if comm.rank == 0 else None, root=0))
    s = config.load(TUBE)
    s = replace(s, garment=replace(s.garment, mesh_size=0.04))
    return run(s, folder, quiet=True)


@pytest.mark.parametrize("instrument", ["ami", "picopress"])
def test_sensor_on_the_laplace_tube_reads_t_over_r(tube, instrument):
    """A pad on the cylinder half-way up the tube reads Laplace's p = T/R (the hoop tension of
    the tube stretched to the body's radius, verification.contact.tube_pressure)."""
    b = tube.built
    p, a, x = gathered_points(b)
    R = b.scene.body.radius
    s = b.model.stiffness
    z_mid = 0.5 * (x[:, 2].min() + x[:, 2].max())
    analytic = tube_pressure(R + s.thickness / 2, R + b.garment.level("mid").clearance, s,
                             warp="axial")  # fmt: skip
    for phi in (0.0, 2.0):
        centre = {"pad": np.array([R * np.cos(phi), R * np.sin(phi), z_mid])}
        (row,) = sensors.read(centre, x, p * a, a, sensors.diameter_of(instrument), instrument)
        assert row["covered"]
        assert row["reading_kPa"] * 1e3 == pytest.approx(analytic, rel=0.01), (phi, analytic)


def test_tube_run_reports_sensors_skipped(tube):
    assert tube.summary["sensors"] == []
    assert "no anatomical landmarks" in tube.summary["sensors_skipped"]
    summary = json.loads((tube.folder / "summary.json").read_text())
    assert "no anatomical landmarks" in summary["sensors_skipped"]
    assert not (tube.folder / "pressure_sensors.csv").exists()


def test_sensor_csv_columns(tmp_path):
    from fenics_garment import output

    rows = sensors.read({"a": np.zeros(3)}, np.zeros((1, 3)), np.ones(1), np.ones(1), 0.02, "ami")
    output.write_text(tmp_path / "s.csv", output.csv_text(rows))
    (r,) = list(csv.DictReader((tmp_path / "s.csv").open()))
    assert {"sensor", "x_m", "y_m", "z_m", "diameter_m", "reading_kPa", "reading_mmHg"} <= set(r)


@pytest.mark.slow
def test_gilet_run_reports_its_sensors():
    """The cotton gilet on the mannequin (4 cm cells, about a minute): every sensor placed and
    read, in summary.json and pressure_sensors.csv, the pads under the gilet covered."""
    comm = MPI.COMM_WORLD
    folder = Path(comm.bcast(tempfile.mkdtemp() if comm.rank == 0 else None, root=0))
    s = config.load(Path(__file__).parent.parent / "demos" / "cotton_gilet.toml")
    res = run(replace(s, garment=replace(s.garment, mesh_size=0.04)), folder, quiet=True)
    assert res.completed and "sensors_skipped" not in res.summary
    rows = res.summary["sensors"]
    assert [r["sensor"] for r in rows] == list(sensors.SITES)
    assert all(r["covered"] and r["diameter_m"] == 0.02 for r in rows)
    assert all(0 <= r["force_N"] <= res.summary["contact_force_N"] for r in rows)
    assert max(r["reading_kPa"] for r in rows) > 0.1  # the gilet presses at the bust and waist
    if comm.rank == 0:
        got = list(csv.DictReader((res.folder / "pressure_sensors.csv").open()))
        assert [r["sensor"] for r in got] == list(sensors.SITES)
        for a, b in zip(got, rows, strict=True):
            assert float(a["reading_kPa"]) == pytest.approx(b["reading_kPa"], rel=1e-5)
        assert json.loads((res.folder / "summary.json").read_text())["sensors"][0]["sensor"] == (
            "bust_left"
        )
