"""Fit the L0 corrections against the L2 continuum model; writes mst_cli/data/l0_correction.json.

Three ratios of the plane-strain web (L0 with E' = E / (1 - nu^2), L2 with lambda_3 = 1)
depend only on the profile's shape, i.e. on theta and t/L (and nu, and the contact allowance
relative to the cell): all forces scale with E b, and the shape scaled by L is fixed by theta
and t/L. The web width b = D drops out.

* stiffness: k_L2 / k_L0 (linear solves). Model ln(ratio) = x * P3(x, s), x = t/L,
  s = theta - pi/4, so the correction vanishes in the slender limit (beam theory).
* lock force: R_L2 / (k d_lock) with the corrected k -- the geometric softening of the walls
  before the cavity closes (nonlinear solves). Model ln(ratio) = sigma * Q(x, s), Q a full
  cubic, sigma = d_lock / (L sin theta) the stroke over a wall's rise: the softening is large
  rotation, first order in the stroke, and does not vanish for slender walls.
* lock stroke: d_lock,L2 / (h - 2t - allowance) -- the cavity closes a little early where the
  rotated wall faces meet before the pads do. Same form.

Least squares over a seeded sample of valid cells inside the bench bounds (theta 15-60 deg,
t 0.4-2.0 mm, h 1.2-6 mm, t/L <= 0.6). Checked out of sample by `mst bench` (seed 0).

Run:  .venv/bin/python benchmarks/fit_l0_correction.py [--samples 150] [--seed 1]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from mst_cli.bench import sample_cells
from mst_cli.material import Material
from mst_cli.mechanics import correction, uncached_layer_law
from mst_cli.mechanics.continuum import linear_stiffness_N_per_mm
from mst_cli.mechanics.spring import layer_stiffness_N_per_mm
from mst_cli import geometry as geo


def _lstsq(A, y):
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    resid = np.exp(y - A @ coef) - 1.0
    return coef, {"ratio_range": [float(np.exp(y.min())), float(np.exp(y.max()))],
                  "median_abs_residual": float(np.median(np.abs(resid))),
                  "max_abs_residual": float(np.max(np.abs(resid)))}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--samples", type=int, default=150)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--max-t-over-L", type=float, default=0.6,
                    help="stubbiest wall sampled (the fitted box's t/L edge) [default: 0.6]")
    ap.add_argument("--out", type=Path, default=correction.DATA,
                    help="where to write the fit [default: the package's mst_cli/data/l0_correction.json]")
    args = ap.parse_args()
    mat = Material()
    cells = sample_cells(args.samples, args.seed, args.max_t_over_L)
    x = np.array([c.t_mm / c.wall_length_mm for c in cells])
    th = np.array([c.theta_rad for c in cells])
    k0 = np.array([float(layer_stiffness_N_per_mm(c.theta_rad, c.t_mm, c.h_mm, c.b_mm,
                                                  mat.youngs_modulus_MPa, mat.poisson_ratio)) for c in cells])
    k2 = np.array([linear_stiffness_N_per_mm(c, mat) for c in cells])
    coef_k, stats_k = _lstsq(correction.design_matrix(x, th), np.log(k2 / k0))

    # lock point of L2 against the corrected L0 (k0 times the stiffness factor just fitted)
    laws = [uncached_layer_law(c, mat, "continuum") for c in cells]
    k0c = k0 * np.exp(correction.design_matrix(x, th) @ coef_k)
    d0 = np.array([float(geo.lock_stroke_mm(c.t_mm, c.h_mm, c.contact_allowance_mm)) for c in cells])
    R2 = np.array([law.lock_force_N for law in laws])
    d2 = np.array([law.d_lock_mm for law in laws])
    L = np.array([c.wall_length_mm for c in cells])
    sigma = correction.stroke_ratio(d0, L, th)
    A_lock = sigma[:, None] * correction.lock_design_matrix(x, th)
    coef_R, stats_R = _lstsq(A_lock, np.log(R2 / (k0c * d0)))
    coef_d, stats_d = _lstsq(A_lock, np.log(d2 / d0))

    out = {
        "model": "ln(k_L2/k_L0) = sum_i c_i * terms_i(x = t/L, theta_rad)",
        "terms": correction.TERMS,
        "coefficients": [float(c) for c in coef_k],
        "lock_force": {"model": "ln(R_L2 / (k d_lock)) = sigma * sum_i c_i * lock_terms_i(x, theta_rad), sigma = d_lock / (L sin theta)",
                       "terms": correction.LOCK_TERMS, "coefficients": [float(c) for c in coef_R], **stats_R},
        "lock_stroke": {"model": "ln(d_lock,L2 / (h - 2t - allowance)) = sigma * sum_i c_i * lock_terms_i(x, theta_rad)",
                        "terms": correction.LOCK_TERMS, "coefficients": [float(c) for c in coef_d], **stats_d},
        "fitted_on": {"samples": len(cells), "seed": args.seed, "poisson_ratio": mat.poisson_ratio,
                      "contact_allowance_mm": cells[0].contact_allowance_mm,
                      "t_over_L_range": [float(x.min()), float(x.max())],
                      "theta_deg_range": [float(np.degrees(th.min())), float(np.degrees(th.max()))],
                      "stroke_ratio_range": [float(sigma.min()), float(sigma.max())],
                      **stats_k},
        "command": (f".venv/bin/python benchmarks/fit_l0_correction.py --samples {args.samples} --seed {args.seed}"
                    + (f" --max-t-over-L {args.max_t_over_L:g}" if args.max_t_over_L != 0.6 else "")),
    }
    path = args.out
    path.write_text(json.dumps(out, indent=2) + "\n")
    for name, s in (("k_L2/k_L0", stats_k), ("R_L2/(k d_lock)", stats_R), ("d_lock,L2/d_lock,L0", stats_d)):
        lo, hi = s["ratio_range"]
        print(f"{name}: from {lo:.3f} to {hi:.3f}; after the fit median |residual| "
              f"{s['median_abs_residual']:.2%}, max {s['max_abs_residual']:.2%}")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
