"""Regenerate the sample meshes, the pictures and the timing table of the geometry layer.

    python meshes/make_samples.py            # writes meshes/*.msh and docs/img/*.png
    python meshes/make_samples.py --timings  # also times body + gilet at 10/15/20 mm

Samples: the default mannequin (size 88) cropped to the torso band with region physical groups,
a gilet and a dress on it (20 mm triangles, to stay small).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import gmsh

from fenics_garment.geometry import MeshSizes, make_mannequin, measurements
from fenics_garment.geometry.garments import make_dress, make_gilet, make_stocking
from fenics_garment.geometry.pictures import body_regions_png, garment_on_body_png

HERE = Path(__file__).parent
IMG = HERE.parent / "docs" / "img"


def write_garment_msh(build, path: Path) -> None:
    """Rebuild a garment inside a gmsh session and write its model (physical groups kept)."""
    import fenics_garment.geometry.garments as gm

    original = gm._finish

    def capture(kind, comm, b, table):
        with gm.gmsh_session(name=kind) as g:
            b(g)
            g.option.setNumber("Mesh.MshFileVersion", 4.1)
            g.option.setNumber("Mesh.SaveAll", 0)
            gmsh.write(str(path))
        return None

    gm._finish = capture
    try:
        build()
    finally:
        gm._finish = original


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--timings", action="store_true")
    args = p.parse_args()
    IMG.mkdir(parents=True, exist_ok=True)
    m = measurements("88")
    full = make_mannequin(m, MeshSizes(0.03, 0.015, band=(0.8, 1.5)))
    body_regions_png(full, IMG / "mannequin_regions.png")
    for make in (make_gilet, make_dress, make_stocking):
        gar = make(full)
        garment_on_body_png(full, gar, IMG / f"{gar.kind}_on_mannequin.png")
    torso = make_mannequin(m, MeshSizes(0.03, 0.02), z_range=(0.75, 1.55), legs=False)
    torso.write(HERE / "mannequin_torso.msh")
    write_garment_msh(lambda: make_gilet(torso, h=0.02), HERE / "gilet.msh")
    write_garment_msh(lambda: make_dress(torso, h=0.025), HERE / "dress.msh")
    if args.timings:
        print("| h (mm) | body s | body triangles | gilet s | gilet cells |")
        print("|---|---|---|---|---|")
        for h in (0.010, 0.015, 0.020):
            t0 = time.perf_counter()
            b = make_mannequin(m, MeshSizes(0.03, h, band=(0.8, 1.5)))
            t1 = time.perf_counter()
            gi = make_gilet(b, h=h)
            t2 = time.perf_counter()
            print(f"| {h * 1e3:.0f} | {t1 - t0:.1f} | {len(b.triangles)} | {t2 - t1:.1f} | "
                  f"{len(gi.cells)} |")  # fmt: skip


if __name__ == "__main__":
    main()
