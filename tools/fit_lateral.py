"""Fit rung L0's lateral stiffness (mst_cli/model/mechanics/lateral.py) to L2 and write
mst_cli/model/data/lateral_fit.json.

* k_x and k_y (infinitely deep web): L2's small-load values (continuum_lateral) on FIT_CELLS
  cells of the seeded sample (mst_cli/bench/sampling.py, seed FIT_SEED), least squares of
  ln(L2 / beam) on lateral.TERMS; verified on CHECK_CELLS others (seed CHECK_SEED): the stored
  out-of-sample median and max relative errors;
* the free faces' factor 1 - c (L + t) / D: the 3D check (tools/lateral_check.py) of the five
  named cells over their L2 antiplane k_y, c by least squares (``--no-3d`` keeps the stored c).

Run:  PYTHONPATH=. .venv/bin/python tools/fit_lateral.py [--no-3d]     # ~1 min, ~5 min with 3D
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from mst_cli.bench.sampling import sample_cells
from mst_cli.model.material import Material
from mst_cli.model.mechanics import lateral
from mst_cli.model.mechanics.continuum_lateral import lateral_stiffness_x_N_per_mm, lateral_stiffness_y_N_per_mm

sys.path.insert(0, str(Path(__file__).resolve().parent))
from lateral_check import CHECK_CELLS, check_k_y_3d_N_per_mm

FIT_SEED, FIT_CELLS = 39, 48
CHECK_SEED, CHECK_CELLS_N = 139, 24


def _measure(cells, mat: Material) -> dict[str, np.ndarray]:
    """L2's k_x, k_y and the closed forms' bases on ``cells``."""
    E, nu, G = mat.youngs_modulus_MPa, mat.poisson_ratio, mat.shear_modulus_MPa
    th = np.array([c.theta_rad for c in cells])
    t = np.array([c.t_mm for c in cells])
    h = np.array([c.h_mm for c in cells])
    b = np.array([c.b_mm for c in cells])
    return {
        "x": np.array([lateral_stiffness_x_N_per_mm(c, mat) for c in cells]),
        "y": np.array([lateral_stiffness_y_N_per_mm(c, mat) for c in cells]),
        "beam_x": lateral.beam_k_x_N_per_mm(th, t, h, b, E, nu),
        "beam_y": lateral.beam_k_y_N_per_mm(th, t, h, b, G),
        "A": lateral.design_matrix(t / np.array([c.wall_length_mm for c in cells]), th),
    }


def _errors(pred: np.ndarray, ref: np.ndarray) -> dict[str, float]:
    rel = np.abs(pred / ref - 1.0)
    return {"median_rel": float(np.median(rel)), "max_rel": float(rel.max())}


def _depth_end_c(mat: Material) -> tuple[float, list[dict]]:
    """c of the free faces' factor from the 3D check of CHECK_CELLS, and the per-cell rows."""
    rows, xs, ys = [], [], []
    for name, cell in CHECK_CELLS.items():
        k_inf = lateral_stiffness_y_N_per_mm(cell, mat)
        k_3d = check_k_y_3d_N_per_mm(cell, mat)
        ell = (cell.wall_length_mm + cell.t_mm) / cell.depth_mm
        rows.append({"cell": name, "k_y_3d": k_3d, "k_y_inf": k_inf, "ratio": k_3d / k_inf, "ell_over_D": ell})
        xs.append(ell)
        ys.append(1.0 - k_3d / k_inf)
        print(f"  3D {name}: {k_3d:.3f} / {k_inf:.3f} = {k_3d / k_inf:.4f}", flush=True)
    x, y = np.array(xs), np.array(ys)
    return float(x @ y / (x @ x)), rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-3d", action="store_true", help="keep the stored depth-end coefficient")
    args = ap.parse_args()
    mat = Material()
    fit_set = _measure(sample_cells(FIT_CELLS, seed=FIT_SEED), mat)
    check_set = _measure(sample_cells(CHECK_CELLS_N, seed=CHECK_SEED), mat)
    out: dict = {"terms": list(lateral.TERMS), "fitted_on": {"seed": FIT_SEED, "n": FIT_CELLS}}
    out["out_of_sample"] = {"seed": CHECK_SEED, "n": CHECK_CELLS_N}
    for k in ("x", "y"):
        coef, *_ = np.linalg.lstsq(fit_set["A"], np.log(fit_set[k] / fit_set[f"beam_{k}"]), rcond=None)
        out[k] = {
            "coef": coef.tolist(),
            "in_sample": _errors(np.exp(fit_set["A"] @ coef) * fit_set[f"beam_{k}"], fit_set[k]),
        }
        pred = np.exp(check_set["A"] @ coef) * check_set[f"beam_{k}"]
        out["out_of_sample"][k] = _errors(pred, check_set[k])
        print(k, "in sample", out[k]["in_sample"], "out of sample", out["out_of_sample"][k])
    if args.no_3d:
        out["depth_end"] = json.loads(lateral.DATA.read_text())["depth_end"]
    else:
        c, rows = _depth_end_c(mat)
        out["depth_end"] = {"c": c, "cells": rows}
        print("depth end c =", c)
    lateral.DATA.write_text(json.dumps(out, indent=1) + "\n")
    lateral.clear_caches()
    print("wrote", lateral.DATA)


if __name__ == "__main__":
    main()
