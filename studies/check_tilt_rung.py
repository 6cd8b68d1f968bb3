"""The tilt rung against L2 under tilted plates, out of sample (issue 24).

For cells drawn uniformly in the printable box (pads longer than 4 t, so the quarter model's pad
cut lies away from the axis), L2 follows one chevron through its lock with the plates closing by d
at the axis and tilting by phi = tau d (mst_cli.model.mechanics.continuum_tilt): the loaded
chevron with +tau, the other with -tau. The tilt rung says, per chevron:

* before the pads touch, the chevron is the untilted layer at the closure d (1 + tau x_c), x_c its
  fitted lever (checked against L2's own untilted curve, so that only the tilt's assumptions are
  tested, not L0's fits);
* the pads touch first at their loaded end: the loaded chevron locks at d = d_lock / (1 + tau a).

Printed: per cell, the largest deviation of the two chevrons' forces before the loaded side
locks, and the loaded side's lock stroke against the rung's; the other chevron from there on
through its own lock (its quarter's pads, from the cut x_cut = a - 4 t to a, touch first at the
cut) and its lock stroke; then medians and maxima, and the same with the lever at the wall
roots' midpoint (the rung before its lever was fitted).

Run:  .venv/bin/python studies/check_tilt_rung.py [--cells 24 --seed 21 --tau 0.03]   # ~1 min
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from mst_cli.bench.tilt_bench import cells_with_long_pads, check_tilt_cell
from mst_cli.model.material import Material


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cells", type=int, default=24)
    ap.add_argument("--seed", type=int, default=21)
    ap.add_argument("--tau", type=float, default=0.03, help="tilt per mm of closure, rad/mm")
    args = ap.parse_args()
    mat = Material()
    t0 = time.perf_counter()
    rows = [check_tilt_cell(c, mat, args.tau) for c in cells_with_long_pads(args.cells, args.seed)]
    print(f"tau = {args.tau} rad/mm; {len(rows)} cells; {time.perf_counter() - t0:.0f} s of L2")
    print(
        "| theta [deg] | t [mm] | h [mm] | L2 lock | fitted lever: halfway / worst before the lock "
        "| roots' midpoint: halfway / worst | lock stroke vs pads touching at +a "
        "| other side through its lock: worst / its lock stroke |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        c = r["cell"]
        print(
            f"| {c.theta_deg:.1f} | {c.t_mm:.2f} | {c.h_mm:.2f} | {r['contact_at']} "
            f"| {100 * r['fit_half']:.2f} / {100 * r['fit']:.2f} % "
            f"| {100 * r['roots_half']:.2f} / {100 * r['roots']:.2f} % | {100 * r['lock_rel']:+.2f} % "
            f"| {100 * r['fit_far']:.2f} % / {100 * r['far_lock_rel']:+.2f} % |"
        )
    shallow = np.array([r["cell"].theta_deg <= 40.0 for r in rows])
    for key, name in (
        ("fit_half", "halfway, fitted lever"),
        ("fit", "worst before the lock, fitted lever"),
        ("roots_half", "halfway, roots' midpoint"),
        ("roots", "worst before the lock, roots' midpoint"),
        ("lock_rel", "lock stroke"),
        ("fit_far", "other side, from the loaded lock through its own, fitted lever"),
        ("far_lock_rel", "other side's lock stroke (pads touching at the cut)"),
    ):
        e = np.abs([r[key] for r in rows])
        print(
            f"{name}: median {100 * np.median(e):.2f} %, max {100 * e.max():.2f} %; "
            f"theta <= 40 deg ({shallow.sum()}): median {100 * np.median(e[shallow]):.2f} %, "
            f"max {100 * e[shallow].max():.2f} %"
        )


if __name__ == "__main__":
    main()
