"""Sweep the continuum rung's lock force along one cell parameter, and check it on finer meshes.

A jump or sawtooth in R along a fine sweep is a bug (docs/design.md section 4, "The lock,
defined by the physics"). For each sweep the script prints R, d_lock, what closed and the
stiffness jump just past the lock, then the largest deviation of a point from the mean of its
two neighbours (for a smooth R(x) that is R'' dx^2 / (2 R): the curvature, halved with every
halving of the step). ``--mesh`` also solves each cell on two finer meshes.

Run:  .venv/bin/python studies/sweep_lock.py                       # the three sweeps
      .venv/bin/python studies/sweep_lock.py --mesh                # + mesh convergence
      .venv/bin/python studies/sweep_lock.py --factors             # + R against the lock factor
      .venv/bin/python studies/sweep_lock.py --sweep theta=12:16:0.25 --cell 0,0.40,1.87
"""

from __future__ import annotations

import argparse

import numpy as np

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import continuum
from mst_cli.model.mechanics.continuum import solve_continuum

# (variable, start, stop, step, fixed theta, t, h): the sweep at the reference
# design's first layer, a thickness sweep of a mid cell, a height sweep of a steep-ish cell
SWEEPS = [
    ("theta", 12.0, 16.0, 0.25, 0.0, 0.40, 1.87),
    ("t", 0.80, 1.20, 0.02, 30.0, 0.0, 3.0),
    ("h", 3.0, 4.0, 0.05, 45.0, 1.0, 0.0),
]
MESHES = [(3, 12), (4, 16), (6, 24)]  # (elements across the wall, along it)
MESH_CELLS = [(14, 0.40, 1.87), (33, 1.0, 2.8), (8, 0.5, 1.6), (45, 2.5, 6.5), (60, 0.6, 4.0), (70, 1.5, 6.0)]


def neighbour_deviation(values) -> np.ndarray:
    """|v_i / mean(v_(i-1), v_(i+1)) - 1| for the inner points."""
    v = np.asarray(values, dtype=float)
    return np.abs(v[1:-1] / (0.5 * (v[:-2] + v[2:])) - 1.0)


def run_sweep(var, start, stop, step, theta, t, h, mat) -> float:
    names = ("theta", "t", "h")
    R = []
    print(f"\nsweep {var} {start:g}..{stop:g} step {step:g} at theta {theta:g} deg, t {t:g} mm, h {h:g} mm")
    print(f"{var:>8} {'R_N':>10} {'d_lock_mm':>10} {'closed':>6} {'k_after/k':>9}")
    for x in np.arange(start, stop + 0.5 * step, step):
        p = dict(zip(names, (theta, t, h)))
        p[var] = float(x)
        res = solve_continuum(HexCell(p["theta"], p["t"], p["h"]), mat)
        R.append(res.force_N[-1])
        print(
            f"{x:8.3f} {res.force_N[-1]:10.5f} {res.d_contact_mm:10.5f} {res.contact_at:>6} "
            f"{res.lock_stiffness_ratio:9.1f}"
        )
    dev = neighbour_deviation(R)
    if dev.size == 0:
        print("(fewer than three points: no neighbour deviation)")
        return float("nan")
    print(f"largest deviation from the neighbours' mean: {100 * dev.max():.3f} %")
    return float(dev.max())


def _mesh_study(n_thick: int, n_length: int) -> continuum.StudyOptions:
    return continuum.StudyOptions(continuum.MeshOptions(n_thick=n_thick, n_length=n_length))


def run_mesh(mat):
    print("\nmesh convergence of the lock force (R on each mesh / R on the finest - 1)")
    print(f"{'cell (theta, t, h)':>22} " + " ".join(f"{f'{a}x{b}':>9}" for a, b in MESHES))
    for cell in MESH_CELLS:
        R = [solve_continuum(HexCell(*cell), mat, _mesh_study(a, b)).force_N[-1] for a, b in MESHES]
        print(f"{str(cell):>22} " + " ".join(f"{100 * (r / R[-1] - 1):+8.2f}%" for r in R))


FACTOR_CELLS = [(14, 0.4, 1.87), (33, 1.0, 2.8), (60, 0.6, 4.0), (45, 2.5, 6.5), (5, 0.4, 1.25), (25, 0.6, 2.0)]


def run_factors(mat, factors=(3.0, 5.0, 10.0)):
    print("\nlock force against the lock's stiffness factor (tangent / k at the lock)")
    print(f"{'cell (theta, t, h)':>22} " + " ".join(f"{f'x{f:g}':>10}" for f in factors) + "   spread")
    for cell in FACTOR_CELLS:
        R = [
            solve_continuum(HexCell(*cell), mat, continuum.StudyOptions(lock_stiffness_factor=f)).force_N[-1]
            for f in factors
        ]
        print(f"{str(cell):>22} " + " ".join(f"{r:10.4f}" for r in R) + f"   {100 * (max(R) / min(R) - 1):.2f} %")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sweep", help="VAR=START:STOP:STEP (VAR theta, t or h); with --cell")
    ap.add_argument("--cell", help="theta,t,h of the fixed parameters (the swept one is ignored)")
    ap.add_argument("--mesh", action="store_true", help="also the mesh convergence table")
    ap.add_argument("--factors", action="store_true", help="also R against the lock's stiffness factor")
    args = ap.parse_args()
    mat = Material()
    sweeps = SWEEPS
    if args.sweep:
        var, rng = args.sweep.split("=")
        start, stop, step = map(float, rng.split(":"))
        sweeps = [(var, start, stop, step, *map(float, args.cell.split(",")))]
    for s in sweeps:
        run_sweep(*s, mat)
    if args.mesh:
        run_mesh(mat)
    if args.factors:
        run_factors(mat)


if __name__ == "__main__":
    main()
