"""L0's lock force against L2 on fresh uniform cells, with and without the wall-pinch hinge.

Issue 20; prints a table, changes nothing. 0.12 ships the hinge at w = 0.01
(mst_cli.model.mechanics.correction.HINGE_TERMS); the first row is 0.11's lock fit.

    python studies/l0_lock_regime.py [--fresh 300] [--fresh-seed 3] [--cache FILE]

The shipped lock fit (tools/fit_l0_correction.py, mst_cli/model/data/l0_correction.json)
is verified on 270 cells of seed 2, of which 150 are uniform in the printable box and the rest
top up shallow, stubby and thin cells. This script solves L2 on those cells, on the fit's own
620 (seed 1) and on ``--fresh`` more uniform cells (``--fresh-seed``, never fitted), about
4 minutes on two cores (``--cache FILE`` keeps the solves), then refits the lock force as the
fit script does, without the hinge (0.11) and with it at two widths. L2 locks either where the
pads meet or earlier, where a wall is pinched between the plate and its mirror; L0's own
lock-stroke fit predicts q = d_lock / (h - 2t - a), so h = w ln(1 + exp(-(ln q + 0.03) / w)),
a smooth hinge that is non-zero where the walls close early (q < 0.97), times 1, t/L, theta
- 45 deg, the stroke ratio, h, (t/L)^2 and (theta - 45 deg)^2, enter the fit unscaled.
Printed per set: median / 90th percentile / max of |R_L0 / R_L2 - 1| (%); then, for the
shipped L0 (the package's own spring law, as a design uses it), the median overall and per L2
lock regime on the uniform sets, and L0's lock stroke error.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))  # the L0 fit
from fit_l0_correction import fit, fit_cells

from mst_cli.bench.sampling import sample_cells
from mst_cli.model.cell import lock_stroke_mm
from mst_cli.model.material import Material
from mst_cli.model.mechanics import correction
from mst_cli.model.mechanics.continuum import solve_continuum
from mst_cli.model.mechanics.spring import layer_stiffness_N_per_mm, spring_layer
from mst_cli.parallel import fork_map

MAT = Material()


def _l2(cell):
    r = solve_continuum(cell, MAT)
    return {"k": r.k_linear_N_per_mm, "d_lock": r.d_contact_mm, "R": float(r.force_N[-1]), "at": r.contact_at}


def solved(cells, cache: dict) -> list[dict]:
    keys = [f"{c.theta_deg:g},{c.t_mm:g},{c.h_mm:g}" for c in cells]
    todo = [c for c, k in zip(cells, keys) if k not in cache]
    for c, r in zip(todo, fork_map(_l2, todo) or [_l2(c) for c in todo]):
        cache[f"{c.theta_deg:g},{c.t_mm:g},{c.h_mm:g}"] = r
    return [cache[k] for k in keys]


def features(cells, coef_k, coef_d, hinge_w):
    x = np.array([c.t_mm / c.wall_length_mm for c in cells])
    th = np.array([c.theta_rad for c in cells])
    E, nu = MAT.youngs_modulus_MPa, MAT.poisson_ratio
    k0 = np.array([float(layer_stiffness_N_per_mm(c.theta_rad, c.t_mm, c.h_mm, c.b_mm, E, nu)) for c in cells])
    k0c = k0 * np.exp(correction.design_matrix(x, th) @ coef_k)
    d0 = np.array([float(lock_stroke_mm(c.t_mm, c.h_mm, c.contact_allowance_mm)) for c in cells])
    sig = correction.stroke_ratio(d0, np.array([c.wall_length_mm for c in cells]), th)
    A = sig[:, None] * correction.lock_design_matrix(x, th, sig)
    if hinge_w:
        A = np.hstack([A, correction.hinge_design_matrix(x, th, sig, A @ coef_d, width=hinge_w)])
    return A, k0c * d0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--fresh", type=int, default=300)
    ap.add_argument("--fresh-seed", type=int, default=3)
    ap.add_argument("--cache", type=Path)
    args = ap.parse_args()
    cache = json.loads(args.cache.read_text()) if args.cache and args.cache.exists() else {}
    fit_set, verify_set = fit_cells(300, 60, 60, 1, thin=200), fit_cells(150, 30, 30, 2, thin=60)
    fresh_set = sample_cells(args.fresh, args.fresh_seed)
    named = (("fit", fit_set), ("verify", verify_set), ("fresh", fresh_set))
    ref = {name: solved(cells, cache) for name, cells in named}
    if args.cache:
        args.cache.write_text(json.dumps(cache))
    (coef_k, _), _, (coef_d, _), _ = fit(fit_set, ref["fit"], MAT)
    sets = {
        "fit, uniform 300 (in sample)": (fit_set[:300], ref["fit"][:300]),
        "verify, all 270": (verify_set, ref["verify"]),
        "verify, uniform 150": (verify_set[:150], ref["verify"][:150]),
        f"fresh, uniform {args.fresh} (seed {args.fresh_seed})": (fresh_set, ref["fresh"]),
    }
    print("| lock-force fit | " + " | ".join(sets) + " |\n|---|" + "---|" * len(sets))
    for hinge_w in (0.0, 0.01, 0.05):
        A, base = features(fit_set, coef_k, coef_d, hinge_w)
        coef, *_ = np.linalg.lstsq(A, np.log(np.array([r["R"] for r in ref["fit"]]) / base), rcond=None)
        cols = []
        for cells, rows in sets.values():
            A, base = features(cells, coef_k, coef_d, hinge_w)
            err = 100 * np.abs(base * np.exp(A @ coef) / np.array([r["R"] for r in rows]) - 1)
            cols.append(f"{np.median(err):.2f} / {np.percentile(err, 90):.1f} / {err.max():.0f}")
        name = "0.11's terms (no hinge), refitted" if not hinge_w else f"+ wall-pinch hinge, w {hinge_w:g}"
        name += " (shipped)" if hinge_w == correction.HINGE_WIDTH else ""
        print(f"| {name} | " + " | ".join(cols) + " |")
    print("\nshipped L0 (mst_cli's own spring law), median |error| against L2:")
    for set_name, (cells, rows) in sets.items():
        if "uniform" not in set_name:
            continue
        laws = [spring_layer(c, MAT) for c in cells]
        eR = np.array([abs(law.lock_force_N / r["R"] - 1) for law, r in zip(laws, rows)])
        ed = np.array([abs(law.d_lock_mm / r["d_lock"] - 1) for law, r in zip(laws, rows)])
        regime = np.array([r["at"] for r in rows])
        parts = [
            f"{at} locks {100 * np.median(eR[regime == at]):.2f} % ({int(np.sum(regime == at))})"
            for at in ("wall", "pad")
        ]
        print(
            f"- {set_name}: lock force {100 * np.median(eR):.2f} %: "
            + ", ".join(parts)
            + f"; lock stroke {100 * np.median(ed):.2f} %"
        )


if __name__ == "__main__":
    main()
