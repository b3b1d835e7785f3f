"""Three-level error analysis (``scene.error_bars.three_level``) on sequences with a known limit."""

import math

import pytest

from fenics_garment.scene.error_bars import three_level


@pytest.mark.parametrize("p", [1.0, 2.0])
def test_monotone_sequence_recovers_order_and_limit(p):
    # Q_h = Q + C h^p exactly: the observed order is p and the extrapolation is Q
    hs = [0.04, 0.04 / math.sqrt(2), 0.02]
    qs = [1.0 + 3.0 * h**p for h in hs]
    c = three_level(hs, qs)
    assert c.order == pytest.approx(p, rel=1e-9)
    assert c.extrapolated == pytest.approx(1.0, rel=1e-9)
    for q, e in zip(qs, c.error, strict=True):  # every bar covers the true error
        assert abs(q - 1.0) <= e <= 2.0 * abs(q - 1.0) + 1e-12


def test_oscillating_sequence_gets_three_times_its_range():
    c = three_level([0.035, 0.0247, 0.0175], [0.318, 0.306, 0.312])
    assert math.isnan(c.order) and c.extrapolated == 0.312
    assert c.error[-1] == pytest.approx(3 * (0.318 - 0.306))
