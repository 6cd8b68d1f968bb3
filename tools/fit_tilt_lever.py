"""Fit the tilt rung's chevron lever against L2 and verify it out of sample; writes
mst_cli/model/data/tilt_lever.json.

When the plates tilt by phi, a chevron is closed by d + phi x_eff: x_eff is where its force
sits (mst_cli.model.mechanics.tilt). L2 gives it at small strain from two linear solves of the
quarter profile (continuum_tilt.linear_tilt_lever_mm). It lies between the wall roots' midpoint
x_r and the chevron's tip W/2, because turning the pad turns the wall's root as well, and the
wall answers that rotation with a deflection along its run. The fit is of the ratio

    a = (x_eff - x_r) / (W/2 - x_r)

as a polynomial in s = theta - pi/4, x = t/L and y = t/(h - t) (the L0 corrections' variables,
mst_cli/model/mechanics/correction.py) and z = t/(t + a_pad), a_pad the inner pad's half width
(a pad shorter than a few t turns with its wall, so the ratio is not the wall's shape alone),
least squares over valid cells drawn uniformly in the printable box
(mst_cli.bench.ladder_bench.sample_cells). Printed: median and max |error| of x_eff out of
sample for the fit, split by pad length, and for the roots' midpoint alone.

Run:  .venv/bin/python tools/fit_tilt_lever.py [--samples 200 --seed 11 --verify 100 --verify-seed 12]
"""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np

from mst_cli.bench.ladder_bench import sample_cells
from mst_cli.model.material import Material
from mst_cli.model.mechanics.continuum import PAD_LENGTH_IN_T
from mst_cli.model.mechanics.continuum_tilt import linear_tilt_lever_mm
from mst_cli.model.mechanics.tilt import LEVER_DATA, lever_features, root_midpoint_mm


def measured(cells, mat):
    """(x_eff from L2, x_c, W/2) of every cell, mm."""
    rows = []
    for c in cells:
        xc = root_midpoint_mm(math.radians(c.theta_deg), c.t_mm, c.p_mm)
        rows.append((linear_tilt_lever_mm(c, mat), xc, 0.5 * c.width_mm))
    return np.array(rows)


def features(cells):
    return np.array([lever_features(math.radians(c.theta_deg), c.t_mm, c.h_mm, c.width_mm) for c in cells])


def errors(coef, cells, rows):
    x_eff, xc, half_w = rows.T
    fitted = xc + (features(cells) @ coef) * (half_w - xc)
    return np.abs(fitted / x_eff - 1.0), np.abs(xc / x_eff - 1.0)


def _short_pad(c) -> bool:
    """The inner pad's half width under PAD_LENGTH_IN_T t: the quarter model's pad reaches the axis."""
    a = c.p_mm - c.t_mm * math.tan(0.5 * math.radians(c.theta_deg))
    return a < PAD_LENGTH_IN_T * c.t_mm


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--samples", type=int, default=200)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--verify", type=int, default=100)
    ap.add_argument("--verify-seed", type=int, default=12)
    args = ap.parse_args()
    mat = Material()
    t0 = time.perf_counter()
    cells = sample_cells(args.samples, args.seed)
    rows = measured(cells, mat)
    x_eff, xc, half_w = rows.T
    coef, *_ = np.linalg.lstsq(features(cells), (x_eff - xc) / (half_w - xc), rcond=None)
    vcells = sample_cells(args.verify, args.verify_seed)
    vrows = measured(vcells, mat)
    fit_in, mid_in = errors(coef, cells, rows)
    fit_out, mid_out = errors(coef, vcells, vrows)
    print(f"L2 linear solves: {len(cells) + len(vcells)} cells in {time.perf_counter() - t0:.0f} s")
    print("| x_eff against L2 | median | max |")
    print("|---|---|---|")
    short = np.array([_short_pad(c) for c in vcells])
    for name, e in (
        (f"fit, in sample ({len(cells)})", fit_in),
        (f"fit, out of sample ({len(vcells)})", fit_out),
        (f"  of which pads shorter than {PAD_LENGTH_IN_T:g} t ({short.sum()})", fit_out[short]),
        (f"  of which longer ({(~short).sum()})", fit_out[~short]),
        ("roots' midpoint alone, out of sample", mid_out),
    ):
        print(f"| {name} | {100 * np.median(e):.2f} % | {100 * e.max():.2f} % |")
    LEVER_DATA.write_text(
        json.dumps(
            {
                "about": "tilt rung lever: a = (x_eff - x_c) / (W/2 - x_c) = coef . lever_features(theta, t, h); "
                "tools/fit_tilt_lever.py",
                "coef": [float(c) for c in coef],
                "samples": args.samples,
                "seed": args.seed,
                "out_of_sample": {
                    "cells": args.verify,
                    "seed": args.verify_seed,
                    "median_rel": float(np.median(fit_out)),
                    "max_rel": float(fit_out.max()),
                },
            },
            indent=2,
        )
        + "\n"
    )
    print(f"wrote {LEVER_DATA}")


if __name__ == "__main__":
    main()
