"""How far rung L2's plane strain sits from a 3D web with free faces (issue 20, part 4).

A measurement, not a rung. For each cell, on the same in-plane mesh (the L2 quarter profile
without corner refinement, n_thick x n_length elements):

* 2D: the plane-strain rung itself (continuum.ContactProblem, levels = 0), its path to the lock;
* 3D held: the profile extruded over y in [0, D/2] with u_y = 0 on both y = 0 and y = D/2 -- the
  continuum answer is plane strain again, so this column measures only what the tetrahedral
  discretisation does (a little softer than the extruded P2 triangles);
* 3D free: y = 0 a symmetry plane, the face y = D/2 free -- the web as printed.

(tools/continuum_3d.py has the model; tests/test_3d_check.py verifies its kernel.) k is
the small-load stiffness, R the force at the lock and d_lock its compression (the lock: the
tangent stiffness reaches 5 k, as in L2). "free/2D" is the ratio asked for; "free/held" is the
free faces' effect alone (same mesh, same elements). The depth grading is checked by repeating
the free run on a finer one (8 layers, the one at the face t/4 thick, against 6 layers and t/2).
--inplane adds the linear k of all three models on the finer in-plane mesh 3 x 12 (L2's default
before corner refinement) to show the ratios do not depend on it.

Run:  .venv/bin/python studies/bench_3d.py                 # 4 cells, ~15 min on one core
      .venv/bin/python studies/bench_3d.py --cells 0 1 --no-fine
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))  # the 3D kernel
import continuum_3d as C3

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import continuum as L2
from mst_cli.model.mechanics.depth import finite_depth_factor

CELLS = [
    ("shallow", HexCell(14, 0.40, 1.87)),
    ("mid", HexCell(33, 1.0, 2.8)),
    ("stubby", HexCell(45, 2.5, 6.5)),
    ("steep", HexCell(60, 0.6, 4.0)),
]


def run(cell, material, n_thick, n_length, fine_too, inplane):
    out = {}
    t0 = time.perf_counter()
    out["2D"] = C3.solve_to_lock(C3.problem_2d(cell, material, n_thick, n_length))
    coarse = C3.depth_grading(cell, fine=False)
    out["held"] = C3.solve_to_lock(C3.Problem3D(cell, material, coarse, n_thick, n_length, y_held_far=True))
    t1 = time.perf_counter()
    prob = C3.Problem3D(cell, material, coarse, n_thick, n_length)
    out["free"] = C3.solve_to_lock(prob)
    out["free"]["seconds"] = time.perf_counter() - t1
    out["free"]["dofs"] = prob.basis.N
    if fine_too:
        t1 = time.perf_counter()
        prob = C3.Problem3D(cell, material, C3.depth_grading(cell, fine=True), n_thick, n_length)
        out["fine"] = C3.solve_to_lock(prob)
        out["fine"]["seconds"] = time.perf_counter() - t1
        out["fine"]["dofs"] = prob.basis.N
    if inplane:
        k2 = L2.linear_k(C3.problem_2d(cell, material, 3, 12))
        kh = L2.linear_k(C3.Problem3D(cell, material, coarse, 3, 12, y_held_far=True))
        kf = L2.linear_k(C3.Problem3D(cell, material, coarse, 3, 12))
        out["inplane"] = (k2, kh, kf)
    out["seconds"] = time.perf_counter() - t0
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cells", type=int, nargs="*", default=list(range(len(CELLS))))
    ap.add_argument("--n-thick", type=int, default=2)
    ap.add_argument("--n-length", type=int, default=8)
    ap.add_argument("--no-fine", action="store_true", help="skip the finer depth grading")
    ap.add_argument("--inplane", action="store_true", help="also the linear k on the 3 x 12 in-plane mesh")
    args = ap.parse_args()
    material = Material()
    rows = []
    for i in args.cells:
        name, cell = CELLS[i]
        res = run(cell, material, args.n_thick, args.n_length, not args.no_fine, args.inplane)
        rows.append((name, cell, res))
        f, h, p = res["free"], res["held"], res["2D"]
        print(
            f"# {name} {cell.theta_deg:g} deg t {cell.t_mm:g} h {cell.h_mm:g}: {res['seconds']:.0f} s "
            f"(3D free: {f['dofs']} dofs, {f['seconds']:.0f} s, {f['iterations']} Newton iterations, "
            f"closes at the {f['at']}, 2D at the {p['at']}, held at the {h['at']})",
            flush=True,
        )

    print(
        f"\nin-plane mesh {args.n_thick} x {args.n_length} (L2 levels = 0), depth y in [0, D/2] = [0, 10] mm, "
        f"6 layers graded to the free face (t/2 there)\n"
    )
    print(
        "| cell | t/D | k 2D | k 3D held | k 3D free | k free/2D | k free/held | R 2D | R 3D held | R 3D free "
        "| R free/2D | R free/held | d_lock free/2D | fine grading: k, R free/2D |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, cell, res in rows:
        p, h, f = res["2D"], res["held"], res["free"]
        fine = res.get("fine")
        conv = f"{fine['k'] / p['k']:.4f}, {fine['R'] / p['R']:.4f}" if fine else "-"
        print(
            f"| {name} ({cell.theta_deg:g}, {cell.t_mm:g}, {cell.h_mm:g}) | {cell.t_mm / cell.b_mm:.3f} "
            f"| {p['k']:.4g} | {h['k']:.4g} | {f['k']:.4g} | {f['k'] / p['k']:.4f} | {f['k'] / h['k']:.4f} "
            f"| {p['R']:.4g} | {h['R']:.4g} | {f['R']:.4g} | {f['R'] / p['R']:.4f} | {f['R'] / h['R']:.4f} "
            f"| {f['d_lock'] / p['d_lock']:.4f} | {conv} |"
        )
    # the adopted finite-depth correction (mst_cli.model.mechanics.depth, fitted by
    # tools/fit_depth_correction.py on other cells) against the free faces' effect alone
    print("\nthe rungs' finite-depth factor phi against free/held (k and R): misses in %")
    for name, cell, res in rows:
        phi = float(finite_depth_factor(cell.theta_rad, cell.t_mm, cell.h_mm, cell.b_mm, material.poisson_ratio))
        f, h = res["free"], res["held"]
        print(
            f"  {name}: phi {phi:.4f}; k {100 * (phi / (f['k'] / h['k']) - 1):+.2f} %, "
            f"R {100 * (phi / (f['R'] / h['R']) - 1):+.2f} % (uncorrected: k {100 * (h['k'] / f['k'] - 1):+.2f} %, "
            f"R {100 * (h['R'] / f['R'] - 1):+.2f} %)"
        )
    if any("inplane" in r for _, _, r in rows):
        print("\nlinear k on the 3 x 12 in-plane mesh (coarse depth grading)\n")
        print("| cell | k 2D | k 3D held | k 3D free | free/2D | free/held |")
        print("|---|---|---|---|---|---|")
        for name, _, res in rows:
            k2, kh, kf = res["inplane"]
            print(f"| {name} | {k2:.4g} | {kh:.4g} | {kf:.4g} | {kf / k2:.4f} | {kf / kh:.4f} |")


if __name__ == "__main__":
    main()
