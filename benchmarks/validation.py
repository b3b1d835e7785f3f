"""Validation (issue 47): the shell against the heavy elastica and against measured fabrics.

``cantilever``: the heavy elastica's master curve, tip drop δ/L and tip angle θ(1) against
Γ = W L³/B from 10⁻² to 10², the shell strip (``verification/cantilever.py``: ν = 0,
h/L = 0.01, one load path through all Γ) beside SciPy's ``solve_bvp`` on the inextensible
elastica, on n × 1 cell pairs for each ``--n``.

``tube``: the membrane law from tension–strain curves
(:func:`fenics_garment.shell.energy.tabulated_membrane`, the synthetic knit-like curves of
``verification/contact.py``) on the Laplace tube, against the curve's hoop tension at the
wrapped strain, beside the quadratic law with the curve's initial slope.

``anticlastic``: the plate-vs-beam effect at ν = 0.3: the effective rigidity of isotropic strips
of growing width against the plate's D (beam 1 − ν², cylindrical bending 1).

``fabrics``: the ASTM D1388 bending length c (41.5° cantilever, 25 mm wide strip, standard
gravity) the model gives for each fabric of ``fenics_garment/data/fabrics_measured.toml``, warp
and (Petrak only: Matsudaira gives one B) weft, beside Peirce's c = (B/W)^(1/3); and, warp only,
the 2.5 mm strip that bends as a beam (anticlastic curvature free: D11 − D12²/D22).

Writes ``benchmarks/results/validation.json``; ``table`` prints it as Markdown (the
"validation" section of REPORT.md, rebuilt by ``python -m benchmarks.report``).

    python -m benchmarks.validation [PART ...] [--n N ...]    # PART: one of PARTS
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from pathlib import Path

from benchmarks import check_args

RESULTS = Path(__file__).resolve().parent / "results" / "validation.json"
PARTS = (
    "cantilever",
    "anticlastic",
    "fabrics",
    "tube",
    "drape",
    "drape-refine",
    "drape-amplitude",
    "drape-hysteresis",
    "table",
)
#: strip widths [m] of the plate-vs-beam study (L = 1 m, h = 0.01 m, ν = 0.3, Γ = 3)
ANTICLASTIC_WIDTHS = (0.01, 0.03, 0.1, 0.3, 1.0)
#: first Cusick drape runs (fabric, mesh size [m], imperfection seed): the seed spread and one
#: mesh refinement on the stiffest Petrak fabric, then a stiff and a limp Matsudaira fabric
DRAPE_RUNS = (("P-m6", 0.012, 0), ("P-m6", 0.012, 1), ("P-m6", 0.012, 2), ("P-m6", 0.009, 0),
              ("M-F", 0.012, 0), ("M-A", 0.012, 0))  # fmt: skip
#: part ``drape-refine``: the mesh sequence 12 → 9 → 6 mm of P-m6 and the limp M-F at 9 mm
DRAPE_REFINE = (("P-m6", 0.006, 0), ("M-F", 0.009, 0))
#: the imperfection amplitudes [m] of part ``drape-amplitude`` (P-m6, 12 mm, seed 0)
DRAPE_AMPLITUDES = (3.0e-4, 3.0e-3)
DRAPE_AMPLITUDE = 1.0e-3
#: part ``drape-hysteresis``: the three Matsudaira fabrics (the data file's 2HB) at one mesh and
#: seed, the elastic law beside the hysteretic one (``shell.energy.HystereticBending``)
DRAPE_HYSTERESIS = tuple((fid, 0.012, 0, law) for fid in ("M-A", "M-B", "M-F")
                         for law in ("elastic", "hysteresis"))  # fmt: skip
#: the Laplace tube of the tabulated membrane law: (warp direction, rest radius r0 [m]) on the
#: rigid cylinder R = 0.1 m: wrapped hoop strain 8.1 % (r0 = 0.093) and 14.2 % (r0 = 0.088)
TUBE_CASES = (("axial", 0.093), ("hoop", 0.093), ("axial", 0.088))
#: the fabric strips' mesh: n × n_width cell pairs (the bending length changes by < 0.1 % to
#: 32 × 4 and 16 × 8, docstring of ``cantilever.bending_length``)
FABRIC_MESH = (16, 4)
NARROW_WIDTH = 0.0025


def _load() -> dict:
    return json.loads(RESULTS.read_text()) if RESULTS.exists() else {}


def _store(section: str, runs: list[dict], **meta) -> None:
    data = _load()
    data[section] = {"runs": runs, "meta": {"loadavg": list(os.getloadavg()), **meta}}
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(data, indent=1, default=float))


def run_cantilever(meshes: list[int], say=print) -> list[dict]:
    from fenics_garment.verification import cantilever

    runs = []
    for n in meshes:
        t0 = time.perf_counter()
        points, st = cantilever.master_curve(n=n)
        mesh = st.model.geometry.mesh
        for p in points:
            rec = {
                "case": f"cantilever Γ = {p.gamma:g}", "gamma": p.gamma, "n": n,
                "cells": mesh.topology.index_map(2).size_global,
                "drop": p.model.tip_drop, "drop_ref": p.reference.tip_drop,
                "drop_error": p.drop_error, "angle": p.model.tip_angle,
                "angle_ref": p.reference.tip_angle, "angle_error": p.angle_error,
                "x": p.model.tip_x, "x_ref": p.reference.tip_x, "wall_s": p.wall_s,
            }  # fmt: skip
            runs.append(rec)
            say(f"n = {n:3d}  Γ = {p.gamma:7g}  δ/L {p.model.tip_drop:.6f} / "
                f"{p.reference.tip_drop:.6f} ({100 * p.drop_error:+.3f} %)  θ(1) "
                f"{p.model.tip_angle:.6f} / {p.reference.tip_angle:.6f} "
                f"({100 * p.angle_error:+.3f} %)  {p.wall_s:.1f} s")  # fmt: skip
        say(f"n = {n}: {time.perf_counter() - t0:.1f} s (JIT {st.solver.timings.jit:.1f} s)")
    _store("cantilever", runs, material=str(cantilever.MASTER_MATERIAL), length=1.0, width=0.1)
    return runs


def run_anticlastic(say=print) -> list[dict]:
    from fenics_garment.verification import cantilever

    runs = []
    for b in ANTICLASTIC_WIDTHS:
        t0 = time.perf_counter()
        nw = max(2, min(12, math.ceil(b / 0.04)))  # cells across: edge layers ~√(R h) = 0.1 m
        drop, ratio = cantilever.effective_rigidity(b, n_width=nw)
        rec = {"case": f"anticlastic b = {b:g}", "width": b, "searle": b**2 / 0.01,
               "n_width": nw, "drop": drop, "b_eff_over_d": ratio,
               "wall_s": time.perf_counter() - t0}  # fmt: skip
        runs.append(rec)
        say(f"b = {b:5g} m (b²/(L h) = {rec['searle']:6.3g}): δ/L {drop:.5f}, B_eff/D "
            f"{ratio:.4f} (beam 1 − ν² = 0.91)  {rec['wall_s']:.0f} s")  # fmt: skip
    _store("anticlastic", runs, nu=0.3, gamma=3.0)
    return runs


def run_fabrics(say=print) -> list[dict]:
    from fenics_garment import measured
    from fenics_garment.verification import cantilever

    n, nw = FABRIC_MESH
    g_star = cantilever.chord_gamma()
    runs = []
    for m in measured.fabrics():
        f = measured.to_fabric(m)
        dirs = [("warp", f, m.B_warp)]
        if m.B_weft != m.B_warp:
            dirs.append(("weft", cantilever.across(f), m.B_weft))
        for direction, mat, B in dirs:
            W = m.weight_per_area
            peirce = cantilever.peirce_bending_length(B, W)
            r = cantilever.bending_length(mat, n=n, n_width=nw)
            rec = {
                "case": f"D1388 {m.id} {direction}", "fabric": m.id, "name": m.name,
                "source": m.source, "direction": direction, "B": B, "W": W,
                "c_peirce": peirce, "c_elastica": g_star ** (1 / 3) / 2 * peirce,
                "c_model": r.c, "gamma_star": r.gamma, "overhang_iterations": r.iterations,
                "rel_error": r.c / peirce - 1, "wall_s": r.wall_s, "n": n, "n_width": nw,
                "dc_measured": m.dc_measured, "dc_clo3d": m.dc_clo3d,
                "nodes_measured": m.nodes_measured,
            }  # fmt: skip
            if direction == "warp":
                narrow = cantilever.bending_length(mat, width=NARROW_WIDTH, n=n, n_width=1)
                rec["c_narrow"] = narrow.c
                s = mat.stiffness()
                rec["c_beam"] = (g_star * (s.D11 - s.D12**2 / s.D22) / W) ** (1 / 3) / 2
                rec["wall_s"] += narrow.wall_s
            runs.append(rec)
            say(f"{m.id:5s} {direction}: c = {100 * r.c:.3f} cm, Peirce {100 * peirce:.3f} cm "
                f"({100 * rec['rel_error']:+.2f} %), Γ* = {r.gamma:.3f}"
                + (f", 2.5 mm strip {100 * rec['c_narrow']:.3f} cm (beam "
                   f"{100 * rec['c_beam']:.3f} cm)" if "c_narrow" in rec else "")
                + f"  {rec['wall_s']:.0f} s")  # fmt: skip
    _store("fabrics", runs, mesh=FABRIC_MESH, elastica_gamma_star=g_star,
           unit_reading=measured.sources()["petrak2025"]["unit_reading"],
           membrane_rule=measured.MISSING_MEMBRANE_RULE)  # fmt: skip
    return runs


def run_tube(say=print) -> list[dict]:
    from fenics_garment._stack import MPI
    from fenics_garment.contact import uzawa
    from fenics_garment.verification import contact as cases

    runs = []
    for warp, r0 in TUBE_CASES:
        t0 = time.perf_counter()
        scene = cases.curve_tube(MPI.COMM_WORLD, warp=warp, r0=r0)
        h = scene.model.stiffness.thickness
        cases.dress_case(scene)
        al = uzawa.augmented_lagrangian(
            scene.state, float(scene.contact.kappa.value), scene.solver.solve, tol=0.01 * h
        )
        p = cases.mid_pressure(scene)
        rec = {
            "case": f"curve tube, warp {warp}, r0 = {r0}", "warp": warp, "r0": r0,
            "curve": scene.extra["hoop_curve"], "strain": scene.extra["strain"], "value": p,
            "reference": scene.reference, "rel_error": p / scene.reference - 1,
            "linear_law": scene.extra["linear_law"], "converged": al.converged,
            "wall_s": time.perf_counter() - t0,
        }  # fmt: skip
        runs.append(rec)
        say(f"tube warp {warp}, e = {rec['strain']:.4f}: p = {p:.4f} Pa, curve "
            f"{scene.reference:.4f} Pa ({100 * rec['rel_error']:+.3f} %), linear law "
            f"{rec['linear_law']:.2f} Pa, {rec['wall_s']:.1f} s")  # fmt: skip
    _store("tube_law", runs)
    return runs


def run_drape(
    cases=None, amplitudes=None, section: str = "drape", say=print, laws=None
) -> list[dict]:
    """Drape runs of ``cases`` (fabric, mesh size, seed), each with its bending law of ``laws``
    ("elastic" or "hysteresis": the fabric's 2HB, ``HystereticBending``; default elastic)."""
    from fenics_garment import drape, measured
    from fenics_garment.shell.energy import HystereticBending

    runs: list[dict] = []
    cases = DRAPE_RUNS if cases is None else cases
    amplitudes = [DRAPE_AMPLITUDE] * len(cases) if amplitudes is None else amplitudes
    laws = ["elastic"] * len(cases) if laws is None else laws
    for (fid, size, seed), amp, law in zip(cases, amplitudes, laws, strict=True):
        m = measured.by_id(fid)
        t0 = time.perf_counter()
        bending = HystereticBending(m.twoHB) if law == "hysteresis" else None
        try:
            r = drape.drape(measured.to_fabric(m), size=size, seed=seed,
                            amplitude=amp, specimen_diameter=m.specimen_diameter,
                            pedestal_diameter=m.pedestal_diameter, bending=bending)  # fmt: skip
        except RuntimeError as e:
            runs.append({"case": f"drape {fid}", "fabric": fid, "size": size, "seed": seed,
                         "amplitude": amp, "law": law, "status": "failed", "error": str(e),
                         "wall_s": time.perf_counter() - t0})  # fmt: skip
            _store(section, runs, amplitude=DRAPE_AMPLITUDE)
            say(f"drape {fid} h = {size} seed {seed} {law}: failed ({e})")
            continue
        tag = "" if law == "elastic" else f"-{law}"
        name = f"drape-{fid}-{1000 * size:g}mm-seed{seed}{tag}.png"
        picture: Path | None = RESULTS.parent / name
        title = (f"{m.id} ({law}): shadow, DC {r.dc:.3f} (measured {m.dc_measured:.3f}), "
                 f"{r.nodes} nodes")  # fmt: skip
        try:
            drape.picture(r, m.pedestal_diameter / 2, m.specimen_diameter / 2, title, picture)
        except ImportError:  # no matplotlib: no picture
            picture = None
        rec = {
            "case": f"drape {fid}", "fabric": fid, "name": m.name, "source": m.source,
            "size": size, "seed": seed, "amplitude": amp, "law": law,
            "twoHB": m.twoHB, "dc": r.dc, "dc_measured": m.dc_measured,
            "dc_clo3d": m.dc_clo3d, "dc_error": r.dc - m.dc_measured, "nodes": r.nodes,
            "nodes_measured": m.nodes_measured, "cells": r.cells, "dofs": r.dofs,
            "steps": r.load_steps, "newton_its": r.newton_its, "wall_s": r.wall_s,
            "edge_strain": r.edge_strain,
            "picture": picture.name if picture is not None else None, "status": "ok",
        }  # fmt: skip
        runs.append(rec)
        _store(section, runs, amplitude=DRAPE_AMPLITUDE)
        say(f"drape {fid} h = {1000 * size:g} mm seed {seed} {law}: DC {r.dc:.3f} (measured "
            f"{m.dc_measured:.3f}, CLO3D {m.dc_clo3d}), nodes {r.nodes} (measured "
            f"{m.nodes_measured}), {r.cells} cells, {r.load_steps} steps, {r.newton_its} its, "
            f"{r.wall_s:.0f} s")  # fmt: skip
    return runs


def _pct(v) -> str:
    return "–" if v is None else f"{100 * v:+.3f}"


def markdown(data: dict | None = None) -> str:
    data = _load() if data is None else data
    out = []
    cant = data.get("cantilever", {}).get("runs", [])
    if cant:
        worst = max(max(abs(r["drop_error"]), abs(r["angle_error"])) for r in cant
                    if r["n"] == max(x["n"] for x in cant))  # fmt: skip
        out += ["### Cantilever under self weight: the heavy elastica", "",
                "Shell strip L × b = 1 × 0.1 m, h = 0.01 m, ν = 0 (plate, beam and anticlastic "
                "stiffness coincide), clamped, self weight in load steps (one path through all "
                "Γ); reference: the inextensible heavy elastica θ'' = −Γ(1 − s) cos θ by SciPy "
                "`solve_bvp` (tests/test_cantilever.py checks it against its own shooting "
                f"solution). Largest |error| on the finest mesh: {100 * worst:.3f} %.", "",
                "| Γ | n | δ/L model | δ/L elastica | error [%] | θ(1) model [rad] | θ(1) "
                "elastica | error [%] | time [s] |", "|---" * 9 + "|"]  # fmt: skip
        for r in cant:
            out.append(f"| {r['gamma']:g} | {r['n']} | {r['drop']:.6f} | {r['drop_ref']:.6f} | "
                       f"{_pct(r['drop_error'])} | {r['angle']:.6f} | {r['angle_ref']:.6f} | "
                       f"{_pct(r['angle_error'])} | {r['wall_s']:.1f} |")  # fmt: skip
        out.append("")
    anti = data.get("anticlastic", {}).get("runs", [])
    if anti:
        out += ["### Plate or beam: the anticlastic effect at ν = 0.3", "",
                "Isotropic strip L = 1 m, h = 0.01 m, ν = 0.3 under the self weight Γ = W L³/D = 3 "
                "(D = E h³/12(1 − ν²), the plate rigidity per unit width); B_eff is the rigidity "
                "of the heavy elastica that drops as far. A narrow strip curls anticlastically "
                "and bends as a beam, B_eff = D(1 − ν²) = E h³/12; a wide one is held in "
                "cylindrical bending, B_eff = D (Searle's parameter b²/(R h), R ~ L).", "",
                "| width b [m] | b²/(L h) | cells across | δ/L | B_eff/D | time [s] |",
                "|---" * 6 + "|"]  # fmt: skip
        for r in anti:
            out.append(
                f"| {r['width']:g} | {r['searle']:.3g} | {r['n_width']} | "
                f"{r['drop']:.5f} | {r['b_eff_over_d']:.4f} | {r['wall_s']:.0f} |"
            )
        out.append("")
    fab = data.get("fabrics", {})
    if fab.get("runs"):
        meta = fab.get("meta", {})
        g = meta.get("elastica_gamma_star", math.nan)
        out += ["### ASTM D1388 bending length of the measured fabrics", "",
                "The model's bending length c = L*/2, L* the overhang at which the tip-to-clamp "
                "line makes 41.5° (25 mm wide strip of the fabric's shell material, standard "
                f"gravity, {meta.get('mesh', FABRIC_MESH)} cell pairs), beside Peirce's "
                "c = (B/W)^(1/3) from the measured bending rigidity B and weight W. The exact "
                f"elastica reaches 41.5° at Γ* = {g:.4f}, i.e. c = {g ** (1 / 3) / 2:.5f} "
                "(B/W)^(1/3): Peirce's 41.5° is exact to 0.02 %. The 25 mm strip bends as a "
                "plate (D11); the 2.5 mm strip curls anticlastically and approaches the beam "
                "value (D11 − D12²/D22, ν12 = 0.3: −3 % in c). Petrak's B: CLO3D's bending "
                f"input, {meta.get('unit_reading', '')}. Drape (DC) is not computed yet: the "
                "measured and CLO3D values are listed for the drape to come.", "",
                "| fabric | source | direction | B [µN·m] | W [N/m²] | c Peirce [cm] | c model "
                "[cm] | error [%] | Γ* | c 2.5 mm strip [cm] | c beam [cm] | DC measured | DC "
                "CLO3D | nodes | time [s] |", "|---" * 15 + "|"]  # fmt: skip
        for r in fab["runs"]:
            narrow = r.get("c_narrow")
            beam = r.get("c_beam")
            out.append(
                f"| {r['fabric']} {r['name']} | {r['source']} | {r['direction']} | "
                f"{1e6 * r['B']:.3f} | {r['W']:.4f} | {100 * r['c_peirce']:.3f} | "
                f"{100 * r['c_model']:.3f} | {_pct(r['rel_error'])} | {r['gamma_star']:.3f} | "
                f"{'–' if narrow is None else f'{100 * narrow:.3f}'} | "
                f"{'–' if beam is None else f'{100 * beam:.3f}'} | {r['dc_measured']:.3f} | "
                f"{'–' if r['dc_clo3d'] is None else r['dc_clo3d']} | "
                f"{r['nodes_measured'] or '–'} | {r['wall_s']:.0f} |"
            )
        out.append("")
    drape = [r for key in ("drape", "drape_refine", "drape_amplitude")
             for r in data.get(key, {}).get("runs", [])]  # fmt: skip
    if drape:
        out += drape_markdown(drape, data.get("drape", {}).get("meta", {}))
    hyst = data.get("drape_hysteresis", {}).get("runs", [])
    if hyst:
        out += hysteresis_markdown(hyst)
    tube = data.get("tube_law", {}).get("runs", [])
    if tube:
        out += tube_markdown(tube)
    return "\n".join(out)


def drape_markdown(runs: list[dict], meta: dict) -> list[str]:
    out = ["### Cusick drape: a first scene (not yet validated)", "",
           "The annulus outside the 180 mm discs of a 300 mm specimen, clamped between them, "
           "hanging under standard gravity (`fenics_garment/drape.py`, the scene kind `drape`); "
           "folding seeded by a "
           f"stress-free vertical waviness of amplitude {1e3 * meta.get('amplitude', 0):g} mm "
           "(modes 2–12, random phases from the seed); path: pseudo-transient continuation "
           "(a proximal term ½k|u − u_prev|², k → 0, the last solve at k = 0 is the "
           "equilibrium). DC from the rasterised shadow (0.5 mm pixels), nodes from the lobes of "
           "the projected hem. **Not converged**: DC falls with the mesh (P-m6: 12 → 9 → 6 mm "
           "gives 0.512 → 0.464 → 0.426, 10 nodes on each) — a fold's radius is of the order of "
           "the bending length (1–2 cm), resolved here by a few cells; seeds and imperfection "
           "amplitude move DC by ≤ 0.02 and the node count by 1. Every fabric folds into 9–11 "
           "nodes and the limp M-F drapes far stiffer than measured on these meshes. Frictional "
           "contact with the pedestal, finer meshes and the other fabrics are not done (the "
           "hysteresis law: the next table): a first look, no target is claimed.", "",
           "| fabric | mesh [mm] | seed | imperfection [mm] | cells | DC model | DC measured | "
           "error | DC CLO3D | nodes model | nodes measured | steps | Newton its | time [s] |",
           "|---" * 14 + "|"]  # fmt: skip
    for r in runs:
        if r.get("status") != "ok":
            out.append(f"| {r['fabric']} | {1e3 * r['size']:g} | {r['seed']} | failed: "
                       f"{r.get('error', '')[:60]} |" + " |" * 10)  # fmt: skip
            continue
        amp = 1e3 * r.get("amplitude", meta.get("amplitude", math.nan))
        out.append(f"| {r['fabric']} {r['name']} | {1e3 * r['size']:g} | {r['seed']} | "
                   f"{amp:g} | {r['cells']} | {r['dc']:.3f} | {r['dc_measured']:.3f} | "
                   f"{r['dc_error']:+.3f} | {r['dc_clo3d'] if r['dc_clo3d'] else '–'} | "
                   f"{r['nodes']} | {r['nodes_measured'] or '–'} | {r['steps']} | "
                   f"{r['newton_its']} | {r['wall_s']:.0f} |")  # fmt: skip
    out.append("")
    out += [f"![{r['picture']}]({r['picture']})" for r in runs if r.get("picture")]
    return [*out, ""]


def hysteresis_markdown(runs: list[dict]) -> list[str]:
    """The DC of each fabric with the elastic and with the hysteretic bending law, side by
    side (part ``drape-hysteresis``)."""
    from fenics_garment import measured
    from fenics_garment.shell.energy import YIELD_CURVATURE

    out = ["### Cusick drape with the KES bending hysteresis (2HB)", "",
           "The three Matsudaira et al. 2015 fabrics (B, 2HB, W, T of the data file; membrane "
           "from the stated rule), one mesh (12 mm) and seed (0), the scene's path (load steps, "
           "then pseudo-time relaxation, each accepted step committed): the elastic bending law "
           "beside `HystereticBending` (a friction moment ±2HB/2 opposing the change of "
           f"curvature, slider range κ_y = {YIELD_CURVATURE:g}/m; its pure-bending loop has width "
           "2HB to 1 %, `tests/test_bending_hysteresis.py`). HB/B is the curvature at which the "
           "friction moment equals the elastic one. Not converged in the mesh (see the elastic "
           "runs above): the effect of the law at one mesh, not a validated DC.", "",
           "| fabric | B [µN·m] | 2HB [mN·m/m] | HB/B [1/m] | DC elastic | DC hysteresis | DC "
           "measured | error elastic | error hysteresis | nodes elastic | nodes hysteresis | "
           "nodes measured | time elastic / hysteresis [s] |", "|---" * 13 + "|"]  # fmt: skip
    by = {}
    for r in runs:
        by.setdefault(r["fabric"], {})[r.get("law", "elastic")] = r
    for fid, laws in by.items():
        m = measured.by_id(fid)
        e, h = laws.get("elastic", {}), laws.get("hysteresis", {})

        def val(r: dict, key: str, fmt: str) -> str:
            return format(r[key], fmt) if r.get("status") == "ok" else "failed" if r else "–"

        out.append(
            f"| {fid} {m.name} | {1e6 * m.B_warp:.2f} | {1e3 * m.twoHB:.3f} | "
            f"{m.twoHB / 2 / m.B_warp:.1f} | {val(e, 'dc', '.3f')} | {val(h, 'dc', '.3f')} | "
            f"{m.dc_measured:.3f} | {val(e, 'dc_error', '+.3f')} | {val(h, 'dc_error', '+.3f')} | "
            f"{val(e, 'nodes', 'd')} | {val(h, 'nodes', 'd')} | {m.nodes_measured or '–'} | "
            f"{val(e, 'wall_s', '.0f')} / {val(h, 'wall_s', '.0f')} |"
        )
    out.append("")
    out += [f"![{r['picture']}]({r['picture']})" for r in runs if r.get("picture")
            and r.get("law") == "hysteresis"]  # fmt: skip
    return [*out, ""]


def tube_markdown(runs: list[dict]) -> list[str]:
    out = ["### Tension–strain membrane law on the Laplace tube", "",
           "A tube (free ends, 1/8 modelled, 8 × 4 cells) wrapped on a rigid cylinder R = 0.1 m, "
           "its membrane law the piecewise-linear tension–strain curves (warp, weft; synthetic "
           "knit-like J curves, not a measurement): the contact pressure in the middle half "
           "against T(e)/R_c at the wrapped strain e (+ bending part), and the quadratic law "
           "with the curve's initial slope.", "",
           "| case | hoop curve | hoop strain | p model [Pa] | p curve [Pa] | error [%] | "
           "p linear law [Pa] | time [s] |", "|---" * 8 + "|"]  # fmt: skip
    for r in runs:
        out.append(f"| {r['case']} | {r['curve']} | {r['strain']:.4f} | {r['value']:.3f} | "
                   f"{r['reference']:.3f} | {_pct(r['rel_error'])} | {r['linear_law']:.2f} | "
                   f"{r['wall_s']:.1f} |")  # fmt: skip
    return [*out, ""]


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    bad = check_args(argv, __doc__, (), {"--n"}, lambda a: a in PARTS or a.isdigit())
    if bad is not None:
        return bad
    meshes = [int(argv[i + 1]) for i, a in enumerate(argv) if a == "--n"] or [8, 16]
    parts = [a for a in argv if a in PARTS] or ["cantilever", "anticlastic", "fabrics", "tube"]
    if "cantilever" in parts:
        run_cantilever(meshes)
    if "anticlastic" in parts:
        run_anticlastic()
    if "fabrics" in parts:
        run_fabrics()
    if "tube" in parts:
        run_tube()
    if "drape" in parts:
        run_drape()
    if "drape-refine" in parts:
        run_drape(DRAPE_REFINE, section="drape_refine")
    if "drape-amplitude" in parts:
        n = len(DRAPE_AMPLITUDES)
        run_drape([("P-m6", 0.012, 0)] * n, DRAPE_AMPLITUDES, section="drape_amplitude")
    if "drape-hysteresis" in parts:
        run_drape([c[:3] for c in DRAPE_HYSTERESIS], section="drape_hysteresis",
                  laws=[c[3] for c in DRAPE_HYSTERESIS])  # fmt: skip
    print(markdown())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
