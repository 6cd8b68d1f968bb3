"""How far the L2 law strays from its own curve between knots, and what sampling costs (0.10).

The continuum law joins its path's samples by straight lines. For ``mst bench``'s cells (48,
seed 0) this solves each cell's law as the rung does and the same problem followed in steps of
1 % of the stroke (no chord control), and prints, at fractions of the lock stroke, the median
and largest |law / fine path - 1|; then the median time per layer of L2 and of L1 (frame) and
their samples per law.

Run on another tree (e.g. 0.9, before the chord control) with that tree first on the path:
    git archive 7fc3056 | tar -x -C /tmp/v09
    PYTHONPATH=/tmp/v09 .venv/bin/python studies/law_sampling.py

Run:  .venv/bin/python studies/law_sampling.py [--samples 48 --seed 0]   # ~3 min
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time

import numpy as np

from mst_cli.bench.sampling import sample_cells
from mst_cli.model.material import Material
from mst_cli.model.mechanics import continuum as L2
from mst_cli.model.mechanics.frame import solve_frame
from mst_cli.model.mechanics.path import StepControl

FRACTIONS = (0.05, 0.1, 0.15, 0.25, 0.5, 0.75, 0.9, 0.95)


def fine_steps() -> StepControl:
    """1 % of the stroke a step, the chord not controlled (a tree without the control ignores it)."""
    kw = dict(first_step_rel=0.01, grow=1.0, max_steps=3000)
    if "chord_tol_rel" in {f.name for f in dataclasses.fields(StepControl)}:
        kw["chord_tol_rel"] = 1e9
    return StepControl(**kw)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--samples", type=int, default=48)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    mat = Material()
    dev, t_l2, t_l1, n_l2, n_l1 = [], [], [], [], []
    for c in sample_cells(args.samples, args.seed):
        t0 = time.perf_counter()
        law = L2.solve_continuum(c, mat)
        t_l2.append(time.perf_counter() - t0)
        n_l2.append(len(law.displacement_mm))
        t0 = time.perf_counter()
        n_l1.append(len(solve_frame(c, mat).displacement_mm))
        t_l1.append(time.perf_counter() - t0)
        prob = L2.ContactProblem(c, mat, L2.MeshOptions(levels=0))
        path, _ = L2.follow_to_lock(prob, L2.linear_k(prob), fine_steps())
        d = np.array([0.0] + list(path.d_mm))
        F = np.array([0.0] + [o[0] for o in path.observations]) * law.mesh_scale
        x = np.array(FRACTIONS) * law.d_contact_mm
        dev.append(np.abs(np.interp(x, law.displacement_mm, law.force_N) / np.interp(x, d, F) - 1.0))
    D = np.array(dev)
    print(f"{len(D)} cells (seed {args.seed}); the law against a path in 1 % steps, |law / fine - 1|:")
    print("| fraction of the lock stroke | median | max |\n|---|---|---|")
    for j, fr in enumerate(FRACTIONS):
        print(f"| {fr:.2f} | {100 * np.median(D[:, j]):.2f} % | {100 * D[:, j].max():.2f} % |")
    print(
        f"L2: {1e3 * statistics.median(t_l2):.0f} ms a layer (median), {statistics.median(n_l2):.0f} samples; "
        f"L1: {1e3 * statistics.median(t_l1):.1f} ms, {statistics.median(n_l1):.0f} samples"
    )


if __name__ == "__main__":
    main()
