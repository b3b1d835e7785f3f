"""The benchmarks reuse a stored run only if it was dressed along the scene's current path."""

from benchmarks import convergence


def test_a_record_of_other_grow_steps_is_not_reused():
    dress = convergence.config_steps("cotton_dress")
    rec = {"schedule": "fixed", "grow_steps": dress}
    assert convergence.same_path(rec, "cotton_dress", "default")
    assert not convergence.same_path(rec | {"grow_steps": dress + 1}, "cotton_dress", "default")
    assert not convergence.same_path(rec | {"schedule": "adaptive"}, "cotton_dress", "default")
    # a variant's steps-N overrides the scene's
    assert convergence.same_path(rec | {"grow_steps": 8}, "cotton_dress", "steps-8")


def test_records_made_before_grow_steps_were_recorded_count_as_four():
    old = {"schedule": "fixed"}
    for stem in ("cotton_gilet", "cotton_dress"):
        assert convergence.same_path(old, stem, "default") == (
            convergence.config_steps(stem) == convergence.LEGACY_GROW_STEPS
        )
