"""The plates together past the first lock, on the whole-part rung (issue 44, docs/design.md 4.7):
what the part's prediction sees of model.past_lock, and its constants fitted on that. Prints a
table; writes a CSV when asked.

    PYTHONPATH=. .venv/bin/python studies/locked_plates_together.py --out FILE [--t-b MM ...] [--plates MM ...]
        [--h-b MM ...]
    PYTHONPATH=. .venv/bin/python studies/locked_plates_together.py --fit FILE [FILE ...]

studies/locked_plates.py measures one plate alone in TPU (the other rigid), the plate over the
locked layer. In the part both plates give at once, and on a stack with a short layer between
them the two together give more than the sum of each alone (the fingertip spec designed
with studies/data/past_lock_richer.patch and plate_joint_log_squeeze.patch applied: 240.9 against
123.1 + 49.9 um/N in its second regime, ``--alone``). Here each stack A, B, A (studies/unlike_plates.py, every A and B
of 13, 20, 28, 40 and 57 degrees) is solved in its own second regime (its first lock, as mst's
forward model orders them), its plates together in TPU (the cap and the base rigid) less every
member rigid, against the closed form's plates in that regime
(model.load_path.member_band_compliances: the open plates' joints and bending, the plate over
the locked layer). Two rung solves a stack, about 10 s each.

``--alone DESIGN.yaml`` prints a design's plates in its second regime, each alone and together,
beside the closed form's (4 rung solves on three layers). ``--fit`` fits model.past_lock's
constants (a, k) to those rows, the error of each the
log of the closed form's plates over the rung's, with the open plates' closed form as it is
(model.plate_joint, fitted on its own), and prints the rows and both sets' errors (a minute).
"""

from __future__ import annotations

import argparse
import csv
import itertools
import math
import tempfile
from pathlib import Path

import numpy as np

import mst_cli as mst
from mst_cli.errors import InputError
from mst_cli.model import load_path as lp
from mst_cli.model import past_lock
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.stack import Stack
from studies.locked_plates import constant_bounds
from studies.unlike_plates import H_MM, PLATE_MM, T_MM, THETA_DEG, stack

COLUMNS = ("theta_a_deg", "theta_b_deg", "t_b_mm", "h_b_mm", "plate_mm", "locked", "rung_um_per_N")


def second_regime(g, m) -> tuple[int, np.ndarray, dict]:
    """(the layer locked first, as the forward model orders the locks; the closed form's members
    per regime, model.load_path.member_band_compliances) of a geometry."""
    parts, laws = lp.members(g, m), layer_laws(g.layers, m, "spring")
    units = lp.capped_units(laws, parts)
    first = int(np.argsort([u.lock_force_N for u in units], kind="stable")[0])
    moving = lp.member_band_compliances(Stack(laws), parts)[2]
    return first, moving["plates"], moving


def rung_row(path: Path, row: dict) -> dict:
    """One stack's row: the rung's plates together in its second regime, um/N."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    first, _, _ = second_regime(g, m)
    locked = {"locked": (first,), "member_factor": wp.RIGID_FACTOR}
    rigid = wp.kept_press(g, m, wp.PartOptions(**locked)).drop_mm_per_N
    plates = wp.kept_press(g, m, wp.PartOptions(**locked, scaled=("base", "cap"))).drop_mm_per_N - rigid
    return {**row, "locked": first, "rung_um_per_N": 1e3 * plates}


def sweep(out: Path, t_b: tuple, plates: tuple, h_b: tuple) -> None:
    with tempfile.TemporaryDirectory() as tmp, out.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        for theta_a, theta_b, t, plate, h in itertools.product(THETA_DEG, THETA_DEG, t_b, plates, h_b):
            row = {"theta_a_deg": theta_a, "theta_b_deg": theta_b, "t_b_mm": t, "h_b_mm": h, "plate_mm": plate}
            try:
                done = rung_row(stack(Path(tmp), theta_a, theta_b, t, plate, h), row)
            except InputError as e:  # a cell that cannot be drawn
                print(f"  skipped {row}: {e}", flush=True)
                continue
            print(f"  {row}: locked {done['locked']}, rung {done['rung_um_per_N']:.2f} um/N", flush=True)
            writer.writerow(done)
            f.flush()  # each row as it comes: a long sweep can be stopped
    print(f"wrote {out}")


def alone_and_together(path: Path) -> None:
    """The plates of a design on the rung in its second regime (its first lock closed): each plate
    alone in TPU (the others, the cap and the base rigid), and all of them together, less every
    member rigid, um/N; the closed form's plates there beside them."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    first, plates, _ = second_regime(g, m)
    base = {"locked": (first,), "member_factor": wp.RIGID_FACTOR}
    rigid = wp.kept_press(g, m, wp.PartOptions(**base)).drop_mm_per_N
    count = len(g.layers) - 1
    alone = []
    for j in range(count):
        others = tuple(i for i in range(count) if i != j)
        opts = wp.PartOptions(**base, scaled=("base", "cap"), rigid_plates=others)
        alone.append(1e3 * (wp.kept_press(g, m, opts).drop_mm_per_N - rigid))
    both = 1e3 * (wp.kept_press(g, m, wp.PartOptions(**base, scaled=("base", "cap"))).drop_mm_per_N - rigid)
    each = ", ".join(f"{a:.1f}" for a in alone)
    closed = 1e3 * float(plates[1])
    print(f"{doc.name}, layer {first + 1} locked: each plate alone {each} um/N (sum {sum(alone):.1f}); "
          f"together {both:.1f}; the closed form's plates {closed:.1f}")  # fmt: skip


def closed_um_per_N(rows: list[dict], folder: Path) -> list:
    """Per row, a function of past_lock's constants giving the closed form's plates in the row's
    second regime, um/N: the part of it past_lock does not give is fixed, the rest recomputed."""
    out = []
    for r in rows:
        path = stack(folder, r["theta_a_deg"], r["theta_b_deg"], r["t_b_mm"], r["plate_mm"], r["h_b_mm"])
        doc, _ = mst.designed(path)
        g, m = doc.geometry(), doc.material

        def plates(q, g=g, m=m) -> float:
            saved = past_lock.LOCKED_FITTED
            past_lock.LOCKED_FITTED = tuple(q)  # a study's fit: the model reads its module constants
            try:
                return 1e3 * float(second_regime(g, m)[1][1])
            finally:
                past_lock.LOCKED_FITTED = saved

        out.append(plates)
    return out


def fit(paths: list[Path], bottom_first: bool = False) -> None:
    from scipy.optimize import least_squares  # deferred: scipy only for the fit

    rows = []
    for path in paths:
        with path.open() as f:
            rows += [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
    if bottom_first:  # only the stacks whose bottom layer locks first: a plate over a locked layer
        rows = [r for r in rows if r["locked"] == 0]
    with tempfile.TemporaryDirectory() as tmp:
        closed = closed_um_per_N(rows, Path(tmp))
        rung = np.array([r["rung_um_per_N"] for r in rows])

        def logs(q) -> np.ndarray:
            return np.log(np.array([c(q) for c in closed]) / rung)

        q = least_squares(logs, list(past_lock.LOCKED_FITTED), bounds=constant_bounds()).x
        now, fitted = np.exp(logs(past_lock.LOCKED_FITTED)) - 1, np.exp(logs(q)) - 1
    print("| θ_A, ° | θ_B, ° | t_B, mm | h_B, mm | plate, mm | locked | rung, µm/N | model.past_lock's | fitted |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r, a, b in zip(rows, now, fitted):
        cells = (f"{r['theta_a_deg']:.0f}", f"{r['theta_b_deg']:.0f}", f"{r['t_b_mm']:g}", f"{r['h_b_mm']:g}",
                 f"{r['plate_mm']:g}", f"{r['locked']:.0f}", f"{r['rung_um_per_N']:.1f}", f"{100 * a:+.1f} %",
                 f"{100 * b:+.1f} %")  # fmt: skip
        print("| " + " | ".join(cells) + " |")
    print(f"\nfitted {', '.join(f'{v:.3f}' for v in q)} (model.past_lock.LOCKED_FITTED: {past_lock.LOCKED_FITTED})")
    for name, e in (("model.past_lock's", now), ("fitted", fitted)):
        print(f"{name}: worst {100 * np.max(np.abs(e)):.1f} %, rms {100 * math.sqrt(np.mean(e**2)):.1f} %")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, help="solve the sweep and write its rows here (CSV)")
    parser.add_argument("--fit", type=Path, nargs="+", help="fit past_lock's constants to these rows (CSVs)")
    parser.add_argument("--alone", type=Path, help="a design (YAML): its plates alone and together, second regime")
    parser.add_argument(
        "--bottom-first", action="store_true", help="with --fit: only the stacks whose bottom locks first"
    )
    parser.add_argument("--t-b", type=float, nargs="*", default=[T_MM], help="with --out: B's walls, mm")
    parser.add_argument("--h-b", type=float, nargs="*", default=[H_MM], help="with --out: B's height, mm")
    parser.add_argument("--plates", type=float, nargs="*", default=[PLATE_MM], help="with --out: the plates, mm")
    args = parser.parse_args()
    if args.out is None and args.fit is None and args.alone is None:
        parser.error("give --out FILE (the sweep), --fit FILE ... or --alone DESIGN")
    if args.alone is not None:
        alone_and_together(args.alone)
    if args.out is not None:
        sweep(args.out, tuple(args.t_b), tuple(args.plates), tuple(args.h_b))
    if args.fit is not None:
        fit(args.fit, args.bottom_first)


if __name__ == "__main__":
    main()
