"""The plate over a locked layer, on the whole-part rung (issue 44, docs/design.md 4.7): the data
mst_cli.model.past_lock is fitted on, and the fit. Prints a table; writes a CSV when asked.

    PYTHONPATH=. .venv/bin/python studies/locked_plates.py --out studies/data/locked_plates.csv
    PYTHONPATH=. .venv/bin/python studies/locked_plates.py --fit studies/data/locked_plates.csv

Each stack is studies/unlike_plates.py's: the forward config with layers A, B, A (t 0.4 mm,
h 1.8 mm, 1.6 mm plates), here for every A and B of 13, 20, 28, 40 and 57 degrees, A below B.
Regime 2 of the rung, layer A (the lowest) locked, its cavity filled; the rung's plate 1 alone
in TPU (plate 2, the cap and the base rigid: ``PartOptions.rigid_plates``) less every member
rigid is what that plate gives over the locked layer, B's root joint on it included. Two rung
solves a stack, about 10 s each (kept in mst's cache: a second run reads them back).

``--fit`` (one file or several) fits model.past_lock's constants (a, k, g) to those rows, the error of
each row being the log of the closed form (B's root joint, model.plate_joint, plus past_lock's
term) over the rung, and prints the rows, the constants and the joint alone's errors beside them
(2 s); ``--fit-press`` the feet's press g alone, a and k held (how g was found: on
locked_plates.csv and locked_plates_thick.csv together).
"""

from __future__ import annotations

import argparse
import csv
import itertools
import math
import tempfile
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

import mst_cli as mst
from mst_cli.errors import InputError
from mst_cli.model import load_path as lp
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.past_lock import LOCKED_FITTED, locked_plates_mm_per_N
from mst_cli.model.plate_joint import root_joint_mm_per_N
from studies.unlike_plates import PLATE_MM, T_MM, THETA_DEG, stack

COLUMNS = ("theta_a_deg", "theta_b_deg", "t_a_mm", "t_b_mm", "h_a_mm", "h_b_mm", "head_a_mm", "head_b_mm",
           "plate_mm", "depth_mm", "E_prime_MPa", "G_MPa", "rung_um_per_N")  # fmt: skip


def rung_row(path: Path) -> dict:
    """One stack's row: its two lower layers, the scene, and the rung's plate over locked layer A."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    scene = lp.member_scene(g, m)
    theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
    _, head, _, _ = lp.layer_supports(scene, theta, t, h)
    locked = {"locked": (0,), "member_factor": wp.RIGID_FACTOR}
    rigid = wp.kept_press(g, m, wp.PartOptions(**locked)).drop_mm_per_N
    alone = wp.PartOptions(**locked, scaled=("base", "cap"), rigid_plates=(1,))
    rung = wp.kept_press(g, m, alone).drop_mm_per_N - rigid
    values = (math.degrees(theta[0]), math.degrees(theta[1]), t[0], t[1], h[0], h[1], head[0], head[1],
              scene.plate_mm, scene.depth_mm, scene.E_prime_MPa, scene.G_MPa, 1e3 * rung)  # fmt: skip
    return dict(zip(COLUMNS, (float(v) for v in values)))


def closed_form_um_per_N(row: dict, constants: tuple[float, float] | None) -> float:
    """B's root joint on the plate, plus past_lock's term with ``constants`` (None: the joint alone)."""
    theta = np.radians([row["theta_a_deg"], row["theta_b_deg"]])
    t, h = np.array([row["t_a_mm"], row["t_b_mm"]]), np.array([row["h_a_mm"], row["h_b_mm"]])
    scene = (row["plate_mm"], row["depth_mm"], row["E_prime_MPa"])
    joint = float(root_joint_mm_per_N(theta[1], t[1], h[1], *scene))
    if constants is None:
        return 1e3 * joint
    head = np.array([row["head_a_mm"], row["head_b_mm"]])
    extra = locked_plates_mm_per_N(theta, t, h, head, *scene, row["G_MPa"], constants)
    return 1e3 * (joint + float(np.asarray(extra)[0]))


def sweep(out: Path, t_b_mm: tuple[float, ...] = (T_MM,), plates_mm: tuple[float, ...] = (PLATE_MM,)) -> None:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for theta_a, theta_b, t_b, plate in itertools.product(THETA_DEG, THETA_DEG, t_b_mm, plates_mm):
            try:
                rows.append(rung_row(stack(Path(tmp), theta_a, theta_b, t_b, plate)))
            except InputError as e:  # a cell that cannot be drawn
                print(f"  skipped A {theta_a:g}, B {theta_b:g} (t {t_b:g} mm), plate {plate:g} mm: {e}", flush=True)
                continue
            print(
                f"  A {theta_a:g}, B {theta_b:g} (t {t_b:g} mm), plate {plate:g} mm: "
                f"rung {rows[-1]['rung_um_per_N']:.2f} um/N",
                flush=True,
            )
    with out.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {out}")


def constant_bounds() -> tuple[list[float], list[float]]:
    """least_squares' bounds on model.past_lock's constants: a in [-1, 10], k in [1e-3, 100], and
    any further ones (g, the feet's press) in [0, 100]."""
    extra = len(LOCKED_FITTED) - 2
    return [-1.0, 1e-3] + [0.0] * extra, [10.0, 100.0] + [100.0] * extra


def fit(paths: list[Path], refit: bool = True, press_only: bool = False) -> None:
    """Fit model.past_lock's constants (a, k, g; as many as LOCKED_FITTED has, the first two bounded
    as a and k, any more at >= 0) to the rows in ``paths`` and print them; with ``press_only`` the
    feet's press g alone, a and k held at the model's; with ``refit`` False, only the errors of
    model.past_lock's own constants on them (rows the fit did not see: a check)."""
    rows = []
    for path in paths:
        with path.open() as f:
            rows += [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]

    def logs(q) -> list[float]:
        return [math.log(closed_form_um_per_N(r, tuple(q)) / r["rung_um_per_N"]) for r in rows]

    if press_only:
        held = LOCKED_FITTED[:2]
        g = least_squares(lambda x: logs((*held, *x)), list(LOCKED_FITTED[2:]), bounds=(0.0, 100.0)).x
        q = (*held, *g)
    else:
        q = least_squares(logs, list(LOCKED_FITTED), bounds=constant_bounds()).x if refit else LOCKED_FITTED
    said = "fitted" if refit else "model.past_lock's"
    print(f"| θ_A, ° | θ_B, ° | t_B, mm | plate, mm | rung, µm/N | joint alone | joint + past_lock ({said}) |")
    print("|---|---|---|---|---|---|---|")
    errors: dict[str, list[float]] = {"alone": [], said: []}
    for r in rows:
        rung, alone, fitted = r["rung_um_per_N"], closed_form_um_per_N(r, None), closed_form_um_per_N(r, tuple(q))
        errors["alone"].append(100 * (alone / rung - 1))
        errors[said].append(100 * (fitted / rung - 1))
        print(
            f"| {r['theta_a_deg']:.0f} | {r['theta_b_deg']:.0f} | {r['t_b_mm']:g} | {r['plate_mm']:g} | {rung:.1f} | "
            f"{alone:.1f} | {fitted:.1f} |"
        )
    print(f"\n{said}: {', '.join(f'{v:.3f}' for v in q)} (model.past_lock.LOCKED_FITTED: {LOCKED_FITTED})")
    for name, e in errors.items():
        rms = math.sqrt(sum(v * v for v in e) / len(e))
        print(f"{name}: worst {max(map(abs, e)):.1f} %, rms {rms:.1f} %")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, help="solve the sweep and write its rows here (CSV)")
    parser.add_argument("--fit", type=Path, nargs="+", help="fit past_lock's constants to these rows (CSVs)")
    parser.add_argument("--check", type=Path, nargs="+", help="past_lock's own constants' errors on these rows (CSVs)")
    parser.add_argument("--fit-press", type=Path, nargs="+", help="fit the feet's press g alone, a and k held (CSVs)")
    parser.add_argument("--t-b", type=float, nargs="*", default=[T_MM], help="with --out: B's walls, mm")
    parser.add_argument("--plates", type=float, nargs="*", default=[PLATE_MM], help="with --out: the plates, mm")
    args = parser.parse_args()
    if args.out is None and args.fit is None and args.check is None and args.fit_press is None:
        parser.error("give --out FILE (the sweep), --fit FILE or --fit-press FILE (the fit) or --check FILE")
    if args.out is not None:
        sweep(args.out, tuple(args.t_b), tuple(args.plates))
    if args.fit is not None:
        fit(args.fit)
    if args.check is not None:
        fit(args.check, refit=False)
    if args.fit_press is not None:
        fit(args.fit_press, press_only=True)


if __name__ == "__main__":
    main()
