"""How much of the shipped designs' lock forces rides on the crease (issue 20). Prints a table; asserts nothing.

    python studies/design_crease.py [--rounds 2] [--specs configs/mohammadi2021.yaml,...]

docs/design.md section 4 ("Steep walls") shows that a steep wall's L2 lock force is not
mesh-converged: graded at its outer root, the wall's outer face creases (its smallest principal
stretch falls past 0.65, where a plane-strain neo-Hookean surface creases; Hong, Zhao and Suo,
Appl. Phys. Lett. 95, 111901 (2009)) and R keeps moving with every grading round. Those cells
were picked to show it. This script asks the question a user of a shipped design asks: does it
touch my layers? For each layer of each spec's design (``mst design``, as printed: the cells
the dear rungs see), it prints

* R on the default path mesh and with the path mesh graded 1..--rounds rounds within 1 t of
  both wall roots (the 3 x 12 base; forces scaled to the fine mesh as the law's are), and the
  largest change against the default;
* the smallest principal stretch anywhere at the lock on the default and the most graded path
  mesh, and whether it is past the crease onset;
* per round, how many times the deformed boundary crosses itself within 0.3 mm of the outer
  root at the lock (the quadratic edges as two chords each): a crease whose faces pass through
  each other, the thing self-contact would stop. Where it is 0, self-contact changes nothing.

A layer whose R holds within 1 % and whose stretch stays above 0.65 is outside the open item.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from mst_cli.api import design
from mst_cli.model.material import CREASE_ONSET_STRETCH
from mst_cli.model.mechanics import continuum
from mst_cli.model.mechanics.depth import in_web
from mst_cli.model.mechanics.path import StepControl
from mst_cli.sensor.as_printed import as_printed

ROOT = Path(__file__).resolve().parents[1]
SPECS = ("configs/mohammadi2021.yaml", "configs/mohammadi2021-compact.yaml")


def boundary_chords(prob, u: np.ndarray, near_xz: np.ndarray, radius_mm: float) -> np.ndarray:
    """The deformed boundary near ``near_xz`` as chords (n, 2, 2): each quadratic edge from its
    ends through its midside node, kept where its first end lies within ``radius_mm``."""
    b, mesh = prob.basis, prob.mesh
    facets = mesh.boundary_facets()
    ends = mesh.facets[:, facets]  # (2, n)
    at = mesh.p + np.stack([u[b.nodal_dofs[0]], u[b.nodal_dofs[1]]])
    mid = mesh.p[:, ends].mean(axis=1) + np.stack([u[b.facet_dofs[0][facets]], u[b.facet_dofs[1][facets]]])
    a, c = at[:, ends[0]].T, at[:, ends[1]].T
    chords = np.concatenate([np.stack([a, mid.T], axis=1), np.stack([mid.T, c], axis=1)])
    return chords[np.hypot(*(chords[:, 0] - near_xz).T) < radius_mm]


def self_crossings(chords: np.ndarray) -> int:
    """How many pairs of chords properly cross (touching at an end does not count)."""

    def orient(p, q, r):
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])

    i, j = np.triu_indices(len(chords), 1)
    p1, p2, q1, q2 = chords[i, 0], chords[i, 1], chords[j, 0], chords[j, 1]
    crossing = (orient(p1, p2, q1) * orient(p1, p2, q2) < 0) & (orient(q1, q2, p1) * orient(q1, q2, p2) < 0)
    return int(crossing.sum())


def lock_on(cell, material, k_fine: float, levels: int) -> tuple[float, float, float, int]:
    """(R in N scaled to the fine mesh, smallest stretch at the lock, seconds, boundary
    self-crossings near the outer root at the lock) on the 3 x 12 path mesh graded ``levels``
    rounds within 1 t of both wall roots."""
    t0 = time.perf_counter()
    corners = ("outer_root", "inner_root") if levels else continuum.CORNERS
    mesh = continuum.MeshOptions(levels=levels, corners=corners, radius_in_t=1.0)
    prob = continuum.ContactProblem(cell, material, mesh)
    k_path = continuum.linear_k(prob)
    path, _ = continuum.follow_to_lock(prob, k_path, StepControl(max_steps=2000))
    R = path.observations[-1][0] * k_fine / k_path
    outer_root = np.asarray(cell.outer_profile_xz()[0], float)
    crossings = self_crossings(boundary_chords(prob, path.state.u, outer_root, 0.3))
    return R, continuum.smallest_stretch(prob, path.state.u), time.perf_counter() - t0, crossings


def layer_rows(spec: str, rounds: int) -> None:
    doc = as_printed(design(ROOT / spec).document)
    print(f"\n{spec}: {len(doc.layers)} layers, as printed")
    for i, cell in enumerate(doc.geometry().layers, start=1):
        material = in_web(cell, doc.material)
        k_fine = continuum.linear_k(continuum.ContactProblem(cell, material))
        rows = [lock_on(cell, material, k_fine, levels) for levels in range(rounds + 1)]
        R0 = rows[0][0]
        moved = max(abs(R / R0 - 1.0) for R, *_ in rows)
        onset = min(rows[0][1], rows[-1][1]) < CREASE_ONSET_STRETCH
        print(
            f"  layer {i} (theta {cell.theta_deg:.2f} deg, t {cell.t_mm:.3f}, h {cell.h_mm:.3f} mm): "
            + ", ".join(f"R{k} {R:.4g} N" for k, (R, *_) in enumerate(rows))
            + f"; moves {100 * moved:.2f} %; smallest stretch {rows[0][1]:.2f} (default), {rows[-1][1]:.2f} "
            f"(graded {rounds}){' past the crease onset' if onset else ''}; "
            f"boundary self-crossings at the outer root per round {[x for *_, x in rows]}; "
            f"{sum(s for _, _, s, _ in rows):.0f} s"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=2, help="grading rounds at both wall roots (each costs more)")
    ap.add_argument("--specs", default=",".join(SPECS), help="comma-separated spec files")
    args = ap.parse_args()
    print(f"R of every layer on the default path mesh (R0) and graded 1..{args.rounds} rounds at both roots")
    for spec in args.specs.split(","):
        layer_rows(spec, args.rounds)


if __name__ == "__main__":
    main()
