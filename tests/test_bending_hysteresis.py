"""The hysteretic bending law (KES 2HB) under pure bending: the moment–curvature loop of a
loading–unloading cycle against the friction slider's closed form (issue 47, item 3)."""

import numpy as np
import pytest

from fenics_garment import measured
from fenics_garment.shell.energy import HystereticBending
from fenics_garment.verification import hysteresis


def slider_curvature(B: float, hb: float, k: float, moments: np.ndarray) -> np.ndarray:
    """κ of an elastic B in parallel with a Jenkins element (spring k, Coulomb threshold hb)
    along the path 0 → M_max → −M_max → M_max, branch by branch in closed form."""
    m_max = moments.max()
    k_top = (m_max - hb) / B  # on the slipping branch at M_max (it slips: m_max > hb (B + k)/k)
    out = []
    phase = 0  # 0: first loading, 1: unloading from the top, 2: reloading from the bottom
    for i, M in enumerate(moments):
        if i and M < moments[i - 1] and phase == 0:
            phase = 1
        if i and M > moments[i - 1] and phase == 1:
            phase = 2
        if phase == 0:
            kap = M / (B + k) if M <= hb * (B + k) / k else (M - hb) / B
        elif phase == 1:  # elastic back from (m_max, k_top) until the slider reverses
            drop = m_max - M
            kap = k_top - drop / (B + k) if drop <= 2 * hb * (B + k) / k else (M + hb) / B
        else:
            rise = M + m_max
            kap = -k_top + rise / (B + k) if rise <= 2 * hb * (B + k) / k else (M - hb) / B
        out.append(kap)
    return np.asarray(out)


def test_hysteretic_law_refuses_bad_values():
    for bad in (0.0, -1e-3, float("nan")):
        with pytest.raises(ValueError, match="2HB"):
            HystereticBending(bad)
    with pytest.raises(ValueError, match="yield curvature"):
        HystereticBending(1e-3, yield_curvature=0.0)


def test_pure_bending_loop_has_width_2HB():
    # M-A of Matsudaira et al. 2015 (data/fabrics_measured.toml): B = 0.118 gf·cm²/cm,
    # 2HB = 0.124 gf·cm/cm; ν12 = 0 so that the strip bends into an arc of κ = M / B exactly
    m = measured.by_id("M-A")
    fabric = measured.to_fabric(m, nu12=0.0)
    law = HystereticBending(m.twoHB)
    B, hb = m.B_warp, m.twoHB / 2
    k = hb / law.yield_curvature
    m_max = B * 40.0 + hb  # slips up to κ = 40 /m
    moments = hysteresis.moment_cycle(m_max, 20)
    loop = hysteresis.bending_loop(fabric, law, moments)
    ref = slider_curvature(B, hb, k, moments)
    # every point of the cycle on the slider's closed form (the strip's discretisation error of
    # pure bending: < 0.2 % of the largest curvature)
    assert np.max(np.abs(loop.curvature - ref)) < 2e-3 * 40.0
    # the KES reading: at κ = 0 and ±10 /m, both branches slip: the loop is 2HB wide
    for kappa in (-10.0, 0.0, 10.0):
        assert hysteresis.loop_width(loop, kappa) == pytest.approx(m.twoHB, rel=1e-2)
    # and the elastic law has no loop
    elastic = hysteresis.bending_loop(fabric, None, moments)
    assert abs(hysteresis.loop_width(elastic, 0.0)) < 1e-3 * m.twoHB
