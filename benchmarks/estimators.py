"""How often do the error bars cover the true error? The three error bars of the scenes and the
convergence study on synthetic data with a known limit and mesh noise.

The data are Q_k = Q₀ (1 + e (h_k/h_fine)ᵖ + σ ξ_k), ξ_k independent standard normal, on the five
levels of the convergence study (h₀ = 35 mm, ratio √2): e is the true relative error of the
finest level, σ the relative mesh noise (``benchmarks.mesh_noise`` measures 0.1–2 % standard
deviation of the gilets' key-region sensor p95 at 12.4–24.7 mm). For each (p, e, σ) and
:data:`DRAWS` draws, the *coverage* is the share of draws in which the finest level's bar is at
least its true error |Q_fine − Q₀|, for

- ``two_level``: :func:`fenics_garment.scene.error_bars.richardson_error` of the last two
  levels (the scene's own ``--error-bars``: h against √2 h, rate 1, 2.4 × their difference);
- ``three_level``: :func:`fenics_garment.scene.error_bars.three_level` on the last three levels
  (grid convergence index, or 3 × the range when the three are not monotone);
- ``least_squares``: :func:`fenics_garment.scene.error_bars.least_squares` on all five (Eça &
  Hoekstra, J. Comput. Phys. 262 (2014) 104–130, whose procedure aims at 95 % coverage).

A bar whose coverage is well below 95 % claims more than it knows; the table says in which
regimes each does. Writes ``benchmarks/results/estimators.json`` (section "estimators" of
REPORT.md).

``window``: the least-squares fit of only the finest 4 or 5 of seven levels (the gilets'
studies, 35 → 4.4 mm) against the fit of all seven: coverage, and the share of draws with a 5 %
true error whose bar claims ≤ 3 % (a window that drops the coarse, pre-asymptotic levels looks
tighter on the gilets' bust; does it still cover?). Stored as ``window_cases`` in the same record.

    python -m benchmarks.estimators [--draws N]
    python -m benchmarks.estimators window [--draws N]
"""

from __future__ import annotations

import json
import sys

import numpy as np

from benchmarks import check_args, convergence
from fenics_garment.scene.error_bars import least_squares, richardson_error, three_level

RESULTS = convergence.RESULTS / "estimators.json"
DRAWS = 1000
SEED = 20261204
ORDERS = (1.0, 2.0)
ERRORS = (0.01, 0.02, 0.05)
NOISES = (0.0, 0.0025, 0.005, 0.01, 0.02)
ESTIMATORS = {
    "two_level": lambda hs, qs: richardson_error(qs[-1], qs[-2]),
    "three_level": lambda hs, qs: three_level(hs, qs).error[-1],
    "least_squares": lambda hs, qs: least_squares(hs, qs).error[-1],
}


def case(p: float, e: float, sigma: float, draws: int, rng: np.random.Generator) -> dict:
    """Coverage and median bar (relative to Q₀ = 1) of each estimator for one regime."""
    hs = convergence.sizes(0.035, 5)
    x = np.asarray(hs) / hs[-1]
    bars: dict[str, list[float]] = {k: [] for k in ESTIMATORS}
    covered = dict.fromkeys(ESTIMATORS, 0)
    for _ in range(draws):
        qs = list(1.0 + e * x**p + sigma * rng.standard_normal(len(hs)))
        true = abs(qs[-1] - 1.0)
        for k, estimate in ESTIMATORS.items():
            u = estimate(hs, qs)
            bars[k].append(u)
            covered[k] += true <= u * (1.0 + 1e-9)  # exact data: equal up to round-off
    out = {"order": p, "error": e, "noise": sigma, "draws": draws}
    for k in ESTIMATORS:
        out[f"{k}_coverage"] = covered[k] / draws
        out[f"{k}_median_bar"] = float(np.median(bars[k]))
        out[f"{k}_within_3pct"] = float(np.mean(np.asarray(bars[k]) <= convergence.TARGET))
    return out


WINDOW_LEVELS = 7
WINDOWS = (7, 5, 4)  # the finest m levels fitted


def window_case(p: float, e: float, sigma: float, draws: int, rng: np.random.Generator) -> dict:
    """Coverage of the least-squares bar fitted to the finest m of seven levels, per m."""
    hs = convergence.sizes(0.035, WINDOW_LEVELS)
    x = np.asarray(hs) / hs[-1]
    covered, passed = dict.fromkeys(WINDOWS, 0), dict.fromkeys(WINDOWS, 0)
    for _ in range(draws):
        qs = 1.0 + e * x**p + sigma * rng.standard_normal(len(hs))
        true = abs(qs[-1] - 1.0)
        for m in WINDOWS:
            u = least_squares(hs[-m:], list(qs[-m:])).error[-1]
            covered[m] += true <= u * (1.0 + 1e-9)
            passed[m] += u / qs[-1] <= convergence.TARGET
    return {"order": p, "error": e, "noise": sigma, "draws": draws,
            **{f"last{m}_coverage": covered[m] / draws for m in WINDOWS},
            **{f"last{m}_within_3pct": passed[m] / draws for m in WINDOWS}}  # fmt: skip


def window_markdown(d: dict) -> str:
    out = ["The least-squares bar fitted to the finest m of seven levels "
           "(`python -m benchmarks.estimators window`): coverage of the true error, and the share "
           "of bars ≤ 3 %, which for a 5 % true error is a false pass.", "",
           "| order p | true error | noise | " + " | ".join(
               f"finest {m}: coverage | bar ≤ 3 %" for m in WINDOWS) + " |",
           "|---|---|---|" + "---|---|" * len(WINDOWS)]  # fmt: skip
    for r in d.get("window_cases", []):
        cells = [f"{r[f'last{m}_coverage']:.0%} | {r[f'last{m}_within_3pct']:.0%}"
                 for m in WINDOWS]  # fmt: skip
        out.append(f"| {r['order']:g} | {r['error']:.0%} | {r['noise']:.2%} | "
                   + " | ".join(cells) + " |")  # fmt: skip
    return "\n".join(out)


def markdown(d: dict) -> str:
    out = ["Coverage of the convergence study's error bars on synthetic data with a known limit "
           "(`python -m benchmarks.estimators`, five levels of ratio √2, "
           f"{d.get('draws', '?')} draws per row): share of draws whose finest-level bar covers "
           "the true error, median bar, and share of bars ≤ 3 %. Noise: relative standard "
           "deviation per level.", "",
           "| order p | true error | noise | "
           + " | ".join(f"{k.replace('_', ' ')}: coverage | median bar | bar ≤ 3 %"
                        for k in ESTIMATORS) + " |",
           "|---|---|---|" + "---|---|---|" * len(ESTIMATORS)]  # fmt: skip
    for r in d.get("cases", []):
        cells = [f"{r[f'{k}_coverage']:.0%} | {r[f'{k}_median_bar']:.1%} | "
                 f"{r[f'{k}_within_3pct']:.0%}" for k in ESTIMATORS]  # fmt: skip
        out.append(f"| {r['order']:g} | {r['error']:.0%} | {r['noise']:.2%} | "
                   + " | ".join(cells) + " |")  # fmt: skip
    if d.get("window_cases"):
        out += ["", window_markdown(d)]
    return "\n".join(out)


def _stored() -> dict:
    """The record as it is (empty when none)."""
    return json.loads(RESULTS.read_text()) if RESULTS.exists() else {}


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    bad = check_args(argv, __doc__, (), {"--draws"}, ("window",))
    if bad is not None:
        return bad
    draws = int(argv[argv.index("--draws") + 1]) if "--draws" in argv else DRAWS
    rng = np.random.default_rng(SEED)
    if "window" in argv:
        data = _stored()
        data["window_cases"] = [window_case(p, e, s, draws, rng) for p in ORDERS
                                for e in ERRORS for s in NOISES[1:4]]  # fmt: skip
        RESULTS.parent.mkdir(exist_ok=True)
        RESULTS.write_text(json.dumps(data, indent=1))
        print(window_markdown(data))
        return 0
    cases = [case(p, e, s, draws, rng) for p in ORDERS for e in ERRORS for s in NOISES]
    old = _stored()
    data = {
        "draws": draws,
        "seed": SEED,
        "cases": cases,  # the window study is kept
        **({"window_cases": old["window_cases"]} if "window_cases" in old else {}),
    }
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(data, indent=1))
    print(markdown(data))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
