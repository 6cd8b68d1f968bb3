"""What each TPU plate adds to the magnet's slide and turn under a tangential force, per regime
(issue 44, docs/design.md 4.7, "The plates under a tangential force: measured"). Prints a table,
changes nothing.

    PYTHONPATH=. .venv/bin/python studies/plate_slide.py [--configs ...]
    PYTHONPATH=. .venv/bin/python studies/plate_slide.py --sweep
    PYTHONPATH=. .venv/bin/python studies/plate_slide.py --sweep --out studies/data/plate_slide_sweep.csv

``--out``: the rows also as CSV (the design's name, regime, plate, the rung's translation), what
studies/plate_frame.py --check reads. ``--base``: the housing's base instead (the cover, the
slot's walls and floor) alone in TPU, its translation less its turn's share about the cover's
mid-plane, as "plate 0".

``--sweep``: instead of the configs, same-layer designs over the box in regime 1
(studies/root_turn_sweep.py's designs: the forward config with three layers (theta, t, h) and
plates 1.6 mm thick), not the bundled ones: the ratio's spread there is what a constant factor
on the roots' estimate can be fitted on and the bundled designs checked against.

mst's closed form turns the plates with their layers under a moment and slides no plate. Here the
whole-part rung (:func:`mst_cli.model.mechanics.whole_part.press_general`) pulls the part along
+x at the top face with every member rigid, then with one plate alone in TPU (the other plates,
the cap and the base rigid: ``PartOptions.rigid_plates``), in every regime (the layers locked
before it closed). Per plate: the slide and turn it adds (as printed less rigid), and the slide
less the turn's share (everything above the plate's mid-plane turning with it: a turn about +y
of -phi moves the magnet phi (z_magnet - z_plate) along +x), what is left to translate.

Beside it, one candidate mechanism: the walls' roots turning into the plate, with the spring the
centred press's fit gives them (:data:`mst_cli.model.plate_joint.FITTED`,
M / phi = c sin(theta)^a (L/t)^b E'D t^2). Along x a wall is a cantilever from its root to the
chevron's tip (:mod:`mst_cli.model.mechanics.lateral`); each of a layer's two chevrons carries
half the force, whose part across the wall, sin(theta) / 2 per newton, gives the root the moment
M = L sin(theta) / 2 and the slide M^2 / k. Two roots of each open layer beside the plate count
(its heads below it, its feet above it); a locked layer's walls carry nothing. The ratio is the
rung's slide less the turn's share over that sum. Nine to twelve rung solves a design, about 7 s each.
"""

from __future__ import annotations

import argparse
import csv
import itertools
import tempfile
from pathlib import Path

import numpy as np

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.cell import wall_centreline_length_mm
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.plate_joint import root_spring_Nmm_per_rad
from mst_cli.model.stack import Stack
from studies.root_turn_sweep import design

ROOT = Path(__file__).resolve().parents[1]
CSV_COLUMNS = ("design", "regime", "plate", "rung_mm_per_N")
CONFIGS = ("mohammadi2021", "mohammadi2021-forward", "fingertip")
SWEEP_THETA_DEG, SWEEP_T_MM, SWEEP_H_MM, SWEEP_PLATE_MM = (15.0, 33.0, 50.0), (0.4, 0.8), (2.4,), 1.6


def root_slides_mm_per_N(geometry, material) -> np.ndarray:
    """(n,) one layer's two roots on one plate turning against the fitted spring, mm of slide per
    newton along x (module docstring)."""
    s = lp.member_scene(geometry, material)
    theta, t, h = (np.array([getattr(c, k) for c in geometry.layers], dtype=float) for k in lp.CELL_KEYS)
    L = wall_centreline_length_mm(theta, t, h)
    k = root_spring_Nmm_per_rad(theta, t, L, s.depth_mm, s.E_prime_MPa)
    M = 0.5 * np.sin(theta) * L
    return 2.0 * M * M / k


def rows(path: Path, regimes: int | None = None, out: list | None = None) -> list[float]:
    """Print per regime (the first ``regimes``; None: all) and plate of the design at ``path``:
    the rung's slide (mm/N) and turn (mrad/N) that plate adds, the roots' estimate and the ratio;
    return the ratios (where the roots' estimate is not 0); append (name, regime, plate, the
    translation) to ``out`` when given."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    roots = root_slides_mm_per_N(g, m)
    plates = range(len(g.layers) - 1)
    z_magnet = g.z_magnet_bottom_mm + 0.5 * g.magnet.thickness_mm
    z_plate = [g.layer_bottoms_mm[j + 1] - 0.5 * g.housing.plate_mm for j in plates]
    ratios = []
    for r, locked in enumerate(wp.regime_locked(Stack(layer_laws(g.layers, m, doc.mechanics)))[:regimes]):
        rigid = wp.press_general(g, m, wp.PartOptions(member_factor=wp.RIGID_FACTOR, locked=locked)).pull
        for j in plates:
            alone = wp.PartOptions(
                member_factor=wp.RIGID_FACTOR,
                scaled=("base", "cap"),
                rigid_plates=tuple(i for i in plates if i != j),
                locked=locked,
            )
            x = wp.press_general(g, m, alone).pull
            slide, turn = x.side_mm_per_N - rigid.side_mm_per_N, x.turn_rad_per_N - rigid.turn_rad_per_N
            moved = slide + turn * (z_magnet - z_plate[j])
            estimate = sum(roots[i] for i in (j, j + 1) if i not in locked)
            ratio = f"{moved / estimate:.1f}" if estimate > 0.0 else "-"
            if estimate > 0.0:
                ratios.append(moved / estimate)
            if out is not None:
                out.append((doc.name, r + 1, j + 1, f"{moved:.6f}"))
            print(
                f"| {doc.name} | {r + 1} | {j + 1} | {rigid.side_mm_per_N:.4f} | {slide:.4f} | {1e3 * turn:+.2f} | "
                f"{moved:.4f} | {estimate:.4f} | {ratio} |",
                flush=True,
            )
    return ratios


def base_rows(path: Path, out: list | None = None) -> None:
    """Print per regime the rung's slide and turn the base alone adds to the magnet's, and what is
    left less the turn's share about the cover's mid-plane; append the rows to ``out`` as plate 0."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    z_magnet = g.z_magnet_bottom_mm + 0.5 * g.magnet.thickness_mm
    z_cover = g.z_base_top_mm - 0.5 * g.housing.cover_mm
    for r, locked in enumerate(wp.regime_locked(Stack(layer_laws(g.layers, m, doc.mechanics)))):
        rigid = wp.press_general(g, m, wp.PartOptions(member_factor=wp.RIGID_FACTOR, locked=locked)).pull
        alone = wp.PartOptions(member_factor=wp.RIGID_FACTOR, scaled=("plate", "cap"), locked=locked)
        x = wp.press_general(g, m, alone).pull
        slide, turn = x.side_mm_per_N - rigid.side_mm_per_N, x.turn_rad_per_N - rigid.turn_rad_per_N
        moved = slide + turn * (z_magnet - z_cover)
        print(f"| {doc.name} | {r + 1} | base | {rigid.side_mm_per_N:.4f} | {slide:.4f} | {1e3 * turn:+.2f} | "
              f"{moved:.4f} | - | - |", flush=True)  # fmt: skip
        if out is not None:
            out.append((doc.name, r + 1, 0, f"{moved:.6f}"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--configs", nargs="*", type=Path, default=[ROOT / "configs" / f"{c}.yaml" for c in CONFIGS])
    ap.add_argument("--sweep", action="store_true", help="same-layer designs over the box, regime 1")
    ap.add_argument("--out", type=Path, help="the rows also as CSV here")
    ap.add_argument("--base", action="store_true", help="the housing's base alone in TPU instead of each plate")
    args = ap.parse_args()
    print("per newton along +x at the top face; a plate alone in TPU, the rest rigid, less all rigid")
    print("| design | regime | plate | slide, all rigid, mm/N | plate's slide, mm/N | plate's turn, mrad/N |", end="")
    print(" less the turn's share, mm/N | roots' M^2/k, mm/N | rung / roots |")
    print("|---|---|---|---|---|---|---|---|---|")
    table: list = []
    if args.base:
        for path in args.configs:
            base_rows(path, out=table)
    elif not args.sweep:
        for path in args.configs:
            rows(path, out=table)
    else:
        ratios = []
        with tempfile.TemporaryDirectory() as tmp:
            for theta, t, h in itertools.product(SWEEP_THETA_DEG, SWEEP_T_MM, SWEEP_H_MM):
                ratios += rows(design(Path(tmp), theta, t, h, SWEEP_PLATE_MM), regimes=1, out=table)
        spread = f"{min(ratios):.2f} to {max(ratios):.2f}"
        print(f"rung / roots over {len(ratios)} plates: median {np.median(ratios):.2f}, {spread}")
    if args.out:
        with args.out.open("w", newline="") as f:
            w = csv.writer(f)
            w.writerow(CSV_COLUMNS)
            w.writerows(table)


if __name__ == "__main__":
    main()
