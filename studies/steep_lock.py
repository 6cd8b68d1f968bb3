"""Why steep walls' lock force is not mesh-converged to 1 %, and what it costs L0 (issue 20).

Three measurements behind docs/design.md section 4 ("Steep walls", "L0 against L2 over the box"):

1. F(d) of steep cells on three meshes, at fractions of the lock stroke: the meshes agree until
   the last tenth of the stroke, where the inner wall face zips shut and the tangent climbs;
2. the same cells with the path's own mesh refined around the inner wall root alone (where the
   contact front runs), on two meshes;
3. L0 (spring) against L2 on cells drawn uniformly in the printable box: the median lock-force
   miss, per band of theta, and one steep slender cell's F / (k d) along its path (the ramp);
4. where the mesh error sits: the same cells refined only across the wall (n_thick) or only
   along it (n_length, which is where a contact front would run), the raw path force beside the
   k-scaled one; then the lock taken at the ramp's foot (tangent = 1 k instead of 5 k) and the
   path mesh graded at both wall roots;
5. whether grading converges: mid cells (30 and 45 deg) with the path mesh graded 0, 1 and 2
   rounds within 1 t of both wall roots, on the default 3 x 12 base and on 6 x 24; then the
   45 deg cell graded at one root at a time (which corner keeps the lock force moving);
6. what keeps it moving: the outer root graded 0-4 rounds with the plate's contact a penalty
   (no active set to churn), the smallest principal stretch at the lock and where, and the
   largest drop of the force along the path (a crease snapping in).

Run:  .venv/bin/python studies/steep_lock.py [--uniform 200 --seed 7] [--parts 1,2,3,4,5,6]   # ~17 min
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from mst_cli.bench.ladder_bench import sample_cells
from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import continuum, uncached_layer_law
from mst_cli.model.mechanics.continuum import continuum_layer, solve_continuum
from mst_cli.model.mechanics.path import PathError, StepControl

STEEP = [(60, 0.6, 4.0), (70, 1.5, 6.0)]
MESHES = [(3, 12), (4, 16), (6, 24)]
FRACTIONS = (0.1, 0.3, 0.5, 0.7, 0.85, 0.95, 1.0)
RAMP_CELL = (61.3, 0.57, 5.25)


def _study(mesh: tuple[int, int], **kw) -> continuum.StudyOptions:
    """The study's options: ``mesh`` (elements across the wall, along it), ``kw`` the rest."""
    return continuum.StudyOptions(continuum.MeshOptions(n_thick=mesh[0], n_length=mesh[1]), **kw)


def curves_on_meshes(mat) -> None:
    print("1. F(d) on each mesh / F on the 6 x 24 mesh - 1, at fractions of the lock stroke")
    for cell in STEEP:
        res = {m: solve_continuum(HexCell(*cell), mat, _study(m)) for m in MESHES}
        ref = res[MESHES[-1]]
        strokes = ", ".join(f"{r.d_contact_mm:.4f}" for r in res.values())
        print(f"{cell}: lock stroke {strokes} mm; R {', '.join(f'{r.force_N[-1]:.3f}' for r in res.values())} N")
        for frac in FRACTIONS:
            d = frac * ref.d_contact_mm * (1 - 1e-9)
            F_ref = np.interp(d, ref.displacement_mm, ref.force_N)
            dev = " ".join(
                f"{a}x{b} {100 * (np.interp(d, r.displacement_mm, r.force_N) / F_ref - 1):+6.2f} %"
                for (a, b), r in res.items()
            )
            print(f"  {frac:4.2f} of the stroke: F = {F_ref:8.3f} N; {dev}")


def inner_root_refined(mat) -> None:
    print("\n2. the path's mesh refined twice within 2 t of the inner wall root (R, N)")
    for cell in STEEP:
        row = []
        for a, b in MESHES[:2]:
            try:
                study = _study((a, b), path_levels=2, path_corners=("inner_root",), path_radius_in_t=2.0)
                r = solve_continuum(HexCell(*cell), mat, study)
                row.append(f"{a}x{b} {r.force_N[-1]:.3f}")
            except Exception as exc:  # a stalled path is the finding, not a crash
                row.append(f"{a}x{b} stalled ({type(exc).__name__})")
        print(f"{cell}: " + ", ".join(row))


def l0_uniform(mat, n: int, seed: int) -> None:
    cells = sample_cells(n, seed)
    rows = []
    for c in cells:
        ref, l0 = continuum_layer(c, mat), uncached_layer_law(c, mat, "spring")
        rows.append((c.theta_deg, abs(l0.lock_force_N / ref.lock_force_N - 1)))
    theta, err = np.array(rows).T
    print(f"\n3. L0 lock force against L2 on {n} uniform cells (seed {seed}): median miss {100 * np.median(err):.2f} %")
    for lo, hi in ((5, 30), (30, 50), (50, 55), (55, 75)):
        sel = (theta >= lo) & (theta < hi)
        print(f"  theta {lo}-{hi} deg: {sel.sum()} cells, median {100 * np.median(err[sel]):.2f} %")
    sel = theta < 50
    print(f"  below 50 deg: {sel.sum()} cells, median {100 * np.median(err[sel]):.2f} %")
    r = solve_continuum(HexCell(*RAMP_CELL), mat)
    l0 = uncached_layer_law(HexCell(*RAMP_CELL), mat, "spring")
    d, F = r.displacement_mm[1:], r.force_N[1:]
    ramp = " ".join(f"{f:.2f}" for f in F / (r.k_linear_N_per_mm * d))
    print(
        f"  {RAMP_CELL}: L2 d_lock {r.d_contact_mm:.3f} mm, R {F[-1]:.2f} N; L0 d_lock {l0.d_lock_mm:.3f} mm, "
        f"R {l0.lock_force_N:.2f} N\n  F / (k d) along the L2 path: {ramp}"
    )


ACROSS_ALONG = [(3, 12), (3, 24), (3, 48), (6, 12), (12, 12)]


def _lock_row(cell, mat, mesh, **kw) -> str:
    t0 = time.perf_counter()
    try:
        r = solve_continuum(HexCell(*cell), mat, _study(mesh, **kw))
    except Exception as exc:  # a stalled path is the finding, not a crash
        return f"{mesh[0]}x{mesh[1]} stalled ({type(exc).__name__}, {time.perf_counter() - t0:.1f} s)"
    seconds = time.perf_counter() - t0
    return (
        f"{mesh[0]}x{mesh[1]} R {r.force_N[-1]:.3f} (path {r.force_N[-1] / r.mesh_scale:.3f}) "
        f"d {r.d_contact_mm:.4f} ({len(r.displacement_mm) - 1} steps, {seconds:.1f} s)"
    )


def across_or_along(mat) -> None:
    print("\n4. R (N) refined across the wall (n_thick) or along it (n_length); 'path': before the k scaling")
    for cell in STEEP:
        print(f"{cell}:")
        for mesh in ACROSS_ALONG:
            print(f"  {_lock_row(cell, mat, mesh)}")
    print("  the lock at the ramp's foot (tangent = 1 k):")
    for cell in STEEP:
        rows = (_lock_row(cell, mat, m, lock_stiffness_factor=1.0) for m in ((3, 12), (6, 12), (12, 12)))
        print(f"  {cell}: " + "; ".join(rows))
    print("  the path mesh graded twice within 1 t of both wall roots (not the tip):")
    roots = dict(path_levels=2, path_corners=("outer_root", "inner_root"), path_radius_in_t=1.0)
    for cell in STEEP:
        print(f"  {cell}: " + "; ".join(_lock_row(cell, mat, m, **roots) for m in MESHES[:2]))


MID = [(30, 0.8, 3.0), (45, 1.0, 4.0)]


def grading_rounds(mat) -> None:
    print("\n5. R (N) with the path mesh graded 0, 1, 2 rounds within 1 t of both wall roots")
    for cell in MID:
        print(f"{cell}:")
        for mesh in ((3, 12), (6, 24)):
            for levels in (0, 1, 2):
                kw = dict(path_levels=levels, path_corners=("outer_root", "inner_root"), path_radius_in_t=1.0)
                print(f"  rounds {levels}: {_lock_row(cell, mat, mesh, max_steps=400, **kw)}")
    print("  one root at a time (3 x 12 base, 1, 2, 3 rounds within 1 t; the outer root to 5):")
    for corner, rounds in (("inner_root", (1, 2, 3)), ("outer_root", (1, 2, 3, 4, 5))):
        for levels in rounds:
            kw = dict(path_levels=levels, path_corners=(corner,), path_radius_in_t=1.0)
            print(f"  {MID[1]} {corner} rounds {levels}: {_lock_row(MID[1], mat, (3, 12), max_steps=2000, **kw)}")


CREASE_CELLS = [(45, 1.0, 4.0), (60, 0.6, 4.0)]
PENALTY_PER_MM = 1e4  # the plate's penalty: within 0.01 % of the active set's R (tests/test_continuum.py)


def _min_stretch(prob, u) -> tuple[float, np.ndarray]:
    """The smallest principal stretch over the quadrature points, and where (the element's centroid)."""
    lam_min = continuum.smallest_stretches(prob, u)
    e = np.unravel_index(np.argmin(lam_min), lam_min.shape)[0]
    return float(lam_min.min()), prob.mesh.p[:, prob.mesh.t[:, e]].mean(axis=1)


def crease_at_outer_root(mat) -> None:
    print(
        f"\n6. the outer root graded 0-4 rounds within 1 t (3 x 12 base), the plate's contact a penalty "
        f"({PENALTY_PER_MM:g} mu per mm): R, the smallest principal stretch at the lock and the largest "
        "force drop along the path"
    )
    for cell in CREASE_CELLS:
        c = HexCell(*cell)
        print(f"{cell}: outer root at x = {c.outer_profile_xz()[0][0]:.3f} mm")
        k_fine = continuum.linear_k(continuum.ContactProblem(c, mat))
        for levels in range(5):
            t0 = time.perf_counter()
            mesh = continuum.MeshOptions(levels=levels, corners=("outer_root",), radius_in_t=1.0)
            prob = continuum.ContactProblem(c, mat, mesh, PENALTY_PER_MM)
            k_path = continuum.linear_k(prob)
            try:
                path, _ = continuum.follow_to_lock(prob, k_path, StepControl(max_steps=2000))
            except PathError as exc:
                print(f"  rounds {levels}: {exc} ({time.perf_counter() - t0:.1f} s)")
                continue
            F = np.array([o[0] for o in path.observations])
            drop = float(np.max(np.maximum.accumulate(F) - F) / F.max())
            stretch, at = _min_stretch(prob, path.state.u)
            seconds = time.perf_counter() - t0
            print(
                f"  rounds {levels}: R {F[-1] * k_fine / k_path:.3f} N, {len(F)} steps, {seconds:.1f} s; "
                f"smallest stretch {stretch:.3f} at ({at[0]:.3f}, {at[1]:.3f}) mm; largest drop {100 * drop:.1f} %"
            )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--uniform", type=int, default=200, help="cells drawn for part 3")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--parts", default="1,2,3,4,5,6", help="which parts to run, comma-separated")
    args = ap.parse_args()
    parts = {int(p) for p in args.parts.split(",")}
    mat = Material()
    if 1 in parts:
        curves_on_meshes(mat)
    if 2 in parts:
        inner_root_refined(mat)
    if 3 in parts:
        l0_uniform(mat, args.uniform, args.seed)
    if 4 in parts:
        across_or_along(mat)
    if 5 in parts:
        grading_rounds(mat)
    if 6 in parts:
        crease_at_outer_root(mat)


if __name__ == "__main__":
    main()
