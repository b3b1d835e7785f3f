"""Least-squares error analysis (``scene.error_bars.least_squares``, after Eça & Hoekstra 2014) on
sequences with a known limit, exact and with noise."""

import numpy as np
import pytest

from fenics_garment.scene.error_bars import least_squares

#: Five levels of ratio √2, as in the convergence study of the garment scenes.
SIZES = [0.035 * 2 ** (-k / 2) for k in range(5)]


@pytest.mark.parametrize("p", [1.0, 2.0])
def test_exact_data_recover_order_limit_and_the_safety_factor(p):
    qs = [1.0 + 3.0 * h**p for h in SIZES]
    ls = least_squares(SIZES, qs)
    assert ls.order == pytest.approx(p, abs=2e-3)
    assert ls.extrapolated == pytest.approx(1.0, rel=1e-6)
    assert ls.sigma == pytest.approx(0.0, abs=1e-9)
    for q, e in zip(qs, ls.error, strict=True):  # U = 1.25 |ε| when the fit is exact
        assert e == pytest.approx(1.25 * (q - 1.0), rel=1e-3)


def test_an_order_outside_the_trusted_range_takes_a_fixed_order_fit_and_factor_three():
    qs = [1.0 + 4e4 * h**3 for h in SIZES]  # p = 3 ≥ 2.1
    ls = least_squares(SIZES, qs)
    assert ls.order == pytest.approx(3.0, abs=2e-3)
    assert ls.fit in ("h", "h^2", "h+h^2") and ls.safety == 3.0
    assert ls.error[-1] >= abs(qs[-1] - 1.0)


def test_constant_data_have_no_error_and_too_few_levels_are_refused():
    assert least_squares(SIZES, [0.5] * 5).error == (0.0,) * 5
    with pytest.raises(ValueError, match="≥ 4 levels"):
        least_squares(SIZES[:3], [1.0, 1.1, 1.2])


@pytest.mark.parametrize("p", [1.0, 2.0])
def test_the_bar_covers_the_true_error_of_noisy_data_mostly(p):
    # 2 % error on the finest mesh, noise of standard deviation 0.25 % of the limit on every
    # level (of the order the mesh-noise benchmark measures on the gilets at 12.4 mm): over many
    # draws the finest level's bar covers its true error in most (benchmarks.estimators measures
    # the coverage over a grid of such cases)
    rng = np.random.default_rng(7)
    c = 0.02 / SIZES[-1] ** p
    covered = 0
    for _ in range(200):
        qs = [1.0 + c * h**p + 0.0025 * rng.standard_normal() for h in SIZES]
        covered += abs(qs[-1] - 1.0) <= least_squares(SIZES, qs).error[-1]
    assert covered / 200 >= {1.0: 0.7, 2.0: 0.9}[p]
