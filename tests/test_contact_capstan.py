"""Capstan (Euler–Eytelwein) on the shell: T_pulled/T_held = e^{μθ} at slip, stick below it.

A ν = 0 shell strip over a rigid cylinder by θ = π/2 (verification/contact.py ``capstan_strip``):
first pre-tensioned without friction, then, with μ = 0.4, its end B pulled further in small
steps. The held tail's tension must not change while the wrap sticks (ratio < e^{μθ}); once it
rises, the whole wrap slips and the ratio is the capstan ratio (Euler 1762; Eytelwein 1808;
e.g. Johnson, "Contact Mechanics", 1985, §7.2 for the belt-friction derivation).
Measured: ratio at slip 1.87472–1.87500 vs 1.87446 (+0.01 … +0.03 %), 7–11 Newton iterations
per step.
"""

from fenics_garment._stack import MPI  # noqa: I001

import numpy as np
import pytest

from fenics_garment.verification import contact as cases


@pytest.mark.slow  # nightly: `make test-slow` (also in .ci/run)
def test_capstan_stick_then_slip():
    mu, theta = 0.4, np.pi / 2
    sc = cases.capstan_strip(MPI.COMM_WORLD, mu=mu, theta=theta)
    friction = sc.contact.friction.mu
    friction.value = 0.0
    total = 2 * sc.extra["tail"] + sc.extra["rho"] * theta
    d0 = 0.02 * total  # pre-tension: 2 % stretch, frictionless
    for f in (0.5, 1.0):
        sc.extra["delta"].value = -f * d0
        its, reason = sc.solver.solve()
        assert reason > 0, (f, its, reason)
        sc.contact.accept_step()
    t0, tb0 = cases.tail_tensions(sc)
    # frictionless: one uniform tension, that of the uniaxial SVK strip at stretch 1 + d0/total
    lam = 1 + d0 / total
    assert abs(tb0 / t0 - 1) < 1e-3
    assert t0 == pytest.approx(lam * sc.extra["EA"] * (lam**2 - 1) / 2, rel=5e-3)
    friction.value = mu
    limit = sc.reference
    assert limit == np.exp(mu * theta)
    history = []
    for k in range(1, 13):  # pull end B by up to 3 mm more
        sc.extra["delta"].value = -(d0 + k * 2.5e-4)
        its, reason = sc.solver.solve()
        assert reason > 0, (k, its, reason)
        sc.contact.accept_step()
        ta, tb = cases.tail_tensions(sc)
        history.append((k, ta, tb, its))
    print(f"\ne^(μθ) = {limit:.5f};  step, T_held [N], T_pulled [N], ratio, Newton its")
    for k, ta, tb, its in history:
        print(f"{k:3d} {ta:.5f} {tb:.5f} {tb / ta:.5f} {its}")
    stick = [(ta, tb) for _, ta, tb, _ in history if tb / ta < 0.99 * limit]
    slip = [(ta, tb) for _, ta, tb, _ in history if ta > 1.01 * t0]
    assert len(stick) >= 4 and len(slip) >= 3
    for ta, tb in stick:  # the held side sticks: its tension does not change
        assert abs(ta / t0 - 1) < 1e-3 and tb / ta < limit
    for ta, tb in slip:  # the whole wrap slips at the capstan ratio
        assert abs(tb / ta / limit - 1) < 0.005
