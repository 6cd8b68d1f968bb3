"""Two modelling choices measured against rung L2, so the numbers quoted for them reproduce.

1. KNEE_FRACTION of the corrected L0 law (mst_cli/mechanics/spring.py): for each fraction f,
   the two-piece curve through L2's own (k, d_lock, R) -- slope k up to f R, then straight to
   the lock point -- against the L2 curve; the median over cells of the largest |d error| up
   to the lock, in units of d_lock.
2. Joint models of rung L1's own (mst_cli/mechanics/frame.py): the small-load stiffness of
   the clamped-guided Timoshenko wall (what L1's beam gives at small load) with the wall
   shortened by rigid end zones, against L2's linear stiffness. Zones: none (beam theory), and
   half the geometric overlaps -- at the tip t/(2 tan theta), where the two walls' strips
   overlap, and at the root the distance from the pad mid-plane to where the inner face leaves
   the pad -- and the full overlaps.

Run:  .venv/bin/python studies/model_choices.py [--knee-cells 12] [--joint-cells 150]
"""

from __future__ import annotations

import argparse

import numpy as np

from mst_cli.bench.ladder_bench import sample_cells
from mst_cli.model.material import Material
from mst_cli.model.mechanics import uncached_layer_law
from mst_cli.model.mechanics.continuum import linear_stiffness_N_per_mm
from mst_cli.model.mechanics.spring import layer_stiffness_N_per_mm


def knee_table(cells, mat, fractions=(0.3, 0.4, 0.5, 0.6, 0.7)):
    laws = [uncached_layer_law(c, mat, "continuum") for c in cells]
    print(f"knee fraction against {len(cells)} L2 curves (bench cells, seed 0):")
    print("fraction  median max|d error|/d_lock   worst")
    for f in fractions:
        errs = []
        for law in laws:
            k, dl, R = law.k_N_per_mm, law.d_lock_mm, law.lock_force_N
            F = np.linspace(0.0, R, 200)[1:]
            F1 = f * R
            two_piece = np.where(F <= F1, F / k, F1 / k + (F - F1) / (R - F1) * (dl - F1 / k))
            errs.append(np.max(np.abs(two_piece - law.displacement_mm(F))) / dl)
        print(f"{f:8.1f}  {np.median(errs):26.1%}  {np.max(errs):6.1%}")


def joint_table(cells, mat):
    k2 = np.array([linear_stiffness_N_per_mm(c, mat) for c in cells])
    rows = {"beam theory (no zones)": [], "half the overlaps rigid": [], "full overlaps rigid": []}
    for c in cells:
        th, t = c.theta_rad, c.t_mm
        u = np.array([np.cos(th), np.sin(th)])
        inner = c.inner_profile_xz()
        outer = c.outer_profile_xz()
        tip = 0.5 * (np.asarray(outer[1]) + np.asarray(inner[1]))
        L = c.wall_length_mm
        root_zone = (np.asarray(inner[0]) - (tip - L * u)) @ u  # inner face leaves the pad
        tip_zone = t / (2.0 * np.tan(th))  # the walls' strips overlap
        for name, share in zip(rows, (0.0, 0.5, 1.0)):
            Lf = L - share * (root_zone + tip_zone)
            # a clamped-guided wall of clear length Lf: same formula, h chosen to give Lf
            h_eff = 2.0 * Lf * np.sin(th) + t
            rows[name].append(
                float(layer_stiffness_N_per_mm(th, t, h_eff, c.b_mm, mat.youngs_modulus_MPa, mat.poisson_ratio))
            )
    print(f"\nL1 joint models against L2 linear stiffness ({len(cells)} cells, seed 1):")
    print("model                      median |err|   p90 |err|")
    for name, k in rows.items():
        e = np.abs(np.array(k) / k2 - 1.0)
        print(f"{name:26s} {np.median(e):13.1%} {np.percentile(e, 90):11.1%}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--knee-cells", type=int, default=12)
    ap.add_argument("--joint-cells", type=int, default=150)
    args = ap.parse_args()
    mat = Material()
    knee_table(sample_cells(args.knee_cells, 0), mat)
    joint_table(sample_cells(args.joint_cells, 1), mat)


if __name__ == "__main__":
    main()
