"""Fit rung L0's lateral stiffness (mst_cli/model/mechanics/lateral.py) to L2 and write
mst_cli/model/data/lateral_fit.json.

* k_x and k_y (infinitely deep web): L2's small-load values (continuum_lateral) on the fit set
  (:func:`fit_cells`: two seeded samples of the box, mst_cli/bench/sampling.py, and four cells
  near each of the box's eight corners, :func:`corner_cells`, where the shallow cells' beams
  fail), least squares of ln(L2 / beam) on lateral.TERMS; verified on another sample and two
  other cells per corner (:func:`check_cells`): the stored out-of-sample median and max relative
  errors (issue 44: within 3 % over the whole box);
* the free faces' factor 1 - c (L + t) / D: the 3D check (tools/lateral_check.py) of the five
  named cells over their L2 antiplane k_y, c by least squares (``--no-3d`` keeps the stored c).

Run:  PYTHONPATH=. .venv/bin/python tools/fit_lateral.py [--no-3d]     # ~4 min, ~8 min with 3D
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
from pathlib import Path

import numpy as np

from mst_cli.bench.sampling import BOUNDS, sample_cells
from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import lateral
from mst_cli.model.mechanics.continuum_lateral import lateral_stiffness_x_N_per_mm, lateral_stiffness_y_N_per_mm

sys.path.insert(0, str(Path(__file__).resolve().parent))
from lateral_check import CHECK_CELLS, check_k_y_3d_N_per_mm

FIT_SAMPLES = ((39, 120), (239, 100))  # (seed, cells) of the box's uniform samples
FIT_CORNERS = ((1039, 4), (3039, 4))  # (seed, cells per corner)
CHECK_SAMPLE, CHECK_CORNERS = (139, 24), (2139, 2)
# the shallow thick corner where the two chevrons share a pad (p_i < 1.5 t): (seed, cells) to
# fit and to check on, drawn in SHARED_PAD_BOX
FIT_SHARED, CHECK_SHARED = (77, 8), (177, 8)
SHARED_PAD_BOX = {"theta_deg": (5.0, 25.0), "t_mm": (1.5, 3.0), "h_mm": (4.5, 8.0)}
CORNER_FRACTION = 0.2  # a corner's cells lie within this fraction of each range from it


def corner_cells(per_corner: int, seed: int, fraction: float = CORNER_FRACTION) -> list[HexCell]:
    """Up to ``per_corner`` valid cells near each of the verified box's eight corners (theta, t,
    h each within ``fraction`` of its range from the corner's end), by seeded rejection; a
    corner with no valid cell nearby (5000 tries) gives none."""
    rng = np.random.default_rng(seed)
    out: list[HexCell] = []
    for corner in itertools.product((0, 1), repeat=3):
        ranges = []
        for key, side in zip(("theta_deg", "t_mm", "h_mm"), corner):
            lo, hi = BOUNDS[key]
            w = fraction * (hi - lo)
            ranges.append((lo, lo + w) if side == 0 else (hi - w, hi))
        got = 0
        for _ in range(5000):
            cell = HexCell(*(round(float(rng.uniform(*r)), 3) for r in ranges))
            if not cell.violations():
                out.append(cell)
                got += 1
            if got == per_corner:
                break
    return out


def shared_pad_cells(n: int, seed: int) -> list[HexCell]:
    """n valid cells of SHARED_PAD_BOX whose inner pad is shorter than 1.5 t."""
    rng = np.random.default_rng(seed)
    out: list[HexCell] = []
    while len(out) < n:
        cell = HexCell(*(round(float(rng.uniform(*SHARED_PAD_BOX[k])), 3) for k in ("theta_deg", "t_mm", "h_mm")))
        if not cell.violations() and cell.p_inner_mm < 1.5 * cell.t_mm:
            out.append(cell)
    return out


def fit_cells() -> list[HexCell]:
    cells = [c for seed, n in FIT_SAMPLES for c in sample_cells(n, seed=seed)]
    return cells + [c for seed, n in FIT_CORNERS for c in corner_cells(n, seed)] + shared_pad_cells(*FIT_SHARED[::-1])


def check_cells() -> list[HexCell]:
    corners = corner_cells(CHECK_CORNERS[1], CHECK_CORNERS[0])
    return sample_cells(CHECK_SAMPLE[1], seed=CHECK_SAMPLE[0]) + corners + shared_pad_cells(*CHECK_SHARED[::-1])


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
        "A": lateral.design_matrix(
            t / np.array([c.wall_length_mm for c in cells]), th, np.array([c.p_inner_mm for c in cells]) / t
        ),
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
    fit, check = fit_cells(), check_cells()
    fit_set, check_set = _measure(fit, mat), _measure(check, mat)
    out: dict = {"terms": list(lateral.TERMS)}
    out["fitted_on"] = {"samples": FIT_SAMPLES, "corners": FIT_CORNERS, "shared_pad": FIT_SHARED, "n": len(fit)}
    out["out_of_sample"] = {
        "sample": CHECK_SAMPLE,
        "corners": CHECK_CORNERS,
        "shared_pad": CHECK_SHARED,
        "n": len(check),
    }
    for k in ("x", "y"):
        coef, *_ = np.linalg.lstsq(fit_set["A"], np.log(fit_set[k] / fit_set[f"beam_{k}"]), rcond=None)
        out[k] = {
            "coef": coef.tolist(),
            "in_sample": _errors(np.exp(fit_set["A"] @ coef) * fit_set[f"beam_{k}"], fit_set[k]),
        }
        pred = np.exp(check_set["A"] @ coef) * check_set[f"beam_{k}"]
        out["out_of_sample"][k] = _errors(pred, check_set[k])
        print(k, "in sample", out[k]["in_sample"], "out of sample", out["out_of_sample"][k])
        worst = np.argsort(-np.abs(pred / check_set[k] - 1.0))[:3]
        print("  worst out of sample:", [(check[i].theta_deg, check[i].t_mm, check[i].h_mm) for i in worst])
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
