"""Fit and verify the finite-depth correction of the plane-strain rungs (issue 20, part 4);
writes mst_cli/model/data/depth_correction.json.

Every rung treats the web (D deep, faces free at y = +-D/2) as plane strain. Near a free face
the walls are in plane stress instead, over a boundary layer a width l from the face, and plane
stress is softer than plane strain by nu^2 (E against E / (1 - nu^2)). So

    k_3D / k_2D = 1 - 2 nu^2 l / D,        l = t * lam(theta, y),  y = t / (h - t),

if l does not depend on D (checked here: the same cell at D = 12 and 20 mm) and is
proportional to t at a fixed profile shape (theta and t/L fix the shape, and y = t / (h - t)
stands for t/L; checked on cells of equal shape and different t). t lam is fitted as
a mix of t and h - t with quadratic weights in theta - 45 deg (mst_cli.model.mechanics.depth)
on the even cells of a grid over the printable box and judged
on the odd ones (held out).

The ratio measured is k 3D free / k 3D held on the same 3D mesh (tools/continuum_3d.py,
y = 0 a symmetry plane, y = D/2 free or held): the held model's exact answer is plane strain,
so the tetrahedra's own discretisation cancels.

Run:  .venv/bin/python tools/fit_depth_correction.py          # 88 3D cells, ~5 min
      .venv/bin/python tools/fit_depth_correction.py --factors-only   # the factor on designs
      .venv/bin/python tools/fit_depth_correction.py --limit 8 --no-write
"""

from __future__ import annotations

import argparse
import itertools
import json
import time
from pathlib import Path

import continuum_3d as C3
import numpy as np

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import continuum as L2
from mst_cli.model.mechanics import depth

SHAPE_DEPTH_MM = 20.0
DEPTH_PAIRS = [(8, 0.4, 1.4), (22, 1.0, 6.0), (38, 2.2, 7.7), (55, 1.0, 3.5), (65, 2.2, 7.7), (72, 0.4, 2.0)]


def shape_cells():
    """Valid cells over the printable box (theta 6-72 deg, t 0.4-2 mm, h up to 8 mm) at D = 20."""
    out = []
    for theta, t, h_over_t in itertools.product(
        (6, 10, 15, 22, 30, 38, 45, 55, 65, 72), (0.4, 1.0, 2.0), (2.8, 3.5, 5.0, 7.0)
    ):
        h = round(h_over_t * t, 3)
        cell = HexCell(theta, t, h, depth_mm=SHAPE_DEPTH_MM)
        if h <= 8.0 and not cell.violations():
            out.append(cell)
    return out


def free_over_held(cell, material, n_thick=2, n_length=8) -> float:
    grading = C3.depth_grading(cell, fine=False)
    k_held = L2.linear_k(C3.Problem3D(cell, material, grading, n_thick, n_length, y_held_far=True))
    k_free = L2.linear_k(C3.Problem3D(cell, material, grading, n_thick, n_length))
    return k_free / k_held


def example_factors() -> None:
    """The stored factor on the reference design's layers and on thick steep cells."""
    from mst_cli import api

    doc = api.design(Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021.yaml").document
    cells = [
        (f"reference design layer {i + 1}", la.theta_deg, la.t_mm, la.h_mm, doc.family.depth_mm)
        for i, la in enumerate(doc.layers)
    ]
    cells += [("thick steep", 72, 2.0, 7.0, SHAPE_DEPTH_MM), ("thick steep", 60, 3.0, 8.0, SHAPE_DEPTH_MM)]
    for name, theta, t, h, D in cells:
        phi = float(depth.finite_depth_factor(np.radians(theta), t, h, D, Material().poisson_ratio))
        print(f"{name}: theta {theta:.2f} deg, t {t:.3f} mm, h {h:.3f} mm, D {D:g} mm: factor {phi:.4f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--limit", type=int, default=0, help="only the first N shape cells (a quick look)")
    ap.add_argument("--no-write", action="store_true", help="do not write the data file")
    ap.add_argument("--factors-only", action="store_true", help="only the stored factor on example designs")
    args = ap.parse_args()
    material = Material()
    nu = material.poisson_ratio
    if args.factors_only:
        return example_factors()

    print("1. l does not depend on D: the boundary-layer width l = (1 - k free/held) D / (2 nu^2)")
    print(f"{'theta':>6} {'t':>5} {'h':>5} {'l at D 12':>10} {'l at D 20':>10} {'change':>7}")
    for theta, t, h in DEPTH_PAIRS:
        ell = [(1 - free_over_held(HexCell(theta, t, h, depth_mm=D), material)) * D / (2 * nu**2) for D in (12.0, 20.0)]
        print(
            f"{theta:6g} {t:5g} {h:5g} {ell[0]:10.4f} {ell[1]:10.4f} {100 * (ell[0] / ell[1] - 1):+6.1f}%", flush=True
        )

    cells = shape_cells()[: args.limit or None]
    print(f"\n2. lam = l / t over {len(cells)} cells at D = {SHAPE_DEPTH_MM:g} mm")
    print(f"{'theta':>6} {'t':>5} {'h':>6} {'y':>6} {'k free/held':>12} {'lam':>7} {'s':>5}")
    rows = []
    for cell in cells:
        t0 = time.perf_counter()
        ratio = free_over_held(cell, material)
        lam = (1 - ratio) * cell.b_mm / (2 * nu**2 * cell.t_mm)
        rows.append((cell.theta_rad, cell.t_mm, cell.h_mm, cell.b_mm, ratio))
        print(
            f"{cell.theta_deg:6g} {cell.t_mm:5g} {cell.h_mm:6g} {cell.t_mm / (cell.h_mm - cell.t_mm):6.3f} "
            f"{ratio:12.4f} {lam:7.3f} {time.perf_counter() - t0:5.1f}",
            flush=True,
        )
    A = np.array(rows)
    theta, t, h, D, ratio = A.T
    lam = (1 - ratio) * D / (2 * nu**2 * t)
    X = depth.design_matrix(theta, t / (h - t))
    fit, hold = np.arange(len(A)) % 2 == 0, np.arange(len(A)) % 2 == 1
    coef = np.linalg.lstsq(X[fit], lam[fit], rcond=None)[0]
    pred = depth.finite_depth_factor(theta, t, h, D, nu, coefficients=coef)
    miss = 100 * np.abs(pred / ratio - 1)
    none = 100 * np.abs(1 / ratio - 1)
    print(f"\nlam fitted on {fit.sum()} cells: {', '.join(f'{c:.4f}' for c in coef)} ({', '.join(depth.TERMS)})")
    print(
        "k 3D / corrected plane strain - 1, largest |.|: "
        f"fitted cells {miss[fit].max():.2f} %, held-out cells {miss[hold].max():.2f} % "
        f"(median {np.median(miss[hold]):.2f} %); "
        f"uncorrected {none.max():.2f} % (median {np.median(none):.2f} %)"
    )
    if not args.no_write and not args.limit:
        out = {
            "command": ".venv/bin/python tools/fit_depth_correction.py",
            "terms": list(depth.TERMS),
            "coefficients": [float(c) for c in coef],
            "fitted_on": {
                "cells": int(fit.sum()),
                "nu": nu,
                "depth_mm": SHAPE_DEPTH_MM,
                "mesh": "2 x 8 in-plane, 6 depth layers graded to t/2 at the face",
            },
            "held_out": {
                "cells": int(hold.sum()),
                "max_abs_err_k_pct": float(miss[hold].max()),
                "median_abs_err_k_pct": float(np.median(miss[hold])),
                "uncorrected_max_abs_err_k_pct": float(none.max()),
            },
        }
        depth.DATA.write_text(json.dumps(out, indent=1) + "\n")
        print(f"wrote {depth.DATA}")


if __name__ == "__main__":
    main()
