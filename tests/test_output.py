"""Output helpers: comfort bands, area-weighted statistics, atomic files (no DOLFINx needed)."""

import json

import numpy as np
import pytest

from fenics_garment import output, units


@pytest.mark.parametrize(
    "kpa, band",
    [(0.1, "negligible"), (0.4, "comfortable"), (1.29, "comfortable"),
     (1.5, "critical for casual wear"), (2.5, "medical/shapewear"), (3.3, "critical")],
)  # fmt: skip
def test_comfort_bands(kpa, band):
    assert output.comfort_band(kpa) == band


def test_weighted_percentile_counts_area():
    # 90 % of the area at 1 kPa (cumulative midpoint 45 %), 10 % at 5 kPa (midpoint 95 %):
    # p95 is 5, p45 and below 1, in between linear (p80 = 1 + 4·35/50)
    p = np.array([5.0, 1.0])
    a = np.array([0.1, 0.9])
    assert output.weighted_percentile(p, a, 95) == pytest.approx(5.0)
    assert output.weighted_percentile(p, a, 30) == pytest.approx(1.0)
    assert output.weighted_percentile(p, a, 80) == pytest.approx(3.8)


@pytest.mark.parametrize("n", [8, 40, 300])
def test_weighted_percentile_of_a_sampled_field(n):
    """p(x) = x on [0, 1] sampled on n unequal cells (value at the cell middle, weight its
    length): the area-weighted p95 of the field is exactly 0.95, and the interpolated estimate
    gets it to round-off for any n once 95 % lies below the last cell's middle (the step
    definition is off by up to a cell length)."""
    inner = np.random.default_rng(n).random(n - 2) * 0.9
    edges = np.sort(np.r_[0.0, inner, 0.9, 1.0])
    mid, w = 0.5 * (edges[1:] + edges[:-1]), np.diff(edges)
    assert output.weighted_percentile(mid, w, 95) == pytest.approx(0.95, abs=1e-12)


def test_region_table_hand_computed():
    regions = {"waist": 7, "bust": 4}
    region = np.array([7, 7, 7, 4])
    p = np.array([1000.0, 3000.0, 0.0, 500.0])  # the 0-pressure point is not in contact
    a = np.array([1.0, 1.0, 5.0, 2.0]) * 1e-4
    rows = {r["region"]: r for r in output.region_table(regions, region, p, a)}
    w = rows["waist"]
    assert w["contact_area_m2"] == pytest.approx(2e-4)
    assert w["force_N"] == pytest.approx(0.1 + 0.3)  # 1000 Pa × 1 cm² + 3000 Pa × 1 cm²
    assert w["mean_kPa"] == pytest.approx(2.0)
    assert w["max_kPa"] == pytest.approx(3.0)
    assert w["mean_mmHg"] == pytest.approx(2000.0 / units.MMHG)
    assert w["comfort"] == "medical/shapewear"  # p95 = 3 kPa, in 2.0–3.3
    assert rows["bust"]["mean_kPa"] == pytest.approx(0.5)
    assert list(rows) == ["bust", "waist"]  # ordered by region number


def test_atomic_write_leaves_no_partial_file(tmp_path):
    path = tmp_path / "summary.json"
    output.write_text(path, json.dumps({"a": 1}))
    assert json.loads(path.read_text()) == {"a": 1}

    def broken(tmp):
        tmp.write_text("half")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError):
        output.atomic_write(path, broken)
    assert json.loads(path.read_text()) == {"a": 1}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["summary.json"]


def test_csv_has_units_in_header():
    rows = output.region_table({"hips": 10}, np.array([10]), np.array([200.0]), np.array([1.0]))
    head = output.csv_text(rows).splitlines()[0].split(",")
    assert {"region", "mean_kPa", "p95_mmHg", "max_kPa", "contact_area_m2", "comfort"} <= set(head)


def test_sensor_reading_is_the_force_over_the_area_within_its_radius():
    """A plane grid of points, pressure p(x) = 1000 + 2000 x: a round sensor of radius R centred
    anywhere in the interior reads the mean over its disc, the value at its centre (linear p),
    and a point outside every ball reads the points it covers."""
    h = 1e-3
    g = np.arange(-50, 51) * h
    x = np.array([[a, b, 0.0] for a in g for b in g])
    a = np.full(len(x), h * h)
    p = 1000.0 + 2000.0 * x[:, 0]
    centres = np.array([[0.0, 0.0, 0.0], [20 * h, -10 * h, 0.0]])
    radius = 10.5 * h  # no grid point at exactly the radius
    got = output.sensor_pressure(centres, x, p * a, a, radius)
    assert got == pytest.approx(1000.0 + 2000.0 * centres[:, 0], rel=1e-9)
    # 1 kPa under the half disc x > 0 (the line x = 0 not pressed): the pressed share
    step = np.where(x[:, 0] > 0, 1000.0, 0.0)
    disc = np.linalg.norm(x - centres[0], axis=1) < radius
    share = np.sum(disc & (x[:, 0] > 0)) / np.sum(disc)
    assert output.sensor_pressure(centres[:1], x, step * a, a, radius)[0] == pytest.approx(
        1000.0 * share, rel=1e-12
    )
    assert 0.45 < share < 0.5


def test_region_table_sensor_p95_is_the_percentile_of_the_readings():
    regions = {"waist": 7}
    region = np.full(100, 7)
    p = np.linspace(100.0, 1000.0, 100)
    a = np.full(100, 1e-4)
    (row,) = output.region_table(regions, region, p, a, sensor=np.full(100, 400.0))
    assert row["sensor_p95_kPa"] == pytest.approx(0.4)
    assert row["p95_kPa"] == pytest.approx(output.weighted_percentile(p, a, 95) / 1e3)


def test_body_sensors_read_the_pressure_where_they_lie_and_only_under_a_pressed_garment():
    # garment points on a 1 mm grid of the plane z = 0, pressure 1 kPa + 2 kPa/m · x for x < 0.03
    # and 0 beyond; body "triangles" of two regions with centres on a 5 mm grid and area 1 cm²
    h = 1e-3
    g = np.arange(-50, 51) * h
    x = np.array([[a, b, 0.0] for a in g for b in g])
    a = np.full(len(x), h * h)
    p = np.where(x[:, 0] < 0.03, 1000.0 + 2000.0 * x[:, 0], 0.0)
    c = np.array([[u, v, 0.0] for u in np.arange(-0.1, 0.1001, 0.005) for v in (0.0, 0.02)])
    region = np.where(c[:, 1] > 0.01, 2, 1).astype(np.int32)
    weight = np.full(len(c), 1e-4)
    radius = 10.5 * h
    reg, reading, area = output.body_sensors(c, region, weight, x, p * a, a, radius)
    # the garment spans x = −0.05 … 0.05, its pressed points x = −0.05 … 0.029: a sensor counts
    # where the garment covers at least half its pad (centre at x ≥ −0.05; the one at −0.055
    # has garment points within its radius but is mostly bare) and a pressed point is within it
    kept = c[(c[:, 0] >= -0.05) & (c[:, 0] <= 0.029 + radius)]
    assert len(reading) == len(kept) and np.all(reading > 0) and np.all(area == 1e-4)
    inside = (kept[:, 0] >= -0.05 + radius) & (kept[:, 0] <= 0.029 - radius)
    lin = 1000.0 + 2000.0 * kept[:, 0]  # the mean of a linear field over a disc: its centre value
    assert reading[inside] == pytest.approx(lin[inside], rel=1e-9)
    assert set(reg.tolist()) == {1, 2}
    (r1, _) = output.region_table({"a": 1, "b": 2}, np.array([1]), np.array([1.0]),
                                   np.array([1.0]), body=(reg, reading, area))  # fmt: skip
    assert r1["body_sensor_p95_kPa"] == pytest.approx(
        output.weighted_percentile(reading[reg == 1], area[reg == 1], 95.0) / 1e3
    )
