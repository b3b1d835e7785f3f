"""Capstan (Euler–Eytelwein): a strip over a rigid cylinder, T_pulled/T_held = e^{μθ} at slip."""

from fenics_garment._stack import MPI  # noqa: I001

import numpy as np

import contact_models as cm


def test_capstan_stick_then_slip():
    mu, theta = 0.4, np.pi / 2
    scene = cm.capstan_strip(MPI.COMM_WORLD, mu=mu, theta=theta)
    st = scene.state
    its, reason = scene.problem.solve()
    assert reason > 0
    st.accept_step()
    t0, _ = cm.end_tensions(scene)
    limit = np.exp(mu * theta)
    history = []
    for delta in np.arange(1, 13) * 2.5e-4:  # pull end B by up to 3 mm
        scene.extra["delta"].value = -delta
        its, reason = scene.problem.solve()
        assert reason > 0, (delta, its, reason)
        st.accept_step()
        ta, tb = cm.end_tensions(scene)
        history.append((delta, ta, tb, its))
    print(f"\ne^(μθ) = {limit:.5f};  δ [mm], T_held [N], T_pulled [N], ratio, Newton its")
    for delta, ta, tb, its in history:
        print(f"{1e3 * delta:5.2f} {ta:.5f} {tb:.5f} {tb / ta:.5f} {its}")
    stick = [(ta, tb) for _, ta, tb, _ in history if tb / ta < 0.99 * limit]
    slip = [(ta, tb) for _, ta, tb, _ in history if ta > 1.01 * t0]
    assert len(stick) >= 4 and len(slip) >= 3
    # below the capstan ratio, the held side sticks: its tension does not change
    for ta, tb in stick:
        assert abs(ta / t0 - 1) < 1e-3 and tb / ta < limit
    # once the held end's tension rises the whole wrap slips: T_pulled/T_held = e^{μθ}
    for ta, tb in slip:
        assert abs(tb / ta / limit - 1) < 0.02
