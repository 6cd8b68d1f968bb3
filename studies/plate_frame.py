"""The plates' sway (model.plate_sway) against the whole-part rung's measure of it, and the frame's
choices side by side (issue 44, docs/design.md 4.7, "The plates' sway: built"). Prints a table,
changes nothing.

    PYTHONPATH=. .venv/bin/python studies/plate_frame.py --check studies/data/plate_slide.csv \
        studies/data/plate_slide_sweep.csv

The CSVs are studies/plate_slide.py's ``--out``: per design, regime and plate, what that plate
alone in TPU adds to the magnet's translation on the rung (every other member rigid). Here each
design is designed again (a bundled config by its name, a same-layer design ``same-THETA-T-H-P``
by studies/root_turn_sweep.design) and model.plate_sway's frame gives the same figure, in its
chosen form (``plate_sway.ZONES``: the plates rigid under the walls' footprints, the walls' ends
in their pads elastic) and in four others: without the rigid zones under the footprints (``no
plate zones``), with the walls' ends rigid in their pads as well (``walls' ends rigid``, the chosen
form before 2026-12-02), without the root springs (``no roots``), and with the walls as beams, not
scaled to L0's k_x (``beam walls``).
Per form: each row's frame / rung, their median and spread, and the rms of the log ratio. Rows
whose rung figure is under 0.005 mm/N (a plate between two locked layers) are printed, not counted.
Rows of plate 0 (studies/plate_slide.py --base) are the housing's base, in the frame as
model.housing_base's portal (``plate_sway.base_translation_mm_per_N``), counted apart, with mst's
column form (``housing_base.base_sway_mm_per_N``, what the general load takes) beside them.

``--edge-joint CONFIG ...`` (a probe, not kept; docs/design.md 4.7): per regime, the frame's base
(its translation, its turn under the pull and under the pull's moment, mrad/N) and the members'
turn ratio, with the cover's end joined to its slot wall's top as the model has it (pi/8 E'D c^2)
and rigid wherever an open layer 1's wall footprint straddles the slot's edge.
"""

from __future__ import annotations

import argparse
import csv
import tempfile
from pathlib import Path

import numpy as np

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model import plate_sway as ps
from mst_cli.model.housing_base import base_sway_mm_per_N
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.plate_sway import stack_section
from mst_cli.model.stack import Stack
from studies.root_turn_sweep import design

ROOT = Path(__file__).resolve().parents[1]
SMALL_MM_PER_N = 0.005  # below it a rung figure is a plate between locked layers: printed, not counted
# (name, zones (plate, wall), roots, walls scaled to L0)
FORMS = (
    ("chosen", ps.ZONES, True, True),
    ("no plate zones", (False, ps.ZONES[1]), True, True),
    ("walls' ends rigid", (ps.ZONES[0], True), True, True),
    ("no roots", ps.ZONES, False, True),
    ("beam walls", ps.ZONES, True, False),
)


def config_path(name: str, folder: Path) -> Path:
    """A bundled config by its name, or a same-layer design ``same-THETA-T-H-PLATE`` made anew."""
    if name.startswith("same-"):
        theta, t, h, plate = (float(v) for v in name.split("-")[1:])
        return design(folder, theta, t, h, plate)
    return ROOT / "configs" / f"{name}.yaml"


def frame_rows(name: str, folder: Path) -> dict[tuple[int, int], list[float]]:
    """{(regime, plate) from 1: each form's figure, mm/N} of one design."""
    doc, _ = mst.designed(config_path(name, folder))
    g, m = doc.geometry(), doc.material
    sec = stack_section(g, m)
    regimes = wp.regime_locked(Stack(layer_laws(g.layers, m, doc.mechanics)))
    out: dict[tuple[int, int], list[float]] = {}
    for _, zones, roots, scaled in FORMS:
        walls = ps.wall_factors(sec, zones) if scaled else np.ones(len(g.layers))
        for r, locked in enumerate(regimes):
            moved = ps.plate_translations_mm_per_N(sec, tuple(locked), walls, zones, roots)
            for j, v in enumerate(moved):
                out.setdefault((r + 1, j + 1), []).append(float(v))
            base = ps.base_translation_mm_per_N(sec, tuple(locked), walls, zones, roots)
            out.setdefault((r + 1, 0), []).append(base)
    return out


def check(paths: list[Path]) -> None:
    rows = [row for p in paths for row in csv.DictReader(p.open())]
    print("| design | regime | plate | rung, mm/N | " + " | ".join(f"{f[0]} / rung" for f in FORMS) + " |")
    print("|---|---|---|---|" + "---|" * len(FORMS))
    ratios: dict[str, list[list[float]]] = {"plates": [[] for _ in FORMS], "base": [[] for _ in FORMS]}
    cache: dict[str, dict] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for row in rows:
            name, r, j, rung = row["design"], int(row["regime"]), int(row["plate"]), float(row["rung_mm_per_N"])
            if name not in cache:
                cache[name] = frame_rows(name, Path(tmp))
            figures = cache[name][(r, j)]
            counted = rung >= SMALL_MM_PER_N
            cells = [f"{v / rung:.2f}" if counted else f"({v:.4f})" for v in figures]
            print(f"| {name} | {r} | {j or 'base'} | {rung:.4f} | " + " | ".join(cells) + " |", flush=True)
            if counted:
                for k, v in enumerate(figures):
                    ratios["base" if j == 0 else "plates"][k].append(v / rung)
    bases = [row for row in rows if int(row["plate"]) == 0]
    if bases:
        print()
        print("| design | regime | the base on the rung, mm/N | frame / rung | mst's column form / rung |")
        print("|---|---|---|---|---|")
        for row in bases:
            name, r, rung = row["design"], int(row["regime"]), float(row["rung_mm_per_N"])
            doc, _ = mst.designed(config_path(name, Path(".")))
            column = base_sway_mm_per_N(lp.member_scene(doc.geometry(), doc.material))
            print(f"| {name} | {r} | {rung:.4f} | {cache[name][(r, 0)][0] / rung:.2f} | {column / rung:.2f} |")
    print()
    print("| members | form | rows | frame / rung: median (spread) | rms log ratio |")
    print("|---|---|---|---|---|")
    for member, by_form in ratios.items():
        for (form, *_), q in zip(FORMS, by_form):
            if not q:
                continue
            q = np.array(q)
            rms = float(np.sqrt(np.mean(np.log(np.maximum(q, 1e-3)) ** 2)))  # a form giving 0: 1e-3
            print(f"| {member} | {form} | {len(q)} | {np.median(q):.2f} ({q.min():.2f} to {q.max():.2f}) | {rms:.3f} |")


def rigid_edge_base(f, s, cover: dict, z_cover: float) -> None:
    """plate_sway._base with the cover's end joint rigid where layer 1's wall footprint (open or
    not: the probe) straddles the slot's edge (the rigid zone under it reaching the joint)."""
    half_print = 0.5 * s.t_mm[0] / np.sin(s.theta_rad[0])
    if abs(s.half_slot_mm - s.head_mm[0]) >= half_print:
        return KEPT_BASE(f, s, cover, z_cover)
    spring = f.spring

    def joint(a, b, k):  # of the base's springs only the cover's end joint stands at the edge
        edge = any(abs(abs(f.nodes[n][0]) - s.half_slot_mm) < 1e-9 for n in (a, b))
        return spring(a, b, ps.RIGID * s.E_prime_MPa * s.depth_mm if edge else k)

    f.spring = joint
    try:
        KEPT_BASE(f, s, cover, z_cover)
    finally:
        f.spring = spring


KEPT_BASE = ps._base


def regimes_of(configs: list[Path]):
    """For each config and regime: (the design's name, the regime from 1, its frame section, the
    walls' factors, the layers locked before it)."""
    for path in configs:
        doc, _ = mst.designed(path)
        g, m = doc.geometry(), doc.material
        sec = stack_section(g, m)
        walls = ps.wall_factors(sec)
        for r, locked in enumerate(wp.regime_locked(Stack(layer_laws(g.layers, m, doc.mechanics)))):
            yield doc.name, r + 1, sec, walls, tuple(locked)


def motions_with_base(base, sec, members, locked, walls):
    """ps.member_motions with the frame's base built by ``base`` for the call only."""
    ps._base = base
    try:
        return ps.member_motions(sec, members, locked, walls)
    finally:
        ps._base = KEPT_BASE


def edge_joint(configs: list[Path]) -> None:
    print("| design | regime | joint | base: translation mm/N | turn | moment's turn | members' ratio |")
    print("|---|---|---|---|---|---|---|")
    for name, regime, sec, walls, locked in regimes_of(configs):
        members = [-1, *range(len(sec.theta_rad) - 1)]
        for label, base in (("as modelled", KEPT_BASE), ("rigid at the edge", rigid_edge_base)):
            mo = motions_with_base(base, sec, members, locked, walls)
            ratio = mo.turn_rad_per_N.sum() / mo.moment_turn_rad_per_N.sum()
            cells = f"{mo.translation_mm_per_N[0]:.4f} | {1e3 * mo.turn_rad_per_N[0]:.3f} | "
            cells += f"{1e3 * mo.moment_turn_rad_per_N[0]:.3f} | {ratio:.3f}"
            print(f"| {name} | {regime} | {label} | {cells} |")


def scaled_columns_base(factor: float, joint_factor: float = 1.0):
    """plate_sway._base with the slot's two walls (their columns and their roots' springs) ``factor``
    times as stiff, and the cover's end joints into their tops ``joint_factor`` times: the probe of
    what the walls' give does to the cover's turn."""

    def base(f, s, cover: dict, z_cover: float) -> None:
        beam, spring = f.beam, f.spring
        z_root = z_cover - 0.5 * s.cover_mm - s.slot_height_mm

        def column(a, b, EA, EI, kGA):  # the only vertical beams of the base are its walls
            vertical = abs(f.nodes[a][0] - f.nodes[b][0]) < 1e-12
            k = factor if vertical else 1.0
            return beam(a, b, k * EA, k * EI, k * kGA)

        def root(a, b, k):  # the roots' springs stand at the slot's floor, the cover's joints at its edge
            if abs(f.nodes[a][1] - z_root) < 1e-12:
                return spring(a, b, factor * k)
            edge = any(abs(abs(f.nodes[n][0]) - s.half_slot_mm) < 1e-9 for n in (a, b))
            return spring(a, b, joint_factor * k if edge else k)

        f.beam, f.spring = column, root
        try:
            KEPT_BASE(f, s, cover, z_cover)
        finally:
            f.beam, f.spring = beam, spring

    return base


def base_columns(configs: list[Path], joint_factor: float = 1.0) -> None:
    """Per config and regime, the base alone in TPU (the frame's): its translation, its turn under
    the pull and the pull's moment-equivalent, with the slot's walls as modelled and 1e5 times as
    stiff (the rung's counterpart: bench_whole_part.py --off-centre --every-regime, "only the base,
    its slot walls rigid"), the cover's end joints ``joint_factor`` times as stiff."""
    print("| design | regime | slot walls | base: translation mm/N | turn under the pull, mrad/N | moment's turn |")
    print("|---|---|---|---|---|---|")
    cases = (("as modelled", 1.0), ("rigid", ps.RIGID))
    for name, regime, sec, walls, locked in regimes_of(configs):
        for label, factor in cases:
            mo = motions_with_base(scaled_columns_base(factor, joint_factor), sec, [-1], locked, walls)
            cells = f"{mo.translation_mm_per_N[0]:.4f} | {1e3 * mo.turn_rad_per_N[0]:.3f} | "
            print(f"| {name} | {regime} | {label} | {cells}{1e3 * mo.moment_turn_rad_per_N[0]:.3f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", type=Path, nargs="+", help="studies/plate_slide.py --out CSVs")
    ap.add_argument("--edge-joint", type=Path, nargs="+", help="configs: the cover's edge joint probe")
    ap.add_argument("--base-columns", type=Path, nargs="+", help="configs: the slot's walls made rigid, a probe")
    ap.add_argument("--joint-factor", type=float, default=1.0, help="with --base-columns: on the cover's end joints")
    args = ap.parse_args()
    if args.edge_joint:
        edge_joint(args.edge_joint)
    elif args.base_columns:
        base_columns(args.base_columns, args.joint_factor)
    elif args.check:
        check(args.check)
    else:
        ap.error("give --check CSVs, --edge-joint or --base-columns configs")


if __name__ == "__main__":
    main()
