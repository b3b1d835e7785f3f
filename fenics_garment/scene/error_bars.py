"""Discretisation error bars on the per-region pressures: the scene solved on two garment meshes.

If a statistic converges as Q_h = Q + C h^r, the solutions on the garment mesh h and on the
coarser mesh ρh (ρ = :data:`RATIO` = √2, the ratio of the convergence study) give the
Richardson estimate of the fine solution's error,

    Q_h − Q ≈ (Q_h − Q_ρh) / (ρ^r − 1).

The rate r of the scene's statistics is not known in advance (contact switches, region borders
and the 95th percentile are not smooth functionals of the solution), so the bar uses r = 1,
2.4 × the difference, which is 2.4 times the r = 2 estimate: on the tight tube with the P1 shell
the measured rate of the mean pressure is about 2 (``tests/test_scene_error_bars.py`` checks
that the bar covers the true error against Laplace's law). The coarse level costs about half the
fine one. (A 2h level, the older choice, made the gilets' 35 mm default mesh a 70 mm one.)

Each region row gets ``<stat>_err_kPa`` / ``<stat>_err_mmHg`` for mean, p95 and max, and
``comfort_range``: the comfort bands that p95 ± its error bar touches (one band when the bar
does not cross a band boundary).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from fenics_garment import output, units
from fenics_garment._stack import MPI
from fenics_garment.scene import config

#: Convergence rate assumed for the bars and the coarse level's mesh size ratio (module doc).
RATE = 1.0
RATIO = 2.0**0.5
STATS = ("mean", "p95", "max", "sensor_p95", "body_sensor_p95")


def richardson_error(fine: float, coarse: float, rate: float = RATE, ratio: float = RATIO) -> float:
    """|Q_h − Q_ρh| / (ρ^r − 1): the estimated error of the fine value (module doc)."""
    return abs(fine - coarse) / (ratio**rate - 1.0)


@dataclass(frozen=True)
class Convergence:
    """A statistic on three garment meshes h₁ > h₂ > h₃ of constant ratio r = h₁/h₂ = h₂/h₃.

    Monotone convergence (the differences keep their sign and shrink): ``order`` is the observed
    p = ln|(Q₁ − Q₂)/(Q₂ − Q₃)| / ln r, ``extrapolated`` Q₃ + (Q₃ − Q₂)/(r^p − 1), and the error
    of level k the grid convergence index 1.25 |Q_k − Q_{k−1}|/(r^p − 1) with p clipped to
    [:data:`MIN_ORDER`, :data:`MAX_ORDER`] (Roache, "Perspective: a method for uniform reporting
    of grid refinement studies", J. Fluids Eng. 116 (1994) 405–413); the coarsest level's error
    is its distance to the extrapolated value plus the finest's. Otherwise (oscillating or
    growing differences: not in the asymptotic range) ``order`` is nan, the extrapolated value
    is the finest one and every level's error is 3 × the range of the three values (Eça &
    Hoekstra, "A procedure for the estimation of the numerical uncertainty of CFD calculations
    based on grid refinement studies", J. Comput. Phys. 262 (2014) 104–130, oscillatory case).
    """

    sizes: tuple[float, ...]
    values: tuple[float, ...]
    order: float
    extrapolated: float
    error: tuple[float, ...]

    def as_dict(self) -> dict:
        return asdict(self)


MIN_ORDER, MAX_ORDER = 0.5, 3.0
OSCILLATION_FACTOR = 3.0


def three_level(sizes: list[float], values: list[float]) -> Convergence:
    """The observed order, Richardson extrapolation and error bars of ``values`` on the meshes
    ``sizes`` (coarse to fine, the last three used; see :class:`Convergence`)."""
    (h1, _, h3), (q1, q2, q3) = sizes[-3:], values[-3:]
    r = (h1 / h3) ** 0.5
    d21, d32 = q2 - q1, q3 - q2
    if d21 * d32 > 0 and abs(d32) < abs(d21):
        order = math.log(abs(d21 / d32)) / math.log(r)
        f = r ** min(max(order, MIN_ORDER), MAX_ORDER) - 1.0
        extra = q3 + d32 / f
        e3, e2 = 1.25 * abs(d32) / f, 1.25 * abs(d21) / f
        errs = [abs(q - extra) + e3 for q in values[:-2]] + [e2, e3]
        return Convergence(tuple(sizes), tuple(values), order, extra, tuple(errs))
    spread = OSCILLATION_FACTOR * (max(q1, q2, q3) - min(q1, q2, q3))
    errs = [abs(q - q3) + spread for q in values[:-3]] + [spread] * 3
    return Convergence(tuple(sizes), tuple(values), float("nan"), q3, tuple(errs))


@dataclass(frozen=True)
class LeastSquares:
    """A statistic on n ≥ 4 garment meshes, fitted in the least-squares sense (Eça & Hoekstra,
    "A procedure for the estimation of the numerical uncertainty of CFD calculations based on grid
    refinement studies", J. Comput. Phys. 262 (2014) 104–130), made for data with scatter.

    The fit of Q_h = Q₀ + α hᵖ (order free) gives ``order``. Inside [:data:`LS_TRUSTED`) it also
    gives the errors ε_k = |α h_kᵖ| with the safety factor F = 1.25; outside, the fixed-order fit
    (α h, α h², α₁ h + α₂ h²) of smallest standard deviation gives them, with F = 3. Each fit is
    made unweighted and with weights ∝ 1/h (more weight to the fine meshes), the one of smaller
    standard deviation σ kept. With the data range Δ = (max Q − min Q)/(n − 1), the uncertainty
    of level k is U_k = F ε_k + σ + |Q_k − fit_k| when σ < Δ (the fit explains the data), else
    3 σ/Δ (ε_k + σ + |Q_k − fit_k|). ``fit`` names the fit that gave the errors.
    """

    sizes: tuple[float, ...]
    values: tuple[float, ...]
    order: float
    extrapolated: float
    fit: str
    sigma: float
    data_range: float
    safety: float
    error: tuple[float, ...]

    def as_dict(self) -> dict:
        return asdict(self)


#: The orders for which the free-order fit's error is trusted (Eça & Hoekstra 2014, §3.3), and
#: the orders the fit searches.
LS_TRUSTED = (0.5, 2.1)
LS_ORDERS = np.linspace(0.05, 10.0, 3981)


def _linear_fit(basis: np.ndarray, q: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, float]:
    """Weighted least squares q ≈ basis @ c; the coefficients and σ = √(n Σ wᵢ rᵢ² / (n − k))."""
    n, k = basis.shape
    sw = np.sqrt(w)
    c = np.linalg.lstsq(basis * sw[:, None], q * sw, rcond=None)[0]
    r = q - basis @ c
    return c, float(np.sqrt(n * np.sum(w * r**2) / (n - k)))


def _free_order_fit(
    x: np.ndarray, q: np.ndarray, w: np.ndarray
) -> tuple[float, float, float, float]:
    """Q₀ + α xᵖ with p ∈ :data:`LS_ORDERS` minimising Σ wᵢ rᵢ²: (p, Q₀, α, σ)."""
    xp = x[None, :] ** LS_ORDERS[:, None]  # for each p a weighted regression of q on xᵖ
    mx, mq = xp @ w, q @ w
    sxx = (xp**2) @ w - mx**2
    alpha = np.where(sxx > 0, (xp * q[None, :]) @ w - mx * mq, 0.0) / np.where(sxx > 0, sxx, 1.0)
    q0 = mq - alpha * mx
    res = ((q[None, :] - q0[:, None] - alpha[:, None] * xp) ** 2) @ w
    i = int(np.argmin(res))
    n = len(q)
    return float(LS_ORDERS[i]), float(q0[i]), float(alpha[i]), float(np.sqrt(n * res[i] / (n - 3)))


def least_squares(sizes: list[float], values: list[float]) -> LeastSquares:
    """The least-squares uncertainty of ``values`` on the meshes ``sizes`` (n ≥ 4; see
    :class:`LeastSquares`)."""
    n = len(values)
    if n < 4 or len(sizes) != n:
        raise ValueError(f"the least-squares estimate needs ≥ 4 levels, got {n}")
    x = np.asarray(sizes, float) / min(sizes)  # relative step size (conditioning)
    q = np.asarray(values, float)
    spread = (q.max() - q.min()) / (n - 1)
    weights = (np.full(n, 1.0 / n), (1.0 / x) / np.sum(1.0 / x))
    p, q0, alpha, sigma = min((_free_order_fit(x, q, w) for w in weights), key=lambda f: f[3])
    if LS_TRUSTED[0] <= p < LS_TRUSTED[1]:
        name, safety, fitted = f"h^{p:.2f}", 1.25, q0 + alpha * x**p
    else:
        fixed = {"h": x[:, None], "h^2": x[:, None] ** 2, "h+h^2": np.stack([x, x**2], axis=1)}
        fits = []
        for label, b in fixed.items():
            basis = np.hstack([np.ones((n, 1)), b])
            fits += [(label, basis, *_linear_fit(basis, q, w)) for w in weights]
        name, basis, c, sigma = min(fits, key=lambda f: f[3])
        safety, q0, fitted = 3.0, float(c[0]), basis @ c
    eps, dev = np.abs(fitted - q0), np.abs(q - fitted)
    if spread == 0.0:  # the same value on every mesh
        err = np.zeros(n)
    elif sigma < spread:
        err = safety * eps + sigma + dev
    else:
        err = 3.0 * sigma / spread * (eps + sigma + dev)
    return LeastSquares(tuple(sizes), tuple(values), p, q0, name, sigma, spread, safety,
                        tuple(float(e) for e in err))  # fmt: skip


def comfort_range(p_kpa: float, err_kpa: float) -> str:
    """The comfort bands touched by p ± err, e.g. ``"comfortable"`` or
    ``"negligible … comfortable"``."""
    low, high = output.comfort_band(max(p_kpa - err_kpa, 0.0)), output.comfort_band(p_kpa + err_kpa)
    return low if low == high else f"{low} … {high}"


def attach(fine: list[dict], coarse: list[dict], rate: float = RATE) -> list[dict]:
    """The fine region rows with error bars from the coarse rows (matched by region name)."""
    by_name = {r["region"]: r for r in coarse}
    rows = []
    for r in fine:
        c = by_name.get(r["region"])
        row = dict(r)
        for s in (s for s in STATS if f"{s}_kPa" in r):
            err = richardson_error(r[f"{s}_kPa"], c[f"{s}_kPa"], rate) if c else float("nan")
            row[f"{s}_err_kPa"] = err
            row[f"{s}_err_mmHg"] = units.pa_to_mmhg(1e3 * err)
        row["comfort_range"] = comfort_range(r["p95_kPa"], row["p95_err_kPa"]) if c else ""
        rows.append(row)
    return rows


def coarse_scene(scene: config.Scene) -> config.Scene:
    """The scene on the coarser garment mesh (:data:`RATIO` × h, and as many fewer elements per
    turn of a limb's curvature), with no files but the summary."""
    g = scene.garment
    g = replace(g, mesh_size=RATIO * g.mesh_size, per_turn=max(8, round(g.per_turn / RATIO)))
    o = replace(scene.output, vtx=False, xdmf=False, pictures=False, error_bars=False, report=False)
    return replace(scene, garment=g, output=o)


def run_with_error_bars(
    run: Callable[..., Any],
    scene: config.Scene,
    out_root: str | Path | None = None,
    *,
    quiet: bool = False,
    comm: MPI.Comm = MPI.COMM_WORLD,
    resume: str | Path | None = None,
    **kwargs,
):
    """Run ``scene`` on the meshes √2 h then h; the fine run's summary and CSV get error bars.

    ``run`` is the one-level run, :func:`fenics_garment.scene.run.run` (passed in, so that this
    module does not import the module that dispatches to it).

    The coarse run's own outputs go to ``<out>/<name>/coarse_level/<name>/``. The whole run's
    folder is locked meanwhile and its ``scene_used.toml`` records ``error_bars = true``, so
    ``--resume`` of it continues both levels: a finished coarse level is read back from its
    ``summary.json``, an interrupted one is resumed from its checkpoint, then the fine level.
    """
    from fenics_garment.scene import folder as run_folder
    from fenics_garment.scene import preflight

    say = (lambda *a: print(*a, flush=True)) if comm.rank == 0 and not quiet else (lambda *a: 0)
    if resume is not None:
        folder = Path(resume)
    else:
        root = Path(out_root if out_root is not None else scene.output.folder)
        folder = run_folder.inside(root, scene.name)
    preflight.scene_limits(scene)
    preflight.output_folder(folder, comm)
    state = run_folder.RunFolder(folder, comm)
    state.acquire()
    try:
        state.start(fresh=resume is None)
        text = config.dumps(scene)
        output.guarded(comm, lambda: output.write_text(folder / "scene_used.toml", text))
        say(f"error bars: solving on the coarser garment mesh first "
            f"(mesh_size {coarse_scene(scene).garment.mesh_size:g} m)")  # fmt: skip
        coarse = _coarse_level(run, scene, folder / run_folder.NESTED / scene.name, comm, kwargs)
        fine = _fine_level(run, scene, folder, comm, quiet, kwargs)
        _attach_bars(fine, coarse, state.run_id, comm)
        if scene.output.report:  # again: the regions now have their error bars
            from fenics_garment.scene.run import write_report

            write_report(folder, comm, say, fine.summary)
        state.finish("completed" if fine.completed and fine.checks_passed else
                     "stopped" if not fine.completed else "checks failed")  # fmt: skip
    except BaseException:
        state.finish("failed", collective=False)
        raise
    finally:
        state.release()
    say(f"  {'region':<12} {'p95 ± error':>16}  kPa   comfort range")
    for r in fine.regions:
        if r["contact_area_m2"] > 0:
            say(f"  {r['region']:<12} {r['p95_kPa']:7.2f} ± {r['p95_err_kPa']:5.2f}        "
                f"{r['comfort_range']}")  # fmt: skip
    return fine


def _has_checkpoint(folder: Path, comm: MPI.Comm) -> bool:
    found = (folder / "checkpoint" / "progress.json").exists() if comm.rank == 0 else None
    return bool(comm.bcast(found, root=0))


def _finished_summary(folder: Path, comm: MPI.Comm) -> dict | None:
    """The summary of a level whose run.json says it ended (completed or checks failed)."""
    import json

    summary = None
    if comm.rank == 0:
        try:
            status = json.loads((folder / "run.json").read_text()).get("status")
            if status in ("completed", "checks failed"):
                summary = json.loads((folder / "summary.json").read_text())
        except (OSError, ValueError, AttributeError):
            summary = None
    summary = comm.bcast(summary, root=0)
    return summary if isinstance(summary, dict) and "regions" in summary else None


def _coarse_level(run, scene: config.Scene, folder: Path, comm: MPI.Comm, kwargs: dict) -> dict:
    """The coarse level's summary: read back when it finished, else resumed or run."""
    done = _finished_summary(folder, comm)
    if done is not None:
        return done
    sc = coarse_scene(scene)
    if _has_checkpoint(folder, comm):
        return run(sc, quiet=True, comm=comm, resume=folder, **kwargs).summary
    return run(sc, folder.parent, quiet=True, comm=comm, **kwargs).summary


def _fine_level(run, scene: config.Scene, folder: Path, comm: MPI.Comm, quiet: bool, kwargs: dict):
    """The fine level (recording the whole run's scene), resumed when it has a checkpoint."""
    fine = replace(scene, output=replace(scene.output, error_bars=False))
    if _has_checkpoint(folder, comm):
        return run(fine, quiet=quiet, comm=comm, resume=folder, record=scene, **kwargs)
    return run(fine, folder.parent, quiet=quiet, comm=comm, record=scene, clear=False, **kwargs)


def _attach_bars(fine, coarse: dict, run_id: str, comm: MPI.Comm) -> None:
    rows = attach(fine.regions, coarse["regions"])
    fine.summary["regions"] = rows
    fine.summary["run_id"] = run_id
    fine.summary["error_bars"] = {
        "method": "Richardson, garment meshes h and √2 h",
        "rate": RATE,
        "ratio": RATIO,
        "coarse_dofs": coarse["dofs"],
        "coarse_completed": coarse["completed"],
        "coarse_time_s": coarse["time_s"]["total"],
    }
    output.guarded(comm, lambda: output.write_summary(fine.folder, fine.summary, rows))
    fine.regions = rows
