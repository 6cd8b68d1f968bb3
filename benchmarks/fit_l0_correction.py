"""Fit the L0 stiffness correction against the L2 continuum model; writes
mst_cli/data/l0_correction.json.

The ratio k_L2 / k_L0 of a plane-stress strut depends only on the profile's shape, i.e. on
theta and t/L (and nu): both stiffnesses scale with E b, and the shape scaled by L is fixed by
theta and t/L. Model: ln(k_L2 / k_L0) = x * P(x, theta), x = t/L, so the correction vanishes
in the slender limit (beam theory). Least squares over a seeded sample of valid cells inside
the design bounds (theta 15-60 deg, t 0.4-2.0 mm, h 1.2-6 mm), linear L2 solves only.

Run:  .venv/bin/python benchmarks/fit_l0_correction.py [--samples 200] [--seed 1]
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from mst_cli.bench import sample_cells
from mst_cli.material import Material
from mst_cli.mechanics import correction
from mst_cli.mechanics.continuum import linear_stiffness_N_per_mm
from mst_cli.mechanics.spring import spring_arrays


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--samples", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    mat = Material()
    cells = sample_cells(args.samples, args.seed)
    x = np.array([c.t_mm / c.wall_length_mm for c in cells])
    th = np.array([c.theta_rad for c in cells])
    k0 = np.array([float(spring_arrays(c.theta_rad, c.t_mm, c.h_mm, c.b_mm, c.struts_per_chevron,
                                       c.width_mm, c.contact_allowance_mm, mat.youngs_modulus_MPa,
                                       mat.poisson_ratio, corrected=False)[0]) for c in cells])
    k2 = np.array([linear_stiffness_N_per_mm(c, mat) for c in cells])
    y = np.log(k2 / k0)
    A = correction.design_matrix(x, th)
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    fit = A @ coef
    resid = np.exp(y - fit) - 1.0
    out = {
        "model": "ln(k_L2/k_L0) = sum_i c_i * terms_i(x = t/L, theta_rad)",
        "terms": correction.TERMS,
        "coefficients": [float(c) for c in coef],
        "fitted_on": {"samples": len(cells), "seed": args.seed, "poisson_ratio": mat.poisson_ratio,
                      "t_over_L_range": [float(x.min()), float(x.max())],
                      "theta_deg_range": [float(np.degrees(th.min())), float(np.degrees(th.max()))],
                      "ratio_range": [float(np.exp(y.min())), float(np.exp(y.max()))],
                      "median_abs_residual": float(np.median(np.abs(resid))),
                      "max_abs_residual": float(np.max(np.abs(resid)))},
        "command": f".venv/bin/python benchmarks/fit_l0_correction.py --samples {args.samples} --seed {args.seed}",
    }
    path = Path(correction.__file__).parent.parent / "data" / "l0_correction.json"
    path.write_text(json.dumps(out, indent=2) + "\n")
    print(f"k_L2/k_L0 from {math.exp(y.min()):.3f} to {math.exp(y.max()):.3f}; after the fit "
          f"median |residual| {np.median(np.abs(resid)):.2%}, max {np.max(np.abs(resid)):.2%}")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
