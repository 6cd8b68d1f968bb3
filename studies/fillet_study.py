"""Does a printed fillet at the outer wall root make steep walls' lock force mesh-converged (issue 20)?

docs/design.md section 4 ("Mesh") traces the steep cells' unconverged lock force to a crease at
the outer wall root A, where the sharp bonded corner is singular. A print has no sharp corner
there: the bead fills the air wedge between the outer face and the plate with a fillet of radius
about half the extrusion width. ``MeshOptions(root_fillet_mm=r)`` (continuum.RootFillet) meshes it. Two parts:

a. k and the lock force R of a shallow, a mid, a 45 deg and a steep cell on the default mesh, for
   fillet radii 0, 0.05, 0.1, 0.2 mm (what shipping a fillet would move);
b. the 45 and 60 deg cells with the path mesh graded 0-2 rounds within 1 t of the outer root
   (A and the fillet's tangent points T1, T2), as steep_lock.py part 5 grades it, at fillet radii
   0.1 and 0.2 mm: R, load steps, seconds, the smallest principal stretch at the lock and where
   (steep_lock.py part 6), the largest force drop along the path. A stalled path is reported.

Run:  MST_WORKERS=1 .venv/bin/python studies/fillet_study.py [--parts a,b] [--rounds 2]
          [--radii-b 0.1,0.2] [--cells-b 45,steep]
      Part a: about 2.5 min (16 solves, 3-30 s each). Part b: round 2 took 74-99 s on three of its
      four paths and 697 s on the 60 deg cell at r = 0.1; a third round (--rounds 3) on the 45 deg
      cell at r = 0.1 had not finished after 14 min. Two cores, shared.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from steep_lock import _min_stretch

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import continuum
from mst_cli.model.mechanics.path import PathError, StepControl

CELLS = {"shallow": (14, 0.4, 1.87), "mid": (33, 1.0, 2.8), "45": (45, 1.0, 4.0), "steep": (60, 0.6, 4.0)}
RADII = (0.0, 0.05, 0.1, 0.2)


def default_mesh(mat) -> None:
    print("a. default mesh: k and R against the sharp corner (r = 0)\n")
    print("| cell (theta, t, h) | r mm | k N/mm | k vs r=0 | R N | R vs r=0 | d_lock mm | lock | steps | s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, cell in CELLS.items():
        ref = None
        for r in RADII:
            t0 = time.perf_counter()
            try:
                study = continuum.StudyOptions(continuum.MeshOptions(root_fillet_mm=r))
                res = continuum.solve_continuum(HexCell(*cell), mat, study)
            except (continuum.ContinuumError, ValueError) as exc:
                print(f"| {name} {cell} | {r} | stalled: {exc} ({time.perf_counter() - t0:.1f} s) |")
                continue
            sec = time.perf_counter() - t0
            k, R = res.k_linear_N_per_mm, res.force_N[-1]
            ref = ref or (k, R)
            print(
                f"| {name} {cell} | {r} | {k:.4f} | {100 * (k / ref[0] - 1):+.2f} % | {R:.3f} | "
                f"{100 * (R / ref[1] - 1):+.2f} % | {res.d_contact_mm:.4f} | {res.contact_at} | "
                f"{len(res.displacement_mm) - 1} | {sec:.1f} |",
                flush=True,
            )


def _graded_row(cell, mat, r: float, rounds: int, k_fine: float) -> str:
    t0 = time.perf_counter()
    mesh = continuum.MeshOptions(levels=rounds, corners=("outer_root",), radius_in_t=1.0, root_fillet_mm=r)
    prob = continuum.ContactProblem(cell, mat, mesh)
    k_path = continuum.linear_k(prob)
    try:
        path, _ = continuum.follow_to_lock(prob, k_path, StepControl(first_step_rel=0.125, max_steps=2000))
    except PathError as exc:
        return f"| {r} | {rounds} | {prob.basis.N} | stalled: {exc} | | | {time.perf_counter() - t0:.1f} |"
    F = np.array([o[0] for o in path.observations])
    drop = float(np.max(np.maximum.accumulate(F) - F) / F.max())
    stretch, at = _min_stretch(prob, path.state.u)
    return (
        f"| {r} | {rounds} | {prob.basis.N} | {F[-1] * k_fine / k_path:.3f} | {path.d_mm[-1]:.4f} | {len(F)} | "
        f"{time.perf_counter() - t0:.1f} | {stretch:.3f} at ({at[0]:.3f}, {at[1]:.3f}) | {100 * drop:.1f} % |"
    )


def graded_outer_root(mat, radii: tuple[float, ...], rounds: int, cells: tuple[str, ...]) -> None:
    print(
        "\nb. the path mesh graded 0..n rounds within 1 t of the outer root (A, T1, T2; 3 x 12 base); "
        "R scaled by the default fine mesh's k ratio, as solve_continuum does\n"
    )
    for name in cells:
        cell = HexCell(*CELLS[name])
        print(f"{name} {CELLS[name]}: outer root A at x = {cell.outer_profile_xz()[0][0]:.3f} mm\n")
        print("| r mm | rounds | path dofs | R N | d_lock mm | steps | s | smallest stretch at (x, z) | largest drop |")
        print("|---|---|---|---|---|---|---|---|---|")
        for r in radii:
            fine = continuum.ContactProblem(cell, mat, continuum.MeshOptions(root_fillet_mm=r))
            k_fine = continuum.linear_k(fine)
            for n in range(rounds + 1):
                print(_graded_row(cell, mat, r, n, k_fine), flush=True)
        print()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--parts", default="a,b", help="which parts to run, comma-separated")
    ap.add_argument("--rounds", type=int, default=2, help="grading rounds of part b (0..rounds)")
    ap.add_argument("--radii-b", default="0.1,0.2", help="fillet radii of part b, mm")
    ap.add_argument("--cells-b", default="45,steep", help="cells of part b (names of CELLS)")
    args = ap.parse_args()
    parts = set(args.parts.split(","))
    mat = Material()
    if "a" in parts:
        default_mesh(mat)
    if "b" in parts:
        radii = tuple(float(x) for x in args.radii_b.split(","))
        graded_outer_root(mat, radii, args.rounds, tuple(args.cells_b.split(",")))


if __name__ == "__main__":
    main()
