"""The benchmarks reuse a stored run only if it was dressed along the scene's current path."""

import pytest

from benchmarks import convergence


def test_a_record_of_other_grow_steps_is_not_reused():
    dress = convergence.config_steps("cotton_dress")
    rec = {"schedule": "fixed", "grow_steps": dress, "body": "human"}
    assert convergence.same_path(rec, "cotton_dress", "default")
    assert not convergence.same_path(rec | {"grow_steps": dress + 1}, "cotton_dress", "default")
    assert not convergence.same_path(rec | {"schedule": "adaptive"}, "cotton_dress", "default")
    # a variant's steps-N overrides the scene's
    assert convergence.same_path(rec | {"grow_steps": 8}, "cotton_dress", "steps-8")


def test_records_made_before_grow_steps_were_recorded_count_as_four():
    old = {"schedule": "fixed", "body": "human"}
    for stem in ("cotton_gilet", "cotton_dress"):
        assert convergence.same_path(old, stem, "rest-loft") == (
            convergence.config_steps(stem) == convergence.LEGACY_GROW_STEPS
        )


def test_a_loft_record_is_not_reused_for_a_pattern_garment():
    """Records made before the rest state was recorded are of lofts (the only one then): not
    the answer of a garment made of flat pattern pieces."""
    old = {"schedule": "fixed", "grow_steps": convergence.config_steps("cotton_dress"),
           "body": "human"}  # fmt: skip
    assert convergence.same_path(old, "cotton_dress", "default")  # shipped as a loft
    assert not convergence.same_path(old, "cotton_dress", "rest-pattern")
    assert convergence.same_path(old | {"rest": "pattern"}, "cotton_dress", "rest-pattern")


def test_a_record_on_another_body_is_not_reused():
    """The dress and the gilets are shipped on the human mannequin: a record made before records
    named their body was on the dress form (the human only with the variant "human") and does
    not count as the shipped scene's; one that names its body counts on that body."""
    steps = convergence.config_steps("cotton_dress")
    old = {"schedule": "fixed", "grow_steps": steps}
    assert convergence.body_of("cotton_dress", "default") == "human"
    assert not convergence.same_path(old, "cotton_dress", "default")
    assert convergence.same_path(old | {"variant": "human"}, "cotton_dress", "human")
    assert convergence.same_path(old | {"body": "human"}, "cotton_dress", "default")
    assert not convergence.same_path(old | {"body": "dress form"}, "cotton_dress", "default")
    assert convergence.body_of("tube_on_cylinder", "default") == "cylinder"


def _noise_record(p95: float) -> dict:
    regions = dict.fromkeys(convergence.KEY_REGIONS, p95)
    return {"status": "ok", "completed": True, "dofs": 100, "regions_p95_kPa": regions,
            "regions_sensor_p95_kPa": regions, "regions_mean_kPa": regions}  # fmt: skip


def test_mesh_noise_of_identical_meshes_is_not_reported_as_zero():
    from benchmarks import mesh_noise

    ana = mesh_noise.analyse([_noise_record(0.5)] * 4)
    assert ana["identical"] and not ana["regions"]


def test_mesh_noise_is_the_sample_standard_deviation():
    from benchmarks import mesh_noise

    # values 0.9, 1.0, 1.1: mean 1, sample variance (0.01 + 0 + 0.01) / 2 = 0.01, std 0.1
    ana = mesh_noise.analyse([_noise_record(v) for v in (0.9, 1.0, 1.1)])
    c = ana["regions"]["waist"]["p95"]
    assert abs(c["rel_std"] - 0.1) < 1e-12 and abs(c["rel_range"] - 0.2) < 1e-12


def test_check_args_stops_a_mistyped_command_line(capsys):
    """A wrong option or scene name is a one-line error (exit 2), ``--help`` prints the doc and
    exits 0, and a valid line passes (``None``) — the convergence study once ran every scene
    for an hour on ``--help``."""
    from benchmarks import check_args

    names = ("cotton_gilet", "tube")
    assert check_args(["tube", "--levels", "3", "--reuse"], "doc", {"--reuse"}, {"--levels"},
                      names) is None  # fmt: skip
    assert check_args(["--help"], "the doc", names=names) == 0
    assert "the doc" in capsys.readouterr().out
    assert check_args(["--hlep"], "doc", {"--reuse"}) == 2
    assert check_args(["cotton_gillet"], "doc", names=names) == 2
    assert check_args(["--levels"], "doc", valued={"--levels"}) == 2
    assert check_args(["tube@0.02"], "doc", names=lambda a: a.partition("@")[0] in names) is None
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and all(line.startswith("error: ") for line in err)


def test_the_least_squares_verdict_of_a_study_names_the_regions_within_the_target():
    # five levels of p95 = 1 + C h² (exact): every key region's least-squares bar is 1.25 × its
    # true error, 1.25 · C h_fine²; C is chosen so that the waist's true error at the finest mesh
    # is 4 % (bar 5 %, not met) and every other region's 1 % (bar 1.25 %, met)
    hs = convergence.sizes(0.035, 5)
    runs = []
    for h in hs:
        vals = {n: 1.0 + (0.04 if n == "waist" else 0.01) * (h / hs[-1]) ** 2
                for n in convergence.KEY_REGIONS}  # fmt: skip
        runs.append({"status": "ok", "mesh_size": h, "dofs": 1, "completed": True,
                     "max_penetration_over_thickness": 0.0, "regions_p95_kPa": vals,
                     "regions_sensor_p95_kPa": vals})  # fmt: skip
    ana = convergence.analyse(runs)
    want = [n for n in convergence.KEY_REGIONS if n != "waist"]
    assert ana["key_p95_least_squares_met"] == want
    assert ana["key_sensor_p95_least_squares_met"] == want
    ls = ana["regions"]["waist"]["p95"]["least_squares"]
    assert ls["relative_error"][-1] == pytest.approx(1.25 * 0.04 / 1.04, rel=1e-3)


def test_the_parallel_ceiling_is_amdahls_law():
    """The 2-rank ceiling of a run whose linear share s gains r and the rest 2×: Amdahl's law,
    1 / (s / r + (1 − s) / 2) — 2 with no linear solve, r with nothing else, and 4/3 for half
    the run not gaining at all."""
    from benchmarks.factor_scaling import ceiling

    assert ceiling(0.0, 1.0) == pytest.approx(2.0)
    assert ceiling(1.0, 1.3) == pytest.approx(1.3)
    assert ceiling(0.5, 1.0) == pytest.approx(4.0 / 3.0)


def test_bodies_sweep_classifies_a_failure_by_its_stage():
    """benchmarks/bodies.py: a run's exit code and one-line message name the stage it failed
    in, and the REPORT.md section lists it with its message."""
    from benchmarks import bodies

    pen = "augmented Lagrangian: penetration 5.41e-06 m not below 4.6e-06 m after 3 updates"
    cases = [({"exit_code": 0}, "ok"), ({"exit_code": 4}, "check failure"),
             ({"exit_code": 3, "error": pen}, "penetration tolerance"),
             ({"exit_code": 3, "error": "dressing stopped: step 0.1 mm"}, "dressing stall"),
             ({"exit_code": 2, "error": "b.stl: the scan is 3.1 m across in 'mm': not a human "
               "body"}, "import/units/up-axis"),
             ({"exit_code": 2, "error": "b.stl: no armpit found"}, "anatomy/landmarks"),
             ({"exit_code": 2, "error": "s.toml: the garment starts 69.1 mm inside the body; "
               "with dressing.margin 2 mm …"}, "garment construction"),
             ({"exit_code": 1, "error": "internal error: ValueError"}, "internal error"),
             ({"exit_code": -15, "timed_out": True}, "time limit")]  # fmt: skip
    for rec, stage in cases:
        assert bodies.classify(rec) == stage, rec
    run = {"body": "f-heavy", "garment": "dress", "exit_code": 3, "wall_s": 738.0,
           "error": pen, "stage": "penetration tolerance", "dofs": 51504, "solves": 24,
           "cuts": 25, "max_penetration_over_thickness": 0.011}  # fmt: skip
    body = {"name": "f-heavy", "fmt": "stl", "units": "cm", "up": "z", "age_years": 25.0,
            "macro": {"gender": 0.0, "muscle": 0.5, "weight": 1.0, "height": 0.5,
                      "proportions": 0.5, "cup": 0.5},
            "import": {"status": "ok", "units": "cm", "up": "z", "units_ok": True,
                       "up_ok": True, "import_s": 8.0, "height_m": 1.59}}  # fmt: skip
    md = bodies.markdown({"bodies": [body], "runs": [run]})
    assert "| f-heavy | dress | 3 | penetration tolerance | 738 | augmented Lagrangian" in md
    assert "| dress | 1 | 0 | penetration tolerance: 1 | 738 / 738 / 738 | 1 | 51504–51504 |" in md
