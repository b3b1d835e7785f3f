"""Stress: the whole load in one step (8× the step the benchmarks use).

The load stepper must recover by cutting the step — more steps accepted than the one asked for —
and still reach the published answers: Sze, Liu & Lo (2004) §3.1 cantilever under end shear
(w_tip = 6.698, −u_tip = 3.286 at P = 4) and §3.2 roll-up into a closed circle (the elastica's
tip travel, 12 at M_max). Measured: both cut 1 → 1/8 and accept 8 steps (60 / 113 Newton its),
errors −0.04 % and +0.30 %.
"""

import pytest

from fenics_garment.verification import shells


@pytest.mark.stress
@pytest.mark.slow  # nightly: `make test-slow` (also in .ci/run)
@pytest.mark.parametrize(
    "case, tol",
    [(shells.cantilever_end_shear, 0.005), (shells.cantilever_rollup, 0.005)],
    ids=["sze-3.1", "sze-3.2"],
)
def test_one_step_for_the_whole_load_recovers(case, tol):
    r = case(n=16, steps=1)
    print(f"\n{r.case}: {r.steps} steps accepted, {r.newton_its} Newton its, "
          f"error {r.rel_error:+.3%}")  # fmt: skip
    assert r.steps > 1  # the single step was cut
    assert abs(r.rel_error) < tol
