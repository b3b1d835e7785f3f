"""NonlinearSolver / LoadStepper behaviour (no timings: speed is measured in ``benchmarks/``)."""

from types import SimpleNamespace

import pytest

from fenics_garment.solve import LoadStepper, is_symmetric
from fenics_garment.verification import shells


def test_symmetry_rule():
    assert is_symmetric(SimpleNamespace(_follower=[], _extra_residual=[]))
    assert not is_symmetric(SimpleNamespace(_follower=[1.0], _extra_residual=[]))
    assert not is_symmetric(SimpleNamespace(_follower=[], _extra_residual=["contact"]))
    assert not is_symmetric(SimpleNamespace())  # unknown models: LU


def test_unknown_predictor_rejected():
    with pytest.raises(ValueError, match="predictor"):
        LoadStepper(solver=None, predictor="quadratic")._predictor_kind()


def _bench():
    # benchmarks/ is in the source tree only: the Docker image runs the tests against the
    # installed package from another folder, where this test is skipped (and says why)
    return pytest.importorskip("benchmarks.shells", reason="needs the source tree's benchmarks/")


def _cantilever(settings):
    created = []
    with _bench().configured(settings, created):
        res = shells.cantilever_end_shear(8, steps=4)
    return res, created[-1]


def test_predictors_and_loose_steps_reach_the_same_state():
    """Tangent predictor + loose intermediate steps + LDLᵀ give the baseline's final state."""
    SolverSettings = _bench().SolverSettings
    new, solver = _cantilever(SolverSettings("direct"))
    old, old_solver = _cantilever(
        SolverSettings(
            "baseline",
            petsc_options={"pc_type": "lu"},
            stepper={"predictor": "secant", "intermediate_rtol": None},
        )
    )
    assert new.value == pytest.approx(old.value, rel=1e-8)
    assert solver.options["pc_type"] == "cholesky"
    assert old_solver.options["pc_type"] == "lu"
    tm = solver.timings
    # one Jacobian per Newton iteration; homogeneous BCs are met by every iterate: no lifting
    assert tm.jacobian_evaluations == tm.newton_iterations
    assert tm.liftings == 0
    assert tm.newton_iterations <= old_solver.timings.newton_iterations
